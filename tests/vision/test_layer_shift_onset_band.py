"""A layer shift seen at two checks whose first check's band straddles the onset (fifteenth session, helper d15):
the layers printed in place below the onset contradict the shift there, and the blurred rim along the moved band's
outline is no evidence either way, at two checks as at one."""
from octoprint_printwatch.core.layer_shift import (confirms_layer_shift, describe_layer_shift, estimate_layer_shift,
                                                   with_history)

from .synthetic import Box
from .test_layer_shift import BAND, BASE, J_ONE, blurred, checks, in_place, partly_hidden_shift, view


def straddling(dx, in_place_rows, rim=0):
    """One camera's evidence at the check whose band the shift began in: its lowest ``in_place_rows`` rows printed in
    place, the rest ``dx`` px sideways (every outline ``rim`` px soft)."""
    lower = Box(BAND.x0, BAND.y1 - in_place_rows, BAND.x1, BAND.y1)
    upper = Box(BAND.x0, BAND.y0, BAND.x1, BAND.y1 - in_place_rows).moved(dx, 0)
    return seen(BASE.mask() | lower.mask() | upper.mask(), rim)


def seen(observed, rim):
    observed, bed = blurred(observed, rim) if rim else (observed, ~observed)
    return {"cam": view(observed, bed=bed, J=J_ONE)}


def test_a_shift_whose_onset_check_shows_the_layers_below_it_in_place_is_confirmed_at_the_next_check():
    # now 0.8 of one view (under 0.85); the onset check 0.72 with 96 px against of 252 confirming (the 8 rows in place)
    onset = straddling(10, 8)
    now = with_history(estimate_layer_shift(partly_hidden_shift()), checks(in_place(), onset))
    assert 0.70 <= now.confirmed < 0.85 and now.against <= 0.25 * now.support
    assert now.previous.confirmed >= 0.70 and now.previous.against > 0.25 * now.previous.support
    assert confirms_layer_shift(now, 1.5)


def test_a_shift_through_a_blurred_outline_seen_at_two_checks_is_confirmed_over_the_decided_pixels():
    # every outline 3 px soft: plainly 0.79 now and 0.68 at the onset check, over the decided pixels 0.90 and 0.78
    in_place_soft = seen(BASE.mask() | BAND.mask(), 3)
    now = with_history(estimate_layer_shift(seen(BASE.mask() | BAND.moved(10, 0).mask(), 3)),
                       checks(in_place_soft, straddling(10, 4, rim=3)))
    assert now.confirmed < 0.85 and now.previous.confirmed < 0.70 <= now.previous.confirmed_sure
    assert confirms_layer_shift(now, 1.5)
    assert "of the clear evidence, and 78% at the previous check" in describe_layer_shift(now)


def test_an_offset_the_check_before_them_showed_too_is_not_confirmed_over_the_decided_pixels():
    shifted = seen(BASE.mask() | BAND.moved(10, 0).mask(), 3)
    there_before = with_history(estimate_layer_shift(shifted), checks(shifted, shifted))
    assert not confirms_layer_shift(there_before, 1.5)
    # and one check alone (the one before it saw the band in place) is not two
    once = with_history(estimate_layer_shift(shifted), checks(seen(BASE.mask() | BAND.mask(), 3),
                                                              seen(BASE.mask() | BAND.mask(), 3)))
    assert once.confirmed < 0.85
    # (new since the previous check: confirmed over the decided pixels at one check, as before this session)
    assert confirms_layer_shift(once, 1.5)
