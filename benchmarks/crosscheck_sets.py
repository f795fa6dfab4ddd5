"""Replay several cross-check seeds with one code version, total them, and compare two versions check by check.

    # recordings: one folder per seed, ROOT/sN (bench_crosscheck.py --out ROOT/sN --seed N --generate-only)
    .venv/bin/python benchmarks/crosscheck_sets.py replay --tag head --seeds 1,5,7,10,12-31 --root /tmp/pw
    .venv/bin/python benchmarks/crosscheck_sets.py replay --tag base --code /tmp/base-tree --seeds 30,31
    .venv/bin/python benchmarks/crosscheck_sets.py tally --tag head --seeds 1,5,7,10,12-31 --seeds 32,33
    .venv/bin/python benchmarks/crosscheck_sets.py compare base head --seeds 1,5,7,10,12-31

Every session measures a change the same way: the same recordings replayed by the base code and by the changed
code, each check's verdict set side by side. ``replay`` runs ``bench_crosscheck.py`` of the code tree ``--code``
(default: this one) on each seed's folder and keeps its per-check JSON as ``RESULTS/TAG_sN.json`` (reused when
present); ``default`` in ``--seeds`` is bench_detection.py's 66 recordings of our own simulator
(``RESULTS/TAG_default.json``). ``tally`` prints, per group of seeds (each ``--seeds`` is one group): normal
prints paused; false-alarm checks (``fail`` before any failure started) of all such checks; failing prints paused
before their onset; failures caught within one check of their onset, per kind. ``compare`` lists every check whose
verdict or reasons changed and flags any check that went from ``ok`` to ``fail`` (the keep rule: none may).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent
FAILURE_KINDS = ("runout", "detach", "spaghetti", "layer_shift")


def parse_seeds(text: str) -> list[str]:
    """'1,5,12-14,default' -> ['1', '5', '12', '13', '14', 'default']."""
    out = []
    for part in text.split(","):
        part = part.strip()
        if "-" in part and part.replace("-", "").isdigit():
            lo, hi = part.split("-")
            out += [str(s) for s in range(int(lo), int(hi) + 1)]
        elif part:
            out.append(part)
    return out


def label(seed: str) -> str:
    return seed if seed == "default" else f"s{seed}"


def results_file(results: Path, tag: str, seed: str) -> Path:
    return results / f"{tag}_{'default' if seed == 'default' else 's' + seed}.json"


def replay(args) -> int:
    code = Path(args.code).resolve()
    python = Path(args.python) if args.python else code / ".venv/bin/python"
    if not python.exists():
        python = Path(sys.executable)
    args.results.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, PYTHONPATH=str(code))
    for group in args.seeds:
        for seed in parse_seeds(group):
            out = results_file(args.results, args.tag, seed)
            if out.exists():
                continue
            if seed == "default":
                cmd = [str(python), "benchmarks/bench_detection.py", "--cached-only", "--data", str(args.default_data),
                       "--json", str(out)]
            else:
                folder = args.root / f"s{seed}"
                if not (folder / "000_normal" / "truth.json").exists():
                    print(f"seed {seed}: no recordings in {folder}; skipped", file=sys.stderr)
                    continue
                cmd = [str(python), "benchmarks/bench_crosscheck.py", "--out", str(folder), "--jobs", str(args.jobs),
                       "--json", str(out)]
            print(f"{args.tag} seed {seed} ...", file=sys.stderr, flush=True)
            done = subprocess.run(cmd, cwd=code, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            if done.returncode != 0:
                print(f"seed {seed}: replay failed:\n{done.stderr[-2000:]}", file=sys.stderr)
                return 1
    return 0


def load_rows(results: Path, tag: str, seed: str) -> list[dict] | None:
    """Rows of one replay as (name, kind, checks [{verdict, reasons, started}], onset index) dicts."""
    path = results_file(results, tag, seed)
    if not path.exists():
        return None
    rows = []
    for r in json.loads(path.read_text()):
        if seed == "default":
            checks = [{"verdict": c["verdict"], "reasons": c["reasons"], "started": c["started"]} for c in r["checks"]]
            kind = r["kind"]
        else:
            if "checks" not in r:
                rows.append({"name": r["name"], "kind": r["truth"]["kind"], "error": r.get("error")})
                continue
            truth = r["truth"]["checks"]
            checks = [{"verdict": c["verdict"], "reasons": c["reasons"], "started": truth[i]["failure_started"]}
                      for i, c in enumerate(r["checks"]) if i < len(truth)]
            kind = r["truth"]["kind"]
        onset = next((i for i, c in enumerate(checks) if c["started"]), None)
        rows.append({"name": r["name"], "kind": kind, "checks": checks, "onset": onset})
    return rows


def totals(rows: list[dict]) -> dict:
    t = {"recordings": len(rows), "errors": 0, "normal": 0, "normal_paused": 0, "fa": 0, "pre_checks": 0,
         "before_onset": 0, "within": dict.fromkeys(FAILURE_KINDS, 0), "of": dict.fromkeys(FAILURE_KINDS, 0)}
    for r in rows:  # the default set also holds under-extrusion
        t["within"].setdefault(r["kind"], 0)
        t["of"].setdefault(r["kind"], 0)
    t["within"].pop("normal", None)
    t["of"].pop("normal", None)
    for r in rows:
        if "checks" not in r:
            t["errors"] += 1
            continue
        pre = [c for c in r["checks"] if not c["started"]]
        pre_fails = sum(c["verdict"] == "fail" for c in pre)
        t["pre_checks"] += len(pre)
        t["fa"] += pre_fails
        if r["kind"] == "normal":
            t["normal"] += 1
            t["normal_paused"] += pre_fails > 0
            continue
        if r["onset"] is None:  # the failure starts after the last check: nothing to catch
            t["before_onset"] += pre_fails > 0
            continue
        t["of"][r["kind"]] += 1
        if pre_fails:
            t["before_onset"] += 1
            continue
        first = next((i for i, c in enumerate(r["checks"]) if c["verdict"] == "fail"), None)
        # a failure starting after the last check has nothing to catch and counts as not caught
        t["within"][r["kind"]] += r["onset"] is not None and first is not None and first <= r["onset"] + 1
    return t


def totals_text(t: dict) -> str:
    kinds = list(t["of"])
    within = "/".join(str(t["within"][k]) for k in kinds)
    of = "/".join(str(t["of"][k]) for k in kinds)
    errors = f"; {t['errors']} CRASHED" if t["errors"] else ""
    return (f"{t['recordings']} recordings: normal paused {t['normal_paused']}/{t['normal']}; false alarms "
            f"{t['fa']}/{t['pre_checks']}; paused before onset {t['before_onset']}; within one check "
            f"{within} of {of} ({'/'.join(kinds)}){errors}")


def tally(args) -> int:
    for group in args.seeds:
        rows, missing = [], []
        for seed in parse_seeds(group):
            got = load_rows(args.results, args.tag, seed)
            if got is None:
                missing.append(seed)
            else:
                rows += got
        note = f" (no results for {','.join(missing)})" if missing else ""
        print(f"{args.tag} seeds {group}{note}: {totals_text(totals(rows))}")
        if args.list:
            for seed in parse_seeds(group):
                for r in load_rows(args.results, args.tag, seed) or []:
                    if "checks" not in r:
                        print(f"  {label(seed)} {r['name']}: CRASH {r['error']}")
                        continue
                    pre = [i for i, c in enumerate(r["checks"]) if c["verdict"] == "fail" and not c["started"]]
                    first = next((i for i, c in enumerate(r["checks"]) if c["verdict"] == "fail"), None)
                    onset = r["onset"]
                    if pre:
                        print(f"  {label(seed)} {r['name']}: paused at check {pre[0]}"
                              + ("" if r["kind"] == "normal" else f" (onset {onset})"))
                    elif r["kind"] != "normal" and onset is not None and (first is None or first > onset + 1):
                        caught = "missed" if first is None else f"caught at check {first}"
                        print(f"  {label(seed)} {r['name']}: {caught} (onset {onset})")
    return 0


def compare(args) -> int:
    worse = 0
    for group in args.seeds:
        counts = {"checks": 0, "ok->fail": 0, "fail->ok": 0, "reasons": 0, "other": 0}
        for seed in parse_seeds(group):
            a, b = load_rows(args.results, args.a, seed), load_rows(args.results, args.b, seed)
            if a is None or b is None:
                print(f"seed {seed}: missing results for {args.a if a is None else args.b}")
                continue
            for ra, rb in zip(a, b):
                if "checks" not in ra or "checks" not in rb:
                    if ("checks" in ra) != ("checks" in rb):
                        print(f"  {label(seed)} {ra['name']}: crash in one version only")
                    continue
                for i, (ca, cb) in enumerate(zip(ra["checks"], rb["checks"])):
                    counts["checks"] += 1
                    if ca["verdict"] == cb["verdict"] and ca["reasons"] == cb["reasons"]:
                        continue
                    change = (f"{ca['verdict']}->{cb['verdict']}" if ca["verdict"] != cb["verdict"] else "reasons")
                    counts[change if change in counts else "other"] += 1
                    worse += change == "ok->fail"
                    if not args.quiet or change == "ok->fail":
                        phase = "after onset" if ca["started"] else "before onset"
                        print(f"  {label(seed)} {ra['name']} check {i} ({phase}): {change}"
                              + (f"\n      {args.a}: {'; '.join(ca['reasons'])[:240]}\n      {args.b}: "
                                 f"{'; '.join(cb['reasons'])[:240]}" if args.reasons else ""))
        print(f"seeds {group}: {counts['checks']} checks; {counts['ok->fail']} ok->fail, {counts['fail->ok']} "
              f"fail->ok, {counts['reasons']} reasons only, {counts['other']} other changes")
    return 1 if worse else 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="command", required=True)
    for name in ("replay", "tally", "compare"):
        p = sub.add_parser(name)
        p.add_argument("--seeds", action="append", required=True,
                       help="a group of seeds, e.g. 1,5,12-31 or default; repeat for several groups")
        p.add_argument("--results", type=Path, default=Path("/tmp/pw/res"), help="replays' JSON files")
        if name == "replay":
            p.add_argument("--tag", required=True, help="name of the code version (results file prefix)")
            p.add_argument("--code", default=str(HERE), help="source tree to replay with (default: this one)")
            p.add_argument("--python", help="interpreter (default: CODE/.venv/bin/python, else this one)")
            p.add_argument("--root", type=Path, default=Path("/tmp/pw"), help="folder holding sN/ per seed")
            p.add_argument("--default-data", type=Path, default=Path("/tmp/printwatch-bench-detection"))
            p.add_argument("--jobs", type=int, default=2)
        elif name == "tally":
            p.add_argument("--tag", required=True)
            p.add_argument("--list", action="store_true", help="also list each false pause and late catch")
        else:
            p.add_argument("a")
            p.add_argument("b")
            p.add_argument("--quiet", action="store_true", help="list only checks that went from ok to fail")
            p.add_argument("--reasons", action="store_true", help="print both versions' reasons per change")
    args = ap.parse_args(argv)
    return {"replay": replay, "tally": tally, "compare": compare}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
