"""Quick intrinsics when no calibration exists (seed section 5.3.2.1, Eq. 5.1-5.4).

Good to a few per cent: enough to place expected silhouettes roughly, not to
measure millimetres. A full :func:`calibrate_intrinsics` replaces it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..boards import Board, detect_board
from ..camera import Camera
from ..errors import CalibrationError


def pixel_size_um(sensor_mm: float, image_px: int) -> float:
    """Eq. 5.1/5.2: pixel pitch (micrometres) from the sensor side (mm) and the image side (px)."""
    if sensor_mm <= 0 or image_px <= 0:
        raise CalibrationError("sensor size and image size must be positive")
    return 1000.0 * sensor_mm / image_px


def focal_px_from_square(square_px: float, distance_mm: float, square_mm: float) -> float:
    """Eq. 5.3: F = P * D / W, the focal length in pixels from a square of ``square_mm`` that
    appears ``square_px`` wide at ``distance_mm`` from the camera (board facing it squarely)."""
    if square_px <= 0 or distance_mm <= 0 or square_mm <= 0:
        raise CalibrationError("square size in pixels, distance and square size must be positive")
    return square_px * distance_mm / square_mm


def focal_mm_from_px(focal_px: float, pixel_um: float) -> float:
    """Eq. 5.4: the focal length in mm is the focal length in pixels times the pixel pitch."""
    return focal_px * pixel_um / 1000.0


def focal_px_from_fov(image_width_px: int, hfov_deg: float) -> float:
    """Focal length in pixels from the horizontal field of view the maker quotes."""
    if not 1.0 < hfov_deg < 179.0:
        raise CalibrationError(f"horizontal field of view must be between 1 and 179 degrees, got {hfov_deg:g}")
    return (image_width_px / 2.0) / np.tan(np.radians(hfov_deg) / 2.0)


def quick_camera(width: int, height: int, focal_px: float, name: str = "camera") -> Camera:
    """Ideal pinhole: principal point in the centre, square pixels, no distortion."""
    K = np.array([[focal_px, 0.0, (width - 1) / 2.0], [0.0, focal_px, (height - 1) / 2.0], [0.0, 0.0, 1.0]])
    return Camera(name=name, width=width, height=height, K=K)


@dataclass
class QuickFocal:
    focal_px: float
    square_px: float
    corners: int
    camera: Camera


def estimate_focal_from_image(image: np.ndarray, board: Board, distance_mm: float,
                              name: str = "camera", label: str = "image") -> QuickFocal:
    """Eq. 5.3 on a frame of the board held square to the camera ``distance_mm`` from the lens.

    The square size in pixels is the median spacing of neighbouring corners near the
    image centre, where lens distortion is least.
    """
    found = detect_board(image, board)
    if found is None:
        raise CalibrationError(f"{label}: board ({board.describe()}) not found")
    obj = found.object_points(board)[:, :2]
    d_obj = np.linalg.norm(obj[:, None] - obj[None], axis=2)
    i, j = np.nonzero(np.isclose(d_obj, board.square_mm))
    d_img = np.linalg.norm(found.pixels[i] - found.pixels[j], axis=1)
    square_px = float(np.median(d_img))
    height, width = image.shape[:2]
    focal = focal_px_from_square(square_px, distance_mm, board.square_mm)
    return QuickFocal(focal, square_px, len(found), quick_camera(width, height, focal, name))
