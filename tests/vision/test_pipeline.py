"""CheckRunner over a sequence of checks of a synthetic box print seen by real (OpenCV) cameras.

The expected views are built here from the box's projected corners, so these tests
exercise the pipeline (regions from the calibrated camera, state across checks,
the decision rule, the JSON contract) without the geometry module.
"""
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.pipeline import CheckRunner, JobPlan, bed_box_mask, camera_bounds
from octoprint_printwatch.core.settings import DetectionSettings

W, H = 320, 240
LO, HI = np.array([90.0, 90.0]), np.array([110.0, 110.0])
HEIGHTS = [(10, 2.0), (20, 4.0), (30, 6.0), (40, 8.0)]


def box_mask(cam: Camera, z: float, offset=(0.0, 0.0)) -> np.ndarray:
    lo, hi = LO + offset, HI + offset
    corners = np.array([[x, y, zz] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for zz in (0.0, z)])
    uv = cam.project(corners)
    mask = np.zeros((cam.height, cam.width), np.uint8)
    cv2.fillConvexPoly(mask, cv2.convexHull(np.round(uv).astype(np.int32)), 1)
    return mask.astype(bool)


def make_plan(cams: dict[str, Camera], settings: DetectionSettings) -> JobPlan:
    views, footprint = {}, np.array([[LO[0], LO[1]], [HI[0], LO[1]], [HI[0], HI[1]], [LO[0], HI[1]]])
    for name, cam in cams.items():
        previous = np.zeros((H, W), bool)
        for _, z in HEIGHTS:
            sil = box_mask(cam, z)
            views[(name, z)] = SimpleNamespace(silhouette=sil, new_band=sil & ~previous, silhouette_undistorted=sil)
            previous = sil
    bounds = {n: camera_bounds(c, footprint, 8.0, settings) for n, c in cams.items()}
    return JobPlan(part=None, cameras=cams, pairs=[], check_heights=HEIGHTS, views=views, footprint=footprint,
                   max_shift_px={n: b[0] for n, b in bounds.items()}, tolerance_px={n: b[1] for n, b in bounds.items()},
                   px_per_mm={n: b[2] for n, b in bounds.items()})


@pytest.fixture(scope="module")
def cams():
    return {"a": Camera.look_at("a", (100, -20, 60), (100, 100, 4), width=W, height=H, hfov_deg=40),
            "b": Camera.look_at("b", (210, 120, 50), (100, 100, 4), width=W, height=H, hfov_deg=40)}


def bed(seed):
    rng = np.random.default_rng(seed)
    img = np.full((H, W, 3), (60, 170, 200), np.float32) + cv2.GaussianBlur(
        rng.normal(0, 8, (H, W, 3)).astype(np.float32), (0, 0), 1.0)
    return np.clip(img, 0, 255).astype(np.uint8)


