"""A view that stopped rising while its newest band turned textured (verdict.stopped_and_textured). Cross-check seed 20
``028_runout``: a part seen small from three views; at the check after the stop two views read the rise only over a
two-check span reaching back before it (71 % and 57 %), the third read a coarse 0 after a held rise of 90 %, nothing
missing anywhere, and that view's band read 4.3x as textured as at its previous check. No median of one-check readings
exists there (the textured-band rule needs one), so the stop was caught a check later."""
from __future__ import annotations

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, stopped_and_textured


def view(name, *, span=None, coarse=None, texture):
    """A passing view with nothing missing that reads the rise only over its span or only to the pixel."""
    r = ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, None, (0, 0), 7.0, 50.0,
                    passed=True, usable=True, reasons=[])
    r.span_growth_pct, r.coarse_growth_pct, r.band_texture = span, coarse, texture
    return r


SPAN_VIEWS = {"a": view("a", span=71.4, texture=16.8), "b": view("b", span=57.1, texture=13.9)}
TEXTURE_BEFORE = {"a": 10.5, "b": 14.1, "c": 7.35}
HELD = {"a": 100.0, "b": 85.7, "c": 90.0}


def test_a_view_that_stopped_under_a_band_turned_textured_pauses_where_no_one_check_reading_exists():
    s = DetectionSettings()
    usable = {**SPAN_VIEWS, "c": view("c", coarse=0.0, texture=31.25)}
    assert stopped_and_textured(usable, s, held_rise_before=HELD, band_texture_before=TEXTURE_BEFORE) == \
        {"c": 31.25 / 7.35}
    verdict, reasons = decide(usable, {}, s, band_texture_before=TEXTURE_BEFORE, held_rise_before=HELD)
    assert verdict == "fail"
    assert any(why.startswith("c: the newest layers look 4.3 times as textured") for why in reasons)
    # not where a top surface closes (its skin changes the band's look while the outline reads no rise)
    assert decide(usable, {}, s, band_texture_before=TEXTURE_BEFORE, held_rise_before=HELD,
                  top_closing=True)[0] == "ok"


def test_no_pause_from_a_view_that_never_rose_reads_a_rise_or_changed_its_look_only_a_little():
    s = DetectionSettings()
    textured = {**SPAN_VIEWS, "c": view("c", coarse=0.0, texture=31.25)}
    # a view that never read the part rise (a top it cannot resolve reads 0 at every check): no stop to witness
    assert decide(textured, {}, s, band_texture_before=TEXTURE_BEFORE, held_rise_before={"a": 100.0})[0] == "ok"
    # the view still reads part of the rise
    rising = {**SPAN_VIEWS, "c": view("c", coarse=25.0, texture=31.25)}
    assert decide(rising, {}, s, band_texture_before=TEXTURE_BEFORE, held_rise_before=HELD)[0] == "ok"
    # a change of look a normal print shows (1.5x: a tier's step entering the band)
    changed = {**SPAN_VIEWS, "c": view("c", coarse=0.0, texture=11.0)}
    assert decide(changed, {}, s, band_texture_before=TEXTURE_BEFORE, held_rise_before=HELD)[0] == "ok"
    # every other view reading the part rising as expected: the median of the finest readings is 80 % or more
    full = {"a": view("a", span=100.0, texture=16.8), "b": view("b", span=100.0, texture=13.9),
            "c": view("c", coarse=0.0, texture=31.25)}
    assert decide(full, {}, s, band_texture_before=TEXTURE_BEFORE, held_rise_before=HELD)[0] == "ok"
