"""The stereo maths on real optics: OpenCV's chessboard pairs, Middlebury Motorcycle and Aloe."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.stereo.matching import MatchSettings, compute_disparity
from octoprint_printwatch.core.stereo.rectify import (FeatureMatches, rectify_calibrated, rectify_seed,
                                                      rectify_uncalibrated, sift_matches)
from octoprint_printwatch.core.stereo.triangulate import reproject_disparity

from .conftest import PATTERN, STEREO

MOTO_F, MOTO_B, MOTO_DOFFS = 994.978, 193.001, 31.086


def test_chessboard_pairs_stereo_calibrate_below_half_a_pixel(chessboard_rig):
    assert chessboard_rig.rms < 0.5
    baseline_squares = np.linalg.norm(chessboard_rig.right.center - chessboard_rig.left.center)
    assert 3.1 < baseline_squares < 3.5


def _row_mismatch(rect, corners_left, corners_right):
    yl = rect.from_camera_pixels(rect.left.undistort_points(corners_left), "left")[:, 1]
    yr = rect.from_camera_pixels(rect.right.undistort_points(corners_right), "right")[:, 1]
    return np.abs(yl - yr)


def test_calibrated_rectification_puts_real_corners_on_the_same_rows(chessboard_rig):
    rig = chessboard_rig
    rect = rectify_calibrated(rig.left, rig.right)
    mismatch = np.concatenate([_row_mismatch(rect, a, b) for a, b in zip(rig.corners_left, rig.corners_right)])
    assert np.median(mismatch) < 0.5
    assert np.percentile(mismatch, 95) < 1.5
    # The warped images themselves (remap with undistortion folded in) agree row by row.
    view = 0
    wl = rect.warp(rig.images_left[view], "left")
    wr = rect.warp(rig.images_right[view], "right")
    ok_l, cl = cv2.findChessboardCorners(wl, PATTERN)
    ok_r, cr = cv2.findChessboardCorners(wr, PATTERN)
    assert ok_l and ok_r
    cl, cr = cl.reshape(-1, 2), cr.reshape(-1, 2)
    assert np.median(np.abs(cl[:, 1] - cr[:, 1])) < 1.0
    # Disparities are positive (x_left > x_right) for a left camera that is really on the left.
    assert np.all(cl[:, 0] > cr[:, 0])


def test_uncalibrated_rectification_from_real_correspondences(chessboard_rig):
    rig = chessboard_rig
    left = rig.left.undistort_points(np.vstack(rig.corners_left))
    right = rig.right.undistort_points(np.vstack(rig.corners_right))
    F, inliers = cv2.findFundamentalMat(left, right, cv2.FM_RANSAC, 1.0, 0.999)
    keep = inliers.ravel().astype(bool)
    matches = FeatureMatches(left[keep], right[keep], np.zeros(keep.sum()), F)
    rect = rectify_uncalibrated(rig.left, rig.right, matches)
    assert rect.trusted, rect.reason
    assert rect.residual_px < 1.0
    mismatch = np.concatenate([_row_mismatch(rect, a, b) for a, b in zip(rig.corners_left, rig.corners_right)])
    assert np.median(mismatch) < 1.0


def test_uncalibrated_rectification_abstains_on_too_few_matches(chessboard_rig):
    rig = chessboard_rig
    few = FeatureMatches(rig.corners_left[0][:6], rig.corners_right[0][:6], np.zeros(6), None)
    rect = rectify_uncalibrated(rig.left, rig.right, few)
    assert not rect.trusted
    assert "feature matches" in rect.reason


def _aloe():
    left = cv2.imread(str(STEREO / "aloeL.jpg"))
    right = cv2.imread(str(STEREO / "aloeR.jpg"))
    gt = cv2.imread(str(STEREO / "aloeGT.png"), cv2.IMREAD_UNCHANGED).astype(np.float32)
    gt[gt == 0] = np.nan
    return left, right, gt


def test_seed_rescale_and_shift_undo_a_known_scale_and_offset():
    left, right, _ = _aloe()
    left, right = cv2.resize(left, None, fx=0.5, fy=0.5), cv2.resize(right, None, fx=0.5, fy=0.5)
    h, w = right.shape[:2]
    scale, shift = 0.9, 14.0  # the right camera "farther away" and lower
    right = cv2.warpAffine(right, np.float64([[scale, 0, 0], [0, scale, shift]]), (w, h))
    cam = Camera("c", w, h, [[800.0, 0, w / 2], [0, 800.0, h / 2], [0, 0, 1]])
    matches = sift_matches(left, right, cam, cam)
    rect = rectify_seed(cam, cam, matches)
    assert rect.trusted, rect.reason
    # Only the larger image is scaled (Eq. A-3): here the left, by about 0.9.
    assert rect.H_left[0, 0] == pytest.approx(scale, rel=0.03)
    assert rect.H_right[0, 0] == pytest.approx(1.0)
    assert rect.residual_px < 1.0


def test_motorcycle_metric_depth_within_one_percent():
    folder = STEREO / "middlebury_motorcycle"
    left = cv2.imread(str(folder / "motorcycle_left.png"))
    right = cv2.imread(str(folder / "motorcycle_right.png"))
    gt = np.load(folder / "motorcycle_disp.npz")["arr_0"]
    h, w = gt.shape
    cx, cy = (w - 1) / 2, (h - 1) / 2
    # Q for rectified images whose principal points differ by doffs (cx_right = cx_left - doffs).
    Q = np.array([[1, 0, 0, -cx], [0, 1, 0, -cy], [0, 0, 0, MOTO_F], [0, 0, 1 / MOTO_B, MOTO_DOFFS / MOTO_B]])
    known = np.isfinite(gt)
    ys, xs = np.nonzero(known)
    truth_z = MOTO_F * MOTO_B / (gt[known] + MOTO_DOFFS)
    for settings, region in ((MatchSettings("sgbm", 0, 64, 5), None),
                             (MatchSettings("sad", 0, 64, 9), (slice(150, 350), slice(250, 500)))):
        mask = None
        if region is not None:
            mask = np.zeros_like(known)
            mask[region] = True
        disparity = compute_disparity(left, right, settings, mask)
        d = disparity[known]
        ok = np.isfinite(d)
        matched_share = ok.sum() / (known.sum() if mask is None else (known & mask).sum())
        assert matched_share > 0.5
        z = reproject_disparity(np.column_stack([xs[ok], ys[ok]]), d[ok], Q)[:, 2]
        error = np.abs(z - truth_z[ok]) / truth_z[ok]
        assert np.median(error) < 0.01, settings.method


def test_aloe_sgbm_disparity_against_ground_truth():
    left, right, gt = _aloe()
    disparity = compute_disparity(left, right, MatchSettings("sgbm", 0, 256, 5))
    both = np.isfinite(disparity) & np.isfinite(gt)
    assert both.sum() > 0.6 * np.isfinite(gt).sum()
    error = np.abs(disparity[both] - gt[both])
    assert np.median(error) < 0.5
    assert np.mean(error > 3) < 0.1
