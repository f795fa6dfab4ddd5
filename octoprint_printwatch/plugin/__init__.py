"""The OctoPrint plugin: mixins and the hook table. Thin; the adapters beside it do the work.

- ``upload.py``: preprocessor hook -> the core's injector; expected views rendered in the background.
- ``checks.py``: the check coordinator (hold -> frames -> vision in a worker -> release/pause/cancel/notify).
- ``cameras.py``: snapshots from OctoPrint's webcams and our own (URL, video device).
- ``history.py``: SQLite history and recordings. ``api.py``: HTTP endpoints. ``settings.py``: defaults.
- ``calibration.py``: the calibration wizard's server side.
"""
from __future__ import annotations

import os
import shutil
import threading
import uuid
from pathlib import Path

import octoprint.filemanager
import octoprint.filemanager.util
import octoprint.plugin
from octoprint.events import Events

from ..core.errors import PrintWatchError
from . import settings as plugin_settings
from .api import ApiMixin
from .calibration import CalibrationWizard
from .cameras import CameraHealth, OctoPrintWebcam, grab_one, own_cameras
from .checks import BACKGROUND_MARKER, CHECK_MARKER, CUSTOM_EVENTS, CheckCoordinator
from .history import History, utc_now
from .upload import OriginalStore, Preparer, inject_upload, is_injected, planned_checks, sha256_of

IDENTIFIER = "printwatch"
END_RESULTS = {
    Events.PRINT_DONE: "done",
    Events.PRINT_FAILED: "failed",
    Events.PRINT_CANCELLED: "cancelled",
}


