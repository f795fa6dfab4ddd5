"""Each stage of the shape check on small synthetic images whose right answer is known."""
import numpy as np
import pytest

from octoprint_printwatch.core.alignment import align_expected
from octoprint_printwatch.core.shape_check import check_shape, compare_masks
from octoprint_printwatch.core.material import material_evidence
from octoprint_printwatch.core.masks import shift_mask

from .synthetic import PART, W, Box, bed_texture, camera_effects, darken, paint_part, regions


@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def background_of(bed):
    return camera_effects(bed, seed=11)


# ------------------------------------------------------------ background removal
def test_shadow_outside_the_part_is_not_material_but_a_dark_part_inside_it_is(bed):
    shadow = Box(60, 170, 260, 200).mask()
    frame = camera_effects(darken(paint_part(bed, PART), shadow, 0.6))
    prior = PART.mask()
    sample = ~Box(90, 60, 230, 215).mask()
    ev = material_evidence(background_of(bed), frame, prior, sample)
    assert ev.material[PART.mask()].mean() > 0.95
    inner_shadow = Box(70, 175, 250, 195).mask()
    assert ev.material[inner_shadow].mean() < 0.02
    # the same darkening inside the prior (a part darker than the bed, same hue) is evidence of material
    dark_part = camera_effects(darken(bed, PART.mask(), 0.6))
    ev2 = material_evidence(background_of(bed), dark_part, prior, sample)
    assert ev2.material[Box(115, 85, 205, 165).mask()].mean() > 0.9
    assert not ev2.strong[Box(115, 85, 205, 165).mask()].any()  # but not strong enough to count as extra


def test_exposure_and_white_balance_change_is_normalised_away(bed):
    frame = camera_effects(bed, gain=(0.7, 0.8, 0.95))
    ev = material_evidence(background_of(bed), frame, PART.mask(), ~PART.mask())
    assert ev.material.mean() < 0.01
    assert ev.gains == pytest.approx([0.7, 0.8, 0.95], abs=0.04)


def test_one_pixel_shake_is_not_a_change(bed):
    frame = camera_effects(bed, shake=(1, -1))
    ev = material_evidence(background_of(bed), frame, PART.mask(), ~PART.mask())
    assert ev.material.mean() < 0.01
    assert ev.bed.mean() > 0.9


# ------------------------------------------------------------------- alignment
def test_alignment_recovers_a_small_shift_exactly():
    expected = PART.mask()
    observed = PART.moved(5, -3).mask()
    assert align_expected(observed, expected, 10) == (5, -3)


def test_alignment_never_moves_further_than_its_bound():
    observed = PART.moved(30, 0).mask()  # a part that moved ~10 mm
    dx, dy = align_expected(observed, PART.mask(), 8)
    assert dx * dx + dy * dy <= 64


def test_alignment_stays_near_its_anchor():
    observed = PART.moved(9, 0).mask()
    assert align_expected(observed, PART.mask(), 10, anchor=(1, 0), max_drift=2) == (3, 0)


# ------------------------------------------------------------------ comparison
def test_compare_masks_counts_missing_extra_and_band():
    expected = PART.mask()
    observed = expected.copy()
    observed[80:110, 110:210] = False          # top 30 rows gone: 3000 px
    observed[100:170, 215:235] = True          # 20x70 extra block beside it: 1400 px
    bed = ~observed
    band = Box(110, 80, 210, 110).mask()
    everywhere = np.ones_like(expected)
    c = compare_masks(observed, bed, expected, band, everywhere, ~everywhere, tolerance=0, band_reach=10)
    assert c.missing.sum() == 3000
    assert c.extra.sum() == 1400
    assert c.band_missing == 3000
    assert 0 < c.band_extra < 1400   # only the extra rows next to the band count for it
    far = expected & False
    far[150:170, 215:235] = True
    c_far = compare_masks(expected[:] | far, ~(expected | far), expected, band, everywhere, ~everywhere,
                          tolerance=0, band_reach=10)
    assert c_far.extra.sum() == 400 and c_far.band_extra == 0
    # with a tolerance, a thin rim does not count
    c2 = compare_masks(shift_mask(expected, 1, 0), ~shift_mask(expected, 1, 0), expected, band, everywhere,
                       ~everywhere, tolerance=2, band_reach=10)
    assert c2.missing.sum() == 0 and c2.extra.sum() == 0


