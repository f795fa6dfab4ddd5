"""Done-when on real images: OpenCV's 13 sample stereo pairs of a 9 x 6 inner-corner chessboard."""
import numpy as np
import pytest

from octoprint_printwatch.core.calibration import calibrate_intrinsics, calibrate_pair, check_pair_consistency


@pytest.fixture(scope="module")
def intrinsics(opencv_images, opencv_board, opencv_paths):
    left, right = opencv_images
    return (calibrate_intrinsics(left, opencv_board, labels=[p.name for p in opencv_paths[0]], name="left"),
            calibrate_intrinsics(right, opencv_board, labels=[p.name for p in opencv_paths[1]], name="right"))


@pytest.fixture(scope="module")
def pair(opencv_images, opencv_board, intrinsics):
    left, right = opencv_images
    return calibrate_pair(left, right, opencv_board, left_camera=intrinsics[0].camera,
                          right_camera=intrinsics[1].camera)


def test_intrinsics_rms_under_half_a_pixel_per_camera(intrinsics):
    for result in intrinsics:
        assert len(result.views_used) == 13 and not result.views_skipped
        assert result.rms_px < 0.5
        assert max(result.per_view_errors.values()) < 1.0
        K = result.camera.K
        # A 640 x 480 webcam-class lens: focal near 535 px, principal point near the centre.
        assert 500 < K[0, 0] < 570 and abs(K[0, 0] - K[1, 1]) < 0.01 * K[0, 0]
        assert abs(K[0, 2] - 320) < 40 and abs(K[1, 2] - 240) < 40
        assert result.focal_uncertainty < 0.005


def test_verdict_points_at_the_frame_corners_the_sample_views_never_reach(intrinsics):
    # OpenCV's sample views keep the board near the centre: sharp and well fitted, but the
    # distortion at the frame's corners is extrapolated, which the verdict must say.
    for result in intrinsics:
        assert result.verdict == "retake"
        assert any("corner of the frame" in reason for reason in result.reasons)
        assert not any("blurred" in reason or "views;" in reason for reason in result.reasons)


def test_stereo_rms_under_half_a_pixel_and_baseline_consistent(pair):
    assert len(pair.views_used) == 13
    assert pair.rms_px < 0.5
    assert pair.epipolar_rms_px < 0.5
    # The sample rig's baseline is about 3.3 square sizes, mostly along x.
    assert 3.2 < pair.baseline_mm < 3.45
    assert abs(pair.T[0]) > 0.99 * pair.baseline_mm
    # Every view pair alone gives the same baseline (within 2 %) and rotation.
    assert pair.baseline_spread_mm < 0.02 * pair.baseline_mm
    assert np.all(np.abs(pair.per_view_baseline_mm - pair.baseline_mm) < 0.05 * pair.baseline_mm)
    assert pair.rotation_spread_deg < 0.5


def test_joint_calibration_without_given_intrinsics_agrees(opencv_images, opencv_board, pair):
    left, right = opencv_images
    joint = calibrate_pair(left, right, opencv_board)
    assert joint.rms_px < 0.5
    assert abs(joint.baseline_mm - pair.baseline_mm) < 0.01 * pair.baseline_mm
    assert set(joint.intrinsics) == {"left", "right"}


def test_pair_consistency_check_catches_a_moved_camera(pair):
    left = pair.left.with_pose([1.2, 0.1, 0.05], [-40.0, 20.0, 300.0])
    # A right camera placed exactly as the stereo calibration says agrees ...
    right = left.with_pose(*_compose(pair.R, pair.T, left))
    right.name = "right"
    ok = check_pair_consistency(pair.R, pair.T, left, right)
    assert ok.ok and ok.baseline_diff_mm < 1e-6 and ok.rotation_diff_deg < 1e-6
    # ... and the same camera turned by 2 degrees does not.
    import cv2
    bumped = right.with_pose(cv2.Rodrigues(cv2.Rodrigues(np.radians([0, 2.0, 0]))[0] @ right.R)[0].ravel(),
                             right.tvec)
    bad = check_pair_consistency(pair.R, pair.T, left, bumped)
    assert not bad.ok and 1.9 < bad.rotation_diff_deg < 2.1
    assert "disagree" in bad.message


def _compose(R, T, left):
    import cv2
    return cv2.Rodrigues(R @ left.R)[0].ravel(), R @ left.tvec + T


def test_too_few_views_is_a_retake_with_the_reason(opencv_images, opencv_board):
    result = calibrate_intrinsics(opencv_images[0][:4], opencv_board)
    assert result.verdict == "retake"
    assert any("only 4 usable views" in reason for reason in result.reasons)
