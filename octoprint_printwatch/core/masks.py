"""Binary-mask helpers shared by the vision checks; every mask is (h, w) bool."""
from __future__ import annotations

import cv2
import numpy as np


def disk(radius: float) -> np.ndarray:
    r = max(0, int(round(radius)))
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))


def dilate(mask: np.ndarray, radius: float) -> np.ndarray:
    """(h, w) bool grown by ``radius`` px (Euclidean; a distance transform, so large radii cost no more)."""
    if radius < 0.5:
        return mask.astype(bool)
    if radius <= 2.5:
        return cv2.dilate(mask.astype(np.uint8), disk(radius)).astype(bool)
    out = np.zeros(mask.shape, bool)
    # (on the box that can be reached only: the 3x3 distance grows by at least 0.955 px per px, so nothing
    # beyond that box is within ``radius``, and inside it the distances are the whole image's)
    box = bounding_box(mask, pad=int(np.ceil(radius / 0.955)) + 1)
    if box is None:
        return out
    inner = (slice(box[0], box[1]), slice(box[2], box[3]))
    out[inner] = cv2.distanceTransform((~mask[inner].astype(bool)).astype(np.uint8), cv2.DIST_L2, 3) <= radius
    return out


def erode(mask: np.ndarray, radius: float) -> np.ndarray:
    """(h, w) bool shrunk by ``radius`` px; the image border does not erode."""
    if radius < 0.5:
        return mask.astype(bool)
    if radius <= 2.5:
        return cv2.erode(mask.astype(np.uint8), disk(radius), borderType=cv2.BORDER_REPLICATE).astype(bool)
    out = np.zeros(mask.shape, bool)
    # (on the mask's box with a ring of background around it, which every distance from inside reaches first)
    box = bounding_box(mask, pad=1)
    if box is None:
        return out
    inner = (slice(box[0], box[1]), slice(box[2], box[3]))
    padded = cv2.copyMakeBorder(mask[inner].astype(np.uint8), 1, 1, 1, 1, cv2.BORDER_REPLICATE)
    out[inner] = cv2.distanceTransform(padded, cv2.DIST_L2, 3)[1:-1, 1:-1] > radius
    return out


def shift_mask(mask: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """(h, w) bool moved by (dx, dy) pixels, zeros shifted in."""
    if dx == 0 and dy == 0:
        return mask
    out = np.zeros_like(mask)
    h, w = mask.shape
    ys, yd = (slice(0, h - dy), slice(dy, h)) if dy >= 0 else (slice(-dy, h), slice(0, h + dy))
    xs, xd = (slice(0, w - dx), slice(dx, w)) if dx >= 0 else (slice(-dx, w), slice(0, w + dx))
    out[yd, xd] = mask[ys, xs]
    return out


def bounding_box(mask: np.ndarray, pad: int = 0) -> tuple[int, int, int, int] | None:
    """(y0, y1, x0, x1) half-open box around the True pixels, padded and clipped; None if empty."""
    rows = np.flatnonzero(mask.any(axis=1))
    if rows.size == 0:
        return None
    cols = np.flatnonzero(mask.any(axis=0))
    h, w = mask.shape
    return (max(0, rows[0] - pad), min(h, rows[-1] + 1 + pad), max(0, cols[0] - pad), min(w, cols[-1] + 1 + pad))


def around(mask: np.ndarray, box: tuple[int, int, int, int], reach_x: int, reach_y: int) -> np.ndarray:
    """(y1 - y0 + 2 reach_y, x1 - x0 + 2 reach_x) float32: ``mask`` around ``box`` (y0, y1, x0, x1),
    grown by the reach on each side, zero beyond the image. ``cv2.matchTemplate(around(m, box, rx, ry),
    template, cv2.TM_CCORR)`` with ``template`` the box's content gives, at index (dy + ry, dx + rx),
    the sum of ``m`` under the template moved by (dx, dy): every shift at once."""
    y0, y1, x0, x1 = box
    h, w = mask.shape
    out = np.zeros((y1 - y0 + 2 * reach_y, x1 - x0 + 2 * reach_x), np.float32)
    sy0, sy1, sx0, sx1 = max(0, y0 - reach_y), min(h, y1 + reach_y), max(0, x0 - reach_x), min(w, x1 + reach_x)
    out[sy0 - (y0 - reach_y): sy1 - (y0 - reach_y), sx0 - (x0 - reach_x): sx1 - (x0 - reach_x)] = \
        mask[sy0:sy1, sx0:sx1]
    return out


def outline_zone(expected: np.ndarray, tolerance: float, top_tolerance: float = 0.0) -> np.ndarray:
    """(h, w) bool: ``expected`` grown by ``tolerance`` px, and upwards (towards row 0) by ``top_tolerance``
    px more (a part's top may stand a little higher in the image than its outline: the vertical alignment
    is the least certain, and a camera may fire a layer late). Material there is not held against the print."""
    grown = dilate(expected, tolerance)
    if top_tolerance >= 1.0:
        k = int(round(top_tolerance))
        grown |= cv2.dilate(grown.astype(np.uint8), np.ones((k + 1, 1), np.uint8), anchor=(0, 0)).astype(bool)
    return grown


def reaching_in_from_above(objects: np.ndarray, search: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """(h, w) bool: the pixels of ``objects`` in blobs that reach in from above the ``search`` box and hang
    there, which are not the print's (the parked hotend, the gantry, a hand).

    A blob counts when 15 % of its pixels lie beyond the box and 5 % above its top edge (a part sliding out
    sideways is the print's), and it does not reach down into the ``expected`` part's lowest quarter (a part
    that tipped over and stands taller than the box does).
    """
    out = np.zeros(objects.shape, bool)
    box = bounding_box(objects)
    if box is None:
        return out
    # (on the objects' box only: every blob lies in it, and the whole frame costs several times more)
    y0, y1, x0, x1 = box
    inner = (slice(y0, y1), slice(x0, x1))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(objects[inner].astype(np.uint8), connectivity=8)
    if count <= 1:
        return out
    area = stats[:, cv2.CC_STAT_AREA]
    ceiling = np.where(search.any(axis=0), np.argmax(search, axis=0), search.shape[0])[x0:x1]
    above = np.arange(y0, y1)[:, None] < ceiling[None, :]
    beyond = np.bincount(labels[~search[inner]], minlength=count)
    from_above = np.bincount(labels[above], minlength=count)
    foreign = (beyond >= 0.15 * np.maximum(area, 1)) & (from_above >= 0.05 * np.maximum(area, 1))
    rows = np.flatnonzero(expected.any(axis=1))
    if rows.size:
        foot_zone = rows[-1] - 0.25 * (rows[-1] - rows[0])
        lowest = y0 + stats[:, cv2.CC_STAT_TOP] + stats[:, cv2.CC_STAT_HEIGHT] - 1
        foreign &= lowest < foot_zone
    foreign[0] = False
    out[inner] = foreign[labels]
    return out
