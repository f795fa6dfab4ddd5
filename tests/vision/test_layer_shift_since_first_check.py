"""An offset of the newest band that every check since the first read already, from one direction only, is no
evidence of a layer shift: the first check's band is the whole part (untested), so nothing ever read the offset
absent, and one view's outline sitting off by a little more at every check (an alignment anchored on the brim
beside the part's foot) reads exactly like a shift printed in the first tested band. Cross-check seed 4
`045_detach` was paused at check 2, three checks before its onset, so: one camera read its band 9, 13, 16 px
beside the aligned model at checks 1-3 (0.76, then 0.93 of the evidence)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import (band_shift, confirms_layer_shift, estimate_layer_shift,
                                                   with_history)

from .synthetic import Box

BASE = Box(110, 110, 210, 170)        # the layers up to the previous check (seen from the side)
BAND = Box(110, 80, 210, 110)         # printed since
J_FRONT = [[5.0, 0.0], [0.0, -2.0]]   # image px per printer X / Y mm at the part
J_SIDE = [[0.0, 5.0], [2.0, 0.0]]     # a second camera, looking along printer X
MIN_DX = 8                            # 1.5 mm sideways


def view(band_moved_by: tuple[int, int] = (0, 0), J=J_FRONT):
    """One camera's band_shift: the older layers where expected, the band moved by ``band_moved_by`` px
    (everything not observed is confident bed)."""
    observed = BASE.mask() | BAND.moved(*band_moved_by).mask()
    return band_shift(observed, ~observed, BASE.mask(), BAND.mask(), 40, 20, MIN_DX, 2.0, bed_to_image=J,
                      height_to_image=[0.0, -2.0])


def test_one_view_off_since_the_first_check_is_not_called_a_layer_shift():
    first, second, now = {"cam": view()}, {"cam": view((11, 0))}, {"cam": view((12, 0))}
    found = with_history(estimate_layer_shift(now), [(False, first), (True, second)])
    # the band alone reads a clear shift from one direction, and the first tested check read it already
    assert found.viewpoints == 1 and found.confirmed > 0.9 and found.support >= 150
    assert found.back_to_first and found.before[0].confirmed > 0.5
    assert not confirms_layer_shift(found, 1.5)
    # a check later (three readings, all showing it): still not
    later = with_history(estimate_layer_shift(now), [(False, first), (True, second), (True, now)])
    assert not confirms_layer_shift(later, 1.5)


def test_the_same_views_are_a_layer_shift_when_a_check_read_the_band_in_place():
    first, in_place, now = {"cam": view()}, {"cam": view()}, {"cam": view((12, 0))}
    # new at this check: the previous check tested its band and read it where expected
    found = with_history(estimate_layer_shift(now), [(False, first), (True, in_place)])
    assert confirms_layer_shift(found, 1.5)
    # at the first tested check itself (nothing before it to read) the one-check rule decides
    assert confirms_layer_shift(with_history(estimate_layer_shift(now), [(False, first)]), 1.5)
    # when the history no longer reaches the first check, the offset is judged as before (was_there_before)
    old = with_history(estimate_layer_shift(now), [(True, in_place), (True, in_place), (True, in_place),
                                                    (True, {"cam": view((11, 0))})])
    assert not old.back_to_first and confirms_layer_shift(old, 1.5)


def test_two_directions_agreeing_since_the_first_check_are_still_a_layer_shift():
    # a shift printed in the first tested band, read from two directions: each view's outline error is its own,
    # one rigid move of the top seen by both is not (cross-check seed 1 `039_layer_shift`, called at check 2)
    shift_mm = np.array([2.4, 2.4])

    def views(scale: float) -> dict:
        out = {}
        for name, J in (("front", J_FRONT), ("side", J_SIDE)):
            dx, dy = np.rint(np.asarray(J) @ (scale * shift_mm)).astype(int)
            out[name] = view((int(dx), int(dy)), J)
        return out

    first = {"front": view(), "side": view(J=J_SIDE)}
    found = with_history(estimate_layer_shift(views(1.0)), [(False, first), (True, views(0.9))])
    assert found.viewpoints == 2 and found.back_to_first and found.before[0].confirmed > 0.5
    assert confirms_layer_shift(found, 1.5)
