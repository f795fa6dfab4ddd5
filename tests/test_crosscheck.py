"""The cross-check simulator (``benchmarks/crosscheck``): an independent renderer whose recordings are valid
per docs/recording-format.md, whose truth says what was asked, and whose pictures put things where OpenCV's
camera model says they are."""
from __future__ import annotations

import ast
import json
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks.crosscheck import render, scenes  # noqa: E402
from benchmarks.crosscheck.render import BedLook, Camera, Light, Mesh, Sensor, look_at, render_view  # noqa: E402


def plain_scene_parts(width=160, height=120, dist=(0.0, 0, 0, 0, 0)):
    """A camera 250 mm from the bed centre at 35 deg elevation, a green bed, a blue backdrop, flat light."""
    rvec, tvec = look_at(np.array([110.0 - 200, 110.0 - 60, 150.0]), np.array([110.0, 110.0, 5.0]))
    f = 0.9 * width
    camera = Camera("c", width, height, np.array([[f, 0, width / 2 - 0.5], [0, f, height / 2 - 0.5], [0, 0, 1.0]]),
                    np.array(dist, float), rvec, tvec)
    texture = np.zeros((220, 220, 3), np.float32)
    texture[:, :, 1] = 0.8
    backdrop = np.zeros((32, 64, 3), np.float32)
    backdrop[:, :, 2] = 0.8
    bed = BedLook(texture, 220.0, np.array([0.0, 0.3, 0.0], np.float32), backdrop)
    light = Light(np.array([0.0, 0.0, 1.0]), ambient=1.0, diffuse=0.0)
    return camera, bed, light


def box_mesh(lo, hi, colour=(1.0, 0.0, 0.0)):
    from manifold3d import Manifold
    m = Manifold.cube(list(np.subtract(hi, lo))).translate(list(lo)).to_mesh()
    return Mesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), colour)


def test_the_renderer_draws_a_box_where_projectPoints_puts_its_corners():
    camera, bed, light = plain_scene_parts()
    lo, hi = (95.0, 100.0, 0.0), (125.0, 118.0, 20.0)
    image = render_view(camera, [box_mesh(lo, hi)], [], light, bed, supersample=2, shadow=np.zeros((4, 4), np.float32))
    red = image[:, :, 0] > 0.5                                   # the box is the only red thing in view

    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    uv = camera.project(corners)
    expected = np.zeros(red.shape, np.uint8)
    cv2.fillConvexPoly(expected, np.round(cv2.convexHull(uv.astype(np.float32)).reshape(-1, 2) * 16).astype(np.int32),
                       1, cv2.LINE_8, 4)
    expected = expected.astype(bool)
    assert red.sum() > 200
    union = (red | expected).sum()
    assert (red & expected).sum() / union > 0.9
    # every disagreement is on the outline: within a pixel of the expected silhouette's edge
    edge = cv2.dilate(expected.astype(np.uint8), np.ones((3, 3))) - cv2.erode(expected.astype(np.uint8), np.ones((3, 3)))
    assert not ((red ^ expected) & (edge == 0)).any()


def test_lens_distortion_puts_small_cubes_where_opencv_projects_them():
    camera, bed, light = plain_scene_parts(160, 120, dist=(-0.18, 0.05, 0.001, -0.001, 0.0))
    # cubes on the bed under pixels near the corners and the centre, where barrel distortion moves most
    pixels = np.array([[18.0, 14], [142, 14], [18, 106], [142, 106], [80, 60]])
    rays = np.c_[render.undistort_normalised(pixels, camera.K, camera.dist), np.ones(len(pixels))] @ camera.R
    eye = camera.centre
    centres = [eye + (1.0 - eye[2]) / r[2] * r for r in rays]
    image = render_view(camera, [box_mesh(c - 1.0, c + 1.0) for c in centres], [], light, bed,
                        shadow=np.zeros((4, 4), np.float32))
    red = (image[:, :, 0] > 0.15).astype(np.uint8)
    n, labels, stats, found = cv2.connectedComponentsWithStats(red)
    uv = camera.project(np.array(centres))
    assert n - 1 == len(centres)
    for u, v in uv:
        nearest = np.min(np.hypot(found[1:, 0] - u, found[1:, 1] - v))
        assert nearest < 0.6, (u, v, nearest)
    # and the distortion is strong enough to matter: an ideal pinhole would put them elsewhere
    pinhole, _ = cv2.projectPoints(np.array(centres), camera.rvec, camera.tvec, camera.K, np.zeros(5))
    assert np.max(np.hypot(*(pinhole.reshape(-1, 2) - uv).T)) > 2.0


def test_the_sensor_keeps_brightness_and_adds_noise():
    flat = np.full((60, 80, 3), 0.2, np.float32)
    rng = np.random.default_rng(1)
    out = render.expose(flat, Sensor(vignetting=0.0, blur_sigma=0.0, sharpen=0.0, gamma=2.2), 1.0, np.ones(3), rng)
    assert out.dtype == np.uint8 and out.shape == (60, 80, 3)
    assert abs(out.mean() - 255 * 0.2 ** (1 / 2.2)) < 3
    assert 0.5 < out.astype(float).std() < 10


