"""Where no view reads the part's rise at one check, their readings over a span of checks stand in for the rise the
textured-band rule weighs (verdict.rise_over_spans).

What a user would notice: spaghetti caught two checks late on a part seen small. Cross-check seed 41
``046_spaghetti`` (a translucent blue polygon 36 mm wide on black PEI, one 800x600 stereo pair, strands from layer 40
on): both views see the part too small to read one check's rise, and read it over three checks (86 and 88 % at layer
45, 62 and 71 % at layer 54). At layer 54 s0R's newest band is 2.1 times as textured as the smoother of its two
readings before. With no one-check reading there was no rise to weigh, and the print went on to layer 72.
"""
from __future__ import annotations

from pathlib import Path

from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import rise_over_spans

from .check_runs import run_checks

RECORDING = (Path(__file__).resolve().parents[1] / "data" / "recordings"
             / "polygon_translucent_strands_seen_small_pair")


def test_strands_on_a_part_seen_small_pause_the_print_where_its_spans_read_it_slow():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results] == ["ok", "ok", "ok", "ok", "fail"]
    assert any(reason.startswith("s0R: the newest layers look") and "over the last checks" in reason
               for reason in results[-1].reasons)


def _view(camera: str, *, fine: float | None = None, coarse: float | None = None,
          span: float | None = None) -> ShapeResult:
    return ShapeResult(camera, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, fine, (0, 0), 7.0, 50.0, passed=True,
                       coarse_growth_pct=coarse, span_growth_pct=span)


def test_spans_stand_in_only_where_no_view_reads_one_check():
    two_spans = {"a": _view("a", span=62.5), "b": _view("b", span=71.4)}
    assert abs(rise_over_spans(two_spans) - 66.95) < 0.01
    # a view that reads the rise at one check (finely or to the pixel) leaves the rise to those readings
    assert rise_over_spans({**two_spans, "c": _view("c", coarse=100.0)}) is None
    assert rise_over_spans({**two_spans, "c": _view("c", fine=100.0)}) is None
    # one view's span among two usable views is no median; the only usable view's is
    assert rise_over_spans({"a": _view("a", span=40.0), "b": _view("b")}) is None
    assert rise_over_spans({"a": _view("a", span=40.0)}) == 40.0
