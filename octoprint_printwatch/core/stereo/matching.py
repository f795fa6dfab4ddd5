"""Dense stereo matching on a rectified pair.

Every matcher returns a disparity map on the *left* image grid, in pixels, with
``x_right = x_left - d`` on the same row and NaN where no trustworthy match was
found. The cost-volume matchers (the seed's SAD, Eq. 1-7 / 2-1, and the costs its
chapter 5 proposes trying: SSD and NCC) are vectorised: one box filter per
candidate disparity over the shifted absolute/squared/product image, never a
Python loop over pixels. ``cv2.StereoSGBM`` is the modern candidate.

Matching can be restricted to a region (``mask``, e.g. the part's expected
silhouette dilated): only its bounding box is computed and pixels outside it
come back NaN, which is both faster and keeps the bed out of the measurement.
"""
from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

MATCHERS = ("sad", "ssd", "ncc", "sgbm")

#: Cost volumes are computed in row strips holding at most this many floats.
_MAX_VOLUME = 24_000_000


@dataclass
class MatchSettings:
    """How to match.

    Attributes
    ----------
    method : str
        One of :data:`MATCHERS`.
    min_disparity : int
        Smallest disparity searched (may be negative).
    num_disparities : int
        Number of disparities searched (the seed's +-15 px search region is 31).
    block_size : int
        Odd side of the square block (the seed used 67).
    uniqueness : float
        A match is kept only when the second-best cost (away from the best's
        neighbours) exceeds the best by this fraction of the cost spread.
    lr_check : bool
        Keep only matches that the right-referenced search finds too (within 1 px).
    """

    method: str = "sad"
    min_disparity: int = 0
    num_disparities: int = 64
    block_size: int = 15
    uniqueness: float = 0.05
    lr_check: bool = True

    def __post_init__(self) -> None:
        if self.method not in MATCHERS:
            raise ValueError(f"unknown matcher {self.method!r}; choose one of {', '.join(MATCHERS)}")
        if self.block_size < 1 or self.block_size % 2 == 0:
            raise ValueError(f"block_size must be a positive odd number, got {self.block_size}")
        if self.num_disparities < 2:
            raise ValueError(f"num_disparities must be at least 2, got {self.num_disparities}")


def to_gray(image: np.ndarray) -> np.ndarray:
    """(h, w) or (h, w, 3) BGR image -> (h, w) float32 grey."""
    if image.ndim == 3:
        image = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY)
    return image.astype(np.float32)


def compute_disparity(left: np.ndarray, right: np.ndarray, settings: MatchSettings | None = None,
                      mask: np.ndarray | None = None) -> np.ndarray:
    """Disparity of a rectified pair.

    Parameters
    ----------
    left, right : (h, w) or (h, w, 3) images of the same size, rectified (matches on the same row).
    settings : MatchSettings
    mask : (h, w) bool, optional
        Left-image pixels to match; the rest are NaN.

    Returns
    -------
    (h, w) float32 disparity, ``x_right = x_left - d``, NaN where unmatched.
    """
    settings = settings or MatchSettings()
    if left.shape[:2] != right.shape[:2]:
        raise ValueError(f"left {left.shape[:2]} and right {right.shape[:2]} images differ in size")
    h, w = left.shape[:2]
    out = np.full((h, w), np.nan, np.float32)
    if mask is None:
        mask = np.ones((h, w), bool)
    rows, cols = np.nonzero(mask)
    if len(rows) == 0:
        return out
    half = settings.block_size // 2
    y0, y1 = max(rows.min() - half, 0), min(rows.max() + half + 1, h)
    x0, x1 = max(cols.min() - half, 0), min(cols.max() + half + 1, w)
    if settings.method == "sgbm":
        disp = _sgbm(left, right, settings, y0, y1, x0, x1)
    else:
        disp = _cost_volume_match(to_gray(left), to_gray(right), settings, y0, y1, x0, x1)
    out[y0:y1, x0:x1] = disp
    out[~mask] = np.nan
    return out


