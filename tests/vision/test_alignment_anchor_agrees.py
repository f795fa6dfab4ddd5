"""The anchor a passing check leaves agrees with the shifts that check could not tell apart.

Recording (tests/data/SOURCES.md): a clear pyramid on aluminium seen by one camera whose view of the part
is its cast shadow and one lit face (the other faces are the bed's grey). The search near the previous
anchor, tie-broken on the upper outline, slid the outline onto the shadow, 9-12 px from every shift the
exact overlap could not tell apart; frozen there, the lit face read 16 % "extra material" from layer 80 on
and paused this normal print.
"""
from pathlib import Path

import numpy as np

from octoprint_printwatch.core.pipeline import agreeing_anchor, evaluate_recording
from octoprint_printwatch.core.recording import load_recording

from .recording_edits import empty_bed_at

PYRAMID = Path(__file__).resolve().parents[1] / "data" / "recordings" / "pyramid_shadow_anchor_single"


def test_an_outline_anchored_on_the_shadow_moves_to_the_overlap_and_does_not_pause_a_normal_print():
    document = evaluate_recording(load_recording(PYRAMID))
    assert [c["verdict"] for c in document["checks"]] == ["ok"] * 5
    shifts = [tuple(c["shape"]["cam0R"]["shift_px"]) for c in document["checks"]]
    # the outline left the shadow (dx about -20) for where the overlap puts it, and stayed there
    assert shifts[0][0] <= -18 and all(dx >= -15 for dx, _ in shifts[2:])
    assert all(c["shape"]["cam0R"]["extra_pct"] < c["shape"]["cam0R"]["threshold"] / 2 for c in document["checks"])


def test_the_same_view_still_sees_the_part_knocked_off(tmp_path):
    # the part gone before layer 80 (the empty bed): the moved anchor must not hide it
    document = evaluate_recording(load_recording(empty_bed_at(PYRAMID, "cam0R", 3, tmp_path)))
    assert [c["verdict"] for c in document["checks"]][:4] == ["ok", "ok", "ok", "fail"]


def test_an_anchor_within_drift_of_the_candidates_is_kept_and_a_far_one_moves_to_the_nearest():
    candidates = np.array([[-14, -4], [-13, -5], [-13, -6], [-14, -6]])
    assert agreeing_anchor((-15, -3), candidates, 2) == (-15, -3)
    assert agreeing_anchor((-19, 5), candidates, 2) == (-14, -4)
    assert agreeing_anchor((-19, 5), None, 2) == (-19, 5)
