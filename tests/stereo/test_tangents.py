"""Height on the plane of the top and width from the tangent planes (core/stereo/tangents.py).

Known answers from the ray-cast box scene (tests/stereo/box_scene.py, independent of the project's
simulator and renderer): two calibrated cameras of a relaxed pair see a box of known width and
height; the measurements must come within 2 % (width) and 3 % (height).
"""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.render import render_silhouette
from octoprint_printwatch.core.stereo.size_check import (PairSizeCheck, SizeSettings, _difference, expected_width,
                                                          foreground_mask, width_direction)
from octoprint_printwatch.core.stereo.tangents import (Sections, plane_height, projected_top_profile,
                                                        tangent_offsets)

from .box_scene import box_mesh, relaxed_pair, render

LO = np.array([90.0, 92.0, 0.0])
HI = np.array([112.0, 106.0, 14.0])
FOOTPRINT = np.array([[90, 92], [112, 92], [112, 106], [90, 106]], float)


def _box(height: float = 14.0, grow_x: float = 0.0):
    lo, hi = LO.copy(), HI.copy()
    hi[2] = height
    lo[0] -= grow_x / 2
    hi[0] += grow_x / 2
    return lo, hi


@pytest.fixture(scope="module")
def pair():
    left, right = relaxed_pair()
    backgrounds = tuple(render(c, LO, HI, part=False) for c in (left, right))
    return left, right, backgrounds


def _observed(camera: Camera, background: np.ndarray, lo, hi):
    """The observed part (background removal, as the size check does alone) and |frame - bed|."""
    frame = render(camera, lo, hi)
    prior = render_silhouette(box_mesh(LO, HI), camera)
    prior = cv2.dilate(prior.astype(np.uint8), np.ones((25, 25), np.uint8)) > 0
    return foreground_mask(background, frame, prior), _difference(frame, background)


def test_the_projected_top_edge_is_the_far_edge_of_the_section():
    left, _ = relaxed_pair()
    sections = Sections(box_mesh(LO, HI))
    profile = projected_top_profile(sections.at(10.0), left, left.width)
    corners = left.project(np.array([[90, 92, 10], [112, 92, 10], [112, 106, 10], [90, 106, 10]], float))
    cols = np.nonzero(np.isfinite(profile))[0]
    # spans the corners' columns; never below the far edge (the top row of the four corners' hull)
    assert cols.min() >= np.floor(corners[:, 0].min()) and cols.max() <= np.ceil(corners[:, 0].max())
    assert len(cols) >= corners[:, 0].max() - corners[:, 0].min() - 2
    far = corners[np.argsort(corners[:, 1])[:2]]  # the two corners highest in the picture
    u = np.arange(int(np.ceil(far[:, 0].min())), int(np.floor(far[:, 0].max())) + 1)
    line = np.interp(u, np.sort(far[:, 0]), far[np.argsort(far[:, 0]), 1])
    assert np.allclose(profile[u], line, atol=0.6)  # lens distortion bends the projected edge slightly
    assert np.all(np.isnan(projected_top_profile(sections.at(20.0), left, left.width)))  # above the part


@pytest.mark.parametrize("true_top", [14.0, 10.0, 6.5])
def test_each_camera_measures_the_printed_height_within_3_percent(pair, true_top):
    """The part printed to ``true_top`` while the G-code says 14 mm: each camera's upper edge on the
    plane of the top gives the printed height on its own."""
    left, right, backgrounds = pair
    sections = Sections(box_mesh(LO, HI))
    for camera, background in zip((left, right), backgrounds):
        mask, diff = _observed(camera, background, *_box(true_top))
        result = plane_height(camera, mask, diff, sections, 14.0, 14.0 - 1e-3)
        assert result.height_mm == pytest.approx(true_top, rel=0.03), (camera.name, result)
        assert result.spread_mm < 0.3 and result.columns >= 20


def test_tangent_planes_give_the_width_within_2_percent(pair):
    """A box 22 mm across, and one 5 mm wider: the width from both cameras' tangent planes."""
    left, right, backgrounds = pair
    mesh = box_mesh(LO, HI)
    sections = Sections(mesh)
    direction = width_direction(left, right)
    expected = expected_width(mesh, 14.0, direction, 1.5)
    for grow, true_width in ((0.0, expected), (5.0, expected + 5.0 * abs(direction[0]))):
        changes = []
        for camera, background in zip((left, right), backgrounds):
            mask, diff = _observed(camera, background, *_box(14.0, grow_x=grow))
            offsets = tangent_offsets(camera, mask, diff, sections, 14.0, 1.5, render_silhouette(mesh, camera, 14.0))
            assert offsets.rows >= 3
            changes.append(offsets.width_change_mm)
        # each camera's tangent planes measure across its own line of sight, close to the pair's
        assert expected + np.mean(changes) == pytest.approx(true_width, rel=0.02), changes


