"""Binary-mask helpers shared by the vision checks; every mask is (h, w) bool."""
from __future__ import annotations

from functools import cached_property
from typing import Callable, NamedTuple

import cv2
import numpy as np


def components(mask: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    """The 8-connected blobs of ``mask`` ((h, w) bool): (count, (h, w) int32 labels, (count,) int64 area in px of
    each label, label 0 the rest), as cv2.connectedComponentsWithStats gives them. (Its statistics cost about five
    times the labelling on a check's masks: the areas are one bincount.)"""
    count, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    return count, labels, np.bincount(labels.ravel(), minlength=count)


def blobs_lying_on(mask: np.ndarray, zone: np.ndarray, share: float) -> np.ndarray:
    """(h, w) bool: the blobs of ``mask`` with at least ``share`` of their pixels in ``zone`` (both (h, w) bool)."""
    count, labels, area = components(mask)
    inside = np.bincount(labels[zone & mask], minlength=count)
    lying = inside >= share * np.maximum(area, 1)
    lying[0] = False
    return lying[labels]


#: lowest_rows tests each label's rows on its own up to this many labels asked.
_LOWEST_ROWS_PER_LABEL = 4


def lowest_rows(labels: np.ndarray, asked: np.ndarray) -> np.ndarray:
    """(count,) int64: the lowest row of each label ``asked`` ((count,) bool) in ``labels`` ((h, w) int), -1 for
    the others (the row cv2.connectedComponentsWithStats' top + height - 1 gives, for the labels read)."""
    lowest = np.full(len(asked), -1, np.int64)
    wanted = np.flatnonzero(asked)
    if wanted.size <= _LOWEST_ROWS_PER_LABEL:
        # (a row test per label: for the one or two blobs usually asked, a few times cheaper than gathering the
        # pixels of all of them)
        for label in wanted:
            rows = np.flatnonzero((labels == label).any(axis=1))
            if rows.size:
                lowest[label] = rows[-1]
    else:
        ys, xs = np.nonzero(asked[labels])
        np.maximum.at(lowest, labels[ys, xs], ys)
    return lowest


def disk(radius: float) -> np.ndarray:
    r = max(0, int(round(radius)))
    return cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))


def dilate(mask: np.ndarray, radius: float) -> np.ndarray:
    """(h, w) bool grown by ``radius`` px (Euclidean; a distance transform, so large radii cost no more)."""
    if radius < 0.5:
        return mask.astype(bool)
    if radius <= 2.5:
        return cv2.dilate(mask.astype(np.uint8), disk(radius)).astype(bool)
    return within(mask, radius)


def within(mask: np.ndarray, radius: float) -> np.ndarray:
    """(h, w) bool: ``cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 3) <= radius`` for a (h, w) bool
    ``mask``, bit for bit, computed on the box that can be reached only: the 3x3 distance grows by at least 0.955 px
    per px, so nothing beyond that box is within ``radius``, and inside it the distances are the whole image's (a
    pixel's shortest 3x3 path to its nearest mask pixel stays within the box around the two; the image's border is
    no source)."""
    out = np.zeros(mask.shape, bool)
    inner = _reachable_box(mask, radius)
    if inner is not None:
        out[inner] = _distances(mask[inner]) <= radius
    return out


def distance_up_to(mask: np.ndarray, reach: float) -> np.ndarray:
    """(h, w) float32: ``cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 3)`` for a (h, w) bool ``mask``
    wherever it is at most ``reach``, bit for bit (as :func:`within`: computed on the box that can be reached only),
    and above ``reach`` (+inf beyond the box) everywhere else: every test of it against a distance up to ``reach``
    gives the whole image's answer."""
    out = np.full(mask.shape, np.inf, np.float32)
    inner = _reachable_box(mask, reach)
    if inner is not None:
        out[inner] = _distances(mask[inner])
    return out


def _reachable_box(mask: np.ndarray, reach: float) -> tuple[slice, slice] | None:
    """The box around ``mask`` within which the 3x3 distance to it can be up to ``reach`` (it grows by at least 0.955
    px per px), as slices; None for an empty mask."""
    box = bounding_box(mask, pad=int(np.ceil(reach / 0.955)) + 1)
    return None if box is None else (slice(box[0], box[1]), slice(box[2], box[3]))


def _distances(mask: np.ndarray) -> np.ndarray:
    """(h, w) float32: each pixel's 3x3 distance to the nearest pixel of ``mask`` ((h, w) bool)."""
    return cv2.distanceTransform((~mask.astype(bool)).astype(np.uint8), cv2.DIST_L2, 3)


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


