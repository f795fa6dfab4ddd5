"""Expected views: what each camera should see of the part at each check height.

Silhouettes are exact and fast without ray tracing. Seen from a point, the
projected front-facing triangles of a closed mesh cover each pixel once per
front surface in the way, so the silhouette is where that count is not zero.
The count changes only across *contour edges* (edges of front faces whose
other face looks away, plus open boundary edges), so only those are
projected, and a scan-line winding count (one ``np.bincount`` and one
``cumsum``) fills the image. Pixels are sampled at their centres, so areas
carry no half-pixel bias. In the distorted image the edges are split every few
pixels before going through the lens model, so straight edges bend as the
lens bends them.

Depth maps and the newest layer band need visibility, so they use a small
vectorised z-buffer rasteriser over the front faces (perspective-correct
depth), rendered once per job and cached (memory, and ``.npz`` files keyed by
the mesh's content hash, the camera and the heights).
"""
from __future__ import annotations

import hashlib
import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable, Sequence

import cv2
import manifold3d as mf
import numpy as np
import trimesh

from .camera import Camera
from .errors import GeometryError
from .geometry import PartModel

#: Distorted silhouettes: contour edges are split into pieces at most this long (px) before distortion.
DISTORTION_STEP_PX = 4.0
#: The z-buffer rasteriser handles this many candidate pixels at a time (memory bound).
RASTER_CHUNK = 2_000_000
#: Geometry closer to the camera plane than this (mm) is not drawn.
NEAR_MM = 1.0
#: Cache file format; bump when the content of a cached view changes.
CACHE_VERSION = 1


@dataclass
class ExpectedView:
    """What one camera should see at one check height.

    All arrays are (h, w) in the camera's image. ``silhouette``, ``depth`` and
    ``new_band`` are in the distorted image (as the camera delivers frames);
    the ``*_undistorted`` ones in the undistorted image with the same ``K``.
    ``depth`` is mm along the optical axis (float32), ``inf`` where the part is
    absent. ``new_band`` is where the visible surface was printed above
    ``z_previous`` (the previous check height), i.e. the newest layer band.
    """

    camera: str
    z: float
    z_previous: float
    silhouette: np.ndarray
    silhouette_undistorted: np.ndarray
    depth: np.ndarray
    depth_undistorted: np.ndarray
    new_band: np.ndarray
    new_band_undistorted: np.ndarray


# ------------------------------------------------------------------- helpers
def _mesh_at(mesh_or_part: Any, z: float | None) -> trimesh.Trimesh:
    if isinstance(mesh_or_part, PartModel):
        return mesh_or_part.mesh if z is None else mesh_or_part.solid_below(z)
    if isinstance(mesh_or_part, trimesh.Trimesh):
        if z is None:
            return mesh_or_part
        from .geometry import part_from_mesh

        return part_from_mesh(mesh_or_part).solid_below(z)
    raise GeometryError(f"cannot render a {type(mesh_or_part).__name__}: give a PartModel or a trimesh.Trimesh")


@dataclass
class _EdgeTable:
    """Per-mesh tables that make a silhouette a few vectorised look-ups per camera.

    ``normals`` (F, 3) and ``offsets`` (F,): face planes (unnormalised). Each
    undirected edge shared by exactly two faces is a row of ``first_edges`` and
    ``second_edges`` (k, 2): its two directed copies, with their faces in
    ``first_faces`` and ``second_faces`` (k,); edges with one face or more than
    two are in ``other_edges`` (j, 2) / ``other_faces`` (j,), and are drawn
    whenever their face is in front.
    """

    token: tuple
    normals: np.ndarray
    offsets: np.ndarray
    first_edges: np.ndarray
    first_faces: np.ndarray
    second_edges: np.ndarray
    second_faces: np.ndarray
    other_edges: np.ndarray
    other_faces: np.ndarray


