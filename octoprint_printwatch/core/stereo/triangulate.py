"""From matched pixels to 3-D points in printer coordinates.

Two ways, compared on the same matches:

* :func:`triangulate_general` — ``cv2.triangulatePoints`` with each camera's
  projection matrix ``K [R | t]`` (printer frame); exact for any geometry.
* :func:`seed_triangulate` — the dissertation's relaxed-geometry equations
  (Eqs. 2-2..2-14): angles from pixel offsets and focal lengths, a left camera
  displaced by ``A`` along the viewing axis and ``b2`` across it and rotated by
  ``theta`` about the vertical, law of sines for the ranges D1, D2, then X, Z
  from the two range circles (Eqs. 2-11, 2-12), Y from the left camera (2-13).
  :func:`seed_triangulate_cameras` applies them to any calibrated pair by first
  levelling each camera (a pure rotation about its own centre, so the equations'
  assumption of horizontal optical axes holds exactly).

Seed frame (as in Figs. 2.3-2.5): origin at the right camera, Z along the right
camera's horizontal viewing direction, X to its right, Y up. The left camera sits
at ``(-b2, ., A)`` (``A > 0``: closer to the object). ``theta`` is the angle by
which the left camera's optical axis is turned from +Z towards -X (away from the
right camera), so that Eq. 2-6 reads ``phi_l = pi/2 - alpha_l/2 + theta``.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from ..camera import Camera


# ------------------------------------------------------------------ general
def triangulate_general(left: Camera, right: Camera, px_left: np.ndarray, px_right: np.ndarray,
                        *, distorted: bool = False) -> np.ndarray:
    """(n, 2) matched pixels in each camera -> (n, 3) printer points (DLT, ``cv2.triangulatePoints``).

    ``distorted=False`` means the pixels are in the undistorted images (same K).
    """
    px_left = np.asarray(px_left, np.float64).reshape(-1, 2)
    px_right = np.asarray(px_right, np.float64).reshape(-1, 2)
    if len(px_left) == 0:
        return np.zeros((0, 3))
    norm = []
    for cam, px in ((left, px_left), (right, px_right)):
        if distorted:
            n = cv2.undistortPoints(px.reshape(-1, 1, 2), cam.K, cam.dist).reshape(-1, 2)
        else:
            n = (px - cam.K[:2, 2]) / np.diag(cam.K)[:2]
        norm.append(n)
    P_left = np.hstack([left.R, left.tvec[:, None]])
    P_right = np.hstack([right.R, right.tvec[:, None]])
    homogeneous = cv2.triangulatePoints(P_left, P_right, norm[0].T, norm[1].T)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (homogeneous[:3] / homogeneous[3]).T


def reproject_disparity(pixels: np.ndarray, disparity: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """(n, 2) rectified left pixels and (n,) disparities -> (n, 3) points in the rectified left frame via Q."""
    pixels = np.asarray(pixels, np.float64).reshape(-1, 2)
    h = np.column_stack([pixels, np.asarray(disparity, np.float64).reshape(-1), np.ones(len(pixels))]) @ Q.T
    with np.errstate(divide="ignore", invalid="ignore"):
        return h[:, :3] / h[:, 3:4]


# --------------------------------------------------------------------- seed
@dataclass
class SeedGeometry:
    """The relaxed camera geometry of Figs. 2.3-2.5 (lengths in mm, angles in radians).

    Attributes
    ----------
    f_left, f_right : focal lengths (mm).
    pixel_left, pixel_right : pixel sizes (mm), the seed's vartheta.
    width_left, height_left, width_right : image sizes (px).
    b2 : sideways distance between the cameras, across the right camera's axis (mm).
    A : how much closer the left camera is to the object, along that axis (mm).
    theta : rotation of the left camera about the vertical (Eq. 2-6), see module docstring.
    left_height : height of the left camera above the right one (0 in the seed).
    """

    f_left: float
    f_right: float
    pixel_left: float
    pixel_right: float
    width_left: float
    height_left: float
    width_right: float
    b2: float
    A: float = 0.0
    theta: float = 0.0
    left_height: float = 0.0

    @property
    def left_center_xz(self) -> tuple[float, float]:
        return (-self.b2, self.A)


@dataclass
class SeedTriangulation:
    """Every intermediate quantity of Eqs. 2-2..2-14, each (n,), for inspection and tests."""

    alpha_left_half: np.ndarray
    alpha_right_half: np.ndarray
    phi_left: np.ndarray
    phi_right: np.ndarray
    omega: float
    b1: float
    beta_left: np.ndarray
    beta_right: np.ndarray
    phi: np.ndarray
    D1: np.ndarray
    D2: np.ndarray
    points: np.ndarray  # (n, 3) X, Y, Z in the seed frame


def seed_triangulate(geometry: SeedGeometry, x_left, y_left, x_right) -> SeedTriangulation:
    """Eqs. 2-2..2-14 for matched pixels ``(x_left, y_left)`` <-> ``x_right`` (arrays of equal length)."""
    g = geometry
    x_left = np.asarray(x_left, np.float64)
    y_left = np.asarray(y_left, np.float64)
    x_right = np.asarray(x_right, np.float64)
    # Eq. 2-4: offsets from the image middle, in mm on the sensor.
    d_left_half = (x_left - g.width_left / 2.0) * g.pixel_left
    d_right_half = (g.width_right / 2.0 - x_right) * g.pixel_right
    # Eq. 2-3: angles between each optical axis and the ray.
    alpha_left_half = np.arctan(d_left_half / g.f_left)
    alpha_right_half = np.arctan(d_right_half / g.f_right)
    # Eq. 2-2 / 2-6: angles between the rays and the x axis (left rotated by theta).
    phi_left = np.pi / 2 - alpha_left_half + g.theta
    phi_right = np.pi / 2 - alpha_right_half
    # Eq. 2-10: the baseline b1 is tilted by omega when the left camera is A closer.
    b1 = float(np.hypot(g.A, g.b2))
    omega = float(np.arcsin(g.A * np.sin(np.pi / 2) / b1))
    beta_left = phi_left + omega
    beta_right = phi_right - omega
    phi = np.pi - beta_left - beta_right  # Eq. 2-9
    with np.errstate(divide="ignore", invalid="ignore"):
        D1 = b1 * np.sin(beta_right) / np.sin(phi)  # Eq. 2-7
        D2 = b1 * np.sin(beta_left) / np.sin(phi)  # Eq. 2-8
    X, Z = _intersect_range_circles(g.left_center_xz, (0.0, 0.0), D1, D2)
    # Eqs. 2-13, 2-14: height from the left camera, with its depth along its own axis.
    depth_left = D1 * np.cos(alpha_left_half)
    y_sensor = (g.height_left / 2.0 - y_left) * g.pixel_left
    Y = g.left_height + y_sensor / g.f_left * depth_left
    bad = ~(np.isfinite(D1) & np.isfinite(D2) & (D1 > 0) & (D2 > 0) & (phi > 0))
    points = np.column_stack([X, Y, Z])
    points[bad] = np.nan
    return SeedTriangulation(alpha_left_half, alpha_right_half, phi_left, phi_right, omega, b1,
                             beta_left, beta_right, phi, D1, D2, points)


def _intersect_range_circles(center_left, center_right, D1, D2):
    """Solve Eqs. 2-11 and 2-12 for (X, Z): the point at range D1 from C_l and D2 from C_r, in front (larger Z)."""
    cl = np.asarray(center_left, np.float64)
    cr = np.asarray(center_right, np.float64)
    base = cr - cl
    b = np.linalg.norm(base)
    u = base / b
    normal = np.array([-u[1], u[0]])
    if normal[1] < 0:
        normal = -normal  # towards +Z, where the object is
    with np.errstate(invalid="ignore"):
        along = (D1 ** 2 - D2 ** 2 + b ** 2) / (2 * b)
        across = np.sqrt(np.maximum(D1 ** 2 - along ** 2, 0.0))
    X = cl[0] + along * u[0] + across * normal[0]
    Z = cl[1] + along * u[1] + across * normal[1]
    return X, Z


@dataclass
class SeedFrame:
    """A calibrated pair expressed in the seed's geometry, with levelled virtual cameras."""

    geometry: SeedGeometry
    origin: np.ndarray  # (3,) right camera centre, printer frame
    axes: np.ndarray  # (3, 3) rows: seed X (right), Y (up), Z (forward) in printer coordinates
    level_left: np.ndarray  # (3, 3) rows: levelled left camera right/down/forward axes
    level_right: np.ndarray


