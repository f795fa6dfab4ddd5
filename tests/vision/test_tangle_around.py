"""Loose material that surrounds the part in one view (core/tangle.py: ``arc_around``, ``surrounds_part``).

Loops of a tangle drape down every side of the part and spread over the bed around its foot; what one view
reads as new material on a normal print lies on one side of it (the part's cast shadow, a glare line on a
glossy bed). A view whose new material spans more than half the circle around the part counts as two sides.
"""
from dataclasses import replace

import numpy as np

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.tangle import (ONE_VIEW_MM2, SURROUNDING_WITNESS_MM2, TWO_VIEWS_MM2, NewMaterial,
                                             arc_around, loose_material, witnessed_by_another)

from .synthetic import PART, Box, H, W
from .test_tangle import PX_PER_MM, measure
from .test_tangle_slowed import figures

MARKS = Box(60, 40, 260, 210).mask()         # the bed-marks zone around the footprint (PART: x 110-210, y 80-170)


def strands_around(sides):
    """(h, w) bool: 3-px strands leaving the part's outline outwards, 25 px long, on the given sides."""
    m = np.zeros((H, W), bool)
    reach = {"left": (slice(120, 123), slice(85, 111)), "right": (slice(150, 153), slice(209, 235)),
             "top": (slice(55, 81), slice(150, 153)), "bottom": (slice(169, 195), slice(130, 133)),
             "bottom-right": (slice(169, 195), slice(190, 193))}
    for side in sides:
        m[reach[side]] = True
    return m


def test_the_arc_of_new_material_around_the_part():
    scale = 1.0 / PX_PER_MM ** 2
    assert arc_around(np.zeros((H, W), bool), PART.mask(), scale) == 0.0
    one_side = arc_around(strands_around(["right"]), PART.mask(), scale)
    assert 0.0 < one_side <= 90.0
    assert arc_around(strands_around(["right", "bottom-right"]), PART.mask(), scale) <= 90.0
    assert arc_around(strands_around(["left", "right", "top", "bottom"]), PART.mask(), scale) > 180.0


def test_strands_at_the_foot_on_every_side_surround_the_part_a_shadow_on_one_side_does_not():
    around = measure(PART.mask() | strands_around(["left", "right", "top", "bottom"]), PART.mask(), marks=MARKS)
    assert around.area_mm2 == 0.0 and around.at_foot_mm2 >= TWO_VIEWS_MM2   # all of it where a skirt would lie
    assert around.surrounds_part and around.figures()["new_arc_deg"] > 180
    # the arc is read on the loops at the foot only: material beyond the zone counts by the other rules already
    # (a glass bed's mirror image of a growing part spreads below it over half the circle)
    beyond = measure(PART.mask() | strands_around(["left", "right", "top", "bottom"]), PART.mask())
    assert beyond.area_mm2 == around.at_foot_mm2 and beyond.arc_deg == 0.0 and not beyond.surrounds_part
    shadow = np.zeros((H, W), bool)
    shadow[140:170, 209:250] = True                  # a cast shadow's dark wedge beside the foot, one side
    one_side = measure(PART.mask() | shadow, PART.mask(), marks=MARKS)
    assert one_side.at_foot_mm2 >= TWO_VIEWS_MM2 and not one_side.surrounds_part


def test_one_view_of_loose_material_around_the_part_pauses_while_it_rises():
    foot = {"a": 8 * TWO_VIEWS_MM2, "b": 2.0 * SURROUNDING_WITNESS_MM2}   # b sees a few of the loops
    pair = {"a": 0.0, "b": np.radians(8.0)}           # a stereo pair: one side
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot=foot, directions=pair, rise_pct=70.0) is None
    reason = loose_material({"a": 0.0, "b": 0.0}, with_foot=foot, directions=pair, rise_pct=70.0, surrounding={"a"})
    assert reason is not None and "around the part in a" in reason
    # too little of it: a surrounding view must see as much as a lone camera (a new brim also lies around the part)
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot={"a": ONE_VIEW_MM2 - 1, "b": 0.0}, directions=pair,
                          rise_pct=70.0, surrounding={"a"}) is None
    # one camera, rising as the model says
    assert loose_material({"a": 0.0}, with_foot={"a": 80.0}, directions={"a": 0.0}, rise_pct=88.0,
                          surrounding={"a"}) is not None


