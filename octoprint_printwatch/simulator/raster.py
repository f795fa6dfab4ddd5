"""A small software rasterizer: which triangle each pixel sees, and where it hits it.

Painter's algorithm into an int32 id image (far triangles first, back faces
culled) is exact for silhouettes and good enough for visibility on the printed
shapes; the exact 3-D point of each pixel then comes from a vectorised
ray/plane intersection with the face it shows.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..core.camera import Camera

#: Sub-pixel precision of cv2.fillConvexPoly (fixed-point bits).
_SHIFT = 4


@dataclass
class PixelRays:
    """Per-pixel viewing rays of an ideal (undistorted) pinhole camera.

    Attributes
    ----------
    origin : (3,) float
        Camera centre, printer coordinates (mm).
    directions : (h, w, 3) float32
        Unit ray directions in printer coordinates.
    """

    origin: np.ndarray
    directions: np.ndarray

    @classmethod
    def of(cls, camera: Camera) -> "PixelRays":
        u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64))
        norm_x = (u - camera.K[0, 2]) / camera.K[0, 0]
        norm_y = (v - camera.K[1, 2]) / camera.K[1, 1]
        d_cam = np.stack([norm_x, norm_y, np.ones_like(norm_x)], axis=-1)
        d = d_cam @ camera.R  # camera -> printer: R.T applied to each row vector
        d /= np.linalg.norm(d, axis=-1, keepdims=True)
        return cls(origin=camera.center, directions=d.astype(np.float32))


def project_pinhole(camera: Camera, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(n, 3) printer points -> ((n, 2) undistorted pixels, (n,) depth along the optical axis)."""
    cam = points @ camera.R.T + camera.tvec
    depth = cam[:, 2]
    safe = np.where(depth > 1e-6, depth, 1e-6)
    uv = (cam[:, :2] / safe[:, None]) @ camera.K[:2, :2].T + camera.K[:2, 2]
    return uv, depth


def face_ids(camera: Camera, vertices: np.ndarray, faces: np.ndarray, *, cull_back: bool = True,
             out: np.ndarray | None = None, id_offset: int = 0) -> np.ndarray:
    """(h, w) int32 image of the index of the face seen at each pixel, -1 where none.

    ``vertices`` (n, 3) and ``faces`` (m, 3) describe closed, outward-oriented
    meshes (trimesh convention). Faces behind the camera are dropped. When
    ``out`` is given, faces are drawn over it (ids shifted by ``id_offset``).
    """
    ids = np.full((camera.height, camera.width), -1, np.int32) if out is None else out
    if len(faces) == 0:
        return ids
    uv, depth = project_pinhole(camera, vertices)
    tri_depth = depth[faces]
    keep = np.all(tri_depth > 1.0, axis=1)
    tri = vertices[faces]
    if cull_back:
        normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        keep &= np.einsum("ij,ij->i", normals, tri[:, 0] - camera.center) < 0
    uv_tri = uv[faces]
    lo, hi = uv_tri.min(axis=1), uv_tri.max(axis=1)
    keep &= (hi[:, 0] >= -1) & (lo[:, 0] <= camera.width) & (hi[:, 1] >= -1) & (lo[:, 1] <= camera.height)
    index = np.nonzero(keep)[0]
    order = index[np.argsort(-tri_depth[index].mean(axis=1), kind="stable")]
    fixed = np.round(uv_tri[order] * (1 << _SHIFT)).astype(np.int32)
    fill = cv2.fillConvexPoly
    for face, pts in zip((order + id_offset).tolist(), fixed):
        fill(ids, pts, face, cv2.LINE_8, _SHIFT)
    return ids


def silhouette(camera: Camera, vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(h, w) bool mask of pixels covered by the mesh (undistorted image)."""
    mask = np.zeros((camera.height, camera.width), np.uint8)
    if len(faces) == 0:
        return mask.astype(bool)
    uv, depth = project_pinhole(camera, vertices)
    keep = np.all(depth[faces] > 1.0, axis=1)
    fixed = np.round(uv[faces[keep]] * (1 << _SHIFT)).astype(np.int32)
    for pts in fixed:
        cv2.fillConvexPoly(mask, pts, 1, cv2.LINE_8, _SHIFT)
    return mask.astype(bool)


def hit_points(rays: PixelRays, ids: np.ndarray, vertices: np.ndarray, faces: np.ndarray,
               pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Exact 3-D hit points and unit face normals for the given pixels.

    ``pixels`` is an (k,) flat index into the id image; returns ``(points (k, 3), normals (k, 3))``.
    """
    face = ids.ravel()[pixels]
    tri = vertices[faces[face]]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-12)
    d = rays.directions.reshape(-1, 3)[pixels].astype(np.float64)
    denom = np.einsum("ij,ij->i", normals, d)
    denom = np.where(np.abs(denom) < 1e-9, -1e-9, denom)
    t = np.einsum("ij,ij->i", normals, tri[:, 0] - rays.origin) / denom
    return rays.origin + d * t[:, None], normals
