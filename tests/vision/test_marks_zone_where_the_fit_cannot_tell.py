"""A short part inside its skirt, at the camera's first look: the skirt is no unexpected material.

Seen on the second simulator (cross-check seed 18 ``059_layer_shift``, seed 29 ``002_normal``: a 10-mm part 2.4 mm
tall in the middle of its skirt, bright filament on a dark bed, JPEG 67-71): the ring and the JPEG halo of the
filament's colour fill a disc several times the part's size, all of it material. The part's small outline fits
anywhere in that disc, and the first look put it on the disc's upper rim, 5-13 px off the part. The bed-marks zone
moved with the outline, off the ring's near side, and the skirt there counted as 30-1,400 % unexpected material.
The zone lies on the bed, where the calibration puts it; the alignment carries it along only as far as it knows
where the part stands: at a first look that cannot tell the part's place it is laid at the calibrated place too.
"""
import cv2
import numpy as np

from octoprint_printwatch.core.shape_check import Placement, check_shape, zone_places

from .synthetic import H, W, Box, bed_texture, camera_effects, regions

DARK_BED = (40, 40, 42)
ORANGE = (20, 110, 235)
PART = Box(150, 110, 164, 122)        # 14 x 12 px: a short part far from the camera
CENTRE, AXES = (157, 116), (30, 18)  # the skirt's ellipse around it


def ellipse(grow: int = 0) -> np.ndarray:
    mask = np.zeros((H, W), np.uint8)
    cv2.ellipse(mask, CENTRE, (AXES[0] + grow, AXES[1] + grow), 0, 0, 360, 1, -1)
    return mask.astype(bool)


def scene_in_its_disc() -> np.ndarray:
    # the skirt's ring and the halo it fills, in the filament's colour (a little darker), the part in it
    scene = bed_texture(seed=5, colour=DARK_BED, grain=3.0).astype(np.float32)
    scene[ellipse()] = np.array(ORANGE, np.float32) * 0.7
    scene[PART.mask()] = ORANGE
    return np.clip(scene, 0, 255).astype(np.uint8)


def check(frame: np.ndarray):
    bed = bed_texture(seed=5, colour=DARK_BED, grain=3.0)
    # the bed-marks zone: the footprint grown on the bed, the skirt well inside it where the part stands
    reg = regions(PART, band_rows=12, max_shift=20, search_margin=60, dont_care=ellipse(grow=3))
    return check_shape("cam", camera_effects(bed, seed=41), camera_effects(frame, seed=42), reg, anchor=None,
                       track_candidates=True)


def test_the_zone_is_laid_at_the_calibrated_place_too_where_the_first_look_cannot_tell():
    one = Placement((3, -2), candidates=np.array([[3, -2]]))
    assert zone_places(one, first_look=True).tolist() == [[3, -2]]         # the fit knows where the part is
    tied = Placement((3, -2), candidates=np.array([[0, 0], [3, -2], [-4, 1]]))
    assert zone_places(tied, first_look=False).tolist() == [[3, -2]]       # an anchored look keeps its place
    assert zone_places(tied, first_look=True).tolist() == [[3, -2], [0, 0]]


def test_a_short_part_in_its_filled_skirt_at_a_first_look_is_no_unexpected_material():
    result = check(scene_in_its_disc())
    assert result.usable
    # the disc gives the outline no place of its own: it may sit anywhere in it ...
    assert result.shift_candidates is not None and len(result.shift_candidates) > 20
    # ... and wherever it sits, the disc is the skirt on the bed, not material where the model has none
    assert result.extra_pct < 7.0 and result.passed


def test_material_rising_out_of_the_zone_still_counts():
    # a blob beside the disc, beyond the zone wherever the part could stand in it: spaghetti, not a mark
    frame = scene_in_its_disc()
    frame[104:128, 194:230] = ORANGE
    result = check(frame)
    assert result.usable and not result.passed
    assert result.extra_pct > 100.0
