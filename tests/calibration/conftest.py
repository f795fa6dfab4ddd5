"""Fixtures for the calibration tests: OpenCV's real chessboard pairs and simulated board scenes."""
from pathlib import Path

import numpy as np
import pytest

from octoprint_printwatch.core.boards import Board, board_for_bed
from octoprint_printwatch.core.calibration import load_images
from octoprint_printwatch.core.camera import Camera

PAIRS = Path(__file__).resolve().parents[1] / "data" / "stereo" / "opencv_chessboard_pairs"


@pytest.fixture(scope="session")
def opencv_board() -> Board:
    """OpenCV's sample board: 9 x 6 inner corners = 10 x 7 squares; unit squares so lengths come
    out in square sizes."""
    return Board("chessboard", 10, 7, 1.0)


@pytest.fixture(scope="session")
def opencv_paths() -> tuple[list[Path], list[Path]]:
    left = sorted(PAIRS.glob("left*.jpg"))
    right = [PAIRS / p.name.replace("left", "right") for p in left]
    assert len(left) == 13 and all(p.is_file() for p in right)
    return left, right


@pytest.fixture(scope="session")
def opencv_images(opencv_paths):
    left, right = opencv_paths
    return load_images(left), load_images(right)


@pytest.fixture(scope="session")
def bed_charuco() -> Board:
    return board_for_bed((220.0, 220.0), kind="charuco")


@pytest.fixture(scope="session")
def bed_chessboard() -> Board:
    return board_for_bed((220.0, 220.0), kind="chessboard")


def webcam(name="cam0", eye=(170.0, -190.0, 170.0), target=(110.0, 100.0, 0.0), width=640, height=480,
           hfov_deg=62.0, dist=(-0.14, 0.05, 0.0005, -0.0004, 0.0), roll_deg=2.0) -> Camera:
    """A webcam on a stand in front of a 220 x 220 mm bed, looking down at about 35 degrees."""
    return Camera.look_at(name, eye, target, width=width, height=height, hfov_deg=hfov_deg, dist=dist,
                          roll_deg=roll_deg)


def pose_errors(found: Camera, truth: Camera) -> tuple[float, float]:
    """(camera-centre error in mm, rotation error in degrees)."""
    import cv2

    position = float(np.linalg.norm(found.center - truth.center))
    rotation = float(np.degrees(np.linalg.norm(cv2.Rodrigues(found.R @ truth.R.T)[0])))
    return position, rotation