def test_uncertain_pixels_are_not_counted_missing():
    expected = PART.mask()
    observed = np.zeros_like(expected)
    bed = np.zeros_like(expected)  # nothing is confidently bed: no evidence either way
    everywhere = np.ones_like(expected)
    c = compare_masks(observed, bed, expected, expected, everywhere, ~everywhere, tolerance=2, band_reach=5)
    assert c.missing.sum() == 0


# ------------------------------------------------------------- the whole check
def run(bed, frame, reg=None, **kw):
    return check_shape("cam", background_of(bed), frame, reg or regions(), **kw)


def test_a_normal_check_passes_despite_shadow_exposure_shake_and_jpeg(bed):
    scene = darken(paint_part(bed, PART), Box(80, 170, 250, 195).mask(), 0.55)
    frame = camera_effects(scene, gain=(0.85, 0.9, 0.8), shake=(1, 0))
    r = run(bed, frame)
    assert r.passed and r.usable
    assert r.error_pct < 3.0
    assert r.band_error_pct is not None and r.band_error_pct < 10


def test_calibration_error_within_the_bound_is_aligned_away(bed):
    frame = camera_effects(paint_part(bed, PART.moved(6, -4)))
    r = run(bed, frame)
    assert abs(r.shift_px[0] - 6) <= 1 and abs(r.shift_px[1] + 4) <= 1
    assert r.passed and r.error_pct < 2.0


def test_runout_is_reported_as_missing_material(bed):
    # the part stopped growing: its top 30 rows (the newest band) are absent
    frame = camera_effects(paint_part(bed, Box(110, 110, 210, 170)))
    r = run(bed, frame)
    assert not r.passed
    # 30 of 90 rows missing: (30 - 2) x (100 - 4) px of 9000 beyond the 2-px tolerance rim, less the few
    # rows JPEG ringing and closing add to the top edge of what is left
    assert 100 * 24 * 96 / 9000 <= r.missing_pct <= 100 * 28 * 96 / 9000 + 0.5
    assert r.extra_pct < 1
    assert r.band_missing_pct > 70   # of the whole band, tolerance rim included
    assert any("missing" in reason for reason in r.reasons)


def test_a_detached_part_moved_10mm_is_not_aligned_back(bed):
    frame = camera_effects(paint_part(bed, PART.moved(35, 0)))   # 35 px ~ 10 mm, bound 10 px
    r = run(bed, frame)
    assert not r.passed
    assert r.missing_pct > 15 and r.extra_pct > 15
    assert abs(r.shift_px[0]) <= 10


def test_strings_and_flat_bed_marks_are_not_extra_material(bed):
    scene = paint_part(bed, PART)
    scene[175:177, 90:230] = (230, 230, 230)            # a 2-px skirt line in front of the part
    scene[120, 210:260] = (40, 40, 210)                 # a 1-px string
    dont_care = Box(80, 172, 240, 182).mask()
    r = run(bed, camera_effects(scene), regions(dont_care=dont_care))
    assert r.passed and r.extra_pct < 0.5


def test_spaghetti_beside_the_part_is_extra_material(bed):
    scene = paint_part(bed, PART)
    rng = np.random.default_rng(5)
    for _ in range(60):  # a tangle of 3-px strands
        x, y = rng.integers(212, 250), rng.integers(90, 165)
        scene = scene.copy()
        import cv2
        cv2.line(scene, (int(x), int(y)), (int(x + rng.integers(-15, 15)), int(y + rng.integers(-15, 15))),
                 (40, 40, 210), 3)
    r = run(bed, camera_effects(scene))
    assert not r.passed
    assert r.extra_pct > r.missing_pct
    assert any("unexpected material" in reason for reason in r.reasons)


