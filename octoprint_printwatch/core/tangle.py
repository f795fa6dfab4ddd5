"""Spaghetti: filament piling up loose on and around the part, seen as material that is new since the
previous check where the model says there is no part.

The camera is fixed and the pipeline brings every frame to the background's exposure, so between two checks
of a normal print only the newest layers change, and they change *inside* the expected silhouette. A tangle
(the nozzle extruding into the air once the part broke loose, or the print lost its base) drapes loops over
the part's top and down its sides: material appears where the model has none, attached to the part, at a
distance no calibration error explains. What does not count:

* anything seen at the previous check (skirt, brim, a shadow, the part's own side beyond a slightly
  misplaced outline: it was there before and only grew with the part);
* anything within ``tolerance`` px of the expected outline, or (upwards) twice that: the top of a part
  standing a layer taller than the model;
* anything closer than ``min_distance_mm`` to the expected part (a misplaced outline leaves the part's edge
  up to about a millimetre outside it);
* the part's reflection zone in a glossy bed, and blobs lying in the bed-marks zone (a skirt or brim line
  flickering in and out of the mask between two frames; strands that also hang higher count);
* objects reaching in from above the search box (the parked hotend), strands leaving it upwards (filament
  pulled towards the parked nozzle), and blobs not attached to the part (the bed's far edge, a thin line
  that may flicker between two frames).

What is left is measured in mm^2 at the part (image pixels / px_per_mm^2), so the figure means the same at
any frame size and camera distance.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Mapping

import cv2
import numpy as np

from .masks import dilate, disk, outline_zone, reaching_in_from_above

#: New material closer than this to the expected silhouette (mm at the part) is not counted: the residual
#: calibration error (1 %, 0.5 deg, 1 mm) leaves a part's edge up to about a millimetre outside its outline.
MIN_DISTANCE_MM = 2.0


@dataclass
class NewMaterial:
    """Material new since the previous check, outside the expected part (one camera, one check).

    area_mm2 : counted area, mm^2 at the part's image scale.
    pixels : counted pixels.
    blobs : number of attached blobs counted.
    mask : (h, w) bool, the counted pixels (crop or frame coordinates, as the inputs), or None.
    """

    area_mm2: float
    pixels: int
    blobs: int
    mask: np.ndarray | None = field(default=None, repr=False)

    def figures(self) -> dict:
        return {"new_outside_mm2": round(self.area_mm2, 1), "new_outside_blobs": self.blobs}


def new_material(
    observed: np.ndarray,
    previous: np.ndarray,
    expected: np.ndarray,
    search: np.ndarray,
    tolerance: float,
    px_per_mm: float,
    *,
    ignore: np.ndarray | None = None,
    marks: np.ndarray | None = None,
    linked: np.ndarray | None = None,
    min_distance_mm: float = MIN_DISTANCE_MM,
    attach_px: float = 3.0,
) -> NewMaterial | None:
    """Material seen now and not at the previous check, outside the expected part and attached to it.

    observed : (h, w) bool, material seen now (the shape check's observed mask, already cleaned).
    previous : (h, w) bool, material seen at the previous check by the same camera (same coordinates).
    expected : (h, w) bool, the expected silhouette now, aligned.
    search : (h, w) bool, where the print's own material may be (the part's surroundings, below the hotend).
    tolerance : px, the outline tolerance of the shape check.
    px_per_mm : image scale at the part (0: unknown, returns None).
    ignore : (h, w) bool or None, where material is never held against the print (the reflection zone).
    marks : (h, w) bool or None, the bed-marks zone (skirt, brim, purge line): a blob of new material lying
        (80 %) in it is such a line flickering in and out of the mask, not a tangle (as in compare_masks).
    linked : (h, w) bool or None, everything not confidently bed: groups pixels into objects for the
        "reaching in from above the search box" test (the parked hotend's nozzle and its dark body).
    attach_px : a blob counts when it comes this close (px) to the outline's tolerance ring: the material
        seen at the previous check is grown by 2 px before it is subtracted, so a strand's root next to the
        part is taken away with it.
    Returns None when the test cannot be made (no scale, no previous mask, empty expected part).
    """
    if px_per_mm <= 0 or previous is None or previous.shape != observed.shape or not expected.any():
        return None
    tol = float(tolerance)
    none = NewMaterial(0.0, 0, 0, np.zeros(observed.shape, bool))
    distance = cv2.distanceTransform((~expected).astype(np.uint8), cv2.DIST_L2, 3)
    # upwards the tolerance is doubled: the part's top may stand a layer higher than the model says
    grown = outline_zone(expected, tol, tol)
    outside = observed & ~grown
    new = outside & search & ~dilate(previous, 2)
    if ignore is not None:
        new &= ~ignore
    far = distance > min_distance_mm * px_per_mm
    if not (new & far).any():   # most checks of a normal print end here
        return none
    # objects reaching in from above the search box are not the print's (the hotend, the gantry), grouped
    # with everything not confidently bed as in compare_masks (the nozzle and its dark body are one object);
    # nor are strands leaving the box upwards on their own (filament pulled towards the parked nozzle)
    new &= ~reaching_in_from_above(outside if linked is None else outside | (linked & ~grown), search, expected)
    new &= ~reaching_in_from_above(outside, search, expected)
    count, labels, stats, _ = cv2.connectedComponentsWithStats(new.astype(np.uint8), connectivity=8)
    keep = np.ones(count, bool)
    keep[0] = False
    ys, xs = np.nonzero(new)
    ids = labels[ys, xs]
    if marks is not None and count > 1:
        inside = np.bincount(ids, weights=marks[ys, xs], minlength=count)
        keep &= inside < 0.8 * np.maximum(stats[:, cv2.CC_STAT_AREA], 1)
    # attached to the part: a blob of new material that reaches the expected part's tolerance ring; a line
    # far from the part flickering between two frames (the bed's edge) is not
    contact = cv2.dilate(grown.astype(np.uint8), disk(attach_px)).astype(bool)
    keep &= np.bincount(ids, weights=contact[ys, xs], minlength=count) > 0
    counted = keep[labels] & far
    pixels = int(counted.sum())
    blobs = int(len(np.unique(labels[counted]))) if pixels else 0
    return NewMaterial(pixels / (px_per_mm * px_per_mm), pixels, blobs, counted)


#: New material (mm^2 at the part) that fails the print when two views see at least this much each...
TWO_VIEWS_MM2 = 6.0
#: ... or, on a rig with one usable camera, when that camera sees this much.
ONE_VIEW_MM2 = 30.0


def loose_material(areas: Mapping[str, float | None], *, two_views_mm2: float = TWO_VIEWS_MM2,
                   one_view_mm2: float = ONE_VIEW_MM2) -> str | None:
    """The reason to pause for loose material piling up around the part, or None.

    ``areas`` maps every usable camera to its :attr:`NewMaterial.area_mm2` (None: not measured). A tangle
    drapes over the part and is seen from most sides, while one view can be fooled (a face the colour of
    what lies behind it flickering in and out of the mask, the part's own side growing beyond an outline
    the calibration misplaced, the parked hotend): with two or more usable cameras two views must agree.
    With one usable camera nothing can corroborate it, so that view must see five times as much.
    """
    seen = {cam: a for cam, a in areas.items() if a is not None and a >= two_views_mm2}
    if len(seen) >= 2 or (len(areas) == 1 and any(a >= one_view_mm2 for a in seen.values())):
        views = ", ".join(f"{cam} {a:.0f} mm²" for cam, a in sorted(seen.items(), key=lambda kv: -kv[1]))
        return (f"material appeared around the part since the previous check where the model has none "
                f"({views}): spaghetti, or the part knocked loose?")
    return None

