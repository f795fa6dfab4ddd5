"""The calibration wizard's server side: frames from the camera in, a camera a user can trust out."""
import numpy as np
import pytest

from octoprint_printwatch.core.calibration import BoardPlacement
from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.errors import CalibrationError
from octoprint_printwatch.plugin.cameras import Snapshot
from octoprint_printwatch.plugin.calibration import CalibrationWizard
from octoprint_printwatch.simulator.board_scene import (Nuisances, random_held_poses, render_board_held,
                                                        render_board_on_bed)

PROFILE = {"volume": {"width": 220, "depth": 220, "height": 250, "origin": "lowerleft"}}


def snap(image):
    return Snapshot("cam0", image, "ok", None, 0.05)


@pytest.fixture(scope="module")
def true_camera():
    return Camera.look_at("cam0", eye=[110, -170, 190], target=[110, 60, 0], hfov_deg=62,
                          dist=[-0.12, 0.05, 0, 0, 0])


def test_board_frames_to_a_camera_close_to_the_truth(tmp_path, true_camera):
    wizard = CalibrationWizard(tmp_path, profile=lambda: PROFILE)
    board = wizard.board()
    assert wizard.board_json()["description"] == board.describe()
    assert wizard.board_png()[:4] == b"\x89PNG"

    noise = Nuisances(noise_sigma=1.5, jpeg_quality=90)
    for index, (rvec, tvec) in enumerate(random_held_poses(true_camera, board, 10, seed=4)):
        session = wizard.capture("cam0", snap(render_board_held(true_camera, board, rvec, tvec, nuisances=noise)))
        assert session["frames"][index]["detected"], index
    on_bed = render_board_on_bed(true_camera, board, BoardPlacement.front_left(board), bed_mm=(220, 220),
                                 nuisances=noise)
    session = wizard.capture("cam0", snap(on_bed))
    assert len(session["frames"]) == 11 and session["needed"] <= 11
    assert wizard.frame_jpeg("cam0", 0)[:2] == b"\xff\xd8"

    result = wizard.compute("cam0", PROFILE)
    assert result["verdict"] in ("good", "acceptable"), result
    assert result["rms_px"] < 1.0
    computed = wizard.result_camera("cam0")
    assert np.linalg.norm(computed.center - true_camera.center) < 5.0  # mm
    assert abs(computed.K[0, 0] / true_camera.K[0, 0] - 1) < 0.02
    assert Camera.from_dict("cam0", result["camera"]).width == 640


def test_computing_without_board_frames_is_a_clear_error(tmp_path, true_camera):
    wizard = CalibrationWizard(tmp_path, profile=lambda: PROFILE)
    blank = np.full((480, 640, 3), 128, np.uint8)
    session = wizard.capture("cam0", snap(blank))
    assert session["frames"][0]["detected"] is False
    with pytest.raises(CalibrationError, match="found in 0 frame"):
        wizard.compute("cam0", PROFILE)
    with pytest.raises(CalibrationError, match="compute the calibration first"):
        wizard.result_camera("cam0")
    assert wizard.drop("cam0", 0)["frames"] == []
    with pytest.raises(KeyError):
        wizard.drop("cam0", 3)


def test_a_dead_camera_during_capture_is_reported(tmp_path):
    wizard = CalibrationWizard(tmp_path, profile=lambda: PROFILE)
    dead = Snapshot("cam0", None, "timeout", "camera cam0: no answer within 5 s", 5.0)
    with pytest.raises(CalibrationError, match="no answer"):
        wizard.capture("cam0", dead)
    with pytest.raises(KeyError):
        wizard.capture("nope", None)
