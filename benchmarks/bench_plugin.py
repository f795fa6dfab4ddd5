"""Plugin benchmark on a real OctoPrint: added print time per check, and API latency while checks run.

    .venv/bin/python benchmarks/bench_plugin.py [--speed 1000] [--part cube]

Starts ``octoprint serve`` with the virtual printer and PrintWatch, the
simulated webcams of ``octoprint_printwatch/demo/webcam_server.py`` (two cameras, one
through OctoPrint's classic webcam, one PrintWatch's own URL camera), and
prints the same library part twice at ``M220 S<speed>``: once as uploaded
(PrintWatch injected the checks) and once "without checks" (the exact upload,
restored through the plugin's API). Reports, as a Markdown table:

* added print time per check = (time with checks - time without) / checks,
  which includes the park moves at the sped-up rate, the frames and the vision;
* the hold per check (frames + vision, from the history) and the vision time;
* the park moves' duration at 100 % feed rate, from the injected blocks
  (distance / feed rate per move), so the figure can be read for a real printer;
* latency of ``GET /api/job`` and ``GET /plugin/printwatch/status``, polled
  every 50 ms, separately for samples taken while a check was running;
* the upload of a large synthetic G-code file (``--upload-mb``): how long the
  upload request takes with the injection inside OctoPrint's preprocessor hook,
  and the latency of ``GET /api/version`` polled meanwhile (the injection must
  not stall the server).
"""
from __future__ import annotations

import argparse
import math
import re
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "plugin"))

from stack import printwatch_stack, start_print, wait_print_end  # noqa: E402

from bench_gcode import synthetic_gcode  # noqa: E402  (this folder, first on sys.path when run as a script)

API = "/plugin/printwatch"


class Poller(threading.Thread):
    """Polls two endpoints every ``interval`` s; keeps (latency, endpoint, checking?) samples."""

    def __init__(self, server, interval=0.05):
        super().__init__(daemon=True)
        self.server, self.interval = server, interval
        self.samples: list[tuple[float, str, bool]] = []
        self.stop = threading.Event()

    def run(self):
        import requests

        session = requests.Session()
        session.headers.update(self.server.headers())
        while not self.stop.is_set():
            t0 = time.perf_counter()
            status = session.get(self.server.url + f"{API}/status", timeout=10).json()
            t1 = time.perf_counter()
            session.get(self.server.url + "/api/job", timeout=10)
            t2 = time.perf_counter()
            checking = status.get("state") == "checking"
            self.samples.append((t1 - t0, "status", checking))
            self.samples.append((t2 - t1, "job", checking))
            self.stop.wait(self.interval)


def block_move_seconds(injected: bytes) -> float:
    """Seconds the moves of one check block take at 100 % feed rate (the mean over blocks)."""
    text = injected.decode("ascii", "replace")
    blocks = re.findall(r"; printwatch check block begin(.*?); printwatch check block end", text, re.S)
    if not blocks:
        return float("nan")
    totals = []
    for block in blocks:
        pos, feed, seconds = {}, None, 0.0
        for line in block.splitlines():
            code = line.split(";")[0].strip().upper()
            if not code.startswith(("G0", "G1")):
                continue
            words = {k: float(v) for k, v in re.findall(r"([XYZEF])(-?\d*\.?\d+)", code)}
            feed = words.get("F", feed)
            axes = {k: words[k] for k in "XYZ" if k in words}
            if "E" in words and not axes:
                axes_distance = 0.0
                e_move = abs(words["E"] - pos.get("E", words["E"]))
                pos["E"] = words["E"]
                distance = e_move
            else:
                distance = math.sqrt(sum((v - pos.get(k, v)) ** 2 for k, v in axes.items()))
                pos.update(axes)
                if "E" in words:
                    pos["E"] = words["E"]
            if feed:
                seconds += distance / feed * 60.0
        totals.append(seconds)
    return statistics.mean(totals[1:] or totals)  # the first block starts from an unknown position


def timed_print(server, gcode: Path, speed: int, *, upload: bool = True) -> tuple[float, Poller]:
    poller = Poller(server)
    poller.start()
    started = time.monotonic()
    if upload:
        start_print(server, gcode, speed_percent=speed)
    else:  # print the file already in storage, as it is
        server.post("/api/printer/command", {"commands": [f"M220 S{speed}"]}).raise_for_status()
        server.post(f"/api/files/local/{gcode.name}", {"command": "select", "print": True}).raise_for_status()
    state = wait_print_end(server, timeout=3600)
    elapsed = time.monotonic() - started
    poller.stop.set()
    poller.join()
    if state != "Operational":
        raise SystemExit(f"print ended in state {state!r}")
    return elapsed, poller


