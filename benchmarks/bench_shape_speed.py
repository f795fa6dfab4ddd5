"""Shape-check speed: captured per-camera checks of real recordings, this tree's code and another revision's
interleaved in one process (a shared, noisy machine: compare within one run, CPU time, several rounds).

    .venv/bin/python benchmarks/bench_shape_speed.py --base HEAD~1                  # default set, every 3rd recording
    .venv/bin/python benchmarks/bench_shape_speed.py --base HEAD~1 --data /tmp/crosscheck --every 1 --rounds 5
    .venv/bin/python benchmarks/bench_shape_speed.py --threads 1      # this tree alone, cv2 threads 1 vs default

Each recording is replayed as ``printwatch evaluate`` replays it (``CheckRunner``, no pictures) and the
arguments of every ``check_shape`` call (second looks and calibration probes included) are kept, compressed,
per check. They are then replayed with each version in turn, alternating which goes first: per check, the
CPU time (``time.process_time``: all threads) of its calls divided by the check's cameras, the figure
bench_detection reports as "CPU per camera per check" without the per-check work outside ``check_shape``
(the regions from the job plan, about 1 ms). Every output of the first round is compared field by field:
an exact speed-up changes no bit. ``--base`` is a git revision of this repository: its
``octoprint_printwatch/core`` is extracted to a temporary package (the core imports nothing else).
"""
from __future__ import annotations

import argparse
import dataclasses
import gc
import inspect
import importlib
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
import zlib
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from octoprint_printwatch.core import pipeline, shape_check  # noqa: E402
from octoprint_printwatch.core.pipeline import CheckRunner, prepare_job  # noqa: E402
from octoprint_printwatch.core.recording import load_recording  # noqa: E402
from octoprint_printwatch.core.settings import DetectionSettings  # noqa: E402

DEFAULT_DATA = Path("/tmp/printwatch-bench-detection")


def capture(folders: list[Path]) -> list[dict]:
    """[{"cameras": n, "calls": [compressed check_shape kwargs]}] per check of each recording."""
    original = shape_check.check_shape
    calls: list[bytes] = []

    def recording_check_shape(**kwargs):
        calls.append(zlib.compress(pickle.dumps(kwargs, protocol=5), 1))
        return original(**kwargs)

    pipeline.check_shape = shape_check.check_shape = recording_check_shape
    checks = []
    try:
        settings = DetectionSettings()
        for folder in folders:
            recording = load_recording(folder)
            ordered = sorted(recording.checks, key=lambda c: (c.z, c.layer))
            plan = prepare_job(gcode_path=recording.gcode, model_path=recording.model, cameras=recording.cameras,
                               pairs=recording.pairs, check_heights=[(c.layer, c.z) for c in ordered],
                               settings=settings)
            runner = CheckRunner(plan, settings, {n: recording.read_background(n) for n in recording.cameras})
            runner.keep_pictures = False
            for check in ordered:
                calls.clear()
                result = runner.run_check(check.layer, check.z,
                                          {n: recording.read_frame(check, n) for n in recording.cameras})
                checks.append({"name": folder.name, "layer": check.layer, "cameras": max(1, len(result.shape)),
                               "calls": list(calls)})
    finally:
        pipeline.check_shape = shape_check.check_shape = original
    return checks


def base_package(revision: str, into: Path):
    """This repository's ``octoprint_printwatch/core`` at ``revision``, importable as ``pw_base_core``."""
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", revision, "octoprint_printwatch/core"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    (into / "octoprint_printwatch" / "core").rename(into / "pw_base_core")
    sys.path.insert(0, str(into))
    return importlib.import_module("pw_base_core.shape_check")


def differences(a, b, path="result") -> list[str]:
    """Where two results differ (dataclasses, arrays bit for bit, numbers exactly)."""
    if dataclasses.is_dataclass(a) and dataclasses.is_dataclass(b):
        return [d for f in dataclasses.fields(a) for d in differences(getattr(a, f.name), getattr(b, f.name),
                                                                       f"{path}.{f.name}")]
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        same = (isinstance(a, np.ndarray) and isinstance(b, np.ndarray) and a.dtype == b.dtype
                and a.shape == b.shape and a.tobytes() == b.tobytes())
        return [] if same else [path]
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)) and len(a) == len(b):
        return [d for i, (x, y) in enumerate(zip(a, b)) for d in differences(x, y, f"{path}[{i}]")]
    if isinstance(a, dict) and isinstance(b, dict) and a.keys() == b.keys():
        return [d for k in a for d in differences(a[k], b[k], f"{path}[{k}]")]
    if isinstance(a, float) and isinstance(b, float) and np.isnan(a) and np.isnan(b):
        return []
    return [] if a == b else [f"{path}: {a!r} != {b!r}"]


