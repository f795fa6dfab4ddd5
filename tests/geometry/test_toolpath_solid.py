"""The part rebuilt from real slicer G-code, compared with the STL it was sliced from."""
import numpy as np
import pytest

from octoprint_printwatch.core.errors import GeometryError
from octoprint_printwatch.core.geometry import (
    _perimeter,
    expected_width,
    load_mesh,
    part_from_mesh,
    place_mesh_on_gcode,
)

from .conftest import SLICED_FROM

#: Corpus files fast enough for unit tests: PrusaSlicer, CuraEngine (adaptive layers; no width comments and
#: E computed for 2.85 mm filament), Slic3r 1.3 without any feature tags, a spiral vase.
SAMPLES = [
    "prusa25_cylinder.gcode",
    "prusa25_pyramid_fwretract.gcode",
    "prusa25_twisted_vase_spiral.gcode",
    "cura413_ender3_pyramid_adaptive_layers.gcode",
    "cura413_ender3_t55_gear_relative_e_zhop.gcode",
    "slic3r13_cube.gcode",
]


@pytest.mark.parametrize("name", SAMPLES)
def test_gcode_solid_matches_the_stl_at_every_check_height(corpus, gcode_part, name):
    part = gcode_part(name)
    placed = part_from_mesh(place_mesh_on_gcode(corpus / SLICED_FROM[name], corpus / name).mesh)
    assert part.mesh.is_watertight
    assert part.height() == pytest.approx(placed.height(), abs=0.15)
    offsets, relative = [], []
    for z in np.arange(1.0, part.height() - 0.5, 2.0):  # a check every 2 mm
        layer = part.layer_at(z)
        expected = placed.cross_section((layer.z_bottom + layer.z_top) / 2)  # slicers slice mid-layer
        got = part.cross_section_area(z)
        want = placed.cross_section_area((layer.z_bottom + layer.z_top) / 2)
        offsets.append((got - want) / _perimeter(expected))  # mean outline offset, mm
        if want > 300.0:  # on small sections a constant offset is a large fraction
            relative.append(abs(got - want) / want)
    assert max(np.abs(offsets)) < 0.1, offsets  # within a quarter of an extrusion width
    assert max(relative) < 0.02, relative


def test_gear_bore_stays_a_hole_while_infill_gaps_are_filled(corpus, gcode_part):
    part = gcode_part("cura413_ender3_t55_gear_relative_e_zhop.gcode")
    layer_areas = [part.cross_section_area(z) for z in np.arange(3.0, 21.0, 1.0)]
    # Sparse infill changes per layer; the outline does not.
    assert np.ptp(layer_areas) < 0.01 * np.mean(layer_areas)
    signed = sorted(np.sign([np.sum(p[:, 0] * np.roll(p[:, 1], -1) - p[:, 1] * np.roll(p[:, 0], -1))
                             for p in part.cross_section(10.0)]))
    assert signed == [-1.0, 1.0]  # one outline, one bore


def test_cura_purge_line_and_skirt_are_not_part_of_the_solid(gcode_part):
    part = gcode_part("cura413_ender3_t55_gear_relative_e_zhop.gcode")
    # Ender-3 start script: purge lines at x = 0.1 and 0.4 from y = 20 to 200; the gear sits at (117.5, 117.5).
    lo, hi = part.mesh.bounds
    assert lo[0] > 117.5 - 27.5 and hi[0] < 117.5 + 27.5 and lo[1] > 117.5 - 27.5
    assert part.apart is not None
    apart_lo, apart_hi = part.apart.bounds
    assert apart_lo[0] < 1.0 and apart_hi[1] > 199.0  # the purge line is kept, apart
    assert apart_hi[2] <= 0.31  # and it is flat
    assert expected_width(part, 0.2, (1, 0)) < 55.0  # the first layer's width ignores the skirt


def test_prusa_skirt_is_kept_apart(gcode_part):
    part = gcode_part("prusa25_cylinder.gcode")
    lo, hi = part.mesh.bounds
    assert np.allclose(lo[:2], 86.0, atol=0.1) and np.allclose(hi[:2], 114.0, atol=0.1)
    assert part.apart.bounds[0, 0] < 81.0 and part.apart.bounds[1, 2] <= 0.21


def test_untagged_slic3r_skirt_and_outline_are_recognised_by_shape(gcode_part):
    part = gcode_part("slic3r13_cube.gcode")  # no ;TYPE comments at all
    lo, hi = part.mesh.bounds
    assert np.allclose(lo, [85.0, 85.0, 0.0], atol=0.1) and np.allclose(hi, [115.0, 115.0, 30.0], atol=0.1)
    assert part.apart is not None and part.apart.bounds[0, 0] < 80.0
    assert any("skirt" in note for note in part.notes)
    # Sparse infill gaps are filled from the external perimeters found by nesting: the full 30 x 30 mm square.
    for z in (0.2, 5.0, 15.0, 29.9):
        assert part.cross_section_area(z) == pytest.approx(900.0, rel=0.02)
        assert len(part.cross_section(z)) == 1


def test_two_objects_are_both_in_the_solid(gcode_part):
    part = gcode_part("prusa25_two_cubes.gcode")
    assert part.cross_section_area(10.0) == pytest.approx(2 * 900.0, rel=0.01)
    assert len(part.mesh.split(only_watertight=False)) == 2