def seed_frame(left: Camera, right: Camera) -> SeedFrame:
    """Express a calibrated pair in the seed's frame; the focal length is kept in pixels (pixel size 1)."""
    up = np.array([0.0, 0.0, 1.0])

    def level_axes(cam: Camera) -> np.ndarray:
        forward = cam.viewing_direction.copy()
        forward[2] = 0.0
        forward /= np.linalg.norm(forward)
        right_axis = np.cross(forward, up)  # camera x (right) for a level camera with y down
        return np.stack([right_axis, -up, forward])

    level_left, level_right = level_axes(left), level_axes(right)
    Zs = level_right[2]
    Xs = level_right[0]
    axes = np.stack([Xs, up, Zs])
    cl = axes @ (left.center - right.center)
    fwd_left = axes @ level_left[2]
    theta = float(np.arctan2(fwd_left[2], fwd_left[0]) - np.pi / 2)
    geometry = SeedGeometry(
        f_left=float(left.K[0, 0]), f_right=float(right.K[0, 0]), pixel_left=1.0, pixel_right=1.0,
        width_left=float(2 * left.K[0, 2]), height_left=float(2 * left.K[1, 2]),
        width_right=float(2 * right.K[0, 2]), b2=float(-cl[0]), A=float(cl[2]), theta=theta,
        left_height=float(cl[1]))
    return SeedFrame(geometry, right.center, axes, level_left, level_right)


def _level_pixels(cam: Camera, level: np.ndarray, pixels: np.ndarray, distorted: bool) -> np.ndarray:
    """Pixels of ``cam`` -> pixels of the levelled virtual camera (same centre, same K)."""
    _, rays = cam.rays(pixels, distorted=distorted)
    local = rays @ level.T
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = local[:, :2] / local[:, 2:3]
    return uv * np.diag(cam.K)[:2] + cam.K[:2, 2]


def seed_triangulate_cameras(left: Camera, right: Camera, px_left: np.ndarray, px_right: np.ndarray,
                             *, distorted: bool = False) -> np.ndarray:
    """The seed's equations on a calibrated pair: (n, 2) matched pixels -> (n, 3) printer points."""
    px_left = np.asarray(px_left, np.float64).reshape(-1, 2)
    px_right = np.asarray(px_right, np.float64).reshape(-1, 2)
    if len(px_left) == 0:
        return np.zeros((0, 3))
    frame = seed_frame(left, right)
    lv = _level_pixels(left, frame.level_left, px_left, distorted)
    rv = _level_pixels(right, frame.level_right, px_right, distorted)
    result = seed_triangulate(frame.geometry, lv[:, 0], lv[:, 1], rv[:, 0])
    return frame.origin + result.points @ frame.axes