def test_a_hidden_lower_part_does_not_count_as_the_sides():
    """Where a wider lower part forms the silhouette's edge, the band's own sides are not measured."""
    left, _ = relaxed_pair()
    import trimesh

    wide = box_mesh([80.0, 92.0, 0.0], [122.0, 120.0, 6.0])
    narrow = box_mesh([95.0, 96.0, 6.0], [105.0, 104.0, 14.0])
    stepped = trimesh.util.concatenate([wide, narrow])
    silhouette = render_silhouette(stepped, left)
    sections = Sections(stepped)
    # the observed part is exactly the model: no offset where the narrow top's sides are visible
    offsets = tangent_offsets(left, silhouette, None, sections, 14.0, 1.5, silhouette)
    assert offsets.width_change_mm == pytest.approx(0.0, abs=0.4)
    # measured at 6.5 mm, the band reaches the step where the wide base forms the edge: rows left out
    low = tangent_offsets(left, silhouette, None, sections, 6.4, 1.5, silhouette)
    assert low.width_change_mm is None or abs(low.width_change_mm) < 0.6


def test_the_pair_learns_its_vertical_calibration_error_once_and_measures_against_it(pair):
    """Both cameras half a degree off in pitch (several pixels, a millimetre or two of height): the
    first well-measured check fixes the offset; a print that then stops growing reads its real height
    and fails, a normal one passes within 3 %."""
    left, right, backgrounds = pair

    def tilted(cam: Camera, degrees: float) -> Camera:
        wrong = cv2.Rodrigues(np.array([np.radians(degrees), 0.0, 0.0]))[0]
        R = wrong @ cam.R
        return Camera(cam.name, cam.width, cam.height, cam.K, cam.dist, cv2.Rodrigues(R)[0].ravel(), -R @ cam.center)

    calibrated = (tilted(left, 0.5), tilted(right, -0.4))
    frames = {h: (render(left, *_box(h)), render(right, *_box(h))) for h in (10.0, 14.0)}

    def check():
        return PairSizeCheck(*calibrated, box_mesh(LO, HI), FOOTPRINT, SizeSettings(), *backgrounds)

    normal = check()
    first = normal.measure(*frames[10.0], 10.0)
    assert first.to_dict()["rectification"].get("height_anchored"), first.to_dict()
    later = normal.measure(*frames[14.0], 14.0)
    assert not later.failed and later.height_mm == pytest.approx(14.0, rel=0.03), later.to_dict()
    assert later.width_mm == pytest.approx(later.expected_width_mm, rel=0.02)

    stopped = check()
    stopped.measure(*frames[10.0], 10.0)
    short = stopped.measure(*frames[10.0], 14.0)  # the G-code says 14 mm, the part stayed at 10
    assert short.height_mm == pytest.approx(10.0, rel=0.03), short.to_dict()
    assert short.failed and short.error_pct > 10


def test_a_low_part_is_measured_only_and_a_runout_after_it_is_caught(pair):
    """Between 16 and 24 px of part in a view the pair measures and learns its offset but holds
    nothing against the print (a brim reads as width there); a print that stops right after is
    caught at the next check with the offset learnt (the demo's runout)."""
    left, right, backgrounds = pair
    check = PairSizeCheck(left, right, box_mesh(LO, HI), FOOTPRINT, SizeSettings(), *backgrounds)
    low = tuple(render(c, *_box(5.0)) for c in (left, right))
    first = check.measure(*low, 5.0)
    assert first.abstained and not first.failed and "measured only" in first.reason, first.to_dict()
    assert first.height_mm == pytest.approx(5.0, rel=0.03)
    assert first.to_dict()["rectification"].get("height_anchored")
    later = check.measure(*low, 9.0)  # the G-code says 9 mm, the part stayed at 5
    assert later.height_mm == pytest.approx(5.0, rel=0.03), later.to_dict()
    assert later.failed and later.error_pct > 10


