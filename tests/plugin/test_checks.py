"""The check coordinator: the job is held only while needed, a failure pauses before a single line more
is printed, dead cameras never pause, and vision never runs on OctoPrint's thread.

The printer is a stand-in recording what the coordinator asks of it (OctoPrint's
own printer needs a server; the integration tests use the real one). The
vision step is scripted here so each decision path can be driven; the real
pipeline runs in ``test_integration.py``.
"""
import threading
import time

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.pipeline import CheckResult
from octoprint_printwatch.plugin.cameras import CameraSource, SnapshotError
from octoprint_printwatch.plugin.checks import CheckCoordinator
from octoprint_printwatch.plugin.history import History


class RecordingPrinter:
    def __init__(self):
        self.calls = []
        self.holds = 0
        self.lock = threading.Lock()

    def set_job_on_hold(self, value, blocking=True):
        with self.lock:
            self.holds += 1 if value else -1
            self.calls.append("hold" if value else "release")
        return True

    def pause_print(self, tags=None):
        self.calls.append("pause")

    def cancel_print(self, tags=None):
        self.calls.append("cancel")

    def commands(self, commands, tags=None):
        self.calls.append(("commands", tuple(commands)))


class MemoryCamera(CameraSource):
    def __init__(self, name, delay=0.0, broken=False):
        super().__init__(name=name, source="url")
        self.delay, self.broken = delay, broken
        image = np.full((120, 160, 3), 40, np.uint8)
        cv2.rectangle(image, (60, 50), (100, 100), (200, 200, 200), -1)
        self.jpeg = cv2.imencode(".jpg", image)[1].tobytes()

    def fetch(self, timeout):
        time.sleep(self.delay)
        if self.broken:
            raise SnapshotError(f"camera {self.name}: connection refused")
        return self.jpeg


class Plans:
    def __init__(self, ready=True):
        self.ready = threading.Event()
        if ready:
            self.ready.set()

    def wait(self, key, timeout):
        return "plan" if self.ready.wait(timeout) else None

    def status(self, key):
        return {"state": "ready" if self.ready.is_set() else "rendering", "progress": 0.0, "message": ""}


class ScriptedRunner:
    """Gives the verdicts a test asks for, as real CheckResult objects; records the frames it got."""

    def __init__(self, verdicts):
        self.verdicts = list(verdicts)
        self.frames = []

    def run_check(self, layer, z, frames):
        self.frames.append({k: v is not None for k, v in frames.items()})
        verdict = self.verdicts.pop(0)
        if verdict == "boom":
            raise ValueError("vision bug")
        reasons = [f"cam0: shape error 15.0 % > 7.0 %"] if verdict == "fail" else []
        return CheckResult(layer=layer, z=z, verdict=verdict, shape_error_pct={"cam0": 15.0 if reasons else 2.0},
                           shape={}, size={}, reasons=reasons, seconds=0.01)


def calibration():
    return Camera("x", 160, 120, [[150, 0, 80], [0, 150, 60], [0, 0, 1]], rvec=[2.0, 0, 0], tvec=[0, 0, 200]).to_dict()


@pytest.fixture
def make(tmp_path, gcode_dir):
    created = []

    def build(cameras, verdicts, *, action="pause", plans=None, timeout=1.0, calibrated=("cam0", "cam1")):
        printer = RecordingPrinter()
        events, pushes = [], []
        values = {"action": action, "camera_timeout_s": timeout, "prepare_wait_s": 0.2,
                  "calibrations": {name: calibration() for name in calibrated}}
        runner = ScriptedRunner(verdicts)
        coordinator = CheckCoordinator(
            printer=printer, history=History(tmp_path / f"data{len(created)}"), settings=lambda: values,
            cameras=lambda: cameras, plans=plans or Plans(), make_runner=lambda plan, det, bgs: runner,
            emit=lambda name, payload: events.append((name, payload)), push=pushes.append,
        )
        coordinator.start_print(origin="local", path="cube.gcode", name="cube.gcode",
                                planned=[(20, 4.0), (40, 8.0)], original_gcode=gcode_dir / "slic3r13_cube.gcode",
                                plan_key="key")
        created.append(coordinator)
        return coordinator, printer, runner, events, pushes

    yield build
    for coordinator in created:
        coordinator.shutdown()


