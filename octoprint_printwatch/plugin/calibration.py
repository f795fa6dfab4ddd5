"""Server side of the calibration wizard: board frames per camera, compute, keep the result.

The wizard's steps (``docs/plugin-api.md``): print the board, capture 10-15
frames of it held in different places and tilts, then one frame with the board
lying flat in the bed's front-left corner (its caption edge to the back) as the
*last* capture; *compute* runs the core's intrinsics calibration on all frames
and the bed pose on the last one; *save* stores the camera in the settings.
Sessions live in memory (a wizard is minutes long); no OctoPrint import.
"""
from __future__ import annotations

import threading
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any, Mapping

import cv2
import numpy as np

from ..core.boards import Board, board_for_bed, detect_board, printable_page
from ..core.camera import Camera
from ..core.errors import CalibrationError
from . import settings as plugin_settings

#: Frames with a detected board before "compute" is offered.
NEEDED_FRAMES = 10


@dataclass
class CapturedFrame:
    image: np.ndarray  # (h, w, 3) uint8 BGR
    corners: int
    pixels: np.ndarray | None  # (n, 2) detected corners


@dataclass
class Session:
    frames: list[CapturedFrame] = field(default_factory=list)
    result: dict | None = None
    camera: Camera | None = None


class CalibrationWizard:
    def __init__(self, folder: str | Path, profile: Mapping[str, Any] | None = None) -> None:
        self.folder = Path(folder)
        self._sessions: dict[str, Session] = {}
        self._lock = threading.Lock()
        self._profile = profile

    def _current_profile(self):
        return self._profile() if callable(self._profile) else self._profile

    def board(self, profile: Mapping[str, Any] | None = None) -> Board:
        x_min, x_max, y_min, y_max, _ = plugin_settings.bed_from_profile(profile or self._current_profile())
        return board_for_bed((x_max - x_min, y_max - y_min))

    def board_json(self, profile: Mapping[str, Any] | None = None) -> dict:
        board = self.board(profile)
        return {**asdict(board), "description": board.describe(), "placement": "front-left",
                "needed_frames": NEEDED_FRAMES}

    def board_png(self, profile: Mapping[str, Any] | None = None) -> bytes:
        ok, data = cv2.imencode(".png", printable_page(self.board(profile), dpi=200))
        return data.tobytes()

    def _session(self, camera: str) -> Session:
        return self._sessions.setdefault(camera, Session())

    def session_json(self, camera: str) -> dict:
        with self._lock:
            session = self._session(camera)
            return {
                "camera": camera,
                "needed": NEEDED_FRAMES,
                "frames": [{"index": i, "detected": f.corners > 0, "corners": f.corners,
                            "image_url": f"calibration/{camera}/frames/{i}.jpg"} for i, f in enumerate(session.frames)],
                "result": session.result,
            }

    def reset(self, camera: str) -> dict:
        with self._lock:
            self._sessions.pop(camera, None)
        return self.session_json(camera)

    def capture(self, camera: str, snap) -> dict:
        if snap is None:
            raise KeyError(f"no camera named {camera!r}")
        if not snap.ok:
            raise CalibrationError(snap.error or f"camera {camera} gave no frame")
        detection = detect_board(snap.image, self.board())
        frame = CapturedFrame(snap.image, len(detection) if detection is not None else 0,
                              detection.pixels if detection is not None else None)
        with self._lock:
            self._session(camera).frames.append(frame)
        return self.session_json(camera)

    def drop(self, camera: str, index: int) -> dict:
        with self._lock:
            frames = self._session(camera).frames
            if not 0 <= index < len(frames):
                raise KeyError(f"camera {camera} has no calibration frame {index}")
            frames.pop(index)
        return self.session_json(camera)

    def frame_jpeg(self, camera: str, index: int) -> bytes | None:
        with self._lock:
            frames = self._session(camera).frames
            if not 0 <= index < len(frames):
                return None
            frame = frames[index]
        image = frame.image.copy()
        if frame.pixels is not None:
            for x, y in frame.pixels:
                cv2.circle(image, (int(round(x)), int(round(y))), 4, (0, 200, 0), 2)
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 85])
        return data.tobytes()

    def compute(self, camera: str, profile: Mapping[str, Any] | None) -> dict:
        from ..core.calibration import BoardPlacement, calibrate_bed_pose, calibrate_intrinsics

        with self._lock:
            frames = list(self._session(camera).frames)
        usable = [f for f in frames if f.corners > 0]
        if len(usable) < 3:
            raise CalibrationError(f"camera {camera}: the board was found in {len(usable)} frame(s); capture at "
                                   f"least {NEEDED_FRAMES} views of it before computing")
        board = self.board(profile)
        intrinsics = calibrate_intrinsics([f.image for f in usable], board, name=camera,
                                          labels=[f"frame {i}" for i, f in enumerate(frames) if f.corners > 0])
        x_min, _, y_min, _, _ = plugin_settings.bed_from_profile(profile or self._current_profile())
        pose = calibrate_bed_pose(usable[-1].image, intrinsics.camera, board,
                                  BoardPlacement.front_left(board, bed_origin=(x_min, y_min)))
        reasons = list(intrinsics.reasons) + list(pose.warnings)
        if intrinsics.verdict == "good" and not pose.warnings:
            verdict = "good"
        elif intrinsics.rms_px <= 2.0 and pose.reprojection_px <= 3.0:
            verdict = "acceptable"
        else:
            verdict = "poor"
        message = ("calibration is good" if verdict == "good" else "; ".join(reasons) or "calibration is usable")
        result = {
            "rms_px": round(float(intrinsics.rms_px), 4),
            "bed_rms_px": round(float(pose.reprojection_px), 4),
            "verdict": verdict,
            "message": message,
            "reasons": reasons,
            "camera": pose.camera.to_dict(),
        }
        with self._lock:
            session = self._session(camera)
            session.result, session.camera = result, pose.camera
        return result

    def result_camera(self, camera: str) -> Camera:
        with self._lock:
            session = self._sessions.get(camera)
            if session is None or session.camera is None:
                raise CalibrationError(f"camera {camera}: nothing to save; compute the calibration first")
            return session.camera
