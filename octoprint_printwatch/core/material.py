"""Background removal: which pixels of a frame are printed material, which are certainly the empty bed.

Stage 1 of the shape check (core/shape_check.py), also used by the stereo size check. The background
frame (the empty bed) is brought to the frame's exposure with per-channel gains measured on pixels that
are certainly bed (far from the expected part), then four cues are compared, each tolerant of a 1-px
camera shake (the frame pixel is compared with the range of the background's 3x3 neighbourhood):
chromaticity (colour with the shading divided out, so shadows do not count), brightening, darkening and
new texture (the last two trusted only where the part is expected: outside it they are mostly shadows).
Each cue is divided by its own noise level measured on the certain-bed pixels, so thresholds are in
units of this camera's noise, not grey levels tuned to one scene. The part's colours (:func:`part_palette`)
then tell its material from a shadow or a change of light (:func:`coverage_by_part`,
:func:`not_the_part_colour`, :func:`detectable_fraction`, :func:`differs_as_a_group`).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from typing import Callable

import cv2
import numpy as np

from .masks import bounding_box, disk
from .shadows import shade_of_clipped_bed, shadow_left

#: Shadows keep at least this fraction of the bed's brightness; darker than that is material anywhere.
SHADOW_MIN_RATIO = 0.35
#: Noise floors (grey levels / chromaticity units) so a perfectly clean synthetic image still has a scale.
_NOISE_FLOOR = {"chroma": 2.0, "bright": 3.0, "dark": 3.0, "texture": 3.0}
#: A bed pixel whose colour moved this far (grey levels, after exposure normalisation) is not the
#: background any more: used to tell a moved camera / changed scene from a failed print.
_CHANGED_LEVELS = 25.0
_KERNEL3 = np.ones((3, 3), np.uint8)
_KERNEL5 = np.ones((5, 5), np.uint8)


@dataclass
class Evidence:
    """Per-pixel result of background removal on a crop.

    material : (h, w) bool, something that is not the empty bed (strong cues, or weak cues inside the prior).
    strong : (h, w) bool, material by the cues shadows cannot cause (colour, brightening, deeper than a shadow);
        only these count as extra material.
    bed : (h, w) bool, confidently the empty bed (every cue within the noise).
    score : (h, w) float32, the strongest cue in noise units (for pictures and debugging).
    noise : per-cue noise scales measured on certain-bed pixels.
    gains : (3,) per-channel exposure gains applied to the background.
    changed_bed_fraction : fraction of certain-bed pixels with strong cues (camera moved / lights changed when high).
    """

    material: np.ndarray
    strong: np.ndarray
    bed: np.ndarray
    score: np.ndarray
    noise: dict
    gains: np.ndarray
    changed_bed_fraction: float
    background_norm: np.ndarray | None = None   # (h, w, 3) float32, the background at the frame's exposure
    frame_gradient: np.ndarray | None = None   # (h, w) float32, the frame's luma gradient (:func:`_gradient`)
    new_edges: np.ndarray | None = None   # (h, w) float32, edges the background has not, in units of their bed noise
    relit: bool = False   # read against a background relit by the bed's smooth change of light (bed_light_change)
    #: (h, w) bool: the bed read brightened only because a shadow in the background frame has moved away
    #: (shadows.shadow_left); None where nothing brightened
    shadow_left: np.ndarray | None = None


def _luma_chroma(image: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(h, w, 3) float32 or uint8 BGR -> luma (h, w) and two shading-invariant chromaticity channels (h, w),
    all float32.

    Chromaticity is an opponent colour divided by brightness (plus a constant that keeps
    the noise of dark pixels from being amplified), scaled to roughly grey-level units.
    """
    # (an image's channels split into contiguous planes first: numpy reads a channel of interleaved pixels at a third
    # of the speed, and the values are the same)
    split = image.ndim == 3 and image.shape[2] == 3 and image.dtype in (np.uint8, np.float32)
    b, g, r = cv2.split(image) if split else (image[..., 0], image[..., 1], image[..., 2])
    # float32 operations on the channels as they are read: a uint8 frame needs no float copy of the whole image
    luma = np.add(b, g, dtype=np.float32)
    np.add(luma, r, out=luma, dtype=np.float32)
    luma *= 1.0 / 3.0
    denom = luma + 6.0
    c1 = np.subtract(r, g, dtype=np.float32)
    c1 *= 100.0 / denom
    c2 = np.add(r, g, dtype=np.float32)
    c2 -= np.multiply(b, 2.0, dtype=np.float32)
    c2 *= 50.0 / denom
    return luma, c1, c2


