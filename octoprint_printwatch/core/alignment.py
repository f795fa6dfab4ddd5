"""Bounded alignment of the expected silhouette on what a camera sees (stage 2 of the shape check).

The expected silhouette may be shifted by at most the image motion the calibration error can cause, and
after a camera's first check by at most a couple of pixels from its previous shift (calibration error
does not change during a print), so a part that moved 10 mm is never aligned back
(:func:`align_expected`). A first look whose overlap cannot tell where the part stands lays the outline on
the frame's new edges (:func:`outline_on_edges`); the shifts a check cannot tell apart are kept for the
next (:func:`align_candidates`). A part found whole somewhere else is :func:`displaced_part`.
"""
from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from .masks import around, bounding_box, erode, shift_mask, upper_profile

def _shift_prior(dxs: np.ndarray, dys: np.ndarray, max_shift: int, area: float) -> np.ndarray:
    """Overlap (px) a shift (dx, dy) must gain to beat no shift. Calibration errors are small more often
    than large: a Gaussian prior on the shift (``max_shift`` is 2.5 standard deviations) makes a far
    shift win only on clearly better overlap, so a faint or partial mask cannot drag the outline across
    the part. It also breaks ties (a runout leaves the top free to slide) towards the smallest move."""
    sigma = max(max_shift / 2.5, 1.0)
    return 0.01 * ((dxs * dxs + dys * dys) / (sigma * sigma)) * area


def align_expected(
    observed: np.ndarray,
    expected: np.ndarray,
    max_shift: int,
    *,
    anchor: tuple[int, int] | None = None,
    max_drift: int = 2,
    profile_of: np.ndarray | None = None,
) -> tuple[int, int]:
    """Shift (dx, dy) of ``expected`` that best matches ``observed`` (both (h, w) bool), searched within
    ``max_shift`` pixels of zero and, when ``anchor`` is given, within ``max_drift`` of the anchor.

    Maximises the overlap, which for binary masks is the same as minimising Eq. 4.1's symmetric
    difference; ties go to the smallest move, or, with ``profile_of`` (the expected silhouette),
    to the shift that best matches the upper outlines. Returns (0, 0) when either mask is empty.
    """
    box = bounding_box(expected)
    if box is None or max_shift <= 0 or not observed.any():
        return (0, 0) if anchor is None else anchor
    y0, y1, x0, x1 = box
    s = int(max_shift)
    padded = around(observed, box, s, s)
    template = expected[y0:y1, x0:x1].astype(np.float32)
    dys, dxs = np.mgrid[-s: s + 1, -s: s + 1]
    if anchor is not None:
        # only the cells near the anchor can win: compute those exactly, nothing else
        overlap = np.full((2 * s + 1, 2 * s + 1), -np.inf, np.float32)
        ya, yb = max(0, anchor[1] - max_drift + s), min(2 * s + 1, anchor[1] + max_drift + s + 1)
        xa, xb = max(0, anchor[0] - max_drift + s), min(2 * s + 1, anchor[0] + max_drift + s + 1)
        if ya < yb and xa < xb:
            window = padded[ya: yb - 1 + template.shape[0], xa: xb - 1 + template.shape[1]]
            overlap[ya:yb, xa:xb] = cv2.matchTemplate(window, template, cv2.TM_CCORR)
    else:
        overlap = _overlap_map(padded, template, s)  # (2s+1, 2s+1), index = shift + s
    allowed = dxs * dxs + dys * dys <= s * s
    if anchor is not None:
        allowed &= (np.abs(dxs - anchor[0]) <= max_drift) & (np.abs(dys - anchor[1]) <= max_drift)
        if not allowed.any():
            return anchor
    score = np.where(allowed, overlap - _shift_prior(dxs, dys, s, float(template.sum())), -np.inf)
    if profile_of is not None:
        # Material attached to the part at bed level (brim, skirt, shadow, reflection) makes the
        # observed blob larger than the template, and the overlap is then flat wherever the template
        # fits inside it. Among those near-best shifts, take the one that puts the expected upper
        # outline on the observed one: bed-level material never reaches the part's top edge.
        best = float(score.max())
        plateau = score >= best - 0.02 * float(template.sum())
        if plateau.sum() > 1:
            cost = _profile_cost(observed, profile_of, dxs[plateau], dys[plateau])
            k = int(np.argmin(cost + 1e-3 * np.hypot(dxs[plateau], dys[plateau])))
            return int(dxs[plateau][k]), int(dys[plateau][k])
    iy, ix = np.unravel_index(int(np.argmax(score)), score.shape)
    return int(dxs[iy, ix]), int(dys[iy, ix])


