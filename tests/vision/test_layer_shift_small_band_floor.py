"""One view's confirming-pixel floor on a band whose move changes few pixels in all (seventeenth session, helper
c17): 150 px is out of reach for a small part, a far camera or a small move, so one view needs no more than
0.75 of every pixel the shift changes (decided or not), and never fewer than several directions need (60)."""
from octoprint_printwatch.core.layer_shift import (SHIFT_MIN_SUPPORT_ONE_VIEW_PX, band_shift, confirms_layer_shift,
                                                   estimate_layer_shift)

from .synthetic import Box
from .test_layer_shift import J_ONE

# a tier 40 px wide; its newest 10-px band printed 10 px (2 mm) sideways
TIER, BAND = Box(110, 110, 150, 170), Box(110, 100, 150, 110)
SHIFTED = TIER.mask() | BAND.moved(10, 0).mask()


def one_view(undecided=None):
    found = band_shift(SHIFTED, ~SHIFTED, TIER.mask(), BAND.mask(), 24, 12, 5, 2.0, undecided=undecided,
                       bed_to_image=J_ONE)
    return estimate_layer_shift({"cam": found})


def test_a_small_band_moved_in_full_view_is_confirmed_under_150_px():
    shift = one_view()
    assert shift.viewpoints == 1 and shift.confirmed > 0.95
    assert shift.support < SHIFT_MIN_SUPPORT_ONE_VIEW_PX and shift.swept == shift.moved
    assert confirms_layer_shift(shift, 1.5)


def test_a_small_band_whose_move_lands_partly_where_nothing_is_decided_is_not():
    # over half of the overhang in the brim / skirt zone: every decided pixel confirms, but those are 96 of the
    # 144 the move changes
    shift = one_view(undecided=Box(150, 95, 165, 106).mask())
    assert shift.confirmed > 0.95 and shift.moved < shift.swept
    assert shift.support < 0.75 * shift.swept
    assert not confirms_layer_shift(shift, 1.5)
