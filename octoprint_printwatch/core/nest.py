"""How much of a region the part's own material covers, pixel by pixel (a stopped part's newest band), and
how textured it looks.

A print that failed into spaghetti stops growing while its strands pile up over the top: the outline of
the pile can rise and fill the expected silhouette, but the newest band is then a mesh of 0.4 mm strands
with the bed showing through, or the bed itself. Unmixing each pixel between the background and the
part's colours (:func:`core.material.coverage_by_part`) reads how much of it the part's material
covers: about 1 on a solid face, about 0.5 where a strand covers half a pixel, 0 on the bare bed. The
figure is a physical share, not a level in noise units, so it stays meaningful where the noise estimate
is inflated (a parked hotend that left the background frame's bed sample).

Strands in the part's own colour piled thickly over it cover the band as a solid face would, but not as
smoothly: each strand has its own highlight and shadow. The band's mean luma gradient
(:func:`region_texture`) against the same view's reading at its previous check (:func:`textured_views`) shows
that change, as it shows the bed (its grain, the part's rim) seen where a stopped part's newest layers should be.
"""
from __future__ import annotations

from typing import Mapping

import numpy as np

from .material import coverage_by_part
from .tangle import SLOWED_RISE_PCT

#: A stalled part's newest band covered less than this share by the part's material is a nest or the bed
#: (strands 0.4 mm wide over the bed read about 0.5 where they cover half of it; a solid face reads 0.9-1.0)
NEST_MAX_COVERAGE = 0.5
#: ... in a view whose newest band read at least this covered at an earlier check (a solid part in its colours)
SOLID_MIN_COVERAGE = 0.8

#: A view that saw the part rise at least this much (% of the expected rise) is not stalled: its band's
#: coverage is not read there (verdict.decide's stall rules all need less), so it need not be measured
STALL_READ_BELOW_GROWTH_PCT = 50.0

#: A view whose newest band looks at least this many times as textured (mean luma gradient) as its band at its
#: previous check shows something else there: strands piled over the part (each 0.4 mm strand its own highlight
#: and shadow over a smooth printed face), or the bed where the part should be. Measured (fourteenth session) on
#: nine cross-check seeds and the default set, 7,589 camera-checks before any failure: 1.4 % of views change by
#: 1.5x or more between two checks (a tier's step entering the band, infill), but at the 24 checks whose part
#: rose under half the expected height the largest was 1.15x; where the rule first paused a failed print, 1.5-3.3x.
TEXTURE_JUMP = 1.5
#: ... and a view whose band turned at least this many times as textured counts while the part rose under
#: PART_SLOWED_SOMEWHAT_PCT. A rise of 50-79 % is what a coarse reading (+-25 %) of a stalled top gives as often as
#: a normal one. Measured (seventeenth session) on six cross-check seeds: of 148 camera-checks before any failure that
#: rose 50-79 %, one band's texture changed by 1.7x, the rest by at most 1.41x; after a failure's onset, 2-8x there.
TEXTURE_JUMP_STRONG = 2.0
PART_SLOWED_SOMEWHAT_PCT = 80.0
#: A view's band is compared with the smoothest of its readings at this many checks before (since it was last
#: unusable; never its first look): strands draped over a part first show as texture while the top still rises, and
#: the top slows a check later (thirty-first session, development seeds 20-39: no check before an onset or on a
#: normal print newly paused, 7 first catches a check or two sooner).
TEXTURE_MEMORY_CHECKS = 2
#: Bands smoother than this (grey levels of mean gradient, the texture cue's noise floor in shape_check) count as
#: this smooth: ratios of smaller readings are noise
SMOOTH_TEXTURE = 3.0

#: Pixels sampled (evenly spread) for the region's mean: the mean of a few thousand is as good as all.
MAX_PIXELS = 2000


def part_coverage(frame: np.ndarray, background: np.ndarray, region: np.ndarray,
                  palette: np.ndarray | None) -> float | None:
    """Mean share of ``region``'s pixels covered by the part's material, or None (no palette, no pixels).

    ``frame`` (h, w, 3) and ``background`` (h, w, 3, at the frame's exposure) of one crop, ``region``
    (h, w) bool, ``palette`` (k, 3) the part's colours. Each pixel's coverage is clipped to 1 before
    averaging (a pixel beyond the palette's colour is no more than covered).
    """
    if palette is None:
        return None
    ys, xs = np.nonzero(region)
    if len(ys) == 0:
        return None
    step = max(1, len(ys) // MAX_PIXELS)
    ys, xs = ys[::step], xs[::step]
    coverage = coverage_by_part(frame[ys, xs], background[ys, xs], palette)
    return float(np.mean(np.minimum(coverage, 1.0)))


def region_texture(gradient: np.ndarray | None, region: np.ndarray) -> float | None:
    """Mean of ``gradient`` ((h, w) float, the frame's luma gradient) over ``region`` ((h, w) bool), or None
    (no gradient, no pixels)."""
    if gradient is None or not region.any():
        return None
    return float(np.mean(gradient[region]))


def texture_jump_for(rise_pct: float | None) -> float | None:
    """How many times as textured as at its checks before a view's newest band must look to show strands or the
    bed on a part that rose ``rise_pct`` (% of the expected; None: no reading): :data:`TEXTURE_JUMP` under
    SLOWED_RISE_PCT, :data:`TEXTURE_JUMP_STRONG` under :data:`PART_SLOWED_SOMEWHAT_PCT`, else None (a part
    rising as expected: a changed look is the view's artefact)."""
    if rise_pct is None or rise_pct >= PART_SLOWED_SOMEWHAT_PCT:
        return None
    return TEXTURE_JUMP if rise_pct < SLOWED_RISE_PCT else TEXTURE_JUMP_STRONG


def texture_jump_for_lone_reading(rise_pct: float) -> float | None:
    """As :func:`texture_jump_for`, for the rise read by the only one of several usable views that reads it (no median
    to weigh; the others' tops hidden, often by the strands themselves): :data:`TEXTURE_JUMP_STRONG` under
    SLOWED_RISE_PCT, else None. One step stricter on both counts than a median's: on the twenty-six development seeds
    (thirty-seventh session) no check before an onset or of a normal print has a view 1.5 times as textured with a lone
    reading under 50 % (two do at 1.3 times, eight at 1.5 times under 80 %); replayed with the lone view's rise at its
    previous check required (verdict.lone_rise_reading), ten failures pause a check or more sooner, six of them within
    one check of their onset where they were not, and no other verdict changes."""
    return TEXTURE_JUMP_STRONG if rise_pct < SLOWED_RISE_PCT else None


def textured_views(texture: Mapping[str, float | None], before: Mapping[str, float],
                   jump: float = TEXTURE_JUMP) -> dict[str, float]:
    """The views whose newest band is ``jump`` times as textured as at their checks before, with that ratio:
    ``texture`` and ``before`` map cameras to :attr:`ShapeResult.band_texture` now and the smoothest of their readings
    at the checks before (a camera missing from ``before`` has no such reading: not counted)."""
    ratios = {cam: t / max(before[cam], SMOOTH_TEXTURE) for cam, t in texture.items()
              if t is not None and before.get(cam) is not None}
    return {cam: ratio for cam, ratio in ratios.items() if ratio >= jump}
