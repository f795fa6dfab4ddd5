"""A shadow that moved between the background frame and a check is not material; material still is.

Scenes (tests/vision/synthetic.py): a textured bed with uneven light, a red part, a hard shadow (the
parked head's) that lies beside the part in the background frame and elsewhere in the check's frame, as
the head rises with every check. The bed where the shadow was is brighter than the background there,
by one factor in every channel, with the bed's own grain.
"""
import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.material import _luma_chroma, coverage_by_part, material_evidence
from octoprint_printwatch.core.shape_check import check_shape

from .synthetic import PART, Box, bed_texture, camera_effects, darken, paint_part, regions

#: where the head's shadow lay in the background frame: beside the part, inside the search box
OLD_SHADOW = Box(66, 120, 104, 180)
#: where it lies at the check: further along the bed
NEW_SHADOW = Box(276, 0, 320, 40)
SAMPLE = ~Box(90, 60, 230, 215).mask()


def textured(bed: np.ndarray, grain: float = 150.0, seed: int = 7) -> np.ndarray:
    """The bed with a grain of brightness (textured PEI): the same pattern in every channel."""
    rng = np.random.default_rng(seed)
    pattern = cv2.GaussianBlur(rng.normal(0, grain, bed.shape[:2]).astype(np.float32), (0, 0), 0.7)
    return np.clip(bed.astype(np.float32) * (1.0 + pattern[..., None] / 255.0), 0, 255).astype(np.uint8)


@pytest.fixture(scope="module", params=[(150, 120, 60), (140, 140, 140)], ids=["gold", "grey"])
def bed(request):
    return bed_texture(colour=request.param)


def background_with_shadow(bed):
    return camera_effects(darken(bed, OLD_SHADOW.mask(), 0.5), seed=11)


def frame_of(scene):
    return camera_effects(darken(scene, NEW_SHADOW.mask(), 0.5), shake=(1, 0))


def test_bed_where_the_shadow_left_is_not_extra_material(bed):
    frame = frame_of(paint_part(bed, PART))
    ev = material_evidence(background_with_shadow(bed), frame, PART.mask(), SAMPLE)
    left = Box(70, 124, 100, 176).mask()   # the old shadow, off its edge
    assert ev.strong[left].mean() < 0.02
    result = check_shape("cam", background_with_shadow(bed), frame, regions())
    assert result.passed and result.extra_pct < 1.0


def test_without_the_physics_the_same_scene_would_be_extra(bed):
    """The scene is hard: the bed where the shadow left is far brighter than the background there."""
    bg = background_with_shadow(bed).astype(np.float32)
    fr = frame_of(paint_part(bed, PART)).astype(np.float32)
    left = Box(70, 124, 100, 176).mask()
    luma_f, _, _ = _luma_chroma(fr)
    luma_b, _, _ = _luma_chroma(bg)
    assert np.median(luma_f[left] - luma_b[left]) > 40   # > 10 noise units of this camera


def test_something_brighter_than_the_lit_bed_where_the_shadow_was_is_material(bed):
    scene = paint_part(paint_part(bed, PART), Box(72, 145, 98, 158), colour=(235, 235, 235), seed=4)
    ev = material_evidence(background_with_shadow(bed), frame_of(scene), PART.mask(), SAMPLE)
    assert ev.strong[Box(75, 147, 95, 156).mask()].mean() > 0.9


def test_material_as_bright_as_the_bed_but_without_its_grain_is_material(bed):
    """A blob in the bed's own colour and brightness but smooth (the bed's grain replaced) where the
    shadow was: the correlation with the background's grain tells it from the returning light."""
    bed = textured(bed)
    flat = np.asarray(bed, np.float32)[Box(72, 140, 98, 176).mask()].mean(axis=0)
    scene = paint_part(paint_part(bed, PART), Box(72, 140, 98, 176), colour=tuple(float(c) for c in flat), seed=4)
    ev = material_evidence(background_with_shadow(bed), frame_of(scene), PART.mask(), SAMPLE)
    assert ev.strong[Box(76, 144, 94, 172).mask()].mean() > 0.5
    assert ev.strong[Box(70, 124, 100, 136).mask()].mean() < 0.1   # the bare bed beside it: the light is back


def test_a_black_part_on_a_grey_bed_with_moving_shadows_is_seen_whole():
    bed = bed_texture(colour=(140, 140, 140))
    scene = paint_part(bed, PART, colour=(25, 25, 25))
    result = check_shape("cam", background_with_shadow(bed), frame_of(scene), regions())
    assert result.observed_mask[Box(115, 85, 205, 165).mask()].mean() > 0.95
    assert result.passed and result.missing_pct < 1.0 and result.extra_pct < 1.0