def wait_idle(coordinator, printer, timeout=10.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if printer.holds == 0 and coordinator.state != "checking" and coordinator._worker._work_queue.empty():
            time.sleep(0.05)
            if printer.holds == 0:
                return
        time.sleep(0.02)
    raise AssertionError(f"still holding: {printer.calls}")


def test_a_passing_check_holds_then_releases_and_is_stored(make):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0"), MemoryCamera("cam1")], ["ok"])
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    wait_idle(coordinator, printer)
    assert printer.calls == ["hold", "release"]
    stored = coordinator.history.get_print(coordinator.job.print_id)["checks"]
    assert [(c["layer"], c["verdict"], c["action"]) for c in stored] == [(20, "ok", "none")]
    assert stored[0]["cameras"]["cam0"]["frame_url"].endswith("/checks/0/cam0/frame.jpg")
    assert runner.frames == [{"cam0": True, "cam1": True}]
    assert [name for name, _ in events] == ["check_done"]
    assert any(p["type"] == "check" for p in pushes)
    assert coordinator.status()["next_check"] == {"layer": 40, "z": 8.0}


def test_a_print_ending_right_after_its_last_check_keeps_that_check(make):
    # The last check sits near the end of the file: once its hold lifts, the print may finish
    # while the check is still being stored (here: a slow disk). The finished print must hold it.
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0"), MemoryCamera("cam1")], ["ok"])
    history = coordinator.history
    stored = threading.Event()
    add_check = history.add_check

    def slow_add_check(print_id, check):
        time.sleep(0.5)
        add_check(print_id, check)
        stored.set()

    history.add_check = slow_add_check
    print_id = coordinator.job.print_id
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    deadline = time.monotonic() + 5
    while "release" not in printer.calls and time.monotonic() < deadline:
        time.sleep(0.005)
    coordinator.end_print("done")  # the job ended as soon as the hold lifted
    assert coordinator.status()["state"] == "idle"
    deadline = time.monotonic() + 5
    while history.get_print(print_id)["result"] != "done" and time.monotonic() < deadline:
        time.sleep(0.01)
    ended = history.get_print(print_id)
    assert ended["result"] == "done" and stored.is_set()
    assert [c["layer"] for c in ended["checks"]] == [20]


def test_a_failure_pauses_before_the_hold_is_lifted_and_says_why(make):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0")], ["fail"], calibrated=("cam0",))
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=40 z=8.0")
    wait_idle(coordinator, printer)
    assert printer.calls.index("pause") < printer.calls.index("release")
    failure = [p for p in pushes if p["type"] == "failure"][0]
    assert "layer 40" in failure["message"] and "15.0 %" in failure["message"]
    assert [name for name, _ in events] == ["check_done", "failure_detected"]
    coordinator.on_paused()  # OctoPrint's PrintPaused event
    assert coordinator.status()["state"] == "paused"
    detail = coordinator.history.get_print(coordinator.job.print_id)
    assert detail["result"] == "paused" and detail["first_failure_layer"] == 40
    assert "15.0 %" in detail["failure_reason"]


@pytest.mark.parametrize("action, expected", [("notify", None), ("cancel", "cancel")])
def test_other_failure_actions(make, action, expected):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0")], ["fail"], action=action,
                                                        calibrated=("cam0",))
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=40 z=8.0")
    wait_idle(coordinator, printer)
    assert "pause" not in printer.calls
    assert (expected in printer.calls) if expected else ("cancel" not in printer.calls)
    assert [p for p in pushes if p["type"] == "failure"][0]["action"] == action


def test_a_dead_camera_is_reported_and_the_other_camera_still_decides(make):
    dead = MemoryCamera("cam1", delay=5.0)
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0"), dead], ["ok"], timeout=0.5)
    started = time.monotonic()
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    wait_idle(coordinator, printer)
    assert time.monotonic() - started < 2.5  # the hold lasts the camera timeout, not the camera's hang
    assert "pause" not in printer.calls
    check = coordinator.history.get_print(coordinator.job.print_id)["checks"][0]
    assert check["cameras"]["cam1"]["status"] == "timeout" and "cam1" in check["cameras"]["cam1"]["error"]
    assert runner.frames == [{"cam0": True, "cam1": False}]
    assert ("camera_error", {"camera": "cam1", "error": check["cameras"]["cam1"]["error"]}) in events
    assert coordinator.health["cam1"].health == "error"


def test_no_camera_at_all_gives_unknown_and_the_print_goes_on(make):
    coordinator, printer, runner, events, pushes = make(
        [MemoryCamera("cam0", broken=True), MemoryCamera("cam1", broken=True)], [])
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    wait_idle(coordinator, printer)
    assert printer.calls == ["hold", "release"]
    check = coordinator.history.get_print(coordinator.job.print_id)["checks"][0]
    assert check["verdict"] == "unknown" and check["reasons"] == ["no camera gave a frame"]
    assert runner.frames == []


