"""The size check's "both views changed where the model's newest band lies" (PairSizeCheck._changed_where_new)
must not depend on a pixel of alignment between two checks.

Each check's frames are moved back by that check's shape-check shift, and a whole-pixel alignment may
differ by a pixel from one check to the next (cross-check seed 6, 010_normal, with the alignment's prior
centred on its anchor: s0L at (-11, -8) then (-12, -8)). The older surface's edges and texture then read
as change, its 99th percentile (the limit) rose above everything in the newest band, and the share fell
from 8.7 % to 0: "nothing reconstructed at the current height" held, a false pause.
"""
from pathlib import Path

import numpy as np

from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.recording import load_recording
from octoprint_printwatch.core.stereo import size_check

DATA = Path(__file__).resolve().parents[1] / "data" / "recordings"


def _last_call(monkeypatch):
    calls = []
    original = size_check.PairSizeCheck._changed_where_new

    def spy(self, previous, current, z):
        calls.append((self, previous, current, z))
        return original(self, previous, current, z)

    monkeypatch.setattr(size_check.PairSizeCheck, "_changed_where_new", spy)
    evaluate_recording(load_recording(DATA / "stack_tier_inside_pair"))
    assert calls, "the tier rule was not reached"
    return calls[-1]


def test_a_pixel_of_alignment_between_checks_does_not_hide_the_growth(monkeypatch):
    pair, (z_prev, before), current, z = _last_call(monkeypatch)
    as_recorded = pair._changed_where_new((z_prev, before), current, z)
    assert min(as_recorded) >= size_check.MIN_CHANGED_FRACTION, as_recorded
    for dx, dy in ((1, 0), (0, 1), (-1, -1), (1, 1), (2, 0)):
        # the previous check's frames moved back one pixel differently (its shift one pixel off)
        moved = tuple(np.roll(np.roll(frame, dy, axis=0), dx, axis=1) for frame in before)
        changed = pair._changed_where_new((z_prev, moved), current, z)
        assert min(changed) >= size_check.MIN_CHANGED_FRACTION, ((dx, dy), changed, as_recorded)


def test_nothing_printed_reads_no_change_however_the_frames_were_moved(monkeypatch):
    # the same frames at both checks (nothing printed between them), one moved by a pixel: still no change
    pair, (z_prev, before), current, z = _last_call(monkeypatch)
    for dx, dy in ((0, 0), (1, 0), (0, -1)):
        moved = tuple(np.roll(np.roll(frame, dy, axis=0), dx, axis=1) for frame in before)
        changed = pair._changed_where_new((z_prev, moved), before, z)
        assert max(changed) < size_check.MIN_CHANGED_FRACTION, ((dx, dy), changed)
