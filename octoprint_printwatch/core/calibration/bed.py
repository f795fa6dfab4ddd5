"""The camera's pose in printer coordinates from a board lying on the bed."""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Sequence

import cv2
import numpy as np

from ..boards import Board, Detection, detect_board
from ..camera import Camera
from ..errors import CalibrationError
from .images import image_labels

#: RMS reprojection error (px) above which the bed pose gets a warning.
MAX_GOOD_BED_RMS_PX = 1.5


@dataclass(frozen=True)
class BoardPlacement:
    """Where the board lies on the bed.

    ``x_mm``, ``y_mm`` are the printer coordinates of the grid's front-left outer
    corner (the corner of the square grid nearest the printer's origin when the
    page's caption edge points to the back of the bed); ``angle_deg`` turns the
    board about that corner, anticlockwise seen from above; ``z_mm`` is the height of
    that corner (paper thickness, or the glass plate's when it lies on one);
    ``tilt_deg`` stands the board up about its front edge (90 = upright).
    """

    x_mm: float = 0.0
    y_mm: float = 0.0
    angle_deg: float = 0.0
    z_mm: float = 0.0
    tilt_deg: float = 0.0

    def board_to_printer(self, board: Board) -> tuple[np.ndarray, np.ndarray]:
        """(R (3, 3), t (3,)) with ``X_printer = R @ X_board + t``.

        Lying flat, board x runs along +X, board y (down the page) towards the front (-Y),
        board z (into the paper) down (-Z). ``tilt_deg`` raises the board's back edge about
        its front edge: at 90 the board stands upright, printed side facing the front (for
        cameras too low to see a board lying on the bed).
        """
        a, b = np.radians(self.angle_deg), np.radians(self.tilt_deg)
        rz = np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.0, 1.0]])
        rx = np.array([[1.0, 0.0, 0.0], [0.0, np.cos(b), -np.sin(b)], [0.0, np.sin(b), np.cos(b)]])
        R = rz @ rx @ np.diag([1.0, -1.0, -1.0])
        height = board.size_mm[1]
        t = np.array([self.x_mm, self.y_mm, self.z_mm]) - R @ np.array([0.0, height, 0.0])
        return R, t

    def to_printer(self, board: Board, points: np.ndarray) -> np.ndarray:
        """(n, 3) board-frame points (mm) -> (n, 3) printer points."""
        R, t = self.board_to_printer(board)
        return np.asarray(points, dtype=np.float64).reshape(-1, 3) @ R.T + t

    @classmethod
    def front_left(cls, board: Board, bed_origin: tuple[float, float] = (0.0, 0.0), **kw) -> "BoardPlacement":
        """Page pushed into the bed's front-left corner (the corner at ``bed_origin``)."""
        return cls(bed_origin[0] + board.margin_mm, bed_origin[1] + board.margin_mm, **kw)

    @classmethod
    def centred(cls, board: Board, bed_mm: tuple[float, float], **kw) -> "BoardPlacement":
        """Grid centred on a ``bed_mm`` = (width, depth) bed whose front-left corner is (0, 0)."""
        w, h = board.size_mm
        angle = np.radians(kw.get("angle_deg", 0.0))
        rz = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
        depth = h * np.cos(np.radians(kw.get("tilt_deg", 0.0)))  # plan-view depth of a tilted board
        corner = np.array(bed_mm, dtype=float) / 2.0 - rz @ np.array([w / 2.0, depth / 2.0])
        return cls(float(corner[0]), float(corner[1]), **kw)

    @classmethod
    def parse(cls, spec: str, board: Board, bed_mm: tuple[float, float] | None = None,
              z_mm: float = 0.0, tilt_deg: float = 0.0) -> "BoardPlacement":
        """``front-left``, ``centre``/``center`` (needs ``bed_mm``) or ``X,Y[,ANGLE]``."""
        text = spec.strip().lower()
        if text in ("front-left", "frontleft", "corner"):
            return cls.front_left(board, z_mm=z_mm, tilt_deg=tilt_deg)
        if text in ("centre", "center", "centred", "centered"):
            if bed_mm is None:
                raise CalibrationError("placement 'centre' needs the bed size (--bed W,D)")
            return cls.centred(board, bed_mm, z_mm=z_mm, tilt_deg=tilt_deg)
        if re.fullmatch(r"[-+\d.eE]+,[-+\d.eE]+(,[-+\d.eE]+)?", text):
            try:
                values = [float(v) for v in text.split(",")]
            except ValueError:
                values = []
            if values:
                return cls(values[0], values[1], values[2] if len(values) > 2 else 0.0, z_mm, tilt_deg)
        raise CalibrationError(f"placement {spec!r}: expected front-left, centre, or X,Y[,ANGLE] "
                               "(mm, degrees) of the grid's front-left corner")


