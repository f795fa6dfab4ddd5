"""Runs every benchmark in ``benchmarks/`` and writes one report: ``docs/benchmarks.md`` + ``docs/img/bench_*.png``.

    .venv/bin/python benchmarks/run_all.py            # everything (the detection benchmark alone takes long)
    .venv/bin/python benchmarks/run_all.py --quick    # each script's short mode (about 15 minutes)
    .venv/bin/python benchmarks/run_all.py --only detection,plugin

Each script runs in its own process (its figures are its own: memory, timing);
its Markdown output goes into the report verbatim, under its command line. A
script that is missing, fails or times out is reported as "not run" with the
reason; the others still run. The headline table and the plots put each figure
beside the dissertation's published one and, where the scripts measure it,
beside the seed's own rules run on the same simulated frames (the detection and
stereo benchmarks replay the seed's grey-difference shape check and its SAD
block matching). Plots are drawn with OpenCV (no plotting library needed).
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"

#: The dissertation's published figures (docs/seed-summary.md), quoted beside ours.
SEED = {
    "shape_normal": (0.7, 6.7),          # % shape error of normal prints (App. B)
    "shape_failing": (7.6, 19.7),        # % shape error of failed prints
    "shape_threshold": 7.0,              # % (webcams, ch. 4)
    "shape_seconds_3_views": (6.6, 10.0),  # s for 3 views on a Raspberry Pi 3
    "pair_seconds": (45.0, 100.0),       # s per stereo pair on a Raspberry Pi 3 (45 average)
    "dwell_seconds": 30.0,               # G4 P30000 per check block
    "size_error": (0.07, 3.94),          # % width/height error on six parts (ch. 3)
    "size_threshold": 10.0,
    "detection": 1.0,                    # 100 % of the failures on its test parts
}


@dataclass
class Bench:
    """One benchmark script and how to run it."""

    key: str
    script: str
    full: list = field(default_factory=list)
    quick: list = field(default_factory=list)
    json_arg: bool = False  # accepts --json PATH (per-check results for the headline and plots)
    title: str = ""


KNOWN = [
    Bench("detection", "bench_detection.py", [], ["--quick"], True,
          "Detection per failure kind, false pauses, shape errors (PrintWatch vs the seed's rule)"),
    Bench("stereo", "bench_stereo.py", [], ["--quick"], True,
          "Size check: width/height errors and time per stereo pair (PrintWatch vs the seed's SAD)"),
    Bench("background", "bench_background.py", [], ["--limit", "4"], False, "Background removal"),
    Bench("plugin", "bench_plugin.py", [], [], False,
          "Added print time per check and API latency on a real OctoPrint"),
    Bench("gcode", "bench_gcode.py", [], ["--size-mb", "10", "--repeat", "1"], False,
          "G-code injection throughput and peak memory"),
    Bench("prepare", "bench_prepare.py", [], ["--parts", "cube"], False,
          "Preparation per job: time and peak memory (injection + expected views, 6 cameras)"),
    Bench("render", "bench_render.py", [], ["--quick"], False, "Preparation: G-code solids and expected views"),
    Bench("simulator", "bench_simulator.py", [], ["--repeat", "1"], False, "Print simulator speed"),
    Bench("calibration", "calibration_accuracy.py", [], [], False, "Calibration accuracy"),
    # a second, independent simulator (docs/crosscheck.md); recordings are generated once and reused
    Bench("crosscheck", "bench_crosscheck.py",
          ["--out", "/tmp/printwatch-crosscheck-seed1", "--count", "60", "--seed", "1", "--jobs", "2"],
          ["--out", "/tmp/printwatch-crosscheck-quick", "--count", "10", "--seed", "1", "--jobs", "2"], False,
          "Second simulator (cross-check)"),
    Bench("perturb", "bench_perturb.py", ["--phase", "pre"],
          ["--phase", "pre", "--only", "normal_0", "--perturb", "jpeg35,cast"], False,
          "Perturbed recordings (webcam and rendering differences)"),
]


def discover() -> list[Bench]:
    """The known scripts (in a useful order: background reuses detection's recordings), then any new one."""
    known = {b.script for b in KNOWN}
    extra = []
    for path in sorted(BENCH.glob("*.py")):
        if path.name in known or path.name == Path(__file__).name or path.name.startswith("_"):
            continue
        quick = ["--quick"] if "--quick" in path.read_text(errors="replace") else []
        extra.append(Bench(path.stem.removeprefix("bench_"), path.name, [], quick, False, path.stem))
    return KNOWN + extra


@dataclass
class Run:
    bench: Bench
    command: list[str]
    status: str                # "ok" | "not run: <why>"
    seconds: float = 0.0
    stdout: str = ""
    json: object = None
    when: str = ""             # UTC time the script ran
    earlier: bool = False      # loaded from an earlier run (--only ran other scripts)

    def save(self, folder: Path) -> None:
        folder.mkdir(parents=True, exist_ok=True)
        doc = {"command": self.command, "status": self.status, "seconds": self.seconds, "stdout": self.stdout,
               "json": self.json, "when": self.when}
        (folder / f"{self.bench.key}.json").write_text(json.dumps(doc))

    @classmethod
    def load(cls, bench: Bench, folder: Path) -> "Run | None":
        path = folder / f"{bench.key}.json"
        if not path.exists():
            return None
        try:
            doc = json.loads(path.read_text())
            return cls(bench, doc["command"], doc["status"], doc["seconds"], doc["stdout"], doc["json"],
                       doc.get("when", ""), earlier=True)
        except (ValueError, KeyError):
            return None


def now_utc() -> str:
    return time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())


