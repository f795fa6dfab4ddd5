"""Two cases of spaghetti over a stopped part that the slowed-part rules caught a check late (cross-check seed 8,
ninth session): known-answer figures through ``decide`` and ``loose_material``.

* A part that stopped *before* the previous check: its gap reaches below the newest band, so the band reads only
  partly missing (10.6 %) while the whole part misses over half the threshold (7.55 %): the slowed-part rule
  counts such a view, as the stall rule's ``band_gone`` does (seed 8 ``054_spaghetti``, check 2).
* A one-camera rig whose only view sees the outline rise under half the expected height and strands beyond it:
  the growth test corroborates the new material there too (seed 8 ``030_spaghetti``, check 5).
"""
from dataclasses import replace

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.tangle import ONE_VIEW_MM2, SLOWED_RISE_PCT, TWO_VIEWS_MM2, NewMaterial, loose_material


def figures(name, *, growth, band_missing=0.0, missing=0.0, new_mm2=0.0, at_foot_mm2=0.0):
    """A ShapeResult with the figures decide reads (failing on missing material alone over the 7 % threshold)."""
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth,
                       (0, 0), 7.0, 50.0, passed=missing <= 7.0, usable=True, reasons=[],
                       new_outside=NewMaterial(new_mm2, 0, 0, at_foot_mm2=at_foot_mm2))


def test_a_slowed_part_missing_half_the_threshold_in_two_views_pauses():
    s = DetectionSettings()
    # seed 8 054, check 2: 28.6 / 25 % rise, band 10.6 / 20.1 % missing, the part 7.55 / 13.6 % missing
    # (s0's missing material passes for the bed pixel by pixel but not all of it as a group: it waits)
    views = {"s0": replace(figures("s0", growth=28.6, band_missing=10.6, missing=7.55),
                           background_missing_pct=6.43, background_band_missing_pct=9.04),
             "s1": figures("s1", growth=25.0, band_missing=20.1, missing=13.61)}
    verdict, reasons = decide(views, {}, s)
    assert verdict == "fail" and any("not grown as expected" in r for r in reasons)
    # the same missing material with the part rising as the model says: a face the camera cannot see
    assert decide({c: replace(r, growth_pct=90.0) for c, r in views.items()}, {}, s)[0] == "ok"
    # one view misses little (under half the threshold, band under 15 %): nothing corroborates the slow rise
    little = dict(views, s0=figures("s0", growth=28.6, band_missing=10.6, missing=3.0))
    assert decide(little, {}, s)[0] == "ok"
    # at a closing top a flat rise and a skin reading missing are expected
    assert decide(views, {}, s, top_closing=True)[0] == "ok"


def test_one_camera_seeing_strands_while_its_outline_rose_under_half_pauses():
    # loose_material: one camera, its own rise as the witness
    assert loose_material({"a": TWO_VIEWS_MM2 + 1}) is None                             # no rise reading
    reason = loose_material({"a": TWO_VIEWS_MM2 + 1}, rise_pct=20.0)
    assert reason is not None and "rose 20%" in reason
    assert loose_material({"a": TWO_VIEWS_MM2 + 1}, rise_pct=SLOWED_RISE_PCT) is None   # rising as it should
    assert loose_material({"a": TWO_VIEWS_MM2 - 1}, rise_pct=0.0) is None               # too little material
    foot = loose_material({"a": 0.0}, with_foot={"a": TWO_VIEWS_MM2 + 2}, directions={"a": 0.0}, rise_pct=20.0)
    assert foot is not None and "a 8 mm²" in foot
    assert loose_material({"a": ONE_VIEW_MM2}) is not None                              # as before

    s = DetectionSettings()
    # seed 8 030, check 5: one camera, 20 % rise, 7.8 mm² of strands beyond the outline and 8.1 at the foot
    view = figures("s0", growth=20.0, band_missing=12.5, missing=5.6, new_mm2=7.8, at_foot_mm2=8.1)
    verdict, reasons = decide({"s0": view}, {}, s)
    assert verdict == "fail" and any("material appeared around the part" in r and "rose 20%" in r for r in reasons)
    # the part rising as the model says, no rise reading, or a closing top: one view of new material is not enough
    assert decide({"s0": replace(view, growth_pct=100.0)}, {}, s)[0] == "ok"
    assert decide({"s0": replace(view, growth_pct=None)}, {}, s)[0] == "ok"
    assert decide({"s0": view}, {}, s, top_closing=True)[0] == "ok"
    # a slow rise without strands beyond the outline is the stall rules' to judge (nothing missing here)
    assert decide({"s0": replace(view, new_outside=NewMaterial(0.0, 0, 0))}, {}, s)[0] == "ok"
