"""Frames of any size are checked at the settings' working width, with the camera scaled to match."""
import cv2
import numpy as np
import pytest
import trimesh

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.pipeline import CheckRunner, prepare_job, to_working_size, working_camera
from octoprint_printwatch.core.render import render_silhouette
from octoprint_printwatch.core.settings import DetectionSettings, SettingsError

HEIGHTS = [(20, 4.0), (40, 8.0), (60, 12.0)]


def test_the_working_camera_sees_every_point_where_the_resized_frame_shows_it():
    cam = Camera.look_at("hd", (100, -60, 90), (100, 100, 5), width=1920, height=1080, hfov_deg=50)
    small = working_camera(cam, 640)
    assert (small.width, small.height) == (640, 360)
    points = np.array([[100.0, 100.0, 0.0], [80.0, 120.0, 10.0], [130.0, 90.0, 20.0]])
    scale = 640 / 1920
    assert np.allclose(small.project(points), (cam.project(points) + 0.5) * scale - 0.5, atol=1e-6)
    assert working_camera(cam, 0) is cam and working_camera(small, 640) is small
    with pytest.raises(SettingsError):
        DetectionSettings(working_width=100)


def paint(cam: Camera, part, z: float, bed: np.ndarray, seed: int) -> np.ndarray:
    img = bed.astype(np.float32).copy()
    img[render_silhouette(part, cam, z)] = (40, 40, 190)
    img += np.random.default_rng(seed).normal(0, 2.5, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def test_a_1280_wide_camera_is_checked_at_640_and_still_catches_a_runout(tmp_path):
    box = trimesh.creation.box(extents=(20.0, 20.0, 12.0))
    box.apply_translation((100.0, 100.0, 6.0))
    model = tmp_path / "box.stl"
    box.export(model)
    cams = {"a": Camera.look_at("a", (100, -40, 70), (100, 100, 5), width=1280, height=960, hfov_deg=40),
            "b": Camera.look_at("b", (230, 110, 60), (100, 100, 5), width=1280, height=960, hfov_deg=40)}
    plan = prepare_job(model_path=model, cameras=cams, check_heights=HEIGHTS, settings=DetectionSettings())
    assert all((c.width, c.height) == (640, 480) for c in plan.cameras.values())
    rng = np.random.default_rng(0)
    beds = {n: np.clip(np.full((960, 1280, 3), (60, 170, 200), np.float32)
                       + cv2.GaussianBlur(rng.normal(0, 8, (960, 1280, 3)).astype(np.float32), (0, 0), 1.5),
                       0, 255).astype(np.uint8) for n in cams}
    from octoprint_printwatch.core.geometry import part_from_mesh
    part = part_from_mesh(model)

    def run(printed_heights):
        runner = CheckRunner(plan, DetectionSettings(), beds)
        verdicts = []
        for k, ((layer, z), printed) in enumerate(zip(HEIGHTS, printed_heights)):
            frames = {n: paint(c, part, printed, beds[n], 10 * k + i) for i, (n, c) in enumerate(cams.items())}
            result = runner.run_check(layer, z, frames)
            assert all(r.observed_mask.shape == (480, 640) for r in result.shape.values())
            verdicts.append(result.verdict)
        return verdicts

    assert run([4.0, 8.0, 12.0]) == ["ok", "ok", "ok"]
    assert run([4.0, 8.0, 8.0])[-1] == "fail"          # stopped at 8 mm: the top third is missing
    assert to_working_size(None, plan.cameras["a"]) is None


def test_projecting_a_strided_view_of_points_matches_projecting_a_copy():
    # cv2.projectPoints refuses non-contiguous input; callers slice point arrays (every other corner)
    cam = Camera.look_at("a", (100, -20, 60), (100, 100, 4), width=320, height=240, hfov_deg=40)
    points = np.array([[x, y, z] for x in (90.0, 110.0) for y in (90.0, 110.0) for z in (0.0, 8.0)])
    assert np.allclose(cam.project(points[1::2]), cam.project(points[1::2].copy()))