def upload_latency(server, size_mb: float, folder: Path) -> tuple[float, list[float]]:
    """(seconds the upload request took, /api/version latencies sampled during it)."""
    import requests

    big = folder / f"synthetic_{size_mb:g}mb.gcode"
    synthetic_gcode(big, size_mb)
    samples, stop = [], threading.Event()

    def poll():
        session = requests.Session()
        session.headers.update(server.headers())
        while not stop.is_set():
            t0 = time.perf_counter()
            session.get(server.url + "/api/version", timeout=120)
            samples.append((t0, time.perf_counter() - t0))
            stop.wait(0.05)

    thread = threading.Thread(target=poll, daemon=True)
    thread.start()
    time.sleep(1.0)
    started = time.perf_counter()
    server.upload(big)
    took = time.perf_counter() - started
    stop.set()
    thread.join()
    return took, [latency for t, latency in samples if started <= t <= started + took]


def stats(values):
    values = sorted(values)
    if not values:
        return "-"
    p95 = values[min(len(values) - 1, int(round(0.95 * (len(values) - 1))))]
    return f"{statistics.median(values) * 1000:.0f} / {p95 * 1000:.0f} / {values[-1] * 1000:.0f}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speed", type=int, default=1000, help="M220 feed rate percent (1000 = 10x)")
    parser.add_argument("--every", type=int, default=20, help="check every N layers")
    parser.add_argument("--upload-mb", type=float, default=30.0, help="size of the large upload (0: skip)")
    args = parser.parse_args(argv)
    gcode = ROOT / "octoprint_printwatch" / "data" / "parts" / "cube.gcode"

    with tempfile.TemporaryDirectory(prefix="bench-plugin-") as tmp:
        with printwatch_stack(Path(tmp), settings={"every_layers": args.every}) as (server, _):
            with_checks, poller = timed_print(server, gcode, args.speed)
            detail = server.get(f"{API}/prints/1")
            checks = detail["checks"]
            injected = server.request("GET", "/downloads/files/local/cube.gcode").content
            moves_1x = block_move_seconds(injected)
            off = server.post(f"{API}/files/local/cube.gcode", {"checks_enabled": False})
            off.raise_for_status()
            without_checks, _ = timed_print(server, gcode, args.speed, upload=False)
            upload = upload_latency(server, args.upload_mb, Path(tmp)) if args.upload_mb > 0 else None

    n = len(checks)
    holds = [c["hold_seconds"] for c in checks]
    vision = [c["seconds"] for c in checks]
    verdicts = ", ".join(sorted({c["verdict"] for c in checks}))
    print(f"## PrintWatch on a real OctoPrint (virtual printer at M220 S{args.speed}, cube, 2 cameras, "
          f"{n} checks, verdicts: {verdicts})\n")
    print("| figure | value |")
    print("|---|---|")
    print(f"| print time with checks | {with_checks:.1f} s |")
    print(f"| print time without checks | {without_checks:.1f} s |")
    print(f"| **added print time per check** (moves at {args.speed} %, frames, vision) | "
          f"**{(with_checks - without_checks) / max(n, 1):.2f} s** |")
    print(f"| job held per check: median / max (frames + vision) | {statistics.median(holds):.2f} / {max(holds):.2f} s |")
    print(f"| vision per check (2 cameras): median / max | {statistics.median(vision):.2f} / {max(vision):.2f} s |")
    print(f"| park moves of one check block at 100 % feed rate | {moves_1x:.1f} s |")
    print(f"| estimated added time per check on a real printer (hold + moves at 100 %) | "
          f"{statistics.median(holds) + moves_1x:.1f} s |")
    print()
    print("| API latency, ms (median / p95 / max) | while a check runs | otherwise |")
    print("|---|---|---|")
    for endpoint, label in (("job", "GET /api/job"), ("status", "GET /plugin/printwatch/status")):
        during = [s for s, e, c in poller.samples if e == endpoint and c]
        other = [s for s, e, c in poller.samples if e == endpoint and not c]
        print(f"| {label} | {stats(during)} (n={len(during)}) | {stats(other)} (n={len(other)}) |")
    if upload is not None:
        took, latencies = upload
        print()
        print(f"Upload of a {args.upload_mb:g} MB G-code file (checks injected inside OctoPrint's preprocessor hook): "
              f"the request took {took:.1f} s ({took / args.upload_mb:.2f} s/MB); meanwhile `GET /api/version` "
              f"answered in {stats(latencies)} ms (median / p95 / max, n={len(latencies)}): the server does not stall.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
