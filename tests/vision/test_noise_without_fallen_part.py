"""A part that fell onto the bed sample is material, not the bed's noise (cross-check seed 8 ``041_detach``: a
white cylinder tipped over 18 % of the certain-bed sample; the noise levels, that sample's 90th percentile, became
the part's own change, chromaticity 171 where 3 is normal, and checks 7-9 read 0 % missing and 0 % extra).
``material_evidence`` leaves the sampled pixels that took the part's colour (its palette from earlier checks) out
of the noise levels; a change of light on the bed (a glare that came or went) keeps the bed's colour and stays in.

Synthetic scene (tests/vision/synthetic.py): the part stands in PART; a second block of the part's colour lies on
the bed beside it, over about a quarter of the sample.
"""
import numpy as np
import pytest

from octoprint_printwatch.core.material import material_evidence, part_palette, took_the_part_colour

from .synthetic import PART, Box, bed_texture, camera_effects, paint_part

WHITE = (215, 225, 225)
FALLEN = Box(0, 0, 100, 150)          # on the sample, left of the part's prior
PRIOR = Box(95, 65, 225, 185)


@pytest.fixture(scope="module")
def scene():
    bed = bed_texture()
    background = camera_effects(bed, seed=11)
    standing = camera_effects(paint_part(bed, PART, colour=WHITE))
    palette = part_palette(standing, PART.mask())
    fallen = camera_effects(paint_part(paint_part(bed, PART, colour=WHITE), FALLEN, colour=WHITE, seed=4))
    glare = bed.astype(np.float32)
    glare[FALLEN.mask()] += 45.0          # white light added on the bed (a glare): the bed's colour, paler
    glare = camera_effects(paint_part(np.clip(glare, 0, 255).astype(np.uint8), PART, colour=WHITE))
    return background, palette, fallen, glare


def test_a_fallen_part_does_not_set_the_noise_levels(scene):
    background, palette, fallen, _ = scene
    prior, sample = PRIOR.mask(), ~PRIOR.mask()
    assert FALLEN.mask()[sample].mean() > 0.2
    before = material_evidence(background, fallen, prior, sample)             # HEAD: the part is the noise
    assert before.noise["chroma"] > 30
    ev = material_evidence(background, fallen, prior, sample, palette=palette)
    assert ev.noise["chroma"] < 10
    assert ev.material[Box(10, 10, 90, 140).mask()].mean() > 0.9


def test_a_change_of_light_still_sets_the_noise_levels(scene):
    background, palette, _, glare = scene
    ys, xs = np.nonzero(Box(10, 10, 90, 140).mask())
    assert took_the_part_colour(glare[ys, xs], background[ys, xs], palette).mean() < 0.05
    prior, sample = PRIOR.mask(), ~PRIOR.mask()
    without = material_evidence(background, glare, prior, sample)
    ev = material_evidence(background, glare, prior, sample, palette=palette)
    assert ev.noise == pytest.approx(without.noise)