def test_the_marker_hook_returns_at_once_even_with_slow_cameras(make):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0", delay=1.5)], ["ok"],
                                                        calibrated=("cam0",))
    started = time.monotonic()
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    assert time.monotonic() - started < 0.5  # far less than the camera's 1.5 s (the machine is shared)
    assert printer.holds == 1 and coordinator.state == "checking"
    wait_idle(coordinator, printer)
    assert printer.holds == 0


def test_an_internal_error_in_vision_still_releases_the_job(make):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0")], ["boom"], calibrated=("cam0",))
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    wait_idle(coordinator, printer)
    assert printer.calls == ["hold", "release"]
    assert any(p["type"] == "notice" and p["level"] == "error" for p in pushes)


def test_views_still_rendering_release_the_job_and_a_late_failure_still_pauses(make):
    plans = Plans(ready=False)
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0")], ["fail"], plans=plans,
                                                        calibrated=("cam0",))
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    wait_idle(coordinator, printer)
    assert printer.calls == ["hold", "release"]  # waited prepare_wait_s, then let the print go on
    pending = coordinator.history.get_print(coordinator.job.print_id)["checks"][0]
    assert pending["verdict"] == "unknown" and pending["pending"] is True
    plans.ready.set()
    deadline = time.monotonic() + 5
    while "pause" not in printer.calls and time.monotonic() < deadline:
        time.sleep(0.05)
    assert "pause" in printer.calls
    judged = coordinator.history.get_print(coordinator.job.print_id)["checks"][0]
    assert judged["verdict"] == "fail" and "pending" not in judged
    assert "judged late" in [p for p in pushes if p["type"] == "failure"][0]["message"]


def test_background_frames_are_kept_for_the_checks(make):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0"), MemoryCamera("cam1")], ["ok"])
    coordinator.on_marker("PRINTWATCH_BACKGROUND", "")
    wait_idle(coordinator, printer)
    assert printer.calls == ["hold", "release"]
    assert set(coordinator.job.backgrounds) == {"cam0", "cam1"}
    assert (coordinator.job.writer.root / "background" / "cam0.jpg").exists()


def test_markers_outside_a_monitored_print_are_ignored(make):
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0")], [])
    coordinator.end_print("done")
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    coordinator.on_marker("PRINTWATCH_CHECK", "garbage")
    assert printer.calls == []


def test_a_camera_missing_at_the_background_gets_a_second_chance(make):
    class FlakyCamera(MemoryCamera):
        calls = 0

        def fetch(self, timeout):
            FlakyCamera.calls += 1
            if FlakyCamera.calls == 1:
                raise SnapshotError("camera cam1: busy")
            return self.jpeg

    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0"), FlakyCamera("cam1")], [])
    coordinator.on_marker("PRINTWATCH_BACKGROUND", "")
    wait_idle(coordinator, printer)
    assert printer.calls == ["hold", "release"]
    assert set(coordinator.job.backgrounds) == {"cam0", "cam1"} and FlakyCamera.calls == 2


def test_the_recording_keeps_the_bytes_the_camera_sent(make):
    camera = MemoryCamera("cam0")
    coordinator, printer, runner, events, pushes = make([camera], ["ok"], calibrated=("cam0",))
    coordinator.on_marker("PRINTWATCH_BACKGROUND", "")
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    wait_idle(coordinator, printer)
    root = coordinator.job.writer.root
    assert (root / "background" / "cam0.jpg").read_bytes() == camera.jpeg
    assert (root / "checks" / "000" / "cam0.jpg").read_bytes() == camera.jpeg


def test_checks_waiting_for_the_views_are_judged_in_order_and_later_ones_queue_behind(make):
    plans = Plans(ready=False)
    coordinator, printer, runner, events, pushes = make([MemoryCamera("cam0")], ["ok", "ok", "fail"],
                                                        plans=plans, calibrated=("cam0",))
    layers = []
    original = runner.run_check

    def recording_run(layer, z, frames):
        layers.append(layer)
        time.sleep(0.1)  # slow enough that a racing judgement would interleave
        return original(layer, z, frames)

    runner.run_check = recording_run
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=20 z=4.0")
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=40 z=8.0")
    wait_idle(coordinator, printer)
    plans.ready.set()
    coordinator.on_marker("PRINTWATCH_CHECK", "layer=60 z=12.0")  # views ready, but two checks still queued
    deadline = time.monotonic() + 10
    while "pause" not in printer.calls and time.monotonic() < deadline:
        time.sleep(0.05)
    assert layers == [20, 40, 60]
    verdicts = [c["verdict"] for c in coordinator.history.get_print(coordinator.job.print_id)["checks"]]
    assert verdicts == ["ok", "ok", "fail"] and printer.holds == 0