def shifted_union(mask: np.ndarray, shifts: np.ndarray) -> np.ndarray:
    """(h, w) bool: the union of ``mask`` moved by each of ``shifts`` ((k, 2) int (dx, dy)), zeros shifted in."""
    shifts = np.asarray(shifts, int).reshape(-1, 2)
    if not len(shifts):
        return np.zeros(mask.shape, bool)
    r = int(np.abs(shifts).max())
    # one dilation whose kernel holds the shifts mirrored (cv2.dilate reads src at x + k - anchor)
    kernel = np.zeros((2 * r + 1, 2 * r + 1), np.uint8)
    kernel[r - shifts[:, 1], r - shifts[:, 0]] = 1
    padded = cv2.copyMakeBorder(mask.astype(np.uint8), r, r, r, r, cv2.BORDER_CONSTANT, value=0)
    return cv2.dilate(padded, kernel, anchor=(r, r))[r:-r or None, r:-r or None].astype(bool)


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


def upper_profile(mask: np.ndarray) -> np.ndarray:
    """(w,) float: row of the top-most True pixel of each column, NaN for empty columns."""
    has = mask.any(axis=0)
    top = np.argmax(mask, axis=0).astype(np.float32)
    top[~has] = np.nan
    return top


def outline_zone(expected: np.ndarray, tolerance: float, top_tolerance: float = 0.0) -> np.ndarray:
    """(h, w) bool: ``expected`` grown by ``tolerance`` px, and upwards (towards row 0) by ``top_tolerance``
    px more (a part's top may stand a little higher in the image than its outline: the vertical alignment
    is the least certain, and a camera may fire a layer late). Material there is not held against the print."""
    grown = dilate(expected, tolerance)
    if top_tolerance >= 1.0:
        k = int(round(top_tolerance))
        grown |= cv2.dilate(grown.astype(np.uint8), np.ones((k + 1, 1), np.uint8), anchor=(0, 0)).astype(bool)
    return grown


#: An object hangs where a foreign object hung at the previous check when this share of its material lies
#: there (grown by FOREIGN_BEFORE_REACH_PX): the parked hotend, followed as its image enters the search box.
FOREIGN_BEFORE_SHARE = 0.5
FOREIGN_BEFORE_REACH_PX = 5
#: ... and only while its material keeps this far (px) from the expected part's outline: the parked head
#: hangs apart from the part, while a piece of the part knocked over leans on its outline.
FOREIGN_APART_PX = 5


#: Blobs are taken apart from a ring this wide (px) around the part's outline zone before they are judged a
#: rod, or an object reaching in from above that only touches the part: a shadow's fringe, or the part's own rim
#: a pixel wider than the model, joins everything that touches the part there.
APART_FROM_OUTLINE_PX = 3
#: An object reaching in from above the box that meets the part's outline along less than this share of its
#: own extent only touches it in the picture (the parked hotend at a tall part's top corner, our normal_08: 9
#: of 259 px); one resting on the part or grown out of it meets it along its whole width (a part tipped over in
#: place, its top rising above the box, our detach_05: 58-80 px of 56-79).
POINT_CONTACT_SHARE = 0.25


def outline_ring(outline: np.ndarray) -> np.ndarray:
    """(h, w) bool: within APART_FROM_OUTLINE_PX of ``outline`` ((h, w) bool, the part's outline zone)."""
    return cv2.dilate(outline.astype(np.uint8), disk(APART_FROM_OUTLINE_PX)).astype(bool)


