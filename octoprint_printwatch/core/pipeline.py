"""THE check: the one code path that runs at every check, in the plugin and in ``printwatch evaluate``.

* :func:`prepare_job` runs once per job (at upload in the plugin, at load in
  ``evaluate``): it builds the expected part, renders every camera's expected
  views at every check height and derives each camera's alignment bound.
* :class:`CheckRunner` runs the checks of one print in order and keeps what a
  check needs from the previous ones (the last mask per camera and the
  alignment found so far).
* :func:`core.verdict.decide` is the combined decision rule (shape per camera, size per
  stereo pair): the one place a pause is decided.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Mapping, Sequence

import cv2
import numpy as np

from .camera import Camera
from .errors import PrintWatchError
from .settings import DetectionSettings
from .alignment import align_candidates, near_any
from .growth import GROWTH_SPAN_CHECKS
from .layer_shift import LayerShift, band_reads_shifted
from .masks import dilate, shift_mask
from .shape_check import ExpectedRegions, ShapeResult, check_shape, not_decisive_where_it_stood
from .nest import SOLID_MIN_COVERAGE, STALL_READ_BELOW_GROWTH_PCT, TEXTURE_MEMORY_CHECKS
from .verdict import (RISE_HELD_READINGS, VISIBLY_RISING_PCT, band_shifts_of, decide, finest_reading, held_rise,
                      layer_shift_of, lowest_missing_while_rising, missing_since_rise, rise_since_previous_check,
                      visibly_rising, without_views_never_seen_whole)

VERDICTS = ("ok", "fail", "unknown")
#: Brim widths (mm) a look tries around a short part (core.alignment.align_with_brim): slicers lay 3-10 mm
#: (PrusaSlicer's default 5, Cura's 8).
BRIM_WIDTHS_MM = (3.0, 5.0, 7.0, 9.0)


# ----------------------------------------------------------------- the plan
class PlannedView:
    """The masks of an ``ExpectedView`` the checks use, bit-packed.

    A job keeps a view per camera per check height for the whole print (6 cameras x 40
    checks is common); the full ``ExpectedView`` with its two float32 depth maps is about
    3.6 MB at 640x480, this about 80 kB, which matters on a Raspberry Pi.
    """

    __slots__ = ("camera", "z", "z_previous", "shape", "_silhouette", "_new_band")

    def __init__(self, view: Any):
        self.camera = view.camera
        self.z = float(view.z)
        self.z_previous = float(view.z_previous)
        self.shape = tuple(np.asarray(view.silhouette).shape)
        self._silhouette = np.packbits(np.asarray(view.silhouette, bool))
        self._new_band = np.packbits(np.asarray(view.new_band, bool))

    def _unpack(self, packed: np.ndarray) -> np.ndarray:
        """(h, w) bool"""
        # (the unpacked bits are 0 or 1: read as bool without a copy)
        return np.unpackbits(packed, count=self.shape[0] * self.shape[1]).reshape(self.shape).view(bool)

    @property
    def silhouette(self) -> np.ndarray:
        """(h, w) bool: the expected part as the (distorted) camera sees it."""
        return self._unpack(self._silhouette)

    @property
    def new_band(self) -> np.ndarray:
        """(h, w) bool: the visible surface printed since the previous check height."""
        return self._unpack(self._new_band)


@dataclass
class JobPlan:
    """Everything computed once per job.

    part : the expected part (``core.geometry.PartModel``).
    cameras : {name: Camera}; pairs : [(left, right)].
    check_heights : [(layer, z)] the planned checks, ascending.
    views : {(camera, z): PlannedView} rendered at the planned heights (more are added on demand).
    footprint : (n, 2) convex hull of the part's XY extent (mm, printer coordinates).
    brim_outline : the contours a brim follows ((n, 2) mm, outer CCW, holes CW: the part's first layer) where they do
        not fill the footprint (:func:`brim_outline_of`: an L, a star, a ring), else empty: the brim zones then follow
        the footprint.
    max_shift_px, tolerance_px : per camera, see :func:`camera_bounds`.
    """

    part: Any
    cameras: dict[str, Camera]
    pairs: list[tuple[str, str]]
    check_heights: list[tuple[int, float]]
    views: dict
    footprint: np.ndarray
    max_shift_px: dict[str, float]
    tolerance_px: dict[str, float]
    px_per_mm: dict[str, float] = field(default_factory=dict)
    prepare_seconds: float = 0.0
    notes: list[str] = field(default_factory=list)
    brim_outline: list = field(default_factory=list)
    cache_dir: Path | None = None
    #: {(camera, margin mm): bed_marks_zone}: the same at every check (read-only arrays)
    _bed_marks: dict = field(default_factory=dict, repr=False, compare=False)
    #: {camera: the bed around the footprint grown by each of BRIM_WIDTHS_MM}: the same at every check
    _brims: dict = field(default_factory=dict, repr=False, compare=False)

    def view(self, camera: str, z: float, previous_z: float | None = None):
        """The expected view of ``camera`` at ``z``; rendered now (and kept) when not planned."""
        key = (camera, _zkey(z))
        found = self.views.get(key)
        if found is None:
            for (cam, zz), view in self.views.items():
                if cam == camera and abs(zz - z) < 1e-6:
                    return view
            from .render import render_expected_views

            heights = [h for h in (previous_z, z) if h is not None and h <= z]
            rendered = render_expected_views(self.part, [self.cameras[camera]], sorted(set(heights)),
                                             cache_dir=self.cache_dir)
            for (cam, zz), view in rendered.items():
                if abs(zz - z) < 1e-6:
                    found = view
            if found is None:
                raise PrintWatchError(f"camera {camera}: no expected view could be rendered at z={z:g} mm")
            found = PlannedView(found)
            self.views[key] = found
        return found

    def top_closing(self, z: float, skin_mm: float = 1.0) -> bool:
        """Whether a top surface closes within ``skin_mm`` above ``z``: the part's cross-section there is
        under half of the one just below ``z`` (the end of the part, or a step). Its solid top skin then
        looks unlike the sparse infill seen before (smooth, often glossy: from some views like the bed)."""
        if self.part is None:   # a plan built from views alone (tests): nothing known about the part's shape
            return False
        # two cross-sections, about 0.1 ms: not worth keeping
        below = self.part.cross_section_area(max(float(z) - 0.1, 0.05))
        above = self.part.cross_section_area(float(z) + skin_mm) if float(z) + skin_mm < self.part.height() else 0.0
        return below > 0 and above < 0.5 * below

    def regions(self, camera: str, z: float, settings: DetectionSettings,
                previous_z: float | None = None) -> ExpectedRegions:
        """The masks the shape check needs for ``camera`` at ``z``."""
        cam = self.cameras[camera]
        view = self.view(camera, z, previous_z)
        silhouette = np.asarray(view.silhouette, bool)
        band = np.asarray(view.new_band, bool)
        search = bed_box_mask(cam, self.footprint, settings.search_margin_mm, 0.0, z + settings.search_above_top_mm)
        dont_care = self._bed_marks.get((camera, settings.bed_marks_margin_mm))
        if dont_care is None:
            dont_care = bed_marks_zone(cam, self.footprint, settings.bed_marks_margin_mm)
            dont_care.flags.writeable = False
            self._bed_marks[(camera, settings.bed_marks_margin_mm)] = dont_care
        brims = self._brims.get(camera)
        if brims is None:
            brims = tuple(brim_zone(cam, self.brim_outline, width) if self.brim_outline
                          else bed_marks_zone(cam, self.footprint, width) for width in BRIM_WIDTHS_MM)
            for brim in brims:
                brim.flags.writeable = False
            self._brims[camera] = brims
        reflection = reflection_zone(cam, self.footprint, z)
        before = None
        if previous_z is not None and previous_z < z:
            before = np.asarray(self.view(camera, previous_z).silhouette, bool)
        # (Limiting how thick a flat mark may look, ExpectedRegions.flat_max_px, was measured to
        # let brims merged with skirts through as "extra": it stays off until it is done better.)
        centre = self.footprint.mean(axis=0)
        at_part = cam.project(np.array([[centre[0], centre[1], z], [centre[0] + 1.0, centre[1], z],
                                        [centre[0], centre[1] + 1.0, z], [centre[0], centre[1], z + 1.0]]))
        bed_to_image = np.stack([at_part[1] - at_part[0], at_part[2] - at_part[0]], axis=1)
        return ExpectedRegions(silhouette=silhouette, new_band=band, search=search, dont_care=dont_care,
                               max_shift_px=self.max_shift_px[camera], tolerance_px=self.tolerance_px[camera],
                               px_per_mm=self.px_per_mm.get(camera, 0.0), previous_silhouette=before,
                               reflection=reflection, bed_to_image=bed_to_image,
                               height_to_image=at_part[3] - at_part[0], camera=cam,
                               height_mm=float(z), brims=brims)


def _zkey(z: float) -> float:
    return round(float(z), 4)


def prepare_job(
    *,
    gcode_path: str | Path | None = None,
    model_path: str | Path | None = None,
    cameras: Mapping[str, Camera],
    pairs: Sequence[Sequence[str]] = (),
    check_heights: Sequence[tuple[int, float]] | None = None,
    settings: DetectionSettings | None = None,
    cache_dir: str | Path | None = None,
    part: Any = None,
) -> JobPlan:
    """Build the job's plan: the expected part (``geometry.part_for_job``: the model when given, else the
    G-code; with both, the G-code's solid when the model cannot be made a solid, which a broken mesh's
    silhouettes would otherwise contradict), the expected views of every camera at every check height, and
    each camera's alignment bounds."""
    from .geometry import part_for_job
    from .render import iter_expected_views

    settings = settings or DetectionSettings()
    started = time.perf_counter()
    if not cameras:
        raise PrintWatchError("no cameras: the checks need at least one calibrated camera")
    notes: list[str] = []
    if part is None:   # part_for_job says so when neither a model nor a G-code file is given
        part = part_for_job(model_path, gcode_path)
    notes.extend(getattr(part, "notes", []) or [])
    cameras = {name: working_camera(cam, settings.working_width) for name, cam in cameras.items()}
    heights = sorted({(int(layer), float(z)) for layer, z in (check_heights or [])}, key=lambda lz: lz[1])
    # one full view at a time: each is large (two depth maps), what the plan keeps of it small
    views = {(cam, _zkey(z)): PlannedView(view) for cam, _, z, view in
             iter_expected_views(part, list(cameras.values()), [z for _, z in heights], cache_dir=cache_dir)}
    footprint = part_footprint(part.mesh)
    max_shift, tolerance, scale = {}, {}, {}
    for name, cam in cameras.items():
        max_shift[name], tolerance[name], scale[name] = camera_bounds(cam, footprint, float(part.height()),
                                                                      settings)
    return JobPlan(part=part, cameras=cameras, pairs=[(a, b) for a, b in pairs], check_heights=heights,
                   views=views, footprint=footprint, max_shift_px=max_shift, tolerance_px=tolerance, px_per_mm=scale,
                   prepare_seconds=time.perf_counter() - started, notes=notes, brim_outline=brim_outline_of(part),
                   cache_dir=Path(cache_dir) if cache_dir else None)