@pytest.mark.parametrize("kind", ["runout", "layer_shift"])
def test_a_generated_recording_is_valid_and_its_truth_is_what_was_asked(tmp_path, kind):
    from octoprint_printwatch.core.recording import load_recording

    truth = scenes.generate(tmp_path / "rec", scenes.Recipe(seed=11, kind=kind, quick=True))
    recording = load_recording(tmp_path / "rec")
    session = json.loads((tmp_path / "rec" / "session.json").read_text())

    assert truth["kind"] == kind
    assert recording.model is not None and recording.gcode is None
    assert set(recording.cameras) == set(truth["cameras_true"])
    assert [(c.layer, round(c.z, 4)) for c in recording.checks] == [(c["layer"], c["z"]) for c in truth["checks"]]
    for name in recording.cameras:
        assert recording.read_background(name).shape[:2] == (120, 160)
    assert all(recording.read_frame(c, n) is not None for c in recording.checks for n in recording.cameras)
    # the stated camera is the true one plus a user's calibration error, not the truth itself
    stated, true = session["cameras"], truth["cameras_true"]
    for name in stated:
        assert stated[name]["rvec"] != true[name]["rvec"]
        assert abs(stated[name]["K"][0][0] / true[name]["K"][0][0] - 1) < 0.05

    n_layers = truth["part"]["layers"]
    onset, flag = truth["onset_layer"], truth["flag_check"]
    assert 0.2 * n_layers - 1 <= onset < n_layers
    first_after = truth["onset_check"]
    assert truth["checks"][first_after]["layer"] > onset
    assert all(not c["failure_started"] for c in truth["checks"][:first_after])
    # visible only once a millimetre has been printed (layer shift) or has gone missing (runout) since onset
    assert (truth["checks"][flag]["layer"] - onset) * 0.2 >= 1.0 - 1e-9
    if kind == "layer_shift":
        assert 2.0 <= float(np.hypot(*truth["shift_mm"])) <= 8.0


def test_the_renderer_never_imports_the_detector():
    """Independence is the point: render.py and scenes.py import numpy/OpenCV/trimesh/manifold3d only."""
    for module in ("render.py", "scenes.py"):
        tree = ast.parse((ROOT / "benchmarks" / "crosscheck" / module).read_text())
        imported = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        imported |= {n.module or "" for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        assert not any(name.startswith("octoprint") for name in imported), (module, imported)


def test_the_part_lands_where_the_detector_expects_it_with_the_true_camera():
    """Cross-validation of the two renderers' conventions (pose, intrinsics, distortion, pixel centres):
    with the true camera, this renderer's part pixels and core.render's expected silhouette agree."""
    import trimesh

    from octoprint_printwatch.core.camera import Camera as DetectorCamera
    from octoprint_printwatch.core.render import render_silhouette

    rng = np.random.default_rng(503)
    part, info = scenes.random_part(rng)
    centre = np.array([110.0, 90.0])
    part = part.translate((110.0, 90.0, 0.0))
    cameras, _, _ = scenes.random_rig(rng, centre, info["footprint_mm"] / 2, info["height_mm"], (320, 240))
    printed = scenes.below(part, info["height_mm"] * 0.6)
    _, bed, light = plain_scene_parts()
    mesh = scenes.to_mesh(printed, (1.0, 0.0, 0.0))
    solid = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    for camera in cameras[:2]:
        ours = render_view(camera, [mesh], [], light, bed, shadow=np.zeros((4, 4), np.float32))[:, :, 0] > 0.5
        expected = render_silhouette(solid, DetectorCamera.from_dict(camera.name, camera.to_json())).astype(bool)
        assert expected.sum() > 300
        assert (ours & expected).sum() / (ours | expected).sum() > 0.95
        ys, xs = np.nonzero(ours)
        ye, xe = np.nonzero(expected)
        assert abs(xs.mean() - xe.mean()) < 0.5 and abs(ys.mean() - ye.mean()) < 0.5


def test_a_set_folder_keeps_one_seed_and_calibration_error(tmp_path):
    """Evaluating a folder with another --seed than its recordings' refuses instead of filling the folder's missing
    recordings with that seed (a seed-2 set was once completed with seed-1 recordings and scored as one set)."""
    from benchmarks.bench_crosscheck import folder_recipe, main
    assert folder_recipe(tmp_path, None, None) == (1, 1.0)          # an empty folder: the defaults
    assert folder_recipe(tmp_path, 4, 2.0) == (4, 2.0)
    recording = tmp_path / "000_normal"
    recording.mkdir()
    (recording / "truth.json").write_text(json.dumps({"seed": 200000, "look": {"calibration_error": 1.0}}))
    assert folder_recipe(tmp_path, None, None) == (2, 1.0)          # the folder's own seed when none is given
    with pytest.raises(SystemExit, match="holds seed 2"):
        main(["--out", str(tmp_path), "--seed", "1", "--count", "3", "--generate-only"])
    with pytest.raises(SystemExit, match="calibration-error scale 1"):
        folder_recipe(tmp_path, 2, 3.0)
    other = tmp_path / "001_runout"
    other.mkdir()
    (other / "truth.json").write_text(json.dumps({"seed": 100001, "look": {"calibration_error": 1.0}}))
    with pytest.raises(SystemExit, match="several seeds"):
        folder_recipe(tmp_path, None, None)