def run_bench(bench: Bench, quick: bool, workdir: Path, timeout: float) -> Run:
    path = BENCH / bench.script
    args = list(bench.quick if quick else bench.full)
    json_path = workdir / f"{bench.key}.json"
    if bench.json_arg:
        args += ["--json", str(json_path)]
    command = [sys.executable, str(path.relative_to(ROOT)), *args]
    shown = ["python", f"benchmarks/{bench.script}", *[a for a in args if a != str(json_path)]]
    if bench.json_arg:
        shown = shown[:-1] if shown[-1] == "--json" else shown
    if not path.exists():
        return Run(bench, shown, "not run: the script does not exist yet")
    print(f"[run_all] {' '.join(shown)} ...", file=sys.stderr, flush=True)
    started = time.perf_counter()
    try:
        done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=timeout,
                              env={**os.environ, "PYTHONUNBUFFERED": "1"})
    except subprocess.TimeoutExpired:
        return Run(bench, shown, f"not run: did not finish within {timeout:.0f} s", time.perf_counter() - started)
    seconds = time.perf_counter() - started
    if done.returncode != 0:
        last = (done.stderr.strip().splitlines() or ["(no error output)"])[-1]
        return Run(bench, shown, f"not run: exited with status {done.returncode}: {last[:300]}", seconds,
                   done.stdout)
    data = None
    if bench.json_arg and json_path.exists():
        data = json.loads(json_path.read_text())
    print(f"[run_all]   done in {seconds:.0f} s", file=sys.stderr, flush=True)
    return Run(bench, shown, "ok", seconds, done.stdout, data, now_utc())


# ---------------------------------------------------------------------------- parsing the scripts' output
def markdown_rows(text: str) -> list[list[str]]:
    """Every Markdown table row in ``text`` as its cells (separator rows dropped)."""
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line.startswith("|") and line.endswith("|") and not re.fullmatch(r"\|[\s\-:|]+\|", line):
            rows.append([c.strip() for c in line.strip("|").split("|")])
    return rows


def row_with(rows: list[list[str]], *words: str) -> list[str] | None:
    for row in rows:
        label = row[0].lower().replace("*", "")
        if all(w.lower() in label for w in words):
            return row
    return None


def numbers(text: str) -> list[float]:
    return [float(x) for x in re.findall(r"-?\d+(?:\.\d+)?", text or "")]


def plugin_figures(stdout: str) -> dict:
    rows = markdown_rows(stdout)
    out = {}
    added = row_with(rows, "added print time per check")
    if added and numbers(added[1]):
        out["added_s"] = numbers(added[1])[0]
    real = row_with(rows, "estimated added time per check")
    if real and numbers(real[1]):
        out["real_printer_s"] = numbers(real[1])[0]
    held = row_with(rows, "job held per check")
    if held and numbers(held[1]):
        out["hold_s"] = numbers(held[1])[0]
    for key, words in (("job", ("/api/job",)), ("status", ("printwatch/status",))):
        row = row_with(rows, *words)
        if row and len(row) >= 3 and len(numbers(row[1])) >= 3:
            out[f"latency_{key}_during_ms"] = numbers(row[1])[:3]
    return out


def gcode_figures(stdout: str) -> list[dict]:
    """bench_gcode's rows: label, MB, wall and CPU MB/s, peak RSS growth (its Markdown table, or the older
    fixed-width one: label, MB, layers, checks, wall s, MB/s, cpu MB/s, RSS, traced)."""
    rows = []
    table = [r for r in markdown_rows(stdout)]
    header = next((r for r in table if any("mb/s" in c.lower() for c in r)), None)
    if header:
        lower = [c.lower() for c in header]

        def col(*words):
            return next((i for i, c in enumerate(lower) if all(w in c for w in words)), None)

        size, wall, cpu, rss = col("size"), col("mb/s", "wall"), col("mb/s", "cpu"), col("rss")
        for row in table[table.index(header) + 1:]:
            try:
                rows.append({"label": row[0], "mb": float(row[size]), "wall_mbps": float(row[wall]),
                             "cpu_mbps": float(row[cpu]), "rss_mb": float(row[rss])})
            except (TypeError, ValueError, IndexError):
                continue
        return rows
    for line in stdout.splitlines():
        tokens = line.split()
        if len(tokens) < 9 or line.startswith(("#", "file")):
            continue
        try:
            values = [float(t) for t in tokens[-8:]]
        except ValueError:
            continue
        rows.append({"label": " ".join(tokens[:-8]), "mb": values[0], "wall_mbps": values[4],
                     "cpu_mbps": values[5], "rss_mb": values[6]})
    return rows


