"""The part's rise since an earlier check, read on its upper outline (the shape check's growth figures).

The same camera and the same processing at both checks, so calibration and alignment errors cancel: a
part that stopped growing (runout, clog, spaghetti) shows none of the newest band, even where the band is
a thin crescent the absolute comparison cannot resolve. verdict.decide's stall rules weigh the readings.
"""
from __future__ import annotations

from dataclasses import dataclass
from itertools import islice
from typing import Iterable

import numpy as np

from .masks import dilate, upper_profile

#: The growth test reads the rise over at most this many checks (ShapeResult.growth_span): where one check's
#: rise is too small to read, against an older look of the camera (check_shape's ``older_looks``)
GROWTH_SPAN_CHECKS = 3

#: The coarse growth reading (ShapeResult.coarse_growth_pct) needs a median expected rise of this many ``min_rise``
COARSE_RISE_FACTOR = 1.0


def profile_growth(observed: np.ndarray, previous: np.ndarray, expected: np.ndarray,
                   expected_before: np.ndarray, min_rise: float = 3.0, min_columns: int = 12,
                   median_factor: float = 1.5, columns: np.ndarray | None = None) -> float | None:
    """How much the part's upper outline rose since the previous check, in % of what the model says.

    Per image column where the expected upper outline rises by at least ``min_rise`` px, the ratio of
    the observed rise (previous vs current material mask) to the expected one; the median over those
    columns, times 100 (None unless the median expected rise is at least ``median_factor`` ``min_rise``).
    A part that stopped growing gives ~0, a normal one ~100. The top face of a
    part is often the colour of what lies behind it, so the outline is compared rather than the band's
    area: the near and the far edge of a top face rise alike. None when fewer than ``min_columns``
    columns qualify (a camera looking straight down, a part that ended). ``columns`` ((w,) bool or None):
    the columns that may count at all (where the view could see the part's top rise: check_shape).
    """
    exp_now = upper_profile(expected)
    exp_before = upper_profile(expected_before)
    rise_expected = exp_before - exp_now
    obs_now, obs_before = upper_profile(observed), upper_profile(previous)
    usable = (rise_expected >= min_rise) & ~np.isnan(obs_now) & ~np.isnan(obs_before)
    if columns is not None:
        usable &= columns
    cols = np.flatnonzero(usable)
    # a rise of a few pixels is within what mask edges wobble by between two frames
    if cols.size < min_columns or float(np.median(rise_expected[cols])) < median_factor * min_rise:
        return None
    ratio = (obs_before[cols] - obs_now[cols]) / rise_expected[cols]
    return float(np.median(np.clip(ratio, -1.0, 2.0)) * 100.0)


#: The top of the observed material is an edge of the frame unless the frame changes across it by less than
#: this share of what the background frame changes by there, and by no more than noise (edge_in_the_frame).
#: Where the hotend's mirror image in a glass bed is hidden by a black part (cross-check seed 5 010_normal)
#: the frame changes by 5-30 % of the background's change, within noise; where a light part's top stands
#: in front of the bed's rim (seed 1 018_normal) by 25-35 %, but 60 grey levels, far beyond noise.
EDGE_OF_THE_FRAME_SHARE = 0.5


