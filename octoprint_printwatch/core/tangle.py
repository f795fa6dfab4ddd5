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
from typing import Callable, Collection, Mapping, Sequence

import cv2
import numpy as np

from .layer_shift import count_viewpoints
from .masks import dilate, disk, labelled_on_its_box, outline_zone, reaching_in_from_above, upper_profile, within

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
    at_foot_mm2 : mm^2 of the attached blobs left out of ``area_mm2`` because they lie in the bed-marks zone
        (loops lying on the bed around the foot, or piled on a short part's top where an oblique view sees
        the bed ring behind it); :func:`loose_material` counts them only when two viewpoints agree.
    direction : radians, the bed direction the camera's image x follows at the part: which side the camera
        looks from (the two cameras of a stereo pair share it, opposite cameras differ by pi); None when
        unknown.
    arc_deg : degrees of the circle around the part's image centre that the new attached material at the foot (the
        blobs of ``at_foot_mm2``) spans: 360 less the widest gap of sectors (``ARC_SECTORS``) holding under
        ``SECTOR_MIN_MM2``.
    """

    area_mm2: float
    pixels: int
    blobs: int
    mask: np.ndarray | None = field(default=None, repr=False)
    at_foot_mm2: float = 0.0
    direction: float | None = None
    arc_deg: float = 0.0

    @property
    def with_foot_mm2(self) -> float:
        """All new material attached to the part beyond the outline, the bed-marks zone included (mm^2)."""
        return self.area_mm2 + self.at_foot_mm2

    def figures(self) -> dict:
        return {"new_outside_mm2": round(self.area_mm2, 1), "new_outside_blobs": self.blobs,
                "new_at_foot_mm2": round(self.at_foot_mm2, 1), "new_arc_deg": round(self.arc_deg)}

    @property
    def surrounds_part(self) -> bool:
        """The new material at the foot lies on more than half the circle around the part (no empty half circle)."""
        return self.arc_deg > SURROUNDS_ARC_DEG

    @property
    def spreads_around(self) -> bool:
        """The new material at the foot lies on a quarter of the circle around the part or more."""
        return self.arc_deg >= SPREAD_ARC_DEG


#: Sectors the circle around the part's image centre is cut into to read how far around it new material lies.
ARC_SECTORS = 8
#: A sector holds new material when at least this much of it (mm^2 at the part) lies there: a strand's root
#: 0.4 mm wide and a few mm long; specks of a flickering edge hold less.
SECTOR_MIN_MM2 = 1.0
#: New material spanning more than this arc around the part surrounds it (see :func:`loose_material`).
SURROUNDS_ARC_DEG = 180.0
#: New material at the foot spanning at least this arc spreads around the part (see :func:`loose_material`).
SPREAD_ARC_DEG = 90.0
#: A surrounding view is corroborated when another view that measured new material sees at least this much of it
#: (mm^2, the bed-marks zone's blobs included): a sector's worth, a strand's root (see :func:`loose_material`).
SURROUNDING_WITNESS_MM2 = SECTOR_MIN_MM2


def arc_around(material: np.ndarray, expected: np.ndarray, scale_mm2: float) -> float:
    """Degrees of the circle around ``expected``'s centre that ``material`` spans (sectors holding
    ``SECTOR_MIN_MM2`` each; 360 less the widest run of sectors holding less)."""
    ys, xs = np.nonzero(material)
    if not len(ys):
        return 0.0
    ey, ex = np.nonzero(expected)
    angle = np.arctan2(ys - ey.mean(), xs - ex.mean())
    sector = ((angle + np.pi) / (2.0 * np.pi) * ARC_SECTORS).astype(int) % ARC_SECTORS
    held = np.bincount(sector, minlength=ARC_SECTORS) * scale_mm2 >= SECTOR_MIN_MM2
    if not held.any():
        return 0.0
    gap = run = 0
    for h in np.concatenate([held, held]):   # (twice round: a gap may wrap past sector 0)
        run = 0 if h else run + 1
        gap = max(gap, run)
    return 360.0 * (1.0 - min(gap, ARC_SECTORS) / ARC_SECTORS)


def beyond(silhouette: np.ndarray, tolerance: float, min_distance_px: float) -> np.ndarray:
    """(h, w) bool: where new material may count against ``silhouette``: outside its tolerance ring (doubled
    upwards) and farther than ``min_distance_px`` from it."""
    return ~outline_zone(silhouette, tolerance, tolerance) & ~within(silhouette, min_distance_px)


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
    bed_to_image: np.ndarray | None = None,
    not_the_prints: Callable[[np.ndarray], np.ndarray] | None = None,
    foreign: np.ndarray | None = None,
    part_in_place: bool = False,
    placed_before: np.ndarray | None = None,
    risen: np.ndarray | Callable[[], np.ndarray] | None = None,
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
    bed_to_image : (2, 2) image px per bed mm at the part (columns: printer X, Y) or None: gives
        :attr:`NewMaterial.direction`.
    not_the_prints : ((h, w) bool material -> (h, w) bool) or None: marks the blobs of the material outside the
        outline that are something else (check_shape: not of the part's colour, a shadow); they never count.
        Called only when there is new material to count (most checks have none).
    foreign : (h, w) bool or None: the material of the objects reaching in from above the search box, as
        compare_masks found them on the same masks (``observed``, ``expected``, ``search``, ``linked``, the
        same tolerance) with no objects of a previous check to follow; given, it is not searched again
        (the same pixels: ``new`` lies in ``observed``). None: searched here.
    part_in_place : the part stands where it belongs (compare_masks' Comparison.part_in_place): objects are then
        taken apart from a ring around its outline before they are searched, as compare_masks does.
    placed_before : (h, w) bool or None, the expected silhouette now laid where the camera's previous check laid its
        outline (its alignment then), when that differs: the calibration error is the same at both checks, so the
        part may stand at either place, and where the outline jumped since, the part's newest band lies beyond this
        check's outline (new since then, far from it) though it is the part's. Material is counted beyond both (the
        pixels near that placement are taken away at the end; which blobs count is judged as without it).
    risen : (h, w) bool or None, where the part's top this camera saw at the previous check stands once risen by
        the model's rise since (:func:`risen_top`): the part's newest band, though beyond an outline the calibration
        error laid off the part. Its pixels are taken away at the end, as ``placed_before``'s, beyond the bed-marks
        zone only. Or a function giving it, called only when there is new material to count (most checks have
        none).
    Returns None when the test cannot be made (no scale, no previous mask, empty expected part).
    """
    if px_per_mm <= 0 or previous is None or previous.shape != observed.shape or not expected.any():
        return None
    tol = float(tolerance)
    direction = None if bed_to_image is None else float(np.arctan2(bed_to_image[0, 1], bed_to_image[0, 0]))
    none = NewMaterial(0.0, 0, 0, np.zeros(observed.shape, bool), direction=direction)
    # upwards the tolerance is doubled: the part's top may stand a layer higher than the model says
    grown = outline_zone(expected, tol, tol)
    outside = observed & ~grown
    new = outside & search & ~dilate(previous, 2)
    if ignore is not None:
        new &= ~ignore
    if not new.any():   # (nothing new at all: the distances below are not needed)
        return none
    # (distance > the minimum: the complement of the pixels within it, read on the box around the part only)
    far = ~within(expected, min_distance_mm * px_per_mm)
    if not (new & far).any():   # most checks of a normal print end here
        return none
    if not_the_prints is not None:
        # judged on whole objects (the material outside the outline), only those holding new material
        objects, object_of = cv2.connectedComponents((outside & search).astype(np.uint8), connectivity=8)
        holding = np.zeros(objects, bool)
        holding[object_of[new & far]] = True
        holding[0] = False
        new &= ~not_the_prints(holding[object_of])
        if not (new & far).any():
            return none
    # objects reaching in from above the search box are not the print's (the hotend, the gantry), grouped
    # with everything not confidently bed as in compare_masks (the nozzle and its dark body are one object);
    # nor are strands leaving the box upwards on their own (filament pulled towards the parked nozzle)
    if foreign is None:
        foreign = reaching_in_from_above(outside if linked is None else outside | (linked & ~grown), search, expected,
                                         outline=grown if part_in_place else None)
    new &= ~foreign
    new &= ~reaching_in_from_above(outside, search, expected)
    # (the blobs are labelled and read on the box around them: the same blobs, the same figures)
    count, labels, inner = labelled_on_its_box(new)
    area = np.bincount(labels[inner].ravel(), minlength=count)
    keep = np.ones(count, bool)
    keep[0] = False
    ys, xs = np.nonzero(new[inner])
    ys, xs = ys + inner[0].start, xs + inner[1].start
    ids = labels[ys, xs]
    # attached to the part: a blob of new material that reaches the expected part's tolerance ring; a line
    # far from the part flickering between two frames (the bed's edge) is not
    contact = cv2.dilate(grown.astype(np.uint8), disk(attach_px)).astype(bool)
    keep &= np.bincount(ids, weights=contact[ys, xs], minlength=count) > 0
    at_foot = np.zeros(count, bool)
    if marks is not None and count > 1:
        inside = np.bincount(ids, weights=marks[ys, xs], minlength=count)
        at_foot = keep & (inside >= 0.8 * np.maximum(area, 1))
        keep &= ~at_foot
    counted, foot = np.zeros(new.shape, bool), np.zeros(new.shape, bool)
    counted[inner] = keep[labels[inner]] & far[inner]
    foot[inner] = at_foot[labels[inner]] & far[inner]
    if placed_before is not None and placed_before.shape == expected.shape and placed_before.any():
        # (only pixels are taken away: the objects above were judged on this check's outline, as without it)
        beyond_before = beyond(placed_before, tol, min_distance_mm * px_per_mm)
        counted &= beyond_before
        foot &= beyond_before
    if callable(risen):
        risen = risen()
    if risen is not None and risen.shape == expected.shape:
        # (not at the foot: there a short part's top and its layer shift's band lie together, and the zone's blobs
        # count only where two sides see them)
        counted &= ~risen
    pixels = int(np.count_nonzero(counted))
    foot_pixels = int(np.count_nonzero(foot)) if at_foot.any() else 0
    blobs = int(len(np.unique(labels[counted]))) if pixels else 0
    scale = 1.0 / (px_per_mm * px_per_mm)
    return NewMaterial(pixels * scale, pixels, blobs, counted, at_foot_mm2=foot_pixels * scale, direction=direction,
                       # (the loops at the foot alone: what lies beyond the zone counts already, and a glass bed's
                       # mirror image of a growing part spreads below it over half the circle, s7 021_detach)
                       arc_deg=arc_around(foot, expected, scale))


