"""A simulated stereo pair in relaxed geometry: stereo calibration agrees with the bed poses."""
import cv2
import numpy as np

from octoprint_printwatch.core.calibration import calibrate_pair, relative_pose
from octoprint_printwatch.simulator.board_scene import Nuisances, random_held_poses, render_board_held

from .conftest import webcam


def test_stereo_and_bed_poses_agree_and_right_pose_follows(bed_charuco):
    # Relaxed positioning: different distances, heights and focal lengths.
    left = webcam("cam0L", eye=(60.0, -200.0, 150.0), target=(110.0, 110.0, 10.0))
    right = webcam("cam0R", eye=(170.0, -170.0, 140.0), target=(110.0, 110.0, 10.0), hfov_deg=55.0,
                   dist=(-0.08, 0.02, 0.0, 0.0, 0.0))
    R, T = relative_pose(left, right)
    frames_l, frames_r = [], []
    w, h = bed_charuco.size_mm
    outline = np.array([[0, 0, 0], [w, 0, 0], [w, h, 0], [0, h, 0]], float)
    for i, (rvec, tvec) in enumerate(random_held_poses(left, bed_charuco, 40, seed=61, fill=(0.3, 0.5))):
        # The same board pose in the right camera's frame.
        Rb = cv2.Rodrigues(rvec)[0]
        rvec_r, tvec_r = cv2.Rodrigues(R @ Rb)[0].ravel(), R @ tvec + T
        px = cv2.projectPoints(outline, rvec_r, tvec_r, right.K, right.dist)[0].reshape(-1, 2)
        if not ((px > 5).all() and (px[:, 0] < right.width - 5).all() and (px[:, 1] < right.height - 5).all()):
            continue
        frames_l.append(render_board_held(left, bed_charuco, rvec, tvec, nuisances=Nuisances(seed=i)))
        frames_r.append(render_board_held(right, bed_charuco, rvec_r, tvec_r, nuisances=Nuisances(seed=100 + i)))
        if len(frames_l) == 8:
            break
    assert len(frames_l) == 8
    result = calibrate_pair(frames_l, frames_r, bed_charuco, left_camera=left, right_camera=right,
                            names=("cam0L", "cam0R"))
    assert result.rms_px < 0.5
    assert abs(result.baseline_mm - np.linalg.norm(T)) < 0.01 * np.linalg.norm(T)
    assert result.consistency is not None and result.consistency.ok, result.consistency.message
    assert np.linalg.norm(result.right.center - right.center) < 2.0