# ------------------------------------------------------------ cost volumes
def _shifted_right(right: np.ndarray, y0: int, y1: int, x0: int, x1: int, d: int) -> tuple[np.ndarray, np.ndarray]:
    """Right image sampled at (x - d) for left columns x0..x1-1 (edge-replicated), and which columns are real."""
    w = right.shape[1]
    src = np.arange(x0, x1) - d
    real = (src >= 0) & (src < w)
    return right[y0:y1][:, np.clip(src, 0, w - 1)], real


def _box(image: np.ndarray, block: int) -> np.ndarray:
    return cv2.boxFilter(image, cv2.CV_32F, (block, block), normalize=True, borderType=cv2.BORDER_REFLECT)


def _costs(left: np.ndarray, right: np.ndarray, settings: MatchSettings, y0: int, y1: int,
           x0: int, x1: int) -> np.ndarray:
    """(D, y1-y0, x1-x0) matching cost, lower is better, +inf where the block leaves the right image."""
    block = settings.block_size
    L = left[y0:y1, x0:x1]
    disparities = range(settings.min_disparity, settings.min_disparity + settings.num_disparities)
    volume = np.empty((settings.num_disparities, y1 - y0, x1 - x0), np.float32)
    if settings.method == "ncc":
        mean_l = _box(L, block)
        var_l = np.maximum(_box(L * L, block) - mean_l * mean_l, 0.0)
    for i, d in enumerate(disparities):
        R, real = _shifted_right(right, y0, y1, x0, x1, d)
        if settings.method == "sad":
            cost = _box(np.abs(L - R), block)
        elif settings.method == "ssd":
            cost = _box((L - R) ** 2, block)
        else:  # ncc: 1 - normalised cross-correlation, in [0, 2]
            mean_r = _box(R, block)
            var_r = np.maximum(_box(R * R, block) - mean_r * mean_r, 0.0)
            cov = _box(L * R, block) - mean_l * mean_r
            cost = 1.0 - cov / np.sqrt(var_l * var_r + 1e-3)
        # A block that reaches outside the right image has no valid cost.
        reach = np.convolve(~real, np.ones(block), mode="same") > 0
        cost[:, reach] = np.inf
        volume[i] = cost
    return volume