#: px the risen top is grown by (:func:`risen_top`).
RISEN_SLACK_PX = 1.0


def risen_top(seen_before: np.ndarray, expected: np.ndarray, before: np.ndarray, reach: float,
              tolerance: float) -> np.ndarray:
    """(h, w) bool: where the part's top that the camera saw at its previous check (``seen_before``) stands now,
    raised by the model's rise since (``before`` -> ``expected``, the silhouettes then and now laid as this check's
    outline; each column's rise of their tops) and grown by a pixel.

    The calibration error is the same at both checks: where the camera saw the part's top a few px beyond the outline
    then (the outline laid low or aside, within ``reach``, the alignment's bound), the newest layers stand as far
    beyond it now, new since then and more than 2 mm beyond the outline at every check. Only the part's top counts:
    the columns of the outline then (grown by the tolerance), where the seen top stands at most ``reach`` above its
    top and no more than ``tolerance`` below it (strands seen higher are no top; a lower one is the part's side, a
    skirt or the foot), and only the rise the model gives: loops lie higher, down the sides and around the foot."""
    none = np.zeros(expected.shape, bool)
    if not (seen_before.any() and expected.any() and before.any()):
        return none
    now, then = upper_profile(expected), upper_profile(before)
    both = ~np.isnan(now) & ~np.isnan(then)
    if not both.any():
        return none
    # each column's own rise; beside the outlines (a part seen a few px aside), the median's
    rise = np.where(both, then - now, float(np.median(then[both] - now[both])))
    seen_top = upper_profile(seen_before & dilate(before, reach))
    outline_top = upper_profile(dilate(before, tolerance))
    columns = ~np.isnan(seen_top) & ~np.isnan(outline_top) & (rise > 0)
    # (the part's top: at or above the outline's, within the bound; a lower top beside the outline is its side, the
    # skirt or the foot, and raised it would cover a layer shift's band sticking out there)
    columns[columns] = ((seen_top[columns] >= outline_top[columns] - reach)
                        & (seen_top[columns] <= outline_top[columns] + tolerance))
    rows = np.arange(expected.shape[0], dtype=np.float32)[:, None]
    top = np.where(columns, seen_top, np.nan)[None, :]
    with np.errstate(invalid="ignore"):
        band = columns[None, :] & (rows >= top - rise[None, :]) & (rows <= top)
    # (a pixel's step: the top is read to the pixel at both checks; no tolerance more, or a layer shift's band,
    # raised along the line of sight just past the outline's ring, would be taken for the part's rise)
    return dilate(band, RISEN_SLACK_PX)


