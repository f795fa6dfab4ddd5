"""A layer shift of a part seen small: each check's band gives fewer confirming pixels than one view's floor
(SHIFT_MIN_SUPPORT_ONE_VIEW_PX) however clear the shift, but the shift persists, and two checks' bands together
are enough evidence (cross-check seed 10 `023`: a stack's 16-px-wide top tier, 82 then 124 confirming px)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import (SHIFT_MIN_SUPPORT_ONE_VIEW_PX, band_shift, confirms_layer_shift,
                                                   estimate_layer_shift, with_history)

from .synthetic import Box

# one camera seeing printer X sideways at 5 px/mm: a 10-px move of the band is a 2-mm layer shift
J_ONE = [[5.0, 0.0], [0.0, -2.0]]
TIER = Box(150, 110, 180, 170)      # a narrow top tier up to the previous check, 30 px wide


def one_camera(band_px: int, dx: int) -> dict:
    """The camera's evidence at a check whose band (``band_px`` tall) was printed ``dx`` px sideways."""
    band = Box(TIER.x0, TIER.y0 - band_px, TIER.x1, TIER.y0)
    observed = TIER.mask() | band.moved(dx, 0).mask()
    return {"cam": band_shift(observed, ~observed, TIER.mask(), band.mask(), 24, 12, 8, 2.0, bed_to_image=J_ONE)}


def checks(*views):
    """with_history's history: the checks before this one, oldest first, each testing its own band"""
    return [(True, v) for v in views]


def test_a_small_parts_shift_seen_at_two_checks_is_confirmed_by_their_evidence_together():
    now = estimate_layer_shift(one_camera(8, 10))
    assert np.allclose(now.shift_mm, [2.0, 0.0], atol=0.3) and now.viewpoints == 1
    assert now.confirmed > 0.9 and now.support < SHIFT_MIN_SUPPORT_ONE_VIEW_PX
    assert not confirms_layer_shift(with_history(now, checks(one_camera(8, 0), one_camera(8, 0))), 1.5)  # once
    twice = with_history(now, checks(one_camera(8, 0), one_camera(8, 10)))
    assert twice.support + twice.previous.support >= SHIFT_MIN_SUPPORT_ONE_VIEW_PX
    assert confirms_layer_shift(twice, 1.5)


def test_two_checks_whose_evidence_together_is_under_the_floor_are_not_enough():
    # bands of 4 px: under half the floor each
    twice = with_history(estimate_layer_shift(one_camera(4, 10)), checks(one_camera(4, 0), one_camera(4, 10)))
    assert twice.support + twice.previous.support < SHIFT_MIN_SUPPORT_ONE_VIEW_PX
    assert not confirms_layer_shift(twice, 1.5)


def test_a_small_parts_offset_there_before_is_still_no_shift():
    # the check before the two read the same offset: not new (a calibration residual, an alignment slip)
    always = with_history(estimate_layer_shift(one_camera(8, 10)), checks(one_camera(8, 10), one_camera(8, 10)))
    assert not confirms_layer_shift(always, 1.5)
