"""Small synthetic scenes with known answers for the shape-check unit tests.

Image-space scenes: a textured bed, a rectangular "part" with layer lines,
optional shadow, exposure change, 1-px shake, JPEG round trip. Every quantity a
test asserts on (how much is missing, how far the part moved) follows from the
parameters, so the tests know the right answer without running the code.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from octoprint_printwatch.core.shape_check import ExpectedRegions

H, W = 240, 320


def bed_texture(seed: int = 0, colour=(150, 120, 60), grain: float = 10.0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    bed = np.empty((H, W, 3), np.float32)
    bed[:] = colour
    bed += cv2.GaussianBlur(rng.normal(0, grain, (H, W, 3)).astype(np.float32), (0, 0), 1.2)
    bed *= np.linspace(0.85, 1.1, W, dtype=np.float32)[None, :, None]  # uneven light
    return np.clip(bed, 0, 255).astype(np.uint8)


@dataclass
class Box:
    x0: int
    y0: int
    x1: int
    y1: int

    def mask(self) -> np.ndarray:
        m = np.zeros((H, W), bool)
        m[max(self.y0, 0):self.y1, max(self.x0, 0):self.x1] = True
        return m

    def moved(self, dx: int = 0, dy: int = 0) -> "Box":
        return Box(self.x0 + dx, self.y0 + dy, self.x1 + dx, self.y1 + dy)


PART = Box(110, 80, 210, 170)


def paint_part(image: np.ndarray, box: Box, colour=(40, 40, 210), seed: int = 1) -> np.ndarray:
    """Paint a shaded part with layer lines into a copy of ``image``."""
    out = image.astype(np.float32).copy()
    rng = np.random.default_rng(seed)
    ys = np.arange(box.y0, box.y1)
    shade = 0.85 + 0.15 * np.cos(ys * 2.0)[:, None]  # layer lines
    xs = np.linspace(1.1, 0.8, box.x1 - box.x0)[None, :]  # light from the left
    patch = np.array(colour, np.float32)[None, None, :] * (shade * xs)[..., None]
    patch += rng.normal(0, 3, patch.shape)
    y0, x0 = max(box.y0, 0), max(box.x0, 0)
    out[y0:box.y1, x0:box.x1] = patch[y0 - box.y0:, x0 - box.x0:]
    return np.clip(out, 0, 255).astype(np.uint8)


def darken(image: np.ndarray, mask: np.ndarray, factor: float) -> np.ndarray:
    out = image.astype(np.float32)
    out[mask] *= factor
    return np.clip(out, 0, 255).astype(np.uint8)


def camera_effects(image: np.ndarray, *, gain=(1.0, 1.0, 1.0), shake=(0, 0), noise: float = 2.5,
                   jpeg: int | None = 85, seed: int = 3) -> np.ndarray:
    """Exposure/white-balance gain, integer shake, sensor noise and a JPEG round trip."""
    out = image.astype(np.float32) * np.asarray(gain, np.float32)
    if shake != (0, 0):
        out = cv2.warpAffine(out, np.float32([[1, 0, shake[0]], [0, 1, shake[1]]]), (W, H),
                             borderMode=cv2.BORDER_REFLECT)
    out += np.random.default_rng(seed).normal(0, noise, out.shape)
    out = np.clip(out, 0, 255).astype(np.uint8)
    if jpeg:
        out = cv2.imdecode(cv2.imencode(".jpg", out, [cv2.IMWRITE_JPEG_QUALITY, jpeg])[1], cv2.IMREAD_COLOR)
    return out


def regions(expected: Box = PART, band_rows: int = 30, *, max_shift: float = 10, tolerance: float = 2,
            dont_care: np.ndarray | None = None, search_margin: int = 50) -> ExpectedRegions:
    silhouette = expected.mask()
    band = np.zeros_like(silhouette)
    band[expected.y0:expected.y0 + band_rows, expected.x0:expected.x1] = True
    search = np.zeros_like(silhouette)
    search[max(expected.y0 - 15, 0):min(expected.y1 + search_margin, H),
           max(expected.x0 - search_margin, 0):min(expected.x1 + search_margin, W)] = True
    return ExpectedRegions(silhouette=silhouette, new_band=band & silhouette, search=search,
                           dont_care=np.zeros_like(silhouette) if dont_care is None else dont_care,
                           max_shift_px=max_shift, tolerance_px=tolerance)