def _edge_table(mesh: trimesh.Trimesh) -> _EdgeTable:
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    faces = np.asarray(mesh.faces, dtype=np.int64)
    token = (vertices.shape, faces.shape, float(vertices.sum()), int(faces.sum()))
    table = getattr(mesh, "_printwatch_edges", None)
    if table is not None and table.token == token:
        return table
    a, b, c = vertices[faces[:, 0]], vertices[faces[:, 1]], vertices[faces[:, 2]]
    u, v = b - a, c - a
    # Written out: np.cross is several times slower on (n, 3) rows.
    normals = np.column_stack([u[:, 1] * v[:, 2] - u[:, 2] * v[:, 1],
                               u[:, 2] * v[:, 0] - u[:, 0] * v[:, 2],
                               u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]])
    offsets = (normals * a).sum(axis=1)
    directed = faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2)
    face_of = np.arange(len(directed)) // 3
    keys = np.minimum(directed[:, 0], directed[:, 1]) * max(len(vertices), 1) + np.maximum(directed[:, 0], directed[:, 1])
    order = np.argsort(keys)  # any order: the two copies of an edge only need to be adjacent
    sorted_keys = keys[order]
    starts = np.r_[0, np.nonzero(sorted_keys[1:] != sorted_keys[:-1])[0] + 1]
    runs = np.diff(np.r_[starts, len(keys)])
    pairs = starts[runs == 2]
    first, second = order[pairs], order[pairs + 1]
    other = order[np.repeat(runs != 2, runs)]
    table = _EdgeTable(token, normals, offsets, directed[first], face_of[first], directed[second], face_of[second],
                       directed[other], face_of[other])
    try:
        mesh._printwatch_edges = table
    except AttributeError:  # pragma: no cover - a mesh class with slots: just do not cache
        pass
    return table


def _front_faces(mesh: trimesh.Trimesh, camera: Camera) -> np.ndarray:
    """(F,) bool: faces whose outward side faces the camera centre."""
    table = _edge_table(mesh)
    return table.normals @ camera.center > table.offsets


def contour_edges(mesh: trimesh.Trimesh, camera: Camera) -> np.ndarray:
    """(m, 2, 3) printer-space edges where the count of front surfaces changes, oriented as in their front face.

    An edge between two front faces (or two back faces) is left out; what
    remains is the outline of the front region (silhouette edges, and open
    boundaries of a non-watertight mesh). Edges of more than two faces are all
    kept: their copies cancel in the winding count, so the fill stays right.
    """
    if len(mesh.faces) == 0:
        return np.zeros((0, 2, 3))
    table = _edge_table(mesh)
    front = table.normals @ camera.center > table.offsets
    depth = np.asarray(mesh.vertices) @ camera.R[2] + camera.tvec[2]
    if depth.min() <= NEAR_MM / 2:  # render_silhouette cuts solids at NEAR_MM before this
        # Faces reaching behind the camera are left out; the outline of the rest is still closed.
        front &= np.all(depth[np.asarray(mesh.faces)] > NEAR_MM / 2, axis=1)
    f0, f1 = front[table.first_faces], front[table.second_faces]
    edges = np.concatenate([table.first_edges[f0 & ~f1], table.second_edges[f1 & ~f0],
                            table.other_edges[front[table.other_faces]]])
    return np.asarray(mesh.vertices)[edges]


