"""The coarse growth reading: a part whose rise per check is 4-6 px (seen small, checks a few layers apart)."""
import numpy as np

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.growth import COARSE_RISE_FACTOR, profile_growth
from octoprint_printwatch.core.shape_check import ShapeResult


def box(top, h=80, w=60, left=10, right=50, bottom=70):
    m = np.zeros((h, w), bool)
    m[top:bottom, left:right] = True
    return m


def test_a_five_pixel_rise_is_read_only_coarsely():
    expected_before, expected = box(40), box(35)          # the model rises 5 px (under 1.5 x 4 px)
    # the fine reading abstains whatever the part did
    assert profile_growth(box(35), box(40), expected, expected_before, min_rise=4.0) is None
    assert profile_growth(box(40), box(40), expected, expected_before, min_rise=4.0) is None
    # the coarse one reads a rising part as rising and a stopped one as stopped
    rising = profile_growth(box(35), box(40), expected, expected_before, min_rise=4.0, median_factor=COARSE_RISE_FACTOR)
    stopped = profile_growth(box(40), box(40), expected, expected_before, min_rise=4.0, median_factor=COARSE_RISE_FACTOR)
    assert rising == 100.0 and stopped == 0.0
    # under min_rise (3 px) it abstains too: that is edge wobble
    assert profile_growth(box(37), box(40), box(37), expected_before, min_rise=4.0,
                          median_factor=COARSE_RISE_FACTOR) is None


def view(name, *, growth=None, coarse=None, band_missing=0.0, missing=0.0):
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth,
                       (0, 0), 7.0, 50.0, passed=True, usable=True, reasons=[], coarse_growth_pct=coarse)


def test_coarse_readings_stand_in_only_where_no_camera_resolves_the_rise():
    s = DetectionSettings()
    rose = {"s0": 80.0, "s1": 75.0, "s2": 100.0}            # each view read the part rising at its previous check
    before = {"s0": 0.0, "s1": 0.0, "s2": 0.0}              # and missed nothing there
    # two views at 4-5 px per check read no rise now and one misses 4.6 % of the part (s5 038-like): stalled
    stopped = {"s0": view("s0", coarse=0.0, band_missing=5.7, missing=4.6), "s1": view("s1", coarse=0.0),
               "s2": view("s2")}
    verdict, reasons = decide(stopped, {}, s, rise_before=rose, missing_before=before)
    assert verdict == "fail" and any("not grown as expected" in r for r in reasons)
    # without the coarse readings (HEAD) nothing could be said
    assert decide({"s0": view("s0", band_missing=5.7, missing=4.6), "s1": view("s1")}, {}, s,
                  rise_before=rose, missing_before=before)[0] == "ok"
    # a coarse rising part does not stall
    assert decide({"s0": view("s0", coarse=75.0, band_missing=5.7, missing=4.6), "s1": view("s1", coarse=100.0)},
                  {}, s, rise_before=rose, missing_before=before)[0] == "ok"
    # a camera that resolves the rise decides: a stopped coarse view next to a rising fine one does not stall
    assert decide({"s0": view("s0", coarse=0.0, band_missing=30.0, missing=4.6), "s1": view("s1", growth=90.0),
                   "s2": view("s2", coarse=0.0)}, {}, s, rise_before=rose, missing_before=before)[0] == "ok"
    # nothing newly missing (a flat rise; a face in the bed's colour that misses as much at every check)
    assert decide({"s0": view("s0", coarse=0.0), "s1": view("s1", coarse=0.0)}, {}, s,
                  rise_before=rose, missing_before=before)[0] == "ok"
    assert decide({"s0": view("s0", coarse=0.0, missing=12.9), "s1": view("s1", coarse=0.0)}, {}, s,
                  rise_before=rose, missing_before={"s0": 13.8, "s1": 0.0})[0] == "ok"
    # a view that did not read the part rising at its previous check (it never sees the top rise) does not count
    assert decide({"s0": view("s0", coarse=0.0, missing=19.9), "s1": view("s1")}, {}, s,
                  rise_before={"s0": 0.0}, missing_before=before)[0] == "ok"
    # nor at a closing top
    assert decide(stopped, {}, s, rise_before=rose, missing_before=before, top_closing=True)[0] == "ok"


