"""The part from a mesh: loading, repair, partial solids, cross-sections, widths."""
import math

import numpy as np
import pytest
import trimesh

from octoprint_printwatch.core.errors import GeometryError
from octoprint_printwatch.core.geometry import (
    expected_width,
    load_mesh,
    part_for_job,
    part_from_mesh,
    polygons_area,
)

CORPUS_MESHES = ["cube.stl", "cylinder.stl", "pyramid.stl", "sun_gear.stl", "t55_gear.stl", "twisted_vase.stl"]


def test_pyramid_cross_section_area_follows_the_analytic_frustum(corpus):
    part = part_from_mesh(corpus / "pyramid.stl")  # frustum: 30 mm square base, 1.5 mm square top at 33 mm
    for z in (0.1, 5.0, 16.5, 30.0):
        side = 30.0 - 28.5 * z / 33.0
        assert part.cross_section_area(z) == pytest.approx(side * side, rel=1e-3)
    assert part.height() == pytest.approx(33.0)


def test_solid_below_is_the_part_trimmed_at_z(corpus):
    part = part_from_mesh(corpus / "cube.stl")  # 30 mm cube on the bed
    for z in (0.2, 7.3, 29.9):
        below = part.solid_below(z)
        assert below.is_watertight
        assert below.volume == pytest.approx(900.0 * z, rel=1e-6)
        assert below.bounds[1, 2] == pytest.approx(z)
    assert part.solid_below(50.0).volume == pytest.approx(27000.0)
    assert len(part.solid_below(-1.0).faces) == 0


def test_cross_section_at_the_very_top_is_the_top_face(corpus):
    part = part_from_mesh(corpus / "cube.stl")
    assert part.cross_section_area(30.0) == pytest.approx(900.0, rel=1e-3)
    assert part.cross_section(31.0) != [] and part.cross_section(-0.5) == []


def test_holes_are_clockwise_and_subtract(corpus):
    part = part_from_mesh(corpus / "t55_gear.stl")  # a gear with a bore
    polygons = part.cross_section(5.0)
    areas = sorted(polygons_area([p]) for p in polygons)
    assert areas[0] < 0 < areas[-1]
    assert part.cross_section_area(5.0) == pytest.approx(sum(areas))


@pytest.mark.parametrize("name", CORPUS_MESHES)
def test_every_corpus_mesh_slices_at_every_layer_height(corpus, name):
    part = part_from_mesh(corpus / name)
    assert part.manifold() is not None and part.notes == []
    heights = np.arange(0.2, part.height() + 1e-9, 0.2)
    empty = [round(z, 2) for z in heights if part.cross_section_area(z) <= 0.0]
    assert empty == []
    assert part.solid_below(part.height() / 2).is_watertight


def test_expected_width_across_directions(corpus):
    cube = part_from_mesh(corpus / "cube.stl")
    assert expected_width(cube, 10.0, (1, 0)) == pytest.approx(30.0, abs=1e-6)
    assert expected_width(cube, 10.0, (1, 1)) == pytest.approx(30.0 * math.sqrt(2), abs=1e-6)
    assert expected_width(cube, 45.0, (0, 1)) == pytest.approx(30.0, abs=1e-6)  # above the top: the top
    pyramid = part_from_mesh(corpus / "pyramid.stl")
    # Half a layer below z: the middle of the newest layer.
    assert expected_width(pyramid, 16.6, (0, 1)) == pytest.approx(30.0 - 28.5 * 16.5 / 33.0, abs=1e-3)
    with pytest.raises(GeometryError, match="direction"):
        expected_width(cube, 10.0, (0, 0))


def test_mesh_with_a_missing_face_is_repaired_and_says_so(corpus, tmp_path):
    mesh = load_mesh(corpus / "cylinder.stl")
    broken = mesh.copy()
    broken.update_faces(np.arange(1, len(mesh.faces)))  # punch a hole
    assert not broken.is_watertight
    path = tmp_path / "holed.stl"
    broken.export(path)
    part = part_from_mesh(path)
    assert any("repaired" in note for note in part.notes)
    assert part.mesh.is_watertight
    assert part.cross_section_area(20.0) == pytest.approx(part_from_mesh(mesh).cross_section_area(20.0), rel=1e-3)


def shredded_cylinder(corpus) -> trimesh.Trimesh:
    """A cylinder without its top cap: a 190-sided hole that hole filling does not close."""
    mesh = load_mesh(corpus / "cylinder.stl")
    keep = mesh.face_normals[:, 2] < 0.9
    return mesh.submesh([np.nonzero(keep)[0]], append=True)


def test_unrepairable_mesh_still_renders_and_says_so(corpus):
    part = part_from_mesh(shredded_cylinder(corpus))
    assert any("could not be repaired" in note for note in part.notes)
    assert part.manifold() is None
    below = part.solid_below(20.0)
    assert len(below.faces) > 0
    assert below.bounds[1, 2] <= 20.0 + 1e-9


def test_unrepairable_mesh_falls_back_to_the_gcode_solid(corpus, tmp_path, gcode_part):
    broken = shredded_cylinder(corpus)
    broken.apply_translation((100, 100, 0))
    path = tmp_path / "broken.stl"
    broken.export(path)
    gcode_part("prusa25_cylinder.gcode")  # build once for the session
    part = part_for_job(path, corpus / "prusa25_cylinder.gcode")
    assert part.source == "gcode"
    assert "fell back to the G-code solid" in part.notes[0]
    assert part.cross_section_area(20.0) == pytest.approx(math.pi * 14.0 ** 2, rel=0.03)


@pytest.mark.parametrize("suffix", [".obj", ".ply", ".3mf"])
def test_other_mesh_formats_load_the_same_part(corpus, tmp_path, suffix):
    mesh = load_mesh(corpus / "pyramid.stl")
    path = tmp_path / f"pyramid{suffix}"
    mesh.export(path)
    part = part_from_mesh(path)
    assert part.mesh.volume == pytest.approx(mesh.volume, rel=1e-4)
    assert part.cross_section_area(10.0) == pytest.approx(part_from_mesh(mesh).cross_section_area(10.0), rel=1e-4)


@pytest.mark.parametrize("content, suffix, message", [
    (None, ".stl", "no such mesh file"),
    (b"solid x\nthis is not an stl\n", ".stl", "holds no triangles|not a readable"),
    (b"\x00" * 20, ".stl", "holds no triangles|not a readable"),
    (b"hello", ".docx", "unsupported mesh format"),
])
def test_bad_mesh_files_give_one_line_errors_naming_the_file(tmp_path, content, suffix, message):
    path = tmp_path / f"model{suffix}"
    if content is not None:
        path.write_bytes(content)
    with pytest.raises(GeometryError, match=message) as info:
        load_mesh(path)
    text = str(info.value)
    assert str(path) in text and "\n" not in text
