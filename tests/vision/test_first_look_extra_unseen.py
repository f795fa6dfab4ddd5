"""A first look's decisive extra material that two other views, seeing the part whole where it belongs, do not see at
all is set aside (verdict.unseen_by_the_other_views, FIRST_LOOK_WITNESSES).

What a user would notice: a print paused at its first check with nothing wrong. Cross-check seed 34
``047_layer_shift`` (a star 15 mm wide on glass, four 1280x720 cameras, s0 relit; its layers shift only from layer 60
on): at layer 20 s3's first look lays the outline beside the part and reads 59.7 % unexpected material, four times its
threshold (decisive), while s1 and s2 see the part whole and nothing extra. Decisive extra material was set aside only
where the failing view and another read the part rising as the model says, and a first look has no rise to read.
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import unseen_by_the_other_views

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "star_glass_first_look_beside_four"


def test_a_first_look_beside_the_part_does_not_pause_the_print():
    results = run_checks(RECORDING)
    assert results[0].verdict == "ok"
    assert results[0].shape["s3"].extra_pct > 4 * 7.0 and not results[0].shape["s3"].passed


def _view(name: str, *, extra: float = 0.0, missing: float = 0.0) -> ShapeResult:
    return ShapeResult(name, extra + missing, extra + missing, missing, extra, 0.0, 0.0, 500, 5000, None, (0, 0), 7.0,
                       50.0, passed=extra + missing <= 7.0, usable=True, first_look=True)


def test_two_clean_witnesses_stand_in_for_the_rise_at_a_first_look():
    failing = replace(_view("s3", extra=59.7), decisive=True)
    clean = {"s1": _view("s1"), "s2": _view("s2")}
    assert unseen_by_the_other_views(failing, {"s3": failing, **clean})
    # one witness is not enough (seed 35 `051_layer_shift`: a shift printed before the first check, one other view)
    assert not unseen_by_the_other_views(failing, {"s3": failing, "s1": clean["s1"]})
    # a witness missing part of the part (knocked off, or not where it belongs) is no witness of a part in place
    knocked = {"s1": clean["s1"], "s2": _view("s2", missing=5.0)}
    assert not unseen_by_the_other_views(failing, {"s3": failing, **knocked})
    # a later look still needs the rise
    later = replace(failing, first_look=False)
    assert not unseen_by_the_other_views(later, {"s3": later, **{k: replace(v, first_look=False)
                                                               for k, v in clean.items()}})
