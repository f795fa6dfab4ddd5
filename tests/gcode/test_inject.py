"""Check-block injection, proved with the independent simulator in gcode_machine.py.

For every corpus file: the original and the injected file print exactly the same
extruding segments; every injected move stays inside the build volume; each
block leaves position, E, modes and feed rate as it found them; markers match
the layer table; stripping the blocks gives back the original byte for byte.
"""
from __future__ import annotations

import re
from pathlib import Path

import pytest

import gcode_machine
from octoprint_printwatch.core.errors import GcodeError
from octoprint_printwatch.core.gcode import analyse
from octoprint_printwatch.core.inject import inject_checks, strip_file, strip_injected

GCODE_DIR = Path(__file__).resolve().parents[1] / "data" / "gcode"
MARKER = re.compile(r"@PRINTWATCH_CHECK layer=(\d+) z=([0-9.]+)$")


def assert_equivalent(original: Path, injected: Path, result, *, bed, max_z, every=None, heights=None):
    """The four properties of the issue, plus byte-exact removal."""
    info = analyse(original)
    before, after = gcode_machine.run(original), gcode_machine.run(injected)

    # (a) the same extruding segments, in the same order, with the same lengths
    assert before.blocks == [] and len(before.segments) > 100
    assert after.segments == before.segments
    assert gcode_machine.states_equal(after.final, before.final)

    # (b) every move inside a block stays in the build volume and extrudes nothing
    (x0, y0), (x1, y1) = bed
    for block in after.blocks:
        assert block.extruding_moves == 0
        for x, y, z in block.positions:
            assert x0 - 1e-6 <= x <= x1 + 1e-6 and y0 - 1e-6 <= y <= y1 + 1e-6, (block.begin_line, x, y)
            assert 0 <= z <= max_z + 1e-6, (block.begin_line, z)
        # M400 before every positioning-mode switch, and before the marker
        for index, code in enumerate(block.lines):
            if code in ("G90", "G91"):
                assert block.lines[index - 1] == "M400", (block.begin_line, block.lines)
        assert len(block.markers) == 1

    # (c) each block restores position, E, modes and feed rate exactly
    for block in after.blocks:
        assert gcode_machine.states_equal(block.before, block.after), (block.begin_line, block.before, block.after)

    # (d) one marker per planned layer, with the layer table's z
    checks = [b for b in after.blocks if b.kind == "check"]
    found = [MARKER.match(b.markers[0]) for b in checks]
    assert all(found)
    layers = [int(m.group(1)) for m in found]
    count = len(info.layers)
    if heights is None:
        assert layers == sorted(set(range(every, count + 1, every)) | {count})
    for match in found:
        assert float(match.group(2)) == pytest.approx(info.layers[int(match.group(1)) - 1].z, abs=1e-4)
    assert [c.layer for c in result.checks] == layers
    lines = injected.read_text(encoding="latin-1").splitlines()
    for check in result.checks:
        assert lines[check.line - 1].startswith(f"@PRINTWATCH_CHECK layer={check.layer} ")

    # each check block sits between that layer's last extrusion and the next layer's first
    markers_at = {c.layer: c.source_line for c in result.checks}
    for layer in info.layers:
        if layer.index in markers_at:
            assert markers_at[layer.index] == layer.last_line

    # byte-exact removal
    assert b"".join(strip_injected(injected)) == original.read_bytes()


def test_equivalence_on_every_corpus_file(corpus_file, tmp_path):
    out = tmp_path / "injected.gcode"
    result = inject_checks(corpus_file, out, every=7, lift=10, bed=(220, 220), max_z=250, background=True)
    assert len(result.checks) >= 2
    assert result.background_line is not None
    assert_equivalent(corpus_file, out, result, bed=((0, 0), (220, 220)), max_z=250, every=7)


def test_defaults_from_the_file_stay_inside_what_the_file_visits(tmp_path):
    # No bed or max Z given and none in the comments: stay within the file's own range.
    src = GCODE_DIR / "third_party" / "simplify3d_400_batman.gcode"
    out = tmp_path / "out.gcode"
    result = inject_checks(src, out, every=4)
    info = analyse(src)
    (lo, hi) = info.move_bounds
    assert any("bed size not given" in w for w in result.warnings)
    assert any("max Z not given" in w for w in result.warnings)
    assert result.max_z == pytest.approx(hi[2])
    assert_equivalent(src, out, result, bed=((lo[0], lo[1]), (hi[0], hi[1])), max_z=hi[2], every=4)


