"""The second look for extra material alone: when the smallest move of the shifts no passing check could tell
apart does not pass, the one that puts the expected upper outline on the observed one gets a look too.

Recording (tests/data/SOURCES.md): cross-check seed 6 ``004_normal``, camera s1 only, layers 15, 30, 45: a red
block on a brim whose stated calibration puts it ~11 px low (true cameras in truth.json: the best shift of the
stated silhouette onto the true one is (0, -11) px). The first check is flat: the outline fits anywhere over
a 45 x 15 px plateau of brim; the first pick (6, -9) sits 7 px right, and from layer 30 the block's left face
beyond the outline read 9-10 % "extra" at every check (the print was paused at layer 30).
"""
import shutil
from pathlib import Path

import cv2

from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.recording import load_recording

DATA = Path(__file__).resolve().parents[1] / "data" / "recordings"
BLOCK = DATA / "stack_brim_calib_offset_single"


def test_an_outline_slid_along_the_brim_is_checked_again_where_the_upper_outlines_agree():
    document = evaluate_recording(load_recording(BLOCK))
    assert [c["verdict"] for c in document["checks"]] == ["ok"] * 3
    later = [c["shape"]["s1"] for c in document["checks"][1:]]
    assert all(s["extra_pct"] < s["threshold"] / 2.0 for s in later)
    # checked again at another shift of the remembered set, near the true offset (0, -11) px
    assert all(s["shift_px"] != document["checks"][0]["shape"]["s1"]["shift_px"] for s in later)
    assert all(abs(s["shift_px"][0]) <= 4 and abs(s["shift_px"][1] + 11) <= 4 for s in later)


def test_a_blob_on_the_part_is_not_explained_away(tmp_path):
    # the same view with a blob of the part's colour stuck to the block's top corner at the last check
    copy = tmp_path / BLOCK.name
    shutil.copytree(BLOCK, copy)
    frame_path = copy / "checks" / "002" / "s1.jpg"
    frame = cv2.imread(str(frame_path))
    colour = [int(v) for v in frame[300, 300]]   # the block's front face
    cv2.circle(frame, (385, 292), 12, colour, -1)
    cv2.imwrite(str(frame_path), frame)
    document = evaluate_recording(load_recording(copy))
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok", "fail"]
    assert document["checks"][-1]["shape"]["s1"]["extra_pct"] > document["checks"][-1]["shape"]["s1"]["threshold"]
