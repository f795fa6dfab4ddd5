"""A layer shift in the first tested band has no tested check before it to refute "the part stands taller" (the
height null). The print's first check has read the height, though: its band is the whole part, so its null reads the
whole part's top against the outline aligned on all of it, and a height error would show there from the first layer on
(cross-check seed 14 `043_layer_shift`: a cone whose top moved along s0's line of sight at check 1; "1.4 mm taller"
scored 788 against the shift's 549, while the first check read that height at -626). Only a taller part: one reading
of a top in the bed's colour is read in place and lower later (cross-check seed 10 `054_spaghetti`), so a shorter part
still needs two readings."""
from octoprint_printwatch.core.layer_shift import confirms_layer_shift
from octoprint_printwatch.core.verdict import layer_shift_of

from .frustum_scene import BEFORE, frustum
from .test_layer_shift_height_history import IN_PLACE, LOWER, SHIFTED, view

# 4 mm away from the camera (8 px up), 1.5 mm sideways (6 px): the band's top sticks out 8 px above the expected top,
# as a part 2.7 mm taller shows it
AWAY = view(BEFORE | frustum(80, 140, 30, dx=6, dy=-8))
TALLER = view(BEFORE | frustum(72, 140, 38))      # a part standing taller, the band in place


def test_one_view_alone_cannot_tell_a_shift_away_from_it_from_a_part_standing_taller():
    found = layer_shift_of({}, [], AWAY)
    assert found is not None and found.null_score > 0.5 * found.score
    assert not confirms_layer_shift(found, 1.5)


def test_the_first_check_that_saw_the_top_in_place_refutes_a_taller_part_alone():
    found = layer_shift_of({}, [(False, IN_PLACE)], AWAY)
    assert found is not None and found.null_score < 0.25 * found.score
    assert confirms_layer_shift(found, 1.5)


def test_a_part_standing_taller_at_the_first_check_too_is_still_explained_by_the_null():
    found = layer_shift_of({}, [(False, TALLER)], AWAY)
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_the_first_check_alone_does_not_refute_a_shorter_part():
    # (a top in the bed's colour is read in place once and lower later: a shorter part needs two readings)
    found = layer_shift_of({}, [(False, IN_PLACE)], SHIFTED)
    assert found is None or not confirms_layer_shift(found, 1.5)
    lower = layer_shift_of({}, [(False, LOWER)], SHIFTED)
    assert lower is None or not confirms_layer_shift(lower, 1.5)


def test_one_tested_reading_still_does_not_refute_it():
    found = layer_shift_of({}, [(True, IN_PLACE)], AWAY)
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_the_first_check_counts_only_while_it_is_one_of_the_last_four():
    # (a height error that grows with the part, a calibration scale error, is small at the first check)
    found = layer_shift_of({}, [(False, IN_PLACE), *[(True, TALLER)] * 4], AWAY)
    assert found is None or not confirms_layer_shift(found, 1.5)
