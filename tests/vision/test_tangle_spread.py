"""Strands spread around the foot of a part that slowed (core/tangle.loose_material, ``spreading``).

Strands falling from a stopped top spread over the bed around the part's foot, while the pile on the top lifts
the outline a little: the part reads slowed, not stopped. One view seeing SPREAD_MM2 of new material spread over
a quarter of the circle around the part or more corroborates a rise under SPREAD_SLOWED_RISE_PCT; less material,
a narrower arc or a part rising as its model does not pause.
"""
from dataclasses import replace

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.tangle import (SLOWED_RISE_PCT, SPREAD_MM2, SPREAD_SLOWED_RISE_PCT, loose_material)
from octoprint_printwatch.core.verdict import decide

from .synthetic import PART
from .test_tangle import measure
from .test_tangle_around import MARKS, strands_around
from .test_tangle_slowed import figures


def test_strands_on_two_sides_of_the_foot_spread_around_the_part_one_strand_does_not():
    two_sides = measure(PART.mask() | strands_around(["right", "bottom"]), PART.mask(), marks=MARKS)
    assert two_sides.at_foot_mm2 > 0 and two_sides.spreads_around and not two_sides.surrounds_part
    one_side = measure(PART.mask() | strands_around(["right"]), PART.mask(), marks=MARKS)
    assert not one_side.spreads_around


def test_one_view_of_strands_spread_around_the_foot_counts_while_the_part_slowed_somewhat():
    foot = {"a": SPREAD_MM2 + 1}
    slowed_somewhat = (SLOWED_RISE_PCT + SPREAD_SLOWED_RISE_PCT) / 2          # 62 %: not under half
    reason = loose_material({"a": 0.0}, with_foot=foot, rise_pct=slowed_somewhat, spreading={"a"})
    assert reason is not None and "a 16 mm²" in reason and "quarter of the circle around the part" in reason
    assert f"rose {slowed_somewhat:.0f}%" in reason
    # the part rising as its model says (or no rise read): one view of them does not pause
    assert loose_material({"a": 0.0}, with_foot=foot, rise_pct=SPREAD_SLOWED_RISE_PCT, spreading={"a"}) is None
    assert loose_material({"a": 0.0}, with_foot=foot, rise_pct=None, spreading={"a"}) is None
    # on one side of the part only (a cast shadow, a glare line): the half-rise rule as before
    assert loose_material({"a": 0.0}, with_foot=foot, rise_pct=slowed_somewhat) is None
    # too little of it
    assert loose_material({"a": 0.0}, with_foot={"a": SPREAD_MM2 - 1}, rise_pct=slowed_somewhat,
                          spreading={"a"}) is None
    # another view measured new material and saw none of it: one view's artefact (a skirt line drawn into its mask)
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot={"a": SPREAD_MM2 + 1, "b": 0.0}, rise_pct=slowed_somewhat,
                          spreading={"a"}) is None
    # under half the rise the old rule holds, and says nothing of an arc
    stopped = loose_material({"a": 0.0}, with_foot=foot, rise_pct=SLOWED_RISE_PCT - 10, spreading={"a"})
    assert stopped is not None and "quarter" not in stopped


def test_decide_pauses_a_one_camera_rig_on_strands_spread_around_a_slowed_part():
    s = DetectionSettings()
    # seed-35-like figures (``058_spaghetti``'s check after its onset): one camera, 21.6 mm² at the foot over 90°,
    # its outline rising 67 % of the expected height
    view = figures("s0", 67.0, at_foot_mm2=21.6)
    view = replace(view, new_outside=replace(view.new_outside, direction=0.0, arc_deg=90.0))
    verdict, reasons = decide({"s0": view}, {}, s)
    assert verdict == "fail" and any("quarter of the circle around the part" in r for r in reasons)
    # the same strands while the part rises as its model says: a normal print's nuisance, no pause
    assert decide({"s0": replace(view, growth_pct=100.0)}, {}, s)[0] == "ok"
    # on one side of the part only
    narrow = replace(view, new_outside=replace(view.new_outside, arc_deg=45.0))
    assert decide({"s0": narrow}, {}, s)[0] == "ok"


def test_where_no_view_reads_one_checks_rise_the_readings_over_a_span_stand_in():
    s = DetectionSettings()
    # seed-27-like figures (``046_spaghetti`` at its onset check): one camera seen small, no reading of one check's
    # rise, 71 % over its span of checks, 27.6 mm² at the foot over 135°
    view = figures("s0", None, at_foot_mm2=27.6)
    view = replace(view, span_growth_pct=71.4, growth_span=3,
                   new_outside=replace(view.new_outside, direction=0.0, arc_deg=135.0))
    verdict, reasons = decide({"s0": view}, {}, s)
    assert verdict == "fail" and any("rose 71% of the expected height over the last checks" in r for r in reasons)
    # rising over the span as its model says: no pause
    assert decide({"s0": replace(view, span_growth_pct=100.0)}, {}, s)[0] == "ok"
    # a view reading one check's rise to the pixel is read first, and it rose
    assert decide({"s0": replace(view, coarse_growth_pct=100.0)}, {}, s)[0] == "ok"
