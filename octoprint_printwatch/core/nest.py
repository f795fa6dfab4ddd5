"""How much of a region the part's own material covers, pixel by pixel (a stopped part's newest band).

A print that failed into spaghetti stops growing while its strands pile up over the top: the outline of
the pile can rise and fill the expected silhouette, but the newest band is then a mesh of 0.4 mm strands
with the bed showing through, or the bed itself. Unmixing each pixel between the background and the
part's colours (:func:`core.shape_check.coverage_by_part`) reads how much of it the part's material
covers: about 1 on a solid face, about 0.5 where a strand covers half a pixel, 0 on the bare bed. The
figure is a physical share, not a level in noise units, so it stays meaningful where the noise estimate
is inflated (a parked hotend that left the background frame's bed sample).
"""
from __future__ import annotations

import numpy as np

#: A stalled part's newest band covered less than this share by the part's material is a nest or the bed
#: (strands 0.4 mm wide over the bed read about 0.5 where they cover half of it; a solid face reads 0.9-1.0)
NEST_MAX_COVERAGE = 0.5
#: ... in a view whose newest band read at least this covered at an earlier check (a solid part in its colours)
SOLID_MIN_COVERAGE = 0.8

#: A view that saw the part rise at least this much (% of the expected rise) is not stalled: its band's
#: coverage is not read there (pipeline.decide's stall rules all need less), so it need not be measured
STALL_READ_BELOW_GROWTH_PCT = 50.0

#: Pixels sampled (evenly spread) for the region's mean: the mean of a few thousand is as good as all.
MAX_PIXELS = 2000


def part_coverage(frame: np.ndarray, background: np.ndarray, region: np.ndarray,
                  palette: np.ndarray | None) -> float | None:
    """Mean share of ``region``'s pixels covered by the part's material, or None (no palette, no pixels).

    ``frame`` (h, w, 3) and ``background`` (h, w, 3, at the frame's exposure) of one crop, ``region``
    (h, w) bool, ``palette`` (k, 3) the part's colours. Each pixel's coverage is clipped to 1 before
    averaging (a pixel beyond the palette's colour is no more than covered).
    """
    from .shape_check import coverage_by_part   # (shape_check imports this module)

    if palette is None:
        return None
    ys, xs = np.nonzero(region)
    if len(ys) == 0:
        return None
    step = max(1, len(ys) // MAX_PIXELS)
    ys, xs = ys[::step], xs[::step]
    coverage = coverage_by_part(frame[ys, xs], background[ys, xs], palette)
    return float(np.mean(np.minimum(coverage, 1.0)))