#: A look without an anchor lays the expected outline on the frame's new edges (edges the background frame
#: has not: the part's rim against the bed or against its own brim) rather than where the material overlaps it
#: best, where the overlap cannot tell where the part is: the shifts within PLATEAU_SHARE of its best overlap
#: span at least this share of the alignment bound (a brim or skirt of the part's colour around the part, or a
#: part seen only in part: the outline fits equally well over much of it). Measured at first looks: default
#: normal_05 (orange vase, orange brim, gold bed, top view) 27-32 px of a 30-px bound, normal_14 under gamma 1.25
#: 32 px; where the overlap placed the part within a few px (seed 10 001_normal s1R, 029_detach s1: 8 px), the
#: edges of a part's lit faces can fit the outline better 8-13 px off, so there they decide nothing.
OUTLINE_AMBIGUOUS_SHARE = 0.5

#: ... and where the outline is distinct there: its mean edge strength (in units of the bed's edge noise) is over
#: the bed factor (what is confidently not the bed) and this many times the 90th percentile over every shift
#: searched (the frame's own edges: grain, JPEG, sensor noise). Measured: normal_05's first look 4.4 at (-1, -5) px (the true calibration error: -1, -4), the 90th
#: percentile 1.0, the overlap's choice 0.5 at (-15, 3); under noise, sharpening and a colour cast the overlap chose
#: (-15, 13), (0, 9), (-16, 6) and the edges (-1, -5); normal_14 under gamma 1.25: 9.9 at (-4, -6) (true -2.5,
#: -7.4), 4.7, the overlap's choice 2.3 at (17, 10). Edges within the noise (seed 10 037_detach: 0.5-2) decide
#: nothing.
OUTLINE_EDGE_DISTINCT = 2.0

#: ... and where the overlap's choice lies off the frame's edges: at most this share of the outline's edge strength.
#: Measured: normal_05 0.11, normal_14 under gamma 1.25 0.23, against 0.41-0.47 where the overlap's choice was
#: right or nearer the truth and a brim's or a lit face's edges parallel to the outline fit it better 10 px off
#: (seed 11 050_spaghetti s0L, side view of a white part with a brim: 12.0 at (-17, 9), true (-5.4, 6.2)).
OUTLINE_CHOICE_OFF_EDGES = 1.0 / 3.0

#: ... and only where the material still covers the outline there nearly as well: at most this share of the
#: template's area less overlap (less the shift prior; the vase above: 1-9 %)
OUTLINE_OVERLAP_LOSS = 0.15

#: ... and only where the edges run along the outline's sides facing away from the move (from the overlap's choice)
#: too: their mean over the bed factor or at least this share of the mean along the sides facing the move. A part's
#: rim is an edge all round it; the outer edge of a brim of the part's colour is the rim grown outwards, so it fits
#: only the sides the outline slid towards across the brim. Measured: seed 15 004_normal s0 (light grey frame on black
#: PEI, saturated white, a brim inside its hole too) 0.39 noise units against 27.9, 0.01, at (23, 2), 22 px off (true
#: error (1, -7); the overlap's choice (-3, -11)), which paused the print three checks later on 37 % "unexpected
#: material". Kept: the rims a16 measured, default normal_05 3.7-5.1 units, 0.99-1.17 of the facing sides (as
#: rendered and under all eight perturbations), normal_14 under gamma 1.25 5.8 units, 0.43; seed 10 001_normal s1R
#: under sharpen1 1.0 units, 0.19-0.24 (true error (-4.7, -3.7), the rim at (-5, -4)); seed 14 008_normal s0L 1.5
#: units, 0.25 (at (1, 3), true (7.5, 1.2), the overlap's choice (8, -1): a bar of 0.25 moved it there, verdicts same).
OUTLINE_TRAILING_SHARE = 0.1