# ---------------------------------------------------------------------------- figures from the JSON results
def _load_module(name: str):
    path = BENCH / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"_bench_{name}", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while the class is built
    spec.loader.exec_module(module)
    return module


def pct(values, q) -> float:
    return float(np.percentile(values, q)) if len(values) else float("nan")


def detection_figures(results: list[dict]) -> dict:
    """Detection and false pauses per rule and kind (scored the way bench_detection scores), errors, times."""
    score = _load_module("bench_detection").score
    rules = {"ours": "verdict", "ours_shape": "shape_verdict", "seed": "seed_verdict"}
    kinds = sorted({r["kind"] for r in results if r["kind"] != "normal"})
    out = {"kinds": kinds, "rules": {}}
    for rule, key in rules.items():
        per_kind = {}
        for kind in kinds:
            scores = [score(r, key) for r in results if r["kind"] == kind]
            valid = [s for s in scores if s["detected"] is not None]
            per_kind[kind] = (sum(1 for s in valid if s["detected"] and not s["false_pause"]), len(valid))
        normals = [score(r, key) for r in results if r["kind"] == "normal"]
        per_kind["normal"] = (sum(s["false_pause"] for s in normals), len(normals))
        out["rules"][rule] = per_kind
    checks = [c for r in results for c in r["checks"]]
    out["errors"] = {
        ("ours", "normal"): [v for c in checks if not c["started"] for v in c["errors"].values()],
        ("ours", "failing"): [v for c in checks if c["should_flag"] for v in c["errors"].values()],
        ("seed", "normal"): [v for c in checks if not c["started"] for v in c["seed_errors"].values()],
        ("seed", "failing"): [v for c in checks if c["should_flag"] for v in c["seed_errors"].values()],
    }
    out["seconds_per_camera"] = [c["seconds_per_camera"] for c in checks]
    out["check_seconds"] = [c["seconds"] for c in checks]
    out["prepare_seconds"] = [r["prepare_seconds"] for r in results]
    out["recordings"] = len(results)
    return out


STEREO_OURS = "calibrated / planes (default)"
STEREO_SEED = "seed rescale+shift / dense SAD 67"
STEREO_SEED_CALIBRATED = "calibrated / dense SAD 67 (seed)"


def stereo_figures(results: list[dict]) -> dict:
    variants = {}
    names = list(results[0]["checks"][0]["sizes"]) if results and results[0]["checks"] else []
    for name in names:
        widths, heights, seconds, abstained, total = [], [], [], 0, 0
        for rec in results:
            for c in rec["checks"]:
                for entry in c["sizes"].get(name, {}).values():
                    total += 1
                    seconds.append(entry["seconds"])
                    if entry.get("abstained"):
                        abstained += 1
                    elif rec["kind"] == "normal":
                        if entry.get("width_error_pct") is not None:
                            widths.append(abs(entry["width_error_pct"]))
                        if entry.get("height_error_pct") is not None:
                            heights.append(abs(entry["height_error_pct"]))
        variants[name] = {"width": widths, "height": heights, "seconds": seconds,
                          "abstained": abstained, "total": total}
    return variants


# ---------------------------------------------------------------------------- plots (OpenCV)
WHITE, BLACK, GREY, LIGHT = (255, 255, 255), (40, 40, 40), (150, 150, 150), (225, 225, 225)
BLUE, ORANGE, GREEN, RED, PURPLE = (180, 110, 30), (20, 130, 240), (60, 160, 60), (50, 50, 210), (160, 80, 150)
SEED_BAND = (200, 225, 250)
FONT = cv2.FONT_HERSHEY_SIMPLEX


