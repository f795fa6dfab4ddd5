"""Whether the part grows, where fewer than two views read its rise finely (verdict.decide, verdict.visibly_rising,
verdict.readings_of_the_rise): a view that sees the part small reads its rise since the previous check only to the pixel
(``coarse_growth_pct``), and that reading stands in beside the fine ones.

What a user would notice: a normal print paused as "material missing: runout, clog or stopped print?" or "the part has
not grown as expected" while the part went on rising. Two shapes of it on cross-check seeds 30 and 31 (base ``CD25``):

* seed 30 ``008_normal`` (black on glass, two cameras): s0 cannot tell the part from the background, so s1 is the only
  usable view; s1 misses 12-17 % of the part (its top face is the colour of the glass behind it) while it reads the
  rise to the pixel at 100-140 %. The "visibly grows" rule read only fine readings, found none, and s1's missing
  material alone, one view of one, paused the print at five checks;
* seed 31 ``033_detach`` check 13 (a slim polygon in the bed's colour, two cameras, 19 checks before the onset): s1
  reads no rise (0 %, finely) and misses 9.8 %, s0 passes and reads the rise to the pixel at 110 %. The stall rule's
  median was s1's reading alone: "0 % of the expected rise seen (median of 1 camera(s))".

A reading to the pixel is +-25 %, so a rise read at 100 % or so is no stopped part (0 +- a pixel step). Where it stands
in for the "visibly grows" rule, it clears only missing material the view already missed at a check that passed (a face
it cannot tell from what lies behind it is missing from its first look on): a part that tipped over goes missing at once
while its outline's top may still read a rise (seed 30 ``053_detach``, caught at its onset as before). A one-camera
rig's own fine reading, a stop read to the pixel in every view, and two views reading finely are judged as before."""
from __future__ import annotations

from dataclasses import replace

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, missed_as_much_before, readings_of_the_rise, visibly_rising


def view(name: str, *, missing: float = 0.0, band_missing: float = 0.0, growth: float | None = None,
         coarse: float | None = None) -> ShapeResult:
    failed = missing > 7.0 or band_missing > 50.0
    r = ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth, (0, 0),
                    7.0, 50.0, passed=not failed, usable=True, reasons=[f"{name}: material missing"] if failed else [])
    return replace(r, coarse_growth_pct=coarse)


def test_the_only_usable_view_reading_the_rise_to_the_pixel_shows_the_part_growing():
    s = DetectionSettings()
    # seed 30 ``008_normal`` check 8: s1 the only usable view, 14.2 % missing, its newest band 55 % missing, coarse
    # 132.5 %; at its first look (check 7, passed: a first look's missing material waits) it missed 16.1 %
    s1 = view("s1", missing=14.2, band_missing=54.8, coarse=132.5)
    before = {"s1": 16.1}
    assert readings_of_the_rise({"s1": s1}) == [132.5] and visibly_rising({"s1": s1})
    assert missed_as_much_before(s1, before)
    assert decide({"s1": s1}, {}, s, most_missing_before=before)[0] == "ok"
    # check 10: 17.1 % missing, within half the threshold of the most it missed at a check that passed
    assert decide({"s1": replace(s1, missing_pct=17.1, error_pct=17.1)}, {}, s, most_missing_before=before)[0] == "ok"
    # a stop read to the pixel (0 +- a pixel step) is no rise: the missing material counts, as before
    assert decide({"s1": replace(s1, coarse_growth_pct=0.0)}, {}, s, most_missing_before=before)[0] == "fail"
    assert decide({"s1": replace(s1, coarse_growth_pct=25.0)}, {}, s, most_missing_before=before)[0] == "fail"
    # no earlier look to have missed it at: as before
    assert decide({"s1": s1}, {}, s)[0] == "fail"


def test_missing_material_that_appears_at_once_is_no_face_the_view_cannot_see():
    s = DetectionSettings()
    # seed 30 ``053_detach`` check 11 (one camera, black on glass): the part tipped over 54 deg and slid 13 mm; s0
    # misses 20.7 % where it missed nothing at its earlier checks, while its outline's top reads 140 % to the pixel
    tipped = view("s0", missing=20.7, band_missing=4.7, coarse=140.0)
    assert visibly_rising({"s0": tipped}) and not missed_as_much_before(tipped, {"s0": 0.0})
    assert decide({"s0": tipped}, {}, s, most_missing_before={"s0": 0.0})[0] == "fail"


def test_one_fine_reading_of_no_rise_is_no_stall_where_another_view_reads_the_full_rise_to_the_pixel():
    s = DetectionSettings()
    # seed 31 ``033_detach`` check 13: s1 0 % finely, 9.8 % missing; s0 passes, 110 % to the pixel
    views = {"s0": view("s0", coarse=110.0), "s1": view("s1", missing=9.8, band_missing=12.1, growth=0.0)}
    assert sorted(readings_of_the_rise(views)) == [0.0, 110.0]
    assert decide(views, {}, s)[0] == "ok"
    # where the other view reads the stop too, to the pixel, the part stalled
    assert decide({**views, "s0": view("s0", coarse=25.0)}, {}, s)[0] == "fail"
    # two views reading finely are a median of their own: a third view's reading to the pixel does not join it
    fine = {**views, "s2": view("s2", growth=0.0, missing=4.0)}
    assert readings_of_the_rise(fine) == [0.0, 0.0]
    assert decide(fine, {}, s)[0] == "fail"


def test_a_one_camera_rigs_fine_reading_is_its_own():
    s = DetectionSettings()
    alone = {"s0": view("s0", missing=9.8, band_missing=30.0, growth=0.0)}
    assert readings_of_the_rise(alone) == [0.0] and not visibly_rising(alone)
    assert decide(alone, {}, s)[0] == "fail"
