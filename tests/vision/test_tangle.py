"""Spaghetti (core/tangle.py): material new since the previous check, outside the part and attached to it.

Small synthetic scenes whose answers follow from how they are drawn: a part that grows inside its outline
adds nothing; loops of filament draped over its side add their area; a brim, a skirt, a string, the parked
hotend, a flickering line far from the part and the top of a part a layer taller than the model add nothing
(or far less than the decision needs).
"""
from dataclasses import replace

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import check_shape
from octoprint_printwatch.core.tangle import (ONE_VIEW_MM2, TWO_VIEWS_MM2, NewMaterial, loose_material, new_material,
                                             viewpoints)

from .synthetic import H, PART, W, Box, bed_texture, camera_effects, paint_part, regions

PX_PER_MM = 4.0          # a 100-px part is 25 mm wide, as at 640x480 from ~30 cm
TOL = 2.0
EVERYWHERE = np.ones((H, W), bool)


def loops(shape=(H, W), centre=(230, 120), count=8, seed=4, thickness=2, spread=(8, 2)) -> np.ndarray:
    """(h, w) bool: ``count`` open loops of filament (ellipses 6-14 px across) around ``centre``, spread
    by up to ``spread`` px (x, y)."""
    rng = np.random.default_rng(seed)
    canvas = np.zeros(shape, np.uint8)
    for _ in range(count):
        c = (int(centre[0] + rng.integers(-spread[0], spread[0] + 1)),
             int(centre[1] + rng.integers(-spread[1], spread[1] + 1)))
        axes = (int(rng.integers(3, 8)), int(rng.integers(3, 8)))
        cv2.ellipse(canvas, c, axes, float(rng.uniform(0, 180)), 0, 330, 1, thickness)
    return canvas.astype(bool)


def measure(observed, previous, expected=None, search=EVERYWHERE, **kw):
    expected = PART.mask() if expected is None else expected
    return new_material(observed, previous, expected, search, TOL, PX_PER_MM, **kw)


# ----------------------------------------------------------------------- masks
def test_a_solid_band_growing_inside_the_outline_adds_nothing():
    before = Box(110, 110, 210, 170).mask()      # the part at the previous check, 30 rows shorter
    now = PART.mask()                              # grown to the full outline
    result = measure(now, before)
    assert result.area_mm2 == 0.0 and result.blobs == 0


def test_loops_draped_over_the_parts_side_count_with_their_area():
    tangle = loops(count=16, spread=(12, 2)) & ~PART.mask()
    # attached: a strand runs from the part's right side (x = 210) through every loop
    tangle[119:122, 208:244] = True
    now = PART.mask() | tangle
    result = measure(now, PART.mask())
    distance = cv2.distanceTransform((~PART.mask()).astype(np.uint8), cv2.DIST_L2, 3)
    beyond = int((tangle & (distance > 2.0 * PX_PER_MM)).sum())   # more than 2 mm from the part
    assert beyond > 0
    # every loop pixel beyond 2 mm is counted (the attached blob is one piece), in mm^2 at the part
    assert result.pixels == beyond
    assert result.area_mm2 == pytest.approx(beyond / PX_PER_MM ** 2)
    assert result.area_mm2 >= ONE_VIEW_MM2


def test_a_brim_seen_before_and_now_adds_nothing():
    brim = Box(100, 165, 220, 180).mask()          # a ring at the part's foot, printed at layer 1
    before = Box(110, 110, 210, 170).mask() | brim
    now = PART.mask() | brim
    assert measure(now, before).area_mm2 == 0.0


def test_a_new_string_is_far_below_the_decision():
    string = np.zeros((H, W), bool)
    cv2.line(string.view(np.uint8), (209, 100), (260, 118), 1, 1)   # 1 px wide, ~14 mm long, attached
    result = measure(PART.mask() | string, PART.mask())
    assert 0 < result.area_mm2 < TWO_VIEWS_MM2 / 2


def test_new_material_far_from_the_part_or_reaching_in_from_above_does_not_count():
    search = Box(60, 65, 260, 200).mask()
    line = Box(20, 30, 300, 32).mask()             # the bed's far edge flickering, not attached to the part
    hotend = Box(215, 0, 235, 90).mask()           # the parked nozzle, hanging in from above the search box
    now = PART.mask() | line | hotend
    result = measure(now, PART.mask(), search=search)
    assert result.area_mm2 == 0.0


