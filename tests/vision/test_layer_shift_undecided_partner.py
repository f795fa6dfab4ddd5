"""A camera counts the pixels a layer shift changes in it at most SHIFT_UNDECIDED_PER_DECIDED times the ones it decides
there (layer_shift._pooled).

What a user would notice: a layer shift one camera sees plainly, never paused. Cross-check seed 37 ``031_layer_shift``
(natural, translucent filament on glass, a frustum 59 mm wide, one stereo pair; the layers from 92 on printed 6.1 mm
off): at layer 100 s0L confirms the shift on 1,191 of the 1,378 pixels it changes, while s0R, which sees the
translucent part against the bright bed, decides almost none of its 1,018 (neither material nor bed). Counted in full,
those undecided pixels halved the pooled share (0.50) and the print went on.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from octoprint_printwatch.core.layer_shift import band_shift, confirms_layer_shift, estimate_layer_shift

from .check_runs import run_checks
from .synthetic import Box, H, W

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "natural_frustum_layer_shift_pair"


def test_a_shift_one_view_of_a_pair_confirms_pauses_where_its_partner_decides_nothing():
    results = run_checks(RECORDING)
    assert [r.verdict for r in results[:4]] == ["ok"] * 4
    shifted = results[4]
    assert shifted.verdict == "fail"
    # ... named as s0L's alone: s0R shows the move but confirms none of it
    assert any("sideways on the layers below" in reason and "confirmed by s0L (" in reason
               for reason in shifted.reasons)
    assert 4.0 <= shifted.layer_shift.magnitude_mm <= 7.0


# A pair's two views of one part (same direction, image x along printer X at 4 px/mm); the newest band moved 3 mm
BEFORE, BAND = Box(100, 120, 220, 200), Box(100, 100, 220, 120)
J = [[4.0, 0.0], [0.0, -1.0]]
MOVE_PX = 12


def _view(observed: np.ndarray, bed: np.ndarray):
    return band_shift(observed, bed, BEFORE.mask(), BAND.mask(), 24, 12, 6, 2.0, bed_to_image=J,
                      height_to_image=[0.0, -3.0])


def _seen(move: int):
    observed = BEFORE.mask() | BAND.moved(move, 0).mask()
    return _view(observed, ~observed)


def test_a_partner_that_decides_nothing_does_not_dilute_the_shift():
    blind = _view(np.zeros((H, W), bool), np.zeros((H, W), bool))
    found = estimate_layer_shift({"L": _seen(MOVE_PX), "R": blind})
    assert found is not None and np.allclose(found.shift_mm, (3.0, 0.0), atol=0.5)
    assert found.confirmed >= 0.85
    assert confirms_layer_shift(found, 1.5)


def test_a_partner_that_sees_the_band_in_place_still_speaks_against_the_shift():
    found = estimate_layer_shift({"L": _seen(MOVE_PX), "R": _seen(0)})
    assert found is None or not confirms_layer_shift(found, 1.5)