def frame(cam, background, z, seed, offset=(0.0, 0.0)):
    img = background.astype(np.float32)
    side = box_mask(cam, z, offset)
    img[side] = (40, 40, 190)
    top_corners = np.array([[x, y, z] for x in (LO[0] + offset[0], HI[0] + offset[0])
                            for y in (LO[1] + offset[1], HI[1] + offset[1])])
    top = np.zeros((H, W), np.uint8)
    cv2.fillConvexPoly(top, cv2.convexHull(np.round(cam.project(top_corners)).astype(np.int32)), 1)
    img[top.astype(bool)] = (70, 70, 230)  # the lit top face
    img += np.random.default_rng(seed).normal(0, 2.5, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def run_print(cams, heights_printed, dead=(), offsets=None):
    settings = DetectionSettings()
    plan = make_plan(cams, settings)
    backgrounds = {n: bed(i) for i, n in enumerate(cams)}
    runner = CheckRunner(plan, settings, backgrounds)
    out = []
    for k, ((layer, z), printed) in enumerate(zip(HEIGHTS, heights_printed)):
        frames = {n: None if (n in dead) else
                  frame(c, backgrounds[n], printed, 10 * k + i, (offsets or {}).get(k, (0.0, 0.0)))
                  for i, (n, c) in enumerate(cams.items())}
        out.append(runner.run_check(layer, z, frames))
    return out


def test_normal_print_passes_every_check(cams):
    results = run_print(cams, [z for _, z in HEIGHTS])
    assert [r.verdict for r in results] == ["ok"] * 4
    assert all(max(r.shape_error_pct.values()) < 3 for r in results)


def test_runout_fails_at_the_first_check_after_the_part_stopped_growing(cams):
    results = run_print(cams, [2.0, 4.0, 4.0, 4.0])
    assert [r.verdict for r in results] == ["ok", "ok", "fail", "fail"]
    assert any("missing" in reason or "not grown" in reason for reason in results[2].reasons)


def test_part_knocked_10mm_fails(cams):
    # a short part slid 10 mm stays inside the bed-marks zone where brims are forgiven: it must
    # still be found, whichever way it went, and never be explained away as a brim
    for offset in [(10.0, 0.0), (0.0, 10.0), (-10.0, 0.0), (0.0, -10.0)]:
        results = run_print(cams, [2.0, 4.0, 6.0, 8.0], offsets={2: offset, 3: offset})
        assert [r.verdict for r in results] == ["ok", "ok", "fail", "fail"], offset
        assert any("away from where it belongs" in reason or "displaced" in reason
                   for reason in results[2].reasons), offset


def test_dead_camera_is_reported_and_never_pauses(cams):
    results = run_print(cams, [z for _, z in HEIGHTS], dead=("b",))
    assert [r.verdict for r in results] == ["ok"] * 4
    assert results[0].unreadable == ["b"] and "b: no frame" in results[0].reasons[0]
    all_dead = run_print(cams, [2.0, 4.0, 4.0, 4.0], dead=("a", "b"))
    assert [r.verdict for r in all_dead] == ["unknown"] * 4


def test_check_json_is_the_evaluate_contract(cams):
    entry = run_print(cams, [2.0, 4.0, 6.0, 8.0], dead=("b",), offsets={2: (10.0, 0.0)})[2].to_json()
    assert {"layer", "z", "verdict", "shape_error_pct", "size", "reasons", "seconds"} <= set(entry)
    assert entry["layer"] == 30 and entry["z"] == 6.0 and entry["verdict"] == "fail"
    assert entry["shape_error_pct"]["b"] is None and entry["shape_error_pct"]["a"] > 7
    assert entry["size"] == {} and entry["seconds"] > 0


def test_search_region_stays_below_the_parked_hotend(cams):
    cam = cams["a"]
    region = bed_box_mask(cam, np.array([LO, [HI[0], LO[1]], HI, [LO[0], HI[1]]]), 20.0, 0.0, 11.0)
    hotend_at_30mm = cam.project(np.array([[100.0, 100.0, 30.0]]))[0]
    part_top = cam.project(np.array([[100.0, 100.0, 8.0]]))[0]
    assert region[int(part_top[1]), int(part_top[0])]
    assert not region[int(hotend_at_30mm[1]), int(hotend_at_30mm[0])]



def test_frames_of_another_aspect_ratio_are_reported_never_checked(cams):
    # camera "a" now delivers 16:9 frames (its resolution was changed after calibration): it is reported
    # with the reason and gives no verdict, so a runout is judged on "b" alone; "b" at twice its
    # calibrated resolution (same picture, same aspect ratio) is resized and checked as usual
    settings = DetectionSettings()
    backgrounds = {n: bed(i) for i, n in enumerate(cams)}
    runner = CheckRunner(make_plan(cams, settings), settings, backgrounds)
    results = []
    for k, ((layer, z), printed) in enumerate(zip(HEIGHTS, [2.0, 4.0, 4.0, 4.0])):
        a = frame(cams["a"], backgrounds["a"], printed, 10 * k)
        b = frame(cams["b"], backgrounds["b"], printed, 10 * k + 1)
        results.append(runner.run_check(layer, z, {"a": cv2.resize(a, (W, W * 9 // 16)),
                                                   "b": cv2.resize(b, (2 * W, 2 * H))}))
    assert [r.verdict for r in results] == ["ok", "ok", "fail", "fail"]
    for r in results:
        assert r.shape_error_pct["a"] is None and "a" in r.unreadable
        assert any(reason.startswith("a: frames are 320x180, another aspect ratio than the calibrated 320x240")
                   for reason in r.reasons)
        assert r.shape_error_pct["b"] is not None


def test_a_background_of_another_aspect_ratio_is_reported(cams):
    settings = DetectionSettings()
    backgrounds = {n: bed(i) for i, n in enumerate(cams)}
    runner = CheckRunner(make_plan(cams, settings), settings,
                         dict(backgrounds, b=cv2.resize(backgrounds["b"], (W, W * 9 // 16))))
    layer, z = HEIGHTS[0]
    result = runner.run_check(layer, z, {n: frame(c, backgrounds[n], z, i) for i, (n, c) in enumerate(cams.items())})
    assert result.verdict == "ok" and "b" in result.unreadable
    assert any(reason.startswith("b: background frames are 320x180") for reason in result.reasons)


def test_a_camera_back_after_a_missed_check_gives_no_growth_reading(cams):
    # "b" gave no frame at the second check: at the third, its only mask is from the first check, while
    # the expected rise is the second check's to the third; comparing the two read 187.5 % (and a stalled
    # part as still growing), so no growth reading is made until it has a mask of the previous check
    settings = DetectionSettings()
    backgrounds = {n: bed(i) for i, n in enumerate(cams)}
    runner = CheckRunner(make_plan(cams, settings), settings, backgrounds)
    growth = []
    for k, (layer, z) in enumerate(HEIGHTS):
        frames = {n: None if (n == "b" and k == 1) else frame(c, backgrounds[n], z, 10 * k + i)
                  for i, (n, c) in enumerate(cams.items())}
        result = runner.run_check(layer, z, frames)
        growth.append({n: r.growth_pct for n, r in result.shape.items()})
        assert result.verdict == "ok"
    assert "b" not in growth[1] and growth[2]["b"] is None
    assert growth[3]["b"] == pytest.approx(100, abs=25)   # consecutive checks again