#: New material (mm^2 at the part) that fails the print when two views see at least this much each...
TWO_VIEWS_MM2 = 6.0
#: ... or, on a rig with one usable camera, when that camera sees this much.
ONE_VIEW_MM2 = 30.0
#: A part whose outline rose under this share of the expected rise (median over two or more views, %) has slowed:
#: then one view seeing TWO_VIEWS_MM2 of new material suffices (:func:`loose_material`, ``rise_pct``)
SLOWED_RISE_PCT = 50.0
#: ... and one view seeing this much of it (mm^2, the bed-marks zone's blobs included) spread around the part
#: (:data:`SPREAD_ARC_DEG`) suffices while the part rose under :data:`SPREAD_SLOWED_RISE_PCT` ...
SPREAD_MM2 = 15.0
#: ... a part slowed somewhat: a pile of strands on a stopped top lifts its outline by about half the model's rise
SPREAD_SLOWED_RISE_PCT = 75.0


def viewpoints(directions: Mapping[str, float | None]) -> int:
    """How many clearly different sides the cameras look from: directions (radians, see
    :attr:`NewMaterial.direction`) less than VIEWPOINT_APART_DEG apart count once (the two cameras of a
    stereo pair look from nearly one place; a camera opposite another sees the part's other side); cameras
    of unknown direction count once together."""
    known = {cam: angle for cam, angle in directions.items() if angle is not None}
    return count_viewpoints(known, period=2.0 * np.pi) + int(len(known) < len(directions))