def outline_on_edges(edges: np.ndarray, silhouette: np.ndarray, observed: np.ndarray, template: np.ndarray,
                     max_shift: int, chosen: tuple[int, int], least_edge: float) -> tuple[int, int] | None:
    """The shift (dx, dy) that lays the outline of ``silhouette`` on ``edges`` ((h, w) float32, the frame's new
    edges in noise units) instead of ``chosen`` (:func:`align_expected`'s shift of ``template`` onto
    ``observed``, all (h, w) bool, within ``max_shift``), or None where the overlap can tell the part's place
    (:data:`OUTLINE_AMBIGUOUS_SHARE`), the outline's edges are not distinct or fainter than ``least_edge`` (noise
    units), the overlap clearly prefers ``chosen`` (:data:`OUTLINE_EDGE_DISTINCT`, :data:`OUTLINE_OVERLAP_LOSS`), or
    the edges lie along the sides the outline moved towards only (a brim's outer edge, :data:`OUTLINE_TRAILING_SHARE`).
    """
    ring = silhouette & ~erode(silhouette, 1)
    ring_box, box = bounding_box(ring), bounding_box(template)
    s = int(max_shift)
    # a look that sees no material keeps the calibrated place (as align_expected does): edges alone can be
    # anything (seed 7 039_layer_shift's first usable look, on a part in the bed's colour: 2.6 noise units, 4-6 px off)
    if ring_box is None or box is None or s <= 0 or abs(chosen[0]) > s or abs(chosen[1]) > s or not observed.any():
        return None
    y0, y1, x0, x1 = box
    area = float(template[y0:y1, x0:x1].sum())
    overlap = _overlap_map(around(observed, box, s, s), template[y0:y1, x0:x1].astype(np.float32), s)
    dys, dxs = np.mgrid[-s: s + 1, -s: s + 1]
    allowed = dxs * dxs + dys * dys <= s * s
    fits = allowed & (overlap >= float(overlap[allowed].max()) - PLATEAU_SHARE * area)
    if max(np.ptp(dxs[fits]), np.ptp(dys[fits])) < OUTLINE_AMBIGUOUS_SHARE * s:
        return None
    y0, y1, x0, x1 = ring_box
    outline = ring[y0:y1, x0:x1].astype(np.float32)
    strength = cv2.matchTemplate(around(edges.astype(np.float32), ring_box, s, s), outline, cv2.TM_CCORR)
    strength /= float(outline.sum())
    iy, ix = np.unravel_index(int(np.argmax(np.where(allowed, strength, -np.inf))), strength.shape)
    best = float(strength[iy, ix])
    score = overlap - _shift_prior(dxs, dys, s, area)
    cy, cx = chosen[1] + s, chosen[0] + s
    if (best < max(least_edge, OUTLINE_EDGE_DISTINCT * float(np.percentile(strength[allowed], 90)))
            or float(strength[cy, cx]) > OUTLINE_CHOICE_OFF_EDGES * best
            or float(score[iy, ix]) < float(score[cy, cx]) - OUTLINE_OVERLAP_LOSS * area):
        return None
    shift = (int(ix) - s, int(iy) - s)
    leading, trailing = edges_by_side(edges, silhouette, shift, (shift[0] - chosen[0], shift[1] - chosen[1]))
    if trailing < min(least_edge, OUTLINE_TRAILING_SHARE * leading):
        return None
    return shift


