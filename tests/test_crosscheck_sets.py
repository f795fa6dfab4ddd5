"""``benchmarks/crosscheck_sets.py``: the totals every session reports (normal prints paused, false alarms, pauses
before an onset, catches within one check) and the check-by-check comparison whose ok -> fail count is the keep
rule."""
from __future__ import annotations

import json
from pathlib import Path

import pytest


@pytest.fixture(scope="module")
def sets(load_benchmark):
    yield from load_benchmark("crosscheck_sets")


def _row(name: str, kind: str, started: list[bool], verdicts: list[str]) -> dict:
    """One recording as bench_crosscheck.py --json writes it (the fields crosscheck_sets reads)."""
    return {"name": name, "truth": {"kind": kind, "checks": [{"failure_started": s} for s in started]},
            "checks": [{"verdict": v, "reasons": ["why"] if v == "fail" else []} for v in verdicts]}


def _write(folder: Path, tag: str, seed: int, rows: list[dict]) -> None:
    (folder / f"{tag}_s{seed}.json").write_text(json.dumps(rows))


BASE = [
    _row("000_normal", "normal", [False] * 4, ["ok", "ok", "fail", "ok"]),
    _row("001_normal", "normal", [False] * 4, ["ok"] * 4),
    _row("010_runout", "runout", [False, False, True, True], ["ok", "ok", "ok", "fail"]),
    _row("020_detach", "detach", [False, True, True, True], ["ok", "ok", "ok", "fail"]),
    _row("030_spaghetti", "spaghetti", [False, False, True], ["fail", "ok", "fail"]),
]


def test_totals_count_pauses_false_alarms_and_catches_within_one_check(sets, tmp_path, capsys):
    _write(tmp_path, "base", 7, BASE)
    assert sets.main(["tally", "--tag", "base", "--seeds", "7", "--results", str(tmp_path), "--list"]) == 0
    out = capsys.readouterr().out
    assert "5 recordings: normal paused 1/2; false alarms 2/13; paused before onset 1" in out
    # the runout fails one check after its onset (caught), the detachment two after (late), the spaghetti early
    assert "within one check 1/0/0/0 of 1/1/1/0" in out
    assert "s7 020_detach: caught at check 3 (onset 1)" in out
    assert "s7 030_spaghetti: paused at check 0 (onset 2)" in out


def test_compare_flags_a_check_that_went_from_ok_to_fail(sets, tmp_path, capsys):
    _write(tmp_path, "base", 7, BASE)
    better = json.loads(json.dumps(BASE))
    better[0]["checks"][2] = {"verdict": "ok", "reasons": []}
    _write(tmp_path, "better", 7, better)
    assert sets.main(["compare", "base", "better", "--seeds", "7", "--results", str(tmp_path)]) == 0
    assert "1 fail->ok" in capsys.readouterr().out

    worse = json.loads(json.dumps(BASE))
    worse[1]["checks"][3] = {"verdict": "fail", "reasons": ["new"]}
    _write(tmp_path, "worse", 7, worse)
    assert sets.main(["compare", "base", "worse", "--seeds", "7", "--results", str(tmp_path), "--quiet"]) == 1
    out = capsys.readouterr().out
    assert "s7 001_normal check 3 (before onset): ok->fail" in out and "1 ok->fail" in out


def test_seed_groups_expand_ranges(sets):
    assert sets.parse_seeds("1,5,12-14,default") == ["1", "5", "12", "13", "14", "default"]