def _scaled(image: np.ndarray, gains: np.ndarray) -> np.ndarray:
    """``np.multiply(image, gains, dtype=np.float32)`` for an (h, w, 3) image and (3,) gains: for a uint8 image,
    each channel's 256 possible products looked up (the same float32 products, a quarter of the time)."""
    if image.dtype != np.uint8 or image.ndim != 3 or image.shape[2] != 3:
        return np.multiply(image, gains, dtype=np.float32)
    table = np.multiply(np.arange(256, dtype=np.float32)[:, None], gains[None, :], dtype=np.float32)
    return cv2.LUT(image, table.reshape(1, 256, 3))


#: bed_light_change reads the change of light on a grid of this many cells across the crop's longer side (fine
#: enough to follow a reflection's soft edge, coarse enough for a strand or a shadow to cover few of a cell's
#: pixels) from cells holding at least LIGHT_CELL_MIN_PIXELS certain-bed pixels
LIGHT_GRID_CELLS = 16
LIGHT_CELL_MIN_PIXELS = 12
#: ... and the relit background is kept only where no more than this share of the bed still looks changed: a
#: reflection relit leaves a few % (median 3 % on eight cross-check seeds); a camera knocked by a strip's width over a
#: bed of tape strips 20-80 px wide leaves 42-100 %. (Knocked by half a broad strip it can leave 8 %: such a view is
#: relit, and a relit view never pauses a print alone, verdict.decide.)
RELIT_MAX_CHANGED = 0.10


