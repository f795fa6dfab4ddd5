"""A layer shift in the first tested band has no tested check before it to refute "the part stands taller / lower"
(the height null). The print's first check has read the height, though: its band is the whole part, so its null reads
the whole part's top against the outline aligned on all of it, and a height error would show there from the first
layer on (cross-check seed 14 `043_layer_shift`: a cone whose top moved along s0's line of sight at check 1; "1.4 mm
taller" scored 788 against the shift's 549, while the first check read that height at -626)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import confirms_layer_shift
from octoprint_printwatch.core.pipeline import layer_shift_of

from .test_layer_shift_height_history import IN_PLACE, LOWER, SHIFTED


def test_the_first_check_that_saw_the_top_in_place_refutes_the_height_alone():
    found = layer_shift_of({}, [(False, IN_PLACE)], SHIFTED)
    assert found is not None and found.null_score < 0.25 * found.score
    assert confirms_layer_shift(found, 1.5)


def test_a_part_standing_lower_at_the_first_check_too_is_still_explained_by_the_null():
    found = layer_shift_of({}, [(False, LOWER)], SHIFTED)
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_one_tested_reading_still_does_not_refute_it():
    # (a band's top can be misread once: the first check stands apart only because its band is the whole part)
    found = layer_shift_of({}, [(True, IN_PLACE)], SHIFTED)
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_the_first_check_counts_only_while_it_is_one_of_the_last_four():
    # (a height error that grows with the part, a calibration scale error, is small at the first check)
    lower = [(True, LOWER)] * 4
    found = layer_shift_of({}, [(False, IN_PLACE), *lower], SHIFTED)
    assert found is None or not confirms_layer_shift(found, 1.5)
