"""Detection benchmark: simulated recordings -> ``evaluate`` -> a Markdown table (PrintWatch rule vs the seed's).

    .venv/bin/python benchmarks/bench_detection.py            # 66 recordings (generated once, then cached)
    .venv/bin/python benchmarks/bench_detection.py --quick    # 14 recordings
    .venv/bin/python benchmarks/bench_detection.py --data DIR --json results.json
    # hostile conditions a different simulator may bring (each set in its own --data folder):
    .venv/bin/python benchmarks/bench_detection.py --holdout 3 --data /tmp/hostile_720p --size 1280x720 \
        --counts normal=8,runout=4,detach=4,spaghetti=4,layer_shift=4
    ... --gcode-only | --jpeg 40 | --background-exposure 0.7 | --calibration-error 2 | --format png
    ... --parts tests/data/gcode/cura413_ender3_sun_gear.gcode,cube     # other parts / other slicers' G-code
    ... --holdout 6 --parts arch,bracket,cup,pin,tiers,hexnut,thin_wall,cone   # shapes never tuned on

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
* seconds per camera = a check's wall time / cameras checked (at the set's frame size).

Generation options (``--size``, ``--gcode-only``, ``--jpeg``, ``--background-exposure``,
``--calibration-error``, ``--format``, ``--parts``) are stored in ``DATA/bench_options.json``; a folder is
never filled under two different sets of options, and ``--cached-only`` takes the set's
``--holdout``/``--counts`` from that file when they are not given.
"""
from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from octoprint_printwatch.core.pipeline import CheckRunner, prepare_job  # noqa: E402
from octoprint_printwatch.core.recording import load_recording  # noqa: E402
from octoprint_printwatch.core.seed_rules import SEED_THRESHOLD_PCT, seed_check, seed_error  # noqa: E402
from octoprint_printwatch.core.settings import DetectionSettings  # noqa: E402

PARTS = ("gear", "cube", "cylinder", "sun_gear", "prism", "twisted_vase", "pyramid", "rect_prism", "tower")
LOOKS = ("seed", "black_on_black", "white_on_glass", "blue_on_blue_tape", "glow", "orange_on_gold",
         "random", "random")
RIGS = ("stations3", "ring", "single", "pair", "ring", "top")
KINDS = {"normal": 18, "runout": 10, "detach": 10, "spaghetti": 10, "layer_shift": 10, "under_extrusion": 8}
QUICK = {"normal": 4, "runout": 2, "detach": 2, "spaghetti": 2, "layer_shift": 2, "under_extrusion": 2}
#: The frame size the rigs' focal lengths (600-950 px) were chosen for.
BASE_SIZE = (640, 480)
OPTIONS_FILE = "bench_options.json"


@dataclass(frozen=True)
class Conditions:
    """How a set's recordings are rendered and stored, beyond the scene itself (all defaults = the benchmark's).

    size: frame width, height; the cameras keep their field of view across the width (focal lengths and
    principal points scale with width / 640), and the optics' blur and the shake, which the simulator gives
    in pixels, scale with it too (a webcam's lens does not get sharper because its sensor has more pixels).
    gcode_only: the recording ships ``print.gcode`` only (no ``model``): the toolpaths define the part.
    jpeg: quality at which frames are stored (the webcam's own JPEG round trip comes on top).
    background_exposure: the empty-bed frame is taken at this multiple of the exposure (lights, auto exposure).
    calibration_error: scale of the calibration error (1 = 1 % focal, 0.5 deg, 1 mm at 1 sigma).
    image_format: "jpg" or "png".
    """

    size: tuple[int, int] = BASE_SIZE
    gcode_only: bool = False
    jpeg: int = 95
    background_exposure: float = 1.0
    calibration_error: float = 1.0
    image_format: str = "jpg"

    def to_dict(self) -> dict:
        d = asdict(self)
        d["size"] = list(self.size)
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "Conditions":
        d = dict(d)
        d["size"] = tuple(d.get("size", BASE_SIZE))
        return cls(**{k: v for k, v in d.items() if k in cls.__dataclass_fields__})


@dataclass
class Spec:
    name: str
    kind: str
    part: str
    look: str
    rig: str
    seed: int


