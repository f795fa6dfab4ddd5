"""Read, validate and write recordings (``docs/recording-format.md``, format ``printwatch-recording/1``).

A recording is a folder: ``session.json``, the part (``model.stl`` and/or
``print.gcode``), one background frame per camera and one frame per camera
per check. Loading validates everything that can be checked without decoding
images and raises :class:`~octoprint_printwatch.core.errors.RecordingError`
with one line naming the file and the problem; images are decoded on use
(:meth:`Recording.read_background`, :meth:`Recording.read_frame`) and an
undecodable image raises the same error.
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import cv2
import numpy as np

from .camera import Camera, CameraError
from .errors import RecordingError

FORMAT = "printwatch-recording/1"
SESSION_FILE = "session.json"
IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png")


@dataclass
class CheckFrames:
    """One check of a recording: layer, nominal top z (mm) and the frame file of each camera.

    A camera missing from ``frames`` gave no frame at that check (dead camera).
    """

    layer: int
    z: float
    frames: dict[str, Path]


@dataclass
class Recording:
    """A validated recording folder. Paths are absolute."""

    root: Path
    cameras: dict[str, Camera]
    pairs: list[tuple[str, str]]
    model: Path | None
    gcode: Path | None
    layer_height: float | None
    backgrounds: dict[str, Path]
    checks: list[CheckFrames]
    raw: dict = field(repr=False, default_factory=dict)
    #: what the reader tolerated and a user may want to know (e.g. frames of a camera with no calibration)
    notes: list[str] = field(default_factory=list)

    def read_background(self, camera: str) -> np.ndarray | None:
        """(h, w, 3) uint8 BGR background of ``camera``, or None when the recording has none."""
        path = self.backgrounds.get(camera)
        return None if path is None else read_image(path)

    def read_frame(self, check: CheckFrames, camera: str) -> np.ndarray | None:
        """(h, w, 3) uint8 BGR frame of ``camera`` at ``check``, or None when that camera gave none."""
        path = check.frames.get(camera)
        return None if path is None else read_image(path)


def read_image(path: str | os.PathLike) -> np.ndarray:
    """(h, w, 3) uint8 BGR image; :class:`RecordingError` naming the file when it cannot be decoded.

    The format is told by the content, not the suffix. Grayscale frames come back as three equal
    channels, an alpha channel is dropped and 16-bit PNGs are scaled to 8 bits (``IMREAD_COLOR``).
    """
    path = Path(path)
    if not path.is_file():
        raise RecordingError(f"{path}: no such image file")
    data = np.fromfile(str(path), dtype=np.uint8)
    image = cv2.imdecode(data, cv2.IMREAD_COLOR) if data.size else None
    if image is None:
        raise RecordingError(f"{path}: unreadable image (not a JPEG or PNG, or truncated)")
    return image


# --------------------------------------------------------------------- reading
def load_recording(session_dir: str | os.PathLike) -> Recording:
    """Read and validate ``session_dir/session.json`` and the files it names."""
    root = Path(session_dir).resolve()
    if not root.is_dir():
        raise RecordingError(f"{session_dir}: not a recording folder (no such directory)")
    session_path = root / SESSION_FILE
    if not session_path.is_file():
        raise RecordingError(f"{session_path}: missing (a recording folder holds session.json)")
    try:
        # utf-8-sig: some Windows tools start UTF-8 text with a byte-order mark
        doc = json.loads(session_path.read_text(encoding="utf-8-sig"))
    except UnicodeDecodeError:
        raise RecordingError(f"{session_path}: not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise RecordingError(f"{session_path}: bad JSON at line {exc.lineno} column {exc.colno}: {exc.msg}") from None
    except OSError as exc:
        raise RecordingError(f"{session_path}: cannot be read ({exc.strerror})") from None
    if not isinstance(doc, dict):
        raise RecordingError(f"{session_path}: expected a JSON object at the top level")

    def fail(message: str) -> RecordingError:
        return RecordingError(f"{session_path}: {message}")

    notes: list[str] = []

    fmt = doc.get("format")
    if fmt != FORMAT:
        raise fail(f"unsupported format {fmt!r} (expected {FORMAT!r})")
    units = doc.get("units", "mm")
    if units != "mm":
        raise fail(f"units must be 'mm', got {units!r}")

    def file_entry(key: str) -> Path | None:
        value = doc.get(key)
        if value is None:
            return None
        if not isinstance(value, str) or not value:
            raise fail(f"'{key}' must be a file name, got {value!r}")
        path = _inside(root, value, session_path, key)
        if not path.is_file():
            raise RecordingError(f"{path}: missing ('{key}' in {SESSION_FILE})")
        return path

    model = file_entry("model")
    gcode = file_entry("gcode")
    if model is None and gcode is None:
        raise fail("neither 'model' nor 'gcode' is given: the expected part is unknown")

    layer_height = doc.get("layer_height")
    if layer_height is not None:
        if not _finite_number(layer_height) or layer_height <= 0:
            raise fail(f"layer_height must be a positive number, got {layer_height!r}")
        layer_height = float(layer_height)

    raw_cameras = doc.get("cameras")
    if not isinstance(raw_cameras, dict) or not raw_cameras:
        raise fail("'cameras' must be a non-empty object {name: camera}")
    cameras: dict[str, Camera] = {}
    for name, data in raw_cameras.items():
        if isinstance(data, dict) and "width" not in data and "height" not in data:
            # K is in the pixels of the frames the camera gives: without a stated size, take theirs
            size = _first_image_size(root, name, doc)
            if size is not None:
                data = dict(data, width=size[0], height=size[1])
                notes.append(f"{session_path}: camera {name}: no width/height given: {size[0]}x{size[1]}, "
                             f"the size of its frames, assumed")
        try:
            cameras[name] = Camera.from_dict(name, data)
        except CameraError as exc:
            raise fail(str(exc)) from None
        cam = cameras[name]
        cx, cy = cam.K[0, 2], cam.K[1, 2]
        if not (0 <= cx <= cam.width and 0 <= cy <= cam.height):
            # the frames' size alone then decides nothing: say which numbers disagree
            notes.append(f"{session_path}: camera {name}: K's principal point ({cx:g}, {cy:g}) lies outside its "
                         f"{cam.width}x{cam.height} image: were width/height and K calibrated at different sizes?")

    pairs: list[tuple[str, str]] = []
    raw_pairs = doc.get("pairs", [])
    if not isinstance(raw_pairs, list):
        raise fail("'pairs' must be a list of [left, right] camera names")
    for i, pair in enumerate(raw_pairs):
        if not (isinstance(pair, (list, tuple)) and len(pair) == 2 and all(isinstance(c, str) for c in pair)):
            raise fail(f"pairs[{i}] must be [left, right] camera names, got {pair!r}")
        for cam in pair:
            if cam not in cameras:
                raise fail(f"pairs[{i}] names unknown camera {cam!r} (cameras: {', '.join(cameras)})")
        if pair[0] == pair[1]:
            raise fail(f"pairs[{i}] pairs camera {pair[0]!r} with itself")
        pairs.append((pair[0], pair[1]))

    raw_bg = doc.get("background", {})
    if not isinstance(raw_bg, dict):
        raise fail("'background' must be an object {camera: file}")
    backgrounds: dict[str, Path] = {}
    uncalibrated: set[str] = set()
    for cam, rel in raw_bg.items():
        if cam not in cameras:
            uncalibrated.add(cam)
            continue
        if rel is None:   # recorded as "no background"
            continue
        backgrounds[cam] = _existing_image(root, rel, session_path, f"background of {cam}")
    for cam in cameras:  # the folder layout alone is enough when session.json omits the entry
        if cam not in backgrounds:
            for suffix in IMAGE_SUFFIXES:
                candidate = root / "background" / f"{cam}{suffix}"
                if candidate.is_file():
                    backgrounds[cam] = candidate
                    break

    raw_checks = doc.get("checks")
    if not isinstance(raw_checks, list):
        raise fail("'checks' must be a list")
    checks: list[CheckFrames] = []
    for i, entry in enumerate(raw_checks):
        if not isinstance(entry, dict):
            raise fail(f"checks[{i}] must be an object")
        layer, z, frames = entry.get("layer"), entry.get("z"), entry.get("frames", {})
        if isinstance(layer, float) and layer.is_integer():
            layer = int(layer)   # 30.0 from a writer whose numbers are all doubles
        if isinstance(layer, bool) or not isinstance(layer, int) or layer < 1:
            raise fail(f"checks[{i}].layer must be an integer >= 1, got {layer!r}")
        if not _finite_number(z) or z < 0:
            raise fail(f"checks[{i}].z must be a number >= 0, got {z!r}")
        if not isinstance(frames, dict):
            raise fail(f"checks[{i}].frames must be an object {{camera: file}}")
        paths: dict[str, Path] = {}
        for cam, rel in frames.items():
            if cam not in cameras:
                uncalibrated.add(cam)
                continue
            if rel is None:  # explicitly recorded as "no frame" (dead camera)
                continue
            paths[cam] = _existing_image(root, rel, session_path, f"checks[{i}] frame of {cam}")
        checks.append(CheckFrames(layer=layer, z=float(z), frames=paths))
    if uncalibrated:
        # the spec ignores unknown keys; frames with no calibration to compare them with are such keys
        notes.append(f"{session_path}: frames of camera(s) not in 'cameras' ignored (no calibration): "
                     f"{', '.join(sorted(map(repr, uncalibrated)))}")

    return Recording(root=root, cameras=cameras, pairs=pairs, model=model, gcode=gcode,
                     layer_height=layer_height, backgrounds=backgrounds, checks=checks, raw=doc, notes=notes)


def _first_image_size(root: Path, camera: str, doc: dict) -> tuple[int, int] | None:
    """(width, height) of ``camera``'s background, else its first check frame, when one can be decoded."""
    candidates = [(doc.get("background") or {}).get(camera) if isinstance(doc.get("background"), dict) else None]
    for entry in doc.get("checks") or []:
        if isinstance(entry, dict) and isinstance(entry.get("frames"), dict):
            candidates.append(entry["frames"].get(camera))
    for suffix in IMAGE_SUFFIXES:
        candidates.append(f"background/{camera}{suffix}")
    for rel in candidates:
        if not isinstance(rel, str) or not rel:
            continue
        path = _locate(root, rel)
        if (root == path or root in path.parents) and path.is_file():
            try:
                height, width = read_image(path).shape[:2]
            except RecordingError:
                continue   # named, with the file, when the checks read it
            return width, height
    return None


