"""A layer shift new since the previous check, seen from one direction (sixteenth session, helper d16): one view's
higher share (0.85) guards against an offset that was there all along, which "new" already rules out, so a new shift
is confirmed at the share several directions need (0.75 of the decided pixels) from one direction too."""
from octoprint_printwatch.core.layer_shift import (confirms_layer_shift, describe_layer_shift, estimate_layer_shift,
                                                   is_new, with_history)

from .synthetic import Box
from .test_layer_shift import BASE, J_ONE, checks, in_place, partly_hidden_shift, view


def test_a_new_shift_from_one_direction_is_confirmed_at_the_share_several_directions_need():
    # 2 mm sideways, a fifth of what the move changes undecided: 0.78 of one view, the check before saw it in place
    now = with_history(estimate_layer_shift(partly_hidden_shift()), checks(in_place(), in_place()))
    assert now.viewpoints == 1 and 0.75 <= now.confirmed_sure < 0.85 and is_new(now)
    assert confirms_layer_shift(now, 1.5)
    assert "new since the previous check" in describe_layer_shift(now)


def test_the_same_reading_not_known_to_be_new_still_needs_one_views_share():
    shifted = partly_hidden_shift()
    # there at the check before too: a calibration residual or an alignment slip reads the same
    there_before = with_history(estimate_layer_shift(shifted), checks(shifted, shifted))
    assert not is_new(there_before) and not confirms_layer_shift(there_before, 1.5)
    # the first check that tested its band: nothing known from before
    first = with_history(estimate_layer_shift(shifted), checks(shifted, first_tested=False))
    assert not confirms_layer_shift(first, 1.5)


def test_a_new_shift_of_a_few_pixels_from_one_direction_is_not_confirmed():
    # a 4-px band moved 10 px: all of its decided pixels, new, but 32 confirming px: under the 60 any reading needs
    base, band = Box(110, 110, 210, 170), Box(110, 106, 150, 110)

    def one(observed, hidden=None):
        hidden = Box(0, 0, 1, 1).mask() if hidden is None else hidden
        return {"cam": view(observed & ~hidden, bed=~observed & ~hidden, before=base.mask(), band=band.mask(),
                            J=J_ONE)}

    in_place_views = one(base.mask() | band.mask())
    small = with_history(estimate_layer_shift(one(base.mask() | band.moved(10, 0).mask())),
                         checks(in_place_views, in_place_views))
    assert is_new(small) and small.support < 150
    assert not confirms_layer_shift(small, 1.5)
