"""Normal prints the combined verdict once paused on a confidently wrong size, replayed through
``printwatch evaluate``'s code path (``evaluate_recording``: shape check, then the pair's size check).

Both recordings are cut from PrintWatch's own simulator's hostile hold-out sets (tests/data/SOURCES.md);
the shape check passed every check of both, the size check alone paused them.
"""
from pathlib import Path

from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.recording import load_recording

DATA = Path(__file__).resolve().parents[1] / "data" / "recordings"


def _pair_checks(document):
    # every recording here has one pair
    return [(check["layer"], next(iter(check["size"].values()))) for check in document["checks"]]


def test_a_skirt_beside_a_low_part_is_not_read_as_its_width():
    # sun gear, grey on green PEI, twice a user's calibration error: at 6.6 mm both cameras' silhouette
    # sides were the skirt ring on the bed, read as a gear 50.3 mm wide for 43.9 (10.2 %, a pause)
    document = evaluate_recording(load_recording(DATA / "sun_gear_skirt_calib2_pair"))
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok"]
    layer, size = _pair_checks(document)[-1]
    assert not (size["error_pct"] or 0.0) > size["threshold_pct"], size
    # not confidently wrong: the width is left unmeasured (the sides may be the skirt's) ...
    assert size["width_mm"] is None and "flat material on the bed" in size["reason"], size
    # ... while the height, which the skirt does not touch, is still measured and right
    assert abs(size["height_mm"] - 6.6) < 0.3 and size["error_pct"] == 0.0, size


def test_not_finding_the_top_of_a_poorly_seen_part_is_no_evidence_that_it_is_missing():
    # black rectangular prism on a black bed: both views see it narrower than the model (its dark sides
    # and top merge with the bed), the outline and matched points miss its top, and the seed's rule
    # ("nothing reconstructed at the current height": 100 %) paused the normal print at 13.2 mm
    document = evaluate_recording(load_recording(DATA / "rect_prism_black_on_black_pair"))
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok", "ok"]
    assert document["first_failure_layer"] is None
    for layer, size in _pair_checks(document):
        assert size["error_pct"] is None or size["error_pct"] <= size["threshold_pct"], (layer, size)
    layer, size = _pair_checks(document)[1]
    assert size["abstained"] and "poorly seen" in size["reason"], size


def _stalled_copy(source: Path, target: Path) -> Path:
    """The recording with its last check's frames replaced by the check before's: the part stopped
    growing between them (a runout), everything else as recorded."""
    import json
    import shutil

    shutil.copytree(source, target)
    session = json.loads((target / "session.json").read_text())
    session["checks"][-1]["frames"] = dict(session["checks"][-2]["frames"])
    (target / "session.json").write_text(json.dumps(session))
    return target


def test_a_tier_seen_inside_its_wider_base_is_not_taken_for_missing_while_it_grows():
    # translucent blue "stack" (cross-check simulator, seed 6, 010_normal): a 16-mm cylinder on a 54-mm
    # box, both seen from above, so in both views the cylinder lies inside the box's silhouette and gives
    # no outline; the outline stereo found nothing at 36 mm ("top found at 24.0 mm"): 100 %, a pause
    document = evaluate_recording(load_recording(DATA / "stack_tier_inside_pair"))
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok", "ok", "ok"]
    for layer, size in _pair_checks(document):
        assert size["error_pct"] is None or size["error_pct"] <= size["threshold_pct"], (layer, size)
    layer, size = _pair_checks(document)[-1]
    assert size["abstained"] and "inside lower, wider material" in size["reason"], size
    # the model itself gives no outline there, and both views saw the cylinder's wall grow
    assert size["rectification"]["model_outline_in_band"] == 0, size
    assert min(size["rectification"]["changed_where_new"]) >= 0.05, size


def test_a_tier_seen_inside_its_wider_base_that_stopped_growing_is_still_caught(tmp_path):
    # the same print with its last picture the previous check's (the cylinder stopped at 33.6 mm while
    # the model is at 36 mm): nothing changed where the model's newest band lies, so "nothing
    # reconstructed at the current height" still holds (as on seed 6's 036_runout, a tier that never came)
    stalled = _stalled_copy(DATA / "stack_tier_inside_pair", tmp_path / "rec")
    document = evaluate_recording(load_recording(stalled))
    layer, size = _pair_checks(document)[-1]
    assert size["error_pct"] == 100.0 and "nothing reconstructed at the current height" in size["reason"], size
    assert max(size["rectification"]["changed_where_new"]) < 0.05, size
    assert document["checks"][-1]["verdict"] == "fail"
