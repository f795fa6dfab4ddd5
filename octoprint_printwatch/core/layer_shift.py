"""Layer shift: the layers printed since the previous check slid sideways on the layers below.

Per camera, :func:`band_shift` tests every image shift of the newest band against what the camera
sees (one correlation per evidence mask, so all shifts cost a few milliseconds). Across cameras,
:func:`estimate_layer_shift` looks for the one shift on the bed (mm, printer X/Y) that the cameras
confirm together: each camera's image shift of a bed shift D is ``J @ D`` (``J``, the camera's
(2, 2) image pixels per bed millimetre at the part), so a camera that sees the shift sideways
confirms it, a camera it would show to and that sees the band in place contradicts it, and a camera
looking along it sees it only as the band moved up or down (or not at all). A real layer shift is one
rigid move of the top of the part, the same in every view; an outline that sits a little off in one
view (alignment, calibration, a face the colour of the bed) is not. A band moved up or down alone is
also a part standing taller or lower: that explanation is one height error in every view
(``_height_null``), and the shift has to beat it.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Mapping, Sequence

import cv2
import numpy as np

from .masks import around, bounding_box, dilate, erode, shift_mask

#: Pooled evidence needed (share of the pixels the shift changes that confirm it) when cameras from
#: two or more directions see the shift, and when one camera (or one stereo pair) does: nothing can
#: contradict it then, so an offset that was there all along (a calibration residual, an alignment anchored
#: a few px off: 0.81 on a 720p cylinder) reads as well as a shift. A shift new since the previous check
#: (:func:`_confirms_new`) is not such an offset, and needs SHIFT_CONFIRMED from one direction too.
SHIFT_CONFIRMED = 0.75
SHIFT_CONFIRMED_ONE_VIEW = 0.85
#: Cameras whose image x follows bed directions at least this far apart look from different places.
VIEWPOINT_APART_DEG = 30.0
#: A direction counts as a viewpoint only where the shift changes at least this share of the pooled
#: pixels it changes in its cameras together: a camera that sees (almost) nothing change there neither
#: confirms nor contradicts it, so it is no second view of the shift.
VIEWPOINT_MIN_SHARE = 0.15
#: ... but a side (``LayerShift.sides``: is the shift's vertical image move read?) counts where its cameras see at least
#: this many of the pixels the shift changes, whatever their share: the question there is not whether that side adds
#: evidence of its own but whether a camera on another side has the band in view to speak against "the part stands
#: taller or lower" (the pooled null, one height in every view): a view that sees the top of a wide part from above
#: changes ten times the pixels a low side view does (cross-check seed 6 `055`: 120-160 px of ~1,050, 11-15 %).
SIDE_MIN_MOVED_PX = 60.0
#: Contradicting pixels allowed, as a share of the confirming ones.
SHIFT_AGAINST = 0.25
#: The shift must explain the image at least this much better than "the part stands a little taller
#: or lower" does (the null hypothesis; both scored as support - 2 x against).
SHIFT_OVER_NULL = 2.0
#: ... or, read from two or more sides (the vertical move counted), the shift beats that null overall and, on a side
#: the one height error fits worst, on that side's pixels alone by SHIFT_OVER_NULL, with SHIFT_MIN_SUPPORT_PX confirming
#: pixels at SHIFT_CONFIRMED and at most SHIFT_AGAINST against: a shift along the lines of sight of cameras on
#: opposite sides raises the top in the near side's views (which a taller part explains as well, and those views may
#: change ten times the pixels) and lowers it in the far side's, which no height error explains (cross-check seed 8
#: `055`: 1,371 against a null of 1,083, the far pair 184 of 208 changed pixels confirming, its null 0).
#: A shift seen at two consecutive checks (the same bed shift confirmed by each check's own views) that
#: the check before them did not show: everything printed after a layer shift stays offset, while a
#: one-check margin case (noise, a strand, a shadow) does not persist, and a calibration residual or an
#: alignment slip was there before too. Then a lower share suffices, at both checks.
SHIFT_PERSISTS_CONFIRMED = 0.62
SHIFT_PERSISTS_CONFIRMED_ONE_VIEW = 0.70
#: ... and the check before them confirmed it less than this (the shift is new). Other checks' evidence
#: is read at the best bed shift within SHIFT_PERSISTS_WITHIN_MM of the one found now: the band printed
#: across the onset fits a smaller move than the layers after it, and one pixel (0.2-0.3 mm) changes a
#: share by 0.1 or more.
SHIFT_WAS_NOT_THERE = 0.5
SHIFT_PERSISTS_WITHIN_MM = 1.0
#: Confirming pixels needed in all (at the 640-px working width: a band's edge a few px wide and tall),
#: from several directions and from one.
SHIFT_MIN_SUPPORT_PX = 60
SHIFT_MIN_SUPPORT_ONE_VIEW_PX = 150
#: ... but one view needs no more than the share several directions need (SHIFT_CONFIRMED) of every pixel the shift
#: changes beyond the tolerance, decided or not (``LayerShift.swept``), nor fewer than several directions need: a small
#: part, a far camera or a small move changes fewer than 150 / 0.75 px in all (a 2-mm move of a 58-mm box at 640 px:
#: 138). A few decided pixels of a move that lands mostly where nothing is decided (a skirt zone, a dark top seen from
#: above: 78 of 612) stay a few: the undecided ones count in ``swept``.
SHIFT_MIN_SUPPORT_ONE_VIEW_SHARE = SHIFT_CONFIRMED
#: A shift the previous check's views read clearly not there (a new one) is also confirmed by the same shares
#: counted over the pixels it changes that are decided (material or bed) or further than the alignment
#: tolerance from the moved band's outline: the moved band's outline is as uncertain as the expected one,
#: so the blurred rim of what is seen around it is no evidence either way. (The plain share counts that rim
#: as unconfirmed; a 1-2 px residual of the calibration along a long edge then hides a shift of 5 mm.)
#: Only where part of the support is material sticking out where the model has none (the overhang every
#: shift makes, SHIFT_OVERHANG_SHARE of it): bed alone showing just inside the expected outline is also a
#: part a little narrower than the model there.
SHIFT_OVERHANG_SHARE = 0.25
#: ... and where the same move the other way reads less than this (of its decided pixels): a shift leaves bed on
#: its trailing side, while an outline that is just swollen (a glowing filament's halo, blur, a top
#: over-extruded) sticks out on every side and supports both.
SHIFT_OPPOSITE_MAX = 0.25
#: A camera counts the pixels a shift changes at most as this many times the ones it decides there (material or
#: bed, confirming or contradicting): pixels a view cannot tell apart (translucent filament against a bright bed) are
#: no evidence either way, and in full they would dilute the share the other views confirm (cross-check seed 37
#: `031_layer_shift`: s0L confirms 1,191 of 1,378 changed pixels, its pair partner s0R decides about 16 of 1,018).
#: A view deciding most of them (0.8-0.95 where the band is seen) is not changed.
SHIFT_UNDECIDED_PER_DECIDED = 4.0
#: The top of the part as one camera sees it may sit this far (px) from where one height error puts it in
#: every view: that camera's calibration residual.
HEIGHT_NULL_TOLERANCE_PX = 1
#: A height error is the same at every check (a camera firing a layer late, a height calibration error): a camera's
#: evidence for a height that HEIGHT_NULL_REFUTED_CHECKS of its own earlier readings (checks that tested their own
#: band) read clearly wrong (score, support - 2 x against, at or below minus this many px: the top it saw stood where
#: the model put it) does not count for that height here. (Its own readings: the null of one view is that camera's
#: own error; two: one earlier reading can be off itself, a top the colour of the bed read in place at one check and
#: lower at the next, cross-check seed 8 `028_runout` s1R before its onset.) A layer shift along a camera's line of
#: sight lowers (or raises) the top in that view only from its onset on, which a part standing lower all along would
#: have shown at the checks before it too (cross-check seed 9 `035`: one camera, the top 8-15 px lower from the onset
#: on, which "2.7 mm shorter" explained as well as the shift, 663 against 665; the checks before read it in place).
HEIGHT_NULL_REFUTED_PX = 60.0
HEIGHT_NULL_REFUTED_CHECKS = 2
# The print's first check is one reading that counts as that many for a part standing *taller*, while it is one of
# the last four checks: its band is the whole part, so its null reads the whole part's top against the outline aligned
# on all of it, where a height error shows from the first layer on. A layer shift in the first tested band has no other
# reading before it (cross-check seed 14 `043`: a cone's top moved along s0's line of sight, "1.4 mm taller" scored 788
# against the shift's 549 at the onset check, while the first check read that height at -626). Only taller: the way one
# reading is known to be off, a top in the bed's colour, reads the top lower later, never material above it
# (cross-check seed 10 `054_spaghetti` s0, natural on kapton: its top 7 px low at check 2, before any failure).
#: (camera name, (m,) heights mm) -> (m,) bool: the heights that camera's earlier checks refute (_refuted_heights)
RefutedHeights = Callable[[str, np.ndarray], np.ndarray]


@dataclass
class BandShift:
    """One camera's evidence on "the newest band was printed shifted".

    dx, dy : the camera's best image shift of the band (px), with a horizontal part of at least ``min_dx``.
    support : pixels confirming it (material where the shifted band lands and nothing was expected;
        confident bed where the band should be and the shift uncovers it).
    against : pixels contradicting it (the same places, the other way round).
    moved : pixels the shift changes outside the alignment tolerance (what full evidence would be).
    null_dy, null_score : the band's top raised (< 0) or lowered (> 0) as the image supports best, and
        how well (support - 2 x against, like a shift): the explanation a layer shift must beat.
    maps : (6, 2 reach_y + 1, 2 reach_x + 1) float32 support, against, moved, overhang (the support that is
        material outside the expected part), moved_sure (moved less the undecided pixels within the
        tolerance of the moved band's outline) and swept (moved plus the undecided zone outside the part: every
        pixel the shift changes beyond the tolerance) for every shift (dx, dy) = (index_x - reach_x, index_y - reach_y).
    bed_to_image : (2, 2) image px per bed mm at the part (columns: printer X, Y), or None.
    """

    dx: int
    dy: int
    support: int
    against: int
    moved: int
    null_dy: int = 0
    null_score: float = 0.0
    min_dx: int = 1
    tolerance: float = 0.0   # the alignment tolerance (px): a top edge moved less than this has not moved
    maps: np.ndarray | None = field(default=None, repr=False)
    bed_to_image: np.ndarray | None = field(default=None, repr=False)
    # (2 reach_y + 1,) the score of the band's top raised or lowered by every dy = index - reach_y (0 at dy 0),
    # and the (2,) image px per mm of height at the part: the pooled null (one height error in every view)
    null_scores: np.ndarray | None = field(default=None, repr=False)
    height_to_image: np.ndarray | None = field(default=None, repr=False)
    # (dx, dy) px: where the camera's alignment laid the expected outline (and so the band) for this reading; every
    # shift above is relative to it
    aligned_at: tuple[int, int] = (0, 0)

    @property
    def confirmed(self) -> float:
        """Share of the pixels the shift changes that confirm it (0..1)."""
        return self.support / max(self.moved, 1)

    def figures(self) -> dict:
        return {"dx": self.dx, "dy": self.dy, "support": self.support, "against": self.against,
                "moved": self.moved, "null_dy": self.null_dy, "null_score": round(float(self.null_score), 1)}


@dataclass
class LayerShift:
    """The bed shift the cameras confirm together (see module docstring).

    shift_mm : (2,) printer X/Y (mm) by which the newest layers sit off.
    support, against, moved : summed over the cameras in whose reach it lies.
    null_score : the same cameras' best "the part stands taller or lower" explanation, summed.
    viewpoints : how many clearly different directions (VIEWPOINT_APART_DEG, opposite sides apart) those cameras look
        from, of those with a share of the evidence (VIEWPOINT_MIN_SHARE of ``moved``).
    moved_by : {camera: pixels the shift changes in it (weighted as pooled)}.
    read_by : {camera: (support, against)} in the cameras it shows to clearly (weighted as pooled).
    cameras : the cameras it shows to clearly (image shift of at least their ``min_dx``), with their px shift.
    overhang : of ``support``, material seen where the model has none.
    moved_sure : of ``moved``, the pixels decided (material or bed) or beyond the alignment tolerance of the
        moved band's outline (see SHIFT_OVERHANG_SHARE).
    swept : every pixel the shift changes beyond the alignment tolerance, decided or not (one view's floor,
        SHIFT_MIN_SUPPORT_ONE_VIEW_SHARE).
    opposite : the evidence for the move the other way (estimate_layer_shift only; see SHIFT_OPPOSITE_MAX).
    sides : as ``viewpoints``, but cameras on opposite sides of the part count apart, and a side counts with
        SIDE_MIN_MOVED_PX changed pixels whatever its share.
    vertical : whether a camera counted the shift's vertical image move too (only when cameras on two or more
        sides see it: one side cannot tell a band moved along its line of sight from a taller part).
    """

    shift_mm: np.ndarray
    support: int
    against: int
    moved: int
    cameras: dict[str, tuple[int, int]]
    null_score: float = 0.0
    viewpoints: int = 1   # of those cameras, how many look from clearly different directions
    moved_by: dict[str, float] = field(default_factory=dict)
    # {camera: (support, against)} of the cameras it shows to clearly, weighted as pooled (see contradicted_in_a_view)
    read_by: dict[str, tuple[float, float]] = field(default_factory=dict)
    overhang: int = 0   # of the support, material seen where the model has none (the moved band sticking out)
    moved_sure: int = 0   # of moved, those decided or beyond the tolerance of the moved band's outline
    swept: int = 0   # every pixel the shift changes beyond the tolerance, decided or not (>= moved)
    opposite: "LayerShift | None" = None   # the same cameras' evidence for the move the other way (-shift_mm)
    sides: int = 1
    vertical: bool = True
    # the side (cameras grouped as for ``sides``) the pooled null fits worst: its (support, against, moved, null)
    side_apart: tuple[float, float, float, float] | None = None
    # the same shift read in the views of the (up to four) checks before this one that tested their own
    # newest band, newest first (None: nothing there changes); see with_history
    before: list = field(default_factory=list)
    back_to_first: bool = False   # ``before`` reaches back to the print's first check (see with_history)
    # every camera it shows to moves the band back to where its own earlier passing checks laid the outline
    # (see onto_earlier_places): the outline walked off the part, the layers did not move
    onto_earlier_places: bool = False
    # the best bed shift lies on the search grid's edge (estimate_layer_shift's max_mm along X or Y): the evidence
    # rises towards the edge, so the move it fits best lies beyond the search, if anywhere
    at_search_edge: bool = False
    # read at the print's first check (with_history: no check before it), whose band is the whole part
    at_first_check: bool = False

    @property
    def score(self) -> float:
        return self.support - 2.0 * self.against

    @property
    def confirmed(self) -> float:
        return self.support / max(self.moved, 1)

    @property
    def confirmed_sure(self) -> float:
        """Share of the decided pixels the shift changes (beyond its own outline's tolerance) that confirm it."""
        return self.support / max(self.moved_sure, 1)

    @property
    def magnitude_mm(self) -> float:
        return float(np.hypot(*self.shift_mm))

    def figures(self) -> dict:
        figures = {"shift_mm": [round(float(v), 2) for v in self.shift_mm], "confirmed": round(self.confirmed, 3),
                   "support": self.support, "against": self.against, "moved": self.moved,
                   "null_score": round(self.null_score, 1), "viewpoints": self.viewpoints,
                   "overhang": self.overhang, "confirmed_sure": round(self.confirmed_sure, 3),
                   "moved_sure": self.moved_sure, "swept": self.swept,
                   **({"opposite_confirmed": round(self.opposite.confirmed_sure, 3)} if self.opposite else {}),
                   "cameras": {name: list(d) for name, d in self.cameras.items()},
                   "moved_by": {name: round(float(v)) for name, v in self.moved_by.items()},
                   "read_by": {name: [round(float(v)) for v in pair] for name, pair in self.read_by.items()}}
        if self.side_apart is not None:
            figures["side_apart"] = [round(float(v)) for v in self.side_apart]
        if self.onto_earlier_places:
            figures["onto_earlier_places"] = True
        if self.before:
            figures["before_confirmed"] = [0.0 if e is None else round(e.confirmed, 3) for e in self.before]
        return figures

    @property
    def previous(self) -> "LayerShift | None":
        """The same shift read in the previous check's views (None: unknown, or nothing changes there)."""
        return self.before[0] if self.before else None


def band_shift(observed: np.ndarray, bed: np.ndarray, before: np.ndarray, band: np.ndarray,
               reach_x: int, reach_y: int, min_dx: int, tolerance: float,
               undecided: np.ndarray | None = None, bed_to_image: np.ndarray | None = None,
               height_to_image: np.ndarray | None = None, aligned_at: tuple[int, int] = (0, 0)) -> BandShift | None:
    """Test every image shift of the newest band against what is seen (module docstring).

    All masks (h, w) bool, already aligned: ``observed`` material, ``bed`` confidently empty bed
    (camouflaged pixels are neither, and count for nothing), ``before`` the part as expected at the
    previous check, ``band`` what was printed since. The hypothesis for a shift d is "before, plus the
    band moved by d" (the layers printed since the previous check slid together). It is compared with
    the null hypothesis only where the two differ, and only on decided pixels, so a top face that
    looks like the bed, or material the shift does not move, neither helps nor hurts. Pixels within
    ``tolerance`` of the expected outline are left out (the alignment is that uncertain), and
    ``undecided`` pixels outside the part (where a brim, skirt or reflection may lie) count for nothing.
    ``bed_to_image`` ((2, 2), the camera's image px per printer X/Y mm) is kept for the pooling, and ``aligned_at``
    (the alignment's (dx, dy) px the masks were laid at) for reading this check's top against later checks' outlines.

    A part that stands a little taller or lower than the model (a camera that fires a layer late, a
    height calibration error) also looks like a band moved up or down: the best such explanation is
    scored too (``null_score``), and a layer shift has to beat it.
    Returns None when the band is empty or no shift of ``min_dx`` px fits in ``reach_x``.
    """
    if not band.any() or reach_x < 1 or min_dx > reach_x:
        return None
    window = _window(band, reach_x, reach_y, tolerance)
    observed, bed, before, band = observed[window], bed[window], before[window], band[window]
    if undecided is not None:
        undecided = undecided[window]
    evidence = _Evidence.of(observed, bed, before | band, tolerance)
    null_dy, null_score, null_scores = _vertical_null(evidence, before, band, reach_y)
    maps = _band_shift_maps(evidence, before, band, reach_x, reach_y, undecided, tolerance)
    support, against, moved = maps[:3]
    dys, dxs = np.mgrid[-reach_y: reach_y + 1, -reach_x: reach_x + 1]
    score = np.where(np.abs(dxs) >= min_dx, support - 2.0 * against, -np.inf)
    iy, ix = np.unravel_index(int(np.argmax(score)), score.shape)
    return BandShift(dx=int(dxs[iy, ix]), dy=int(dys[iy, ix]), support=int(round(float(support[iy, ix]))),
                     against=int(round(float(against[iy, ix]))), moved=int(round(float(moved[iy, ix]))),
                     null_dy=null_dy, null_score=null_score, min_dx=int(min_dx), tolerance=float(tolerance),
                     maps=maps, bed_to_image=None if bed_to_image is None else np.asarray(bed_to_image, float),
                     null_scores=null_scores,
                     height_to_image=None if height_to_image is None else np.asarray(height_to_image, float),
                     aligned_at=(int(aligned_at[0]), int(aligned_at[1])))


def _window(band: np.ndarray, reach_x: int, reach_y: int, tolerance: float) -> tuple[slice, slice]:
    """The part of the image :func:`band_shift` reads: the band's box grown by the reach and the tolerance
    (every count, the undecided rim), and by what the tolerance ring there reads around it (masks.dilate /
    erode: tolerance / 0.955 + 1 px), so every count is the whole image's."""
    y0, y1, x0, x1 = bounding_box(band)
    reads = int(np.ceil(tolerance)) + int(np.ceil(tolerance / 0.955)) + 3
    h, w = band.shape
    return (slice(max(0, y0 - reach_y - reads), min(h, y1 + reach_y + reads)),
            slice(max(0, x0 - reach_x - reads), min(w, x1 + reach_x + reads)))


@dataclass
class _Evidence:
    """The decided pixels of one camera-check, (h, w) bool each: ``ring`` within the alignment
    tolerance of the expected outline (decides nothing), ``seen`` material and ``empty`` confident bed
    outside it."""

    ring: np.ndarray
    seen: np.ndarray
    empty: np.ndarray

    @classmethod
    def of(cls, observed: np.ndarray, bed: np.ndarray, expected: np.ndarray, tolerance: float) -> "_Evidence":
        ring = dilate(expected, tolerance) & ~erode(expected, tolerance)
        return cls(ring=ring, seen=observed & ~ring, empty=bed & ~observed & ~ring)


def stretched(band: np.ndarray, dy: int) -> np.ndarray:
    """(h, w) bool: the band with its top raised by -dy px (dy < 0: the part stands taller) or
    lowered by dy px (dy > 0: shorter); its bottom, where it sits on the older layers, stays."""
    if dy < 0:
        # each pixel also on when the band is within -dy px below it
        return cv2.dilate(band.astype(np.uint8), np.ones((1 - dy, 1), np.uint8), anchor=(0, 0)).astype(bool)
    if dy > 0:
        return band & shift_mask(band, 0, dy)
    return band


def _vertical_null(evidence: _Evidence, before: np.ndarray, band: np.ndarray,
                   reach_y: int) -> tuple[int, float, np.ndarray]:
    """(dy, score, scores): the top of the band raised (dy < 0) or lowered as the image supports best, scored
    like a shift (support - 2 x against; (0, 0.0) when no change is supported), and (2 reach_y + 1,) the
    score of every dy = index - reach_y."""
    y0, y1, x0, x1 = bounding_box(band)
    # only the band's columns and the rows it can reach change: work on that window
    window = (slice(max(0, y0 - reach_y - 1), min(band.shape[0], y1 + reach_y + 1)), slice(x0, x1))
    band_w, before_w, ring = band[window], before[window], evidence.ring[window]
    seen, empty = evidence.seen[window], evidence.empty[window]
    free = ~before_w & ~ring
    # (every dy at once, with the same counts as stretching the band dy by dy:) raising the top by n px
    # gains the pixels outside the band whose nearest band pixel below, in their column, is at most n px
    # down; lowering it by n loses the band's pixels that have no band pixel n px above them
    rows = band_w.shape[0]
    index = np.where(band_w, np.arange(rows)[:, None], rows + reach_y + 1)
    below = np.minimum.accumulate(index[::-1], axis=0)[::-1]   # the first band row at or below each pixel
    down = np.full(band_w.shape, reach_y + 1, np.int64)
    down[:-1] = below[1:] - np.arange(rows - 1)[:, None]        # ... strictly below: how far down it is
    gain = free & ~band_w & (down <= reach_y)
    gained_seen = np.cumsum(np.bincount(down[gain & seen], minlength=reach_y + 1)[:reach_y + 1])
    gained_empty = np.cumsum(np.bincount(down[gain & empty], minlength=reach_y + 1)[:reach_y + 1])
    lose = free & band_w
    lose_seen, lose_empty = lose & seen, lose & empty
    all_seen, all_empty = np.count_nonzero(lose_seen), np.count_nonzero(lose_empty)
    best, best_dy = 0.0, 0
    scores = np.zeros(2 * reach_y + 1, np.float32)
    for dy in range(-reach_y, reach_y + 1):
        if dy == 0:
            continue
        if dy < 0:
            g_seen, g_empty, l_seen, l_empty = int(gained_seen[-dy]), int(gained_empty[-dy]), 0, 0
        else:
            g_seen = g_empty = 0
            # lost: band pixels whose pixel dy above is not band (rows above the window count as not band)
            kept = band_w[:-dy] if dy < rows else band_w[:0]
            l_seen = all_seen - np.count_nonzero(lose_seen[dy:] & kept)
            l_empty = all_empty - np.count_nonzero(lose_empty[dy:] & kept)
        score = (g_seen + l_empty - 2.0 * (g_empty + l_seen))
        scores[dy + reach_y] = score
        if score > best:
            best, best_dy = score, dy
    return best_dy, float(best), scores


def _band_shift_maps(evidence: _Evidence, before: np.ndarray, band: np.ndarray, reach_x: int, reach_y: int,
                     undecided: np.ndarray | None, tolerance: float) -> np.ndarray:
    """(6, 2 reach_y + 1, 2 reach_x + 1) float32: support, against, moved, overhang, moved_sure and swept of
    :func:`band_shift` (``BandShift.maps``) for every shift; each count is a correlation of the band (or its
    rim, or the band grown by ``tolerance``) with one evidence mask."""
    box = bounding_box(band)
    y0, y1, x0, x1 = box
    ring, seen, empty = evidence.ring, evidence.seen, evidence.empty
    fresh = band & ~before                       # the band where nothing older hides it
    outside = ~(before | band) & ~ring
    if undecided is not None:
        outside &= ~undecided   # (inside the part, a brim or reflection cannot be what is seen)
    template = band[y0:y1, x0:x1].astype(np.float32)

    def corr(mask: np.ndarray) -> np.ndarray:
        """sum over the band of ``mask`` at the band's pixel + (dx, dy), for every shift"""
        return cv2.matchTemplate(around(mask, box, reach_x, reach_y), template, cv2.TM_CCORR)

    def uncovered(mask: np.ndarray) -> np.ndarray:
        """pixels of ``mask`` (inside the band) that the shifted band no longer covers"""
        return float(np.count_nonzero(mask)) - corr(mask)

    # where the moved band lands outside the expected part: material confirms, bed contradicts;
    # where the band should be and the moved band no longer covers: bed confirms, material contradicts
    overhang = corr(seen & outside)
    support = overhang + uncovered(fresh & empty)
    against = corr(empty & outside) + uncovered(fresh & seen)
    moved = corr(outside) + uncovered(fresh & ~ring)
    # every pixel the move changes beyond the tolerance, decided or not (what the shift could show at best)
    swept = moved if undecided is None else moved + corr(~(before | band) & ~ring & undecided)
    # undecided pixels within the tolerance of the moved band's outline: inside it (where the moved band lands
    # outside the part: its rim) and just beyond it (where it uncovers the band: the band grown, less the band)
    unsure = ~seen & ~empty
    pad = int(np.ceil(tolerance))
    near = bounding_box(band, pad)
    window = (slice(near[0], near[1]), slice(near[2], near[3]))
    inner = band[window] & ~erode(band[window], tolerance)
    halo = dilate(band[window], tolerance) & ~band[window]
    rim_unsure = (cv2.matchTemplate(around(outside & unsure, near, reach_x, reach_y), inner.astype(np.float32),
                                    cv2.TM_CCORR)
                  + cv2.matchTemplate(around(fresh & ~ring & unsure, near, reach_x, reach_y), halo.astype(np.float32),
                                      cv2.TM_CCORR))
    return np.stack([support, against, moved, overhang, moved - rim_unsure, swept]).astype(np.float32)


def estimate_layer_shift(views: Mapping[str, BandShift], *, max_mm: float = 8.0,
                         step_mm: float = 0.25, earlier: Sequence[Mapping[str, BandShift]] = (),
                         first: Mapping[str, BandShift] | None = None) -> LayerShift | None:
    """The bed shift (printer X/Y, mm, within ``max_mm``) the cameras' evidence confirms best together.

    Each camera contributes its support, against and moved pixels at its own image shift ``J @ D``
    (nearest pixel), weighted by how clearly that shift shows sideways in it (see below); the score is
    support - 2 x against summed over cameras. Cameras without ``bed_to_image`` cannot take part.
    ``earlier``: the views of earlier checks that tested their own band; a camera's support for a height its own
    readings there refute does not count in the null (HEIGHT_NULL_REFUTED_PX); ``first``: the views of the print's
    first check, whose reading alone refutes a taller part (HEIGHT_NULL_REFUTED_CHECKS). None when no shift shows
    clearly to any camera.
    """
    refuted = _refuted_heights(earlier, views, first)
    steps = np.arange(-max_mm, max_mm + 1e-9, step_mm)
    gx, gy = np.meshgrid(steps, steps)
    grid = np.stack([gx.ravel(), gy.ravel()], axis=1)
    found = _pooled(views, grid, refuted=refuted, testable_only=True)
    if found is not None and found.sides < 2:
        # seen from one side, a move up or down the image is also a part standing taller or lower, or that
        # camera's calibration error (3x the stated one paused a normal print): only sideways counts there
        found = _pooled(views, grid, vertical=False, refuted=refuted, testable_only=True)
    if found is not None:
        found.opposite = _pooled(views, -found.shift_mm.reshape(1, 2), vertical=found.vertical, refuted=refuted)
        found.at_search_edge = bool(np.max(np.abs(found.shift_mm)) >= max_mm - 0.5 * step_mm)
    return found


def layer_shift_at(views: Mapping[str, BandShift], shift_mm, within_mm: float = 0.0,
                   step_mm: float = 0.25, vertical: bool = True) -> LayerShift | None:
    """The cameras' best pooled evidence (as in :func:`estimate_layer_shift`) for a bed shift within
    ``within_mm`` of ``shift_mm`` ((2,) printer X/Y mm): how well another check's views confirm the
    shift found now (read as it was found: ``vertical``). None when none of them shows clearly to any camera."""
    centre = np.asarray(shift_mm, np.float64).reshape(1, 2)
    steps = np.arange(-within_mm, within_mm + 1e-9, step_mm) if within_mm > 0 else np.zeros(1)
    gx, gy = np.meshgrid(steps, steps)
    offsets = np.stack([gx.ravel(), gy.ravel()], axis=1)
    offsets = offsets[np.hypot(offsets[:, 0], offsets[:, 1]) <= within_mm + 1e-9]
    return _pooled(views, centre + offsets, vertical=vertical)


def _refuted_heights(earlier: Sequence[Mapping[str, BandShift]],
                     now: Mapping[str, BandShift] | None = None,
                     first: Mapping[str, BandShift] | None = None) -> RefutedHeights | None:
    """A function of a camera's name and (m,) heights (mm; its top moves by height x its image y px per mm of height)
    giving (m,) bool: the heights HEIGHT_NULL_REFUTED_CHECKS of that camera's readings at the ``earlier`` checks read
    clearly wrong (HEIGHT_NULL_REFUTED_PX); None when no camera has that many readings.

    A reading measured the top against the outline where that check's alignment laid it; where this check's
    (``now``, per camera) lies elsewhere, the same top in the image reads that many pixels lower or higher here. So
    a height is read there where it puts the top in the image now (``BandShift.aligned_at``): an outline that
    slipped up since (a slide onto the part's reflection) shows the top standing lower from then on, which the
    checks before the slip read in place against their own outline, and so do not refute. The move is counted less
    HEIGHT_NULL_TOLERANCE_PX: an anchored outline wobbles by a pixel, which this check's null already allows.
    ``first``: the print's first check's views, one reading that counts as HEIGHT_NULL_REFUTED_CHECKS for heights
    above the model's (its band is the whole part; see there)."""
    readings: dict[str, list] = {}
    weighted = [(views, 1) for views in earlier] + ([(first, HEIGHT_NULL_REFUTED_CHECKS)] if first else [])
    for views, counts in weighted:
        for name, view in views.items():
            if view.null_scores is not None and view.height_to_image is not None:
                current = (now or {}).get(name)
                moved = 0 if current is None else int(current.aligned_at[1]) - int(view.aligned_at[1])
                # (a pixel of it is the alignment's own wobble, within the residual this check's null allows)
                slipped = int(np.sign(moved)) * max(abs(moved) - HEIGHT_NULL_TOLERANCE_PX, 0)
                readings.setdefault(name, []).append((view.null_scores.astype(np.float64),
                                                      float(view.height_to_image[1]), slipped, counts))
    readings = {name: read for name, read in readings.items()
                if sum(counts for *_, counts in read) >= HEIGHT_NULL_REFUTED_CHECKS}
    if not readings:
        return None

    def refuted(name: str, heights: np.ndarray) -> np.ndarray:
        out = np.zeros(len(heights), int)
        # (each reading untolerant: the camera's calibration residual is the same at every check, and the null of
        # this check already allows it)
        for scores, k, slipped, counts in readings.get(name, ()):
            r = len(scores) // 2
            there = np.rint(heights * k).astype(int) + slipped
            # (the first check's reading counts as several only for a taller part: see HEIGHT_NULL_REFUTED_CHECKS)
            weight = np.where(heights > 0, counts, min(counts, 1))
            out += weight * (scores[np.clip(there + r, 0, 2 * r)] <= -HEIGHT_NULL_REFUTED_PX)
        return (out >= HEIGHT_NULL_REFUTED_CHECKS) & (heights != 0)
    return refuted


def _tolerant(scores: np.ndarray) -> np.ndarray:
    """(2 r + 1,) a camera's null scores with its top allowed HEIGHT_NULL_TOLERANCE_PX off (its calibration
    residual): the best within that many px."""
    tolerant = scores.astype(np.float64)
    for e in range(1, HEIGHT_NULL_TOLERANCE_PX + 1):
        tolerant = np.maximum(tolerant, np.maximum(np.r_[scores[e:], np.full(e, -np.inf)],
                                                   np.r_[np.full(e, -np.inf), scores[:-e]]))
    return tolerant


def _pooled(views: Mapping[str, BandShift], grid: np.ndarray, vertical: bool = True,
            refuted: RefutedHeights | None = None, testable_only: bool = False) -> LayerShift | None:
    """The best of the (n, 2) bed shifts ``grid`` (mm) by the pooled score (estimate_layer_shift); a camera
    counts the shift's vertical image move beyond its tolerance too unless ``vertical`` is False. ``testable_only``
    (the search for the move, not the reading of a given one at other checks): a move lying beyond the search of a
    camera it would show to clearly is not a candidate."""
    total = np.zeros((6, len(grid)), np.float64)
    null = np.zeros(len(grid), np.float64)
    clear = np.zeros(len(grid), bool)          # the shift shows clearly in at least one camera
    untested = np.zeros(len(grid), bool)       # ... or lies beyond the search of a camera it shows to clearly
    shows, directions, moved_by, per_camera = {}, {}, {}, {}
    heights = {}    # per camera: (weight per shift, its null scores, image y px per mm of height)
    for name, view in views.items():
        if view.maps is None or view.bed_to_image is None:
            continue
        J = view.bed_to_image
        _, ny, nx = view.maps.shape
        reach_y, reach_x = ny // 2, nx // 2
        image = np.rint(grid @ J.T).astype(int)                      # (n, 2) px
        directions[name] = float(np.arctan2(J[0, 1], J[0, 0]))        # the bed direction image x follows
        ix = image[:, 0] + reach_x
        iy = image[:, 1] + reach_y
        ok = (ix >= 0) & (ix < nx) & (iy >= 0) & (iy < ny)
        # A camera counts in full where the shift shows by its min_dx, not at all below half of
        # that (little but the outline's own wobble changes there), and in proportion between: a hard
        # gate would let a shift hide from a camera that sees the band in place by staying a pixel under it.
        # A shift shows by its whole image move (seventh session): sideways, and vertically beyond the alignment
        # tolerance (a top edge that close to where it is expected has not moved). A vertical move alone is also
        # what a part standing taller or lower shows: the pooled null below (one height error in every view,
        # _height_null) weighs it, and a shift along the lines of sight of cameras on different sides, its top
        # moving up in one view and down in another, fits no height error.
        shown = (np.hypot(image[:, 0], np.maximum(np.abs(image[:, 1]) - view.tolerance, 0.0)) if vertical
                 else np.abs(image[:, 0]).astype(np.float64))
        weight = np.clip((shown - 0.5 * view.min_dx) / (0.5 * view.min_dx), 0.0, 1.0) * ok
        values = np.zeros((6, len(grid)))
        values[:, ok] = view.maps[:, iy[ok], ix[ok]]
        most = SHIFT_UNDECIDED_PER_DECIDED * (values[0] + values[1])
        values[2] = np.minimum(values[2], most)
        values[4] = np.minimum(values[4], most)
        moved_by[name] = values[2] * weight
        per_camera[name] = values * weight
        total += values * weight
        if view.null_scores is not None and view.height_to_image is not None:
            heights[name] = (weight, view.null_scores, float(view.height_to_image[1]))
        else:
            null += view.null_score * weight
        clear |= weight >= 1.0
        untested |= ~ok & (shown >= view.min_dx)
        shows[name] = (ok & (shown >= view.min_dx), image)
    if not shows:
        return None
    if heights:
        null += _height_null(heights, refuted=refuted)
    score = total[0] - 2.0 * total[1]
    # In the search for the move (testable_only), a move a camera would show clearly but whose image shift lies beyond
    # that camera's search (BandShift.maps: the band's own reach, half as far up and down) is one that camera cannot
    # speak to, and the others' pixels alone confirm none: a view's outline laid off the part reads as a large move
    # there that its stereo partner or another view, looking from elsewhere, would show 12-16 px away, just beyond its
    # search (cross-check seeds 24 `018_normal`, 35 `020_runout`, 43 `025_detach`: 9-10 mm, one view, before any
    # failure). Readings of a given move at other checks (layer_shift_at) keep every view's say as it is.
    score[(total[2] <= 0) | ~clear | (untested & testable_only)] = -np.inf
    best = int(np.argmax(score))
    if not np.isfinite(score[best]):
        return None
    cameras = {name: (int(image[best, 0]), int(image[best, 1])) for name, (ok, image) in shows.items() if ok[best]}
    share = {name: float(moved_by[name][best]) for name in cameras}
    read_by = {name: (float(per_camera[name][0, best]), float(per_camera[name][1, best])) for name in cameras}
    looking = {name: directions[name] for name in cameras}
    min_share = VIEWPOINT_MIN_SHARE * float(total[2, best])
    side_apart = None
    if vertical and heights and len(cameras) >= 2:
        side_apart = _side_apart(per_camera, best, heights, {name: directions[name] for name in per_camera},
                                 refuted=refuted)
    return LayerShift(side_apart=side_apart, shift_mm=grid[best].copy(), support=int(round(total[0, best])),
                      against=int(round(total[1, best])), moved=int(round(total[2, best])), cameras=cameras,
                      null_score=float(null[best]), moved_by=share, read_by=read_by,
                      overhang=int(round(total[3, best])), moved_sure=int(round(total[4, best])),
                      swept=int(round(total[5, best])),
                      # (cameras facing each other count apart: each one's outline error is its own, so two agreeing
                      # on one bed shift are no offset of one view; they see it move the opposite ways in their images)
                      viewpoints=count_viewpoints(looking, share, min_share, period=2 * np.pi),
                      sides=count_viewpoints(looking, share, min(min_share, SIDE_MIN_MOVED_PX), period=2 * np.pi),
                      vertical=vertical)


def _side_apart(per_camera: Mapping[str, np.ndarray], best: int,
                heights: Mapping[str, tuple[np.ndarray, np.ndarray, float]],
                directions: Mapping[str, float],
                refuted: RefutedHeights | None = None) -> tuple[float, float, float, float] | None:
    """(support, against, moved, null) of the side (cameras looking from directions within VIEWPOINT_APART_DEG,
    modulo 2 pi, as ``LayerShift.sides``) whose cameras the pooled null (the one height error that fits all views
    best at shift ``best``) explains worst relative to the shift, or None. ``per_camera``: each camera's weighted
    (5, n) values as pooled."""
    at_best = {name: (np.asarray(w)[best:best + 1], scores, k) for name, (w, scores, k) in heights.items()}
    _, parts = _height_null(at_best, parts=True, refuted=refuted)
    apart = np.radians(VIEWPOINT_APART_DEG)
    groups: list[list] = []      # [direction, [names]]
    for name in sorted(per_camera, key=lambda n: -float(per_camera[n][2, best])):
        angle = directions[name]
        for group in groups:
            difference = abs(angle - group[0]) % (2 * np.pi)
            if min(difference, 2 * np.pi - difference) < apart:
                group[1].append(name)
                break
        else:
            groups.append([angle, [name]])
    if len(groups) < 2:
        return None
    found = None
    for _, names in groups:
        support = sum(float(per_camera[n][0, best]) for n in names)
        against = sum(float(per_camera[n][1, best]) for n in names)
        moved = sum(float(per_camera[n][2, best]) for n in names)
        null = sum(float(parts.get(n, 0.0)) for n in names)
        margin = support - 2.0 * against - SHIFT_OVER_NULL * max(null, 0.0)
        if found is None or margin > found[0]:
            found = (margin, (support, against, moved, null))
    return found[1]


def _height_null(cameras: Mapping[str, tuple[np.ndarray, np.ndarray, float]], parts: bool = False,
                 refuted: RefutedHeights | None = None):
    """(n,) the pooled null of :func:`_pooled`'s n shifts: the best score of one height error (the part standing
    taller or lower by the same millimetres in every view) summed over the cameras, each weighted as in the
    pooling. ``cameras``: {name: ((n,) weight, (2 r + 1,) the band's top moved by dy = index - r scored, image y
    px per mm of height)}. A camera may read its top HEIGHT_NULL_TOLERANCE_PX off (its calibration residual).
    With one camera this is its own best null; cameras on opposite sides of a shift along their line of sight
    see its top move up in one and down in the other, which no single height explains. ``refuted``: see
    :func:`_refuted_heights` (a camera's support for a height its own earlier readings refute does not count)."""
    rise = max(abs(k) for _, _, k in cameras.values())
    reach = max(len(scores) // 2 for _, scores, _ in cameras.values())
    # heights half a pixel apart in the camera that sees them move most, over its whole reach
    heights = np.arange(-reach, reach + 1e-9, 0.5) / max(rise, 1e-6)
    weights, scores_at = [], []
    for name, (weight, scores, k) in cameras.items():
        r = len(scores) // 2
        tolerant = _tolerant(scores)
        dy = np.rint(heights * k).astype(int)
        # a height beyond this camera's reach moves its top further than it tested: it reads that height as it
        # reads its reach's end (a top seen in place contradicts a taller part more, the further it stands), not
        # as nothing, which let one camera's null stand alone for heights the other camera refutes
        at = tolerant[np.clip(dy + r, 0, 2 * r)]
        if refuted is not None:
            at = np.where(refuted(name, heights), np.minimum(at, 0.0), at)
        scores_at.append(at)
        weights.append(weight)
    # (n, heights): a sum of outer products, not a matrix product: a product this size wakes BLAS's thread
    # pool, whose threads then spin on the other core and slowed the next checks' shape tests by ~15 % CPU
    pooled = sum(np.multiply.outer(weight, at) for weight, at in zip(weights, scores_at))
    if parts:
        # (for one shift:) the pooled null and each camera's part of it at the best height
        h = int(np.argmax(pooled[0]))
        return (max(float(pooled[0, h]), 0.0),
                {name: float(weight[0] * at[h]) for name, weight, at in zip(cameras, weights, scores_at)})
    return np.maximum(pooled.max(axis=1), 0.0)


def count_viewpoints(directions: Mapping[str, float], moved_by: Mapping[str, float] | None = None,
                     min_moved: float = 0.0, period: float = np.pi) -> int:
    """How many clearly different directions the cameras look from: directions (radians, modulo ``period``)
    less than VIEWPOINT_APART_DEG apart count once (the two cameras of a stereo pair look from nearly one
    place), and a direction counts only where the shift changes at least ``min_moved`` pixels in its
    cameras together (``moved_by``, per camera). A sideways shift is seen along one axis from either side
    (``period`` pi); ``core.tangle`` counts opposite sides apart (2 pi)."""
    apart = np.radians(VIEWPOINT_APART_DEG)
    moved_by = moved_by or {}
    kept: list[list] = []            # [direction, pixels changed] per viewpoint, the most changed first
    for name in sorted(directions, key=lambda n: -moved_by.get(n, 0.0)):
        angle = directions[name]
        for group in kept:
            difference = abs(angle - group[0]) % period
            if min(difference, period - difference) < apart:
                group[1] += moved_by.get(name, 0.0)
                break
        else:
            kept.append([angle, moved_by.get(name, 0.0)])
    return sum(1 for _, moved in kept if moved >= min_moved)


def with_history(shift: LayerShift | None,
                 history: Sequence[tuple[bool, Mapping[str, BandShift]]]) -> LayerShift | None:
    """``shift`` with the same bed shift (within SHIFT_PERSISTS_WITHIN_MM) read in the views of the checks
    before it: ``history`` holds (tested, views) of those checks, oldest first, where ``views`` is what
    :func:`band_shift` gave per camera and ``tested`` says the check had a check before it (the first
    check's band is the whole part, not the newest layers). Fills ``before``: the last four checks,
    newest first, up to the first that did not test its band (``back_to_first``: that was the first check)."""
    if shift is None:
        return None
    shift.before = []
    shift.back_to_first = False
    shift.at_first_check = not history
    for tested, views in reversed(list(history[-4:])):
        if not tested:
            shift.back_to_first = True
        if not (tested and views):
            break
        shift.before.append(layer_shift_at(views, shift.shift_mm, SHIFT_PERSISTS_WITHIN_MM, vertical=shift.vertical))
    return shift


def _was_there(shift: LayerShift | None, sure: bool = False) -> bool:
    return shift is not None and (shift.confirmed_sure if sure else shift.confirmed) >= SHIFT_WAS_NOT_THERE


def _confirms(shift: LayerShift, min_mm: float, several_share: float, one_view_share: float,
              sure: bool = False, straddles_onset: bool = False) -> bool:
    several = shift.viewpoints >= 2
    share = shift.confirmed_sure if sure else shift.confirmed
    return (bool(shift.cameras) and shift.magnitude_mm >= min_mm
            and shift.support >= _min_support(shift, several)
            and share >= (several_share if several else one_view_share)
            and (not sure or _sticks_out(shift))
            and (straddles_onset or shift.against <= SHIFT_AGAINST * shift.support)
            and (shift.score >= SHIFT_OVER_NULL * shift.null_score or beats_null_apart(shift)))


def _min_support(shift: LayerShift, several: bool) -> float:
    """Confirming pixels the shift needs: SHIFT_MIN_SUPPORT_PX from several directions; from one,
    SHIFT_MIN_SUPPORT_ONE_VIEW_PX or, where that exceeds SHIFT_MIN_SUPPORT_ONE_VIEW_SHARE of all the pixels the shift
    can change (a small band), that share of them, never under SHIFT_MIN_SUPPORT_PX."""
    if several:
        return SHIFT_MIN_SUPPORT_PX
    return max(SHIFT_MIN_SUPPORT_PX,
               min(SHIFT_MIN_SUPPORT_ONE_VIEW_PX, SHIFT_MIN_SUPPORT_ONE_VIEW_SHARE * shift.swept))


def beats_null_apart(shift: LayerShift) -> bool:
    """Whether, read from two or more sides, the shift beats the pooled null overall and, on the side the null fits
    worst, on that side's pixels alone as a shift must (SHIFT_OVER_NULL, SHIFT_MIN_SUPPORT_PX, SHIFT_CONFIRMED,
    SHIFT_AGAINST): a shift along the lines of sight of cameras on opposite sides, which no height error fits."""
    if not (shift.vertical and shift.sides >= 2 and shift.side_apart is not None
            and shift.score >= shift.null_score):
        return False
    support, against, moved, null = shift.side_apart
    return (support >= SHIFT_MIN_SUPPORT_PX and support >= SHIFT_CONFIRMED * moved
            and against <= SHIFT_AGAINST * support
            and support - 2.0 * against >= SHIFT_OVER_NULL * max(null, 0.0))


def _sticks_out(shift: LayerShift) -> bool:
    """Whether SHIFT_OVERHANG_SHARE of the confirming pixels are material sticking out where the model has none."""
    return shift.overhang >= SHIFT_OVERHANG_SHARE * shift.support


#: A view's newest band reads shifted on its own where its best shift is confirmed by this share of the pixels it
#: changes (BandShift.confirmed) ... (band_reads_shifted)
BAND_SHIFTED_SHARE = 0.5


def band_reads_shifted(reading: BandShift | None) -> bool:
    """Whether one camera's newest band reads shifted on its own: most of the pixels its best shift changes confirm
    it (:data:`BAND_SHIFTED_SHARE`), and as many as a layer shift needs at least (:data:`SHIFT_MIN_SUPPORT_PX`)."""
    return (reading is not None and reading.confirmed >= BAND_SHIFTED_SHARE
            and reading.support >= SHIFT_MIN_SUPPORT_PX)


def band_reads_lowered(reading: BandShift | None) -> bool:
    """Whether one camera's newest band reads its top lowered on its own: the band's top moved down by more than the
    alignment's tolerance explains the image best (``null_dy``), on as many pixels as a layer shift needs at least
    (``null_score``, :data:`SHIFT_MIN_SUPPORT_PX`): confident bed where the top of the newest layers should stand."""
    return (reading is not None and reading.null_dy > reading.tolerance
            and reading.null_score >= SHIFT_MIN_SUPPORT_PX)


def _one_sided(shift: LayerShift) -> bool:
    """Whether the move the other way is read clearly not there (SHIFT_OPPOSITE_MAX)."""
    return shift.opposite is None or shift.opposite.confirmed_sure < SHIFT_OPPOSITE_MAX


def _confirms_new(shift: LayerShift, min_mm: float) -> bool:
    """Confirmed at this check over the decided pixels: new (:func:`is_new`), with an overhang
    (SHIFT_OVERHANG_SHARE) on one side only (SHIFT_OPPOSITE_MAX), at SHIFT_CONFIRMED from any number of directions:
    what one direction's higher share guards against, an offset there all along, the check before read clearly
    not there (the one-view confirming-pixel floor stays: a handful of pixels is a small sample either way)."""
    return (is_new(shift) and _one_sided(shift)
            and _confirms(shift, min_mm, SHIFT_CONFIRMED, SHIFT_CONFIRMED, sure=True))


def is_new(shift: LayerShift) -> bool:
    """Whether the previous check tested its own band and its views read this shift clearly not there (under
    SHIFT_WAS_NOT_THERE of the decided pixels it changes there)."""
    return _read_not_there(shift.previous)


def _read_not_there(earlier: LayerShift | None) -> bool:
    """Whether ``earlier`` (a check's reading of this shift) tested its band and read it under SHIFT_WAS_NOT_THERE of
    the decided pixels it changes there."""
    return earlier is not None and earlier.moved_sure > 0 and earlier.confirmed_sure < SHIFT_WAS_NOT_THERE


def _confirms_grown_in(shift: LayerShift, min_mm: float) -> bool:
    """Confirmed at this check by SHIFT_CONFIRMED of every pixel it changes, from any number of directions, where the
    check before the previous one read it clearly not there: the previous check's band is usually the one the shift
    began in, which shows it only in part (its newest few layers moved, the rest in place), neither clearly not there
    (:func:`is_new`) nor as clearly as :func:`persists` needs; an offset there all along was there two checks ago too.
    Only with the overhang on one side that a new shift needs (SHIFT_OVERHANG_SHARE, SHIFT_OPPOSITE_MAX): bed inside
    the outline alone is also a part a little narrower than the model, and the rest of the readings of the last
    four checks still rule out an offset there all along (:func:`was_there_before`)."""
    return (len(shift.before) >= 2 and _read_not_there(shift.before[1]) and _one_sided(shift) and _sticks_out(shift)
            and _confirms(shift, min_mm, SHIFT_CONFIRMED, SHIFT_CONFIRMED))


def persists(shift: LayerShift, min_mm: float) -> bool:
    """Whether the shift is new and seen at two consecutive checks: confirmed now and in the previous
    check's views by SHIFT_PERSISTS_CONFIRMED (one view: ..._ONE_VIEW, the other rules as
    :func:`confirms_layer_shift`), and by less than SHIFT_WAS_NOT_THERE at the check before them (all three
    checks testing their own band; see :func:`with_history`). The previous check's contradicting pixels are not held to
    SHIFT_AGAINST: its band is usually the one the shift began in, whose layers printed in place below the onset
    contradict it where the moved band uncovers them (its share bounds them). Counted over every pixel the shift changes or,
    as at one check (:func:`_confirms_new`: an overhang on one side only), over the decided ones at all three
    checks: the blurred rim along the moved band's outline is no evidence at two checks either."""
    return _persists_over(shift, min_mm, sure=False) or (_one_sided(shift) and _persists_over(shift, min_mm, sure=True))


def _persists_over(shift: LayerShift, min_mm: float, sure: bool) -> bool:
    """:func:`persists` with every share counted over all the pixels the shift changes, or (``sure``) the decided ones."""
    return (len(shift.before) >= 2 and shift.before[0] is not None and not _was_there(shift.before[1], sure)
            and _confirms(shift, min_mm, SHIFT_PERSISTS_CONFIRMED, SHIFT_PERSISTS_CONFIRMED_ONE_VIEW, sure=sure)
            and _confirms(shift.before[0], min_mm, SHIFT_PERSISTS_CONFIRMED, SHIFT_PERSISTS_CONFIRMED_ONE_VIEW,
                          sure=sure, straddles_onset=True))


def was_there_before(shift: LayerShift) -> bool:
    """Whether at least three checks before this one (and every one of the last four that tested its band)
    showed this shift already (SHIFT_WAS_NOT_THERE): an offset there all along is a calibration residual or
    an alignment slip of the whole part, not layers that slid since. A real shift has a check without it
    just before its onset, so this hides only one left unconfirmed for four checks. Also where the last three
    showed it and a height error explained each of them (:func:`_offset_held_by_the_null`), or where none of the
    last four read it clearly absent (:func:`_partly_there_all_along`), or where the two checks before the previous one
    read it partly but not clearly (:func:`_grown_into_view`: an outline's offset that grew into view with the part)."""
    return ((len(shift.before) >= 3 and all(_was_there(e) for e in shift.before))
            or _offset_held_by_the_null(shift) or _partly_there_all_along(shift)
            or _grown_into_view(shift))


#: A reading of a shift at this share or more of the pixels it changes does not read it clearly absent, and a shift
#: read so at each of this many checks that tested their band (the whole history with_history keeps) was partly there
#: all along (_partly_there_all_along).
SHIFT_PARTLY_THERE = 0.25
SHIFT_PARTLY_THERE_CHECKS = 4
#: The checks that must each have read a shift (SHIFT_WAS_NOT_THERE) explained as well by a height error
#: (_offset_held_by_the_null).
SHIFT_HELD_BY_NULL_CHECKS = 3


def _offset_held_by_the_null(shift: LayerShift) -> bool:
    """Whether each of the last SHIFT_HELD_BY_NULL_CHECKS checks read this shift already (SHIFT_WAS_NOT_THERE) and
    explained it no better than the part standing taller or lower (score under SHIFT_OVER_NULL x its null): one
    view's band sitting off by the same pixels at every check (cross-check seed 21 `009_normal`, a stack's tier seen
    from high above: 0.74, 0.85, 0.87, held by the null each time) is that view's standing offset; its confirming
    pixels growing past twice the null at a fourth check do not make it new. A real shift left unconfirmed over
    three checks by other guards (too few pixels, one view's share, contradicting pixels) is not held back here."""
    readings = shift.before[:SHIFT_HELD_BY_NULL_CHECKS]
    return (len(readings) == SHIFT_HELD_BY_NULL_CHECKS
            and all(_was_there(e) and e.score < SHIFT_OVER_NULL * e.null_score for e in readings))


def _partly_there_all_along(shift: LayerShift) -> bool:
    """Whether every one of the last SHIFT_PARTLY_THERE_CHECKS checks that tested their band read this shift partly
    there (SHIFT_PARTLY_THERE or more): a real shift has a check before its onset that reads it clearly absent,
    while one view's offset growing into view over several checks reads half there at each of them (cross-check
    seed 22 `003_normal`: 0.41, 0.52, 0.40, 0.42 before 0.82 at the print's last check)."""
    readings = shift.before[:SHIFT_PARTLY_THERE_CHECKS]
    return (len(readings) == SHIFT_PARTLY_THERE_CHECKS
            and all(e is not None and e.confirmed >= SHIFT_PARTLY_THERE for e in readings))


#: The checks before the previous one that must each read a shift partly, never clearly (SHIFT_PARTLY_THERE up to
#: SHIFT_WAS_NOT_THERE), for it to have grown into view with the part (_grown_into_view).
SHIFT_GROWN_INTO_VIEW_CHECKS = 2


def _grown_into_view(shift: LayerShift) -> bool:
    """Whether each of the SHIFT_GROWN_INTO_VIEW_CHECKS checks before the previous one read this shift partly, but
    not clearly (SHIFT_PARTLY_THERE up to SHIFT_WAS_NOT_THERE): an offset that grew into view over checks. A view whose
    outline lies a few px off the part (a first look on a brim of the part's colour fits it anywhere along the brim,
    and the anchor then holds it) cannot show that while the part stands inside the brim or the bed-marks zone around
    its foot; as the part rises out of it, more of the offset shows at each check, and the newest band, tested against
    the outline, reads as moved by it (cross-check seed 27 `029_detach` s0, the outline 6 px beside the part: 0.44,
    0.46, 0.85, then 0.94 before any failure). Layers that slid are a step in time: clearly absent before the onset
    (SHIFT_PARTLY_THERE), fully there after it, and only the onset check's band, just before the first catch, reads
    them partly."""
    readings = shift.before[1:1 + SHIFT_GROWN_INTO_VIEW_CHECKS]
    return (len(readings) == SHIFT_GROWN_INTO_VIEW_CHECKS
            and all(e is not None and SHIFT_PARTLY_THERE <= e.confirmed < SHIFT_WAS_NOT_THERE for e in readings))


def there_since_first_check(shift: LayerShift) -> bool:
    """Whether every check since the first tested its band and read this shift already (SHIFT_WAS_NOT_THERE), from
    one direction only: the first check's band is the whole part, so nothing shows the shift new, and one view's
    outline sitting off by a little more at every check (an alignment anchored on the brim beside the part's foot,
    a calibration error growing with the height) reads the same as a shift printed in the first tested band. Cameras
    from two directions agreeing on one rigid move of the top are not fooled so (each view's error is its own)."""
    return (shift.viewpoints < 2 and shift.back_to_first and bool(shift.before)
            and all(_was_there(e) for e in shift.before))


def confirms_layer_shift(shift: LayerShift, min_mm: float) -> bool:
    """Whether the pooled evidence says the newest layers were printed shifted by ``min_mm`` or more:
    at this check alone (SHIFT_CONFIRMED, ..._ONE_VIEW; for a new shift, :func:`is_new`, the same shares of
    the decided pixels, see SHIFT_OVERHANG_SHARE and SHIFT_OPPOSITE_MAX), or new and seen at two checks
    (:func:`persists`), or grown in over the previous check (:func:`_confirms_grown_in`), and not there all along
    (:func:`was_there_before`, :func:`there_since_first_check`).

    The thresholds are shares of pixels (scale-free); see docs/detection-log.md for what they were
    measured on.
    """
    return ((_confirms(shift, min_mm, SHIFT_CONFIRMED, SHIFT_CONFIRMED_ONE_VIEW) or _confirms_new(shift, min_mm)
             or persists(shift, min_mm) or _confirms_grown_in(shift, min_mm))
            and not was_there_before(shift) and not there_since_first_check(shift) and not shift.onto_earlier_places
            and not beyond_the_search_at_the_first_check(shift) and not contradicted_in_a_view(shift))


def contradicted_in_a_view(shift: LayerShift) -> bool:
    """Whether a camera the shift shows to clearly reads it as clearly not there on its own: SHIFT_MIN_SUPPORT_PX or
    more of the pixels it changes there contradict it, and those confirming it are at most SHIFT_AGAINST of them (the
    share a confirmed shift allows the other way round). Layers that slid are one rigid move of the part's top, the
    same in every view; the pooled share lets a view that changes many pixels outvote one that changes few, and an
    outline laid off the part along a brim in one view reads as a large move there (cross-check seed 47
    ``028_runout`` s1: 404 of 440 pixels confirming 9 px, while s0, whose outline sits on the part, contradicts the
    same bed move with 74 of its 90 and confirms it with 6)."""
    return any(against >= SHIFT_MIN_SUPPORT_PX and support <= SHIFT_AGAINST * against
               for support, against in shift.read_by.values())


def beyond_the_search_at_the_first_check(shift: LayerShift) -> bool:
    """Whether the shift was read at the print's first check and lies on the search grid's edge: the first check's
    band is the whole part, so nothing shows its layers moved on layers below, and a best fit pressed against the
    8-mm edge is an outline laid far off the part (a view missing much of a part the bed's colour, a brim or skirt
    beside it), not a move read. Three development recordings paused so before any failure, one of them a normal
    print (cross-check seeds 28 ``003_normal``, 32 ``053_detach``, 36 ``025_detach``: 8-10 mm, one view); a part
    knocked off before the first check shows at the next one as displaced or missing."""
    return shift.at_first_check and shift.at_search_edge


#: A camera's image shift of the band lands on one of its earlier places when within this many px (each axis) of it
#: (the pooled bed shift is read at a rounded image shift) ...
EARLIER_PLACE_WITHIN_PX = 1
#: ... which lies at least this many px (each axis, the larger) from where the outline is laid now: closer, the
#: outline did not move.
EARLIER_PLACE_MIN_WALK_PX = 2


def onto_earlier_places(shift: LayerShift, places: Mapping[str, tuple[tuple[int, int], Sequence[tuple[int, int]]]]
                        ) -> bool:
    """Whether every camera ``shift`` shows to (``shift.cameras``, their image shifts) moves the newest band back to
    where that camera's own earlier passing checks laid the expected outline: ``places`` {camera: (where the outline
    lies now, the (dx, dy) px of its earlier places)}. A first look on a brim of the part's colour fits the outline
    equally well along it, and later checks can walk it off the part by a few px each (towards the calibrated
    position); the newest layers, printed on the part, then sit where the first checks laid it, which reads as a
    band moved by the walk. A layer shift moves the band by the printer's move, which matches the outline's own walk
    back in every view it shows to only by chance."""
    if not shift.cameras:
        return False
    for name, (dx, dy) in shift.cameras.items():
        if name not in places:
            return False
        (ax, ay), earlier = places[name]
        walks = [(px - ax, py - ay) for px, py in earlier
                 if max(abs(px - ax), abs(py - ay)) >= EARLIER_PLACE_MIN_WALK_PX]
        if not any(abs(dx - wx) <= EARLIER_PLACE_WITHIN_PX and abs(dy - wy) <= EARLIER_PLACE_WITHIN_PX
                   for wx, wy in walks):
            return False
    return True


def describe_layer_shift(shift: LayerShift) -> str:
    """One line for the user: how far, which way, seen by whom."""
    dx, dy = (float(v) for v in shift.shift_mm)
    share = f"{shift.confirmed:.0%} of the evidence"
    twice = ""
    if shift.previous is not None and _persists_over(shift, 0.0, sure=False):
        twice = f", and {shift.previous.confirmed:.0%} at the previous check"
    elif shift.previous is not None and _one_sided(shift) and _persists_over(shift, 0.0, sure=True):
        # (persists' second reading, over the decided pixels)
        share = f"{shift.confirmed_sure:.0%} of the clear evidence"
        twice = f", and {shift.previous.confirmed_sure:.0%} at the previous check"
    if not _confirms(shift, 0.0, SHIFT_CONFIRMED, SHIFT_CONFIRMED_ONE_VIEW) and _confirms_new(shift, 0.0):
        share, twice = f"{shift.confirmed_sure:.0%} of the clear evidence, new since the previous check", ""
    elif not (_confirms(shift, 0.0, SHIFT_CONFIRMED, SHIFT_CONFIRMED_ONE_VIEW) or twice) \
            and _confirms_grown_in(shift, 0.0):
        twice = ", new since the check before the previous one"
    # (named: the cameras with a share of the evidence, as for viewpoints; one that shows the move but decides
    # next to none of its pixels confirms nothing)
    named = [name for name in shift.cameras
             if shift.moved_by.get(name, 0.0) >= VIEWPOINT_MIN_SHARE * shift.moved] or list(shift.cameras)
    return (f"the newest layers sit {shift.magnitude_mm:.1f} mm sideways on the layers below "
            f"(X {dx:+.1f} mm, Y {dy:+.1f} mm), confirmed by {', '.join(sorted(named))}"
            f" ({share}{twice}): layer shift?")
