"""A view held a rise up to a stop late in the interval before its previous check (verdict.held_rise).

What a user would notice: a runout caught two or more checks late, or not at all. Cross-check seed 37 ``044_runout``
(a grey cylinder 55 mm wide on gold PEI, one stereo pair): the filament ran out late in the interval before layer 96;
at layer 96 both views read part of the rise (20 % and 40 %: the layers printed before the stop), at layer 104 none,
with a trace of the newest layers missing in s0L (1.2 %). A stop that two views show with nothing much missing yet
needs each to have held a rise before it, and a view's held rise was the lowest of its last two readings: the partial
reading of the interval the stop fell in hid the 100 % readings before it, and the stop was never read (the top's
crescent went missing only two checks later, by then no longer read against a rise).
"""
from __future__ import annotations

from pathlib import Path

from octoprint_printwatch.core.verdict import held_rise

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "cylinder_grey_late_stop_pair"


def test_a_stop_late_in_the_interval_pauses_the_print_at_the_next_check():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results[:4]] == ["ok"] * 4
    assert results[4].verdict == "fail"
    assert any("has not grown as expected" in reason for reason in results[4].reasons)


def test_a_partial_reading_keeps_the_rise_only_after_a_held_rise():
    assert held_rise((100.0, 100.0, 20.0), True) == 100.0     # the stop fell late in the last interval
    assert held_rise((100.0, 20.0), True) == 20.0             # one reading of a rise before it is no history
    assert held_rise((0.0, 100.0, 20.0), True) == 20.0        # nor a pixel step's 100 after a 0
    assert held_rise((100.0, 100.0, 5.0), True) == 5.0        # a stall reading is no partial rise
