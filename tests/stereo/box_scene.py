"""A tiny ray-cast scene for the size-check tests: a textured box on a textured bed.

Independent of the project's simulator on purpose: the size check is tested
against geometry computed here in a few lines (slab ray-box intersection), so a
bug shared with the simulator cannot hide. Textures are a smooth function of
the 3-D point (sums of sinusoids, periods 1-4 mm), so both cameras see the same
surface pattern, as with real layer lines and bed grain.
"""
from __future__ import annotations

import numpy as np
import trimesh

from octoprint_printwatch.core.camera import Camera


def _texture(points: np.ndarray, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    value = np.zeros(len(points))
    for _ in range(24):
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        period = rng.uniform(1.0, 6.0)
        value += np.sin(points @ direction * 2 * np.pi / period + rng.uniform(0, 2 * np.pi))
    return value / np.sqrt(12)


def render(camera: Camera, box_min, box_max, *, part: bool = True, seed: int = 0, noise: float = 2.0) -> np.ndarray:
    """(h, w, 3) uint8 BGR frame (with the camera's lens distortion) of the box on the bed (z = 0)."""
    h, w = camera.height, camera.width
    u, v = np.meshgrid(np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64))
    origin, d = camera.rays(np.column_stack([u.ravel(), v.ravel()]), distorted=False)
    grey = np.full(len(d), 20.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_bed = -origin[2] / d[:, 2]
    hit_bed = np.isfinite(t_bed) & (t_bed > 0)
    at_bed = origin + d * np.where(hit_bed, t_bed, 0)[:, None]
    hit_bed &= np.all((at_bed[:, :2] >= 0) & (at_bed[:, :2] <= 200), axis=1)  # a 200 x 200 bed
    t_hit = np.where(hit_bed, t_bed, np.inf)
    normal_z = hit_bed.copy()
    face = np.full(len(d), -1)
    if part:
        lo, hi = np.asarray(box_min, float), np.asarray(box_max, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            t1 = (lo - origin) / d
            t2 = (hi - origin) / d
        t_near = np.nanmax(np.minimum(t1, t2), axis=1)
        t_far = np.nanmin(np.maximum(t1, t2), axis=1)
        hit_box = (t_near <= t_far) & (t_near > 0) & (t_near < t_hit)
        t_hit = np.where(hit_box, t_near, t_hit)
        face[hit_box] = np.argmax(np.minimum(t1, t2), axis=1)[hit_box]  # axis of the entry face
    points = origin + d * np.where(np.isfinite(t_hit), t_hit, 0)[:, None]
    bed = np.isfinite(t_hit) & (face < 0)
    grey[bed] = 110 + 35 * _texture(points[bed], seed + 1)
    shade = {0: 0.8, 1: 0.65, 2: 1.0}
    for axis, s in shade.items():
        sel = face == axis
        grey[sel] = s * (150 + 40 * _texture(points[sel], seed + 2))
    # A red part on a grey-green bed: colour tells them apart, as filament and bed do.
    tint = np.where((face >= 0)[:, None], [[0.35, 0.45, 1.0]], [[0.85, 1.0, 0.8]])
    rng = np.random.default_rng(seed + 99)
    colour = grey[:, None] * tint + rng.normal(0, noise, (len(grey), 3))
    bgr = np.clip(colour, 0, 255).reshape(h, w, 3).astype(np.uint8)
    return camera.distort_image(bgr)


def box_mesh(box_min, box_max) -> trimesh.Trimesh:
    lo, hi = np.asarray(box_min, float), np.asarray(box_max, float)
    return trimesh.creation.box(extents=hi - lo, transform=trimesh.transformations.translation_matrix((lo + hi) / 2))


def relaxed_pair(seed: int = 0):
    """True cameras of a relaxed pair looking at the bed centre (100, 100), 640 x 480 with distortion."""
    rng = np.random.default_rng(seed)
    target = np.array([100.0, 100.0, 10.0])
    left = Camera.look_at("camL", target + [-25, -185, 55], target, focal_px=820,
                          dist=[-0.12, 0.05, 0, 0, 0], roll_deg=1.0)
    right = Camera.look_at("camR", target + [35, -150, 48], target + [2, 0, 1], focal_px=760,
                           dist=[-0.08, 0.02, 0, 0, 0], roll_deg=-0.8)
    del rng
    return left, right
