"""DetectionSettings, the seed's rule, and the combined decision rule."""
from dataclasses import replace

import numpy as np
import pytest

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.seed_rules import seed_error
from octoprint_printwatch.core.settings import DetectionSettings, SettingsError, parse_camera_threshold
from octoprint_printwatch.core.shape_check import ShapeResult

from .synthetic import PART


def test_defaults_are_the_seed_values_and_round_trip():
    s = DetectionSettings()
    assert s.shape_threshold_pct == 7.0 and s.size_threshold_pct == 10.0
    s2 = DetectionSettings.from_dict({**s.to_dict(), "camera_thresholds": {"c1": 9}, "unknown": 1})
    assert s2.threshold_for("c1") == 9.0 and s2.threshold_for("c2") == 7.0
    assert DetectionSettings.from_dict(s2.to_dict()) == s2


@pytest.mark.parametrize("bad", [{"shape_threshold_pct": -1}, {"shape_threshold_pct": "x"},
                                 {"camera_thresholds": {"a": float("nan")}}, {"min_failing_cameras": 0}])
def test_bad_settings_are_refused(bad):
    with pytest.raises(SettingsError):
        DetectionSettings.from_dict(bad)


def test_camera_threshold_syntax():
    assert parse_camera_threshold("cam0L=8.5") == ("cam0L", 8.5)
    with pytest.raises(SettingsError, match="CAMERA=PERCENT"):
        parse_camera_threshold("8.5")


def test_seed_rule_absorbs_scale_and_position_which_is_its_weakness():
    expected = PART.mask()
    assert seed_error(expected, expected) == 0.0
    moved = np.roll(expected, 40, axis=1)       # a part that slid 40 px is "aligned back" by the seed
    assert seed_error(moved, expected) < 1.0
    half = expected.copy()
    half[80:125] = False                          # half the height missing is still seen
    assert seed_error(half, expected) > 40


def shape(name, passed=True, usable=True):
    return ShapeResult(name, 1.0 if passed else 20.0, 1.0, 0.0, 0.0, None, None, 0, 100, None, (0, 0), 7.0, 25.0,
                       passed=passed, usable=usable, reasons=[] if passed else [f"{name}: bad"])


def test_decide_fails_on_one_failing_camera_and_names_it():
    verdict, reasons = decide({"a": shape("a"), "b": shape("b", passed=False)}, {}, DetectionSettings())
    assert verdict == "fail" and reasons == ["b: bad"]


def test_decide_never_pauses_on_missing_evidence():
    s = DetectionSettings()
    assert decide({}, {}, s, ["a", "b"])[0] == "unknown"
    assert decide({"a": shape("a", passed=True, usable=False)}, {}, s)[0] == "unknown"
    verdict, reasons = decide({"a": shape("a")}, {}, s, ["b"])
    assert verdict == "ok" and "b: no frame" in reasons[0]


def test_decide_size_rule_and_abstention():
    s = DetectionSettings()
    assert decide({"a": shape("a")}, {"a+b": {"error_pct": 25.0}}, s)[0] == "fail"
    assert decide({"a": shape("a")}, {"a+b": {"error_pct": None, "abstained": True}}, s)[0] == "ok"
    assert decide({}, {"a+b": {"error_pct": 3.0}}, s)[0] == "ok"


def test_min_failing_cameras():
    s = DetectionSettings(min_failing_cameras=2)
    assert decide({"a": shape("a", passed=False), "b": shape("b")}, {}, s)[0] == "ok"
    assert decide({"a": shape("a", passed=False), "b": shape("b", passed=False)}, {}, s)[0] == "fail"


def figures(name, *, missing=0.0, extra=0.0, growth=None, band_missing=0.0):
    """A ShapeResult with the figures the decision rule reads (failing when over the 7 % threshold)."""
    error = missing + extra
    return ShapeResult(name, error, error, missing, extra, band_missing, band_missing, 500, 5000, growth,
                       (0, 0), 7.0, 50.0, passed=error <= 7.0, usable=True,
                       reasons=[] if error <= 7.0 else [f"{name}: shape differs"])


def test_missing_alone_from_one_camera_of_two_does_not_pause_a_growing_part():
    s = DetectionSettings()
    # a face the colour of the backdrop: one of two views "misses" material, the part still rises
    assert decide({"a": figures("a", missing=12.0, growth=100.0), "b": figures("b", growth=100.0)}, {}, s)[0] == "ok"
    assert decide({"a": figures("a", missing=12.0, growth=30.0), "b": figures("b", growth=40.0)}, {}, s)[0] == "ok"
    # ... but both views, or the only view, missing material is a failure
    assert decide({"a": figures("a", missing=12.0, growth=30.0),
                   "b": figures("b", missing=9.0, growth=40.0)}, {}, s)[0] == "fail"
    assert decide({"a": figures("a", missing=12.0)}, {}, s)[0] == "fail"
    # missing AND extra material (the part moved: decisive, as check_shape marks it) from one camera is enough
    moved = replace(figures("a", missing=8.0, extra=8.0), decisive=True)
    assert decide({"a": moved, "b": figures("b")}, {}, s)[0] == "fail"


