"""Shadows that moved between the background frame and a check are not material.

The parked head, its carriage and the gantry rise with every check, so the shadows they cast on the bed
move: where the background frame had such a shadow the bed is now lit, and reads as "brighter than the
background". Physics tells the two apart without numbers tuned to one scene:

* light that returns brightens the bed by one factor in every channel (white light keeps the bed's
  chromaticity; the colour cue already checks that);
* it cannot make the bed brighter than the lit bed itself;
* the bed keeps its own texture: where the background shows a pattern above the noise, the frame's
  local pattern correlates with it (normalised cross-correlation, blind to the brightness factor).
Material (a strand, a moved part) replaces the bed's colour or its texture, or is brighter than the lit
bed; only a part whose colour, brightness and (on a smooth bed) lack of texture match the lit bed
passes for a shadow that left, and such a part is camouflaged anyway.
"""
from __future__ import annotations

from typing import Callable

import cv2
import numpy as np

from .masks import bounding_box

#: Side (px) of the window the local pattern is compared in.
TEXTURE_WINDOW = 11
#: The background's local grain (standard deviation) must reach this many noise units (the brightening
#: cue's noise on certain bed, which a 1-px shake does not inflate) before its correlation is asked for.
TEXTURE_MIN_Z = 2.0
#: Where the bed shows a pattern, the frame must correlate with it at least this well to be the same bed.
MIN_CORRELATION = 0.5
#: How far (px) a pixel's correlation reads around it: the window's half side plus the 1-px shift.
_CORRELATION_REACH = TEXTURE_WINDOW // 2 + 1
#: How far (px) the test of one pixel reads around it, at most (the window's half side over the 5x5
#: median's residual, grown by the 5x5 dilation of the background's edges: 9), with a margin.
_READS = 12


def shadow_left(luma_f: np.ndarray, luma_b: np.ndarray, sample: np.ndarray, bright_noise: float,
                factor: float, where: np.ndarray, min_ratio: float, prior: np.ndarray,
                surroundings: np.ndarray, kept: Callable[[], np.ndarray] | None = None) -> np.ndarray:
    """(h, w) bool: the pixels of ``where`` ((h, w) bool: brighter than the background) where the
    frame (``luma_f``, (h, w) float32) may be brighter than the background (``luma_b``, (h, w) float32,
    already at the frame's exposure) only because a shadow in the background frame has moved away: not
    brighter than the lit bed (the upper quartile of either image's certain bed, ``sample`` flat
    indices, plus ``factor`` x ``bright_noise``), brighter by at most 1 / ``min_ratio`` (the least light a
    shadow leaves), not a thin line, and, where the background has a grain
    above the noise, correlating with it (on the residual of a 5x5 median, which keeps edges). Within
    ``prior`` ((h, w) bool, where the part is expected: a lit face of a part in the bed's colour is brighter
    than the bed too) only the correlation with the bed's grain tells the bed, never its absence. A head's
    or gantry's shadow is large: a region that passes is kept only where a quarter of it lies outside
    ``surroundings`` ((h, w) bool, the part's surroundings), so a reflection or a skirt next to the part
    never passes for one; nor where half of it is ``kept`` (a function giving an (h, w) bool mask, called only where
    a region fails that test: bed this camera read so at its previous check, unchanged in the frame since): a shadow
    that left the bed beside a growing part lies ever more inside the part's surroundings, which grow with it, while
    nothing there changed. The work is done on the box around the pixels that may have been in a shadow only (on
    many scenes the part's own lit faces: about 2-3 ms per camera-check, see docs/detection-shadows.md)."""
    out = np.zeros(luma_f.shape, bool)
    if sample.size < 50 or not where.any():
        return out
    # the lit bed: its upper quartile (most of the certain bed is lit in one of the two images; a higher
    # percentile would reach the glass's glare or a bright backdrop, which a white part can match)
    lit = max(float(np.percentile(luma_b.ravel()[sample], 75)), float(np.percentile(luma_f.ravel()[sample], 75)))
    # ... and brighter by at most the factor a shadow can take away (it keeps ``min_ratio`` of the light):
    # a lit part in front of a dark backdrop is brighter than that
    # (tested on the pixels of ``where`` only, usually a small share of the crop)
    index = np.flatnonzero(where)
    f_at, b_at = luma_f.ravel()[index], luma_b.ravel()[index]
    candidate = np.zeros(where.shape, bool)
    candidate.ravel()[index] = (f_at <= lit + factor * bright_noise) & (f_at <= b_at / min_ratio + factor * bright_noise)
    # the rest reads at most _READS px around a candidate, so the box around them gives the same answer
    box = bounding_box(candidate, pad=_READS)
    if box is None:
        return out
    y0, y1, x0, x1 = box
    inner = (slice(y0, y1), slice(x0, x1))
    wanted = candidate[inner]
    passed = np.zeros(wanted.shape, bool)
    # ... and, where the candidates lie in separate groups (often both sides of the part), the box around
    # each group (its pixels are _READS px inside it or at the crop's edge) gives the same answer again
    for (b0, b1, a0, a1), own in _candidate_groups(wanted):
        box_in = (slice(b0, b1), slice(a0, a1))
        fy, fx = slice(y0 + b0, y0 + b1), slice(x0 + a0, x0 + a1)
        passed[box_in] |= own & _shading_only(luma_f[fy, fx], luma_b[fy, fx], bright_noise, factor,
                                              prior[fy, fx], own)
    # (regions are grouped across gaps of a few pixels: grain and noise break a shadow's area up)
    grouped = cv2.dilate(passed.astype(np.uint8), np.ones((7, 7), np.uint8))
    count, labels = cv2.connectedComponents(grouped, connectivity=8)
    if count > 1:
        area = np.bincount(labels[passed], minlength=count)
        near = np.bincount(labels[passed & surroundings[inner]], minlength=count)
        large = near <= 0.75 * area
        if kept is not None and not large[1:].all():
            large |= np.bincount(labels[passed & kept()[inner]], minlength=count) >= 0.5 * area
        large[0] = False
        passed &= large[labels]
    out[inner] = passed
    return out


