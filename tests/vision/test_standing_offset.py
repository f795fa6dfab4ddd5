"""Missing material a view already read while it saw the part rise is a standing offset, not a runout: decide
lets it wait unless more of the part, or of its newest band, is missing now (verdict.standing_offset; CheckRunner
keeps each view's lowest readings at its rising checks: verdict.lowest_missing_while_rising)."""
from functools import reduce

from octoprint_printwatch.core.verdict import decide, lowest_missing_while_rising
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult


def view(name, missing, band, *, growth=None, coarse=None):
    failing = missing > 7.0 or band > 50.0
    return ShapeResult(name, missing, missing, missing, 0.0, band, band, 500, 5000, growth, (0, 0), 7.0, 50.0,
                       passed=not failing, usable=True, reasons=[f"{name}: material missing"] if failing else [],
                       coarse_growth_pct=coarse)


def while_rising(history):
    """The lowest readings CheckRunner keeps from a view's checks: (missing, band missing, rise read), oldest first."""
    return reduce(lambda kept, check: lowest_missing_while_rising(kept, check[2], check[0], check[1]), history, None)


def test_a_view_that_misses_what_it_missed_while_the_part_rose_waits():
    """Cross-check seed 15 030_spaghetti (filament like the bed; the three other cameras cannot tell the part from
    the bed): s3 misses 14.5 %, 21.8 % and 10.8 % at its first checks while it reads the part rising 67 % and 108 %,
    then 13.8 % (band 24 %) with a rise of 33 %: the only usable view fails and the print paused 3 checks before
    the spaghetti started."""
    s = DetectionSettings()
    kept = while_rising([(14.52, 14.52, None), (21.8, 12.87, 66.7), (10.78, 16.95, 108.3)])
    assert kept == (10.78, 12.87)
    now = {"s3": view("s3", 13.83, 24.17, growth=33.3)}
    assert decide(now, {}, s)[0] == "fail"                                   # the base
    assert decide(now, {}, s, missing_while_rising={"s3": kept})[0] == "ok"
    # a stop leaves more missing on top of the offset: half the threshold more of the part, or its newest band gone
    more = {"s3": view("s3", 10.78 + 3.5, 24.17, growth=33.3)}
    assert decide(more, {}, s, missing_while_rising={"s3": kept})[0] == "fail"
    band_gone = {"s3": view("s3", 13.83, 12.87 + 25.0, growth=33.3)}
    assert decide(band_gone, {}, s, missing_while_rising={"s3": kept})[0] == "fail"


def test_two_views_with_standing_offsets_wait():
    """Cross-check seed 14 042_spaghetti check 9 (filament like the kapton bed, one check before the onset): s0
    missed 46-61 % at every check since its first, 46.5 % (band 54.5-58 %) while reading rises of 100-150 %; s1
    missed 20.2 % (band 62 %) at its coarse rise of 100 %. Now 44 % and 17.8 % (bands 55 % and 61 %), two views of
    three, with a median rise of 40 %: the base paused."""
    s = DetectionSettings()
    s0 = while_rising([(53.45, 55.95, 120.0), (49.32, 54.86, 108.3), (47.24, 54.49, 100.0), (42.76, 51.28, 16.7),
                       (46.49, 58.36, 150.0)])
    s1 = while_rising([(20.36, 56.46, None), (20.17, 61.88, 100.0)])
    assert s0 == (46.49, 54.49) and s1 == (20.17, 61.88)
    now = {"s0": view("s0", 44.05, 55.5, growth=66.7), "s1": view("s1", 17.78, 61.01, coarse=100.0),
           "s2": view("s2", 5.1, 2.32, growth=14.3)}
    assert decide(now, {}, s)[0] == "fail"
    assert decide(now, {}, s, missing_while_rising={"s0": s0, "s1": s1})[0] == "ok"


def test_only_rising_checks_set_the_offset():
    assert while_rising([(30.0, 60.0, None), (30.0, 60.0, 49.9), (12.0, 20.0, 0.0)]) is None
    assert while_rising([(12.0, None, 50.0), (15.0, 30.0, 80.0), (9.0, 40.0, 10.0)]) == (12.0, 30.0)


def test_a_view_missing_a_share_of_every_band_while_rising_may_miss_that_share_of_the_part():
    """Cross-check seed 23 033_detach (a 9 mm polygon, filament like the kapton bed, pair + 1; onset check 17): s0R
    missed 55-61 % of its newest band while it read the part rising 60-100 % (26-29 % of the part). As the layers
    it cannot tell from the bed piled up, its share of the whole part climbed check by check (34, 36, 38 ... 52 %)
    with its band still 54-65 % missing: s0L (18 %) and s0R, two views of three, paused the print 11 checks before
    its onset."""
    s = DetectionSettings()
    s0r = while_rising([(27.16, 55.03, 100.0), (26.15, 60.0, 60.0), (29.23, 60.96, 66.7)])
    assert s0r == (26.15, 55.03)
    now = {"s0L": view("s0L", 18.28, 40.59, coarse=20.0), "s0R": view("s0R", 36.02, 62.4, growth=33.3),
           "s1": view("s1", 0.0, 0.0, coarse=120.0)}
    assert decide(now, {}, s, missing_while_rising={"s0R": s0r})[0] == "ok"
    # the base read only half the threshold over its lowest share of the part: 36 % is 10 points over 26 %
    assert decide(now, {}, s, missing_while_rising={"s0R": (26.15, None)})[0] == "fail"
    # more of the part missing than of each band it read while rising, or the newest band gone, still counts
    beyond = {**now, "s0R": view("s0R", 55.03 + 0.5, 62.4, growth=33.3)}
    assert decide(beyond, {}, s, missing_while_rising={"s0R": s0r})[0] == "fail"
    band_gone = {**now, "s0R": view("s0R", 36.02, 55.03 + 25.0, growth=33.3)}
    assert decide(band_gone, {}, s, missing_while_rising={"s0R": s0r})[0] == "fail"
