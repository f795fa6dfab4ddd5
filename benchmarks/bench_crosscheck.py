"""Cross-check benchmark: recordings from a second, independent simulator -> ``printwatch evaluate`` -> a table.

    .venv/bin/python benchmarks/bench_crosscheck.py --out /tmp/crosscheck --count 60 --seed 1
    ... --jobs 2                   # generate and evaluate in two processes (niced)
    ... --json results.json        # every recording's scores and per-check figures
    ... --only 003_runout,017_detach --show   # re-evaluate some, print them check by check

The renderer (``benchmarks/crosscheck/``) was written from docs/recording-format.md alone and imports
nothing from ``octoprint_printwatch``; parts are random primitives and extrusions, not the project's
part library (docs/crosscheck.md). This script evaluates each recording exactly as ``printwatch
evaluate`` does (``core.pipeline.evaluate_recording``) and scores it against ``truth.json``:

* onset check = the first check after the failure started; flag check = the first check at which the
  failure is physically visible (runout: >= 1 mm missing; detachment: moved; spaghetti: >= 4 strands;
  layer shift: >= 1 mm printed above the shift);
* a failing print is caught "at flag" when the first ``fail`` is at or before the flag check (and not
  before the onset), "flag+1" one check later, "later", or "missed"; any ``fail`` before the onset is a
  false pause, as is any ``fail`` on a normal print;
* per-check false-alarm rate = ``fail`` verdicts / checks before any failure started.

Recordings already generated under ``--out`` are reused (``truth.json`` present); a folder holds one seed and one
calibration-error scale only (:func:`folder_recipe`: without ``--seed``/``--calibration-error`` the folder's own).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
import traceback
from multiprocessing import Pool
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from benchmarks.crosscheck.scenes import KINDS, Recipe, generate, plan_kinds  # noqa: E402


def _generate_one(args) -> tuple[str, float, str | None]:
    folder, seed, kind, calibration_error = args
    if os.getpid() != _MAIN_PID:
        os.nice(10)
    t = time.time()
    try:
        generate(Path(folder), Recipe(seed=seed, kind=kind, calibration_error=calibration_error))
        return folder, time.time() - t, None
    except Exception:  # a generator bug must not stop the run: it is reported
        return folder, time.time() - t, traceback.format_exc(limit=3)


def _evaluate_one(folder: str) -> dict:
    """Evaluate one recording; keep the contract JSON beside it (``evaluate.json``)."""
    from octoprint_printwatch.core.pipeline import evaluate_recording
    from octoprint_printwatch.core.recording import load_recording
    if os.getpid() != _MAIN_PID:
        os.nice(10)
    t = time.time()
    try:
        doc = evaluate_recording(load_recording(folder))
    except Exception as exc:  # the detector crashing on a valid recording is a finding, not a stop
        return {"folder": folder, "error": f"{type(exc).__name__}: {exc}", "trace": traceback.format_exc(limit=4)}
    doc.pop("_results", None)
    Path(folder, "evaluate.json").write_text(json.dumps(doc, indent=1, default=str))
    return {"folder": folder, "seconds": time.time() - t, "checks": doc["checks"]}


_MAIN_PID = os.getpid()


def folder_recipe(out: Path, seed: int | None, calibration_error: float | None) -> tuple[int, float]:
    """(seed, calibration-error scale) for the recordings under ``out``: those of the recordings already there,
    which ``seed`` / ``calibration_error`` (None: not given) must match, else 1 and 1.0.

    Evaluating a folder whose generation has not finished, with another seed, used to fill its missing
    recordings with that seed: a set of two seeds, scored as one (ninth session, seed 2)."""
    found: set[tuple[int, float]] = set()
    for truth_path in sorted(out.glob("*/truth.json")):
        truth = json.loads(truth_path.read_text())
        found.add((int(truth["seed"]) // 100000, float(truth["look"]["calibration_error"])))
    if len(found) > 1:
        raise SystemExit(f"{out}: holds recordings of several seeds / calibration-error scales {sorted(found)}; "
                         f"use one folder per set")
    if found:
        (have_seed, have_error), = found
        if (seed is not None and seed != have_seed) or (calibration_error is not None
                                                        and calibration_error != have_error):
            raise SystemExit(f"{out}: holds seed {have_seed} at calibration-error scale {have_error:g}, not "
                             f"seed {seed if seed is not None else have_seed} at "
                             f"{calibration_error if calibration_error is not None else have_error:g}; "
                             f"use another --out")
        return have_seed, have_error
    return (1 if seed is None else seed), (1.0 if calibration_error is None else calibration_error)


def score(truth: dict, checks: list[dict]) -> dict:
    """One recording's outcome against its truth: see the module docstring."""
    verdicts = [c["verdict"] for c in checks]
    n = min(len(verdicts), len(truth["checks"]))
    started = [truth["checks"][i]["failure_started"] for i in range(n)]
    fails = [i for i in range(n) if verdicts[i] == "fail"]
    before = [i for i in fails if not started[i]]
    out = {"first_fail": fails[0] if fails else None, "unknown": verdicts.count("unknown"),
           "pre_checks": sum(1 for s in started if not s), "pre_fails": len(before)}
    if truth["kind"] == "normal":
        out["outcome"] = "FALSE PAUSE" if fails else "ok"
        return out
    if before:
        out["outcome"] = "FALSE PAUSE"
        return out
    flag, onset = truth.get("flag_check"), truth.get("onset_check")
    if flag is None or flag >= n:
        out["outcome"] = "n/a"
        return out
    first = fails[0] if fails else None
    out["delay_vs_flag"] = None if first is None else first - flag
    out["delay_vs_onset"] = None if first is None else first - onset
    out["outcome"] = ("missed" if first is None else "at flag" if first <= flag else
                      "flag+1" if first == flag + 1 else "later")
    return out