def edges_by_side(edges: np.ndarray, silhouette: np.ndarray, shift: tuple[int, int],
                  move: tuple[int, int]) -> tuple[float, float]:
    """(leading, trailing): the mean of ``edges`` ((h, w) float32) along the outline of ``silhouette`` ((h, w) bool)
    shifted by ``shift`` (dx, dy), over the outline's sides facing the direction ``move`` (dx, dy; outward normal
    within 90 degrees of it, a hole's sides included: they face into the hole) and over those facing away; a set with
    no pixels in the frame reads 0."""
    h, w = edges.shape
    ring = silhouette & ~erode(silhouette, 1)
    # the outward normal: down the gradient of the smoothed silhouette (sides parallel to the move count in neither)
    smooth = cv2.GaussianBlur(silhouette.astype(np.float32), (0, 0), 2.0)
    ys, xs = np.nonzero(ring)
    facing = -(cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3)[ys, xs] * move[0]
               + cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3)[ys, xs] * move[1])
    xs, ys = xs + shift[0], ys + shift[1]
    inside = (xs >= 0) & (xs < w) & (ys >= 0) & (ys < h)
    values, facing = edges[ys[inside], xs[inside]].astype(np.float64), facing[inside]
    ahead, behind = facing > 0, facing < 0
    return (float(values[ahead].mean()) if ahead.any() else 0.0,
            float(values[behind].mean()) if behind.any() else 0.0)