def test_background_block_comes_before_the_first_extrusion_and_extrudes_nothing(tmp_path):
    src = GCODE_DIR / "prusa25_two_cubes.gcode"
    out = tmp_path / "out.gcode"
    result = inject_checks(src, out, every=50, background=True)
    trace = gcode_machine.run(out)
    background = [b for b in trace.blocks if b.kind == "background"]
    assert len(background) == 1 and background[0].markers == ["@PRINTWATCH_BACKGROUND"]
    first_segment_line = None
    for number, line in enumerate(out.read_text().splitlines(), 1):
        if re.match(r"G1 X[0-9.]+ Y[0-9.]+ E[0-9.]+", line):
            first_segment_line = number
            break
    assert result.background_line < first_segment_line
    assert background[0].positions[-1][2] == pytest.approx(0.2)  # back down on the first layer


def test_heights_choose_the_first_layer_reaching_each_height(tmp_path):
    src = GCODE_DIR / "cura413_ender3_pyramid_adaptive_layers.gcode"  # layers at 0.3, 0.6, 0.9 ...
    out = tmp_path / "out.gcode"
    result = inject_checks(src, out, heights=[1.0, 6.0, 99.0], bed=(235, 235), max_z=250)
    assert [(c.layer, round(c.z, 3)) for c in result.checks] == [(4, 1.2), (20, 6.0), (110, 33.0)]
    assert any("above the top of the print" in w for w in result.warnings)
    assert_equivalent(src, out, result, bed=((0, 0), (235, 235)), max_z=250, heights=[1.0, 6.0])


def test_lift_is_clamped_to_max_z_and_said_so(tmp_path):
    src = GCODE_DIR / "prusa25_pyramid_fwretract.gcode"  # 33.05 mm tall, layer 40 at 12.05 mm
    out = tmp_path / "out.gcode"
    result = inject_checks(src, out, every=40, lift=30, max_z=45, bed=(200, 200))
    trace = gcode_machine.run(out)
    tops = [max(z for _, _, z in b.positions) for b in trace.blocks]
    assert tops[0] == pytest.approx(12.05 + 30)  # the full lift fits
    assert tops[1:] == pytest.approx([45, 45])  # layers 80 and 110: clamped
    assert any("lift clamped at max Z 45" in w for w in result.warnings)
    assert_equivalent(src, out, result, bed=((0, 0), (200, 200)), max_z=45, every=40)


def test_park_outside_the_bed_is_clamped_and_said_so(tmp_path):
    src = GCODE_DIR / "prusa25_pyramid_fwretract.gcode"
    out = tmp_path / "out.gcode"
    result = inject_checks(src, out, every=50, park=(-50, 500), bed=(200, 180), max_z=200)
    assert result.park == (10.0, 170.0)
    assert any("outside the bed" in w for w in result.warnings)
    trace = gcode_machine.run(out)
    assert all((10.0, 170.0) in [p[:2] for p in b.positions] for b in trace.blocks)
    assert_equivalent(src, out, result, bed=((0, 0), (200, 180)), max_z=200, every=50)


def test_firmware_retraction_file_gets_g10_g11(tmp_path):
    src = GCODE_DIR / "prusa25_pyramid_fwretract.gcode"
    out = tmp_path / "out.gcode"
    inject_checks(src, out, every=10, bed=(200, 200), max_z=200)
    blocks = [b for b in gcode_machine.run(out).blocks]
    assert blocks
    for block in blocks:
        assert not any(re.match(r"G1 .*E", code) for code in block.lines)
        # either the file was already retracted there, or the block retracts with G10 and undoes it
        assert ("G10" in block.lines) == ("G11" in block.lines)
    assert any("G10" in b.lines for b in blocks)


def test_no_double_retraction_when_the_slicer_already_retracted(tmp_path):
    # Simplify3D retracts (G1 E-3) before its layer-change comment.
    src = GCODE_DIR / "third_party" / "simplify3d_302_dual_extruder.gcode"
    out = tmp_path / "out.gcode"
    inject_checks(src, out, every=10, bed=(220, 220), max_z=200)
    for block in gcode_machine.run(out).blocks:
        assert not any("E" in code for code in block.lines), block.lines


# ------------------------------------------------------------------ transformed real files

def transform_moves(src: Path, dst: Path, rewrite, header: str = "") -> None:
    """Write src to dst with every G0/G1 line passed through rewrite(words, state)."""
    state = {"X": 0.0, "Y": 0.0, "Z": 0.0}
    with open(src, encoding="latin-1") as fin, open(dst, "w", encoding="latin-1") as fout:
        fout.write(header)
        for line in fin:
            code, _, comment = line.rstrip("\n").partition(";")
            words = code.split()
            if words and words[0] in ("G0", "G1"):
                line = rewrite(words, state) + (";" + comment if comment else "") + "\n"
            fout.write(line)


