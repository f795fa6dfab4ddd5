"""A layer shift along the cameras' lines of sight: it moves the newest band up or down in the image, which in
one view is also what a part standing a little taller or lower shows. Cameras on opposite sides see the top
move opposite ways, while one height error moves it the same way in every view (seventh session, helper N)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import band_shift, confirms_layer_shift, estimate_layer_shift

from .synthetic import Box

# the part as expected at the previous check, its top face seen from above (rows 100-110), and the band since
BEFORE = Box(110, 100, 210, 170)
BAND = Box(110, 80, 210, 110)
# Two cameras looking along printer Y from opposite sides, 4 px per mm sideways (printer X), 3 px per mm of Y
# vertically: a move away from a camera rises in its image. A part standing 1 mm taller: 3 px up in both.
J_FRONT, J_BACK = [[4.0, 0.0], [0.0, -3.0]], [[-4.0, 0.0], [0.0, 3.0]]
HEIGHT = [0.0, -3.0]
MIN_DX = 6          # 1.5 mm sideways


def view(top_row: int, J) -> "band_shift":
    """One camera's band_shift when it sees the band's top at ``top_row`` (expected: 80); the band sits on the
    part below, so it reaches down into what was there before."""
    observed = BEFORE.mask() | Box(110, top_row, 210, 110 + top_row - 80).mask()
    return band_shift(observed, ~observed, BEFORE.mask(), BAND.mask(), 24, 12, MIN_DX, 2.0,
                      bed_to_image=J, height_to_image=HEIGHT)


def test_a_shift_along_both_lines_of_sight_is_found_from_the_opposite_vertical_moves():
    # 2.7 mm towards the back: 8 px up in the front camera's image, 8 px down in the back camera's
    views = {"front": view(72, J_FRONT), "back": view(88, J_BACK)}
    for one in views.values():
        # each view alone: the top moved 8 px, which a part 2.7 mm taller or shorter explains as well
        assert one.null_score >= 0.9 * one.support > 0
    found = estimate_layer_shift(views)
    assert found is not None and np.allclose(found.shift_mm, [0.0, 2.67], atol=0.3)
    # no one height explains both views (each may sit a pixel off it: its calibration residual)
    assert found.null_score < 0.25 * found.support
    assert confirms_layer_shift(found, 1.5)
    assert not confirms_layer_shift(estimate_layer_shift({"front": views["front"]}), 1.5)


def test_a_part_standing_taller_in_every_view_is_no_shift_along_the_lines_of_sight():
    views = {"front": view(72, J_FRONT), "back": view(72, J_BACK)}
    found = estimate_layer_shift(views)
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_from_one_side_only_the_sideways_move_counts():
    # The band 8 px lower and 2 px sideways in the only camera (and in a second one beside it): one side
    # cannot tell a band moved along its line of sight from a part standing lower, or from its own
    # calibration error (three times the stated error paused a normal print on the cross-check).
    observed = BEFORE.mask() | BAND.moved(2, 8).mask()
    one = band_shift(observed, ~observed, BEFORE.mask(), BAND.mask(), 24, 12, MIN_DX, 2.0,
                     bed_to_image=J_FRONT, height_to_image=HEIGHT)
    for views in ({"front": one}, {"front": one, "beside": one}):
        found = estimate_layer_shift(views)
        assert found is None or (not found.vertical and not confirms_layer_shift(found, 1.5))
    # from two sides the same move is read in full
    other = band_shift(BEFORE.mask() | BAND.moved(-2, -8).mask(), ~(BEFORE.mask() | BAND.moved(-2, -8).mask()),
                       BEFORE.mask(), BAND.mask(), 24, 12, MIN_DX, 2.0, bed_to_image=J_BACK, height_to_image=HEIGHT)
    both = estimate_layer_shift({"front": one, "back": other})
    assert both is not None and both.vertical and both.sides == 2
