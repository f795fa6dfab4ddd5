"""The chart code of the PrintWatch tab, run in Chromium with the vendored uPlot (no OctoPrint needed).

What a user sees in the chart: one point per camera per check, a gap where a
camera gave nothing, a dashed threshold line at the configured percentage, a
red band at every failed check, and the chart following a re-run's new data.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from browser_session import browser, chromium_available, new_page

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not chromium_available(), reason="needs /usr/bin/chromium and playwright"),
]

STATIC = Path(__file__).resolve().parents[2] / "octoprint_printwatch" / "static"


def check(layer, verdict, shapes, size=None, shape_limits=None, size_limit=10.0):
    return {
        "layer": layer, "z": layer * 0.2, "verdict": verdict,
        "shape_error_pct": shapes,
        "size": {pair: {"error_pct": pct} for pair, pct in (size or {}).items()},
        "thresholds": {"shape_pct": shape_limits or {cam: 7.0 for cam in shapes}, "size_pct": size_limit},
        "reasons": [],
    }


@pytest.fixture(scope="module")
def page():
    with browser() as chromium:
        page = new_page(chromium, width=900, height=700)
        page.set_content('<div id="shape" style="width: 800px"></div>')
        page.add_style_tag(path=str(STATIC / "vendor/uplot/uPlot.min.css"))
        for script in ("vendor/uplot/uPlot.iife.min.js", "js/printwatch_format.js", "js/printwatch_chart.js"):
            page.add_script_tag(path=str(STATIC / script))
        yield page
        assert page.printwatch_log.errors == []


def chart_input(page, checks, settings=None):
    return page.evaluate(
        "([checks, settings]) => PrintWatchFormat.chartInput(checks, settings)", [checks, settings]
    )


def draw(page, checks, settings=None):
    """Draw the shape chart of ``checks``; returns the element's data-* attributes."""
    return page.evaluate(
        """([checks, settings]) => {
            const el = document.getElementById("shape");
            window.chart = window.chart || new PrintWatchChart.ErrorChart(el, {yLabel: "Shape error"});
            window.chart.update(PrintWatchFormat.chartInput(checks, settings).shape);
            return {points: +el.dataset.points, series: +el.dataset.series, failed: +el.dataset.failed,
                    thresholds: el.dataset.thresholds};
        }""",
        [checks, settings],
    )


def pixel_at(page, layer, value):
    """RGBA of the chart canvas at (layer, error %) in data coordinates."""
    return page.evaluate(
        """([layer, value]) => {
            const u = window.chart.plot;
            const x = Math.round(u.valToPos(layer, "x", true)), y = Math.round(u.valToPos(value, "y", true));
            return Array.from(u.ctx.getImageData(x, y, 1, 1).data);
        }""",
        [layer, value],
    )


def test_one_threshold_line_when_every_camera_has_the_same_limit(page):
    data = chart_input(page, [check(30, "ok", {"cam0": 2.0, "cam1": 3.0})])
    assert data["shape"]["seriesNames"] == ["cam0", "cam1"]
    assert [t["value"] for t in data["shape"]["thresholds"]] == [7.0]
    assert [(t["value"], t["label"]) for t in data["size"]["thresholds"]] == [(10.0, "limit 10 %")]


def test_a_line_per_distinct_camera_limit_naming_the_cameras(page):
    checks = [check(30, "ok", {"cam0": 2.0, "cam1": 3.0, "cam2": 1.0},
                    shape_limits={"cam0": 5.0, "cam1": 9.0, "cam2": 5.0})]
    lines = chart_input(page, checks)["shape"]["thresholds"]
    assert sorted(t["value"] for t in lines) == [5.0, 9.0]
    labels = {t["value"]: t["label"] for t in lines}
    assert "cam0" in labels[5.0] and "cam2" in labels[5.0] and "cam1" in labels[9.0]


def test_thresholds_fall_back_to_the_print_settings(page):
    bare = {"layer": 30, "verdict": "ok", "shape_error_pct": {"cam0": 2.0}, "size": {}}
    lines = chart_input(page, [bare], {"shape_threshold_pct": 6.5, "size_threshold_pct": 12.0})
    assert [t["value"] for t in lines["shape"]["thresholds"]] == [6.5]
    assert [t["value"] for t in lines["size"]["thresholds"]] == [12.0]


