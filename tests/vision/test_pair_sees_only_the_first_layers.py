"""A stereo pair that sees the part no higher than its first layers measures no height (stereo.tangents.plane_height).

What a user would notice: a normal print paused with "size differs from the model by 55 %". Cross-check seed 29
``044_runout`` (a cylinder 40 mm wide in filament the colour of its blue-tape bed, one 1280x720 stereo pair), checks at
layers 27 and 36, long before its filament runs out: the part itself hardly stands out, and both views' upper edges lie
at or below the lowest height the fit considers, so both read "1.0 mm" against the 9 mm the G-code says; the sides at
1 mm (the first layers) fit the model, so the low top held and the pair paused the print.
"""
from __future__ import annotations

from pathlib import Path

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "cylinder_like_bed_blue_tape_pair"


def test_a_pair_that_sees_only_the_first_layers_does_not_pause_the_print():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results] == ["ok", "ok"]
    size = results[1].size["s0L+s0R"]
    assert size["height_mm"] is None and not size["error_pct"]
    assert "not seen above" in size["reason"]
