"""A part knocked off its place inside its skirt: the bed it leaves must read as missing material.

Seen on the second simulator (cross-check seed 4 ``025_detach``, seed 1 ``045_detach``: a part knocked off and
tipped over on black PEI): the skirt, thin and bright, and the fallen part close a ring around the empty
outline. Morphology fills holes the model also fills (a top face in the bed's colour seen within the part's
sides is the part), so the bed inside the ring was filled into the part: every core pixel "observed", 0 %
missing. A hole now stays filled only if material within the aligned outline closes it in too.
"""
from dataclasses import replace

import numpy as np

from octoprint_printwatch.core.shape_check import check_shape
from octoprint_printwatch.core.material import clean_mask, enclosed

from .synthetic import Box, bed_texture, camera_effects, regions

DARK_BED = (58, 60, 62)        # black PEI, a little grain
NEAR_WHITE = (236, 240, 240)
PART = Box(130, 70, 190, 130)  # a 60 x 60 px part, its surroundings searched 60 px around it
PALETTE = np.tile(np.array(NEAR_WHITE, np.float32), (5, 1)) * np.linspace(0.85, 1.0, 5)[:, None]


def skirt_ring(gap: int = 8, width: int = 2) -> np.ndarray:
    """(H, W) bool: a skirt line ``gap`` px outside PART, ``width`` px wide, all the way round."""
    outer = Box(PART.x0 - gap - width, PART.y0 - gap - width, PART.x1 + gap + width, PART.y1 + gap + width).mask()
    return outer & ~Box(PART.x0 - gap, PART.y0 - gap, PART.x1 + gap, PART.y1 + gap).mask()


def check(scene: np.ndarray, **kw):
    bed = bed_texture(seed=21, colour=DARK_BED, grain=4.0)
    ring_zone = Box(PART.x0 - 14, PART.y0 - 14, PART.x1 + 14, PART.y1 + 14).mask()   # the bed-marks zone
    reg = regions(PART, band_rows=15, max_shift=10, search_margin=60, dont_care=ring_zone)
    return check_shape("cam", camera_effects(bed, seed=31), camera_effects(scene, seed=32), reg, anchor=(0, 0),
                       previous_mask=PART.mask(), **kw)


def test_enclosed_finds_what_a_ring_closes_in_and_nothing_else():
    ring = skirt_ring()
    inside = enclosed(ring)
    assert inside[PART.mask()].all()
    assert not inside[ring].any()
    assert inside.sum() == (60 + 16) ** 2     # the ring's inner square, PART grown by the 8-px gap
    # clean_mask fills as before: the holes of what survives its opening (a 4-px ring does), where ``fill_like``
    filled = clean_mask(skirt_ring(width=4), fill_like=PART.mask())
    assert filled[PART.mask()].all() and not filled[skirt_ring(gap=3, width=3)].any()


def test_an_empty_outline_inside_its_skirt_reads_missing():
    # the part was knocked away (out of the search box); the skirt it was printed inside stays and closes a
    # ring round the place it stood: the bed seen there is not a face of the part in the bed's colour
    scene = bed_texture(seed=21, colour=DARK_BED, grain=4.0)
    scene[skirt_ring()] = NEAR_WHITE
    result = check(scene, palette=PALETTE)
    assert result.usable and not result.passed
    # all of the outline but its 2-px tolerance rim: (60 - 4)^2 of 60^2 px
    assert result.missing_pct > 0.9 * 100 * 56 * 56 / 3600
    assert result.extra_pct < 1.0   # the skirt lies flat in the bed-marks zone


def test_a_top_face_in_the_beds_colour_within_the_parts_sides_is_still_the_part():
    # the same skirt, but the part stands in it: its sides (a 6-px rim) close in its top face, which has the
    # bed's colour and texture; that face is the part, not bed where the part should be
    scene = bed_texture(seed=21, colour=DARK_BED, grain=4.0)
    scene[skirt_ring()] = NEAR_WHITE
    scene[PART.mask() & ~Box(PART.x0 + 6, PART.y0 + 6, PART.x1 - 6, PART.y1 - 6).mask()] = NEAR_WHITE
    result = check(scene)
    assert result.usable and result.passed
    assert result.missing_pct < 1.0


# A brim hugs the footprint, so the bed it closes in where a knocked-off part stood reaches the outline's foot; a top
# face lies the part's height above it (shape_check.holes_its_top_can_fill). Here the part is 20 mm tall at 1 px per
# mm of height, straight up the image: its footprint is PART's lowest 40 rows, its top face the highest 40.
LIFT = dict(height_to_image=np.array([0.0, -1.0]), height_mm=20.0)
FOOTPRINT = Box(PART.x0, PART.y0 + 20, PART.x1, PART.y1)


def brim_around_footprint(width: int = 10) -> np.ndarray:
    """(H, W) bool: a brim ``width`` px wide hugging FOOTPRINT."""
    f = FOOTPRINT
    return Box(f.x0 - width, f.y0 - width, f.x1 + width, f.y1 + width).mask() & ~f.mask()


def check_lifted(scene: np.ndarray):
    bed = bed_texture(seed=21, colour=DARK_BED, grain=4.0)
    brim_zone = Box(PART.x0 - 24, PART.y0 - 24, PART.x1 + 24, PART.y1 + 24).mask()   # the bed-marks zone
    reg = replace(regions(PART, band_rows=15, max_shift=10, search_margin=60, dont_care=brim_zone), **LIFT)
    return check_shape("cam", camera_effects(bed, seed=31), camera_effects(scene, seed=32), reg, anchor=(0, 0),
                       previous_mask=PART.mask(), palette=PALETTE)


def test_the_bed_a_brim_closes_in_where_the_part_stood_reads_missing():
    # the part knocked 20 px sideways, standing in the bed-marks zone, covers the outline's right two thirds; its
    # brim and it close in the bed where it stood, down to the outline's foot: no top face lies there
    scene = bed_texture(seed=21, colour=DARK_BED, grain=4.0)
    scene[brim_around_footprint()] = NEAR_WHITE
    scene[PART.moved(dx=20).mask()] = NEAR_WHITE
    result = check_lifted(scene)
    assert result.usable and not result.passed
    # the bed where the part stood reads missing (the footprint's uncovered columns, at least 16 of them over 30 of its
    # rows, with the outline's 2-px alignment and tolerance), not only the strip above the brim (3 % when it passed)
    assert result.missing_pct > 100 * 16 * 30 / 3600


def test_a_top_face_in_the_beds_colour_above_its_brim_is_still_the_part():
    # the part stands in its brim; its sides (a 6-px rim) close in its top face in the bed's colour and grain
    scene = bed_texture(seed=21, colour=DARK_BED, grain=4.0)
    scene[brim_around_footprint()] = NEAR_WHITE
    scene[PART.mask() & ~Box(PART.x0 + 6, PART.y0 + 6, PART.x1 - 6, PART.y0 + 34).mask()] = NEAR_WHITE
    result = check_lifted(scene)
    assert result.usable and result.passed
    assert result.missing_pct < 1.0