def _winding_fill(p0: np.ndarray, p1: np.ndarray, width: int, height: int) -> np.ndarray:
    """Non-zero winding fill of closed, oriented 2-D edge sets sampled at pixel centres.

    ``p0``, ``p1``: (m, 2) edge start and end in pixels. Returns (height, width) bool.
    """
    ok = np.all(np.isfinite(p0), axis=1) & np.all(np.isfinite(p1), axis=1) & (p0[:, 1] != p1[:, 1])
    p0, p1 = p0[ok], p1[ok]
    mask = np.zeros((height, width), bool)
    if len(p0) == 0:
        return mask
    y_lo = np.minimum(p0[:, 1], p1[:, 1])
    y_hi = np.maximum(p0[:, 1], p1[:, 1])
    # Rows whose centre r satisfies y_lo <= r < y_hi (half-open: shared vertices count once).
    r0 = np.maximum(np.ceil(y_lo), 0).astype(np.int64)
    r1 = np.minimum(np.ceil(y_hi) - 1, height - 1).astype(np.int64)
    n = np.maximum(r1 - r0 + 1, 0)
    total = int(n.sum())
    if total == 0:
        return mask
    edge = np.repeat(np.arange(len(p0)), n)
    starts = np.cumsum(n) - n
    rows = r0[edge] + (np.arange(total) - starts[edge])
    x0, y0, x1, y1 = p0[edge, 0], p0[edge, 1], p1[edge, 0], p1[edge, 1]
    x = x0 + (rows - y0) * (x1 - x0) / (y1 - y0)
    # A crossing at x counts for the pixel centres c > x, i.e. from column floor(x) + 1.
    cols = np.clip(np.floor(x) + 1, 0, width).astype(np.int64)
    sign = np.where(y1 > y0, 1.0, -1.0)
    acc = np.bincount(rows * (width + 1) + cols, weights=sign, minlength=height * (width + 1))
    winding = np.cumsum(acc.reshape(height, width + 1), axis=1)[:, :width]
    return np.abs(winding) > 0.5