#: Grouping the candidates costs a few passes over their box; a separate box per group is worth it only
#: where it saves at least this many pixels (each box costs a fixed overhead of calls too).
_BOX_OVERHEAD_PX = 4000
#: At most this many separate boxes (the rest: one box around several groups).
_MAX_BOXES = 8


def _candidate_groups(wanted: np.ndarray) -> list[tuple[tuple[int, int, int, int], np.ndarray]]:
    """The candidates ``wanted`` ((h, w) bool, padded by _READS around its candidates, or at the image's
    edge) split into groups by empty bands of rows or columns wider than two reads, each with its box
    (the group's bounding box padded by _READS, clipped to ``wanted``: every pixel its candidates read):
    [((y0, y1, x0, x1), own (y1-y0, x1-x0) bool: the group's candidates in its box)]. One group, or no
    saving worth a box's fixed cost: the whole of ``wanted``."""
    h, w = wanted.shape
    leaves = []

    def split(y0, y1, x0, x1, axis_first):
        piece = wanted[y0:y1, x0:x1]
        for axis in (axis_first, 1 - axis_first):
            filled = np.flatnonzero(piece.any(axis=1 - axis))  # rows (axis 0) or columns (axis 1) with candidates
            cuts = np.flatnonzero(np.diff(filled) > 2 * _READS + 1)
            if cuts.size:
                starts = np.concatenate([filled[:1], filled[cuts + 1]])
                ends = np.concatenate([filled[cuts], filled[-1:]]) + 1
                for a, b in zip(starts.tolist(), ends.tolist()):
                    if axis == 0:
                        sub = wanted[y0 + a:y0 + b, x0:x1]
                        cols = np.flatnonzero(sub.any(axis=0))
                        split(y0 + a, y0 + b, x0 + int(cols[0]), x0 + int(cols[-1]) + 1, 1)
                    else:
                        sub = wanted[y0:y1, x0 + a:x0 + b]
                        rows = np.flatnonzero(sub.any(axis=1))
                        split(y0 + int(rows[0]), y0 + int(rows[-1]) + 1, x0 + a, x0 + b, 0)
                return
        leaves.append((y0, y1, x0, x1))

    rows, cols = np.flatnonzero(wanted.any(axis=1)), np.flatnonzero(wanted.any(axis=0))
    if rows.size == 0:
        return [((0, h, 0, w), wanted)]
    split(int(rows[0]), int(rows[-1]) + 1, int(cols[0]), int(cols[-1]) + 1, 1)
    boxes = [(max(0, y0 - _READS), min(h, y1 + _READS), max(0, x0 - _READS), min(w, x1 + _READS))
             for y0, y1, x0, x1 in leaves]
    if len(boxes) == 1 or len(boxes) > _MAX_BOXES \
            or sum((b[1] - b[0]) * (b[3] - b[2]) + _BOX_OVERHEAD_PX for b in boxes) >= h * w:
        return [((0, h, 0, w), wanted)]
    out = []
    for (y0, y1, x0, x1), (ly0, ly1, lx0, lx1) in zip(boxes, leaves):
        own = np.zeros((y1 - y0, x1 - x0), bool)
        own[ly0 - y0:ly1 - y0, lx0 - x0:lx1 - x0] = wanted[ly0:ly1, lx0:lx1]
        out.append(((y0, y1, x0, x1), own))
    return out


