"""An offset one view reads partly, never clearly, at the two checks before the previous one grew into view with the
part: an outline laid a few px beside the part (a first look on a brim of the part's colour) shows only as the part
rises out of the brim and the bed-marks zone that hide the offset, more at each check (cross-check seed 27
`029_detach` s0: 0.44, 0.46, 0.85, then 0.94 before any failure). Layers that slid are a step in time: clearly absent
before the onset, fully there after it; only the onset check's band reads them partly."""
import numpy as np

from octoprint_printwatch.core.layer_shift import LayerShift, confirms_layer_shift, was_there_before


def reading(share: float, moved: int = 120) -> LayerShift:
    """One check's pooled reading of the shift from one view: ``share`` of ``moved`` pixels confirm it, all of them
    material sticking out."""
    support = int(round(share * moved))
    return LayerShift(shift_mm=np.array([-0.25, 2.25]), support=support, against=support // 25, moved=moved,
                      cameras={"cam": (4, -3)}, viewpoints=1, overhang=support, moved_sure=moved, swept=moved)


def now_with(before: list) -> LayerShift:
    """This check: 0.94 of 120 px from one view (a small band's floor: 75 % of it and 60 px), ``before`` newest
    first."""
    shift = reading(0.94)
    shift.before = before
    return shift


def test_an_offset_read_partly_at_the_two_checks_before_the_previous_is_no_new_shift():
    grown = now_with([reading(0.85), reading(0.46), reading(0.44), reading(0.0)])
    assert was_there_before(grown)
    assert not confirms_layer_shift(grown, 1.5)


def test_a_shift_absent_before_its_onset_is_still_confirmed():
    # the onset check's band reads it partly (the previous check's, or the one before it), the checks before it
    # clearly absent
    assert confirms_layer_shift(now_with([reading(0.46), reading(0.05), reading(0.0), reading(0.0)]), 1.5)
    assert confirms_layer_shift(now_with([reading(0.85), reading(0.46), reading(0.05), reading(0.0)]), 1.5)
    # one partial reading two checks back, and nothing read before it, is no growth over checks
    assert confirms_layer_shift(now_with([reading(0.85), reading(0.46), None]), 1.5)
    # read clearly at those checks: the rules for an offset there all along decide (three of four, not two)
    assert confirms_layer_shift(now_with([reading(0.85), reading(0.55), reading(0.44), reading(0.0)]), 1.5)
