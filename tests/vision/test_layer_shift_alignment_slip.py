"""Earlier checks refute a height error only where they saw the top: against their own outline. When a camera's
alignment has moved since (cross-check seed 13 `027_layer_shift`: one camera, its anchor pulled 7 px up onto the
part's reflection at one check; seed 13 `024_runout`: an outline walking 2 px a check down a brim of the part's
colour), the same top in the image stands that many pixels lower or higher against this check's outline. A top seen
in place by the earlier outlines, and lower only against an outline that slipped up since, is the outline's move,
which the height null explains; read against this check's outline, the earlier checks "refuted" it and the slip
paused both prints before their onset as a layer shift along the line of sight."""
import numpy as np

from octoprint_printwatch.core.layer_shift import band_shift, confirms_layer_shift
from octoprint_printwatch.core.verdict import layer_shift_of

from .frustum_scene import BAND, BEFORE, HEIGHT, J, MIN_DX, frustum


def view(observed: np.ndarray, aligned_at=(0, 0)):
    """One camera's reading, its masks laid at the alignment ``aligned_at`` (the observed mask in its frame)."""
    return {"cam": band_shift(observed, ~observed, BEFORE, BAND, 24, 12, MIN_DX, 2.0, bed_to_image=J,
                              height_to_image=HEIGHT, aligned_at=aligned_at)}


# the band's top 8 px lower (and 6 px sideways) against the outline this check aligned
TOP_LOWER = BEFORE | frustum(80, 140, 30, dx=6, dy=8)


def reading_with_outline_at(dy: int):
    """The layer shift read at this check, its outline laid at (3, dy), after three checks that saw the part in
    place against their own outline at (3, 1) (the first of them a first look)."""
    earlier = view(BEFORE | BAND, aligned_at=(3, 1))
    return layer_shift_of({}, [(False, earlier), (True, earlier), (True, earlier)], view(TOP_LOWER, aligned_at=(3, dy)))


def test_checks_that_saw_the_top_in_place_against_the_same_outline_refute_a_lower_top():
    found = reading_with_outline_at(1)
    assert found.null_score < 0.25 * found.score
    assert confirms_layer_shift(found, 1.5)


def test_an_outline_that_slipped_up_since_explains_the_lower_top():
    # this check's outline lies 8 px above the earlier checks' (aligned_at dy 1 -> -7): the top they saw in place
    # is where it is seen now, 8 px below this outline's top
    found = reading_with_outline_at(-7)
    assert found is None or found.null_score > 0.5 * found.score
    assert found is None or not confirms_layer_shift(found, 1.5)


def test_an_outline_that_slipped_down_since_leaves_the_top_lower_still():
    # this check's outline lies 2 px below the earlier checks' (aligned_at dy 1 -> 3): the top stands 10 px lower
    # than where they saw it, which they refute all the more
    found = reading_with_outline_at(3)
    assert found.null_score < 0.25 * found.score
    assert confirms_layer_shift(found, 1.5)