def camera_figures(check: dict) -> str:
    """Per-camera figures of one check, short: error %, missing/extra, band, growth."""
    parts = []
    for cam, fig in (check.get("shape") or {}).items():
        if not fig.get("usable", True):
            parts.append(f"{cam}: unusable")
            continue
        bits = [f"err {fig.get('error_pct')}"]
        for key, label in (("missing_pct", "miss"), ("extra_pct", "extra"), ("band_error_pct", "band"),
                           ("growth_pct", "growth"), ("new_outside_mm2", "new mm2"), ("shift_px", "shift")):
            v = fig.get(key)
            if v is not None:
                bits.append(f"{label} {round(v, 1) if isinstance(v, float) else v}")
        parts.append(f"{cam}: " + ", ".join(bits))
    return "; ".join(parts)


def describe(truth: dict) -> str:
    p, lk = truth["part"], truth["look"]
    bits = [f"{p['shape']} {p['footprint_mm']}x{p['height_mm']} mm", f"{lk['filament']} on {lk['bed']}",
            f"rig {lk['layout']} {lk['size'][0]}x{lk['size'][1]}", f"every {truth['every']} layers",
            f"jpeg {lk['jpeg_quality'] or 'png'}"]
    if lk.get("gantry"):
        bits.append("gantry")
    if lk.get("skirt"):
        bits.append("skirt")
    if lk.get("brim"):
        bits.append("brim")
    if truth.get("shift_mm"):
        bits.append(f"shift {truth['shift_mm']}")
    if truth.get("detach"):
        bits.append(f"detach {truth['detach']}")
    return ", ".join(bits)


