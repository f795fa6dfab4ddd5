"""Recordings: written by RecordingWriter, read back by load_recording, and every kind of bad input
refused with one line naming the file and the problem."""
import json

import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.errors import RecordingError
from octoprint_printwatch.core.recording import RecordingWriter, load_recording


def cams():
    return {name: Camera.look_at(name, eye, (100, 100, 10), width=160, height=120)
            for name, eye in (("a", (100, -80, 80)), ("b", (130, -80, 80)))}


@pytest.fixture
def recording(tmp_path, gcode_dir):
    rng = np.random.default_rng(0)
    img = lambda: rng.integers(0, 255, (120, 160, 3), dtype=np.uint8)  # noqa: E731
    w = RecordingWriter(tmp_path / "rec", cams(), pairs=[("a", "b")], gcode=gcode_dir / "prusa25_cylinder.gcode",
                        layer_height=0.2, image_format="png")
    w.add_background("a", img())
    w.add_background("b", img())
    w.add_check(30, 6.0, {"a": img(), "b": img()})
    w.add_check(60, 12.0, {"a": img(), "b": None})  # camera b died
    return tmp_path / "rec"


def edit(path, change):
    doc = json.loads((path / "session.json").read_text())
    change(doc)
    (path / "session.json").write_text(json.dumps(doc))


def test_round_trip(recording):
    rec = load_recording(recording)
    assert set(rec.cameras) == {"a", "b"}
    assert rec.pairs == [("a", "b")]
    assert rec.gcode.name == "print.gcode" and rec.model is None
    assert [(c.layer, c.z) for c in rec.checks] == [(30, 6.0), (60, 12.0)]
    assert rec.read_frame(rec.checks[1], "b") is None       # dead camera: no frame, not an error
    assert rec.read_frame(rec.checks[0], "a").shape == (120, 160, 3)
    np.testing.assert_allclose(rec.cameras["a"].K, cams()["a"].K)


def test_missing_folder_and_session(tmp_path):
    with pytest.raises(RecordingError, match="no such directory"):
        load_recording(tmp_path / "nope")
    with pytest.raises(RecordingError, match="session.json: missing"):
        load_recording(tmp_path)


def test_bad_json_names_the_line(recording):
    (recording / "session.json").write_text('{"format": "printwatch-recording/1",\n "cameras": }')
    with pytest.raises(RecordingError, match=r"session.json: bad JSON at line 2"):
        load_recording(recording)


@pytest.mark.parametrize("change, message", [
    (lambda d: d.update(pairs=[["a", "zz"]]), "pairs\\[0\\] names unknown camera 'zz'"),
    (lambda d: d.update(format="other/2"), "unsupported format"),
    (lambda d: d.pop("gcode"), "neither 'model' nor 'gcode'"),
    (lambda d: d["checks"][0].update(layer=-1), "checks\\[0\\].layer"),
    (lambda d: d["checks"][0]["frames"].update(a="checks/000"), "000: missing"),
    (lambda d: d["checks"][0].update(layer=2.5), "checks\\[0\\].layer"),
    (lambda d: d["cameras"]["a"].update(K=[[1, 2], [3]]), "camera a"),
    (lambda d: d.update(units="inch"), "units must be 'mm'"),
    (lambda d: d.update(model="../outside.stl"), "outside the recording folder"),
])
def test_invalid_session_is_refused_with_one_line(recording, change, message):
    edit(recording, change)
    with pytest.raises(RecordingError, match=message) as info:
        load_recording(recording)
    assert "\n" not in str(info.value)


def test_missing_frame_file_is_named(recording):
    (recording / "checks" / "000" / "a.png").unlink()
    with pytest.raises(RecordingError, match=r"000/a.png: missing"):
        load_recording(recording)


def test_unreadable_image_is_named_when_read(recording):
    (recording / "checks" / "000" / "a.png").write_bytes(b"not an image")
    rec = load_recording(recording)
    with pytest.raises(RecordingError, match=r"a.png: unreadable image"):
        rec.read_frame(rec.checks[0], "a")


def test_writer_keeps_session_valid_after_every_check(tmp_path, gcode_dir):
    w = RecordingWriter(tmp_path / "r", cams(), gcode=gcode_dir / "prusa25_cylinder.gcode")
    assert load_recording(tmp_path / "r").checks == []
    w.add_background("a", np.zeros((120, 160, 3), np.uint8))
    w.add_check(5, 1.0, {"a": np.zeros((120, 160, 3), np.uint8)})
    assert len(load_recording(tmp_path / "r").checks) == 1
