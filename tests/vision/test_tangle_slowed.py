"""Spaghetti seen by one view while the part's rise slowed (core/tangle.loose_material, ``rise_pct``).

A tangle stops the part while its strands drape beyond the outline; often only one view sees strands beyond
the outline (the others see them hang inside it, or over what they saw at the previous check). Material new
since the previous check in one view is then corroborated by the growth test: the outline rose under half the
expected height in the median of two or more views. Without the slowed rise, one view still never pauses.
"""
from dataclasses import replace

import numpy as np
import pytest

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import check_shape
from octoprint_printwatch.core.tangle import ONE_VIEW_MM2, SLOWED_RISE_PCT, TWO_VIEWS_MM2, NewMaterial, loose_material

from .synthetic import PART, bed_texture, camera_effects, paint_part, regions
from .test_tangle import PX_PER_MM, loops


def test_one_view_of_new_material_counts_only_while_the_part_slowed():
    one_view = {"a": TWO_VIEWS_MM2 + 1, "b": 0.0, "c": 0.0}
    assert loose_material(one_view) is None                                     # as before: one view
    reason = loose_material(one_view, rise_pct=30.0)
    assert reason is not None and "a 7 mm²" in reason and "rose 30%" in reason
    assert loose_material(one_view, rise_pct=SLOWED_RISE_PCT) is None            # rising as the model says
    assert loose_material({"a": TWO_VIEWS_MM2 - 1, "b": 0.0}, rise_pct=0.0) is None   # too little material
    assert loose_material({"a": ONE_VIEW_MM2 - 1}) is None         # one camera without a rise reading: not enough
    # one camera whose own outline rose under half: its growth test corroborates (test_slowed_part_stopped_earlier)
    assert loose_material({"a": TWO_VIEWS_MM2 + 1}, rise_pct=0.0) is not None
    # loops at the foot (the bed-marks zone) seen by one camera count too, from one side
    foot = loose_material({"a": 0.0, "b": 0.0}, with_foot={"a": TWO_VIEWS_MM2 + 2, "b": 0.0},
                          directions={"a": 0.0, "b": np.radians(8.0)}, rise_pct=20.0)
    assert foot is not None and "a 8 mm²" in foot


def figures(name, growth, new_mm2=0.0, at_foot_mm2=0.0):
    """A passing view with its growth reading and new material (decide's inputs)."""
    from octoprint_printwatch.core.shape_check import ShapeResult
    return ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, growth, (0, 0), 7.0, 50.0, passed=True,
                       usable=True, reasons=[], new_outside=NewMaterial(new_mm2, 0, 0, at_foot_mm2=at_foot_mm2))


def test_decide_pauses_on_one_view_of_strands_when_the_median_rise_is_under_half():
    s = DetectionSettings()
    # seed-4-like figures at a spaghetti flag check: 22 / 33 / 26 % rise, one view sees 14 mm² of new material
    views = {"s0L": figures("s0L", 22.0), "s0R": figures("s0R", 33.0, new_mm2=13.6, at_foot_mm2=19.3),
             "s1": figures("s1", 26.0, new_mm2=5.2)}
    verdict, reasons = decide(views, {}, s)
    assert verdict == "fail" and any("material appeared around the part" in r and "rose 26%" in r for r in reasons)
    # the same material while the part rises as the model says: one view, no pause
    rising = {cam: replace(r, growth_pct=100.0) for cam, r in views.items()}
    assert decide(rising, {}, s)[0] == "ok"
    # a slow rise measured by one view only is no median to trust
    one_growth = {cam: replace(r, growth_pct=None) for cam, r in views.items()}
    one_growth["s0L"] = views["s0L"]
    assert decide(one_growth, {}, s)[0] == "ok"
    # where a top surface closes a normal part's outline may not rise (a ridge's last layers are too thin to see)
    assert decide(views, {}, s, top_closing=True)[0] == "ok"
    # a slow rise without new material is not this rule's (nothing missing: the other stall rules judge it)
    assert decide({cam: replace(r, new_outside=NewMaterial(0.0, 0, 0)) for cam, r in views.items()}, {}, s)[0] == "ok"


@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def test_strands_measured_by_the_shape_check_pause_a_slowed_part_seen_by_one_view(bed):
    reg = replace(regions(), px_per_mm=PX_PER_MM)
    first = check_shape("a", camera_effects(bed, seed=11), camera_effects(paint_part(bed, PART)), reg)
    scene = paint_part(bed, PART)
    strands = loops(count=6, thickness=2)
    strands[120:122, 206:240] = True                               # hanging from the part's side
    scene[strands & ~PART.mask()] = (40, 40, 210)
    tangled = check_shape("a", camera_effects(bed, seed=11), camera_effects(scene, seed=5), reg,
                          last_observed=first.observed_mask)
    clean = check_shape("b", camera_effects(bed, seed=12), camera_effects(paint_part(bed, PART), seed=6), reg,
                        last_observed=first.observed_mask)
    # thin strands: the view passes its shape check, but sees the strands as new material
    assert tangled.passed and tangled.new_outside.with_foot_mm2 >= TWO_VIEWS_MM2
    assert clean.passed and clean.new_outside.with_foot_mm2 < 1.0
    s = DetectionSettings()
    slowed = {"a": replace(tangled, growth_pct=30.0), "b": replace(clean, growth_pct=20.0)}
    verdict, reasons = decide(slowed, {}, s)
    assert verdict == "fail" and any("spaghetti" in r for r in reasons)
    rising = {"a": replace(tangled, growth_pct=95.0), "b": replace(clean, growth_pct=100.0)}
    assert decide(rising, {}, s)[0] == "ok"
