"""An independent webcam renderer for the cross-check simulator.

Written from ``docs/recording-format.md`` alone: it shares no code with ``octoprint_printwatch``
(numpy, OpenCV and nothing else). The pipeline per frame:

1. a pinhole *canvas* wide enough to cover the distorted view, supersampled;
2. a z-buffered triangle rasteriser (``cv2.fillConvexPoly`` per triangle, perspective-correct depth)
   for the solid meshes and for strands (camera-facing ribbons built per view);
3. per-pixel shading: Lambert + ambient from one directional light, faint layer lines, a cast shadow of
   everything onto the bed along the light, a textured bed (decals such as a skirt drawn into it),
   a glossy bed's specular streak and mirror image, a backdrop looked up by ray direction;
4. lens distortion by remapping the canvas through the camera's distortion model (exact, per pixel),
   area-downsampled to the frame size;
5. a webcam sensor: exposure and white balance, vignetting, optical blur, Poisson + read noise,
   gamma, sharpening, 8-bit; the caller writes JPEG or PNG.

Units: millimetres, printer coordinates (z up, bed top at z = 0); images are (H, W, 3) float32 linear
RGB until :func:`expose`, which returns (H, W, 3) uint8 BGR.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

LAYER_HEIGHT_MM = 0.2


@dataclass
class Camera:
    """An OpenCV camera: ``x_cam = R(rvec) @ X_printer + tvec``."""
    name: str
    width: int
    height: int
    K: np.ndarray      # (3, 3) intrinsics, pixels
    dist: np.ndarray   # (5,) k1 k2 p1 p2 k3
    rvec: np.ndarray   # (3,) Rodrigues vector, printer -> camera
    tvec: np.ndarray   # (3,) mm

    @property
    def R(self) -> np.ndarray:
        return cv2.Rodrigues(np.asarray(self.rvec, np.float64).reshape(3, 1))[0]

    @property
    def centre(self) -> np.ndarray:
        """(3,) camera centre in printer coordinates."""
        return -self.R.T @ np.asarray(self.tvec, np.float64)

    def project(self, points: np.ndarray) -> np.ndarray:
        """(N, 3) printer mm -> (N, 2) distorted pixel coordinates."""
        uv, _ = cv2.projectPoints(np.asarray(points, np.float64).reshape(-1, 1, 3), self.rvec, self.tvec,
                                  self.K, self.dist)
        return uv.reshape(-1, 2)

    def to_json(self) -> dict:
        return {"width": int(self.width), "height": int(self.height),
                "K": [[float(v) for v in row] for row in self.K],
                "dist": [float(v) for v in self.dist],
                "rvec": [float(v) for v in np.ravel(self.rvec)],
                "tvec": [float(v) for v in np.ravel(self.tvec)]}


def look_at(eye: np.ndarray, target: np.ndarray, roll_deg: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Pose of a camera at ``eye`` (3,) looking at ``target`` (3,), rolled about its axis -> (rvec, tvec)."""
    forward = np.asarray(target, float) - np.asarray(eye, float)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    down = np.cross(forward, right)
    R = np.stack([right, down, forward])
    c, s = np.cos(np.radians(roll_deg)), np.sin(np.radians(roll_deg))
    R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]]) @ R
    rvec = cv2.Rodrigues(R)[0].ravel()
    return rvec, -R @ np.asarray(eye, float)


@dataclass
class Mesh:
    """A closed triangle mesh with one material. vertices (N, 3) mm, faces (M, 3) counter-clockwise seen
    from outside (normals point out)."""
    vertices: np.ndarray
    faces: np.ndarray
    colour: tuple                 # linear RGB albedo, 0..1
    layer_lines: float = 0.0      # relative amplitude of the 0.2-mm layer shading on side faces
    specular: float = 0.0
    flat: float = 0.0             # 0 = plain Lambert, 1 = no directional shading (translucent look)
    casts_shadow: bool = True
    two_sided: bool = False


