"""Alignment across checks: the shifts a flat first check cannot tell apart are remembered, a taller
check narrows them to the true one, and a part that moved is never aligned back.

Synthetic masks whose right answer follows from how they are built (tests/vision/synthetic.py), and the
synthetic box print of tests/vision/test_pipeline.py for the per-print state.
"""
import numpy as np

from octoprint_printwatch.core.pipeline import CheckRunner, _still_in_place
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.alignment import align_candidates, align_expected

from .synthetic import Box
from .test_pipeline import HEIGHTS, bed, cams, frame, make_plan  # noqa: F401  (cams is a fixture)

TRUE_SHIFT = (-7, 3)   # the calibration error, in px, the checks have to find


def part_on_brim(height: int) -> tuple[np.ndarray, np.ndarray]:
    """(expected, observed) of a part ``height`` px tall standing on a brim: the expected outline at the
    calibrated place, the observed part at TRUE_SHIFT from it, with a brim 12 px wider on each side and
    6 px deeper below it (bed-level material the model does not have)."""
    part = Box(110, 150 - height, 210, 150)
    seen = part.moved(*TRUE_SHIFT)
    brim = Box(seen.x0 - 12, seen.y1 - 8, seen.x1 + 12, seen.y1 + 6)
    return part.mask(), seen.mask() | brim.mask()


def test_a_flat_first_check_keeps_every_shift_it_cannot_tell_apart():
    expected, observed = part_on_brim(6)   # a first layer barely taller than its brim
    best, candidates = align_candidates(observed, expected, 20)
    kept = {tuple(c) for c in candidates}
    assert TRUE_SHIFT in kept and best in kept
    assert np.ptp(candidates[:, 0]) >= 10    # the brim leaves the horizontal shift open
    assert all(dx * dx + dy * dy <= 400 for dx, dy in kept)   # never beyond the bound


def test_an_ambiguous_first_check_followed_by_a_taller_one_ends_at_the_true_shift():
    expected, observed = part_on_brim(6)
    _, candidates = align_candidates(observed, expected, 20)
    tall_expected, tall_observed = part_on_brim(50)
    best, narrowed = align_candidates(tall_observed, tall_expected, 20, candidates=candidates)
    assert best == TRUE_SHIFT
    assert np.ptp(narrowed[:, 0]) <= 4 < np.ptp(candidates[:, 0])   # the set has narrowed around it
    # an anchor taken at the far end of what the flat check allowed, drifting 2 px per check, stays off
    far = tuple(candidates[np.argmax(candidates[:, 0])])
    assert align_expected(tall_observed, tall_expected, 20, anchor=far, max_drift=2) != TRUE_SHIFT


def test_the_candidates_cannot_follow_a_part_that_moved_beyond_them():
    expected = Box(110, 80, 210, 170).mask()
    candidates = np.array([(dx, dy) for dx in range(-2, 3) for dy in range(-2, 3)])
    moved = Box(110, 80, 210, 170).moved(15, 0).mask()   # knocked ~5 mm sideways
    best, kept = align_candidates(moved, expected, 20, candidates=candidates, max_drift=2)
    assert abs(best[0]) <= 4 and abs(best[1]) <= 4
    assert np.abs(kept).max() <= 4


def test_a_part_displaced_after_the_alignment_froze_is_not_aligned_back(cams):  # noqa: F811
    settings = DetectionSettings()
    backgrounds = {n: bed(i) for i, n in enumerate(cams)}
    runner = CheckRunner(make_plan(cams, settings), settings, backgrounds)
    shifts = {}
    for k, (layer, z) in enumerate(HEIGHTS[:2]):
        result = runner.run_check(layer, z, {n: frame(c, backgrounds[n], z, 10 * k + i)
                                             for i, (n, c) in enumerate(cams.items())})
        assert result.verdict == "ok"
        shifts = {n: result.shape[n].shift_px for n in cams}
    assert all(runner.cameras[name].frozen for name in cams)
    for k, (layer, z) in enumerate(HEIGHTS[2:], start=2):
        # knocked 4 mm sideways: within reach of the calibration bound, had the alignment been free
        result = runner.run_check(layer, z, {n: frame(c, backgrounds[n], z, 10 * k + i, (4.0, 0.0))
                                             for i, (n, c) in enumerate(cams.items())})
        for n in cams:
            dx, dy = result.shape[n].shift_px
            assert abs(dx - shifts[n][0]) <= 1 and abs(dy - shifts[n][1]) <= 1, (n, k)
        # camera a sees the slide across its view (~13 px, inside its 19-px bound): the outline stays put
        # and the part is reported missing there (b looks along the slide and sees little change)
        assert not result.shape["a"].passed and result.shape["a"].missing_pct > settings.threshold_for("a")


def test_a_second_look_needs_the_part_still_where_the_previous_check_saw_it():
    before = Box(110, 80, 210, 170).mask()
    grown = Box(110, 60, 210, 170).mask()             # the same part, taller: still in place
    slid = Box(110, 80, 210, 170).moved(25, 0).mask()  # slid ~8 mm: most of what was seen is gone
    assert _still_in_place(grown, before)
    assert not _still_in_place(slid, before)
    assert not _still_in_place(grown, None)           # nothing seen before: no second look
