"""Self-check during printing: is the printed first layer where the calibration says?"""
import numpy as np
import pytest

from octoprint_printwatch.core.calibration import (check_pose_against_first_layer, first_layer_mask,
                                                   refine_pose_from_shift)
from octoprint_printwatch.core.errors import CalibrationError
from octoprint_printwatch.simulator.board_scene import Nuisances, render_empty_bed, render_first_layer

from .conftest import webcam


def _skirt(cx=110.0, cy=110.0, w=60.0, d=40.0, loops=2, gap=0.45):
    """Rectangular skirt loops around a part, (n, 2) mm each."""
    paths = []
    for k in range(loops):
        hw, hd = w / 2 + k * gap, d / 2 + k * gap
        paths.append(np.array([[cx - hw, cy - hd], [cx + hw, cy - hd], [cx + hw, cy + hd], [cx - hw, cy + hd],
                               [cx - hw, cy - hd]]))
    return paths


def _bumped(camera, pan_deg, tilt_deg=0.0):
    import cv2
    turn = cv2.Rodrigues(np.radians([tilt_deg, pan_deg, 0.0]))[0]  # about the camera's own axes
    return camera.with_pose(cv2.Rodrigues(turn @ camera.R)[0].ravel(), turn @ camera.tvec)


@pytest.fixture(scope="module")
def scene():
    camera = webcam()
    background = render_empty_bed(camera, nuisances=Nuisances(seed=21))
    return camera, background


def test_first_layer_where_expected_is_ok(scene):
    camera, background = scene
    frame = render_first_layer(camera, background, _skirt(), seed=1)
    check = check_pose_against_first_layer(camera, frame, background, first_layer_mask(camera, _skirt()))
    assert check.status == "ok" and check.ok
    assert check.offset_px < 1.0 and check.match > 0.6


@pytest.mark.parametrize("pan,tilt", [(1.0, 0.0), (-0.6, 0.5)])
def test_bumped_camera_is_reported_with_the_shift(scene, pan, tilt):
    camera, background = scene
    moved = _bumped(camera, pan, tilt)
    # Same room, same light; the bed and the skirt move in the picture.
    frame = render_first_layer(moved, render_empty_bed(moved, nuisances=Nuisances(seed=21)), _skirt(), seed=2)
    expected = first_layer_mask(camera, _skirt())
    check = check_pose_against_first_layer(camera, frame, background, expected)
    assert check.status == "moved" and not check.ok
    # The true image shift of the skirt's centre.
    centre = np.array([[110.0, 110.0, 0.2]])
    true_shift = (moved.project(centre) - camera.project(centre))[0]
    assert np.linalg.norm(check.shift_px - true_shift) < 1.5
    assert "bumped" in check.message
    # Turning the calibrated camera by what the check measured puts the first layer back in place.
    refined, note = refine_pose_from_shift(camera, check.shift_px, at_px=camera.project(centre)[0])
    assert "turned by" in note
    again = check_pose_against_first_layer(refined, frame, background, first_layer_mask(refined, _skirt()))
    assert again.status == "ok" and again.offset_px < 1.5


def test_nothing_printed_is_unknown_never_moved(scene):
    camera, background = scene
    frame = render_empty_bed(camera, nuisances=Nuisances(seed=23))  # same bed, new noise
    check = check_pose_against_first_layer(camera, frame, background, first_layer_mask(camera, _skirt()))
    assert check.status == "unknown" and check.ok and check.offset_px is None


def test_first_layer_out_of_view_is_unknown(scene):
    camera, background = scene
    far_away = _skirt(cx=2000.0)
    check = check_pose_against_first_layer(camera, background, background, first_layer_mask(camera, far_away))
    assert check.status == "unknown"


def test_refinement_is_bounded(scene):
    camera, _ = scene
    with pytest.raises(CalibrationError, match="recalibrate"):
        refine_pose_from_shift(camera, (200.0, 0.0), max_deg=2.0)


def test_wrong_sizes_are_a_clear_error(scene):
    camera, background = scene
    with pytest.raises(CalibrationError, match="frame is 320x240"):
        check_pose_against_first_layer(camera, background[::2, ::2], background,
                                       np.zeros((480, 640), bool))


