"""Objects entering the search box from the side: the printer's X rods (or their reflection in a glass bed)
are not the print's; whatever crosses the box that belongs to the print still is.

Synthetic scenes with known answers (tests/vision/synthetic.py): a textured bed, a part with layer
lines (rows 80-170), the search box 50 px around it (columns 60-260). A rod is drawn into the
background frame and, 10 px lower (the gantry rose with the check height), into the frame, behind the
part, at the height of the part's lowest quarter: there the "reaching in from above" rule keeps
everything (a part that tipped over lies on the bed at its foot), so only the rod rule can drop it.
"""
import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.masks import MIRROR_MATCH_SHARE, crossing_the_box, outline_zone
from octoprint_printwatch.core.shape_check import check_shape

from .synthetic import PART, Box, H, W, bed_texture, camera_effects, paint_part, regions

ROD_COLOUR = (205, 210, 200)
FILAMENT = (40, 40, 210)


@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def with_rod(image, row, x_end=W, thickness=4):
    """``image`` with a straight rod from the left edge to ``x_end``, at ``row`` on the left and rising
    8 px over the picture's width (seen at a slant)."""
    out = image.copy()
    cv2.line(out, (0, row), (x_end, row - int(8 * x_end / W)), ROD_COLOUR, thickness)
    return out


def check(background, frame):
    return check_shape("cam", camera_effects(background, seed=11), camera_effects(frame), regions())


def test_a_rod_crossing_the_search_box_behind_the_part_is_not_material(bed):
    r = check(with_rod(bed, 150), paint_part(with_rod(bed, 160), PART))
    assert r.passed, r.reasons
    assert r.extra_pct < 0.3 * r.threshold


def test_a_rod_ending_behind_the_part_is_not_material_while_the_part_stands_in_place(bed):
    # it enters from the left; its end is hidden behind the part
    r = check(with_rod(bed, 150, x_end=160), paint_part(with_rod(bed, 160, x_end=160), PART))
    assert r.passed, r.reasons
    assert r.extra_pct < 0.3 * r.threshold


def test_a_straight_bar_that_ends_inside_the_box_still_counts(bed):
    # a rod-like bar lying on the bed with both ends seen inside the search box: it does not cross it
    frame = bed.copy()
    cv2.line(frame, (70, 164), (250, 160), FILAMENT, 6)
    r = check(bed, paint_part(frame, PART))
    assert not r.passed and r.extra_pct > r.threshold


def test_material_hanging_on_a_rod_still_counts(bed):
    # a blob of filament stuck on the rod beside the part: the rod's strip is dropped, the blob is not
    frame = with_rod(bed, 160)
    frame[125:165, 222:250] = FILAMENT
    r = check(with_rod(bed, 150), paint_part(frame, PART))
    blob_pct = 100.0 * (40 * 28) / PART.mask().sum()
    assert not r.passed and r.extra_pct > 0.6 * blob_pct


def test_a_part_that_slid_sideways_is_still_extra_material(bed):
    # (slid further, past the box's edge at x = 260, it fills too much of this small picture's certain bed
    # for the exposure and noise estimates; the next test has a part lying across the box's edge)
    r = check(bed, paint_part(bed, PART.moved(40, 0)))
    assert not r.passed
    assert r.extra_pct > r.threshold and r.missing_pct > r.threshold


def test_a_tall_part_that_tipped_over_and_lies_across_the_box_edge_is_still_extra_material(bed):
    # a long straight bar from where the part stood out of the box: the part is gone from its place
    r = check(bed, paint_part(bed, Box(150, 150, W, 170)))
    assert not r.passed
    assert r.extra_pct > r.threshold


def test_a_strand_draped_over_the_side_is_still_extra_material(bed):
    frame = paint_part(bed, PART)
    ys = np.arange(82, 200, dtype=np.float64)
    xs = 212 + 0.25 * (ys - 82) + 6 * np.sin((ys - 82) / 8.0)   # down the side to the bed, wandering
    cv2.polylines(frame, [np.stack([xs, ys], axis=1).astype(np.int32)], False, FILAMENT, 6)
    r = check(bed, frame)
    assert not r.passed and r.extra_pct > r.threshold


