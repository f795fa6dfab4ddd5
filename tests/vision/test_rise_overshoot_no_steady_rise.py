"""A reading of the rise of 150 % or more is no sign that the part rises as its model says (verdict.visibly_rising,
``steadily``): no part rises faster than its model, so its top jumped in the picture. Where every view misses a
third of the part, such readings must not explain the missing material away as faces the cameras cannot tell.

What a user would notice: a detached part left printing. Cross-check seed 43 ``033_detach`` (a dark grey frame 28 mm
tall on a dark bed, four 640x480 cameras, two kept here): at layer 97 the frame tipped 71 degrees and slid 26 mm, and
stood up on its edge. At layer 100 both views miss 35 % of the part (13 % and none at layer 75), while their
upper outlines read 200 % and 52 % of the expected rise: the median, 126 %, said "rising as the model says", so the
missing material was taken for faces of the dark part that the cameras cannot tell from the dark bed, and the print
went on to its end.
"""
from __future__ import annotations

from pathlib import Path

from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import RISE_OVERSHOOT_PCT, visibly_rising, visibly_rising_finely

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "frame_standing_up_dark"


def test_a_part_standing_up_whose_top_jumps_is_paused_for_its_missing_material():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results] == ["ok", "ok", "ok", "fail"]
    last = results[-1]
    assert max(v.growth_pct for v in last.shape.values()) >= RISE_OVERSHOOT_PCT
    assert sum("material missing" in reason for reason in last.reasons) == 2


def view(name: str, growth: float | None, coarse: float | None = None) -> ShapeResult:
    return ShapeResult(name, 30.0, 30.0, 30.0, 0.0, 30.0, 30.0, 500, 5000, growth, (0, 0), 7.0, 50.0,
                       passed=False, usable=True, reasons=[], coarse_growth_pct=coarse)


def test_a_reading_over_the_models_rise_counts_as_none_only_when_asked():
    views = {"a": view("a", 200.0), "b": view("b", 52.0)}
    assert visibly_rising_finely(views) and visibly_rising(views)
    assert not visibly_rising_finely(views, steadily=True)
    assert not visibly_rising(views, steadily=True)
    # steady readings still say the part rises
    steady = {"a": view("a", 100.0), "b": view("b", 90.0)}
    assert visibly_rising_finely(steady, steadily=True)
    # ... and so do readings to the pixel of a part seen small, where none is an overshoot
    small = {"a": view("a", None, coarse=100.0), "b": view("b", None, coarse=75.0)}
    assert visibly_rising(small, steadily=True)
    assert not visibly_rising({"a": view("a", None, coarse=200.0), "b": view("b", None, coarse=25.0)},
                              steadily=True)
