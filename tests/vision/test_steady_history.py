"""One reading is no history: the span stall rule's "it rose at its previous check" needs the view's reading before
that to read a rise too (verdict.held_rise; CheckRunner passes decide only such views, as ``held_rise_before``)."""
from octoprint_printwatch.core.verdict import decide, held_rise
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult


def view(name, *, span=None):
    return ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, None, (0, 0), 7.0, 50.0, passed=True,
                       usable=True, reasons=[], span_growth_pct=span, growth_span=None if span is None else 3)


def known(levels):
    """decide's mapping: only the views with a level."""
    return {cam: level for cam, level in levels.items() if level is not None}


def test_a_single_rise_reading_before_a_zero_span_is_no_stop():
    """Cross-check seed 13 011_normal (a cone in the bed's colour, one camera that cannot see its top): the view's
    readings jump 163 (span), 83 (span), 25 (coarse only), 50 (span), then 0 (span) with nothing missing. The
    one 50 % reading before the 0 made the span stall rule read a stop and pause a normal print."""
    s = DetectionSettings()
    now = {"s0": view("s0", span=0.0)}
    assert decide(now, {}, s, held_rise_before={"s0": 50.0})[0] == "fail"        # the base's single reading
    # its readings up to check 6 (fine, else span, else coarse): ..., 83 (span), 25 (coarse), 50 (span)
    assert held_rise([163.3, 83.3, 25.0, 50.0], True) == 25.0
    assert decide(now, {}, s, held_rise_before=known({"s0": held_rise([25.0, 50.0], True)}))[0] == "ok"
    # its first reading is no history either, nor a previous check without any reading
    assert held_rise([50.0], True) is None and held_rise([83.3, 25.0], False) is None
    # a view that read the part rising at its last two readings, then nothing: a stop (seed 9 040_runout's form);
    # a check without any reading between them does not break the history (seed 13 024_runout's s0L: 100 % at
    # check 11, none at 12-13, 60 % at 14, 33 % at 15, its onset being 14)
    assert held_rise([100.0, 60.0], True) == 60.0
    pair = {"s0L": view("s0L", span=14.3), "s0R": view("s0R", span=33.3)}
    held = known({"s0L": held_rise([83.3, 50.0], True), "s0R": held_rise([100.0, 66.7], True)})
    assert decide(pair, {}, s, held_rise_before=held)[0] == "fail"
