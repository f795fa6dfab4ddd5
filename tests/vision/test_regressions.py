"""Recordings of real false alarms, replayed through ``printwatch evaluate``'s code path."""
from pathlib import Path

from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.recording import load_recording

DATA = Path(__file__).resolve().parents[1] / "data" / "recordings"


def test_shadow_and_skirt_at_the_foot_of_a_normal_part_are_not_extra_material():
    # once paused a normal print in the OctoPrint integration test ("unexpected material 12.2 %" on cam1)
    document = evaluate_recording(load_recording(DATA / "cube_black_pei_shadow"))
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok"]
    assert document["first_failure_layer"] is None
    for check in document["checks"]:
        for camera, figures in check["shape"].items():
            assert figures["usable"], camera
            assert figures["extra_pct"] < 3.0, (check["layer"], camera, figures)


def test_the_top_of_a_normal_part_seen_through_double_jpeg_is_not_extra_material():
    # paused a normal demo print (`printwatch demo --part cube --cameras 2 --every 25 --failure none`) at
    # layer 75: cam0R "unexpected material 7.7 %", a sliver along the cube's top edge, where the
    # alignment had crept a few pixels down the part (frames JPEG'd by the camera and again by the server)
    document = evaluate_recording(load_recording(DATA / "cube_jpeg_top_sliver"))
    assert [c["verdict"] for c in document["checks"]] == ["ok", "ok", "ok"]
    for check in document["checks"]:
        for camera, figures in check["shape"].items():
            assert figures["extra_pct"] < 3.0, (check["layer"], camera, figures)