def test_decide_pauses_on_one_view_whose_new_material_surrounds_the_part():
    s = DetectionSettings()
    # seed-5-like figures at a spaghetti's onset + 1: a stereo pair, 80 / 93 mm² at the foot, rising 80 / 90 %
    # (not slowed: test_tangle_spread.py has the part that slowed)
    views = {"s0L": figures("s0L", 80.0, at_foot_mm2=80.0), "s0R": figures("s0R", 90.0, at_foot_mm2=93.0)}
    views = {cam: replace(r, new_outside=replace(r.new_outside, direction=0.0, arc_deg=135.0))
             for cam, r in views.items()}
    assert decide(views, {}, s)[0] == "ok"             # one side, each view's material on one side of the part
    views["s0R"] = replace(views["s0R"], new_outside=replace(views["s0R"].new_outside, arc_deg=225.0))
    verdict, reasons = decide(views, {}, s)
    assert verdict == "fail" and any("around the part in s0R" in r for r in reasons)
    assert isinstance(views["s0R"].new_outside, NewMaterial)


def test_a_view_surrounded_alone_while_the_others_see_nothing_new_is_no_tangle():
    # seed-18-like figures: a skirt (or brim) line drawn into one view's mask at one check lies all around the
    # part, 35-116 mm² at the foot over 225°, while the other views measured no new material at all
    pair = {"a": 0.0, "b": np.radians(8.0)}
    alone = {"a": 4 * ONE_VIEW_MM2, "b": 0.0}
    assert not witnessed_by_another(("a",), alone)
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot=alone, directions=pair, rise_pct=100.0,
                          surrounding={"a"}) is None
    # another view seeing a strand's root of it corroborates: loops on every side are seen from other sides too
    seen = {"a": 4 * ONE_VIEW_MM2, "b": SURROUNDING_WITNESS_MM2}
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot=seen, directions=pair, rise_pct=100.0,
                          surrounding={"a"}) is not None
    # two surrounding views corroborate each other
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot={"a": 66.0, "b": 60.0}, directions=pair,
                          rise_pct=100.0, surrounding={"a", "b"}) is not None
    # no other view measured new material (a one-camera rig, or the others' first look): nothing to ask
    assert witnessed_by_another(("a",), {"a": 80.0, "b": None})
    assert loose_material({"a": 0.0, "b": None}, with_foot={"a": 80.0}, directions=pair, rise_pct=100.0,
                          surrounding={"a"}) is not None
    # the other view's silence does not hide a slowed part: one view of strands still pauses a part that stopped
    assert loose_material({"a": 0.0, "b": 0.0}, with_foot=alone, directions=pair, rise_pct=20.0,
                          surrounding={"a"}) is not None


def test_decide_ignores_one_view_surrounded_alone_while_the_part_rises():
    s = DetectionSettings()
    views = {"s0": figures("s0", 100.0, at_foot_mm2=35.0), "s1": figures("s1", 88.0)}
    views["s0"] = replace(views["s0"], new_outside=replace(views["s0"].new_outside, direction=0.0, arc_deg=225.0))
    views["s1"] = replace(views["s1"], new_outside=replace(views["s1"].new_outside, direction=np.pi / 2))
    assert decide(views, {}, s)[0] == "ok"
    views["s1"] = replace(views["s1"], new_outside=replace(views["s1"].new_outside, at_foot_mm2=2.0))  # a strand's root
    verdict, reasons = decide(views, {}, s)
    assert verdict == "fail" and any("around the part in s0" in r for r in reasons)