def edge_in_the_frame(observed: np.ndarray, frame: np.ndarray, background: np.ndarray,
                      tolerance: float, bed_sample: np.ndarray | None = None,
                      material_factor: float = 5.0) -> np.ndarray:
    """(w,) bool: the columns where the top of the observed material is an edge of the current frame.

    ``observed`` (h, w) bool; ``frame`` (h, w, 3) and ``background`` (h, w, 3, at the frame's exposure). Per
    column, the mean colour over a few rows just above the top-most material pixel (from ``tolerance`` + 1
    to 2 ``tolerance`` + 3 px, past the soft rim every outline has) is compared with that over as many rows
    just below it, in the frame and in the background frame. A part's top is an edge of the frame (the part
    below it, what lies behind above it). A top across which the frame changes by less than
    :data:`EDGE_OF_THE_FRAME_SHARE` of what the background frame changes by, and by no more than
    ``material_factor`` times the noise of such a step (from the spread of frame - background on the certain
    bed ``bed_sample``, (h, w) bool; None: no noise test), is the outline of something the background frame
    held there, not of the part: a black part on a dark bed reads as material only where it hides a bright
    reflection of the hotend the background frame shows, and that material's top stays where the
    reflection's was however the part grows; above it the part looks like what lies behind it.
    """
    h, w = observed.shape
    top = upper_profile(observed)
    columns = np.zeros(w, bool)
    cols = np.flatnonzero(~np.isnan(top))
    if cols.size == 0:
        return columns
    near, far = int(np.ceil(tolerance)) + 1, int(np.ceil(2.0 * tolerance)) + 3
    offsets = np.arange(near, far + 1)
    t = top[cols].astype(int)[:, None]
    above, below = t - offsets[None, :], t + offsets[None, :]
    ok = (above >= 0).all(axis=1) & (below < h).all(axis=1)
    cols, above, below = cols[ok], above[ok], below[ok]
    if cols.size == 0:
        return columns
    # (float32 copies of the pixels read only, not of the whole images)
    def at(image: np.ndarray, ys: np.ndarray, xs: np.ndarray) -> np.ndarray:
        return image[ys, xs].astype(np.float32)

    c = cols[:, None]
    frame_step = np.linalg.norm(at(frame, above, c).mean(axis=1) - at(frame, below, c).mean(axis=1), axis=1)
    background_step = np.linalg.norm(at(background, above, c).mean(axis=1) - at(background, below, c).mean(axis=1),
                                     axis=1)
    edge = frame_step >= EDGE_OF_THE_FRAME_SHARE * background_step
    # a change of the frame clear of the noise is an edge whatever the background did: the part differs from
    # what lies above its top, and would be seen there had it risen (a difference of two means of n rows has
    # 1/sqrt(n) of the per-pixel spread of frame - background, norm over the three channels)
    # (measured only where a column fails the test above: on most checks every column passes it)
    least_step = np.inf
    if bed_sample is not None and not edge.all() and int(bed_sample.sum()) >= 50:
        sample = np.flatnonzero(bed_sample)
        sample = sample[:: sample.size // 6000 + 1]
        rows_s, cols_s = np.divmod(sample, w)
        diff = at(frame, rows_s, cols_s) - at(background, rows_s, cols_s)
        spread = 1.4826 * np.median(np.abs(diff - np.median(diff, axis=0)), axis=0)
        least_step = material_factor * float(np.linalg.norm(spread)) / np.sqrt(len(offsets))
    columns[cols] = edge | (frame_step >= least_step)
    return columns


@dataclass
class Rise:
    """The part's rise read by one camera at one check, % of what the model says (ShapeResult's growth figures);
    at most one of the three is read, the finest the check allows (None: not read)."""

    growth_pct: float | None = None          # since the previous check
    coarse_growth_pct: float | None = None   # since the previous check, to the pixel (a rise of 4-6 px)
    span_growth_pct: float | None = None     # since an older look, where one check's rise is too small for either
    span: int | None = None                  # how many checks back the reading was measured against


def read_rise(observed: np.ndarray, seen_before: np.ndarray, expected: np.ndarray, expected_before: np.ndarray,
              older_looks: Iterable[tuple[np.ndarray, np.ndarray] | None], columns: np.ndarray,
              tolerance: float) -> Rise:
    """The rise of the ``observed`` material's top (within the expected outlines) since the camera's previous look
    ``seen_before``, against the model's: ``expected`` and ``expected_before`` its silhouettes now and then, all
    (h, w) bool, aligned alike; read in the ``columns`` ((w,) bool) where the material's top is an edge of the frame
    (:func:`edge_in_the_frame`), only where the model's top rises enough (:func:`profile_growth`).

    Where it rises 4-6 px, the rise is read coarsely (a pixel of edge wobble is 20-25 %; verdict.decide uses it only
    where no camera reads finer). Where it rises too little for either (2-3 px), against ``older_looks``, the
    camera's looks before the previous one, newest first, each (material mask, the model's silhouette then) or None
    (not usable), lazily: the newest the top rose enough since to read it finely, up to :data:`GROWTH_SPAN_CHECKS`
    checks back (the same pixel precision as a one-check reading; a stall persists, so it is read all the same,
    only once the whole span lies after the stop)."""
    min_rise = max(4.0, 2.0 * tolerance)
    before = seen_before & dilate(expected_before, tolerance)
    growth = profile_growth(observed, before, expected, expected_before, min_rise=min_rise, columns=columns)
    if growth is not None:
        return Rise(growth_pct=growth, span=1)
    coarse = profile_growth(observed, before, expected, expected_before, min_rise=min_rise,
                            median_factor=COARSE_RISE_FACTOR, columns=columns)
    if coarse is not None:
        return Rise(coarse_growth_pct=coarse, span=1)
    for span, look in enumerate(islice(older_looks, GROWTH_SPAN_CHECKS - 1), start=2):
        if look is None:
            continue
        older, older_expected = look
        span_growth = profile_growth(observed, older & dilate(older_expected, tolerance), expected, older_expected,
                                     min_rise=min_rise, columns=columns)
        if span_growth is not None:
            return Rise(span_growth_pct=span_growth, span=span)
    return Rise()