def test_relative_positioning_file(tmp_path):
    """The whole print in G91 (relative XYZ), E absolute via M82 after it: blocks switch to
    G90 and back with M400 first, and restore the E mode G91 would reset."""
    src = GCODE_DIR / "slic3r13_cube.gcode"
    rel = tmp_path / "relative.gcode"

    def to_relative(words, state):
        out = [words[0]]
        for word in words[1:]:
            axis = word[0]
            if axis in "XYZ":
                value = float(word[1:])
                out.append(f"{axis}{value - state[axis]:.3f}")
                state[axis] = round(value, 3)
            else:
                out.append(word)
        return " ".join(out)

    text_src = tmp_path / "src.gcode"
    # an absolute move after G28 makes the position known (the firmware's home could be
    # anywhere); the start script's G90 becomes G91 and its M82 follows it
    text_src.write_text(src.read_text().replace("G28 ; home all axes", "G28\nG1 X0 Y0 Z0", 1)
                        .replace("G90 ; use absolute coordinates", "G91", 1))
    transform_moves(text_src, rel, to_relative)
    info = analyse(rel)
    assert info.positioning == "mixed"
    assert [round(l.z, 3) for l in info.layers] == [round(l.z, 3) for l in analyse(src).layers]
    out = tmp_path / "out.gcode"
    result = inject_checks(rel, out, every=25, bed=(200, 200), max_z=200)
    blocks = gcode_machine.run(out).blocks
    assert all("G91" in b.lines and "G90" in b.lines and "M82" in b.lines for b in blocks)
    assert_equivalent(rel, out, result, bed=((0, 0), (200, 200)), max_z=200, every=25)


def test_inch_file_is_converted_and_blocks_are_written_in_inches(tmp_path):
    src = GCODE_DIR / "slic3r13_cube.gcode"
    inches = tmp_path / "inches.gcode"

    def to_inches(words, state):
        return " ".join([words[0]] + [
            f"{w[0]}{float(w[1:]) / 25.4:.7f}" if w[0] in "XYZEF" and len(w) > 1 else w for w in words[1:]])

    text_src = tmp_path / "src.gcode"
    text_src.write_text(src.read_text().replace("G21 ; set units to millimeters", "G20", 1))
    transform_moves(text_src, inches, to_inches)
    info = analyse(inches)
    assert info.units == "inch"
    assert [l.z for l in info.layers] == pytest.approx([l.z for l in analyse(src).layers], abs=1e-5)
    out = tmp_path / "out.gcode"
    result = inject_checks(inches, out, every=30, bed=(200, 200), max_z=100)
    trace = gcode_machine.run(out)
    for block in trace.blocks:
        assert max(z for _, _, z in block.positions) <= 100 + 1e-6
        park_line = next(code for code in block.lines if code.startswith("G1 X"))
        assert park_line.startswith("G1 X0.3937 Y0.3937")  # 10 mm in inches
    assert_equivalent(inches, out, result, bed=((0, 0), (200, 200)), max_z=100, every=30)


def test_crlf_file_keeps_crlf_and_strips_exactly(tmp_path):
    src = GCODE_DIR / "prusa25_pyramid_fwretract.gcode"
    crlf = tmp_path / "crlf.gcode"
    crlf.write_bytes(src.read_bytes().replace(b"\n", b"\r\n"))
    assert [l.z for l in analyse(crlf).layers] == [l.z for l in analyse(src).layers]
    out = tmp_path / "out.gcode"
    result = inject_checks(crlf, out, every=20, bed=(200, 200), max_z=200)
    data = out.read_bytes()
    assert data.count(b"\n") == data.count(b"\r\n")  # no bare LF was added
    assert_equivalent(crlf, out, result, bed=((0, 0), (200, 200)), max_z=200, every=20)


