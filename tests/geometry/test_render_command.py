"""``printwatch render``: expected views as PNG files, and one-line errors."""
import json

import cv2
import numpy as np

from octoprint_printwatch.cli import main
from octoprint_printwatch.core.camera import Camera


def write_cameras(tmp_path):
    paths = []
    for name, eye in (("left", (230.0, 10.0, 110.0)), ("right", (-30.0, 10.0, 110.0))):
        path = tmp_path / f"{name}.json"
        Camera.look_at(name, eye, (100.0, 100.0, 15.0), focal_px=700.0, dist=[-0.2, 0.05, 0, 0, 0]).save(path)
        paths.append(path)
    return paths


def test_render_writes_every_view_of_a_gcode_part(tmp_path, corpus, capsys):
    left, right = write_cameras(tmp_path)
    out = tmp_path / "views"
    code = main(["render", str(out), "--gcode", str(corpus / "prusa25_pyramid_fwretract.gcode"),
                 "--camera", str(left), "--camera", str(right), "--z", "5", "--z", "15"])
    assert code == 0
    summary = json.loads((out / "views.json").read_text())
    assert summary["part"]["source"] == "gcode"
    assert [(v["camera"], v["z"]) for v in summary["views"]] == [("left", 5.0), ("left", 15.0), ("right", 5.0), ("right", 15.0)]
    low = cv2.imread(str(out / "left_z005.000_silhouette.png"), cv2.IMREAD_GRAYSCALE)
    high = cv2.imread(str(out / "left_z015.000_silhouette.png"), cv2.IMREAD_GRAYSCALE)
    band = cv2.imread(str(out / "left_z015.000_band.png"), cv2.IMREAD_GRAYSCALE)
    depth = cv2.imread(str(out / "left_z015.000_depth.png"), cv2.IMREAD_GRAYSCALE)
    assert low.shape == (480, 640) and set(np.unique(low)) == {0, 255}
    assert (high > 0).sum() > (low > 0).sum() > 1000
    assert 0 < (band > 0).sum() < (high > 0).sum() and not np.any((band > 0) & (high == 0))
    assert np.count_nonzero((depth > 0) ^ (high > 0)) < 0.005 * (high > 0).sum()
    assert "left z=15.000 mm" in capsys.readouterr().out


def test_render_reports_bad_input_in_one_line(tmp_path, corpus, capsys):
    left, _ = write_cameras(tmp_path)
    cases = [
        (["--model", str(tmp_path / "none.stl"), "--camera", str(left)], "none.stl: no such mesh file"),
        (["--model", str(corpus / "cube.stl"), "--camera", str(tmp_path / "cam.json")], "cam.json: no such file"),
        (["--model", str(corpus / "cube.stl")], "--camera"),
        (["--camera", str(left)], "--model, --gcode or --session"),
        (["--model", str(corpus / "cube.stl"), "--camera", str(left), "--z", "-1"], "above the bed"),
    ]
    for extra, message in cases:
        assert main(["render", str(tmp_path / "out")] + extra) == 2
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1 and "Traceback" not in err


def test_render_takes_cameras_part_and_heights_from_a_recording(tmp_path, corpus, capsys):
    import shutil

    session = tmp_path / "session"
    (session / "checks" / "000").mkdir(parents=True)
    cube = __import__("trimesh").load(corpus / "cube.stl")
    cube.apply_translation((100.0, 100.0, 0.0))
    cube.export(session / "model.stl")
    camera = Camera.look_at("cam0", (230.0, 10.0, 110.0), (100.0, 100.0, 15.0), focal_px=700.0)
    frame = np.zeros((480, 640, 3), np.uint8)
    cv2.imwrite(str(session / "checks" / "000" / "cam0.png"), frame)
    doc = {"format": "printwatch-recording/1", "units": "mm", "model": "model.stl", "layer_height": 0.2,
           "cameras": {"cam0": camera.to_dict()}, "pairs": [],
           "checks": [{"layer": 60, "z": 12.0, "frames": {"cam0": "checks/000/cam0.png"}}]}
    (session / "session.json").write_text(json.dumps(doc))
    out = tmp_path / "views"
    assert main(["render", str(out), "--session", str(session)]) == 0
    summary = json.loads((out / "views.json").read_text())
    assert [(v["camera"], v["z"]) for v in summary["views"]] == [("cam0", 12.0)]
    assert summary["part"]["source"] == "mesh"
    shutil.rmtree(session / "checks")
    assert main(["render", str(out), "--session", str(session)]) == 2  # a broken recording: one line
    assert "cam0.png" in capsys.readouterr().err
