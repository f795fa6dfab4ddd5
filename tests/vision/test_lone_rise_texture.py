"""Strands piled over a part where only one of several views reads the rise (verdict.lone_rise_reading). Cross-check
seed 42 ``038_spaghetti`` (a flat natural stack on gold PEI, a pair and a single camera): at the check after the
strands began, every view's newest band read 2.4-3.0 times as textured as at the check before, and the strands hid the
pair's tops, so only the single camera read the rise (25 %, to the pixel). The textured-band rule needs a median of
two readings (or a one-camera rig's own), so the print was paused a check later, when two views read the stop."""
from __future__ import annotations

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, lone_rise_reading


def view(name, *, texture, coarse=None, growth=None):
    """A passing view with nothing missing, reading the rise finely (``growth``), to the pixel (``coarse``) or not."""
    r = ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, None, (0, 0), 7.0, 50.0,
                    passed=True, usable=True, reasons=[])
    r.growth_pct, r.coarse_growth_pct, r.band_texture = growth, coarse, texture
    return r


BEFORE = {"s0L": 10.68, "s0R": 13.65, "s1": 5.09}
ROSE = {"s1": 100.0}   # s1's reading at the check before (to the pixel)


def seed42(*, rise=25.0, textures=(27.21, 33.11, 15.24)):
    return {"s0L": view("s0L", texture=textures[0]), "s0R": view("s0R", texture=textures[1]),
            "s1": view("s1", texture=textures[2], coarse=rise)}


def test_a_band_turned_textured_pauses_with_the_only_reading_of_a_slow_rise():
    s = DetectionSettings()
    usable = seed42()
    assert lone_rise_reading(usable, ROSE) == 25.0
    verdict, reasons = decide(usable, {}, s, band_texture_before=BEFORE, rise_before=ROSE)
    assert verdict == "fail"
    assert any(why.startswith("s1: the newest layers look 3.0 times as textured as at the checks before while the part "
                              "rose 25% of the expected height (read by one view)") for why in reasons), reasons


def test_no_pause_where_the_lone_reading_shows_the_part_rising_or_the_look_changed_as_normal_prints_do():
    s = DetectionSettings()
    # the one view reads over half the rise: a normal print's top read to the pixel (+-25 %) by one view
    assert decide(seed42(rise=60.0), {}, s, band_texture_before=BEFORE, rise_before=ROSE)[0] == "ok"
    # bands 1.5-1.9 times as textured: what a tier's step or infill entering the band does (a median's rule under
    # 50 % takes 1.5x; a lone reading needs twice)
    mild = seed42(textures=(1.9 * 10.68, 1.9 * 13.65, 1.9 * 5.09))
    assert decide(mild, {}, s, band_texture_before=BEFORE, rise_before=ROSE)[0] == "ok"
    # where a top surface closes (its skin changes the band's look while the outline reads no rise)
    assert decide(seed42(), {}, s, band_texture_before=BEFORE, rise_before=ROSE, top_closing=True)[0] == "ok"
    # a view that read no rise at its previous check either: a top it cannot resolve reads 0 at every check
    assert lone_rise_reading(seed42(), {"s1": 0.0}) is None
    assert decide(seed42(), {}, s, band_texture_before=BEFORE, rise_before={"s1": 0.0})[0] == "ok"
    # no view reads the rise (every top hidden): no reading to witness anything
    none = seed42(rise=None)
    assert lone_rise_reading(none, ROSE) is None
    assert decide(none, {}, s, band_texture_before=BEFORE, rise_before=ROSE)[0] == "ok"


def test_two_readings_make_a_median_the_lone_reading_does_not_override():
    s = DetectionSettings()
    usable = seed42()
    usable["s0L"].growth_pct = 95.0
    # two readings (95 % fine, 25 % to the pixel): no lone reading; their median (60 %) weighs 2x bands as before
    assert lone_rise_reading(usable, ROSE) is None
    verdict, reasons = decide(usable, {}, s, band_texture_before=BEFORE, rise_before=ROSE)
    assert verdict == "fail"
    assert any("as textured" in why and "rose 60% of the expected height" in why for why in reasons), reasons
    assert not any("(read by one view)" in why for why in reasons)