@dataclass
class BedPoseResult:
    """Outcome of :func:`calibrate_bed_pose`.

    Attributes
    ----------
    camera : Camera
        The intrinsics camera with ``rvec``/``tvec`` mapping printer to camera coordinates.
    reprojection_px : float
        RMS distance between the detected corners and the board reprojected with the pose.
    corners_used : int
    center_mm : (3,) float
        Camera centre in printer coordinates.
    position_sigma_mm : float
        One standard deviation of the camera centre (largest axis) from the corner noise.
    rotation_sigma_deg : float
        One standard deviation of the orientation from the corner noise.
    warnings : list[str]
    """

    camera: Camera
    reprojection_px: float
    corners_used: int
    center_mm: np.ndarray
    position_sigma_mm: float
    rotation_sigma_deg: float
    warnings: list[str] = field(default_factory=list)

    def summary(self) -> dict:
        return {
            "bed_reprojection_px": round(self.reprojection_px, 4),
            "bed_corners": self.corners_used,
            "center_mm": [round(float(v), 3) for v in self.center_mm],
            "position_sigma_mm": round(self.position_sigma_mm, 3),
            "rotation_sigma_deg": round(self.rotation_sigma_deg, 4),
            "bed_warnings": list(self.warnings),
        }


def calibrate_bed_pose(image: np.ndarray | Sequence[np.ndarray], intrinsics_camera: Camera, board: Board,
                       placement: BoardPlacement, *, labels: Sequence[str] | None = None) -> BedPoseResult:
    """Camera pose from one frame (or several frames of the same, unmoved board).

    The frames may be any size with the calibrated aspect ratio (the intrinsics are scaled).
    Raises :class:`CalibrationError` when the board is not found, or the pose puts the
    camera under the bed (placement or board wrong).
    """
    images = [image] if isinstance(image, np.ndarray) else list(image)
    if not images:
        raise CalibrationError("no bed image given")
    labels = image_labels(images, labels)
    camera = _camera_for_size(intrinsics_camera, images[0], labels[0])
    detections: list[Detection] = []
    for img, label in zip(images, labels):
        if (img.shape[1], img.shape[0]) != camera.size:
            raise CalibrationError(f"{label}: image is {img.shape[1]}x{img.shape[0]} but {labels[0]} is "
                                   f"{camera.width}x{camera.height}")
        found = detect_board(img, board, min_corners=6)
        if found is None:
            hint = ("; a far or low camera finds a plain chessboard more easily (printwatch board --type "
                    "chessboard)" if board.kind == "charuco" else "")
            raise CalibrationError(f"{label}: board ({board.describe()}) not found; make sure the whole "
                                   f"board is in view, lit evenly and not hidden by the nozzle or clips{hint}")
        detections.append(found)
    object_pts = np.concatenate([placement.to_printer(board, d.object_points(board)) for d in detections])
    pixels = np.concatenate([d.pixels for d in detections])
    rvec, tvec = _solve_planar_pose(object_pts, pixels, camera)
    posed = camera.with_pose(rvec, tvec)
    residual = np.linalg.norm(posed.project(object_pts) - pixels, axis=1)
    # A corner misplaced by glare, a clip or a misread marker would pull the whole pose.
    keep = residual <= max(4.0 * float(np.median(residual)), 1.0)
    if not keep.all() and keep.sum() >= 6:
        object_pts, pixels = object_pts[keep], pixels[keep]
        rvec, tvec = _solve_planar_pose(object_pts, pixels, camera)
        posed = camera.with_pose(rvec, tvec)
        residual = np.linalg.norm(posed.project(object_pts) - pixels, axis=1)
    rms = float(np.sqrt(np.mean(residual ** 2)))
    R_bp, t_bp = placement.board_to_printer(board)
    if (R_bp.T @ (posed.center - t_bp))[2] >= 0:  # board z points into the paper
        raise CalibrationError(f"{labels[0]}: the pose puts the camera behind the board (below the bed); "
                               "check the placement and that the board lies printed side up")
    noise = max(rms * np.sqrt(len(pixels) * 2 / max(len(pixels) * 2 - 6, 1)), 0.05)
    pos_sigma, rot_sigma = _pose_uncertainty(posed, object_pts, noise)

    warnings = []
    if rms > MAX_GOOD_BED_RMS_PX:
        warnings.append(f"reprojection error {rms:.2f} px is high: is the board flat and the intrinsics "
                        "from this camera at this zoom/focus?")
    if board.symmetric:
        warnings.append("the board looks the same turned half round; use a board with an odd and an even "
                        "number of squares, or ChArUco, or check the camera position")
    if pos_sigma > 1.0:
        warnings.append(f"camera position uncertain by {pos_sigma:.1f} mm; use a larger board or move it "
                        "nearer the camera")
    return BedPoseResult(posed, rms, len(pixels), posed.center, pos_sigma, rot_sigma, warnings)


