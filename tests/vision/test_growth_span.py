"""The growth test over more than one check: a part whose top rises 2-3 px per check (seen small, checks a few
layers apart), too little for the fine or the coarse reading (cross-check seed 9 048_runout, 040_runout)."""
from dataclasses import replace

import pytest

from octoprint_printwatch.core.pipeline import CameraState
from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.growth import GROWTH_SPAN_CHECKS
from octoprint_printwatch.core.shape_check import ShapeResult, check_shape

from .synthetic import Box, bed_texture, camera_effects, paint_part, regions


def _looks(bed, tops_model, tops_part):
    """check_shape at each check: the model's top row ``tops_model[i]``, the part's ``tops_part[i]``; the last
    result, with the camera's earlier looks handed over as the pipeline does."""
    background = camera_effects(bed, seed=11)
    state = CameraState()
    silhouettes = {}
    result = None
    for i, (top_model, top_part) in enumerate(zip(tops_model, tops_part)):
        model = Box(110, top_model, 210, 170)
        silhouettes[top_model] = model.mask()
        reg = regions(model)
        if i:
            reg = replace(reg, previous_silhouette=silhouettes[tops_model[i - 1]])
        frame = camera_effects(paint_part(bed, Box(110, top_part, 210, 170)), seed=20 + i)
        older = [(mask, silhouettes[z]) for z, mask in state.older_observed]
        result = check_shape("cam", background, frame, reg, last_observed=state.last_observed,
                             anchor=None if result is None else result.shift_px, older_looks=older)
        assert result.usable
        state.saw(result.observed_mask, top_model)
    return result


def test_a_stall_too_small_to_read_at_one_check_is_read_over_two():
    bed = bed_texture()
    model = [113, 110, 107, 104, 101]                 # the model's top rises 3 px per check
    stopped = _looks(bed, model, [113, 110, 107, 107, 107])
    # no one-check reading, fine or coarse: 3 px is edge wobble
    assert stopped.growth_pct is None and stopped.coarse_growth_pct is None
    # over two checks (6 px) the stall is read, finely
    assert stopped.growth_span == 2 and stopped.span_growth_pct == pytest.approx(0, abs=20)
    rising = _looks(bed, model, model)
    assert rising.growth_pct is None and rising.coarse_growth_pct is None
    assert rising.span_growth_pct == pytest.approx(100, abs=20)


def view(name, *, growth=None, span=None, band_missing=0.0, missing=0.0):
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth,
                       (0, 0), 7.0, 50.0, passed=True, usable=True, reasons=[], span_growth_pct=span,
                       growth_span=None if span is None else 3)


def test_the_stall_rules_read_a_span_where_no_view_reads_one_check():
    """Seed 9 048_runout check 6: both views read no rise over three checks (0 %), and s0L misses 4.2 % of the
    part (6.6 % of the newest band), s0R 2.8 %: no view gives any one-check reading."""
    s = DetectionSettings()
    now = {"s0L": view("s0L", span=0.0, band_missing=6.55, missing=4.17),
           "s0R": view("s0R", span=0.0, band_missing=4.44, missing=2.78)}
    verdict, reasons = decide(now, {}, s)
    assert verdict == "fail" and any("not grown as expected" in r for r in reasons)
    # HEAD: no reading, and under the threshold in both views
    head = {cam: replace(r, span_growth_pct=None, growth_span=None) for cam, r in now.items()}
    assert decide(head, {}, s)[0] == "ok"
    # a span that still reaches back before the stop reads part of the rise: no stall yet
    assert decide({"s0L": view("s0L", span=42.9, band_missing=6.55, missing=4.17),
                   "s0R": view("s0R", span=60.0, band_missing=4.44, missing=2.78)}, {}, s)[0] == "ok"
    # nothing missing: a flat rise is no stall on its own
    assert decide({"s0L": view("s0L", span=0.0), "s0R": view("s0R", span=0.0)}, {}, s)[0] == "ok"
    # a one-check stall is never undone by a span still reaching back before the stop
    both = {"s0": view("s0", growth=0.0, band_missing=30.0, missing=4.0), "s1": view("s1", span=80.0)}
    assert decide(both, {}, s)[0] == "fail"


def test_a_camera_remembers_its_older_looks():
    state = CameraState()
    for z in (2.0, 4.0, 6.0, 8.0):
        state.saw(f"mask{z}", z)
    assert state.last_observed == "mask8.0" and state.last_observed_z == 8.0
    assert [z for z, _ in state.older_observed] == [6.0, 4.0][:GROWTH_SPAN_CHECKS - 1]
    state.saw("again", 8.0)                           # a second look at the same check replaces it
    assert state.last_observed == "again"
    assert [z for z, _ in state.older_observed] == [6.0, 4.0][:GROWTH_SPAN_CHECKS - 1]
