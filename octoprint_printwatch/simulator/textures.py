"""Procedural bed surfaces and backdrops, in linear RGB (0..1 floats)."""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

#: Bed texture resolution, mm per texel.
BED_TEXEL_MM = 0.25


def srgb_to_linear(rgb) -> np.ndarray:
    return (np.asarray(rgb, dtype=np.float32) / 255.0) ** 2.2


def _smooth_noise(rng, shape, scale_px: float) -> np.ndarray:
    """(h, w) float32 band-limited noise, zero mean, unit-ish amplitude, feature size ~scale_px."""
    h, w = shape
    small = rng.normal(size=(max(2, int(h / scale_px) + 2), max(2, int(w / scale_px) + 2))).astype(np.float32)
    big = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    return big / max(float(big.std()), 1e-6)


@dataclass
class BedSurface:
    """Albedo texture plus how shiny the surface is.

    Attributes
    ----------
    albedo : (rows, cols, 3) float32, linear RGB; row = y / BED_TEXEL_MM, col = x / BED_TEXEL_MM
    specular : float      strength of light highlights
    shininess : float     Blinn-Phong exponent (higher = sharper highlight)
    reflectivity : (rows, cols) float32  mirror reflection of the part (glass, smooth PEI)
    """

    albedo: np.ndarray
    specular: float
    shininess: float
    reflectivity: np.ndarray


def bed_surface(kind: str, bed: tuple[float, float], seed: int) -> BedSurface:
    rng = np.random.default_rng([seed, 0xBED])
    rows, cols = int(round(bed[1] / BED_TEXEL_MM)), int(round(bed[0] / BED_TEXEL_MM))
    shape = (rows, cols)
    fine = rng.normal(size=shape).astype(np.float32)
    blotch = _smooth_noise(rng, shape, 120)
    refl = np.zeros(shape, np.float32)
    if kind == "blue_tape":
        base = srgb_to_linear((60, 125, 200))
        albedo = np.empty((rows, cols, 3), np.float32)
        albedo[:] = base
        strip_px = int(48 / BED_TEXEL_MM)  # 2-inch painter's tape laid along X
        y0 = int(rng.integers(0, strip_px))
        for start in range(y0 - strip_px, rows, strip_px - int(rng.integers(0, 8))):
            a, b = max(start, 0), min(start + strip_px, rows)
            if a >= b:
                continue
            albedo[a:b] *= 1 + rng.normal(0, 0.05, 3).astype(np.float32)
            albedo[a:min(a + 4, rows)] *= 0.82  # overlap seam: a darker double layer edge
        albedo *= (1 + 0.06 * blotch + 0.05 * cv2.GaussianBlur(fine, (0, 0), 1.0) * 3)[..., None]
        # Wrinkles and nozzle scuffs: a few thin light scratches along random directions.
        scratch = np.zeros(shape, np.float32)
        for _ in range(int(rng.integers(6, 16))):
            p = rng.uniform(0, 1, 2) * (cols, rows)
            q = p + rng.normal(0, 60, 2)
            cv2.line(scratch, tuple(int(v) for v in p), tuple(int(v) for v in q), 1.0, 1)
        albedo += 0.08 * cv2.GaussianBlur(scratch, (0, 0), 1.0)[..., None]
        return BedSurface(albedo, 0.05, 8.0, refl)
    if kind in ("black_pei", "gold_pei", "green_pei"):
        base = {"black_pei": (30, 30, 33), "gold_pei": (175, 135, 62), "green_pei": (70, 95, 60)}[kind]
        speckle = cv2.GaussianBlur(fine, (0, 0), 0.7) * 3.0
        albedo = srgb_to_linear(base)[None, None, :] * (1 + 0.18 * speckle + 0.05 * blotch)[..., None]
        if kind == "green_pei":  # smooth PEI: glossy, mirrors the part faintly
            refl[:] = np.clip(0.10 + 0.03 * blotch, 0, 1)
        # Worn patch in the middle where most prints went.
        yy, xx = np.mgrid[0:rows, 0:cols].astype(np.float32)
        worn = np.exp(-(((xx - cols / 2) / (cols * 0.2)) ** 2 + ((yy - rows / 2) / (rows * 0.2)) ** 2))
        albedo *= (1 + 0.08 * worn)[..., None]
        return BedSurface(albedo.astype(np.float32), 0.25 if kind != "gold_pei" else 0.15, 20.0, refl)
    if kind in ("glass", "aluminium"):
        base = (38, 38, 42) if kind == "glass" else (150, 150, 155)
        albedo = np.empty((rows, cols, 3), np.float32)
        albedo[:] = srgb_to_linear(base)
        albedo *= (1 + 0.04 * blotch)[..., None]
        if kind == "glass":  # a faint grid printed on the heater beneath the glass
            step = int(10 / BED_TEXEL_MM)
            albedo[::step, :] *= 1.6
            albedo[:, ::step] *= 1.6
            # Fingerprints and glue-stick smears: cloudy patches that scatter light.
            smear = np.clip(_smooth_noise(rng, shape, 160) - 0.8, 0, None)
            albedo += 0.008 * smear[..., None]
            refl[:] = np.clip(0.22 - 0.06 * smear, 0.05, 1)
        return BedSurface(albedo.astype(np.float32), 0.6 if kind == "glass" else 0.3, 60.0, refl)
    raise ValueError(f"unknown bed {kind!r}")


def backdrop_panorama(kind: str, seed: int, *, width: int = 1440, height: int = 480) -> np.ndarray:
    """(height, width, 3) float32 linear RGB indexed by (elevation -40..+70 deg, azimuth 0..360 deg)."""
    rng = np.random.default_rng([seed, 0xBAC])
    elev = np.linspace(70, -40, height, dtype=np.float32)[:, None]
    grad = np.clip(1.0 - (elev + 40) / 220.0, 0.4, 1.0)  # darker toward the ceiling
    noise = _smooth_noise(rng, (height, width), 40)
    if kind == "black":
        img = np.full((height, width, 3), 0.012, np.float32) * (1 + 0.3 * noise)[..., None]
    elif kind == "grey":
        img = srgb_to_linear((120, 120, 118))[None, None] * (grad * (1 + 0.08 * noise))[..., None]
    elif kind == "white_wall":
        img = srgb_to_linear((225, 222, 212))[None, None] * (grad * (1 + 0.04 * noise))[..., None]
    elif kind in ("frame", "cluttered"):
        img = srgb_to_linear((45, 45, 50))[None, None] * (grad * (1 + 0.1 * noise))[..., None]
        n_items = 6 if kind == "frame" else 30
        for _ in range(n_items):
            if kind == "frame":  # aluminium extrusions and a gantry bar
                x = int(rng.integers(0, width))
                w = int(rng.integers(8, 22))
                img[:, x:x + w] = srgb_to_linear((150, 152, 155)) * rng.uniform(0.6, 1.1)
                img[:, x + w // 3:x + w // 3 + 2] *= 0.4
            else:  # shelves, boxes and spools in the room
                x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
                w, h = int(rng.integers(20, 160)), int(rng.integers(15, 140))
                img[y:y + h, x:x + w] = srgb_to_linear(rng.integers(20, 235, 3)) * rng.uniform(0.4, 1.0)
        if kind == "frame":
            y = int(rng.integers(40, 140))
            img[y:y + 18] = srgb_to_linear((140, 140, 145))
        img = cv2.GaussianBlur(img, (0, 0), 1.5)
    else:
        raise ValueError(f"unknown backdrop {kind!r}")
    return np.clip(img, 0, 1).astype(np.float32)
