"""One view of new material while a part seen small rose under half, read coarsely (verdict.rise_for_loose_material).

Cross-check seed 8 ``053_detach``: a 9.8-mm box (about 20 px wide at 640x480) is knocked 27 mm away; the nozzle
keeps extruding where it stood, and that pile covers the small outline's core, so nothing reads missing at the
onset. Its rise is 4-6 px per check, too little for the fine growth reading: both views give only a coarse one
(25 % and 10 %). One view sees 18.6 mm² of strands beyond the outline. The slowed-part clause of the loose-material
rule needs a rise reading as its second witness; the coarse readings now stand in where too few views read finely.
"""
from dataclasses import replace

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.tangle import NewMaterial


def view(name, coarse, new_mm2=0.0, growth=None):
    """A passing view with no fine growth reading, a coarse one, and its new material (decide's inputs)."""
    return ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 300, 360, growth, (0, 0), 7.0, 50.0, passed=True,
                       usable=True, reasons=[], new_outside=NewMaterial(new_mm2, 0, 0), coarse_growth_pct=coarse)


def test_coarse_readings_stand_in_for_the_rise_when_no_view_reads_it_finely():
    s = DetectionSettings()
    views = {"s0L": view("s0L", 25.0, new_mm2=18.6), "s0R": view("s0R", 10.0)}
    verdict, reasons = decide(views, {}, s)
    assert verdict == "fail" and any("material appeared around the part" in r and "rose 18%" in r for r in reasons)
    # the same material on a part that keeps rising (coarsely read): one view, no pause
    assert decide({c: replace(r, coarse_growth_pct=100.0) for c, r in views.items()}, {}, s)[0] == "ok"
    # a coarse slow rise without new material is not this rule's
    assert decide({c: replace(r, new_outside=NewMaterial(0.0, 0, 0)) for c, r in views.items()}, {}, s)[0] == "ok"
    # not where a top surface closes
    assert decide(views, {}, s, top_closing=True)[0] == "ok"
    # one coarse reading of two views is no median
    assert decide({**views, "s0R": replace(views["s0R"], coarse_growth_pct=None)}, {}, s)[0] == "ok"


def test_fine_readings_come_first_and_mix_with_coarse_ones_where_too_few():
    from octoprint_printwatch.core.verdict import rise_for_loose_material
    two_fine = {"a": view("a", None, growth=100.0), "b": view("b", None, growth=90.0), "c": view("c", 0.0)}
    assert rise_for_loose_material(two_fine, [100.0, 90.0]) == 95.0          # as before: the fine median
    one_fine = {"a": view("a", None, growth=100.0), "b": view("b", 50.0), "c": view("c", 20.0)}
    assert rise_for_loose_material(one_fine, [100.0]) == 50.0                # each view's fine, else coarse
    assert rise_for_loose_material({"a": view("a", 30.0)}, []) == 30.0       # one-camera rig: its own reading
    assert rise_for_loose_material({"a": view("a", None), "b": view("b", -40.0)}, []) is None   # sunk: left out
