"""A layer shift along the only camera's line of sight lowers the top of the part in its image, which one view alone
cannot tell from a part standing lower than the model (the height null: a camera firing a layer late, a height
calibration error). A height error is the same at every check, though: a check before the onset that saw its top
where the model put it refutes it (cross-check seed 9 `035_layer_shift`: a black frustum on blue tape, one camera,
a 6.5-mm shift towards it; the top 8-15 px lower from the onset on, which "2.7 mm shorter" explained as well as the
shift, 663 against 665; the check before the onset read the top in place, 0 px)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import (band_shift, confirms_layer_shift, estimate_layer_shift,
                                                   with_history)
from octoprint_printwatch.core.verdict import layer_shift_of

from .frustum_scene import BAND, BEFORE, HEIGHT, J, MIN_DX, frustum


def view(observed: np.ndarray):
    return {"cam": band_shift(observed, ~observed, BEFORE, BAND, 24, 12, MIN_DX, 2.0, bed_to_image=J,
                              height_to_image=HEIGHT)}


IN_PLACE = view(BEFORE | BAND)
# 4 mm towards the camera (8 px down), 1.5 mm sideways (6 px): the moved band lies inside the older layers' outline,
# so all the camera sees is its top 8 px lower, as a part 2.7 mm shorter shows it
SHIFTED = view(BEFORE | frustum(80, 140, 30, dx=6, dy=8))
LOWER = view(BEFORE | frustum(88, 140, 38))      # a part standing lower, the band in place


def test_one_view_alone_cannot_tell_a_shift_towards_it_from_a_part_standing_lower():
    found = estimate_layer_shift(SHIFTED)
    assert found is not None and found.confirmed > 0.85 and found.support >= 150
    assert found.null_score > 0.5 * found.score
    assert not confirms_layer_shift(with_history(found, [(False, IN_PLACE)]), 1.5)


def test_a_check_that_saw_the_top_in_place_refutes_the_part_standing_lower():
    # (as CheckRunner reads it: the previous checks' band_shifts, oldest first, the first untested)
    found = layer_shift_of({}, [(False, IN_PLACE), (True, IN_PLACE), (True, IN_PLACE)], SHIFTED)
    assert found.null_score < 0.25 * found.score
    assert confirms_layer_shift(found, 1.5)


def test_a_part_standing_lower_at_the_checks_before_too_is_still_explained_by_the_null():
    found = layer_shift_of({}, [(False, LOWER), (True, LOWER), (True, LOWER)], SHIFTED)
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_one_earlier_reading_or_another_cameras_readings_do_not_refute_it():
    # one reading in place can be off itself (a top the colour of the bed); another camera's top in place says
    # nothing about this camera's own error (cross-check seed 8 `028_runout`: s1R alone, usable from one check on)
    once = layer_shift_of({}, [(False, {}), (True, IN_PLACE)], SHIFTED)
    assert once is None or not confirms_layer_shift(once, 1.5)
    elsewhere = {"other": IN_PLACE["cam"]}
    others = layer_shift_of({}, [(False, elsewhere), (True, elsewhere), (True, elsewhere)], SHIFTED)
    assert others is None or not confirms_layer_shift(others, 1.5)