def apart_from_ring(objects: np.ndarray, ring_zone: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``objects`` ((h, w) bool) -> (the pixels outside ``ring_zone`` (:func:`outline_ring`), those inside): the
    objects taken apart where only the part's rim or a fringe joins them."""
    ring = ring_zone & objects
    return objects & ~ring, ring


def reaching_in_from_above(objects: np.ndarray, search: np.ndarray, expected: np.ndarray,
                           material: np.ndarray | None = None, before: np.ndarray | None = None,
                           outline: np.ndarray | None = None) -> np.ndarray:
    """(h, w) bool: the pixels of ``objects`` in blobs that reach in from above the ``search`` box and hang
    there, which are not the print's (the parked hotend, the gantry, a hand).

    A blob counts when 15 % of its pixels lie beyond the box and 5 % above its top edge (a part sliding out
    sideways is the print's), and it does not reach down into the ``expected`` part's lowest quarter (a part
    that tipped over and stands taller than the box does).
    ``before`` ((h, w) bool, the same coordinates): the material of the objects found foreign at the
    camera's previous check; ``material`` ((h, w) bool): the pixels of ``objects`` that are material (the rest
    are merely not confidently bed). A blob whose material lies (FOREIGN_BEFORE_SHARE) where one of them
    hung, and keeps apart from the ``expected`` outline (FOREIGN_APART_PX), is the same object, a check's rise
    further on, and still foreign, however much of it now lies inside the box: the parked hotend rises with
    every check while the box's top rises with the part, and from some views its image enters the box whole.
    For such a followed object the foot rule is read on its material: the weak pixels grouped with it below
    (its shadow or mirror image on glass) are no foot, while a piece of the part knocked over leans on the
    outline (and its first reading, with the weak pixels, already kept it as the print's).
    ``outline`` ((h, w) bool, the part's outline zone) or None: a blob kept only for reaching the foot is
    looked at again taken apart from a ring around the outline (apart_from_ring): a piece of it that reaches
    in from above on its own and meets the outline at a point (POINT_CONTACT_SHARE) hangs beside the part in
    this view, joined to its foot by nothing but the part's rim. So is a blob that holds as much material where
    ``before``'s objects hung as half of them (the object followed, joined to the part's top by its shadow and the
    rim's fringe as the part rises towards it in the picture: cross-check seed 43 ``012_normal``); a piece of it
    followed there (its material apart from the outline) is foreign however long its contact with the ring.
    """
    first = _reaching_in(objects, search, expected, material, before)
    out = first.foreign
    if outline is not None and (first.kept_at_foot.any() or first.holding.any()):
        apart, ring = apart_from_ring(first.kept_at_foot | first.holding, outline_ring(outline))
        pieces = _reaching_in(apart, search, expected, material, before)
        # (a piece followed from the previous check keeps its material apart from the outline already: only weak
        # pixels, its shadow or the rim's fringe, join it to the part, however long the contact)
        out |= pieces.followed | _touching_at_a_point(pieces.foreign & first.kept_at_foot & ~pieces.followed, ring)
    return out


#: An object found reaching in from above the box is the part itself, tipped over with its top above the box, where bed
#: shows in the part's place in that view (over PART_IN_PLACE_MAX_MISSING of it missing; a part merely not seen whole
#: there may have the parked hotend of its colour above it: our default set's ``under_extrusion_02`` tower), the object
#: is new there since the previous check (not lying, FOREIGN_BEFORE_SHARE, where that check's objects hung), of the
#: part's colour (at most this share of its material read as another colour: the parked hotend, a hand) and meets the
#: part's outline along half its extent or more (TIPPED_MIN_CONTACT_SHARE; the hotend at a part's corner meets it at a
#: point). Measured (thirty-third session, cross-check seeds 20-37: 309 normal prints, 150 detachments): of 697 such
#: objects (100 px or more) at normal prints' checks, 57 lay where bed showed in the part's place, 48 of them new, 32 of
#: those of the part's colour and 1 met the outline along half its extent (230 px; no verdict changed); of 192 after a
#: detachment's onset, 20. Seed 45 ``021_detach`` (a frame tipped 38 degrees before the first check) was missed.
TIPPED_MAX_OTHER_COLOUR_SHARE = 0.2
TIPPED_MIN_CONTACT_SHARE = 0.5


def tipped_over(foreign: np.ndarray, material: np.ndarray, outline: np.ndarray, before: np.ndarray | None,
                not_the_prints: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """(h, w) bool: the blobs of ``foreign`` (:func:`reaching_in_from_above`, (h, w) bool) that are the part itself,
    tipped over: each new since the previous check (``before``: the material of the objects found foreign there, or
    None), its ``material`` ((h, w) bool) the print's (``not_the_prints``: (h, w) bool material -> (h, w) bool, its
    blobs of another colour than the part's or the hotend's mirror image: shape_check's) and in contact with the part's
    ``outline`` zone ((h, w) bool) along TIPPED_MIN_CONTACT_SHARE of its extent or more. Call it only where bed shows
    in the part's place in this view."""
    out = np.zeros(foreign.shape, bool)
    contact = _ring_contact(foreign, outline_ring(outline))
    if contact is None:
        return out
    inner, labels, span, extent = contact
    held = material[inner] & (labels > 0)
    total = np.bincount(labels[held], minlength=span.size)
    tipped = (span >= TIPPED_MIN_CONTACT_SHARE * extent) & (total > 0)
    if before is not None and before.any():
        tipped &= _held_where_before(labels, held, before, inner) < FOREIGN_BEFORE_SHARE * total
    tipped[0] = False
    if tipped.any():
        candidates = np.zeros(foreign.shape, bool)
        candidates[inner] = tipped[labels] & held
        other = np.bincount(labels[not_the_prints(candidates)[inner]], minlength=span.size)
        tipped &= other <= TIPPED_MAX_OTHER_COLOUR_SHARE * total
        out[inner] = tipped[labels]
    return out


def _held_where_before(labels: np.ndarray, held: np.ndarray, before: np.ndarray, inner: tuple[slice, slice]
                       ) -> np.ndarray:
    """(count,) int: per blob of ``labels`` (labelled on the box ``inner`` of the full masks), its ``held`` pixels
    ((h', w') bool on that box) lying where ``before``'s objects hung ((h, w) bool, grown FOREIGN_BEFORE_REACH_PX): how
    much of it lies where an object found foreign at the previous check was."""
    return np.bincount(labels[held & dilate(before, FOREIGN_BEFORE_REACH_PX)[inner]], minlength=int(labels.max()) + 1)


def foreign_at_both_checks(foreign: np.ndarray | None, before: np.ndarray | None) -> np.ndarray | None:
    """Of the objects not the print's (``foreign``, (h, w) bool: Comparison.foreign), those foreign at the camera's
    previous check too (lying, FOREIGN_BEFORE_SHARE, where ``before``'s objects were, grown FOREIGN_BEFORE_REACH_PX):
    the parked hotend followed into the box; None where there are none to read. An object found foreign at one check
    only may be the part itself, tipped over with its top above the box."""
    if foreign is None or before is None or not foreign.any() or not before.any():
        return None
    return blobs_lying_on(foreign, dilate(before, FOREIGN_BEFORE_REACH_PX), FOREIGN_BEFORE_SHARE)


class _Reach(NamedTuple):
    """:func:`_reaching_in`'s answer, each (h, w) bool."""
    foreign: np.ndarray        # the pixels of the blobs not the print's
    kept_at_foot: np.ndarray   # of the blobs reaching in from above, those kept for reaching the part's foot
    followed: np.ndarray       # of the foreign blobs, those followed from ``before``
    # blobs not foreign that hold as much material where ``before``'s object hung as half that object: the object
    # followed, joined to the part by weak pixels (its shadow, the rim's fringe)
    holding: np.ndarray


def _touching_at_a_point(pieces: np.ndarray, ring: np.ndarray) -> np.ndarray:
    """The blobs of ``pieces`` ((h, w) bool) whose contact with ``ring`` (its pixels next to them) spans less
    than POINT_CONTACT_SHARE of their own extent (the longer side of their bounding box)."""
    out = np.zeros(pieces.shape, bool)
    contact = _ring_contact(pieces, ring)
    if contact is not None:
        inner, labels, span, extent = contact
        point = span < POINT_CONTACT_SHARE * extent
        point[0] = False
        out[inner] = point[labels]
    return out


def _ring_contact(pieces: np.ndarray, ring: np.ndarray
                  ) -> tuple[tuple[slice, slice], np.ndarray, np.ndarray, np.ndarray] | None:
    """(the pieces' box, its blob labels, each blob's contact span, each blob's extent) or None without pieces: how
    far (px, along x or y) the pixels of ``ring`` next to each blob of ``pieces`` ((h, w) bool) spread, and the longer
    side of the blob's bounding box; label 0 is the rest."""
    box = bounding_box(pieces, pad=1)
    if box is None:
        return None
    inner = (slice(box[0], box[1]), slice(box[2], box[3]))
    count, labels, stats, _ = cv2.connectedComponentsWithStats(pieces[inner].astype(np.uint8), connectivity=8)
    # each ring pixel next to a piece, with that piece's label (where two pieces meet at one, either)
    near = cv2.dilate(labels.astype(np.uint16), np.ones((3, 3), np.uint8))
    ys, xs = np.nonzero(ring[inner] & (near > 0))
    which = near[ys, xs].astype(np.int64)
    low_x, low_y = np.full(count, 1 << 30), np.full(count, 1 << 30)
    high_x, high_y = np.full(count, -1), np.full(count, -1)
    np.minimum.at(low_x, which, xs)
    np.minimum.at(low_y, which, ys)
    np.maximum.at(high_x, which, xs)
    np.maximum.at(high_y, which, ys)
    span = np.maximum(np.maximum(high_x - low_x, high_y - low_y) + 1, 0)
    extent = np.maximum(stats[:, cv2.CC_STAT_WIDTH], stats[:, cv2.CC_STAT_HEIGHT])
    return inner, labels, span, extent


def _reaching_in(objects: np.ndarray, search: np.ndarray, expected: np.ndarray, material: np.ndarray | None,
                 before: np.ndarray | None) -> _Reach:
    """:func:`reaching_in_from_above` on one grouping of the pixels into blobs."""
    painted = _Reach(*(np.zeros(objects.shape, bool) for _ in range(4)))
    box = bounding_box(objects)
    if box is None:
        return painted
    # (on the objects' box only: every blob lies in it, and the whole frame costs several times more)
    y0, y1, x0, x1 = box
    inner = (slice(y0, y1), slice(x0, x1))
    count, labels, area = components(objects[inner])
    if count <= 1:
        return painted
    # (each column's top row of the search box, read on the objects' columns only)
    columns = search[:, x0:x1]
    ceiling = np.where(columns.any(axis=0), np.argmax(columns, axis=0), search.shape[0])
    above = np.arange(y0, y1)[:, None] < ceiling[None, :]
    beyond = np.bincount(labels[~search[inner]], minlength=count)
    from_above = np.bincount(labels[above], minlength=count)
    foreign = (beyond >= 0.15 * np.maximum(area, 1)) & (from_above >= 0.05 * np.maximum(area, 1))
    followed, holding = np.zeros(count, bool), np.zeros(count, bool)
    if before is not None and before.any():
        held = objects[inner] if material is None else material[inner] & objects[inner]
        there = _held_where_before(labels, held, before, inner)
        total = np.bincount(labels[held], minlength=count)
        near_part = np.bincount(labels[held & dilate(expected, FOREIGN_APART_PX)[inner]], minlength=count)
        followed = (total > 0) & (near_part == 0) & (there >= FOREIGN_BEFORE_SHARE * np.maximum(total, 1))
        holding = ~followed & ~foreign & (there >= FOREIGN_BEFORE_SHARE * np.count_nonzero(before))
    rows = np.flatnonzero(expected.any(axis=1))
    at_foot = np.zeros(count, bool)
    if rows.size:
        foot_zone = rows[-1] - 0.25 * (rows[-1] - rows[0])
        # (read for the blobs this rule can still change only; label 0 is the rest, never foreign)
        asked = foreign | followed
        asked[0] = False
        lowest = y0 + lowest_rows(labels, asked)
        at_foot = foreign & (lowest >= foot_zone)
        foreign &= lowest < foot_zone
        if material is not None and followed.any():
            # (a blob without material pixels keeps its own extent: it counts in no figure anyway)
            ys, xs = np.nonzero(material[inner] & (labels > 0))
            deepest = np.full(count, -1, np.int64)
            np.maximum.at(deepest, labels[ys, xs], ys + y0)
            lowest = np.where(deepest >= 0, deepest, lowest)
        followed &= lowest < foot_zone
    foreign |= followed
    at_foot &= ~foreign
    # (painted only where a blob has them: most checks have no object from above; label 0 is the rest)
    for blobs, mask in zip((foreign, at_foot, followed, holding), painted):
        blobs[0] = False
        if blobs.any():
            mask[inner] = blobs[labels]
    return painted


#: A rod or a gantry is at least this many times longer (within the picture) than it is thick.
ROD_MIN_ELONGATION = 2.5
#: The part stands where it belongs while at most this share of it is missing from its place (a part that
#: tipped over or slid away can look like a rod ending behind it, or rise above the box joined to its foot only
#: along its old outline) ...
PART_IN_PLACE_MAX_MISSING = 0.02
#: ... and at least this share of it is seen there (a part that cannot be told apart is not known in place).
PART_IN_PLACE_MIN_SEEN = 0.9
#: A rod that ends behind the part runs on beyond the box, at its other end, for at least this many times its
#: thickness, or out of the picture (a strand on the bed grazing the box's edge: 1.5 px for 14 px thick, seed 8
#: 025_detach; the X rods of seed 10 015_normal: 18-31 px for 13-15).
ROD_BEYOND_THICKNESSES = 1.0
#: Share of a rod's cross-sections that must be on its line and of its thickness (the rest: where
#: something else touches it, the oblique cut at the picture's edge).
ROD_REGULAR_SHARE = 0.8


def crossing_the_box(objects: np.ndarray, search: np.ndarray, outline: np.ndarray,
                     part_in_place: bool = True, material: np.ndarray | None = None) -> np.ndarray:
    """(h, w) bool: the pixels of ``objects`` that belong to a rod or a gantry crossing the ``search`` box
    from the side, which are not the print's (the X rods, their reflection in a glass bed).

    A rod is long, straight and of one thickness. The blobs of ``objects`` are taken apart from a 3-px ring
    around the part's ``outline`` zone (where a shadow's fringe joins everything to the part). Along a
    blob's principal axis its cross-sections (1 px apart; half a thickness at each end left out, where the
    picture's edge cuts it obliquely, and those next to the part) keep their centre on one line (within a
    quarter of the thickness, or 1.5 px) and their width (-40 %/+60 %), ROD_REGULAR_SHARE of them, and the
    blob is ROD_MIN_ELONGATION times longer than thick. It leaves the box at both ends, or at one end (and runs
    on beyond it, ROD_BEYOND_THICKNESSES) while the other runs on behind the part (it ends at the ring); then the
    part must stand where it belongs (``part_in_place``: a part that tipped over or slid out of the box, which
    may look as long and straight, is missing from its place). Only the strip along the fitted line is returned
    (with the ring's pixels on it): whatever else touches the rod still counts. A tangle is not straight; a part
    that slid or tipped over inside the box does not leave it at both ends.

    ``material`` ((h, w) bool, within ``objects``): the certain material alone. Where it is given, the blobs
    that are no rod are taken apart again on it: the weakly seen pixels that keep a rod whole also join it
    to whatever lies next to it (the place the rod held in the background frame, a brim, the part's
    reflection in a glass bed), and such a blob is neither straight nor of one thickness.
    """
    zones = _OutlineZones(outline)
    out = _rods_among(objects, search, zones, part_in_place)
    if material is not None:
        out |= _rods_among(material & ~out, search, zones, part_in_place)
    return out


class _OutlineZones:
    """The zones around the part's outline zone that :func:`_rods_among` reads, each made once for both of
    :func:`crossing_the_box`'s groupings (the same outline) and only when a grouping gets that far."""

    def __init__(self, outline: np.ndarray):
        self.outline = outline

    @cached_property
    def ring(self) -> np.ndarray:
        """(h, w) bool: :func:`outline_ring` of the outline zone."""
        return outline_ring(self.outline)

    @cached_property
    def at_part(self) -> np.ndarray:
        """(h, w) bool: within 5 px of the outline zone (a rod's end there runs on behind the part)."""
        return cv2.dilate(self.outline.astype(np.uint8), disk(5)).astype(bool)


def labelled_on_its_box(mask: np.ndarray) -> tuple[int, np.ndarray, tuple[slice, slice]]:
    """cv2.connectedComponents(mask, connectivity=8) for a (h, w) bool ``mask`` -> (count, labels (h, w) int32, the
    box the labelling was done on (slices of ``mask``)), computed on the mask's bounding box only: every blob lies in
    it, and a mask's blobs often fill a small part of the crop. The box's top-left corner is moved to even
    coordinates: OpenCV's labelling scans 2x2 blocks and numbers the blobs in the order it meets them, so on a box
    that keeps the block grid every blob gets the label it gets on the whole mask (the order decides which rod line a
    piece is matched to first, :func:`_rods_come_out`)."""
    box = bounding_box(mask)
    labels = np.zeros(mask.shape, np.int32)
    if box is None:
        return 1, labels, (slice(0, 0), slice(0, 0))
    inner = (slice(box[0] - box[0] % 2, box[1]), slice(box[2] - box[2] % 2, box[3]))
    count, labels[inner] = cv2.connectedComponents(mask[inner].astype(np.uint8), connectivity=8)
    return count, labels, inner


def _fill_extents(stats: np.ndarray, labels: np.ndarray, indices: np.ndarray, inner: tuple[slice, slice]):
    """Writes the bounding box (cv2.connectedComponentsWithStats' left, top, width and height) of each blob of
    ``indices`` in ``labels`` ((h, w) int, the blobs within the box ``inner``) into its row of ``stats``. (OpenCV's
    statistics of every blob cost twice the labelling; a check reads a blob or two.)"""
    for index in indices:
        hit = labels[inner] == index
        rows, cols = np.flatnonzero(hit.any(axis=1)), np.flatnonzero(hit.any(axis=0))
        stats[index, cv2.CC_STAT_TOP] = inner[0].start + rows[0]
        stats[index, cv2.CC_STAT_HEIGHT] = rows[-1] + 1 - rows[0]
        stats[index, cv2.CC_STAT_LEFT] = inner[1].start + cols[0]
        stats[index, cv2.CC_STAT_WIDTH] = cols[-1] + 1 - cols[0]


def _rods_among(objects: np.ndarray, search: np.ndarray, zones: _OutlineZones, part_in_place: bool) -> np.ndarray:
    """:func:`crossing_the_box` for one grouping of the pixels into blobs (``objects``)."""
    out = np.zeros(objects.shape, bool)
    apart, ring = apart_from_ring(objects, zones.ring)
    count, labels, inner = labelled_on_its_box(apart)
    if count <= 1:
        return out
    # a cheap first look: in the box and beyond it, and long (a blob of length L and thickness T has a
    # bounding box whose diagonal is about L and an area of L T); the extents are read for the large blobs that
    # cross the box's edge only
    stats = np.zeros((count, 5), np.int32)     # (cv2.connectedComponentsWithStats' layout, filled where read)
    stats[:, cv2.CC_STAT_AREA] = np.bincount(labels[inner].ravel(), minlength=count)
    area = stats[:, cv2.CC_STAT_AREA].astype(np.float64)
    in_box = np.bincount(labels[inner][search[inner]], minlength=count)
    candidates = (area >= 30) & (in_box > 0) & (in_box < area)
    candidates[0] = False
    _fill_extents(stats, labels, np.flatnonzero(candidates), inner)
    diagonal_2 = stats[:, cv2.CC_STAT_WIDTH].astype(np.float64) ** 2 + stats[:, cv2.CC_STAT_HEIGHT] ** 2.0
    candidates &= diagonal_2 >= ROD_MIN_ELONGATION * area
    if not candidates.any():
        return out
    at_part = zones.at_part
    h, w = objects.shape
    behind = []     # the lines of the rods that run on behind the part
    for index in np.flatnonzero(candidates):
        ys, xs = _blob_pixels(labels, stats, index)
        at_edge = (xs == 0) | (ys == 0) | (xs == w - 1) | (ys == h - 1)
        line = _rod_line(xs.astype(np.float64), ys.astype(np.float64), at_part[ys, xs], search[ys, xs],
                         part_in_place, at_edge)
        if line is None:
            continue
        centre, direction, normal, first, last, half_width, part_end = line
        if part_end:
            behind.append((centre, direction, normal, last if part_end > 0 else first, part_end, half_width))
        # the strip along the line, over the blob's length and the ring at its ends
        by0, by1, bx0, bx1 = max(0, ys.min() - 6), min(h, ys.max() + 7), max(0, xs.min() - 6), min(w, xs.max() + 7)
        gy, gx = np.mgrid[by0:by1, bx0:bx1]
        along = (gx - centre[0]) * direction[0] + (gy - centre[1]) * direction[1]
        across = (gx - centre[0]) * normal[0] + (gy - centre[1]) * normal[1]
        strip = (np.abs(across) <= half_width) & (along >= first - 6) & (along <= last + 6)
        out[by0:by1, bx0:bx1] |= strip & ((labels[by0:by1, bx0:bx1] == index) | ring[by0:by1, bx0:bx1])
    if behind:
        # (every large blob is read there: the extents not read yet)
        unread = (stats[:, cv2.CC_STAT_AREA] >= 30) & (stats[:, cv2.CC_STAT_WIDTH] == 0)
        unread[0] = False
        _fill_extents(stats, labels, np.flatnonzero(unread), inner)
        out |= _rods_come_out(labels, stats, at_part, behind) & ~out
    return out


def _blob_pixels(labels: np.ndarray, stats: np.ndarray, index: int) -> tuple[np.ndarray, np.ndarray]:
    """(ys, xs) of blob ``index`` of cv2.connectedComponentsWithStats' ``labels``, read within its bounding box."""
    x0, y0 = stats[index, cv2.CC_STAT_LEFT], stats[index, cv2.CC_STAT_TOP]
    x1, y1 = x0 + stats[index, cv2.CC_STAT_WIDTH], y0 + stats[index, cv2.CC_STAT_HEIGHT]
    ys, xs = np.nonzero(labels[y0:y1, x0:x1] == index)
    return ys + y0, xs + x0


def _rods_come_out(labels: np.ndarray, stats: np.ndarray, at_part: np.ndarray, behind: list) -> np.ndarray:
    """(h, w) bool: the pieces of rods that come out on the far side of the part. A rod that runs on behind
    the part shows again beyond it, where it may end inside the box (at the carriage, or its own end): a
    blob next to the part, wholly past the rod's end at the part, on the rod's line (ROD_REGULAR_SHARE of
    its pixels within the rod's strip). Only its pixels on the strip are returned."""
    out = np.zeros(labels.shape, bool)
    for index in range(1, len(stats)):
        if stats[index, cv2.CC_STAT_AREA] < 30:
            continue
        ys, xs = _blob_pixels(labels, stats, index)
        if not at_part[ys, xs].any():
            continue
        for origin, direction, normal, end, side, half_width in behind:
            along = (xs - origin[0]) * direction[0] + (ys - origin[1]) * direction[1]
            on_line = np.abs((xs - origin[0]) * normal[0] + (ys - origin[1]) * normal[1]) <= half_width
            if np.all(side * (along - end) > 0) and on_line.mean() >= ROD_REGULAR_SHARE:
                out[ys[on_line], xs[on_line]] = True
                break
    return out


def _rod_line(xs: np.ndarray, ys: np.ndarray, at_part: np.ndarray, in_box: np.ndarray, part_in_place: bool,
              at_edge: np.ndarray):
    """See :func:`crossing_the_box`: one blob's pixels (n,) with, per pixel, whether it is next to the
    part's outline zone, inside the search box and on the picture's edge -> (centre (2,), direction (2,),
    normal (2,), first, last, half width, part end) of the rod's strip in image coordinates, or None when the
    blob is no rod crossing the box; part end: 1 or -1 where the rod's last or first end runs on behind the
    part, else 0."""
    points = np.stack([xs, ys], axis=1)
    centre = points.mean(axis=0)
    _, vectors = np.linalg.eigh(np.cov((points - centre).T))
    direction, normal = vectors[:, 1], vectors[:, 0]
    along = (points - centre) @ direction
    across = (points - centre) @ normal
    bins = np.floor(along - along.min()).astype(np.int64)
    n = int(bins.max()) + 1
    order = np.argsort(bins, kind="stable")
    present, starts = np.unique(bins[order], return_index=True)
    low = np.full(n, np.inf)
    high = np.full(n, -np.inf)
    low[present] = np.minimum.reduceat(across[order], starts)
    high[present] = np.maximum.reduceat(across[order], starts)
    width = high - low + 1.0
    filled = np.isfinite(low)
    thickness = float(np.median(width[filled]))
    if n < ROD_MIN_ELONGATION * thickness:
        return None
    trim = int(np.ceil(0.5 * thickness))
    # (sections at the part are left out: the ring cut them, or the rod runs on behind the part there)
    inner = filled & ~(np.bincount(bins, weights=at_part.astype(np.float64), minlength=n) > 0)
    inner[:trim] = inner[n - trim:] = False
    if np.count_nonzero(inner) < 1.5 * thickness:
        return None
    positions = np.flatnonzero(inner).astype(np.float64)
    middle = 0.5 * (low[inner] + high[inner])
    slope, offset = np.polyfit(positions, middle, 1)
    straight = np.abs(middle - (slope * positions + offset)) <= max(1.5, 0.25 * thickness)
    even = (width[inner] >= 0.6 * thickness) & (width[inner] <= 1.6 * thickness)
    if (straight & even).mean() < ROD_REGULAR_SHARE:
        return None
    # the ends (a thickness long): beyond the box, or at the part (it runs on behind it)
    ends = []
    for selected in (bins < trim, bins >= n - trim):
        if in_box[selected].mean() <= 0.5:
            ends.append("beyond")
        elif at_part[selected].any():
            ends.append("part")
        else:
            return None
    if ends != ["beyond", "beyond"] and ("beyond" not in ends or not part_in_place):
        return None
    if "part" in ends:
        # seen at one end only, it must run on beyond the box for its thickness, or out of the picture: a strand
        # lying on the bed from the part's foot across the box's edge is no rod
        half = bins < n / 2 if ends[0] == "beyond" else bins >= n / 2
        if (np.count_nonzero(~in_box[half]) < ROD_BEYOND_THICKNESSES * thickness ** 2
                and not at_edge[half].any()):
            return None
    # the strip: the fitted line (straighten the axis by the fitted slope), as wide as the regular sections
    tilt = np.arctan(slope)
    direction, normal = (np.cos(tilt) * direction + np.sin(tilt) * normal,
                         -np.sin(tilt) * direction + np.cos(tilt) * normal)
    # a point on the fitted line: bin 0 (along = its minimum), across = the fitted offset, in the old axes
    origin = centre + along.min() * vectors[:, 1] + offset * vectors[:, 0]
    pixel_along = (points - origin) @ direction
    pixel_across = (points - origin) @ normal
    regular = np.zeros(n, bool)
    regular[np.flatnonzero(inner)[straight & even]] = True
    half_width = float(np.percentile(np.abs(pixel_across[regular[bins]]), 98)) + 1.0
    part_end = 1 if ends[1] == "part" else -1 if ends[0] == "part" else 0
    return origin, direction, normal, float(pixel_along.min()), float(pixel_along.max()), half_width, part_end


#: A blob is the mirror image of something above the search box when, at the best distance tried, this
#: share of its mirrored pixels (those in the frame and above the box) lands on something that is not in
#: the background frame.
MIRROR_MATCH_SHARE = 0.7
#: ... and at least this share of its pixels mirror into the frame, outside the search box.
MIRROR_MIN_SEEN = 0.5


def mirror_match(pixels: np.ndarray, camera, changed_at, search: np.ndarray, min_height: float = 0.0,
                 distances: int = 48, sample: int = 400) -> float:
    """Share of a blob's mirror image that lands on something new above the ``search`` box, at the best
    distance from the camera (or the first at or above MIRROR_MATCH_SHARE): high when the blob is the
    reflection, in a glossy bed, of an object hanging above it (the parked hotend). 0.0 when it cannot be one.

    ``pixels`` (n, 2) x, y of the blob in the image of ``camera`` (a core.camera.Camera: ``rays``,
    ``project``); ``changed_at(xs, ys)`` -> (m,) bool, whether the frame differs from the background
    frame at those integer pixels; ``search`` (h, w) bool, the part's search box (the object itself is
    never in front of the part). A mirror image in the bed plane z = 0 shows the point (x, y, -z) of an
    object point (x, y, z): each pixel's ray is followed below the bed to a vertical plane facing the
    camera at a trial distance, the point found there is mirrored up and projected; distances from where
    the rays meet the bed out to five times that are tried. The object hangs at ``min_height`` mm or
    higher (the nozzle is never below the part's top): a distance that puts the blob's nearest points
    (5th percentile) less deep below the bed is not tried. Material standing on the bed (a part, a tangle)
    mirrors onto whatever lies above it in the image, which rarely is new and of its mirrored shape; right
    at the foot of the hanging object it would, but its mirror image there starts at the bed (depth 0).
    """
    points = np.asarray(pixels, np.float64).reshape(-1, 2)
    if len(points) == 0:
        return 0.0
    if len(points) > sample:
        points = points[np.linspace(0, len(points) - 1, sample).astype(int)]
    origin, directions = camera.rays(points)
    if origin[2] <= 0 or not (directions[:, 2] < 0).all():
        return 0.0   # a ray that never meets the bed sees no reflection in it
    to_bed = -origin[2] / directions[:, 2]
    heading = directions[:, :2].mean(axis=0)
    heading /= max(float(np.linalg.norm(heading)), 1e-9)
    across = directions[:, :2] @ heading
    if not (across > 1e-6).all():
        return 0.0
    bed_distance = float(np.median(to_bed * across))
    h, w = search.shape
    best = 0.0
    for distance in bed_distance * np.geomspace(1.0, 5.0, distances):
        at = origin + directions * (distance / across)[:, None]
        below = at[:, 2] < 0   # only a point below the bed can be a mirror image
        if below.mean() < MIRROR_MIN_SEEN or np.percentile(-at[below, 2], 5) < min_height:
            continue
        mirrored = at[below] * np.array([1.0, 1.0, -1.0])
        projected = camera.project(mirrored)
        # a mirrored point behind the camera projects to NaN, one near its plane far out of int64's range:
        # never inside either way
        projected[~np.isfinite(projected).all(axis=1)] = -1.0
        image = np.round(np.clip(projected, -1.0, float(max(w, h)))).astype(np.int64)
        inside = (image[:, 0] >= 0) & (image[:, 0] < w) & (image[:, 1] >= 0) & (image[:, 1] < h)
        inside[inside] = ~search[image[inside, 1], image[inside, 0]]
        if inside.sum() < MIRROR_MIN_SEEN * len(points):
            continue
        best = max(best, float(np.mean(changed_at(image[inside, 0], image[inside, 1]))))
        if best >= MIRROR_MATCH_SHARE:
            break   # (enough to tell: the farther distances cost as much again)
    return best
