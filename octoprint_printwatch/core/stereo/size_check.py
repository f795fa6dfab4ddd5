"""The two-camera size check: width at the current print height and printed height, in millimetres.

Per pair and check (seed section 5.3.3.2, "horizontal and vertical magnitude"; details and
measured figures in ``docs/stereo.md``):

1. undo the calibration error at the part: frames and masks are moved back by the image shift
   the shape check measured per camera (else stabilised onto the empty-bed frames);
2. rectify the pair into a window around the part (:mod:`.rectify`);
3. outline stereo (silhouette-edge stereo on the rectified rows) and dense matching
   (:mod:`.matching`, :mod:`.triangulate`): what is reconstructed at the current height;
4. height on the plane of the top (:mod:`.tangents`): each camera's upper silhouette edge against
   the model's top cut at each height, with the picture's vertical calibration error learnt once
   per job; the two cameras must agree;
5. width across the pair's line of sight from the tangent planes (:mod:`.tangents`): each camera's
   silhouette sides against the model's on the same rows, in mm at the part; the two cameras' mean;
6. compare with the model: ``error_pct`` is the larger relative error beyond what the pair's
   calibration can explain (a low top only when the part is well seen at its own top; a width too
   wide by what both cameras agree; a narrower width is not held against the print, since an unseen
   side looks the same); 100 % when the part is reconstructed but nothing at the current height
   (the rule that made the seed's detection 100 %).

It abstains (``error_pct`` None, never a pause) when the evidence is missing: a frame missing,
the part's top outside a view or too low to measure, untrusted rectification, too few outline
points, neither height nor width measured with both cameras agreeing; and when its match failed: nothing
reconstructed at the current height while both views' upper edges stand at it.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import cv2
import numpy as np

from ..camera import Camera
from ..material import clean_mask, material_evidence
from ..render import render_heights, render_silhouette
from .matching import MATCHERS, MatchSettings, compute_disparity
from .rectify import (RECTIFICATIONS, Rectification, align_on_bed, phase_shift, predict_disparity_range,
                      rectify_calibrated, rectify_seed, rectify_uncalibrated, refine_vertical, sift_matches)
from .tangents import Sections, half_contrast_edges, plane_height, tangent_offsets  # noqa: F401 (re-exported)
from .triangulate import seed_triangulate_cameras, triangulate_general

TRIANGULATIONS = ("general", "seed")
#: Where the model itself, rendered and reconstructed the same way, gives fewer outline points than this
#: in the band (its material at the current height stands inside lower, wider material in a view), the
#: seed's "nothing reconstructed at the current height" is no evidence by itself: it is not held when in
#: both views the picture changed since the previous check on at least MIN_CHANGED_FRACTION of the
#: model's newest band (five times the 1 % the part's older surface gives by construction): the part
#: grew there.
MIN_EXPECTED_OUTLINE = 4
MIN_CHANGED_FRACTION = 0.05
#: the newest band is looked for this far (px) around where the model puts it (the calibration's residual)
NEW_BAND_REACH_PX = 4
#: and this far (px) inside the part's silhouette (the bed's noise and the shake at the outline)
INSIDE_PX = 4
#: the previous picture is registered onto the current one within this many px (whole-pixel alignment
#: differs by a pixel between checks; shake)
REGISTER_PX = 2
#: a change of fewer grey levels is JPEG's quantisation
CHANGE_FLOOR = 4.0
#: 'rims': silhouette-edge stereo on rectified rows; 'dense': the matcher's points (the seed's way);
#: 'hybrid': height on the plane of the top, width from the tangent planes (tangents.py).
MEASURES = ("hybrid", "rims", "dense")
#: Default block side per matcher (SGBM aggregates along paths, so its block is small).
DEFAULT_BLOCK = {"sad": 15, "ssd": 15, "ncc": 15, "sgbm": 5}


@dataclass
class SizeSettings:
    """How the size check runs; defaults are the measured best (docs/stereo.md).

    rectification : 'calibrated' | 'uncalibrated' | 'seed'.
    matcher : 'sad' | 'ssd' | 'ncc' | 'sgbm'; block_size 0 means :data:`DEFAULT_BLOCK`.
    triangulation : 'general' (cv2.triangulatePoints) | 'seed' (Eqs. 2-2..2-14).
    threshold_pct : the seed's 10 %.
    band_mm : the width is measured over the top ``band_mm`` below the current height.
    min_points : 'dense' abstains with fewer reconstructed points over the footprint.
    min_band_points : fewer matched points in the band give no dense width.
    bed_reference : align the right camera's window on the empty bed (calibrated rectification only).
    measure : 'hybrid' (default: height on the plane of the top and width from the tangent planes,
        outline stereo and matched points for "nothing at the current height" and a part knocked far
        from its place), 'rims' (silhouette-edge stereo only) or 'dense' (the matcher's points only,
        as the seed); the last two are for comparison.
    min_height_px : below this many pixels of printed height in a view, the pair abstains.
    min_width_height_px : below this many, only the height is measured and held (default measure):
        at the foot of a low part a brim or skirt on the bed reads as width.
    width_tolerance_pct : width error a user's calibration (1 % focal, 0.5 degree) explains; with two
        pixels of silhouette edge and the height tolerance (0.5 degree at the part's distance + 1 mm)
        it is subtracted before the error is held against the print (``error_pct``).
    flat_margin_mm : flat material on the bed within this distance of the footprint (skirt, brim,
        shadow) may extend a silhouette's side: a side edge standing outside the model's where that
        material can show is not taken for the part's (the shape check's ``bed_marks_margin_mm``).
    """

    rectification: str = "calibrated"
    matcher: str = "sgbm"
    triangulation: str = "general"
    block_size: int = 0
    threshold_pct: float = 10.0
    band_mm: float = 1.5
    min_points: int = 300
    min_band_points: int = 25
    bed_reference: bool = True
    measure: str = "hybrid"
    min_height_px: float = 16.0
    min_width_height_px: float = 24.0
    width_tolerance_pct: float = 2.0
    flat_margin_mm: float = 12.0

    def __post_init__(self) -> None:
        if self.rectification not in RECTIFICATIONS:
            raise ValueError(f"unknown rectification {self.rectification!r}; choose one of {', '.join(RECTIFICATIONS)}")
        if self.matcher not in MATCHERS:
            raise ValueError(f"unknown matcher {self.matcher!r}; choose one of {', '.join(MATCHERS)}")
        if self.measure not in MEASURES:
            raise ValueError(f"unknown measurement {self.measure!r}; choose one of {', '.join(MEASURES)}")
        if self.triangulation not in TRIANGULATIONS:
            raise ValueError(f"unknown triangulation {self.triangulation!r}; choose one of {', '.join(TRIANGULATIONS)}")

    @property
    def block(self) -> int:
        return int(self.block_size or DEFAULT_BLOCK[self.matcher])


@dataclass
class SizeResult:
    """The size check of one pair at one check; ``to_dict`` is the ``size`` entry of ``evaluate``."""

    pair: str
    width_mm: float | None
    height_mm: float | None
    expected_width_mm: float | None
    expected_height_mm: float | None
    error_pct: float | None
    width_error_pct: float | None = None
    height_error_pct: float | None = None
    abstained: bool = False
    reason: str = ""
    threshold_pct: float = 10.0
    n_points: int = 0
    seconds: float = 0.0
    rectification: dict = field(default_factory=dict)
    points: np.ndarray | None = field(default=None, repr=False)  # (n, 3) printer points

    @property
    def failed(self) -> bool:
        return (not self.abstained) and self.error_pct is not None and self.error_pct > self.threshold_pct

    def to_dict(self) -> dict:
        def r(v, nd=2):
            return None if v is None else round(float(v), nd)

        return {"width_mm": r(self.width_mm), "height_mm": r(self.height_mm),
                "expected_width_mm": r(self.expected_width_mm), "expected_height_mm": r(self.expected_height_mm),
                "error_pct": r(self.error_pct), "width_error_pct": r(self.width_error_pct),
                "height_error_pct": r(self.height_error_pct), "abstained": self.abstained, "reason": self.reason,
                "threshold_pct": self.threshold_pct, "points": self.n_points, "seconds": r(self.seconds, 3),
                "rectification": self.rectification}


# ------------------------------------------------------------------ geometry
def width_direction(left: Camera, right: Camera) -> np.ndarray:
    """(2,) unit bed-plane direction across the pair's line of sight (perpendicular to the mean view)."""
    view = left.viewing_direction + right.viewing_direction
    xy = view[:2] / max(np.linalg.norm(view[:2]), 1e-12)
    return np.array([xy[1], -xy[0]])


