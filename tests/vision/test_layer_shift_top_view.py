"""A layer shift along the line of sight of a camera looking down on a wide top, seen sideways by a low camera on
another side (cross-check seed 6 `055_layer_shift`, tenth session, helper M). The top view sees the newest
band's top rise by 9 px over a wide face (about a thousand pixels): alone that is also a part standing 3 mm
taller. The low view sees the band move a few pixels sideways along its short edges (about a hundred pixels, a
tenth of the pooled evidence), and sees its top where the model puts it: no part standing taller. Two things
hid the shift: the pooled null let the low view abstain on heights beyond its own (shorter) vertical reach, so
the top view's null stood alone; and the low view's tenth of the pixels did not make it a second side, so the
vertical move was not read at all."""
import numpy as np

from octoprint_printwatch.core.layer_shift import band_shift, confirms_layer_shift, estimate_layer_shift

from .synthetic import Box

# The top view: the part's top face (rows 100-200), the newest band reaching 9 rows above it.
TOP_BEFORE = Box(60, 100, 260, 200)
TOP_BAND = Box(60, 91, 260, 200)
# 4 px per mm of printer X sideways, printer Y up the image by 3 px per mm; a part 1 mm taller: 3 px up
J_TOP, H_TOP = [[4.0, 0.0], [0.0, -3.0]], [0.0, -3.0]
# The low view on another side (its image x follows printer X turned by ~150 degrees: one viewpoint, two sides):
# a wide, short side face and a band 16 px tall on it.
LOW_BEFORE = Box(60, 150, 240, 200)
LOW_BAND = Box(60, 134, 240, 150)
J_LOW, H_LOW = [[-4.0, 2.0], [0.5, 0.5]], [0.0, -3.0]
SHIFT_MM = (0.0, 3.0)        # along the top view's line of sight: (0, -9) px there, (6, 1.5) px in the low view


def _view(before: Box, band: Box, move, J, H, reach_y: int):
    observed = before.mask() | band.moved(*move).mask()
    return band_shift(observed, ~observed, before.mask(), band.mask(), 24, reach_y, 5, 2.0,
                      bed_to_image=J, height_to_image=H)


def views():
    # the low view is seen at its own smaller vertical reach (its image scale)
    return {"top": _view(TOP_BEFORE, TOP_BAND, (0, -9), J_TOP, H_TOP, 12),
            "low": _view(LOW_BEFORE, LOW_BAND, (6, 2), J_LOW, H_LOW, 6)}


def test_a_shift_along_a_top_views_line_of_sight_is_confirmed_by_a_low_view_on_another_side():
    both = views()
    top = both["top"]
    # alone, the top view's move is a part standing 3 mm taller, as well as a shift
    assert top.null_score >= 0.9 * top.support > 0
    assert not confirms_layer_shift(estimate_layer_shift({"top": top}), 1.5)
    found = estimate_layer_shift(both)
    assert found is not None and found.vertical and found.sides == 2
    assert np.allclose(found.shift_mm, SHIFT_MM, atol=0.5)
    # the low view sees the top in place: a part 3 mm taller would show there 9 px higher, beyond its reach (6 px)
    assert found.null_score < 0.5 * found.score
    assert confirms_layer_shift(found, 1.5)


def test_a_part_standing_taller_in_both_views_is_no_shift():
    taller = {"top": _view(TOP_BEFORE, TOP_BAND, (0, -9), J_TOP, H_TOP, 12),
              "low": _view(LOW_BEFORE, Box(60, 128, 240, 150), (0, 0), J_LOW, H_LOW, 6)}
    found = estimate_layer_shift(taller)
    assert found is None or not confirms_layer_shift(found, 1.5)
