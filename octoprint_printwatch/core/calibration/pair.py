"""Relative pose of two cameras: from simultaneous board views, or from their bed poses."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import cv2
import numpy as np

from ..boards import Board
from ..camera import Camera
from ..errors import CalibrationError
from .images import common_size, image_labels
from .intrinsics import IntrinsicsResult, calibrate_intrinsics, detect_views

#: Baselines from the stereo calibration and from the bed poses may differ by this much.
MAX_BASELINE_DIFF_FRACTION = 0.03
#: ... and the relative rotations by this many degrees.
MAX_ROTATION_DIFF_DEG = 1.0


@dataclass
class PairConsistency:
    """Agreement of two estimates of one pair's relative pose."""

    baseline_diff_mm: float
    rotation_diff_deg: float
    ok: bool
    message: str


@dataclass
class PairResult:
    """Outcome of :func:`calibrate_pair`.

    ``x_right = R @ x_left + T`` (camera coordinates, mm). ``left``/``right`` carry the
    intrinsics used; when the left camera came with a bed pose, ``right`` carries the
    printer pose that follows from it.

    Attributes
    ----------
    R : (3, 3) float
    T : (3,) float
    rms_px : float
        Stereo RMS reprojection error over both cameras.
    baseline_mm : float
        Distance between the two camera centres.
    left, right : Camera
    views_used : list[str]
    per_view_baseline_mm : (n,) float
        Baseline from each view pair alone (each camera's own board pose).
    baseline_spread_mm : float
        Standard deviation of ``per_view_baseline_mm``: small when the views agree.
    rotation_spread_deg : float
        RMS angle between each view's relative rotation and ``R``.
    epipolar_rms_px : float
        RMS distance of right-image corners from the epipolar lines of their left partners.
    consistency : PairConsistency | None
        Comparison with the bed poses, when both cameras came with one.
    intrinsics : dict[str, IntrinsicsResult]
        Per-camera intrinsics computed here (empty when they were given).
    """

    R: np.ndarray
    T: np.ndarray
    rms_px: float
    baseline_mm: float
    left: Camera
    right: Camera
    views_used: list[str]
    per_view_baseline_mm: np.ndarray
    baseline_spread_mm: float
    rotation_spread_deg: float
    epipolar_rms_px: float
    consistency: PairConsistency | None = None
    intrinsics: dict = field(default_factory=dict)

    def summary(self) -> dict:
        doc = {
            "format": "printwatch-pair/1",
            "left": self.left.name,
            "right": self.right.name,
            "R": self.R.tolist(),
            "T": self.T.tolist(),
            "rms_px": round(self.rms_px, 4),
            "baseline_mm": round(self.baseline_mm, 4),
            "baseline_spread_mm": round(self.baseline_spread_mm, 4),
            "rotation_spread_deg": round(self.rotation_spread_deg, 4),
            "epipolar_rms_px": round(self.epipolar_rms_px, 4),
            "views_used": list(self.views_used),
        }
        if self.consistency is not None:
            doc["consistency"] = {"baseline_diff_mm": round(self.consistency.baseline_diff_mm, 3),
                                  "rotation_diff_deg": round(self.consistency.rotation_diff_deg, 3),
                                  "ok": self.consistency.ok, "message": self.consistency.message}
        return doc


