"""``benchmarks/bench_perturb.py``: recordings replayed through a plausible webcam difference (noise, JPEG,
gamma, ...) are copies, the originals untouched, and their outcomes are scored as bench_detection scores them."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
RECORDING = ROOT / "tests" / "data" / "recordings" / "cube_black_pei_shadow"


@pytest.fixture(scope="module")
def bench(load_benchmark):
    yield from load_benchmark("bench_perturb")


def test_a_normal_print_paused_and_a_failure_caught_late_are_scored(bench):
    normal = bench.outcome("normal", [False] * 4, ["ok", "fail", "ok", "ok"])
    assert normal["normal_paused"] and normal["fa"] == 1
    late = bench.outcome("runout", [False, False, True, True, True], ["ok", "ok", "ok", "ok", "fail"])
    assert late["within"] is False and not late["before_onset"]
    caught = bench.outcome("runout", [False, False, True, True], ["ok", "ok", "unknown", "fail"])
    assert caught["within"] is True
    early = bench.outcome("detach", [False, True, True], ["fail", "fail", "fail"])
    assert early["before_onset"] and early["within"] is False


def test_perturbed_copies_are_replayed_and_the_original_is_kept(bench, tmp_path, capsys):
    recordings = tmp_path / "set"
    shutil.copytree(RECORDING, recordings / RECORDING.name)
    checks = json.loads((RECORDING / "session.json").read_text())["checks"]
    (recordings / RECORDING.name / "truth.json").write_text(
        json.dumps({"kind": "normal", "checks": [{"failure_started": False} for _ in checks]}))
    before = {p: p.read_bytes() for p in (recordings / RECORDING.name).rglob("*") if p.is_file()}

    assert bench.main([str(recordings), "--scratch", str(tmp_path / "scratch"), "--perturb", "noise4",
                       "--json", str(tmp_path / "out.json")]) == 0

    assert {p: p.read_bytes() for p in before} == before          # the recording itself is untouched
    frame = checks[0]["frames"][next(iter(checks[0]["frames"]))]
    original = bench.read_image(RECORDING / frame).astype(int)
    noisy = bench.read_image(tmp_path / "scratch" / "copies" / "set" / "noise4" / RECORDING.name / frame).astype(int)
    assert noisy.shape == original.shape and 2.0 < np.abs(noisy - original).mean() < 6.0
    report = json.loads((tmp_path / "out.json").read_text())["set"]
    assert report["none"]["normal"] == report["noise4"]["normal"] == 1
    assert report["none"]["pre_checks"] == len(checks)
    assert "noise4: normal paused" in capsys.readouterr().out


def test_an_unknown_perturbation_is_refused_with_the_known_ones(bench, tmp_path, capsys):
    with pytest.raises(SystemExit):
        bench.main([str(tmp_path), "--perturb", "fog"])
    assert "noise4" in capsys.readouterr().err


@pytest.mark.parametrize("name, sigma", [("noise4", 4.0), ("noise8", 8.0)])
def test_each_noise_perturbation_adds_the_sensor_noise_it_is_named_after(bench, name, sigma):
    perturb, on_background = bench.PERTURBATIONS[name]
    grey = np.full((240, 320, 3), 128, np.uint8)
    noisy = perturb(grey, np.random.default_rng(0)).astype(float)
    assert on_background
    assert abs(noisy.mean() - 128.0) < 0.2 and 0.95 * sigma < noisy.std() < 1.05 * sigma
