"""Printed height and width from each camera's silhouette against the model's cross-sections.

Two measurements that stay well conditioned where matching the outline between the two views is
not (``docs/stereo.md``, steps 4 and 5):

* **Height on the plane of the top.** The upper edge of a view's silhouette is the far edge of the
  part's top (cameras look down on the bed). Each pixel of it is a ray; the ray meets the plane
  ``Z = h`` on the model's cross-section boundary at ``h`` only when the top is at ``h``. Solved per
  image column (the ray against the section's far boundary at a grid of heights, interpolated), the
  median over the columns is the camera's printed height; the two cameras of a pair measure it
  independently and must agree. A millimetre of height moves the far edge by about
  ``cos(elevation) / mm_per_px`` pixels vertically, so a pixel is a fraction of a millimetre -- against
  several millimetres for triangulating the same near-horizontal edge along the epipolar rows.
* **Width from the tangent planes.** The left and right edges of a view's silhouette are the
  camera's two tangent planes to the part. Their offsets from the model's tangent planes (the
  projected cross-sections' extreme points over the band below the current height), measured at the
  part's distance, say how much wider or narrower than the model the part is across that camera's
  line of sight, whatever the part's position (a shift moves both planes alike and cancels). The
  pair's width is the model's width across the pair's line of sight plus the mean of the two
  cameras' offsets; both cameras must see it.

Both work in each camera's own (distorted) image, on the observed mask moved back by the shape
check's calibration shift, with edges placed at half contrast against the empty bed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..camera import Camera


def half_contrast_edges(diff: np.ndarray, rows: np.ndarray, x: np.ndarray, inward: int, reach: int = 8) -> np.ndarray:
    """Move silhouette edge positions to where the frame's difference from the empty bed is half way
    between the bed's and the part's, along each row.

    A background-removal mask marks everything detectably different from the bed, which puts its edge
    out in the blur's tail (a pixel or two per side, several percent of a small part's width). The
    half-contrast point of the blurred step is where the edge really is.

    diff : (h, w) float, |frame - background| in the same window; rows, x : (k,) edge positions;
    inward : +1 when the part lies to the right of the edge (a left edge), -1 otherwise.
    """
    h, w = diff.shape
    if len(x) == 0:
        return x
    k = np.arange(-reach, reach + 1)
    cols = np.clip(np.round(x)[:, None].astype(int) + inward * k[None, :], 0, w - 1)
    profile = diff[np.clip(rows, 0, h - 1)[:, None], cols]  # (n, 2 reach + 1), inward to the right
    outside = np.median(profile[:, : reach // 2], axis=1)
    inside = np.median(profile[:, -reach // 2:], axis=1)
    half = 0.5 * (outside + inside)
    above = profile >= half[:, None]
    # the outermost position from which the profile stays above half towards the inside
    run = np.flip(np.cumprod(np.flip(above, axis=1), axis=1), axis=1).astype(bool)
    first = np.argmax(run, axis=1)
    ok = run.any(axis=1) & (first > 0) & (inside - outside > 6.0)
    lo = profile[np.arange(len(x)), np.maximum(first - 1, 0)]
    hi = profile[np.arange(len(x)), first]
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.clip((half - lo) / (hi - lo), 0.0, 1.0)
    offset = (first - 1 + frac) - reach  # in k units from the original edge, inward positive
    return np.where(ok, np.round(x) + inward * offset, x)


class Sections:
    """The model's cross-sections by height (trimesh ``mesh_plane``), cached: checks reuse heights."""

    def __init__(self, mesh):
        self.mesh = mesh
        self.top = float(mesh.bounds[1, 2])
        self._cache: dict[float, np.ndarray] = {}

    def at(self, h: float) -> np.ndarray:
        """(n, 2, 3) segments of the section at height ``h`` (empty above the part's top)."""
        from trimesh.intersections import mesh_plane

        key = round(float(h), 3)
        if key not in self._cache:
            if key <= 0.0 or key >= self.top:
                self._cache[key] = np.zeros((0, 2, 3))
            else:
                self._cache[key] = np.asarray(mesh_plane(self.mesh, [0.0, 0.0, 1.0], [0.0, 0.0, key]),
                                              np.float64).reshape(-1, 2, 3)
        return self._cache[key]


