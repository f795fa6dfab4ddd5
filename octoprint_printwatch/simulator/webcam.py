"""What a cheap webcam does to the light that reaches it: exposure, colour, optics, sensor, JPEG."""
from __future__ import annotations

import cv2
import numpy as np

from ..core.camera import Camera
from .look import Nuisances


_LUT_SIZE, _LUT_RANGE = 8192, 3.0


def _response_curve() -> np.ndarray:
    """Linear light (0.._LUT_RANGE) -> 8-bit sRGB, with a soft shoulder: highlights compress before they clip."""
    x = np.linspace(0, _LUT_RANGE, _LUT_SIZE)
    knee = 0.7
    y = np.where(x > knee, knee + (1 - knee) * (1 - np.exp(-(x - knee) / (1 - knee))), x)
    return (np.clip(y, 0, 1) ** (1 / 2.2) * 255.0 + 0.5).astype(np.uint8)


_RESPONSE = _response_curve()


def distortion_maps(camera: Camera) -> tuple[np.ndarray, np.ndarray] | None:
    """Remap tables taking the ideal pinhole image to this lens's distorted view, None without distortion."""
    if not np.any(camera.dist):
        return None
    u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64))
    ideal = camera.undistort_points(np.column_stack([u.ravel(), v.ravel()]))
    return (ideal[:, 0].reshape(camera.height, camera.width).astype(np.float32),
            ideal[:, 1].reshape(camera.height, camera.width).astype(np.float32))


def vignette(camera: Camera, strength: float) -> np.ndarray:
    """(h, w) float32 relative illumination, 1 at the centre, 1 - strength in the corners (cos^4-like)."""
    u, v = np.meshgrid(np.arange(camera.width, dtype=np.float32), np.arange(camera.height, dtype=np.float32))
    r2 = ((u - camera.K[0, 2]) ** 2 + (v - camera.K[1, 2]) ** 2) / (0.25 * (camera.width ** 2 + camera.height ** 2))
    return (1.0 - strength * np.clip(r2, 0, 1.5) ** 1.5).astype(np.float32)


def draw_hotend(linear: np.ndarray, rng: np.random.Generator) -> None:
    """The parked hotend poking into the top of the frame (fan shroud, heat sink, block, nozzle), in place."""
    h, w = linear.shape[:2]
    cx = rng.uniform(0.1, 0.9) * w
    size = rng.uniform(0.18, 0.45) * w
    reach = rng.uniform(0.05, 0.3) * h  # how far the nozzle tip reaches down into the frame
    tilt = rng.normal(0, 0.04)
    top = reach - 1.25 * size  # assembly spans 1.25 * size in height, most of it above the frame

    def poly(points, rgb, light=(0.55, 1.05), stripes=0):
        pts = np.array([(cx + x * size + tilt * y * size, top + y * size) for x, y in points])
        mask = np.zeros((h, w), np.uint8)
        cv2.fillPoly(mask, [np.round(pts * 16).astype(np.int32)], 1, cv2.LINE_AA, 4)
        if not mask.any():
            return
        rows, cols = np.nonzero(mask)
        colour = (np.asarray(rgb, np.float32) / 255.0) ** 2.2
        # Lit from one side: a horizontal ramp; fins: dark grooves every few pixels.
        ramp = light[0] + (light[1] - light[0]) * (cols - pts[:, 0].min()) / max(np.ptp(pts[:, 0]), 1)
        if stripes:
            ramp = ramp * np.where(((rows - top) / (size / stripes)).astype(int) % 2 == 0, 1.0, 0.45)
        linear[rows, cols] = colour[None, :] * ramp[:, None].astype(np.float32)

    shroud = rng.choice([(25, 25, 28), (235, 110, 20), (200, 200, 205), (30, 60, 160)])
    poly([(-0.7, 0.0), (0.7, 0.0), (0.65, 0.75), (0.3, 0.85), (-0.3, 0.85), (-0.65, 0.75)], shroud, (0.4, 1.0))
    poly([(-0.28, 0.55), (0.28, 0.55), (0.28, 0.92), (-0.28, 0.92)], (170, 172, 178), (0.4, 1.1), stripes=14)
    sock = [(150, 40, 40), (60, 60, 70), (180, 180, 185), (40, 90, 170)][int(rng.integers(4))]
    poly([(-0.26, 0.92), (0.3, 0.92), (0.3, 1.12), (-0.26, 1.12)], sock, (0.5, 1.0))
    poly([(-0.07, 1.12), (0.07, 1.12), (0.025, 1.25), (-0.025, 1.25)], (200, 150, 60), (0.5, 1.3))


