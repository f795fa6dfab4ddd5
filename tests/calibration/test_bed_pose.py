"""Done-when on simulator frames: the camera's printer pose within 1 mm and 0.3 degrees."""
import numpy as np
import pytest

from octoprint_printwatch.core.boards import Board
from octoprint_printwatch.core.calibration import BoardPlacement, calibrate_bed_pose, calibrate_intrinsics
from octoprint_printwatch.core.errors import CalibrationError
from octoprint_printwatch.simulator.board_scene import (Nuisances, random_held_poses, render_board_held,
                                                        render_board_on_bed, render_empty_bed)

from .conftest import pose_errors, webcam

# Different cameras, boards, placements and image nuisances; none is tuned for.
SCENES = [
    dict(kind="charuco", eye=(170, -190, 170), size=(640, 480), at="centre", angle=0.0,
         nuisances=Nuisances(seed=1)),
    dict(kind="chessboard", eye=(-80, -150, 200), size=(640, 480), at="front-left", angle=0.0,
         nuisances=Nuisances(seed=2, blur_sigma_px=1.2, noise_sigma=4, jpeg_quality=60, exposure=0.7)),
    dict(kind="charuco", eye=(330, 20, 150), size=(1280, 720), at="centre", angle=15.0,
         nuisances=Nuisances(seed=3, light_gradient=0.6, vignetting=0.4, exposure=1.15)),
    dict(kind="chessboard", eye=(110, -200, 160), size=(800, 600), at="centre", angle=-10.0,
         nuisances=Nuisances(seed=4, blur_sigma_px=0.9, noise_sigma=3, jpeg_quality=75)),
]


def _placement(board, scene):
    if scene["at"] == "front-left":
        return BoardPlacement.front_left(board, angle_deg=scene["angle"])
    return BoardPlacement.centred(board, (220, 220), angle_deg=scene["angle"])


@pytest.mark.parametrize("scene", SCENES, ids=[f"{s['kind']}-{s['size'][0]}" for s in SCENES])
def test_bed_pose_within_1mm_and_0_3deg(scene, bed_charuco, bed_chessboard):
    board = bed_charuco if scene["kind"] == "charuco" else bed_chessboard
    truth = webcam(eye=scene["eye"], width=scene["size"][0], height=scene["size"][1])
    placement = _placement(board, scene)
    frame = render_board_on_bed(truth, board, placement, nuisances=scene["nuisances"])
    # The intrinsics are known; only the pose is sought (it starts at identity).
    result = calibrate_bed_pose(frame, truth.with_pose(np.zeros(3), np.zeros(3)), board, placement)
    position, rotation = pose_errors(result.camera, truth)
    assert position < 1.0, f"camera centre off by {position:.2f} mm"
    assert rotation < 0.3, f"orientation off by {rotation:.3f} deg"
    assert result.reprojection_px < 0.5
    assert result.position_sigma_mm < 1.0 and not result.warnings
    # The stated uncertainty is honest: the true error is within a few sigma.
    assert position < 4 * result.position_sigma_mm + 0.1


def test_low_camera_uses_an_upright_board(bed_chessboard):
    # A camera 12 degrees above the bed sees a flat board edge-on; the board stands up instead.
    truth = webcam(eye=(110, -260, 80), target=(110, 110, 30))
    placement = BoardPlacement.centred(bed_chessboard, (220, 220), tilt_deg=90.0)
    corners = placement.to_printer(bed_chessboard, bed_chessboard.corner_points())
    assert np.allclose(corners[:, 1], 110.0) and corners[:, 2].min() > 0  # a wall across the bed
    frame = render_board_on_bed(truth, bed_chessboard, placement, nuisances=Nuisances(seed=11))
    result = calibrate_bed_pose(frame, truth, bed_chessboard, placement)
    position, rotation = pose_errors(result.camera, truth)
    assert position < 1.0 and rotation < 0.3


def test_wrong_placement_moves_the_camera_by_the_same_amount(bed_chessboard):
    truth = webcam()
    placement = BoardPlacement.centred(bed_chessboard, (220, 220))
    frame = render_board_on_bed(truth, bed_chessboard, placement, nuisances=Nuisances(seed=5))
    told = BoardPlacement(placement.x_mm + 10.0, placement.y_mm, 0.0)
    result = calibrate_bed_pose(frame, truth, bed_chessboard, told)
    # The user said the board is 10 mm further right: the whole camera moves with it.
    assert np.allclose(result.center_mm - truth.center, [10.0, 0.0, 0.0], atol=1.0)


