"""One view's fine reading of no rise is no stall where two other views read, over their spans of checks, more rise
than a part stopped since the previous check can show (verdict.rising_over_spans).

What a user would notice: a normal print paused near its end. Cross-check seed 47 ``004_normal`` (a red tower 56 mm
tall tapering to its top, three 640x480 cameras, a normal print): at layer 256 s1 read the newest band's top as the
mauve wall behind it (its readings at layers 240-264: 100, 43, 0, 157 %), and its band as part-coloured over 35 % of
its area. s0L and s0R, seeing the tower small, read the rise only over three checks: 100 % and 86 %, where a part
stopped since layer 248 shows at most 67 %. One view's 0 % made the median, and the print was paused for a runout.
"""
from __future__ import annotations

from pathlib import Path

from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import rising_over_spans

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "tower_top_read_as_background"


def test_two_views_reading_the_rise_over_their_spans_outvote_one_view_reading_none():
    results = run_checks(RECORDING)
    assert all(r.verdict == "ok" for r in results), [(r.layer, r.reasons) for r in results if r.verdict != "ok"]
    last = results[-1].shape
    assert last["s1"].growth_pct is not None and last["s1"].growth_pct < 17.0
    assert rising_over_spans(last)


def view(name: str, span_growth: float | None, span: int | None, growth: float | None = None,
         passed: bool = True) -> ShapeResult:
    return ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, growth, (0, 0), 7.0, 50.0, passed=passed,
                       usable=True, reasons=[], span_growth_pct=span_growth, growth_span=span)


def test_only_readings_a_stop_cannot_give_outvote():
    one_stalled = {"s1": view("s1", None, 1, growth=0.0)}
    # over three checks a part stopped since the previous one rose at most two thirds of the expected
    assert rising_over_spans({**one_stalled, "a": view("a", 100.0, 3), "b": view("b", 86.0, 3)})
    assert not rising_over_spans({**one_stalled, "a": view("a", 100.0, 3), "b": view("b", 71.0, 3)})
    # over two checks, half
    assert rising_over_spans({**one_stalled, "a": view("a", 100.0, 2), "b": view("b", 83.0, 2)})
    assert not rising_over_spans({**one_stalled, "a": view("a", 100.0, 2), "b": view("b", 60.0, 2)})
    # a top that jumped in the picture reads no steady rise; one view is no majority
    assert not rising_over_spans({**one_stalled, "a": view("a", 100.0, 3), "b": view("b", 183.0, 3)})
    assert not rising_over_spans({**one_stalled, "a": view("a", 100.0, 3)})
    # a view seeing material where the model has none reads the top of that, not the part's
    assert not rising_over_spans({**one_stalled, "a": view("a", 100.0, 3), "b": view("b", 100.0, 2, passed=False)})
