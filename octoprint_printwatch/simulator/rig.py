"""Camera rigs around the bed, and the imperfect calibration a user would hand the detector."""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from ..core.camera import Camera
from ..core.errors import PrintWatchError

RIG_KINDS = ("stations3", "single", "pair", "ring", "top")


@dataclass
class Rig:
    """True cameras (used to render) and their calibrated estimates (handed to the detector).

    ``pairs`` lists stereo pairs as ``(left, right)`` camera names.
    """

    cameras_true: list[Camera]
    cameras_calibrated: list[Camera]
    pairs: list[tuple[str, str]] = field(default_factory=list)
    bed: tuple[float, float] = (200.0, 200.0)

    @property
    def names(self) -> list[str]:
        return [c.name for c in self.cameras_true]

    def true(self, name: str) -> Camera:
        return self._find(self.cameras_true, name)

    def calibrated(self, name: str) -> Camera:
        return self._find(self.cameras_calibrated, name)

    @staticmethod
    def _find(cameras: list[Camera], name: str) -> Camera:
        for cam in cameras:
            if cam.name == name:
                return cam
        raise PrintWatchError(f"no camera named {name!r} in the rig ({', '.join(c.name for c in cameras)})")


def _rotate_about(camera: Camera, axis_world: np.ndarray, degrees: float) -> Camera:
    """The camera turned about a world axis through its own centre."""
    rot = cv2.Rodrigues(np.asarray(axis_world, float) / np.linalg.norm(axis_world) * np.radians(degrees))[0]
    centre = camera.center
    R = camera.R @ rot.T
    return camera.with_pose(cv2.Rodrigues(R)[0].ravel(), -R @ centre)


def _webcam(rng, name, eye, target, width, height, focal_px, distortion: bool) -> Camera:
    dist = None
    if distortion:  # cheap wide lenses: barrel distortion, a little decentring
        dist = [rng.uniform(-0.30, -0.05), rng.uniform(-0.02, 0.12), rng.normal(0, 0.0008), rng.normal(0, 0.0008), 0.0]
    cam = Camera.look_at(name, eye, target, width=width, height=height, focal_px=focal_px,
                         dist=dist, roll_deg=float(rng.normal(0, 1.5)))
    K = cam.K.copy()
    K[0, 2] += rng.normal(0, 6)
    K[1, 2] += rng.normal(0, 6)
    K[1, 1] *= 1 + rng.normal(0, 0.003)  # non-square pixels, as calibrations of real webcams find
    return Camera(name, width, height, K, cam.dist, cam.rvec, cam.tvec)


def miscalibrate(camera: Camera, rng: np.random.Generator, *, focal_pct: float = 1.0, rotation_deg: float = 0.5,
                 position_mm: float = 1.0) -> Camera:
    """A calibration estimate of ``camera`` with realistic errors (1 sigma magnitudes)."""
    K = camera.K.copy()
    scale = 1 + rng.normal(0, focal_pct / 100.0)
    K[0, 0] *= scale
    K[1, 1] *= scale * (1 + rng.normal(0, 0.002))
    K[:2, 2] += rng.normal(0, 2.0, 2)
    dist = camera.dist.copy()
    dist[:2] += rng.normal(0, 0.01, 2)
    axis = rng.normal(size=3)
    wrong = cv2.Rodrigues(axis / np.linalg.norm(axis) * np.radians(abs(rng.normal(0, rotation_deg))))[0]
    R = wrong @ camera.R
    centre = camera.center + rng.normal(0, position_mm / np.sqrt(3), 3)
    return Camera(camera.name, camera.width, camera.height, K, dist, cv2.Rodrigues(R)[0].ravel(), -R @ centre)


def make_rig(kind: str = "stations3", n_cameras: int | None = None, bed: tuple[float, float] = (200.0, 200.0),
             seed: int = 0, *, width: int = 640, height: int = 480, target_z: float = 12.0,
             distortion: bool = True, calibration_error: bool = True) -> Rig:
    """Cameras around the bed centre.

    kinds: ``stations3`` (the seed: three stations 120 degrees apart, each a
    relaxed stereo pair, 6 cameras), ``single`` (one camera), ``pair`` (one
    relaxed pair), ``ring`` (``n_cameras`` single cameras evenly around, 1..6),
    ``top`` (one camera looking almost straight down, for tests).
    """
    if kind not in RIG_KINDS:
        raise PrintWatchError(f"unknown rig {kind!r}; choose from {', '.join(RIG_KINDS)}")
    rng = np.random.default_rng([seed, 0x816])
    cx, cy = bed[0] / 2.0, bed[1] / 2.0
    target = np.array([cx, cy, target_z])
    cameras: list[Camera] = []
    pairs: list[tuple[str, str]] = []

    def place(azimuth_deg, distance, elevation_deg):
        a, e = np.radians(azimuth_deg), np.radians(elevation_deg)
        return target + distance * np.array([np.cos(e) * np.cos(a), np.cos(e) * np.sin(a), np.sin(e)])

    if kind in ("stations3", "pair"):
        stations = 3 if kind == "stations3" else 1
        for s in range(stations):
            azimuth = -90.0 + 120.0 * s + rng.normal(0, 4)
            distance = rng.uniform(150, 220)
            elevation = rng.uniform(10, 24)
            focal = rng.uniform(650, 950)
            left_eye = place(azimuth, distance, elevation)
            view = (target - left_eye) / np.linalg.norm(target - left_eye)
            right_dir = np.cross(view, [0, 0, 1.0])
            right_dir /= np.linalg.norm(right_dir)
            baseline = rng.uniform(40, 70)
            # Relaxed geometry: the right camera stands closer or farther by a few cm and is yawed a few degrees.
            forward = rng.choice([-1, 1]) * rng.uniform(15, 45)
            right_eye = left_eye + baseline * right_dir + forward * view * np.array([1, 1, 0])
            right_eye[2] += rng.normal(0, 3)
            left = _webcam(rng, f"cam{s}L", left_eye, target, width, height, focal, distortion)
            right = _webcam(rng, f"cam{s}R", right_eye, target + rng.normal(0, 4, 3), width, height,
                            focal * (1 + rng.uniform(-0.08, 0.08)), distortion)
            right = _rotate_about(right, np.array([0, 0, 1.0]), rng.choice([-1, 1]) * rng.uniform(1.5, 5))
            cameras += [left, right]
            pairs.append((left.name, right.name))
    elif kind in ("single", "ring"):
        n = 1 if kind == "single" else int(n_cameras or 3)
        if not 1 <= n <= 6:
            raise PrintWatchError(f"a ring rig has 1 to 6 cameras, got {n}")
        start = rng.uniform(0, 360) if kind == "ring" else -90.0
        for k in range(n):
            eye = place(start + 360.0 * k / n + rng.normal(0, 3), rng.uniform(150, 220), rng.uniform(10, 28))
            cameras.append(_webcam(rng, f"cam{k}", eye, target, width, height, rng.uniform(600, 950), distortion))
    else:  # top
        eye = target + np.array([0.0, -25.0, 200.0])
        cameras.append(_webcam(rng, "cam0", eye, target, width, height, 800.0, distortion))

    calib_rng = np.random.default_rng([seed, 0xCA1])
    calibrated = [miscalibrate(c, calib_rng) if calibration_error else
                  Camera(c.name, c.width, c.height, c.K.copy(), c.dist.copy(), c.rvec.copy(), c.tvec.copy())
                  for c in cameras]
    return Rig(cameras, calibrated, pairs, (float(bed[0]), float(bed[1])))