def working_camera(camera: Camera, width: int) -> Camera:
    """``camera`` for its frames resized to ``width`` px wide (same aspect ratio); unchanged for 0.

    Pixel centres map as cv2.resize maps them: x' = (x + 0.5) * s - 0.5.
    """
    if not width or camera.width == width:
        return camera
    height = max(1, int(round(camera.height * width / camera.width)))
    sx, sy = width / camera.width, height / camera.height
    K = camera.K.astype(float).copy()
    K[0, 0] *= sx
    K[0, 1] *= sx
    K[1, 1] *= sy
    K[0, 2] = (K[0, 2] + 0.5) * sx - 0.5
    K[1, 2] = (K[1, 2] + 0.5) * sy - 0.5
    return Camera(camera.name, width, height, K, camera.dist.copy(), camera.rvec.copy(), camera.tvec.copy())


def frame_size_problem(image: np.ndarray | None, camera: Camera, what: str = "frames") -> str | None:
    """Why ``image`` (h, w, 3) cannot be checked against ``camera``'s calibration, or None.

    Another resolution of the same picture is fine (it is resized); another aspect ratio is not: the
    webcam now delivers another crop of its sensor (a resolution changed after calibration is the
    usual cause), and no resize maps it onto the calibrated view.
    """
    if image is None or camera.width <= 0 or camera.height <= 0:
        return None
    h, w = image.shape[:2]
    if h <= 0 or abs((w / h) / (camera.width / camera.height) - 1.0) <= 0.02:
        return None
    return (f"{what} are {w}x{h}, another aspect ratio than the calibrated {camera.width}x{camera.height} "
            f"(the webcam's resolution changed?): set it back or calibrate this camera again")


def to_working_size(image: np.ndarray | None, camera: Camera) -> np.ndarray | None:
    """(h, w, 3) frame resized to ``camera``'s (working) size; None stays None."""
    if image is None or image.shape[:2] == (camera.height, camera.width):
        return image
    shrink = image.shape[1] > camera.width
    return cv2.resize(image, (camera.width, camera.height),
                      interpolation=cv2.INTER_AREA if shrink else cv2.INTER_LINEAR)


def part_footprint(mesh) -> np.ndarray:
    """(n, 2) convex hull (mm) of the part's vertices projected on the bed."""
    xy = np.asarray(mesh.vertices, np.float64)[:, :2]
    if len(xy) < 3:
        raise PrintWatchError("the expected part has no extent on the bed")
    return hull_of(xy)


def hull_of(points: np.ndarray) -> np.ndarray:
    """(m, 2) convex hull of (n, 2) points (mm)."""
    return cv2.convexHull(np.asarray(points, np.float32)).reshape(-1, 2).astype(np.float64)


#: The first layer's contours are read this far above the part's bottom (mm): within any first layer.
FIRST_LAYER_CUT_MM = 0.1
#: A first layer covering this share of its convex hull's area is the hull, for the brim zones: they are grown from
#: the footprint as before (a cylinder's zones differ by polygonisation alone, 1.4-2.6 % of their pixels).
FIRST_LAYER_FILLS_HULL = 0.95


def brim_outline_of(part) -> list[np.ndarray]:
    """The part's contours ((n, 2) mm) at its first layer where a brim around them is unlike one around their hull
    (they cover under FIRST_LAYER_FILLS_HULL of it: an L's inner corner, a star's notches, a ring's hole), else []."""
    from .geometry import polygons_area

    try:
        contours = [c for c in part.cross_section(float(part.bottom()) + FIRST_LAYER_CUT_MM) if len(c) >= 3]
    except Exception:  # noqa: BLE001 - a section the mesh cannot give leaves the footprint's zones
        return []
    if not contours:
        return []
    hull_area = abs(polygons_area([hull_of(np.vstack(contours))]))
    return [] if abs(polygons_area(contours)) >= FIRST_LAYER_FILLS_HULL * hull_area else contours


def camera_bounds(camera: Camera, footprint: np.ndarray, height: float,
                  settings: DetectionSettings) -> tuple[float, float, float]:
    """(max_shift_px, tolerance_px, px_per_mm) for one camera looking at the part.

    max_shift_px is the image motion the stated calibration error can cause at the part, taken
    ``calibration_sigmas`` times: rotation error f*tan(a) + position error f*d/D + focal error
    (pct of the part's distance from the principal point); never more is absorbed by the
    alignment. tolerance_px grows with the image size (a 1280-px frame shows the same blur over
    twice the pixels). px_per_mm is the image scale at the part.
    """
    centre = np.array([*footprint.mean(axis=0), height / 2.0])
    distance = float(np.linalg.norm(camera.center - centre))
    focal = float(camera.K[0, 0])
    corners = np.array([[x, y, z] for x, y in footprint for z in (0.0, height)])
    uv = camera.project(corners)
    uv = uv[np.all(np.isfinite(uv), axis=1)]
    reach = float(np.max(np.linalg.norm(uv - camera.K[:2, 2], axis=1))) if len(uv) else camera.width / 2
    shift = (focal * math.tan(math.radians(settings.calibration_rotation_deg))
             + focal * settings.calibration_position_mm / max(distance, 1.0)
             + reach * settings.calibration_focal_pct / 100.0)
    scale = max(1.0, camera.width / 640.0)
    return (max(2.0, shift * settings.calibration_sigmas), settings.boundary_tolerance_px * scale,
            focal / max(distance, 1.0))


# ------------------------------------------------------------- image regions
def _offset_polygon(polygon: np.ndarray, margin: float, samples: int = 16) -> np.ndarray:
    """(m, 2) convex hull of ``polygon`` grown by ``margin`` mm (Minkowski sum with a circle)."""
    if margin <= 0:
        return polygon
    angles = np.linspace(0, 2 * np.pi, samples, endpoint=False)
    ring = np.column_stack([np.cos(angles), np.sin(angles)]) * margin
    return hull_of((polygon[:, None, :] + ring[None, :, :]).reshape(-1, 2))


def _densify(polygon: np.ndarray, step: float = 2.0) -> np.ndarray:
    """(n, 2) closed polygon with extra points every ~``step`` mm (so lens distortion bends its edges)."""
    nxt = np.roll(polygon, -1, axis=0)
    counts = np.maximum(1, (np.linalg.norm(nxt - polygon, axis=1) / step).astype(int))
    index = np.repeat(np.arange(len(polygon)), counts)
    t = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    t = t / counts[index]
    return polygon[index] + (nxt[index] - polygon[index]) * t[:, None]


def _pixels(camera: Camera, uv: np.ndarray) -> np.ndarray:
    """(n, 2) int32 pixels of (n, 2) finite image points, clipped a few frame widths beyond the frame (points near
    the horizon project arbitrarily far)."""
    return np.round(np.clip(uv, -4 * camera.width, 5 * camera.width)).astype(np.int32)


def _fill_projection(camera: Camera, points: np.ndarray) -> np.ndarray:
    """(h, w) bool: convex hull of the projections of (n, 3) printer points."""
    mask = np.zeros((camera.height, camera.width), np.uint8)
    uv = camera.project(points)
    uv = uv[np.all(np.isfinite(uv), axis=1)]
    if len(uv) >= 3:
        hull = cv2.convexHull(_pixels(camera, uv))
        cv2.fillConvexPoly(mask, hull, 1)
    return mask.astype(bool)


