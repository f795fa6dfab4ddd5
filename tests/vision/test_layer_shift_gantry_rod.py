"""A rod crossing the box is neither the print's material nor bed for the layer-shift test (eighteenth session, helper
b18): the gantry's X rod hangs just behind and above the part's top, and the newest band moved up and sideways onto
it read as a layer shift from one view (cross-check seed 14 `031`). Material thicker than the rod on its line is
something in front of it (a shifted band merged with the rod in the image) and stays evidence."""
import numpy as np

from octoprint_printwatch.core.layer_shift import band_shift
from octoprint_printwatch.core.shape_check import compare_masks, shift_evidence_without

from .synthetic import Box
from .test_layer_shift import J_ONE

# a top face seen from above: the newest band (the top at its new height) overlaps the part as it stood before
BEFORE, BAND = Box(110, 104, 210, 200), Box(110, 100, 210, 130)
EXPECTED = BEFORE.mask() | BAND.mask()
SEARCH = Box(80, 70, 240, 215).mask()


def maps_of(observed, rods=None):
    """band_shift's (support, against, moved) maps on ``observed``, with ``rods`` neither material nor bed."""
    bed, undecided = ~observed, np.zeros_like(observed)
    if rods is not None:
        observed, bed, undecided = shift_evidence_without(observed, bed, undecided, EXPECTED, rods=rods)
    found = band_shift(observed, bed, BEFORE.mask(), BAND.mask(), 24, 12, 5, 2.0, undecided=undecided,
                       bed_to_image=J_ONE)
    return found, found.maps[:3]


def rods_of(observed):
    """The rods compare_masks finds crossing the search box."""
    comparison = compare_masks(observed, ~observed, EXPECTED, BAND.mask(), SEARCH, np.zeros_like(observed), 2.0, 4.0)
    return comparison.rods


def test_a_rod_touching_the_top_is_found_crossing_the_box():
    rod = Box(0, 88, 320, 100)          # 12 px thick, from one side of the picture to the other, above the top
    rods = rods_of(EXPECTED | rod.mask())
    assert rods is not None and rods[rod.mask() & ~Box(100, 0, 220, 240).mask()].mean() > 0.9


def test_a_band_moved_onto_a_rod_above_the_top_is_no_evidence():
    rod = Box(0, 88, 320, 100)
    observed = EXPECTED | rod.mask()
    found, (support, against, moved) = maps_of(observed)
    # the band printed in place, moved 5 px sideways and 12 up, lands on the rod: it reads as a confirmed move
    at = (12 - 12, 24 + 5)
    assert support[at] >= 150 and support[at] >= 0.75 * moved[at]
    found, (support, against, moved) = maps_of(observed, rods_of(observed))
    assert support[at] < 60 and found.support < 60


def test_a_band_moved_in_front_of_a_rod_stays_evidence():
    rod = Box(0, 110, 320, 122)          # behind the part, at the band's height
    shifted = BAND.moved(20, 0)          # the newest band printed 20 px (4 mm) to the right, over the rod's line
    observed = BEFORE.mask() | shifted.mask() | rod.mask()
    rods = rod.mask()                     # the rod's strip runs on through the band merged with it in the image
    plain, _ = maps_of(observed)
    found, _ = maps_of(observed, rods)
    assert (plain.dx, plain.dy) == (found.dx, found.dy) == (20, 0)
    assert found.support >= 0.95 * plain.support and found.support >= 0.75 * found.moved