def test_end_to_end_with_intrinsics_from_simulated_hand_held_views(bed_chessboard):
    truth = webcam(dist=(-0.2, 0.08, 0.0, 0.0, 0.0))
    poses = random_held_poses(truth, bed_chessboard, 10, seed=7)
    views = [render_board_held(truth, bed_chessboard, r, t, nuisances=Nuisances(seed=10 + i, noise_sigma=3))
             for i, (r, t) in enumerate(poses)]
    intrinsics = calibrate_intrinsics(views, bed_chessboard)
    assert intrinsics.verdict == "good", intrinsics.reasons
    assert intrinsics.rms_px < 0.3
    assert abs(intrinsics.camera.K[0, 0] / truth.K[0, 0] - 1) < 0.01
    placement = BoardPlacement.front_left(bed_chessboard)
    frame = render_board_on_bed(truth, bed_chessboard, placement, nuisances=Nuisances(seed=6))
    result = calibrate_bed_pose(frame, intrinsics.camera, bed_chessboard, placement)
    position, rotation = pose_errors(result.camera, truth)
    assert position < 1.0 and rotation < 0.3


def test_empty_bed_is_a_clear_error_naming_the_frame(bed_charuco):
    truth = webcam()
    frame = render_empty_bed(truth)
    with pytest.raises(CalibrationError, match=r"^bed\.jpg: board .* not found"):
        calibrate_bed_pose(frame, truth, bed_charuco, BoardPlacement.front_left(bed_charuco), labels=["bed.jpg"])


def test_frames_at_another_resolution_of_the_same_shape_use_scaled_intrinsics(bed_charuco):
    truth = webcam(width=1280, height=960)
    placement = BoardPlacement.centred(bed_charuco, (220, 220))
    frame = render_board_on_bed(truth, bed_charuco, placement, nuisances=Nuisances(seed=8))
    half = truth.scaled(640, 480)
    result = calibrate_bed_pose(frame, half, bed_charuco, placement)
    assert result.camera.size == (1280, 960)
    assert pose_errors(result.camera, truth)[0] < 1.0
    with pytest.raises(CalibrationError, match="different shape"):
        calibrate_bed_pose(frame, truth.scaled(640, 360), bed_charuco, placement)


def test_placement_specs():
    board = Board("chessboard", 8, 5, 25.0, margin_mm=10.0)
    assert BoardPlacement.parse("front-left", board) == BoardPlacement(10.0, 10.0)
    centre = BoardPlacement.parse("centre", board, (220, 220))
    corners = centre.to_printer(board, [[0, 0, 0], [200, 125, 0]])
    assert np.allclose(corners.mean(axis=0), [110, 110, 0])
    assert BoardPlacement.parse("12.5,30,90", board) == BoardPlacement(12.5, 30.0, 90.0)
    for bad in ("middle", "1,2,3,4", "centre"):
        with pytest.raises(CalibrationError):
            BoardPlacement.parse(bad, board)  # 'centre' needs the bed size
    # The board's back edge (y = 0 on the page) lies further back (+Y) than its front edge.
    back, front = BoardPlacement(0, 0).to_printer(board, [[0, 0, 0], [0, 125, 0]])
    assert back[1] - front[1] == pytest.approx(125.0)


def test_several_frames_of_the_same_board_are_pooled(bed_charuco):
    truth = webcam(eye=(300.0, -150.0, 180.0))
    placement = BoardPlacement.centred(bed_charuco, (220, 220), angle_deg=5.0)
    frames = [render_board_on_bed(truth, bed_charuco, placement, nuisances=Nuisances(seed=70 + i, noise_sigma=5))
              for i in range(3)]
    single = calibrate_bed_pose(frames[0], truth, bed_charuco, placement)
    pooled = calibrate_bed_pose(frames, truth, bed_charuco, placement, labels=["a.jpg", "b.jpg", "c.jpg"])
    assert pooled.corners_used > 2 * single.corners_used
    assert pooled.position_sigma_mm < single.position_sigma_mm
    assert pose_errors(pooled.camera, truth)[0] < 1.0
