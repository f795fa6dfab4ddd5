"""A brim follows the part's own first layer, not its convex hull: slicers lay it as loops offset from the first
layer's outline, into a star's notches and an L's inner corner. The brim zones the first look fits the part with its
brim against (``core.alignment.align_with_brim``) were the footprint's hull grown by each width: around a star or an L
they claim bed the brim never covers, the brim's ring is not "seen all round" there, and the outline went where the
shift prior put it (cross-check seed 45 ``050_spaghetti``: a silver star in its brim, s0's first look 8.5 px off the
true calibration; its later looks read the part's newest layers "shifted" 3.8 mm and paused the print six checks before
its onset; seed 42 ``047_layer_shift``, a ring whose hole the hull's zones fill, 7.3 px off, paused a check before its
onset). ``core.pipeline.brim_zone`` grows the first layer itself (``JobPlan.brim_outline``, ``brim_outline_of``:
where it does not fill its hull; a box's or a cylinder's zones stay the footprint's).

Synthetic scene (tests/vision/synthetic.py), seen from above: an L-shaped part painted flat in the filament's colour,
standing 5 px left of and 4 px above where the calibration expects it, in a brim 12 px wide that follows its outline.
"""
from dataclasses import replace

import cv2
import numpy as np
import pytest
import trimesh

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.geometry import part_from_mesh
from octoprint_printwatch.core.masks import dilate
from octoprint_printwatch.core.pipeline import bed_marks_zone, brim_outline_of, brim_zone
from octoprint_printwatch.core.shape_check import check_shape

from .synthetic import Box, bed_texture, camera_effects, regions

# an L: a tall bar on the left and a foot to the right; the inner corner's bed is 60 px across
BAR, FOOT = Box(100, 60, 130, 170), Box(130, 140, 220, 170)
TRUE_SHIFT = (-5, -4)
BRIM_PX = 12
BOUND = 14
FILAMENT = (60, 110, 230)


def l_mask(dx: int = 0, dy: int = 0) -> np.ndarray:
    return BAR.moved(dx, dy).mask() | FOOT.moved(dx, dy).mask()


def hull_mask(mask: np.ndarray) -> np.ndarray:
    ys, xs = np.nonzero(mask)
    hull = cv2.convexHull(np.column_stack([xs, ys]).astype(np.int32))
    out = np.zeros(mask.shape, np.uint8)
    cv2.fillConvexPoly(out, hull, 1)
    return out.astype(bool)


def first_look_shift(zones: tuple) -> tuple[int, int]:
    part = l_mask(*TRUE_SHIFT)
    bed = bed_texture()
    scene = bed.copy()
    scene[dilate(part, BRIM_PX)] = FILAMENT
    background, frame = camera_effects(bed, seed=11), camera_effects(scene, seed=12)
    expected = l_mask()
    base = regions(Box(100, 60, 220, 170), band_rows=40, max_shift=BOUND, tolerance=2)
    looked = replace(base, silhouette=expected, new_band=expected & base.new_band, brims=zones)
    return check_shape("cam", background, frame, looked).shift_px


def off_by(shift) -> int:
    return max(abs(shift[0] - TRUE_SHIFT[0]), abs(shift[1] - TRUE_SHIFT[1]))


def test_a_first_look_finds_an_l_shaped_part_by_a_brim_that_follows_it():
    widths = (6, 12, 18)
    along_the_hull = tuple(dilate(hull_mask(l_mask()), w) for w in widths)
    along_the_part = tuple(dilate(l_mask(), w) for w in widths)
    # the hull's zones claim the inner corner's bed for the brim: no brim is taken, and the outline lies where the
    # shift prior puts it, across the brim (12 px off, as with no brim zones at all)
    assert off_by(first_look_shift(along_the_hull)) >= 8
    # (within the 2 px the brim's blurred edge leaves: it reads as material a little wider than the brim)
    assert off_by(first_look_shift(along_the_part)) <= 2


def test_the_brim_zone_follows_the_first_layer_into_its_inner_corner():
    # a camera straight above the bed (image x along printer x, image y against printer y), about 2.3 px per mm
    camera = Camera.look_at("top", (100, 100, 250), (100, 100.01, 0), width=400, height=300, hfov_deg=60)
    first_layer = [np.array([[80, 80], [120, 80], [120, 90], [90, 90], [90, 120], [80, 120]], float)]   # CCW
    hull = np.array([[80, 80], [120, 80], [120, 90], [90, 120], [80, 120]], float)
    zone, hull_zone = brim_zone(camera, first_layer, 3.0), bed_marks_zone(camera, hull, 3.0)

    def at(x, y) -> tuple[bool, bool]:
        u, v = np.round(camera.project(np.array([[x, y, 0.0]]))[0]).astype(int)
        return bool(zone[v, u]), bool(hull_zone[v, u])

    assert at(85, 100) == (True, True)       # on the part
    assert at(78, 100) == (True, True)       # 2 mm beside its outer edge: brim
    assert at(92, 92) == (True, True)        # 2 mm into the inner corner: brim
    assert at(100, 100) == (False, True)     # 10 mm into the inner corner: bed a brim never covers
    assert at(75, 100) == (False, False)     # 5 mm out: beyond a 3-mm brim


def test_the_brim_zone_leaves_a_rings_hole_bare_where_the_hull_fills_it():
    camera = Camera.look_at("top", (100, 100, 250), (100, 100.01, 0), width=400, height=300, hfov_deg=60)
    angles = np.linspace(0, 2 * np.pi, 64, endpoint=False)
    circle = np.column_stack([np.cos(angles), np.sin(angles)])
    ring = [100 + 20 * circle, 100 + 12 * circle[::-1]]          # outer CCW, hole CW: a ring 8 mm wide
    zone, hull_zone = brim_zone(camera, ring, 3.0), bed_marks_zone(camera, ring[0], 3.0)

    def at(x, y) -> tuple[bool, bool]:
        u, v = np.round(camera.project(np.array([[x, y, 0.0]]))[0]).astype(int)
        return bool(zone[v, u]), bool(hull_zone[v, u])

    assert at(116, 100) == (True, True)      # on the ring
    assert at(110, 100) == (True, True)      # 2 mm into the hole: brim
    assert at(100, 100) == (False, True)     # the hole's middle, 12 mm from the ring: bed a brim never covers
    # and the ring's first layer is kept as its brim outline: it covers under 95 % of its hull
    tube = trimesh.creation.annulus(r_min=12, r_max=20, height=10).apply_translation((100, 100, 5))
    contours = brim_outline_of(part_from_mesh(tube))
    assert len(contours) == 2


def test_only_a_first_layer_unlike_its_hull_has_brim_zones_of_its_own():
    def block(x0, y0, x1, y1):
        return trimesh.creation.box(bounds=[[x0, y0, 0.0], [x1, y1, 10.0]])

    # a box's and a cylinder's brims are their hull's: the zones stay the footprint's
    assert brim_outline_of(part_from_mesh(block(80, 80, 120, 120))) == []
    cylinder = trimesh.creation.cylinder(radius=8, height=10).apply_translation((100, 100, 5))
    assert brim_outline_of(part_from_mesh(cylinder)) == []
    # an L's brim reaches into its inner corner: the first layer's own contours
    l_shape = trimesh.boolean.union([block(80, 80, 120, 90), block(80, 80, 90, 120)], engine="manifold")
    contours = brim_outline_of(part_from_mesh(l_shape))
    assert len(contours) == 1 and np.ptp(contours[0], axis=0) == pytest.approx([40.0, 40.0], abs=0.01)