def _camera_for_size(camera: Camera, image: np.ndarray, label: str) -> Camera:
    height, width = image.shape[:2]
    if (width, height) == camera.size:
        return camera
    if abs(width / height - camera.width / camera.height) > 0.01:
        raise CalibrationError(f"{label}: image is {width}x{height} but the intrinsics are for "
                               f"{camera.width}x{camera.height}, a different shape; calibrate at this resolution")
    return camera.scaled(width, height)


def _solve_planar_pose(object_pts: np.ndarray, pixels: np.ndarray, camera: Camera) -> tuple[np.ndarray, np.ndarray]:
    """Pose of a planar target: IPPE for the closed-form start, Levenberg-Marquardt to refine."""
    obj = object_pts.astype(np.float64).reshape(-1, 1, 3)
    img = pixels.astype(np.float64).reshape(-1, 1, 2)
    best = None
    for method in (cv2.SOLVEPNP_IPPE, cv2.SOLVEPNP_ITERATIVE):
        try:
            ok, rvec, tvec = cv2.solvePnP(obj, img, camera.K, camera.dist, flags=method)
        except cv2.error:
            continue
        if not ok:
            continue
        rvec, tvec = cv2.solvePnPRefineLM(obj, img, camera.K, camera.dist, rvec, tvec)
        err = np.linalg.norm(cv2.projectPoints(obj, rvec, tvec, camera.K, camera.dist)[0].reshape(-1, 2)
                             - pixels, axis=1).mean()
        if best is None or err < best[0]:
            best = (err, rvec.ravel(), tvec.ravel())
    if best is None:
        raise CalibrationError("the board's corners give no camera pose (are they all on one line?)")
    return best[1], best[2]


def _pose_uncertainty(camera: Camera, object_pts: np.ndarray, noise_px: float) -> tuple[float, float]:
    """(largest std of the camera centre in mm, std of the rotation in degrees) for corner noise ``noise_px``."""
    _, jac = cv2.projectPoints(object_pts.reshape(-1, 1, 3), camera.rvec, camera.tvec, camera.K, camera.dist)
    J = jac[:, :6]
    try:
        cov = np.linalg.inv(J.T @ J) * noise_px ** 2
    except np.linalg.LinAlgError:
        return float("inf"), float("inf")
    # Centre C = -R(r)^T t: propagate numerically.
    def centre(params):
        R = cv2.Rodrigues(params[:3])[0]
        return -R.T @ params[3:]
    p0 = np.concatenate([camera.rvec, camera.tvec])
    G = np.zeros((3, 6))
    for k in range(6):
        step = np.zeros(6)
        step[k] = 1e-6
        G[:, k] = (centre(p0 + step) - centre(p0 - step)) / 2e-6
    cov_c = G @ cov @ G.T
    pos = float(np.sqrt(max(np.linalg.eigvalsh(cov_c).max(), 0.0)))
    rot = float(np.degrees(np.sqrt(max(np.linalg.eigvalsh(cov[:3, :3]).max(), 0.0))))
    return pos, rot
