"""A stereo pair's first width of the print, too wide, is not held alone (stereo.size_check.PairSizeCheck._held_width).

What a user would notice: a normal print paused halfway by the size check. Cross-check seed 36 ``016_normal`` (a
natural-coloured L 6.4 mm thin across the pair's line of sight and 49 mm tall, on glass, two 640x480 cameras): its
sides first showed as silhouette edges in both views at layer 88, where the pair read it 8.9 mm wide, 40 % over the
model, and 7.0-7.3 mm at every later check. A width too wide at the first reading because the part is (loose material,
a shifted tier) is too wide at the next one too; this one was not.
"""
from __future__ import annotations

from pathlib import Path

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "l_thin_first_width_pair"
PAIR = "s0L+s0R"


def test_a_pairs_first_width_too_wide_does_not_pause_the_print():
    results = run_checks(RECORDING)
    assert all(r.verdict == "ok" for r in results), [(r.layer, r.reasons) for r in results if r.verdict != "ok"]
    widths = [r.size[PAIR] for r in results if r.size[PAIR].get("width_mm")]
    first, later = widths[0], widths[1:]
    assert first["width_error_pct"] > 30.0
    assert first["error_pct"] is None or first["error_pct"] <= first["threshold_pct"]
    assert "first width reading" in first["reason"]
    # the pair measures on: its next width is held, and within the limit
    assert later and later[0]["error_pct"] is not None and later[0]["error_pct"] < later[0]["threshold_pct"]
