"""Speed-ups that must not change a single figure: each faster form against the plain form it replaced, on
random inputs (exact equality, not a tolerance)."""
import cv2
import numpy as np

from octoprint_printwatch.core.layer_shift import _Evidence, _vertical_null, stretched
from octoprint_printwatch.core.masks import bounding_box
from octoprint_printwatch.core.shape_check import _hypot, _luma_chroma


def _vertical_null_plain(evidence, before, band, reach_y):
    """The band's top stretched dy by dy (the form before the counts were read off at once)."""
    y0, y1, x0, x1 = bounding_box(band)
    window = (slice(max(0, y0 - reach_y - 1), min(band.shape[0], y1 + reach_y + 1)), slice(x0, x1))
    band_w, before_w, ring = band[window], before[window], evidence.ring[window]
    seen, empty = evidence.seen[window], evidence.empty[window]
    best, best_dy = 0.0, 0
    scores = np.zeros(2 * reach_y + 1, np.float32)
    for dy in range(-reach_y, reach_y + 1):
        if dy == 0:
            continue
        changed = (stretched(band_w, dy) ^ band_w) & ~before_w & ~ring
        gained = changed & ~band_w
        lost = changed & band_w
        score = (np.count_nonzero(gained & seen) + np.count_nonzero(lost & empty)
                 - 2.0 * (np.count_nonzero(gained & empty) + np.count_nonzero(lost & seen)))
        scores[dy + reach_y] = score
        if score > best:
            best, best_dy = score, dy
    return best_dy, float(best), scores


def test_vertical_null_counts_every_dy_as_stretching_dy_by_dy():
    rng = np.random.default_rng(7)
    for trial in range(300):
        h, w = rng.integers(20, 90, size=2)
        # a ragged band (holes, several pieces, touching the image's top or bottom sometimes)
        band = cv2.dilate((rng.random((h, w)) < rng.uniform(0.005, 0.05)).astype(np.uint8),
                          np.ones((int(rng.integers(1, 6)), int(rng.integers(1, 9))), np.uint8)).astype(bool)
        if not band.any():
            continue
        before = (rng.random((h, w)) < 0.2) & ~band
        observed = rng.random((h, w)) < rng.uniform(0.1, 0.9)
        bed = ~observed & (rng.random((h, w)) < 0.8)
        evidence = _Evidence.of(observed, bed, before | band, float(rng.choice([0.0, 1.0, 2.0])))
        reach_y = int(rng.integers(1, 14))
        fast = _vertical_null(evidence, before, band, reach_y)
        plain = _vertical_null_plain(evidence, before, band, reach_y)
        assert fast[:2] == plain[:2], trial
        assert np.array_equal(fast[2], plain[2]), trial


def test_hypot_is_numpys_hypot():
    rng = np.random.default_rng(3)
    x = np.maximum(rng.normal(0, 20, (120, 90)), 0).astype(np.float32)
    y = np.maximum(rng.normal(0, 20, (120, 90)), 0).astype(np.float32)
    y[:10] = x[:10]
    assert np.array_equal(_hypot(x, y), np.hypot(x, y))
    zero = np.zeros_like(x)
    assert np.array_equal(_hypot(zero, zero), zero)


def _luma_chroma_plain(image):
    """The whole-image float32 form the channel-wise one replaced."""
    b, g, r = (image[..., k].astype(np.float32) for k in range(3))
    luma = (b + g + r) * (1.0 / 3.0)
    denom = luma + 6.0
    return luma, (r - g) * (100.0 / denom), (r + g - 2.0 * b) * (50.0 / denom)


def test_luma_chroma_of_uint8_and_float32_is_the_plain_float_form():
    rng = np.random.default_rng(5)
    image = rng.integers(0, 256, (70, 50, 3), dtype=np.uint8)
    view = np.zeros((90, 80, 3), np.uint8)
    view[10:80, 20:70] = image
    scaled = image.astype(np.float32) * np.float32(1.37)   # a background at the frame's exposure
    # contiguous, a crop's strided view, and a float32 image
    for source in (image, view[10:80, 20:70], scaled):
        for fast, plain in zip(_luma_chroma(source), _luma_chroma_plain(source)):
            assert fast.dtype == plain.dtype == np.float32
            assert np.array_equal(fast, plain)