def table(rows: list[dict]) -> str:
    lines = ["| kind | recordings | at flag check | flag+1 | later | missed | paused before onset |",
             "|---|---|---|---|---|---|---|"]
    for kind in KINDS[1:]:
        rs = [r for r in rows if r["truth"]["kind"] == kind and "score" in r]
        if not rs:
            continue
        c = {k: sum(r["score"]["outcome"] == k for r in rs) for k in ("at flag", "flag+1", "later", "missed",
                                                                    "FALSE PAUSE")}
        lines.append(f"| {kind} | {len(rs)} | {c['at flag']} | {c['flag+1']} | {c['later']} | {c['missed']} | "
                     f"{c['FALSE PAUSE']} |")
    lines += ["", "Relative to the onset check (the first check after the failure started; bench_detection's "
              "'within one check' = onset or onset+1):", "",
              "| kind | at onset check | onset+1 | later | missed | paused before onset |", "|---|---|---|---|---|---|"]
    for kind in KINDS[1:]:
        rs = [r["score"] for r in rows if r["truth"]["kind"] == kind and "score" in r
              and r["score"]["outcome"] != "n/a"]
        if not rs:
            continue
        d = [s.get("delay_vs_onset") for s in rs if s["outcome"] != "FALSE PAUSE"]
        lines.append(f"| {kind} | {sum(x == 0 for x in d)} | {sum(x == 1 for x in d)} | "
                     f"{sum(x is not None and x > 1 for x in d)} | {sum(x is None for x in d)} | "
                     f"{sum(s['outcome'] == 'FALSE PAUSE' for s in rs)} |")
    normal = [r for r in rows if r["truth"]["kind"] == "normal" and "score" in r]
    paused = sum(r["score"]["outcome"] == "FALSE PAUSE" for r in normal)
    pre = sum(r["score"]["pre_checks"] for r in rows if "score" in r)
    pre_fails = sum(r["score"]["pre_fails"] for r in rows if "score" in r)
    unknown = sum(r["score"]["unknown"] for r in rows if "score" in r)
    lines.append("")
    lines.append(f"Normal prints with a false pause: {paused} / {len(normal)}. Per-check false-alarm rate (checks "
                 f"before any failure, all recordings): {pre_fails} / {pre} = {pre_fails / max(pre, 1):.1%}. "
                 f"'unknown' verdicts: {unknown}.")
    return "\n".join(lines)


