"""A layer shift along the lines of sight of cameras on opposite sides of the part (cross-check seed 8
`055_layer_shift`, eleventh session, helper T). The near side's views see the newest band's top rise by 9 px over
a wide face: a part standing 3 mm taller explains that as well as the shift does, and those views change ten times
the pixels the far side's do. The far side sees the band's top *lower* by 5 px (its top rows show bed), which no
height error explains (a taller part raises the top in every view). Pooled, the shift scored 1,371 against a null of
1,083: the near side's evidence counts for both, so "twice the null" could never be met, though the far side on its
own confirms the shift (184 of 208 changed pixels) and the height error explains nothing there."""
import numpy as np

from octoprint_printwatch.core.layer_shift import (band_shift, beats_null_apart, confirms_layer_shift,
                                                   estimate_layer_shift)

from .synthetic import Box

# The near view: the part's top face (rows 100-200), the newest band reaching 9 rows above it;
# printer Y moves up its image by 3 px per mm, a part 1 mm taller by 3 px.
NEAR_BEFORE = Box(60, 100, 260, 200)
NEAR_BAND = Box(60, 91, 260, 200)
J_NEAR, H_NEAR = [[4.0, 0.0], [0.0, -3.0]], [0.0, -3.0]
# The far view on the opposite side (image x follows printer X the other way): the part seen smaller, printer Y
# moves *down* its image by 1.7 px per mm, a part 1 mm taller up by 1.5 px.
FAR_BEFORE = Box(100, 150, 160, 200)
FAR_BAND = Box(100, 140, 160, 150)
J_FAR, H_FAR = [[-2.0, 0.0], [0.0, 5.0 / 3.0]], [0.0, -1.5]
SHIFT_MM = (0.0, 3.0)        # the near view: (0, -9) px; the far view: (0, +5) px


def _view(before: Box, band: Box, move, J, H, reach_x: int, reach_y: int, min_dx: int):
    observed = before.mask() | band.moved(*move).mask()
    return band_shift(observed, ~observed, before.mask(), band.mask(), reach_x, reach_y, min_dx, 2.0,
                      bed_to_image=J, height_to_image=H)


def near(move=(0, -9)):
    return _view(NEAR_BEFORE, NEAR_BAND, move, J_NEAR, H_NEAR, 24, 12, 6)


def test_a_shift_along_opposite_sides_lines_of_sight_is_confirmed_by_the_far_side():
    far = _view(FAR_BEFORE, FAR_BAND, (0, 5), J_FAR, H_FAR, 12, 6, 3)
    found = estimate_layer_shift({"near": near(), "far": far})
    assert found is not None and found.vertical and found.sides == 2
    assert np.allclose(found.shift_mm, SHIFT_MM, atol=0.5)
    # the near view's rise is a taller part as well: the pooled null is most of the score (HEAD: not confirmed)
    assert found.null_score > 0.5 * found.score > 0
    # ... but on the far side the shift is confirmed and the height error explains nothing there
    support, against, moved, null = found.side_apart
    assert support >= 0.75 * moved and null <= 0
    assert beats_null_apart(found)
    assert confirms_layer_shift(found, 1.5)


def test_a_part_standing_taller_in_both_views_is_no_shift():
    # the far view sees its top raised (about 4.5 px for 3 mm), as a taller part shows it
    far = _view(FAR_BEFORE, Box(100, 135, 160, 150), (0, 0), J_FAR, H_FAR, 12, 6, 3)
    found = estimate_layer_shift({"near": near(), "far": far})
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_the_far_side_seeing_the_band_in_place_does_not_confirm():
    far = _view(FAR_BEFORE, FAR_BAND, (0, 0), J_FAR, H_FAR, 12, 6, 3)
    found = estimate_layer_shift({"near": near(), "far": far})
    assert found is None or not confirms_layer_shift(found, 1.5)
