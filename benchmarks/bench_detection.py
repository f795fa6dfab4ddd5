"""Detection benchmark: simulated recordings -> ``evaluate`` -> a Markdown table (PrintWatch rule vs the seed's).

    .venv/bin/python benchmarks/bench_detection.py            # 66 recordings (generated once, then cached)
    .venv/bin/python benchmarks/bench_detection.py --quick    # 14 recordings
    .venv/bin/python benchmarks/bench_detection.py --data DIR --json results.json

Every recording is written by ``octoprint_printwatch.simulator`` (parts, failure
kinds, looks incl. the hard cases, several rigs, calibration error on every
camera) with a ``truth.json`` that the evaluation reads only to score.
The detector sees exactly what ``printwatch evaluate`` sees.

Scoring (per recording, from truth.json):
* onset check = the first check after the failure started; a failure is
  "detected within one check" when the first ``fail`` verdict is at the onset
  check or the next one, and not before the failure started;
* a normal print with any ``fail`` is a false pause; so is a failing print
  that fails before its failure started;
* per-check false-alarm rate = failing verdicts / checks before any failure;
* seconds per camera = a check's wall time / cameras checked (frames 640x480).
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from octoprint_printwatch.core.pipeline import CheckRunner, decide, prepare_job  # noqa: E402
from octoprint_printwatch.core.recording import load_recording  # noqa: E402
from octoprint_printwatch.core.seed_rules import SEED_THRESHOLD_PCT, seed_check, seed_error  # noqa: E402
from octoprint_printwatch.core.settings import DetectionSettings  # noqa: E402

PARTS = ("gear", "cube", "cylinder", "sun_gear", "prism", "twisted_vase", "pyramid", "rect_prism", "tower")
LOOKS = ("seed", "black_on_black", "white_on_glass", "blue_on_blue_tape", "glow", "orange_on_gold",
         "random", "random")
RIGS = ("stations3", "ring", "single", "pair", "ring", "top")
KINDS = {"normal": 18, "runout": 10, "detach": 10, "spaghetti": 10, "layer_shift": 10, "under_extrusion": 8}
QUICK = {"normal": 4, "runout": 2, "detach": 2, "spaghetti": 2, "layer_shift": 2, "under_extrusion": 2}


@dataclass
class Spec:
    name: str
    kind: str
    part: str
    look: str
    rig: str
    seed: int


def plan_specs(counts: dict[str, int], holdout: int = 0) -> list[Spec]:
    """A deterministic spread over parts, looks and rigs for each failure kind.

    ``holdout`` > 0 gives a different set (other seeds, so other random looks, calibration errors and
    noise, and other part/look/rig combinations) to check that a change does not only fit the default set.
    """
    specs = []
    for k, (kind, n) in enumerate(counts.items()):
        for i in range(n):
            j = i + 3 * k + 5 * holdout
            part = PARTS[j % len(PARTS)]
            look = LOOKS[(i + k + 3 * holdout) % len(LOOKS)]
            rig = RIGS[(i + 2 * k + holdout) % len(RIGS)]
            seed = 1000 + 37 * k + i + 7919 * holdout
            specs.append(Spec(f"{kind}_{i:02d}_{part}_{look}_{rig}", kind, part, look, rig, seed))
    return specs


def generate(spec: Spec, out: Path) -> Path:
    """Render one recording (skipped when it is already there)."""
    folder = out / spec.name
    if (folder / "truth.json").exists():
        return folder
    from octoprint_printwatch.simulator.look import PRESETS, random_look
    from octoprint_printwatch.simulator.recording import write_recording
    from octoprint_printwatch.simulator.rig import make_rig
    from octoprint_printwatch.simulator.scenario import Scenario
    from octoprint_printwatch.simulator.scene import PrintSimulator

    rig = make_rig(spec.rig, n_cameras=3 if spec.rig == "ring" else None, seed=spec.seed)
    look = random_look(spec.seed, rig.bed) if spec.look == "random" else PRESETS[spec.look]
    sim = PrintSimulator(spec.part, rig, look, Scenario(spec.kind), seed=spec.seed)
    tmp = out / (spec.name + ".partial")
    if tmp.exists():
        import shutil

        shutil.rmtree(tmp)
    write_recording(tmp, sim)
    tmp.rename(folder)
    return folder


def evaluate(folder: Path, settings: DetectionSettings) -> dict:
    """Our rule and the seed's rule on one recording, scored against truth.json."""
    recording = load_recording(folder)
    truth = json.loads((folder / "truth.json").read_text())
    checks = sorted(recording.checks, key=lambda c: c.z)
    plan = prepare_job(gcode_path=recording.gcode, model_path=recording.model, cameras=recording.cameras,
                       pairs=recording.pairs, check_heights=[(c.layer, c.z) for c in checks], settings=settings)
    backgrounds = {n: recording.read_background(n) for n in recording.cameras}
    # the seed's rule needs the undistorted silhouettes, which the job plan does not keep
    from octoprint_printwatch.core.render import render_expected_views
    undistorted = {(cam, round(z, 4)): view.silhouette_undistorted for (cam, z), view in render_expected_views(
        plan.part, list(recording.cameras.values()), [c.z for c in checks]).items()}
    runner = CheckRunner(plan, settings, backgrounds)
    runner.keep_pictures = False
    seed_prev: dict[str, np.ndarray] = {}
    rows = []
    for check, t in zip(checks, truth["checks"]):
        frames = {n: recording.read_frame(check, n) for n in recording.cameras}
        result = runner.run_check(check.layer, check.z, frames)
        seed_errors, seed_fail = {}, False
        mixed_errors, mixed_fail = {}, False
        for name, frame in frames.items():
            if frame is None or backgrounds.get(name) is None:
                continue
            view = plan.view(name, check.z)
            s = seed_check(name, backgrounds[name], frame, undistorted[(name, round(check.z, 4))],
                           recording.cameras[name], seed_prev.get(name))
            seed_prev[name] = s.mask
            seed_errors[name] = s.error_pct
            seed_fail |= not s.passed
            ours = result.shape.get(name)
            if ours is not None and ours.usable:
                # the seed's rescale + Eq. 4.1 + 7 % on OUR background removal: separates the two stages
                mixed_errors[name] = seed_error(ours.observed_mask, view.silhouette)
                mixed_fail |= mixed_errors[name] > SEED_THRESHOLD_PCT
        n_cams = max(1, len(result.shape))
        shape_only, _ = decide(result.shape, {}, settings, result.unreadable)
        size_errors = {k: v.get("error_pct") for k, v in result.size.items()}
        rows.append({
            "layer": check.layer, "z": check.z, "started": t["failure_started"], "should_flag": t["should_flag"],
            "verdict": result.verdict, "shape_verdict": shape_only,
            "seconds_per_camera": result.shape_seconds / n_cams, "seconds": result.seconds,
            "cpu_seconds_per_camera": result.shape_cpu_seconds / n_cams,
            "size_errors": size_errors,
            "errors": {k: v for k, v in result.shape_error_pct.items() if v is not None},
            "band": {k: r.band_error_pct for k, r in result.shape.items()},
            "reasons": result.reasons,
            "seed_verdict": "fail" if seed_fail else "ok", "seed_errors": seed_errors,
            "mixed_verdict": "fail" if mixed_fail else "ok", "mixed_errors": mixed_errors,
        })
    return {"name": folder.name, "kind": truth["scenario"]["kind"], "part": truth["part"],
            "look": truth["look"], "onset_layer": truth["scenario"]["onset_layer"],
            "first_failure_layer": next((c["layer"] for c in rows if c["verdict"] == "fail"), None),
            "prepare_seconds": plan.prepare_seconds, "checks": rows}