def test_size_error_per_pair_with_a_gap_where_a_pair_measured_nothing(page):
    checks = [
        check(20, "ok", {"cam0": 1.0}, size={"cam0+cam1": 2.5}),
        check(40, "unknown", {"cam0": 1.5}),
        check(60, "ok", {"cam0": 1.2}, size={"cam0+cam1": 3.0}),
    ]
    size = chart_input(page, checks)["size"]
    assert size["seriesNames"] == ["cam0+cam1"]
    assert [c["values"].get("cam0+cam1") for c in size["checks"]] == [2.5, None, 3.0]


def test_chart_draws_a_point_per_camera_and_check_and_marks_failures(page):
    checks = [
        check(30, "ok", {"cam0": 2.0, "cam1": 3.0}),
        check(60, "ok", {"cam0": 2.5, "cam1": 3.5}),
        check(90, "fail", {"cam0": 14.0, "cam1": 12.0}),
    ]
    drawn = draw(page, checks)
    assert drawn == {"points": 6, "series": 2, "failed": 1, "thresholds": "7"}
    # The failure band at layer 90 is red-tinted; at layer 60 (passed) the background is not.
    r, g, b, a = pixel_at(page, 90, 1.0)
    assert a > 0 and r > g + 10 and r > b + 10
    assert pixel_at(page, 60, 1.0)[3] == 0 or pixel_at(page, 60, 1.0)[0] <= pixel_at(page, 60, 1.0)[1] + 10
    # The dashed threshold line crosses the plot at 7 %: some pixel on that row is red.
    row = page.evaluate(
        """() => {
            const u = window.chart.plot, y = Math.round(u.valToPos(7, "y", true));
            const d = u.ctx.getImageData(u.bbox.left, y, u.bbox.width, 1).data;
            let red = 0;
            for (let i = 0; i < d.length; i += 4) if (d[i] > 150 && d[i + 1] < 100 && d[i + 2] < 100) red++;
            return red;
        }"""
    )
    assert row > 20


def test_a_camera_without_a_frame_leaves_a_gap_not_a_zero(page):
    checks = [
        check(30, "ok", {"cam0": 2.0, "cam1": 3.0}),
        check(60, "ok", {"cam0": 2.5}),  # cam1 timed out
        check(90, "ok", {"cam0": 2.2, "cam1": 3.1}),
    ]
    assert draw(page, checks)["points"] == 5
    data = page.evaluate("() => window.chart.plot.data.map(s => Array.from(s))")
    assert data[2] == [3.0, None, 3.1]


def test_redrawing_with_rerun_results_updates_points_and_failures(page):
    recorded = [check(l, "ok", {"cam0": 3.0 + l / 100}) for l in (30, 60, 90, 120)]
    assert draw(page, recorded)["failed"] == 0
    rerun = [dict(c, verdict="fail", thresholds={"shape_pct": {"cam0": 3.5}, "size_pct": 10.0})
             if c["shape_error_pct"]["cam0"] > 3.5 else dict(c, thresholds={"shape_pct": {"cam0": 3.5}, "size_pct": 10.0})
             for c in recorded]
    drawn = draw(page, rerun)
    assert drawn["failed"] == 3 and drawn["thresholds"] == "3.5" and drawn["points"] == 4  # 3.6, 3.9, 4.2 > 3.5
    # The y axis always shows the threshold, even when every value is below it.
    low = [check(30, "ok", {"cam0": 0.5}, shape_limits={"cam0": 20.0})]
    draw(page, low)
    top = page.evaluate("() => window.chart.plot.scales.y.max")
    assert top >= 20.0


def test_layer_axis_spans_the_whole_print_when_the_plan_is_known(page):
    checks = [check(20, "ok", {"cam0": 1.0}), check(40, "ok", {"cam0": 1.1})]
    page.evaluate(
        """(checks) => {
            const input = PrintWatchFormat.chartInput(checks).shape;
            input.lastLayer = 100;
            window.chart.update(input);
        }""",
        checks,
    )
    x = page.evaluate("() => [window.chart.plot.scales.x.min, window.chart.plot.scales.x.max]")
    assert x == [0, 100]