class PrintWatchPlugin(
    ApiMixin,
    octoprint.plugin.SettingsPlugin,
    octoprint.plugin.TemplatePlugin,
    octoprint.plugin.AssetPlugin,
    octoprint.plugin.StartupPlugin,
    octoprint.plugin.ShutdownPlugin,
    octoprint.plugin.EventHandlerPlugin,
    octoprint.plugin.BlueprintPlugin,
    octoprint.plugin.WebcamProviderPlugin,
):
    def __init__(self) -> None:
        super().__init__()
        self._bypass = threading.local()  # set while we re-add a file ourselves (no second injection)
        self._upload_notes: dict[str, dict] = {}
        self._injected_cache: dict[str, tuple[float, bool]] = {}
        self.history: History | None = None
        self.coordinator: CheckCoordinator | None = None

    # ------------------------------------------------------------------ life cycle
    def initialize(self) -> None:
        data = Path(self.get_plugin_data_folder())
        self.data_dir = data
        self.history = History(data)
        interrupted = self.history.close_interrupted()
        if interrupted:
            self._logger.info("PrintWatch: prints %s were cut off by a restart; kept as 'interrupted'", interrupted)
        self.originals = OriginalStore(data / "originals")
        self.tmp_dir = data / "tmp"
        shutil.rmtree(self.tmp_dir, ignore_errors=True)
        self.tmp_dir.mkdir(parents=True, exist_ok=True)
        self.preparer = Preparer(self._prepare_job, on_change=self._on_preparation, logger=self._logger)
        self.coordinator = CheckCoordinator(
            printer=self._printer,
            history=self.history,
            settings=self.values,
            cameras=self.camera_sources,
            plans=self.preparer,
            make_runner=self._make_runner,
            emit=self._emit,
            push=self._push,
            logger=self._logger,
        )
        self.coordinator.status_extra = self._status_extra
        self.calibration = CalibrationWizard(data / "calibration", profile=self.bed_profile)

    def on_after_startup(self) -> None:
        self.history.enforce_limits(
            int(float(self.values().get("recording_max_mb", 500)) * 1024 * 1024),
            int(self.values().get("history_keep_prints", 100)),
        )
        self._logger.info("PrintWatch ready: %d calibrated camera(s)", len(plugin_settings.calibrated_cameras(self.values())))
        threading.Thread(target=self._prune_originals, name="printwatch-prune", daemon=True).start()

    #: Expected-view caches kept at start-up (newest first); a file printed again re-renders.
    KEEP_RENDER_CACHES = 20

    def _prune_originals(self) -> None:
        """Kept uploads of files deleted from OctoPrint since, and old view caches: removed at start-up."""
        try:
            listing = self._file_manager.list_files(locations=["local"], recursive=True).get("local", {})
            paths = []

            def walk(entries):
                for entry in entries.values():
                    if entry.get("type") == "folder":
                        walk(entry.get("children") or {})
                    elif entry.get("type") == "machinecode":
                        paths.append(self._file_manager.path_on_disk("local", entry["path"]))

            walk(listing)
            removed = self.originals.prune(paths)
            if removed:
                self._logger.info("PrintWatch: removed %d kept upload(s) of deleted files", len(removed))
            # rendered expected views: keep the most recently used ones
            cache = self.data_dir / "cache"
            folders = sorted((p for p in cache.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime,
                             reverse=True) if cache.exists() else []
            for folder in folders[self.KEEP_RENDER_CACHES:]:
                shutil.rmtree(folder, ignore_errors=True)
        except Exception:
            self._logger.exception("PrintWatch: could not clean up kept uploads")

    def on_shutdown(self) -> None:
        if self.coordinator is not None:
            self.coordinator.shutdown()
        self.preparer.stop()

    # ------------------------------------------------------------------ settings / UI
    def get_settings_defaults(self) -> dict:
        return dict(plugin_settings.DEFAULTS)

    def get_settings_version(self) -> int:
        return 1

    def values(self) -> dict:
        return self._settings.get([], merged=True, asdict=True) or {}

    def on_settings_save(self, data: dict) -> dict:
        # Refuse a change that would break the checks (a negative threshold, an unknown action, a
        # broken calibration) instead of failing at the next check; the UI gets the reason.
        try:
            plugin_settings.validate({**self.values(), **(data or {})})
        except PrintWatchError as exc:
            self._logger.warning("PrintWatch: settings not saved: %s", exc)
            self._push({"type": "notice", "level": "error", "message": f"PrintWatch settings not saved: {exc}"})
            return {}
        saved = octoprint.plugin.SettingsPlugin.on_settings_save(self, data)
        self.coordinator.push_status()
        return saved

    def is_template_autoescaped(self) -> bool:
        return True

    def is_blueprint_csrf_protected(self) -> bool:
        return True  # the UI posts through OctoPrint's JS client (CSRF header); scripts use the API key

    def get_template_configs(self) -> list[dict]:
        return [
            {"type": "tab", "name": "PrintWatch", "template": "printwatch_tab.jinja2", "custom_bindings": True},
            {"type": "settings", "name": "PrintWatch", "template": "printwatch_settings.jinja2", "custom_bindings": True},
            {"type": "generic", "template": "printwatch.jinja2"},
        ]

    #: Script order of the UI (docs/ui.md); any other script in static/js is appended.
    UI_SCRIPTS = ["printwatch_api.js", "printwatch_format.js", "printwatch_chart.js", "printwatch_status.js",
                  "printwatch_print.js", "printwatch_history.js", "printwatch_failure.js",
                  "printwatch_calibration.js", "printwatch_settings.js"]

    def get_assets(self) -> dict:
        static = Path(self._basefolder) / "static"
        present = sorted(p.name for p in (static / "js").glob("*.js"))
        ordered = [n for n in self.UI_SCRIPTS if n in present] + [n for n in present if n not in self.UI_SCRIPTS]
        js = ["vendor/uplot/uPlot.iife.min.js"] if (static / "vendor/uplot/uPlot.iife.min.js").exists() else []
        css = ["vendor/uplot/uPlot.min.css"] if (static / "vendor/uplot/uPlot.min.css").exists() else []
        css += [f"css/{p.name}" for p in sorted((static / "css").glob("*.css"))]
        return {"js": js + [f"js/{n}" for n in ordered], "css": css}

    # ------------------------------------------------------------------ permissions and events (hooks)
    def get_additional_permissions(self, *args, **kwargs) -> list[dict]:
        from octoprint.access import ADMIN_GROUP, USER_GROUP

        return [
            {"key": "VIEW", "name": "PrintWatch: view",
             "description": "See PrintWatch status, checks, history, frames and recordings",
             "roles": ["view"], "default_groups": [USER_GROUP]},
            {"key": "ADMIN", "name": "PrintWatch: administer",
             "description": "Change PrintWatch per-file checks, take snapshots, calibrate, re-run and delete recordings",
             "roles": ["admin"], "dangerous": True, "default_groups": [ADMIN_GROUP]},
        ]

    def register_custom_events(self, *args, **kwargs) -> list[str]:
        return list(CUSTOM_EVENTS)

    def _emit(self, name: str, payload: dict) -> None:
        self._event_bus.fire(f"plugin_{IDENTIFIER}_{name}", payload)

    def _push(self, message: dict) -> None:
        self._plugin_manager.send_plugin_message(IDENTIFIER, message)

    # ------------------------------------------------------------------ upload (preprocessor hook)
    def on_preprocess(self, path, file_object, links=None, printer_profile=None, allow_overwrite=False, *args, **kwargs):
        if getattr(self._bypass, "active", False):
            return file_object
        values = self.values()
        if not (values.get("enabled", True) and values.get("inject_on_upload", True)):
            return file_object
        if not octoprint.filemanager.valid_file_type(path, type="gcode"):
            return file_object
        src = self.tmp_dir / f"upload-{uuid.uuid4().hex}.gcode"
        dst = src.with_name(src.stem + ".injected.gcode")
        file_object.save(str(src))  # consumes the upload stream: from here on we hand back files on disk
        if is_injected(src):
            return octoprint.filemanager.util.DiskFileWrapper(file_object.filename, str(src))
        try:
            result = inject_upload(src, dst, values, printer_profile, self.originals)
        except Exception as exc:  # the upload itself must never be lost: store it as it came
            if isinstance(exc, PrintWatchError):
                self._logger.warning("PrintWatch: %s stored without checks: %s", path, exc)
            else:
                self._logger.exception("PrintWatch: %s stored without checks after an internal error", path)
            self._push({"type": "notice", "level": "warning",
                        "message": f"PrintWatch: {path} was stored without checks: {exc}"})
            self._upload_notes[path] = {"warnings": [str(exc)], "injected": False}
            return octoprint.filemanager.util.DiskFileWrapper(file_object.filename, str(src))
        warnings = [str(w) for w in getattr(result, "warnings", [])]
        self._upload_notes[path] = {"warnings": warnings, "injected": True}
        for warning in warnings:
            self._push({"type": "notice", "level": "warning", "message": f"PrintWatch: {path}: {warning}"})
        src.unlink(missing_ok=True)
        return octoprint.filemanager.util.DiskFileWrapper(file_object.filename, str(dst))

    # ------------------------------------------------------------------ markers (comm thread hook)
    def on_atcommand_sending(self, comm, phase, command, parameters, tags=None, *args, **kwargs):
        if command in (CHECK_MARKER, BACKGROUND_MARKER):
            self.coordinator.on_marker(command, parameters)
        return None

    # ------------------------------------------------------------------ events
    def on_event(self, event: str, payload: dict) -> None:
        payload = payload or {}
        if event == Events.PRINT_STARTED:
            self._on_print_started(payload)
        elif event in END_RESULTS:
            self.coordinator.end_print(END_RESULTS[event])
        elif event == Events.PRINT_PAUSED:
            self.coordinator.on_paused()
        elif event == Events.PRINT_RESUMED:
            self.coordinator.on_resumed()
        elif event == Events.FILE_ADDED and payload.get("storage") == "local":
            self._on_file_added(payload)
        elif event == Events.SETTINGS_UPDATED:
            self.coordinator.push_status()

    def _on_file_added(self, payload: dict) -> None:
        path = payload.get("path")
        if not path or "gcode" not in (payload.get("type") or []):
            return
        note = self._upload_notes.pop(path, None)
        if note is not None:
            try:
                self._file_manager.set_additional_metadata("local", path, IDENTIFIER, note, overwrite=True)
            except Exception:
                self._logger.exception("PrintWatch: could not store notes of %s", path)
        disk = Path(self._file_manager.path_on_disk("local", path))
        planned = planned_checks(disk)
        if planned:
            original = self.originals.original_of(disk)
            self._request_preparation(original, planned)

    def _on_print_started(self, payload: dict) -> None:
        origin, path, name = payload.get("origin"), payload.get("path"), payload.get("name")
        if origin != "local":
            self._push({"type": "notice", "level": "info",
                        "message": "PrintWatch cannot hold SD card prints; this print is not monitored"})
            return
        disk = Path(self._file_manager.path_on_disk("local", path))
        planned = planned_checks(disk)
        if not planned:
            self._push({"type": "notice", "level": "info",
                        "message": f"PrintWatch: {name} has no checks (printed without checks, or uploaded before PrintWatch)"})
            return
        original = self.originals.original_of(disk)
        key = self._request_preparation(original, planned)
        self.coordinator.start_print(origin=origin, path=path, name=name, planned=planned,
                                     original_gcode=original, plan_key=key)

    # ------------------------------------------------------------------ expected views
    def _request_preparation(self, original: Path | None, planned) -> str | None:
        values = self.values()
        cameras = plugin_settings.calibrated_cameras(values)
        if not cameras or original is None:
            return None
        pairs = plugin_settings.stereo_pairs(values, cameras)
        key = Preparer.key_for(sha256_of(original), plugin_settings.camera_set_key(cameras, pairs), planned)
        self.preparer.request(
            key, gcode_path=str(original), cameras=cameras, pairs=pairs, check_heights=list(planned),
            settings=plugin_settings.detection_settings(values), cache_dir=str(self.data_dir / "cache" / key),
        )
        return key

    @staticmethod
    def _prepare_job(**kwargs):
        from ..core.pipeline import prepare_job

        return prepare_job(**kwargs)

    @staticmethod
    def _make_runner(plan, detection, backgrounds):
        from ..core.pipeline import CheckRunner

        return CheckRunner(plan, detection, backgrounds=backgrounds)

    def _on_preparation(self, key: str, status: dict) -> None:
        job = self.coordinator.job if self.coordinator else None
        if job is not None and job.plan_key == key:
            self.coordinator.push_status()
        if status.get("state") == "failed":
            self._push({"type": "notice", "level": "error",
                        "message": f"PrintWatch: expected views could not be rendered: {status.get('message')}"})

    # ------------------------------------------------------------------ cameras
    def camera_sources(self) -> list:
        values = self.values()
        sources = own_cameras(values.get("cameras") or [])
        names = {s.name for s in sources}
        if values.get("use_octoprint_webcams", True):
            try:
                from octoprint.webcams import get_webcams

                for name, provided in get_webcams(self._plugin_manager).items():
                    if provided.providerIdentifier == IDENTIFIER or name in names or not provided.config.canSnapshot:
                        continue
                    info = self._plugin_manager.get_plugin_info(provided.providerIdentifier)
                    implementation = getattr(info, "implementation", None)
                    sources.append(OctoPrintWebcam(
                        name=name, label=provided.config.displayName, source="octoprint",
                        snapshot=getattr(implementation, "take_webcam_snapshot", None),
                    ))
            except Exception:
                self._logger.exception("PrintWatch: could not list OctoPrint's webcams")
        return sources

    def snapshot(self, name: str):
        source = next((s for s in self.camera_sources() if s.name == name), None)
        if source is None:
            return None
        snap = grab_one(source, float(self.values().get("camera_timeout_s", 5.0)))
        if self.coordinator.health.setdefault(name, CameraHealth()).update(snap, utc_now()):
            self.coordinator.push_status()
        return snap

    # WebcamProviderPlugin: our own cameras appear in OctoPrint's webcam list too
    def get_webcam_configurations(self):
        from octoprint.schema.webcam import Webcam, WebcamCompatibility

        webcams = []
        for source in own_cameras(self.values().get("cameras") or []):
            if not source.enabled:
                continue
            url = getattr(source, "url", "") or ""
            webcams.append(Webcam(
                name=source.name,
                displayName=source.label or source.name,
                canSnapshot=True,
                snapshotDisplay=url or source.describe(),
                compat=WebcamCompatibility(snapshot=url, stream=url) if url else None,
                extras={"printwatch": True},
            ))
        return webcams

    def take_webcam_snapshot(self, webcamName):
        source = next((s for s in own_cameras(self.values().get("cameras") or []) if s.name == webcamName), None)
        if source is None:
            from octoprint.webcams import WebcamNotAbleToTakeSnapshotException

            raise WebcamNotAbleToTakeSnapshotException(webcamName)
        return iter([source.fetch(float(self.values().get("camera_timeout_s", 5.0)))])

    # ------------------------------------------------------------------ status
    def _status_extra(self) -> dict:
        values = self.values()
        calibrated = plugin_settings.calibrated_cameras(values)
        cameras = []
        for source in self.camera_sources():
            health = self.coordinator.health.get(source.name, CameraHealth())
            cameras.append({
                "name": source.name, "label": source.label or source.name, "source": source.source,
                "enabled": source.enabled, "calibrated": source.name in calibrated,
                "health": health.health, "last_error": health.last_error, "last_ok": health.last_ok,
                "last_seconds": health.last_seconds, "snapshot_url": f"cameras/{source.name}/snapshot",
            })
        job = None
        current = (self._printer.get_current_job() or {}).get("file") or {}
        if current.get("path"):
            injected = False
            if current.get("origin") == "local":
                injected = self._file_is_injected(current["path"])
            job = {"origin": current.get("origin"), "path": current["path"], "name": current.get("name"),
                   "checks_enabled": injected, "injected": injected}
        return {
            "enabled": bool(values.get("enabled", True)),
            "job": job,
            "cameras": cameras,
            "pairs": [list(p) for p in plugin_settings.stereo_pairs(values, calibrated)],
        }

    def full_status(self) -> dict:
        return self.coordinator.status()

    def _file_is_injected(self, path: str) -> bool:
        try:
            disk = self._file_manager.path_on_disk("local", path)
            mtime = os.path.getmtime(disk)
        except Exception:
            return False
        cached = self._injected_cache.get(disk)
        if cached is None or cached[0] != mtime:
            cached = (mtime, is_injected(disk))
            self._injected_cache[disk] = cached
        return cached[1]

    # ------------------------------------------------------------------ per-file checks
    def _check_file(self, origin: str, path: str) -> Path:
        if origin != "local":
            raise PrintWatchError(f"{origin}:{path}: only files in OctoPrint's local storage can have checks")
        if not self._file_manager.file_exists("local", path):
            raise FileNotFoundError(f"no file {path!r} in local storage")
        return Path(self._file_manager.path_on_disk("local", path))

    def file_checks(self, origin: str, path: str) -> dict:
        disk = self._check_file(origin, path)
        injected = is_injected(disk)
        notes = self._file_manager.get_additional_metadata("local", path, IDENTIFIER) or {}
        planned = planned_checks(disk) if injected else []
        key = None
        if planned:
            values = self.values()
            cameras = plugin_settings.calibrated_cameras(values)
            original = self.originals.original_of(disk)
            if cameras and original is not None:
                pairs = plugin_settings.stereo_pairs(values, cameras)
                key = Preparer.key_for(sha256_of(original), plugin_settings.camera_set_key(cameras, pairs), planned)
        return {
            "origin": origin, "path": path, "injected": injected, "checks_enabled": injected,
            "checks": [{"layer": l, "z": z} for l, z in planned],
            "warnings": list(notes.get("warnings") or []),
            "preparation": self.preparer.status(key),
        }

    def set_file_checks(self, origin: str, path: str, enabled: bool) -> dict:
        disk = self._check_file(origin, path)
        current = (self._printer.get_current_job() or {}).get("file") or {}
        if current.get("path") == path and current.get("origin") == origin and (
                self._printer.is_printing() or self._printer.is_paused()):
            raise PermissionError(f"{path} is being printed; change its checks after the print")
        if enabled == is_injected(disk):
            return self.file_checks(origin, path)
        work = self.tmp_dir / f"toggle-{uuid.uuid4().hex}.gcode"
        if enabled:
            original = self.tmp_dir / f"toggle-{uuid.uuid4().hex}.orig.gcode"
            shutil.copyfile(disk, original)
            profile = self._printer_profile_manager.get_current_or_default()
            result = inject_upload(original, work, self.values(), profile, self.originals)
            original.unlink(missing_ok=True)
            note = {"warnings": [str(w) for w in getattr(result, "warnings", [])], "injected": True}
        else:
            original = self.originals.original_of(disk)
            shutil.copyfile(original, work)
            note = {"warnings": [], "injected": False, "printed_without_checks": True}
        self._upload_notes[path] = note
        self._bypass.active = True
        try:
            self._file_manager.add_file(
                "local", path, octoprint.filemanager.util.DiskFileWrapper(Path(path).name, str(work)),
                allow_overwrite=True,
            )
        finally:
            self._bypass.active = False
        return self.file_checks(origin, path)

    # ------------------------------------------------------------------ evaluate / calibration
    def evaluate_recording(self, root: Path, overrides: dict) -> dict:
        from ..core.pipeline import evaluate_recording
        from ..core.recording import load_recording

        detection = plugin_settings.detection_settings(self.values(), **overrides)
        recording = load_recording(root)
        doc = evaluate_recording(recording, detection, session_label=f"print {root.name}",
                                 cache_dir=self.data_dir / "cache" / f"evaluate-{root.name}")
        for check in doc.get("checks", []):
            check.setdefault("thresholds", {
                "shape_pct": {cam: detection.threshold_for(cam) for cam in check.get("shape_error_pct", {})},
                "size_pct": detection.size_threshold_pct,
            })
        return doc

    def bed_profile(self) -> dict:
        return self._printer_profile_manager.get_current_or_default()

    def save_calibration(self, camera: str) -> dict:
        computed = self.calibration.result_camera(camera)
        calibrations = dict(self.values().get("calibrations") or {})
        calibrations[camera] = computed.to_dict()
        self._settings.set(["calibrations"], calibrations)
        self._settings.save()
        self.coordinator.push_status()
        entry = next((c for c in self._status_extra()["cameras"] if c["name"] == camera), None)
        return {"saved": True, "camera": entry}


def plugin_hooks(plugin: PrintWatchPlugin) -> dict:
    return {
        "octoprint.filemanager.preprocessor": plugin.on_preprocess,
        "octoprint.comm.protocol.atcommand.sending": plugin.on_atcommand_sending,
        "octoprint.access.permissions": plugin.get_additional_permissions,
        "octoprint.events.register_custom_events": plugin.register_custom_events,
    }