def _overlap_map(padded: np.ndarray, template: np.ndarray, s: int) -> np.ndarray:
    """(2s+1, 2s+1) overlap of ``template`` with ``padded`` at every shift, = cv2.matchTemplate TM_CCORR.

    Large searches are done at half resolution first and the map is then filled in at full
    resolution only around the coarse optimum (a few ms instead of tens at 640x480).
    """
    if s <= 6 or min(template.shape) < 16:
        return cv2.matchTemplate(padded, template, cv2.TM_CCORR)
    small_p = cv2.resize(padded, (padded.shape[1] // 2, padded.shape[0] // 2), interpolation=cv2.INTER_AREA)
    small_t = cv2.resize(template, (template.shape[1] // 2, template.shape[0] // 2), interpolation=cv2.INTER_AREA)
    coarse = cv2.matchTemplate(small_p, small_t, cv2.TM_CCORR) * 4.0
    # upsample the coarse map to every shift, then refine exactly within +-3 px of its best cells
    full = cv2.resize(coarse, (2 * s + 1, 2 * s + 1), interpolation=cv2.INTER_LINEAR)
    top = np.argsort(full.ravel())[-3:]
    for index in top:
        cy, cx = np.unravel_index(int(index), full.shape)
        ya, yb = max(0, cy - 3), min(2 * s + 1, cy + 4)
        xa, xb = max(0, cx - 3), min(2 * s + 1, cx + 4)
        window = padded[ya: yb - 1 + template.shape[0], xa: xb - 1 + template.shape[1]]
        full[ya:yb, xa:xb] = cv2.matchTemplate(window, template, cv2.TM_CCORR)
    return full


#: A brim explains a look where the part with it fits the material clearly better than the part alone does:
#: by at least this share of the brim's own pixels (its ring beyond the part, about two thirds of it seen).
BRIM_EXPLAINS_SHARE = 0.3


def align_with_brim(observed: np.ndarray, expected: np.ndarray, brims: Sequence[np.ndarray],
                    max_shift: int, *, anchor: tuple[int, int] | None = None,
                    max_drift: int = 2) -> tuple[int, int] | None:
    """Where a look's material is the part with a brim around it: the shift (dx, dy), or None.

    ``observed`` (h, w) bool material, ``expected`` (h, w) bool the part's silhouette, ``brims`` (h, w) bool each
    the bed around the part's footprint grown by one brim width, at bed level. A brim is material of the part's
    colour all round its foot: the part alone fits anywhere inside the disc it makes (the overlap is flat there),
    while the part with its brim fits only where the disc lies. Each template (the part, and the part with each
    brim) is scored as Eq. 4.1 ranks shapes, 2 x overlap - area (material it leaves out or covers wrongly costs),
    less the shift prior (twice :func:`_shift_prior`, as the overlap counts twice); a brim is taken where its best
    score beats the part alone's by BRIM_EXPLAINS_SHARE of its ring and its ring is seen all round the part there
    (:func:`seen_all_round`); of several widths, the one that gains most. None where no brim explains the look.
    Searched within ``max_shift`` px of zero and, with an ``anchor`` (a later look), within ``max_drift`` px of it:
    the brim keeps the outline on the part while it is short, where the prior would pull it across the brim.
    """
    s = int(max_shift)
    if s <= 0 or not observed.any() or not expected.any():
        return None
    dys, dxs = np.mgrid[-s: s + 1, -s: s + 1]
    allowed = dxs * dxs + dys * dys <= s * s
    if anchor is not None:
        allowed &= (np.abs(dxs - anchor[0]) <= max_drift) & (np.abs(dys - anchor[1]) <= max_drift)
        if not allowed.any():
            return None
    prior = 2.0 * _shift_prior(dxs, dys, s, float(np.count_nonzero(expected)))

    def scores_of(template_mask: np.ndarray) -> np.ndarray:
        """(2s+1, 2s+1) score of the template at every shift (index = shift + s)"""
        box = bounding_box(template_mask)
        y0, y1, x0, x1 = box
        template = template_mask[y0:y1, x0:x1].astype(np.float32)
        overlap = cv2.matchTemplate(around(observed, box, s, s), template, cv2.TM_CCORR)
        return np.where(allowed, 2.0 * overlap - float(template.sum()) - prior, -np.inf)

    alone = float(scores_of(expected).max())
    best_gain, found = 0.0, None
    for brim in brims:
        ring = brim & ~expected
        if not ring.any():
            continue
        score = scores_of(expected | brim)
        iy, ix = np.unravel_index(int(np.argmax(score)), score.shape)
        shift = (int(dxs[iy, ix]), int(dys[iy, ix]))
        gain = float(score[iy, ix]) - alone - BRIM_EXPLAINS_SHARE * float(np.count_nonzero(ring))
        if gain > best_gain and seen_all_round(observed, shift_mask(ring, *shift)):
            best_gain, found = gain, shift
    return found


#: A brim lies all round the part: each side of its ring (BRIM_SIDES sectors around the part, those holding at least
#: BRIM_SIDE_MIN_SHARE of the ring's pixels: the part hides the rest) must be material over this share. The part's
#: mirror image in a glass bed, its shadow or a skirt of its colour fill one side, or a thin line on each. Measured
#: at the first check of every recording of the twenty-six development seeds (residual: the outline's shift less
#: the true calibration error): at 0.8, 268 views with a brim take it, 150 come 2 px or more nearer the truth, none
#: go further, and those over 8 px off go from 31 to 0; 64 views without one take a "brim" (a skirt with the part's
#: mirror image or shadow filling its inside), 27 nearer, 4 further (the most 3.0 -> 9.2 px); at 0.5, 448 without
#: one, 44 further.
BRIM_SIDE_SEEN = 0.8
BRIM_SIDES = 8
BRIM_SIDE_MIN_SHARE = 0.04


def seen_all_round(observed: np.ndarray, ring: np.ndarray) -> bool:
    """Whether ``observed`` covers ``ring`` (both (h, w) bool) over BRIM_SIDE_SEEN on every side of it that shows."""
    ys, xs = np.nonzero(ring)
    if len(ys) == 0:
        return False
    angle = np.arctan2(ys - ys.mean(), xs - xs.mean())
    side = np.minimum(((angle + np.pi) / (2 * np.pi) * BRIM_SIDES).astype(int), BRIM_SIDES - 1)
    pixels = np.bincount(side, minlength=BRIM_SIDES)
    seen = np.bincount(side, weights=observed[ys, xs].astype(np.float64), minlength=BRIM_SIDES)
    shows = pixels >= BRIM_SIDE_MIN_SHARE * len(ys)
    return bool(np.all(seen[shows] >= BRIM_SIDE_SEEN * pixels[shows]))


#: Shifts within this share of the template's area of the best overlap are ones the image cannot tell apart.
PLATEAU_SHARE = 0.02

def align_candidates(
    observed: np.ndarray,
    expected: np.ndarray,
    max_shift: int,
    *,
    candidates: np.ndarray | None = None,
    max_drift: int = 2,
) -> tuple[tuple[int, int] | None, np.ndarray]:
    """The shifts of ``expected`` onto ``observed`` (both (h, w) bool) that this check cannot tell apart,
    and the best of them: ((dx, dy) or None, (k, 2) int array of (dx, dy)).

    Searched within ``max_shift`` px of zero and, when ``candidates`` ((k, 2) int: what earlier checks
    could not tell apart) are given, within ``max_drift`` px (per axis) of one of them. The set is every
    shift whose overlap is within PLATEAU_SHARE of the template's area of the best overlap; the best is
    the one with the best overlap less the Gaussian prior (:func:`_shift_prior`). The overlap is exact
    at every shift (cv2.matchTemplate).
    """
    box = bounding_box(expected)
    none = np.zeros((0, 2), int)
    if box is None or max_shift <= 0 or not observed.any():
        return None, none if candidates is None else np.asarray(candidates, int).reshape(-1, 2)
    s = int(max_shift)
    y0, y1, x0, x1 = box
    padded = around(observed, box, s, s)
    template = expected[y0:y1, x0:x1].astype(np.float32)
    overlap = cv2.matchTemplate(padded, template, cv2.TM_CCORR)   # (2s+1, 2s+1), index = shift + s
    dys, dxs = np.mgrid[-s: s + 1, -s: s + 1]
    allowed = dxs * dxs + dys * dys <= s * s
    if candidates is not None:
        c = np.asarray(candidates, int).reshape(-1, 2)
        c = c[(np.abs(c[:, 0]) <= s) & (np.abs(c[:, 1]) <= s)]
        near = np.zeros(allowed.shape, np.uint8)
        near[c[:, 1] + s, c[:, 0] + s] = 1
        allowed &= cv2.dilate(near, np.ones((2 * max_drift + 1, 2 * max_drift + 1), np.uint8)) > 0
    if not allowed.any():
        return None, none
    area = float(template.sum())
    fits = allowed & (overlap >= float(overlap[allowed].max()) - PLATEAU_SHARE * area)
    score = np.where(fits, overlap - _shift_prior(dxs, dys, s, area), -np.inf)
    iy, ix = np.unravel_index(int(np.argmax(score)), score.shape)
    return (int(dxs[iy, ix]), int(dys[iy, ix])), np.stack([dxs[fits], dys[fits]], axis=1)


def outline_candidate(observed: np.ndarray, expected: np.ndarray,
                      shifts: np.ndarray | None) -> tuple[int, int] | None:
    """Of ``shifts`` ((k, 2) int (dx, dy) of ``expected`` onto ``observed``, both (h, w) bool: shifts the overlap
    cannot tell apart), the one that puts the expected upper outline on the observed one (the smallest move
    among equals); None when there are none.

    Bed-level material attached to the part (brim, cast shadow) makes the overlap flat wherever the outline
    fits inside it, and the smallest move of such a set slides the outline down onto the brim. The part's
    upper outline is the one cue bed-level material never gives (:func:`align_expected` breaks its ties on it).
    """
    if shifts is None or not len(shifts):
        return None
    shifts = np.asarray(shifts, int).reshape(-1, 2)
    cost = _profile_cost(observed, expected, shifts[:, 0], shifts[:, 1])
    k = int(np.argmin(cost + 1e-3 * np.hypot(shifts[:, 0], shifts[:, 1])))
    return int(shifts[k, 0]), int(shifts[k, 1])


def _profile_cost(observed: np.ndarray, expected: np.ndarray, dxs: np.ndarray, dys: np.ndarray,
                  cap: float = 6.0) -> np.ndarray:
    """(n,) capped mean |observed top row - shifted expected top row| over the expected columns.

    ``dxs``, ``dys``: (n,) int shifts of ``expected`` onto ``observed`` (both (h, w) bool). Columns a shift
    moves out of the frame do not count; a shift that moves them all out costs ``cap``.
    """
    obs = upper_profile(observed)
    exp = upper_profile(expected)
    cols = np.flatnonzero(~np.isnan(exp))
    w = observed.shape[1]
    dxs, dys = np.asarray(dxs, np.int64), np.asarray(dys, np.int64)
    # (n, m): every shift against every expected column at once (hundreds of shifts per check)
    target = cols[None, :] + dxs[:, None]
    inside = (target >= 0) & (target < w)
    seen = obs[np.clip(target, 0, w - 1)]
    diff = np.abs(seen - (exp[cols][None, :] + dys[:, None].astype(np.float32)))
    diff = np.where(np.isnan(diff), np.float32(cap), np.minimum(diff, np.float32(cap)))
    counted = inside.sum(axis=1)
    # rows are whole pixels, so the sums are exact and the means those of the per-shift loop this replaced
    total = np.where(inside, diff, np.float32(0.0)).sum(axis=1, dtype=np.float64)
    return np.where(counted > 0, total / np.maximum(counted, 1), cap).astype(np.float32)


def displaced_part(observed: np.ndarray, expected: np.ndarray, reach: int, min_move: float,
                   min_cover: float = 0.8) -> tuple[int, int] | None:
    """(dx, dy) px by which the whole expected part is found moved, or None.

    ``observed`` and ``expected`` are (h, w) bool, ``expected`` already aligned. Every shift within
    ``reach`` px is tried; the part counts as moved when the shifted outline is covered by material
    (``min_cover`` of it) far better than the aligned one (by half of what the aligned one misses), and
    the shift is at least ``min_move`` px. A brim, skirt or shadow next to a part still in place cannot
    pass: it is far thinner than the part, so no shift covers the outline with it, while the part itself
    still covers the aligned outline. A part that slid off is found wherever it lies, inside the
    bed-marks zone or not.
    """
    box = bounding_box(expected)
    total = float(expected.sum())
    if box is None or reach < 1 or total <= 0:
        return None
    y0, y1, x0, x1 = box
    s = int(reach)
    padded = around(observed, box, s, s)
    template = expected[y0:y1, x0:x1].astype(np.float32)
    cover = _overlap_map(padded, template, s) / total   # (2s+1, 2s+1), index = shift + s
    dys, dxs = np.mgrid[-s: s + 1, -s: s + 1]
    far = dxs * dxs + dys * dys >= min_move * min_move
    if not far.any():
        return None
    at_zero = float(cover[s, s])
    best = np.where(far, cover, -1.0)
    iy, ix = np.unravel_index(int(np.argmax(best)), best.shape)
    dx, dy = int(dxs[iy, ix]), int(dys[iy, ix])
    # the coarse search only proposes; the figures are exact
    at_zero = float(np.count_nonzero(observed & expected)) / total
    found = float(np.count_nonzero(observed & shift_mask(expected, dx, dy))) / total
    if found >= min_cover and found - at_zero >= 0.5 * (1.0 - at_zero) and found - at_zero >= 0.2:
        return dx, dy
    return None


def near_any(shift: tuple[int, int], shifts: np.ndarray | None, within: int) -> bool:
    """Whether ``shift`` (dx, dy) lies within ``within`` px (per axis) of one of ``shifts`` ((k, 2) int, or None:
    no)."""
    if shifts is None or not len(shifts):
        return False
    c = np.asarray(shifts).reshape(-1, 2)
    return bool((np.abs(c - np.asarray(shift)).max(axis=1) <= within).any())