def projected_top_profile(segments: np.ndarray, camera: Camera, width: int) -> np.ndarray:
    """(width,) the topmost image row of the section's projection per integer column (NaN where none).

    segments : (n, 2, 3) section segments in printer coordinates (one height)."""
    out = np.full(width, np.inf)
    if len(segments) == 0:
        return np.full(width, np.nan)
    uv = camera.project(segments.reshape(-1, 3)).reshape(-1, 2, 2)
    uv = uv[np.all(np.isfinite(uv), axis=(1, 2))]
    u0, v0, u1, v1 = uv[:, 0, 0], uv[:, 0, 1], uv[:, 1, 0], uv[:, 1, 1]
    lo = np.ceil(np.minimum(u0, u1)).astype(int)
    hi = np.floor(np.maximum(u0, u1)).astype(int)
    count = np.maximum(hi - lo + 1, 0)
    if count.sum() == 0:
        return np.full(width, np.nan)
    seg = np.repeat(np.arange(len(uv)), count)
    cols = np.repeat(lo, count) + (np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count))
    du = u1[seg] - u0[seg]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(np.abs(du) > 1e-9, (cols - u0[seg]) / du, 0.0)
    v = v0[seg] + np.clip(t, 0.0, 1.0) * (v1[seg] - v0[seg])
    ok = (cols >= 0) & (cols < width)
    np.minimum.at(out, cols[ok], v[ok])
    out[~np.isfinite(out)] = np.nan
    return out