def test_real_gcode_first_layer_and_the_check_command(tmp_path, capsys, gcode_dir):
    import cv2

    from octoprint_printwatch.cli import main
    from octoprint_printwatch.core.calibration import first_layer_paths
    from octoprint_printwatch.core.camera import Camera

    gcode = gcode_dir / "prusa25_sun_gear_zhop_relative_e.gcode"
    paths, width, z = first_layer_paths(gcode)
    assert z == pytest.approx(0.2) and width == pytest.approx(0.4, abs=0.01)
    points = np.concatenate(paths)
    assert np.allclose(points[:, 2], 0.2)  # nothing from the second layer
    assert 50 < np.ptp(points[:, 0]) < 70  # the skirt around the 50 mm gear
    camera = webcam(eye=(100.0, -120.0, 150.0), target=(100.0, 100.0, 0.0))
    background = render_empty_bed(camera, nuisances=Nuisances(seed=31))
    moved = _bumped(camera, 0.0, 0.8)  # the camera tipped down a little
    frame = render_first_layer(moved, render_empty_bed(moved, nuisances=Nuisances(seed=31)), paths,
                               line_width_mm=width, z_mm=z, colour_bgr=(30, 200, 240), seed=3)
    camera.save(tmp_path / "cam.json")
    cv2.imwrite(str(tmp_path / "bg.png"), background)
    cv2.imwrite(str(tmp_path / "frame.png"), frame)
    argv = ["calibrate", "check", str(tmp_path / "frame.png"), "--camera", str(tmp_path / "cam.json"),
            "--background", str(tmp_path / "bg.png"), "--gcode", str(gcode)]
    assert main(argv + ["--refine-out", str(tmp_path / "refined.json")]) == 1
    out = capsys.readouterr().out
    assert "bumped" in out and "turned by" in out
    refined = Camera.load(tmp_path / "refined.json")
    assert main(argv[:4] + [str(tmp_path / "refined.json")] + argv[5:]) == 0
    assert "where expected" in capsys.readouterr().out
    # The refined camera is closer to the truth than the stale calibration.
    def angle(a, b):
        return np.degrees(np.linalg.norm(cv2.Rodrigues(a.R @ b.R.T)[0]))
    assert angle(refined, moved) < 0.2 < angle(camera, moved)


@pytest.mark.parametrize("gcode_name,colour", [("cura413_ender3_sun_gear.gcode", (30, 200, 240)),
                                              ("prusa25_two_cubes.gcode", (60, 60, 60))])
def test_lighting_change_between_background_and_frame_is_not_a_move(gcode_dir, gcode_name, colour):
    from octoprint_printwatch.core.calibration import first_layer_paths

    paths, width, z = first_layer_paths(gcode_dir / gcode_name)
    camera = webcam(eye=(120.0, -150.0, 170.0), target=(110.0, 110.0, 0.0), hfov_deg=70.0)
    background = render_empty_bed(camera, nuisances=Nuisances(seed=41, exposure=1.0))
    # The room got brighter and the light moved while the first layer was printed.
    lit = render_empty_bed(camera, nuisances=Nuisances(seed=41, exposure=1.25, light_angle_deg=120.0))
    frame = render_first_layer(camera, lit, paths, line_width_mm=width, z_mm=z, colour_bgr=colour, seed=4)
    check = check_pose_against_first_layer(camera, frame, background, first_layer_mask(camera, paths, width, z))
    assert check.status == "ok", check.message
    assert check.offset_px < 1.0


def test_grey_filament_on_a_dark_bed_is_unknown_not_moved(gcode_dir):
    from octoprint_printwatch.core.calibration import first_layer_paths

    paths, width, z = first_layer_paths(gcode_dir / "cura413_ender3_sun_gear.gcode")
    camera = webcam(eye=(120.0, -150.0, 170.0), target=(110.0, 110.0, 0.0), hfov_deg=70.0)
    background = render_empty_bed(camera, nuisances=Nuisances(seed=41))
    lit = render_empty_bed(camera, nuisances=Nuisances(seed=41, exposure=1.25, light_angle_deg=120.0))
    frame = render_first_layer(camera, lit, paths, line_width_mm=width, z_mm=z, colour_bgr=(60, 60, 60), seed=4)
    check = check_pose_against_first_layer(camera, frame, background, first_layer_mask(camera, paths, width, z))
    assert check.status != "moved" and check.ok


def test_print_head_and_cable_in_view_do_not_fool_the_check(gcode_dir):
    import cv2

    from octoprint_printwatch.core.calibration import first_layer_paths

    paths, width, z = first_layer_paths(gcode_dir / "prusa25_two_cubes.gcode")
    camera = webcam(eye=(120.0, -150.0, 170.0), target=(110.0, 110.0, 0.0), hfov_deg=70.0)
    background = render_empty_bed(camera, nuisances=Nuisances(seed=5))
    expected = first_layer_mask(camera, paths, width, z)
    ys, xs = np.nonzero(expected)
    centre = np.array([[110.0, 110.0, z]])
    for pan, should_be in ((0.0, "ok"), (0.7, "moved")):
        moved = _bumped(camera, pan)
        frame = render_first_layer(moved, render_empty_bed(moved, nuisances=Nuisances(seed=5)), paths,
                                   line_width_mm=width, z_mm=z, colour_bgr=(200, 80, 40))
        # The parked head's dark shadow over a third of the first layer, and a bright cable across it.
        x0 = int(xs.min() + 0.6 * np.ptp(xs))
        cv2.rectangle(frame, (x0, ys.min() - 60), (xs.max() + 30, int(ys.min() + 0.5 * np.ptp(ys))), (25, 25, 25), -1)
        cv2.line(frame, (xs.min() - 40, ys.max() + 20), (xs.max(), ys.min() - 50), (200, 200, 200), 3)
        check = check_pose_against_first_layer(camera, frame, background, expected)
        assert check.status == should_be, check.message
        true_shift = (moved.project(centre) - camera.project(centre))[0]
        assert np.linalg.norm(check.shift_px - true_shift) < 1.0