@pytest.mark.parametrize("size", [(320, 240), (1280, 960)])
def test_other_frame_sizes_measure_the_same(size):
    """Thresholds are in millimetres at the part or scale with it: the same box seen at a quarter and
    at four times the pixels measures within the same tolerances, and a stopped print fails."""
    left, right = (c.scaled(*size) for c in relaxed_pair())
    backgrounds = tuple(render(c, LO, HI, part=False) for c in (left, right))
    check = PairSizeCheck(left, right, box_mesh(LO, HI), FOOTPRINT, SizeSettings(), *backgrounds)
    full = tuple(render(c, LO, HI) for c in (left, right))
    result = check.measure(*full, 14.0)
    assert not result.failed and result.height_mm == pytest.approx(14.0, rel=0.03), result.to_dict()
    assert result.width_mm == pytest.approx(result.expected_width_mm, rel=0.02)
    stopped = check.measure(*(render(c, *_box(10.0)) for c in (left, right)), 14.0)
    assert stopped.height_mm == pytest.approx(10.0, rel=0.03) and stopped.failed, stopped.to_dict()


def test_a_brim_on_the_bed_beside_a_low_part_does_not_read_as_width():
    """A camera looking steeply down sees a low part's sides on the same rows as the brim (or skirt, or
    shadow) lying on the bed around it: the silhouette's side there is the brim's, and read as the
    part's it made a normal sun gear 6 mm too wide (14 %, a false pause). Where flat material on the bed
    can show, a side edge outside the model's is not measured; the part's own side still is, and above
    the brim's rows (a taller part) the width is measured as before."""
    target = np.array([100.0, 100.0, 3.0])
    camera = Camera.look_at("steep", target + [10, -110, 110], target, focal_px=800)
    part_lo, part_hi = np.array([90.0, 92.0, 0.0]), np.array([112.0, 106.0, 6.0])
    footprint = np.array([[90, 92], [112, 92], [112, 106], [90, 106]], float)
    mesh = box_mesh(part_lo, part_hi)
    brim = box_mesh(part_lo - [7.0, 7.0, 0.0], [part_hi[0] + 7.0, part_hi[1] + 7.0, 0.4])
    part_alone = render_silhouette(mesh, camera)
    with_brim = part_alone | render_silhouette(brim, camera)
    check = PairSizeCheck(camera, camera, mesh, footprint, SizeSettings())
    flat_zone = check.flat_zone["steep"]
    sections = Sections(mesh)

    def change(mask, zone, top=6.0, model=mesh):
        return tangent_offsets(camera, mask, None, Sections(model) if model is not mesh else sections, top, 1.5,
                               render_silhouette(model, camera, top), flat_zone=zone)

    # the cause: the brim's edge taken for the part's side reads millimetres too wide
    assert change(with_brim, None).width_change_mm > 4.0
    # left out where the brim can show: not measured, never confidently wrong
    guarded = change(with_brim, flat_zone)
    assert guarded.width_change_mm is None and guarded.on_bed > 0
    # the part alone is measured as before (its sides are where the model's are)
    assert change(part_alone, flat_zone).width_change_mm == pytest.approx(0.0, abs=0.4)
    # a taller part's band stands above the brim's rows: measured, brim or not
    tall = box_mesh(part_lo, [part_hi[0], part_hi[1], 30.0])
    tall_with_brim = render_silhouette(tall, camera) | render_silhouette(brim, camera)
    assert change(tall_with_brim, flat_zone, top=30.0, model=tall).width_change_mm == pytest.approx(0.0, abs=0.4)


@pytest.mark.parametrize("true_top", [0.6, 2.5])
def test_an_edge_no_higher_than_the_lowest_height_considered_is_no_height(pair, true_top):
    """Only the first layers seen while the G-code says 14 mm (filament the bed's colour, the brim alone standing out):
    every column's edge lies at or below the lowest height the fit considers (1 mm), which bounds the height but does
    not measure it; the pair paused a normal print on such a "1.0 mm". An edge above it is still measured."""
    left, right, backgrounds = pair
    sections = Sections(box_mesh(LO, HI))
    for camera, background in zip((left, right), backgrounds):
        mask, diff = _observed(camera, background, *_box(true_top))
        result = plane_height(camera, mask, diff, sections, 14.0, 14.0 - 1e-3)
        if true_top < 1.0:
            assert result.height_mm is None and "not seen above" in result.reason, (camera.name, result)
        else:
            assert result.height_mm == pytest.approx(true_top, abs=0.4), (camera.name, result)
