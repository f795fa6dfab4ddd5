"""``benchmarks/outline_residual.py``: the shift a camera's outline was laid at, less where the true camera puts the
part; a calibrated outline reads near zero, one laid off the part reads its offset, and the summary counts those
over FAR_PX by filament, verdict and onset."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

K = [[500.0, 0.0, 320.0], [0.0, 500.0, 240.0], [0.0, 0.0, 1.0]]


@pytest.fixture(scope="module")
def residual(load_benchmark):
    yield from load_benchmark("outline_residual")


def _camera(tx: float) -> dict:
    # looking straight down the z axis from 300 mm: 1 mm of x at the part moves the image by 500/300 px
    return {"width": 640, "height": 480, "K": K, "dist": [0.0] * 5, "rvec": [0.0, 0.0, 0.0], "tvec": [tx, 0.0, 300.0]}


def _recording(folder: Path, filament: str, started: list[bool]) -> Path:
    folder.mkdir(parents=True)
    (folder / "session.json").write_text(json.dumps({"cameras": {"s0": _camera(0.0)}}))
    (folder / "truth.json").write_text(json.dumps({
        "part": {"centre": [0.0, 0.0]}, "look": {"filament": filament},
        "checks": [{"z": 0.0, "failure_started": s} for s in started],
        # the true camera sits 6 mm off the stated one along x: the part appears 10 px to the right
        "cameras_true": {"s0": {"tvec": [6.0, 0.0, 300.0]}}}))
    return folder


def _check(shift: list[int], passed: bool) -> dict:
    return {"z": 0.0, "shape": {"s0": {"shift_px": shift, "passed": passed, "usable": True,
                                       "missing_pct": 0.0 if passed else 12.0, "extra_pct": 0.0}}}


def test_a_calibrated_outline_reads_near_zero_and_one_laid_off_the_part_its_offset(residual, tmp_path):
    folder = _recording(tmp_path / "s1" / "000_normal", "like bed", [False, False])
    rows = residual.recording_rows(folder, [_check([10, 0], True), _check([10, 15], False)], "1")
    assert rows[0].truth == pytest.approx((10.0, 0.0), abs=1e-6)
    assert rows[0].residual_px == pytest.approx(0.0, abs=1e-6)
    assert rows[1].residual == pytest.approx((0.0, 15.0), abs=1e-6)
    assert rows[1].like_bed and not rows[1].passed


def test_the_summary_counts_outlines_off_the_part_by_filament_verdict_and_onset(residual, tmp_path, capsys):
    _recording(tmp_path / "s1" / "010_runout", "like bed", [False, False, True])
    _recording(tmp_path / "s1" / "011_runout", "black", [False, False, True])
    off = _check([10, 15], False)
    replay = [{"name": "010_runout", "checks": [_check([10, 0], True), off, off]},
              {"name": "011_runout", "checks": [_check([10, 1], True), _check([11, 0], True), _check([10, 0], False)]}]
    (tmp_path / "base_s1.json").write_text(json.dumps(replay))
    assert residual.main(["--root", str(tmp_path), "--seeds", "1", "--results", str(tmp_path), "--tag", "base"]) == 0
    out = capsys.readouterr().out
    assert "before onset like-bed pass 0/1 (0.0 %); fail 1/1 (100.0 %); all 1/2 (50.0 %)" in out
    assert "before onset others   pass 0/2 (0.0 %); fail 0/0; all 0/2 (0.0 %)" in out
    assert "after onset  like-bed pass 0/0; fail 1/1 (100.0 %)" in out
    assert "(+0.0, +15.0)" in out and "FAR" in out
