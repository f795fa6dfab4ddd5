"""A runout seen by one camera that cannot read the rise: the second look for missing material must not slide
the outline down onto the stalled top (cross-check seed 8 056_runout)."""
from types import SimpleNamespace

import numpy as np

import octoprint_printwatch.core.pipeline as pipeline
from octoprint_printwatch.core.pipeline import CameraState, CheckRunner
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult

from .synthetic import Box


def failing_on_missing(shift, candidates, best):
    seen = Box(110, 80, 160, 150).mask()
    return ShapeResult("s0", 8.38, 8.38, 8.38, 0.0, 26.3, 26.3, 500, 5000, None, shift, 7.0, 50.0,
                       passed=False, usable=True, reasons=["s0: material missing"], observed_mask=seen,
                       shift_candidates=np.array(candidates), best_candidate=best), seen


def second_look(monkeypatch, result, seen, remembered):
    looked = []

    def check_shape(**args):        # the check again at the target: it passes there (2.9 % missing)
        looked.append(args["anchor"])
        return ShapeResult("s0", 2.9, 2.9, 2.9, 0.0, 9.1, 9.1, 500, 5000, None, args["anchor"], 7.0, 50.0,
                           passed=True, usable=True, reasons=[])
    monkeypatch.setattr(pipeline, "check_shape", check_shape)
    runner = SimpleNamespace(settings=DetectionSettings(),
                             cameras={"s0": CameraState(anchor=(0, 4), frozen=True, shift_candidates=remembered)})
    return CheckRunner._second_look(runner, "s0", result, {"last_observed": seen, "anchor": (0, 4)},
                                    missing=True, growth_before=None), looked


def test_missing_material_where_the_overlap_cannot_tell_the_shift_apart_gets_no_second_look(monkeypatch):
    """056_runout check 19 (one camera looking down on a small L, 2 px of rise per check: no growth reading):
    the first look at (-1, 5), next to the frozen anchor (0, 4), misses 8.4 % of the part; its shift is among
    those this check's overlap cannot tell apart, the best of which, (-2, 8), puts the outline 3 px lower, on
    the stalled top, and passes (2.9 %). HEAD took it and the runout was never paused."""
    remembered = np.array([(dx, dy) for dx in range(-3, 1) for dy in range(3, 10)])
    result, seen = failing_on_missing((-1, 5), [(dx, dy) for dx in range(-3, 1) for dy in range(3, 10)], (-2, 8))
    second, looked = second_look(monkeypatch, result, seen, remembered)
    assert second is None and looked == []


def test_an_outline_the_overlap_says_is_misplaced_still_gets_its_second_look(monkeypatch):
    """hold-out 2 normal_03 (tests/vision/test_single_usable_camera.py): the anchor froze ~20 px off at the
    first check; at the last one the overlap's shifts lie 13-17 px away from the first look's, which it can
    tell apart from them: the outline is misplaced, and the second look keeps the normal print running."""
    remembered = np.array([(dx, dy) for dx in range(-15, 30) for dy in range(-16, 31)])
    result, seen = failing_on_missing((-4, 1), [(dx, dy) for dx in range(9, 17) for dy in range(9, 18)], (13, 12))
    second, looked = second_look(monkeypatch, result, seen, remembered)
    assert second is not None and second.passed and looked == [(13, 12)]