def expose(linear: np.ndarray, camera: Camera, nuisances: Nuisances, rng: np.random.Generator, *,
           base_gain: float, maps, vignetting: np.ndarray | None) -> np.ndarray:
    """Linear RGB scene radiance (h, w, 3) -> the webcam's BGR uint8 frame."""
    img = linear
    if vignetting is not None:
        img = img * vignetting[..., None]
    gain = base_gain
    if nuisances.exposure_drift:
        gain *= float(np.exp(rng.normal(0, nuisances.exposure_drift)))
    if nuisances.white_balance_drift:
        wb = np.exp(rng.normal(0, nuisances.white_balance_drift, 3)).astype(np.float32)
        img = img * wb[None, None, :]
    img = img * np.float32(gain)
    if nuisances.exposure_drift:
        # Room light changing between checks (a lamp, daylight): a gentle gradient across the picture.
        h, w = img.shape[:2]
        gx, gy = rng.normal(0, 0.6 * nuisances.exposure_drift, 2)
        ramp = (1 + gx * np.linspace(-1, 1, w, dtype=np.float32)[None, :]
                + gy * np.linspace(-1, 1, h, dtype=np.float32)[:, None])
        img = img * ramp[..., None]
    if nuisances.banding:
        rows = np.arange(img.shape[0], dtype=np.float32)
        period = rng.uniform(20, 90)  # rows per flicker cycle; the phase rolls from frame to frame
        bands = 1 + nuisances.banding * np.sin(2 * np.pi * rows / period + rng.uniform(0, 2 * np.pi))
        img = img * bands[:, None, None].astype(np.float32)
    if nuisances.blur:
        # Autofocus hunts a little: the blur differs from frame to frame.
        img = cv2.GaussianBlur(img, (0, 0), nuisances.blur * float(np.exp(rng.normal(0, 0.15))))
    # Lens distortion and a little shake: one remap.
    shake = rng.normal(0, nuisances.shake_px, 2) if nuisances.shake_px else np.zeros(2)
    if maps is not None:
        img = cv2.remap(img, maps[0] + np.float32(shake[0]), maps[1] + np.float32(shake[1]),
                        cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    elif np.any(shake):
        m = np.float32([[1, 0, -shake[0]], [0, 1, -shake[1]]])
        img = cv2.warpAffine(img, m, (camera.width, camera.height), flags=cv2.INTER_LINEAR,
                             borderMode=cv2.BORDER_REPLICATE)
    if nuisances.noise:
        # Shot noise grows with brightness; read noise does not; webcam denoising leaves it blotchy.
        sigma = nuisances.noise / 255.0 * max(1.0, gain) ** 0.5  # gain turned up for a dark scene amplifies noise
        fine = rng.standard_normal(img.shape, dtype=np.float32)
        coarse = cv2.resize(rng.standard_normal((img.shape[0] // 2, img.shape[1] // 2, 3), dtype=np.float32),
                            (img.shape[1], img.shape[0]), interpolation=cv2.INTER_LINEAR)
        img = img + (0.5 * fine + 0.8 * coarse) * sigma * (0.4 + 1.6 * np.sqrt(np.clip(img, 0, 1)))
    index = np.clip(img[..., ::-1] * np.float32(_LUT_SIZE / _LUT_RANGE), 0, _LUT_SIZE - 1).astype(np.uint16)
    bgr = _RESPONSE[index]
    if nuisances.jpeg_quality:
        ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, int(nuisances.jpeg_quality)])
        bgr = cv2.imdecode(buf, cv2.IMREAD_COLOR)
    return bgr
