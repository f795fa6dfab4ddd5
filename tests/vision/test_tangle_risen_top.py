"""The new-material test (core/tangle.py) where the calibration error laid a view's outline a few px off the part.

The error is the same at every check, so the part's top, seen beyond the outline at the previous check, stands as far
beyond it now once the part has risen by the model's rise: its newest band, new since then and more than 2 mm beyond
the outline at every check, is the part's own. Loops standing higher, beside it or around its foot still count.
"""
import numpy as np

from octoprint_printwatch.core.tangle import TWO_VIEWS_MM2, new_material, risen_top

from .synthetic import H, PART, W, Box

PX_PER_MM = 4.0
TOL = 2.0
REACH = 25.0                                      # the alignment's bound, px
EVERYWHERE = np.ones((H, W), bool)
LOW_PX = 16                                       # the outline laid 4 mm below the part
RISE_PX = 30                                      # the model's rise between the two checks
OUTLINE_NOW = Box(PART.x0, PART.y0 + LOW_PX, PART.x1, PART.y1).mask()
OUTLINE_THEN = Box(PART.x0, PART.y0 + LOW_PX + RISE_PX, PART.x1, PART.y1).mask()
SEEN_THEN = Box(PART.x0, PART.y0 + RISE_PX, PART.x1, PART.y1).mask()       # the part then, where it stands


def measure(observed, previous, **kw):
    return new_material(observed, previous, OUTLINE_NOW, EVERYWHERE, TOL, PX_PER_MM, **kw)


def risen(previous=SEEN_THEN):
    return risen_top(previous, OUTLINE_NOW, OUTLINE_THEN, REACH, TOL)


def test_the_newest_band_above_an_outline_laid_low_is_the_parts():
    now = PART.mask()
    # against the outline alone, the part's newest band above it reads as new material at every check
    assert measure(now, SEEN_THEN).area_mm2 >= TWO_VIEWS_MM2
    # the part's top seen then, risen by the model's rise, explains it
    assert measure(now, SEEN_THEN, risen=risen()).area_mm2 == 0.0


def test_loops_above_the_risen_top_and_beside_the_part_still_count():
    loops_above = Box(150, PART.y0 - 40, 170, PART.y0 + 2).mask()          # standing on the top, reaching higher
    loops_beside = Box(PART.x1 - 2, 140, PART.x1 + 40, 160).mask()          # draped down a side
    now = PART.mask() | loops_above | loops_beside
    alone = measure(now, SEEN_THEN)
    with_rise = measure(now, SEEN_THEN, risen=risen())
    assert with_rise.area_mm2 >= TWO_VIEWS_MM2
    assert with_rise.mask[:PART.y0 - RISE_PX - 2 * int(TOL) - 1].sum() == alone.mask[:PART.y0 - RISE_PX - 2 * int(TOL) - 1].sum()
    assert with_rise.mask[:, PART.x1 + int(TOL) + 1:].sum() == alone.mask[:, PART.x1 + int(TOL) + 1:].sum() > 0


def test_a_strand_seen_beyond_the_alignment_bound_lifts_nothing():
    strand_then = Box(150, 10, 154, PART.y0 + RISE_PX).mask()               # far above the outline then
    band = risen(SEEN_THEN | strand_then)
    # in the strand's columns the risen top is the part's, not the strand's
    top = PART.y0 + RISE_PX
    reach_top = PART.y0 + LOW_PX + RISE_PX - int(REACH)
    assert not band[:reach_top - RISE_PX - 2 * int(TOL) - 1, 150:154].any()
    assert band[top - RISE_PX, 150:154].all()


def test_no_look_before_or_no_rise_lifts_nothing():
    assert not risen(np.zeros((H, W), bool)).any()
    assert not risen_top(SEEN_THEN, OUTLINE_NOW, np.zeros((H, W), bool), REACH, TOL).any()


def test_a_lower_top_beside_the_outline_lifts_nothing():
    # beside the outline then (within its tolerance) the camera saw only the part's foot: no top of the part there
    foot = Box(PART.x1, PART.y1 - 6, PART.x1 + 2, PART.y1).mask()
    band = risen(SEEN_THEN | foot)
    assert not band[:PART.y1 - 6 - 2, PART.x1 + 2:PART.x1 + 3].any()


def test_the_bed_marks_zone_keeps_its_blobs():
    # a short part's top and its shifted band lie in the bed-marks zone together: the zone's blobs are not taken away
    now = PART.mask()
    marks = np.zeros((H, W), bool)
    marks[:PART.y0 + LOW_PX, :] = True
    alone = measure(now, SEEN_THEN, marks=marks)
    assert alone.at_foot_mm2 > 0.0
    assert measure(now, SEEN_THEN, marks=marks, risen=risen()).at_foot_mm2 == alone.at_foot_mm2
