"""A camera whose anchor only short looks laid lays its outline again, once, where the part now stands tall, fits
clearly, stayed in place and grew (CheckRunner._anchor_again_once_clear).

What a user would notice: a normal print paused as "unexpected material (spaghetti, blob or moved part?)" and "the
newest layers are displaced" by one camera for the rest of the print. Cross-check seed 36 ``007_normal`` (a red
polygon with a brim of its colour on gold PEI, two cameras): s0's first look, at 3 mm, fitted the outline along the
brim 19 px left of the part (the part's shadowed side read only partly as material), the next short look passed
there too, and from layer 45 on the part rising out of the brim read 39-25 % extra and 7-13 % missing beside the
outline at every check; with no passing look the anchor never moved, and eight checks paused the print. Free of the
anchor the part fits at (+1, -6) px, 1 px from where the true camera puts it, with nothing missing or extra: at layer
75, where it stands tall in that view (72 rows, over twice the alignment's bound), and already at layer 45, where
every shift the overlap cannot tell from its best lies away from the anchor (test_anchor_again_off_the_overlap.py).
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from octoprint_printwatch.core.masks import shift_mask

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "polygon_red_brim_short_anchor_pair"


#: the check (layer 45) at which s0 first fails beside the outline its short looks laid
FIRST_FAILING = 2


def _run(before_failing=None) -> list:
    def hook(runner, results: list) -> None:
        if len(results) == FIRST_FAILING and before_failing is not None:
            before_failing(runner.cameras["s0"], runner)
    return run_checks(RECORDING, hook)


def test_the_part_beside_an_outline_short_looks_laid_does_not_pause_the_print():
    results = _run()
    assert [r.verdict for r in results] == ["ok"] * 5
    assert all(r.shape["s0"].passed for r in results)
    last = results[-1].shape["s0"]
    assert last.error_pct < 3.5
    # laid within 3 px of where the part stands (the true camera: +1.5, -5.3 px)
    assert abs(last.shift_px[0] - 1.5) <= 3 and abs(last.shift_px[1] + 5.3) <= 3
    assert any("first, short looks laid" in reason for reason in results[FIRST_FAILING].shape["s0"].reasons)


def test_an_anchor_a_tall_look_laid_stays_and_the_print_pauses():
    """The rule rests on the anchor not being held yet: held, the same frames pause the print as before."""
    def hold(state, runner) -> None:
        state.frozen = True
    assert _run(hold)[-1].verdict == "fail"


def test_a_part_not_where_it_was_at_the_previous_check_is_not_laid_again():
    """A part that slid or was knocked off since the previous check is not in place: no new outline excuses it."""
    def moved(state, runner) -> None:
        state.last_observed = np.roll(state.last_observed, 25, axis=1)
    assert not _run(moved)[FIRST_FAILING].shape["s0"].passed


def test_a_part_its_last_passing_look_saw_where_the_outline_lay_is_not_laid_again():
    """Had the camera's last passing look seen the part exactly where the anchor put the outline, the part (or its
    newest layers) moved since: the frames of now fit elsewhere, and the view fails."""
    def seen_at_the_anchor(state, runner) -> None:
        z_then, placed_then = state.previous_mask_at
        state.previous_mask = shift_mask(runner.plan.view("s0", z_then).silhouette, *placed_then)
    assert not _run(seen_at_the_anchor)[FIRST_FAILING].shape["s0"].passed