def _finite_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _locate(root: Path, rel: str) -> Path:
    """The absolute path ``rel`` names in the recording folder (``\\`` separators from Windows writers too).

    An absolute path that is not in the folder (written where the recording was made, then moved) names
    the file at the longest tail of it that exists in the folder: ``/home/u/rec/checks/000/a.jpg`` is
    ``checks/000/a.jpg`` of a folder moved elsewhere.
    """
    path = (root / rel).resolve()
    if "\\" in rel and not path.exists():
        path = (root / rel.replace("\\", "/")).resolve()
    if (path.exists() and (root == path or root in path.parents)) or not _is_absolute(rel):
        return path
    parts = [p for p in rel.replace("\\", "/").split("/") if p and p not in (".", "..")]
    for start in range(len(parts)):
        candidate = root.joinpath(*parts[start:])
        if candidate.exists():
            return candidate.resolve()
    return path


def _is_absolute(rel: str) -> bool:
    """A POSIX absolute path or a Windows one (``C:\\...``, ``\\\\server\\...``)."""
    return rel.startswith(("/", "\\")) or (len(rel) > 2 and rel[1] == ":" and rel[2] in "/\\")


def _inside(root: Path, rel: str, session_path: Path, what: str) -> Path:
    path = _locate(root, rel)
    if root != path and root not in path.parents:
        raise RecordingError(f"{session_path}: {what} {rel!r} points outside the recording folder")
    return path