def _shading_only(luma_f: np.ndarray, luma_b: np.ndarray, bright_noise: float, factor: float,
                  prior: np.ndarray, wanted: np.ndarray | None = None) -> np.ndarray:
    """(h, w) bool: where a brightening keeps the bed's pattern and is no thin line, see :func:`shadow_left`.
    ``wanted`` ((h, w) bool or None: everywhere): the pixels whose answer is read; elsewhere a textured
    pixel's correlation may be left unmeasured (then it reads as not the same grain)."""
    # the bed's grain, without edges: a 5x5 median keeps a shadow's edge (in the background, not in the
    # frame, once the shadow left) and removes the grain, so the residual holds the grain alone
    smooth_b = cv2.medianBlur(luma_b, 5)
    grain_f = luma_f - cv2.medianBlur(luma_f, 5)
    grain_b = luma_b - smooth_b
    win = (TEXTURE_WINDOW, TEXTURE_WINDOW)
    mean_f, mean_b = cv2.blur(grain_f, win), cv2.blur(grain_b, win)
    var_f = np.maximum(cv2.blur(grain_f * grain_f, win) - mean_f * mean_f, 0.0)
    var_b = np.maximum(cv2.blur(grain_b * grain_b, win) - mean_b * mean_b, 0.0)
    textured = var_b > (TEXTURE_MIN_Z * bright_noise) ** 2
    # ... but not along an edge of the background itself (the border of the shadow that left): the median
    # only approximates a sharp or stepped edge, and what it leaves there is no grain
    gx = cv2.Sobel(smooth_b, cv2.CV_32F, 1, 0, ksize=3)
    gy = cv2.Sobel(smooth_b, cv2.CV_32F, 0, 1, ksize=3)
    edge_b = (np.abs(gx) + np.abs(gy)) * 0.25 > factor * bright_noise + 2.0 * np.sqrt(var_b)
    textured &= ~cv2.dilate(edge_b.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    correlation = np.full(luma_f.shape, -1.0, np.float32)
    asked = bounding_box(textured if wanted is None else textured & wanted, pad=_CORRELATION_REACH)
    if asked is not None:
        # the best of the nine 1-px shifts: a shaken camera moves the grain, the light does not change it
        # (only around the pixels that ask: a pixel's correlation reads _CORRELATION_REACH px around it, so
        # it is the same on that box as on the whole crop, and the box is often far smaller)
        y0, y1, x0, x1 = asked
        inner = (slice(y0, y1), slice(x0, x1))
        h, w = y1 - y0, x1 - x0
        padded = [cv2.copyMakeBorder(a, 1, 1, 1, 1, cv2.BORDER_REPLICATE)[y0:y1 + 2, x0:x1 + 2]
                  for a in (grain_b, mean_b, var_b)]
        g_f, m_f, v_f = grain_f[inner], mean_f[inner], var_f[inner]
        best = correlation[inner]
        for dy in (0, 1, 2):
            for dx in (0, 1, 2):
                g_b, m_b, v_b = (a[dy:dy + h, dx:dx + w] for a in padded)
                cov = cv2.blur(g_f * g_b, win) - m_f * m_b
                np.maximum(best, cov / np.sqrt(np.maximum(v_f * v_b, 1e-6)), out=best)
    # a strand (thin, darker or brighter than both its sides) is no shadow's edge, which is a step the
    # median keeps; nor is it the bed's grain, brightened with the bed
    light_back = np.maximum(cv2.blur(luma_f, win) / np.maximum(cv2.blur(luma_b, win), 1.0), 1.0)
    thin = np.abs(grain_f) > factor * bright_noise + 3.0 * light_back * np.sqrt(var_b)
    thin = cv2.dilate(thin.astype(np.uint8), np.ones((3, 3), np.uint8)).astype(bool)
    same_grain = textured & (correlation >= MIN_CORRELATION)
    return ~thin & np.where(prior, same_grain, same_grain | ~textured)


def shade_of_clipped_bed(frame: np.ndarray, background: np.ndarray, clipped: np.ndarray, tolerance: float,
                         where: np.ndarray) -> np.ndarray:
    """(h, w) bool: the pixels of ``where`` whose colour change is a shadow on a bed with a saturated
    channel. A shadow scales every channel by one factor, but where a channel of the background frame is
    clipped (``clipped`` (h, w, 3) bool) its true value is unknown (at least what was stored), so the
    chromaticity seems to change. Here the factor is fitted on the unclipped channels, which must follow it
    within ``tolerance`` grey levels, and a clipped channel must be at least the factor times its stored
    value. ``frame`` (h, w, 3) float32 or uint8, ``background`` (h, w, 3) float32, the background at the frame's
    exposure."""
    out = np.zeros(where.shape, bool)
    if not clipped.any():   # (most beds: no channel clipped anywhere)
        return out
    # (per pixel of ``where`` only: reducing the whole (h, w, 3) mask costs more than the rest)
    index = np.flatnonzero(where)
    c = clipped.reshape(-1, 3)[index]
    partly = c.any(axis=1) & ~c.all(axis=1)
    if not partly.any():
        return out
    index, c = index[partly], c[partly]
    f, b = frame.reshape(-1, 3)[index].astype(np.float32, copy=False), background.reshape(-1, 3)[index]
    free = ~c
    k = (f * b * free).sum(axis=1) / np.maximum((b * b * free).sum(axis=1), 1.0)
    predicted = k[:, None] * b
    fits = np.where(free, np.abs(f - predicted) <= tolerance, f >= predicted - tolerance).all(axis=1)
    out.ravel()[index] = fits & (k < 1.0)
    return out