def section_extent(mesh, z: float, direction: np.ndarray) -> tuple[float, float] | None:
    """(min, max) of the part's cross-section at height ``z`` along the unit bed direction; None if empty."""
    from trimesh.intersections import mesh_plane

    segments = mesh_plane(mesh, [0.0, 0.0, 1.0], [0.0, 0.0, float(z)])
    if len(segments) == 0:
        return None
    t = segments.reshape(-1, 3)[:, :2] @ np.asarray(direction, np.float64)
    return float(t.min()), float(t.max())


def expected_width(mesh, z: float, direction: np.ndarray, band_mm: float) -> float | None:
    """Extent along ``direction`` of the part between ``z - band_mm`` and ``z`` (what the band can show)."""
    top = float(mesh.bounds[1, 2])
    hi = min(z, top) - 0.05
    lows, highs = [], []
    for h in np.linspace(max(hi - band_mm, 0.05), hi, 5):
        extent = section_extent(mesh, h, direction)
        if extent is not None:
            lows.append(extent[0])
            highs.append(extent[1])
    if not lows:
        return None
    return max(highs) - min(lows)


def _grow_polygon(polygon: np.ndarray, margin: float) -> np.ndarray:
    angles = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    ring = np.column_stack([np.cos(angles), np.sin(angles)]) * margin
    grown = (np.asarray(polygon)[:, None, :] + ring[None]).reshape(-1, 2)
    return cv2.convexHull(grown.astype(np.float32)).reshape(-1, 2).astype(np.float64)


def _inside_polygon(polygon: np.ndarray, xy: np.ndarray, res: float = 0.25) -> np.ndarray:
    """(n,) bool: which (n, 2) bed points lie inside the convex polygon (rasterised at ``res`` mm)."""
    lo = polygon.min(axis=0) - 1
    size = np.ceil((polygon.max(axis=0) + 1 - lo) / res).astype(int) + 1
    grid = np.zeros((size[1], size[0]), np.uint8)
    cv2.fillPoly(grid, [np.round((polygon - lo) / res).astype(np.int32)], 1)
    ij = np.round((xy - lo) / res).astype(int)
    ok = (ij[:, 0] >= 0) & (ij[:, 0] < size[0]) & (ij[:, 1] >= 0) & (ij[:, 1] < size[1])
    out = np.zeros(len(xy), bool)
    out[ok] = grid[ij[ok, 1], ij[ok, 0]] > 0
    return out


def _box_points(footprint: np.ndarray, z0: float, z1: float, margin: float) -> np.ndarray:
    ring = _grow_polygon(footprint, margin)
    return np.vstack([np.column_stack([ring, np.full(len(ring), z)]) for z in (z0, z1)])


def _roi(camera: Camera, points: np.ndarray, pad: int = 12):
    uv = camera.project(points)
    uv = uv[np.all(np.isfinite(uv), axis=1)]
    if len(uv) == 0:
        return None
    x0, y0 = np.floor(uv.min(axis=0)) - pad
    x1, y1 = np.ceil(uv.max(axis=0)) + pad
    x0, y0 = max(x0, 0), max(y0, 0)
    x1, y1 = min(x1, camera.width - 1), min(y1, camera.height - 1)
    if x1 <= x0 or y1 <= y0:
        return None
    return (int(x0), int(y0), int(x1), int(y1))


def _in_view(camera: Camera, points: np.ndarray) -> bool:
    uv = camera.project(points)
    return bool(np.all(np.isfinite(uv)) and np.all((uv >= 0) & (uv <= [camera.width - 1, camera.height - 1])))


def _fill_hull(camera: Camera, points: np.ndarray) -> np.ndarray:
    mask = np.zeros((camera.height, camera.width), np.uint8)
    uv = camera.project(points)
    uv = uv[np.all(np.isfinite(uv), axis=1)]
    if len(uv) >= 3:
        cv2.fillConvexPoly(mask, cv2.convexHull(np.round(np.clip(uv, -5000, 5000)).astype(np.int32)), 1)
    return mask.astype(bool)


