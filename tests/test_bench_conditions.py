"""``benchmarks/bench_detection.py`` generation conditions: other frame sizes, G-code-only recordings,
and a data folder that never mixes two sets of conditions (the hostile hold-out sets depend on them)."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def bench(load_benchmark):
    yield from load_benchmark("bench_detection")


def test_a_larger_frame_keeps_the_field_of_view_and_scales_the_image(bench):
    from octoprint_printwatch.simulator.rig import make_rig

    camera = make_rig("single", seed=3).cameras_true[0]
    wide = bench._resized_camera(camera, 1280, 720)
    small = bench._resized_camera(camera, 320, 240)
    assert (wide.width, wide.height, small.width, small.height) == (1280, 720, 320, 240)
    fov = [2 * np.degrees(np.arctan(c.width / 2 / c.K[0, 0])) for c in (camera, wide, small)]
    assert fov[1] == pytest.approx(fov[0]) and fov[2] == pytest.approx(fov[0])
    # the same bed points land at the same place relative to the frame's centre, scaled with the width
    points = np.array([[100.0, 100.0, 0.0], [120.0, 90.0, 10.0], [85.0, 110.0, 5.0]])
    base = camera.project(points) - [camera.width / 2, camera.height / 2]
    for cam, scale in ((wide, 2.0), (small, 0.5)):
        moved = cam.project(points) - [cam.width / 2, cam.height / 2]
        np.testing.assert_allclose(moved, base * scale, atol=1e-6)


def test_a_gcode_only_recording_at_320x240_is_read_and_checked_from_the_toolpaths(bench, tmp_path):
    from octoprint_printwatch.core.recording import load_recording

    spec = bench.Spec("normal_00_cube_seed_single", "normal", "cube", "seed", "single", 1234)
    conditions = bench.Conditions(size=(320, 240), gcode_only=True)
    folder = bench.generate(spec, tmp_path, conditions)
    session = json.loads((folder / "session.json").read_text())
    assert "model" not in session and not list(folder.glob("model.*"))
    recording = load_recording(folder)
    assert recording.model is None and recording.gcode is not None
    camera = recording.cameras["cam0"]
    assert (camera.width, camera.height) == (320, 240)
    assert recording.read_frame(recording.checks[0], "cam0").shape == (240, 320, 3)
    assert recording.read_background("cam0").shape == (240, 320, 3)
    # the same scene at 640x480: the calibrated focal length is twice as long there
    reference = bench.make_scene(spec).rig.calibrated("cam0")
    assert camera.K[0, 0] == pytest.approx(reference.K[0, 0] / 2)

    result = bench.evaluate(folder, bench.DetectionSettings())
    assert result["frame_size"] == [320, 240] and result["has_model"] is False
    assert len(result["checks"]) == len(recording.checks)
    assert all(c["verdict"] != "unknown" for c in result["checks"])  # the part was seen and judged


def test_a_data_folder_is_never_filled_under_two_sets_of_conditions(bench, tmp_path):
    first = bench.Conditions(size=(1280, 720))
    stored = bench.set_options(tmp_path, first, 3, {"normal": 2})
    assert stored["conditions"]["size"] == [1280, 720]
    assert bench.set_options(tmp_path, first, 3, {"normal": 2})["holdout"] == 3  # same conditions: fine
    with pytest.raises(SystemExit, match="bench_options.json: this folder was rendered with"):
        bench.set_options(tmp_path, bench.Conditions(gcode_only=True), 3, None)


def test_a_set_can_be_built_from_other_slicers_gcode(bench):
    gcode = ROOT / "tests" / "data" / "gcode" / "cura413_ender3_t55_gear_relative_e_zhop.gcode"
    specs = bench.plan_specs({"normal": 2, "runout": 1}, holdout=5, parts=[str(gcode), "cube"])
    assert [s.part for s in specs].count(str(gcode)) >= 1 and any(s.part == "cube" for s in specs)
    named = [s for s in specs if s.part == str(gcode)]
    assert all("cura413_ender3_t55_gear_relative_e_zhop" in s.name and "/" not in s.name for s in named)
    # the default parts are unchanged without the option
    assert [s.name for s in bench.plan_specs({"normal": 2}, holdout=5)] == \
        [s.name for s in bench.plan_specs({"normal": 2}, holdout=5, parts=None)]
    assert all(s.part in bench.PARTS for s in bench.plan_specs({"normal": 3}, holdout=5))
