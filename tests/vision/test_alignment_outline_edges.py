"""A first look at a part inside a brim of its own colour (a top view): the material covers the whole brim, so the
overlap fits the outline equally well anywhere on it, and which shift wins was noise (default set's
``normal_05_twisted_vase_orange_on_gold_top``: the first look anchored at (-15, 3), (-15, 13), (0, 9) or (-16, 6) px
unperturbed and under webcam noise, sharpening and a colour cast, the true calibration error being (-1, -4); under
noise the twisted part read 9.5-13.4 % "part displaced" at its last checks). The part's rim is an edge of the frame
the background frame has not: a look without an anchor lays the outline on it where it is distinct
(``shape_check.outline_on_edges``).

Synthetic scene (tests/vision/synthetic.py): a brim 20 px wider than the part on every side, in the part's colour,
and the part in a darker shade of it, standing 6 px left of and 4 px below where the calibration expects it.
"""
import numpy as np
import pytest

from octoprint_printwatch.core.shape_check import check_shape

from .synthetic import Box, bed_texture, camera_effects, regions

EXPECTED = Box(130, 90, 190, 150)
TRUE_SHIFT = (-6, 4)
BRIM = Box(EXPECTED.x0 - 20, EXPECTED.y0 - 20, EXPECTED.x1 + 20, EXPECTED.y1 + 20).moved(*TRUE_SHIFT)


def flat(image: np.ndarray, box: Box, colour) -> np.ndarray:
    """``image`` with ``box`` painted in one colour (seen from above: a brim and a top face, no layer lines)."""
    out = image.copy()
    out[box.mask()] = colour
    return out


@pytest.fixture(scope="module")
def scene():
    bed = bed_texture()
    background = camera_effects(bed, seed=11)
    part = flat(flat(bed, BRIM, (60, 110, 230)), EXPECTED.moved(*TRUE_SHIFT), (30, 55, 115))
    frame = camera_effects(part, noise=4.0)   # sensor noise of sigma 4 grey levels, as in bench_perturb's noise4
    return background, frame


def test_a_first_look_lays_the_outline_on_the_parts_rim_inside_its_brim(scene):
    background, frame = scene
    result = check_shape("cam", background, frame, regions(EXPECTED, band_rows=60, max_shift=15, tolerance=2))
    # HEAD: (0, 0), the smallest move among the shifts the brim fits equally well
    assert abs(result.shift_px[0] - TRUE_SHIFT[0]) <= 1 and abs(result.shift_px[1] - TRUE_SHIFT[1]) <= 1, \
        result.shift_px


def test_the_shifts_left_to_tell_apart_are_those_by_the_rim(scene):
    background, frame = scene
    result = check_shape("cam", background, frame, regions(EXPECTED, band_rows=60, max_shift=15, tolerance=2),
                         track_candidates=True)
    assert result.shift_candidates is not None and len(result.shift_candidates)
    assert (abs(result.shift_candidates - TRUE_SHIFT).max(axis=1) <= 2).all(), result.shift_candidates
