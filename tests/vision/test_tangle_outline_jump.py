"""The new-material test (core/tangle.py) where a view's outline jumped between two checks.

The calibration error is the same at every check, so where a camera laid its outline at its previous check and
where it lays it now are two guesses at one place: the part may stand at either. Its newest band, new since then,
lies beyond this check's outline when the outline jumped away from the part, and is the part's own, not a strand.
Material is measured beyond both placements; loops beyond both still count.
"""
import numpy as np

from octoprint_printwatch.core.pipeline import CameraState
from octoprint_printwatch.core.shape_check import outline_jumped
from octoprint_printwatch.core.tangle import TWO_VIEWS_MM2, new_material

from .synthetic import H, PART, W, Box

PX_PER_MM = 4.0
TOL = 2.0
EVERYWHERE = np.ones((H, W), bool)
JUMP_PX = 12                                       # 3 mm at the part
OUTLINE_NOW = Box(PART.x0 + JUMP_PX, PART.y0, PART.x1 + JUMP_PX, PART.y1).mask()


def measure(observed, previous, **kw):
    return new_material(observed, previous, OUTLINE_NOW, EVERYWHERE, TOL, PX_PER_MM, **kw)


def test_the_newest_band_beyond_an_outline_that_jumped_is_the_parts():
    before = Box(PART.x0, PART.y0 + 30, PART.x1, PART.y1).mask()    # the part 30 rows shorter, where it stands
    now = PART.mask()                                                # grown by its newest band
    # against this check's outline alone, the band's edge the outline jumped away from reads as new material
    assert measure(now, before).area_mm2 >= TWO_VIEWS_MM2
    # the previous check laid the outline on the part: nothing new beyond either placement
    assert measure(now, before, placed_before=PART.mask()).area_mm2 == 0.0


def test_loops_beyond_both_placements_still_count():
    before = Box(PART.x0, PART.y0 + 30, PART.x1, PART.y1).mask()
    strand = Box(PART.x1 + JUMP_PX - 2, 118, PART.x1 + JUMP_PX + 40, 122).mask()   # from the side outward
    loops = Box(PART.x1 + JUMP_PX + 20, 100, PART.x1 + JUMP_PX + 40, 140).mask()
    now = PART.mask() | strand | loops
    alone = measure(now, before, placed_before=PART.mask())
    assert alone.area_mm2 >= TWO_VIEWS_MM2
    # (the band's edge beyond this check's outline is not among them)
    assert not alone.mask[:, :PART.x0 + JUMP_PX].any()


def test_no_jump_measures_as_before():
    before = Box(PART.x0, PART.y0 + 30, PART.x1, PART.y1).mask()
    now = PART.mask()
    assert (measure(now, before, placed_before=OUTLINE_NOW).area_mm2 == measure(now, before).area_mm2)


def test_a_camera_remembers_where_its_last_look_laid_the_outline():
    state = CameraState()
    mask = np.zeros((H, W), bool)
    state.saw(mask, 2.0, (3, -1))
    assert state.last_observed_shift == (3, -1)
    state.saw(mask, 4.0, (12, -3))
    assert state.last_observed_shift == (12, -3) and state.last_observed_z == 4.0


def test_only_a_jump_beyond_the_tolerance_is_a_jump():
    assert not outline_jumped(None, (3, 0), TOL)
    assert not outline_jumped((1, 1), (2, 2), TOL)            # jitter the tolerance ring absorbs
    assert not outline_jumped((3, -2), (2, 0), TOL)           # 2.2 px: the rings still overlap
    assert outline_jumped((1, -1), (10, -3), TOL)             # an outline laid 9 px away


def test_the_previous_placement_only_takes_material_away():
    # a dark object reaching down from above the search box to the part's side, through where the previous
    # check laid the outline: it stays the object it is (not the print's), however the placements differ
    search = Box(60, 40, 280, 200).mask()
    before = Box(PART.x0, PART.y0 + 30, PART.x1, PART.y1).mask()
    hotend = Box(PART.x0 - 14, 0, PART.x0 - 4, PART.y0 + 40).mask()
    loops = Box(PART.x1 + JUMP_PX + 2, 100, PART.x1 + JUMP_PX + 30, 140).mask()
    now = PART.mask() | hotend | loops
    for placed in (PART.mask(), Box(PART.x0 - 10, PART.y0, PART.x1 - 10, PART.y1).mask()):
        with_it = new_material(now, before, OUTLINE_NOW, search, TOL, PX_PER_MM, placed_before=placed)
        without = new_material(now, before, OUTLINE_NOW, search, TOL, PX_PER_MM)
        assert with_it.pixels <= without.pixels
        assert not (with_it.mask & ~without.mask).any()
