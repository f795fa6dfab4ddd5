"""Lens intrinsics from several views of a board, with a verdict a hobbyist can act on."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import cv2
import numpy as np

from ..boards import Board, Detection, detect_board, to_gray
from ..camera import Camera
from ..errors import CalibrationError
from .images import common_size, image_labels

#: Views with the board found needed before the result can be called good.
MIN_GOOD_VIEWS = 8
#: RMS reprojection error (px) above which the calibration is not trusted.
MAX_GOOD_RMS_PX = 1.0
#: Union of the boards' outlines, as a fraction of the frame, needed for a good verdict.
MIN_COVERAGE = 0.5
#: Relative standard deviation of the focal length above which it is not trusted.
MAX_FOCAL_UNCERTAINTY = 0.01
#: Estimated edge blur (Gaussian sigma, px) above which a view is called blurred.
MAX_BLUR_SIGMA_PX = 2.5
#: Fewest corners a ChArUco view must show to be used (spread over two rows at least).
MIN_VIEW_CORNERS = 8


@dataclass
class IntrinsicsResult:
    """Outcome of :func:`calibrate_intrinsics`.

    Attributes
    ----------
    camera : Camera
        K and distortion; pose left at identity (set by the bed calibration).
    rms_px : float
        RMS reprojection error over all corners of the views used.
    per_view_errors : dict[str, float]
        RMS error (px) of each view used, keyed by its label.
    verdict : str
        ``"good"`` or ``"retake"``.
    reasons : list[str]
        Why a retake is advised (empty when good), each an instruction.
    coverage : float
        Fraction of the frame covered by at least one view of the board (0..1).
    views_used : list[str]
        Labels of the views that went into the result.
    views_skipped : dict[str, str]
        Labels of views left out, with why.
    focal_uncertainty : float
        One standard deviation of fx, relative (0.004 = 0.4 %).
    blur_sigma_px : dict[str, float]
        Estimated edge blur of each view used.
    max_tilt_deg : float
        Largest angle between the board and the image plane over the views.
    """

    camera: Camera
    rms_px: float
    per_view_errors: dict[str, float]
    verdict: str
    reasons: list[str]
    coverage: float
    views_used: list[str]
    views_skipped: dict[str, str] = field(default_factory=dict)
    focal_uncertainty: float = 0.0
    blur_sigma_px: dict[str, float] = field(default_factory=dict)
    max_tilt_deg: float = 0.0

    def summary(self) -> dict:
        """JSON-ready figures stored beside the camera (``Camera.save(path, **summary)``)."""
        return {
            "rms_px": round(self.rms_px, 4),
            "verdict": self.verdict,
            "reasons": list(self.reasons),
            "coverage": round(self.coverage, 3),
            "views_used": list(self.views_used),
            "views_skipped": dict(self.views_skipped),
            "focal_uncertainty": round(self.focal_uncertainty, 5),
        }


def detect_views(images: Sequence[np.ndarray], board: Board, labels: Sequence[str],
                 min_corners: int = MIN_VIEW_CORNERS) -> tuple[list[Detection | None], dict[str, str]]:
    """Board detections per image (None where unusable) and why each unusable one was skipped."""
    detections: list[Detection | None] = []
    skipped: dict[str, str] = {}
    for image, label in zip(images, labels):
        found = detect_board(image, board, min_corners=4)
        if found is None:
            skipped[label] = "no board found"
            found = None
        elif len(found) < min_corners or _collinear(found, board):
            skipped[label] = f"only {len(found)} corners visible"
            found = None
        detections.append(found)
    return detections, skipped


def _collinear(detection: Detection, board: Board) -> bool:
    obj = detection.object_points(board)[:, :2]
    return np.linalg.matrix_rank(obj - obj.mean(axis=0), tol=1e-6) < 2


def calibrate_intrinsics(images: Sequence[np.ndarray], board: Board, *, labels: Sequence[str] | None = None,
                         name: str = "camera", fix_k3: bool | None = None) -> IntrinsicsResult:
    """K and lens distortion from several views of ``board`` (list of (H, W[, 3]) uint8 frames).

    Views without the board are skipped (and listed); a view whose error is far
    above the others (moved or bent board) is dropped once. Raises
    :class:`CalibrationError` for fewer than two images, mixed sizes, or fewer
    than three usable views.
    """
    labels = image_labels(images, labels)
    if len(images) < 2:
        raise CalibrationError(f"{labels[0] if labels else 'no images'}: one image only; take 10-15 views of the "
                               "board, tilted and moved into every corner of the frame" if images else
                               "no images given")
    size = common_size(images, labels)
    detections, skipped = detect_views(images, board, labels)
    usable = [(lab, det, img) for lab, det, img in zip(labels, detections, images) if det is not None]
    if len(usable) < 3:
        where = ", ".join(f"{k} ({v})" for k, v in list(skipped.items())[:4])
        raise CalibrationError(f"board ({board.describe()}) usable in only {len(usable)} of {len(images)} "
                               f"images, need at least 3: {where}")
    if fix_k3 is None:
        fix_k3 = len(usable) < 10  # the sixth-order term overfits a handful of views
    flags = cv2.CALIB_FIX_K3 if fix_k3 else 0
    views = usable
    result = _calibrate(views, board, size, flags)
    errors = result[4]
    limit = max(3.0 * float(np.median(errors)), 1.0)
    worst = int(np.argmax(errors))
    if errors[worst] > limit and len(views) > 4:
        skipped[views[worst][0]] = (f"error {errors[worst]:.2f} px, far above the others "
                                    "(board moved, bent or blurred)")
        views = views[:worst] + views[worst + 1:]
        result = _calibrate(views, board, size, flags)
    rms, K, dist, rvecs, errors, std_intrinsics = result
    camera = Camera(name=name, width=size[0], height=size[1], K=K, dist=dist.ravel())
    view_labels = [lab for lab, _, _ in views]
    coverage, missed_corners = _coverage([det for _, det, _ in views], size)
    blur = {lab: estimate_blur_sigma(img, det) for lab, det, img in views}
    tilts = [_tilt_deg(r) for r in rvecs]
    focal_unc = float(std_intrinsics[0] / K[0, 0]) if std_intrinsics is not None else 0.0

    reasons = []
    if len(views) < MIN_GOOD_VIEWS:
        reasons.append(f"only {len(views)} usable views; take at least {MIN_GOOD_VIEWS} (10-15 is best)")
    if rms > MAX_GOOD_RMS_PX:
        reasons.append(f"reprojection error {rms:.2f} px is high; hold the board still, keep it flat, "
                       "and use sharp, well-lit frames")
    if coverage < MIN_COVERAGE:
        reasons.append(f"the board covered only {coverage:.0%} of the frame; move it closer and "
                       "towards the edges")
    if missed_corners:
        reasons.append(f"no view reached the {', '.join(missed_corners)} corner of the frame; "
                       "lens distortion is strongest there")
    if max(tilts) < 20.0:
        reasons.append("the board was always nearly square to the camera; tilt it by 20-45 degrees in "
                       "some views so the focal length can be measured")
    elif focal_unc > MAX_FOCAL_UNCERTAINTY:
        reasons.append(f"focal length uncertain by {focal_unc:.1%}; add views with the board tilted "
                       "in different directions")
    blurred = [lab for lab, sigma in blur.items() if sigma > MAX_BLUR_SIGMA_PX]
    if blurred and len(blurred) * 4 >= len(views):
        reasons.append(f"{len(blurred)} views are blurred ({', '.join(blurred[:3])}"
                       f"{', ...' if len(blurred) > 3 else ''}); focus the camera or add light")
    return IntrinsicsResult(
        camera=camera,
        rms_px=float(rms),
        per_view_errors={lab: float(e) for lab, e in zip(view_labels, errors)},
        verdict="retake" if reasons else "good",
        reasons=reasons,
        coverage=coverage,
        views_used=view_labels,
        views_skipped=skipped,
        focal_uncertainty=focal_unc,
        blur_sigma_px=blur,
        max_tilt_deg=float(max(tilts)),
    )


def _calibrate(views, board: Board, size: tuple[int, int], flags: int):
    objects = [det.object_points(board).astype(np.float32) for _, det, _ in views]
    pixels = [det.pixels.astype(np.float32).reshape(-1, 1, 2) for _, det, _ in views]
    criteria = (cv2.TERM_CRITERIA_COUNT + cv2.TERM_CRITERIA_EPS, 100, 1e-9)
    try:
        rms, K, dist, rvecs, _, std_intr, _, per_view = cv2.calibrateCameraExtended(
            objects, pixels, size, None, None, flags=flags, criteria=criteria)
    except cv2.error as exc:
        raise CalibrationError(f"calibration did not converge on {len(views)} views "
                               f"({str(exc).strip().splitlines()[-1]})") from None
    if not (np.all(np.isfinite(K)) and np.all(np.isfinite(dist))):
        raise CalibrationError(f"calibration did not converge on {len(views)} views")
    return rms, K, dist, rvecs, np.asarray(per_view).ravel(), np.asarray(std_intr).ravel()


def _tilt_deg(rvec: np.ndarray) -> float:
    """Angle between the board's normal and the optical axis."""
    normal = cv2.Rodrigues(np.asarray(rvec))[0][:, 2]
    return float(np.degrees(np.arccos(min(1.0, abs(normal[2])))))


