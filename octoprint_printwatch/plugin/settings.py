"""Plugin settings: defaults (``plugins.printwatch.*``) and their mapping to the core's inputs.

Kept free of OctoPrint imports: the functions take plain dicts (what
``self._settings.get([], merged=True)`` returns), so they are unit-tested
without a server. The keys are documented in ``docs/plugin-api.md``.
"""
from __future__ import annotations

import hashlib
import json
from typing import Any, Mapping

from ..core.camera import Camera, CameraError
from ..core.errors import PrintWatchError
from ..core.settings import DetectionSettings

ACTIONS = ("pause", "cancel", "notify")

DEFAULTS: dict[str, Any] = {
    "enabled": True,
    "inject_on_upload": True,
    "interval_mode": "layers",
    "every_layers": 30,
    "every_mm": 5.0,
    "lift_mm": 10.0,
    "park_x": None,  # None: the injector's default, the bed's front-left corner
    "park_y": None,
    "action": "pause",
    "shape_threshold_pct": 7.0,
    "shape_threshold_per_camera": {},
    "size_check": True,
    "size_threshold_pct": 10.0,
    "camera_timeout_s": 5.0,
    "use_octoprint_webcams": True,
    "cameras": [],
    "calibrations": {},
    "pairs": [],
    "recording_enabled": True,
    "recording_max_mb": 500,
    "history_keep_prints": 100,
    # Longest time a check may hold the job while waiting for the expected views;
    # past it the frames are kept and judged as soon as the views are ready.
    "prepare_wait_s": 2.0,
    # Advanced: any DetectionSettings field by name, e.g. {"band_threshold_pct": 30}.
    "detection": {},
}


class SettingsValueError(PrintWatchError):
    """A plugin setting with an unusable value."""


def detection_settings(values: Mapping[str, Any], **overrides: Any) -> DetectionSettings:
    """The core's :class:`DetectionSettings` from plugin settings (plus API overrides with the same keys)."""
    merged = {**DEFAULTS, **dict(values or {}), **{k: v for k, v in overrides.items() if v is not None}}
    data = dict(merged.get("detection") or {})
    data["shape_threshold_pct"] = merged["shape_threshold_pct"]
    data["size_threshold_pct"] = merged["size_threshold_pct"]
    # the UI clears a per-camera override by sending null (OctoPrint only sends changed keys)
    data["camera_thresholds"] = {cam: pct for cam, pct in (merged.get("shape_threshold_per_camera") or {}).items()
                                 if pct is not None and pct != ""}
    return DetectionSettings.from_dict(data)


def validate(values: Mapping[str, Any]) -> None:
    """Raise PrintWatchError (one line naming the setting) for values the checks cannot use."""
    detection_settings(values)
    action(values)
    calibrated_cameras(values)
    for key in ("every_layers", "every_mm", "lift_mm", "camera_timeout_s", "recording_max_mb",
                "history_keep_prints", "prepare_wait_s"):
        value = values.get(key, DEFAULTS[key])
        try:
            ok = float(value) >= 0 and (key not in ("every_layers", "every_mm") or float(value) > 0)
        except (TypeError, ValueError):
            ok = False
        if not ok:
            raise SettingsValueError(f"setting plugins.printwatch.{key}: must be a positive number, got {value!r}")
    park_position(values, None)


def action(values: Mapping[str, Any]) -> str:
    chosen = str(values.get("action", DEFAULTS["action"])).lower()
    if chosen not in ACTIONS:
        raise SettingsValueError(f"setting plugins.printwatch.action: {chosen!r} is not one of {', '.join(ACTIONS)}")
    return chosen


def calibrated_cameras(values: Mapping[str, Any]) -> dict[str, Camera]:
    """Cameras with a calibration, {name: Camera}; a broken calibration entry raises naming the camera."""
    cameras = {}
    for name, data in (values.get("calibrations") or {}).items():
        try:
            cameras[name] = Camera.from_dict(name, data)
        except (CameraError, KeyError, TypeError, ValueError) as exc:
            raise SettingsValueError(f"setting plugins.printwatch.calibrations.{name}: {exc}") from None
    return cameras


def stereo_pairs(values: Mapping[str, Any], cameras: Mapping[str, Any]) -> list[tuple[str, str]]:
    """Configured pairs whose two cameras are both calibrated (others cannot be measured)."""
    if not values.get("size_check", True):
        return []
    pairs = []
    for pair in values.get("pairs") or []:
        if isinstance(pair, (list, tuple)) and len(pair) == 2 and pair[0] in cameras and pair[1] in cameras:
            pairs.append((str(pair[0]), str(pair[1])))
    return pairs


def camera_set_key(cameras: Mapping[str, Camera], pairs) -> str:
    """Short stable hash of the calibrated camera set: the expected views depend on it."""
    doc = {name: cam.to_dict() for name, cam in sorted(cameras.items())}
    blob = json.dumps({"cameras": doc, "pairs": [list(p) for p in pairs]}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:12]


def bed_from_profile(profile: Mapping[str, Any] | None) -> tuple[float, float, float, float, float]:
    """(x_min, x_max, y_min, y_max, max_z) of the printer's volume from an OctoPrint printer profile."""
    volume = dict((profile or {}).get("volume") or {})
    width = float(volume.get("width") or 200.0)
    depth = float(volume.get("depth") or 200.0)
    height = float(volume.get("height") or 200.0)
    if volume.get("origin") == "center":
        x_min, x_max, y_min, y_max = -width / 2, width / 2, -depth / 2, depth / 2
    else:
        x_min, x_max, y_min, y_max = 0.0, width, 0.0, depth
    custom = volume.get("custom_box")
    if isinstance(custom, Mapping) and custom:
        x_min, x_max = float(custom.get("x_min", x_min)), float(custom.get("x_max", x_max))
        y_min, y_max = float(custom.get("y_min", y_min)), float(custom.get("y_max", y_max))
        height = float(custom.get("z_max", height))
    return x_min, x_max, y_min, y_max, height


def park_position(values: Mapping[str, Any], profile: Mapping[str, Any] | None) -> tuple[float, float] | None:
    """Where the head waits during a check: the configured (x, y), or None for the injector's default
    (the bed's front-left corner, kept inside the bed)."""
    x = values.get("park_x")
    y = values.get("park_y")
    if x is None or y is None or x == "" or y == "":
        return None
    try:
        return float(x), float(y)
    except (TypeError, ValueError):
        raise SettingsValueError(f"setting plugins.printwatch.park_x/park_y: not numbers: {x!r}, {y!r}") from None