@dataclass
class Strand:
    """A thin filament strand: a polyline (N, 3) mm drawn as a camera-facing ribbon ``width`` mm wide."""
    points: np.ndarray
    width: float
    colour: tuple


@dataclass
class Light:
    direction: np.ndarray         # (3,) unit vector from the scene towards the light
    ambient: float
    diffuse: float
    colour: np.ndarray = field(default_factory=lambda: np.ones(3, np.float32))
    penumbra_mm: float = 1.5


@dataclass
class BedLook:
    """The bed and its surroundings. ``texture`` (T, T, 3) linear albedo covering [0, size] x [0, size] mm,
    row = y. ``backdrop`` (Hb, Wb, 3) indexed by ray azimuth (columns) and elevation (rows)."""
    texture: np.ndarray
    size_mm: float
    frame_colour: np.ndarray
    backdrop: np.ndarray
    specular: float = 0.0         # strength of the glossy streak (glass)
    streak_sigma_deg: tuple = (20.0, 3.0)   # along / across the streak
    streak_axis_deg: float = 0.0
    reflectivity: float = 0.0     # mirror image of the part in a glossy bed

    @property
    def mm_per_texel(self) -> float:
        return self.size_mm / self.texture.shape[1]


@dataclass
class Sensor:
    vignetting: float = 0.2       # brightness lost in the corners (0..1)
    blur_sigma: float = 0.6       # px
    full_well: float = 800.0      # photo-electrons at white: Poisson noise
    read_noise: float = 0.004     # fraction of white: Gaussian noise
    gamma: float = 2.2
    sharpen: float = 0.3


# ---------------------------------------------------------------------------------------------- lens

def undistort_normalised(uv: np.ndarray, K: np.ndarray, dist: np.ndarray, iterations: int = 30) -> np.ndarray:
    """(N, 2) distorted pixels -> (N, 2) ideal normalised coordinates (x/z, y/z), by fixed-point
    iteration of the Brown-Conrady model (the inverse of what cv2.projectPoints applies)."""
    k1, k2, p1, p2, k3 = (list(np.ravel(dist)) + [0.0] * 5)[:5]
    xd = (uv[:, 0] - K[0, 2]) / K[0, 0]
    yd = (uv[:, 1] - K[1, 2]) / K[1, 1]
    x, y = xd.copy(), yd.copy()
    for _ in range(iterations):
        r2 = x * x + y * y
        radial = 1 + r2 * (k1 + r2 * (k2 + r2 * k3))
        dx = 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
        dy = p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
        x = (xd - dx) / radial
        y = (yd - dy) / radial
    return np.stack([x, y], axis=1)


@dataclass
class Canvas:
    """Pinhole canvas covering one distorted camera view at ``supersample`` times its resolution."""
    K: np.ndarray                 # (3, 3) canvas intrinsics
    width: int
    height: int
    map_x: np.ndarray             # (H*s, W*s) float32: where each supersampled frame pixel reads the canvas
    map_y: np.ndarray
    rays: np.ndarray              # (Hc, Wc, 3) float32 ray directions in printer coords (camera z = 1)


_CANVAS_CACHE: dict = {}


def _interp2(values: np.ndarray, rows: np.ndarray, cols: np.ndarray, H: int, W: int) -> np.ndarray:
    """Bilinear interpolation of ``values`` (len(rows), len(cols)) sampled at integer rows/cols onto (H, W)."""
    r = np.arange(H)
    c = np.arange(W)
    along_rows = np.stack([np.interp(r, rows, values[:, j]) for j in range(values.shape[1])], 1)   # (H, nc)
    return np.stack([np.interp(c, cols, along_rows[i]) for i in range(H)], 0)


