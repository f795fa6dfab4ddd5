"""Loose material (core/tangle.py) is measured against the previous look risen with the part.

A camera whose outline sits a few px below the part (an anchor a little off the part's true place) sees the
part's top standing above the outline at every check, by the same few px: what stood above the outline at the
last two looks, raised by the model's rise since, is where the part's top is now, and that is no new material
(cross-check seed 7 `007_normal`: 16-20 mm² at every check in one view of a pair, paused at check 3). Strands
draped over the part's side are still new, and so is a layer shift's overhang that stuck out at one look only
(seed 9 `031_layer_shift`: shifted just before the first check, caught by the new material at the second).
"""
from dataclasses import replace

import numpy as np

from octoprint_printwatch.core.shape_check import check_shape, risen_with_the_part
from octoprint_printwatch.core.masks import dilate
from octoprint_printwatch.core.tangle import TWO_VIEWS_MM2, new_material

from .synthetic import PART, Box, bed_texture, camera_effects, paint_part, regions
from .test_tangle import loops

PX_PER_MM = 4.0
RISE = 30                 # rows the model's top rises between two checks
ABOVE = 12                # rows the part's top stands above its outline (over 2 mm: 8 px)
BEFORE = Box(PART.x0, PART.y0 + RISE, PART.x1, PART.y1)          # the model at the previous check
OLDER = Box(PART.x0, PART.y0 + 2 * RISE, PART.x1, PART.y1)       # ... and at the one before


def above(box: Box) -> Box:
    """The part seen ABOVE rows taller than the model ``box``."""
    return Box(box.x0, box.y0 - ABOVE, box.x1, box.y1)


def test_what_stood_above_the_outline_at_two_looks_rises_with_the_models_top():
    seen = above(BEFORE).mask()
    older = (above(OLDER).mask(), OLDER.mask())
    risen = risen_with_the_part(seen, BEFORE.mask(), PART.mask(), 14, older, 2)
    # the ABOVE rows over the outline then, raised by the model's rise: now the ABOVE rows over the outline
    assert (risen == (above(PART).mask() & ~PART.mask())).all()
    # nothing rises without the older look, where it stood in place then (a layer shift's first layers), where
    # the model did not rise, or beside the outline (a brim, loops at the foot)
    assert not risen_with_the_part(seen, BEFORE.mask(), PART.mask(), 14, None, 2).any()
    in_place = (OLDER.mask(), OLDER.mask())
    assert not risen_with_the_part(seen, BEFORE.mask(), PART.mask(), 14, in_place, 2).any()
    assert not risen_with_the_part(seen, PART.mask(), PART.mask(), 14, older, 2).any()
    beside = np.zeros_like(seen)
    beside[150:168, 215:240] = True
    assert not risen_with_the_part(beside, BEFORE.mask(), PART.mask(), 14, older, 2).any()


def shape_of(bed, scene, previous, older):
    reg = replace(regions(max_shift=14), px_per_mm=PX_PER_MM, previous_silhouette=BEFORE.mask())
    # the outline kept where earlier checks anchored it (the part stands ABOVE px higher)
    return check_shape("cam", camera_effects(bed, seed=11), camera_effects(scene, seed=5), reg,
                       last_observed=previous, anchor=(0, 0), max_drift=0, older_looks=[(older, OLDER.mask())])


def test_a_top_standing_above_its_outline_at_every_check_is_no_new_material():
    bed = bed_texture()
    now = above(PART)
    previous, older = above(BEFORE).mask(), above(OLDER).mask()     # what the camera saw at the last two checks
    result = shape_of(bed, paint_part(bed, now), previous, older)
    assert result.new_outside is not None and result.new_outside.area_mm2 < 1.0   # HEAD: 32 mm²

    # strands hanging from the part's side are new all the same
    scene = paint_part(bed, now)
    strands = loops(count=10, thickness=3)
    strands[119:122, 206:240] = True
    scene[strands & ~now.mask()] = (40, 40, 210)
    assert shape_of(bed, scene, previous, older).new_outside.area_mm2 >= TWO_VIEWS_MM2
    # and so is a top that stuck out at the previous look only (the layers above a shift, printed since)
    assert shape_of(bed, paint_part(bed, now), previous, OLDER.mask()).new_outside.area_mm2 >= TWO_VIEWS_MM2


def test_material_the_parts_growth_explains_is_not_counted_but_still_attaches():
    # a blob beside the part joined to its outline only through the risen top (a part knocked over, seen from
    # above: seed `detach_03`'s cam1) is attached all the same; the risen top itself is not counted
    observed = PART.mask().copy()
    top = np.zeros_like(observed)
    top[PART.y0 - ABOVE:PART.y0, PART.x0:PART.x1] = True
    blob = np.zeros_like(observed)
    blob[PART.y0 - ABOVE:PART.y0 + 20, PART.x1 + 9:PART.x1 + 40] = True
    blob[PART.y0 - ABOVE:PART.y0 - ABOVE + 4, PART.x1 - 5:PART.x1 + 10] = True     # joined along the top
    observed |= top | blob
    previous = BEFORE.mask()
    whole = new_material(observed, previous, PART.mask(), np.ones_like(observed), 2.0, PX_PER_MM)
    explained = new_material(observed, previous, PART.mask(), np.ones_like(observed), 2.0, PX_PER_MM,
                             explained=top)
    assert whole.pixels > explained.pixels > 0.8 * np.count_nonzero(blob & ~dilate(PART.mask(), 8))
    assert not (explained.mask & top).any()