def witnessed_by_another(cameras: Collection[str], with_foot: Mapping[str, float | None]) -> bool:
    """A view other than ``cameras`` (one view, or the two of a stereo pair) that measured new material (mm^2, the
    bed-marks zone's blobs included) sees at least ``SURROUNDING_WITNESS_MM2`` of it, or no other view measured any
    (a one-camera rig, a first check)."""
    others = [a for cam, a in with_foot.items() if cam not in cameras and a is not None]
    return not others or max(others) >= SURROUNDING_WITNESS_MM2


def loose_material(areas: Mapping[str, float | None], *, two_views_mm2: float = TWO_VIEWS_MM2,
                   one_view_mm2: float = ONE_VIEW_MM2, with_foot: Mapping[str, float | None] | None = None,
                   directions: Mapping[str, float | None] | None = None,
                   rise_pct: float | None = None, rise_over: str = "", surrounding: Collection[str] = (),
                   spreading: Collection[str] = (), pairs: Sequence[Sequence[str]] = ()) -> str | None:
    """The reason to pause for loose material piling up around the part, or None.

    ``areas`` maps every usable camera to its :attr:`NewMaterial.area_mm2` (None: not measured). A tangle
    drapes over the part and is seen from most sides, while one view can be fooled (a face the colour of
    what lies behind it flickering in and out of the mask, the part's own side growing beyond an outline
    the calibration misplaced, the parked hotend): with two or more usable cameras two views must agree.
    With one usable camera nothing can corroborate it, so that view must see five times as much.

    ``with_foot`` (per camera, :attr:`NewMaterial.with_foot_mm2`) adds the blobs lying in the bed-marks
    zone, and ``directions`` where each camera looks from: loops lying on the bed around the foot, or piled
    on a short part's top where an oblique camera sees the bed ring behind it, count when cameras on two
    different sides (:func:`viewpoints`) each see ``two_views_mm2`` of them. A skirt or brim line
    flickering in and out of the mask is one camera's artefact (its contrast at that camera's threshold),
    and a stereo pair's two cameras see the same artefact from one place.

    ``rise_pct``: the median rise of the part's outline since the previous check (% of the model's) when two or
    more views measured it (on a one-camera rig, that camera's own reading), or over their spans of checks where no
    view reads one check's rise (``rise_over`` then says so in the reason), else None. Under
    ``SLOWED_RISE_PCT`` the part has slowed, and then one view seeing ``two_views_mm2`` (the zone's blobs
    included) suffices: a tangle stops the part while its strands drape beyond the outline, and what one view
    may read as new material on a normal print (a shadow edge at the rim, the part's own side beyond a
    misplaced outline, a flickering skirt line) comes with a part that keeps rising. Other views of a tangle
    often see no strands beyond the outline (they hang inside it, or over what was seen before): the growth
    test is the second witness.

    ``surrounding``: the cameras whose new material lies around the part on more than half the circle
    (:attr:`NewMaterial.surrounds_part`). Such a view, seeing ``one_view_mm2`` (the zone's blobs included),
    counts as two sides: loops drape down every side of the
    part and spread over the bed around its foot, while what one view reads on a normal print lies on one side
    of it (its cast shadow, a glare line on a glossy bed, its own side beyond a misplaced outline). Loops on
    every side are on the sides the other views see too, so where another view measured new material it must
    see some (:func:`witnessed_by_another`): a skirt or brim line drawn into one view's mask at one check (its
    contrast near that view's threshold) also lies all around the part, and is that view's alone.

    ``spreading``: the cameras whose new material at the foot spans a quarter of the circle around the part or more
    (:attr:`NewMaterial.spreads_around`). Such a view seeing :data:`SPREAD_MM2` (the zone's blobs included, witnessed
    as a surrounding view must be) corroborates a part that rose under :data:`SPREAD_SLOWED_RISE_PCT`, not only under
    ``SLOWED_RISE_PCT``: strands falling from a stopped top spread over the bed around the foot while the pile on the
    top lifts the outline a little (about half the model's rise on the development seeds); what one view reads on a
    normal print lies on one side of the part or comes with a part rising as its model (on the twenty-six
    development seeds, no check before a failure read 15 mm^2 over a quarter circle with the median rise under 75 %).

    ``pairs``: stereo pairs ([left, right] names). Both cameras of a pair each seeing ``one_view_mm2`` (the zone's
    blobs included), as much as a lone camera must see, count as two sides, unless a view outside the pair measured
    new material and saw under :data:`SURROUNDING_WITNESS_MM2` of it: loops spreading over the bed around the foot
    of a part seen small and from one place (cross-check seed 28 ``050_spaghetti``: 44 and 58 mm² at the onset
    check, caught three checks later by the stall), while the most a pair's views saw together on a normal print
    of the development seeds was under 10 mm² each.
    """
    seen = {cam: a for cam, a in areas.items() if a is not None and a >= two_views_mm2}
    slowed = ""
    if not (len(seen) >= 2 or (len(areas) == 1 and any(a >= one_view_mm2 for a in seen.values()))):
        measured = {**areas, **(with_foot or {})}
        seen = {cam: a for cam, a in measured.items() if a is not None and a >= two_views_mm2}
        if not seen:
            return None
        # (as much as a lone camera must see: a brim of the part's colour, new in one view, also lies around it)
        around = sorted(cam for cam, a in seen.items() if cam in surrounding and a >= one_view_mm2
                        and witnessed_by_another((cam,), measured))
        paired = [pair for pair in pairs if all(cam in seen and seen[cam] >= one_view_mm2 for cam in pair)
                  and witnessed_by_another(pair, measured)]
        if around:
            slowed = f" on more than half the circle around the part in {', '.join(around)}"
        elif paired:
            slowed = f" in both views of {' and '.join('+'.join(pair) for pair in paired)}"
        elif viewpoints({cam: (directions or {}).get(cam) for cam in seen}) < 2:
            spread = sorted(cam for cam, a in seen.items() if cam in spreading and a >= SPREAD_MM2
                            and witnessed_by_another((cam,), measured))
            if rise_pct is None or rise_pct >= (SPREAD_SLOWED_RISE_PCT if spread else SLOWED_RISE_PCT):
                return None
            spread_in = (f" spread over a quarter of the circle around the part or more in {', '.join(spread)},"
                         if rise_pct >= SLOWED_RISE_PCT else "")
            slowed = f"{spread_in} while the part rose {rise_pct:.0f}% of the expected height{rise_over}"
    views = ", ".join(f"{cam} {a:.0f} mm²" for cam, a in sorted(seen.items(), key=lambda kv: -kv[1]))
    return (f"material appeared around the part since the previous check where the model has none "
            f"({views}){slowed}: spaghetti, or the part knocked loose?")

