"""Preparation per job: time and memory of what happens once, at upload.

    .venv/bin/python benchmarks/bench_prepare.py [--parts twisted_vase,gear] [--every 10]

For each library part, in a fresh subprocess (so peak memory is the job's own):
injection of the check blocks into its real PrusaSlicer G-code, then
``prepare_job`` for the seed's rig (three stations of relaxed stereo pairs,
6 cameras, 640x480) at every check height: the G-code solid, every camera's
expected view at every height. Reports wall and CPU seconds, the number of
views, the memory the finished plan keeps (what stays resident during the
print) and the process's peak RSS. Prints a Markdown table.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

CHILD = r"""
import json, resource, sys, tempfile, time
from pathlib import Path
from octoprint_printwatch.core.inject import inject_checks
from octoprint_printwatch.core.pipeline import prepare_job
from octoprint_printwatch.simulator.scene import make_rig, library_part

part, every = sys.argv[1], int(sys.argv[2])
gcode = Path(library_part(part)).with_suffix(".gcode")
rig = make_rig("stations3", seed=3)
cameras = {c.name: c for c in rig.cameras_calibrated}
with tempfile.TemporaryDirectory() as tmp:
    t0, c0 = time.perf_counter(), time.process_time()
    result = inject_checks(gcode, Path(tmp) / "out.gcode", every=every)
    inject_s = time.perf_counter() - t0
    heights = [(c.layer, c.z) for c in result.checks]
    t1, c1 = time.perf_counter(), time.process_time()
    plan = prepare_job(gcode_path=gcode, cameras=cameras, pairs=rig.pairs, check_heights=heights)
    prepare_s, prepare_cpu = time.perf_counter() - t1, time.process_time() - c1
kept = sum(v._silhouette.nbytes + v._new_band.nbytes for v in plan.views.values())
print(json.dumps({
    "part": part, "mb": gcode.stat().st_size / 1e6, "checks": len(heights), "views": len(plan.views),
    "inject_s": inject_s, "prepare_s": prepare_s, "prepare_cpu_s": prepare_cpu,
    "plan_views_mb": kept / 1e6,
    "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
}))
"""


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--parts", default="twisted_vase,gear,cube")
    parser.add_argument("--every", type=int, default=10, help="check every N layers (default 10)")
    args = parser.parse_args(argv)
    rows = []
    for part in args.parts.split(","):
        out = subprocess.run([sys.executable, "-c", CHILD, part, str(args.every)], cwd=ROOT,
                             capture_output=True, text=True)
        if out.returncode:
            print(f"{part}: failed: {out.stderr.strip().splitlines()[-1]}", file=sys.stderr)
            continue
        rows.append(json.loads(out.stdout.strip().splitlines()[-1]))
    print(f"| part | G-code MB | checks | views (6 cameras) | injection s | prepare s (CPU s) "
          f"| views kept in the plan MB | peak RSS MB |")
    print("|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['part']} | {r['mb']:.1f} | {r['checks']} | {r['views']} | {r['inject_s']:.2f} "
              f"| {r['prepare_s']:.1f} ({r['prepare_cpu_s']:.1f}) | {r['plan_views_mb']:.1f} | {r['peak_rss_mb']:.0f} |")
    return 0 if rows else 1


if __name__ == "__main__":
    sys.exit(main())
