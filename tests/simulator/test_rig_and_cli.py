"""Camera rigs as the issue describes them, and the `printwatch simulate` command."""
import json

import cv2
import numpy as np
import pytest

from octoprint_printwatch.cli import main
from octoprint_printwatch.core.errors import PrintWatchError
from octoprint_printwatch.core.recording import load_recording
from octoprint_printwatch.simulator.rig import make_rig


def angle_deg(R1, R2):
    return float(np.degrees(np.linalg.norm(cv2.Rodrigues(R1 @ R2.T)[0])))


def test_three_stations_120_degrees_apart_each_a_relaxed_pair_all_seeing_the_bed_centre():
    rig = make_rig("stations3", seed=7)
    assert rig.names == ["cam0L", "cam0R", "cam1L", "cam1R", "cam2L", "cam2R"]
    assert rig.pairs == [("cam0L", "cam0R"), ("cam1L", "cam1R"), ("cam2L", "cam2R")]
    centre = np.array([100.0, 100.0, 10.0])
    azimuths = []
    for left, right in rig.pairs:
        L, R = rig.true(left), rig.true(right)
        azimuths.append(np.degrees(np.arctan2(*(L.center - centre)[1::-1])))
        # Relaxed: different distances to the part, yawed relative to each other, different focal lengths.
        assert abs(np.linalg.norm(L.center - centre) - np.linalg.norm(R.center - centre)) > 8
        assert angle_deg(L.R, R.R) > 1.0
        assert abs(L.K[0, 0] / R.K[0, 0] - 1) > 0.001
        for cam in (L, R):
            u, v = cam.project([centre])[0]
            assert 0.15 * cam.width < u < 0.85 * cam.width and 0.15 * cam.height < v < 0.85 * cam.height
    az = np.sort(np.asarray(azimuths) % 360)
    gaps = np.diff(np.append(az, az[0] + 360))
    assert gaps == pytest.approx([120, 120, 120], abs=15)


def test_calibration_handed_to_the_detector_is_realistically_wrong():
    focal, rotation, position = [], [], []
    for seed in range(6):
        rig = make_rig("stations3", seed=seed)
        for true, cal in zip(rig.cameras_true, rig.cameras_calibrated):
            focal.append(abs(cal.K[0, 0] / true.K[0, 0] - 1) * 100)
            rotation.append(angle_deg(true.R, cal.R))
            position.append(np.linalg.norm(true.center - cal.center))
    # About 1 % focal, half a degree, a millimetre; never exact, never wild.
    assert 0.4 < np.mean(focal) < 1.6 and max(focal) < 4
    assert 0.2 < np.mean(rotation) < 0.8 and max(rotation) < 2.0
    assert 0.4 < np.mean(position) < 1.6 and max(position) < 4.0
    assert min(rotation) > 0 and min(position) > 0


def test_rig_kinds_and_bad_rigs():
    assert len(make_rig("ring", n_cameras=5).names) == 5
    assert len(make_rig("single").names) == 1
    with pytest.raises(PrintWatchError, match="1 to 6 cameras"):
        make_rig("ring", n_cameras=7)
    with pytest.raises(PrintWatchError, match="unknown rig 'dome'"):
        make_rig("dome")


def test_simulate_writes_a_readable_recording_with_truth(tmp_path):
    out = tmp_path / "rec"
    code = main(["simulate", str(out), "--part", "prism", "--scenario", "runout", "--onset-layer", "40",
                 "--rig", "pair", "--size", "320x240", "--seed", "4", "--every", "20"])
    assert code == 0
    rec = load_recording(out)
    assert sorted(rec.cameras) == ["cam0L", "cam0R"] and rec.pairs == [("cam0L", "cam0R")]
    assert rec.model is not None and rec.gcode is not None and rec.layer_height == 0.2
    assert [c.layer for c in rec.checks] == [20, 40, 60, 80, 90]
    assert rec.checks[2].z == pytest.approx(12.0)
    frame = rec.read_frame(rec.checks[-1], "cam0R")
    assert frame.shape == (240, 320, 3)
    assert rec.read_background("cam0L").shape == (240, 320, 3)
    truth = json.loads((out / "truth.json").read_text())
    assert truth["scenario"]["kind"] == "runout" and truth["onset_z"] == pytest.approx(7.8)
    assert [c["should_flag"] for c in truth["checks"]] == [False, False, True, True, True]
    assert [c["true_top_z"] for c in truth["checks"]] == pytest.approx([4.0, 7.8, 7.8, 7.8, 7.8])
    # The detector gets the calibrated cameras, not the truth.
    session = json.loads((out / "session.json").read_text())
    assert session["cameras"]["cam0L"]["K"] != truth["cameras_true"]["cam0L"]["K"]


@pytest.mark.parametrize("argv,message", [
    (["--part", "no_such_part"], "no_such_part: no such file"),
    (["--onset-layer", "0", "--scenario", "runout"], "onset layer must be 1 or more"),
    (["--size", "big"], "--size must look like 640x480"),
    (["--every", "0"], "--every must be 1 or more"),
    (["--onset-layer", "5"], "--onset-layer needs a failing --scenario"),
])
def test_simulate_bad_input_is_one_line_exit_2(tmp_path, capsys, argv, message):
    assert main(["simulate", str(tmp_path / "x"), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_simulate_refuses_a_mesh_that_is_not_a_solid(tmp_path, capsys):
    import trimesh

    flat = tmp_path / "two_triangles.stl"
    trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0], [5, 5, 5], [6, 5, 5], [5, 6, 5]],
                    [[0, 1, 2], [3, 4, 5]]).export(flat)
    assert main(["simulate", str(tmp_path / "out"), "--part", str(flat)]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{flat}: the mesh is not a closed solid" in err and len(err.splitlines()) == 1
    assert not (tmp_path / "out" / "session.json").exists()