def canvas_for(camera: Camera, supersample: int) -> Canvas:
    key = (camera.width, camera.height, tuple(np.ravel(camera.K)), tuple(np.ravel(camera.dist)),
           tuple(np.ravel(camera.rvec)), supersample)
    if key in _CANVAS_CACHE:
        return _CANVAS_CACHE[key]
    s = supersample
    W, H = camera.width * s, camera.height * s
    u = (np.arange(W) + 0.5) / s - 0.5
    v = (np.arange(H) + 0.5) / s - 0.5
    # the distortion is smooth: solve it on every 4th pixel (and the last) and interpolate bilinearly
    step = 4
    cols = np.unique(np.r_[np.arange(0, W, step), W - 1])
    rows = np.unique(np.r_[np.arange(0, H, step), H - 1])
    uu, vv = np.meshgrid(u[cols], v[rows])
    coarse = undistort_normalised(np.stack([uu.ravel(), vv.ravel()], 1), camera.K, camera.dist)
    coarse = coarse.reshape(len(rows), len(cols), 2)
    ideal = np.stack([_interp2(coarse[:, :, k], rows, cols, H, W) for k in range(2)], -1).reshape(-1, 2)
    fx, fy = camera.K[0, 0] * s, camera.K[1, 1] * s
    x0, x1 = ideal[:, 0].min(), ideal[:, 0].max()
    y0, y1 = ideal[:, 1].min(), ideal[:, 1].max()
    Wc, Hc = int(np.ceil((x1 - x0) * fx)) + 4, int(np.ceil((y1 - y0) * fy)) + 4
    cx, cy = -x0 * fx + 2, -y0 * fy + 2
    Kc = np.array([[fx, 0, cx], [0, fy, cy], [0, 0, 1.0]])
    map_x = (ideal[:, 0] * fx + cx).reshape(H, W).astype(np.float32)
    map_y = (ideal[:, 1] * fy + cy).reshape(H, W).astype(np.float32)
    gx, gy = np.meshgrid((np.arange(Wc) - cx) / fx, (np.arange(Hc) - cy) / fy)
    d_cam = np.stack([gx, gy, np.ones_like(gx)], -1)
    rays = (d_cam @ camera.R).astype(np.float32)          # R^T d for every pixel
    canvas = Canvas(Kc, Wc, Hc, map_x, map_y, rays)
    if len(_CANVAS_CACHE) > 16:
        _CANVAS_CACHE.clear()
    _CANVAS_CACHE[key] = canvas
    return canvas


# ---------------------------------------------------------------------------------------- rasteriser

