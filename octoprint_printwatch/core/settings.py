"""Detection settings: every threshold the checks use, with defaults, in one dataclass.

The same object drives the plugin (mapped from OctoPrint's settings) and
``printwatch evaluate`` (overridable on the command line), so a recording
replayed with the plugin's settings gives the plugin's verdicts.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields
from typing import Any, Mapping

from .errors import PrintWatchError


class SettingsError(PrintWatchError):
    """A detection setting with an unusable value."""


@dataclass
class DetectionSettings:
    """Thresholds and margins of the shape and size checks.

    Percentages are percent (7.0 means 7 %). Millimetre margins describe the
    calibration a user can achieve (recording-format.md: ~1 % focal, 0.5 deg,
    1 mm); the shape check turns them into pixel bounds per camera.
    """

    #: Seed Eq. 4.1 error (with boundary tolerance) above which a camera fails; seed ch. 4 webcam value.
    shape_threshold_pct: float = 7.0
    #: Per-camera overrides of ``shape_threshold_pct``: {camera name: percent}.
    camera_thresholds: dict[str, float] = field(default_factory=dict)
    #: Error within the newest layer band (material added since the previous check) above which a camera fails.
    band_threshold_pct: float = 50.0
    #: The band rule needs at least this many band pixels beyond the boundary tolerance (too thin a band says nothing).
    band_min_pixels: int = 150
    #: Fail when less than this share of the new layers expected since the previous check is seen
    #: (only counted where the part would be visible against what is behind it).
    min_growth_pct: float = 15.0
    #: The newest layers sitting this far (mm) sideways from the layers below is a layer shift.
    layer_shift_mm: float = 1.5
    #: Stereo size check threshold (seed ch. 5 value), used once the size check is wired in.
    size_threshold_pct: float = 10.0

    # -- calibration error the alignment may absorb (never more) --
    #: Typical (one standard deviation) calibration errors, as recording-format.md states them ...
    calibration_rotation_deg: float = 0.5
    calibration_position_mm: float = 1.0
    calibration_focal_pct: float = 1.0
    #: ... and how many standard deviations the alignment may absorb (2.5: 99 % of calibrations).
    calibration_sigmas: float = 2.5

    #: Differences closer than this to the expected outline are not counted (blur, JPEG, residual calibration).
    boundary_tolerance_px: float = 2.0
    #: Material lying flat on the bed within this distance of the part's footprint (skirt, brim) is not "extra".
    bed_marks_margin_mm: float = 12.0
    #: Extra material is looked for within this distance (mm) of the part's footprint ...
    search_margin_mm: float = 20.0
    #: ... and up to this far above the nominal top (the parked hotend and its strings stay out).
    search_above_top_mm: float = 3.0

    #: Background removal: material threshold and confident-bed threshold, in units of the measured bed noise.
    material_noise_factor: float = 5.0
    bed_noise_factor: float = 2.5
    #: Camera unusable (moved, lights changed) when this fraction of its far-from-part bed pixels changed.
    max_changed_bed_fraction: float = 0.35

    #: Plain shape failures must come from at least this many usable cameras (and from at least
    #: half of them); a decisive one (part displaced, layer shift) needs one camera.
    min_failing_cameras: int = 1

    #: Frames are checked at this width (px; height keeps the aspect ratio), whatever the camera gives:
    #: every pixel-sized step (morphology, shake range, tolerances) then means the same share of the
    #: view, and a 1080p camera costs what a 640x480 one does. 0 checks at the camera's own size.
    working_width: int = 640

    def threshold_for(self, camera: str) -> float:
        """Shape threshold (percent) for one camera, honouring per-camera overrides."""
        return float(self.camera_thresholds.get(camera, self.shape_threshold_pct))

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name == "camera_thresholds":
                if not isinstance(value, Mapping):
                    raise SettingsError("camera_thresholds must map camera names to percentages")
                clean = {}
                for cam, pct in value.items():
                    clean[str(cam)] = _positive(f"camera_thresholds[{cam}]", pct)
                self.camera_thresholds = clean
            elif f.name in ("band_min_pixels", "min_failing_cameras"):
                setattr(self, f.name, int(_positive(f.name, value, allow_zero=False)))
            elif f.name == "working_width":
                width = int(_positive(f.name, value, allow_zero=True))
                if 0 < width < 160:
                    raise SettingsError(f"working_width must be 0 (camera size) or at least 160 px, got {width}")
                self.working_width = width
            else:
                setattr(self, f.name, _positive(f.name, value, allow_zero=True))
        if self.bed_noise_factor >= self.material_noise_factor:
            raise SettingsError("bed_noise_factor must be smaller than material_noise_factor")

    # ------------------------------------------------------------ dict I/O
    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: Mapping[str, Any] | None) -> "DetectionSettings":
        """Settings from a plain dict; unknown keys are ignored, bad values raise :class:`SettingsError`."""
        if data is None:
            return cls()
        if not isinstance(data, Mapping):
            raise SettingsError(f"detection settings must be an object, got {type(data).__name__}")
        known = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in data.items() if k in known})

    def with_overrides(self, **changes: Any) -> "DetectionSettings":
        """A copy with some fields replaced (None values are ignored)."""
        data = self.to_dict()
        data.update({k: v for k, v in changes.items() if v is not None})
        return type(self).from_dict(data)


def _positive(name: str, value: Any, *, allow_zero: bool = True) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise SettingsError(f"setting {name}: not a number: {value!r}") from None
    if number != number or number in (float("inf"), float("-inf")):
        raise SettingsError(f"setting {name}: must be finite, got {value!r}")
    if number < 0 or (number == 0 and not allow_zero):
        raise SettingsError(f"setting {name}: must be {'>= 0' if allow_zero else '> 0'}, got {value!r}")
    return number


def parse_camera_threshold(text: str) -> tuple[str, float]:
    """``'cam0L=8.5'`` -> ``('cam0L', 8.5)`` (the ``--camera-threshold`` CLI syntax)."""
    name, sep, pct = str(text).partition("=")
    if not sep or not name.strip():
        raise SettingsError(f"camera threshold {text!r}: expected CAMERA=PERCENT, e.g. cam0L=8")
    return name.strip(), _positive(f"camera threshold for {name.strip()}", pct)
