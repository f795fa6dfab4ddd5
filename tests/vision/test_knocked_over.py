"""A part knocked off its place that no view reads as extra material (verdict.knocked_over). Cross-check seed 20
``053_detach``: a slim box moved 21 mm, seen by a stereo pair; at the check after it both views read their outline
sunk by a whole check's rise (coarse -100 %), one view misses 55 % of the part and the other, which cannot tell the
part from the bed, nothing: missing material alone from one of two views (a face the colour of what lies behind it
looks like that) paused nothing, and the print was missed."""
from __future__ import annotations

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, knocked_over


def view(name, *, coarse, missing, relit=False):
    """A view reading the rise to the pixel only, with ``missing`` % of the part missing and nothing extra."""
    r = ShapeResult(name, missing, missing, missing, 0.0, 0.0, 0.0, 500, 5000, None, (0, 0), 7.0, 50.0,
                    passed=missing <= 7.0, usable=True, reasons=[f"{name}: material missing"] if missing > 7.0 else [])
    r.coarse_growth_pct, r.relit = coarse, relit
    return r


def test_two_sunk_outlines_with_most_of_the_part_gone_in_one_pause():
    s = DetectionSettings()
    fallen = {"a": view("a", coarse=-100.0, missing=0.0), "b": view("b", coarse=-100.0, missing=55.5)}
    assert knocked_over(fallen) is not None
    verdict, reasons = decide(fallen, {}, s)
    assert verdict == "fail"
    assert any("outline sank in a, b" in why and "b misses 56%" in why for why in reasons)


def test_one_sunk_outline_little_missing_or_a_relit_view_pause_nothing():
    s = DetectionSettings()
    # one view's outline sinking over a face it cannot tell from what lies behind it, most of the part "missing"
    one = {"a": view("a", coarse=0.0, missing=0.0), "b": view("b", coarse=-100.0, missing=55.5)}
    assert decide(one, {}, s)[0] == "ok"
    # two sunk outlines over a black top on a black bed, a few % missing (the default set's normal_01 under gamma 0.8)
    little = {"a": view("a", coarse=-100.0, missing=0.1), "b": view("b", coarse=-100.0, missing=9.4)}
    assert decide(little, {}, s)[0] == "ok"
    # an outline lowered by a pixel step (-25 %) is no fall
    step = {"a": view("a", coarse=-25.0, missing=0.0), "b": view("b", coarse=-25.0, missing=55.5)}
    assert decide(step, {}, s)[0] == "ok"
    # a view read against a relit background only corroborates
    relit = {"a": view("a", coarse=-100.0, missing=0.0, relit=True), "b": view("b", coarse=-100.0, missing=55.5),
             "c": view("c", coarse=0.0, missing=0.0)}
    assert decide(relit, {}, s)[0] == "ok"
