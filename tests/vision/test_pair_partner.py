"""Extra material seen by one camera of a stereo pair only: its partner looks from nearly the same side, so
when it passes and sees no extra material at all, the one view's "extra" is not material standing there (a
hair of stringing drooping from the top edge). Where the partner gives no evidence, the check is a
single-camera check and the one view speaks alone.

Recording (tests/data/SOURCES.md): the independent cross-check simulator's seed-1 048_runout, a 16 mm orange
cylinder on black PEI seen by a pair, with a stringing hair at layer 40 and the runout seen at layer 90.
"""
from dataclasses import replace
from pathlib import Path

from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.verdict import decide, unseen_by_partner
from octoprint_printwatch.core.recording import load_recording
from octoprint_printwatch.core.settings import DetectionSettings

from .recording_edits import without_background

DATA = Path(__file__).resolve().parents[1] / "data" / "recordings"
HAIR = DATA / "cylinder_hair_pair"


def test_a_hair_seen_by_one_camera_of_a_pair_does_not_pause_and_the_runout_still_does():
    document = evaluate_recording(load_recording(HAIR))
    checks = {c["layer"]: c for c in document["checks"]}
    hair = checks[40]["shape"]
    # the hair is still measured as extra material in s0L, and nothing in s0R
    assert hair["s0L"]["extra_pct"] > 2 * hair["s0L"]["threshold"] and not hair["s0L"]["passed"]
    assert hair["s0R"]["passed"] and hair["s0R"]["extra_pct"] == 0.0
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok", "ok", "ok", "fail"]
    runout = checks[90]["shape"]
    assert all(runout[cam]["missing_pct"] > runout[cam]["threshold"] for cam in ("s0L", "s0R"))


def test_without_the_partners_evidence_the_one_view_speaks_alone(tmp_path):
    document = evaluate_recording(load_recording(without_background(HAIR, "s0R", tmp_path)))
    assert [c["verdict"] for c in document["checks"]][:4] == ["ok", "ok", "ok", "fail"]


def test_extra_material_the_partner_also_sees_or_a_decisive_view_still_fails():
    document = evaluate_recording(load_recording(HAIR), keep_results=True)
    shape = next(r for r in document["_results"] if r.layer == 40).shape
    left, right = shape["s0L"], shape["s0R"]
    settings = DetectionSettings()
    pairs = [("s0L", "s0R")]
    before = {"s0L": 0.0, "s0R": 0.0}

    def verdict(left=left, right=right, pairs=pairs, before=before):
        return decide({"s0L": left, "s0R": right}, {}, settings, pairs=pairs, extra_before=before)[0]

    assert verdict() == "ok"
    usable = {"s0L": left, "s0R": right}
    assert not unseen_by_partner(left, usable, (), 0.0)                  # no pair: two separate views
    assert not unseen_by_partner(left, usable, pairs, None)              # s0L had no previous check
    assert not unseen_by_partner(left, usable, pairs, 6.0)               # built up check by check
    # ... where the other view sees no extra material at all, the hair is still unseen by the other views
    # (verdict.unseen_by_the_other_views, tests/vision/test_extra_unseen_by_other_views.py)
    assert verdict(pairs=()) == verdict(before={"s0R": 0.0}) == verdict(before={"s0L": 6.0, "s0R": 0.0}) == "ok"
    assert verdict(right=replace(right, extra_pct=1.0)) == "fail"        # the partner sees some too
    # a decisive view still fails where it does not read the part rising (both views read the rise here to the
    # pixel, and decisive extra material that no other view sees while both read the part rise is the view's own
    # error: verdict.unseen_by_the_other_views)
    assert verdict(left=replace(left, decisive=True, coarse_growth_pct=None)) == "fail"
    assert verdict(left=replace(left, decisive=True), pairs=()) == "ok"
    assert verdict(right=replace(right, usable=False)) == "fail"         # a single usable view
