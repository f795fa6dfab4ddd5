"""A part that stopped under a nest of strands (spaghetti): its newest band is a mesh over the bed, not a
solid face (core/nest.py, the stall rule in verdict.decide). Known-answer images, the rule's figures, and
one spaghetti print rendered by the independent cross-check simulator."""
from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from octoprint_printwatch.core.nest import NEST_MAX_COVERAGE, SOLID_MIN_COVERAGE, part_coverage
from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult, check_shape

from .synthetic import PART, bed_texture, camera_effects, paint_part, regions

ROOT = Path(__file__).resolve().parents[2]
RED = (40, 40, 210)


def strand_mesh(box, share: float, seed: int = 5) -> np.ndarray:
    """(H, W) bool: random straight strands 2 px wide over ``box`` until about ``share`` of it is covered."""
    rng = np.random.default_rng(seed)
    mesh = np.zeros(box.mask().shape, np.uint8)
    area = box.mask()
    while mesh[area].mean() < share:
        x0, x1 = rng.uniform(box.x0 - 20, box.x1 + 20, 2)
        y0, y1 = rng.uniform(box.y0 - 20, box.y1 + 20, 2)
        cv2.line(mesh, (int(x0), int(y0)), (int(x1), int(y1)), 1, 2)
    return mesh.astype(bool) & area


def band_box(rows: int = 30):
    return type(PART)(PART.x0, PART.y0, PART.x1, PART.y0 + rows)


def test_a_solid_band_reads_covered_a_strand_mesh_reads_its_share_and_the_bare_bed_none():
    bed = bed_texture()
    solid = paint_part(bed, PART, RED)
    band = band_box().mask()
    palette = np.array([[c * s for c in RED] for s in (0.7, 0.85, 1.0)], np.float32)
    background = bed.astype(np.float32)

    assert part_coverage(solid, background, band, palette) > 0.9
    mesh = strand_mesh(band_box(), 0.45)
    nest = np.where(mesh[..., None], solid, bed)
    share = float(mesh[band].mean())
    assert abs(part_coverage(nest, background, band, palette) - share) < 0.1
    assert part_coverage(bed, background, band, palette) < 0.05
    # nothing to measure: no palette, no pixels
    assert part_coverage(solid, background, band, None) is None
    assert part_coverage(solid, background, np.zeros_like(band), palette) is None


def test_check_shape_sees_the_mesh_in_the_newest_band_where_the_outline_reads_nothing_missing():
    """The nest's holes close in the material mask (no material missing, no error), but the band's pixels
    show the bed between the strands."""
    bed = bed_texture()
    background = camera_effects(bed, seed=11)
    solid = paint_part(bed, PART, RED)
    band = band_box().mask()
    mesh = strand_mesh(band_box(), 0.35)
    nest = np.where((band & ~mesh)[..., None], bed, solid)
    r = regions(PART, band_rows=30)

    whole = check_shape("c", background, camera_effects(solid, seed=12), r)
    piled = check_shape("c", background, camera_effects(nest, seed=12), r)
    assert whole.band_part_coverage > 0.85
    # the strands' share, give or take what the JPEG round trip smears into the holes
    assert abs(piled.band_part_coverage - float(mesh[band].mean())) < 0.15
    assert piled.band_part_coverage < NEST_MAX_COVERAGE
    # ... while the outline comparison reads the nest as the part (this is why the cue is needed)
    assert piled.error_pct < whole.threshold


def figures(name, *, growth, coverage=None, before=None):
    """(a passing ShapeResult with nothing missing, carrying the growth and newest-band coverage figures,
    the camera's highest band coverage at earlier checks or None)."""
    r = ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, growth, (0, 0), 7.0, 50.0,
                    passed=True, usable=True, reasons=[])
    r.band_part_coverage = coverage
    return r, before


def judge(views, settings, **kwargs):
    """decide() on {camera: figures(...)}, as CheckRunner calls it."""
    before = {name: b for name, (_, b) in views.items() if b is not None}
    return decide({name: r for name, (r, _) in views.items()}, {}, settings, band_coverage_before=before, **kwargs)


def test_a_stalled_part_whose_band_turned_to_mesh_pauses_and_a_band_that_always_looked_bare_does_not():
    s = DetectionSettings()
    # one camera, no rise, the band a third covered where it read solid before: spaghetti over a stopped part
    verdict, reasons = judge({"a": figures("a", growth=0.0, coverage=0.3, before=0.95)}, s)
    assert verdict == "fail" and any("not grown as expected" in why for why in reasons)
    assert any(why.startswith("a: the newest layers show the part's colours over 30%") for why in reasons)
    # the view with the mesh could not measure the rise; another view saw none
    assert judge({"a": figures("a", growth=None, coverage=0.3, before=0.95),
                   "b": figures("b", growth=0.0, coverage=0.9, before=0.95)}, s)[0] == "fail"
    # a top face in the bed's colour reads bare at every check: not a change of the band
    assert judge({"a": figures("a", growth=0.0, coverage=0.1, before=0.15)}, s)[0] == "ok"
    # no earlier reading (first checks): nothing to compare with
    assert judge({"a": figures("a", growth=0.0, coverage=0.1)}, s)[0] == "ok"
    # the band still solid: nothing corroborates the flat rise
    assert judge({"a": figures("a", growth=0.0, coverage=SOLID_MIN_COVERAGE, before=0.95)}, s)[0] == "ok"
    # the part keeps rising in most views
    assert judge({"a": figures("a", growth=0.0, coverage=0.3, before=0.95), "b": figures("b", growth=100.0),
                   "c": figures("c", growth=90.0)}, s)[0] == "ok"
    # a top surface closing: its smooth skin may look like the bed
    assert judge({"a": figures("a", growth=0.0, coverage=0.3, before=0.95)}, s, top_closing=True)[0] == "ok"


def test_a_spaghetti_print_from_the_cross_check_simulator_turns_its_newest_band_to_mesh(tmp_path):
    """A grey part on blue tape (cross-check seed 3, one 160x120 camera): its band reads solid until the
    onset and ever less covered at the checks after it, where the strands pile over the stopped part."""
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    from benchmarks.crosscheck import scenes
    from octoprint_printwatch.core.pipeline import evaluate_recording
    from octoprint_printwatch.core.recording import load_recording

    truth = scenes.generate(tmp_path / "rec", scenes.Recipe(seed=3, kind="spaghetti", quick=True,
                                                             max_checks_after_flag=3))
    results = evaluate_recording(load_recording(tmp_path / "rec"), keep_results=True)["_results"]
    onset = truth["onset_layer"]
    before = [r for c in results if c.layer <= onset for r in c.shape.values() if r.band_part_coverage is not None]
    after = [r for c in results if c.layer > onset + truth["every"]
             for r in c.shape.values() if r.band_part_coverage is not None]
    assert before and after
    assert min(r.band_part_coverage for r in before) >= SOLID_MIN_COVERAGE
    # the pile thins the band's colour check by check, down to the bed between a few strands
    assert max(r.band_part_coverage for r in after) < min(r.band_part_coverage for r in before) - 0.2
    assert after[-1].band_part_coverage < NEST_MAX_COVERAGE / 2
    assert all(c.verdict != "fail" for c in results if c.layer <= onset)
