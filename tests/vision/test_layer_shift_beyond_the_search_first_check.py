"""A layer shift read at the print's first check on the search grid's edge is not confirmed
(layer_shift.beyond_the_search_at_the_first_check).

What a user would notice: a normal print paused at its first check. Cross-check seed 28 ``003_normal`` (an L 59 mm wide
in filament close to its smooth PEI bed's colour, two 640x480 stereo pairs, s1's unusable): at layer 13 s0R reads the
whole part 8.0 mm off along X, the grid's edge, on 96 % of the pixels that move changes. The first check's band is
the whole part, so nothing shows layers moved on the layers below; a fit pressed against the edge of the search is an
outline laid far off a part the view barely separates. Later checks read such a move against layers printed in place.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from octoprint_printwatch.core.layer_shift import (band_shift, beyond_the_search_at_the_first_check,
                                                   confirms_layer_shift, estimate_layer_shift, with_history)

from .check_runs import run_checks
from .synthetic import Box

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "l_like_bed_first_check_pair"


def test_a_normal_print_is_not_paused_on_a_shift_at_the_searchs_edge_at_its_first_check():
    results = run_checks(RECORDING)
    assert results[0].verdict == "ok"
    assert not any("sideways on the layers below" in reason for reason in results[0].reasons)


# One side view, printer X along image x at 4 px/mm: the band moved 9 mm, beyond the 8-mm search
BEFORE, BAND = Box(60, 120, 180, 200), Box(60, 100, 180, 120)
J = [[4.0, 0.0], [0.0, -1.0]]


def _view(move_px: int):
    observed = BEFORE.mask() | BAND.moved(move_px, 0).mask()
    return {"s0": band_shift(observed, ~observed, BEFORE.mask(), BAND.mask(), 40, 8, 6, 2.0, bed_to_image=J,
                             height_to_image=[0.0, -3.0])}


def test_an_edge_reading_counts_only_after_the_first_check():
    views = _view(36)
    first = with_history(estimate_layer_shift(views), [])
    assert first.at_search_edge and np.isclose(abs(first.shift_mm[0]), 8.0)
    assert beyond_the_search_at_the_first_check(first) and not confirms_layer_shift(first, 1.5)
    # the same reading at a later check, the band read in place at the check before: a shift
    later = with_history(estimate_layer_shift(views), [(False, _view(0)), (True, _view(0))])
    assert not later.at_first_check and confirms_layer_shift(later, 1.5)
    # a move inside the search, at the first check: still read
    inside = with_history(estimate_layer_shift(_view(24)), [])
    assert not inside.at_search_edge and np.isclose(inside.shift_mm[0], 6.0, atol=0.3)
    assert confirms_layer_shift(inside, 1.5)
