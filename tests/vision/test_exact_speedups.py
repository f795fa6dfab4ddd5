"""Speed-ups that must not change a single figure: each faster form against the plain form it replaced, on
random inputs (exact equality, not a tolerance)."""
import cv2
import numpy as np

from octoprint_printwatch.core import shadows
from octoprint_printwatch.core.layer_shift import _Evidence, _vertical_null, stretched
from octoprint_printwatch.core.masks import bounding_box
from octoprint_printwatch.core.material import _hypot, _luma_chroma, _zero_where, material_evidence, part_palette
from octoprint_printwatch.core.shape_check import compare_masks
from octoprint_printwatch.core.tangle import new_material


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


# ------------------------------------------------ twelfth session: more exact speed-ups


def _shadow_scene(rng):
    """A grained bed, a part in the middle, shadows in the background frame that have left by the frame
    (lit again), in several separate places: uint8 background and frame, prior, bed sample, previous, part."""
    h, w = (int(v) for v in rng.integers(120, 260, size=2))
    grain = cv2.GaussianBlur(rng.normal(0, rng.uniform(2, 12), (h, w)).astype(np.float32), (0, 0),
                             rng.uniform(0.6, 2))
    tint = rng.uniform(60, 200, 3)
    bed = np.clip(tint[None, None, :] + grain[..., None] * rng.uniform(0.5, 1.5, 3), 0, 255)
    background, frame = bed.copy(), bed.copy()
    for _ in range(int(rng.integers(1, 6))):   # shadows of the head that lay here in the background frame
        y, x = int(rng.integers(0, h - 10)), int(rng.integers(0, w - 10))
        sh, sw = int(rng.integers(8, h // 2)), int(rng.integers(8, w // 2))
        background[y:y + sh, x:x + sw] *= rng.uniform(0.45, 0.9)
    if rng.random() < 0.5:   # clipped channels on a bright bed
        background[: h // 3] = np.clip(background[: h // 3] * 1.6, 0, 255)
    py0, px0 = h // 3, w // 3
    part = np.zeros((h, w), bool)
    part[py0:py0 + h // 3, px0:px0 + w // 3] = True
    frame[part] = rng.uniform(0, 255, 3)
    for _ in range(int(rng.integers(0, 4))):   # a few strands
        y, x = int(rng.integers(0, h)), int(rng.integers(0, w))
        cv2.line(frame, (x, y), (int(rng.integers(0, w)), int(rng.integers(0, h))), rng.uniform(0, 255, 3).tolist(), 2)
    frame = frame * rng.uniform(0.85, 1.15) + rng.normal(0, rng.uniform(0.5, 4), frame.shape)
    background = background + rng.normal(0, 1.5, background.shape)
    background, frame = (np.clip(np.rint(a), 0, 255).astype(np.uint8) for a in (background, frame))
    prior = cv2.dilate(part.astype(np.uint8), np.ones((15, 15), np.uint8)).astype(bool)
    bed_sample = ~cv2.dilate(prior.astype(np.uint8), np.ones((21, 21), np.uint8)).astype(bool)
    previous = part if rng.random() < 0.5 else None
    grown_part = cv2.dilate(part.astype(np.uint8), np.ones((5, 5), np.uint8)).astype(bool)
    return background, frame, prior, bed_sample, previous, grown_part


def _one_box(wanted):
    """The form before: one box around every candidate."""
    return [((0, wanted.shape[0], 0, wanted.shape[1]), wanted)]


def test_shadow_test_on_each_group_of_candidates_is_the_test_on_their_whole_box(monkeypatch):
    """shadows.shadow_left on one box per group of candidates answers as on the box around all of them
    (the form before), on random scenes with several shadows that left; material_evidence unchanged."""
    rng = np.random.default_rng(12)
    groups = shadows._candidate_groups
    for trial in range(60):
        scene = _shadow_scene(rng)
        background, frame, prior, bed_sample, previous, part = scene
        fast = material_evidence(background, frame, prior, bed_sample, previous=previous, part=part)
        monkeypatch.setattr(shadows, "_candidate_groups", _one_box)
        plain = material_evidence(background, frame, prior, bed_sample, previous=previous, part=part)
        monkeypatch.setattr(shadows, "_candidate_groups", groups)
        for name in ("material", "strong", "bed", "score"):
            assert np.array_equal(getattr(fast, name), getattr(plain, name)), (trial, name)
        assert fast.noise == plain.noise and fast.changed_bed_fraction == plain.changed_bed_fraction


def test_shadow_left_groups_against_one_box_on_scattered_candidates(monkeypatch):
    """shadow_left itself, with candidates scattered in separate groups (so the groups are used)."""
    rng = np.random.default_rng(4)
    groups = shadows._candidate_groups
    used = 0
    for trial in range(80):
        h, w = (int(v) for v in rng.integers(80, 240, size=2))
        grain = cv2.GaussianBlur(rng.normal(0, 8, (h, w)).astype(np.float32), (0, 0), 1.0)
        luma_b = np.clip(100 + grain, 0, 255).astype(np.uint8).astype(np.float32) * np.float32(rng.uniform(0.7, 1.3))
        luma_f = luma_b * np.float32(rng.uniform(1.0, 1.8)) + rng.normal(0, 1.0, (h, w)).astype(np.float32)
        luma_f = np.rint(luma_f * 3.0).astype(np.float32) * np.float32(1.0 / 3.0)   # a sum of three channels / 3
        where = np.zeros((h, w), bool)
        for _ in range(int(rng.integers(1, 6))):
            y, x = int(rng.integers(0, h - 4)), int(rng.integers(0, w - 4))
            where[y:y + int(rng.integers(2, 20)), x:x + int(rng.integers(2, 20))] = True
        prior = rng.random((h, w)) < 0.3
        surroundings = np.zeros((h, w), bool)
        surroundings[h // 4: 3 * h // 4, w // 4: 3 * w // 4] = True
        sample = np.flatnonzero(~surroundings)[::3]
        args = (luma_f, luma_b, sample, 1.5, 5.0, where, 0.4, prior, surroundings)
        used += len(groups(where)) > 1
        fast = shadows.shadow_left(*args)
        monkeypatch.setattr(shadows, "_candidate_groups", _one_box)
        plain = shadows.shadow_left(*args)
        monkeypatch.setattr(shadows, "_candidate_groups", groups)
        assert np.array_equal(fast, plain), trial
    assert used >= 10


def test_candidate_groups_partition_the_candidates_with_their_reach():
    rng = np.random.default_rng(9)
    for trial in range(300):
        h, w = (int(v) for v in rng.integers(30, 300, size=2))
        wanted = rng.random((h, w)) < rng.uniform(0.0001, 0.01)
        seen = np.zeros((h, w), np.int32)
        for (y0, y1, x0, x1), own in shadows._candidate_groups(wanted):
            assert own.shape == (y1 - y0, x1 - x0)
            assert not (own & ~wanted[y0:y1, x0:x1]).any()
            seen[y0:y1, x0:x1] += own
            ys, xs = np.nonzero(own)
            # every candidate reads _READS px around it: inside its box, or the box reaches the image's edge
            reads = shadows._READS
            assert ((ys >= reads) | (y0 == 0)).all() and ((ys + reads < y1 - y0) | (y1 == h)).all()
            assert ((xs >= reads) | (x0 == 0)).all() and ((xs + reads < x1 - x0) | (x1 == w)).all()
        assert np.array_equal(seen, wanted.astype(np.int32)), trial


def test_zero_where_is_np_where():
    rng = np.random.default_rng(2)
    value = np.abs(rng.normal(0, 9, (60, 70))).astype(np.float32)
    mask = rng.random((60, 70)) < 0.1
    fast, plain = _zero_where(value, mask), np.where(mask, 0.0, value)
    assert fast.dtype == plain.dtype and np.array_equal(fast, plain)
    assert not np.array_equal(value, fast)   # the input is left as it was


def _part_palette_plain(frame, mask, groups=5):
    pixels = frame[mask]
    if len(pixels) < 50:
        return None
    if len(pixels) > 4000:
        pixels = pixels[:: len(pixels) // 4000 + 1]
    pixels = pixels.astype(np.float32)
    order = np.argsort(pixels.sum(axis=1))
    return np.stack([chunk.mean(axis=0) for chunk in np.array_split(pixels[order], groups)])


def test_part_palette_gathers_the_same_pixels():
    rng = np.random.default_rng(6)
    for trial in range(100):
        full = rng.integers(0, 256, (150, 200, 3), dtype=np.uint8)
        frame = full[10:140, 20:190]   # a crop's strided view, as check_shape passes it
        mask = rng.random(frame.shape[:2]) < rng.choice([0.001, 0.01, 0.1, 0.5, 0.9])
        fast, plain = part_palette(frame, mask), _part_palette_plain(frame, mask)
        assert (fast is None) == (plain is None)
        if fast is not None:
            assert fast.dtype == plain.dtype and np.array_equal(fast, plain), trial


def _random_scene(rng, max_size: int, search_margin: int, max_objects: int, max_height: int):
    """A random part (a box in the lower half), its search box (``search_margin`` px in from the sides), the
    observed material (the part, 3 % of it lost, with hanging objects, strands and blobs) and the linked pixels
    (observed plus 5 % noise) -> (h, w, the part's top row, expected, search, observed, linked)."""
    h, w = (int(v) for v in rng.integers(80, max_size, size=2))
    expected = np.zeros((h, w), bool)
    ey0, ex0 = int(rng.integers(h // 3, h // 2)), int(rng.integers(w // 4, w // 2))
    expected[ey0:ey0 + h // 3, ex0:ex0 + w // 4] = True
    search = np.zeros((h, w), bool)
    search[int(rng.integers(5, ey0)):, search_margin:w - search_margin] = True
    observed = expected & (rng.random((h, w)) < 0.97)
    for _ in range(int(rng.integers(1, max_objects))):
        y, x = int(rng.integers(0, h - 3)), int(rng.integers(0, w - 3))
        observed[y:y + int(rng.integers(2, max_height)), x:x + int(rng.integers(2, 30))] = True
    return h, w, ey0, expected, search, observed, observed | (rng.random((h, w)) < 0.05)


def test_new_material_with_compare_masks_objects_from_above_is_new_material_alone():
    """new_material(..., foreign=compare_masks(...).foreign) == new_material(...) when no objects of a
    previous check are followed (random parts, hanging objects, strands)."""
    rng = np.random.default_rng(11)
    counted = 0
    for trial in range(200):
        h, w, ey0, expected, search, observed, linked = _random_scene(rng, 200, 0, 8, 40)
        previous = expected | (rng.random((h, w)) < 0.01)
        bed = ~linked
        band = expected & (np.arange(h)[:, None] < ey0 + 5)
        tol = float(rng.choice([1.0, 2.0, 3.0]))
        comparison = compare_masks(observed, bed, expected, band, search, np.zeros((h, w), bool), tol,
                                   band_reach=2 * tol, top_tolerance=tol, linked=linked)
        kwargs = dict(linked=linked, ignore=None, marks=np.zeros((h, w), bool))
        plain = new_material(observed, previous, expected, search, tol, 2.0, **kwargs)
        fast = new_material(observed, previous, expected, search, tol, 2.0, foreign=comparison.foreign, **kwargs)
        assert (plain is None) == (fast is None)
        if plain is not None:
            counted += plain.pixels > 0
            assert (plain.area_mm2, plain.pixels, plain.blobs, plain.at_foot_mm2) == \
                (fast.area_mm2, fast.pixels, fast.blobs, fast.at_foot_mm2), trial
            assert np.array_equal(plain.mask, fast.mask), trial
    assert counted > 10


# ------------------------------------------------ fourteenth session (helper E14)
def test_scaled_background_is_np_multiply():
    """_scaled (a per-channel lookup table) == np.multiply(image, gains, dtype=float32), bit for bit, on uint8
    crops (views too) with float32 or float64 gains; other images are multiplied as before."""
    from octoprint_printwatch.core.material import _scaled
    rng = np.random.default_rng(21)
    for trial in range(60):
        image = rng.integers(0, 256, (int(rng.integers(5, 90)), int(rng.integers(5, 90)), 3)).astype(np.uint8)
        if trial % 3 == 0:
            image = image[2:-1, 3:]
        gains = rng.uniform(0.2, 5.0, 3).astype(np.float32 if trial % 2 else np.float64)
        plain = np.multiply(image, gains, dtype=np.float32)
        fast = _scaled(image, gains)
        assert fast.dtype == plain.dtype and fast.shape == plain.shape
        assert fast.tobytes() == plain.tobytes(), trial
    floats = rng.uniform(0, 255, (20, 30, 3)).astype(np.float32)
    gains = np.array([0.9, 1.1, 1.3], np.float32)
    assert _scaled(floats, gains).tobytes() == np.multiply(floats, gains, dtype=np.float32).tobytes()


def _blob_scene(rng):
    h, w = (int(v) for v in rng.integers(20, 140, size=2))
    mask = cv2.dilate((rng.random((h, w)) < rng.uniform(0.002, 0.05)).astype(np.uint8),
                      np.ones((int(rng.integers(1, 7)), int(rng.integers(1, 9))), np.uint8)).astype(bool)
    return mask | (rng.random((h, w)) < 0.01)


def test_components_and_lowest_rows_are_connected_components_with_stats():
    """masks.components: the labels and areas cv2.connectedComponentsWithStats gives; lowest_rows: its
    top + height - 1 for the labels asked, -1 for the others."""
    from octoprint_printwatch.core.masks import components, lowest_rows
    rng = np.random.default_rng(22)
    for trial in range(200):
        mask = _blob_scene(rng)
        count, labels, area = components(mask)
        count_s, labels_s, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
        assert count == count_s and np.array_equal(labels, labels_s), trial
        assert np.array_equal(area, stats[:, cv2.CC_STAT_AREA]), trial
        asked = rng.random(count) < 0.5
        lowest = lowest_rows(labels, asked)
        want = np.where(asked, stats[:, cv2.CC_STAT_TOP] + stats[:, cv2.CC_STAT_HEIGHT] - 1, -1)
        assert np.array_equal(lowest, want), trial


def test_objects_from_above_are_those_read_with_connected_component_statistics(monkeypatch):
    """reaching_in_from_above, compare_masks and new_material give the same masks and figures with the blobs'
    areas and lowest rows read from cv2.connectedComponentsWithStats (the form before masks.components)."""
    from octoprint_printwatch.core import masks, shape_check, tangle

    def components_with_stats(mask):
        count, labels, stats, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
        return count, labels, stats[:, cv2.CC_STAT_AREA]

    def lowest_of_every_blob(labels, asked):
        count = len(asked)
        _, _, stats, _ = cv2.connectedComponentsWithStats((labels > 0).astype(np.uint8), connectivity=8)
        lowest = np.full(count, -1, np.int64)
        for label in range(1, count):   # (every blob, asked or not: the rule reads only the asked ones)
            rows = np.flatnonzero((labels == label).any(axis=1))
            lowest[label] = rows[-1] if rows.size else -1
        return lowest

    rng = np.random.default_rng(23)
    results = {}
    for form in ("fast", "plain"):
        if form == "plain":
            for module in (masks, shape_check, tangle):
                monkeypatch.setattr(module, "components", components_with_stats, raising=False)
            monkeypatch.setattr(masks, "lowest_rows", lowest_of_every_blob)
        rng = np.random.default_rng(23)
        out = []
        for trial in range(120):
            h, w, ey0, expected, search, observed, linked = _random_scene(rng, 180, 3, 9, 60)
            before = np.roll(observed & ~expected, int(rng.integers(-3, 4)), axis=0) if trial % 2 else None
            tol = float(rng.choice([1.0, 2.0, 3.0]))
            foreign = masks.reaching_in_from_above(linked & ~expected, search, expected, material=observed & ~expected,
                                                   before=before)
            comparison = compare_masks(observed, ~linked, expected, expected & (np.arange(h)[:, None] < ey0 + 5),
                                       search, rng.random((h, w)) < 0.3, tol, band_reach=2 * tol,
                                       top_tolerance=tol, linked=linked, foreign_before=before)
            new = new_material(observed, expected | (rng.random((h, w)) < 0.01), expected, search, tol, 2.0,
                               linked=linked, marks=rng.random((h, w)) < 0.2)
            out.append((foreign, comparison.missing, comparison.extra, comparison.foreign,
                        None if new is None else (new.pixels, new.blobs, new.at_foot_mm2, new.mask)))
        results[form] = out
    found = 0
    for trial, (fast, plain) in enumerate(zip(results["fast"], results["plain"])):
        found += bool(fast[0].any())
        for a, b in zip(fast[:4], plain[:4]):
            assert (a is None) == (b is None) and (a is None or np.array_equal(a, b)), trial
        assert (fast[4] is None) == (plain[4] is None), trial
        if fast[4] is not None:
            assert fast[4][:3] == plain[4][:3] and np.array_equal(fast[4][3], plain[4][3]), trial
    assert found > 20


def test_clipped_bed_test_without_a_clipped_channel_finds_nothing():
    """shade_of_clipped_bed returns at once when no channel is clipped anywhere: the answer it gave before."""
    rng = np.random.default_rng(24)
    frame = rng.uniform(0, 255, (40, 50, 3)).astype(np.float32)
    background = rng.uniform(0, 255, (40, 50, 3)).astype(np.float32)
    where = rng.random((40, 50)) < 0.5
    assert not shadows.shade_of_clipped_bed(frame, background, np.zeros((40, 50, 3), bool), 10.0, where).any()
    clipped = np.zeros((40, 50, 3), bool)
    clipped[..., 2] = True
    background[..., 2] = 255.0
    frame = background * 0.6
    assert shadows.shade_of_clipped_bed(frame, background, clipped, 10.0, where)[where].all()


def test_edge_noise_is_read_only_where_a_column_fails_the_share_test():
    """edge_in_the_frame with the bed sample: the columns of the share test alone plus those clear of the
    noise; where the share test passes every column, the sample changes nothing (it is then not read)."""
    from octoprint_printwatch.core.growth import edge_in_the_frame
    rng = np.random.default_rng(25)
    both_kinds = set()
    for trial in range(150):
        h, w = 90, 70
        background = (rng.normal(100, 3, (h, w, 3))).clip(0, 255).astype(np.float32)
        frame = (background + rng.normal(0, 3, (h, w, 3))).clip(0, 255).astype(np.uint8)
        top = int(rng.integers(20, 60))
        observed = np.zeros((h, w), bool)
        observed[top:, 20:50] = True
        frame[top:, 20:50] = rng.integers(0, 256, 3)
        ghost = rng.integers(20, 50, 2)   # an edge the background frame holds
        background[top:, ghost.min():ghost.max() + 1] += float(rng.uniform(0, 120))
        sample = np.zeros((h, w), bool)
        sample[:, :12] = True
        alone = edge_in_the_frame(observed, frame, background, 2.0, None)
        noise = edge_in_the_frame(observed, frame, background, 2.0, sample)
        assert not (alone & ~noise).any(), trial
        readable = edge_in_the_frame(observed, frame, frame.astype(np.float32) * 0 + 100.0, 2.0, None)
        if alone[readable].all():
            assert np.array_equal(alone, noise), trial
        both_kinds.add(bool(alone[readable].all()))
    assert both_kinds == {True, False}


def test_bed_marks_zone_is_kept_per_camera_and_equals_bed_marks_mask():
    """JobPlan.regions reads the bed ring (the same at every height) once per camera: the arrays it gives
    are bed_marks_mask's, read-only."""
    from types import SimpleNamespace
    from octoprint_printwatch.core.camera import Camera
    from octoprint_printwatch.core.pipeline import JobPlan, bed_marks_mask
    from octoprint_printwatch.core.settings import DetectionSettings
    cam = Camera.look_at("a", (100, -20, 60), (100, 100, 4), width=160, height=120, hfov_deg=40)
    footprint = np.array([[90.0, 90.0], [110.0, 90.0], [110.0, 110.0], [90.0, 110.0]])
    views = {("a", z): SimpleNamespace(silhouette=np.zeros((120, 160), bool), new_band=np.zeros((120, 160), bool))
             for z in (2.0, 4.0)}
    plan = JobPlan(part=None, cameras={"a": cam}, pairs=[], check_heights=[(1, 2.0), (2, 4.0)], views=views,
                   footprint=footprint, max_shift_px={"a": 5.0}, tolerance_px={"a": 2.0})
    settings = DetectionSettings()
    first, second = plan.regions("a", 2.0, settings), plan.regions("a", 4.0, settings, 2.0)
    for z, regions in ((2.0, first), (4.0, second)):
        flat, mirror = bed_marks_mask(cam, footprint, z, settings.bed_marks_margin_mm)
        assert np.array_equal(regions.dont_care, flat) and np.array_equal(regions.reflection, mirror)
    assert second.dont_care is first.dont_care and not first.dont_care.flags.writeable


def test_band_shift_on_its_window_is_band_shift_on_the_whole_image(monkeypatch):
    """layer_shift.band_shift reads the band's window only (its box grown by the reach, the tolerance and what
    the tolerance ring reads): every figure, map and null score as on the whole image, bands at the image's edge
    and tolerances that take either of masks.dilate's forms included."""
    from octoprint_printwatch.core import layer_shift
    rng = np.random.default_rng(26)
    cases = []
    for trial in range(150):
        h, w = (int(v) for v in rng.integers(60, 200, size=2))
        before = np.zeros((h, w), bool)
        top, left = int(rng.integers(0, h - 10)), int(rng.integers(0, w // 2))
        right = min(w, left + int(rng.integers(8, w // 2 + 10)))
        rows = int(rng.integers(2, 12))
        before[top + rows:, left:right] = True
        band = np.zeros((h, w), bool)
        band[top:top + rows, left:right] = True
        band &= rng.random((h, w)) < 0.95
        dx, dy = (int(v) for v in rng.integers(-6, 7, size=2))
        seen = before | np.roll(np.roll(band, dx, axis=1), dy, axis=0)
        observed = seen & (rng.random((h, w)) < 0.9) | (rng.random((h, w)) < 0.02)
        bed = ~observed & (rng.random((h, w)) < 0.85)
        undecided = (rng.random((h, w)) < 0.1) if trial % 2 else None
        reach = int(rng.integers(4, 30))
        tol = float(rng.choice([0.0, 1.0, 2.0, 3.0, 4.5]))
        cases.append((observed, bed, before, band, reach, reach // 2, int(rng.integers(1, 5)), tol, undecided))

    def run():
        return [layer_shift.band_shift(*c[:8], undecided=c[8]) for c in cases]

    fast = run()
    monkeypatch.setattr(layer_shift, "_window", lambda band, *_: (slice(None), slice(None)))
    plain = run()
    tested = 0
    for trial, (a, b) in enumerate(zip(fast, plain)):
        assert (a is None) == (b is None), trial
        if a is not None:
            tested += 1
            assert a.figures() == b.figures() and (a.null_dy, a.null_score) == (b.null_dy, b.null_score), trial
            assert np.array_equal(a.maps, b.maps) and np.array_equal(a.null_scores, b.null_scores), trial
    assert tested > 100


# ------------------------------------------------ twenty-sixth session: work on the blobs' own box
# What a user would notice if one of these differed: a check's verdict or figures changing with nothing but the
# speed-up (an extra blob or a rod counted differently near the crop's edge, a pause that was not there before).


def _whole_mask_labelling(mask):
    """masks.labelled_on_its_box's plain form: the whole mask labelled."""
    count, labels = cv2.connectedComponents(mask.astype(np.uint8), connectivity=8)
    return count, labels, (slice(0, mask.shape[0]), slice(0, mask.shape[1]))


def test_labelled_on_its_box_gives_every_blob_its_label_on_the_whole_mask():
    """Labelling on the blobs' box (its corner moved to even coordinates) numbers the blobs as the whole mask does,
    wherever the box starts (odd rows and columns) and at the frame's edges; an empty mask has no blob."""
    from octoprint_printwatch.core.masks import labelled_on_its_box
    rng = np.random.default_rng(31)
    for trial in range(400):
        h, w = (int(v) for v in rng.integers(10, 160, size=2))
        mask = _blob_scene(rng)[:h, :w] if trial % 4 else np.zeros((h, w), bool)
        h, w = mask.shape
        # clear a random margin on each side (odd box corners), or keep blobs on the frame's edges
        if trial % 3:
            mask[: int(rng.integers(0, h // 2 + 1))] = False
            mask[:, : int(rng.integers(0, w // 2 + 1))] = False
        count, labels, inner = labelled_on_its_box(mask)
        count_w, labels_w, _ = _whole_mask_labelling(mask)
        assert count == count_w and np.array_equal(labels, labels_w), trial
        assert not labels[~mask].any() and (labels[inner] > 0).sum() == mask.sum(), trial


def _rod_scene(rng):
    """A part, its outline zone and search box, and objects: rods crossing the box (some from the frame's edge,
    some ending behind the part, some pieces coming out beyond it), strands and blobs, weak pixels joining them."""
    from octoprint_printwatch.core.masks import outline_zone
    h, w = (int(v) for v in rng.integers(90, 240, size=2))
    part = np.zeros((h, w), bool)
    py0, px0 = int(rng.integers(h // 3, h // 2)), int(rng.integers(w // 4, w // 2))
    part[py0:py0 + h // 3, px0:px0 + w // 5] = True
    outline = outline_zone(part, 2.0, 2.0)
    search = np.zeros((h, w), bool)
    top, bottom = int(rng.integers(0, py0 - 5)), h - int(rng.integers(0, 10))
    search[top:bottom, int(rng.integers(0, 20)):w - int(rng.integers(0, 20))] = True
    objects = np.zeros((h, w), np.uint8)
    for _ in range(int(rng.integers(0, 4))):   # rods across the picture, or from one edge to the part
        y = int(rng.integers(0, h))
        x_end = w if rng.random() < 0.6 else px0 + int(rng.integers(0, w // 5))
        cv2.line(objects, (0 if rng.random() < 0.7 else int(rng.integers(0, 10)), y),
                 (x_end, y + int(rng.integers(-12, 13))), 1, int(rng.integers(3, 12)))
        if x_end < w and rng.random() < 0.7:   # the rod's piece coming out beyond the part
            yy = y + int(rng.integers(-3, 4))
            cv2.line(objects, (px0 + w // 5 + int(rng.integers(2, 8)), yy), (w - int(rng.integers(0, 30)), yy), 1,
                     int(rng.integers(3, 12)))
    for _ in range(int(rng.integers(0, 12))):   # strands and blobs
        x, y = int(rng.integers(0, w)), int(rng.integers(0, h))
        cv2.line(objects, (x, y), (x + int(rng.integers(-25, 25)), y + int(rng.integers(-25, 25))), 1,
                 int(rng.integers(1, 6)))
    objects = objects.astype(bool) & ~outline
    material = objects & (rng.random((h, w)) < rng.uniform(0.7, 1.0))
    linked = (objects | (rng.random((h, w)) < 0.03)) & ~outline
    return search, outline, linked, material


def test_rods_read_on_the_objects_box_are_the_rods_read_on_the_whole_crop(monkeypatch):
    """crossing_the_box labels each grouping on its blobs' box and reads the extents of the few blobs it tests (and,
    where a rod runs on behind the part, of every large blob): the same strips as the whole crop labelled with
    cv2.connectedComponentsWithStats, on rods at the frame's edges, rods ending behind the part, empty objects."""
    from octoprint_printwatch.core import masks

    def every_extent(stats, labels, indices, inner):
        mask = labels > 0
        _, labels_w, stats_w, _ = cv2.connectedComponentsWithStats(mask.astype(np.uint8), connectivity=8)
        assert np.array_equal(labels_w, labels)
        stats[1:, :4] = stats_w[1:, :4]

    behind = []
    come_out = masks._rods_come_out
    monkeypatch.setattr(masks, "_rods_come_out", lambda *a: behind.append(1) or come_out(*a))
    scenes = [_rod_scene(np.random.default_rng(1000 + trial)) for trial in range(160)]
    scenes.append((scenes[0][0], scenes[0][1], np.zeros_like(scenes[0][2]), np.zeros_like(scenes[0][2])))

    def run():
        return [(masks.crossing_the_box(linked, search, outline, part_in_place=bool(i % 2), material=material),
                 masks.crossing_the_box(linked, search, outline, part_in_place=True))
                for i, (search, outline, linked, material) in enumerate(scenes)]

    fast = run()
    monkeypatch.setattr(masks, "labelled_on_its_box", _whole_mask_labelling)
    monkeypatch.setattr(masks, "_fill_extents", every_extent)
    plain = run()
    for trial, (a, b) in enumerate(zip(fast, plain)):
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]), trial
    assert sum(a[0].any() for a in fast) > 20 and len(behind) > 10


def test_distances_read_on_the_box_are_the_whole_images():
    """masks.within and masks.distance_up_to against cv2.distanceTransform of the whole image, thresholded at every
    distance they are read at: masks touching the frame's edges, a single pixel, an empty and a full mask."""
    from octoprint_printwatch.core.masks import distance_up_to, within
    rng = np.random.default_rng(33)
    masks_tried = [np.zeros((40, 30), bool), np.ones((40, 30), bool)]
    single = np.zeros((50, 60), bool)
    single[0, 59] = True
    masks_tried.append(single)
    masks_tried += [_blob_scene(rng) for _ in range(150)]
    for trial, mask in enumerate(masks_tried):
        whole = cv2.distanceTransform((~mask).astype(np.uint8), cv2.DIST_L2, 3)
        for reach in (0.5, 1.0, 2.6, 3.0, float(rng.uniform(3, 40)), np.float64(rng.uniform(3, 40))):
            assert np.array_equal(within(mask, reach), whole <= reach), (trial, reach)
            up_to = distance_up_to(mask, reach)
            for t in (0.0, 1.0, reach / 3, reach / 2, reach):
                assert np.array_equal(up_to <= t, whole <= t), (trial, reach, t)
                assert np.array_equal(up_to > t, whole > t), (trial, reach, t)


def test_extra_blobs_judged_on_their_box_are_judged_on_the_whole_crop(monkeypatch):
    """compare_masks drops specks and flat blobs (bed marks, reflections) on the extra material's box with a ring of
    bed: the same masks and figures as on the whole crop, blobs on the crop's edges included."""
    from octoprint_printwatch.core import shape_check

    def run(seed):
        rng = np.random.default_rng(seed)
        out = []
        for trial in range(150):
            h, w, ey0, expected, search, observed, linked = _random_scene(rng, 200, int(rng.integers(0, 4)), 10, 50)
            if trial % 3 == 0:   # blobs on the crop's edges
                observed[:, : int(rng.integers(1, 8))] |= rng.random((h, 1)) < 0.5
                observed[h - int(rng.integers(1, 8)):] = True
            tol = float(rng.choice([1.0, 2.0, 3.0]))
            marks = cv2.dilate((rng.random((h, w)) < 0.01).astype(np.uint8), np.ones((9, 15), np.uint8)).astype(bool)
            reflection = (np.roll(expected, int(rng.integers(5, 30)), axis=0) & ~expected) if trial % 2 else None
            comparison = compare_masks(observed, ~linked, expected, expected & (np.arange(h)[:, None] < ey0 + 5),
                                       search, marks, tol, band_reach=2 * tol, flat_max_px=float(rng.uniform(4, 20)),
                                       reflection=reflection, top_tolerance=tol, linked=linked)
            out.append(comparison)
        return out

    fast = run(34)
    monkeypatch.setattr(shape_check, "bounding_box",
                        lambda mask, pad=0: (0, mask.shape[0], 0, mask.shape[1]) if mask.any() else None)
    plain = run(34)
    counted = 0
    for trial, (a, b) in enumerate(zip(fast, plain)):
        counted += bool(a.extra.any())
        assert np.array_equal(a.missing, b.missing) and np.array_equal(a.extra, b.extra), trial
        assert (a.band_extra, a.raw_diff_pixels, a.part_in_place) == (b.band_extra, b.raw_diff_pixels, b.part_in_place)
    assert counted > 30


def test_new_material_blobs_on_their_box_and_risen_top_made_when_read(monkeypatch):
    """new_material labels the new material on its box, and takes the risen top as a function it calls only when it
    counts: the same figures and masks as the whole crop labelled with the risen top given made."""
    from octoprint_printwatch.core import tangle

    def run(seed, lazy):
        rng = np.random.default_rng(seed)
        out, calls = [], []
        for trial in range(150):
            h, w, ey0, expected, search, observed, linked = _random_scene(rng, 200, 0, 8, 40)
            previous = expected | (rng.random((h, w)) < 0.01)
            risen = np.roll(expected, -int(rng.integers(1, 8)), axis=0) & ~expected
            given = (lambda r=risen: calls.append(1) or r) if lazy else risen
            new = new_material(observed, previous, expected, search, float(rng.choice([1.0, 2.0])), 2.0,
                               linked=linked, marks=rng.random((h, w)) < 0.2, risen=given)
            out.append(None if new is None else (new.pixels, new.blobs, new.at_foot_mm2, new.arc_deg, new.mask))
        return out, len(calls)

    fast, made = run(35, lazy=True)
    monkeypatch.setattr(tangle, "labelled_on_its_box", _whole_mask_labelling)
    plain, _ = run(35, lazy=False)
    counted = 0
    for trial, (a, b) in enumerate(zip(fast, plain)):
        assert (a is None) == (b is None), trial
        if a is not None:
            counted += a[0] > 0
            assert a[:4] == b[:4] and np.array_equal(a[4], b[4]), trial
    assert counted > 20 and 0 < made < len(fast)


def test_lowest_rows_per_label_and_luma_chroma_of_small_shapes():
    """lowest_rows reads each of up to four labels asked on its own and gathers the pixels of more: both give
    connectedComponentsWithStats' lowest rows; _luma_chroma splits (h, w, 3) images into planes, including the
    (n, 1, 3) and (1, k, 3) arrays detectable_fraction passes, and reads (n, 3) rows as before."""
    from octoprint_printwatch.core.masks import components, lowest_rows
    rng = np.random.default_rng(36)
    for trial in range(200):
        count, labels, _ = components(_blob_scene(rng))
        _, _, stats, _ = cv2.connectedComponentsWithStats((labels > 0).astype(np.uint8), connectivity=8)
        asked = np.zeros(count, bool)
        asked[rng.choice(np.arange(1, count), size=min(count - 1, trial % 8), replace=False)] = True
        want = np.where(asked, stats[:, cv2.CC_STAT_TOP] + stats[:, cv2.CC_STAT_HEIGHT] - 1, -1)
        assert np.array_equal(lowest_rows(labels, asked), want), trial
    for shape in ((7, 1, 3), (1, 5, 3), (9, 3), (1, 1, 3)):
        values = rng.uniform(0, 255, shape).astype(np.float32)
        for fast, plain in zip(_luma_chroma(values), _luma_chroma_plain(values)):
            assert fast.shape == plain.shape and np.array_equal(fast, plain), shape
