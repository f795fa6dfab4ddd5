"""The outline match that breaks the alignment's ties (shape_check.outline_candidate) on masks with a known answer."""
import numpy as np

from octoprint_printwatch.core.alignment import outline_candidate


def block(h=60, w=80, top=20, bottom=40, left=30, right=50):
    mask = np.zeros((h, w), bool)
    mask[top:bottom, left:right] = True
    return mask


def test_the_shift_that_puts_the_upper_outline_on_the_part_wins_over_one_onto_the_brim():
    expected = block()
    # the part stands 3 px right and 2 px higher than the model says, on a brim wider than the part
    observed = block(top=18, bottom=38, left=33, right=53)
    observed[34:42, 25:60] = True
    # every shift that keeps the expected block inside the observed material ties on overlap
    shifts = np.array([(dx, dy) for dx in range(-5, 6) for dy in range(-6, 7)])
    assert outline_candidate(observed, expected, shifts) == (3, -2)


def test_among_equal_outline_matches_the_smallest_move_wins():
    expected = block()
    observed = block(top=20, bottom=40, left=0, right=80)  # a flat top as wide as the frame: any dx fits
    assert outline_candidate(observed, expected, np.array([(4, 0), (-1, 0), (2, 0)])) == (-1, 0)


def test_a_shift_that_moves_the_outline_out_of_the_frame_is_not_chosen():
    expected = block(left=60, right=80)
    observed = block(left=60, right=80)
    # (30, 0) moves every expected column past the frame's edge: nothing to compare is the worst cost
    assert outline_candidate(observed, expected, np.array([(30, 0), (0, 1)])) == (0, 1)
    assert outline_candidate(observed, expected, None) is None
    assert outline_candidate(observed, expected, np.zeros((0, 2), int)) is None