def test_a_stop_between_two_checks_is_read_against_the_last_check_that_rose():
    """Cross-check seed 7 044_runout: the views read the part rising (100 %) at check 12, no rise at check 13
    (the stop) with nothing missing yet (the newest layers too thin), and at check 14 no rise again with 3.9 %
    of the part missing. At check 14 the previous reading is the stop itself (0 %), so the coarse rule of
    HEAD, which needs a rise at the previous check, never looked again."""
    from octoprint_printwatch.core.verdict import missing_since_rise
    s = DetectionSettings()
    # the state a view keeps: its missing material at the check that rose, while it reads a stall since
    kept, quiet = missing_since_rise(None, 100.0, 0.0, s.min_growth_pct)    # check 12: rose, 0 % missing
    assert (kept, quiet) == (0.0, 0)
    kept, quiet = missing_since_rise(kept, 0.0, 0.0, s.min_growth_pct, quiet, 7.0)   # check 13: the stop
    assert (kept, quiet) == (0.0, 1)                                    # (nothing missing yet: one quiet check)
    # any other reading (a rise of 15-50 %, an outline that sank) forgets it
    assert missing_since_rise(0.0, 30.0, 1.0, s.min_growth_pct)[0] is None
    assert missing_since_rise(0.0, -40.0, 1.0, s.min_growth_pct)[0] is None
    # check 14: both views read no rise, 3.9 / 4.1 % missing; at check 13 they read 0 % (rise_before) and
    # missed nothing (missing_before)
    now = {"s0L": view("s0L", coarse=0.0, band_missing=10.8, missing=3.86),
           "s0R": view("s0R", coarse=0.0, band_missing=12.8, missing=4.09)}
    before = dict(rise_before={"s0L": 0.0, "s0R": 0.0}, missing_before={"s0L": 0.0, "s0R": 0.0})
    assert decide(now, {}, s, **before)[0] == "ok"                    # HEAD: no view rose at its previous check
    verdict, reasons = decide(now, {}, s, **before, missing_at_rise={"s0L": kept, "s0R": kept})
    assert verdict == "fail" and any("not grown as expected" in r for r in reasons)
    # a view that never read a rise (a face in the bed's colour reads 0 % at every check) still does not count
    assert decide(now, {}, s, **before, missing_at_rise={})[0] == "ok"
    # nor does material missing as much as when the part last rose (a face the camera cannot tell apart)
    assert decide(now, {}, s, **before, missing_at_rise={"s0L": 3.0, "s0R": 3.5})[0] == "ok"
    # nor where a fine reading exists, nor at a closing top
    fine = dict(now, s1=view("s1", growth=95.0))
    assert decide(fine, {}, s, **before, missing_at_rise={"s0L": 0.0, "s0R": 0.0})[0] == "ok"
    assert decide(now, {}, s, **before, missing_at_rise={"s0L": 0.0, "s0R": 0.0}, top_closing=True)[0] == "ok"


def test_a_view_keeps_its_rise_through_checks_where_the_model_gives_it_nothing_to_read():
    """Cross-check seed 8 020_runout (a stack on blue tape, two cameras; s0 looks down and sees the upper tier
    inside the lower one's silhouette, so only s1 can see the stop). s1 read the part rising at check 4 (coarse
    60 %, 0 % missing), no rise at check 5 (3.3 % missing), then no reading at checks 6-7: the upper tier is
    printed inside the silhouette of the lower one there, so the model's outline does not rise in this view at
    all (0 columns) and a runout and a normal print look the same. At check 8 s1 reads no rise with 6.7 %
    missing. HEAD forgot the rise at the first check without a reading, and s1's missing material (one camera of
    two) never counted: the print was never paused."""
    from octoprint_printwatch.core.verdict import missing_since_rise
    s = DetectionSettings()
    state = missing_since_rise(None, 60.0, 0.0, s.min_growth_pct)                       # check 4
    for rise, missing in ((0.0, 3.27), (None, 3.30), (None, 4.71)):                     # checks 5-7
        state = missing_since_rise(*state[:1], rise, missing, s.min_growth_pct, state[1], 7.0)
    assert state[0] == 0.0
    # check 8: s1 reads no rise with 6.7 % missing, s0 (no reading at all, nothing missing) passes
    now = {"s0": view("s0"), "s1": view("s1", coarse=0.0, band_missing=21.5, missing=6.71)}
    before = dict(rise_before={"s1": None}, missing_before={"s0": 0.0, "s1": 4.71})
    assert decide(now, {}, s, **before)[0] == "ok"                                      # HEAD: forgotten
    verdict, reasons = decide(now, {}, s, **before, missing_at_rise={"s1": state[0]})
    assert verdict == "fail" and any("not grown as expected" in r for r in reasons)