def score(rec: dict, verdict_key: str) -> dict:
    """detected (within one check), late, missed, false (fail before the failure started)."""
    checks = rec["checks"]
    false_before = any(c[verdict_key] == "fail" and not c["started"] for c in checks)
    if rec["kind"] == "normal":
        return {"false_pause": false_before, "detected": None}
    started = [i for i, c in enumerate(checks) if c["started"]]
    fails = [i for i, c in enumerate(checks) if c[verdict_key] == "fail" and c["started"]]
    if not started:
        return {"false_pause": false_before, "detected": None, "note": "failure after the last check"}
    onset = started[0]
    within = bool(fails) and fails[0] <= onset + 1
    return {"false_pause": false_before, "detected": within, "ever": bool(fails),
            "delay_checks": (fails[0] - onset) if fails else None}


def pct(values, q):
    return float(np.percentile(values, q)) if len(values) else float("nan")


def table(results: list[dict]) -> str:
    lines = []
    kinds = [k for k in KINDS if any(r["kind"] == k for r in results)]
    lines.append("| rule | " + " | ".join(
        f"{k} detected" if k != "normal" else "normal prints paused" for k in kinds)
        + " | false alarms per check |")
    lines.append("|---" * (len(kinds) + 2) + "|")
    for label, key in (("PrintWatch shape check (this issue)", "shape_verdict"),
                       ("PrintWatch combined: shape + stereo size", "verdict"),
                       ("seed rule as published (grey diff, bbox rescale, Eq. 4.1, 7 %)", "seed_verdict"),
                       ("seed's rescale + Eq. 4.1 + 7 % on PrintWatch's masks", "mixed_verdict")):
        cells = []
        for kind in kinds:
            rs = [r for r in results if r["kind"] == kind]
            scores = [score(r, key) for r in rs]
            if kind == "normal":
                cells.append(f"{sum(s['false_pause'] for s in scores)} / {len(rs)}")
            else:
                valid = [s for s in scores if s["detected"] is not None]
                ok = sum(1 for s in valid if s["detected"] and not s["false_pause"])
                cells.append(f"{ok} / {len(valid)}")
        pre = [c for r in results for c in r["checks"] if not c["started"]]
        rate = sum(c[key] == "fail" for c in pre) / max(1, len(pre))
        lines.append(f"| {label} | " + " | ".join(cells) + f" | {rate:.1%} ({len(pre)} checks) |")
    lines.append("")
    lines.append("| error % per camera | checks | p50 | p90 | p99 | max |")
    lines.append("|---|---|---|---|---|---|")
    for label, key in (("PrintWatch", "errors"), ("seed as published", "seed_errors"),
                       ("seed rescale on our masks", "mixed_errors")):
        for group, pick in (("normal (before any failure)", lambda c: not c["started"]),
                            ("failing (failure due)", lambda c: c["should_flag"])):
            vals = [v for r in results for c in r["checks"] if pick(c) for v in c[key].values()]
            lines.append(f"| {label}, {group} | {len(vals)} | {pct(vals, 50):.1f} | {pct(vals, 90):.1f} | "
                         f"{pct(vals, 99):.1f} | {max(vals) if vals else float('nan'):.1f} |")
    secs = [c["seconds_per_camera"] for r in results for c in r["checks"]]
    whole = [c["seconds"] for r in results for c in r["checks"]]
    cpu = [c["cpu_seconds_per_camera"] for r in results for c in r["checks"]]
    prep = [r["prepare_seconds"] for r in results]
    lines.append("")
    lines.append(f"Shape check, median time per check per camera (640x480): "
                 f"{statistics.median(secs) * 1000:.1f} ms wall (p90 {pct(secs, 90) * 1000:.1f} ms), "
                 f"{statistics.median(cpu) * 1000:.1f} ms CPU. "
                 f"Whole check (all cameras and pairs): median {statistics.median(whole) * 1000:.0f} ms. "
                 f"Median prepare (expected views) per recording: {statistics.median(prep):.2f} s.")
    return "\n".join(lines)


