"""HTTP endpoints under ``/plugin/printwatch/`` (``docs/plugin-api.md``), as a mixin of the plugin class.

Each view checks its permission first (``PLUGIN_PRINTWATCH_VIEW`` for reading,
``PLUGIN_PRINTWATCH_ADMIN`` for changes and on-demand frames) and answers bad
input with ``{"error": "<one line>"}`` and a 4xx status, never a traceback.
The work itself is in the plugin's adapters and the core.
"""
from __future__ import annotations

import io
import re
import tempfile
import zipfile
from pathlib import Path

import flask
import octoprint.plugin
from octoprint.access.permissions import Permissions

from ..core.errors import PrintWatchError

route = octoprint.plugin.BlueprintPlugin.route
_SAFE_NAME = re.compile(r"^[A-Za-z0-9_.\-]+$")


def error(status: int, message: str):
    response = flask.jsonify(error=message)
    response.status_code = status
    return response


def require(permission_name: str):
    """403 unless the current user has ``PLUGIN_PRINTWATCH_<name>``."""
    permission = getattr(Permissions, f"PLUGIN_PRINTWATCH_{permission_name}", None)
    if permission is None or not permission.can():
        flask.abort(403)


class ApiMixin:
    """Blueprint views. ``self`` is the :class:`PrintWatchPlugin`."""

    # ------------------------------------------------------------------ status
    @route("/status", methods=["GET"])
    def api_status(self):
        require("VIEW")
        return flask.jsonify(self.full_status())

    # ------------------------------------------------------------------ history
    @route("/prints", methods=["GET"])
    def api_prints(self):
        require("VIEW")
        try:
            limit = max(1, min(500, int(flask.request.args.get("limit", 50))))
            offset = max(0, int(flask.request.args.get("offset", 0)))
        except ValueError:
            return error(400, "limit and offset must be whole numbers")
        prints, total = self.history.list_prints(limit, offset)
        return flask.jsonify(prints=prints, total=total)

    @route("/prints/<int:print_id>", methods=["GET"])
    def api_print(self, print_id):
        require("VIEW")
        detail = self.history.get_print(print_id)
        if detail is None:
            return error(404, f"print {print_id} is not in the history")
        return flask.jsonify(detail)

    @route("/prints/<int:print_id>", methods=["DELETE"])
    def api_print_delete(self, print_id):
        require("ADMIN")
        job = self.coordinator.job
        if job is not None and job.print_id == print_id:
            return error(409, f"print {print_id} is running; it can be deleted once it ends")
        if not self.history.delete_print(print_id):
            return error(404, f"print {print_id} is not in the history")
        return flask.jsonify(deleted=print_id)

    def _recording_file(self, print_id: int, rel: str) -> Path | None:
        root = self.history.recording_dir(print_id).resolve()
        path = (root / rel).resolve()
        if root not in path.parents or not path.is_file():
            return None
        return path

    @route("/prints/<int:print_id>/checks/<int:index>/<camera>/frame.jpg", methods=["GET"])
    def api_check_frame(self, print_id, index, camera):
        require("VIEW")
        if not _SAFE_NAME.match(camera):
            return error(400, f"bad camera name {camera!r}")
        for suffix in (".jpg", ".png"):
            path = self._recording_file(print_id, f"checks/{index:03d}/{camera}{suffix}")
            if path is not None:
                return flask.send_file(str(path), mimetype="image/jpeg" if suffix == ".jpg" else "image/png",
                                       max_age=3600)
        return error(404, f"print {print_id} check {index} has no frame of camera {camera}")

    @route("/prints/<int:print_id>/checks/<int:index>/<camera>/overlay.png", methods=["GET"])
    def api_check_overlay(self, print_id, index, camera):
        require("VIEW")
        if not _SAFE_NAME.match(camera):
            return error(400, f"bad camera name {camera!r}")
        path = self._recording_file(print_id, f"checks/{index:03d}/{camera}.overlay.png")
        if path is None:
            return error(404, f"print {print_id} check {index} has no overlay of camera {camera}")
        return flask.send_file(str(path), mimetype="image/png", max_age=3600)

    @route("/prints/<int:print_id>/background/<camera>.jpg", methods=["GET"])
    def api_background(self, print_id, camera):
        require("VIEW")
        if not _SAFE_NAME.match(camera):
            return error(400, f"bad camera name {camera!r}")
        for suffix in (".jpg", ".png"):
            path = self._recording_file(print_id, f"background/{camera}{suffix}")
            if path is not None:
                return flask.send_file(str(path), mimetype="image/jpeg" if suffix == ".jpg" else "image/png")
        return error(404, f"print {print_id} has no background frame of camera {camera}")

    @route("/prints/<int:print_id>/recording.zip", methods=["GET"])
    def api_recording(self, print_id):
        require("VIEW")
        root = self.history.recording_dir(print_id)
        if not (root / "session.json").is_file():
            return error(404, f"print {print_id} has no recording (none was made, or it was removed by the size cap)")
        spool = tempfile.SpooledTemporaryFile(max_size=32 * 1024 * 1024)
        folder = f"printwatch-print-{print_id}"
        with zipfile.ZipFile(spool, "w", zipfile.ZIP_DEFLATED) as archive:
            for path in sorted(root.rglob("*")):
                if path.is_file() and not path.name.endswith(".tmp"):
                    # frames are JPEG/PNG already: storing them is as small and much faster
                    method = zipfile.ZIP_STORED if path.suffix in (".jpg", ".png") else zipfile.ZIP_DEFLATED
                    archive.write(path, f"{folder}/{path.relative_to(root).as_posix()}", compress_type=method)
        spool.seek(0)
        return flask.send_file(spool, mimetype="application/zip", as_attachment=True,
                               download_name=f"{folder}.zip")

    @route("/prints/<int:print_id>/evaluate", methods=["POST"])
    def api_evaluate(self, print_id):
        require("ADMIN")
        root = self.history.recording_dir(print_id)
        if not (root / "session.json").is_file():
            return error(404, f"print {print_id} has no recording to re-run")
        body = flask.request.get_json(silent=True) or {}
        overrides = body.get("settings") or {}
        if not isinstance(overrides, dict):
            return error(400, "settings must be an object of settings keys")
        try:
            return flask.jsonify(self.evaluate_recording(root, overrides))
        except PrintWatchError as exc:
            return error(400, str(exc))

    # ------------------------------------------------------------------ cameras
    @route("/cameras", methods=["GET"])
    def api_cameras(self):
        require("VIEW")
        status = self.full_status()
        return flask.jsonify(cameras=status["cameras"], pairs=status["pairs"])

    @route("/cameras/<name>/snapshot", methods=["GET"])
    def api_snapshot(self, name):
        require("ADMIN")
        snap = self.snapshot(name)
        if snap is None:
            return error(404, f"no camera named {name!r}")
        if not snap.ok:
            return error(503, snap.error or f"camera {name} gave no frame")
        data = snap.encoded
        mimetype = "image/png" if data[:4] == b"\x89PNG" else "image/jpeg"
        return flask.send_file(io.BytesIO(data), mimetype=mimetype, max_age=0)

    @route("/cameras/<name>/test", methods=["POST"])
    def api_camera_test(self, name):
        require("ADMIN")
        if self.snapshot(name) is None:
            return error(404, f"no camera named {name!r}")
        camera = next((c for c in self.full_status()["cameras"] if c["name"] == name), None)
        return flask.jsonify(camera)

    # ------------------------------------------------------------------ files
    @route("/files/<origin>/<path:path>", methods=["GET"])
    def api_file(self, origin, path):
        require("VIEW")
        try:
            return flask.jsonify(self.file_checks(origin, path))
        except FileNotFoundError as exc:
            return error(404, str(exc))
        except PrintWatchError as exc:
            return error(400, str(exc))

    @route("/files/<origin>/<path:path>", methods=["POST"])
    def api_file_set(self, origin, path):
        require("ADMIN")
        body = flask.request.get_json(silent=True) or {}
        if not isinstance(body.get("checks_enabled"), bool):
            return error(400, 'body must be {"checks_enabled": true|false}')
        try:
            return flask.jsonify(self.set_file_checks(origin, path, body["checks_enabled"]))
        except FileNotFoundError as exc:
            return error(404, str(exc))
        except PermissionError as exc:
            return error(409, str(exc))
        except PrintWatchError as exc:
            return error(400, str(exc))

    # ------------------------------------------------------------------ calibration wizard
    @route("/calibration/board", methods=["GET"])
    def api_calibration_board(self):
        require("VIEW")
        return flask.jsonify(board=self.calibration.board_json(), image_url="calibration/board.png")

    @route("/calibration/board.png", methods=["GET"])
    def api_calibration_board_png(self):
        require("VIEW")
        return flask.send_file(io.BytesIO(self.calibration.board_png()), mimetype="image/png",
                               download_name="printwatch-board.png")

    @route("/calibration/<camera>", methods=["GET"])
    def api_calibration_session(self, camera):
        require("ADMIN")
        return self._calibration_call(lambda: self.calibration.session_json(camera))

    @route("/calibration/<camera>", methods=["DELETE"])
    def api_calibration_reset(self, camera):
        require("ADMIN")
        return self._calibration_call(lambda: self.calibration.reset(camera))

    @route("/calibration/<camera>/capture", methods=["POST"])
    def api_calibration_capture(self, camera):
        require("ADMIN")
        return self._calibration_call(lambda: self.calibration.capture(camera, self.snapshot(camera)))

    @route("/calibration/<camera>/frames/<int:index>", methods=["DELETE"])
    def api_calibration_drop(self, camera, index):
        require("ADMIN")
        return self._calibration_call(lambda: self.calibration.drop(camera, index))

    @route("/calibration/<camera>/frames/<int:index>.jpg", methods=["GET"])
    def api_calibration_frame(self, camera, index):
        require("ADMIN")
        data = self.calibration.frame_jpeg(camera, index)
        if data is None:
            return error(404, f"camera {camera} has no calibration frame {index}")
        return flask.send_file(io.BytesIO(data), mimetype="image/jpeg", max_age=0)

    @route("/calibration/<camera>/compute", methods=["POST"])
    def api_calibration_compute(self, camera):
        require("ADMIN")
        return self._calibration_call(lambda: self.calibration.compute(camera, self.bed_profile()))

    @route("/calibration/<camera>/save", methods=["POST"])
    def api_calibration_save(self, camera):
        require("ADMIN")
        return self._calibration_call(lambda: self.save_calibration(camera))

    def _calibration_call(self, fn):
        try:
            return flask.jsonify(fn())
        except KeyError as exc:
            return error(404, str(exc.args[0]) if exc.args else "unknown camera")
        except PrintWatchError as exc:
            return error(400, str(exc))
