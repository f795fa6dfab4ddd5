"""Two cameras facing each other across the part confirm a layer shift as two directions do (eighteenth session,
helper b18): each sees the same bed move sideways, the opposite way in its image, and each camera's outline error
(calibration, alignment) is its own, so two of them agreeing on one bed shift is no offset of one view. Counted as one
direction (image x along one bed line) they needed one view's 0.85 (cross-check seed 15 `023`: s0 and s2 read the
4.4-mm shift at 0.84, 0.76, 0.78 and 0.87 over four checks and it was never called)."""
from octoprint_printwatch.core.layer_shift import confirms_layer_shift, estimate_layer_shift

from .synthetic import Box
from .test_layer_shift import BAND, BASE, J_ONE, view

# the camera on the other side: printer X runs the other way in its image
J_FACING = [[-5.0, 0.0], [0.0, 2.0]]


def partly_hidden(dx, J):
    """The band printed dx px sideways in one camera, a fifth of what the move changes neither material nor bed: about
    0.8 confirmed (under one view's 0.85)."""
    observed = BASE.mask() | BAND.moved(dx, 0).mask()
    x0, x1 = (211, 207 + dx) if dx > 0 else (113 + dx, 109)
    hidden = Box(x0, 84, x1, 104).mask()
    return view(observed & ~hidden, bed=~observed & ~hidden, J=J)


def test_a_shift_seen_by_two_cameras_facing_each_other_is_confirmed_as_from_two_directions():
    found = estimate_layer_shift({"a": partly_hidden(10, J_ONE), "b": partly_hidden(-10, J_FACING)})
    assert 0.75 <= found.confirmed < 0.85 and set(found.cameras) == {"a", "b"}
    assert found.viewpoints == 2
    assert confirms_layer_shift(found, 1.5)


def test_one_camera_alone_or_a_facing_camera_seeing_the_band_in_place_does_not_confirm_it():
    alone = estimate_layer_shift({"a": partly_hidden(10, J_ONE)})
    assert alone.viewpoints == 1 and not confirms_layer_shift(alone, 1.5)
    in_place = view(BASE.mask() | BAND.mask(), J=J_FACING)
    contradicted = estimate_layer_shift({"a": partly_hidden(10, J_ONE), "b": in_place})
    assert contradicted is None or not confirms_layer_shift(contradicted, 1.5)