def as_version(kwargs: dict, module) -> dict:
    """check_shape's arguments for ``module``'s own ExpectedRegions class, without the arguments its check_shape
    does not take, nor the regions' fields its ExpectedRegions has not (both added since that revision)."""
    accepted = inspect.signature(module.check_shape).parameters
    kwargs = {k: v for k, v in kwargs.items() if k in accepted}
    regions = kwargs["regions"]
    if type(regions) is module.ExpectedRegions:
        return kwargs
    known = {f.name for f in dataclasses.fields(module.ExpectedRegions)}
    return dict(kwargs, regions=module.ExpectedRegions(**{f.name: getattr(regions, f.name)
                                                          for f in dataclasses.fields(regions) if f.name in known}))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=DEFAULT_DATA, help="a folder of recordings")
    ap.add_argument("--every", type=int, default=3, help="every k-th recording (sorted by name)")
    ap.add_argument("--only", default="", help="comma-separated recording names")
    ap.add_argument("--base", default="", help="git revision to compare with (interleaved)")
    ap.add_argument("--threads", type=int, default=0, help="without --base: cv2 threads N against the default")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args(argv)

    folders = sorted(p for p in args.data.iterdir() if (p / "session.json").exists()) \
        if not args.only else [args.data / n for n in args.only.split(",")]
    folders = folders[:: args.every] if not args.only else folders
    started = time.perf_counter()
    checks = capture(folders)
    print(f"{len(folders)} recordings, {len(checks)} checks, {sum(len(c['calls']) for c in checks)} check_shape "
          f"calls captured in {time.perf_counter() - started:.0f} s", flush=True)

    default_threads = cv2.getNumThreads()
    with tempfile.TemporaryDirectory() as tmp:
        versions = {"this": shape_check}
        if args.base:
            versions = {"base": base_package(args.base, Path(tmp)), "this": shape_check}
        elif args.threads:
            versions = {"default threads": shape_check, f"{args.threads} thread(s)": shape_check}
        names = list(versions)
        cpu = {n: [[] for _ in checks] for n in names}
        wall = {n: [[] for _ in checks] for n in names}
        differing = 0
        for round_ in range(args.rounds):
            for i, check in enumerate(checks):
                calls = [pickle.loads(zlib.decompress(blob)) for blob in check["calls"]]
                outputs = {}
                for name in (names if (i + round_) % 2 == 0 else names[::-1]):
                    module = versions[name]
                    if args.threads and not args.base:
                        cv2.setNumThreads(args.threads if name != "default threads" else default_threads)
                    inputs = [as_version(kw, module) for kw in calls]
                    gc.collect()
                    gc.disable()
                    t, tw = time.process_time(), time.perf_counter()
                    outputs[name] = [module.check_shape(**kw) for kw in inputs]
                    cpu[name][i].append((time.process_time() - t) / check["cameras"])
                    wall[name][i].append((time.perf_counter() - tw) / check["cameras"])
                    gc.enable()
                if round_ == 0 and len(names) == 2:
                    for a, b in zip(outputs[names[0]], outputs[names[1]]):
                        found = differences(a, b)
                        if found:
                            differing += 1
                            print(f"  differs: {check['name']} layer {check['layer']}: {found[:3]}")
            cv2.setNumThreads(default_threads)
            line = ", ".join(f"{n} {statistics.median(c[round_] for c in cpu[n]) * 1000:.2f}" for n in names)
            print(f"round {round_ + 1}: median CPU ms per camera-check: {line}", flush=True)
    for n in names:
        print(f"{n}: median CPU {statistics.median(statistics.median(c) for c in cpu[n]) * 1000:.2f} ms, "
              f"wall {statistics.median(statistics.median(c) for c in wall[n]) * 1000:.2f} ms per camera-check "
              f"(median over checks of each check's median over rounds)")
    if len(names) == 2:
        ratio = [statistics.median(b) / statistics.median(a) for a, b in zip(cpu[names[0]], cpu[names[1]])]
        print(f"{names[1]} / {names[0]}: median per-check CPU ratio {statistics.median(ratio):.3f}")
        if args.base:
            print(f"identical outputs: {sum(len(c['calls']) for c in checks) - differing} of "
                  f"{sum(len(c['calls']) for c in checks)} calls")
    return 0


if __name__ == "__main__":
    sys.exit(main())