def _existing_image(root: Path, rel: Any, session_path: Path, what: str) -> Path:
    if not isinstance(rel, str) or not rel:
        raise RecordingError(f"{session_path}: {what} must be a file name, got {rel!r}")
    path = _inside(root, rel, session_path, what)
    if not path.is_file():
        raise RecordingError(f"{path}: missing ({what} in {SESSION_FILE})")
    # any suffix: read_image tells JPEG from PNG by the content and names the file it cannot decode
    return path


# --------------------------------------------------------------------- writing
class RecordingWriter:
    """Writes a recording incrementally; ``session.json`` is rewritten (atomically) after every change,
    so a recording interrupted mid-print is still a valid recording of the checks so far.

    >>> w = RecordingWriter(out, cameras, pairs=[("a", "b")], gcode=src_gcode)   # doctest: +SKIP
    >>> w.add_background("a", image); w.add_check(30, 6.0, {"a": frame, "b": None})
    """

    def __init__(
        self,
        out_dir: str | os.PathLike,
        cameras: Mapping[str, Camera] | Sequence[Camera],
        *,
        pairs: Sequence[Sequence[str]] = (),
        model: str | os.PathLike | None = None,
        gcode: str | os.PathLike | None = None,
        layer_height: float | None = None,
        image_format: str = "jpg",
        jpeg_quality: int = 92,
        extra: Mapping[str, Any] | None = None,
    ) -> None:
        self.root = Path(out_dir)
        if isinstance(cameras, Mapping):
            self.cameras = dict(cameras)
        else:
            self.cameras = {cam.name: cam for cam in cameras}
        if not self.cameras:
            raise RecordingError(f"{self.root}: a recording needs at least one camera")
        for left_right in pairs:
            for cam in left_right:
                if cam not in self.cameras:
                    raise RecordingError(f"{self.root}: pair names unknown camera {cam!r}")
        if model is None and gcode is None:
            raise RecordingError(f"{self.root}: a recording needs the model or the G-code")
        if image_format not in ("jpg", "png"):
            raise RecordingError(f"{self.root}: image format must be jpg or png, got {image_format!r}")
        self.image_format = image_format
        self.jpeg_quality = int(jpeg_quality)
        self.root.mkdir(parents=True, exist_ok=True)
        self.doc: dict[str, Any] = {"format": FORMAT, "units": "mm"}
        if model is not None:
            self.doc["model"] = self._copy_in(Path(model), "model" + (Path(model).suffix.lower() or ".stl"))
        if gcode is not None:
            self.doc["gcode"] = self._copy_in(Path(gcode), "print.gcode")
        if layer_height is not None:
            self.doc["layer_height"] = float(layer_height)
        self.doc["cameras"] = {name: cam.to_dict() for name, cam in self.cameras.items()}
        self.doc["pairs"] = [list(p) for p in pairs]
        self.doc["background"] = {}
        self.doc["checks"] = []
        if extra:
            for key, value in extra.items():
                self.doc.setdefault(key, value)
        self._flush()

    def _copy_in(self, source: Path, name: str) -> str:
        target = self.root / name
        if source.resolve() != target.resolve():
            if not source.is_file():
                raise RecordingError(f"{source}: no such file")
            tmp = target.with_name(target.name + ".tmp")
            tmp.write_bytes(source.read_bytes())
            tmp.replace(target)
        return name

    def _write_image(self, rel: str, image: np.ndarray) -> None:
        path = self.root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        params = [cv2.IMWRITE_JPEG_QUALITY, self.jpeg_quality] if self.image_format == "jpg" else []
        ok, buf = cv2.imencode("." + self.image_format, np.ascontiguousarray(image), params)
        if not ok:
            raise RecordingError(f"{path}: could not encode image")
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_bytes(buf.tobytes())
        tmp.replace(path)

    def add_background(self, camera: str, image: np.ndarray) -> None:
        """Store the empty-bed frame (h, w, 3) uint8 BGR of ``camera``."""
        if camera not in self.cameras:
            raise RecordingError(f"{self.root}: background for unknown camera {camera!r}")
        rel = f"background/{camera}.{self.image_format}"
        self._write_image(rel, image)
        self.doc["background"][camera] = rel
        self._flush()

    def add_check(self, layer: int, z: float, frames: Mapping[str, np.ndarray | None], **extra: Any) -> int:
        """Store one check's frames ({camera: (h, w, 3) uint8 BGR or None}); returns its index."""
        index = len(self.doc["checks"])
        entry: dict[str, Any] = {"layer": int(layer), "z": round(float(z), 4), "frames": {}}
        for camera, image in frames.items():
            if camera not in self.cameras:
                raise RecordingError(f"{self.root}: frame for unknown camera {camera!r}")
            if image is None:
                continue  # a dead camera leaves no frame; readers treat it as missing evidence
            rel = f"checks/{index:03d}/{camera}.{self.image_format}"
            self._write_image(rel, image)
            entry["frames"][camera] = rel
        entry.update(extra)
        self.doc["checks"].append(entry)
        self._flush()
        return index

    def _flush(self) -> None:
        path = self.root / SESSION_FILE
        tmp = path.with_name(path.name + ".tmp")
        tmp.write_text(json.dumps(self.doc, indent=1), encoding="utf-8")
        tmp.replace(path)

    @property
    def session_path(self) -> Path:
        return self.root / SESSION_FILE