def plan_specs(counts: dict[str, int], holdout: int = 0,
               parts: tuple[str, ...] | list[str] | None = None) -> list[Spec]:
    """A deterministic spread over parts, looks and rigs for each failure kind.

    ``holdout`` > 0 gives a different set (other seeds, so other random looks, calibration errors and
    noise, and other part/look/rig combinations) to check that a change does not only fit the default set.
    ``parts`` replaces the benchmark's parts: library names (any of the simulator's, e.g. the hold-out
    shapes ``cup``, ``pin``, ``tiers``, ``hexnut``, ``thin_wall``, ``cone``), paths of G-code (the part is
    rebuilt from its toolpaths, e.g. another slicer's output) or mesh files.
    """
    parts = tuple(parts) if parts else PARTS
    specs = []
    for k, (kind, n) in enumerate(counts.items()):
        for i in range(n):
            j = i + 3 * k + 5 * holdout
            part = parts[j % len(parts)]
            label = Path(part).stem if part not in PARTS else part
            look = LOOKS[(i + k + 3 * holdout) % len(LOOKS)]
            rig = RIGS[(i + 2 * k + holdout) % len(RIGS)]
            seed = 1000 + 37 * k + i + 7919 * holdout
            specs.append(Spec(f"{kind}_{i:02d}_{label}_{look}_{rig}", kind, part, look, rig, seed))
    return specs


def _resized_camera(camera, width: int, height: int):
    """The same lens and pose on a ``width`` x ``height`` sensor: the horizontal field of view is kept
    (focal length and principal point scale with width / 640; a 16:9 frame sees less vertically)."""
    from octoprint_printwatch.core.camera import Camera

    s = width / BASE_SIZE[0]
    K = camera.K.copy()
    K[0, 0] *= s
    K[1, 1] *= s
    K[0, 2] = width / 2.0 + (K[0, 2] - BASE_SIZE[0] / 2.0) * s
    K[1, 2] = height / 2.0 + (K[1, 2] - BASE_SIZE[1] / 2.0) * s
    return Camera(camera.name, width, height, K, camera.dist.copy(), camera.rvec.copy(), camera.tvec.copy())


def make_scene(spec: Spec, conditions: Conditions = Conditions()):
    """The simulator for one recording under ``conditions`` (same scene, same seeds, whatever the conditions)."""
    from octoprint_printwatch.simulator.look import PRESETS, random_look
    from octoprint_printwatch.simulator.rig import make_rig, miscalibrate
    from octoprint_printwatch.simulator.scenario import Scenario
    from octoprint_printwatch.simulator.scene import PrintSimulator

    rig = make_rig(spec.rig, n_cameras=3 if spec.rig == "ring" else None, seed=spec.seed)
    if conditions.calibration_error != 1.0:
        # make_rig's own calibration generator, with scaled error magnitudes
        calib_rng = np.random.default_rng([spec.seed, 0xCA1])
        k = conditions.calibration_error
        rig.cameras_calibrated = [miscalibrate(c, calib_rng, focal_pct=1.0 * k, rotation_deg=0.5 * k,
                                               position_mm=1.0 * k) for c in rig.cameras_true]
    look = random_look(spec.seed, rig.bed) if spec.look == "random" else PRESETS[spec.look]
    if tuple(conditions.size) != BASE_SIZE:
        width, height = conditions.size
        rig.cameras_true = [_resized_camera(c, width, height) for c in rig.cameras_true]
        rig.cameras_calibrated = [_resized_camera(c, width, height) for c in rig.cameras_calibrated]
        s = width / BASE_SIZE[0]
        nz = look.nuisances
        look = replace(look, nuisances=replace(nz, blur=nz.blur * s, shake_px=nz.shake_px * s))

    class Simulator(PrintSimulator):
        def background(self, camera_name):
            if conditions.background_exposure == 1.0:
                return super().background(camera_name)
            # PrintSimulator.background with the exposure changed (exposure drift on in every look used here)
            from octoprint_printwatch.simulator.scene import _hash_seed
            from octoprint_printwatch.simulator.webcam import draw_hotend

            view = self._view(camera_name)
            rng = np.random.default_rng(_hash_seed(self.seed, camera_name, "background"))
            linear = view.static.copy()
            if rng.random() < self.look.nuisances.hotend_probability:
                draw_hotend(linear, rng)
            return self._finish(view, linear, rng, float(conditions.background_exposure))

    return Simulator(spec.part, rig, look, Scenario(spec.kind), seed=spec.seed)


