"""Strands piled over a part that slowed: the newest band turns textured (core/nest.py ``region_texture``,
``textured_views``; the textured-band rule in verdict.decide). Cross-check seed 10 ``054_spaghetti``: strands in
the part's own colour fill the band (nothing missing, band coverage 0.83), the outline rises 46 %, and the band's
mean gradient reads 1.6x what it read at the previous check."""
from __future__ import annotations

import cv2
import numpy as np

from octoprint_printwatch.core.nest import (NEST_MAX_COVERAGE, SMOOTH_TEXTURE, TEXTURE_JUMP, region_texture,
                                            textured_views)
from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult, check_shape

from .synthetic import PART, bed_texture, camera_effects, paint_part, regions

PALE = (200, 205, 215)


def strands_over(image: np.ndarray, box, count: int = 40, seed: int = 7) -> np.ndarray:
    """A copy of ``image`` with ``count`` strands 2 px wide in the part's pale colour, each with a dark rim (its
    own shadow), lying across ``box``."""
    rng = np.random.default_rng(seed)
    out = image.copy()
    clip = np.zeros(out.shape[:2], np.uint8)
    clip[box.y0:box.y1, box.x0:box.x1] = 1
    for _ in range(count):
        x0, x1 = rng.uniform(box.x0, box.x1, 2)
        y0, y1 = rng.uniform(box.y0, box.y1, 2)
        rim, strand = np.zeros_like(clip), np.zeros_like(clip)
        cv2.line(rim, (int(x0), int(y0) + 1), (int(x1), int(y1) + 1), 1, 3)
        cv2.line(strand, (int(x0), int(y0)), (int(x1), int(y1)), 1, 2)
        out[(rim & clip & ~strand).astype(bool)] = (np.array(PALE) * 0.55).astype(np.uint8)
        out[(strand & clip).astype(bool)] = PALE
    return out


def band_box(rows: int = 30):
    return type(PART)(PART.x0, PART.y0, PART.x1, PART.y0 + rows)


def test_region_texture_is_the_mean_gradient_over_the_region():
    gradient = np.zeros((10, 10), np.float32)
    gradient[:5] = 4.0
    region = np.zeros((10, 10), bool)
    region[3:7, :] = True
    assert region_texture(gradient, region) == 2.0
    assert region_texture(None, region) is None
    assert region_texture(gradient, np.zeros_like(region)) is None


def test_strands_in_the_parts_colour_make_the_band_textured_where_the_outline_and_colour_read_nothing():
    bed = bed_texture(colour=(60, 120, 170))
    background = camera_effects(bed, seed=11)
    solid = paint_part(bed, PART, PALE)
    piled = strands_over(solid, band_box())
    r = regions(PART, band_rows=30)

    whole = check_shape("c", background, camera_effects(solid, seed=12), r)
    nest = check_shape("c", background, camera_effects(piled, seed=12), r)
    assert whole.band_texture is not None and nest.band_texture is not None
    assert nest.band_texture >= TEXTURE_JUMP * max(whole.band_texture, SMOOTH_TEXTURE)
    # ... while the outline comparison and the band's colours read the pile as the part
    assert nest.passed and nest.error_pct < nest.threshold
    assert nest.band_part_coverage is None or nest.band_part_coverage > NEST_MAX_COVERAGE
    assert nest.figures()["band_texture"] == round(nest.band_texture, 2)


def test_textured_views_compare_each_view_with_its_own_previous_reading():
    assert textured_views({"a": 12.0, "b": 9.0}, {"a": 6.0, "b": 8.0}) == {"a": 2.0}
    # a smooth band's reading counts as the noise floor: a ratio of two near-zero readings is noise
    assert textured_views({"a": 4.0}, {"a": 1.0}) == {}
    assert textured_views({"a": 2 * SMOOTH_TEXTURE}, {"a": 1.0}) == {"a": 2.0}
    # no reading now or none before (first look, not usable, no band figures): not counted
    assert textured_views({"a": None, "b": 12.0}, {"a": 3.0}) == {}


def figures(name, *, growth, texture):
    r = ShapeResult(name, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 500, 5000, growth, (0, 0), 7.0, 50.0,
                    passed=True, usable=True, reasons=[])
    r.band_texture = texture
    return r


def test_a_part_that_slowed_under_a_textured_band_pauses_and_a_rising_or_closing_one_does_not():
    s = DetectionSettings()
    before = {"a": 10.0, "b": 9.0}
    # 054-like: the outline rose under half the expected height, one view's band 1.6x as textured
    slowed = {"a": figures("a", growth=66.7, texture=16.0), "b": figures("b", growth=25.0, texture=10.0)}
    verdict, reasons = decide(slowed, {}, s, band_texture_before=before)
    assert verdict == "fail"
    assert any(why.startswith("a: the newest layers look 1.6 times as textured") for why in reasons)
    # the part rising as the model says: a textured band alone is a view's artefact (a seam, a glint)
    rising = {"a": figures("a", growth=100.0, texture=16.0), "b": figures("b", growth=90.0, texture=10.0)}
    assert decide(rising, {}, s, band_texture_before=before)[0] == "ok"
    # a top surface closing: its last layers may read no rise on a normal part
    assert decide(slowed, {}, s, band_texture_before=before, top_closing=True)[0] == "ok"
    # no reading at the previous check, or a band no more textured than before
    assert decide(slowed, {}, s)[0] == "ok"
    assert decide(slowed, {}, s, band_texture_before={"a": 14.0, "b": 9.0})[0] == "ok"


def test_a_band_turned_twice_as_textured_pauses_a_part_that_rose_only_part_of_the_expected_height():
    # cross-check seed 13 ``026_spaghetti``: one view, a coarse rise of 60 % (+-25 %), band texture 3.9 -> 12.3
    s = DetectionSettings()
    before = {"a": 4.0}
    strands = {"a": figures("a", growth=60.0, texture=12.0)}
    verdict, reasons = decide(strands, {}, s, band_texture_before=before)
    assert verdict == "fail"
    assert any(why.startswith("a: the newest layers look 3.0 times as textured") for why in reasons)
    # the same rise with a change of look a normal print shows (a tier's step entering the band): no pause
    assert decide({"a": figures("a", growth=60.0, texture=7.0)}, {}, s, band_texture_before=before)[0] == "ok"
    # a part rising as expected: even a strongly changed band is a view's artefact (a normal print read 5.7x)
    assert decide({"a": figures("a", growth=100.0, texture=20.0)}, {}, s, band_texture_before=before)[0] == "ok"
    assert decide({"a": figures("a", growth=85.0, texture=20.0)}, {}, s, band_texture_before=before)[0] == "ok"
