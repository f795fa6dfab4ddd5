"""A band read back where the camera's own earlier checks laid its outline is the outline's walk, not a layer shift
(nineteenth session, helper a19). A first look on a brim of the part's colour fits the outline equally well along the
brim; later checks, not yet frozen, move it up to 2 px a check towards the calibrated position (cross-check seed 17
`001_normal`, a cone on its brim seen by a stereo pair: s0L's outline went (-6, -4) -> (-4, -2) -> (-2, 0) -> (0, 0)).
The newest layers, printed on the part, stay where the first look saw it: against the walked outline they read as a
band moved by (-6, -4) px, 4.3 mm, from one direction, and paused the normal print twice."""
from octoprint_printwatch.core.layer_shift import band_shift, confirms_layer_shift, onto_earlier_places
from octoprint_printwatch.core.verdict import layer_shift_of

from .frustum_scene import BAND, BEFORE, HEIGHT, J, MIN_DX, frustum


def view(observed, aligned_at=(0, 0)):
    return {"cam": band_shift(observed, ~observed, BEFORE, BAND, 24, 12, MIN_DX, 2.0, bed_to_image=J,
                              height_to_image=HEIGHT, aligned_at=aligned_at)}


def band_8px_sideways():
    """The band 8 px to the right of the outline this check laid, after three checks that saw it in place."""
    in_place = view(BEFORE | BAND)
    return layer_shift_of({}, [(False, in_place), (True, in_place), (True, in_place)],
                          view(BEFORE | frustum(80, 140, 30, dx=8)))


def test_a_band_moved_where_no_earlier_outline_lay_is_a_layer_shift():
    found = band_8px_sideways()
    assert confirms_layer_shift(found, 1.5)
    # the outline stood still, or walked the other way, or by less than the move
    for earlier in ([(0, 0)], [(1, 0), (0, 0)], [(-8, 0), (-4, 0), (0, 0)], [(4, 0), (2, 0), (0, 0)]):
        assert not onto_earlier_places(found, {"cam": ((0, 0), earlier)})
    # a camera it shows to whose places are unknown (no passing check yet) vouches for it
    assert not onto_earlier_places(found, {})


def test_a_band_moved_back_onto_an_earlier_outline_is_the_outline_walking():
    found = band_8px_sideways()
    dx, dy = found.cameras["cam"]
    assert abs(dx - 8) <= 1 and abs(dy) <= 1
    # the first looks laid the outline 8 px to the right; it walked 2 px a check to where it lies now
    assert onto_earlier_places(found, {"cam": ((0, 0), [(8, 0), (6, 0), (4, 0), (2, 0), (0, 0)])})
    # ... also where this check's outline lies off the calibrated position
    assert onto_earlier_places(found, {"cam": ((-3, 2), [(5, 2), (-3, 2)])})
    found.onto_earlier_places = True
    assert not confirms_layer_shift(found, 1.5)
    assert found.figures()["onto_earlier_places"] is True


def test_the_pooled_shift_reads_the_walk_from_each_cameras_earlier_places():
    in_place = view(BEFORE | BAND)
    history = [(False, in_place), (True, in_place), (True, in_place)]
    now = view(BEFORE | frustum(80, 140, 30, dx=8))
    walked = layer_shift_of({}, history, now, placed_at={"cam": [(8, 0), (6, 0), (4, 0), (2, 0), (0, 0)]})
    assert walked.onto_earlier_places and not confirms_layer_shift(walked, 1.5)
    stood_still = layer_shift_of({}, history, now, placed_at={"cam": [(0, 0)]})
    assert not stood_still.onto_earlier_places and confirms_layer_shift(stood_still, 1.5)
