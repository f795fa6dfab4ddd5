"""Filament in the bed's own colour: a face that passes for the bed pixel by pixel, but not as a group.

Synthetic scenes with known answers (tests/vision/synthetic.py): a textured, unevenly lit bed; a part
whose side is shaded and whose top face is the bed a few per cent brighter or darker (filament of nearly
the bed's colour lit like the bed, even with the bed's grain: only the offset tells it); the same part
with its top really gone, the bed showing through.
"""
import numpy as np
import pytest

from octoprint_printwatch.core.verdict import decide
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult, check_shape
from octoprint_printwatch.core.material import differs_as_a_group, material_evidence

from .synthetic import H, W, Box, bed_texture, camera_effects, paint_part, regions

TOP = Box(110, 80, 210, 110)      # the top face: the upper 30 rows of the part
SIDE = Box(110, 110, 210, 170)    # the shaded side below it


@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def camouflaged_face(scene: np.ndarray, box: Box, tint) -> np.ndarray:
    """``scene`` with ``box`` times ``tint`` (per channel BGR)."""
    out = scene.astype(np.float32).copy()
    out[box.mask()] *= np.asarray(tint, np.float32)
    return np.clip(out, 0, 255).astype(np.uint8)


def inside(box: Box, margin: int = 5) -> np.ndarray:
    m = np.zeros((H, W), bool)
    m[box.y0 + margin:box.y1 - margin, box.x0 + margin:box.x1 - margin] = True
    return m


def evidence_of(background, frame):
    prior = np.zeros((H, W), bool)
    prior[60:190, 90:230] = True
    return material_evidence(background, frame, prior, ~prior), prior


@pytest.mark.parametrize("tint", [(1.04, 1.04, 1.04), (0.96, 0.96, 0.96), (0.97, 0.95, 0.96), (1.05, 1.02, 1.0)])
def test_a_face_a_few_percent_off_the_beds_colour_differs_as_a_group(bed, tint):
    background = camera_effects(bed, seed=11)
    frame = camera_effects(camouflaged_face(bed, TOP, tint))
    ev, prior = evidence_of(background, frame)
    # the premise: pixel by pixel, most of the face passes for the bed
    assert ev.bed[inside(TOP)].mean() > 0.7
    # ... and as a group none of those pixels does (the group: the pixels that pass one by one)
    flagged = differs_as_a_group(frame, ev.background_norm, ev.bed, ~prior, 2.5)
    assert (ev.bed & ~flagged)[inside(TOP)].mean() < 0.02
    # the bed around it, with its grain, uneven light, noise and JPEG, is not flagged
    assert flagged[~prior].mean() < 0.01


@pytest.mark.parametrize("gain, shake", [((1.0, 1.0, 1.0), (0, 0)), ((1.15, 1.1, 0.9), (1, 0))])
def test_the_bed_itself_never_differs_as_a_group(bed, gain, shake):
    # what a camera sees where the part should be and is not: the bed, with another exposure, a 1-px shake
    background = camera_effects(bed, seed=11)
    frame = camera_effects(bed, gain=gain, shake=shake, seed=4)
    ev, prior = evidence_of(background, frame)
    assert differs_as_a_group(frame, ev.background_norm, ev.bed, ~prior, 2.5).mean() < 0.01


def scene_with(bed, top_present: bool, tint=(1.05, 1.04, 1.06)) -> np.ndarray:
    frame = paint_part(bed, SIDE, colour=(90, 70, 40))        # the side: the bed's hue, shaded
    if top_present:
        frame = camouflaged_face(frame, TOP, tint)
    return camera_effects(frame)


def test_a_top_face_in_the_beds_colour_is_missing_pixel_by_pixel_but_not_the_background(bed):
    background = camera_effects(bed, seed=11)
    r = check_shape("cam", background, scene_with(bed, top_present=True), regions())
    assert r.usable
    # pixel by pixel the face reads as bed: "missing", as before
    assert r.missing_pct > 7.0
    # ... but none of it shows the background itself
    assert r.background_missing_pct is not None and r.background_missing_pct < 1.0
    assert r.background_band_missing_pct is not None and r.background_band_missing_pct < 2.0


def test_the_same_part_with_its_top_really_gone_shows_the_background(bed):
    background = camera_effects(bed, seed=11)
    r = check_shape("cam", background, scene_with(bed, top_present=False), regions())
    # 30 of 90 rows gone: (30 - 2) x (100 - 4) px of 9000 beyond the 2-px tolerance rim, less a few rows
    # JPEG ringing and closing add to the top edge of what is left; all of it the background itself
    assert r.missing_pct >= 100 * 22 * 96 / 9000
    assert r.background_missing_pct == pytest.approx(r.missing_pct, abs=0.5)
    assert not r.passed


def figures(name, *, missing, background_missing, growth=None, band_missing=0.0, background_band=0.0):
    """A failing-on-missing ShapeResult with the figures the decision rule reads."""
    return ShapeResult(name, missing, missing, missing, 0.0, band_missing, band_missing, 500, 5000, growth,
                       (0, 0), 7.0, 50.0, passed=missing <= 7.0 and band_missing <= 50.0, usable=True,
                       reasons=[f"{name}: shape differs"], background_missing_pct=background_missing,
                       background_band_missing_pct=background_band)


def test_missing_material_that_is_not_the_background_does_not_pause():
    s = DetectionSettings()
    # one camera (020_runout of the second simulator: a stack in the bed's colour, 27 % "missing",
    # the newest band 61 % "missing", none of it the background)
    face = {"cam": figures("cam", missing=27.0, background_missing=0.5, band_missing=61.0, background_band=2.0)}
    assert decide(face, {}, s)[0] == "ok"
    # the same figures, the background showing where the part should be: a runout
    gone = {"cam": figures("cam", missing=27.0, background_missing=25.0, band_missing=61.0, background_band=58.0)}
    assert decide(gone, {}, s)[0] == "fail"
    # the newest layers gone although the rest is a camouflaged face: still a failure
    band = {"cam": figures("cam", missing=27.0, background_missing=3.0, band_missing=61.0, background_band=55.0)}
    assert decide(band, {}, s)[0] == "fail"
