"""A stalled part reads 0 +- a pixel of rise: a fine reading of the rise (one check's, or over a span) reads a stall
up to just above one pixel of the smallest rise a view reads finely (``growth.profile_growth``: a median expected rise
of 1.5 x 4 px, so one pixel is 16.7 %: ``verdict.FINE_STALL_PCT``), not only under ``min_growth_pct`` (15 %), where a
stopped part's one-pixel reading at a 6-px rise counted as rising. A reading to the pixel (``coarse_growth_pct``, a rise
of 4-6 px: a pixel is 17-25 %) keeps ``min_growth_pct``.

What a user would notice: a failed print caught a check later than it could be. Cross-check seed 33 ``034_spaghetti``
(a frame in the bed's colour, one stereo pair, onset check 17): at check 18 both views read 16.7 % of the expected rise
(1 px of 6), s0R misses 4.46 % of the part and 19 % of its newest band; with a 15 % limit the print ran on until check
19. Seed 28 ``024_runout`` (three cameras, onset check 10): at its onset check every view reads 16.7 %, two of them
missing 3.4 % and 4.4 %. A part that rose reads its whole rise (100 % +- a pixel): a reading of one pixel where six
were due is no part still rising."""
from __future__ import annotations

from dataclasses import replace

from octoprint_printwatch.core.growth import profile_growth
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, fine_stall_limit

import numpy as np


def view(name: str, *, missing: float = 0.0, band_missing: float = 0.0, growth: float | None = None) -> ShapeResult:
    failed = missing > 7.0 or band_missing > 50.0
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth, (0, 0),
                       7.0, 50.0, passed=not failed, usable=True,
                       reasons=[f"{name}: material missing"] if failed else [])


def rise_read(expected_px: int, seen_px: int) -> float:
    """The fine reading of a part seen rising ``seen_px`` where the model rises ``expected_px`` (a wide flat top)."""
    h, w = 80, 40
    expected_before = np.zeros((h, w), bool)
    expected_before[50:] = True
    expected = np.zeros((h, w), bool)
    expected[50 - expected_px:] = True
    observed = np.zeros((h, w), bool)
    observed[50 - seen_px:] = True
    return profile_growth(observed, expected_before, expected, expected_before, min_rise=4.0)


def test_one_pixel_of_the_smallest_fine_rise_reads_no_rise():
    s = DetectionSettings()
    one_pixel = rise_read(6, 1)           # the smallest rise read finely: 1.5 x 4 px
    assert one_pixel is not None and abs(one_pixel - 100.0 / 6.0) < 1e-3
    assert one_pixel < fine_stall_limit(s)
    assert rise_read(6, 0) < fine_stall_limit(s)
    # two pixels of six, or the rise read in full, are a part still rising
    assert rise_read(6, 2) > fine_stall_limit(s) and rise_read(6, 6) > fine_stall_limit(s)
    # a user's higher limit still holds
    assert fine_stall_limit(DetectionSettings(min_growth_pct=25.0)) == 25.0


def test_two_views_reading_one_pixel_of_rise_with_the_newest_layers_missing_stall_the_print():
    s = DetectionSettings()
    # seed 33 ``034_spaghetti`` check 18 (onset 17)
    views = {"s0L": view("s0L", missing=1.44, band_missing=6.52, growth=100.0 / 6.0),
             "s0R": view("s0R", missing=4.46, band_missing=19.32, growth=100.0 / 6.0)}
    verdict, reasons = decide(views, {}, s)[:2]
    assert verdict == "fail"
    assert any("has not grown" in r and "16.7% of the expected rise seen" in r and "limit 17%" in r for r in reasons)
    # a view that read the rise in full keeps the print running, as before
    rising = {**views, "s0L": replace(views["s0L"], growth_pct=100.0, missing_pct=0.0, band_missing_pct=0.0,
                                      error_pct=0.0, raw_error_pct=0.0, band_error_pct=0.0)}
    assert decide(rising, {}, s)[0] == "ok"
    # with nothing of the newest layers missing, one pixel of rise is no stall either (a top face in the bed's colour)
    quiet = {name: replace(r, missing_pct=0.0, band_missing_pct=0.0, error_pct=0.0, raw_error_pct=0.0,
                           band_error_pct=0.0) for name, r in views.items()}
    assert decide(quiet, {}, s)[0] == "ok"


def test_three_views_reading_one_pixel_at_the_onset_check():
    s = DetectionSettings()
    # seed 28 ``024_runout`` check 10 (its onset)
    views = {"s0": view("s0", missing=3.36, band_missing=8.94, growth=100.0 / 6.0),
             "s1": view("s1", missing=4.43, band_missing=13.15, growth=100.0 / 6.0),
             "s2": view("s2", missing=0.28, band_missing=0.49, growth=100.0 / 6.0)}
    assert decide(views, {}, s)[0] == "fail"


def test_a_reading_to_the_pixel_keeps_the_settings_limit():
    s = DetectionSettings()
    # cross-check seed 28 ``023_layer_shift`` check 9 (one camera, before its onset, a face in the bed's colour): a
    # reading to the pixel of 16.7 % (a rise of 4-6 px, where a pixel is 17-25 %), material missing since the view read
    # the part rising: under the settings' 15 % only a reading of no rise is a stall
    before = dict(rise_before={"s0": 50.0}, missing_before={"s0": 0.0})
    coarse = replace(view("s0", missing=5.0, band_missing=14.0), coarse_growth_pct=100.0 / 6.0)
    assert decide({"s0": coarse}, {}, s, **before)[0] == "ok"
    assert decide({"s0": replace(coarse, coarse_growth_pct=0.0)}, {}, s, **before)[0] == "fail"
