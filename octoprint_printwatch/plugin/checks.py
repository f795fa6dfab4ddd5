"""The check coordinator: marker -> hold -> frames -> vision (worker thread) -> release / pause / cancel / notify.

OctoPrint calls :meth:`CheckCoordinator.on_marker` from its send thread when an
injected ``@PRINTWATCH_CHECK`` (or ``@PRINTWATCH_BACKGROUND``) comes up; it
puts the job on hold and returns at once. A single worker thread grabs the
frames, runs the core's :class:`CheckRunner`, stores the check, and either
releases the hold or pauses/cancels the job *before* releasing it, so not one
more line of the file is printed after a failure. The hold is released in a
``finally`` whatever happens (OctoPrint's ``set_job_on_hold`` contract).

When the expected views are still rendering at a check, the frames are kept,
the hold is released after ``prepare_wait_s`` and the check is judged as soon
as the views are ready (a late pause beats no check); the print never waits
for rendering. Dead cameras are reported and never fail a check; with no frame
at all the verdict is ``unknown`` and the print goes on.

Host-independent: the printer, event bus and push channel are passed in, so the
unit tests drive it with a recording printer and real frames.
"""
from __future__ import annotations

import logging
import re
import shutil
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

import cv2
import numpy as np

from ..core.camera import Camera
from ..core.recording import RecordingWriter
from . import settings as plugin_settings
from .cameras import CameraHealth, CameraSource, Snapshot, grab_all
from .history import History, utc_now

CHECK_MARKER = "PRINTWATCH_CHECK"
BACKGROUND_MARKER = "PRINTWATCH_BACKGROUND"
_PARAM = re.compile(r"(\w+)=([^\s]+)")

EVENT_CHECK_DONE = "check_done"
EVENT_FAILURE = "failure_detected"
EVENT_CAMERA_ERROR = "camera_error"
CUSTOM_EVENTS = [EVENT_CHECK_DONE, EVENT_FAILURE, EVENT_CAMERA_ERROR]


class CameraBytesWriter(RecordingWriter):
    """A recording writer that stores the JPEG bytes each camera sent, unchanged.

    Re-encoding would make a replay (``printwatch evaluate``, the re-run endpoint) see other
    pixels than the live check saw; with the camera's own bytes both decode identically.
    """

    def __init__(self, *args, **kwargs) -> None:
        self._sent: dict[int, bytes] = {}
        super().__init__(*args, **kwargs)

    def remember(self, image: np.ndarray, encoded: bytes | None) -> None:
        if encoded and encoded[:2] == b"\xff\xd8":
            self._sent[id(image)] = encoded

    def _write_image(self, rel: str, image: np.ndarray) -> None:
        encoded = self._sent.pop(id(image), None)
        if encoded is None or not rel.endswith(".jpg"):
            return super()._write_image(rel, image)
        path = self.root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(encoded)
        tmp.replace(path)


def parse_marker_parameters(parameters: str) -> dict[str, str]:
    """``'layer=30 z=6.0'`` -> ``{'layer': '30', 'z': '6.0'}``."""
    return {k.lower(): v for k, v in _PARAM.findall(parameters or "")}


@dataclass
class JobContext:
    """Everything the coordinator knows about the print that is running."""

    print_id: int
    origin: str
    path: str
    name: str
    planned: list[tuple[int, float]]
    plan_key: str | None
    cameras: dict[str, Camera]
    pairs: list[tuple[str, str]]
    writer: CameraBytesWriter | None
    backgrounds: dict[str, np.ndarray] = field(default_factory=dict)
    runner: Any = None
    checks_done: int = 0
    paused_by_us: bool = False
    last_check: dict | None = None
    deferred: int = 0  # checks waiting for the expected views; later checks queue behind them, in order


