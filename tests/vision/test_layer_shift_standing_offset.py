"""A band offset one view reads at check after check is that view's standing offset, not layers that slid since:

* read at each of the last three checks and explained there no better than the part standing taller or lower (cross-check
  seed 21 `009_normal`: one view of a stack's tier from high above, 0.74, 0.85, 0.87, each under twice its null, then
  0.86 at twice the null at the fourth check);
* or read partly there (a quarter or more) at each of the last four checks, none of them clearly absent (cross-check
  seed 22 `003_normal`: 0.41, 0.52, 0.40, 0.42, then 0.82 at the last check).

A real shift has a check before its onset that reads it clearly absent, and one left unconfirmed over three checks for
other reasons than the null is still confirmed (the history's other rules are unchanged)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import LayerShift, confirms_layer_shift


def reading(share: float, null: float = 0.0, moved: int = 500) -> LayerShift:
    """One check's pooled reading of the shift: ``share`` of ``moved`` pixels confirm it, a tenth of that against."""
    support = int(round(share * moved))
    return LayerShift(shift_mm=np.array([3.0, 0.0]), support=support, against=support // 10, moved=moved,
                      cameras={"cam": (12, 0), "side": (0, 8)}, null_score=null, viewpoints=2, moved_sure=moved,
                      swept=moved)


def now_with(before: list) -> LayerShift:
    """This check: confirmed at one check (0.86 from two directions, the null beaten), with ``before`` newest first."""
    shift = reading(0.86)
    shift.before = before
    return shift


def test_an_offset_the_null_held_for_three_checks_is_no_new_shift():
    held = [reading(0.87, null=250.0), reading(0.85, null=230.0), reading(0.74, null=250.0), reading(0.0)]
    assert all(e.score < 2.0 * e.null_score for e in held[:3])
    assert not confirms_layer_shift(now_with(held), 1.5)


def test_a_shift_read_but_not_confirmed_for_three_checks_is_still_confirmed_where_no_height_explained_it():
    # (held back by other guards: the same readings, with no height error that explains them)
    unexplained = [reading(0.87), reading(0.85), reading(0.74), reading(0.0)]
    assert confirms_layer_shift(now_with(unexplained), 1.5)
    # and held by the null at two checks only: the third (the onset's) read it beyond any height error
    assert confirms_layer_shift(now_with([reading(0.87, null=250.0), reading(0.85, null=230.0), reading(0.74),
                                          reading(0.0)]), 1.5)


def test_an_offset_half_there_at_four_checks_is_no_new_shift():
    assert not confirms_layer_shift(now_with([reading(0.42), reading(0.52), reading(0.40), reading(0.41)]), 1.5)


def test_a_shift_with_a_check_that_read_it_clearly_absent_is_confirmed():
    assert confirms_layer_shift(now_with([reading(0.42), reading(0.52), reading(0.40), reading(0.05)]), 1.5)
    assert confirms_layer_shift(now_with([reading(0.42), reading(0.52), reading(0.40), None]), 1.5)
    # three checks of history only: nothing says it was there before them
    assert confirms_layer_shift(now_with([reading(0.42), reading(0.52), reading(0.40)]), 1.5)
