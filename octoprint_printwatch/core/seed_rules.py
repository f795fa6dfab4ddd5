"""The seed's own single-camera rule (dissertation ch. 3-4), kept to compare against in the benchmark.

As the dissertation describes it (section 4.3): subtract the background frame
from the object frame and binarise (grey -> binary, object white), combine with
the previous check's mask, remove lens distortion, find the edge bounding boxes
of the camera image and of the expected ("stl") image, rescale the expected
image by the ratio of the widths, align the two on (minX, maxY), and compute
Eq. 4.1 ``error % = sum|camera - expected| / sum(expected) * 100``; a camera
fails above 7 % (webcams) and the check fails when any camera fails.

The dissertation does not give the binarisation threshold; we use a grey-level
difference of 30 (of 255), stated here so the comparison is reproducible.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from .camera import Camera

SEED_THRESHOLD_PCT = 7.0
SEED_GREY_DIFFERENCE = 30


@dataclass
class SeedResult:
    camera: str
    error_pct: float
    passed: bool
    mask: np.ndarray  # (h, w) bool, the seed's binarised object mask (undistorted image)


def seed_object_mask(background: np.ndarray, frame: np.ndarray, camera: Camera | None = None,
                     previous: np.ndarray | None = None, grey_difference: int = SEED_GREY_DIFFERENCE) -> np.ndarray:
    """(h, w) bool: |frame - background| in grey above ``grey_difference``, undistorted, OR the previous mask."""
    diff = cv2.absdiff(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY), cv2.cvtColor(background, cv2.COLOR_BGR2GRAY))
    if camera is not None:
        diff = camera.undistort_image(diff)
    mask = diff > grey_difference
    if previous is not None and previous.shape == mask.shape:
        mask = mask | previous
    return mask


def _edge_box(mask: np.ndarray) -> tuple[int, int, int, int] | None:
    """(min_x, min_y, max_x, max_y) of the Canny edges of a binary image."""
    edges = cv2.Canny(mask.astype(np.uint8) * 255, 50, 150)
    ys, xs = np.nonzero(edges)
    if xs.size == 0:
        return None
    return int(xs.min()), int(ys.min()), int(xs.max()), int(ys.max())


def seed_error(observed: np.ndarray, expected: np.ndarray) -> float:
    """Eq. 4.1 after the seed's bounding-box rescale and (minX, maxY) alignment; both (h, w) bool."""
    total = float(expected.sum())
    if total == 0:
        return 0.0
    box_o, box_e = _edge_box(observed), _edge_box(expected)
    if box_o is None or box_e is None:
        return 100.0 * float(np.count_nonzero(observed ^ expected)) / total
    width_o = max(box_o[2] - box_o[0], 1)
    width_e = max(box_e[2] - box_e[0], 1)
    scale = width_o / width_e
    h, w = expected.shape
    # scale about the expected (minX, maxY) corner, then move that corner onto the observed one
    matrix = np.array([[scale, 0.0, box_o[0] - scale * box_e[0]],
                       [0.0, scale, box_o[3] - scale * box_e[3]]], np.float32)
    warped = cv2.warpAffine(expected.astype(np.uint8), matrix, (w, h), flags=cv2.INTER_NEAREST) > 0
    scaled_total = float(warped.sum()) or total
    return 100.0 * float(np.count_nonzero(observed ^ warped)) / scaled_total


def seed_check(name: str, background: np.ndarray, frame: np.ndarray, expected_undistorted: np.ndarray,
               camera: Camera | None = None, previous: np.ndarray | None = None,
               threshold: float = SEED_THRESHOLD_PCT) -> SeedResult:
    """The seed's rule for one camera at one check (images (h, w, 3) uint8 BGR)."""
    h, w = expected_undistorted.shape
    if frame.shape[:2] != (h, w):
        frame = cv2.resize(frame, (w, h), interpolation=cv2.INTER_AREA)
        background = cv2.resize(background, (w, h), interpolation=cv2.INTER_AREA)
    mask = seed_object_mask(background, frame, camera, previous)
    error = seed_error(mask, expected_undistorted.astype(bool))
    return SeedResult(camera=name, error_pct=error, passed=error <= threshold, mask=mask)
