"""The layer-shift test in the bed-marks zone (skirt, brim): what a mark cannot be counts.

Seen on the second simulator (cross-check seed 5 ``027_layer_shift``: a 37-mm box inside its skirt, one camera):
the newest layers slid 6.7 mm and stuck out 20-28 px beside the part, all of it inside the bed-marks zone around
the part's foot, where material counts for nothing (a skirt or brim may lie there). The shift was read only from
the bed it uncovered, which "the part stands lower" explains as well, and it was missed. Marks are printed in the
first layers: material there that the previous check did not see (beyond the part's own rise since) is no mark,
and confident bed there is bed.
"""
import numpy as np

from octoprint_printwatch.core.layer_shift import estimate_layer_shift
from octoprint_printwatch.core.shape_check import ExpectedRegions, _not_a_mark, check_shape

from .synthetic import Box, bed_texture, camera_effects, paint_part

BASE = Box(110, 110, 210, 170)        # the layers up to the previous check
BAND = Box(110, 90, 210, 110)         # printed since
ZONE = Box(84, 64, 236, 196)          # the bed-marks zone around the part's foot (it covers the part too)
PX_PER_MM = 3.0


def regions() -> ExpectedRegions:
    silhouette = BASE.mask() | BAND.mask()
    search = Box(40, 40, 290, 220).mask()
    return ExpectedRegions(silhouette=silhouette, new_band=BAND.mask(), search=search,
                           dont_care=ZONE.mask() & ~silhouette, max_shift_px=4, tolerance_px=2,
                           px_per_mm=PX_PER_MM, previous_silhouette=BASE.mask(),
                           bed_to_image=np.eye(2) * PX_PER_MM, height_to_image=np.array([0.0, -PX_PER_MM]))


def check(scene: np.ndarray, last_observed: np.ndarray):
    bed = bed_texture(seed=5)
    return check_shape("cam", camera_effects(bed, seed=6), camera_effects(scene, seed=7), regions(),
                       anchor=(0, 0), previous_mask=BASE.mask(), last_observed=last_observed)


def overhang_at(found, dx: int, dy: int) -> float:
    _, ny, nx = found.maps.shape
    return float(found.maps[3, dy + ny // 2, dx + nx // 2])


def test_a_band_slid_into_the_marks_zone_is_seen_sticking_out():
    scene = paint_part(paint_part(bed_texture(seed=5), BASE), BAND.moved(18, 0), seed=2)
    result = check(scene, last_observed=BASE.mask())
    found = result.band_shift
    assert abs(found.dx - 18) <= 1 and abs(found.dy) <= 1
    # the moved band's 18 x 20 px beyond the part, less the tolerance rims
    assert overhang_at(found, found.dx, found.dy) > 0.6 * 18 * 20
    shift = estimate_layer_shift({"cam": found})
    assert abs(shift.shift_mm[0] - 6.0) <= 0.5 and shift.confirmed > 0.85 and shift.overhang > 0


def test_a_mark_the_previous_check_saw_counts_for_nothing():
    # a brim-like slab beside the part, there at the previous check already; the band in place
    mark = Box(212, 92, 230, 168)
    scene = paint_part(paint_part(paint_part(bed_texture(seed=5), BASE), BAND, seed=2), mark, seed=3)
    result = check(scene, last_observed=BASE.mask() | mark.mask())
    found = result.band_shift
    assert abs(overhang_at(found, 18, 0)) < 1.0
    shift = estimate_layer_shift({"cam": found})
    assert shift is None or shift.support < 0.5 * shift.moved


def test_the_part_rising_by_its_newest_band_is_no_new_material_beyond_it():
    # the previous check saw the part 20 px lower; what the part adds by rising is the rise, not beyond it
    expected, previous = BASE.mask() | BAND.mask(), BASE.mask()
    observed = BASE.moved(4, 0).mask() | BAND.moved(4, 0).mask()      # the whole part 4 px off (calibration)
    assert not _not_a_mark(observed, BASE.moved(4, 0).mask(), expected, previous, 2.0).any()
    beside = observed | Box(216, 90, 236, 110).mask()
    assert _not_a_mark(beside, BASE.moved(4, 0).mask(), expected, previous, 2.0).sum() >= 0.8 * 20 * 20