def test_a_view_that_reads_no_rise_while_nothing_goes_missing_forgets_its_rise():
    """Cross-check seed 1 007_normal s0R (a normal print): one coarse reading of 100 % at check 4, then 0 % at
    every check with nothing missing (the view cannot see this part's top rise), then none at checks 11-13 (a
    tier inside the silhouette), then 0 % with a passing 19.9 % missing at check 15. A stop late in an interval
    may show nothing missing at the first check after it, never at the second: the rise is forgotten there."""
    from octoprint_printwatch.core.verdict import RISE_QUIET_CHECKS, missing_since_rise
    s = DetectionSettings()
    state = missing_since_rise(None, 100.0, 0.0, s.min_growth_pct)                      # check 4
    state = missing_since_rise(*state[:1], 0.0, 0.0, s.min_growth_pct, state[1], 7.0)   # check 5: quiet, kept
    assert state == (0.0, 1) and RISE_QUIET_CHECKS == 2
    state = missing_since_rise(*state[:1], 0.0, 0.19, s.min_growth_pct, state[1], 7.0)  # check 6: forgotten
    assert state[0] is None
    # no reading keeps nothing that is forgotten
    assert missing_since_rise(None, None, 19.9, s.min_growth_pct, 0, 7.0)[0] is None
    # material going missing is not quiet: kept however many checks it takes
    state = (0.0, 1)
    for missing in (2.0, 3.0, 3.2):
        state = missing_since_rise(*state[:1], 0.0, missing, s.min_growth_pct, state[1], 7.0)
    assert state == (0.0, 1)


def test_a_view_that_reads_the_rise_only_coarsely_corroborates_the_stall_the_fine_readings_find():
    # cross-check seed 17 ``032_runout`` check 3: s0L reads the part still, finely, and misses 2.5 %; s0R, at 4-5 px
    # per check, reads it still to the pixel and misses 10 % of it (19 % of the newest band)
    s = DetectionSettings()
    fine = view("s0L", growth=0.0, band_missing=4.7, missing=2.5)
    verdict, reasons = decide({"s0L": fine, "s0R": view("s0R", coarse=0.0, band_missing=19.4, missing=10.0)}, {}, s)
    assert verdict == "fail" and any("has not grown" in why for why in reasons)
    # ... not where the coarse view reads the part rising, nor where it misses nothing
    assert decide({"s0L": fine, "s0R": view("s0R", coarse=100.0, band_missing=19.4, missing=10.0)}, {}, s)[0] == "ok"
    assert decide({"s0L": fine, "s0R": view("s0R", coarse=0.0)}, {}, s)[0] == "ok"