def test_crossing_the_box_returns_the_rods_strip_and_nothing_else():
    outline = outline_zone(PART.mask(), 2, 2)
    search = Box(60, 65, 260, 220).mask()
    rod = np.zeros((H, W), np.uint8)
    cv2.line(rod, (0, 120), (W, 104), 1, 9)
    tangle = np.zeros((H, W), np.uint8)
    rng = np.random.default_rng(4)
    for _ in range(25):                           # a tangle beside the part, below the rod
        x, y = int(rng.integers(215, 250), ), int(rng.integers(140, 200))
        cv2.line(tangle, (x, y), (x + int(rng.integers(-20, 20)), y + int(rng.integers(-20, 20))), 1, 5)
    tangle[110:124] = 0
    objects = (rod.astype(bool) | tangle.astype(bool)) & ~outline
    foreign = crossing_the_box(objects, search, outline)
    assert foreign[rod.astype(bool) & ~outline].mean() > 0.95
    assert not foreign[tangle.astype(bool)].any()
    # behind the part: only while the part stands where it belongs
    left = rod.astype(bool) & ~outline
    left[:, PART.x0:] = False
    assert crossing_the_box(left, search, outline, part_in_place=True)[left].mean() > 0.95
    assert not crossing_the_box(left, search, outline, part_in_place=False).any()


# ------------------------------------------------ the mirror image of the parked hotend in a glass bed
# A calibrated camera looks at a part's search box (60-140 mm square, 40 mm high); the parked hotend
# hangs behind it and to the side, above the box. Its reflection in the bed is the hotend mirrored about
# z = 0; the image of a box is the convex hull of its corners' images (a box is convex).

def _camera():
    from octoprint_printwatch.core.camera import Camera
    return Camera.look_at("cam", (100.0, -250.0, 200.0), (100.0, 100.0, 10.0), width=640, height=480,
                          hfov_deg=55.0)


def _box_image(camera, x, y, z):
    """(480, 640) bool: the image of the box x0-x1, y0-y1, z0-z1 (mm)."""
    corners = np.array([[cx, cy, cz] for cx in x for cy in y for cz in z], np.float64)
    hull = cv2.convexHull(np.round(camera.project(corners)).astype(np.int32))
    out = np.zeros((480, 640), np.uint8)
    cv2.fillConvexPoly(out, hull, 1)
    return out.astype(bool)


HOTEND = dict(x=(150.0, 175.0), y=(170.0, 190.0), z=(60.0, 110.0))


#: the check height: the part is printed up to here, the hotend hangs higher
PRINTED_MM = 30.0


def _mirror_share(blob, changed, search):
    from octoprint_printwatch.core.masks import mirror_match
    ys, xs = np.nonzero(blob)
    return mirror_match(np.stack([xs, ys], axis=1), _camera(), lambda qx, qy: changed[qy, qx], search,
                        min_height=PRINTED_MM)


def _scene():
    camera = _camera()
    search = _box_image(camera, (60.0, 140.0), (60.0, 140.0), (0.0, 40.0))
    hotend = _box_image(camera, **HOTEND)
    reflection = _box_image(camera, HOTEND["x"], HOTEND["y"], (-HOTEND["z"][1], -HOTEND["z"][0]))
    return camera, search, hotend, reflection


def test_the_parked_hotends_reflection_is_matched_to_the_hotend_above_it():
    _, search, hotend, reflection = _scene()
    assert hotend.sum() > 300 and reflection.sum() > 300
    assert not (hotend & search).any()           # the hotend hangs above the box, outside it
    assert _mirror_share(reflection, hotend, search) >= MIRROR_MATCH_SHARE


