"""A stop under way since before the print's first reading of the rise (verdict.stopped_at_the_first_reading).
Cross-check seed 20 ``030_spaghetti``: the tangle began before the first check, whose outline was placed on the short
part; at the second check, the print's first reading of the rise, both views of a stereo pair read none (0 % and
10 %) and one missed 3.5 % of the part, none at the first check. With no earlier reading no view held a rise, so
every stall rule that a stop is a change of needed more missing material, and the print was never paused. Before any
onset on the development seeds no view that read no rise at the print's first reading missed over 0.74 %."""
from __future__ import annotations

from octoprint_printwatch.core.layer_shift import BandShift
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide


def view(name, *, fine=0.0, missing=0.0, band_missing=None, relit=False, coarse=None):
    """A usable, passing view with a one-check (fine) or coarse reading of the rise and ``missing`` % of the part
    missing (and of its newest band, by default the same)."""
    band = missing if band_missing is None else band_missing
    r = ShapeResult(name, missing, missing, missing, 0.0, band, band, 500, 5000, fine, (0, 0), 7.0, 50.0,
                    passed=True, usable=True, reasons=[])
    r.coarse_growth_pct, r.relit = coarse, relit
    return r


BEFORE = {"s0L": 0.0, "s0R": 0.0}


def pair(**left):
    return {"s0L": view("s0L", **{"fine": 0.0, "missing": 3.4, **left}), "s0R": view("s0R", fine=10.0, missing=1.2)}


def test_two_views_read_no_rise_at_the_first_reading_with_the_layers_missing():
    s = DetectionSettings()
    verdict, reasons = decide(pair(), {}, s, first_rise_reading=True, missing_before=BEFORE)
    assert verdict == "fail"
    assert any("has not grown" in why for why in reasons)


def test_no_stop_where_the_view_missed_as_much_at_its_previous_check():
    """A normal print's top view of a black prism on black PEI (tests/data/recordings/prism_black_on_black_top): its
    outline anchored off the part missed 8.3 %, 3.7 % and 2.3 % at its first three checks, the third the print's
    first reading of the rise (a coarse 0 %): a standing offset, nothing gone since."""
    s = DetectionSettings()
    top = {"cam0": view("cam0", fine=None, coarse=0.0, missing=2.3)}
    assert decide(top, {}, s, first_rise_reading=True, missing_before={"cam0": 3.7})[0] == "ok"
    assert decide(top, {}, s, first_rise_reading=True, missing_before={"cam0": 0.0})[0] == "fail"
    # a view not usable at its previous check shows nothing gone since
    assert decide(pair(), {}, s, first_rise_reading=True, missing_before={"s0R": 0.0})[0] == "ok"


def test_no_stop_without_the_first_reading_the_trace_or_a_second_view():
    s = DetectionSettings()
    # not the print's first reading: a view that never held a rise since is a top it cannot resolve (as before)
    assert decide(pair(), {}, s)[0] == "ok"
    # a top the camera cannot resolve reads no rise with (almost) nothing missing
    assert decide(pair(missing=0.74, band_missing=0.9), {}, s, first_rise_reading=True,
                  missing_before=BEFORE)[0] == "ok"
    # one view reading no rise while the other reads some is one view's pixel step
    views = pair()
    views["s0R"] = view("s0R", fine=40.0, missing=1.2)
    assert decide(views, {}, s, first_rise_reading=True, missing_before=BEFORE)[0] == "ok"
    # a view read against a relit background does not count toward the stopped views
    assert decide(pair(relit=True), {}, s, first_rise_reading=True, missing_before=BEFORE)[0] == "ok"


def test_no_stop_while_a_view_reads_the_full_rise_or_where_the_top_closes():
    s = DetectionSettings()
    views = {**pair(), "s1": view("s1", fine=0.0, missing=0.0), "s2": view("s2", fine=120.0)}
    assert decide(views, {}, s, first_rise_reading=True, missing_before=BEFORE)[0] == "ok"
    # a top skin closing may look like the bed as a whole
    assert decide(pair(), {}, s, first_rise_reading=True, top_closing=True, missing_before=BEFORE)[0] == "ok"


def test_a_band_read_lowered_witnesses_the_stop_with_nothing_missing_yet():
    """Cross-check seed 7 ``024_runout``: a stop before the first check, 2-3 px of the newest layers left beyond the
    outline's tolerance; at the print's first reading both views read 0 % with 0.0 and 0.36 % missing, and one read its
    band's top 4 px low on 94 px of bed (the next check paused it)."""
    s = DetectionSettings()
    views = {"s0L": view("s0L"), "s0R": view("s0R", missing=0.36)}
    assert decide(views, {}, s, first_rise_reading=True, missing_before=BEFORE)[0] == "ok"
    views["s0R"].band_shift = BandShift(dx=-4, dy=4, support=134, against=11, moved=172, null_dy=4, null_score=94.0,
                                        tolerance=2.0)
    assert decide(views, {}, s, first_rise_reading=True, missing_before=BEFORE)[0] == "fail"
    # lowered on fewer pixels than a layer shift needs (before any onset: at most 53), or not at the first reading
    views["s0R"].band_shift = BandShift(dx=-4, dy=4, support=60, against=11, moved=172, null_dy=4, null_score=53.0,
                                        tolerance=2.0)
    assert decide(views, {}, s, first_rise_reading=True, missing_before=BEFORE)[0] == "ok"


def test_a_one_camera_rig_needs_its_view_to_read_the_stop():
    s = DetectionSettings()
    before = {"s0": 0.0}
    assert decide({"s0": view("s0", coarse=0.0, fine=None, missing=2.5)}, {}, s, first_rise_reading=True,
                  missing_before=before)[0] == "fail"
    assert decide({"s0": view("s0", coarse=0.0, fine=None, missing=1.5)}, {}, s, first_rise_reading=True,
                  missing_before=before)[0] == "ok"
