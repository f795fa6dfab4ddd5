"""When one camera alone may pause the print: "missing AND extra material" is not decisive when the part stands
where this camera's earlier passing checks laid the outline, and the outline walked off it since (a part in a
colour close to the bed's, its cast shadow at the foot pulling the alignment; s18 ``044_runout`` s2)."""
import pytest

from octoprint_printwatch.core.shape_check import check_shape, not_decisive_where_it_stood

from .synthetic import PART, bed_texture, camera_effects, paint_part, regions


@pytest.fixture(scope="module")
def bed():
    return bed_texture()


def run(bed, part, anchor, placed_at):
    # the anchor is where the outline lies now (max_drift=0 keeps it there); placed_at, where earlier checks laid it
    args = dict(camera="cam", background=camera_effects(bed, seed=11), frame=camera_effects(paint_part(bed, part)),
                regions=regions(), anchor=anchor, max_drift=0, placed_at=tuple(placed_at))
    return not_decisive_where_it_stood(check_shape(**args), args)


def test_an_outline_walked_off_a_part_that_stands_where_it_was_placed_before_is_not_decisive(bed):
    # the part stands 8 px right of the calibrated place, where the earlier checks found it; the outline walked
    # 8 px further: neither the calibrated place nor where it lies now fits, the earlier place does
    r = run(bed, PART.moved(8, 8), (16, 16), [(8, 8), (12, 12)])
    assert r.shift_px == (16, 16)
    assert not r.passed
    assert min(r.missing_pct, r.extra_pct) >= r.threshold / 3   # what makes it decisive
    assert not r.decisive
    assert any("shape differs from the model" in reason for reason in r.reasons)   # still reported and failing


def test_a_part_that_moved_away_from_every_earlier_place_is_decisive(bed):
    # the outline stayed where the earlier checks laid it; the part slid 8 px: it fits nowhere known
    r = run(bed, PART.moved(8, 16), (8, 8), [(8, 8), (7, 8)])
    assert not r.passed and r.decisive
    # nor does an earlier place the part never stood at clear it
    r = run(bed, PART.moved(8, 16), (8, 8), [(0, 0), (8, 0)])
    assert not r.passed and r.decisive


def test_without_earlier_places_nothing_changes(bed):
    r = run(bed, PART.moved(8, 8), (16, 16), [])
    assert not r.passed and r.decisive