def _split_edges(edges: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Distorted 2-D pieces (p0, p1) of 3-D edges, split so bent edges follow the lens."""
    ideal = camera.project(edges.reshape(-1, 3), distorted=False).reshape(-1, 2, 2)
    length = np.linalg.norm(ideal[:, 1] - ideal[:, 0], axis=1)
    pieces = np.clip(np.ceil(np.nan_to_num(length, nan=1.0) / DISTORTION_STEP_PX), 1, 256).astype(np.int64)
    edge = np.repeat(np.arange(len(edges)), pieces)
    starts = np.cumsum(pieces) - pieces
    k = np.arange(int(pieces.sum())) - starts[edge]
    t0 = (k / pieces[edge])[:, None]
    t1 = ((k + 1) / pieces[edge])[:, None]
    a, b = edges[edge, 0], edges[edge, 1]
    q0 = camera.project(a + (b - a) * t0, distorted=True)
    q1 = camera.project(a + (b - a) * t1, distorted=True)
    return q0, q1


def _in_front(mesh: trimesh.Trimesh, camera: Camera) -> trimesh.Trimesh:
    """The mesh cut at the camera's near plane when some of it lies behind (exactly, for solids)."""
    if len(mesh.faces) == 0:
        return mesh
    axis = camera.R[2]  # printer-frame direction of the optical axis
    if float((np.asarray(mesh.vertices) @ axis).min()) + camera.tvec[2] > NEAR_MM:
        return mesh
    from .geometry import manifold_from_trimesh, trimesh_from_manifold

    solid = manifold_from_trimesh(mesh)
    if solid.status() != mf.Error.NoError:
        return mesh  # contour_edges leaves the faces behind out
    return trimesh_from_manifold(solid.trim_by_plane(tuple(axis), NEAR_MM - camera.tvec[2]))


_RADIUS_CACHE: dict = {}


def _within_lens_model(points: np.ndarray, camera: Camera) -> bool:
    """Whether (n, 3) points lie where the lens model is trustworthy: within 1.2 x the field of view
    (in normalised image radius) and in front of the camera."""
    key = camera_key(camera)
    if key not in _RADIUS_CACHE:
        w, h = camera.width, camera.height
        border = np.array([[0, 0], [w - 1, 0], [0, h - 1], [w - 1, h - 1], [w / 2, 0], [0, h / 2],
                           [w - 1, h / 2], [w / 2, h - 1]], dtype=np.float64)
        normalised = cv2.undistortPoints(border.reshape(-1, 1, 2), camera.K, camera.dist).reshape(-1, 2)
        _RADIUS_CACHE[key] = 1.2 * float(np.max(np.hypot(normalised[:, 0], normalised[:, 1])))
    cam = camera.to_camera(points)
    if np.any(cam[:, 2] <= NEAR_MM):
        return False
    radius = np.hypot(cam[:, 0] / cam[:, 2], cam[:, 1] / cam[:, 2])
    return bool(np.all(radius <= _RADIUS_CACHE[key]))


def render_silhouette(mesh_or_part: Any, camera: Camera, z: float | None = None, *, distorted: bool = True) -> np.ndarray:
    """(h, w) bool mask of the part (up to height ``z`` when given) as ``camera`` sees it.

    ``distorted=True`` gives the mask in the camera's own (distorted) image,
    ``False`` in the undistorted image with the same ``K``.
    """
    mesh = _in_front(_mesh_at(mesh_or_part, z), camera)
    edges = contour_edges(mesh, camera)
    if len(edges) == 0:
        return np.zeros((camera.height, camera.width), bool)
    if distorted and np.any(camera.dist):
        if _within_lens_model(edges.reshape(-1, 3), camera):
            p0, p1 = _split_edges(edges, camera)
        else:
            # Far outside the view the distortion polynomial folds back into the image: render
            # undistorted on a canvas covering every pixel's ray and resample instead.
            K, pad, size = _canvas(camera)
            cam = camera.to_camera(edges.reshape(-1, 3))
            uv = (cam[:, :2] / cam[:, 2:]) @ K[:2, :2].T + K[:2, 2]
            canvas = _winding_fill(uv[0::2], uv[1::2], size[0], size[1])
            map_x, map_y = _distortion_maps(camera, pad)
            return cv2.remap(canvas.astype(np.uint8), map_x, map_y, cv2.INTER_NEAREST,
                             borderMode=cv2.BORDER_CONSTANT, borderValue=0) > 0
    else:
        uv = camera.project(edges.reshape(-1, 3), distorted=False).reshape(-1, 2, 2)
        p0, p1 = uv[:, 0], uv[:, 1]
    return _winding_fill(p0, p1, camera.width, camera.height)


# ------------------------------------------------------------------ z-buffer
def _canvas(camera: Camera) -> tuple[np.ndarray, tuple[int, int], tuple[int, int]]:
    """Undistorted canvas large enough for every distorted pixel: (K_canvas, (pad_x, pad_y), (w, h))."""
    if not np.any(camera.dist):
        return camera.K.copy(), (0, 0), (camera.width, camera.height)
    w, h = camera.width, camera.height
    border = np.concatenate([
        np.column_stack([np.arange(w), np.zeros(w)]), np.column_stack([np.arange(w), np.full(w, h - 1)]),
        np.column_stack([np.zeros(h), np.arange(h)]), np.column_stack([np.full(h, w - 1), np.arange(h)])])
    ideal = camera.undistort_points(border)
    ideal = ideal[np.all(np.isfinite(ideal), axis=1)]
    pad_x = int(np.clip(np.ceil(max(-ideal[:, 0].min(), ideal[:, 0].max() - (w - 1), 0)) + 2, 0, w // 2))
    pad_y = int(np.clip(np.ceil(max(-ideal[:, 1].min(), ideal[:, 1].max() - (h - 1), 0)) + 2, 0, h // 2))
    K = camera.K.copy()
    K[0, 2] += pad_x
    K[1, 2] += pad_y
    return K, (pad_x, pad_y), (w + 2 * pad_x, h + 2 * pad_y)


_MAP_CACHE: dict = {}


def _distortion_maps(camera: Camera, pad: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """For each distorted pixel, where it lies in the padded undistorted canvas (float32 maps)."""
    key = (camera_key(camera), pad)
    if key not in _MAP_CACHE:
        u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64))
        ideal = camera.undistort_points(np.column_stack([u.ravel(), v.ravel()]))
        map_x = (ideal[:, 0] + pad[0]).reshape(camera.height, camera.width).astype(np.float32)
        map_y = (ideal[:, 1] + pad[1]).reshape(camera.height, camera.width).astype(np.float32)
        if len(_MAP_CACHE) > 32:
            _MAP_CACHE.clear()
        _MAP_CACHE[key] = (map_x, map_y)
    return _MAP_CACHE[key]


def _affine(values: np.ndarray, tri: np.ndarray, det: np.ndarray):
    """Per triangle, the screen-affine (ax, ay, a0) with value = ax*x + ay*y + a0 through its 3 corners."""
    x0, y0 = tri[:, 0, 0], tri[:, 0, 1]
    dx1, dy1 = tri[:, 1, 0] - x0, tri[:, 1, 1] - y0
    dx2, dy2 = tri[:, 2, 0] - x0, tri[:, 2, 1] - y0
    da1, da2 = values[:, 1] - values[:, 0], values[:, 2] - values[:, 0]
    ax = (da1 * dy2 - da2 * dy1) / det
    ay = (da2 * dx1 - da1 * dx2) / det
    return ax, ay, values[:, 0] - ax * x0 - ay * y0


def _scan(tri: np.ndarray, inv_z: np.ndarray, wz_over_z: np.ndarray, w: int, h: int,
          depth: np.ndarray, world_z: np.ndarray) -> None:
    """Scan-convert (F, 3, 2) triangles into the flat z-buffer ``depth`` (and ``world_z``), in place.

    Rows are the pixel-centre rows inside each triangle; each row's span comes
    from the three edges, so only covered pixels are generated. 1/z and Z/z are
    affine on the screen (perspective-correct interpolation).
    """
    det = ((tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1])
           - (tri[:, 2, 0] - tri[:, 0, 0]) * (tri[:, 1, 1] - tri[:, 0, 1]))
    keep = np.abs(det) > 1e-12
    tri, inv_z, wz_over_z, det = tri[keep], inv_z[keep], wz_over_z[keep], det[keep]
    iz, wz = _affine(inv_z, tri, det), _affine(wz_over_z, tri, det)
    ys = tri[:, :, 1]
    r0 = np.maximum(np.ceil(ys.min(axis=1)), 0).astype(np.int64)
    r1 = np.minimum(np.floor(ys.max(axis=1)), h - 1).astype(np.int64)
    rows = np.maximum(r1 - r0 + 1, 0)
    t = np.repeat(np.arange(len(tri)), rows)
    y = (r0[t] + np.arange(len(t)) - np.repeat(np.cumsum(rows) - rows, rows)).astype(np.float64)
    lo = np.full(len(t), np.inf)
    hi = np.full(len(t), -np.inf)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        xa, ya, xb, yb = tri[t, a, 0], tri[t, a, 1], tri[t, b, 0], tri[t, b, 1]
        crossing = (np.minimum(ya, yb) <= y) & (y <= np.maximum(ya, yb))
        flat = ya == yb
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(flat, xa, xa + (y - ya) * (xb - xa) / (yb - ya))
        lo = np.where(crossing, np.minimum(lo, np.where(flat, np.minimum(xa, xb), x)), lo)
        hi = np.where(crossing, np.maximum(hi, np.where(flat, np.maximum(xa, xb), x)), hi)
    c0 = np.maximum(np.ceil(lo), 0).astype(np.int64)
    c1 = np.minimum(np.floor(hi), w - 1).astype(np.int64)
    cols = np.maximum(c1 - c0 + 1, 0)
    span = np.repeat(np.arange(len(t)), cols)
    x = (c0[span] + np.arange(len(span)) - np.repeat(np.cumsum(cols) - cols, cols)).astype(np.float64)
    tt, yy = t[span], y[span]
    d = 1.0 / (iz[0][tt] * x + iz[1][tt] * yy + iz[2][tt])
    zz = (wz[0][tt] * x + wz[1][tt] * yy + wz[2][tt]) * d
    pix = yy.astype(np.int64) * w + x.astype(np.int64)
    np.minimum.at(depth, pix, d)  # unbuffered: the nearest surface wins (fast in numpy >= 1.25)
    nearest = d <= depth[pix]
    world_z[pix[nearest]] = zz[nearest]


def _rasterize(mesh: trimesh.Trimesh, camera: Camera, K: np.ndarray, size: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Z-buffer of the front faces in an undistorted image with intrinsics ``K`` and ``size`` (w, h).

    Returns ``(depth, height_z)``: (h, w) float32 depth along the optical axis
    (inf where empty) and the printer Z of the visible surface (NaN where empty).
    """
    w, h = size
    depth = np.full(h * w, np.inf)
    world_z = np.full(h * w, np.nan)
    if len(mesh.faces) == 0:
        return depth.reshape(h, w).astype(np.float32), world_z.reshape(h, w)
    faces = np.asarray(mesh.faces)[_front_faces(mesh, camera)]
    cam = camera.to_camera(mesh.vertices)
    faces = faces[np.all(cam[:, 2][faces] > NEAR_MM / 2, axis=1)]
    zc = cam[:, 2]
    px = cam[:, :2] / zc[:, None] @ K[:2, :2].T + K[:2, 2]
    tri = px[faces]  # (F, 3, 2)
    inv_z = 1.0 / zc[faces]  # (F, 3)
    wz_over_z = np.asarray(mesh.vertices)[:, 2][faces] * inv_z
    # Chunks of triangles whose bounding boxes hold at most RASTER_CHUNK pixels (memory bound).
    box = np.clip(tri.max(axis=1), 0, [w, h]) - np.clip(tri.min(axis=1), 0, [w, h]) + 1
    bounds = np.cumsum(box[:, 0] * box[:, 1])
    start = 0
    while start < len(tri):
        stop = max(int(np.searchsorted(bounds, (bounds[start - 1] if start else 0) + RASTER_CHUNK)), start + 1)
        _scan(tri[start:stop], inv_z[start:stop], wz_over_z[start:stop], w, h, depth, world_z)
        start = stop
    return depth.reshape(h, w).astype(np.float32), world_z.reshape(h, w)


def render_depth(mesh_or_part: Any, camera: Camera, z: float | None = None, *, distorted: bool = True) -> np.ndarray:
    """(h, w) float32 depth (mm along the optical axis) of the part up to ``z``; inf where empty."""
    return _depth_and_height(_mesh_at(mesh_or_part, z), camera)[0 if distorted else 2]


def render_heights(mesh_or_part: Any, camera: Camera, z: float | None = None) -> np.ndarray:
    """(h, w) float32 printer Z (mm) of the visible surface of the part up to ``z``, in the camera's own
    (distorted) image; NaN where empty."""
    return _depth_and_height(_mesh_at(mesh_or_part, z), camera)[1]


def _depth_and_height(mesh: trimesh.Trimesh, camera: Camera):
    """(depth distorted, printer Z distorted, depth undistorted, printer Z undistorted)."""
    K, pad, size = _canvas(camera)
    depth, world_z = _rasterize(mesh, camera, K, size)
    h, w = camera.height, camera.width
    depth_u = depth[pad[1]:pad[1] + h, pad[0]:pad[0] + w]
    z_u = world_z[pad[1]:pad[1] + h, pad[0]:pad[0] + w]
    if not np.any(camera.dist):
        return depth_u, z_u, depth_u, z_u
    map_x, map_y = _distortion_maps(camera, pad)
    depth_d = cv2.remap(depth, map_x, map_y, cv2.INTER_NEAREST, borderMode=cv2.BORDER_CONSTANT, borderValue=np.inf)
    z_d = cv2.remap(world_z.astype(np.float32), map_x, map_y, cv2.INTER_NEAREST,
                    borderMode=cv2.BORDER_CONSTANT, borderValue=np.nan)
    return depth_d, z_d, depth_u, z_u


# --------------------------------------------------------------- the views
def camera_key(camera: Camera) -> str:
    """Short hash of everything that changes what a camera sees."""
    doc = json.dumps({"name": camera.name, **camera.to_dict()}, sort_keys=True)
    return hashlib.sha1(doc.encode()).hexdigest()[:16]


def mesh_key(mesh: trimesh.Trimesh) -> str:
    """Content hash of a mesh (vertices and faces)."""
    digest = hashlib.sha1()
    digest.update(np.ascontiguousarray(mesh.vertices, dtype=np.float64).tobytes())
    digest.update(np.ascontiguousarray(mesh.faces, dtype=np.int64).tobytes())
    return digest.hexdigest()[:16]


def render_view(part: PartModel, camera: Camera, z: float, z_previous: float = 0.0, *,
                layer: int | None = None, previous_layer: int | None = None) -> ExpectedView:
    """The expected view of ``part`` printed up to ``z`` for one camera (no caching).

    With ``layer`` (and ``previous_layer``) and a G-code part, the part is the
    state after that layer in print order (right for sequential printing, where
    objects are finished one after another) and the newest band is what was
    printed after ``previous_layer`` and is visible.
    """
    by_layer = layer is not None and hasattr(part, "solid_through_layer")
    solid = part.solid_through_layer(layer) if by_layer else part.solid_below(z)
    mesh = _in_front(solid, camera)
    depth_d, z_d, depth_u, z_u = _depth_and_height(mesh, camera)
    silhouette = render_silhouette(mesh, camera, distorted=True)
    silhouette_u = render_silhouette(mesh, camera, distorted=False)
    # The z-buffer and the exact silhouette may disagree on boundary pixels: the silhouette wins.
    depth_d = _agree(depth_d, silhouette)
    depth_u = _agree(depth_u, silhouette_u)
    if by_layer:
        # New where the visible surface is nearer than anything printed before (or nothing was there).
        older = _in_front(part.solid_through_layer(previous_layer or 0), camera)
        old_d, _, old_u, _ = _depth_and_height(older, camera)
        band_d = depth_d < old_d - 1e-3
        band_u = depth_u < old_u - 1e-3
    else:
        # The visible surface printed above the previous check (a hair of tolerance for rounding).
        band_d = np.nan_to_num(z_d, nan=-np.inf) > z_previous + 1e-3
        band_u = np.nan_to_num(z_u, nan=-np.inf) > z_previous + 1e-3
    return ExpectedView(
        camera=camera.name, z=float(z), z_previous=float(z_previous),
        silhouette=silhouette, silhouette_undistorted=silhouette_u,
        depth=np.asarray(depth_d, np.float32), depth_undistorted=np.asarray(depth_u, np.float32),
        new_band=band_d & silhouette, new_band_undistorted=band_u & silhouette_u)


def _agree(depth: np.ndarray, silhouette: np.ndarray) -> np.ndarray:
    """Depth made to cover exactly the silhouette: boundary pixels the z-buffer missed take a neighbour's depth."""
    depth = np.where(silhouette, depth, np.inf).astype(np.float32)
    for _ in range(2):
        missing = silhouette & ~np.isfinite(depth)
        if not missing.any():
            break
        nearest = cv2.erode(depth, np.ones((3, 3), np.uint8))  # min filter: the nearest surface around
        depth[missing] = nearest[missing]
    return depth


_MEMORY_CACHE: dict = {}
#: Views kept in memory (each is about 3.6 MB at 640x480: four masks, two float32 depth maps); the
#: on-disk cache serves repeats, so this stays small for a long-running OctoPrint on a Raspberry Pi.
_MEMORY_CACHE_LIMIT = 8


def _save(path: Path, view: ExpectedView) -> None:
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp.npz")
    np.savez_compressed(
        tmp, version=CACHE_VERSION, camera=view.camera, z=view.z, z_previous=view.z_previous,
        shape=np.array(view.silhouette.shape),
        silhouette=np.packbits(view.silhouette), silhouette_undistorted=np.packbits(view.silhouette_undistorted),
        new_band=np.packbits(view.new_band), new_band_undistorted=np.packbits(view.new_band_undistorted),
        depth=view.depth, depth_undistorted=view.depth_undistorted)
    os.replace(tmp, path)


def _load(path: Path) -> ExpectedView | None:
    try:
        with np.load(path) as data:
            if int(data["version"]) != CACHE_VERSION:
                return None
            shape = tuple(int(v) for v in data["shape"])
            count = shape[0] * shape[1]

            def mask(name: str) -> np.ndarray:
                return np.unpackbits(data[name])[:count].reshape(shape).astype(bool)

            return ExpectedView(
                camera=str(data["camera"]), z=float(data["z"]), z_previous=float(data["z_previous"]),
                silhouette=mask("silhouette"), silhouette_undistorted=mask("silhouette_undistorted"),
                depth=data["depth"], depth_undistorted=data["depth_undistorted"],
                new_band=mask("new_band"), new_band_undistorted=mask("new_band_undistorted"))
    except (OSError, ValueError, KeyError, EOFError):
        return None  # a damaged cache file is re-rendered, never an error


def render_expected_views(part: PartModel, cameras: Sequence[Camera], heights: Iterable[float],
                          cache_dir: str | Path | None = None) -> dict:
    """Expected views for every camera and check height: ``{(camera name, z): ExpectedView}``.

    Heights are sorted; each view's ``new_band`` is relative to the previous
    height (the first to the bed). Views are cached in memory and, with
    ``cache_dir``, on disk as ``<mesh hash>_<camera hash>_<z>_<z_prev>.npz``.
    For sequential prints (objects printed one after another) use
    :func:`render_expected_views_by_layer`.
    """
    return {(camera, z): view for camera, _, z, view in iter_expected_views(part, cameras, heights, cache_dir)}


def iter_expected_views(part: PartModel, cameras: Sequence[Camera], heights: Iterable[float],
                        cache_dir: str | Path | None = None):
    """:func:`render_expected_views` one view at a time: yields ``(camera name, None, z, ExpectedView)``,
    heights ascending, every camera at one height before the next height.

    A full view holds two float32 depth maps (about 3.6 MB at 640x480): a caller that keeps only
    what it needs of each view (``core.pipeline.PlannedView``) never holds more than one. The part
    trimmed at a height is rendered for every camera while it is at hand.
    """
    heights = sorted({round(float(z), 4) for z in heights})
    yield from _render_checks(part, cameras, [(None, z) for z in heights], cache_dir)


def render_expected_views_by_layer(part: PartModel, cameras: Sequence[Camera], checks: Iterable[tuple[int, float]],
                                   cache_dir: str | Path | None = None) -> dict:
    """Expected views for checks given as (layer, z): ``{(camera name, layer): ExpectedView}``.

    The part is the state after each layer in print order, so sequential prints
    (the next object starts again at the bed) get the right views; otherwise the
    same as :func:`render_expected_views`. Each ``new_band`` is relative to the
    previous check's layer.
    """
    checks = sorted({(int(layer), round(float(z), 4)) for layer, z in checks})
    return {(camera, layer): view for camera, layer, _, view in _render_checks(part, cameras, checks, cache_dir)}


def _render_checks(part: PartModel, cameras: Sequence[Camera], checks: list, cache_dir):
    """Yields (camera name, layer or None, z, view) for sorted ``checks`` [(layer or None, z)], with caching:
    every camera at one check before the next check (the part trimmed at that check is then at hand)."""
    part_hash = mesh_key(part.mesh)
    directory = Path(cache_dir) if cache_dir is not None else None
    if directory is not None:
        directory.mkdir(parents=True, exist_ok=True)
    cam_hashes = [camera_key(camera) for camera in cameras]
    previous_layer, previous = None, 0.0
    for layer, z in checks:
        for camera, cam_hash in zip(cameras, cam_hashes):
            key = (part_hash, cam_hash, z, previous, layer, previous_layer)
            view = _MEMORY_CACHE.get(key)
            name = f"{part_hash}_{cam_hash}_{z:.4f}_{previous:.4f}"
            if layer is not None:
                name += f"_L{layer}_{previous_layer or 0}"
            path = directory / f"{name}.npz" if directory else None
            if view is None and path is not None and path.is_file():
                view = _load(path)
            if view is None:
                view = render_view(part, camera, z, previous, layer=layer, previous_layer=previous_layer)
                if path is not None:
                    _save(path, view)
            if len(_MEMORY_CACHE) >= _MEMORY_CACHE_LIMIT:
                _MEMORY_CACHE.pop(next(iter(_MEMORY_CACHE)))
            _MEMORY_CACHE[key] = view
            yield camera.name, layer, z, view
        previous_layer, previous = layer, z
