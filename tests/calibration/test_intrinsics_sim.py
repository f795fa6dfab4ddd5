"""Intrinsics on simulated hand-held views: ChArUco partial views, and the verdict's reasons."""
import numpy as np
import pytest

from octoprint_printwatch.core.boards import detect_board
from octoprint_printwatch.core.calibration import calibrate_intrinsics
from octoprint_printwatch.simulator.board_scene import Nuisances, random_held_poses, render_board_held

from .conftest import webcam


@pytest.fixture(scope="module")
def truth():
    return webcam(dist=(-0.22, 0.09, 0.0, 0.0, 0.0))


def test_charuco_views_cut_by_the_frame_edge_are_used(truth, bed_charuco):
    poses = random_held_poses(truth, bed_charuco, 10, seed=41)
    views, partial = [], []
    for i, (rvec, tvec) in enumerate(poses):
        if i % 3 == 0:
            # Push the board half out of the frame towards the nearest side: only ChArUco copes.
            tvec = tvec + np.array([np.sign(tvec[0] + 1e-9) * 0.5 * bed_charuco.size_mm[0], 0.0, 0.0])
            partial.append(f"image {i + 1}")
        views.append(render_board_held(truth, bed_charuco, rvec, tvec, nuisances=Nuisances(seed=50 + i)))
    result = calibrate_intrinsics(views, bed_charuco)
    for i in range(0, len(views), 3):
        found = detect_board(views[i], bed_charuco)
        assert 8 <= len(found) < bed_charuco.n_corners  # really cut by the frame edge
    for label in partial:
        assert label in result.views_used
    assert result.rms_px < 0.5
    assert abs(result.camera.K[0, 0] / truth.K[0, 0] - 1) < 0.01
    # Distortion recovered: a point near the frame corner maps within a pixel of the truth.
    corner = np.array([[20.0, 20.0]])
    assert np.linalg.norm(result.camera.undistort_points(corner) - truth.undistort_points(corner)) < 1.0


def test_blurred_untilted_views_get_a_retake_with_reasons(truth, bed_chessboard):
    poses = random_held_poses(truth, bed_chessboard, 6, seed=42, max_tilt_deg=11.0)
    views = [render_board_held(truth, bed_chessboard, r, t, nuisances=Nuisances(seed=i, blur_sigma_px=3.5))
             for i, (r, t) in enumerate(poses)]
    result = calibrate_intrinsics(views, bed_chessboard)
    assert result.verdict == "retake"
    text = " ".join(result.reasons)
    assert "only 6 usable views" in text
    assert "tilt" in text
    assert "blurred" in text