def relative_pose(left: Camera, right: Camera) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), T (3,)) with ``x_right = R @ x_left + T`` from two printer poses."""
    R = right.R @ left.R.T
    return R, right.tvec - R @ left.tvec


def rotation_angle_deg(R: np.ndarray) -> float:
    return float(np.degrees(np.linalg.norm(cv2.Rodrigues(np.asarray(R, dtype=np.float64))[0])))


def calibrate_pair(left_images: Sequence[np.ndarray], right_images: Sequence[np.ndarray], board: Board, *,
                   left_camera: Camera | None = None, right_camera: Camera | None = None,
                   left_labels: Sequence[str] | None = None, right_labels: Sequence[str] | None = None,
                   names: tuple[str, str] = ("left", "right")) -> PairResult:
    """Stereo calibration from simultaneous frames (``left_images[i]`` with ``right_images[i]``).

    Intrinsics are taken from ``left_camera``/``right_camera`` when given (their
    poses, if any, are used for the consistency check), otherwise calibrated from
    these frames first. Raises :class:`CalibrationError` on unequal counts, mixed
    sizes, or fewer than three frames where both cameras see the board.
    """
    left_labels = image_labels(left_images, left_labels)
    right_labels = image_labels(right_images, right_labels)
    if len(left_images) != len(right_images):
        raise CalibrationError(f"{len(left_images)} left images but {len(right_images)} right images; "
                               "give the frames of each pair in the same order")
    if len(left_images) < 2:
        raise CalibrationError("one image pair only; take 10-15 pairs with the board in different places")
    size_l = common_size(left_images, left_labels)
    size_r = common_size(right_images, right_labels)
    intrinsics: dict[str, IntrinsicsResult] = {}
    if left_camera is None:
        intrinsics[names[0]] = calibrate_intrinsics(left_images, board, labels=left_labels, name=names[0])
        left_camera = intrinsics[names[0]].camera
    if right_camera is None:
        intrinsics[names[1]] = calibrate_intrinsics(right_images, board, labels=right_labels, name=names[1])
        right_camera = intrinsics[names[1]].camera
    for cam, size, label in ((left_camera, size_l, left_labels[0]), (right_camera, size_r, right_labels[0])):
        if cam.size != size:
            raise CalibrationError(f"{label}: image is {size[0]}x{size[1]} but camera {cam.name} is calibrated "
                                   f"for {cam.width}x{cam.height}")

    det_l, _ = detect_views(left_images, board, left_labels, min_corners=6)
    det_r, _ = detect_views(right_images, board, right_labels, min_corners=6)
    objects, pts_l, pts_r, used = [], [], [], []
    for dl, dr, label in zip(det_l, det_r, left_labels):
        if dl is None or dr is None:
            continue
        common, il, ir = np.intersect1d(dl.ids, dr.ids, return_indices=True)
        if len(common) < 6:
            continue
        objects.append(board.corner_points()[common].astype(np.float32))
        pts_l.append(dl.pixels[il].astype(np.float32).reshape(-1, 1, 2))
        pts_r.append(dr.pixels[ir].astype(np.float32).reshape(-1, 1, 2))
        used.append(label)
    if len(used) < 3:
        raise CalibrationError(f"both cameras see the board in only {len(used)} of {len(left_images)} frame "
                               "pairs, need at least 3")
    criteria = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-9)
    rms, *_, R, T, E, F = cv2.stereoCalibrate(
        objects, pts_l, pts_r, left_camera.K, left_camera.dist, right_camera.K, right_camera.dist,
        size_l, flags=cv2.CALIB_FIX_INTRINSIC, criteria=criteria)
    T = T.ravel()

    # Each view on its own: a spread in the baseline means a moved board or a bad view.
    baselines, angles = [], []
    for obj, pl, pr in zip(objects, pts_l, pts_r):
        Rl, tl = _view_pose(obj, pl, left_camera)
        Rr, tr = _view_pose(obj, pr, right_camera)
        Rv = Rr @ Rl.T
        Tv = tr - Rv @ tl
        baselines.append(np.linalg.norm(Tv))
        angles.append(rotation_angle_deg(Rv @ R.T))
    baselines = np.array(baselines)

    right_out = right_camera.with_pose(right_camera.rvec, right_camera.tvec)
    consistency = None
    has_pose_l = np.any(left_camera.tvec) or np.any(left_camera.rvec)
    has_pose_r = np.any(right_camera.tvec) or np.any(right_camera.rvec)
    if has_pose_l and has_pose_r:
        consistency = check_pair_consistency(R, T, left_camera, right_camera)
    if has_pose_l:
        # Right pose in printer coordinates: x_r = R (R_l X + t_l) + T.
        right_out = right_camera.with_pose(cv2.Rodrigues(R @ left_camera.R)[0].ravel(),
                                           R @ left_camera.tvec + T)
    return PairResult(
        R=R, T=T, rms_px=float(rms), baseline_mm=float(np.linalg.norm(T)),
        left=left_camera, right=right_out, views_used=used,
        per_view_baseline_mm=baselines,
        baseline_spread_mm=float(np.std(baselines)),
        rotation_spread_deg=float(np.sqrt(np.mean(np.square(angles)))),
        epipolar_rms_px=_epipolar_rms(F, pts_l, pts_r, left_camera, right_camera),
        consistency=consistency, intrinsics=intrinsics,
    )


def _view_pose(obj: np.ndarray, pixels: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    ok, rvec, tvec = cv2.solvePnP(obj.reshape(-1, 1, 3).astype(np.float64), pixels.astype(np.float64),
                                  camera.K, camera.dist, flags=cv2.SOLVEPNP_IPPE)
    rvec, tvec = cv2.solvePnPRefineLM(obj.reshape(-1, 1, 3).astype(np.float64), pixels.astype(np.float64),
                                      camera.K, camera.dist, rvec, tvec)
    return cv2.Rodrigues(rvec)[0], tvec.ravel()


def _epipolar_rms(F: np.ndarray, pts_l, pts_r, left: Camera, right: Camera) -> float:
    """RMS point-to-epipolar-line distance (px), on undistorted corners (F is for undistorted pixels)."""
    ul = left.undistort_points(np.concatenate(pts_l).reshape(-1, 2))
    ur = right.undistort_points(np.concatenate(pts_r).reshape(-1, 2))
    lines = cv2.computeCorrespondEpilines(ul.reshape(-1, 1, 2), 1, F).reshape(-1, 3)
    dist = np.abs(np.sum(lines[:, :2] * ur, axis=1) + lines[:, 2]) / np.linalg.norm(lines[:, :2], axis=1)
    return float(np.sqrt(np.mean(dist ** 2)))


def check_pair_consistency(R: np.ndarray, T: np.ndarray, left: Camera, right: Camera) -> PairConsistency:
    """Compare a stereo calibration's (R, T) with the relative pose implied by two bed poses."""
    Rb, Tb = relative_pose(left, right)
    baseline = float(np.linalg.norm(T))
    diff_mm = float(abs(np.linalg.norm(Tb) - baseline))
    diff_deg = rotation_angle_deg(np.asarray(R) @ Rb.T)
    ok = diff_mm <= MAX_BASELINE_DIFF_FRACTION * max(baseline, 1e-9) and diff_deg <= MAX_ROTATION_DIFF_DEG
    if ok:
        message = (f"{left.name}/{right.name}: stereo and bed calibrations agree (baseline within "
                   f"{diff_mm:.1f} mm, rotation within {diff_deg:.2f} deg)")
    else:
        message = (f"{left.name}/{right.name}: stereo and bed calibrations disagree: baseline "
                   f"{baseline:.1f} mm vs {np.linalg.norm(Tb):.1f} mm, rotation differs by {diff_deg:.2f} deg; "
                   "a camera moved or the board placement was wrong, recalibrate the bed pose")
    return PairConsistency(diff_mm, diff_deg, bool(ok), message)