def _coverage(detections: Sequence[Detection], size: tuple[int, int], cells: int = 32
              ) -> tuple[float, list[str]]:
    """Fraction of the frame inside at least one view's corner hull, and the frame corners
    (outer 20 % x 20 %) that no detected corner reached."""
    w, h = size
    grid = np.zeros((cells, cells), np.uint8)
    scale = np.array([cells / w, cells / h])
    reached = {"top-left": False, "top-right": False, "bottom-left": False, "bottom-right": False}
    for det in detections:
        hull = cv2.convexHull((det.pixels * scale).astype(np.float32)).round().astype(np.int32)
        cv2.fillConvexPoly(grid, hull, 1)
        u, v = det.pixels[:, 0] / w, det.pixels[:, 1] / h
        reached["top-left"] |= bool(np.any((u < 0.2) & (v < 0.2)))
        reached["top-right"] |= bool(np.any((u > 0.8) & (v < 0.2)))
        reached["bottom-left"] |= bool(np.any((u < 0.2) & (v > 0.8)))
        reached["bottom-right"] |= bool(np.any((u > 0.8) & (v > 0.8)))
    return float(grid.mean()), [corner for corner, ok in reached.items() if not ok]


def estimate_blur_sigma(image: np.ndarray, detection: Detection) -> float:
    """Edge blur of the board region as a Gaussian sigma in pixels.

    For an ideal step of contrast C blurred by a Gaussian of sigma s, the steepest
    gradient is C / (s * sqrt(2 pi)); the board's squares give plenty of such steps.
    """
    gray = to_gray(image).astype(np.float32)
    mask = np.zeros(gray.shape, np.uint8)
    cv2.fillConvexPoly(mask, cv2.convexHull(detection.pixels.astype(np.float32)).round().astype(np.int32), 1)
    inside = mask.astype(bool)
    if inside.sum() < 50:
        return float("nan")
    gx = cv2.Sobel(gray, cv2.CV_32F, 1, 0, ksize=3) / 8.0
    gy = cv2.Sobel(gray, cv2.CV_32F, 0, 1, ksize=3) / 8.0
    grad = np.hypot(gx, gy)[inside]
    values = gray[inside]
    contrast = float(np.percentile(values, 95) - np.percentile(values, 5))
    steepest = float(np.percentile(grad, 99.5))
    if steepest <= 0 or contrast <= 0:
        return float("inf")
    # A Sobel of a perfectly sharp edge still spreads it over about one pixel.
    sigma = contrast / (np.sqrt(2 * np.pi) * steepest)
    return float(np.sqrt(max(sigma ** 2 - 0.5 ** 2, 0.0)))
