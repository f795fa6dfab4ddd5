"""Dense matchers on pairs with a known disparity."""
from __future__ import annotations

import cv2
import numpy as np
import pytest

from octoprint_printwatch.core.stereo.matching import MATCHERS, MatchSettings, compute_disparity


def _textured_pair(disparity: float, size=(160, 200), seed=0):
    """A random-texture left image and the right image shifted left by ``disparity`` px."""
    rng = np.random.default_rng(seed)
    h, w = size
    base = cv2.GaussianBlur(rng.uniform(0, 255, (h, w)).astype(np.float32), (0, 0), 1.5)
    left = np.clip(base, 0, 255).astype(np.uint8)
    shift = np.float64([[1, 0, -disparity], [0, 1, 0]])  # right(x) = left(x + d)
    right = cv2.warpAffine(left, shift, (w, h), flags=cv2.INTER_CUBIC, borderMode=cv2.BORDER_REFLECT)
    return left, right


@pytest.mark.parametrize("method", MATCHERS)
def test_each_matcher_recovers_a_known_subpixel_disparity(method):
    left, right = _textured_pair(12.4)
    disparity = compute_disparity(left, right, MatchSettings(method, 0, 32, 9))
    inner = disparity[20:-20, 60:-20]
    assert np.isfinite(inner).mean() > 0.9
    # SGBM's 1/16-px output and its interpolation lock towards whole pixels (a known bias).
    assert np.nanmedian(inner) == pytest.approx(12.4, abs=0.35 if method == "sgbm" else 0.1)


def test_seed_sad_with_its_67_pixel_block_and_15_pixel_search():
    left, right = _textured_pair(-6.0, size=(200, 240))
    settings = MatchSettings("sad", min_disparity=-15, num_disparities=31, block_size=67)
    disparity = compute_disparity(left, right, settings)
    assert np.nanmedian(disparity[60:-60, 60:-60]) == pytest.approx(-6.0, abs=0.25)


def test_mask_restricts_matching_and_the_rest_is_nan():
    left, right = _textured_pair(5.0)
    mask = np.zeros(left.shape, bool)
    mask[50:90, 80:140] = True
    disparity = compute_disparity(left, right, MatchSettings("ncc", 0, 16, 7), mask)
    assert np.all(np.isnan(disparity[~mask]))
    assert np.isfinite(disparity[mask]).mean() > 0.9


def test_textureless_region_gives_no_match_rather_than_a_guess():
    left, right = _textured_pair(5.0)
    left[:, :100] = 128
    right[:, :100] = 128
    disparity = compute_disparity(left, right, MatchSettings("sad", 0, 16, 9))
    assert np.isfinite(disparity[20:-20, 20:80]).mean() < 0.05


def test_disparity_outside_the_search_range_is_rejected():
    left, right = _textured_pair(17.0)
    disparity = compute_disparity(left, right, MatchSettings("sad", 0, 16, 9))
    # The true match lies just beyond the range: the minimum lands on the range's end and is dropped.
    assert np.isfinite(disparity[20:-20, 40:-20]).mean() < 0.1


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="block_size"):
        MatchSettings("sad", block_size=8)
    with pytest.raises(ValueError, match="unknown matcher"):
        MatchSettings("census")
