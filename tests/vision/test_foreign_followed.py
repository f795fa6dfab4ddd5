"""The parked hotend, followed into the search box (cross-check seed 6 ``013_normal``).

The hotend rises with every check, and so does the search box's top (the check height + 3 mm). From a
camera that sees the hotend hanging near it, the hotend's image first reaches in from above the box (not the
print's: masks.reaching_in_from_above), then, near the end of the print, lies inside the box whole, where
nothing in one frame tells it from material standing there. Two things keep it foreign:

* an object whose material lies where a foreign object's material was at the camera's previous check, and
  that keeps apart from the part's outline, is that object, a check's rise further on;
* for such a followed object, how far it reaches down towards the part's foot (where a part knocked over
  stands, and nothing is foreign) is read on its material, not on the "not confidently bed" pixels it is
  grouped with (the hotend's shadow and mirror image on the glass below it). Read afresh, the weak pixels
  still count: a tipped part in the bed's colour may be material only at its top (our detach_09).

Synthetic scenes (tests/vision/synthetic.py): the part fills rows 80-170, the search box starts at row 65.
"""
import numpy as np
import pytest

from octoprint_printwatch.core.masks import reaching_in_from_above
from octoprint_printwatch.core.shape_check import check_shape

from .synthetic import PART, Box, H, W, bed_texture, camera_effects, paint_part, regions

HOTEND = (235, 235, 240)


@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def with_hotend(image, box):
    out = image.copy()
    out[box.y0:box.y1, box.x0:box.x1] = HOTEND
    return out


def check(background, frame, **kw):
    return check_shape("cam", camera_effects(background, seed=11), camera_effects(frame), regions(), **kw)


def test_the_hotend_followed_into_the_search_box_is_not_extra_material(bed):
    # at the previous check the block reached in from above the box (rows 40-90; the box starts at row 65)
    before = check(bed, with_hotend(paint_part(bed, PART), Box(225, 40, 250, 90)))
    assert before.passed, before.reasons
    assert before.foreign_mask is not None and before.foreign_mask[60, 235]
    # a check later it hangs lower in this view, inside the box whole (rows 68-118, above the part's foot)
    frame = with_hotend(paint_part(bed, PART), Box(225, 68, 250, 118))
    alone = check(bed, frame)
    assert not alone.passed and alone.extra_pct > alone.threshold   # one frame alone cannot tell
    followed = check(bed, frame, foreign_before=before.foreign_mask)
    assert followed.passed, followed.reasons
    assert followed.extra_pct < 0.3 * followed.threshold


def test_material_elsewhere_in_the_box_still_counts_after_a_foreign_object(bed):
    before = check(bed, with_hotend(paint_part(bed, PART), Box(225, 40, 250, 90)))
    # a blob beside the part's other side, where no foreign object hung
    frame = with_hotend(paint_part(bed, PART), Box(70, 100, 100, 150))
    r = check(bed, frame, foreign_before=before.foreign_mask)
    assert not r.passed and r.extra_pct > r.threshold


def _scene():
    search = np.zeros((H, W), bool)
    search[65:220, 60:260] = True
    expected = PART.mask()
    block = Box(225, 30, 250, 100).mask()          # hangs from above the box: 35 of its 70 rows beyond it
    tail = np.zeros((H, W), bool)
    tail[100:165:2, 236:240] = True                # a sparse "not bed" trail down to the part's foot
    tail[100:165, 237] = True
    return search, expected, block, tail


def test_a_followed_object_reaches_the_parts_foot_only_with_its_material():
    search, expected, block, tail = _scene()
    objects = block | tail
    # grouped with its trail, the object reaches the part's lowest quarter (rows 147-170): a part knocked
    # over would stand there, so read afresh it is kept (also when told what is material: a part in the
    # bed's colour may be material only at its top) ...
    assert not reaching_in_from_above(objects, search, expected)[50, 235]
    assert not reaching_in_from_above(objects, search, expected, material=block)[50, 235]
    # ... but followed from the previous check, where it hung, its material (the block) ends far above the foot
    assert reaching_in_from_above(objects, search, expected, material=block, before=block)[50, 235]


def test_a_part_standing_on_the_bed_where_a_foreign_object_hung_is_not_foreign():
    search, expected, block, _ = _scene()
    # material from above the box down to the part's foot (a tall part knocked over leaning there)
    standing = Box(225, 60, 250, 168).mask()
    hung_there = Box(220, 30, 255, 170).mask()     # (wholly where a foreign object hung before)
    assert not reaching_in_from_above(standing, search, expected, material=standing, before=hung_there).any()
    # while the same object ending above the foot is followed
    hanging = Box(225, 70, 250, 120).mask()
    assert not reaching_in_from_above(hanging, search, expected, material=hanging).any()
    assert reaching_in_from_above(hanging, search, expected, material=hanging, before=block)[80, 235]


def test_a_piece_leaning_on_the_parts_outline_is_not_followed():
    # a part knocked over whose top rose above the box at the previous check (read as foreign there) and now
    # leans on the outline (cross-check seed 2 029_detach): it is the print's, however it was read before
    search, expected, _, _ = _scene()
    leaning = Box(150, 68, 215, 100).mask() & ~Box(108, 78, 212, 170).mask()   # (up to the outline's edge)
    hung_there = Box(140, 50, 225, 130).mask()
    assert not reaching_in_from_above(leaning, search, expected, material=leaning, before=hung_there).any()
    # the same piece 10 px clear of the outline would be followed
    apart = Box(150, 66, 215, 70).mask()
    assert reaching_in_from_above(apart, search, expected, material=apart, before=hung_there).all(where=apart)