def test_material_outside_the_search_region_is_ignored(bed):
    scene = paint_part(bed, PART)
    scene[0:40, 100:220] = (90, 90, 90)   # the parked hotend at the top of the frame
    r = run(bed, camera_effects(scene))
    assert r.passed and r.extra_pct < 0.5


def test_a_moved_camera_gives_no_verdict_instead_of_a_pause():
    # a bed with strong structure (tape strips); the camera was knocked by half a strip after the background
    taped = bed_texture(grain=4).astype(np.float32)
    strips = (np.arange(W) // 20) % 2 == 0
    taped[:, strips] *= 0.55
    taped = np.clip(taped, 0, 255).astype(np.uint8)
    frame = camera_effects(paint_part(np.roll(taped, 10, axis=1), PART.moved(10, 0)))
    r = check_shape("cam", background_of(taped), frame, regions())
    assert not r.usable and r.passed
    assert "no verdict" in r.reasons[0]


def test_overlay_paints_missing_red_and_extra_magenta(bed):
    frame = camera_effects(paint_part(bed, Box(110, 110, 240, 170)))
    r = run(bed, frame)
    img = r.overlay
    assert img.shape == (240, 320, 3) and img.dtype == np.uint8
    b, g, rr = img[95, 160].astype(int)       # missing top
    assert rr > 120 and rr > b + 40 and rr > g + 40
    b, g, rr = img[140, 230].astype(int)      # extra to the right
    assert b > 100 and rr > 100 and g < min(b, rr) - 40


# ------------------------------------------------------- newest band and growth
def test_profile_growth_is_full_for_a_growing_part_and_nil_for_a_stalled_one():
    from octoprint_printwatch.core.growth import profile_growth

    before, now = Box(110, 110, 210, 170).mask(), PART.mask()     # the model rises by 30 rows
    assert profile_growth(now, before, now, before) == pytest.approx(100)
    assert profile_growth(before, before, now, before) == pytest.approx(0)
    half = Box(110, 95, 210, 170).mask()
    assert profile_growth(half, before, now, before) == pytest.approx(50)
    assert profile_growth(now, before, now, now) is None                 # the model did not rise


def test_a_part_the_colour_of_its_background_is_not_declared_missing(bed):
    from octoprint_printwatch.core.material import detectable_fraction

    noise = {"chroma": 2.0, "bright": 3.0, "dark": 3.0}
    palette = np.array([[30, 30, 32], [40, 40, 42]], np.float32)              # a black part
    behind = np.array([[35, 35, 36], [200, 200, 200]], np.float32)             # black backdrop, white wall
    assert detectable_fraction(palette, behind, noise, 5.0).tolist() == [0.0, 1.0]
    # in a whole check: the top third of a black part in front of a black strip is "not seen",
    # yet only counted missing where it would have been visible
    scene = bed.copy()
    scene[60:110] = (30, 30, 32)                                              # a black backdrop strip
    background = camera_effects(scene, seed=11)
    frame = camera_effects(paint_part(scene, Box(110, 110, 210, 170), colour=(32, 32, 34)))
    r = check_shape("cam", background, frame, regions(), palette=np.array([[32, 32, 34]], np.float32))
    assert r.missing_pct < 2 and r.passed


def test_displaced_part_finds_a_moved_part_but_not_a_brim():
    from octoprint_printwatch.core.alignment import displaced_part

    expected = np.zeros((200, 300), bool)
    expected[80:130, 100:160] = True
    brim = np.zeros_like(expected)
    brim[120:140, 85:175] = True                         # a flat ring at the foot, in front
    brim[80:140, 85:100] = brim[80:140, 160:175] = True
    # the part in place with a brim, or with a face the camera cannot see (half of it missing)
    assert displaced_part(expected | brim, expected, reach=60, min_move=6) is None
    half = expected.copy()
    half[80:105] = False
    assert displaced_part(half | brim, expected, reach=60, min_move=6) is None
    # the part knocked 40 px sideways (its old place empty), standing on its brim or not
    moved = np.roll(expected, 40, axis=1)
    assert displaced_part(moved | brim, expected, reach=60, min_move=6) == (40, 0)
    assert displaced_part(np.roll(expected, -25, axis=0), expected, reach=60, min_move=6) == (0, -25)
    # a move smaller than the limit is the alignment's business, not a detachment
    assert displaced_part(np.roll(expected, 4, axis=1), expected, reach=60, min_move=6) is None


def test_a_part_standing_a_little_taller_than_its_outline_is_not_extra_material():
    # The check's vertical position is its least certain (calibration, a frame taken a layer late):
    # a sliver above the outline is tolerated, the same sliver beside the part is not.
    expected = PART.mask()
    everywhere = np.ones_like(expected)
    above = expected | Box(PART.x0, PART.y0 - 8, PART.x1, PART.y0).mask()
    beside = expected | Box(PART.x1, PART.y0, PART.x1 + 8, PART.y1).mask()
    for observed, extra_expected in ((above, False), (beside, True)):
        c = compare_masks(observed, ~observed, expected, expected, everywhere, ~everywhere, tolerance=2,
                          band_reach=10, top_tolerance=4)
        assert bool(c.extra.any()) is extra_expected
    # without the top tolerance the sliver above would count: the tolerance is what makes the difference
    c = compare_masks(above, ~above, expected, expected, everywhere, ~everywhere, tolerance=2, band_reach=10)
    assert c.extra.any()


def test_missing_is_claimed_only_where_most_of_the_parts_shades_would_show(bed):
    # A part whose top faces look like the bed (a dark part on a dark bed seen from above) is not
    # "missing" where the camera sees bed colour: those shades may be the part itself.
    from octoprint_printwatch.core.material import detectable_fraction

    noise = {"chroma": 2.0, "bright": 3.0, "dark": 3.0}
    bed_colour = np.array([[150, 120, 60]], np.float32)
    four_of_five = np.array([[40, 40, 210], [45, 45, 220], [35, 35, 190], [50, 50, 230], [150, 121, 61]],
                            np.float32)
    assert detectable_fraction(four_of_five, bed_colour, noise, 5.0).tolist() == [0.8]
    three_of_five = np.array([[40, 40, 210], [45, 45, 220], [35, 35, 190], [148, 118, 60], [151, 121, 61]],
                             np.float32)
    assert detectable_fraction(three_of_five, bed_colour, noise, 5.0).tolist() == [0.6]
    # in a whole check, with the part gone from view (its colours known from earlier checks): a red part
    # is missing, a part that showed the bed's colour on 2 of its 5 shades is not held to it
    frame = camera_effects(bed)
    red = check_shape("cam", background_of(bed), frame, regions(), palette=four_of_five)
    camouflaged = check_shape("cam", background_of(bed), frame, regions(), palette=three_of_five)
    assert red.missing_pct > 80 and not red.passed
    assert camouflaged.missing_pct < 5


def test_a_shadow_darker_than_any_ambient_light_allows_is_not_extra_but_dark_strands_are(bed):
    # one strong light, little ambient light: the part's shadow keeps 15 % of the bed's brightness
    import cv2

    shadow = np.zeros(PART.mask().shape, np.float32)
    shadow[176:200, 150:225] = 1.0
    shadow = cv2.GaussianBlur(shadow, (0, 0), 3)            # a soft penumbra, no new edges
    scene = paint_part(bed, PART).astype(np.float32) * (1.0 - 0.85 * shadow[..., None])
    r = run(bed, camera_effects(np.clip(scene, 0, 255).astype(np.uint8)))
    assert r.passed and r.extra_pct < 0.5 * r.threshold   # (15 % when any deep dark counted anywhere)
    # black strands in the same place (grey, no colour of their own) are material
    tangle = paint_part(bed, PART)
    rng = np.random.default_rng(2)
    for _ in range(40):
        x, y = int(rng.integers(150, 220)), int(rng.integers(178, 204))
        cv2.line(tangle, (x, y), (x + int(rng.integers(-14, 14)), y + int(rng.integers(-8, 8))), (12, 12, 12), 3)
    r = run(bed, camera_effects(tangle))
    assert not r.passed and r.extra_pct > r.threshold


def test_the_parked_hotends_nozzle_is_foreign_but_a_part_that_tipped_over_is_not():
    # extra material entering the search box from above belongs to the hotend unless it reaches down
    # to the part's foot (a tipped part stands on the bed); grouping follows everything not confidently bed
    expected = PART.mask()                                  # rows 80..170
    search = Box(50, 65, 270, 200).mask()                   # the box's ceiling is row 65
    body = Box(150, 20, 190, 70).mask()                     # dark hotend body, weak evidence only
    nozzle = Box(162, 66, 178, 78).mask()                   # its tip, certain material, inside the box
    observed = expected | nozzle
    c = compare_masks(observed, ~(observed | body), expected, expected, search, ~search, tolerance=2,
                      band_reach=10, linked=observed | body)
    assert not c.extra.any()
    tipped = Box(212, 40, 240, 170).mask()                  # from above the box down to the bed
    observed = expected | tipped
    c = compare_masks(observed, ~observed, expected, expected, search, ~search, tolerance=2, band_reach=10,
                      linked=observed)
    assert c.extra.sum() > 0.5 * (tipped & search).sum()


def test_massive_unexpected_material_is_decisive_from_one_camera(bed):
    # a blob four times the threshold's worth of the part (a detached part, a nest of spaghetti) is
    # something no camouflage or lighting produces: one camera suffices; a smaller one needs company
    def with_blob(width):
        scene = paint_part(bed, PART)
        scene[95:165, 216:216 + width] = (40, 160, 40)
        return run(bed, camera_effects(scene))
    big, small = with_blob(40), with_blob(20)
    assert not big.passed and big.extra_pct >= 4 * big.threshold and big.decisive
    assert not small.passed and small.extra_pct < 4 * small.threshold and not small.decisive


def test_growth_is_not_read_on_the_outline_of_something_the_background_frame_held(bed):
    """A black part on a dark bed reads as material only where it hides a bright patch the background
    frame shows there (the hotend's mirror image in a glass bed): that material's top is the patch's top at
    every check, however the part grows. It is an edge of the background frame, not of the frame, so the
    growth test does not read it (HEAD: 0 %, a stalled part). A part that really stalled, seen against its
    backdrop, still reads 0 %."""
    from dataclasses import replace
    dark_bed = bed_texture(colour=(45, 38, 55), grain=2.0)
    patch = Box(140, 120, 180, 165)
    held = paint_part(dark_bed, patch, colour=(200, 180, 230))            # the bright patch, background only
    background = camera_effects(held, seed=11)
    before_box, now_box = Box(110, 110, 210, 170), PART                   # the part rose 30 rows
    # a part in the bed's very colour: where it stands, the frames show the bed (and not the patch)
    frame_before = camera_effects(dark_bed, seed=5)
    frame_now = camera_effects(dark_bed, seed=6)
    reg_before = regions(before_box)
    reg_now = replace(regions(now_box), previous_silhouette=before_box.mask())
    first = check_shape("cam", background, frame_before, reg_before)
    assert first.usable and first.observed_mask[patch.mask()].mean() > 0.8   # seen where it hides the patch
    second = check_shape("cam", background, frame_now, reg_now, last_observed=first.observed_mask,
                         anchor=first.shift_px)
    assert second.growth_pct is None
    # the same part stalled in a colour the bed shows it in: its top is an edge of the frame
    visible_before = camera_effects(paint_part(dark_bed, before_box), seed=5)
    visible_stalled = camera_effects(paint_part(dark_bed, before_box), seed=6)
    first = check_shape("cam", background, visible_before, reg_before)
    second = check_shape("cam", background, visible_stalled, reg_now, last_observed=first.observed_mask,
                         anchor=first.shift_px)
    assert second.growth_pct == pytest.approx(0, abs=10)
