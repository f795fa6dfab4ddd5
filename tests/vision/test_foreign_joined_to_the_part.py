"""The parked hotend followed into the search box stays foreign where weak pixels join it to the part's top
(masks.reaching_in_from_above: a blob that holds half the object followed from the previous check is taken apart
from the outline's ring, and a piece followed there is foreign however long its contact through weak pixels), and an
object not the print's is no evidence of a layer shift (shape_check: a band moved onto it lands on no layer).

What a user would notice: a normal print paused for a layer shift. Cross-check seed 43 ``012_normal`` (a natural ring
on glass, a 640x480 stereo pair; the left camera looks past the part at the parked hotend): the hotend, followed as
foreign from the print's second check, comes within a few pixels of the rising part's top at layer 99. The shadow and
rim pixels between them joined it to the part's blob, so the left view read it as 30-40 % unexpected material, and
the newest band moved onto it as an 8.8-mm layer shift: the print paused at layer 108.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "ring_natural_parked_hotend_pair"
#: The recording's checks at layers 63-108: the index of the one at layer 99, where the hotend meets the part's top.
MEETS_THE_TOP = 4


def test_the_hotend_at_the_parts_top_stays_foreign_and_the_print_goes_on():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results] == ["ok"] * 6
    for r in results[MEETS_THE_TOP:]:
        view = r.shape["s0L"]
        assert view.extra_pct < view.threshold
        assert np.count_nonzero(view.foreign_mask) > 800   # the hotend, followed
    assert results[-1].layer_shift.magnitude_mm < 8.0      # no band read as moved onto it


def test_without_the_object_followed_the_left_view_reads_it_as_unexpected_material():
    """Keeping the hotend foreign rests on following it: forgetting it before the check at layer 99, the left view
    reads it as unexpected material there."""
    def forget(runner, results: list) -> None:
        if len(results) == MEETS_THE_TOP:
            runner.cameras["s0L"].last_foreign = None
    view = run_checks(RECORDING, forget)[MEETS_THE_TOP].shape["s0L"]
    assert view.extra_pct > view.threshold
    assert any("unexpected material" in reason for reason in view.reasons)
