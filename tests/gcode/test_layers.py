"""Layer tables of real slicer files, checked against what the slicers themselves wrote.

The analysis finds layers from the Z of extruding moves; the expected values here
come from each slicer's own comments (``;Z:``, ``;LAYER:n``, ``; layer n, Z =``,
``;LAYER_COUNT``) or from the slicing settings, read independently by the test.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from octoprint_printwatch.core.gcode import analyse, iter_moves, normalise_feature

GCODE_DIR = Path(__file__).resolve().parents[1] / "data" / "gcode"


def comment_values(path, pattern):
    regex = re.compile(pattern)
    values = []
    with open(path, encoding="latin-1") as handle:
        for line in handle:
            match = regex.match(line)
            if match:
                values.append(float(match.group(1)))
    return values


def z_after_cura_layer_comments(path):
    """Z in effect at the first extruding line after each ``;LAYER:n`` comment (Cura moves
    to the next layer's Z *before* writing the comment)."""
    zs, waiting, current_z = [], False, None
    with open(path, encoding="latin-1") as handle:
        for line in handle:
            if re.match(r";LAYER:-?\d", line):
                waiting = True
                continue
            code = line.split(";")[0]
            if not re.match(r"G[01]\s", code):
                continue
            z_word = re.search(r"Z([0-9.]+)", code)
            if z_word:
                current_z = float(z_word.group(1))
            if waiting and re.search(r"X.*E[0-9.]", code):
                zs.append(current_z)
                waiting = False
    return zs


def assert_tiles_file(info):
    """Layers are contiguous, ordered line ranges with positive heights summing to the top."""
    for before, after in zip(info.layers, info.layers[1:]):
        assert after.first_line == before.last_line + 1
        assert after.index == before.index + 1
    for layer in info.layers:
        assert layer.first_line <= layer.last_line <= info.total_lines
        assert layer.height > 0
        assert layer.extrudes
    if all(a.z < b.z for a, b in zip(info.layers, info.layers[1:])):
        assert math.isclose(sum(l.height for l in info.layers), info.layers[-1].z, abs_tol=1e-9)


PRUSA_FILES = [
    "prusa25_cylinder.gcode",
    "prusa25_pyramid_fwretract.gcode",
    "prusa25_sun_gear_zhop_relative_e.gcode",
    "prusa25_twisted_vase_spiral.gcode",
    "prusa25_two_cubes.gcode",
    "prusa25_two_cubes_sequential.gcode",
    "third_party/ideamaker_34_calibration_box.gcode",
]


@pytest.mark.parametrize("name", PRUSA_FILES)
def test_layer_z_values_match_the_slicers_z_comments(name):
    path = GCODE_DIR / name
    expected = comment_values(path, r";Z:([0-9.]+)")
    info = analyse(path)
    assert len(info.layers) == len(expected)
    assert [round(l.z, 4) for l in info.layers] == pytest.approx(expected, abs=1e-4)
    assert_tiles_file(info)
    if name.startswith("prusa"):
        assert sum(1 for line in open(path) if line.startswith(";LAYER_CHANGE")) == len(info.layers)


@pytest.mark.parametrize("name,header_count", [
    ("cura413_ender3_sun_gear.gcode", 200),
    ("cura413_ender3_t55_gear_relative_e_zhop.gcode", 120),
    ("third_party/cura_360_ender3_base.gcode", 31),
    # These two headers announce one layer more than the file holds (LAYER:0..n-2):
    ("cura413_ender3_pyramid_adaptive_layers.gcode", 111),
    ("third_party/cura_lulzbot_369_cube.gcode", 16),
    ("third_party/slic3r_prusa_1372_spool.gcode", None),
])
def test_cura_style_layer_comments_give_count_and_z(name, header_count):
    path = GCODE_DIR / name
    info = analyse(path)
    expected_z = z_after_cura_layer_comments(path)
    layer_comments = sum(1 for line in open(path, encoding="latin-1") if re.match(r";LAYER:-?\d", line))
    assert len(info.layers) == layer_comments == len(expected_z)
    assert [l.z for l in info.layers] == pytest.approx(expected_z, abs=1e-6)
    assert info.slicer_layer_count == header_count
    if header_count is not None and header_count != layer_comments:
        assert header_count == layer_comments + 1  # the documented off-by-one of those files
    assert_tiles_file(info)


def test_cura_purge_line_before_layer_0_is_not_a_layer():
    path = GCODE_DIR / "cura413_ender3_sun_gear.gcode"
    info = analyse(path)
    first_layer_comment = next(i for i, line in enumerate(open(path), 1) if line.startswith(";LAYER:0"))
    assert info.layers[0].first_line == first_layer_comment
    assert info.layers[0].z == pytest.approx(0.3)  # Ender-3 definition's initial layer
    # the start script's purge line (X0.1 and X0.4, Y20..200) extrudes before ;LAYER:0
    purge = [m for m in iter_moves(path) if m.extruding and m.line_no < first_layer_comment]
    assert len(purge) == 2 and all(m.end[0] < 1 and m.length_xy > 150 for m in purge)
    assert len(info.layers) == 200


def test_layer_heights_follow_the_moves_not_the_header():
    # Cura's header says ";Layer height: 0.2" but the adaptive-layers pyramid was
    # sliced at 0.3 mm (constant slope): the table must follow the real Z.
    path = GCODE_DIR / "cura413_ender3_pyramid_adaptive_layers.gcode"
    assert ";Layer height: 0.2" in open(path).read()
    info = analyse(path)
    assert {round(l.height, 4) for l in info.layers} == {0.3}
    assert info.layers[-1].z == pytest.approx(33.0)


def test_simplify3d_layer_comments():
    path = GCODE_DIR / "third_party" / "simplify3d_400_batman.gcode"
    expected = comment_values(path, r"; layer \d+, Z\s*=\s*([0-9.]+)")
    info = analyse(path)
    assert [l.z for l in info.layers] == pytest.approx(expected)


def test_no_comments_at_all_layers_from_extrusion_z():
    # Slic3r 1.3 with no layer comments: a 30 mm cube at 0.2 mm layers.
    path = GCODE_DIR / "slic3r13_cube.gcode"
    assert not any(l.startswith((";LAYER", ";Z:")) for l in open(path))
    info = analyse(path)
    assert info.layer_markers == 0
    assert len(info.layers) == 150
    assert [l.z for l in info.layers] == pytest.approx([0.2 * i for i in range(1, 151)])
    assert info.filament_diameter == 3.0 and info.filament_diameter_source == "comment"
    assert_tiles_file(info)


def test_two_extruders_without_comments():
    path = GCODE_DIR / "third_party" / "simplify3d_302_dual_extruder.gcode"
    info = analyse(path)
    assert info.tools == [0, 1]
    # layerHeight 0.3 with a 90 % first layer, as in the file's settings header
    assert [l.z for l in info.layers] == pytest.approx([0.27 + 0.3 * i for i in range(len(info.layers))])
    assert info.layers[-1].z == pytest.approx(20.07)
    # the start script heats and selects both nozzles, then prints with T0
    assert {m.tool for m in iter_moves(path) if m.extruding} == {0}


def test_spiral_vase_one_layer_per_revolution():
    path = GCODE_DIR / "prusa25_twisted_vase_spiral.gcode"
    info = analyse(path)
    assert info.spiral_vase
    changes = sum(1 for line in open(path) if line.startswith(";LAYER_CHANGE"))
    assert len(info.layers) == changes == 190
    # Z rises inside the spiral layers; each layer's z is the top of its revolution
    spiral_layer = info.layers[100]
    zs = [m.end[2] for m in iter_moves(path)
          if m.extruding and spiral_layer.first_line <= m.line_no <= spiral_layer.last_line]
    assert max(zs) == pytest.approx(spiral_layer.z)
    assert max(zs) - min(zs) > 0.15  # continuous rise of about one layer height
    assert spiral_layer.height == pytest.approx(0.2, abs=1e-3)


def test_spiral_vase_without_comments_uses_the_layer_height(tmp_path):
    src = GCODE_DIR / "prusa25_twisted_vase_spiral.gcode"
    stripped = tmp_path / "vase_no_comments.gcode"
    with open(src) as fin, open(stripped, "w") as fout:
        for line in fin:
            if not line.startswith(";"):
                fout.write(line)
    with_comments, without = analyse(src), analyse(stripped)
    assert without.layer_markers == 0
    assert abs(len(without.layers) - len(with_comments.layers)) <= 2
    tops = [l.z for l in without.layers]
    assert tops[-1] == pytest.approx(with_comments.layers[-1].z, abs=0.01)
    assert all(0.1 < l.height < 0.31 for l in without.layers)


def test_z_hop_travel_is_not_a_layer():
    # PrusaSlicer lifts on every retraction; this Cura file lifts only twice (by 1 mm).
    for name, count, hops in (("prusa25_sun_gear_zhop_relative_e.gcode", 200, 100),
                              ("cura413_ender3_t55_gear_relative_e_zhop.gcode", 120, 1)):
        path = GCODE_DIR / name
        info = analyse(path)
        # The file really hops: travel goes down again after each lift.
        drops = [m for m in iter_moves(path) if m.e == 0 and m.end[2] < m.start[2] - 1e-6
                 and m.line_no > info.layers[0].first_line]
        assert len(drops) >= hops, name
        assert len(info.layers) == count
        assert all(l.height == pytest.approx(0.2) for l in info.layers[1:]), name


def filament_used_mm(path):
    text = open(path, encoding="latin-1").read()
    match = re.search(r"; filament used \[mm\] = ([0-9.]+)", text) or re.search(
        r"; filament used = ([0-9.]+)mm", text)
    if match:
        return float(match.group(1))
    match = re.search(r";Filament used: ([0-9.]+)m", text)
    return float(match.group(1)) * 1000


@pytest.mark.parametrize("name", [
    "prusa25_cylinder.gcode",  # M82 absolute E with G92 resets
    "prusa25_sun_gear_zhop_relative_e.gcode",  # M83 relative E
    "prusa25_pyramid_fwretract.gcode",  # G10/G11
    "slic3r13_cube.gcode",
    "third_party/cura_360_ender3_base.gcode",
    "third_party/cura_lulzbot_369_cube.gcode",
    "third_party/slic3r_prusa_1372_spool.gcode",
])
def test_extruded_filament_matches_the_slicers_total(name):
    path = GCODE_DIR / name
    info = analyse(path)
    first, last = info.layers[0].first_line, info.layers[-1].last_line
    net = sum(m.e for m in iter_moves(path) if first <= m.line_no <= last)
    assert net == pytest.approx(filament_used_mm(path), rel=0.01)


def test_width_and_feature_from_slicer_comments():
    moves = [m for m in iter_moves(GCODE_DIR / "prusa25_two_cubes.gcode") if m.extruding]
    features = {m.feature for m in moves}
    assert {"external perimeter", "perimeter", "skirt"} <= features
    assert all(m.width is not None and 0.3 < m.width < 0.8 for m in moves)
    cura = {m.feature for m in iter_moves(GCODE_DIR / "cura413_ender3_sun_gear.gcode") if m.extruding}
    assert {"external perimeter", "perimeter", "infill", "skirt"} <= cura
    assert normalise_feature("WALL-OUTER") == normalise_feature("External perimeter") == "external perimeter"
    # Simplify3D writes "; feature ..." and the width in "; tool H<height> W<width>"
    s3d = [m for m in iter_moves(["G92 E0", "; feature outer perimeter", "; tool H0.200 W0.480",
                                  "G1 X1 Y1 E1", "; feature solid layer", "G1 X2 Y1 E2"])]
    assert [(m.feature, m.width) for m in s3d] == [("external perimeter", 0.48), ("solid infill", 0.48)]


def test_hints_from_slicer_comments():
    info = analyse(GCODE_DIR / "prusa25_cylinder.gcode")
    assert info.bed_size == (200.0, 200.0) and info.max_z == 200.0
    assert info.nominal_layer_height == pytest.approx(0.2)
    assert info.slicer.startswith("PrusaSlicer 2.5.0")
    assert info.extrusion_mode == "absolute"
    assert analyse(GCODE_DIR / "prusa25_sun_gear_zhop_relative_e.gcode").extrusion_mode == "relative"
    assert analyse(GCODE_DIR / "prusa25_pyramid_fwretract.gcode").firmware_retraction
    box = analyse(GCODE_DIR / "third_party" / "ideamaker_34_calibration_box.gcode")
    assert box.bed_size == (225.0, 225.0) and box.max_z == 240.0


def test_arcs_become_chords_on_the_circle(tmp_path):
    arcs = tmp_path / "arcs.gcode"
    arcs.write_text("G21\nG90\nM83\nG92 E0\nG1 X120 Y100 Z0.2 F3000\n"
                    ";LAYER:0\n"
                    "G2 X120 Y100 I-20 J0 E6.2832 F1200\n"  # full circle, radius 20, centre (100, 100)
                    "G3 X100 Y120 R20 E1.5708\n"  # quarter, counter-clockwise, back on the same circle
                    "G1 X100 Y130 E0.5\n")
    moves = [m for m in iter_moves(arcs) if m.extruding]
    full = [m for m in moves if m.line_no == 7]
    quarter = [m for m in moves if m.line_no == 8]
    assert len(full) > 60 and len(quarter) > 15
    for m in full + quarter:
        assert math.hypot(m.end[0] - 100, m.end[1] - 100) == pytest.approx(20, abs=1e-9)
        # chords stay within the arc tolerance of the circle
        mid = ((m.start[0] + m.end[0]) / 2, (m.start[1] + m.end[1]) / 2)
        assert 20 - math.hypot(mid[0] - 100, mid[1] - 100) <= 0.0051
    assert sum(m.length_xy for m in full) == pytest.approx(2 * math.pi * 20, rel=1e-3)
    assert sum(m.e for m in full) == pytest.approx(6.2832)
    assert full[0].end[1] < 100  # G2 is clockwise: from (120, 100) it goes down first
    assert quarter[-1].end == pytest.approx((100, 120, 0.2))
    assert quarter[0].end[0] < 120 and quarter[0].end[1] > 100  # G3 counter-clockwise: up first
    assert analyse(arcs).layers[0].z == pytest.approx(0.2)


@pytest.mark.parametrize("name,diameter,line_width", [
    # CuraEngine run without the Ender-3 extruder definition keeps fdmprinter's 2.85 mm
    # material: only 2.85 gives the 0.4 mm nozzle's line width
    ("cura413_ender3_pyramid_adaptive_layers.gcode", 2.85, 0.4),
    ("third_party/cura_lulzbot_369_cube.gcode", 2.85, 0.5),  # TAZ 6: 2.85 mm filament, 0.5 mm nozzle
    ("third_party/cura_360_ender3_base.gcode", 1.75, 0.4),
])
def test_filament_diameter_estimated_when_no_comment_gives_it(name, diameter, line_width):
    path = GCODE_DIR / name
    info = analyse(path)
    assert info.filament_diameter_source == "default" and info.filament_diameter == 1.75
    assert info.filament_diameter_estimate == diameter
    area = math.pi * (diameter / 2) ** 2
    widths = sorted(m.e * area / (m.length_xy * info.nominal_layer_height)
                    for m in iter_moves(path) if m.extruding and m.feature == "external perimeter"
                    and m.length_xy > 1 and m.end[2] > 1)
    assert widths[len(widths) // 2] == pytest.approx(line_width, rel=0.2)


def test_sequential_printing_starts_the_layers_again():
    # Two 30 mm cubes printed one after the other: layers 1-150, then 151-300 from 0.2 mm again.
    info = analyse(GCODE_DIR / "prusa25_two_cubes_sequential.gcode")
    assert len(info.layers) == 300
    assert info.layers[149].z == pytest.approx(30.0) and info.layers[150].z == pytest.approx(0.2)
    assert info.layers[150].height == pytest.approx(0.2)  # the next object starts on the bed


def test_first_layer_comment_only_from_layer_2_keeps_layer_1(tmp_path):
    # A slicer whose first layer comment comes at the second layer: what came before
    # is a real layer (0.2 mm below), not a purge line, and stays in the table.
    src = GCODE_DIR / "slic3r13_cube.gcode"
    text = src.read_text().replace("G1 Z0.400 F7800.000", ";LAYER:1\nG1 Z0.400 F7800.000", 1)
    marked = tmp_path / "marked.gcode"
    marked.write_text(text)
    info = analyse(marked)
    assert info.layer_markers == 1
    assert [l.z for l in info.layers] == pytest.approx([0.2 * i for i in range(1, 151)])
    assert info.layers[1].first_line == text.splitlines().index(";LAYER:1") + 1