def test_strands_pulled_up_out_of_the_search_box_do_not_count():
    search = Box(60, 65, 260, 200).mask()          # up to 15 px (~3 mm) above the part's top
    strands = np.zeros((H, W), bool)
    for x0 in (130, 185):                           # two wisps from the top towards the parked nozzle
        cv2.line(strands.view(np.uint8), (x0, 79), (x0 + 12, 0), 1, 3)
    assert measure(PART.mask() | strands, PART.mask(), search=search).area_mm2 == 0.0
    # the same strands hanging down the part's side stay inside the box and count
    hanging = np.zeros((H, W), bool)
    cv2.line(hanging.view(np.uint8), (209, 90), (250, 190), 1, 3)
    assert measure(PART.mask() | hanging, PART.mask(), search=search).area_mm2 > 0


def test_a_part_a_layer_taller_than_its_outline_adds_nothing():
    before = Box(110, 112, 210, 170).mask()
    now = Box(110, 77, 210, 170).mask()            # 3 px above the outline: within the doubled top tolerance
    assert measure(now, before).area_mm2 == 0.0


def test_a_skirt_line_flickering_into_the_mask_does_not_count():
    skirt = Box(95, 176, 225, 178).mask()            # a 2-px line 6 px in front of the part, unseen last time
    skirt[170:176, 150:152] = True                   # touching the part's foot through one tooth of the brim
    marks = Box(90, 172, 230, 182).mask()            # the bed-marks zone around the footprint
    now = PART.mask() | skirt
    assert measure(now, PART.mask()).area_mm2 > 0
    assert measure(now, PART.mask(), marks=marks).area_mm2 == 0.0
    # strands that lie in the zone but also hang higher are a tangle
    strand = np.zeros((H, W), bool)
    strand[120:180, 214:217] = True
    strand[119:122, 208:217] = True
    assert measure(now | strand, PART.mask(), marks=marks).area_mm2 > 0


def test_loops_lying_around_the_foot_are_measured_apart():
    # a tangle lying on the bed beside the part's foot, wholly inside the bed-marks zone
    marks = Box(60, 150, 260, 200).mask()
    tangle = loops(centre=(236, 178), spread=(10, 6), count=12, thickness=2) & ~PART.mask()
    tangle[150:179, 211:214] = True                  # attached: one strand down the part's side ...
    tangle[176:179, 211:250] = True                  # ... and along the bed through the loops
    tangle &= marks
    now = PART.mask() | tangle
    distance = cv2.distanceTransform((~PART.mask()).astype(np.uint8), cv2.DIST_L2, 3)
    beyond = int((tangle & (distance > 2.0 * PX_PER_MM)).sum())
    # looking along printer X with x (a camera in front of the bed), then along printer Y (from the side)
    front = measure(now, PART.mask(), marks=marks, bed_to_image=np.array([[PX_PER_MM, 0.0], [0.0, -2.0]]))
    side = measure(now, PART.mask(), marks=marks, bed_to_image=np.array([[0.0, PX_PER_MM], [2.0, 0.0]]))
    assert front.area_mm2 == 0.0                     # not counted as before: it lies where a skirt would
    assert front.at_foot_mm2 == pytest.approx(beyond / PX_PER_MM ** 2) and front.at_foot_mm2 >= TWO_VIEWS_MM2
    assert front.with_foot_mm2 == pytest.approx(front.at_foot_mm2)
    assert front.direction == pytest.approx(0.0) and side.direction == pytest.approx(np.pi / 2)
    assert front.figures()["new_at_foot_mm2"] == pytest.approx(front.at_foot_mm2, abs=0.05)
    # a skirt line flickering in the same zone is not attached to the part: nothing at all
    skirt = Box(95, 190, 225, 192).mask()
    assert measure(PART.mask() | skirt, PART.mask(), marks=marks).at_foot_mm2 == 0.0


def test_material_at_the_foot_counts_when_two_sides_see_it():
    assert viewpoints({"a": 0.0, "b": np.radians(10.0)}) == 1       # a stereo pair: one place
    assert viewpoints({"a": np.radians(-175.0), "b": np.radians(178.0)}) == 1   # 7 deg apart
    assert viewpoints({"a": 0.0, "b": np.pi}) == 2                             # opposite sides
    assert viewpoints({"a": 0.0, "b": np.radians(60.0), "c": None}) == 3
    outside = {"a": 0.0, "b": 0.0}
    foot = {"a": TWO_VIEWS_MM2 + 2, "b": TWO_VIEWS_MM2 + 1}
    two_sides = {"a": 0.0, "b": np.radians(90.0)}
    reason = loose_material(outside, with_foot=foot, directions=two_sides)
    assert reason is not None and "a 8 mm²" in reason
    # one side only: a pair (or one camera) that sees a line flicker at the foot does not pause
    assert loose_material(outside, with_foot=foot, directions={"a": 0.0, "b": np.radians(12.0)}) is None
    assert loose_material(outside, with_foot={"a": foot["a"], "b": TWO_VIEWS_MM2 - 1}, directions=two_sides) is None
    assert loose_material({"a": 0.0}, with_foot={"a": 10 * ONE_VIEW_MM2}, directions={"a": 0.0}) is None
    assert loose_material(outside) is None                            # without the zone's blobs: nothing


