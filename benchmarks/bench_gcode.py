"""Injection throughput and peak memory: the largest corpus file and a synthetic 100 MB file.

    .venv/bin/python benchmarks/bench_gcode.py [--size-mb 100] [--repeat 3]

Each measurement runs in a fresh subprocess so its peak memory is its own:
``peak RSS`` is the process's maximum resident size (``ru_maxrss``) minus its
size just before the injection started; ``traced peak`` is tracemalloc's peak of
Python allocations during a second, separate run (tracemalloc slows the code,
so throughput is measured without it). Throughput = input bytes / time of
``inject_checks`` (analysis pass + copy pass), wall clock and CPU. The synthetic
file is written to a temporary folder and deleted afterwards.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CORPUS = ROOT / "tests" / "data" / "gcode"

_CHILD = r"""
import json, os, resource, sys, time, tracemalloc
from octoprint_printwatch.core.inject import inject_checks
src, dst, mode = sys.argv[1], sys.argv[2], sys.argv[3]
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
if mode == "trace":
    tracemalloc.start()
wall, cpu = time.perf_counter(), time.process_time()
result = inject_checks(src, dst, every=10, bed=(250, 210), max_z=400)
wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
traced = tracemalloc.get_traced_memory()[1] if mode == "trace" else None
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
os.unlink(dst)
print(json.dumps({"bytes": result.bytes_in, "layers": result.layers, "checks": len(result.checks),
                  "wall": wall, "cpu": cpu, "rss_kb": peak - base, "traced": traced}))
"""


def synthetic_gcode(path: Path, size_mb: float) -> None:
    """A plausible print: 0.2 mm layers of a 40 mm square part (perimeters + zig-zag infill)."""
    target = size_mb * 1e6
    written = 0
    e = 0.0
    with open(path, "w") as out:
        header = ("; synthetic benchmark file\nG21\nG90\nM82\nG28\nG92 E0\n")
        out.write(header)
        written += len(header)
        layer = 0
        while written < target:
            layer += 1
            z = round(0.2 * layer, 3)
            lines = [f";LAYER_CHANGE\n;Z:{z}\nG1 E{e - 0.8:.5f} F2100\nG1 Z{z} F9000\n"
                     f"G1 X80 Y80 F9000\nG1 E{e:.5f} F2100\nG1 F1800\n"]
            for inset in (0.0, 0.45, 0.9):
                lo, hi = 80 + inset, 120 - inset
                for x, y in ((hi, lo), (hi, hi), (lo, hi), (lo, lo)):
                    e += 0.04 * 40
                    lines.append(f"G1 X{x:.3f} Y{y:.3f} E{e:.5f}\n")
            y = 81.5
            while y < 118.5:
                for x in ((81.5, 118.5) if int(y * 10) % 9 else (118.5, 81.5)):
                    e += 0.0012 * 37
                    lines.append(f"G1 X{x:.3f} Y{y:.3f} E{e:.5f}\n")
                y += 0.45
                # short segments, as slicers write curved parts
                for step in range(12):
                    e += 0.0012 * 0.3
                    lines.append(f"G1 X{118.5 - step * 0.31:.3f} Y{y:.3f} E{e:.5f}\n")
            chunk = "".join(lines)
            out.write(chunk)
            written += len(chunk)
        out.write("G1 Z{0} F600\nM84\n".format(round(0.2 * layer + 10, 3)))


def measure(src: Path, tmp: Path) -> dict:
    dst = tmp / "out.gcode"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    results = {}
    for mode in ("time", "trace"):
        done = subprocess.run([sys.executable, "-c", _CHILD, str(src), str(dst), mode],
                              capture_output=True, text=True, env=env, check=True)
        results[mode] = json.loads(done.stdout)
    timed = results["time"]
    return {"bytes": timed["bytes"], "layers": timed["layers"], "checks": timed["checks"],
            "wall": timed["wall"], "cpu": timed["cpu"], "rss_mb": timed["rss_kb"] / 1024,
            "traced_mb": results["trace"]["traced"] / 1e6}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size-mb", type=float, default=100.0, help="size of the synthetic file (default 100)")
    parser.add_argument("--repeat", type=int, default=3, help="timed runs per file; the best is reported")
    args = parser.parse_args()
    corpus = sorted(CORPUS.rglob("*.gcode"), key=lambda p: p.stat().st_size)
    largest = corpus[-1]
    rows = []
    with tempfile.TemporaryDirectory(prefix="printwatch-bench-") as folder:
        tmp = Path(folder)
        synthetic = tmp / "synthetic.gcode"
        synthetic_gcode(synthetic, args.size_mb)
        for label, path in ((largest.name, largest), (f"synthetic {args.size_mb:g} MB", synthetic)):
            runs = [measure(path, tmp) for _ in range(max(1, args.repeat))]
            best = min(runs, key=lambda r: r["wall"])
            best["cpu"] = min(r["cpu"] for r in runs)
            best["rss_mb"] = max(r["rss_mb"] for r in runs)
            rows.append((label, best))
        synthetic.unlink()
    print("| file | size MB | layers | checks | wall s | MB/s (wall) | MB/s (CPU) | peak RSS growth MB | tracemalloc peak MB |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, r in rows:
        mb = r["bytes"] / 1e6
        print(f"| {label} | {mb:.1f} | {r['layers']} | {r['checks']} | {r['wall']:.2f} | "
              f"{mb / r['wall']:.1f} | {mb / r['cpu']:.1f} | {r['rss_mb']:.1f} | {r['traced_mb']:.2f} |")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\nPython {sys.version.split()[0]}, {os.cpu_count()} CPUs, load average {load:.1f} at the end "
          f"(wall-clock figures drop with load; CPU figures much less). Target: >= 10 MB/s, flat memory.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
