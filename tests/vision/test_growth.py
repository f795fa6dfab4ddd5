"""The stall rule for a part that slowed (spaghetti piling on a stopped part): known-answer figures."""
from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult


def figures(name, *, growth, band_missing=0.0, missing=0.0):
    """A passing ShapeResult carrying the growth and newest-band figures the stall rule reads."""
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth,
                       (0, 0), 7.0, 50.0, passed=True, usable=True, reasons=[])


def test_a_part_rising_at_a_third_of_the_rate_with_its_newest_band_thinning_in_two_views_pauses():
    s = DetectionSettings()
    views = {"a": figures("a", growth=11.0, band_missing=21.0), "b": figures("b", growth=38.0, band_missing=35.0),
             "c": figures("c", growth=44.0, band_missing=17.0)}
    verdict, reasons = decide(views, {}, s)
    assert verdict == "fail"
    assert any("not grown as expected" in r for r in reasons)


def test_a_slow_rise_without_band_missing_or_in_one_view_or_at_a_closing_top_does_not_pause():
    s = DetectionSettings()
    # strands fill the band: nothing missing, nothing to corroborate the slow rise
    assert decide({"a": figures("a", growth=33.0), "b": figures("b", growth=30.0)}, {}, s)[0] == "ok"
    # one view's band thins (a face the colour of the bed), the other's does not
    assert decide({"a": figures("a", growth=30.0, band_missing=40.0), "b": figures("b", growth=30.0)},
                  {}, s)[0] == "ok"
    # the part keeps rising fully: a band reading missing is the camera, not the part
    assert decide({"a": figures("a", growth=100.0, band_missing=40.0),
                   "b": figures("b", growth=90.0, band_missing=40.0)}, {}, s)[0] == "ok"
    # a top surface closing: a flat rise and a smooth skin reading missing are expected
    assert decide({"a": figures("a", growth=20.0, band_missing=40.0), "b": figures("b", growth=20.0,
                   band_missing=40.0)}, {}, s, top_closing=True)[0] == "ok"
    # one usable camera: nothing corroborates it
    assert decide({"a": figures("a", growth=20.0, band_missing=40.0)}, {}, s)[0] == "ok"
