"""The ``printwatch board`` and ``printwatch calibrate`` commands, run as a user runs them."""
import json
import subprocess
import sys

import cv2
import numpy as np
import pytest

from octoprint_printwatch.cli import main
from octoprint_printwatch.core.boards import Board, detect_board
from octoprint_printwatch.core.calibration import BoardPlacement
from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.simulator.board_scene import Nuisances, render_board_on_bed

from .conftest import pose_errors, webcam


def run(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def test_board_command_writes_a_detectable_page_and_its_description(tmp_path, capsys):
    code, out, err = run(capsys, "board", "--out", tmp_path / "board.png", "--bed", "235,235")
    assert code == 0, err
    board = Board.parse(str(tmp_path / "board.json"))
    assert board.kind == "charuco" and "board.png" in out
    page = cv2.imread(str(tmp_path / "board.png"), cv2.IMREAD_GRAYSCALE)
    found = detect_board(page, board)
    assert found is not None and len(found) == board.n_corners


def test_intrinsics_and_pair_on_opencv_samples(tmp_path, capsys, opencv_paths):
    left, right = opencv_paths
    code, out, err = run(capsys, "calibrate", "intrinsics", *left, "--board", "chessboard:10x7:25",
                         "-o", tmp_path / "left.json")
    assert code == 1  # verdict: retake (the sample views miss the frame corners); file written anyway
    assert "RETAKE" in out and "corner of the frame" in out
    doc = json.loads((tmp_path / "left.json").read_text())
    assert doc["format"] == "printwatch-camera/1" and doc["rms_px"] < 0.5 and len(doc["views_used"]) == 13
    Camera.load(tmp_path / "left.json")
    code, out, err = run(capsys, "calibrate", "pair", "--left", *left, "--right", *right,
                         "--board", "chessboard:10x7:25", "-o", tmp_path / "pair.json")
    assert code == 0, err
    pair = json.loads((tmp_path / "pair.json").read_text())
    assert pair["rms_px"] < 0.5 and 80 < pair["baseline_mm"] < 86  # 3.3 squares of 25 mm


def test_bed_command_recovers_a_simulated_camera(tmp_path, capsys, bed_chessboard):
    truth = webcam(name="cam0L")
    board_file = tmp_path / "board.json"
    bed_chessboard.save(board_file)
    frame = render_board_on_bed(truth, bed_chessboard, BoardPlacement.front_left(bed_chessboard),
                                nuisances=Nuisances(seed=31))
    cv2.imwrite(str(tmp_path / "bed.jpg"), frame)
    truth.with_pose(np.zeros(3), np.zeros(3)).save(tmp_path / "cam0L.json", rms_px=0.2)
    code, out, err = run(capsys, "calibrate", "bed", tmp_path / "bed.jpg", "--board", board_file,
                         "--intrinsics", tmp_path / "cam0L.json", "--at", "front-left", "-o", tmp_path / "cam0L.json")
    assert code == 0, err
    found = Camera.load(tmp_path / "cam0L.json")
    doc = json.loads((tmp_path / "cam0L.json").read_text())
    assert doc["rms_px"] == 0.2  # the intrinsics' figures are kept
    position, rotation = pose_errors(found, truth)
    assert position < 1.0 and rotation < 0.3
    assert "camera at X" in out


@pytest.mark.parametrize("case", ["one image", "mixed sizes", "no board", "unreadable", "bad board", "pair count"])
def test_bad_input_is_one_line_and_exit_2(tmp_path, capsys, opencv_paths, case):
    left, right = opencv_paths
    (tmp_path / "broken.jpg").write_bytes(b"not a jpeg")
    small = tmp_path / "small.jpg"
    cv2.imwrite(str(small), cv2.resize(cv2.imread(str(left[1])), (320, 240)))
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((480, 640, 3), 128, np.uint8))
    argv, expected = {
        "one image": (["calibrate", "intrinsics", left[0]], "one image only"),
        "mixed sizes": (["calibrate", "intrinsics", left[0], small, left[2]], "small.jpg: image is 320x240"),
        "no board": (["calibrate", "bed", blank, "--focal-px", "500"], "blank.png: board"),
        "unreadable": (["calibrate", "intrinsics", left[0], tmp_path / "broken.jpg"], "broken.jpg: not a readable"),
        "bad board": (["calibrate", "intrinsics", *left[:3]], "expected a board .json file"),
        "pair count": (["calibrate", "pair", "--left", *left[:4], "--right", *right[:3]], "4 left images but 3"),
    }[case]
    board = "chess:9x6" if case == "bad board" else "chessboard:10x7:25"
    code, out, err = run(capsys, *argv, "--board", board, "-o", tmp_path / "out.json")
    assert code == 2
    assert expected in err and err.count("\n") == 1 and "Traceback" not in err


def test_printwatch_executable_runs(tmp_path):
    result = subprocess.run([sys.executable, "-m", "octoprint_printwatch", "calibrate", "quick", "--hfov", "70",
                             "--size", "640x480", "-o", str(tmp_path / "q.json")], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert Camera.load(tmp_path / "q.json").K[0, 0] == pytest.approx(457.0, abs=0.1)
