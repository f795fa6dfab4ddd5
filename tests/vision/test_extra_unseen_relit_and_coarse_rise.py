"""One view's extra material that no other view not read against a relit background sees (verdict.decide,
verdict.unseen_by_the_other_views), two readings of the other views:

* a relit view (``ShapeResult.relit``: a reflection swept across a glossy bed) reads lit bed as extra material where the
  reflection crosses the part; decide never lets it fail a print alone, and its extra is no witness for another view's
  either (cross-check seed 22 ``017_normal``: s0R's outline laid down a brim, 33-53 % extra at every check, its stereo
  partner s0L 0.0 %, the relit third view s1 1-44 % of lit bed: paused at seven checks);
* a view that sees the part small reads its rise since the previous check to the pixel (``coarse_growth_pct``); that
  reading says the part rose as much as a fine one does (seed 28 ``002_normal``: s1, 28.6 % extra, coarse 100 %, the three
  other views 0.0 % and rising). A reading over a span of checks reaches back before the check and does not count.

A relit view alone, a relit view with no other view that was not relit, and a decisive view with no reading of the rise
since the previous check in another view still pause."""
from __future__ import annotations

from dataclasses import replace

from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, rise_since_previous_check, unseen_by_the_other_views


def view(name: str, *, extra: float = 0.0, missing: float = 0.0, band: float = 0.0, relit: bool = False) -> ShapeResult:
    error = extra + missing
    failed = error > 7.0 or band > 50.0
    r = ShapeResult(name, error, error, missing, extra, band, 0.0, 500, 5000, 100.0, (0, 0), 7.0, 50.0,
                    passed=not failed, usable=True, reasons=[f"{name}: differs"] if failed else [])
    r.decisive = error > 7.0 and (min(missing, extra) >= 7.0 / 3.0 or extra >= 28.0)
    r.relit = relit
    return r


def test_a_relit_views_extra_material_does_not_witness_another_views():
    s = DetectionSettings()
    # seed 22 ``017_normal`` check 4: s0R 39.7 % extra (decisive), its band "61 % displaced"; s0L 0.0 %; relit s1 1.9 %
    brim = view("s0R", extra=39.7, band=61.0)
    views = {"s0L": view("s0L"), "s0R": brim, "s1": view("s1", extra=1.9, relit=True)}
    assert brim.decisive and unseen_by_the_other_views(brim, views)
    assert decide(views, {}, s)[0] == "ok"
    # ... and where the relit view fails on its own lit bed (check 12: 29 % extra, band 115 %), it fails nothing alone
    lit = view("s1", extra=29.2, band=115.0, relit=True)
    assert decide({**views, "s1": lit}, {}, s)[0] == "ok"
    # the same relit reading beside a view that was not relit and sees some extra too still corroborates
    assert decide({**views, "s0L": view("s0L", extra=1.0), "s1": lit}, {}, s)[0] == "fail"
    # no view that was not relit to ask: the failing view speaks
    assert not unseen_by_the_other_views(brim, {"s0R": brim, "s1": view("s1", relit=True)})
    assert decide({"s0R": brim, "s1": view("s1", relit=True)}, {}, s)[0] == "fail"
    # a view that was not relit and sees some extra material is a witness, as before
    assert decide({**views, "s0L": view("s0L", extra=0.5)}, {}, s)[0] == "fail"


def test_a_rise_read_to_the_pixel_counts_a_rise_over_a_span_does_not():
    s = DetectionSettings()
    # seed 28 ``002_normal`` check 9: s1 28.6 % extra, band "60 % displaced", its rise read to the pixel (100 %)
    small = replace(view("s1", extra=28.6, band=60.4), growth_pct=None, coarse_growth_pct=100.0)
    others = {name: view(name) for name in ("s0", "s2", "s3")}
    views = {**others, "s1": small}
    assert rise_since_previous_check(small) == 100.0
    assert small.decisive and unseen_by_the_other_views(small, views)
    assert decide(views, {}, s)[0] == "ok"
    # the other view's rise read to the pixel counts too
    two = {"a": replace(view("a", extra=40.0), growth_pct=100.0),
           "b": replace(view("b"), growth_pct=None, coarse_growth_pct=100.0)}
    assert decide(two, {}, s)[0] == "ok"
    # a coarse reading of no rise, in the failing view or in every other, is none (strands from a part that stopped)
    assert decide({**views, "s1": replace(small, coarse_growth_pct=25.0)}, {}, s)[0] == "fail"
    assert decide({**two, "b": replace(two["b"], coarse_growth_pct=0.0)}, {}, s)[0] == "fail"
    # a rise read over a span of checks reaches back before the check (seed 13 ``042_spaghetti``'s first catch: s0
    # 99 % extra, s1 0.0 % with only a two-check span reading): not a reading of the part rising since then
    spanned = replace(view("b"), growth_pct=None, span_growth_pct=83.3)
    assert rise_since_previous_check(spanned) is None
    assert decide({"a": two["a"], "b": spanned}, {}, s)[0] == "fail"
