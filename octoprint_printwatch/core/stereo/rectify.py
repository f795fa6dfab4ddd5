"""Rectifying a relaxed camera pair, three ways, each reporting whether it can be trusted.

All three are expressed the same way: a homography per camera from its
*undistorted* image to a common rectified window in which matching points lie
on the same row. The remap tables fold lens undistortion in, so a distorted
frame goes to the rectified window in one ``cv2.remap``, and rectified pixels
map back to undistorted camera pixels for triangulation with the real cameras.

* :func:`rectify_calibrated` — ``cv2.stereoRectify`` from the two cameras'
  printer-frame extrinsics (relative pose ``R = R_r R_l^T``, ``T = t_r - R t_l``),
  optionally refined by a vertical offset measured on feature matches, since a
  user's calibration is half a degree off and that is several pixels of rows.
* :func:`rectify_uncalibrated` — SIFT matches, RANSAC fundamental matrix,
  ``cv2.stereoRectifyUncalibrated``: the proper form of what the seed approximated.
* :func:`rectify_seed` — the seed's own rescale (Eqs. A-1..A-3) then vertical
  shift (Eq. A-4), kept as the reference it is.

A result whose ``trusted`` is False must not be measured: the caller abstains.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import cv2
import numpy as np

from ..camera import Camera

RECTIFICATIONS = ("calibrated", "uncalibrated", "seed")

#: Fewest RANSAC inliers for a feature-based rectification to be believed.
MIN_INLIERS = 12
#: Largest median row mismatch (px) of inlier matches after rectification.
MAX_RESIDUAL_PX = 1.5


@dataclass
class Rectification:
    """A rectified window shared by both cameras of a pair.

    Attributes
    ----------
    method : str
    left, right : Camera
    H_left, H_right : (3, 3) homographies, undistorted camera pixels -> rectified window pixels.
    size : (width, height) of the rectified window.
    trusted : bool
    inliers : int
        Feature matches supporting the rectification (0 when none were measured).
    residual_px : float
        Median |row difference| of those matches after rectifying (NaN when unmeasured).
    reason : str
        Why it is not trusted ('' when it is).
    disparity_range : (2,) ints or None
        Disparities expected for the region, ``x_left - x_right`` in the window.
    """

    method: str
    left: Camera
    right: Camera
    H_left: np.ndarray
    H_right: np.ndarray
    size: tuple[int, int]
    trusted: bool = True
    inliers: int = 0
    residual_px: float = float("nan")
    reason: str = ""
    disparity_range: tuple[int, int] | None = None
    #: Calibrated only: window intrinsics, rotation printer -> rectified left frame, signed baseline (mm).
    K_rect: np.ndarray | None = None
    R_rect: np.ndarray | None = None
    baseline_mm: float = float("nan")
    _maps: dict = field(default_factory=dict, repr=False)

    def maps(self, which: str) -> tuple[np.ndarray, np.ndarray]:
        """Remap tables (window -> distorted frame of that camera) for ``which`` in {'left', 'right'}."""
        if which not in self._maps:
            cam, H = (self.left, self.H_left) if which == "left" else (self.right, self.H_right)
            R = np.linalg.inv(cam.K) @ H @ cam.K  # initUndistortRectifyMap inverts (K @ R)
            self._maps[which] = cv2.initUndistortRectifyMap(cam.K, cam.dist, R, cam.K, self.size, cv2.CV_32FC1)
        return self._maps[which]

    def warp(self, image: np.ndarray, which: str, *, interpolation: int = cv2.INTER_LINEAR) -> np.ndarray:
        """A distorted frame (or mask) of the ``which`` camera -> the rectified window."""
        map_x, map_y = self.maps(which)
        return cv2.remap(image, map_x, map_y, interpolation, borderMode=cv2.BORDER_CONSTANT)

    def to_camera_pixels(self, window_px: np.ndarray, which: str) -> np.ndarray:
        """(n, 2) window pixels -> (n, 2) undistorted pixels of that camera."""
        H = self.H_left if which == "left" else self.H_right
        return _apply_h(np.linalg.inv(H), window_px)

    def from_camera_pixels(self, undistorted_px: np.ndarray, which: str) -> np.ndarray:
        """(n, 2) undistorted pixels of that camera -> (n, 2) window pixels."""
        H = self.H_left if which == "left" else self.H_right
        return _apply_h(H, undistorted_px)

    def rectified_to_printer(self, points: np.ndarray) -> np.ndarray:
        """(n, 3) points in the rectified left camera frame (calibrated only) -> (n, 3) printer points."""
        if self.R_rect is None:
            raise ValueError(f"{self.method} rectification has no metric frame")
        return self.left.center + np.asarray(points, np.float64).reshape(-1, 3) @ self.R_rect

    def summary(self) -> dict:
        return {"method": self.method, "trusted": self.trusted, "inliers": self.inliers,
                "residual_px": None if not np.isfinite(self.residual_px) else round(float(self.residual_px), 3),
                "reason": self.reason}


def _apply_h(H: np.ndarray, px: np.ndarray) -> np.ndarray:
    px = np.asarray(px, np.float64).reshape(-1, 2)
    h = np.column_stack([px, np.ones(len(px))]) @ H.T
    with np.errstate(divide="ignore", invalid="ignore"):
        return h[:, :2] / h[:, 2:3]


def _translate(dx: float, dy: float) -> np.ndarray:
    return np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])


def _fit_window(H_left: np.ndarray, H_right: np.ndarray, roi_left: np.ndarray, roi_right: np.ndarray,
                margin: int, max_size: tuple[int, int]):
    """Translate both homographies so the two regions (corner pixels, (4, 2)) fit one window."""
    corners = np.vstack([_apply_h(H_left, roi_left), _apply_h(H_right, roi_right)])
    lo = np.floor(corners.min(axis=0)) - margin
    hi = np.ceil(corners.max(axis=0)) + margin
    size = np.minimum(hi - lo, max_size).astype(int)
    # If clipped, keep the window centred on the regions.
    centre = (lo + hi) / 2
    lo = np.floor(centre - size / 2)
    T = _translate(-lo[0], -lo[1])
    return T @ H_left, T @ H_right, (int(size[0]), int(size[1]))


def _roi_corners(roi, cam: Camera) -> np.ndarray:
    """(x0, y0, x1, y1) distorted-pixel box (or None for the whole frame) -> (4, 2) undistorted corners."""
    if roi is None:
        roi = (0, 0, cam.width - 1, cam.height - 1)
    x0, y0, x1, y1 = roi
    # Sample the box's edges, not only its corners: distortion bends them.
    t = np.linspace(0, 1, 9)
    edge = np.vstack([np.column_stack([x0 + (x1 - x0) * t, np.full_like(t, y0)]),
                      np.column_stack([x0 + (x1 - x0) * t, np.full_like(t, y1)]),
                      np.column_stack([np.full_like(t, x0), y0 + (y1 - y0) * t]),
                      np.column_stack([np.full_like(t, x1), y0 + (y1 - y0) * t])])
    return cam.undistort_points(edge)


# --------------------------------------------------------------- calibrated
def rectify_calibrated(left: Camera, right: Camera, *, roi_left=None, roi_right=None, margin: int = 8,
                       max_size: tuple[int, int] = (1600, 1200)) -> Rectification:
    """Rectification from the cameras' own calibration (printer-frame extrinsics).

    ``roi_left``/``roi_right`` are (x0, y0, x1, y1) boxes in the distorted frames that the
    window must contain (the part's region); default the whole frames.
    """
    R = right.R @ left.R.T
    T = right.tvec - R @ left.tvec
    R1, R2, P1, _P2, _Q, _roi1, _roi2 = cv2.stereoRectify(
        left.K, np.zeros(5), right.K, np.zeros(5), left.size, R, T.reshape(3, 1), flags=cv2.CALIB_ZERO_DISPARITY, alpha=-1)
    f = float(np.mean([left.K[0, 0], left.K[1, 1], right.K[0, 0], right.K[1, 1]]))
    K_new = np.array([[f, 0.0, 0.0], [0.0, f, 0.0], [0.0, 0.0, 1.0]])
    H_left = K_new @ R1 @ np.linalg.inv(left.K)
    H_right = K_new @ R2 @ np.linalg.inv(right.K)
    if np.linalg.det(R1) < 0 or np.linalg.det(R2) < 0:
        return Rectification("calibrated", left, right, H_left, H_right, (1, 1), trusted=False,
                             reason="stereoRectify returned a reflection")
    H_left, H_right, size = _fit_window(H_left, H_right, _roi_corners(roi_left, left),
                                        _roi_corners(roi_right, right), margin, max_size)
    K_rect = H_left @ left.K @ R1.T  # the window translation folded into K_new
    # Signed baseline along the rectified x axis: the right camera sits at +B.
    B = float((R1 @ left.R @ (right.center - left.center))[0])
    return Rectification("calibrated", left, right, H_left, H_right, size, K_rect=K_rect,
                         R_rect=R1 @ left.R, baseline_mm=B)


def baseline_mm(left: Camera, right: Camera) -> float:
    return float(np.linalg.norm(left.center - right.center))


def predict_disparity_range(rect: Rectification, points: np.ndarray, margin_px: float) -> tuple[int, int]:
    """Disparities (x_left - x_right in the window) of printer points (n, 3), widened by a margin."""
    pl = rect.from_camera_pixels(rect.left.project(points, distorted=False), "left")
    pr = rect.from_camera_pixels(rect.right.project(points, distorted=False), "right")
    d = pl[:, 0] - pr[:, 0]
    d = d[np.isfinite(d)]
    if len(d) == 0:
        return (0, 0)
    return (int(np.floor(d.min() - margin_px)), int(np.ceil(d.max() + margin_px)))


# ------------------------------------------------------------------ features
@dataclass
class FeatureMatches:
    """SIFT matches that survived the ratio test and RANSAC on the fundamental matrix."""

    left: np.ndarray  # (n, 2) undistorted pixels
    right: np.ndarray  # (n, 2)
    distance: np.ndarray  # (n,) descriptor distances, smaller is better
    F: np.ndarray | None  # (3, 3) or None


_SIFT = None


def sift_matches(left_img: np.ndarray, right_img: np.ndarray, left: Camera, right: Camera,
                 mask_left: np.ndarray | None = None, mask_right: np.ndarray | None = None,
                 ratio: float = 0.75, max_features: int = 1500, ransac: bool = True) -> FeatureMatches:
    """SIFT + Lowe ratio test (+ RANSAC F unless ``ransac=False``) on two distorted frames; pixels undistorted."""
    global _SIFT
    if _SIFT is None:
        _SIFT = cv2.SIFT_create(nfeatures=max_features)
    grey = [img if img.ndim == 2 else cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) for img in (left_img, right_img)]
    masks = [None if m is None else (m > 0).astype(np.uint8) * 255 for m in (mask_left, mask_right)]
    kl, dl = _SIFT.detectAndCompute(grey[0], masks[0])
    kr, dr = _SIFT.detectAndCompute(grey[1], masks[1])
    empty = FeatureMatches(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0), None)
    if dl is None or dr is None or len(kl) < 2 or len(kr) < 2:
        return empty
    pairs = cv2.BFMatcher(cv2.NORM_L2).knnMatch(dl, dr, k=2)
    good = [m[0] for m in pairs if len(m) == 2 and m[0].distance < ratio * m[1].distance]
    if len(good) < 8:
        return empty
    pl = left.undistort_points(np.array([kl[m.queryIdx].pt for m in good]))
    pr = right.undistort_points(np.array([kr[m.trainIdx].pt for m in good]))
    dist = np.array([m.distance for m in good])
    if not ransac:
        return FeatureMatches(pl, pr, dist, None)
    F, inlier = cv2.findFundamentalMat(pl, pr, cv2.FM_RANSAC, 1.0, 0.999)
    if F is None or F.shape != (3, 3):
        return FeatureMatches(pl, pr, dist, None)
    keep = inlier.ravel().astype(bool)
    return FeatureMatches(pl[keep], pr[keep], dist[keep], F)


def _row_residual(rect: Rectification, matches: FeatureMatches) -> np.ndarray:
    """Signed row difference (left - right) of the matches in the window."""
    return rect.from_camera_pixels(matches.left, "left")[:, 1] - rect.from_camera_pixels(matches.right, "right")[:, 1]


def refine_vertical(rect: Rectification, matches: FeatureMatches, max_shift_px: float | None = None) -> Rectification:
    """Correct a calibrated rectification's row error with feature matches, and report the residual.

    The matches need no RANSAC: the calibrated geometry already says where they should be, so the
    row differences of true matches cluster tightly while wrong ones scatter. The cluster (mode of
    the row differences, within 1.5 px) gives the inliers; an affine fit ``dy = a + b x + c y`` on them
    is removed from the right camera's homography. With too few inliers the calibrated
    rectification is kept unrefined (residual unmeasured): calibration alone is still usable.
    """
    if max_shift_px is None:
        max_shift_px = rect.K_rect[0, 0] * np.tan(np.radians(2.0)) if rect.K_rect is not None else 40.0
    if len(matches.left) < MIN_INLIERS:
        rect.inliers = 0
        return rect
    wl = rect.from_camera_pixels(matches.left, "left")
    wr = rect.from_camera_pixels(matches.right, "right")
    dy = wl[:, 1] - wr[:, 1]
    plausible = np.abs(dy) <= max_shift_px
    if plausible.sum() < MIN_INLIERS:
        rect.inliers = 0
        return rect
    bins = np.arange(-max_shift_px, max_shift_px + 1.0, 1.0)
    counts, edges = np.histogram(dy[plausible], bins=bins)
    smooth = np.convolve(counts, [1, 1, 1], mode="same")
    mode = edges[np.argmax(smooth)] + 0.5
    inliers = plausible & (np.abs(dy - mode) < 1.5)
    if inliers.sum() < MIN_INLIERS:
        rect.inliers = int(inliers.sum())
        return rect
    A = np.column_stack([np.ones(inliers.sum()), wr[inliers, 0], wr[inliers, 1]])
    spread = np.ptp(wr[inliers], axis=0)
    if inliers.sum() >= 3 * MIN_INLIERS and np.all(spread > 0.25 * np.array(rect.size)):
        coef, *_ = np.linalg.lstsq(A, dy[inliers], rcond=None)
    else:
        coef = np.array([float(np.median(dy[inliers])), 0.0, 0.0])
    # Right rows y' = y + a + b x + c y, so that left and right rows agree.
    correction = np.array([[1.0, 0.0, 0.0], [coef[1], 1.0 + coef[2], coef[0]], [0.0, 0.0, 1.0]])
    rect.H_right = correction @ rect.H_right
    rect._maps.clear()
    rect.inliers = int(inliers.sum())
    residual = np.abs(_row_residual(rect, FeatureMatches(matches.left[inliers], matches.right[inliers],
                                                         matches.distance[inliers], None)))
    rect.residual_px = float(np.median(residual))
    if rect.residual_px > MAX_RESIDUAL_PX:
        rect.trusted = False
        rect.reason = f"rows still differ by {rect.residual_px:.1f} px after calibrated rectification"
    return rect


# ------------------------------------------------------------ uncalibrated
def rectify_uncalibrated(left: Camera, right: Camera, matches: FeatureMatches, *, roi_left=None,
                         roi_right=None, margin: int = 8, max_size: tuple[int, int] = (1600, 1200)) -> Rectification:
    """``cv2.stereoRectifyUncalibrated`` from RANSAC-filtered SIFT matches (undistorted pixels)."""
    untrusted = Rectification("uncalibrated", left, right, np.eye(3), np.eye(3), left.size, trusted=False,
                              inliers=len(matches.left))
    if matches.F is None or len(matches.left) < MIN_INLIERS:
        untrusted.reason = f"only {len(matches.left)} feature matches survived RANSAC (need {MIN_INLIERS})"
        return untrusted
    ok, H1, H2 = cv2.stereoRectifyUncalibrated(matches.left, matches.right, matches.F, left.size, threshold=3.0)
    if not ok:
        untrusted.reason = "stereoRectifyUncalibrated failed"
        return untrusted
    # Keep orientation: a reflected or badly sheared window is not a rectification to trust.
    for H in (H1, H2):
        if np.linalg.det(H[:2, :2]) <= 0 or H[0, 0] < 0:
            untrusted.reason = "uncalibrated rectification flips the image"
            return untrusted
    # Rescale both so the window's pixels are about as large as the cameras'.
    centre = np.array([[left.width / 2, left.height / 2], [left.width / 2 + 1, left.height / 2],
                       [left.width / 2, left.height / 2 + 1]])
    p = _apply_h(H1, centre)
    scale = 1.0 / max(np.sqrt(abs(np.linalg.det(np.column_stack([p[1] - p[0], p[2] - p[0]])))), 1e-9)
    S = np.diag([scale, scale, 1.0])
    H1, H2 = S @ H1, S @ H2
    H1, H2, size = _fit_window(H1, H2, _roi_corners(roi_left, left), _roi_corners(roi_right, right), margin,
                               max_size)
    rect = Rectification("uncalibrated", left, right, H1, H2, size, inliers=len(matches.left))
    dy = _row_residual(rect, matches)
    rect.residual_px = float(np.median(np.abs(dy)))
    if rect.residual_px > MAX_RESIDUAL_PX:
        rect.trusted = False
        rect.reason = f"rows differ by {rect.residual_px:.1f} px after uncalibrated rectification"
    rect.disparity_range = _match_disparity_range(rect, matches)
    return rect


def _match_disparity_range(rect: Rectification, matches: FeatureMatches, margin: float = 6.0):
    d = rect.from_camera_pixels(matches.left, "left")[:, 0] - rect.from_camera_pixels(matches.right, "right")[:, 0]
    lo, hi = np.percentile(d, [2, 98])
    return (int(np.floor(lo - margin)), int(np.ceil(hi + margin)))


# -------------------------------------------------------------------- seed
def seed_height_ratio(y_left: np.ndarray, y_right: np.ndarray) -> tuple[float, float, float]:
    """Eqs. A-1..A-3 on the best matches (already sorted best first).

    Returns ``(sum_H_left, sum_H_right, ratio)`` with the heights summed over consecutive pairs
    (i, i+1), i stepping by 2. The ratio (<= 1) is what the larger image is scaled by: the seed's
    worked example (32.96 vs 32.27 px) scales the left image by 0.98.
    """
    n = len(y_left) - len(y_left) % 2
    sum_left = float(np.sum(np.abs(y_left[0:n:2] - y_left[1:n:2])))
    sum_right = float(np.sum(np.abs(y_right[0:n:2] - y_right[1:n:2])))
    if sum_left <= 0 or sum_right <= 0:
        return sum_left, sum_right, float("nan")
    return sum_left, sum_right, min(sum_left, sum_right) / max(sum_left, sum_right)


def rectify_seed(left: Camera, right: Camera, matches: FeatureMatches, *, top_fraction: float = 0.1,
                 roi_left=None, roi_right=None, margin: int = 8,
                 max_size: tuple[int, int] = (1600, 1200)) -> Rectification:
    """The seed's rescale (A-1..A-3) then vertical shift (A-4) from the top 10 % matches.

    The seed re-ran SIFT after rescaling; rescaling maps the matches exactly, so they are
    transformed instead of re-detected.
    """
    untrusted = Rectification("seed", left, right, np.eye(3), np.eye(3), left.size, trusted=False,
                              inliers=len(matches.left))
    if len(matches.left) < MIN_INLIERS:
        untrusted.reason = f"only {len(matches.left)} feature matches (need {MIN_INLIERS})"
        return untrusted
    order = np.argsort(matches.distance)
    n_top = max(MIN_INLIERS, int(round(top_fraction * len(order))))
    top = order[:n_top]
    sum_left, sum_right, ratio = seed_height_ratio(matches.left[top, 1], matches.right[top, 1])
    if not np.isfinite(ratio):
        untrusted.reason = "matched points have no height spread to rescale by"
        return untrusted
    S_left = np.diag([ratio, ratio, 1.0]) if sum_left > sum_right else np.eye(3)
    S_right = np.eye(3) if sum_left > sum_right else np.diag([ratio, ratio, 1.0])
    y_left = _apply_h(S_left, matches.left[top])[:, 1]
    y_right = _apply_h(S_right, matches.right[top])[:, 1]
    diff_y = float(np.median(y_left - y_right))  # Eq. A-4; the median over the top matches
    H1 = _translate(0.0, -diff_y) @ S_left  # "the left image is moved up by Diff_y"
    H2 = S_right
    H1, H2, size = _fit_window(H1, H2, _roi_corners(roi_left, left), _roi_corners(roi_right, right), margin,
                               max_size)
    rect = Rectification("seed", left, right, H1, H2, size, inliers=len(matches.left))
    rect.residual_px = float(np.median(np.abs(_row_residual(rect, matches))))
    if rect.residual_px > MAX_RESIDUAL_PX:
        rect.trusted = False
        rect.reason = f"rows differ by {rect.residual_px:.1f} px after the seed's rescale and shift"
    rect.disparity_range = _match_disparity_range(rect, matches)
    return rect


# ------------------------------------------------------------- bed plane
def plane_homography(rect: Rectification, z: float = 0.0) -> np.ndarray:
    """(3, 3) map from left-window pixels to right-window pixels induced by the plane Z = z."""
    w, h = rect.size
    grid = np.array([[x, y] for x in np.linspace(0, w - 1, 5) for y in np.linspace(0, h - 1, 5)], np.float64)
    bed = rect.left.unproject_to_plane(rect.to_camera_pixels(grid, "left"), z, distorted=False)
    right = rect.from_camera_pixels(rect.right.project(bed, distorted=False), "right")
    ok = np.all(np.isfinite(right), axis=1)
    if ok.sum() < 4:
        raise ValueError("the bed plane is not in view")
    H, _ = cv2.findHomography(grid[ok], right[ok], 0)
    return H


def phase_shift(reference: np.ndarray, moved: np.ndarray, mask: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """((dx, dy), response): ``moved`` shows ``reference``'s content displaced by (dx, dy) pixels.

    Phase correlation on grey images; ``mask`` weights the pixels (softly, so the mask's own outline,
    identical in both, does not pull the answer to zero).
    """
    a = _grey(reference)
    b = _grey(moved)
    weight = cv2.createHanningWindow((a.shape[1], a.shape[0]), cv2.CV_32F)
    if mask is not None:
        m = mask.astype(bool)
        if m.sum() < 100:
            return np.zeros(2), 0.0
        weight = weight * cv2.GaussianBlur(m.astype(np.float32), (0, 0), 6.0)
        a = np.where(m, a - a[m].mean(), 0.0).astype(np.float32)
        b = np.where(m, b - b[m].mean(), 0.0).astype(np.float32)
    (dx, dy), response = cv2.phaseCorrelate(a, b, weight)
    return np.array([dx, dy]), float(response)


def _grey(image: np.ndarray) -> np.ndarray:
    return (image if image.ndim == 2 else cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)).astype(np.float32)


def _dense_shift(reference: np.ndarray, moved: np.ndarray, mask: np.ndarray, max_shift: float):
    """(shift (2,), spread px, matched share): the median displacement of ``moved`` against ``reference``
    on ``mask``, from dense matching along x and then along y (on the transposed images)."""
    from .matching import MatchSettings, compute_disparity

    r = int(np.ceil(max_shift))
    settings = MatchSettings("sgbm", -r, 2 * r + 1, 5)
    shift, spreads, shares = np.zeros(2), [], []
    for axis in (0, 1):
        a, b, m = (reference, moved, mask) if axis == 0 else \
            (np.ascontiguousarray(np.swapaxes(reference, 0, 1)), np.ascontiguousarray(np.swapaxes(moved, 0, 1)),
             np.ascontiguousarray(mask.T))
        d = compute_disparity(a, b, settings, m)[m]
        d = d[np.isfinite(d)]
        shares.append(len(d) / max(int(m.sum()), 1))
        if len(d) < 50:
            return shift, np.inf, 0.0
        median = float(np.median(d))
        shift[axis] = -median  # matched x_moved = x_ref - d: the content moved by -d
        spreads.append(1.4826 * float(np.median(np.abs(d - median))))
    return shift, max(spreads), min(shares)


def align_on_bed(rect: Rectification, background_left: np.ndarray, background_right: np.ndarray,
                 bed_mask_left: np.ndarray, max_shift_px: float = 40.0) -> tuple[bool, str]:
    """Correct the right camera's window placement with the empty bed, in place.

    The right empty-bed frame is warped into the left window through the bed plane; with a perfect
    calibration the two then coincide on the bed. Whatever shift remains (calibration error: a
    rotation of half a degree is several pixels) is measured by dense matching along x and along y
    on the bed around the part (median; accepted only when enough of the bed matches consistently)
    and removed from the right camera's homography: its x part is a disparity offset, its y part a
    row offset. Returns (applied, note).
    """
    try:
        H = plane_homography(rect, 0.0)
    except (ValueError, cv2.error):
        return False, "bed reference: the bed is not in view"
    wl = rect.warp(background_left, "left")
    wr = rect.warp(background_right, "right")
    w, h = rect.size
    # What the right camera would show if its calibration were exact: the left view carried over
    # through the bed plane, compared with what it does show, in the right window itself.
    expected = cv2.warpPerspective(wl, H, (w, h), flags=cv2.INTER_LINEAR)
    covered = cv2.warpPerspective((bed_mask_left & (rect.warp(np.full(background_left.shape[:2], 255, np.uint8),
                                                              "left", interpolation=cv2.INTER_NEAREST) > 0))
                                  .astype(np.uint8), H, (w, h), flags=cv2.INTER_NEAREST) > 0
    region = covered & (rect.warp(np.full(background_right.shape[:2], 255, np.uint8), "right",
                                  interpolation=cv2.INTER_NEAREST) > 0)
    offset, spread, share = _dense_shift(expected, wr, region, max_shift_px)
    if share < 0.1 or spread > 2.5:
        return False, (f"bed reference: no reliable alignment on the bed ({share:.0%} of it matched, "
                       f"spread {spread:.1f} px)")
    response = share
    # The right window shows the bed displaced by ``offset`` from where the calibration puts it.
    rect.H_right = _translate(-offset[0], -offset[1]) @ rect.H_right
    rect._maps.clear()
    return True, (f"bed reference: right window moved by ({-offset[0]:+.2f}, {-offset[1]:+.2f}) px, "
                  f"{response:.0%} of the bed matched")
