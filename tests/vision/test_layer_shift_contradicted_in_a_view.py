"""A bed move that a view seeing it clearly reads as not there is no layer shift (layer_shift.contradicted_in_a_view):
layers that slid are one rigid move of the part's top, the same in every view.

What a user would notice: a normal stretch of a print paused for a layer shift. Cross-check seed 47 ``028_runout`` (a
white L 51 mm wide on a brim of its colour, two 640x480 cameras, a runout only at layer 176): s1's outline lies along
the brim, 9 px beside the part, and its newest band reads moved by 9 px on 404 of the 440 pixels that move changes.
s0's outline sits on the part, and of the 90 pixels the same bed move changes there 74 contradict it. Pooled, s1's
pixels outvoted s0's (77 % of the evidence) and the print was paused at layer 60 for a 5.8-mm layer shift.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from octoprint_printwatch.core.layer_shift import (SHIFT_CONFIRMED, SHIFT_MIN_SUPPORT_PX, LayerShift,
                                                   contradicted_in_a_view)

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "l_outline_along_brim"


# the tested move needs an outline along the brim in one view; since a look finds a part in a brim by its brim
# (core.alignment.align_with_brim) this recording's outline lies on the part in both, and the rule is tested on the
# outline as it was laid before (a miscalibrated camera lays one so)
pytestmark = pytest.mark.usefixtures("brims_not_looked_for")


def test_a_move_one_view_contradicts_does_not_pause_the_print():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results] == ["ok"] * 6
    # the pooled evidence alone would confirm the move: s1's pixels outweigh s0's
    shift = results[3].layer_shift
    assert shift.confirmed >= SHIFT_CONFIRMED and shift.magnitude_mm >= 2.0
    support, against = shift.read_by["s0"]
    assert against >= SHIFT_MIN_SUPPORT_PX and against > support
    assert contradicted_in_a_view(shift)


def shift_read(read_by: dict) -> LayerShift:
    support = int(sum(s for s, _ in read_by.values()))
    against = int(sum(a for _, a in read_by.values()))
    return LayerShift(shift_mm=np.array([3.0, 0.0]), support=support, against=against, moved=support + against,
                      cameras={name: (6, 0) for name in read_by}, read_by=read_by)


def test_only_a_view_deciding_enough_pixels_against_the_move_contradicts_it():
    # a view that sees the move on a handful of pixels, or confirms it on over a quarter as many as contradict it,
    # is outvoted
    assert not contradicted_in_a_view(shift_read({"a": (400.0, 10.0), "b": (5.0, SHIFT_MIN_SUPPORT_PX - 1.0)}))
    assert not contradicted_in_a_view(shift_read({"a": (400.0, 10.0), "b": (147.0, 154.0)}))
    assert not contradicted_in_a_view(shift_read({"a": (400.0, 10.0), "b": (30.0, 80.0)}))
    assert contradicted_in_a_view(shift_read({"a": (400.0, 10.0), "b": (6.0, 74.0)}))
