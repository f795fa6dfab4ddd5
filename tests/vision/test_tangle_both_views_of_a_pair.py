"""Loose material both cameras of a stereo pair see around the part's foot, each as much as a lone camera must see
(core/tangle.py: ``loose_material``'s ``pairs``).

What a user would notice: spaghetti caught three checks late. Cross-check seed 28 ``050_spaghetti`` (an L 24 mm wide
in natural filament on kapton, seen small by one 640x480 stereo pair; loops spread over the bed from layer 22 on): at
layer 30 the pair's views see 44 and 58 mm² of new material around the foot, where a skirt or brim would lie. The
zone's blobs count when two sides see them, and a pair looks from one side, so the print went on until the stall
showed at layer 60. A pair's two views agreeing on as much as one camera alone must see is no flickering skirt line:
the most a pair saw on a normal print of the development seeds was under 10 mm² per view.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from octoprint_printwatch.core.tangle import ONE_VIEW_MM2, SURROUNDING_WITNESS_MM2, TWO_VIEWS_MM2, loose_material

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "l_natural_loops_at_foot_pair"
PAIR = [("s0L", "s0R")]
ONE_SIDE = {"s0L": 0.0, "s0R": np.radians(6.0)}


def test_loops_both_views_of_a_pair_see_at_the_foot_pause_the_print():
    results = run_checks(RECORDING)
    assert results[0].verdict == "ok"
    assert results[1].verdict == "fail"
    assert any(reason.startswith("material appeared around the part") and "both views of s0L+s0R" in reason
               for reason in results[1].reasons)


def _loose(foot, *, pairs=PAIR, others=None):
    areas = {cam: 0.0 for cam in foot} | (others or {})
    directions = ONE_SIDE | {cam: np.radians(120.0) for cam in (others or {})}
    return loose_material(areas, with_foot=foot | (others or {}), directions=directions, rise_pct=90.0, pairs=pairs)


def test_a_pair_needs_what_a_lone_camera_needs_in_both_views():
    assert _loose({"s0L": ONE_VIEW_MM2 + 1, "s0R": 2 * ONE_VIEW_MM2}) is not None
    # one view of the pair under it: a pair looks from one side, as before
    assert _loose({"s0L": ONE_VIEW_MM2 - 1, "s0R": 2 * ONE_VIEW_MM2}) is None
    assert _loose({"s0L": 2 * TWO_VIEWS_MM2, "s0R": 2 * TWO_VIEWS_MM2}) is None
    # not paired (two cameras of one side that are no stereo pair): unchanged
    assert _loose({"s0L": 2 * ONE_VIEW_MM2, "s0R": 2 * ONE_VIEW_MM2}, pairs=()) is None


def test_a_view_outside_the_pair_that_sees_none_sets_it_aside():
    foot = {"s0L": 2 * ONE_VIEW_MM2, "s0R": 2 * ONE_VIEW_MM2}
    assert _loose(foot, others={"s1": 0.0}) is None
    assert _loose(foot, others={"s1": 0.5 * SURROUNDING_WITNESS_MM2}) is None
    assert _loose(foot, others={"s1": SURROUNDING_WITNESS_MM2}) is not None