def test_a_part_standing_on_the_bed_below_the_hotend_is_no_reflection():
    camera, search, hotend, _ = _scene()
    # a piece of the part (knocked off, as wide as the hotend) standing on the bed in front of the hotend
    standing = _box_image(camera, HOTEND["x"], (100.0, 120.0), (0.0, 25.0))
    assert standing.sum() > 300
    assert _mirror_share(standing, hotend, search) < MIRROR_MATCH_SHARE


def test_a_reflection_deeper_than_the_nozzle_can_hang_is_not_matched():
    _, search, hotend, reflection = _scene()
    from octoprint_printwatch.core.masks import mirror_match
    ys, xs = np.nonzero(reflection)
    # printed higher than the hotend hangs: whatever this blob mirrors, the nozzle cannot be there
    share = mirror_match(np.stack([xs, ys], axis=1), _camera(), lambda qx, qy: hotend[qy, qx], search,
                         min_height=HOTEND["z"][1] + 20.0)
    assert share < MIRROR_MATCH_SHARE


def test_no_reflection_without_something_new_above_the_box():
    _, search, _, reflection = _scene()
    nothing = np.zeros_like(reflection)
    assert _mirror_share(reflection, nothing, search) == 0.0


def test_the_reflection_of_an_object_elsewhere_is_not_matched():
    camera, search, _, reflection = _scene()
    # the only new thing above the box hangs 60 mm to the left: nothing mirrors onto this blob
    elsewhere = _box_image(camera, (60.0, 85.0), HOTEND["y"], HOTEND["z"])
    assert _mirror_share(reflection, elsewhere, search) < 0.5


def test_blobs_found_to_be_something_else_count_in_no_figure():
    """A blob the caller recognises with the whole frame (the hotend's mirror image) is left out of the
    extra material and of the newest band's figures alike, so the band rule cannot fail on it either."""
    from octoprint_printwatch.core.shape_check import compare_masks

    expected = np.zeros((120, 160), bool)
    expected[40:100, 60:100] = True
    band = np.zeros_like(expected)
    band[40:46, 60:100] = True
    blob = np.zeros_like(expected)
    blob[30:50, 102:118] = True                      # beside the newest band, outside the outline
    observed = expected | blob
    search = np.ones_like(expected)
    args = (observed, ~observed, expected, band, search, np.zeros_like(expected), 2.0, 10.0)
    counted = compare_masks(*args)
    assert counted.extra.sum() > 200 and counted.band_extra > 0
    dropped = compare_masks(*args, not_the_prints=lambda extra: extra & blob)
    assert not dropped.extra.any() and dropped.band_extra == 0
    assert dropped.missing.sum() == counted.missing.sum()


@pytest.mark.parametrize("dist", [None, (0.2, 0.1, 0.0, 0.0, 0.05), (-0.3, 0.12, 0.0, 0.0, -0.02)])
def test_a_blob_whose_mirror_image_falls_behind_a_steep_camera_is_scored_quietly(dist):
    """A camera looking steeply down: at the farther trial distances a blob's mirror image lies behind it
    (projected to NaN), or, through a lens with distortion, far beyond int64's range. Those points are simply
    not in the frame: no numpy cast warning, a share in 0-1."""
    import dataclasses
    import warnings
    from octoprint_printwatch.core.camera import Camera
    from octoprint_printwatch.core.masks import mirror_match
    camera = Camera.look_at("top", (100.0, -60.0, 250.0), (100.0, 60.0, 0.0), width=640, height=480,
                            hfov_deg=70.0)
    if dist is not None:
        camera = dataclasses.replace(camera, dist=np.array(dist))
    search = np.zeros((480, 640), bool)
    search[200:300, 250:400] = True
    changed = np.ones((480, 640), bool)
    ys, xs = np.mgrid[0:30, 100:200]           # a blob at the top edge of the frame
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        share = mirror_match(np.stack([xs.ravel(), ys.ravel()], axis=1), camera,
                             lambda qx, qy: changed[qy, qx], search)
    assert 0.0 <= share <= 1.0