class CheckCoordinator:
    """Runs the checks of the print in progress. One instance per plugin.

    Parameters
    ----------
    printer : object with ``set_job_on_hold(bool)``, ``pause_print(tags=...)``,
        ``cancel_print(tags=...)``, ``commands(list)``
    history : History
    settings : () -> dict, the current ``plugins.printwatch`` settings
    cameras : () -> list[CameraSource], every camera the plugin can use
    plans : object with ``wait(key, timeout) -> JobPlan | None`` and ``status(key) -> dict``
    make_runner : (plan, DetectionSettings, backgrounds) -> object with ``run_check(layer, z, frames)``
    emit : (event_name_without_prefix, payload) -> None   (OctoPrint custom events)
    push : (message dict) -> None                          (plugin message to the UI)
    """

    def __init__(self, *, printer, history: History, settings: Callable[[], Mapping[str, Any]],
                 cameras: Callable[[], list[CameraSource]], plans, make_runner,
                 emit: Callable[[str, dict], None], push: Callable[[dict], None],
                 logger: logging.Logger | None = None) -> None:
        self._printer = printer
        self.history = history
        self._settings = settings
        self._cameras = cameras
        self._plans = plans
        self._make_runner = make_runner
        self._emit = emit
        self._push = push
        self._log = logger or logging.getLogger(__name__)
        self._lock = threading.RLock()
        self._worker = ThreadPoolExecutor(max_workers=1, thread_name_prefix="printwatch-check")
        self._late = ThreadPoolExecutor(max_workers=1, thread_name_prefix="printwatch-late")
        self.job: JobContext | None = None
        self.state = "idle"
        self.health: dict[str, CameraHealth] = {}
        self.last_failure: dict | None = None
        self.hold_count = 0  # holds taken and not yet released (0 between checks)
        #: () -> dict merged into every status (job file, cameras, pairs: things the plugin knows).
        self.status_extra: Callable[[], dict] | None = None

    # ------------------------------------------------------------------ print lifecycle
    def start_print(self, *, origin: str, path: str, name: str, planned: list[tuple[int, float]],
                    original_gcode: Path | None, plan_key: str | None) -> int | None:
        values = self._settings()
        if not values.get("enabled", True):
            return None
        cameras = plugin_settings.calibrated_cameras(values)
        pairs = plugin_settings.stereo_pairs(values, cameras)
        detection = plugin_settings.detection_settings(values)
        print_id = self.history.start_print(
            origin, path, name, [{"layer": l, "z": z} for l, z in planned], detection.to_dict()
        )
        writer = None
        if cameras and original_gcode is not None and Path(original_gcode).is_file():
            try:
                writer = CameraBytesWriter(self.history.recording_dir(print_id), cameras, pairs=pairs,
                                           gcode=original_gcode)
            except Exception as exc:  # no recording is no reason to stop watching
                self._notice("warning", f"PrintWatch: cannot write the recording of print {print_id}: {exc}")
        with self._lock:
            self.job = JobContext(print_id, origin, path, name, list(planned), plan_key, cameras, pairs, writer)
            self.state = "monitoring"
            self.last_failure = None
        if not cameras:
            self._notice("warning", "PrintWatch: no calibrated camera; checks will report 'unknown' until one is calibrated")
        self.push_status()
        return print_id

    def end_print(self, result: str) -> None:
        with self._lock:
            job, self.job = self.job, None
            self.state = "idle"
        if job is None:
            return
        # A check whose hold was released may still be storing when the job ends (the last check sits
        # close to the end of the file): the single worker closes the print after it, so a finished
        # print's history always holds every check it ran.
        try:
            self._worker.submit(self._close_print, job, result)
        except RuntimeError:  # executor shut down (OctoPrint stopping)
            self._close_print(job, result)

    def _close_print(self, job: JobContext, result: str) -> None:
        self.history.end_print(job.print_id, result)
        values = self._settings()
        if not values.get("recording_enabled", True):
            shutil.rmtree(self.history.recording_dir(job.print_id), ignore_errors=True)
        self.history.enforce_limits(
            int(float(values.get("recording_max_mb", 500)) * 1024 * 1024),
            int(values.get("history_keep_prints", 100)),
        )
        self.push_status()

    def on_paused(self) -> None:
        with self._lock:
            job = self.job
            if job is not None and job.paused_by_us:
                self.state = "paused"
                self.history.set_result(job.print_id, "paused")
        self.push_status()

    def on_resumed(self) -> None:
        with self._lock:
            job = self.job
            if job is not None:
                job.paused_by_us = False
                self.state = "monitoring"
                self.history.set_result(job.print_id, "running")
        self.push_status()

    def shutdown(self) -> None:
        self._worker.shutdown(wait=False, cancel_futures=False)
        self._late.shutdown(wait=False, cancel_futures=True)

    # ------------------------------------------------------------------ markers (OctoPrint's send thread)
    def on_marker(self, command: str, parameters: str) -> None:
        """Called from OctoPrint's comm thread: hold the job and hand the work to the worker. Never blocks long."""
        job = self.job
        if job is None or command not in (CHECK_MARKER, BACKGROUND_MARKER):
            return
        if command == CHECK_MARKER:
            params = parse_marker_parameters(parameters)
            try:
                layer, z = int(params["layer"]), float(params["z"])
            except (KeyError, ValueError):
                self._log.warning("PrintWatch: ignoring malformed marker @%s %s", command, parameters)
                return
        if not self._hold():
            self._log.warning("PrintWatch: could not put the job on hold for @%s; skipped", command)
            return
        held_at = time.monotonic()
        try:
            if command == BACKGROUND_MARKER:
                self._worker.submit(self._guarded, self._capture_background, job, held_at)
            else:
                with self._lock:
                    self.state = "checking"
                self._worker.submit(self._guarded, self._run_check, job, layer, z, held_at)
        except RuntimeError:  # executor shut down (OctoPrint stopping): never leave the job held
            self._release()

    def _hold(self) -> bool:
        ok = bool(self._printer.set_job_on_hold(True))
        if ok:
            with self._lock:
                self.hold_count += 1
        return ok

    def _release(self) -> None:
        with self._lock:
            if self.hold_count <= 0:
                return
            self.hold_count -= 1
        self._printer.set_job_on_hold(False)

    def _guarded(self, fn, job: JobContext, *args) -> None:
        """Worker entry: whatever ``fn`` does or raises, the hold it was given is released exactly once."""
        released = {"done": False}

        def release_once():
            if not released["done"]:
                released["done"] = True
                self._release()

        try:
            fn(job, *args, release=release_once)
        except Exception:
            self._log.exception("PrintWatch: check failed with an internal error; the print continues")
            self._notice("error", "PrintWatch: internal error during a check (see octoprint.log); the print continues")
        finally:
            release_once()
            with self._lock:
                if self.state == "checking" and self.job is job:
                    self.state = "monitoring"
            self.push_status()

    # ------------------------------------------------------------------ frames
    def _grab(self, job: JobContext, only: set[str] | None = None) -> dict[str, Snapshot]:
        values = self._settings()
        sources = [s for s in self._cameras() if only is None or s.name in only]
        snaps = grab_all(sources, float(values.get("camera_timeout_s", 5.0)))
        now = utc_now()
        for name, snap in snaps.items():
            changed = self.health.setdefault(name, CameraHealth()).update(snap, now)
            if not snap.ok:
                self._log.warning("PrintWatch: %s", snap.error)
                if changed:
                    self._emit(EVENT_CAMERA_ERROR, {"camera": name, "error": snap.error})
                    self._notice("warning", f"PrintWatch: {snap.error}")
        return snaps

    def _capture_background(self, job: JobContext, held_at: float, *, release) -> None:
        snaps = self._grab(job)
        missing = {name for name, snap in snaps.items() if not snap.ok and name in job.cameras}
        if missing:
            # Without its empty-bed frame a camera gives no verdict for the whole print:
            # one more try is worth a few seconds before the first layer.
            snaps.update(self._grab(job, only=missing))
        release()  # the bed is captured; the print may go on while we store it
        for name, snap in snaps.items():
            if snap.ok and name in job.cameras:
                job.backgrounds[name] = snap.image
                if job.writer is not None:
                    job.writer.remember(snap.image, snap.encoded)
                    job.writer.add_background(name, snap.image)

    # ------------------------------------------------------------------ a check
    def _run_check(self, job: JobContext, layer: int, z: float, held_at: float, *, release) -> None:
        values = self._settings()
        snaps = self._grab(job)
        frames = {name: (snap.image if snap.ok else None) for name, snap in snaps.items() if name in job.cameras}
        index = job.checks_done
        job.checks_done += 1
        if job.writer is not None and job.cameras:
            for name, snap in snaps.items():
                if snap.ok and name in job.cameras:
                    job.writer.remember(snap.image, snap.encoded)
            job.writer.add_check(layer, z, {name: frames.get(name) for name in job.cameras})
        plan = self._plans.wait(job.plan_key, float(values.get("prepare_wait_s", 2.0))) if job.plan_key else None
        if (plan is None or job.deferred) and job.plan_key and any(f is not None for f in frames.values()):
            state = self._plans.status(job.plan_key).get("state")
            if state not in ("failed", "none"):
                # Expected views not ready: judge later, do not keep the printer waiting.
                check = self._check_json(job, index, layer, z, snaps, None, time.monotonic() - held_at, values)
                check["verdict"] = "unknown"
                check["pending"] = True
                check["reasons"] = ["expected views are still being rendered; this check is judged when they are ready"]
                self._store(job, check)
                release()
                with self._lock:
                    job.deferred += 1
                self._late.submit(self._judge_late, job, index, layer, z, snaps, held_at, check["hold_seconds"])
                return
        self._judge(job, index, layer, z, snaps, plan, held_at, release=release)

    def _judge_late(self, job: JobContext, index: int, layer: int, z: float, snaps, held_at: float,
                    held_for: float) -> None:
        try:
            plan = self._plans.wait(job.plan_key, 3600.0)
            self._judge(job, index, layer, z, snaps, plan, held_at, release=lambda: None, late=True,
                        held_for=held_for)
        except Exception:
            self._log.exception("PrintWatch: late check failed with an internal error")
        finally:
            with self._lock:  # one thread (the late executor) runs these, in the order of the checks
                job.deferred -= 1

    def _judge(self, job: JobContext, index: int, layer: int, z: float, snaps: Mapping[str, Snapshot],
               plan, held_at: float, *, release, late: bool = False, held_for: float | None = None) -> None:
        values = self._settings()
        detection = plugin_settings.detection_settings(values)
        frames = {name: (snap.image if snap.ok else None) for name, snap in snaps.items() if name in job.cameras}
        result = None
        reasons: list[str] = []
        if not job.cameras:
            reasons.append("no calibrated camera: nothing to compare")
        elif not any(f is not None for f in frames.values()):
            reasons.append("no camera gave a frame")
        elif plan is None:
            status = self._plans.status(job.plan_key) if job.plan_key else {}
            reasons.append("expected views unavailable: " + (status.get("message") or "no G-code analysis"))
        else:
            if job.runner is None or getattr(job.runner, "_printwatch_plan", None) is not plan:
                job.runner = self._make_runner(plan, detection, dict(job.backgrounds))
                job.runner._printwatch_plan = plan
            result = job.runner.run_check(layer, z, frames)
        check = self._check_json(job, index, layer, z, snaps, result, time.monotonic() - held_at, values)
        if result is None:
            check["verdict"] = "unknown"
            check["reasons"] = reasons
        failed = check["verdict"] == "fail"
        action = plugin_settings.action(values) if failed else "none"
        check["action"] = action
        if failed:
            message = (f"PrintWatch {'paused' if action == 'pause' else 'cancelled' if action == 'cancel' else 'flagged'}"
                       f" the print at layer {layer} (z {z:.2f} mm): " + "; ".join(check["reasons"] or ["check failed"]))
            if late:
                message += " (judged late: the expected views were still rendering at the check)"
            with self._lock:
                if action == "pause" and self.job is job:
                    job.paused_by_us = True
                    self._printer.pause_print(tags={"plugin:printwatch"})
                elif action == "cancel" and self.job is job:
                    self._printer.cancel_print(tags={"plugin:printwatch"})
                self.last_failure = {"print_id": job.print_id, "layer": layer, "reason": message, "action": action}
            try:  # the reason on the printer's display too, where supported
                self._printer.commands([f"M117 PrintWatch: layer {layer} failed"], tags={"plugin:printwatch"})
            except Exception:
                pass
        check["hold_seconds"] = round(time.monotonic() - held_at, 3) if held_for is None else held_for
        release()  # after pause_print: the comm layer is already paused when the hold lifts
        self._write_overlays(job, index, result)
        self._store(job, check)
        payload = {"print_id": job.print_id, "file": {"origin": job.origin, "path": job.path, "name": job.name}, **check}
        self._emit(EVENT_CHECK_DONE, payload)
        self._push({"type": "check", "print_id": job.print_id, "check": check})
        if failed:
            self._emit(EVENT_FAILURE, {**payload, "message": message, "action": action})
            self._push({"type": "failure", "print_id": job.print_id, "check": check, "action": action, "message": message})

    def _check_json(self, job: JobContext, index: int, layer: int, z: float, snaps: Mapping[str, Snapshot],
                    result, elapsed: float, values: Mapping[str, Any]) -> dict:
        detection = plugin_settings.detection_settings(values)
        data = result.to_json() if result is not None else {}
        cameras = {}
        for name, snap in snaps.items():
            entry = {"status": snap.status, "error": snap.error, "frame_url": None, "overlay_url": None}
            if snap.ok and job.writer is not None and name in job.cameras:
                entry["frame_url"] = f"prints/{job.print_id}/checks/{index}/{name}/frame.jpg"
                if _overlay_of(result, name) is not None:  # written by _write_overlays, after the hold
                    entry["overlay_url"] = f"prints/{job.print_id}/checks/{index}/{name}/overlay.png"
            if name not in job.cameras and snap.ok:
                entry["error"] = f"camera {name} is not calibrated; its frame is not checked"
            cameras[name] = entry
        return {
            "index": index,
            "layer": int(layer),
            "z": float(z),
            "time": utc_now(),
            "verdict": data.get("verdict", "unknown"),
            "shape_error_pct": data.get("shape_error_pct", {}),
            "size": data.get("size", {}),
            "thresholds": {
                "shape_pct": {name: detection.threshold_for(name) for name in job.cameras},
                "size_pct": detection.size_threshold_pct,
            },
            "reasons": list(data.get("reasons", [])),
            "cameras": cameras,
            "seconds": data.get("seconds", 0.0),
            "hold_seconds": round(elapsed, 3),
            "action": "none",
        }

    @staticmethod
    def _write_overlays(job: JobContext, index: int, result) -> None:
        """The core's overlays (frame, expected outline, missing/extra material) beside the frames."""
        if result is None or job.writer is None:
            return
        for name in job.cameras:
            overlay = _overlay_of(result, name)
            if overlay is not None:
                path = job.writer.root / "checks" / f"{index:03d}" / f"{name}.overlay.png"
                path.parent.mkdir(parents=True, exist_ok=True)
                cv2.imwrite(str(path), overlay)

    def _store(self, job: JobContext, check: dict) -> None:
        self.history.add_check(job.print_id, check)
        job.last_check = check

    # ------------------------------------------------------------------ status
    def _notice(self, level: str, message: str) -> None:
        self._push({"type": "notice", "level": level, "message": message})

    def status(self, extra: Mapping[str, Any] | None = None) -> dict:
        with self._lock:
            job = self.job
            planned = [{"layer": l, "z": z} for l, z in (job.planned if job else [])]
            done = job.checks_done if job else 0
            status = {
                "api": "printwatch-api/1",
                "state": self.state,
                "print_id": job.print_id if job else None,
                "planned_checks": planned,
                "checks_done": done,
                "next_check": planned[done] if job and done < len(planned) else None,
                "last_check": job.last_check if job else None,
                "last_failure": self.last_failure,
                "preparation": self._plans.status(job.plan_key) if job and job.plan_key else {"state": "none", "progress": 0.0, "message": ""},
            }
        if self.status_extra is not None:
            status.update(self.status_extra())
        if extra:
            status.update(extra)
        return status

    def push_status(self) -> None:
        try:
            self._push({"type": "status", "status": self.status()})
        except Exception:
            self._log.exception("PrintWatch: could not push the status")


def _overlay_of(result, camera: str) -> np.ndarray | None:
    """The overlay image (h, w, 3) uint8 BGR the core drew for ``camera``, if any."""
    if result is None:
        return None
    shape = getattr(result, "shape", None)
    entry = shape.get(camera) if isinstance(shape, Mapping) else None
    overlay = getattr(entry, "overlay", None) if entry is not None else None
    return overlay if isinstance(overlay, np.ndarray) else None
