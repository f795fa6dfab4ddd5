"""A first look at a part standing in a brim of its own colour: the material is one disc, the part alone fits anywhere
inside it, and the outline went wherever the shift prior and the upper-outline tie-break put it (cross-check seed 38
``003_normal``: a small orange ring in a brim on kapton, all three views 9-14 px off at the first look, s0R failing ten
checks of a normal print on "missing" and "unexpected" material beside the outline; seed 45 ``046_spaghetti``: 6-12 px
off in all four views). Slicers lay the brim all round the part's foot, so the part *with* its brim fits the material
only where the part stands (``core.alignment.align_with_brim``, tried at the brim widths of ``ExpectedRegions.brims``);
the brim must be seen all round (``seen_all_round``): the part's mirror image in a glass bed below it, or a skirt line
around it, is no brim. A camera whose first look found a brim keeps finding the part by it at its later looks (within
its anchor's drift) until the part stands tall enough to freeze the anchor (``CameraState.brim_found``): the prior
pulled those outlines back across the brim 2 px a check (seed 20 ``038_spaghetti`` s2: (-9, -8) px, the true
calibration error, to (-5, -4) in two checks); a camera whose first look found none is left as it was.

Synthetic scenes (tests/vision/synthetic.py), seen from above: a square part painted flat in the filament's colour
(its rim no edge: the edges cannot tell either), standing 5 px left of and 4 px above where the calibration expects it,
with a brim 12 px wide in the same colour, or a skirt line, or a mirror image below it.
"""
from dataclasses import replace

import numpy as np
import pytest

from octoprint_printwatch.core.alignment import align_with_brim, seen_all_round
from octoprint_printwatch.core.masks import dilate, erode
from octoprint_printwatch.core.pipeline import CameraState
from octoprint_printwatch.core.shape_check import ShapeResult, check_shape

from .synthetic import Box, bed_texture, camera_effects, regions

EXPECTED = Box(130, 90, 180, 140)
TRUE_SHIFT = (-5, -4)
BRIM_PX = 12
BOUND = 14
FILAMENT = (60, 110, 230)
PART = EXPECTED.moved(*TRUE_SHIFT).mask()


def brim_zones(widths=(6, 12, 18)) -> tuple:
    """The bed around the expected footprint grown by each brim width (px here: the scene is a top view)."""
    return tuple(dilate(EXPECTED.mask(), w) for w in widths)


def look(extra: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(background, frame): the empty bed, and the part with ``extra`` ((h, w) bool) in the filament's colour."""
    bed = bed_texture()
    scene = bed.copy()
    scene[PART | extra] = FILAMENT
    return camera_effects(bed, seed=11), camera_effects(scene, seed=12)


def first_look(extra: np.ndarray, with_brims: bool) -> tuple[int, int]:
    background, frame = look(extra)
    expected = regions(EXPECTED, band_rows=50, max_shift=BOUND, tolerance=2)
    if with_brims:
        expected = replace(expected, brims=brim_zones())
    return check_shape("cam", background, frame, expected).shift_px


def off_by(shift) -> int:
    return max(abs(shift[0] - TRUE_SHIFT[0]), abs(shift[1] - TRUE_SHIFT[1]))


def test_a_first_look_finds_the_part_by_its_brim():
    brim = dilate(PART, BRIM_PX)
    # without the brim zones (the code before): the outline lies where the prior and the tie-break put it
    assert off_by(first_look(brim, with_brims=False)) >= 3
    assert off_by(first_look(brim, with_brims=True)) <= 1


@pytest.mark.parametrize("what", ["skirt line", "mirror image below", "skirt line and mirror image"])
def test_no_brim_is_taken_where_none_lies_all_round(what):
    ring = dilate(PART, BRIM_PX)
    skirt = ring & ~erode(ring, 2)
    mirror = np.roll(dilate(PART, 4), PART.any(axis=1).sum(), axis=0)   # a glossy bed's, a little blurred
    extra = {"skirt line": skirt, "mirror image below": mirror, "skirt line and mirror image": skirt | mirror}[what]
    # (the last fills most of a brim's ring, all but its upper sides: taken as a brim, the outline moved 6 px down)
    assert first_look(extra, with_brims=True) == first_look(extra, with_brims=False)


def test_align_with_brim_reads_the_shift_and_nothing_without_a_brim():
    expected = EXPECTED.mask()
    assert align_with_brim(dilate(PART, BRIM_PX), expected, list(brim_zones()), BOUND) == TRUE_SHIFT
    assert align_with_brim(PART, expected, list(brim_zones()), BOUND) is None


def test_seen_all_round_needs_every_side_of_the_ring():
    ring = dilate(PART, BRIM_PX) & ~PART
    assert seen_all_round(ring, ring)
    lower_half = ring.copy()
    lower_half[: (PART.nonzero()[0].mean()).astype(int)] = False
    assert not seen_all_round(lower_half, ring)


def test_a_later_look_keeps_its_anchor_whatever_the_brim():
    background, frame = look(dilate(PART, BRIM_PX))
    expected = replace(regions(EXPECTED, band_rows=50, max_shift=BOUND, tolerance=2), brims=brim_zones())
    result = check_shape("cam", background, frame, expected, anchor=(4, 4), max_drift=2,
                         last_observed=np.zeros(expected.silhouette.shape, bool))
    assert max(abs(result.shift_px[0] - 4), abs(result.shift_px[1] - 4)) <= 2


def passing(placed_by_brim: bool, shift=(-5, -4)) -> ShapeResult:
    return ShapeResult("cam", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 100, 1000, None, shift, 7.0, 50.0, passed=True,
                       placed_by_brim=placed_by_brim)


def test_a_camera_remembers_whether_the_look_that_laid_its_anchor_found_a_brim():
    found = CameraState()
    found.placed(passing(True), max_drift=2, tall=False)
    assert found.anchor == (-5, -4) and found.brim_found
    found.placed(passing(False, (-4, -4)), max_drift=2, tall=False)   # a later look: the first one's finding stays
    assert found.brim_found
    none = CameraState()
    none.placed(passing(False), max_drift=2, tall=False)
    none.placed(passing(True, (-4, -4)), max_drift=2, tall=False)
    assert not none.brim_found