def _drop_model(folder: Path) -> None:
    """Make a recording G-code only: no model file, no ``model`` key."""
    session = folder / "session.json"
    doc = json.loads(session.read_text())
    model = doc.pop("model", None)
    if model:
        (folder / model).unlink(missing_ok=True)
    session.write_text(json.dumps(doc, indent=1))


def generate(spec: Spec, out: Path, conditions: Conditions = Conditions()) -> Path:
    """Render one recording (skipped when it is already there)."""
    folder = out / spec.name
    if (folder / "truth.json").exists():
        return folder
    from octoprint_printwatch.simulator.recording import write_recording

    sim = make_scene(spec, conditions)
    tmp = out / (spec.name + ".partial")
    if tmp.exists():
        import shutil

        shutil.rmtree(tmp)
    write_recording(tmp, sim, image_format=conditions.image_format, jpeg_quality=conditions.jpeg)
    if conditions.gcode_only:
        _drop_model(tmp)
    tmp.rename(folder)
    return folder


def _parse_size(text: str) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1280x720") from None
    if not (16 <= width <= 8192 and 16 <= height <= 8192):
        raise argparse.ArgumentTypeError(f"--size {text!r}: width and height must be 16..8192")
    return width, height


def set_options(data: Path, conditions: Conditions, holdout: int, counts: dict[str, int] | None,
                parts: list[str] | None = None) -> dict:
    """The folder's stored options, written on first use; a folder is never filled under other conditions."""
    path = data / OPTIONS_FILE
    mine = {"conditions": conditions.to_dict(), "holdout": holdout, "counts": counts}
    if parts:
        mine["parts"] = list(parts)
    if path.exists():
        stored = json.loads(path.read_text())
        if stored.get("conditions") != mine["conditions"]:
            raise SystemExit(f"{path}: this folder was rendered with {stored.get('conditions')}, not "
                             f"{mine['conditions']}; use another --data")
        return stored
    if any(data.glob("*/truth.json")) and conditions != Conditions():
        raise SystemExit(f"{data}: holds recordings rendered without {OPTIONS_FILE} (default conditions); "
                         f"use another --data for other conditions")
    path.write_text(json.dumps(mine, indent=1))
    return mine


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
        shape_only, _ = runner.decide_again(size={})
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
    first_camera = next(iter(recording.cameras.values()))
    return {"name": folder.name, "kind": truth["scenario"]["kind"], "part": truth["part"],
            "frame_size": [first_camera.width, first_camera.height], "has_model": recording.model is not None,
            "look": truth["look"], "onset_layer": truth["scenario"]["onset_layer"],
            "first_flag_layer": truth.get("first_flag_layer"),
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
    sizes = sorted({tuple(r.get("frame_size", BASE_SIZE)) for r in results})
    size_text = ", ".join(f"{w}x{h}" for w, h in sizes)
    lines.append(f"Shape check, median time per check per camera ({size_text}): "
                 f"{statistics.median(secs) * 1000:.1f} ms wall (p90 {pct(secs, 90) * 1000:.1f} ms), "
                 f"{statistics.median(cpu) * 1000:.1f} ms CPU. "
                 f"Whole check (all cameras and pairs): median {statistics.median(whole) * 1000:.0f} ms. "
                 f"Median prepare (expected views) per recording: {statistics.median(prep):.2f} s.")
    return "\n".join(lines)


def details(results: list[dict]) -> str:
    out = ["", "| recording | shape check | combined | seed | first shape fail | onset layer | first flag layer |",
           "|---|---|---|---|---|---|---|"]
    for r in results:
        ours, both, seed = score(r, "shape_verdict"), score(r, "verdict"), score(r, "seed_verdict")

        def word(s):
            if s["false_pause"]:
                return "FALSE PAUSE"
            if s["detected"] is None:
                return "ok" if r["kind"] == "normal" else "n/a"
            return "detected" if s["detected"] else ("late" if s.get("ever") else "MISSED")

        first = next((c["layer"] for c in r["checks"] if c["shape_verdict"] == "fail"), None)
        out.append(f"| {r['name']} | {word(ours)} | {word(both)} | {word(seed)} | {first} | {r['onset_layer']} | "
                   f"{r.get('first_flag_layer')} |")
    return "\n".join(out)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="14 recordings instead of 66")
    parser.add_argument("--data", default="/tmp/printwatch-bench-detection", help="recordings folder (cache)")
    parser.add_argument("--json", help="write per-check results here")
    parser.add_argument("--holdout", type=int, default=None,
                        help="N > 0: a hold-out set with other seeds and combinations (use another --data)")
    parser.add_argument("--counts", help="recordings per kind, e.g. normal=8,runout=4 (instead of the default set)")
    hostile = parser.add_argument_group("conditions (generation; stored in DATA/bench_options.json)")
    hostile.add_argument("--size", type=_parse_size, default=BASE_SIZE,
                         help="frame size WIDTHxHEIGHT (default 640x480); the field of view scales with the width")
    hostile.add_argument("--gcode-only", action="store_true", help="ship print.gcode only, no model")
    hostile.add_argument("--jpeg", type=int, default=95, help="JPEG quality of the stored frames (default 95)")
    hostile.add_argument("--background-exposure", type=float, default=1.0,
                         help="exposure of the empty-bed frame relative to the checks' (default 1)")
    hostile.add_argument("--calibration-error", type=float, default=1.0,
                         help="scale of the calibration error (default 1: 1 %% focal, 0.5 deg, 1 mm)")
    hostile.add_argument("--format", choices=("jpg", "png"), default="jpg", help="stored image format")
    parser.add_argument("--parts", help="comma-separated parts instead of the library's: names, or G-code/mesh "
                                        "paths (e.g. another slicer's G-code)")
    parser.add_argument("--only", help="only recordings whose name contains this")
    parser.add_argument("--details", action="store_true", help="also list every recording's outcome")
    parser.add_argument("--generate-only", action="store_true", help="only render the recordings (cache)")
    parser.add_argument("--cached-only", action="store_true", help="only evaluate recordings already rendered")
    args = parser.parse_args(argv)
    data = Path(args.data)
    data.mkdir(parents=True, exist_ok=True)
    if not 1 <= args.jpeg <= 100:
        parser.error(f"--jpeg {args.jpeg}: quality must be 1..100")
    if args.background_exposure <= 0 or args.calibration_error < 0:
        parser.error("--background-exposure must be > 0 and --calibration-error >= 0")
    conditions = Conditions(size=tuple(args.size), gcode_only=args.gcode_only, jpeg=args.jpeg,
                            background_exposure=args.background_exposure,
                            calibration_error=args.calibration_error, image_format=args.format)
    counts = QUICK if args.quick else KINDS
    if args.counts:
        counts = {kind: int(n) for kind, n in (item.split("=") for item in args.counts.split(","))}
    stored_path = data / OPTIONS_FILE
    if args.cached_only and stored_path.exists():
        # evaluating a set: its own holdout and counts unless given; conditions do not matter to evaluation
        stored = json.loads(stored_path.read_text())
        if args.holdout is None:
            args.holdout = stored.get("holdout") or 0
        if not args.counts and not args.quick and stored.get("counts"):
            counts = stored["counts"]
        if not args.parts and stored.get("parts"):
            args.parts = ",".join(stored["parts"])
    parts = None
    if args.parts:
        from octoprint_printwatch.simulator.parts import LIBRARY_PARTS

        parts = [p.strip() for p in args.parts.split(",") if p.strip()]
        for part in parts:
            if part not in LIBRARY_PARTS and not args.cached_only and not Path(part).is_file():
                parser.error(f"--parts: {part}: neither a library part ({', '.join(LIBRARY_PARTS)}) nor a file")
        parts = [p if p in LIBRARY_PARTS or args.cached_only else str(Path(p).resolve()) for p in parts]
    if not args.cached_only:
        set_options(data, conditions, args.holdout or 0, counts if (args.counts or args.quick) else None, parts)
    holdout = args.holdout or 0
    specs = plan_specs(counts, holdout, parts)
    if args.only:
        specs = [s for s in specs if args.only in s.name]
    if args.cached_only:
        specs = [s for s in specs if (data / s.name / "truth.json").exists()]
    settings = DetectionSettings()
    results = []
    started = time.perf_counter()
    for i, spec in enumerate(specs):
        t0 = time.perf_counter()
        folder = generate(spec, data, conditions)
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