def rasterise(tri_cam: np.ndarray, Kc: np.ndarray, width: int, height: int, cull: np.ndarray,
              inv_depth: np.ndarray, face_id: np.ndarray, first_id: int = 0) -> None:
    """Z-buffer triangles (F, 3, 3) in camera coordinates into ``inv_depth`` / ``face_id`` (Hc, Wc).

    ``cull`` (F,) bool: drop the triangle when it faces away from the camera. Depth test on 1/z, which
    is affine in image coordinates on a planar triangle (perspective-correct)."""
    if len(tri_cam) == 0:
        return
    Z = tri_cam[:, :, 2]
    ok = (Z > 1.0).all(axis=1)
    if cull.any():
        normal = np.cross(tri_cam[:, 1] - tri_cam[:, 0], tri_cam[:, 2] - tri_cam[:, 0])
        facing = (normal * tri_cam[:, 0]).sum(axis=1) < 0          # normal towards the camera centre
        ok &= facing | ~cull
    idx = np.nonzero(ok)[0]
    if len(idx) == 0:
        return
    t = tri_cam[idx]
    u = Kc[0, 0] * t[:, :, 0] / t[:, :, 2] + Kc[0, 2]
    v = Kc[1, 1] * t[:, :, 1] / t[:, :, 2] + Kc[1, 2]
    w = 1.0 / t[:, :, 2]
    A = np.stack([u, v, np.ones_like(u)], axis=2)                   # (F, 3, 3)
    det = np.linalg.det(A)
    good = np.abs(det) > 1e-6
    abc = np.zeros((len(idx), 3))
    abc[good] = np.linalg.solve(A[good], w[good][:, :, None])[:, :, 0]
    x0 = np.clip(np.floor(u.min(1)).astype(int) - 1, 0, width)
    x1 = np.clip(np.ceil(u.max(1)).astype(int) + 2, 0, width)
    y0 = np.clip(np.floor(v.min(1)).astype(int) - 1, 0, height)
    y1 = np.clip(np.ceil(v.max(1)).astype(int) + 2, 0, height)
    for k in np.nonzero(good & (x1 > x0) & (y1 > y0))[0]:
        xa, xb, ya, yb = x0[k], x1[k], y0[k], y1[k]
        sub = np.zeros((yb - ya, xb - xa), np.uint8)
        pts = np.round(np.stack([u[k] - xa, v[k] - ya], 1) * 16).astype(np.int32)
        cv2.fillConvexPoly(sub, pts, 1, lineType=cv2.LINE_8, shift=4)
        if not sub.any():
            continue
        a, b, c = abc[k]
        gx = np.arange(xa, xb, dtype=np.float32)
        gy = np.arange(ya, yb, dtype=np.float32)[:, None]
        depth = a * gx + b * gy + c
        zview = inv_depth[ya:yb, xa:xb]
        nearer = (sub > 0) & (depth > zview)
        zview[nearer] = depth[nearer]
        face_id[ya:yb, xa:xb][nearer] = first_id + idx[k]