def observed_top_profile(mask: np.ndarray, diff: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
    """The silhouette's upper edge per column: ``(cols (k,), rows (k,) sub-pixel)``.

    mask : (h, w) bool; diff : (h, w) float |frame - background| or None (then the mask's edge)."""
    has = mask.any(axis=0)
    cols = np.nonzero(has)[0]
    first = np.argmax(mask[:, cols], axis=0).astype(np.float64)
    if diff is not None:
        # the same half-contrast placement as for the side edges, along the columns (inward = down)
        first = half_contrast_edges(diff.T, cols, first, +1)
    else:
        first = first - 0.5  # the boundary between the last bed pixel and the first part pixel
    return cols, first


def observed_side_edges(mask: np.ndarray, diff: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The silhouette's left and right edge per row: ``(rows (k,), left (k,), right (k,))``, sub-pixel."""
    has = mask.any(axis=1)
    rows = np.nonzero(has)[0]
    w = mask.shape[1]
    left = np.argmax(mask[rows], axis=1).astype(np.float64)
    right = (w - 1 - np.argmax(mask[rows, ::-1], axis=1)).astype(np.float64)
    if diff is not None:
        left = half_contrast_edges(diff, rows, left, +1)
        right = half_contrast_edges(diff, rows, right, -1)
    else:
        left, right = left - 0.5, right + 0.5
    return rows, left, right


@dataclass
class PlaneHeight:
    """One camera's printed height from its silhouette's upper edge on the plane of the top."""

    height_mm: float | None
    columns: int  # image columns that gave a height
    spread_mm: float  # their median absolute deviation (the fit's consistency)
    reason: str = ""
    residual_px: float = float("nan")  # median (observed - model at z) row of the upper edge, down positive


def plane_height(camera: Camera, mask: np.ndarray, diff: np.ndarray | None, sections: Sections, z: float,
                 z_max: float, *, v_offset: float = 0.0, fine_mm: float = 0.25, coarse_mm: float = 1.0,
                 fine_span_mm: float = 4.0, min_columns: int = 8) -> PlaneHeight:
    """The height at which the model's top, cut at that height, projects onto this camera's silhouette
    upper edge; per column, then the median.

    mask : (h, w) bool observed part (this camera's frame, moved back by the calibration shift);
    z : the expected top; z_max : the highest height to consider (the mask is limited below it).
    ``v_offset``: px by which the picture stands lower than the calibration says (subtracted).
    Only columns where the model's top edge runs at most 1 px per column (a steep edge, at the
    silhouette's sides, is ill-conditioned) and away from the silhouette's ends are used."""
    w = mask.shape[1]
    low = np.arange(max(coarse_mm, 0.3), max(z - fine_span_mm, 0.3), coarse_mm)
    high = np.arange(max(z - fine_span_mm, 0.3), z_max + 1e-9, fine_mm)
    heights = np.unique(np.round(np.r_[low, high, min(z, z_max), z_max], 3))
    heights = heights[(heights < sections.top) & (heights <= z_max + 1e-9)]
    if len(heights) < 2:
        return PlaneHeight(None, 0, np.nan, "the model has no section at these heights")
    profiles = np.vstack([projected_top_profile(sections.at(h), camera, w) for h in heights])  # (k, w)
    # The solid printed up to h shows, per column, the highest of its sections up to h (a wider lower
    # part seen beyond a narrower upper one): the running minimum row over the heights below.
    profiles = np.minimum.accumulate(np.where(np.isnan(profiles), np.inf, profiles), axis=0)
    profiles[~np.isfinite(profiles)] = np.nan
    cols, observed = observed_top_profile(mask, diff)
    observed = observed - v_offset
    if len(cols) < min_columns:
        return PlaneHeight(None, 0, np.nan, "the silhouette has no upper edge")
    # Columns usable: there the model's top edge rises with the height near z (it is the top's far
    # edge, not a lower part's), it is not steep across the columns (ill-conditioned), and the
    # observed silhouette extends a few pixels either side (its ends are the side walls).
    k_z = int(np.searchsorted(heights, min(z, heights[-1]), side="right") - 1)
    k_below = int(np.searchsorted(heights, heights[max(k_z, 0)] - 1.0, side="right") - 1)
    at_z, below_z = profiles[max(k_z, 0)], profiles[max(k_below, 0)]
    slope = np.abs(np.gradient(at_z))
    rising = below_z - at_z >= 1.0
    margin = 3
    inner = (cols >= cols.min() + margin) & (cols <= cols.max() - margin)
    keep = inner & np.isfinite(at_z[cols]) & rising[cols] & (slope[cols] <= 1.0)
    cols, observed = cols[keep], observed[keep]
    if len(cols) < min_columns:
        return PlaneHeight(None, int(len(cols)), np.nan, "too little of the top edge is seen")
    residual = float(np.median(observed - at_z[cols]))
    e = profiles[:, cols]  # (k, n) expected row at each grid height; non-increasing with height
    # Per column, the first height at which the solid reaches the observed edge, interpolated from the
    # height below it. The running minimum leaves a column undefined only below the first section that
    # covers it, so the heights below the crossing are defined from that section up.
    finite = np.isfinite(e)
    reached = finite & (e <= observed[None, :])
    first_cover = np.argmax(finite, axis=0)
    i = np.argmax(reached, axis=0)
    found = np.full(len(cols), np.nan)
    none = ~reached.any(axis=0) & finite.any(axis=0)
    found[none] = np.inf  # above the highest height considered
    at_bottom = reached.any(axis=0) & (i <= first_cover)
    found[at_bottom] = -np.inf  # at or below the lowest height that shows this column
    mid = reached.any(axis=0) & (i > first_cover)
    j = np.nonzero(mid)[0]
    v0, v1 = e[i[j] - 1, j], e[i[j], j]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(v0 != v1, (v0 - observed[j]) / (v0 - v1), 1.0)
    found[j] = heights[i[j] - 1] + np.clip(t, 0.0, 1.0) * (heights[i[j]] - heights[i[j] - 1])
    found = found[~np.isnan(found)]
    if len(found) < min_columns:
        return PlaneHeight(None, int(len(found)), np.nan, "the top edge matches the model at too few columns")
    # Columns beyond the heights considered count at the range's ends (the mask is limited there).
    found = np.clip(found, heights[0], heights[-1])
    median = float(np.median(found))
    if median <= heights[0]:
        # most columns' edge stands at or below the lowest height considered: a bound, not a height. The part is
        # not seen above its first layers there (filament the bed's colour on blue tape: both views read 1.0 mm
        # of a 9-mm part, only its brim seen, and the pair paused the print before any failure)
        return PlaneHeight(None, int(len(found)), np.nan, "the silhouette's upper edge stands no higher than the "
                           f"lowest height considered ({heights[0]:.1f} mm): the part is not seen above it")
    return PlaneHeight(median, int(len(found)), float(np.median(np.abs(found - median))), residual_px=residual)



@dataclass
class TangentOffsets:
    """One camera's silhouette sides against the model's, at the part (mm, outward positive)."""

    left_mm: float | None
    right_mm: float | None
    rows: int
    on_bed: int = 0  # rows left out: the edge stood outside the model's where flat material can show

    @property
    def width_change_mm(self) -> float | None:
        if self.left_mm is None or self.right_mm is None:
            return None
        return self.left_mm + self.right_mm


def tangent_offsets(camera: Camera, mask: np.ndarray, diff: np.ndarray | None, sections: Sections, z_top: float,
                    band_mm: float, model_silhouette: np.ndarray | None = None, *, v_offset: float = 0.0,
                    flat_zone: np.ndarray | None = None, flat_slack_px: float = 2.0,
                    step_mm: float = 0.1, min_rows: int = 3) -> TangentOffsets:
    """How far the silhouette's left and right edges stand outside the model's over the band
    ``[z_top - band_mm, z_top]``, converted to mm at the tangent point's distance.

    The model's edge at each height of the band is its section's extreme projected point on that side
    (the camera's tangent plane touches the section there); the observed edge is taken on the same
    image row. The top quarter millimetre is left out (the corner's blur). ``model_silhouette``
    ((h, w) bool, the model printed up to ``z_top``): rows where another part of the model (a wider
    lower part seen beyond) forms the silhouette's edge are left out. ``v_offset``: px by which the
    picture stands lower than the calibration says (the observed edge is read that much lower).
    ``flat_zone`` ((h, w) bool, where flat material on the bed near the part -- a skirt, a brim, the
    part's shadow -- can show): an observed edge standing more than ``flat_slack_px`` outside the
    model's there may be that material rather than the part's side, so the row is left out; a side
    with more such rows than measured ones is not measured (its edge is the bed's, not the part's)."""
    heights = np.arange(max(z_top - band_mm, 0.3), z_top - 0.25 + 1e-9, step_mm)
    rows, obs_left, obs_right = observed_side_edges(mask, diff)
    if len(rows) == 0 or len(heights) == 0:
        return TangentOffsets(None, None, 0)
    f = float(camera.K[0, 0])
    out = {}
    for side, sign, observed in (("left", -1.0, obs_left), ("right", 1.0, obs_right)):
        offsets, on_bed = [], 0
        for h in heights:
            seg = sections.at(h)
            if len(seg) == 0:
                continue
            pts = seg.reshape(-1, 3)
            uv = camera.project(pts)
            ok = np.all(np.isfinite(uv), axis=1)
            if not ok.any():
                continue
            i = np.argmax(sign * np.where(ok, uv[:, 0], -sign * np.inf))
            u, v = uv[i]
            if model_silhouette is not None and not _forms_edge(model_silhouette, int(np.floor(v)), u, sign):
                continue
            v_seen = v + v_offset
            r0 = int(np.floor(v_seen))
            at = np.searchsorted(rows, r0)
            if at + 1 >= len(rows) or rows[at] != r0 or rows[at + 1] != r0 + 1:
                continue
            edge = observed[at] + (v_seen - r0) * (observed[at + 1] - observed[at])  # on the same (sub-pixel) row
            if flat_zone is not None and sign * (edge - u) > flat_slack_px and _inside(flat_zone, r0, edge):
                on_bed += 1
                continue
            depth = float(camera.to_camera(pts[i:i + 1])[0, 2])
            offsets.append(sign * (edge - u) * depth / f)
        measured = len(offsets) >= min_rows and on_bed <= len(offsets)
        out[side] = float(np.median(offsets)) if measured else None
        out[side + "_n"] = len(offsets)
        out[side + "_bed"] = on_bed
    return TangentOffsets(out["left"], out["right"], min(out["left_n"], out["right_n"]),
                          out["left_bed"] + out["right_bed"])


def _inside(zone: np.ndarray, row: int, x: float) -> bool:
    h, w = zone.shape
    col = int(round(x))
    return 0 <= row < h and 0 <= col < w and bool(zone[row, col])


def _forms_edge(silhouette: np.ndarray, row: int, u: float, sign: float, slack_px: float = 1.5) -> bool:
    """Whether the point at column ``u`` is the model silhouette's edge on ``row`` and the next
    (sign -1: left edge, +1: right edge), not hidden inside a wider part's outline."""
    h, w = silhouette.shape
    for r in (row, row + 1):
        if not 0 <= r < h:
            return False
        line = np.nonzero(silhouette[r])[0]
        if len(line) == 0:
            return False
        edge = line[0] - 0.5 if sign < 0 else line[-1] + 0.5
        if sign * (edge - u) > slack_px:
            return False
    return True
