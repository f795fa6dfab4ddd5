"""The layer-shift test on synthetic masks with known answers: per camera (every image shift of the
newest band at once) and pooled over cameras (one shift on the bed that every view must agree with)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import band_shift, confirms_layer_shift, estimate_layer_shift
from octoprint_printwatch.core.masks import shift_mask

from .synthetic import Box

BASE = Box(110, 110, 210, 170)        # the layers up to the previous check
BAND = Box(110, 80, 210, 110)         # printed since


def view(observed, *, bed=None, before=BASE.mask(), band=BAND.mask(), reach=24, min_dx=5, J=None):
    """band_shift of one synthetic camera; by default everything not observed is confidently bed."""
    return band_shift(observed, ~observed if bed is None else bed, before, band, reach, reach // 2, min_dx, 2.0,
                      bed_to_image=J)


def test_a_band_printed_sideways_is_found_with_its_shift():
    observed = BASE.mask() | BAND.moved(9, 0).mask()
    found = view(observed)
    assert (found.dx, found.dy) == (9, 0)
    assert found.confirmed > 0.9 and found.against < 0.05 * found.support


def test_a_part_as_expected_contradicts_every_sideways_shift():
    found = view(BASE.mask() | BAND.mask())
    assert found.confirmed < 0.2 and found.against > found.support


def test_a_part_standing_a_little_taller_is_not_a_shift():
    # a camera firing a layer late or a height calibration error: the top stands 4 px higher
    observed = BASE.mask() | Box(110, 76, 210, 110).mask()
    found = view(observed)
    assert found.null_dy < 0                       # explained by the vertical null hypothesis
    assert found.confirmed < 0.3


def test_a_top_face_the_colour_of_the_bed_neither_helps_nor_hurts():
    observed = BASE.mask() | BAND.moved(8, 0).mask()
    undecided = Box(125, 80, 200, 100).mask()        # the top face: neither material nor confident bed
    observed &= ~undecided
    found = view(observed, bed=~observed & ~undecided)
    assert found.dx == 8 and found.confirmed > 0.8


def test_the_cameras_agree_on_one_shift_on_the_bed():
    # two cameras looking from different sides: printer X shows sideways in the first, Y in the second
    J1, J2 = [[5.0, 0.0], [0.0, -2.0]], [[0.0, 5.0], [2.0, 0.0]]
    shift_mm = np.array([2.0, -3.0])
    views = {}
    for name, J in (("a", J1), ("b", J2)):
        dx, dy = np.rint(np.asarray(J) @ shift_mm).astype(int)
        views[name] = view(BASE.mask() | shift_mask(BAND.mask(), int(dx), int(dy)), J=J)
    found = estimate_layer_shift(views)
    assert np.allclose(found.shift_mm, shift_mm, atol=0.5)
    assert set(found.cameras) == {"a", "b"} and found.confirmed > 0.85
    assert confirms_layer_shift(found, 1.5)


def test_one_view_off_while_the_other_sees_the_band_in_place_is_contradicted():
    # an outline off in one view only (alignment, calibration) is no rigid move of the top of the part
    J1, J2 = [[5.0, 0.0], [0.0, -2.0]], [[5.0, 0.5], [0.0, -2.0]]
    off = view(BASE.mask() | BAND.moved(10, 0).mask(), J=J1)
    in_place = view(BASE.mask() | BAND.mask(), J=J2)
    alone = estimate_layer_shift({"a": off})
    together = estimate_layer_shift({"a": off, "b": in_place})
    assert confirms_layer_shift(alone, 1.5)
    assert not confirms_layer_shift(together, 1.5)


def test_a_small_shift_of_a_wide_part_is_found():
    # 6 px of a 240-px-wide band: a share of the band's area no area rule would ever reach
    base, band = Box(40, 110, 280, 170), Box(40, 80, 280, 110)
    found = view(base.mask() | band.moved(6, 0).mask(), before=base.mask(), band=band.mask())
    assert (found.dx, found.dy) == (6, 0) and found.confirmed > 0.8