def bed_box_mask(camera: Camera, footprint: np.ndarray, margin: float, z0: float, z1: float) -> np.ndarray:
    """(h, w) bool: image of the box over the footprint grown by ``margin`` mm, from z0 to z1."""
    ring = _densify(_offset_polygon(footprint, margin))
    pts = np.vstack([np.column_stack([ring, np.full(len(ring), z)]) for z in (z0, z1)])
    return _fill_projection(camera, pts)


def bed_marks_mask(camera: Camera, footprint: np.ndarray, z: float, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """((h, w) bool, (h, w) bool): where flat things on the bed near the part (skirt, brim, purge)
    can appear, and where the part's mirror image in a glossy bed can appear.

    The bed ring is the footprint grown by ``margin`` mm at bed level; the reflection is the part's
    box mirrored below the bed (z -> -z). The shape check ignores extra material only when it lies
    wholly in this zone, so a tall thing standing in it (a moved part, spaghetti) still counts.
    """
    return bed_marks_zone(camera, footprint, margin), reflection_zone(camera, footprint, z)


def bed_marks_zone(camera: Camera, footprint: np.ndarray, margin: float) -> np.ndarray:
    """(h, w) bool: the bed ring of :func:`bed_marks_mask` (the same at every height)."""
    grown = _densify(_offset_polygon(footprint, margin))
    return _fill_projection(camera, np.column_stack([grown, np.zeros(len(grown))]))


def brim_zone(camera: Camera, outline: Sequence[np.ndarray], width: float) -> np.ndarray:
    """(h, w) bool: the bed a brim ``width`` mm wide covers with the part's first layer (``outline``: its contours,
    mm, :func:`brim_outline_of`), at bed level. Slicers lay a brim as loops offset from the first layer itself, into
    a star's notches and an L's inner corner (a skirt follows the hull instead: :func:`bed_marks_zone`)."""
    from .geometry import grown_polygons   # (manifold3d: loaded with the part, not with this module)

    mask = np.zeros((camera.height, camera.width), np.uint8)
    contours = []
    for contour in grown_polygons(outline, width):
        dense = _densify(contour)
        uv = camera.project(np.column_stack([dense, np.zeros(len(dense))]))
        if not np.all(np.isfinite(uv)):   # (behind the camera: the hull's zone, filled from the points in front)
            return bed_marks_zone(camera, hull_of(np.vstack(outline)), width)
        contours.append(_pixels(camera, uv))
    if contours:
        cv2.fillPoly(mask, contours, 1)
    return mask.astype(bool)


def reflection_zone(camera: Camera, footprint: np.ndarray, z: float) -> np.ndarray:
    """(h, w) bool: the reflection zone of :func:`bed_marks_mask` at height ``z``."""
    tight = _densify(_offset_polygon(footprint, 0.5))
    return _fill_projection(camera, np.vstack([np.column_stack([tight, np.full(len(tight), -h)])
                                               for h in (0.0, max(z, 0.2))]))


# ----------------------------------------------------------------- results
@dataclass
class CheckResult:
    """One check of all cameras (and pairs): what ``evaluate`` writes and the plugin shows.

    shape : {camera: ShapeResult} for every camera that gave a frame.
    size : {"left+right": size-check dict} per pair (filled by the stereo size check; empty until then).
    unreadable : cameras that gave no usable frame at this check (never a cause for a pause).
    """

    layer: int
    z: float
    verdict: str
    shape_error_pct: dict[str, float | None]
    shape: dict[str, ShapeResult]
    size: dict[str, dict]
    reasons: list[str]
    seconds: float
    unreadable: list[str] = field(default_factory=list)
    shape_seconds: float = 0.0       # the part of ``seconds`` spent in the shape checks (wall time)
    shape_cpu_seconds: float = 0.0   # CPU time of the shape checks (all threads; less sensitive to load)
    layer_shift: LayerShift | None = None   # the newest layers' best bed shift the cameras agree on
    top_closing: bool = False   # a top surface closes in the newest layers (JobPlan.top_closing)

    def to_json(self) -> dict:
        """The check entry of the ``printwatch evaluate`` contract (plus a ``shape`` detail block)."""
        return {
            "layer": self.layer,
            "z": round(self.z, 4),
            "verdict": self.verdict,
            "shape_error_pct": {cam: (None if pct is None else round(pct, 2))
                                for cam, pct in self.shape_error_pct.items()},
            "size": self.size,
            "reasons": list(self.reasons),
            "seconds": round(self.seconds, 4),
            "shape": {cam: result.figures() for cam, result in self.shape.items()},
            "layer_shift": None if self.layer_shift is None else self.layer_shift.figures(),
            "unreadable": list(self.unreadable),
        }


# ------------------------------------------------------------------ running
#: How far a camera that sees the part displaced at its first checks may be aligned, in multiples of its
#: stated-calibration bound, to learn a calibration error larger than the stated one (CheckRunner).
CALIBRATION_PROBE_WIDEN = 2.5
#: ... and the largest shift it may learn (multiples of that bound, 5 standard deviations of the stated error):
#: a fit near the edge of the widened search may have its best beyond it, and is no calibration error.
CALIBRATION_MAX_LEARNED = 2.0
#: With no camera to vouch, the part must grow at the learned shift by this share of the expected rise.
CALIBRATION_GROWTH_PCT = 50.0
#: A camera whose anchor lies at least this share of its bound from the calibrated position is pinned at the
#: bound: the part may lie beyond it (CheckRunner._learn_beyond_pinned_anchor looks there when it fails).
CALIBRATION_PINNED_SHARE = 0.9
#: A learned shift is refused when one move of the part on the bed explains every camera's shift to within
#: this share of it (CheckRunner._learn_calibration_offsets).
MOVE_FIT_SHARE = 0.3


def one_move_explains(views: Sequence[tuple[tuple[int, int], np.ndarray | None]], tolerance_px: float) -> bool:
    """Whether one move (mm) of the part on the bed explains every camera's image shift to within
    ``tolerance_px``. ``views`` are ((dx, dy) px, bed_to_image (2, 2): image motion per mm of bed x and y)."""
    rows = [(np.asarray(shift, float), np.asarray(jac, float)) for shift, jac in views if jac is not None]
    if len(rows) < 2:
        return False
    move = np.linalg.lstsq(np.vstack([jac for _, jac in rows]), np.concatenate([shift for shift, _ in rows]),
                           rcond=None)[0]
    return all(float(np.hypot(*(shift - jac @ move))) <= tolerance_px for shift, jac in rows)


def _probe_beyond_bound(args: dict, failed: ShapeResult, bound: float, beyond: float) -> ShapeResult | None:
    """A failing camera's check again (``args``: its check_shape arguments) with its alignment bound widened
    ``CALIBRATION_PROBE_WIDEN`` times ``bound`` (the stated calibration's), free of its anchor; the result when
    the part fits there clearly, at a shift beyond ``beyond`` px and within ``CALIBRATION_MAX_LEARNED`` times
    ``bound``, else None. Clearly: half the threshold and half the failing check's error to spare, not merely a
    pass (a shorter part, a runout, slid down the outline trades missing material at the top for missing
    material at the foot)."""
    wide = replace(args["regions"], max_shift_px=bound * CALIBRATION_PROBE_WIDEN, brims=())
    probe = check_shape(**dict(args, regions=wide, anchor=None, max_drift=2))
    offset = float(np.hypot(*probe.shift_px))
    if (probe.usable and probe.passed and beyond < offset <= CALIBRATION_MAX_LEARNED * bound
            and probe.error_pct <= probe.threshold / 2.0 and probe.error_pct <= failed.error_pct / 2.0):
        return probe
    return None


def _moved_as_one(probe: ShapeResult, args: dict, vouching: Sequence[tuple[ShapeResult, dict]]) -> bool:
    """Whether one move of the part on the bed explains ``probe``'s shift and those of the ``vouching`` cameras
    ((result, check_shape arguments) of each camera that passes with the part in place): a part knocked off
    moves every camera's view as one move on the bed would; independent calibration errors do not (a camera
    looking along such a move sees little of it: then nothing is learned either). False with no camera."""
    if not vouching:
        return False
    views = [(probe.shift_px, args["regions"].bed_to_image)] + [
        (result.shift_px, other_args["regions"].bed_to_image) for result, other_args in vouching]
    offset = float(np.hypot(*probe.shift_px))
    return one_move_explains(views, max(2.0 * float(args["regions"].tolerance_px) + 1.0, MOVE_FIT_SHARE * offset))


@dataclass
class CameraState:
    """What :class:`CheckRunner` remembers of one camera between the checks of a print."""

    #: (dx, dy) px: the alignment of its first passing checks, the start of every later one
    anchor: tuple[int, int] | None = None
    #: the look that laid the anchor found the part with a brim around it (ShapeResult.placed_by_brim): later looks
    #: keep the outline on the part by the brim too, while the prior would pull it across the brim
    brim_found: bool = False
    #: the anchor is held (the part was tall enough for an unambiguous alignment, or a calibration offset
    #: was learned): calibration error does not change during a print
    frozen: bool = False
    #: the largest share of the expected part the material covered where its passing looks laid the outline
    #: (ShapeResult.outline_coverage; None: no passing look yet): a view that never saw more than part of the part
    #: placed the outline by the faces it saw (verdict.without_views_never_seen_whole)
    seen_share: float | None = None
    #: the share of the expected part the material covered at the passing look that laid the anchor where it is
    #: (ShapeResult.outline_coverage; None: no anchor yet): the outline stays where that look put it
    anchor_share: float | None = None
    #: (k, 2) shifts no passing check so far could tell apart (each narrows them; _second_look)
    shift_candidates: np.ndarray | None = None
    #: the (dx, dy) px its passing checks aligned the outline at (each once; its reflection zone covers them)
    placed_at: list[tuple[int, int]] = field(default_factory=list)
    #: the part's colours, from its last passing check
    palette: np.ndarray | None = None
    #: (h, w) bool observed mask of its last passing check (background removal's prior)
    previous_mask: np.ndarray | None = None
    #: (z, (dx, dy) px): the height of that check and where it laid the outline (None: no passing check yet)
    previous_mask_at: tuple[float, tuple[int, int]] | None = None
    #: (h, w) bool observed mask of its last usable check, and the height it was seen at (the growth test
    #: needs the previous check's)
    last_observed: np.ndarray | None = None
    last_observed_z: float | None = None
    #: (dx, dy) px: where that check laid the outline (the new-material test measures beyond it too)
    last_observed_shift: tuple[int, int] | None = None
    #: its frame at its last usable check and the bed it read there as a shadow that left (shadows.shadow_left), or
    #: None: the next check keeps that bed where the frame did not change
    left_before: tuple[np.ndarray, np.ndarray] | None = None
    #: (z, observed mask) of its usable checks before the last one, newest first (at most
    #: GROWTH_SPAN_CHECKS - 1): the growth test's older looks, where one check's rise is too small to read
    older_observed: list = field(default_factory=list)
    #: the growth it read at its last usable check (None: it could not measure one)
    last_growth: float | None = None
    #: its last RISE_HELD_READINGS + 1 readings of the rise (fine, else over the span, else coarse) at the checks that
    #: gave one since it was last unusable, oldest first, and whether its previous check gave one: held_rise, for
    #: decide's stall rules
    rise_readings: tuple[float, ...] = ()
    read_rise_last_check: bool = False
    #: its extra material at the previous check (None: not usable there)
    last_extra: float | None = None
    #: its growth reading at the previous check, fine or else coarse (None: none), and its missing material
    #: there (None: not usable there): decide's coarse stall rule
    last_rise: float | None = None
    last_missing: float | None = None
    #: its missing material at the last check it read the part rising (COARSE_ROSE_BEFORE_PCT), kept while
    #: every later reading of it (fine or else coarse) is a stall (-15 % to ``min_growth_pct``) or none, until
    #: the RISE_QUIET_CHECKS-th of those checks at which nothing more went missing; None otherwise, and once
    #: it is not usable: decide's coarse stall rule (a stop between two checks; missing_since_rise)
    rise_missing: float | None = None
    #: the checks since that rise at which it missed nothing more (missing_since_rise)
    rise_quiet: int = 0
    #: its lowest missing material, overall and of the newest band (None: no band figures), at the checks it read
    #: the part rising and the print passed, since it was last unusable (None: none): decide's standing offset
    #: (lowest_missing_while_rising)
    missing_while_rising: tuple[float, float | None] | None = None
    #: the most material it missed (%) at the checks that passed since it was last unusable (None: none yet):
    #: decide's "visibly grows" rule where readings to the pixel stand in (verdict.missed_as_much_before)
    most_missing: float | None = None
    #: the highest share of its newest band covered by the part's material so far (core/nest.py)
    band_coverage: float | None = None
    #: its newest band's texture at its last TEXTURE_MEMORY_CHECKS checks since it was last unusable, oldest first
    #: (ShapeResult.band_texture; None: its first look, whose band is the whole part, or no band figures): decide's
    #: textured-band rules compare with the smoothest of them (smoothest_band_texture)
    band_textures: tuple[float | None, ...] = ()
    #: (dx, dy) px: a calibration error larger than the stated one, learned once (_learn_calibration_offsets);
    #: its alignment bound is widened to reach it
    calibration_offset: tuple[int, int] | None = None
    #: a shift to confirm at the next check (no other camera vouched), and whether it abstained for one
    #: already (once per print)
    pending_offset: tuple[int, int] | None = None
    offset_abstained: bool = False
    #: (h, w) bool: the objects it found reaching in from above the search box at the previous check (the
    #: parked hotend; None: none, or not usable there)
    last_foreign: np.ndarray | None = None
    #: the shift whose upper outline matched the observed one at its first usable look, where that look's
    #: alignment chose a shift further than OUTLINE_DISAGREES_PX from it (None: they agreed, or no look yet):
    #: a first look's tie-break the outline contradicts (CheckRunner._second_look)
    first_look_outline: tuple[int, int] | None = None

    def placed(self, result: ShapeResult, max_drift: int, tall: bool) -> None:
        """Learn where a passing check (``result``, searched ``max_drift`` px from the anchor) laid the outline;
        ``tall``: the part is tall enough in this view for an unambiguous alignment.

        A view whose anchor would follow its newest band's shift (:func:`follows_the_shifted_top`) keeps it: the
        older part it aligns on holds the shifted layers from the next check on, and an outline moved onto them
        would sit on the shifted top (the layers below would then read beside it, the next band in place, and the
        view contradict the shift)."""
        if result.shift_px not in self.placed_at:
            self.placed_at.append(result.shift_px)
        if result.shift_candidates is not None and len(result.shift_candidates):
            self.shift_candidates = result.shift_candidates
        # Calibration error does not change during a print: once the part is tall enough in this view for the
        # alignment to be unambiguous, later checks stay near that shift (and a runout cannot walk the expected
        # outline down, check by check).
        if not self.frozen:
            anchor = agreeing_anchor(result.shift_px, result.shift_candidates, max_drift)
            if follows_the_shifted_top(self.anchor, anchor, result):
                return
            if anchor != self.anchor or self.anchor_share is None:
                self.anchor_share = result.outline_coverage
            if self.anchor is None:
                self.brim_found = result.placed_by_brim
            self.anchor = anchor
            self.frozen = tall

    def saw(self, mask: np.ndarray | None, z: float, shift: tuple[int, int] | None = None) -> None:
        """Remember ``mask`` as the camera's look at ``z`` (its latest usable check), its outline laid at ``shift``."""
        if self.last_observed is not None and self.last_observed_z is not None and self.last_observed_z != z:
            self.older_observed = [(self.last_observed_z, self.last_observed),
                                   *self.older_observed][:GROWTH_SPAN_CHECKS - 1]
        self.last_observed, self.last_observed_z, self.last_observed_shift = mask, z, shift


#: A first look's chosen shift and its upper-outline match disagree beyond this many pixels (either axis)
OUTLINE_DISAGREES_PX = 2
#: a view whose newest band reads shifted on its own (layer_shift.band_reads_shifted) on a part that rose by at least
#: this share of the expected rise (ShapeResult.growth_pct) may have had its newest layers printed shifted
TOP_ROSE_PCT = 50.0


def _among(shift: tuple[int, int], candidates: np.ndarray | None) -> bool:
    """Whether ``shift`` (dx, dy) is one of ``candidates`` ((k, 2) int, or None: no)."""
    return near_any(shift, candidates, 0)


def _px_apart(a: tuple[int, int], b: tuple[int, int]) -> int:
    return max(abs(int(a[0]) - int(b[0])), abs(int(a[1]) - int(b[1])))


class CheckRunner:
    """Runs the checks of one print in order, keeping per-camera state (:class:`CameraState`) between them."""

    def __init__(self, plan: JobPlan, settings: DetectionSettings | None,
                 backgrounds: Mapping[str, np.ndarray | None]):
        self.plan = plan
        self.settings = settings or DetectionSettings()
        # every frame is checked at the plan's (working) camera size; one of another aspect ratio not at all
        self.background_problems = {name: problem for name, image in backgrounds.items() if name in plan.cameras
                                    and (problem := frame_size_problem(image, plan.cameras[name], "background frames"))}
        self.backgrounds = {name: None if name in self.background_problems
                            else to_working_size(image, plan.cameras[name]) if name in plan.cameras else image
                            for name, image in backgrounds.items()}
        self.cameras = {name: CameraState() for name in plan.cameras}
        self.previous_z: float | None = None
        self.keep_pictures = True
        self.size_checks: dict = {}  # "left+right" -> stereo.PairSizeCheck, kept for the whole print
        # the last four checks' layer-shift evidence: (had a check before it, {camera: BandShift})
        self.band_shift_history: list[tuple[bool, dict]] = []
        self.last_decision: dict[str, Any] = {}  # the last check's arguments of decide()
        # ... and the layer-shift history before it and each camera's earlier places (decide_again)
        self.last_layer_shift_inputs: tuple = ((), {})
        # whether an earlier check gave any view a reading of the rise (decide's first_rise_reading)
        self.rise_ever_read = False

    def run_check(self, layer: int, z: float, frames: Mapping[str, np.ndarray | None]) -> CheckResult:
        """Shape check per camera (size per pair once wired in) and the combined verdict."""
        started = time.perf_counter()
        cpu_started = time.process_time()
        settings = self.settings
        problems = {name: problem for name, image in frames.items() if name in self.plan.cameras
                    and (problem := frame_size_problem(image, self.plan.cameras[name]))}
        frames = {name: None if name in problems
                  else to_working_size(image, self.plan.cameras[name]) if name in self.plan.cameras else image
                  for name, image in frames.items()}
        shape: dict[str, ShapeResult] = {}
        errors: dict[str, float | None] = {}
        unreadable: dict[str, str] = {}
        shape_inputs: dict[str, dict] = {}
        growth_before = {name: state.last_growth for name, state in self.cameras.items()}
        extra_before = {name: state.last_extra for name, state in self.cameras.items() if state.last_extra is not None}
        rise_before = {name: state.last_rise for name, state in self.cameras.items() if state.last_rise is not None}
        held_rise_before = {name: rise for name, state in self.cameras.items()
                            if (rise := held_rise(state.rise_readings, state.read_rise_last_check,
                                                  settings.min_growth_pct)) is not None}
        missing_before = {name: state.last_missing for name, state in self.cameras.items()
                          if state.last_missing is not None}
        missing_at_rise = {name: state.rise_missing for name, state in self.cameras.items()
                           if state.rise_missing is not None}
        texture_before = {name: texture for name, state in self.cameras.items()
                          if (texture := smoothest_band_texture(state.band_textures)) is not None}
        while_rising = {name: state.missing_while_rising for name, state in self.cameras.items()
                        if state.missing_while_rising is not None}
        most_missing_before = {name: state.most_missing for name, state in self.cameras.items()
                               if state.most_missing is not None}
        for name, state in self.cameras.items():
            frame = frames.get(name)
            background = self.backgrounds.get(name)
            if frame is None or background is None:
                unreadable[name] = (problems.get(name) or self.background_problems.get(name)
                                    or ("no frame (camera unavailable)" if frame is None else "no background frame"))
                errors[name] = None
                continue
            regions = self.plan.regions(name, z, settings, self.previous_z)
            if state.frozen or (state.anchor is not None and not state.brim_found):
                # a brim places the outline from a camera's first look, and at its later looks only where that look
                # found one, until the part stands tall enough for the outline alone
                regions = replace(regions, brims=())
            if state.calibration_offset is not None:
                regions = replace(regions, max_shift_px=regions.max_shift_px
                                  + float(np.hypot(*state.calibration_offset)))
            shape_args = dict(
                camera=name, background=background, frame=frame, regions=regions,
                threshold=settings.threshold_for(name),
                band_threshold=settings.band_threshold_pct,
                # the band rule needs the same share of a view at any resolution
                band_min_pixels=int(settings.band_min_pixels * max(1.0, (regions.silhouette.shape[1] / 640) ** 2)),
                material_factor=settings.material_noise_factor,
                bed_factor=settings.bed_noise_factor,
                max_changed_bed_fraction=settings.max_changed_bed_fraction,
                layer_shift_mm=settings.layer_shift_mm,
                last_observed=state.last_observed,
                # a camera that could not see the part at the previous check (glare, a face in the bed's
                # colour) has no mask of that height to measure the rise from: no growth reading
                measure_growth=state.last_observed_z == self.previous_z,
                previous_mask=state.previous_mask,
                anchor=state.anchor,
                max_drift=1 if state.frozen else 2,
                palette=state.palette,
                keep_pictures=self.keep_pictures,
                # once its band read solid, a camera's band coverage is read only where the part stalls
                band_coverage_wanted=((state.band_coverage or 0.0) < SOLID_MIN_COVERAGE
                                      or settings.min_growth_pct >= STALL_READ_BELOW_GROWTH_PCT),
                foreign_before=state.last_foreign,
                # (where one check's rise is too small to read, the growth test reads it against an older look)
                older_looks=[(mask, self.plan.view(name, zz).silhouette) for zz, mask in state.older_observed
                             if self.previous_z is not None and zz < self.previous_z],
                placed_at=tuple(state.placed_at),
                shift_before=state.last_observed_shift,
                left_before=state.left_before,
            )
            result = check_shape(**shape_args, candidates=state.shift_candidates, track_candidates=True)
            result = not_decisive_where_it_stood(result, shape_args)
            shape_inputs[name] = shape_args
            shape[name] = self._second_look(name, result, shape_args) or result
            if result.usable and result.first_look and result.outline_best_candidate is not None \
                    and _px_apart(result.outline_best_candidate, result.shift_px) > OUTLINE_DISAGREES_PX:
                state.first_look_outline = result.outline_best_candidate
            errors[name] = shape[name].error_pct if result.usable else None
            state.left_before = ((frame, result.shadow_left_mask)
                                 if result.usable and result.shadow_left_mask is not None else None)
            if result.usable:
                state.saw(result.observed_mask, z, shape[name].shift_px)
                state.last_growth = result.growth_pct
            # (a view read against a relit background is remembered only for the part's rise: lit bed read as the
            # part where the light under it was guessed would be taken for the part's colours and outline next
            # time, and would pull the alignment the anchor holds for the rest of the print)
            places = result.usable and result.passed and not result.relit
            if result.palette is not None and places:
                state.palette = result.palette
            if places:
                state.previous_mask, state.previous_mask_at = result.observed_mask, (z, result.shift_px)
                state.seen_share = max(result.outline_coverage, state.seen_share or 0.0)
                state.placed(result, shape_args["max_drift"],
                             tall=_silhouette_rows(regions.silhouette) >= 2 * regions.max_shift_px)
        self._learn_calibration_offsets(z, shape, shape_inputs, errors)
        # missing material alone gets its second look only from a camera no other camera corroborates
        failing = [name for name, r in shape.items() if r.usable and not r.passed]
        if len(failing) == 1:
            name = failing[0]
            second = self._second_look(name, shape[name], shape_inputs[name], missing=True,
                                       growth_before=growth_before.get(name))
            if second is not None:
                shape[name] = second
                errors[name] = second.error_pct
        # how solid each camera's newest band looked before this check (decide: a stall under a nest of strands)
        coverage_before = {name: state.band_coverage for name, state in self.cameras.items()
                           if state.band_coverage is not None}
        for name, r in shape.items():
            if r.usable and not r.first_look and r.band_part_coverage is not None:
                state = self.cameras[name]
                state.band_coverage = max(r.band_part_coverage, state.band_coverage or 0.0)
        shape_seconds = time.perf_counter() - started
        shape_cpu_seconds = time.process_time() - cpu_started
        size = self._size_check(z, frames, shape)
        band_shifts = band_shifts_of(shape)
        placed_at = {name: state.placed_at for name, state in self.cameras.items()}
        layer_shift = layer_shift_of(shape, self.band_shift_history, band_shifts, placed_at=placed_at)
        history_before = self.band_shift_history
        self.band_shift_history = [*self.band_shift_history, (self.previous_z is not None, band_shifts)][-4:]
        top_closing = self.plan.top_closing(z)
        # kept for a re-decision on other evidence (bench_detection's shape-only verdict: size={})
        self.last_decision = dict(shape=shape, size=size, settings=settings, unreadable=unreadable,
                                  layer_shift=layer_shift, top_closing=top_closing, pairs=self.plan.pairs,
                                  extra_before=extra_before, band_coverage_before=coverage_before,
                                  rise_before=rise_before, missing_before=missing_before,
                                  missing_at_rise=missing_at_rise, band_texture_before=texture_before,
                                  held_rise_before=held_rise_before, missing_while_rising=while_rising,
                                  first_rise_reading=not self.rise_ever_read,
                                  most_missing_before=most_missing_before)
        self.last_layer_shift_inputs = (history_before, placed_at)
        verdict, reasons = self.decide_again()
        for name, state in self.cameras.items():
            r = shape.get(name)
            if r is None or not r.usable:
                state.last_extra = state.last_rise = state.last_missing = state.last_foreign = None
                state.read_rise_last_check, state.rise_readings = False, ()
                state.rise_missing, state.rise_quiet = None, 0
                state.band_textures = ()
                state.missing_while_rising = None
                state.most_missing = None
                continue
            if verdict == "ok":   # (a check that failed is no healthy look: a part knocked over misses much)
                state.most_missing = max(r.missing_pct, state.most_missing or 0.0)
            texture = None if r.first_look else r.band_texture
            state.band_textures = (*state.band_textures, texture)[-TEXTURE_MEMORY_CHECKS:]
            state.last_extra, state.last_missing, state.last_foreign = r.extra_pct, r.missing_pct, r.foreign_mask
            rise_before_this = state.last_rise
            reading = finest_reading(r)
            state.read_rise_last_check = reading is not None
            if reading is not None:
                self.rise_ever_read = True
                # (one more than a held rise needs: a stop late in an interval reads part of the rise first)
                state.rise_readings = (*state.rise_readings, reading)[-RISE_HELD_READINGS - 1:]
            state.last_rise = rise_since_previous_check(r)
            if verdict == "ok":   # (a check that failed is no healthy look: a part knocked loose still "rises")
                state.missing_while_rising = lowest_missing_while_rising(
                    state.missing_while_rising, state.last_rise, r.missing_pct, r.band_missing_pct)
            state.rise_missing, state.rise_quiet = missing_since_rise(
                state.rise_missing, state.last_rise, r.missing_pct, settings.min_growth_pct,
                quiet=state.rise_quiet, threshold=r.threshold, rise_before=rise_before_this)
        self.previous_z = z
        return CheckResult(layer=int(layer), z=float(z), verdict=verdict, shape_error_pct=errors, shape=shape,
                           size=size, reasons=reasons, seconds=time.perf_counter() - started,
                           unreadable=list(unreadable), shape_seconds=shape_seconds, layer_shift=layer_shift,
                           shape_cpu_seconds=shape_cpu_seconds, top_closing=top_closing)

    def decide_again(self, **overrides: Any) -> tuple[str, list[str]]:
        """(verdict, reasons) of the last check's evidence, :func:`decide`'s arguments changed by ``overrides`` (e.g.
        ``size={}``: the shape check's verdict alone), a failure decided once more with the evidence of the views that
        never saw the part whole set aside (:func:`without_views_never_seen_whole`: they laid their outline by the faces
        they saw)."""
        decision = {**self.last_decision, **overrides}
        verdict, reasons = decide(**decision)
        if verdict != "fail":
            return verdict, reasons
        return without_views_never_seen_whole(
            decision, {name: state.seen_share for name, state in self.cameras.items()},
            *self.last_layer_shift_inputs,
            anchor_share={name: state.anchor_share for name, state in self.cameras.items()}) or (verdict, reasons)

    def _second_look(self, name: str, result: ShapeResult, shape_args: dict,
                     missing: bool = False, growth_before: float | None = None) -> ShapeResult | None:
        """The camera's check again at the best of the shifts earlier checks could not tell apart, when it
        failed in a way a misplaced outline explains and nothing moved; the new result if it passes
        clearly, else None.

        A flat first layer with a brim fits the outline anywhere along the brim (a top view of a part on its
        shadow and brim, anywhere over tens of pixels), and the anchor the first checks leave may sit
        several pixels off; a later check then shows the part's side beyond the outline as "extra", or the
        bed beside it as "missing". Only those failures get a second look: extra material alone
        (``missing`` False), or missing material alone (``missing`` True: the caller asks only when no other
        camera fails, since a detached or stopped part is missed by several views) in a view that did not
        see the part slow (growth under 50 %) at this check nor at its previous one (``growth_before``: a
        runout or a part knocked away stops the rise, and with one usable camera nothing else can tell) and
        whose own shift is not among those this check cannot tell apart (``shift_candidates``: there the part
        fits as well as anywhere, and the best of them would only slide the outline down onto a stalled top);
        not decisive, no newest-band failure, the material seen at the previous check
        (``shape_args["last_observed"]``) still seen (a part that slid or was knocked off is not in place),
        the shift among those no passing check could tell apart, and the check passing
        there with half the threshold to spare. It changes nothing kept for later checks (anchor,
        candidates, masks): it can turn a failing camera into a passing one, never the other way round.
        """
        threshold = self.settings.threshold_for(name)
        if missing:
            # (and only where the overlap itself says the outline is misplaced: when this check's own shift is
            # among those it cannot tell apart, the part fits there as well as anywhere, and what is missing
            # there is material that is not there; the best of those shifts would slide the outline down onto
            # a stalled top, a runout seen by one view that cannot read the rise)
            shape_fits = (result.extra_pct < threshold / 3.0 <= result.missing_pct
                          and all(growth is None or growth >= 50.0 for growth in (result.growth_pct, growth_before))
                          and not _among(result.shift_px, result.shift_candidates))
        else:
            shape_fits = result.missing_pct < threshold / 3.0
        # Extra material alone is also what an outline slid down onto a brim or shadow shows (the part's side
        # above it): when the smallest move does not pass, the shift that puts the upper outlines together gets
        # a look too. Missing material alone is also what a stalled top shows, and matching upper outlines would
        # slide the outline down onto it: the smallest move only.
        # Only where the camera's first look already disagreed with its outline (and still does, at the same
        # place): material on top of the part (a stringing hair, a blob) also moves the outline match up onto
        # it, but it was not there at the first look.
        targets = [result.best_candidate]
        first_outline = self.cameras[name].first_look_outline
        if (not missing and result.outline_best_candidate not in (None, result.best_candidate)
                and first_outline is not None
                and _px_apart(result.outline_best_candidate, first_outline) <= OUTLINE_DISAGREES_PX):
            targets.append(result.outline_best_candidate)
        if (not shape_fits or not result.usable or result.passed or result.decisive or result.best_candidate is None
                or self.cameras[name].shift_candidates is None
                or (result.band_error_pct is not None and result.band_error_pct > self.settings.band_threshold_pct)
                or not _still_in_place(result.observed_mask, shape_args.get("last_observed"))):
            return None
        for target in targets:
            if target == result.shift_px:
                continue
            second = check_shape(**dict(shape_args, anchor=target, max_drift=0))
            if second.usable and second.passed and second.error_pct <= threshold / 2.0:
                if target != result.best_candidate:
                    # a layer shift or loose material also moves the upper outline: the outline's fit excuses
                    # the shape figures only; the newest band's shift and the new material stay the first look's
                    second = replace(second, band_shift=result.band_shift, new_outside=result.new_outside)
                return second
        return None

    def _learn_calibration_offsets(self, z: float, shape: dict[str, ShapeResult], shape_inputs: dict[str, dict],
                                   errors: dict[str, float | None]) -> None:
        """Learn a camera's calibration error when it is larger than the stated one (updates ``shape``).

        A camera that has never passed a check and fails is checked again with its alignment bound widened
        (``CALIBRATION_PROBE_WIDEN`` times; the part partly outside the reach of its outline reads as missing
        material). When the part then fits, beyond the ordinary bound but within ``CALIBRATION_MAX_LEARNED``
        times it, with half the threshold and half the error to spare, the camera's calibration is off by that
        shift, or the part was knocked off before the camera's first check. It is the calibration when another
        camera passes this check with the part where its calibration puts it and no single move of the part
        on the bed explains every camera's shift; with no camera to vouch, when the part, seen there at the
        next check, grew there as the model says (a knocked-off part does not grow). Until then the camera
        abstains, once per print, with the reason. A learned shift becomes the camera's anchor for the rest
        of the print (frozen) and its bound is widened to reach it."""
        in_place = [name for name, r in shape.items()
                    if r.usable and r.passed and self.cameras[name].calibration_offset is None
                    and float(np.hypot(*r.shift_px)) <= shape_inputs[name]["regions"].max_shift_px]
        for name, result in list(shape.items()):
            state = self.cameras[name]
            if not result.usable or result.passed:
                continue
            if state.anchor is not None:
                # it passed before (or learned already): an anchor only short looks laid may be laid again, else
                # only an anchor pinned at the bound may move
                if not self._anchor_again_once_clear(name, z, result, shape, shape_inputs, errors):
                    self._learn_beyond_pinned_anchor(name, z, result, shape, shape_inputs, errors, in_place)
                continue
            pending, state.pending_offset = state.pending_offset, None
            vouching = [other for other in in_place if other != name]
            if not vouching and pending is None and state.offset_abstained:
                continue
            args = shape_inputs[name]
            bound = float(args["regions"].max_shift_px)
            probe = _probe_beyond_bound(args, result, bound, beyond=bound)
            if probe is None:
                continue
            offset = float(np.hypot(*probe.shift_px))
            where = (f"{name}: the part appears {offset:.0f} px from where the calibration puts it "
                     f"({probe.shift_px[0]:+d}, {probe.shift_px[1]:+d} px; the stated calibration error allows "
                     f"{bound:.0f} px)")
            if vouching:
                if _moved_as_one(probe, args, [(shape[other], shape_inputs[other]) for other in vouching]):
                    continue
                why = f"while {', '.join(vouching)} see it in place"
            elif pending is None:
                state.pending_offset, state.offset_abstained = probe.shift_px, True
                state.saw(probe.observed_mask, z, probe.shift_px)
                shape[name] = replace(result, usable=False, passed=True, decisive=False, reasons=[
                    f"{where}, and no other camera sees the part in place: not judged until the next check tells "
                    f"a calibration error (the part grows there) from a part knocked off (it does not)"])
                errors[name] = None
                continue
            elif (float(np.hypot(probe.shift_px[0] - pending[0], probe.shift_px[1] - pending[1])) > 3.0
                  or probe.growth_pct is None or probe.growth_pct < CALIBRATION_GROWTH_PCT):
                continue
            else:
                why = f"at two checks, and it grew there ({probe.growth_pct:.0f} % of the expected rise)"
            self._adopt_offset(name, z, probe, f"{where} {why}: this camera's calibration is off and its checks now "
                                               f"use that shift (recalibrate it)", shape, errors)

    def _adopt_offset(self, name: str, z: float, probe: ShapeResult, reason: str, shape: dict[str, ShapeResult],
                      errors: dict[str, float | None]) -> None:
        """Make ``probe``'s shift the camera's learned calibration offset and ``probe`` (with ``reason``) its
        result at this check (updates ``shape`` and ``errors``)."""
        self.cameras[name].calibration_offset = probe.shift_px
        self._adopt_place(name, z, probe, reason, shape, errors)

    def _adopt_place(self, name: str, z: float, probe: ShapeResult, reason: str, shape: dict[str, ShapeResult],
                     errors: dict[str, float | None]) -> None:
        """Make ``probe``'s shift the camera's anchor, held for the rest of the print, and ``probe`` (with
        ``reason``) its result at this check (updates ``shape`` and ``errors``)."""
        state = self.cameras[name]
        state.anchor = probe.shift_px
        state.anchor_share = probe.outline_coverage
        state.placed_at = [probe.shift_px]   # (the earlier places are not where the part is)
        # held there: the alignment's prior, centred on the stated calibration, would walk it back
        state.frozen = True
        probe.reasons.append(reason)
        shape[name] = probe
        errors[name] = probe.error_pct
        state.saw(probe.observed_mask, z, probe.shift_px)
        state.previous_mask, state.last_growth = probe.observed_mask, probe.growth_pct
        state.previous_mask_at = (z, probe.shift_px)
        if probe.palette is not None:
            state.palette = probe.palette

    def _anchor_again_once_clear(self, name: str, z: float, result: ShapeResult, shape: dict[str, ShapeResult],
                                shape_inputs: dict[str, dict], errors: dict[str, float | None]) -> bool:
        """A camera whose anchor only short looks laid, failing where the part now stands tall in its view or where
        the overlap rules the anchor out (:func:`_anchor_off_the_overlap`): lay the outline again, free of that
        anchor, when the part clearly fits elsewhere within the bound and its own frames show it in place and grown
        there (updates ``shape``; True when it did).

        A first look at a part a few millimetres tall on a brim of its colour, or a top on its shadow, fits the
        outline anywhere along the brim, and the anchor it leaves may sit 10-20 px off the part; while the part
        is short that still passes, and the anchor is held only once a tall look passes (``CameraState.frozen``).
        As the part rises out of the brim, its side beyond the misplaced outline reads as extra material and the
        bed inside it as missing, at every check, and no look passes to move the anchor. A tall look is
        unambiguous, and so is a shorter one whose ties (the shifts the overlap cannot tell from its best) all lie
        away from the anchor (cross-check seed 38 ``003_normal``: 64 rows, one short of twice the bound, ties 4 px
        and more from it) while the other views see the part rise (:func:`core.verdict.visibly_rising`; strands on
        a part that slowed fit the outline away from the anchor too). The part must fit at one place, clearly (half
        the threshold and half the failing error to spare, its newest band in place, not decisive), and the
        camera's frames tell a misplaced outline from a part that moved: the material seen at the previous check is
        still seen (a part that slid or was knocked off is not), the part grew there as the model says (a stopped or
        detached part does not), and the part as the camera's last passing check saw it covers the model's outline
        of then at the new place as well as where that check laid it: an anchor that was wrong was wrong then too,
        while a part that moved or layers that shifted since leave that look's part at the old place (an outline
        fitted on shifted newest layers leaves the layers below beside it). Once per print: the new anchor is held
        (frozen)."""
        state = self.cameras[name]
        args = shape_inputs[name]
        regions = args["regions"]
        # (args["measure_growth"]: its last look is the previous check's, whose model outline is known)
        if (state.frozen or result.first_look or not args["measure_growth"] or state.previous_mask_at is None
                or not _still_in_place(result.observed_mask, args.get("last_observed"))):
            return False
        tall = _silhouette_rows(regions.silhouette) >= 2 * regions.max_shift_px
        # (cross-check seed 34 ``034_spaghetti``: a short look on strands, the other views reading 50 % and 21 %)
        others = {other: r for other, r in shape.items() if other != name and r.usable}
        if not (tall or (visibly_rising(others) and _anchor_off_the_overlap(result.observed_mask, regions,
                                                                            state.anchor, args["max_drift"]))):
            return False
        refit = check_shape(**dict(args, anchor=None, max_drift=2))
        z_then, placed_then = state.previous_mask_at
        before, then = state.previous_mask, self.plan.view(name, z_then).silhouette
        if not (refit.usable and refit.passed and not refit.decisive
                and refit.error_pct <= refit.threshold / 2.0 and refit.error_pct <= result.error_pct / 2.0
                and (refit.band_error_pct is None or refit.band_error_pct <= self.settings.band_threshold_pct)
                and (rise := rise_since_previous_check(refit)) is not None and rise >= VISIBLY_RISING_PCT
                and _covered_share(before, then, refit.shift_px, regions.tolerance_px)
                >= _covered_share(before, then, placed_then, regions.tolerance_px)
                and _px_apart(refit.shift_px, state.anchor) > args["max_drift"]):
            return False
        moved = _px_apart(refit.shift_px, state.anchor)
        state.shift_candidates = refit.shift_candidates
        self._adopt_place(name, z, refit, (
            f"{name}: the outline its first, short looks laid {moved} px off the part; the part, "
            f"{'tall now' if tall else 'clear of that outline now'}, fits at "
            f"({refit.shift_px[0]:+d}, {refit.shift_px[1]:+d}) px, in place since the previous check and grown there "
            f"({rise:.0f} % of the expected rise): its checks use that place from now on"), shape, errors)
        return True

    def _learn_beyond_pinned_anchor(self, name: str, z: float, result: ShapeResult, shape: dict[str, ShapeResult],
                                    shape_inputs: dict[str, dict], errors: dict[str, float | None],
                                    in_place: list[str]) -> None:
        """A camera that passed its earlier checks with its outline pinned at its bound and fails now: learn its
        calibration error beyond the bound when its own view shows the part in place and grown there
        (updates ``shape``).

        A calibration error larger than the stated one first shows as an anchor at the edge of the
        alignment's reach (the short part still fits within the tolerance), then, as the part grows, as extra
        or missing material beside the outline. The camera's own frames tell that from a failure: the material
        seen at the previous check is still seen (a part that moved is not), and at a shift beyond the anchor,
        in the direction the anchor was pinned, the part fits clearly and grew as the model says (a stopped
        part does not). A camera whose learned shift falls short as the part grows learns again the same way.
        Another camera that passes with the part in place must not see one move of the part on the bed
        explain both views (a knocked part)."""
        state = self.cameras[name]
        args = shape_inputs[name]
        regions = args["regions"]
        # the stated calibration's bound (a learned shift widened this camera's by its length)
        bound = float(regions.max_shift_px) - float(np.hypot(*(state.calibration_offset or (0, 0))))
        anchor = np.asarray(state.anchor, float)
        reach = float(np.hypot(*anchor))
        if reach < CALIBRATION_PINNED_SHARE * bound \
                or not _still_in_place(result.observed_mask, args.get("last_observed")):
            return
        probe = _probe_beyond_bound(args, result, bound, beyond=max(bound, reach))
        if probe is None or probe.growth_pct is None or probe.growth_pct < CALIBRATION_GROWTH_PCT:
            return
        offset = float(np.hypot(*probe.shift_px))
        # beyond the bound where the anchor was pinned: the anchor is the bound's nearest point to that shift
        towards = np.asarray(probe.shift_px, float) * (reach / offset)
        if float(np.hypot(*(towards - anchor))) > 2.0 * float(regions.tolerance_px) + 1.0:
            return
        if _moved_as_one(probe, args, [(shape[other], shape_inputs[other]) for other in in_place if other != name]):
            return
        # the shifts earlier checks could not tell apart lay within the old reach
        state.shift_candidates = None
        self._adopt_offset(name, z, probe, (
            f"{name}: the part appears {offset:.0f} px from where the calibration puts it ({probe.shift_px[0]:+d}, "
            f"{probe.shift_px[1]:+d} px; the stated calibration error allows {bound:.0f} px), in place since the "
            f"previous check and grown there ({probe.growth_pct:.0f} % of the expected rise): this camera's "
            f"calibration is off and its checks now use that shift (recalibrate it)"), shape, errors)

    def _size_check(self, z: float, frames: Mapping[str, np.ndarray | None],
                    shape: Mapping[str, ShapeResult]) -> dict[str, dict]:
        """The stereo size check of every pair (seed ch. 5), fed with the shape check's observed masks
        and image shifts. A pair that cannot measure abstains (``error_pct`` None): never a pause.
        """
        from .stereo.size_check import PairSizeCheck, SizeResult, SizeSettings

        size: dict[str, dict] = {}
        for left, right in self.plan.pairs:
            key = f"{left}+{right}"
            check = self.size_checks.get(key)
            if check is None:
                check = PairSizeCheck(self.plan.cameras[left], self.plan.cameras[right], self.plan.part.mesh,
                                      self.plan.footprint,
                                      SizeSettings(threshold_pct=self.settings.size_threshold_pct,
                                                   flat_margin_mm=self.settings.bed_marks_margin_mm),
                                      self.backgrounds.get(left), self.backgrounds.get(right))
                self.size_checks[key] = check

            # Shape first, then size (seed 3.5): a pair is measured only on silhouettes its cameras'
            # shape checks accepted; otherwise the verdict is the shape check's and the pair abstains.
            refused = [name for name in (left, right)
                       if shape.get(name) is None or not shape[name].usable or not shape[name].passed]
            if refused:
                size[key] = SizeResult(key, None, None, None, None, None, abstained=True,
                                       threshold_pct=self.settings.size_threshold_pct,
                                       reason=f"not measured: the shape check did not pass on {', '.join(refused)}"
                                       ).to_dict()
                continue
            # The shape check's image shift is the calibration error at the part (bounded, frozen).
            result = check.measure(frames.get(left), frames.get(right), z,
                                   mask_left=shape[left].observed_mask, mask_right=shape[right].observed_mask,
                                   shift_left=shape[left].shift_px, shift_right=shape[right].shift_px)
            size[key] = unless_both_views_grew(result.to_dict(),
                                               [shape[name].growth_pct for name in (left, right)])
        return size


def unless_both_views_grew(entry: dict, growth_pct: Sequence[float | None]) -> dict:
    """A pair's size entry, abstaining instead of the seed's "nothing at the current height" (100 %) when
    both of the pair's cameras saw the part's outline rise as the model says since the previous check
    (``growth_pct`` >= 50 each): then the reconstruction missed the top (an outline read millimetres
    low on a tower), not the part. Other entries are returned unchanged."""
    if (entry.get("error_pct") is None or entry.get("width_mm") != 0.0
            or not all(g is not None and g >= 50.0 for g in growth_pct)):
        return entry
    rises = ", ".join(f"{g:.0f} %" for g in growth_pct)
    return dict(entry, error_pct=None, abstained=True,
                reason=f"{entry.get('reason', '')}; not held: both views saw the part grow ({rises} of the "
                       f"expected rise)")


def follows_the_shifted_top(anchor: tuple[int, int] | None, moved_to: tuple[int, int], result: ShapeResult) -> bool:
    """Whether a passing check would move a camera's anchor (dx, dy) to ``moved_to`` along the shift its newest band
    reads, on a part whose newest layers may have been printed shifted (:func:`top_may_have_shifted`): the outline
    following the shifted top. (An outline that moves the other way, or none, follows something else.)"""
    if anchor is None or not top_may_have_shifted(result):
        return False
    band = result.band_shift
    return (moved_to[0] - anchor[0]) * band.dx + (moved_to[1] - anchor[1]) * band.dy > 0


def top_may_have_shifted(result: ShapeResult) -> bool:
    """Whether a camera's newest layers may have been printed shifted: its newest band reads shifted
    (:func:`band_reads_shifted`) on a part it saw rise (a fine growth reading of TOP_ROSE_PCT or more: the new
    layers are all there, beside; strands or a stalled top that read as a shifted band do not rise)."""
    return (band_reads_shifted(result.band_shift) and result.growth_pct is not None
            and result.growth_pct >= TOP_ROSE_PCT)


def agreeing_anchor(shift: tuple[int, int], candidates: np.ndarray | None, drift: int) -> tuple[int, int]:
    """The anchor a passing check leaves: its shift (dx, dy), or, when that lies more than ``drift`` px (per
    axis) from every shift the check could not tell apart (``candidates``, (k, 2) (dx, dy)), the nearest of
    those.

    The shift comes from a search near the previous anchor that breaks ties on the upper outline; the
    candidates from the exact overlap near the shifts earlier checks left. When they part, the anchor sits
    where the overlap is clearly worse (a part standing on its own cast shadow: the outline slides onto the
    shadow), and the smallest move that makes it agree with the overlap is to the nearest candidate."""
    if candidates is None or not len(candidates):
        return shift
    offsets = np.asarray(candidates, int).reshape(-1, 2) - np.asarray(shift, int)
    if int(np.abs(offsets).max(axis=1).min()) <= drift:
        return shift
    nearest = int(np.argmin(offsets[:, 0] ** 2 + offsets[:, 1] ** 2))
    return int(shift[0] + offsets[nearest, 0]), int(shift[1] + offsets[nearest, 1])


def _still_in_place(observed: np.ndarray | None, before: np.ndarray | None, share: float = 0.9) -> bool:
    """Whether at least ``share`` of the material seen at the previous check (``before``, (h, w) bool) is
    still seen now (``observed``). A part that slid or was knocked off is not."""
    if observed is None or before is None or before.shape != observed.shape or not before.any():
        return False
    return np.count_nonzero(observed & before) >= share * np.count_nonzero(before)


def _anchor_off_the_overlap(observed: np.ndarray | None, regions: ExpectedRegions, anchor: tuple[int, int] | None,
                            max_drift: int) -> bool:
    """Whether the overlap of the expected silhouette on ``observed`` ((h, w) bool) rules ``anchor`` out: every shift
    it cannot tell from the best (:func:`core.alignment.align_candidates`, within the bound) lies more than
    ``max_drift`` px (per axis) from the anchor. A short look cannot tell where along a brim of the part's colour the
    outline belongs (ties spanning 10-20 px there), but one whose ties all lie away from the anchor shows it wrong."""
    if observed is None or anchor is None:
        return False
    _, ties = align_candidates(observed, np.asarray(regions.silhouette, bool), int(regions.max_shift_px))
    return bool(len(ties)) and not near_any(anchor, ties, max_drift)


def smoothest_band_texture(readings: Sequence[float | None]) -> float | None:
    """The smoothest of a camera's band texture readings at its last checks (None where it has none)."""
    known = [reading for reading in readings if reading is not None]
    return min(known) if known else None


def _covered_share(observed: np.ndarray, silhouette: np.ndarray, shift: tuple[int, int], tolerance_px: float) -> float:
    """The share of ``silhouette`` ((h, w) bool, the model's outline at the calibrated place) moved by ``shift``
    (dx, dy) that ``observed`` ((h, w) bool material) covers, to within ``tolerance_px``."""
    expected = shift_mask(silhouette, int(shift[0]), int(shift[1]))
    area = np.count_nonzero(expected)
    return float(np.count_nonzero(expected & dilate(observed, tolerance_px))) / area if area else 0.0


def _silhouette_rows(mask: np.ndarray) -> int:
    rows = np.flatnonzero(mask.any(axis=1))
    return int(rows[-1] - rows[0] + 1) if rows.size else 0


def first_failure_layer(results: Sequence[CheckResult]) -> int | None:
    for r in results:
        if r.verdict == "fail":
            return r.layer
    return None


# ------------------------------------------------------------------- replay
def evaluate_recording(recording, settings: DetectionSettings | None = None, *, session_label: str | None = None,
                       cache_dir: str | Path | None = None, overlay_dir: str | Path | None = None,
                       keep_results: bool = False) -> dict:
    """Replay a loaded :class:`~octoprint_printwatch.core.recording.Recording` through :class:`CheckRunner`
    and return the ``printwatch evaluate`` document (``docs/recording-format.md``).

    ``overlay_dir`` (optional) receives one overlay picture per camera per check
    (``<NNN>_<camera>.jpg``). With ``keep_results`` the :class:`CheckResult` objects are
    returned too, under the key ``"_results"`` (not JSON; for benchmarks and tests).
    """
    settings = settings or DetectionSettings()
    # a writer may list checks in any order; they ran bottom up (same height: by layer)
    checks = sorted(recording.checks, key=lambda c: (c.z, c.layer))
    plan = prepare_job(gcode_path=recording.gcode, model_path=recording.model, cameras=recording.cameras,
                       pairs=recording.pairs, check_heights=[(c.layer, c.z) for c in checks],
                       settings=settings, cache_dir=cache_dir)
    backgrounds = {name: recording.read_background(name) for name in recording.cameras}
    runner = CheckRunner(plan, settings, backgrounds)
    runner.keep_pictures = overlay_dir is not None
    out_dir = Path(overlay_dir) if overlay_dir else None
    if out_dir:
        out_dir.mkdir(parents=True, exist_ok=True)
    results = []
    for index, check in enumerate(checks):
        frames = {name: recording.read_frame(check, name) for name in recording.cameras}
        result = runner.run_check(check.layer, check.z, frames)
        results.append(result)
        if out_dir:
            for name, shape in result.shape.items():
                # a camera's name may hold a path separator ("usb/1"): one file per camera all the same
                target = out_dir / f"{index:03d}_{name.replace('/', '_').replace(chr(92), '_')}.jpg"
                if shape.overlay is not None and not cv2.imwrite(str(target), shape.overlay):
                    raise PrintWatchError(f"{target}: cannot write the overlay picture")
    doc = {
        "session": session_label if session_label is not None else str(recording.root),
        "prepare_seconds": round(plan.prepare_seconds, 3),
        "checks": [r.to_json() for r in results],
        "first_failure_layer": first_failure_layer(results),
        "settings": settings.to_dict(),
        "notes": [*recording.notes, *plan.notes],
    }
    if keep_results:
        doc["_results"] = results
    return doc
