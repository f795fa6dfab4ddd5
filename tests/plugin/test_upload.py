"""Upload side: injection on real slicer G-code keeps the original exactly; rendering never blocks a check."""
import threading
import time

import pytest

from octoprint_printwatch.core.errors import PrintWatchError
from octoprint_printwatch.plugin.upload import (OriginalStore, Preparer, inject_upload, is_injected,
                                                planned_checks, sha256_of)

PROFILE = {"volume": {"width": 235, "depth": 235, "height": 250, "origin": "lowerleft"}}


@pytest.mark.parametrize("name", ["prusa25_cylinder.gcode", "cura413_ender3_t55_gear_relative_e_zhop.gcode"])
def test_injected_upload_has_the_checks_and_the_exact_original_is_kept(gcode_dir, tmp_path, name):
    src = tmp_path / name
    src.write_bytes((gcode_dir / name).read_bytes())
    dst = tmp_path / "out.gcode"
    store = OriginalStore(tmp_path / "originals")
    result = inject_upload(src, dst, {"every_layers": 10, "lift_mm": 10}, PROFILE, store)

    assert is_injected(dst) and not is_injected(src)
    planned = planned_checks(dst)
    assert planned == [(c.layer, pytest.approx(c.z, abs=1e-3)) for c in result.checks]
    assert len(planned) >= 2
    layers = [layer for layer, _ in planned]
    assert layers == sorted(layers)
    # the kept copy and the stripped file are both the upload, byte for byte
    kept = store.path_for(sha256_of(dst))
    assert kept.read_bytes() == src.read_bytes()
    assert store.original_of(dst) == kept
    kept.unlink()
    assert store.original_of(dst).read_bytes() == src.read_bytes()


def test_checks_every_x_mm_follow_the_height(gcode_dir, tmp_path):
    src = gcode_dir / "prusa25_cylinder.gcode"
    dst = tmp_path / "out.gcode"
    inject_upload(src, dst, {"interval_mode": "mm", "every_mm": 3.0}, PROFILE, OriginalStore(tmp_path / "o"))
    heights = [z for _, z in planned_checks(dst)]
    # one check at (or just above) each multiple of 3 mm, plus the final layer
    assert all(b > a for a, b in zip(heights, heights[1:]))
    for target in (3.0, 6.0, 9.0):
        assert any(target - 1e-6 <= z < target + 0.5 for z in heights), (target, heights)


def test_a_file_the_injector_cannot_use_raises_a_one_line_error(tmp_path):
    src = tmp_path / "notes.gcode"
    src.write_text("; just a comment\nM117 hello\n")
    with pytest.raises(PrintWatchError) as info:
        inject_upload(src, tmp_path / "out.gcode", {}, PROFILE, OriginalStore(tmp_path / "o"))
    assert "\n" not in str(info.value)
    assert not (tmp_path / "out.gcode").exists()


def test_a_check_does_not_wait_for_rendering_longer_than_asked():
    release = threading.Event()

    def slow_prepare(**kwargs):
        release.wait(10)
        return {"plan for": kwargs["name"]}

    changes = []
    preparer = Preparer(slow_prepare, on_change=lambda key, status: changes.append((key, status["state"])))
    try:
        preparer.request("k1", name="cube")
        started = time.monotonic()
        assert preparer.wait("k1", 0.3) is None
        assert 0.25 < time.monotonic() - started < 1.5
        assert preparer.status("k1")["state"] == "rendering"
        assert preparer.request("k1", name="cube") is preparer._jobs["k1"]  # no second rendering queued
        release.set()
        assert preparer.wait("k1", 5) == {"plan for": "cube"}
        assert preparer.status("k1")["state"] == "ready"
        assert ("k1", "ready") in changes
    finally:
        release.set()
        preparer.stop()


def test_a_failed_rendering_is_reported_and_can_be_retried():
    attempts = []

    def flaky(**kwargs):
        attempts.append(1)
        if len(attempts) == 1:
            raise PrintWatchError("model.stl: not watertight")
        return "plan"

    preparer = Preparer(flaky)
    try:
        preparer.request("k")
        assert preparer.wait("k", 5) is None
        assert preparer.status("k") == {"state": "failed", "progress": 0.0, "message": "model.stl: not watertight",
                                        "seconds": preparer.status("k")["seconds"]}
        preparer.request("k")
        assert preparer.wait("k", 5) == "plan"
    finally:
        preparer.stop()


def test_unknown_key_is_not_waited_for():
    preparer = Preparer(lambda **kw: "plan")
    try:
        started = time.monotonic()
        assert preparer.wait("nothing", 5) is None
        assert preparer.wait(None, 5) is None
        assert time.monotonic() - started < 0.5
        assert preparer.status(None)["state"] == "none"
    finally:
        preparer.stop()


def test_kept_originals_of_deleted_files_are_pruned(gcode_dir, tmp_path):
    store = OriginalStore(tmp_path / "originals")
    outputs = []
    for name in ("prusa25_cylinder.gcode", "slic3r13_cube.gcode"):
        dst = tmp_path / f"injected-{name}"
        inject_upload(gcode_dir / name, dst, {"every_layers": 20}, PROFILE, store)
        outputs.append(dst)
    assert len(list(store.folder.glob("*.gcode"))) == 2
    outputs[0].unlink()  # the user deleted this file in OctoPrint
    removed = store.prune(outputs)
    assert len(removed) == 1
    assert store.original_of(outputs[1]).read_bytes() == (gcode_dir / "slic3r13_cube.gcode").read_bytes()
    assert store.path_for(sha256_of(outputs[1])).exists()
