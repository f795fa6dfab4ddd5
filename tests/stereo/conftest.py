"""Fixtures for the stereo tests: real images nobody on the project made (tests/data/stereo)."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera

STEREO = Path(__file__).resolve().parents[1] / "data" / "stereo"
PATTERN = (9, 6)


@dataclass
class ChessboardRig:
    left: Camera
    right: Camera
    rms: float
    corners_left: list  # per view, (54, 2) distorted pixels
    corners_right: list
    images_left: list
    images_right: list


@pytest.fixture(scope="session")
def chessboard_rig() -> ChessboardRig:
    """The OpenCV sample pairs stereo-calibrated with plain cv2 calls (square = 1 unit)."""
    folder = STEREO / "opencv_chessboard_pairs"
    grid = np.zeros((PATTERN[0] * PATTERN[1], 3), np.float32)
    grid[:, :2] = np.mgrid[0:PATTERN[0], 0:PATTERN[1]].T.reshape(-1, 2)
    obj, cl, cr, il, ir = [], [], [], [], []
    criteria = (cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 30, 0.01)
    for left_path in sorted(folder.glob("left*.jpg")):
        right_path = folder / left_path.name.replace("left", "right")
        gl = cv2.imread(str(left_path), cv2.IMREAD_GRAYSCALE)
        gr = cv2.imread(str(right_path), cv2.IMREAD_GRAYSCALE)
        ok_l, c_l = cv2.findChessboardCorners(gl, PATTERN)
        ok_r, c_r = cv2.findChessboardCorners(gr, PATTERN)
        if not (ok_l and ok_r):
            continue
        c_l = cv2.cornerSubPix(gl, c_l, (11, 11), (-1, -1), criteria)
        c_r = cv2.cornerSubPix(gr, c_r, (11, 11), (-1, -1), criteria)
        obj.append(grid)
        cl.append(c_l)
        cr.append(c_r)
        il.append(gl)
        ir.append(gr)
    size = il[0].shape[::-1]
    _, K1, d1, _, _ = cv2.calibrateCamera(obj, cl, size, None, None)
    _, K2, d2, _, _ = cv2.calibrateCamera(obj, cr, size, None, None)
    rms, K1, d1, K2, d2, R, T, _, _ = cv2.stereoCalibrate(
        obj, cl, cr, K1, d1, K2, d2, size, flags=cv2.CALIB_FIX_INTRINSIC + 0,
        criteria=(cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-5))
    # Refine all together, as OpenCV's stereo_calib sample does.
    rms, K1, d1, K2, d2, R, T, _, _ = cv2.stereoCalibrate(
        obj, cl, cr, K1, d1, K2, d2, size, flags=cv2.CALIB_USE_INTRINSIC_GUESS,
        criteria=(cv2.TERM_CRITERIA_EPS + cv2.TERM_CRITERIA_MAX_ITER, 100, 1e-5))
    left = Camera("left", size[0], size[1], K1, d1.ravel(), np.zeros(3), np.zeros(3))
    right = Camera("right", size[0], size[1], K2, d2.ravel(), cv2.Rodrigues(R)[0].ravel(), T.ravel())
    return ChessboardRig(left, right, float(rms), [c.reshape(-1, 2) for c in cl], [c.reshape(-1, 2) for c in cr],
                         il, ir)