def test_ignored_zones_and_missing_inputs():
    tangle = loops(centre=(150, 190), spread=(2, 8)) & ~PART.mask()
    tangle[168:200, 149:152] = True                 # hanging from the part's foot through every loop
    now = PART.mask() | tangle
    assert measure(now, PART.mask()).area_mm2 > 0
    assert measure(now, PART.mask(), ignore=Box(0, 171, W, H).mask()).area_mm2 == 0.0   # reflection zone
    assert measure(now, None) is None                                                    # first check
    assert new_material(now, PART.mask(), PART.mask(), EVERYWHERE, TOL, 0.0) is None     # no scale


# ---------------------------------------------------------------- the decision
def test_two_views_or_one_strong_view_decide():
    assert loose_material({"a": TWO_VIEWS_MM2, "b": TWO_VIEWS_MM2 + 1, "c": 0.0}) is not None
    assert loose_material({"a": TWO_VIEWS_MM2 + 1, "b": TWO_VIEWS_MM2 - 1}) is None
    assert loose_material({"a": ONE_VIEW_MM2}) is not None                 # the only usable camera
    assert loose_material({"a": ONE_VIEW_MM2 - 1}) is None
    assert loose_material({"a": 10 * ONE_VIEW_MM2, "b": None}) is None     # another view could corroborate
    reason = loose_material({"cam1": 40.0, "cam0": 7.0})
    assert reason.index("cam1 40 mm²") < reason.index("cam0 7 mm²") and "spaghetti" in reason


# ------------------------------------------------- through the whole shape check
@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def shape_of(bed, frame, previous):
    reg = replace(regions(), px_per_mm=PX_PER_MM)
    return check_shape("cam", camera_effects(bed, seed=11), frame, reg, last_observed=previous)


def test_check_shape_reports_the_tangle_and_decide_pauses_on_two_views(bed):
    first = shape_of(bed, camera_effects(paint_part(bed, PART)), None)
    assert first.new_outside is None                               # nothing to compare with yet
    normal = shape_of(bed, camera_effects(paint_part(bed, PART), seed=5), first.observed_mask)
    assert normal.new_outside.area_mm2 < 1.0

    scene = paint_part(bed, PART)
    strands = loops(count=10, thickness=3)
    strands[119:122, 206:240] = True                               # hanging from the part's side
    scene[strands & ~PART.mask()] = (40, 40, 210)
    tangled = shape_of(bed, camera_effects(scene, seed=5), first.observed_mask)
    assert tangled.new_outside.area_mm2 >= TWO_VIEWS_MM2
    assert tangled.figures()["new_outside_mm2"] == pytest.approx(tangled.new_outside.area_mm2, abs=0.05)

    settings = DetectionSettings()
    # the shape figures alone may pass (the strands are thin): the tangle from two views pauses
    verdict, reasons = decide({"cam0": tangled, "cam1": replace(tangled, camera="cam1")}, {}, settings)
    assert verdict == "fail" and any("material appeared around the part" in r for r in reasons)
    verdict, _ = decide({"cam0": normal, "cam1": replace(normal, camera="cam1")}, {}, settings)
    assert verdict == "ok"


def test_decide_pauses_on_loops_at_the_foot_seen_from_two_sides(bed):
    first = shape_of(bed, camera_effects(paint_part(bed, PART)), None)
    normal = shape_of(bed, camera_effects(paint_part(bed, PART), seed=5), first.observed_mask)
    settings = DetectionSettings()

    def seen(direction_deg):
        foot = NewMaterial(0.0, 0, 0, at_foot_mm2=TWO_VIEWS_MM2 + 3, direction=np.radians(direction_deg))
        return replace(normal, new_outside=foot)

    verdict, reasons = decide({"cam0": seen(0), "cam1": replace(seen(70), camera="cam1")}, {}, settings)
    assert verdict == "fail" and any("material appeared around the part" in r for r in reasons)
    # the two cameras of one stereo pair look from one side: no pause
    verdict, _ = decide({"cam0": seen(0), "cam1": replace(seen(8), camera="cam1")}, {}, settings)
    assert verdict == "ok"
