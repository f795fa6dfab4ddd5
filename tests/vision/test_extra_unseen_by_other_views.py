"""Extra material that one view reads while every other view passes and sees none at all (verdict.decide,
verdict.unseen_by_the_other_views). Material standing beside the part stands on the bed, where the other cameras look
too; extra material no other view sees in any amount is the failing view's own error: its outline laid beside the part
(a first look or an anchor on a brim: the part's side beyond the outline) or its background frame (a parked head's
shadow whose edge moved). In a two-view rig one failing view is half of them and paused the print alone (cross-check
seed 12 ``010_normal``, seed 24 ``013_normal``). Decisive extra material, a displaced newest band, extra material a
second view sees some of, and a view with no other view to ask still fail as before."""
from __future__ import annotations

from dataclasses import replace

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.tangle import NewMaterial
from octoprint_printwatch.core.verdict import decide, unseen_by_the_other_views


def view(name: str, *, extra: float = 0.0, missing: float = 0.0, band: float = 0.0) -> ShapeResult:
    error = extra + missing
    failed = error > 7.0 or band > 50.0
    r = ShapeResult(name, error, error, missing, extra, band, 0.0, 500, 5000, 100.0, (0, 0), 7.0, 50.0,
                    passed=not failed, usable=True, reasons=[f"{name}: differs"] if failed else [])
    r.decisive = error > 7.0 and (min(missing, extra) >= 7.0 / 3.0 or extra >= 28.0)
    return r


def test_extra_material_no_other_view_sees_does_not_pause_a_two_view_rig():
    s = DetectionSettings()
    # the part's side beside an outline anchored a few px off it: 16 % extra, 2 % missing in one of two views
    beside = view("a", extra=16.3, missing=2.0)
    assert not beside.decisive and unseen_by_the_other_views(beside, {"a": beside, "b": view("b")})
    assert decide({"a": beside, "b": view("b")}, {}, s)[0] == "ok"
    # a second view that sees some extra material (and passes) is a witness: the first view counts
    verdict, reasons = decide({"a": beside, "b": view("b", extra=1.0)}, {}, s)
    assert verdict == "fail" and "a: differs" in reasons
    # ... and one that measured new material beside the part (strands off the outline; seed 24 ``030_spaghetti``'s
    # first failing check: 11 % extra in s0, s1 passing with none in its outline but 9 mm^2 new beside it)
    strands = replace(view("b"), new_outside=NewMaterial(9.0, 150, 2))
    verdict, reasons = decide({"a": beside, "b": strands}, {}, s)
    assert verdict == "fail" and reasons == ["a: differs"]
    assert decide({"a": beside, "b": replace(strands, new_outside=NewMaterial(0.8, 12, 1))}, {}, s)[0] == "ok"
    # (the loops at the part's foot count: 1.1 mm^2 beyond the bed-marks zone, 7.4 in it)
    at_foot = replace(strands, new_outside=NewMaterial(1.1, 20, 1, at_foot_mm2=7.4))
    assert decide({"a": beside, "b": at_foot}, {}, s)[0] == "fail"
    # ... as does a second view that fails itself
    assert decide({"a": beside, "b": view("b", missing=20.0, extra=8.0)}, {}, s)[0] == "fail"


def test_decisive_extra_a_displaced_band_or_no_view_to_ask_still_pause():
    s = DetectionSettings()
    other = view("b")
    # four times the threshold where a view cannot read the part rising (a part knocked loose, strands from a nozzle
    # printing in the air), or extra material under three times the missing (the part displaced: it left a gap): a
    # detachment or a spaghetti seen from one side only
    heap = view("a", extra=40.0)
    assert heap.decisive
    assert decide({"a": replace(heap, growth_pct=None), "b": other}, {}, s)[0] == "fail"
    assert decide({"a": replace(heap, growth_pct=30.0), "b": other}, {}, s)[0] == "fail"
    assert decide({"a": heap, "b": replace(other, growth_pct=None)}, {}, s)[0] == "fail"
    assert decide({"a": view("a", extra=40.0, missing=25.0), "b": other}, {}, s)[0] == "fail"
    assert decide({"a": view("a", extra=9.0, missing=6.0), "b": other}, {}, s)[0] == "fail"
    # (seed 20 ``043_layer_shift`` s0 after its onset: 25.9 % extra, 13.0 % missing, twice as much, the others at 0.0
    # and rising)
    assert decide({"a": view("a", extra=27.0, missing=13.0), "b": other}, {}, s)[0] == "fail"
    assert decide({"a": replace(heap, moved_px=(30, 0)), "b": other}, {}, s)[0] == "fail"
    # the newest band displaced (a layer shift one view's band sees)
    banded = view("a", extra=8.0, band=57.0)
    assert not unseen_by_the_other_views(banded, {"a": banded, "b": other})
    assert decide({"a": banded, "b": other}, {}, s)[0] == "fail"
    # the only other view read against a relit background is no witness either way
    lit = replace(other, relit=True)
    assert decide({"a": view("a", extra=16.3, missing=2.0), "b": lit}, {}, s)[0] == "fail"
    # a one-camera rig
    assert decide({"a": view("a", extra=16.3, missing=2.0)}, {}, s)[0] == "fail"
    # missing material is not this rule's
    missing = view("a", missing=12.0, extra=1.0)
    assert not unseen_by_the_other_views(missing, {"a": missing, "b": other})


def test_decisive_extra_no_other_view_sees_while_two_views_read_the_part_rise_does_not_pause():
    # lit bed where the background frame had a shadow, far beside a part that rises as the model says in this view
    # and another (cross-check seed 27 ``016_normal`` s1, 39.6 %); the part's side beyond an outline laid down a brim
    # (seed 22 ``017_normal`` s0R, 53 %, its band "displaced" by the same material)
    s = DetectionSettings()
    heap = view("a", extra=39.6, band=92.0)
    views = {"a": heap, "b": view("b"), "c": replace(view("c"), growth_pct=None), "d": view("d")}
    assert heap.decisive and unseen_by_the_other_views(heap, views)
    assert decide(views, {}, s)[0] == "ok"
    # the part's side beyond an outline frozen a few px off it, a sliver of missing bed at its other edge (seed 14
    # ``009_normal`` s1: 11.1 % extra, 2.5 % missing, decisive by a tenth of a point)
    side = view("a", extra=11.1, missing=2.5)
    assert side.decisive and decide({"a": side, "b": view("b"), "c": view("c")}, {}, s)[0] == "ok"
    # ... a second view that sees some of it is a witness
    assert decide({**views, "d": view("d", extra=0.5)}, {}, s)[0] == "fail"