def _cost_volume_match(left: np.ndarray, right: np.ndarray, settings: MatchSettings,
                       y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    half = settings.block_size // 2
    strip = max(8, _MAX_VOLUME // max(1, settings.num_disparities * (x1 - x0)))
    out = np.full((y1 - y0, x1 - x0), np.nan, np.float32)
    for s0 in range(y0, y1, strip):
        s1 = min(s0 + strip, y1)
        # Pad the strip by half a block so box sums near its edges see real rows.
        p0, p1 = max(s0 - half, 0), min(s1 + half, left.shape[0])
        volume = _costs(left, right, settings, p0, p1, x0, x1)
        disp = _winner(volume, settings)
        out[s0 - y0: s1 - y0] = disp[s0 - p0: s1 - p0]
    return out


def _winner(volume: np.ndarray, settings: MatchSettings) -> np.ndarray:
    """Winner-take-all with sub-pixel parabola, uniqueness and left-right checks."""
    D, h, w = volume.shape
    finite = np.isfinite(volume)
    vol = np.where(finite, volume, np.float32(np.finfo(np.float32).max))
    best = np.argmin(vol, axis=0)
    best_cost = np.take_along_axis(vol, best[None], 0)[0]
    valid = np.take_along_axis(finite, best[None], 0)[0]

    # Uniqueness: the best must beat every candidate beyond its neighbours clearly.
    idx = np.arange(D)[:, None, None]
    far = np.abs(idx - best[None]) > 1
    second = np.where(far & finite, vol, np.inf).min(axis=0)
    spread = np.where(finite, vol, -np.inf).max(axis=0) - best_cost
    valid &= (second - best_cost) > settings.uniqueness * np.maximum(spread, 1e-6)

    # Sub-pixel: parabola through the best and its two neighbours.
    lo = np.take_along_axis(volume, np.clip(best - 1, 0, D - 1)[None], 0)[0].astype(np.float64)
    hi = np.take_along_axis(volume, np.clip(best + 1, 0, D - 1)[None], 0)[0].astype(np.float64)
    interior = (best > 0) & (best < D - 1) & np.isfinite(lo) & np.isfinite(hi)
    denom = lo - 2 * best_cost.astype(np.float64) + hi
    with np.errstate(divide="ignore", invalid="ignore"):
        offset = np.where(interior & (denom > 0), 0.5 * (lo - hi) / denom, 0.0)
    # A minimum at the end of the search range is a clipped search, not a match.
    valid &= interior
    disp = best + np.clip(offset, -0.5, 0.5) + settings.min_disparity

    if settings.lr_check:
        # Right-referenced winner: a right pixel j (in left-crop columns shifted by the disparity index)
        # sees candidates C[i, y, j + i]; j runs over [-(D-1), w-1], stored at j + D - 1.
        j = np.arange(-(D - 1), w)
        cols = j[None, :] + np.arange(D)[:, None]  # (D, w + D - 1) left columns
        inside = (cols >= 0) & (cols < w)
        index = np.broadcast_to(np.clip(cols, 0, w - 1)[:, None, :], (D, h, len(j)))
        gathered = np.where(inside[:, None, :], np.take_along_axis(vol, index, 2), np.inf)
        best_right = np.argmin(gathered, axis=0)  # (h, w + D - 1) disparity index
        index_left = disp - settings.min_disparity
        j_of_left = np.clip(np.round(np.arange(w)[None, :] - index_left).astype(np.intp) + D - 1, 0, len(j) - 1)
        back = np.take_along_axis(best_right, j_of_left, 1)
        valid &= np.abs(back - index_left) <= 1.0
    return np.where(valid, disp, np.nan).astype(np.float32)


# ------------------------------------------------------------------- SGBM
def _sgbm(left: np.ndarray, right: np.ndarray, settings: MatchSettings,
          y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    num = int(np.ceil(settings.num_disparities / 16.0) * 16)
    dmin = settings.min_disparity
    # SGBM leaves the first numDisparities columns of its input unmatched and wants minDisparity
    # small, so the right image is pre-shifted by dmin and both are padded on the left.
    pad = num + 1
    cols = np.arange(x0 - pad, x1)
    w = left.shape[1]
    real_left = (cols >= 0) & (cols < w)
    src_right = cols - dmin
    real_right = (src_right >= 0) & (src_right < w)
    L = left[y0:y1][:, np.clip(cols, 0, w - 1)]
    R = right[y0:y1][:, np.clip(src_right, 0, w - 1)]
    L[:, ~real_left] = 0
    R[:, ~real_right] = 0
    channels = 1 if L.ndim == 2 else L.shape[2]
    block = min(settings.block_size, 11)  # SGBM's smoothness term does the aggregating
    sgbm = cv2.StereoSGBM_create(
        minDisparity=0, numDisparities=num, blockSize=block,
        P1=8 * channels * block * block, P2=32 * channels * block * block,
        disp12MaxDiff=1 if settings.lr_check else -1,
        uniquenessRatio=max(0, int(round(settings.uniqueness * 100))),
        speckleWindowSize=100, speckleRange=2, mode=cv2.STEREO_SGBM_MODE_SGBM_3WAY)
    raw = sgbm.compute(np.ascontiguousarray(L), np.ascontiguousarray(R)).astype(np.float32) / 16.0
    raw[raw < 0] = np.nan
    # A match at the very end of the range is a clipped search, not a match.
    raw[raw >= settings.num_disparities - 1] = np.nan
    return raw[:, pad:] + dmin