def test_arcs_are_moves_and_injection_keeps_them(tmp_path):
    arcs = tmp_path / "arcs.gcode"
    lines = ["G21", "G90", "M82", "G28", "G92 E0", "G1 Z0.2 F600", "G1 X80 Y100 F3000"]
    e = 0.0
    for layer in range(1, 16):
        z = round(0.2 * layer, 3)
        lines += [f";LAYER:{layer - 1}", f"G1 Z{z} F600", "G1 X80 Y100 F3000"]
        e += 2.0
        lines.append(f"G2 X120 Y100 I20 J0 E{e:.4f} F1200")  # half circle, clockwise
        e += 2.0
        lines.append(f"G3 X80 Y100 R20 E{e:.4f}")  # and back, counter-clockwise
        lines.append(f"G1 X80 Y100 E{e:.4f}")
        lines.append(f"G1 E{e - 1:.4f}")
        lines.append(f"G1 E{e:.4f}")
    arcs.write_text("\n".join(lines) + "\n")
    info = analyse(arcs)
    assert len(info.layers) == 15
    out = tmp_path / "out.gcode"
    result = inject_checks(arcs, out, every=5, bed=(200, 200), max_z=100)
    assert_equivalent_arcs = gcode_machine.run(out)
    original = gcode_machine.run(arcs)
    assert [s for s in assert_equivalent_arcs.segments] == original.segments
    assert len(result.checks) == 3
    for block in assert_equivalent_arcs.blocks:
        assert gcode_machine.states_equal(block.before, block.after)


def test_file_without_e_reset_does_not_retract(tmp_path):
    """Absolute E but no G92 E anywhere: the E origin is the firmware's, so the block leaves E alone."""
    src = GCODE_DIR / "slic3r13_cube.gcode"
    no_reset = tmp_path / "no_reset.gcode"
    no_reset.write_text("".join(line for line in open(src) if not line.startswith("G92")))
    out = tmp_path / "out.gcode"
    result = inject_checks(no_reset, out, every=50, bed=(200, 200), max_z=200)
    assert any("never sets the E position" in w for w in result.warnings)
    for block in gcode_machine.run(out).blocks:
        assert not any("E" in code for code in block.lines)
    assert_equivalent(no_reset, out, result, bed=((0, 0), (200, 200)), max_z=200, every=50)


# ------------------------------------------------------------------ files and errors

def test_already_injected_file_is_refused_and_strip_restores(tmp_path):
    src = GCODE_DIR / "prusa25_two_cubes.gcode"
    once = tmp_path / "once.gcode"
    inject_checks(src, once, every=30)
    twice = tmp_path / "twice.gcode"
    with pytest.raises(GcodeError, match="already contains PrintWatch blocks"):
        inject_checks(once, twice)
    assert not twice.exists()
    # the analysis of an injected file ignores the blocks
    assert analyse(once).layers[-1].z == analyse(src).layers[-1].z
    assert len(analyse(once).layers) == len(analyse(src).layers)
    restored = tmp_path / "restored.gcode"
    strip_file(once, restored)
    assert restored.read_bytes() == src.read_bytes()
    text = once.read_text()
    assert strip_injected(text) == src.read_text()  # the whole text in, the whole text out


def test_error_leaves_no_output_and_no_temporary_file(tmp_path):
    bad = tmp_path / "travel_only.gcode"
    bad.write_text("G28\nG1 X10 Y10 Z5 F3000\nG1 X20\n")
    out = tmp_path / "out.gcode"
    with pytest.raises(GcodeError, match="no extruding moves"):
        inject_checks(bad, out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["travel_only.gcode"]
    with pytest.raises(GcodeError, match="every must be"):
        inject_checks(GCODE_DIR / "slic3r13_cube.gcode", out, every=0)
    with pytest.raises(GcodeError, match="bed must be"):
        inject_checks(GCODE_DIR / "slic3r13_cube.gcode", out, bed=(200, -5))
    with pytest.raises(GcodeError, match="does not exist"):
        inject_checks(GCODE_DIR / "slic3r13_cube.gcode", tmp_path / "missing" / "out.gcode")
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["travel_only.gcode"]


def test_output_replaces_an_existing_file_only_when_complete(tmp_path):
    out = tmp_path / "out.gcode"
    out.write_text("previous content\n")
    with pytest.raises(GcodeError):
        inject_checks(tmp_path / "nope.gcode", out)
    assert out.read_text() == "previous content\n"
    inject_checks(GCODE_DIR / "slic3r13_cube.gcode", out, every=50)
    assert "@PRINTWATCH_CHECK layer=50 " in out.read_text()


def test_sequential_print_parks_above_the_finished_object(tmp_path):
    src = GCODE_DIR / "prusa25_two_cubes_sequential.gcode"
    out = tmp_path / "out.gcode"
    result = inject_checks(src, out, every=100, lift=5, bed=(200, 200), max_z=200)
    assert [c.layer for c in result.checks] == [100, 200, 300]
    blocks = gcode_machine.run(out).blocks
    # layer 200 is at 10 mm in the second cube: the head must clear the first, 30 mm tall
    assert max(z for _, _, z in blocks[1].positions) == pytest.approx(30 + 5)
    assert blocks[1].before.z == pytest.approx(10.0)
