"""A view whose anchor would follow the shift its newest band reads, on a part that rose, keeps it (cross-check
seed 18 `043_layer_shift`: a box, one of three views looking steeply down, the shift 9.6 px along its image y; at the
onset check its band read the shift at 0.73 on its own with the part risen 144 %, and the check moved its anchor 8 px
along the shift, to a shift it could not tell apart: from the next check on the outline sat on the shifted top, the
shifted layers read in place and the camera contradicted the shift)."""
import numpy as np

from octoprint_printwatch.core.layer_shift import BandShift
from octoprint_printwatch.core.pipeline import CameraState, follows_the_shifted_top, top_may_have_shifted
from octoprint_printwatch.core.shape_check import ShapeResult

EARLIER = np.array([[dx, dy] for dx in range(-3, 0) for dy in range(-10, 1)])
# the shifts the onset check could not tell apart: the overlap follows the shifted top (image y)
ONTO_THE_TOP = np.array([[-2, -8], [-1, -9], [-1, -10], [-2, -10]])

SHIFTED = BandShift(dx=5, dy=-7, support=98, against=37, moved=135)
SHIFTED_AWAY = BandShift(dx=-5, dy=7, support=98, against=37, moved=135)   # the band read the other way
IN_PLACE = BandShift(dx=5, dy=1, support=0, against=40, moved=40)
FEW_PIXELS = BandShift(dx=3, dy=-4, support=8, against=4, moved=12)    # most of a dozen pixels: no reading


def passing(band: BandShift | None, growth_pct: float | None = 144.0) -> ShapeResult:
    return ShapeResult("cam", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 100, 1000, growth_pct, (-4, -2), 7.0, 50.0,
                       passed=True, band_shift=band, shift_candidates=ONTO_THE_TOP, best_candidate=(-1, -10))


def state() -> CameraState:
    return CameraState(anchor=(-2, 0), shift_candidates=EARLIER, placed_at=[(-2, 0)])


def test_a_band_read_shifted_on_a_part_that_rose_is_told_from_the_others():
    assert top_may_have_shifted(passing(SHIFTED))
    assert not any(top_may_have_shifted(passing(band)) for band in (IN_PLACE, FEW_PIXELS, None))
    # strands or a stalled top read as a shifted band do not rise (cross-check seed 21 `054_spaghetti`: 30-38 %)
    assert not top_may_have_shifted(passing(SHIFTED, 30.0)) and not top_may_have_shifted(passing(SHIFTED, None))


def test_only_an_anchor_moving_along_the_band_s_shift_follows_the_shifted_top():
    assert follows_the_shifted_top((-2, 0), (-2, -8), passing(SHIFTED))
    # (cross-check seed 13 `042_spaghetti`: strands read as a band shifted left and up while the outline moved right
    # and down, as it had walked since the first check)
    assert not follows_the_shifted_top((-2, 0), (-2, -8), passing(SHIFTED_AWAY))
    assert not follows_the_shifted_top((-2, 0), (-2, 0), passing(SHIFTED))
    assert not follows_the_shifted_top(None, (-2, -8), passing(SHIFTED))


def test_a_view_whose_anchor_would_follow_the_shifted_top_keeps_it():
    camera = state()
    camera.placed(passing(SHIFTED), max_drift=2, tall=True)
    assert camera.anchor == (-2, 0) and not camera.frozen
    assert camera.placed_at == [(-2, 0), (-4, -2)]   # (where the outline was laid, for the walked-outline rule)


def test_any_other_passing_view_moves_its_anchor_as_before():
    for result in (passing(IN_PLACE), passing(None), passing(FEW_PIXELS), passing(SHIFTED, 30.0),
                   passing(SHIFTED_AWAY)):
        camera = state()
        camera.placed(result, max_drift=2, tall=True)
        assert camera.anchor == (-2, -8) and camera.frozen
        assert np.array_equal(camera.shift_candidates, ONTO_THE_TOP)