class Plot:
    """A small chart on a white canvas: categorical x slots, linear or log y."""

    def __init__(self, title: str, ylabel: str, lo: float, hi: float, *, log: bool = False,
                 size=(1000, 560), margins=(90, 60, 30, 110)) -> None:
        self.w, self.h = size
        self.left, self.top, self.right, self.bottom = margins
        self.lo, self.hi, self.log = lo, hi, log
        self.clip: float | None = None  # values above it are counted ("N above"), not drawn
        self.img = np.full((self.h, self.w, 3), 255, np.uint8)
        self.text(title, (self.left, 32), 0.62, BLACK, 2)
        self.ylabel = ylabel

    # geometry
    def y(self, value: float) -> int:
        value = min(max(value, self.lo), self.hi)
        if self.log:
            t = (np.log10(value) - np.log10(self.lo)) / (np.log10(self.hi) - np.log10(self.lo))
        else:
            t = (value - self.lo) / (self.hi - self.lo)
        return int(round(self.h - self.bottom - t * (self.h - self.bottom - self.top)))

    def x(self, slot: float, slots: int) -> int:
        width = self.w - self.left - self.right
        return int(round(self.left + (slot + 0.5) * width / slots))

    def text(self, text, org, scale=0.45, color=BLACK, thickness=1, anchor="left") -> None:
        (tw, th), _ = cv2.getTextSize(text, FONT, scale, thickness)
        x, y = org
        if anchor == "center":
            x -= tw // 2
        elif anchor == "right":
            x -= tw
        cv2.putText(self.img, text, (int(x), int(y)), FONT, scale, color, thickness, cv2.LINE_AA)

    def axes(self, ticks) -> None:
        x0, x1 = self.left, self.w - self.right
        for t in ticks:
            yy = self.y(t)
            cv2.line(self.img, (x0, yy), (x1, yy), LIGHT, 1)
            self.text(f"{t:g}", (x0 - 8, yy + 5), 0.42, GREY, anchor="right")
        cv2.line(self.img, (x0, self.top), (x0, self.h - self.bottom), BLACK, 1)
        cv2.line(self.img, (x0, self.h - self.bottom), (x1, self.h - self.bottom), BLACK, 1)
        self.text(self.ylabel, (8, self.top - 12), 0.45, BLACK)

    def band(self, x0: int, x1: int, v0: float, v1: float, color=SEED_BAND) -> None:
        top, bottom = self.y(v1), self.y(v0)
        if bottom - top < 6:  # a single published value: a visible bar, not a hairline
            top, bottom = (top + bottom) // 2 - 3, (top + bottom) // 2 + 3
        cv2.rectangle(self.img, (x0, top), (x1, bottom), color, -1)

    def hline(self, value: float, color, label: str = "", dashed: bool = True, label_dy: int = 6) -> None:
        yy = self.y(value)
        x0, x1 = self.left, self.w - self.right
        if dashed:
            for xx in range(x0, x1, 14):
                cv2.line(self.img, (xx, yy), (min(xx + 8, x1), yy), color, 2)
        else:
            cv2.line(self.img, (x0, yy), (x1, yy), color, 2)
        if label:
            self.text(label, (x1 - 4, yy - label_dy), 0.42, color, anchor="right")

    def strip(self, cx: int, values, color, half_width: int = 28, seed: int = 0) -> None:
        """Dots (jittered), the p10-p90 box and the median; values above the range drawn as triangles."""
        values = [v for v in values if v is not None and np.isfinite(v)]
        if not values:
            self.text("no data", (cx, self.y(self.lo) - 8), 0.4, GREY, anchor="center")
            return
        rng = np.random.default_rng(seed)
        limit = self.clip if self.clip is not None else self.hi
        over = 0
        for v in values:
            if v > limit:
                over += 1
                continue
            xx = int(cx + rng.uniform(-half_width, half_width))
            cv2.circle(self.img, (xx, self.y(v)), 2, color, -1, cv2.LINE_AA)
        p10, p50, p90 = pct(values, 10), pct(values, 50), pct(values, 90)
        cv2.rectangle(self.img, (cx - half_width - 4, self.y(min(p90, limit))), (cx + half_width + 4, self.y(min(p10, limit))),
                      color, 1)
        cv2.line(self.img, (cx - half_width - 8, self.y(min(p50, limit))), (cx + half_width + 8, self.y(min(p50, limit))),
                 color, 3)
        if over:
            top = self.y(limit)
            pts = np.array([[cx - 6, top + 10], [cx + 6, top + 10], [cx, top]], np.int32)
            cv2.fillPoly(self.img, [pts], color)
            self.text(f"{over} above", (cx, top - 4), 0.38, color, anchor="center")

    def bar(self, x0: int, x1: int, value: float, color, label: str = "") -> None:
        base = self.y(self.lo)
        cv2.rectangle(self.img, (x0, self.y(value)), (x1, base), color, -1)
        if label:
            self.text(label, ((x0 + x1) // 2, self.y(value) - 6), 0.38, BLACK, anchor="center")

    def xlabel(self, cx: int, lines: list[str], color=BLACK) -> None:
        for i, line in enumerate(lines):
            self.text(line, (cx, self.h - self.bottom + 22 + 18 * i), 0.42, color, anchor="center")

    def legend(self, items, origin=None) -> None:
        x, y = origin or (self.left + 10, self.top + 16)
        for color, label in items:
            cv2.rectangle(self.img, (x, y - 10), (x + 14, y + 2), color, -1)
            self.text(label, (x + 20, y), 0.42, BLACK)
            y += 20

    def save(self, path: Path) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        cv2.imwrite(str(path), self.img)


def plot_shape_errors(det: dict, path: Path) -> None:
    plot = Plot("Shape error per camera and check: PrintWatch vs the seed's rule, same simulated frames",
                "shape error %", 0, 52)  # the band above 40 % holds the legend
    plot.axes([0, 5, 7, 10, 15, 20, 30, 40])
    plot.clip = 40.0
    slots = 6
    groups = (("normal", "normal prints", SEED["shape_normal"]), ("failing", "failing prints (failure due)",
                                                                  SEED["shape_failing"]))
    for g, (kind, label, published) in enumerate(groups):
        base = 3 * g
        for s, (rule, color, name) in enumerate((("ours", BLUE, "PrintWatch"), ("seed", ORANGE, "seed rule"))):
            cx = plot.x(base + s, slots)
            plot.strip(cx, det["errors"][(rule, kind)], color, seed=g * 7 + s)
            plot.xlabel(cx, [name, f"n={len(det['errors'][(rule, kind)])}"])
        cx = plot.x(base + 2, slots)
        plot.band(cx - 30, cx + 30, *published)
        plot.text(f"{published[0]:g}-{published[1]:g} %", (cx, plot.y(published[1]) - 6), 0.4, BLACK, anchor="center")
        plot.xlabel(cx, ["seed published", "(App. B)"])
        plot.text(label, (plot.x(base + 1, slots), plot.h - 30), 0.5, BLACK, 2, anchor="center")
    plot.hline(SEED["shape_threshold"], RED, "threshold 7 % (seed, and PrintWatch's default)")
    plot.legend([(BLUE, "PrintWatch: dots, p10-p90 box, median bar"), (ORANGE, "seed's rule (grey difference, "
                 "bbox rescale, Eq. 4.1) on the same frames"), (SEED_BAND, "range the dissertation published")],
                origin=(plot.left + 140, plot.y(49)))
    plot.save(path)


def plot_detection(det: dict, path: Path) -> None:
    kinds = det["kinds"] + ["normal"]
    plot = Plot("Failures detected within one check, and normal prints paused (lower is better)", "% of prints",
                0, 145)
    plot.axes([0, 20, 40, 60, 80, 100])
    rules = (("ours", BLUE, "PrintWatch (shape, then stereo size)"), ("ours_shape", GREEN, "PrintWatch shape only"),
             ("seed", ORANGE, "seed's rule, same frames"))
    slots = len(kinds)
    for k, kind in enumerate(kinds):
        cx = plot.x(k, slots)
        width = int((plot.w - plot.left - plot.right) / slots / 4.5)
        for r, (rule, color, _) in enumerate(rules):
            hit, n = det["rules"][rule][kind]
            value = 100.0 * hit / n if n else 0.0
            x0 = cx + (r - 1.5) * width
            plot.bar(int(x0), int(x0 + width - 3), value, color, f"{hit}/{n}")
        plot.xlabel(cx, [kind.replace("_", " "), "(paused)" if kind == "normal" else "(detected)"])
    plot.hline(100 * SEED["detection"], RED, "seed published: 100 % of its failures detected", label_dy=26)
    plot.legend([(c, n) for _, c, n in rules], origin=(plot.left + 10, plot.top + 12))
    plot.save(path)


def plot_size_errors(stereo: dict, path: Path) -> None:
    names = [n for n in (STEREO_OURS, "calibrated / dense SGBM", STEREO_SEED_CALIBRATED, STEREO_SEED) if n in stereo]
    plot = Plot("Size check on normal prints: width and height error per pair and check", "error %", 0, 30)
    plot.axes([0, 4, 10, 15, 20, 30])
    slots = len(names) + 1
    for i, name in enumerate(names):
        cx = plot.x(i, slots)
        plot.strip(cx - 22, stereo[name]["width"], BLUE, half_width=14, seed=i)
        plot.strip(cx + 22, stereo[name]["height"], PURPLE, half_width=14, seed=i + 50)
        words = name.split(" / ")
        plot.xlabel(cx, words + [f"abstained {stereo[name]['abstained']}/{stereo[name]['total']}"])
    cx = plot.x(len(names), slots)
    plot.band(cx - 30, cx + 30, *SEED["size_error"])
    plot.text("0.07-3.94 %", (cx, plot.y(SEED["size_error"][1]) - 6), 0.4, BLACK, anchor="center")
    plot.xlabel(cx, ["seed published", "(ch. 3, six parts)"])
    plot.hline(SEED["size_threshold"], RED, "threshold 10 %")
    plot.legend([(BLUE, "width error"), (PURPLE, "height error"), (SEED_BAND, "range the dissertation published")],
                origin=(plot.w - 300, plot.top + 8))
    plot.save(path)


def plot_timing(rows: list[tuple[str, float | None, tuple | None, str]], path: Path) -> None:
    """rows: (label, ours seconds or None, seed (lo, hi) or None, note)."""
    plot = Plot("Time per step (log scale): PrintWatch on this machine vs the seed on a Raspberry Pi 3",
                "seconds", 0.01, 300, log=True, size=(1000, 560), margins=(90, 60, 30, 120))
    plot.axes([0.01, 0.1, 1, 10, 100])
    slots = len(rows)
    for i, (label, ours, seed, note) in enumerate(rows):
        cx = plot.x(i, slots)
        if ours is not None:
            plot.bar(cx - 34, cx - 4, ours, BLUE, f"{ours:.2g}")
        else:
            plot.text("not run", (cx - 19, plot.y(0.01) - 8), 0.38, GREY, anchor="center")
        if seed is not None:
            plot.band(cx + 4, cx + 34, seed[0], seed[1], SEED_BAND)
            short = lambda v: f"{v:.2g}" if v < 10 else f"{v:.0f}"  # noqa: E731
            text = short(seed[0]) if seed[0] == seed[1] else f"{short(seed[0])}-{short(seed[1])}"
            plot.text(text, (cx + 19, plot.y(seed[1]) - 6), 0.38, BLACK, anchor="center")
        plot.xlabel(cx, label.split("\n") + ([note] if note else []))
    plot.legend([(BLUE, "PrintWatch (median, this machine)"), (SEED_BAND, "seed published (Raspberry Pi 3)")],
                origin=(plot.w - 330, plot.top + 8))
    plot.save(path)


# ---------------------------------------------------------------------------- the report
def fmt_frac(hit_n) -> str:
    hit, n = hit_n
    return f"{hit}/{n} ({100.0 * hit / n:.0f} %)" if n else "n/a"


def fmt_dist(values, qs=(50, 90)) -> str:
    if not values:
        return "n/a"
    return " / ".join(f"{pct(values, q):.1f}" for q in qs) + " %"


def headline(runs: dict[str, Run], det: dict | None, stereo: dict | None) -> list[str]:
    lines = ["| figure | PrintWatch (this run) | seed's rules on the same data | seed published (dissertation) |",
             "|---|---|---|---|"]
    if det:
        total = lambda rule: tuple(map(sum, zip(*[det["rules"][rule][k] for k in det["kinds"]])))  # noqa: E731
        lines.append(f"| failures detected within one check ({det['recordings'] - det['rules']['ours']['normal'][1]}"
                     f" simulated failing prints, {', '.join(det['kinds'])}) | {fmt_frac(total('ours'))} | "
                     f"{fmt_frac(total('seed'))} | 100 % (clog, runout, incomplete print on its parts) |")
        lines.append(f"| normal prints paused (false pauses) | {fmt_frac(det['rules']['ours']['normal'])} | "
                     f"{fmt_frac(det['rules']['seed']['normal'])} | none reported |")
        lines.append(f"| shape error, normal prints: median / p90 | {fmt_dist(det['errors'][('ours', 'normal')])} | "
                     f"{fmt_dist(det['errors'][('seed', 'normal')])} | 0.7-6.7 % (threshold 7 %) |")
        lines.append(f"| shape error, failing prints (failure due): p10 / median | "
                     f"{fmt_dist(det['errors'][('ours', 'failing')], (10, 50))} | "
                     f"{fmt_dist(det['errors'][('seed', 'failing')], (10, 50))} | 7.6-19.7 % |")
    else:
        lines.append("| detection, false pauses, shape errors | not run | not run | 100 %; 0.7-6.7 % / 7.6-19.7 % |")
    if stereo and STEREO_OURS in stereo:
        ours, seed = stereo[STEREO_OURS], stereo.get(STEREO_SEED)
        both = lambda v: fmt_dist(v["width"] + v["height"]) if v else "n/a"  # noqa: E731
        count = lambda v: len(v["width"]) + len(v["height"]) if v else 0  # noqa: E731
        lines.append(f"| size check width/height error, normal prints: median / p90 | {both(ours)} "
                     f"(n={count(ours)}) | {both(seed)} (SAD 67 px, rescale + shift; n={count(seed)}, "
                     f"abstained {seed['abstained'] if seed else 0}/{seed['total'] if seed else 0}) | 0.07-3.94 % |")
    else:
        lines.append("| size check width/height error | not run | not run | 0.07-3.94 % |")
    if det:
        per_cam = statistics.median(det["seconds_per_camera"])
        lines.append(f"| shape check time per camera view (640x480) | {per_cam * 1000:.0f} ms | - | "
                     f"2.2-3.3 s (6.6-10 s for 3 views, Raspberry Pi 3) |")
    if stereo and STEREO_OURS in stereo and stereo[STEREO_OURS]["seconds"]:
        seed_s = stereo.get(STEREO_SEED, {}).get("seconds") or []
        lines.append(f"| size check time per stereo pair | {statistics.median(stereo[STEREO_OURS]['seconds']):.2f} s | "
                     + (f"{statistics.median(seed_s):.2f} s" if seed_s else "n/a")
                     + " | 45 s average, up to 100 s (Raspberry Pi 3) |")
    if det:
        lines.append(f"| preparation per job (expected views of every camera and check) | "
                     f"{statistics.median(det['prepare_seconds']):.1f} s median | - | by hand (Slic3r + plots; "
                     f"failed on some meshes) |")
    plugin = plugin_figures(runs["plugin"].stdout) if runs.get("plugin") and runs["plugin"].status == "ok" else {}
    if plugin.get("added_s") is not None:
        real = f"; about {plugin['real_printer_s']:.1f} s on a real printer" if "real_printer_s" in plugin else ""
        lines.append(f"| added print time per check | {plugin['added_s']:.2f} s (virtual printer at 10x{real}) | - | "
                     f"30 s dwell + the lift moves |")
    else:
        lines.append("| added print time per check | not run | - | 30 s dwell + the lift moves |")
    if plugin.get("latency_job_during_ms"):
        med, p95, top = plugin["latency_job_during_ms"]
        lines.append(f"| OctoPrint API latency while a check runs (`/api/job`): median / p95 / max | "
                     f"{med:g} / {p95:g} / {top:g} ms | - | (no host integration) |")
    gcode = gcode_figures(runs["gcode"].stdout) if runs.get("gcode") and runs["gcode"].status == "ok" else []
    if gcode:
        big = max(gcode, key=lambda r: r["mb"])
        lines.append(f"| G-code injection throughput / peak memory ({big['mb']:.0f} MB file) | "
                     f"{big['wall_mbps']:.1f} MB/s wall ({big['cpu_mbps']:.1f} MB/s CPU) / +{big['rss_mb']:.1f} MB | "
                     f"- | edited by hand in a text editor |")
    return lines


def machine() -> str:
    model = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{model}, {os.cpu_count()} logical CPUs, Python {platform.python_version()}, {platform.system()}; "
            f"{library_versions()}")


def library_versions() -> str:
    """The versions of the libraries the detector's figures depend on: the same recordings gave other verdicts
    under another OpenCV / NumPy / trimesh (docs/detection-log.md, ninth session)."""
    from importlib.metadata import PackageNotFoundError, version
    found = []
    for name in ("numpy", "opencv-python-headless", "trimesh", "manifold3d", "scipy"):
        try:
            found.append(f"{name} {version(name)}")
        except PackageNotFoundError:
            found.append(f"{name} not installed")
    return ", ".join(found)


def git_commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True, text=True,
                              timeout=10).stdout.strip() or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def section(run: Run) -> list[str]:
    out = [f"### {run.bench.title or run.bench.key}", "",
           f"`{' '.join(run.command)}` - " + (f"{run.seconds:.0f} s" if run.status == "ok" else f"**{run.status}**")
           + (f" (kept from an earlier run, {run.when})" if run.earlier else ""), ""]
    if run.stdout.strip():
        text = run.stdout.strip()
        if markdown_rows(text):
            # headings inside a script's output would break the report's outline: bold lines instead;
            # and a table needs a blank line before it to render as one
            kept: list[str] = []
            for line in text.splitlines():
                line = f"**{line.lstrip('#').strip()}**" if line.startswith("#") else line
                if line.startswith("|") and kept and kept[-1].strip() and not kept[-1].startswith("|"):
                    kept.append("")
                kept.append(line)
            out.append("\n".join(kept))
        else:
            out += ["```text", text, "```"]
        out.append("")
    return out


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="each script's short mode")
    parser.add_argument("--only", help="comma-separated keys: " + ", ".join(b.key for b in KNOWN))
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "benchmarks.md")
    parser.add_argument("--img", type=Path, default=ROOT / "docs" / "img")
    parser.add_argument("--timeout", type=float, default=None, help="seconds per script (default 900 quick, 7200)")
    parser.add_argument("--report-only", action="store_true",
                        help="run nothing: rebuild the report from the kept results")
    parser.add_argument("--results", type=Path, default=Path(tempfile.gettempdir()) / "printwatch-bench-runs",
                        help="each script's last successful output is kept here; with --only, the others' "
                             "last outputs fill the rest of the report")
    args = parser.parse_args(argv)
    timeout = args.timeout or (900.0 if args.quick else 7200.0)
    benches = discover()
    every = list(benches)
    if args.only:
        wanted = {k.strip() for k in args.only.split(",") if k.strip()}
        unknown = wanted - {b.key for b in benches}
        if unknown:
            print(f"run_all: error: --only {','.join(sorted(unknown))}: no such benchmark; "
                  f"choose from {', '.join(b.key for b in benches)}", file=sys.stderr)
            return 2
        benches = [b for b in benches if b.key in wanted]
    if args.report_only:
        benches = []

    load_before = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    started = time.perf_counter()
    runs: dict[str, Run] = {}
    with tempfile.TemporaryDirectory(prefix="printwatch-bench-all-") as tmp:
        for bench in every:
            if bench in benches:
                runs[bench.key] = run_bench(bench, args.quick, Path(tmp), timeout)
                if runs[bench.key].status == "ok":  # a failed run never replaces the last good one
                    runs[bench.key].save(args.results)
            else:
                earlier = Run.load(bench, args.results)
                runs[bench.key] = earlier or Run(bench, ["python", f"benchmarks/{bench.script}"],
                                                 "not run: left out with --only, and no earlier result kept")
    total = time.perf_counter() - started
    load_after = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")

    det = detection_figures(runs["detection"].json) if runs.get("detection") and runs["detection"].json else None
    stereo = stereo_figures(runs["stereo"].json) if runs.get("stereo") and runs["stereo"].json else None
    images = []
    if det:
        plot_shape_errors(det, args.img / "bench_shape_errors.png")
        plot_detection(det, args.img / "bench_detection.png")
        images += [("bench_detection.png", "Detection per failure kind and false pauses"),
                   ("bench_shape_errors.png", "Shape errors, normal vs failing prints")]
    if stereo and STEREO_OURS in stereo:
        plot_size_errors(stereo, args.img / "bench_size_errors.png")
        images.append(("bench_size_errors.png", "Size check errors on normal prints"))
    plugin = plugin_figures(runs["plugin"].stdout) if runs.get("plugin") and runs["plugin"].status == "ok" else {}
    timing = [
        ("shape check\nper camera view", statistics.median(det["seconds_per_camera"]) if det else None,
         tuple(s / 3 for s in SEED["shape_seconds_3_views"]), ""),
        ("size check\nper stereo pair", statistics.median(stereo[STEREO_OURS]["seconds"])
         if stereo and stereo.get(STEREO_OURS, {}).get("seconds") else None, SEED["pair_seconds"], ""),
        ("whole check\n(all cameras, pairs)", statistics.median(det["check_seconds"]) if det else None, None, ""),
        ("added print time\nper check", plugin.get("added_s"), (SEED["dwell_seconds"], SEED["dwell_seconds"]),
         "(seed: dwell only)"),
        ("expected views\nper job", statistics.median(det["prepare_seconds"]) if det else None, None, "(seed: by hand)"),
    ]
    if any(ours is not None for _, ours, _, _ in timing):
        plot_timing(timing, args.img / "bench_timing.png")
        images.append(("bench_timing.png", "Time per step"))

    img_rel = os.path.relpath(args.img, args.out.parent)
    kept = [r for r in runs.values() if r.earlier]
    mode = "quick" if args.quick else "full"
    lines = [
        "# PrintWatch benchmarks",
        "",
        f"Generated by `python benchmarks/run_all.py` on {now_utc()}, commit {git_commit()}"
        + (f" ({mode} run, every script ran, {total / 60:.0f} min). " if not kept else
           f"; the sections show each script's own command, and {len(kept)} of them are kept from their last "
           f"successful runs ({', '.join(f'`{r.bench.script}` {r.when}' for r in kept)}; `--only` re-runs a "
           f"subset, `--report-only` none). ")
        + f"Machine: {machine()}; load average {load_before:.1f} before, {load_after:.1f} after (the machine is "
        f"shared: wall-clock figures are pessimistic; the scripts also give CPU time where it matters).",
        "",
        "Detection figures come from recordings rendered by PrintWatch's print simulator (parts, failure kinds, "
        "filament and bed colours, lighting, several camera rigs, calibration error on every camera) and "
        "replayed through the same code path as `printwatch evaluate`; the seed's own rules are replayed on the "
        "same frames. The dissertation's figures are from real prints on its test parts with a Raspberry Pi 3, "
        "so they are the reference points, not a like-for-like race.",
        "",
        "## Headline",
        "",
        *headline(runs, det, stereo),
        "",
        "Reproduce: `.venv/bin/python benchmarks/run_all.py` (full) or `--quick`; each script below also "
        "runs alone.",
        "",
    ]
    if images:
        lines += ["## Plots", ""]
        for name, alt in images:
            lines += [f"![{alt}]({img_rel}/{name})", ""]
    lines += ["## Every benchmark", ""]
    for run in runs.values():
        lines += section(run)
    not_run = [r for r in runs.values() if r.status != "ok"]
    if not_run:
        lines += ["## Not run", ""] + [f"- `{r.bench.script}`: {r.status}" for r in not_run] + [""]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("\n".join(lines))
    print(f"wrote {args.out} and {len(images)} plot(s) in {args.img} "
          f"({len(runs) - len(not_run)}/{len(runs)} benchmarks ran)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
