"""A reading of half again the expected rise or more is a top read late, not a rise held (verdict.RISE_OVERSHOOT_PCT,
held_rise): the reading before it joins the view's history of rising.

What a user would notice: a normal print paused as a runout. Cross-check seed 43 ``013_normal`` (a black L 30 mm tall on
glass, a stereo pair whose right camera cannot tell the part from the bed until layer 128): the left view reads the rise
over its last checks as 33, 33, 17, 0, 67, then 200 % at layer 128 and 17 % at layer 136. A part never rises faster
than its model, so the 200 % is the top read a check late; taken with the 67 % as a history of rising, it made the 17 %
a stop and paused the print. With the 0 % before them there is no steady rise to stop.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from octoprint_printwatch.core.verdict import held_rise

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "l_black_top_read_late_pair"
#: The recording's checks at layers 56-136, 8 apart: the last one's index.
LAST_CHECK = 10


def test_a_late_top_reading_after_no_rise_does_not_make_the_next_low_reading_a_stop():
    results = run_checks(RECORDING)
    assert results[-1].shape["s0L"].span_growth_pct < 17.0  # the reading the old history called a stop
    assert [r.verdict for r in results] == ["ok"] * len(results)


def test_a_steady_rise_before_the_late_reading_still_makes_the_low_reading_a_stop():
    """The rule reaches back one reading, no further: had the view read the part rising before the late reading, the
    same frames pause the print."""
    def rising_before(runner, results: list) -> None:
        if len(results) == LAST_CHECK:
            state = runner.cameras["s0L"]
            state.rise_readings = [100.0, *state.rise_readings[-2:]]
    results = run_checks(RECORDING, rising_before)
    assert results[-1].verdict == "fail"
    assert any("has not grown as expected over the last checks" in reason for reason in results[-1].reasons)


@pytest.mark.parametrize("readings, held", [
    ([0.0, 66.7, 200.0], 0.0),        # seed 43 013_normal: no steady rise
    ([85.7, 100.0, 200.0], 85.7),     # seed 41 045_detach: a steady rise, then the top read late
    ([66.7, 200.0], None),            # too short a history to hold a rise read late
    ([100.0, 125.0], 100.0),          # no overshoot: the last two readings, as before
])
def test_held_rise_reaches_back_past_an_overshoot(readings, held):
    assert held_rise(readings, True) == held