def findings(rows: list[dict]) -> str:
    out = ["", "| recording | outcome | first fail / onset / flag check | scene | figures at the flag check "
               "(or first false fail) |", "|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            out.append(f"| {r['name']} | CRASH | | {describe(r['truth'])} | {r['error']} |")
            continue
        s = r["score"]
        if s["outcome"] in ("ok", "at flag", "n/a"):
            continue
        t = r["truth"]
        at = s["first_fail"] if s["outcome"] == "FALSE PAUSE" else t.get("flag_check")
        check = r["checks"][at] if at is not None and at < len(r["checks"]) else {}
        why = "; ".join(check.get("reasons", [])) if s["outcome"] == "FALSE PAUSE" else ""
        out.append(f"| {r['name']} | {s['outcome']} | {s['first_fail']} / {t.get('onset_check')} / "
                   f"{t.get('flag_check')} | {describe(t)} | {why} {camera_figures(check)} |")
    return "\n".join(out)


def contact_sheet(folders: list[Path], out: Path, tile=(256, 192)) -> None:
    """One row per recording (first camera): the empty bed, the check before the flag check, the flag check
    and the last check; JPEG."""
    import cv2
    import numpy as np
    rows = []
    for folder in folders:
        truth = json.loads((folder / "truth.json").read_text())
        session = json.loads((folder / "session.json").read_text())
        cam = next(iter(session["cameras"]))
        last = len(session["checks"]) - 1
        flag = truth.get("flag_check")
        flag = last if flag is None else flag
        paths = [session["background"][cam]] + [session["checks"][i]["frames"][cam]
                                                for i in (max(flag - 1, 0), flag, last)]
        tiles = [cv2.resize(cv2.imread(str(folder / p)), tile, interpolation=cv2.INTER_AREA) for p in paths]
        row = np.hstack(tiles)
        cv2.putText(row, f"{folder.name}: {truth['part']['shape']}, {truth['look']['filament']} on "
                         f"{truth['look']['bed']}", (6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 255), 1, cv2.LINE_AA)
        rows.append(row)
    cv2.imwrite(str(out), np.vstack(rows), [cv2.IMWRITE_JPEG_QUALITY, 80])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", required=True, type=Path, help="folder of recordings (created; reused)")
    ap.add_argument("--count", type=int, default=60, help="recordings: a third normal, the rest four failure kinds")
    ap.add_argument("--seed", type=int, default=None, help="default: the folder's own, else 1")
    ap.add_argument("--calibration-error", type=float, default=None, metavar="SCALE",
                    help="scale of the stated calibration's error (1 = 0.3 deg, 0.6 mm, 1 %% focal, 1.5 px per "
                         "axis; default: the folder's own, else 1)")
    ap.add_argument("--jobs", type=int, default=1, help="processes for generation and evaluation (niced)")
    ap.add_argument("--json", type=Path, help="write every recording's scores and per-check figures here")
    ap.add_argument("--only", help="comma-separated recording names (or name prefixes) to evaluate")
    ap.add_argument("--generate-only", action="store_true")
    ap.add_argument("--show", action="store_true", help="print every check of the evaluated recordings")
    ap.add_argument("--sheet", type=Path, help="write a contact sheet of the --only recordings (JPEG) and stop")
    ap.add_argument("--rescore", type=Path, help="print the tables of a saved --json file (no generation, no evaluation)")
    args = ap.parse_args(argv)
    if args.rescore:
        rows = json.loads(args.rescore.read_text())
        for r in rows:
            if "checks" in r:
                r["score"] = score(r["truth"], r["checks"])
        print(table(rows))
        print(findings(rows))
        return 0

    args.out.mkdir(parents=True, exist_ok=True)
    args.seed, args.calibration_error = folder_recipe(args.out, args.seed, args.calibration_error)
    kinds = plan_kinds(args.count)
    wanted = args.only.split(",") if args.only else None
    todo = []
    names = []
    for i, kind in enumerate(kinds):
        name = f"{i:03d}_{kind}"
        if wanted and not any(name.startswith(w) for w in wanted):
            continue
        names.append(name)
        folder = args.out / name
        if not (folder / "truth.json").exists() and not args.sheet:
            todo.append((str(folder), args.seed * 100000 + i, kind, args.calibration_error))
    t0 = time.time()
    gen_times = []
    if todo:
        with Pool(args.jobs) as pool:
            for folder, secs, err in pool.imap_unordered(_generate_one, todo):
                gen_times.append(secs)
                print(f"generated {Path(folder).name} in {secs:.1f} s" + (f"  FAILED:\n{err}" if err else ""),
                      file=sys.stderr, flush=True)
        print(f"generation: {len(todo)} recordings in {time.time() - t0:.0f} s wall with {args.jobs} process(es), "
              f"{sum(gen_times):.0f} s CPU-ish total", file=sys.stderr)
    if args.generate_only:
        return 0
    folders = [str(args.out / n) for n in names if (args.out / n / "truth.json").exists()]
    if args.sheet:
        contact_sheet([Path(f) for f in folders], args.sheet)
        return 0
    t1 = time.time()
    rows = []
    with Pool(args.jobs) as pool:
        for res in pool.imap(_evaluate_one, folders):
            folder = Path(res["folder"])
            truth = json.loads((folder / "truth.json").read_text())
            row = {"name": folder.name, "truth": truth}
            if "error" in res:
                row.update(error=res["error"], trace=res["trace"])
                print(f"{folder.name}: evaluate FAILED {res['error']}", file=sys.stderr, flush=True)
            else:
                row.update(checks=res["checks"], seconds=res["seconds"], score=score(truth, res["checks"]))
                print(f"{folder.name}: {row['score']['outcome']} ({res['seconds']:.1f} s)", file=sys.stderr, flush=True)
            rows.append(row)
    print(f"evaluation: {len(rows)} recordings in {time.time() - t1:.0f} s wall", file=sys.stderr)
    print(table(rows))
    print(findings(rows))
    if args.show:
        for r in rows:
            print(f"\n## {r['name']}: {describe(r['truth'])}; onset check {r['truth'].get('onset_check')}, "
                  f"flag check {r['truth'].get('flag_check')}")
            for i, c in enumerate(r.get("checks", [])):
                print(f"  {i:2d} L{c['layer']:4d} {c['verdict']:7s} {'; '.join(c['reasons'])[:200]}")
                print(f"       {camera_figures(c)}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1, default=str))
    return 0


if __name__ == "__main__":
    sys.exit(main())
