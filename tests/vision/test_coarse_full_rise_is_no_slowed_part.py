"""A rise read to the pixel alone, in which one view reads the full rise, is no slowed part for the texture rule
(verdict.rose_in_a_view_read_to_the_pixel).

What a user would notice: a normal print paused at its third check. Cross-check seed 39 ``006_normal`` (a yellow cone
17 mm tall on black PEI, two 800x600 cameras that see it small): at layer 39 both views read the rise only to the pixel,
s0 50 % and s1 100 % (median 75 %, "slowed somewhat"), and s0's newest band, near its texture floor at the two checks
before, looked 2.9 times as textured at the cone's shoulder. The print was paused for strands piled over the part.
"""
from __future__ import annotations

from pathlib import Path

from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import rose_in_a_view_read_to_the_pixel

from .check_runs import run_checks

RECORDING = Path(__file__).resolve().parents[1] / "data" / "recordings" / "cone_yellow_coarse_full_rise_pair"


def test_a_view_reading_the_full_rise_to_the_pixel_keeps_a_changed_band_from_pausing():
    results = run_checks(RECORDING)
    assert all(r.verdict == "ok" for r in results), [(r.layer, r.reasons) for r in results if r.verdict != "ok"]
    last = results[-1].shape
    assert all(r.growth_pct is None for r in last.values())
    assert sorted(r.coarse_growth_pct for r in last.values()) == [50.0, 100.0]
    assert rose_in_a_view_read_to_the_pixel(last)


def view(name: str, coarse: float | None, fine: float | None = None) -> ShapeResult:
    return ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, fine, (0, 0), 7.0, 50.0, passed=True,
                       usable=True, reasons=[], coarse_growth_pct=coarse)


def test_only_a_full_reading_to_the_pixel_with_no_fine_reading_counts():
    assert rose_in_a_view_read_to_the_pixel({"a": view("a", 50.0), "b": view("b", 100.0)})
    # two views each reading two thirds: the part may have slowed
    assert not rose_in_a_view_read_to_the_pixel({"a": view("a", 66.7), "b": view("b", 71.4)})
    # a fine reading decides the rise where there is one
    assert not rose_in_a_view_read_to_the_pixel({"a": view("a", 100.0), "b": view("b", None, fine=44.4)})
    # a top that jumped in the picture (150 % or more) read no steady rise
    assert not rose_in_a_view_read_to_the_pixel({"a": view("a", 50.0), "b": view("b", 150.0)})
    assert not rose_in_a_view_read_to_the_pixel({"a": view("a", None), "b": view("b", None)})
