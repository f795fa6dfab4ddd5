"""A stop whose newest layers are too thin to read missing, but whose band's top reads lowered (verdict.part_stalled,
layer_shift.band_reads_lowered). Cross-check seed 22 ``024_runout`` and ``036_runout``: a one-camera rig at 1280x720;
at the check after the stop its view read a coarse 0 after a held rise of 75-100 %, with nothing missing (a filament in
the bed's colour; a top seen from above, whose own face fills the band's place), so the trace of the newest layers the
one-view stop needs was not there. Its band read the top lowered, 4 px, on 79 and 129 pixels of bed where the band
should stand (support - 2 x against); before the stop it read 0 at every check."""
from __future__ import annotations

from octoprint_printwatch.core.layer_shift import BandShift, band_reads_lowered
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide

HELD = {"s0": 75.0}


def view(*, coarse=0.0, null_dy=4, null_score=79.0, missing=0.0, relit=False, name="s0", fine=None):
    """A usable view (the one of a one-camera rig by default): passing, nothing missing, a coarse (or fine) rise reading
    and a band read as lowered by null_dy."""
    r = ShapeResult(name, 0.0, missing, missing, 0.0, 0.0, 0.0, 500, 5000, fine, (0, 0), 7.0, 50.0,
                    passed=True, usable=True, reasons=[])
    r.coarse_growth_pct, r.relit = (coarse if fine is None else None), relit
    r.band_shift = BandShift(dx=3, dy=6, support=79, against=0, moved=89, null_dy=null_dy, null_score=null_score,
                             tolerance=2.0)
    return r


def test_a_band_read_lowered_stands_in_for_the_trace_a_one_view_stop_needs():
    s = DetectionSettings()
    assert band_reads_lowered(view().band_shift)
    verdict, reasons = decide({"s0": view()}, {}, s, held_rise_before=HELD)
    assert verdict == "fail"
    assert any("has not grown" in why for why in reasons)


def test_no_stop_without_a_lowered_top_a_held_rise_or_a_reading_of_none():
    s = DetectionSettings()
    # nothing read lowered (a top the camera cannot resolve reads 0 with its band in place): as before, no pause
    assert decide({"s0": view(null_dy=0, null_score=0.0)}, {}, s, held_rise_before=HELD)[0] == "ok"
    # lowered by no more than the alignment's tolerance, or on fewer pixels than a layer shift needs
    assert not band_reads_lowered(view(null_dy=2).band_shift)
    assert decide({"s0": view(null_dy=2)}, {}, s, held_rise_before=HELD)[0] == "ok"
    assert decide({"s0": view(null_score=59.0)}, {}, s, held_rise_before=HELD)[0] == "ok"
    # the top raised is no stop
    assert decide({"s0": view(null_dy=-4)}, {}, s, held_rise_before=HELD)[0] == "ok"
    # a view that never held a rise, or that still reads one
    assert decide({"s0": view()}, {}, s, held_rise_before={"s0": 25.0})[0] == "ok"
    assert decide({"s0": view(coarse=50.0)}, {}, s, held_rise_before=HELD)[0] == "ok"
    # a view read against a relit background gives no band evidence
    assert decide({"s0": view(relit=True)}, {}, s, held_rise_before=HELD)[0] == "ok"


def test_no_stop_from_a_lowered_top_while_another_view_reads_the_full_rise():
    """The default set's black tower on black PEI, sharpened (a perturbed replay): two views that held a rise read
    0 % and 4 % with nothing missing, one of them its top 17 px low on 95 px, while the third read 200 %."""
    s = DetectionSettings()
    held = {"a": 90.0, "b": 91.0, "c": 95.0}
    views = {"a": view(name="a", fine=0.0, null_dy=6, null_score=9.0),
             "b": view(name="b", fine=4.2, null_dy=17, null_score=95.0),
             "c": view(name="c", fine=200.0, null_dy=0, null_score=0.0)}
    assert decide(views, {}, s, held_rise_before=held)[0] == "ok"
    # without the view reading the full rise, the lowered top witnesses the two views' stop
    views["c"] = view(name="c", fine=50.0, null_dy=0, null_score=0.0)
    assert decide(views, {}, s, held_rise_before=held)[0] == "fail"
