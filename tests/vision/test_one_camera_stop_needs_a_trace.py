"""A one-camera rig's one reading of no rise after readings of a rise, with nothing missing (verdict.part_stalled, the
"held a rise" path of the stall rule): the stopped view shows the stop itself, a trace missing or its band's top read
lowered (verdict.stop_witnessed), as the rule for views that read a stop with nothing missing already asks where fewer
views are usable than it needs (verdict.stopped_views_needed).

What a user would notice: a normal print on a one-camera printer paused as "the part has not grown as expected since
the previous check: 0% of the expected rise seen (median of 1 camera(s))" while nothing of the part was missing.
Cross-check seed 30 ``007_normal`` (an orange ring on gold PEI, one camera): s0 read the rise at 100 % for nine checks,
0 % at check 10 with 0.0 % of the part and of its newest band missing, then 200 % at check 11: its top read one check
late; seed 34 ``003_normal`` (a translucent blue stack on kapton, one camera) the same at its check 11. A second view
would have outvoted it; with one camera, only missing layers tell a stop from that pixel step.
A stop with a trace missing, and two views reading it, stall as before."""
from __future__ import annotations

from dataclasses import replace

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide


def view(name: str, *, missing: float = 0.0, band_missing: float = 0.0, growth: float | None = 0.0) -> ShapeResult:
    failed = missing > 7.0 or band_missing > 50.0
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth, (0, 0),
                       7.0, 50.0, passed=not failed, usable=True, reasons=[f"{name}: material missing"] if failed else [])


def test_one_cameras_reading_of_no_rise_with_nothing_missing_is_no_stall():
    s = DetectionSettings()
    held = {"s0": 100.0}
    # seed 30 ``007_normal`` check 10
    assert decide({"s0": view("s0")}, {}, s, held_rise_before=held)[0] == "ok"
    # a trace of the part missing (1 %) or of its newest band (2 %) is the stop showing: as before
    assert decide({"s0": view("s0", missing=1.5)}, {}, s, held_rise_before=held)[0] == "fail"
    assert decide({"s0": view("s0", band_missing=3.0)}, {}, s, held_rise_before=held)[0] == "fail"
    # half the threshold missing corroborates any reading of no rise, held or not: as before
    assert decide({"s0": view("s0", missing=4.0)}, {}, s)[0] == "fail"


def test_two_views_reading_no_rise_after_a_held_rise_still_stall_with_nothing_missing():
    s = DetectionSettings()
    views = {"a": view("a"), "b": view("b")}
    assert decide(views, {}, s, held_rise_before={"a": 100.0, "b": 100.0})[0] == "fail"
    # one of them reading a rise: no stall
    assert decide({**views, "b": replace(views["b"], growth_pct=100.0)}, {}, s,
                  held_rise_before={"a": 100.0, "b": 100.0})[0] == "ok"