def test_a_stall_needs_the_newest_layers_missing_in_a_view_that_saw_no_rise():
    s = DetectionSettings()
    # runout: no rise anywhere, and the newest layers are gone from one of those views
    stalled = {"a": figures("a", growth=0.0, missing=4.0, band_missing=30.0), "b": figures("b", growth=5.0),
               "c": figures("c", growth=60.0)}
    verdict, reasons = decide(stalled, {}, s)
    assert verdict == "fail" and any("not grown" in r for r in reasons)
    # a top skin closing: one view sees no rise but the newest layers in place; the view that "misses"
    # them saw the outline sink (impossible for a growing or a stalled part: that camera was fooled)
    closing = {"a": figures("a", growth=0.0), "b": figures("b", growth=127.0),
               "c": figures("c", growth=-100.0, missing=5.0, band_missing=26.0)}
    assert decide(closing, {}, s)[0] == "ok"


def test_outlines_that_sank_are_camouflage_not_a_stall():
    # a black top skin closing on a black bed: both outlines sink a little (-33 %, -20 % of the
    # expected rise) and some of the part looks missing; a stalled part reads 0 +- a pixel step
    s = DetectionSettings()
    sinking = {"a": figures("a", growth=-33.0, missing=5.4, band_missing=30.0),
               "b": figures("b", growth=-20.0, missing=2.0)}
    assert decide(sinking, {}, s)[0] == "ok"
    stalled = {"a": figures("a", growth=-8.0, missing=5.4, band_missing=30.0), "b": figures("b", growth=4.0)}
    assert decide(stalled, {}, s)[0] == "fail"


def test_a_top_skin_closing_that_reads_missing_as_a_whole_is_not_a_stall():
    # the last layers of a part close its top with a smooth skin that can look like the bed: no view
    # sees the outline rise and much of the top reads missing, but not the newest band itself
    s = DetectionSettings()
    closing = {"a": figures("a", growth=0.0, missing=6.0, band_missing=15.0), "b": figures("b", growth=0.0),
               "c": figures("c", growth=10.0, missing=1.7, band_missing=4.0)}
    assert decide(closing, {}, s, top_closing=True)[0] == "ok"
    # the same readings in the middle of the part are a stall (runout)
    verdict, reasons = decide(closing, {}, s, top_closing=False)
    assert verdict == "fail" and any("not grown" in r for r in reasons)
    # and at a closing top the newest band itself gone still is one
    gone = dict(closing, a=figures("a", growth=0.0, missing=6.0, band_missing=40.0))
    assert decide(gone, {}, s, top_closing=True)[0] == "fail"


def test_job_plan_knows_where_a_top_surface_closes():
    from octoprint_printwatch.core.geometry import part_from_mesh
    from octoprint_printwatch.core.pipeline import JobPlan
    from octoprint_printwatch.simulator.parts import library_part

    def plan(name):
        part = part_from_mesh(library_part(name))
        return JobPlan(part=part, cameras={}, pairs=[], check_heights=[], views={}, footprint=np.zeros((0, 2)),
                       max_shift_px={}, tolerance_px={})

    cube = plan("cube")   # 20 mm
    assert not cube.top_closing(10.0) and not cube.top_closing(18.5)
    assert cube.top_closing(19.4) and cube.top_closing(20.0)
    tiers = plan("tiers")   # steps at 8 and 16 mm (r 20 -> 13 -> 7), top at 26
    assert tiers.top_closing(7.6) and not tiers.top_closing(12.0) and tiers.top_closing(15.4)
    assert not tiers.top_closing(20.0) and tiers.top_closing(26.0)


def test_missing_material_alone_waits_for_a_cameras_second_look():
    """At a camera's first look, a top face the colour of the bed and a part that printed less look the
    same (material missing, nothing extra): the print is not paused until the next check can tell."""
    s = DetectionSettings()

    def missing(name, first_look, extra=0.0, decisive=False):
        return ShapeResult(name, 25.0 + extra, 30.0, 25.0, extra, None, None, 0, 100, None, (0, 0), 7.0, 50.0,
                           passed=False, reasons=[f"{name}: material missing"], decisive=decisive,
                           first_look=first_look)

    first = {"a": missing("a", True), "b": missing("b", True)}
    assert decide(first, {}, s)[0] == "ok"
    later = {"a": missing("a", False), "b": missing("b", False)}
    assert decide(later, {}, s)[0] == "fail"
    # a part displaced at the first look (missing AND extra material) does not wait
    moved = {"a": missing("a", True, extra=20.0, decisive=True), "b": shape("b")}
    assert decide(moved, {}, s)[0] == "fail"
