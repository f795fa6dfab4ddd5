"""The seed's relaxed-geometry triangulation (Eqs. 2-2..2-14) against geometry and cv2.triangulatePoints."""
from __future__ import annotations

import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.stereo.rectify import rectify_calibrated
from octoprint_printwatch.core.stereo.triangulate import (SeedGeometry, reproject_disparity, seed_frame,
                                                          seed_triangulate, seed_triangulate_cameras,
                                                          triangulate_general)

# The seed's chapter-2 cameras: Firefly MV, 640 x 480, 6 um pixels, 16.6 mm lens.
W, H, PIXEL, F = 640, 480, 0.006, 16.6


def _seed_pixels(geometry: SeedGeometry, point):
    """Forward model of Figs. 2.3-2.5: where a seed-frame point (X, Y, Z) images in each camera."""
    X, Y, Z = point
    x_right = W / 2 + F / PIXEL * X / Z
    axis = np.array([-np.sin(geometry.theta), np.cos(geometry.theta)])  # left optical axis in (x, z)
    across = np.array([np.cos(geometry.theta), np.sin(geometry.theta)])  # left image x direction
    v = np.array([X, Z]) - np.array(geometry.left_center_xz)
    x_left = W / 2 + F / PIXEL * (v @ across) / (v @ axis)
    y_left = H / 2 - F / PIXEL * Y / (v @ axis)
    return x_left, y_left, x_right


@pytest.mark.parametrize("A, theta_deg", [(0.0, 0.0), (100.0, 0.0), (-80.0, 0.0), (100.0, 7.0), (-80.0, -4.5)])
def test_worked_example_of_the_relaxed_equations(A, theta_deg):
    """Fig. 2.6's four set-ups: left camera 200 mm aside, moved forward/back, turned 7 or 4.5 degrees."""
    geometry = SeedGeometry(f_left=F, f_right=F, pixel_left=PIXEL, pixel_right=PIXEL, width_left=W, height_left=H,
                            width_right=W, b2=200.0, A=A, theta=np.radians(theta_deg))
    P = np.array([-60.0, 40.0, 1200.0])
    x_left, y_left, x_right = _seed_pixels(geometry, P)
    result = seed_triangulate(geometry, [x_left], [y_left], [x_right])

    C_l = np.array(geometry.left_center_xz)
    # Eq. 2-10: the baseline and its tilt.
    assert result.b1 == pytest.approx(np.hypot(200.0, A))
    assert result.omega == pytest.approx(np.arctan2(A, 200.0))
    # Eqs. 2-7, 2-8: the ranges are the true distances in the horizontal plane.
    assert result.D1[0] == pytest.approx(np.linalg.norm(P[[0, 2]] - C_l), rel=1e-9)
    assert result.D2[0] == pytest.approx(np.linalg.norm(P[[0, 2]]), rel=1e-9)
    # Eq. 2-9: phi is the angle at the object between the two rays.
    to_l, to_r = C_l - P[[0, 2]], -P[[0, 2]]
    angle = np.arccos(to_l @ to_r / np.linalg.norm(to_l) / np.linalg.norm(to_r))
    assert result.phi[0] == pytest.approx(angle, rel=1e-9)
    # Eqs. 2-11..2-14: the point itself.
    np.testing.assert_allclose(result.points[0], P, atol=1e-6)


def test_the_seed_rotation_sign_matters():
    """Triangulating with theta of the wrong sign must give a visibly wrong point."""
    geometry = SeedGeometry(F, F, PIXEL, PIXEL, W, H, W, b2=200.0, A=100.0, theta=np.radians(7.0))
    P = np.array([-60.0, 40.0, 1200.0])
    pixels = _seed_pixels(geometry, P)
    wrong = SeedGeometry(F, F, PIXEL, PIXEL, W, H, W, b2=200.0, A=100.0, theta=np.radians(-7.0))
    point = seed_triangulate(wrong, *[[p] for p in pixels]).points[0]
    assert np.linalg.norm(point - P) > 50.0


def _relaxed_pair(rng):
    """A printer-like relaxed pair: different distances, heights, focal lengths, a few degrees of yaw and tilt."""
    target = np.array([0.0, 0.0, 15.0])
    left = Camera.look_at("L", [-70 + rng.uniform(-10, 10), -240 + rng.uniform(-20, 20), 60 + rng.uniform(-10, 30)],
                          target + rng.uniform(-8, 8, 3), focal_px=rng.uniform(550, 750), roll_deg=rng.uniform(-3, 3))
    right = Camera.look_at("R", [60 + rng.uniform(-10, 10), -150 + rng.uniform(-20, 20), 40 + rng.uniform(-10, 30)],
                           target + rng.uniform(-8, 8, 3), focal_px=rng.uniform(550, 750), roll_deg=rng.uniform(-3, 3))
    return left, right


def test_seed_equations_agree_with_general_triangulation_on_relaxed_pairs():
    rng = np.random.default_rng(6)
    for _ in range(5):
        left, right = _relaxed_pair(rng)
        points = rng.uniform([-25, -25, 0], [25, 25, 40], (200, 3))
        pl, pr = left.project(points, distorted=False), right.project(points, distorted=False)
        general = triangulate_general(left, right, pl, pr)
        seed = seed_triangulate_cameras(left, right, pl, pr)
        np.testing.assert_allclose(general, points, atol=1e-6)
        np.testing.assert_allclose(seed, points, atol=1e-6)
        # The frame really is relaxed: the left camera is not level with, nor as far as, the right.
        g = seed_frame(left, right).geometry
        assert abs(g.A) > 1.0 and abs(g.theta) > 0.01


def test_noisy_matches_give_similar_errors_with_both_triangulations():
    rng = np.random.default_rng(7)
    left, right = _relaxed_pair(rng)
    points = rng.uniform([-25, -25, 0], [25, 25, 40], (500, 3))
    pl = left.project(points, distorted=False) + rng.normal(0, 0.3, (500, 2))
    pr = right.project(points, distorted=False) + rng.normal(0, 0.3, (500, 2))
    err_general = np.linalg.norm(triangulate_general(left, right, pl, pr) - points, axis=1)
    err_seed = np.linalg.norm(seed_triangulate_cameras(left, right, pl, pr) - points, axis=1)
    assert np.median(err_general) < 0.5
    assert np.median(err_seed) < 2 * np.median(err_general) + 0.1


def test_q_reprojection_and_triangulation_agree_after_calibrated_rectification():
    rng = np.random.default_rng(8)
    left, right = _relaxed_pair(rng)
    rect = rectify_calibrated(left, right)
    points = rng.uniform([-25, -25, 0], [25, 25, 40], (100, 3))
    wl = rect.from_camera_pixels(left.project(points, distorted=False), "left")
    wr = rect.from_camera_pixels(right.project(points, distorted=False), "right")
    np.testing.assert_allclose(wl[:, 1], wr[:, 1], atol=1e-6)  # same rows
    # Q of the window: rectified left camera frame from (x, y, d).
    K_rect = rect.K_rect
    Q = np.array([[1, 0, 0, -K_rect[0, 2]], [0, 1, 0, -K_rect[1, 2]], [0, 0, 0, K_rect[0, 0]],
                  [0, 0, 1 / rect.baseline_mm, 0]])
    local = reproject_disparity(wl, wl[:, 0] - wr[:, 0], Q)
    printer = rect.rectified_to_printer(local)
    np.testing.assert_allclose(printer, points, atol=1e-6)
