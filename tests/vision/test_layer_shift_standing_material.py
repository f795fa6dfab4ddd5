"""The layer-shift test reads the newest band's overhang only on material that was not already standing there.

Seen on the second simulator (cross-check seed 21 `009_normal`, seed 27 `014_normal`: "stack" parts, a narrower tier
on a wider one, seen from high above): the newest band is the new tier's top face, lying wholly inside the older
layers' outline, so a move of it shows only where it would stick out past the older layers' edge. There the older
layers' own outline misfit (the part a few px wider or taller than the model in that view, at every check) is
material beyond the expected outline, and a move of 6-7 mm onto it read as a layer shift new since the previous
check (84 %, 97 % of the clear evidence). Material the camera saw there at both of its looks before is older than the
layers printed since the previous check: it counts for nothing. A real shift's overhang is new material.
"""
import numpy as np

from octoprint_printwatch.core.layer_shift import estimate_layer_shift
from octoprint_printwatch.core.shape_check import ExpectedRegions, check_shape, standing_material

from .synthetic import Box, bed_texture, camera_effects, paint_part

BASE = Box(100, 80, 220, 180)       # the older layers, seen from above (their top face and sides)
BAND = Box(160, 100, 212, 160)      # the new tier's top face, inside them
MISFIT = Box(220, 90, 236, 170)     # the older layers stand 16 px wider than the model on one side, at every check
PX_PER_MM = 3.0


def regions() -> ExpectedRegions:
    silhouette = BASE.mask() | BAND.mask()
    search = Box(40, 40, 300, 220).mask()
    return ExpectedRegions(silhouette=silhouette, new_band=BAND.mask(), search=search,
                           dont_care=np.zeros_like(silhouette), max_shift_px=4, tolerance_px=2,
                           px_per_mm=PX_PER_MM, previous_silhouette=BASE.mask(),
                           bed_to_image=np.eye(2) * PX_PER_MM, height_to_image=np.array([0.0, -PX_PER_MM]))


def check(scene: np.ndarray, earlier_look: np.ndarray):
    bed = bed_texture(seed=5)
    return check_shape("cam", camera_effects(bed, seed=6), camera_effects(scene, seed=7), regions(),
                       anchor=(0, 0), previous_mask=earlier_look, last_observed=earlier_look,
                       older_looks=[(earlier_look, BASE.mask())])


def test_a_band_inside_the_older_layers_does_not_move_onto_their_standing_misfit():
    scene = paint_part(paint_part(bed_texture(seed=5), BASE.moved(0, 0)), MISFIT)
    scene = paint_part(scene, BAND, seed=2)
    result = check(scene, earlier_look=BASE.mask() | MISFIT.mask())
    shift = estimate_layer_shift({"cam": result.band_shift})
    # (without the two earlier looks, the band moved 8 mm right reads 14 x 60 px of overhang on the misfit alone)
    assert shift is None or shift.support < 60


def test_a_band_moved_out_past_the_older_layers_is_still_read():
    scene = paint_part(paint_part(bed_texture(seed=5), BASE), BAND.moved(21, 0), seed=2)
    result = check(scene, earlier_look=BASE.mask())
    shift = estimate_layer_shift({"cam": result.band_shift})
    assert shift is not None and abs(shift.shift_mm[0] - 7.0) <= 0.75 and abs(shift.shift_mm[1]) <= 0.75
    assert shift.confirmed >= 0.85 and shift.overhang >= 0.8 * shift.support


def test_standing_material_needs_both_looks_and_material_now():
    now = Box(0, 0, 10, 10).mask()
    last = Box(5, 0, 15, 10).mask()
    before = Box(0, 0, 8, 10).mask()
    assert standing_material(now, last, None) is None
    assert standing_material(now, None, before) is None
    assert standing_material(now, last, before).sum() == 3 * 10   # columns 5-7 only
