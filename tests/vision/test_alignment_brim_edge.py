"""A first look at a part standing on a brim of its own colour, the frame saturated (one flat white from the part's
rim to the brim's edge, seed 15 ``004_normal`` s0: a light grey frame on black PEI): the only new edges are the
brim's own. The brim's outer edge is the part's rim grown outwards, so the outline laid on it fits only the sides it
slid towards, across the brim: 22 px off there, and the part's side beyond the outline read 37 % "unexpected
material" three checks later. A part's rim is an edge all round it: the outline goes onto the frame's edges only
where the sides it moved away from lie on edges too (``shape_check.outline_on_edges``, ``OUTLINE_TRAILING_SHARE``).

Synthetic masks: a square part 60 px wide on a brim 10 px wide (rounded corners, as an offset outline has), the part
3 px left of and 2 px below where the calibration expects it, a 30-px alignment bound, and the frame's new edges
(noise units) along the brim's outer edge, with or without the part's own rim.
"""
import cv2
import numpy as np

from octoprint_printwatch.core.masks import dilate, erode
from octoprint_printwatch.core.alignment import edges_by_side, outline_on_edges

from .synthetic import Box

EXPECTED = Box(130, 90, 190, 150)
TRUE_SHIFT = (-3, 2)
BRIM_PX = 10
BOUND = 30
BED_FACTOR = 2.5


def rim(mask: np.ndarray) -> np.ndarray:
    return mask & ~erode(mask, 1)


def scene(part_rim_seen: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(silhouette, observed material, new edges): the part and its brim where they stand."""
    silhouette = EXPECTED.mask()
    part = np.roll(np.roll(silhouette, TRUE_SHIFT[1], axis=0), TRUE_SHIFT[0], axis=1)
    brim = dilate(part, BRIM_PX)
    edges = np.random.default_rng(3).uniform(0.0, 1.0, silhouette.shape).astype(np.float32)   # the bed's grain
    edges[rim(brim)] = 20.0
    if part_rim_seen:
        edges[rim(part)] = 20.0
    return silhouette, brim, cv2.GaussianBlur(edges, (3, 3), 0)


def test_the_outline_stays_off_the_outer_edge_of_a_brim_in_the_parts_colour():
    silhouette, observed, edges = scene(part_rim_seen=False)
    # HEAD: (-13, 12), the outline's lower left corner on the brim's, 10 px off
    assert outline_on_edges(edges, silhouette, observed, silhouette, BOUND, TRUE_SHIFT, BED_FACTOR) is None


def test_the_outline_still_goes_onto_the_parts_rim_inside_its_brim():
    silhouette, observed, edges = scene(part_rim_seen=True)
    off = (TRUE_SHIFT[0] + 8, TRUE_SHIFT[1] - 8)     # where an upper-outline tie-break might have put it
    assert outline_on_edges(edges, silhouette, observed, silhouette, BOUND, off, BED_FACTOR) == TRUE_SHIFT


def test_edges_by_side_reads_the_sides_facing_a_move_apart_from_those_facing_away():
    silhouette = EXPECTED.mask()
    edges = np.zeros(silhouette.shape, np.float32)
    edges[:, EXPECTED.x1 - 1] = 10.0          # the right side only
    leading, trailing = edges_by_side(edges, silhouette, (0, 0), (5, 0))
    assert leading > 3.0 and trailing == 0.0
    leading, trailing = edges_by_side(edges, silhouette, (0, 0), (-5, 0))
    assert leading == 0.0 and trailing > 3.0
