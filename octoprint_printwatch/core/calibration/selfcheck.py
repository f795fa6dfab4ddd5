"""Has the camera moved since calibration? Compare the printed first layer with where it should be.

At the first checks of a print, the skirt and first layer are on the bed and
nothing hides them. Where they appear in the frame (frame minus the empty-bed
background) is compared with where the calibration projects them; a bumped
camera shows as a shift of the whole picture. No visible first layer means
"cannot tell", never "moved".
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np

from ..camera import Camera
from ..errors import CalibrationError
from ..gcode import iter_moves

#: Offsets (px) up to this are normal calibration error.
DEFAULT_TOLERANCE_PX = 3.0
#: Largest offset searched for (px, at 640 px frame width; scaled with the frame).
DEFAULT_SEARCH_PX = 40
#: Distances (px) beyond this count as "no match" so clutter cannot dominate.
_TRUNCATE_PX = 6.0


@dataclass
class PoseCheck:
    """Outcome of :func:`check_pose_against_first_layer`.

    Attributes
    ----------
    status : str
        ``"ok"``, ``"moved"`` or ``"unknown"`` (no usable evidence; not a failure).
    offset_px : float | None
        Length of the shift between expected and observed first layer (None when unknown).
    shift_px : (2,) float | None
        (dx, dy): observed minus expected position, pixels.
    match : float
        Fraction of expected first-layer pixels that lie on observed change after the shift (0..1).
    message : str
    """

    status: str
    offset_px: float | None
    shift_px: np.ndarray | None
    match: float
    message: str

    @property
    def ok(self) -> bool:
        """False only when the camera evidently moved."""
        return self.status != "moved"


def first_layer_paths(gcode_source) -> tuple[list[np.ndarray], float, float]:
    """The first layer's extrusions of a G-code file (path or lines): ``(paths, line_width_mm, z_mm)``.

    ``paths`` are (n, 3) polylines in printer mm (skirt, purge line, perimeters, infill);
    reading stops at the first extrusion above the first layer.
    """
    paths: list[list[tuple]] = []
    widths: list[float] = []
    first_z = None
    previous_end = None
    for move in iter_moves(gcode_source):
        if not move.extruding:
            if move.end[:2] != move.start[:2] or move.end[2] != move.start[2]:
                previous_end = None
            continue
        z = move.end[2]
        if first_z is None:
            first_z = z
        elif z > first_z + 1e-3:
            break
        if move.width:
            widths.append(move.width)
        if previous_end is not None and previous_end == move.start and paths:
            paths[-1].append(move.end)
        else:
            paths.append([move.start, move.end])
        previous_end = move.end
    if first_z is None:
        raise CalibrationError(f"{getattr(gcode_source, 'name', gcode_source)}: no extrusion found")
    width = float(np.median(widths)) if widths else 0.45
    return [np.asarray(p, dtype=np.float64) for p in paths], width, float(first_z)


def first_layer_mask(camera: Camera, paths_mm: Sequence[np.ndarray], line_width_mm: float = 0.45,
                     z_mm: float = 0.2) -> np.ndarray:
    """(H, W) bool: where extruded lines along ``paths_mm`` (each (n, 2) or (n, 3) printer mm) appear.

    Each segment is drawn as a quadrilateral of the line's width on the bed plane at ``z_mm``
    (the projected width changes across the bed).
    """
    mask = np.zeros((camera.height, camera.width), np.uint8)
    half = line_width_mm / 2.0
    quads = []
    for path in paths_mm:
        pts = np.asarray(path, dtype=np.float64)
        if pts.ndim != 2 or len(pts) < 2:
            continue
        z = pts[:, 2] if pts.shape[1] > 2 else np.full(len(pts), z_mm)
        a, b = pts[:-1, :2], pts[1:, :2]
        length = np.linalg.norm(b - a, axis=1)
        keep = length > 1e-9
        if not keep.any():
            continue
        a, b, za, zb = a[keep], b[keep], z[:-1][keep], z[1:][keep]
        normal = np.column_stack([-(b - a)[:, 1], (b - a)[:, 0]]) / length[keep, None] * half
        quads.append(np.stack([np.column_stack([a + normal, za]), np.column_stack([b + normal, zb]),
                               np.column_stack([b - normal, zb]), np.column_stack([a - normal, za])], axis=1))
    if not quads:
        return mask.astype(bool)
    quads = np.concatenate(quads)  # (n, 4, 3)
    pixels = camera.project(quads.reshape(-1, 3)).reshape(-1, 4, 2)
    # Behind the camera, or so far outside the frame that the lens model means nothing.
    limit = 4 * max(camera.width, camera.height)
    usable = ~np.isnan(pixels).any(axis=(1, 2)) & (np.nan_to_num(np.abs(pixels), nan=np.inf).max(axis=(1, 2)) < limit)
    fixed = np.round(pixels[usable] * 16).astype(np.int32)
    for quad in fixed:
        cv2.fillConvexPoly(mask, quad, 1, cv2.LINE_8, shift=4)
    # Lines thinner than a pixel still mark the pixels they cross.
    cv2.polylines(mask, list(fixed), True, 1, 1, cv2.LINE_8, shift=4)
    return mask.astype(bool)


def change_mask(frame: np.ndarray, background: np.ndarray, region: tuple[slice, slice] | None = None) -> np.ndarray:
    """(H, W) bool: pixels that differ from the empty bed by more than noise and lighting drift.

    The noise level (median and MAD of the difference) is measured inside ``region``
    (default: the whole frame), where most pixels are still bare bed.
    """
    f = cv2.GaussianBlur(np.asarray(frame, dtype=np.float32), (3, 3), 0)
    b = cv2.GaussianBlur(np.asarray(background, dtype=np.float32), (3, 3), 0)
    if f.ndim == 2:
        f, b = f[:, :, None], b[:, :, None]
    diff = f - b
    sample = diff[region] if region is not None else diff
    # A global exposure change shifts every pixel alike; remove it per channel.
    diff -= np.median(sample.reshape(-1, diff.shape[2]), axis=0)
    magnitude = np.abs(diff).max(axis=2)
    values = magnitude[region] if region is not None else magnitude
    med = float(np.median(values))
    mad = float(np.median(np.abs(values - med))) + 1e-6
    threshold = max(med + 6.0 * 1.4826 * mad, 10.0)
    return magnitude > threshold


def check_pose_against_first_layer(camera: Camera, frame: np.ndarray, background: np.ndarray,
                                   expected_first_layer_mask: np.ndarray, *,
                                   tolerance_px: float = DEFAULT_TOLERANCE_PX,
                                   search_px: int | None = None) -> PoseCheck:
    """Compare where the first layer appears in ``frame`` ((H, W, 3) uint8, after the first layer
    or skirt is printed) with ``expected_first_layer_mask`` ((H, W) bool, from the calibration)."""
    frame = np.asarray(frame)
    background = np.asarray(background)
    expected = np.asarray(expected_first_layer_mask).astype(bool)
    size = (camera.height, camera.width)
    for what, array in (("frame", frame), ("background", background), ("expected mask", expected)):
        if array.shape[:2] != size:
            raise CalibrationError(f"{what} is {array.shape[1]}x{array.shape[0]} but camera {camera.name} is "
                                   f"{camera.width}x{camera.height}")
    if frame.ndim != background.ndim:
        raise CalibrationError("frame and background must both be colour or both grey")
    n_expected = int(expected.sum())
    if n_expected < 20:
        return PoseCheck("unknown", None, None, 0.0,
                         f"{camera.name}: the first layer is (almost) out of view; cannot check the camera pose")
    if search_px is None:
        search_px = int(round(DEFAULT_SEARCH_PX * camera.width / 640.0))
    ys, xs = np.nonzero(expected)
    pad = search_px + int(_TRUNCATE_PX) + 2
    y0, y1 = max(ys.min() - pad, 0), min(ys.max() + pad + 1, size[0])
    x0, x1 = max(xs.min() - pad, 0), min(xs.max() + pad + 1, size[1])
    region = change_mask(frame, background, (slice(y0, y1), slice(x0, x1)))[y0:y1, x0:x1]
    if region.sum() < 0.2 * n_expected:
        return PoseCheck("unknown", None, None, 0.0,
                         f"{camera.name}: the first layer does not stand out from the bed; cannot check the pose")
    # Truncated chamfer distance from each expected pixel to the nearest observed change,
    # for every shift in the search window, as one correlation.
    dist = cv2.distanceTransform((~region).astype(np.uint8), cv2.DIST_L2, 5)
    dist = np.minimum(dist, _TRUNCATE_PX).astype(np.float32)
    template = expected[ys.min():ys.max() + 1, xs.min():xs.max() + 1].astype(np.float32)
    # Place the region in a canvas wide enough for every shift, unseen parts counting as "far".
    ty, tx = ys.min() - y0, xs.min() - x0  # template's unshifted position inside `region`
    canvas = np.full((template.shape[0] + 2 * search_px, template.shape[1] + 2 * search_px), _TRUNCATE_PX,
                     np.float32)
    cy0, cx0 = ty - search_px, tx - search_px  # canvas origin in region coordinates
    ry0, rx0 = max(cy0, 0), max(cx0, 0)
    ry1 = min(cy0 + canvas.shape[0], dist.shape[0])
    rx1 = min(cx0 + canvas.shape[1], dist.shape[1])
    canvas[ry0 - cy0:ry1 - cy0, rx0 - cx0:rx1 - cx0] = dist[ry0:ry1, rx0:rx1]
    cost = cv2.matchTemplate(canvas, template, cv2.TM_CCORR) / n_expected  # mean truncated distance
    iy, ix = np.unravel_index(int(np.argmin(cost)), cost.shape)
    dy, dx = _subpixel(cost, iy, ix)
    shift = np.array([ix + dx - search_px, iy + dy - search_px], dtype=float)
    best = float(cost[iy, ix])
    match = float(np.mean(_shifted(dist, expected[y0:y1, x0:x1], ix - search_px, iy - search_px) <= 1.5))
    if best > 0.5 * _TRUNCATE_PX or match < 0.3:
        return PoseCheck("unknown", None, None, match,
                         f"{camera.name}: the printed first layer does not match its expected shape anywhere "
                         f"within {search_px} px; the camera may have moved a lot, or the first layer failed")
    offset = float(np.hypot(*shift))
    if offset <= tolerance_px:
        return PoseCheck("ok", offset, shift, match,
                         f"{camera.name}: first layer where expected (off by {offset:.1f} px)")
    return PoseCheck("moved", offset, shift, match,
                     f"{camera.name}: the first layer appears {offset:.1f} px from where the calibration puts it "
                     f"(dx {shift[0]:+.1f}, dy {shift[1]:+.1f}); the camera was probably bumped, recalibrate "
                     "its bed pose")


def _subpixel(cost: np.ndarray, iy: int, ix: int) -> tuple[float, float]:
    def vertex(m, c, p):
        denom = m - 2 * c + p
        return 0.0 if denom <= 1e-12 else float(np.clip(0.5 * (m - p) / denom, -0.5, 0.5))
    dy = vertex(cost[iy - 1, ix], cost[iy, ix], cost[iy + 1, ix]) if 0 < iy < cost.shape[0] - 1 else 0.0
    dx = vertex(cost[iy, ix - 1], cost[iy, ix], cost[iy, ix + 1]) if 0 < ix < cost.shape[1] - 1 else 0.0
    return dy, dx


def _shifted(dist: np.ndarray, mask: np.ndarray, dx: int, dy: int) -> np.ndarray:
    """Distances at the pixels of ``mask`` moved by (dx, dy); pixels moved outside count as far."""
    ys, xs = np.nonzero(mask)
    ys, xs = ys + dy, xs + dx
    inside = (ys >= 0) & (ys < dist.shape[0]) & (xs >= 0) & (xs < dist.shape[1])
    values = np.full(len(ys), _TRUNCATE_PX, np.float32)
    values[inside] = dist[ys[inside], xs[inside]]
    return values


def refine_pose_from_shift(camera: Camera, shift_px: Sequence[float], *, at_px: Sequence[float] | None = None,
                           max_deg: float = 2.0) -> tuple[Camera, str]:
    """Turn the camera about its centre so image content moves by ``shift_px`` (dx, dy) at ``at_px``
    (default: the image centre). A bumped webcam mostly turns on its mount, which this undoes.

    Returns the new camera and a sentence saying what changed. Raises CalibrationError when the
    correction would exceed ``max_deg`` (then the bed pose must be recalibrated).
    """
    shift = np.asarray(shift_px, dtype=np.float64).reshape(2)
    at = np.asarray(at_px if at_px is not None else camera.K[:2, 2], dtype=np.float64).reshape(1, 2)
    p = camera.undistort_points(at)[0]
    q = camera.undistort_points(at + shift)[0]
    Kinv = np.linalg.inv(camera.K)
    d_old = Kinv @ np.array([p[0], p[1], 1.0])
    d_new = Kinv @ np.array([q[0], q[1], 1.0])
    d_old /= np.linalg.norm(d_old)
    d_new /= np.linalg.norm(d_new)
    axis = np.cross(d_old, d_new)
    sin, cos = np.linalg.norm(axis), float(np.dot(d_old, d_new))
    angle = float(np.arctan2(sin, cos))
    if np.degrees(angle) > max_deg:
        raise CalibrationError(f"camera {camera.name}: correcting a {np.hypot(*shift):.0f} px shift needs "
                               f"{np.degrees(angle):.1f} deg of rotation (limit {max_deg:g}); recalibrate the bed pose")
    if sin < 1e-12:
        return camera.with_pose(camera.rvec, camera.tvec), f"camera {camera.name}: no change"
    rc = cv2.Rodrigues(axis / sin * angle)[0]
    R_new = rc @ camera.R
    refined = camera.with_pose(cv2.Rodrigues(R_new)[0].ravel(), rc @ camera.tvec)
    pan = np.degrees(np.arctan2(d_new[0], d_new[2]) - np.arctan2(d_old[0], d_old[2]))
    tilt = np.degrees(np.arctan2(d_new[1], d_new[2]) - np.arctan2(d_old[1], d_old[2]))
    return refined, (f"camera {camera.name}: turned by {np.degrees(angle):.2f} deg (pan {pan:+.2f}, tilt "
                     f"{tilt:+.2f}) to follow a {np.hypot(*shift):.1f} px shift; position unchanged")
