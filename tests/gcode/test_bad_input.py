"""Bad input: a clear one-line error or a documented best effort; never a traceback or a partial file."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from octoprint_printwatch.cli import main
from octoprint_printwatch.core.errors import GcodeError
from octoprint_printwatch.core.gcode import analyse
from octoprint_printwatch.core.inject import inject_checks, strip_injected

GCODE_DIR = Path(__file__).resolve().parents[1] / "data" / "gcode"
SMALL = GCODE_DIR / "prusa25_pyramid_fwretract.gcode"


def one_line_error(capsys, argv) -> str:
    """Run the CLI; it must exit 2 with exactly one line on stderr."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("content,message", [
    (b"", "file is empty"),
    (b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR\x00\x00\x02\x80", "binary data"),
    (bytes(range(256)) * 64, "binary data"),
    (b"solid cube\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 1\n  endloop\n endfacet\nendsolid\n",
     "no extruding moves"),
    (b"G28\nG1 Z5 F3000\nG1 X10 Y10\nM84\n", "no extruding moves"),
    (b"G1 X1 E1\n" + b";" + b"x" * (2 << 20), "longer than"),
])
def test_unusable_files_give_one_line_errors(tmp_path, capsys, content, message):
    bad = tmp_path / "bad.gcode"
    bad.write_bytes(content)
    with pytest.raises(GcodeError, match=message):
        analyse(bad)
    err = one_line_error(capsys, ["layers", str(bad)])
    assert message in err and str(bad) in err
    out = tmp_path / "out.gcode"
    one_line_error(capsys, ["inject", str(bad), "-o", str(out)])
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["bad.gcode"]


def test_missing_file_and_folder(tmp_path, capsys):
    assert "no such file" in one_line_error(capsys, ["layers", str(tmp_path / "nope.gcode")])
    assert "directory" in one_line_error(capsys, ["layers", str(tmp_path)])


def test_truncated_mid_line_is_a_best_effort_with_a_warning(tmp_path):
    data = SMALL.read_bytes()
    cut = data[: len(data) // 2]
    cut = cut[: cut.rindex(b"\n") + 12]  # stop 11 bytes into a line
    assert not cut.endswith(b"\n")
    truncated = tmp_path / "truncated.gcode"
    truncated.write_bytes(cut)
    info = analyse(truncated)
    full = analyse(SMALL)
    assert 10 < len(info.layers) < len(full.layers)
    assert [l.z for l in info.layers[:-1]] == [l.z for l in full.layers[: len(info.layers) - 1]]
    assert any("no line end" in w for w in info.warnings)
    out = tmp_path / "out.gcode"
    result = inject_checks(truncated, out, every=10)
    assert result.checks[-1].layer == len(info.layers)
    assert out.read_bytes().endswith(cut[cut.rindex(b"\n"):])  # the partial line is kept, unchanged
    assert b"".join(strip_injected(out)) == cut


def test_non_ascii_comments_and_long_lines_pass_through_exactly(tmp_path):
    lines = SMALL.read_bytes().split(b"\n")
    lines.insert(5, "; température ✓ 温度".encode("utf-8"))
    lines.insert(6, b"; latin-1 \xe9\xe8 \xff")
    lines.insert(7, b"M117 " + b"long message " * 8000)  # a 100 kB command line
    lines.insert(8, b";" + b"c" * 100_000)  # and a 100 kB comment
    odd = tmp_path / "odd.gcode"
    odd.write_bytes(b"\n".join(lines))
    assert [l.z for l in analyse(odd).layers] == [l.z for l in analyse(SMALL).layers]
    out = tmp_path / "out.gcode"
    inject_checks(odd, out, every=25)
    assert b"".join(strip_injected(out)) == odd.read_bytes()


def test_unexpanded_placeholder_is_a_warning_not_an_error():
    # Real CuraEngine output: its end script kept "G1 X0 Y{machine_depth}".
    info = analyse(GCODE_DIR / "cura413_ender3_sun_gear.gcode")
    assert any("Y{MACHINE_DEPTH}" in w.upper() and "not a number" in w for w in info.warnings)
    assert len(info.layers) == 200


def test_cli_as_a_separate_process(tmp_path):
    out = tmp_path / "out.gcode"
    done = subprocess.run([sys.executable, "-m", "octoprint_printwatch", "inject", str(SMALL), "-o", str(out),
                           "--every", "30", "--bed", "200,200", "--max-z", "200"],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert "4 checks after layers 30, 60, 90, 110 of 110" in done.stdout
    bad = subprocess.run([sys.executable, "-m", "octoprint_printwatch", "inject", str(SMALL), "-o", str(out),
                          "--park", "ten,20"], capture_output=True, text=True, timeout=120)
    assert bad.returncode == 2 and "--park" in bad.stderr and "Traceback" not in bad.stderr
