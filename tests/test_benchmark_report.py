"""``benchmarks/run_all.py``: one report from every benchmark script, whatever state each script is in."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture()
def run_all(monkeypatch, tmp_path):
    spec = importlib.util.spec_from_file_location("_run_all_under_test", ROOT / "benchmarks" / "run_all.py")
    module = importlib.util.module_from_spec(spec)
    monkeypatch.setitem(sys.modules, spec.name, module)
    spec.loader.exec_module(module)
    return module


def test_a_failing_or_missing_script_is_reported_as_not_run_and_the_others_still_run(run_all, monkeypatch, tmp_path):
    bench = tmp_path / "benchmarks"
    bench.mkdir()
    (bench / "bench_ok.py").write_text(
        "import sys\nprint('| figure | value |')\nprint('|---|---|')\nprint('| speed | 42 widgets/s |')\n")
    (bench / "bench_broken.py").write_text("import sys\nprint('half a table')\nsys.exit('boom: no data folder')\n")
    monkeypatch.setattr(run_all, "BENCH", bench)
    monkeypatch.setattr(run_all, "ROOT", tmp_path)
    monkeypatch.setattr(run_all, "KNOWN", [
        run_all.Bench("missing", "bench_missing.py", title="A script not written yet"),
        run_all.Bench("broken", "bench_broken.py", title="Broken"),
    ])
    out = tmp_path / "docs" / "benchmarks.md"
    common = ["--quick", "--out", str(out), "--img", str(tmp_path / "docs" / "img"),
              "--results", str(tmp_path / "results")]
    assert run_all.main(common) == 0
    report = out.read_text()
    assert "| speed | 42 widgets/s |" in report  # bench_ok.py was discovered and its table kept verbatim
    assert "`bench_missing.py`: not run: the script does not exist yet" in report
    assert "`bench_broken.py`: not run: exited with status 1: boom: no data folder" in report
    # nothing measured: the headline says so instead of inventing figures
    assert "| added print time per check | not run |" in report
    assert "| size check width/height error | not run |" in report

    # only successful runs are kept for later reports: a broken run never replaces a good one
    assert (tmp_path / "results" / "ok.json").exists() and not (tmp_path / "results" / "broken.json").exists()

    # re-running one script keeps the others' last results in the report, marked as such
    (bench / "bench_ok.py").write_text("print('| figure | value |')\nprint('|---|---|')\nprint('| speed | 7 |')\n")
    assert run_all.main(common + ["--only", "broken"]) == 0
    report = out.read_text()
    assert "| speed | 42 widgets/s |" in report and "kept from an earlier run" in report
    assert run_all.main(common + ["--only", "nonsense"]) == 2


def test_plugin_and_gcode_figures_are_read_from_the_scripts_own_tables(run_all):
    plugin = """## PrintWatch on a real OctoPrint (virtual printer at M220 S1000, cube, 2 cameras, 5 checks, verdicts: ok)

| figure | value |
|---|---|
| print time with checks | 17.2 s |
| print time without checks | 12.4 s |
| **added print time per check** (moves at 1000 %, frames, vision) | **0.95 s** |
| job held per check: median / max (frames + vision) | 0.66 / 0.95 s |
| estimated added time per check on a real printer (hold + moves at 100 %) | 5.2 s |

| API latency, ms (median / p95 / max) | while a check runs | otherwise |
|---|---|---|
| GET /api/job | 7 / 25 / 113 (n=40) | 5 / 21 / 292 (n=300) |
| GET /plugin/printwatch/status | 12 / 49 / 115 (n=40) | 10 / 60 / 241 (n=300) |
"""
    figures = run_all.plugin_figures(plugin)
    assert figures["added_s"] == 0.95 and figures["real_printer_s"] == 5.2 and figures["hold_s"] == 0.66
    assert figures["latency_job_during_ms"] == [7, 25, 113]
    assert figures["latency_status_during_ms"] == [12, 49, 115]

    gcode = """file                                            MB layers checks  wall s   MB/s cpu MB/s peak RSS +MB traced MB
prusa25_sun_gear_zhop_relative_e.gcode         5.4    200     20    1.21    4.5     17.1          9.5      8.70
synthetic 100 MB                             100.0   2554    256    8.22   12.2     22.3         10.5      9.10
# Python 3.11.7, 2 CPUs, load average 9.0 at the end
"""
    rows = run_all.gcode_figures(gcode)
    assert [r["label"] for r in rows] == ["prusa25_sun_gear_zhop_relative_e.gcode", "synthetic 100 MB"]
    assert rows[1]["mb"] == 100.0 and rows[1]["wall_mbps"] == 12.2 and rows[1]["rss_mb"] == 10.5

    markdown = """| file | size MB | layers | checks | wall s | MB/s (wall) | MB/s (CPU) | peak RSS growth MB | tracemalloc peak MB |
|---|---|---|---|---|---|---|---|---|
| prusa25_sun_gear_zhop_relative_e.gcode | 5.4 | 200 | 20 | 0.29 | 18.6 | 18.6 | 9.5 | 8.70 |
| synthetic 10 MB | 10.0 | 264 | 27 | 0.54 | 18.7 | 22.4 | 9.8 | 7.98 |
"""
    rows = run_all.gcode_figures(markdown)
    assert [(r["mb"], r["wall_mbps"], r["cpu_mbps"], r["rss_mb"]) for r in rows] == [
        (5.4, 18.6, 18.6, 9.5), (10.0, 18.7, 22.4, 9.8)]
