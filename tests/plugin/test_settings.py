"""Plugin settings map onto the core's detection settings and the injector's options."""
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.plugin import settings as ps
from octoprint_printwatch.plugin.upload import injection_options


def camera_dict():
    cam = Camera("c", 640, 480, [[800, 0, 320], [0, 800, 240], [0, 0, 1]], rvec=[2.0, 0, 0], tvec=[-100, 50, 300])
    return cam.to_dict()


def test_thresholds_reach_the_detection_settings():
    detection = ps.detection_settings({"shape_threshold_pct": 5.5, "shape_threshold_per_camera": {"left": 9},
                                       "size_threshold_pct": 12, "detection": {"band_threshold_pct": 30}})
    assert detection.threshold_for("left") == 9
    assert detection.threshold_for("other") == 5.5
    assert detection.size_threshold_pct == 12
    assert detection.band_threshold_pct == 30


def test_api_overrides_win_over_stored_settings():
    detection = ps.detection_settings({"shape_threshold_pct": 7.0}, shape_threshold_pct=4.0)
    assert detection.threshold_for("x") == 4.0


def test_a_bad_threshold_is_a_one_line_error_naming_the_setting():
    with pytest.raises(ps.PrintWatchError, match="shape_threshold_pct"):
        ps.detection_settings({"shape_threshold_pct": "lots"})


def test_unknown_action_is_refused():
    assert ps.action({"action": "Cancel"}) == "cancel"
    with pytest.raises(ps.SettingsValueError, match="explode"):
        ps.action({"action": "explode"})


def test_broken_calibration_names_the_camera():
    good = camera_dict()
    assert set(ps.calibrated_cameras({"calibrations": {"c": good}})) == {"c"}
    with pytest.raises(ps.SettingsValueError, match="calibrations.bad"):
        ps.calibrated_cameras({"calibrations": {"bad": {**good, "K": [1, 2]}}})


def test_pairs_need_two_calibrated_cameras_and_the_size_check_on():
    cams = {"a": 1, "b": 2}
    assert ps.stereo_pairs({"pairs": [["a", "b"], ["a", "z"]]}, cams) == [("a", "b")]
    assert ps.stereo_pairs({"pairs": [["a", "b"]], "size_check": False}, cams) == []


def test_camera_set_key_changes_with_the_calibration():
    a = Camera.from_dict("c", camera_dict())
    b = Camera.from_dict("c", {**camera_dict(), "tvec": [-100, 50, 301]})
    assert ps.camera_set_key({"c": a}, []) == ps.camera_set_key({"c": Camera.from_dict("c", camera_dict())}, [])
    assert ps.camera_set_key({"c": a}, []) != ps.camera_set_key({"c": b}, [])


def test_centre_origin_printer_profile_gives_a_centred_bed_for_the_injector():
    profile = {"volume": {"width": 250, "depth": 210, "height": 220, "origin": "center"}}
    options = injection_options({"every_layers": 15, "lift_mm": 8}, profile)
    assert options["bed"] == (-125.0, 125.0, -105.0, 105.0)
    assert options["max_z"] == 220.0
    assert options["every"] == 15 and options["lift"] == 8.0
    assert options["park"] is None
    assert injection_options({"park_x": 20, "park_y": 180}, profile)["park"] == (20.0, 180.0)


def test_a_cleared_per_camera_threshold_means_no_override():
    detection = ps.detection_settings({"shape_threshold_pct": 6.0,
                                       "shape_threshold_per_camera": {"cam0": None, "cam1": 9.0}})
    assert detection.threshold_for("cam0") == 6.0
    assert detection.threshold_for("cam1") == 9.0


@pytest.mark.parametrize("change, named", [
    ({"shape_threshold_pct": -1}, "shape_threshold_pct"),
    ({"action": "explode"}, "action"),
    ({"every_layers": 0}, "every_layers"),
    ({"camera_timeout_s": "soon"}, "camera_timeout_s"),
    ({"park_x": "left", "park_y": 3}, "park_x"),
])
def test_settings_that_would_break_the_checks_are_refused_naming_the_key(change, named):
    ps.validate(dict(ps.DEFAULTS))
    with pytest.raises(ps.PrintWatchError, match=named):
        ps.validate({**ps.DEFAULTS, **change})
