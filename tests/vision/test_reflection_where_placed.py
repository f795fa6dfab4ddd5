"""The part's mirror image in a glossy bed lies below where the part stands, not below a walked outline.

A short part over its own mirror image in a glass bed is one blob taller than the outline: the overlap is flat
along it, and the alignment's prior walks an anchored outline a few px per check off the part (cross-check seed 5
`019_normal`: s0 placed at (3, 6), (1, 7), (0, 5), then (0, 3); true (1, 10)). The reflection zone, moved with the
outline, then ends above the mirror image's foot: the part's side below the outline and its mirror image lie 69 %
in it (under the 80 % that makes a blob a reflection) and read 88.7 % extra, decisive from one camera. The camera's
calibration error is the same at every check, so where its passing checks placed the outline is as likely as where
this one does: the reflection zone covers those places too.
"""
from dataclasses import replace

import numpy as np

from octoprint_printwatch.core.masks import shift_mask, shifted_union
from octoprint_printwatch.core.shape_check import check_shape

from .synthetic import PART, Box, bed_texture, camera_effects, paint_part, regions

WALK = 8                  # px the outline walked up off the part's foot since an earlier passing check


def test_shifted_union_is_the_union_of_the_shifts():
    rng = np.random.default_rng(0)
    mask = rng.random((30, 40)) < 0.05
    shifts = np.array([[3, -7], [0, 0], [-5, 2]])
    union = shift_mask(mask, 3, -7) | mask | shift_mask(mask, -5, 2)
    assert (shifted_union(mask, shifts) == union).all()
    assert not shifted_union(mask, np.zeros((0, 2), int)).any()


def shape_of(mirror_rows: int, placed_at=()):
    """The part stands WALK px lower than its outline (its foot below the outline's), its mirror image below."""
    bed = bed_texture()
    foot = PART.y1 + WALK
    frame = paint_part(bed, Box(PART.x0, PART.y0, PART.x1, foot))
    frame = paint_part(frame, Box(PART.x0, foot, PART.x1, foot + mirror_rows), colour=(30, 30, 150), seed=2)
    # the model's mirror image at the stated calibration: the footprint below the outline's foot, 18 rows deep
    reflection = np.zeros(PART.mask().shape, bool)
    reflection[PART.y1:PART.y1 + 18, PART.x0 - 2:PART.x1 + 2] = True
    reg = replace(regions(max_shift=25), reflection=reflection)
    return check_shape("cam", camera_effects(bed, seed=11), camera_effects(frame, seed=5), reg,
                       anchor=(0, 0), max_drift=0, placed_at=placed_at)


def test_a_mirror_image_below_where_an_earlier_check_placed_the_part_is_no_extra_material():
    walked = shape_of(16)
    assert walked.shift_px == (0, 0)
    assert walked.extra_pct > 7.0            # 8 rows of side + 16 of mirror image, 75 % in the zone
    placed = shape_of(16, placed_at=[(0, WALK), (0, WALK // 2)])
    assert placed.shift_px == (0, 0) and placed.extra_pct == 0.0 and placed.passed


def test_material_reaching_beyond_every_place_still_counts():
    # something far longer than the part's mirror image (strands, a part knocked over) still counts
    beyond = shape_of(36, placed_at=[(0, WALK)])
    assert beyond.extra_pct > 7.0