def details(results: list[dict]) -> str:
    out = ["", "| recording | shape check | combined | seed | first shape fail | onset layer |",
           "|---|---|---|---|---|---|"]
    for r in results:
        ours, both, seed = score(r, "shape_verdict"), score(r, "verdict"), score(r, "seed_verdict")

        def word(s):
            if s["false_pause"]:
                return "FALSE PAUSE"
            if s["detected"] is None:
                return "ok" if r["kind"] == "normal" else "n/a"
            return "detected" if s["detected"] else ("late" if s.get("ever") else "MISSED")

        first = next((c["layer"] for c in r["checks"] if c["shape_verdict"] == "fail"), None)
        out.append(f"| {r['name']} | {word(ours)} | {word(both)} | {word(seed)} | {first} | {r['onset_layer']} |")
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="14 recordings instead of 66")
    parser.add_argument("--data", default="/tmp/printwatch-bench-detection", help="recordings folder (cache)")
    parser.add_argument("--json", help="write per-check results here")
    parser.add_argument("--holdout", type=int, default=0,
                        help="N > 0: a hold-out set with other seeds and combinations (use another --data)")
    parser.add_argument("--counts", help="recordings per kind, e.g. normal=8,runout=4 (instead of the default set)")
    parser.add_argument("--only", help="only recordings whose name contains this")
    parser.add_argument("--details", action="store_true", help="also list every recording's outcome")
    parser.add_argument("--generate-only", action="store_true", help="only render the recordings (cache)")
    parser.add_argument("--cached-only", action="store_true", help="only evaluate recordings already rendered")
    args = parser.parse_args(argv)
    data = Path(args.data)
    data.mkdir(parents=True, exist_ok=True)
    counts = QUICK if args.quick else KINDS
    if args.counts:
        counts = {kind: int(n) for kind, n in (item.split("=") for item in args.counts.split(","))}
    specs = plan_specs(counts, args.holdout)
    if args.only:
        specs = [s for s in specs if args.only in s.name]
    if args.cached_only:
        specs = [s for s in specs if (data / s.name / "truth.json").exists()]
    settings = DetectionSettings()
    results = []
    started = time.perf_counter()
    for i, spec in enumerate(specs):
        t0 = time.perf_counter()
        folder = generate(spec, data)
        t1 = time.perf_counter()
        if args.generate_only:
            print(f"[{i + 1}/{len(specs)}] {spec.name}: generated in {t1 - t0:.1f} s", file=sys.stderr)
            continue
        results.append(evaluate(folder, settings))
        print(f"[{i + 1}/{len(specs)}] {spec.name}: generated in {t1 - t0:.1f} s, evaluated in "
              f"{time.perf_counter() - t1:.1f} s", file=sys.stderr)
    if args.generate_only:
        return 0
    print(f"# Detection benchmark: {len(results)} simulated recordings "
          f"({time.perf_counter() - started:.0f} s)\n")
    print(table(results))
    if args.details:
        print(details(results))
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