def strand_triangles(strand: Strand, eye: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A strand as a ribbon facing ``eye``: triangles (2(N-1), 3, 3) and their shading normals (2(N-1), 3)."""
    p = np.asarray(strand.points, float)
    if len(p) < 2:
        return np.zeros((0, 3, 3)), np.zeros((0, 3))
    a, b = p[:-1], p[1:]
    seg = b - a
    seg /= np.maximum(np.linalg.norm(seg, axis=1, keepdims=True), 1e-9)
    view = eye - (a + b) / 2
    view /= np.linalg.norm(view, axis=1, keepdims=True)
    side = np.cross(seg, view)
    side /= np.maximum(np.linalg.norm(side, axis=1, keepdims=True), 1e-9)
    side *= strand.width / 2
    # a tube's normal facing the viewer: the view direction with the strand's own direction removed
    normal = view - (view * seg).sum(1, keepdims=True) * seg
    normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-9)
    q0, q1, q2, q3 = a - side, a + side, b + side, b - side
    tris = np.concatenate([np.stack([q0, q1, q2], 1), np.stack([q0, q2, q3], 1)])
    return tris, np.concatenate([normal, normal])


# ------------------------------------------------------------------------------------------- shading

def shadow_map(meshes: list[Mesh], strands: list[Strand], light: Light, lo: float, hi: float,
               mm_per_cell: float) -> np.ndarray:
    """(N, N) float32 in [0, 1]: how much of the light each bed cell of [lo, hi]^2 mm loses, casting every
    shadow-casting triangle along the light direction onto z = 0, softened by the penumbra."""
    n = int(np.ceil((hi - lo) / mm_per_cell))
    grid = np.zeros((n, n), np.uint8)
    L = np.asarray(light.direction, float)
    if L[2] <= 0.05:
        return grid.astype(np.float32)

    def cast(tris):
        flat = tris - tris[:, :, 2:3] / L[2] * L                   # slide each vertex down the light ray
        pts = np.round((flat[:, :, :2] - lo) / mm_per_cell * 16).astype(np.int32)
        for tri in pts:
            cv2.fillConvexPoly(grid, tri, 1, lineType=cv2.LINE_8, shift=4)

    for mesh in meshes:
        if mesh.casts_shadow and len(mesh.faces):
            cast(np.asarray(mesh.vertices, float)[mesh.faces])
    for strand in strands:
        p = np.asarray(strand.points, float)
        if len(p) >= 2:
            sun_side = np.cross(p[1:] - p[:-1], L)
            sun_side /= np.maximum(np.linalg.norm(sun_side, axis=1, keepdims=True), 1e-9)
            sun_side *= strand.width / 2
            a, b = p[:-1], p[1:]
            cast(np.concatenate([np.stack([a - sun_side, a + sun_side, b + sun_side], 1),
                                 np.stack([a - sun_side, b + sun_side, b - sun_side], 1)]))
    soft = grid.astype(np.float32)
    sigma = max(light.penumbra_mm / mm_per_cell, 0.5)
    return cv2.GaussianBlur(soft, (0, 0), sigma)


def _lookup(image: np.ndarray, px: np.ndarray, py: np.ndarray, border) -> np.ndarray:
    return cv2.remap(image, px.astype(np.float32), py.astype(np.float32), cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_CONSTANT, borderValue=border)


def render_view(camera: Camera, meshes: list[Mesh], strands: list[Strand], light: Light, bed: BedLook,
                decals: np.ndarray | None = None, supersample: int = 2,
                shadow: np.ndarray | None = None, shadow_extent: tuple = (-60.0, 280.0, 0.5)) -> np.ndarray:
    """One camera's view, (H, W, 3) float32 linear RGB (radiance; 1.0 = white paper in full light).

    ``decals`` (T, T, 4) RGBA drawn onto the bed texture (a skirt). ``shadow`` from :func:`shadow_map`
    over ``shadow_extent`` = (lo, hi, mm per cell); computed here when not given."""
    cv = canvas_for(camera, supersample)
    R, t, eye = camera.R, np.asarray(camera.tvec, float), camera.centre
    L = np.asarray(light.direction, np.float32)
    Hc, Wc = cv.height, cv.width
    inv_depth = np.zeros((Hc, Wc), np.float32)
    face_id = np.full((Hc, Wc), -1, np.int32)

    normals, albedo, layer_amp, spec, flat = [], [], [], [], []
    for mesh, n in _rasterise_meshes(meshes, camera, cv, inv_depth, face_id):
        normals.append(n)
        albedo.append(np.tile(np.asarray(mesh.colour, float), (len(n), 1)))
        layer_amp.append(np.full(len(n), mesh.layer_lines))
        spec.append(np.full(len(n), mesh.specular))
        flat.append(np.full(len(n), mesh.flat))
    first = sum(len(n) for n in normals)
    # strands go into their own buffer, depth-tested against the solids, and are blended with what lies
    # behind them by their true width in pixels (a 0.1-mm hair covers a fraction of a pixel, while the
    # rasteriser draws at least one)
    strand_depth = inv_depth.copy()
    strand_id = np.full((Hc, Wc), -1, np.int32)
    coverage = [np.ones(first)]
    for strand in strands:
        tris, n = strand_triangles(strand, eye)
        if len(tris) == 0:
            continue
        tri_cam = tris @ R.T + t
        rasterise(tri_cam, cv.K, Wc, Hc, np.zeros(len(tris), bool), strand_depth, strand_id, first)
        # fillConvexPoly marks every pixel a thin ribbon touches: about 1.5 px wide on average
        width_px = strand.width * cv.K[0, 0] / np.maximum(tri_cam[:, :, 2].mean(1), 1.0)
        coverage.append(np.clip(width_px / 1.5, 0.03, 1.0))
        normals.append(n)
        albedo.append(np.tile(np.asarray(strand.colour, float), (len(tris), 1)))
        layer_amp.append(np.zeros(len(tris)))
        spec.append(np.full(len(tris), 0.05))
        flat.append(np.zeros(len(tris)))
        first += len(tris)

    rays = cv.rays
    light_rgb = np.asarray(light.colour, np.float32)
    st = _static_ground(cv, camera, bed, decals)
    on_bed, bx, by = st["on_bed"], st["bx"], st["by"]

    # --- the bed, its frame and the backdrop
    lo, hi, cell = shadow_extent
    if shadow is None:
        shadow = shadow_map(meshes, strands, light, lo, hi, cell)
    lit = 1.0 - _lookup(shadow, (bx - lo) / cell - 0.5, (by - lo) / cell - 0.5, 0)
    bed_shade = light.ambient + light.diffuse * max(float(L[2]), 0.0) * lit
    ground = st["ground_albedo"] * (bed_shade[:, :, None] * light_rgb)
    if bed.specular > 0:
        # an elongated highlight (a tube light or a window): angle to the light split along/across an axis
        refl = st["refl"]
        a = np.radians(bed.streak_axis_deg)
        axis = np.array([np.cos(a), np.sin(a), 0.0], np.float32)
        across = np.cross(L, axis)
        across /= max(np.linalg.norm(across), 1e-9)
        along = np.cross(across, L).astype(np.float32)
        across = across.astype(np.float32)
        d_along = np.arcsin(np.clip(refl @ along, -1, 1))
        d_across = np.arcsin(np.clip(refl @ across, -1, 1))
        forward = (refl @ L) > 0
        sa, sc = np.radians(bed.streak_sigma_deg[0]), np.radians(bed.streak_sigma_deg[1])
        glint = np.exp(-0.5 * ((d_along / sa) ** 2 + (d_across / sc) ** 2)) * forward
        ground = ground + (bed.specular * glint * lit * on_bed)[:, :, None] * light_rgb
    if bed.reflectivity > 0 and meshes:
        mirrored = [Mesh(m.vertices * np.array([1, 1, -1.0]), np.asarray(m.faces)[:, ::-1], m.colour, m.layer_lines,
                         0.0, m.flat, False, m.two_sided) for m in meshes]
        mirror_img, seen = render_meshes_only(cv, camera, mirrored, light)
        ground = np.where((seen & on_bed)[:, :, None], ground * (1 - bed.reflectivity)
                          + bed.reflectivity * mirror_img, ground)
    back = st["back_albedo"] * ((light.ambient + light.diffuse * 0.5) * light_rgb)
    out = np.where(st["ground_mask"][:, :, None], ground, back).astype(np.float32)

    # --- the meshes and strands
    if first:
        normals_a = np.concatenate(normals).astype(np.float32)
        albedo_a = np.concatenate(albedo).astype(np.float32)
        layer_a = np.concatenate(layer_amp).astype(np.float32)
        spec_a = np.concatenate(spec).astype(np.float32)
        flat_a = np.concatenate(flat).astype(np.float32)
        cover_a = np.concatenate(coverage).astype(np.float32)

        def shade(pix, ids, inv):
            fid = ids[pix]
            z = 1.0 / inv[pix]
            P = eye[None].astype(np.float32) + z[:, None] * rays[pix]
            n = normals_a[fid]
            to_eye = eye[None] - P
            to_eye /= np.linalg.norm(to_eye, axis=1, keepdims=True)
            flip = (n * to_eye).sum(1) < 0                         # two-sided faces seen from behind
            n[flip] *= -1
            lam = np.clip(n @ L, 0, 1)
            shading = light.ambient + light.diffuse * (flat_a[fid] * 0.6 + (1 - flat_a[fid]) * lam)
            lines = 1 + layer_a[fid] * np.cos(2 * np.pi * P[:, 2] / LAYER_HEIGHT_MM) * (1 - np.abs(n[:, 2]))
            colour = albedo_a[fid] * (shading * lines)[:, None]
            half = L[None] + to_eye
            half /= np.linalg.norm(half, axis=1, keepdims=True)
            colour += (spec_a[fid] * np.clip((n * half).sum(1), 0, 1) ** 30)[:, None]
            return colour * light_rgb, fid

        pix = face_id >= 0
        if pix.any():
            out[pix] = shade(pix, face_id, inv_depth)[0]
        spix = strand_id >= 0
        if spix.any():
            colour, fid = shade(spix, strand_id, strand_depth)
            cov = cover_a[fid][:, None]
            out[spix] = cov * colour + (1 - cov) * out[spix]

    frame = cv2.remap(out, cv.map_x, cv.map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return cv2.resize(frame, (camera.width, camera.height), interpolation=cv2.INTER_AREA)


_GROUND_CACHE: dict = {}


def clear_caches() -> None:
    """Forget every cached canvas and bed lookup (start of a recording)."""
    _CANVAS_CACHE.clear()
    _GROUND_CACHE.clear()


def _static_ground(cv: Canvas, camera: Camera, bed: BedLook, decals) -> dict:
    """What does not change between frames of one camera: where each canvas ray meets the bed, the bed's
    albedo there (decals drawn in), the backdrop's albedo, the mirrored rays."""
    key = (id(cv), id(bed), id(decals))
    hit = _GROUND_CACHE.get(key)
    if hit is not None and hit["refs"][0] is cv and hit["refs"][1] is bed and hit["refs"][2] is decals:
        return hit
    rays, eye = cv.rays, camera.centre
    dz = rays[:, :, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        depth_bed = np.where(dz < -1e-6, -eye[2] / dz, np.inf).astype(np.float32)
    hits = np.isfinite(depth_bed)
    bx = np.where(hits, eye[0] + depth_bed * rays[:, :, 0], -1e4).astype(np.float32)
    by = np.where(hits, eye[1] + depth_bed * rays[:, :, 1], -1e4).astype(np.float32)
    on_bed = hits & (bx >= 0) & (bx <= bed.size_mm) & (by >= 0) & (by <= bed.size_mm)
    on_frame = hits & ~on_bed & (bx > -25) & (bx < bed.size_mm + 25) & (by > -25) & (by < bed.size_mm + 25)
    tex = bed.texture
    if decals is not None:
        alpha = decals[:, :, 3:4]
        tex = tex * (1 - alpha) + decals[:, :, :3] * alpha
    mpt = bed.mm_per_texel
    bed_albedo = _lookup(tex.astype(np.float32), bx / mpt - 0.5, by / mpt - 0.5, (0, 0, 0))
    ground_albedo = np.where(on_bed[:, :, None], bed_albedo,
                             np.asarray(bed.frame_colour, np.float32)[None, None]).astype(np.float32)
    az = np.arctan2(rays[:, :, 1], rays[:, :, 0])
    el = np.arctan2(rays[:, :, 2], np.hypot(rays[:, :, 0], rays[:, :, 1]))
    hb, wb = bed.backdrop.shape[:2]
    back = _lookup(bed.backdrop.astype(np.float32), (az + np.pi) / (2 * np.pi) * wb - 0.5,
                   (np.pi / 2 - el) / np.pi * hb - 0.5, (0.3, 0.3, 0.3))
    st = {"on_bed": on_bed, "bx": bx, "by": by, "ground_albedo": ground_albedo, "back_albedo": back,
          "ground_mask": on_bed | on_frame,
          "refs": (cv, bed, decals)}      # held, so their ids cannot be reused while cached
    if bed.specular > 0:
        refl = rays / np.linalg.norm(rays, axis=2, keepdims=True)
        st["refl"] = (refl * np.array([1, 1, -1], np.float32)).astype(np.float32)   # mirrored about the bed
    if len(_GROUND_CACHE) > 12:
        _GROUND_CACHE.clear()
    _GROUND_CACHE[key] = st
    return st


def _rasterise_meshes(meshes: list[Mesh], camera: Camera, cv: Canvas, inv_depth: np.ndarray, face_id: np.ndarray,
                      cull_all: bool = False):
    """Rasterise ``meshes`` into ``inv_depth`` / ``face_id`` ((Hc, Wc) canvas buffers, face ids numbered
    across the meshes in order) and yield (mesh, (n, 3) unit face normals) for each non-empty mesh. Back
    faces are culled for one-sided meshes, or for all with ``cull_all``."""
    R, t = camera.R, np.asarray(camera.tvec, float)
    first = 0
    for mesh in meshes:
        tris = np.asarray(mesh.vertices, float)[np.asarray(mesh.faces)]
        if len(tris) == 0:
            continue
        n = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
        n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
        cull = np.full(len(tris), cull_all or not mesh.two_sided)
        rasterise(tris @ R.T + t, cv.K, cv.width, cv.height, cull, inv_depth, face_id, first)
        first += len(tris)
        yield mesh, n


def render_meshes_only(cv: Canvas, camera: Camera, meshes: list[Mesh], light: Light) -> tuple[np.ndarray, np.ndarray]:
    """Shaded meshes on the canvas without bed or shadows: ((Hc, Wc, 3) colour, (Hc, Wc) bool coverage)."""
    inv_depth = np.zeros((cv.height, cv.width), np.float32)
    face_id = np.full((cv.height, cv.width), -1, np.int32)
    normals, albedo = [], []
    for mesh, n in _rasterise_meshes(meshes, camera, cv, inv_depth, face_id, cull_all=True):
        normals.append(n)
        albedo.append(np.tile(np.asarray(mesh.colour, float), (len(n), 1)))
    first = sum(len(n) for n in normals)
    out = np.zeros((cv.height, cv.width, 3), np.float32)
    pix = face_id >= 0
    if first:
        n = np.concatenate(normals).astype(np.float32)[face_id[pix]]
        lam = np.clip(n @ np.asarray(light.direction, np.float32), 0, 1)
        out[pix] = np.concatenate(albedo).astype(np.float32)[face_id[pix]] * (light.ambient + light.diffuse * lam)[:, None]
    return out, pix


# ------------------------------------------------------------------------------------------- sensor

def expose(radiance: np.ndarray, sensor: Sensor, gain: float, white_balance: np.ndarray,
           rng: np.random.Generator) -> np.ndarray:
    """(H, W, 3) linear RGB radiance -> (H, W, 3) uint8 BGR as a webcam delivers it."""
    img = radiance * (gain * np.asarray(white_balance, np.float32))[None, None]
    h, w = img.shape[:2]
    yy, xx = np.ogrid[0:h, 0:w]
    r2 = (((xx - w / 2) ** 2 + (yy - h / 2) ** 2) / ((w / 2) ** 2 + (h / 2) ** 2)).astype(np.float32)
    img = img * (1 - sensor.vignetting * r2)[:, :, None]
    if sensor.blur_sigma > 0:
        img = cv2.GaussianBlur(img, (0, 0), sensor.blur_sigma)
    img = np.clip(img, 0, 1.5)
    # shot noise (Gaussian with the Poisson variance: photon counts are in the hundreds) + read noise
    sigma = np.sqrt(img / sensor.full_well + sensor.read_noise ** 2)
    img = img + sigma * rng.standard_normal(img.shape, dtype=np.float32)
    img = np.clip(img, 0, 1) ** (1 / sensor.gamma)
    if sensor.sharpen > 0:
        img = img + sensor.sharpen * (img - cv2.GaussianBlur(img, (0, 0), 1.2))
    bgr = np.clip(img[:, :, ::-1] * 255 + 0.5, 0, 255).astype(np.uint8)
    return np.ascontiguousarray(bgr)


def write_image(path, bgr: np.ndarray, jpeg_quality: int | None) -> None:
    """JPEG at ``jpeg_quality`` or PNG when None (suffix chosen by the caller)."""
    params = [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)] if jpeg_quality else []
    if not cv2.imwrite(str(path), bgr, params):
        raise OSError(f"{path}: could not write the image")