def test_a_shadow_on_a_bed_with_a_saturated_channel_is_no_colour_change_but_a_red_blob_is():
    """A violet bed whose blue channel is clipped in the frames: a shadow lowers the stored blue less than
    red and green (its true value was higher), which reads as a colour change unless the clipping is
    taken into account."""
    bed = bed_texture(colour=(120, 100, 190))
    bright = bed.astype(np.float32)
    bright[..., 0] = bright[..., 0] * 2.5   # blue far above what the sensor stores
    shadow_beside = Box(72, 150, 108, 190)
    shaded = bright.copy()
    shaded[shadow_beside.mask()] *= 0.6
    lit_bed = np.clip(bright, 0, 255).astype(np.uint8)
    frame = camera_effects(paint_part(np.clip(shaded, 0, 255).astype(np.uint8), PART), noise=1.5)
    background = camera_effects(lit_bed, seed=11, noise=1.5)
    assert (background[..., 0] >= 250).mean() > 0.9
    result = check_shape("cam", background, frame, regions())
    assert result.passed and result.extra_pct < 1.0
    blob = Box(72, 160, 100, 185)
    red = camera_effects(paint_part(paint_part(np.clip(shaded, 0, 255).astype(np.uint8), PART), blob,
                                    colour=(40, 40, 210), seed=6), noise=1.5)
    result_red = check_shape("cam", background, red, regions())
    assert not result_red.passed and result_red.extra_pct > 7


def tinted_shadow(image: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """The head's shadow where the warm key light is blocked and the cool ambient light remains: the bed
    darkens, red most and blue least, so its colour changes too (strong evidence, pixel by pixel)."""
    out = image.astype(np.float32)
    out[mask] *= np.array([0.8, 0.55, 0.35], np.float32)
    return np.clip(out, 0, 255).astype(np.uint8)


def strands_across(image: np.ndarray, box: Box, colour, coverage: float) -> np.ndarray:
    """Horizontal 3-px strands every 5 rows across ``box``, each pixel ``coverage`` of the way to ``colour``."""
    out = image.astype(np.float32)
    for y in range(box.y0, box.y1, 5):
        region = out[y:y + 3, box.x0:box.x1]
        region += coverage * (np.asarray(colour, np.float32) - region)
    return np.clip(out, 0, 255).astype(np.uint8)


ORANGE, BLUE_TAPE = (40, 120, 230), (170, 120, 60)
BESIDE = Box(60, 100, 100, 170)   # left of the part, inside the search box


def test_a_tinted_head_shadow_beside_the_part_is_not_extra_material_but_strands_there_are():
    bed = bed_texture(colour=BLUE_TAPE)
    background = camera_effects(bed, seed=11)
    scene = paint_part(bed, PART, colour=ORANGE)
    shadowed = camera_effects(tinted_shadow(scene, BESIDE.mask()), shake=(1, 0))
    ev = material_evidence(background, shadowed, PART.mask(), SAMPLE)
    assert ev.strong[BESIDE.mask()].mean() > 0.5     # pixel by pixel, the shadow reads as a colour change
    result = check_shape("cam", background, shadowed, regions())
    assert result.passed and result.extra_pct < 1.0
    # strands of the part's colour lying there, each pixel only half covered, are the part's material
    tangled = camera_effects(strands_across(scene, BESIDE, ORANGE, 0.5), shake=(1, 0))
    result = check_shape("cam", background, tangled, regions())
    assert not result.passed and result.extra_pct > 7.0


def test_coverage_reads_how_far_a_pixel_moved_towards_the_parts_colour():
    palette = np.array([[40, 120, 230], [60, 130, 200]], np.float32)    # the orange part's lit faces
    bed = np.array([[170, 120, 60]] * 4, np.float32)
    frame = np.array([[105, 120, 145],                                   # half way to the lit orange
                      [170, 120, 60],                                    # the bed itself
                      [136, 66, 21],                                     # the tinted shadow: bluer
                      [40, 120, 230]], np.float32)                       # the part
    assert coverage_by_part(frame, bed, palette) == pytest.approx([0.5, 0.0, 0.0, 1.0], abs=0.12)


def test_bare_bed_where_a_stalled_part_should_have_risen_under_a_shadow_that_left_is_not_material():
    """Runout under the head's old shadow (cross-check seed 6 ``048_runout``): the background frame had the
    parked head's shadow over where the part now should be; the part stopped growing, so the top of its
    expected outline shows the bed, lit again. On a bed without grain only the part's colour tells: a part
    whose pixels differ in colour from the bed has no lit face that passes for the bed brightened."""
    bed = bed_texture(colour=(140, 160, 150), grain=1.0)
    printed = Box(110, 125, 210, 170)                       # stopped 45 rows below the expected top (PART)
    old_shadow = Box(100, 40, 220, 118)                     # half of it beyond the part's surroundings
    background = camera_effects(darken(bed, old_shadow.mask(), 0.5), seed=11)
    frame = camera_effects(darken(paint_part(bed, printed), NEW_SHADOW.mask(), 0.5), shake=(1, 0))
    prior = PART.moved(0, -10).mask() | PART.moved(0, 10).mask()
    top = Box(115, 85, 205, 118).mask()                     # bare bed inside the expected outline
    ev = material_evidence(background, frame, prior, SAMPLE, previous=printed.mask(), part=PART.mask())
    assert ev.material[top].mean() < 0.1
    assert ev.material[Box(115, 130, 205, 165).mask()].mean() > 0.95      # the part itself
    # a part in the bed's own colour: its lit face might be the bed brightened, so there it stays material
    alike = camera_effects(darken(paint_part(bed, printed, colour=(140, 160, 150)), NEW_SHADOW.mask(), 0.5),
                           shake=(1, 0))
    ev_alike = material_evidence(background, alike, prior, SAMPLE, previous=printed.mask(), part=PART.mask())
    assert ev_alike.material[top].mean() > 0.5