# ------------------------------------------------------------------- the check
class PairSizeCheck:
    """The size check of one stereo pair over one print; keeps the per-job rectification and bed reference.

    Parameters
    ----------
    left, right : the pair's calibrated cameras.
    mesh : the expected part (trimesh.Trimesh, printer coordinates).
    footprint : (n, 2) convex hull of the part on the bed (mm).
    background_left, background_right : empty-bed frames (distorted, BGR), optional but recommended.
    """

    def __init__(self, left: Camera, right: Camera, mesh, footprint: np.ndarray,
                 settings: SizeSettings | None = None, background_left: np.ndarray | None = None,
                 background_right: np.ndarray | None = None):
        self.left, self.right = left, right
        self.mesh = mesh
        self.footprint = np.asarray(footprint, np.float64)
        self.settings = settings or SizeSettings()
        self.background = (background_left, background_right)
        self.key = f"{left.name}+{right.name}"
        self.direction = width_direction(left, right)
        self.top = float(mesh.bounds[1, 2])
        self.sections = Sections(mesh)
        #: per camera, the picture's vertical offset at the part's top (raw frame px, down positive)
        self._v_anchor: dict[str, float] = {}
        self._rect: Rectification | None = None
        self._rect_plain: Rectification | None = None
        self._bed_note = ""
        #: the previous measured check: (z, (left frame, right frame)), moved back like the masks
        self._previous: tuple[float, tuple[np.ndarray, np.ndarray]] | None = None
        box = _box_points(self.footprint, 0.0, self.top + 3.0, 6.0)
        self.roi_left, self.roi_right = _roi(left, box), _roi(right, box)
        #: per camera, where flat material on the bed near the part (skirt, brim, shadow) can show
        flat = _box_points(self.footprint, 0.0, 0.0, self.settings.flat_margin_mm)
        self.flat_zone = {cam.name: _fill_hull(cam, flat) for cam in (left, right)}
        centre = np.array([*self.footprint.mean(axis=0), self.top / 2])
        distance = float(np.mean([np.linalg.norm(c.center - centre) for c in (left, right)]))
        #: How far above the current height a point may triangulate from calibration error alone
        #: (0.5 degree at the part's distance, plus a millimetre).
        self.z_tolerance = distance * np.tan(np.radians(0.5)) + 1.0
        #: Millimetres per pixel at the part (a silhouette edge is good to about a pixel or two).
        self.px_mm = distance / float(np.mean([left.K[0, 0], right.K[0, 0]]))
        #: Narrower than this (mm) a width is a few pixels wide: an edge's pixel or a stray touching it
        #: is tens of percent of it, so it is neither measured nor expected to be reconstructed.
        self.narrow_mm = max(4.0, 10.0 * self.px_mm)
        #: Widths this pair measured at its earlier checks of the print, too narrow ones too (:meth:`_held_width`: the
        #: first, too wide, is not held alone)
        self.widths_read = 0

    # -------------------------------------------------------- rectification
    def _region_masks(self) -> tuple[np.ndarray, np.ndarray]:
        box = _box_points(self.footprint, 0.0, self.top + 3.0, 25.0)
        bed = _box_points(self.footprint, 0.0, 0.0, 40.0)
        return (_fill_hull(self.left, box) | _fill_hull(self.left, bed),
                _fill_hull(self.right, box) | _fill_hull(self.right, bed))

    def rectification(self, frame_left: np.ndarray, frame_right: np.ndarray, *,
                      aligned: bool = False) -> Rectification:
        """The pair's rectification. ``aligned``: the frames were already moved back by the calibration
        error measured on the part, so the calibrated rectification is used as is (refining it on the
        bed as well would correct the same error twice)."""
        method = self.settings.rectification
        if method == "calibrated" and aligned:
            if self._rect_plain is None:
                self._rect_plain = rectify_calibrated(self.left, self.right, roi_left=self.roi_left,
                                                      roi_right=self.roi_right)
            return self._rect_plain
        if method == "calibrated":
            if self._rect is None:
                rect = rectify_calibrated(self.left, self.right, roi_left=self.roi_left, roi_right=self.roi_right)
                bg_left, bg_right = self.background
                applied = False
                if self.settings.bed_reference and bg_left is not None and bg_right is not None:
                    bed = _fill_hull(self.left, _box_points(self.footprint, 0.0, 0.0, 50.0)).astype(np.uint8)
                    bed_w = rect.warp(bed, "left", interpolation=cv2.INTER_NEAREST) > 0
                    applied, self._bed_note = align_on_bed(rect, bg_left, bg_right, bed_w)
                if not applied:
                    source = (bg_left, bg_right) if bg_left is not None and bg_right is not None \
                        else (frame_left, frame_right)
                    matches = sift_matches(source[0], source[1], self.left, self.right, *self._region_masks(),
                                           ransac=False)
                    rect = refine_vertical(rect, matches)
                self._rect = rect
            return self._rect
        masks = self._region_masks()
        matches = sift_matches(frame_left, frame_right, self.left, self.right, *masks)
        if method == "uncalibrated":
            return rectify_uncalibrated(self.left, self.right, matches, roi_left=self.roi_left,
                                        roi_right=self.roi_right)
        return rectify_seed(self.left, self.right, matches, roi_left=self.roi_left, roi_right=self.roi_right)

    def stabilise(self, frame: np.ndarray, which: str) -> np.ndarray:
        """The frame moved back onto its empty-bed frame (webcams shake by a pixel or two per frame)."""
        background = self.background[0 if which == "left" else 1]
        if background is None or background.shape != frame.shape:
            return frame
        cam = self.left if which == "left" else self.right
        busy = _fill_hull(cam, _box_points(self.footprint, 0.0, self.top + 10.0, 15.0))
        shift, response = phase_shift(background, frame, ~busy)
        if response < 0.05 or np.any(np.abs(shift) > 8) or np.all(np.abs(shift) < 0.1):
            return frame
        move = np.float32([[1, 0, -shift[0]], [0, 1, -shift[1]]])
        return cv2.warpAffine(frame, move, (frame.shape[1], frame.shape[0]), flags=cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_REPLICATE)

    # ------------------------------------------------------------ hybrid
    def _hybrid(self, result: SizeResult, views, z: float, exp_height: float, exp_width: float | None,
                tol_z: float, shift_left, shift_right, rim_height: float | None, dense_height: float | None,
                anything: bool, stereo_widths, started: float, model_outline_in_band=None,
                grew_inside=None) -> SizeResult:
        """The default measurement and verdict (docs/stereo.md, steps 4-6).

        Height on the plane of the top and width from the tangent planes (tangents.py), each camera
        on its own and the two agreeing; a low top counts only when the part is well seen at its own
        top. ``views``: ((camera, mask, |frame - bed|), ...) for left and right, frames already moved
        back by the shape check's shift. ``stereo_widths``: (outline, matched points) widths in the band,
        used only where the tangent planes cannot measure (a part knocked far from its place)."""
        s = self.settings
        diag = result.rectification
        z_top = min(z, self.top)
        z_hi = min(z + tol_z, self.top - 1e-3)
        # The picture's vertical calibration error at the part, learnt once per job (_anchor_heights),
        # kept in the raw frame: the shape check's shift may still move by a pixel later.
        dy_now = [float(sh[1]) for sh in (shift_left, shift_right)] \
            if shift_left is not None and shift_right is not None else [0.0, 0.0]

        def v_offsets():
            return [(self._v_anchor[cam.name] - dy) if cam.name in self._v_anchor else 0.0
                    for (cam, _, _), dy in zip(views, dy_now)]

        def fit_planes():
            return [plane_height(cam, m, d, self.sections, z, z_hi, v_offset=offset)
                    for (cam, m, d), offset in zip(views, v_offsets())]

        planes = fit_planes()
        if self._anchor_heights(planes, views, z, dy_now):
            planes = fit_planes()
            diag["height_anchored"] = True
        diag["height_anchor_px"] = [None if c.name not in self._v_anchor else round(self._v_anchor[c.name], 2)
                                    for c, _, _ in views]
        # A camera's height counts only when its upper edge fits the model's across the columns (an
        # edge that is not the part's far top edge -- the near rim of a dark vase whose top is unseen
        # -- gives heights that disagree from column to column).
        # Until the vertical offset is learnt, a camera's height is good only to what the calibration
        # can cause (half a degree at the part's distance and a millimetre); after, to a millimetre and
        # two pixels (the focal length's error and the edges), with or without the shape check's shift.
        if all(c.name in self._v_anchor for c, _, _ in views):
            tol_z = min(self.z_tolerance, 1.0 + 2.0 * self.px_mm)
        else:
            tol_z = self.z_tolerance
        fits = [p.height_mm is not None and p.spread_mm <= 2.0 * self.px_mm for p in planes]
        heights = [p.height_mm if ok else None for p, ok in zip(planes, fits)]
        diag["plane_heights_mm"] = [None if p.height_mm is None else round(p.height_mm, 2) for p in planes]
        diag["plane_spread_mm"] = [None if p.height_mm is None else round(p.spread_mm, 2) for p in planes]
        diag["outline_top_mm"] = None if rim_height is None else round(rim_height, 2)
        diag["matched_top_mm"] = None if dense_height is None else round(dense_height, 2)
        notes = []
        height = None
        if all(h is not None for h in heights) and abs(heights[0] - heights[1]) <= tol_z:
            height = float(np.mean(heights))
        elif all(h is not None for h in heights):
            notes.append(f"height not measured: the two cameras disagree ({heights[0]:.1f} / {heights[1]:.1f} mm)")
        else:
            # (Tried: the outline's top as a fallback, as before; it found one runout a check earlier
            # on one set, at 6 % median error: not kept -- abstaining beats a weak height.)
            why = "; ".join(f"{cam.name}: {p.reason}" for (cam, _, _), p in zip(views, planes)
                            if p.height_mm is None and p.reason)
            notes.append("height not measured: " + (why or "the upper edge does not fit the model's in both views"))
        # A low top (a print that stopped) counts only when the part is well seen at its own top: its
        # sides there where the model's are (an unseen side eats into the silhouette's top as well as its
        # sides). (Tried as a second corroboration: the outline's top by silhouette-edge stereo, which
        # read 2-5 mm high on the demo's rig and hid a runout; and "only bed between the observed and
        # the expected upper edge", which the part's own shadow on the bed defeats.)
        low_top = height is not None and height < z_top - tol_z
        z_band = max(height, 0.3) if low_top else z_top
        band_width = expected_width(self.mesh, z_band, self.direction, s.band_mm) if low_top else exp_width
        # A side edge outside the model's where a skirt, brim or shadow on the bed can show is not taken
        # for the part's (a skirt ring read as a sun gear 6 mm too wide). For a low top the sides only
        # tell whether the part is well seen, which a wider edge does not contradict.
        tangents = [tangent_offsets(cam, m, d, self.sections, z_band, s.band_mm,
                                    render_silhouette(self.mesh, cam, z_band), v_offset=offset,
                                    flat_zone=None if low_top else self.flat_zone[cam.name])
                    for (cam, m, d), offset in zip(views, v_offsets())]
        changes = [t.width_change_mm for t in tangents]
        diag["width_changes_mm"] = [None if c is None else round(c, 2) for c in changes]
        diag["side_rows_on_bed"] = [t.on_bed for t in tangents]
        measured = band_width is not None and band_width >= self.narrow_mm and all(c is not None for c in changes)
        width = at_least = None
        if measured:
            width, at_least = band_width + float(np.mean(changes)), band_width + float(min(changes))
        tolerance = None if band_width is None else band_width * s.width_tolerance_pct / 100.0 + self.px_mm * 2.0
        if low_top:
            if not measured or width < band_width - tolerance:
                notes.append(f"low top ({height:.1f} mm) not held: the part is not well seen at its top")
                height = None
            width = at_least = None  # that was the width at the part's own top, not at the current height
        terms = []
        if height is not None:
            result.height_mm = height
            result.height_error_pct = 100.0 * abs(height - exp_height) / max(exp_height, 1e-6)
            # what counts is the error beyond what the pair's own calibration can cause
            terms.append(100.0 * max(0.0, abs(height - exp_height) - tol_z) / max(exp_height, 1e-6))
        if self._low:
            # Below min_width_height_px the pair only measures (and learns its offset, for the checks
            # to come): at a low part's foot a brim reads as width, and the outline stereo is short.
            result.error_pct, result.abstained = None, True
            notes.append(f"measured only: the part is under {s.min_width_height_px:g} px tall in a view, "
                         f"too low to hold a size against the print yet")
            result.reason = "; ".join(notes)
            result.seconds = time.perf_counter() - started
            return result
        if not anything and (exp_width is None or exp_width < self.narrow_mm):
            # a top this narrow (a pyramid's apex, a spire) is a few pixels wide: not finding it is no
            # evidence that it is missing (a 3-mm apex paused a normal pyramid print on the benchmark)
            result.error_pct, result.abstained = None, True
            notes.append("the part is too narrow at the current height to be reconstructed")
            result.reason = "; ".join(notes)
            result.seconds = time.perf_counter() - started
            return result
        seed_rule = not anything
        if seed_rule and tolerance is not None and all(c is not None and c < -tolerance for c in changes):
            # Both views see the part narrower than the model: it is poorly seen (dark filament on a
            # dark bed eats into the silhouette's top as well as its sides), so not finding its top is
            # no evidence that it is missing. (Tried as well: not when the previous check reconstructed
            # material up to the current band -- material does not vanish; but a matched top reads up
            # to the height tolerance high, and it hid a runout on the stereo benchmark: not kept.)
            seed_rule = False
            notes.append("nothing reconstructed at the current height, not held: both views see the part "
                         "narrower than the model (poorly seen)")
        if seed_rule and _edges_reach(planes, z_top, tol_z):
            # Each camera's own silhouette stands up to the current height (its upper edge on the plane of
            # the top, the two agreeing), so the part is there: the outline stereo and the matcher failing
            # to reconstruct it is a failed match (a top edge that does not run steeply, a poorly seen face,
            # noise), not a measurement: no 100 % then, and say so (a height measured still counts). A print
            # that stopped shows a low top in both views.
            seed_rule = False
            notes.append("nothing reconstructed at the current height, not held: both views' upper edges stand "
                         "at it (" + ", ".join(f"{p.height_mm:.1f}" for p in planes) + " mm): the stereo match "
                         "failed, not the print")
        if seed_rule and _a_view_sees_the_top(heights, z_top, tol_z):
            # One camera's upper edge fits the model's across the columns at the current height: the part is
            # there. A view can lose a top it cannot tell from what lies behind it (black filament against a
            # dark backdrop) and read it low, but no view finds a top edge, shaped as the model's, where there
            # is none; a print that stopped shows a low top in both views. (A black frame on glass paused a
            # normal print on cross-check seed 21: one view's top at 33-45 mm as printed, the other's stuck at
            # 28-34.) A height measured still counts: the two disagreeing give none.
            seed_rule = False
            notes.append("nothing reconstructed at the current height, not held: one view's upper edge stands at "
                         "it (" + ", ".join("-" if h is None else f"{h:.1f}" for h in heights) + " mm, fitting "
                         "the model's): the other view does not see the top, the part is there")
        if seed_rule and _tops_disagree(planes, tol_z):
            # The two cameras' upper edges put the top at heights farther apart than the pair's calibration
            # explains: they are not the same edge, and at least one view is not seeing the part's top (black
            # filament on glass, where the top merges into what lies behind it). A print that stopped shows one
            # low top to both views; "nothing at the current height" from views that disagree on where the top
            # is measures nothing. (Cross-check seed 26 030_spaghetti: 12.8 / 8.2 mm at 16.8 mm, four checks
            # paused before the onset; every size-alone catch of the development sets has its two edges within
            # 0.9 mm, or one unmeasured.)
            seed_rule = False
            notes.append("nothing reconstructed at the current height, not held: the two views' upper edges "
                         "disagree on the top (" + ", ".join(f"{p.height_mm:.1f}" for p in planes) + " mm): "
                         "they do not see the same edge")
        if seed_rule and model_outline_in_band is not None:
            expected_points = model_outline_in_band()
            diag["model_outline_in_band"] = expected_points
            changed = None if expected_points >= MIN_EXPECTED_OUTLINE or grew_inside is None else grew_inside()
            diag["changed_where_new"] = None if changed is None else [round(c, 3) for c in changed]
            if changed is not None and min(changed) >= MIN_CHANGED_FRACTION:
                # The model itself, printed as sliced, gives (almost) no outline at this height: its material
                # here stands inside the silhouette of lower, wider material in a view (a narrow tier on a
                # wide base seen from above), where the outline stereo cannot see it and only the matched
                # points could (none on an untextured part). Not finding it is then no evidence that it is
                # missing, and both views saw the picture change where the model's newest band lies: the
                # part grew there. (A 16-mm tier on a 54-mm base paused a normal print on cross-check
                # seed 6; where that tier never came -- a runout -- the pictures do not change and the rule
                # still holds.)
                seed_rule = False
                notes.append("nothing reconstructed at the current height, not held: the model's material there "
                             "is inside lower, wider material in the views (no outline), and both views changed "
                             "where it is new (" + ", ".join(f"{100 * c:.0f} %" for c in changed) + ")")
        if seed_rule:
            # the seed's rule: the part is there (outline points were reconstructed), but nothing at
            # the current height. (Tried: not when a camera's upper edge reaches z; it removed a
            # size-alone false pause where the shape check had already failed, and a spaghetti
            # detection: not kept.)
            top = height if height is not None else rim_height
            result.width_mm, result.width_error_pct, result.error_pct = 0.0, 100.0, 100.0
            result.reason = "nothing reconstructed at the current height" + \
                ("" if top is None else f" (top found at {top:.1f} mm)")
            result.seconds = time.perf_counter() - started
            return result
        if width is not None and exp_width is not None:
            result.width_mm = width
            result.width_error_pct = 100.0 * abs(width - exp_width) / exp_width
            if width < exp_width - tolerance:
                # Too narrow is what a poorly seen side gives (dark filament on a dark bed shrinks the
                # silhouette in both views alike); a print that stopped or shrank shows in the height,
                # so a short width is not held against it (nor taken as evidence that all is well).
                notes.append("narrower than the model: not held against the print (a side may be poorly seen)")
            else:
                # too wide counts by what both cameras agree the part is at least
                terms += self._held_width(100.0 * max(0.0, at_least - exp_width - tolerance) / exp_width, notes)
        elif not low_top:
            # Where the tangent planes cannot measure (the part's sides are not where the model's are,
            # e.g. knocked over), a width that the outline and the matched points both find too wide
            # still counts (the shorter of the two, against the widest the model shows near this height).
            # Not where a side's edge stood on flat material on the bed (skirt, brim, shadow): the outline and
            # the matched points there span that material too (a blurred picture's skirt read a low part 12 %
            # too wide), the very rows the tangent planes left out.
            both = [w for w in stereo_widths if w]
            flat_sides = any(t.on_bed for t in tangents)
            widest = None
            if len(both) == 2 and not flat_sides and exp_width is not None and exp_width >= self.narrow_mm:
                widest = max(expected_width(self.mesh, z, self.direction, s.band_mm + 2.0 * tol_z) or exp_width, exp_width)
            if widest is not None and min(both) > widest + tolerance:
                result.width_mm = min(both)
                result.width_error_pct = 100.0 * abs(result.width_mm - exp_width) / exp_width
                notes.append("width from the outline and the matched points (the sides are not where the model's are)")
                terms += self._held_width(100.0 * (result.width_mm - widest - tolerance) / exp_width, notes)
            elif exp_width is not None and exp_width < self.narrow_mm:
                notes.append(f"width not measured: the part is under {self.narrow_mm:.1f} mm wide here (a few pixels)")
            else:
                notes.append("width not measured: the sides at this height are not seen as silhouette edges in both views"
                             + (" (a side's edge may be flat material on the bed: skirt, brim, shadow)"
                                if flat_sides else ""))
        result.error_pct = max(terms) if terms else None
        result.abstained = not terms
        result.reason = "; ".join(notes)
        if result.width_mm is not None:
            self.widths_read += 1
        result.seconds = time.perf_counter() - started
        return result

    def _held_width(self, error_pct: float, notes: list[str]) -> list[float]:
        """The width term (% beyond what the model and the pair's calibration allow) to hold against the print: none
        for a too-wide reading where this pair has measured no width before (:attr:`widths_read`; noted in ``notes``).
        A width needs both sides of the part seen as silhouette edges in both views, so a pair's first one comes where
        those edges first show, with no reading of its own to compare it with; from the second on, a width over the
        limit is held at once. A part too wide at the first reading (loose material, a shifted tier) is still too wide
        at the next (cross-check seed 36 ``016_normal``: a thin L read 8.9 mm wide at the pair's first width, 39.6 %
        over its 6.4 mm, and 7.0-7.3 mm at every later check)."""
        if self.widths_read == 0 and error_pct > self.settings.threshold_pct:
            notes.append(f"too wide by {error_pct:.1f} % beyond the tolerance at this pair's first width reading: "
                         f"not held until a second reading")
            return []
        return [error_pct]

    def _changed_where_new(self, previous, current, z: float) -> list[float] | None:
        """Per camera, the fraction of the pixels where the model's visible surface was printed since the
        previous check (within :data:`NEW_BAND_REACH_PX`, and at least :data:`INSIDE_PX` inside the
        part's silhouette, away from the bed's noise and the shake at the outline) whose picture changed
        since then, beyond what the part's older visible surface shows: its 99th percentile, or
        :data:`CHANGE_FLOOR` grey levels (JPEG's quantisation), after matching the exposure on that surface.
        About 1 % where nothing was printed; where the part grew, the newest band's edge moved there.
        None when there is no previous check below ``z`` or too few pixels to tell."""
        z_prev, before = previous
        if not z_prev < z:
            return None
        out = []
        for cam, b, c in zip((self.left, self.right), before, current):
            if b.shape != c.shape:
                return None
            b, c = _grey(b), _grey(c)
            heights = np.nan_to_num(render_heights(self.mesh, cam, min(z, self.top)), nan=-np.inf)
            new = (heights > z_prev + 1e-3).astype(np.uint8)
            inside = cv2.erode((heights > 0).astype(np.uint8), _disc(INSIDE_PX)) > 0
            zone = inside & (cv2.dilate(new, _disc(NEW_BAND_REACH_PX)) > 0)
            old = inside & (cv2.dilate(new, _disc(NEW_BAND_REACH_PX + 4)) == 0)
            if zone.sum() < 20 or old.sum() < 100:
                return None
            # The two frames were each moved back by their own check's shift, and whole-pixel alignment can
            # differ by a pixel between checks (or the camera shook): the older surface's edges and texture
            # then read as change and its 99th percentile hides the new band's. The older surface did not
            # change, so the previous picture is registered onto this one where it changes least.
            b = _registered(b, c, old, zone, REGISTER_PX)
            if b is None:
                return None
            gain = float(np.median(c[old])) / max(float(np.median(b[old])), 1.0)
            change = np.abs(c - gain * b)
            limit = max(float(np.quantile(change[old], 0.99)), CHANGE_FLOOR)
            out.append(float(np.mean(change[zone] > limit)))
        return out

    def _anchor_heights(self, planes, views, z: float, dy_now) -> bool:
        """Learn each camera's vertical offset at the part's top, once per job.

        A user's calibration (half a degree, a millimetre) moves the picture at the part by several
        pixels, which is a millimetre or two of height; the shape check's alignment is whole pixels
        and weak vertically (a shorter part slides inside a taller outline). The first check at which
        both cameras' upper edges fit the model well, the part is well seen (its sides not inside the
        model's) and the offset is within what the calibration can cause, fixes the offset for
        the rest of the print: later heights are measured against it. A failure that has already
        started by then (below about 5 mm, where the pair starts to measure) and is within that
        bound is absorbed into it: the part then stops growing from there, which later checks see."""
        if any(c.name in self._v_anchor for c, _, _ in views):
            return False
        if any(p.height_mm is None or not np.isfinite(p.residual_px) or p.spread_mm > 2.0 * self.px_mm
               for p in planes):
            return False
        bound_px = self.z_tolerance / self.px_mm
        if any(abs(p.residual_px) > bound_px for p in planes):
            return False
        band_width = expected_width(self.mesh, min(z, self.top), self.direction, self.settings.band_mm)
        if band_width is None:
            return False
        tolerance = band_width * self.settings.width_tolerance_pct / 100.0 + self.px_mm * 2.0
        for (cam, m, d), p in zip(views, planes):
            change = tangent_offsets(cam, m, d, self.sections, min(z, self.top), self.settings.band_mm,
                                     render_silhouette(self.mesh, cam, min(z, self.top)),
                                     v_offset=p.residual_px).width_change_mm
            # narrower than the model: a side poorly seen, maybe the top too (wider -- a brim, a
            # shadow at the foot -- does not move the upper edge, so the sides are read here without
            # leaving out flat material on the bed)
            if change is None or change < -tolerance:
                return False
        for (cam, _, _), p, dy in zip(views, planes, dy_now):
            self._v_anchor[cam.name] = dy + p.residual_px
        return True

    # -------------------------------------------------------------- measure
    def measure(self, frame_left: np.ndarray, frame_right: np.ndarray, z: float, *,
                mask_left: np.ndarray | None = None, mask_right: np.ndarray | None = None,
                shift_left=None, shift_right=None, keep_points: bool = False) -> SizeResult:
        """Measure the pair at print height ``z`` (mm).

        ``mask_left``/``mask_right``: the observed part (full distorted frame, bool), e.g. the shape
        check's; computed from the empty-bed frames when not given.
        ``shift_left``/``shift_right``: (dx, dy) px by which the shape check found the observed part
        displaced from the part rendered with the calibrated camera (calibration error plus shake,
        bounded and frozen once the part is tall enough, so a failing print cannot pull it). When
        given, frames and masks are moved back by it, which removes most of the pair's calibration
        error at the part; otherwise each frame is only stabilised onto its empty-bed frame.
        """
        started = time.perf_counter()
        s = self.settings
        exp_width = expected_width(self.mesh, z, self.direction, s.band_mm)
        exp_height = float(min(z, self.top))
        result = SizeResult(self.key, None, None, exp_width, exp_height, None, threshold_pct=s.threshold_pct)

        def abstain(reason: str) -> SizeResult:
            result.abstained, result.reason = True, reason
            result.seconds = time.perf_counter() - started
            return result

        top_ring = _box_points(self.footprint, z, z, 0.0)
        for cam in (self.left, self.right):
            if not _in_view(cam, top_ring):
                return abstain(f"{cam.name}: the part's top at z={z:g} mm is outside the picture")
        if frame_left is None or frame_right is None:
            return abstain("a camera of the pair gave no frame")
        centre = np.array([*self.footprint.mean(axis=0), 0.0])
        tall_px = []
        for cam in (self.left, self.right):
            foot, head = cam.project(np.array([centre, centre + [0.0, 0.0, z]]))
            tall_px.append(float(np.linalg.norm(head - foot)))
            # the outline stereo and the matched points need the taller part; the plane of the top less
            limit = s.min_height_px if s.measure == "hybrid" else s.min_width_height_px
            if tall_px[-1] < limit:
                return abstain(f"{cam.name}: the part is only {tall_px[-1]:.0f} px tall in the "
                               f"picture, too low to measure yet")
        self._low = min(tall_px) < s.min_width_height_px
        frame_left, frame_right = _to_size(frame_left, self.left), _to_size(frame_right, self.right)
        # |frame - empty bed| per view, for locating silhouette edges at half contrast
        diffs = [_difference(frame, bg) for frame, bg in zip((frame_left, frame_right), self.background)]
        if shift_left is not None and shift_right is not None:
            frame_left, mask_left = _moved(frame_left, mask_left, shift_left)
            frame_right, mask_right = _moved(frame_right, mask_right, shift_right)
            diffs = [None if d is None else _moved(d, None, sh)[0] for d, sh in zip(diffs, (shift_left, shift_right))]
            self.aligned_on_part = True
            # Aligned on the part: what remains is a pixel or two and the focal-length error.
            tol_z = min(self.z_tolerance, 1.0 + 2.0 * self.px_mm)
        else:
            tol_z = self.z_tolerance
            frame_left = self.stabilise(frame_left, "left")
            frame_right = self.stabilise(frame_right, "right")
            self.aligned_on_part = False

        current = (frame_left, frame_right)
        previous, self._previous = self._previous, (float(z), current)

        def grew_inside() -> list[float] | None:
            return None if previous is None else self._changed_where_new(previous, current, z)

        rect = self.rectification(frame_left, frame_right, aligned=self.aligned_on_part)
        result.rectification = rect.summary()
        result.rectification["aligned_on_part"] = self.aligned_on_part
        if self._bed_note and not self.aligned_on_part:
            result.rectification["bed_reference"] = self._bed_note
        if not rect.trusted:
            return abstain(f"rectification not trusted: {rect.reason}")

        # The observed part in each view: the shape check's masks when given, else background difference.
        region_left = _fill_hull(self.left, _box_points(self.footprint, 0.0, z + tol_z + 1.0, 4.0))
        region_right = _fill_hull(self.right, _box_points(self.footprint, 0.0, z + tol_z + 1.0, 4.0))
        if mask_left is None and self.background[0] is not None:
            mask_left = foreground_mask(self.background[0], frame_left, region_left)
        if mask_right is None and self.background[1] is not None:
            mask_right = foreground_mask(self.background[1], frame_right, region_right)
        mask_left = _clean_mask(mask_left, region_left)
        mask_right = _clean_mask(mask_right, region_right)
        if s.measure != "dense" and (mask_left is None or mask_right is None):
            return abstain("no observed silhouette in both views (background frames missing?)")

        wl, wr = rect.warp(frame_left, "left"), rect.warp(frame_right, "right")
        if rect.method == "calibrated":
            dmin, dmax = predict_disparity_range(rect, _box_points(self.footprint, 0.0, z + 2.0, 6.0),
                                                 margin_px=8 + rect.K_rect[0, 0] * np.tan(np.radians(1.0)))
        else:
            dmin, dmax = rect.disparity_range
        triangulate = seed_triangulate_cameras if s.triangulation == "seed" else triangulate_general

        def to_printer(x_left, y, x_right):
            pl = rect.to_camera_pixels(np.column_stack([x_left, y]).astype(np.float64), "left")
            pr = rect.to_camera_pixels(np.column_stack([x_right, y]).astype(np.float64), "right")
            return triangulate(self.left, self.right, pl, pr)

        def in_volume(points, margin=4.0):
            ok = np.all(np.isfinite(points), axis=1)
            ok[ok] = _inside_polygon(_grow_polygon(self.footprint, margin), points[ok, :2]) & \
                (points[ok, 2] > 0.3) & (points[ok, 2] < z + tol_z)
            return ok

        def outline_points(rows, a_l, b_l, a_r, b_r):
            """Silhouette-edge stereo of the outline on common rectified rows: (points, side 0/1, in band)."""
            # Where the outline runs along the rows (the top and bottom of the silhouette) its match is
            # ill-posed: a row error of a pixel moves it by many pixels. Keep steep outline only. Each
            # outline point stands on its own: rows may cut the part obliquely when the baseline tilts.
            steep_a = _steep(a_l, rows) & _steep(a_r, rows)
            steep_b = _steep(b_l, rows) & _steep(b_r, rows)
            rims = np.vstack([to_printer(a_l[steep_a], rows[steep_a], a_r[steep_a]),
                              to_printer(b_l[steep_b], rows[steep_b], b_r[steep_b])])
            side = np.r_[np.zeros(int(steep_a.sum()), int), np.ones(int(steep_b.sum()), int)]
            # Tangent rays of different edges (a box's corners) meet outside the part: the outline is
            # gated loosely around the footprint for the height, tightly for the width.
            kept = in_volume(rims, margin=12.0)
            rims, side = rims[kept], side[kept]
            in_band = (rims[:, 2] >= z - s.band_mm - tol_z) & (rims[:, 2] <= z + tol_z) & \
                _inside_polygon(_grow_polygon(self.footprint, 4.0), rims[:, :2])
            return rims, side, in_band

        def model_outline_in_band() -> int:
            """How many outline points the model itself, printed up to ``z``, gives in the band. The frames
            were moved back to where the calibrated cameras see the model, so it is rendered there. (Almost) none
            where its material at this height lies, in a view, inside the silhouette of lower and wider
            material (a narrow tier on a wide base seen from above): the outline stereo cannot see it."""
            sils = [rect.warp(render_silhouette(self.mesh, cam, min(z, self.top)).astype(np.float32), which)
                    for cam, which in ((self.left, "left"), (self.right, "right"))]
            outline = silhouette_rims(*sils)
            return 0 if len(outline[0]) < 4 else int(outline_points(*outline)[2].sum())

        rim_height = rim_width = dense_height = dense_width = None
        rim_any = dense_any = False
        if s.measure in ("rims", "hybrid") and mask_left is not None and mask_right is not None:
            # Silhouette-edge stereo: on each rectified row, the part's left and right outline in one
            # view matches the same outline in the other (the epipolar plane cuts the part's outline in
            # the same two points where both views share them), so the outline's depth needs no texture.
            fl_w = rect.warp(mask_left.astype(np.float32), "left")
            fr_w = rect.warp(mask_right.astype(np.float32), "right")
            rows, a_l, b_l, a_r, b_r = silhouette_rims(fl_w, fr_w)
            if diffs[0] is not None and diffs[1] is not None:
                dl, dr = rect.warp(diffs[0], "left"), rect.warp(diffs[1], "right")
                a_l, b_l = half_contrast_edges(dl, rows, a_l, +1), half_contrast_edges(dl, rows, b_l, -1)
                a_r, b_r = half_contrast_edges(dr, rows, a_r, +1), half_contrast_edges(dr, rows, b_r, -1)
            if len(rows) < 4:
                return abstain("the part's outline is not seen on common rows by both cameras")
            if not (dmin - 20 <= np.median(a_l - a_r) <= dmax + 20):
                return abstain("the two silhouettes do not correspond (disparity out of range)")
            rims, side, in_band = outline_points(rows, a_l, b_l, a_r, b_r)
            result.n_points = len(rims)
            if keep_points:
                result.points = rims
            if len(rims) < 8:
                return abstain(f"only {len(rims)} outline points reconstructed over the part")
            # Printed height: the top of the part's steep outline (its top corners).
            rim_height = dense_top(rims[:, 2], window_mm=0.5, min_count=5)
            rim_any = bool(in_band.any())
            # A width needs both sides of the outline at this height.
            if min((in_band & (side == 0)).sum(), (in_band & (side == 1)).sum()) >= 2:
                rim_width = _side_span(rims[in_band, :2] @ self.direction, side[in_band])
        if s.measure in ("dense", "hybrid"):
            region = region_left
            if mask_left is not None:
                region = region_left & (cv2.dilate(mask_left.astype(np.uint8), np.ones((9, 9), np.uint8)) > 0)
            region_w = rect.warp(region.astype(np.uint8), "left", interpolation=cv2.INTER_NEAREST) > 0
            settings = MatchSettings(s.matcher, dmin, max(dmax - dmin, 16), s.block)
            disparity = compute_disparity(wl, wr, settings, region_w) if region_w.any() else None
            if disparity is not None and mask_left is not None:
                # Every pixel of the observed part gets a depth, as in the seed (which matched every ROI
                # pixel): its own match, or the nearest match along its row; the edges then come from
                # the silhouette, sharper than any block matcher's depth edge.
                part_w = rect.warp(mask_left.astype(np.uint8), "left", interpolation=cv2.INTER_NEAREST) > 0
                disparity = fill_along_rows(disparity, part_w, max_gap=max(12, 2 * s.block))
            points = np.zeros((0, 3))
            if disparity is not None:
                ys, xs = np.nonzero(np.isfinite(disparity))
                d = disparity[ys, xs].astype(np.float64)
                points = to_printer(xs, ys, xs - d)
                points = points[in_volume(points)]
            if s.measure == "dense":
                result.n_points = len(points)
                if keep_points:
                    result.points = points
                if len(points) < s.min_points:
                    return abstain(f"only {len(points)} points reconstructed over the part")
            if len(points) >= s.min_points:
                dense_height = dense_top(points[:, 2], window_mm=0.5, min_count=max(8, len(points) // 500))
                band = points[(points[:, 2] >= z - s.band_mm - tol_z) & (points[:, 2] <= z + tol_z)]
                dense_any = len(band) > 0
                if len(band) >= s.min_band_points:
                    dense_width = robust_extent(band[:, :2] @ self.direction)
        if s.measure == "hybrid":
            views = [(self.left, mask_left, diffs[0]), (self.right, mask_right, diffs[1])]
            return self._hybrid(result, views, z, exp_height, exp_width, tol_z, shift_left, shift_right,
                                rim_height, dense_height, rim_any or dense_any, (rim_width, dense_width),
                                started, model_outline_in_band, grew_inside)
        if s.measure == "rims":
            height, width, anything = rim_height, rim_width, rim_any
        else:
            height, width, anything = dense_height, dense_width, dense_any
        if height is None:
            return abstain("no observed silhouette in both views (background frames missing?)")
        result.height_mm = height
        result.height_error_pct = 100.0 * abs(height - exp_height) / max(exp_height, 1e-6)
        # What counts towards a pause is the error beyond what the pair's own calibration can cause.
        terms = [100.0 * max(0.0, abs(height - exp_height) - tol_z) / max(exp_height, 1e-6)]
        if not anything:
            result.width_mm = 0.0
            result.width_error_pct = 100.0
            result.error_pct = 100.0
            result.reason = f"nothing reconstructed at the current height (top found at {height:.1f} mm)"
        elif width is None:
            result.error_pct = max(terms) if terms else None
            result.abstained = not terms
            result.reason = "width not measured at this height (one side of the outline unseen)"
        else:
            result.width_mm = width
            if exp_width is not None and exp_width >= 3.0:
                result.width_error_pct = 100.0 * abs(width - exp_width) / exp_width
                tolerance = exp_width * s.width_tolerance_pct / 100.0 + self.px_mm * 2.0
                # The band holds points down to tol_z below it, and each point's own height is good
                # to about tol_z too (the height the calibration can explain), so a correct print can
                # show whatever the model holds down to 2 tol_z below the band, where a tapering or
                # stepped part is wider: that widest extent is the upper bound a correct print can read.
                widest = expected_width(self.mesh, z, self.direction, s.band_mm + 2.0 * tol_z) or exp_width
                if width < exp_width - tolerance:
                    # Too narrow is what a poorly seen side gives (dark filament on a dark bed shrinks
                    # the silhouette in both views alike, so the two measurements agree on it); a print
                    # that stopped or shrank shows in the height, so a short width is not held against it
                    # (no term: nor is it taken as evidence that the print is fine).
                    result.reason = "narrower than the model: not held against the print (a side may be poorly seen)"
                else:
                    terms.append(100.0 * max(0.0, width - max(widest, exp_width) - tolerance) / exp_width)
            result.error_pct = max(terms) if terms else None
            result.abstained = not terms
        result.seconds = time.perf_counter() - started
        return result


def _a_view_sees_the_top(heights, z_top: float, tol_z: float) -> bool:
    """Whether a camera's upper-edge height, kept only where the edge fits the model's across the columns
    (None elsewhere), puts the part's top within ``tol_z`` (what the pair's calibration explains) of ``z_top``."""
    return any(h is not None and h >= z_top - tol_z for h in heights)


def _tops_disagree(planes, tol_z: float) -> bool:
    """Whether both cameras' upper edges (:func:`.tangents.plane_height`, fitting well or not) are measured and put
    the part's top more than ``tol_z`` (what the pair's calibration explains) apart."""
    heights = [p.height_mm for p in planes]
    return all(h is not None for h in heights) and abs(heights[0] - heights[1]) > tol_z


def _edges_reach(planes, z_top: float, tol_z: float) -> bool:
    """Whether both cameras' upper edges (:func:`.tangents.plane_height`, fitting well or not) put the part's
    top within ``tol_z`` (what the pair's calibration explains) of ``z_top`` and agree with each other."""
    heights = [p.height_mm for p in planes]
    if any(h is None for h in heights):
        return False
    return abs(heights[0] - heights[1]) <= tol_z and min(heights) >= z_top - tol_z


def silhouette_rims(left: np.ndarray, right: np.ndarray, min_run_px: int = 3):
    """Sub-pixel left and right outline of two rectified soft masks ((h, w) float in [0, 1]) per common row.

    Returns ``(rows, a_left, b_left, a_right, b_right)``: for each row seen by both, the leftmost
    (a) and rightmost (b) x where each mask crosses 0.5.
    """
    def edges(mask):
        inside = mask >= 0.5
        has = inside.sum(axis=1) >= min_run_px
        h, w = mask.shape
        first = np.argmax(inside, axis=1)
        last = w - 1 - np.argmax(inside[:, ::-1], axis=1)
        rows = np.arange(h)

        def crossing(col, step):
            prev = np.clip(col - step, 0, w - 1)
            v0, v1 = mask[rows, prev], mask[rows, col]
            with np.errstate(divide="ignore", invalid="ignore"):
                frac = np.where(np.abs(v1 - v0) > 1e-6, (0.5 - v0) / (v1 - v0), 1.0)
            return prev + step * np.clip(frac, 0.0, 1.0)

        return has, crossing(first, 1), crossing(last, -1)

    has_l, a_l, b_l = edges(left)
    has_r, a_r, b_r = edges(right)
    rows = np.nonzero(has_l & has_r)[0]
    return rows, a_l[rows], b_l[rows], a_r[rows], b_r[rows]


def _steep(x: np.ndarray, rows: np.ndarray, max_slope: float = 1.5) -> np.ndarray:
    """(k,) bool: the outline x(row) changes by at most ``max_slope`` px per row around each row."""
    if len(x) < 3:
        return np.zeros(len(x), bool)
    slope = np.abs(np.gradient(x.astype(np.float64), rows.astype(np.float64)))
    # both neighbours must be steep too: a corner's neighbour is not
    slope = np.maximum(slope, np.maximum(np.r_[slope[1:], np.inf], np.r_[np.inf, slope[:-1]]))
    return slope <= max_slope


def _side_span(values: np.ndarray, side: np.ndarray) -> float:
    """Distance between the two outline sides' median positions: (k,) positions, (k,) side 0/1.

    Each side of the outline in the band is one generator of the part (a wall seen edge-on), so its
    points share a position up to noise; the medians cancel the noise that the extremes add."""
    return float(abs(np.median(values[side == 1]) - np.median(values[side == 0])))


def _clean_mask(mask: np.ndarray | None, region: np.ndarray) -> np.ndarray | None:
    """The observed part inside its possible region: thin strings opened away, the largest blob kept."""
    if mask is None or mask.shape != region.shape:
        return None
    m = (mask.astype(bool) & region).astype(np.uint8)
    m = cv2.morphologyEx(m, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(m, connectivity=8)
    if count <= 1:
        return None
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    return labels == largest


def dense_top(z: np.ndarray, window_mm: float, min_count: int) -> float:
    """The highest z with at least ``min_count`` points in the ``window_mm`` below it."""
    zs = np.sort(z)
    below = np.arange(len(zs)) + 1 - np.searchsorted(zs, zs - window_mm, side="left")
    dense = np.nonzero(below >= min_count)[0]
    return float(zs[dense[-1]] if len(dense) else zs[-1])


def robust_extent(values: np.ndarray, tail: float = 0.01) -> float:
    """Extent of ``values`` that ignores a ``tail`` fraction of strays at each end.

    Pixels sample the part uniformly across the image, so the points' density across the line of
    sight is close to uniform and the trimmed range is rescaled by 1 / (1 - 2 tail) to undo the trim.
    """
    lo, hi = np.quantile(values, [tail, 1.0 - tail])
    return float((hi - lo) / (1.0 - 2.0 * tail))


def fill_along_rows(disparity: np.ndarray, mask: np.ndarray, max_gap: int, edge_gap: int = 3) -> np.ndarray:
    """(h, w) disparity defined on ``mask``: matched values kept; holes between two matches of the same
    row (each within ``max_gap`` px) take the nearer one; beyond the last match of a row only
    ``edge_gap`` px are filled, since what lies there (a side only one camera sees) has no depth here."""
    h, w = disparity.shape
    valid = np.isfinite(disparity)
    cols = np.broadcast_to(np.arange(w)[None, :], (h, w))
    far = 10 ** 9
    left = np.maximum.accumulate(np.where(valid, cols, -far), axis=1)
    right = np.minimum.accumulate(np.where(valid, cols, far)[:, ::-1], axis=1)[:, ::-1]
    dist_left, dist_right = cols - left, right - cols
    source = np.where(dist_left <= dist_right, left, right)
    between = (dist_left <= max_gap) & (dist_right <= max_gap)
    near_end = np.minimum(dist_left, dist_right) <= edge_gap
    ok = mask & (between | near_end)
    out = np.full((h, w), np.nan, np.float32)
    rows = np.broadcast_to(np.arange(h)[:, None], (h, w))
    out[ok] = disparity[rows[ok], np.clip(source[ok], 0, w - 1)]
    return out


def foreground_mask(background: np.ndarray, frame: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """(h, w) bool: the material the shape check's background removal finds, for when its mask is not at hand.

    ``prior`` is where the part may be; the bed around it is the noise reference.
    """
    if background.shape != frame.shape:
        background = cv2.resize(background, (frame.shape[1], frame.shape[0]), interpolation=cv2.INTER_AREA)
    near = cv2.dilate(prior.astype(np.uint8), np.ones((31, 31), np.uint8)) > 0
    ys, xs = np.nonzero(cv2.dilate(near.astype(np.uint8), np.ones((41, 41), np.uint8)))
    out = np.zeros(prior.shape, bool)
    if len(ys) == 0:
        return out
    crop = (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
    evidence = material_evidence(background[crop], frame[crop], prior[crop], ~near[crop])
    out[crop] = clean_mask(evidence.material)
    return out


def _disc(radius: int) -> np.ndarray:
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * radius + 1, 2 * radius + 1))


def _registered(before: np.ndarray, now: np.ndarray, still: np.ndarray, used: np.ndarray,
                reach: int) -> np.ndarray | None:
    """``before`` translated by the whole-pixel shift within ``reach`` px that leaves the least change
    (99th percentile, after matching the exposure) on ``still`` (surface that did not change between the
    two pictures). Pixels outside the box of ``still | used`` are left as they were. None when that box
    is too close to the frame's border to move."""
    ys, xs = np.nonzero(still | used)
    h, w = now.shape[:2]
    y0, y1, x0, x1 = ys.min(), ys.max() + 1, xs.min(), xs.max() + 1
    if y0 < reach or x0 < reach or y1 > h - reach or x1 > w - reach:
        return None
    now_c, still_c = now[y0:y1, x0:x1], still[y0:y1, x0:x1]
    ref = now_c[still_c]
    best, best_q = None, np.inf
    for dy in range(-reach, reach + 1):
        for dx in range(-reach, reach + 1):
            moved = before[y0 - dy:y1 - dy, x0 - dx:x1 - dx]
            seen = moved[still_c]
            gain = float(np.median(ref)) / max(float(np.median(seen)), 1.0)
            q = float(np.quantile(np.abs(ref - gain * seen), 0.99)) + 1e-3 * (abs(dx) + abs(dy))
            if q < best_q:
                best, best_q = (dx, dy), q
    out = before.copy()
    dx, dy = best
    out[y0:y1, x0:x1] = before[y0 - dy:y1 - dy, x0 - dx:x1 - dx]
    return out


def _grey(frame: np.ndarray) -> np.ndarray:
    """(h, w) float32 grey of a frame, lightly smoothed (JPEG noise)."""
    grey = cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY) if frame.ndim == 3 else frame
    return cv2.GaussianBlur(grey.astype(np.float32), (3, 3), 0)


def _difference(frame: np.ndarray, background: np.ndarray | None) -> np.ndarray | None:
    """(h, w) float32 colour distance between a frame and its empty-bed frame (lightly smoothed)."""
    if background is None or background.shape != frame.shape:
        return None
    diff = cv2.absdiff(frame, background).astype(np.float32)
    diff = np.sqrt((diff ** 2).sum(axis=2)) if diff.ndim == 3 else diff
    return cv2.GaussianBlur(diff, (3, 3), 0)


def _moved(frame: np.ndarray, mask: np.ndarray | None, shift) -> tuple[np.ndarray, np.ndarray | None]:
    """Frame (and mask) translated by -shift: back to where the calibrated camera expects things."""
    dx, dy = float(shift[0]), float(shift[1])
    if dx == 0 and dy == 0:
        return frame, mask
    move = np.float32([[1, 0, -dx], [0, 1, -dy]])
    size = (frame.shape[1], frame.shape[0])
    frame = cv2.warpAffine(frame, move, size, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    if mask is not None:
        mask = cv2.warpAffine(mask.astype(np.uint8), move, size, flags=cv2.INTER_NEAREST) > 0
    return frame, mask


def _to_size(frame: np.ndarray, camera: Camera) -> np.ndarray:
    if frame.shape[:2] != (camera.height, camera.width):
        frame = cv2.resize(frame, (camera.width, camera.height), interpolation=cv2.INTER_AREA)
    return frame
