"""A gantry rod near the camera can be thicker than a slim part's crop is wide (nineteenth session, helper a19). Cut
by the crop's edges at both ends, what the shape check sees of it is a slab barely longer than thick, which the rod
test (masks.crossing_the_box: ROD_MIN_ELONGATION, the regular sections) cannot tell from a lump of material, and it was
"unexpected material" (cross-check seed 16 `013_normal`: a 10-mm stack 60 mm tall, camera s3, a 60-px rod across a
120-px crop: 340-400 % extra at the last three checks, a normal print paused). Read in a band of the picture as wide as
the picture, the same rod is long and straight."""
import numpy as np

from octoprint_printwatch.core.masks import crossing_the_box
from octoprint_printwatch.core.shape_check import check_shape, cut_by_the_crop

from .synthetic import Box, bed_texture, camera_effects, paint_part, regions

PART = Box(150, 60, 162, 170)      # a slim column, 12 px wide
# the search box reaches 20 px beside it: the crop (search box + 12 px) is 76 px wide


def rod_painted(image: np.ndarray, box: Box) -> np.ndarray:
    """A light grey cylinder lying across the picture, lit from above."""
    out = image.astype(np.float32).copy()
    rows = np.arange(box.y0, box.y1)
    shade = 0.75 + 0.25 * np.sin(np.pi * (rows - box.y0) / (box.y1 - box.y0))
    out[box.y0:box.y1, max(box.x0, 0):box.x1] = (225.0 * shade)[:, None, None] * np.array([1.0, 0.97, 0.95])
    return np.clip(out, 0, 255).astype(np.uint8)


def scene(thing: Box):
    bed = bed_texture()
    frame = rod_painted(paint_part(bed, PART, colour=(200, 205, 210)), thing)
    return camera_effects(bed, seed=4), camera_effects(frame, seed=5)


def shape_of(thing: Box):
    """The check with ``thing`` in front of the part, after one that saw the part alone (its colours: sampled bed
    pixels of the part's colour stay out of the noise levels, as a rod of a light part's colour does)."""
    view = regions(PART, band_rows=20, search_margin=20)
    background, alone = scene(Box(0, 0, 0, 0))
    first = check_shape("cam", background, alone, view)
    assert first.passed and first.palette is not None
    _, frame = scene(thing)
    return check_shape("cam", background, frame, view, palette=first.palette, anchor=first.shift_px,
                       previous_mask=first.observed_mask)


def test_a_thick_rod_across_a_narrow_crop_is_the_gantry_not_extra_material():
    result = shape_of(Box(0, 120, 320, 160))     # 40 px thick, from one side of the picture to the other
    assert result.usable and result.extra_pct == 0.0 and result.passed


def test_in_the_crop_alone_the_rod_is_no_rod():
    # (what the check saw before: the rod's piece within the crop, left and right of the part, 76 px for 40)
    crop = np.zeros((240, 320), bool)
    crop[:, 118:194] = True
    rod = Box(0, 120, 320, 160).mask() & crop
    outline = Box(148, 58, 164, 172).mask()
    search = Box(130, 45, 182, 190).mask()
    objects = (rod & ~outline)[:, 118:194]
    assert cut_by_the_crop(objects | outline[:, 118:194], rod[:, 118:194] & search[:, 118:194]) == (True, False)
    assert not crossing_the_box(objects, search[:, 118:194], outline[:, 118:194]).any()


def test_a_slab_barely_wider_than_the_crop_is_still_extra_material():
    # cut by the crop's edges too, but in the whole picture as long as it is there: 90 px for 40, no rod
    result = shape_of(Box(111, 120, 201, 160))
    assert not result.passed and result.extra_pct > 7.0
