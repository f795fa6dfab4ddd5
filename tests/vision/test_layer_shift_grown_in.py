"""A layer shift that grows in over the check whose band it began in (twentieth session, helper b20): that check's
band holds a few shifted layers on top of many in place, so it reads the shift only in part, neither clearly not there
(a new shift, confirmed at one check) nor as clearly as a shift seen at two checks needs. Where the check before it read
the shift clearly not there, one view's share at the next check is that of several directions (0.75), with the
overhang a new shift makes on one side only."""
from octoprint_printwatch.core.layer_shift import (confirms_layer_shift, describe_layer_shift, estimate_layer_shift,
                                                   is_new, persists, with_history)

from .synthetic import Box
from .test_layer_shift import BASE, BAND, J_ONE, checks, in_place, partly_hidden_shift, view


def partly_shifted():
    """One view of the check the shift began in: the top 60 % of its band printed 10 px sideways, the rest in place."""
    top = Box(BAND.x0, BAND.y0, BAND.x1, BAND.y0 + 18)
    rest = Box(BAND.x0, top.y1, BAND.x1, BAND.y1)
    return {"cam": view(BASE.mask() | rest.mask() | top.moved(10, 0).mask(), J=J_ONE)}


def narrower():
    """One view reading bed just inside the expected outline on one side (a part a little narrower than the model)."""
    return {"cam": view(BASE.mask() | Box(BAND.x0 + 10, BAND.y0, BAND.x1, BAND.y1).mask(), J=J_ONE)}


def test_a_shift_grown_in_over_the_previous_check_is_confirmed_from_one_direction():
    now = with_history(estimate_layer_shift(partly_hidden_shift()), checks(in_place(), partly_shifted()))
    assert now.viewpoints == 1 and 0.75 <= now.confirmed < 0.85
    assert 0.5 <= now.previous.confirmed_sure and now.previous.confirmed < 0.70     # in part: not new, not persisting
    assert not is_new(now) and not persists(now, 1.5)
    assert confirms_layer_shift(now, 1.5)
    assert "new since the check before the previous one" in describe_layer_shift(now)


def test_a_reading_there_two_checks_ago_too_or_without_overhang_is_not_confirmed():
    # the check before the previous one read it in part too: nothing shows it new
    there = with_history(estimate_layer_shift(partly_hidden_shift()), checks(partly_shifted(), partly_shifted()))
    assert not confirms_layer_shift(there, 1.5)
    # bed inside the outline alone (no material sticking out): a part a little narrower than the model
    inside = with_history(estimate_layer_shift(narrower()), checks(in_place(), partly_shifted()))
    assert inside.overhang < 0.25 * max(inside.support, 1)
    assert not confirms_layer_shift(inside, 1.5)
