"""The two G-code subcommands, run in-process through the real ``printwatch`` entry point."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from octoprint_printwatch.cli import main

GCODE_DIR = Path(__file__).resolve().parents[1] / "data" / "gcode"
CUBE = GCODE_DIR / "slic3r13_cube.gcode"  # 150 layers of 0.2 mm, no layer comments


def test_layers_prints_one_row_per_layer(capsys):
    assert main(["layers", str(CUBE)]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"# {CUBE}: 150 layers, slicer Slic3r 1.3.0, filament 3 mm (comment)")
    rows = [line.split() for line in out if line[:1] == " " or line[:1].isdigit()]
    rows = [r for r in rows if r[0].isdigit()]
    assert len(rows) == 150
    assert rows[0][:3] == ["1", "0.200", "0.200"] and rows[-1][:3] == ["150", "30.000", "0.200"]
    assert all(r[5] == "yes" for r in rows)
    assert [int(r[3]) for r in rows[1:]] == [int(r[4]) + 1 for r in rows[:-1]]  # contiguous lines


def test_layers_json(capsys):
    assert main(["layers", "--json", str(GCODE_DIR / "prusa25_twisted_vase_spiral.gcode")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert len(data["layers"]) == 190 and data["spiral_vase"] is True
    assert data["layers"][-1]["z"] == pytest.approx(38.0)


def test_inject_and_strip_round_trip(tmp_path, capsys):
    out, back = tmp_path / "out.gcode", tmp_path / "back.gcode"
    assert main(["inject", str(CUBE), "-o", str(out), "--every", "50", "--lift", "5",
                 "--park", "190,190", "--bed", "200,200", "--max-z", "180", "--background"]) == 0
    printed = capsys.readouterr().out
    assert "3 checks after layers 50, 100, 150 of 150; park 190,190, max Z 180 mm" in printed
    assert "background frame at line" in printed
    text = out.read_text()
    assert text.count("@PRINTWATCH_CHECK") == 3 and text.count("@PRINTWATCH_BACKGROUND") == 1
    assert "G1 X190 Y190 F3000" in text and "G1 Z15 F300" in text  # layer 50 at 10 mm + 5 mm lift
    assert main(["inject", str(out), "-o", str(back), "--strip"]) == 0
    assert back.read_bytes() == CUBE.read_bytes()


def test_heights_option(tmp_path, capsys):
    out = tmp_path / "out.gcode"
    assert main(["inject", str(CUBE), "-o", str(out), "--heights", "5,12.1"]) == 0
    assert "checks after layers 25, 61, 150 of 150" in capsys.readouterr().out


@pytest.mark.parametrize("command", ["layers", "inject"])
def test_help(command, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main([command, "--help"])
    assert exit_info.value.code == 0
    assert "usage: printwatch " + command in capsys.readouterr().out
