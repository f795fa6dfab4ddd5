"""Geometry benchmark: G-code solids and expected-view rendering, as a Markdown table.

    .venv/bin/python benchmarks/bench_render.py            # everything (about a minute)
    .venv/bin/python benchmarks/bench_render.py --quick    # the two headline figures only

Measures, on this machine (single process, wall time, best of ``--repeat``):

* building the G-code solid of every corpus file (parsing included), with the
  size of the file and of the resulting mesh; the largest file is the 5 MB target;
* one 640x480 silhouette of a >100k-triangle mesh (the corpus twisted vase,
  subdivided), distorted and undistorted lens, mesh caches warm and cold;
* 6 cameras x every check height (every 5 layers of 0.2 mm) of that mesh:
  the partial solid and its silhouette per camera, then the full expected views
  (silhouettes, depth maps, newest band) as ``render_expected_views`` makes them.

Targets (issue 3): G-code solid < 5 s for a 5 MB file; one silhouette < 50 ms.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
import trimesh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from octoprint_printwatch.core import render  # noqa: E402
from octoprint_printwatch.core.camera import Camera  # noqa: E402
from octoprint_printwatch.core.geometry import load_mesh, part_from_mesh  # noqa: E402
from octoprint_printwatch.core.toolpath_solid import _PART_CACHE, build_gcode_part  # noqa: E402

CORPUS = ROOT / "tests" / "data" / "gcode"


def best_of(repeat: int, function, *args, **kwargs):
    """(best wall seconds, best CPU seconds of this process, result): CPU time is what the
    code costs when the 2 cores are shared with other work, wall time what a user waits."""
    walls, cpus, result = [], [], None
    for _ in range(repeat):
        started, cpu = time.perf_counter(), time.process_time()
        result = function(*args, **kwargs)
        walls.append(time.perf_counter() - started)
        cpus.append(time.process_time() - cpu)
    return min(walls), min(cpus), result


def ring_cameras(count: int, center, distorted: bool) -> list[Camera]:
    cams = []
    for k in range(count):
        a = 2 * np.pi * k / count
        eye = (center[0] + 160 * np.cos(a), center[1] + 160 * np.sin(a), 90.0)
        cams.append(Camera.look_at(f"cam{k}", eye, (center[0], center[1], 18.0), focal_px=720.0,
                                   dist=[-0.25, 0.08, 0.0, 0.0, 0.0] if distorted else None))
    return cams


def bench_gcode(files: list[Path], repeat: int) -> list[str]:
    rows = ["| G-code file | size (MB) | layers | solid, wall (s) | solid, CPU (s) | mesh triangles | notes |",
            "|---|---:|---:|---:|---:|---:|---|"]
    for path in files:
        def build():
            _PART_CACHE.clear()
            return build_gcode_part(path)
        seconds, cpu, part = best_of(repeat, build)
        rows.append(f"| {path.name} | {path.stat().st_size / 1e6:.1f} | {len(part.layers)} | {seconds:.2f} | {cpu:.2f} | "
                    f"{len(part.mesh.faces)} | {'; '.join(part.notes) or '-'} |")
    return rows


def peak_memory(path: Path) -> float:
    """Peak Python + numpy allocation (MB) while building one G-code solid (tracemalloc; slow, so apart)."""
    import tracemalloc

    _PART_CACHE.clear()
    tracemalloc.start()
    build_gcode_part(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    _PART_CACHE.clear()
    return peak / 1e6


def big_mesh() -> trimesh.Trimesh:
    mesh = load_mesh(CORPUS / "twisted_vase.stl")
    for _ in range(2):
        mesh = mesh.subdivide()
    mesh.apply_translation((100.0, 100.0, 0.0))
    return mesh


def bench_silhouette(repeat: int) -> list[str]:
    mesh = big_mesh()
    rows = ["| silhouette, 640x480, %d triangles | wall (ms) | CPU (ms) |" % len(mesh.faces), "|---|---:|---:|"]
    for distorted in (False, True):
        camera = ring_cameras(1, (100.0, 100.0), distorted)[0]
        cold_mesh = mesh.copy()
        cold, cold_cpu, _ = best_of(1, render.render_silhouette, cold_mesh, camera, distorted=distorted)
        warm, warm_cpu, _ = best_of(repeat, render.render_silhouette, mesh, camera, distorted=distorted)
        lens = "distorted lens" if distorted else "no distortion"
        rows.append(f"| {lens}, edge tables of the mesh cached | {warm * 1000:.1f} | {warm_cpu * 1000:.1f} |")
        rows.append(f"| {lens}, first call on a new mesh (edge tables built) | {cold * 1000:.1f} | {cold_cpu * 1000:.1f} |")
    return rows


def bench_views(layer_every: int = 5) -> list[str]:
    mesh = big_mesh()
    part = part_from_mesh(mesh)
    cameras = ring_cameras(6, (100.0, 100.0), True)
    heights = list(np.arange(0.2 * layer_every, part.height() + 1e-9, 0.2 * layer_every))
    t_solids, c_solids, solids = best_of(1, lambda: [part.solid_below(z) for z in heights])

    def silhouettes():
        for solid in solids:
            for camera in cameras:
                render.render_silhouette(solid, camera)
    t_sil, c_sil, _ = best_of(1, silhouettes)
    render._MEMORY_CACHE.clear()

    def all_views():  # one camera at a time: 228 views held at once would be ~0.8 GB
        return sum(len(render.render_expected_views(part, [camera], heights)) for camera in cameras)
    t_views, c_views, count = best_of(1, all_views)
    n = len(heights) * len(cameras)
    return [
        f"| 6 cameras x {len(heights)} check heights ({len(mesh.faces)}-triangle mesh) | wall (s) | CPU (s) | CPU per item (ms) |",
        "|---|---:|---:|---:|",
        f"| partial solids (manifold trim), once per height | {t_solids:.2f} | {c_solids:.2f} | {c_solids / len(heights) * 1000:.0f} per height |",
        f"| distorted silhouettes of those solids | {t_sil:.2f} | {c_sil:.2f} | {c_sil / n * 1000:.1f} per view |",
        f"| full expected views (2 silhouettes, depth maps, band; {count} views) | {t_views:.2f} | {c_views:.2f} | {c_views / n * 1000:.0f} per view |",
    ]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="only the largest G-code file and one silhouette")
    parser.add_argument("--repeat", type=int, default=3, help="best of N runs (default 3)")
    args = parser.parse_args(argv)
    files = sorted(CORPUS.glob("*.gcode"), key=lambda p: p.stat().st_size, reverse=True)
    if args.quick:
        files = files[:1]
    print(f"# bench_render ({time.strftime('%Y-%m-%d %H:%M')}, {'quick' if args.quick else 'full'})\n")
    print("\n".join(bench_gcode(files, 1 if not args.quick else args.repeat)))
    print(f"\nPeak memory building the solid of {files[0].name}: {peak_memory(files[0]):.0f} MB (tracemalloc)\n")
    print("\n".join(bench_silhouette(max(args.repeat, 5))))
    if not args.quick:
        print()
        print("\n".join(bench_views()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
