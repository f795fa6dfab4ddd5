"""The seed's quick focal estimate (Eq. 5.1-5.4) and its field-of-view variant."""
import numpy as np
import pytest

from octoprint_printwatch.core.boards import Board
from octoprint_printwatch.core.calibration import (estimate_focal_from_image, focal_mm_from_px, focal_px_from_fov,
                                                   focal_px_from_square, pixel_size_um)
from octoprint_printwatch.core.errors import CalibrationError
from octoprint_printwatch.simulator.board_scene import Nuisances, render_board_held

from .conftest import webcam


def test_seed_numbers():
    # Section 5.3.2.1: 7 mm squares, 20 px wide at 230 mm; C525 sensor 3.73 mm over 640 px.
    assert focal_px_from_square(20, 230, 7) == pytest.approx(657.14, abs=0.01)
    pitch = pixel_size_um(3.73, 640)
    assert pitch == pytest.approx(5.828, abs=0.001)
    assert focal_mm_from_px(657.14, pitch) == pytest.approx(3.83, abs=0.01)
    assert focal_px_from_fov(640, 90) == pytest.approx(320.0)
    with pytest.raises(CalibrationError):
        focal_px_from_fov(640, 200)


@pytest.mark.parametrize("distance", [250.0, 400.0])
def test_focal_from_one_square_on_image_within_three_percent(distance):
    truth = webcam(dist=(-0.05, 0.0, 0.0, 0.0, 0.0))
    board = Board("charuco", 7, 5, 20.0, 14.4)
    w, h = board.size_mm
    # Board facing the camera squarely, centred, at `distance` mm.
    frame = render_board_held(truth, board, np.zeros(3), np.array([-w / 2, -h / 2, distance]),
                              nuisances=Nuisances(seed=3))
    estimate = estimate_focal_from_image(frame, board, distance)
    assert abs(estimate.focal_px / truth.K[0, 0] - 1) < 0.03
    assert estimate.camera.size == truth.size
