"""Simulator speed: seconds per 640x480 frame, per part and scenario, first frame at a height vs. cached.

    .venv/bin/python benchmarks/bench_simulator.py [--repeat 5]

Prints a Markdown table of wall-clock seconds and, in brackets, CPU seconds of
this process (steadier on a shared machine). "first camera" includes the per-height work (partial
solid, shadows, skirt), shared by the other cameras at that height; "other
cameras" is what each further camera costs; "new camera" is the one-time
per-camera setup (rays, bed lookups, lighting).
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from octoprint_printwatch.simulator.rig import make_rig  # noqa: E402
from octoprint_printwatch.simulator.scenario import Scenario  # noqa: E402
from octoprint_printwatch.simulator.scene import PrintSimulator  # noqa: E402

CASES = [("cube", "normal"), ("gear", "normal"), ("twisted_vase", "normal"), ("sun_gear", "spaghetti"),
         ("cylinder", "detach"), ("prism", "under_extrusion"), ("gear", "white_on_glass")]


def timed(fn, *args) -> tuple[float, float]:
    """(wall seconds, CPU seconds) of one call."""
    wall, cpu = time.perf_counter(), time.process_time()
    fn(*args)
    return time.perf_counter() - wall, time.process_time() - cpu


def cell(samples) -> str:
    return (f"{statistics.median(w for w, _ in samples):.3f} "
            f"({statistics.median(c for _, c in samples):.3f})")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="heights per case")
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print("| part | scenario / look | new camera s | first camera at a height s | other cameras s | max s |")
    print("|---|---|---|---|---|---|")
    for part, what in CASES:
        look = what if what == "white_on_glass" else "seed"
        scenario = "normal" if what == "white_on_glass" else what
        sim = PrintSimulator(part, make_rig("stations3", seed=3), look, Scenario(scenario), seed=3)
        names = sim.camera_names
        setup = [timed(sim.background, name) for name in names]
        first, other = [], []
        for k in range(args.repeat):
            z = sim.layer_z(int(sim.n_layers * (0.3 + 0.6 * k / max(args.repeat - 1, 1))))
            first.append(timed(sim.frame, names[0], z, k))
            other += [timed(sim.frame, name, z, k) for name in names[1:]]
        print(f"| {part} | {what} | {cell(setup)} | {cell(first)} | {cell(other)} "
              f"| {max(w for w, _ in first + other):.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