@pytest.mark.parametrize("name, rotation", [
    ("cura413_ender3_t55_gear_relative_e_zhop.gcode", 0.0),
    ("prusa25_cylinder.gcode", 0.0),
    ("cura413_ender3_pyramid_adaptive_layers.gcode", 0.0),
    ("slic3r13_cube.gcode", 0.0),
])
def test_stl_is_placed_where_the_slicer_put_it(corpus, gcode_part, name, rotation):
    gcode_part(name)
    centre = 117.5 if name.startswith("cura") else 100.0
    placement = place_mesh_on_gcode(corpus / SLICED_FROM[name], corpus / name)
    assert placement.dx == pytest.approx(centre, abs=0.5) and placement.dy == pytest.approx(centre, abs=0.5)
    assert placement.rotation_deg == pytest.approx(rotation, abs=0.5)
    assert placement.residual_mm < 0.3


def test_rotated_stl_is_placed_with_its_rotation(corpus, gcode_part):
    import trimesh

    name = "prusa25_pyramid_fwretract.gcode"
    gcode = gcode_part(name)
    mesh = load_mesh(corpus / "pyramid.stl")
    mesh.apply_transform(trimesh.transformations.rotation_matrix(np.radians(20.0), (0, 0, 1)))
    mesh.apply_translation((-30.0, 12.0, 0.0))
    placement = place_mesh_on_gcode(mesh, corpus / name)
    # The pyramid's square is the same every 90 degrees.
    assert (placement.rotation_deg + 20.0) % 90.0 == pytest.approx(0.0, abs=0.5) or \
        (placement.rotation_deg + 20.0) % 90.0 == pytest.approx(90.0, abs=0.5)
    assert placement.residual_mm < 0.3
    placed = part_from_mesh(placement.mesh)
    for z in (1.0, 10.0, 25.0):
        assert placed.cross_section_area(z) == pytest.approx(gcode.cross_section_area(z), rel=0.05)
    assert placement.mesh.bounds[:, :2].mean(axis=0) == pytest.approx([100.0, 100.0], abs=0.5)


def test_wrong_stl_for_the_gcode_is_refused(corpus, gcode_part):
    gcode_part("prusa25_cylinder.gcode")
    gcode_part("slic3r13_cube.gcode")
    with pytest.raises(GeometryError, match="wrong model"):
        place_mesh_on_gcode(corpus / "pyramid.stl", corpus / "prusa25_cylinder.gcode")  # other height
    narrow = load_mesh(corpus / "cube.stl")
    narrow.apply_scale((0.9, 0.9, 1.0))  # same height, 3 mm narrower
    with pytest.raises(GeometryError, match="does not match the G-code's footprint") as info:
        place_mesh_on_gcode(narrow, corpus / "slic3r13_cube.gcode")
    assert "slic3r13_cube.gcode" in str(info.value)


def test_gcode_with_nothing_to_build_gives_a_clear_error(tmp_path):
    from octoprint_printwatch.core.errors import PrintWatchError
    from octoprint_printwatch.core.toolpath_solid import build_gcode_part

    path = tmp_path / "travel_only.gcode"
    path.write_text("G28\nG1 X10 Y10 Z0.2 F3000\nG1 X20 Y20\n")
    with pytest.raises(PrintWatchError) as info:
        build_gcode_part(path)
    assert "travel_only.gcode" in str(info.value)
    with pytest.raises(GeometryError, match="no such G-code file"):
        build_gcode_part(tmp_path / "missing.gcode")


def test_untagged_gear_keeps_its_bore(tmp_path, corpus, gcode_part):
    """The same Cura file with every ;TYPE comment removed gives the same outline, bore included."""
    from octoprint_printwatch.core.toolpath_solid import build_gcode_part

    name = "cura413_ender3_t55_gear_relative_e_zhop.gcode"
    tagged = gcode_part(name)
    stripped = tmp_path / "untagged.gcode"
    with open(corpus / name) as source, open(stripped, "w") as target:
        target.writelines(line for line in source if not line.startswith(";TYPE:"))
    part = build_gcode_part(stripped)
    assert any("no feature tags" in note for note in part.notes)
    for z in (2.0, 10.0, 20.0):
        assert part.cross_section_area(z) == pytest.approx(tagged.cross_section_area(z), rel=0.02)
        assert len(part.cross_section(z)) == 2  # the gear and its bore
    lo, hi = part.mesh.bounds
    # Purge line and brim apart (a brim keeps at most 0.6 mm round the part: it touches it).
    assert lo[0] > 117.5 - 27.0 - 0.7 and hi[0] < 117.5 + 27.0 + 0.7
    assert part.apart.bounds[0, 0] < 1.0 and part.apart.bounds[1, 0] > 117.5 + 30.0


@pytest.mark.parametrize("name, size", [
    ("third_party/cura_lulzbot_369_cube.gcode", (20.0, 20.0, 4.78)),  # 2.85 mm filament, no diameter comment
    ("third_party/ideamaker_34_calibration_box.gcode", (20.0, 20.0, 10.08)),
])
def test_real_user_files_give_their_nominal_part_size(gcode_part, name, size):
    part = gcode_part(name)
    assert part.mesh.extents == pytest.approx(size, abs=0.1)
    assert part.apart is not None  # their skirts are kept apart