def bed_light_change(bg: np.ndarray, frame: np.ndarray, sample: np.ndarray) -> np.ndarray | None:
    """The smooth change of light on the bed between the background ``bg`` ((h, w, 3) float32, at the frame's
    exposure) and ``frame`` ((h, w, 3) uint8), as an (h, w, 3) float32 offset to add to ``bg``, or None (too few
    sampled pixels). ``sample``: flat indices of certain-bed pixels. Each grid cell's offset is the median of its
    sampled pixels' differences (strands or a shadow over a few of them do not move it), cells without enough of
    them take their neighbours', and the grid is interpolated over the crop. A reflection adds light without
    changing the bed's grain, so the offset is added, not multiplied."""
    h, w = frame.shape[:2]
    if sample.size < LIGHT_CELL_MIN_PIXELS * 4:
        return None
    cell = max(8, int(np.ceil(max(h, w) / LIGHT_GRID_CELLS)))
    gh, gw = -(-h // cell), -(-w // cell)
    rows, cols = np.divmod(sample, w)
    difference = frame[rows, cols].astype(np.float32) - bg[rows, cols]
    cell_of = (rows // cell) * gw + cols // cell
    grid = np.zeros((gh * gw, 3), np.float32)
    known = np.zeros(gh * gw, np.float32)
    order = np.argsort(cell_of, kind="stable")
    cells, starts = np.unique(cell_of[order], return_index=True)
    for c, part in zip(cells, np.split(order, starts[1:])):
        if part.size >= LIGHT_CELL_MIN_PIXELS:
            grid[c] = np.median(difference[part], axis=0)
            known[c] = 1.0
    if not known.any():
        return None
    grid, known = grid.reshape(gh, gw, 3), known.reshape(gh, gw)
    # cells without bed (under the part) take a weighted mean of their known neighbours, spreading until filled
    filled = grid * known[..., None]
    weight = known.copy()
    while (weight == 0).any():
        spread = cv2.blur(filled, (3, 3), borderType=cv2.BORDER_REPLICATE)
        spread_weight = cv2.blur(weight, (3, 3), borderType=cv2.BORDER_REPLICATE)
        empty = weight == 0
        reached = empty & (spread_weight > 0)
        filled[reached] = spread[reached] / spread_weight[reached][:, None]
        weight[reached] = 1.0
    return cv2.resize(filled, (w, h), interpolation=cv2.INTER_LINEAR)


def _outside_range(value: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """How far ``value`` lies outside [low, high], per pixel (0 inside)."""
    out = low - value
    np.maximum(out, value - high, out=out)
    return np.maximum(out, 0.0, out=out)


def _noise_scale(score: np.ndarray, sample: np.ndarray, floor: float) -> float:
    """Robust noise level of a non-negative cue on certain-bed pixels (``sample``: flat indices):
    its 90th percentile, so a few changed pixels (strings, a skirt) cannot dominate."""
    values = score.ravel()[sample]
    if values.size < 50:
        return floor
    return max(floor, float(np.percentile(values, 90)))


# --------------------------------------------------- stage 1: background removal
def material_evidence(
    background: np.ndarray,
    frame: np.ndarray,
    prior: np.ndarray,
    bed_sample: np.ndarray,
    *,
    material_factor: float = 5.0,
    bed_factor: float = 2.5,
    previous: np.ndarray | None = None,
    part: np.ndarray | None = None,
    palette: np.ndarray | None = None,
    relight_above: float | None = None,
    left_before: tuple[np.ndarray, np.ndarray] | None = None,
) -> Evidence:
    """Background removal on one crop.

    Parameters
    ----------
    background, frame : (h, w, 3) uint8 BGR, same size.
    prior : (h, w) bool where the part may be (expected silhouette grown by the alignment bound);
        darkening and new texture count as material only here (elsewhere they are mostly shadows).
    bed_sample : (h, w) bool pixels that are certainly empty bed (exposure gains and noise levels).
    material_factor, bed_factor : thresholds in noise units for "material" and "confidently bed".
    previous : (h, w) bool, the previous check's material mask: inside it (and the prior) weaker evidence
        suffices, as the seed reused its ``prev`` mask; a part that left it shows bed and is not kept.
    part : (h, w) bool or None, the expected silhouette (grown by the outline tolerance): a lit face of a
        part in the bed's colour looks like the bed brightened, so there only the bed's own grain tells a
        shadow that left (core/shadows.py); None: the whole prior.
    palette : (k, 3) the part's colours seen at earlier checks (:func:`part_palette`), or None: sampled pixels
        that took the part's colour (:func:`took_the_part_colour`: a part fallen onto the bed, its strands)
        are material, not the bed's noise, and are left out of the noise levels.
    relight_above : where more of the empty bed than this share looks changed after the exposure gains
        (``changed_bed_fraction``), the light on the bed changed unevenly (a lamp's reflection that swept
        across a glossy bed, a lamp that moved): the bed's smooth change of light (:func:`bed_light_change`)
        is added to the background and the evidence read again, kept (``relit``) where the bed then matches
        (RELIT_MAX_CHANGED); None: never.
    left_before : (the previous check's frame (h, w, 3) uint8, the bed it read as a shadow that left (h, w) bool), the
        same crop, or None: that bed, unchanged in the frame since, is still such bed (see unchanged_since).
    """
    sample_mask = bed_sample if int(np.count_nonzero(bed_sample)) >= 50 else ~prior
    sample = np.flatnonzero(sample_mask)
    if sample.size > 6000:  # statistics need a few thousand pixels, not all of them
        sample = sample[:: sample.size // 6000 + 1]
    # exposure / white balance: per-channel gain, median ratio on certain-bed pixels
    gains = np.ones(3, np.float32)
    if sample.size:
        # (the sampled pixels only: a float copy of the whole frame is not needed, and the background's is
        # made once, already scaled)
        rows, cols = np.divmod(sample, background.shape[1])
        gains = exposure_gains(background[rows, cols].astype(np.float32), frame[rows, cols].astype(np.float32))
    kept = _left_and_unchanged(left_before, frame, sample, material_factor)
    args = (background, frame, prior, sample, material_factor, bed_factor, previous, part, palette, gains, kept)
    bg = _scaled(background, gains)
    evidence = _evidence_against(bg, *args)
    if relight_above is None or evidence.changed_bed_fraction <= relight_above:
        return evidence
    light = bed_light_change(bg, frame, np.flatnonzero(sample_mask))
    if light is None:
        return evidence
    relit = _evidence_against(bg + light, *args)
    if relit.changed_bed_fraction > min(relight_above, RELIT_MAX_CHANGED):
        return evidence
    relit.relit = True
    return relit


def _evidence_against(bg: np.ndarray, background: np.ndarray, frame: np.ndarray, prior: np.ndarray,
                      sample: np.ndarray, material_factor: float, bed_factor: float, previous: np.ndarray | None,
                      part: np.ndarray | None, palette: np.ndarray | None, gains: np.ndarray,
                      kept: Callable[[], np.ndarray] | None = None) -> Evidence:
    """material_evidence's cues read against ``bg``, the background as the frame's light should show it
    ((h, w, 3) float32); ``sample``: the flat indices of the certain-bed pixels it reads the noise on."""
    fr = np.ascontiguousarray(frame)

    luma_f, c1_f, c2_f = _luma_chroma(fr)
    luma_b, c1_b, c2_b = _luma_chroma(bg)
    # 3x3 neighbourhood ranges of the background: a 1-px shake between background and frame is not a change
    lo_l, hi_l = cv2.erode(luma_b, _KERNEL3), cv2.dilate(luma_b, _KERNEL3)
    # the chromaticity change, brought back to grey levels at the frame's brightness so its noise
    # does not grow in dark pixels (where JPEG's coarse chroma would otherwise look like a colour change)
    chroma = _hypot(_outside_range(c1_f, cv2.erode(c1_b, _KERNEL3), cv2.dilate(c1_b, _KERNEL3)),
                    _outside_range(c2_f, cv2.erode(c2_b, _KERNEL3), cv2.dilate(c2_b, _KERNEL3)))
    chroma *= (luma_f + 6.0) * 0.01
    bright = luma_f - hi_l
    np.maximum(bright, 0.0, out=bright)
    dark = lo_l - luma_f
    np.maximum(dark, 0.0, out=dark)
    grad_f = _gradient(luma_f)
    texture = cv2.dilate(_gradient(luma_b), _KERNEL3)
    texture *= 1.5
    np.subtract(grad_f, texture, out=texture)
    np.maximum(texture, 0.0, out=texture)

    cues = {"chroma": chroma, "bright": bright, "dark": dark, "texture": texture}
    # the noise levels are the empty bed's: a part that fell onto the sampled bed (a white cylinder tipped over
    # 18 % of it made the 90th percentile the part's own change, chromaticity 171 where 3 is normal, and nothing
    # counted as material) is left out; a change of light keeps the bed's colour and stays in
    noise_sample = sample
    if palette is not None and sample.size:
        rows, cols = np.divmod(sample, background.shape[1])
        took = took_the_part_colour(cv2.blur(fr, (5, 5))[rows, cols], cv2.blur(bg, (5, 5))[rows, cols], palette)
        if sample.size - int(np.count_nonzero(took)) >= 50:
            noise_sample = sample[~took]
    noise = {name: _noise_scale(cue, noise_sample, _NOISE_FLOOR[name]) for name, cue in cues.items()}
    z = {name: cue * (1.0 / noise[name]) for name, cue in cues.items()}
    # darker than any plausible shadow is material anywhere
    # (on the 5x5 mean: sensor noise in a shadow on a dark bed pushes single pixels under the ratio,
    # and closing would join them into blobs; real dark material is dark over an area)
    deep_dark = (cv2.blur(luma_f, (5, 5)) < SHADOW_MIN_RATIO * lo_l) & (z["dark"] > material_factor)
    # ... but with one strong light and little ambient light a shadow can be darker still: away from the
    # part, deep dark counts only where it also brings new edges (strands, a part's outline); a shadow
    # darkens the bed smoothly
    edges = cv2.dilate((z["texture"] > material_factor).astype(np.uint8), _KERNEL5).astype(bool)
    deep_dark &= prior | edges
    # a shadow on a bed with a saturated channel seems to change its colour (the clipped channel's true
    # value is unknown): ratio constancy on the other channels tells it (core/shadows.py)
    # (np.where's value, set by a masked store on a copy: most pixels keep theirs)
    chroma_strong = _zero_where(z["chroma"], shade_of_clipped_bed(fr, bg, background >= 250,
                                                                  material_factor * noise["chroma"],
                                                                  where=z["chroma"] > material_factor))
    # a shadow of the parked head or gantry that lay here in the background frame and has moved away
    # brightens the bed without changing its colour or pattern (core/shadows.py): a weak cue there, like
    # darkening
    # ... on the part only a grain match tells the bed from a lit face in the bed's colour; a part whose
    # colour differs from the bed's (its pixels at the previous check changed chromaticity) has no such face
    grain_needed = prior if part is None else part
    if previous is not None:
        seen = previous & prior
        if int(np.count_nonzero(seen)) >= 50 and float(np.median(z["chroma"][seen])) > material_factor:
            grain_needed = np.zeros_like(prior)
    left = shadow_left(luma_f, luma_b, sample, noise["bright"], material_factor,
                       where=(z["bright"] > material_factor) & (chroma_strong <= material_factor),
                       min_ratio=SHADOW_MIN_RATIO, prior=grain_needed, surroundings=prior, kept=kept)
    bright_strong = _zero_where(z["bright"], left)
    strong = np.maximum(chroma_strong, bright_strong)
    # (a shadow that left, where the bed's grain shows through, is the bed even inside the prior: a part
    # there would hide the grain; counting it kept a stalled part's missing top "seen" under the head's
    # old shadow)
    weak = np.maximum(np.maximum(z["dark"], z["texture"]), np.maximum(bright_strong, z["chroma"]))
    strong_material = (strong > material_factor) | deep_dark
    material = strong_material | ((weak > material_factor) & prior)
    if previous is not None:
        hint = previous & prior
        material |= hint & (np.maximum(strong, weak) > bed_factor)
    score = np.maximum(strong, weak)
    bed = score < bed_factor
    # absolute (not noise-relative) test: when the whole scene changed, the noise levels change with it
    # (read on the sampled pixels only)
    changed_px = ((chroma.ravel()[sample] > 0.6 * _CHANGED_LEVELS) | (bright.ravel()[sample] > _CHANGED_LEVELS)
                  | (dark.ravel()[sample] > _CHANGED_LEVELS))
    changed = float(np.mean(changed_px)) if sample.size else 0.0
    return Evidence(material=material, strong=strong_material, bed=bed, score=score, noise=noise, gains=gains,
                    background_norm=bg, frame_gradient=grad_f, new_edges=z["texture"],
                    changed_bed_fraction=changed, shadow_left=left if left.any() else None)


#: A pixel took the part's colour where its chromaticity moved from the bed's to within this share of the
#: distance between the bed's and a part colour's (the rest is left to blur, JPEG and shading) ...
PART_COLOUR_REACHED_SHARE = 0.3


def took_the_part_colour(frame: np.ndarray, background: np.ndarray, palette: np.ndarray) -> np.ndarray:
    """(n,) bool: the pixels whose colour in ``frame`` ((n, 3) BGR) is one of the part's (``palette``, (k, 3))
    where ``background`` ((n, 3), at the frame's exposure) had another: the part's material now covers them.

    Chromaticity only (a face of the part in another light keeps its colour), distances in grey levels at the
    part colour's brightness: the bed's colour must lie a clear colour change (0.6 x _CHANGED_LEVELS) from the
    part colour, and the frame's within PART_COLOUR_REACHED_SHARE of that distance from it. A change of light
    (a glare or shadow that came or went, a reflection that moved) keeps the bed's colour, or moves it towards
    the light's; a dark pixel's noisy chromaticity is not read at its own brightness. Blur both images first:
    single noisy pixels of a dark bed take any colour."""
    out = np.zeros(len(frame), bool)
    if len(frame) == 0 or palette is None or len(palette) == 0:
        return out
    _, c1_f, c2_f = _luma_chroma(np.asarray(frame, np.float32))
    _, c1_b, c2_b = _luma_chroma(np.asarray(background, np.float32))
    luma_p, c1_p, c2_p = _luma_chroma(np.asarray(palette, np.float32))
    for lp, a, b in zip(luma_p, c1_p, c2_p):
        scale = (float(lp) + 6.0) * 0.01
        to_bed = np.hypot(c1_b - a, c2_b - b) * scale
        to_frame = np.hypot(c1_f - a, c2_f - b) * scale
        out |= (to_bed > 0.6 * _CHANGED_LEVELS) & (to_frame < PART_COLOUR_REACHED_SHARE * to_bed)
    return out


def _gradient(luma: np.ndarray) -> np.ndarray:
    gx = np.abs(cv2.Sobel(luma, cv2.CV_32F, 1, 0, ksize=3))
    gx += np.abs(cv2.Sobel(luma, cv2.CV_32F, 0, 1, ksize=3))
    out = cv2.blur(gx, (3, 3))
    out *= 0.25
    return out


def _left_and_unchanged(left_before: tuple[np.ndarray, np.ndarray] | None, frame: np.ndarray, sample: np.ndarray,
                        factor: float) -> Callable[[], np.ndarray] | None:
    """shadows.shadow_left's ``kept``: the bed ``left_before`` read as a shadow that left (material_evidence), where
    ``frame`` is unchanged since (:func:`unchanged_since`), worked out at its first use only: shadow_left asks only
    where a region fails its size test."""
    if left_before is None or not left_before[1].any():
        return None
    then, left_then = left_before
    return cache(lambda: unchanged_since(then, frame, sample, factor, left_then))


def exposure_gains(reference: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """(3,) float32 per-channel gains that bring ``reference`` to ``frame``'s exposure and white balance: the median
    ratio over pixels known to be bed ((n, 3) float32 each, the same pixels), those with a channel under 8 grey levels
    left out (their ratio is noise), clipped to 0.2-5; ones where fewer than 50 pixels are left."""
    ok = reference.min(axis=1) > 8.0
    if np.count_nonzero(ok) < 50:
        return np.ones(3, np.float32)
    return np.clip(np.median(frame[ok] / reference[ok], axis=0), 0.2, 5.0).astype(np.float32)


def unchanged_since(before: np.ndarray, frame: np.ndarray, sample: np.ndarray, factor: float,
                    where: np.ndarray) -> np.ndarray:
    """(h, w) bool: the pixels of ``where`` ((h, w) bool) at which ``frame`` looks as ``before`` did (both (h, w, 3)
    uint8, the same crop of one camera's frames at two checks): in no channel, ``before`` brought to this frame's
    exposure by per-channel median ratios on the certain bed (``sample``, flat indices), do they differ by more than
    ``factor`` times the certain bed's own such difference (its 90th percentile, at least one grey level). Read on
    the box around ``where`` only."""
    out = np.zeros(frame.shape[:2], bool)
    box = bounding_box(where)
    if sample.size < 50 or box is None:
        return out
    rows, cols = np.divmod(sample, frame.shape[1])
    now_s, then_s = frame[rows, cols].astype(np.float32), before[rows, cols].astype(np.float32)
    gains = exposure_gains(then_s, now_s)
    noise = max(float(np.percentile(np.abs(now_s - then_s * gains).max(axis=1), 90)), 1.0)
    y0, y1, x0, x1 = box
    inner = (slice(y0, y1), slice(x0, x1))
    difference = np.abs(frame[inner].astype(np.float32) - before[inner].astype(np.float32) * gains).max(axis=2)
    out[inner] = where[inner] & (difference <= factor * noise)
    return out


def _zero_where(value: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """``np.where(mask, 0.0, value)`` for a float32 ``value``: a copy of it with the pixels of ``mask`` set to
    0 (a masked store touches only those, usually few)."""
    out = value.copy()
    out[mask] = 0.0
    return out


def _hypot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """np.hypot of two non-negative (h, w) float32 arrays, computed only where both are non-zero (where
    one is zero it is exactly the other: the chromaticity change is zero on most pixels)."""
    out = np.maximum(x, y)
    both = np.flatnonzero((x > 0.0) & (y > 0.0))
    if both.size:
        out.ravel()[both] = np.hypot(x.ravel()[both], y.ravel()[both])
    return out


def part_palette(frame: np.ndarray, mask: np.ndarray, groups: int = 5) -> np.ndarray | None:
    """(groups, 3) float32 typical colours of the part: the frame's pixels under ``mask`` sorted by
    brightness and averaged in equal groups (lit faces to shaded ones). None when too few pixels."""
    # (the sampled pixels are gathered alone: the same pixels, in the same order, as frame[mask][::step])
    index = np.flatnonzero(mask)
    if index.size < 50:
        return None
    if index.size > 4000:
        index = index[:: index.size // 4000 + 1]
    rows, cols = np.divmod(index, mask.shape[1])
    pixels = frame[rows, cols].astype(np.float32)
    order = np.argsort(pixels.sum(axis=1))
    return np.stack([chunk.mean(axis=0) for chunk in np.array_split(pixels[order], groups)])


#: An extra blob whose pixels moved, on average, less than this share of the way from the bed towards the
#: part's colours holds none of the part's material: the hotend's shadow, a lighting change. Measured on
#: both simulators: 0.02-0.07 for head shadows; 0.28 or more for detached parts, shifted layers and
#: spaghetti (a strand covering half a pixel reads about 0.5; docs/detection-shadows.md).
PART_COLOUR_MIN_COVERAGE = 0.15


def coverage_by_part(frame: np.ndarray, background: np.ndarray, palette: np.ndarray) -> np.ndarray:
    """(n,) how far each pixel moved from the background towards the part's colour: 0 the background,
    1 the part, about 0.5 where a strand covers half of it. ``frame`` and ``background`` (n, 3), ``palette``
    (k, 3): per pixel, the palette colour whose linear mix ``background + c (colour - background)`` best
    explains the frame (least residual) gives ``c``, clipped to [0, 1.5]. Where the part's colour is
    the background's, any change reads as high coverage (no blob is ever dropped for it)."""
    bg = background.astype(np.float32)
    change = frame.astype(np.float32) - bg                                        # (n, 3)
    colours = np.asarray(palette, np.float32)                                     # (k, 3)
    # with towards = colour - background, per pixel and colour (n, k), expanded so no (n, k, 3) is built
    along = change @ colours.T - (change * bg).sum(axis=1)[:, None]               # change . towards
    length2 = ((colours * colours).sum(axis=1)[None, :] - 2.0 * (bg @ colours.T)
               + (bg * bg).sum(axis=1)[:, None])                                  # |towards|^2
    c = np.clip(along / np.maximum(length2, 1.0), 0.0, 1.5)
    residual2 = (change * change).sum(axis=1)[:, None] - 2.0 * c * along + c * c * length2
    return c[np.arange(len(c)), np.argmin(residual2, axis=1)] if len(c) else np.zeros(0, np.float32)


def not_the_part_colour(extra: np.ndarray, frame: np.ndarray, background: np.ndarray,
                        palette: np.ndarray) -> np.ndarray:
    """(h, w) bool: the blobs of ``extra`` ((h, w) bool) whose mean :func:`coverage_by_part` is under
    PART_COLOUR_MIN_COVERAGE, on ``frame`` (h, w, 3) and ``background`` (h, w, 3, at the frame's exposure)
    with the part's ``palette`` (k, 3)."""
    out = np.zeros(extra.shape, bool)
    ys, xs = np.nonzero(extra)
    if len(ys) == 0:
        return out
    y0, x0 = int(ys.min()), int(xs.min())
    box = (slice(y0, int(ys.max()) + 1), slice(x0, int(xs.max()) + 1))
    count, labels = cv2.connectedComponents(extra[box].astype(np.uint8), connectivity=8)
    # a blob's mean is estimated on up to ~2,000 of the pixels (evenly spread); a blob none of them falls
    # in is never dropped
    step = max(1, len(ys) // 2000)
    ys, xs = ys[::step], xs[::step]
    which = labels[ys - y0, xs - x0]
    coverage = coverage_by_part(frame[ys, xs], background[ys, xs], palette)
    sampled = np.bincount(which, minlength=count)
    mean = np.bincount(which, weights=coverage, minlength=count) / np.maximum(sampled, 1)
    faint = (sampled > 0) & (mean < PART_COLOUR_MIN_COVERAGE)
    faint[0] = False
    out[box] = faint[labels]
    return out


def detectable_fraction(palette: np.ndarray, background: np.ndarray, noise: dict,
                        material_factor: float) -> np.ndarray:
    """(n,) fraction of the palette's colours that background removal would tell apart from each of
    the (n, 3) background colours: a missing part can only be claimed where it would have been seen."""
    pal = palette.astype(np.float32)[None, :, :]          # (1, k, 3)
    bg = background.astype(np.float32)[:, None, :]        # (n, 1, 3)
    luma_p, c1_p, c2_p = _luma_chroma(pal)
    luma_b, c1_b, c2_b = _luma_chroma(bg)
    chroma = np.hypot(c1_p - c1_b, c2_p - c2_b) * (luma_p + 6.0) * 0.01
    z = np.maximum(np.maximum(chroma / noise["chroma"], np.maximum(luma_p - luma_b, 0) / noise["bright"]),
                   np.maximum(luma_b - luma_p, 0) / noise["dark"])
    return (z > material_factor).mean(axis=1)


def differs_as_a_group(frame: np.ndarray, background: np.ndarray, group: np.ndarray, bed_sample: np.ndarray,
                       factor: float, where: np.ndarray | None = None, radius: int = 4) -> np.ndarray:
    """(h, w) bool: pixels of ``where`` (default everywhere) whose neighbourhood (the ``group`` pixels
    within ``radius``), averaged, differs from the background more than a patch of certain bed
    (``bed_sample``) does.

    ``frame`` (h, w, 3) uint8 and ``background`` (h, w, 3) float32 (exposure-normalised). A face of nearly
    the bed's colour (filament in the bed's colour, a top face lit like the bed) passes the per-pixel test
    for "bed" in most pixels, but it is off by the same amount in all of them, while the bed showing
    through is off only by noise: averaging over a patch divides the noise, not the offset. Patches of the
    bed sample give the scale (lighting gradients, grain, JPEG), so the test is in units of this camera's
    patch noise, like every other cue: beyond ``factor`` times the 90th percentile of the bed patches'
    offsets, in luma or in either chromaticity channel.
    """
    h, w = group.shape
    out = np.zeros((h, w), bool)
    box = bounding_box(group if where is None else where, pad=radius)
    if box is None:
        return out
    luma_f, c1_f, c2_f = _luma_chroma(frame.astype(np.float32))
    luma_b, c1_b, c2_b = _luma_chroma(background)
    scale = (luma_f + 6.0) * 0.01
    diff = np.dstack([luma_f - luma_b, (c1_f - c1_b) * scale, (c2_f - c2_b) * scale])   # (h, w, 3)
    # the bed's patch offsets: means over (2 radius + 1)-px blocks lying on certain bed
    side = 2 * radius + 1
    bh, bw = h // side, w // side
    if bh < 1 or bw < 1:
        return out
    bed = bed_sample[: bh * side, : bw * side].astype(np.float32)
    bed_share = cv2.resize(bed, (bw, bh), interpolation=cv2.INTER_AREA)
    bed_sum = cv2.resize(diff[: bh * side, : bw * side] * bed[..., None], (bw, bh), interpolation=cv2.INTER_AREA)
    whole = bed_share > 0.9
    if int(np.count_nonzero(whole)) < 12:
        return out
    patches = bed_sum[whole] / bed_share[whole][:, None]                                  # (n, 3)
    centre = np.median(patches, axis=0)
    spread = np.maximum(np.percentile(np.abs(patches - centre), 90, axis=0), 0.25)
    # the group's own mean around each pixel (normalised convolution: material next to a face must not
    # make the face look different)
    y0, y1, x0, x1 = box
    g = group[y0:y1, x0:x1].astype(np.float32)
    weight = cv2.blur(g, (side, side))
    mean = cv2.blur(diff[y0:y1, x0:x1] * g[..., None], (side, side)) / np.maximum(weight, 1e-3)[..., None]
    off = (np.abs(mean - centre) > factor * spread).any(axis=2) & (weight > 0.25)
    out[y0:y1, x0:x1] = off
    return out if where is None else out & where


def clean_mask(material: np.ndarray, fill_like: np.ndarray | None = None) -> np.ndarray:
    """Morphology: drop specks and 1-2 px strings (opening), bridge small gaps (closing), and fill holes
    that the expected silhouette also fills (a part seen through its own bore keeps the hole)."""
    m = cv2.morphologyEx(material.astype(np.uint8), cv2.MORPH_OPEN, _KERNEL3)
    m = cv2.morphologyEx(m, cv2.MORPH_CLOSE, disk(2))
    if fill_like is not None and m.any():
        return m.astype(bool) | (enclosed(m) & fill_like)
    return m.astype(bool)


def enclosed(mask: np.ndarray) -> np.ndarray:
    """(h, w) bool: the pixels outside ``mask`` ((h, w) bool or uint8) that it closes in (its holes)."""
    h, w = mask.shape
    padded = cv2.copyMakeBorder(mask.astype(np.uint8), 1, 1, 1, 1, cv2.BORDER_CONSTANT, value=0)
    cv2.floodFill(padded, np.zeros((h + 4, w + 4), np.uint8), (0, 0), 1)
    return padded[1:-1, 1:-1] == 0