def test_two_views_that_held_a_rise_and_read_none_now_stalled_with_little_missing_yet():
    # cross-check seed 17 ``024_runout`` check 6 (and seed 13 ``032``, seed 15 ``032``): three views of a part seen
    # small read it rising (coarsely) at their last two checks and not at all now; the stop came late in the
    # interval, so one view misses 3 % of the part (under half the threshold) and the others nothing
    s = DetectionSettings()
    now = {"s0L": view("s0L", coarse=0.0, band_missing=5.8, missing=3.0), "s0R": view("s0R", coarse=0.0),
           "s1": view("s1", coarse=0.0)}
    rose = {cam: 100.0 for cam in now}                       # each read a rise at its previous check
    verdict, reasons = decide(now, {}, s, rise_before=rose, held_rise_before={"s0L": 75.0, "s0R": 100.0, "s1": 75.0})
    assert verdict == "fail" and any("has not grown" in why for why in reasons)
    # one view alone is a pixel step of that view (a top it cannot resolve reads 0-200 % by turns)
    assert decide(now, {}, s, rise_before=rose, held_rise_before={"s0L": 75.0, "s0R": 25.0, "s1": 0.0})[0] == "ok"
    # ... and views that did not hold a rise before need missing material, as ever
    assert decide(now, {}, s, rise_before=rose)[0] == "ok"
    # ... and a trace of the newest layers must be missing: two views misread a black top on a black bed under JPEG's
    # blocks as still, with nothing missing (the default set's layer_shift_05 at quality 35)
    blank = {cam: view(cam, coarse=0.0) for cam in now}
    assert decide(blank, {}, s, rise_before=rose, held_rise_before={"s0L": 75.0, "s0R": 100.0, "s1": 75.0})[0] == "ok"
    # views that read the part rising now keep the median up; nor where a top surface closes
    rising = {"s0L": now["s0L"], "s0R": now["s0R"], "s2": view("s2", growth=100.0), "s3": view("s3", growth=83.3)}
    assert decide(rising, {}, s, rise_before=rose, held_rise_before={"s0L": 75.0, "s0R": 100.0})[0] == "ok"
    assert decide(now, {}, s, rise_before=rose, held_rise_before={"s0L": 75.0, "s0R": 100.0, "s1": 75.0},
                  top_closing=True)[0] == "ok"


def test_two_views_that_read_the_rise_finely_and_stopped_need_little_missing_either():
    # cross-check seed 1 ``052_runout`` check 4: both views read 83 % at the check before and 0 % now; one misses
    # 2.3 % of the part (under half the threshold), the other 0.4 %
    s = DetectionSettings()
    now = {"s0": view("s0", growth=0.0, band_missing=3.8, missing=2.3),
           "s1": view("s1", growth=0.0, band_missing=0.5, missing=0.4)}
    assert decide(now, {}, s)[0] == "ok"
    assert decide(now, {}, s, held_rise_before={"s0": 83.3, "s1": 83.3})[0] == "fail"


def test_the_only_usable_view_that_held_a_rise_and_reads_none_now_stalled_with_a_trace_missing():
    # a one-camera rig sees a part small: its view read the part rising (coarsely) at its last two checks and not at
    # all now; the stop came late in the interval, so it misses 0.9 % of the part and 3.2 % of its newest band (under
    # half the threshold, under the band's 25 %)
    s = DetectionSettings()
    now = {"s0": view("s0", coarse=0.0, band_missing=3.2, missing=0.9)}
    rose = {"s0": 100.0}
    verdict, reasons = decide(now, {}, s, rise_before=rose, held_rise_before={"s0": 75.0})
    assert verdict == "fail" and any("has not grown" in why for why in reasons)
    # the view must have held the rise before (one reading of a rise before a 0 is a pixel step) ...
    assert decide(now, {}, s, rise_before=rose)[0] == "ok"
    # ... and a trace must be missing: a top the camera cannot resolve reads 0 now and then with nothing missing
    blank = {"s0": view("s0", coarse=0.0)}
    assert decide(blank, {}, s, rise_before=rose, held_rise_before={"s0": 75.0})[0] == "ok"
    # nor where a top surface closes
    assert decide(now, {}, s, rise_before=rose, held_rise_before={"s0": 75.0}, top_closing=True)[0] == "ok"
    # on a rig of two usable views, one such view is still a pixel step of that view while the other reads the rise
    two = {**now, "s1": view("s1", coarse=100.0)}
    assert decide(two, {}, s, rise_before={**rose, "s1": 100.0}, held_rise_before={"s0": 75.0, "s1": 75.0})[0] == "ok"
