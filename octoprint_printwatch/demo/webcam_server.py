"""Simulated webcams for the integration tests: frames of the print *as it actually is*.

An HTTP server with one snapshot URL per camera (``/<camera>.jpg``). For each
request it asks OctoPrint's ``/api/job`` where the job is in its file, looks
that byte position up in the file's own layer table (the highest Z at which the
file has extruded so far; built by downloading the file being printed, so the
injected check blocks are accounted for) and renders that state with the print
simulator (:class:`~octoprint_printwatch.simulator.scene.PrintSimulator`) -
the empty bed before the first extrusion. It knows nothing of the plugin under
test: a plugin that checks at the wrong moment gets the wrong picture.

Options make a camera dead (``--dead cam1``: the request hangs past any
timeout) and inject a failure (``--scenario runout --onset-layer 40``).

Run: ``python -m octoprint_printwatch.demo.webcam_server --port 8899 --octoprint http://127.0.0.1:5000 --apikey KEY``
"""
from __future__ import annotations

import argparse
import json
import re
import sys
import threading
import time
import urllib.parse
import urllib.request
from bisect import bisect_right
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import cv2

_WORD = re.compile(r"([A-Za-z])\s*([-+]?\d*\.?\d+)")


def layer_table(data: bytes) -> tuple[list[int], list[float]]:
    """Byte offsets (ascending) after which the printed top rises, and the top height there (mm).

    The top is the highest Z at which an extruding move (E increasing) has ended so far;
    travel, lifts and parking moves do not count. Handles G90/G91, M82/M83 and G92.
    """
    offsets: list[int] = []
    tops: list[float] = []
    z = 0.0
    e = 0.0
    top = 0.0
    absolute_xyz = True
    absolute_e = True
    position = 0
    for raw in data.splitlines(keepends=True):
        position += len(raw)
        line = raw.split(b";", 1)[0].strip().decode("ascii", "replace").upper()
        if not line:
            continue
        words = {k: float(v) for k, v in _WORD.findall(line)}
        code = line.split()[0]
        if code == "G90":
            absolute_xyz, absolute_e = True, True
        elif code == "G91":
            absolute_xyz, absolute_e = False, False
        elif code == "M82":
            absolute_e = True
        elif code == "M83":
            absolute_e = False
        elif code == "G92":
            if "E" in words:
                e = words["E"]
            if "Z" in words:
                z = words["Z"]
        elif code in ("G0", "G1", "G2", "G3"):
            if "Z" in words:
                z = words["Z"] if absolute_xyz else z + words["Z"]
            extruding = False
            if "E" in words:
                new_e = words["E"] if absolute_e else e + words["E"]
                extruding = new_e > e + 1e-9 and ("X" in words or "Y" in words)
                e = new_e
            if extruding and z > top + 1e-6:
                top = z
                offsets.append(position)
                tops.append(round(top, 4))
        elif code == "G28":
            z = 0.0
    return offsets, tops


class PrintFollower:
    """Where the real job is: file position from OctoPrint -> printed top Z from the file's layer table."""

    def __init__(self, octoprint: str, apikey: str) -> None:
        self.octoprint = octoprint.rstrip("/")
        self.apikey = apikey
        self._tables: dict[tuple[str, int], tuple[list[int], list[float]]] = {}
        self._lock = threading.Lock()

    def _get(self, path: str) -> bytes:
        request = urllib.request.Request(self.octoprint + path, headers={"X-Api-Key": self.apikey})
        with urllib.request.urlopen(request, timeout=10) as response:
            return response.read()

    def _table(self, file: dict):
        key = (file["path"], int(file.get("date") or 0))
        with self._lock:
            table = self._tables.get(key)
            if table is None:
                data = self._get("/downloads/files/local/" + urllib.parse.quote(file["path"]))
                table = layer_table(data)
                self._tables[key] = table
        return table

    def poll_forever(self, interval: float = 0.5) -> None:
        """Background poll: builds the layer table of a new job before its first snapshot is asked for."""
        while True:
            try:
                job = json.loads(self._get("/api/job"))
                file = (job.get("job") or {}).get("file") or {}
                if file.get("path") and file.get("origin") == "local":
                    self._table(file)
            except Exception:
                pass  # OctoPrint restarting or not up yet: try again
            time.sleep(interval)

    def printed_top(self) -> float:
        job = json.loads(self._get("/api/job"))  # fresh: the exact position at this snapshot
        file = (job.get("job") or {}).get("file") or {}
        filepos = (job.get("progress") or {}).get("filepos")
        if not file.get("path") or filepos is None or job.get("state", "").startswith("Operational"):
            return 0.0
        offsets, tops = self._table(file)
        index = bisect_right(offsets, int(filepos)) - 1
        return tops[index] if index >= 0 else 0.0


class WebcamApp:
    def __init__(self, simulator, follower: PrintFollower, dead: set[str], hang_s: float = 60.0) -> None:
        self.simulator = simulator
        self.follower = follower
        self.dead = dead
        self.hang_s = hang_s
        self.served: list[dict] = []  # what each request showed, for tests that want to look
        self._render_lock = threading.Lock()

    def snapshot(self, camera: str) -> bytes:
        top = self.follower.printed_top()
        with self._render_lock:  # the simulator caches per height; one render at a time keeps it simple
            if top <= 0:
                image = self.simulator.background(camera)
            else:
                image = self.simulator.frame(camera, top, 0)
        self.served.append({"camera": camera, "z": top, "time": time.time()})
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 90])
        return data.tobytes()


def make_handler(app: WebcamApp):
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args):  # quiet
            pass

        def do_GET(self):
            path = urllib.parse.urlparse(self.path).path.strip("/")
            if path == "served":
                body = json.dumps(app.served).encode()
                self.send_response(200)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(body)))
                self.end_headers()
                self.wfile.write(body)
                return
            camera = path[:-4] if path.endswith(".jpg") else path
            if camera not in app.simulator.camera_names:
                self.send_error(404, f"no camera {camera}")
                return
            if camera in app.dead:
                time.sleep(app.hang_s)  # a dead webcam: the connection opens, no picture ever comes
                return
            try:
                body = app.snapshot(camera)
            except Exception as exc:
                self.send_error(500, f"{type(exc).__name__}: {exc}")
                return
            self.send_response(200)
            self.send_header("Content-Type", "image/jpeg")
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

    return Handler


def build_simulator(part: str, rig: str, seed: int, scenario: str, onset_layer: int | None, look: str | None):
    from octoprint_printwatch.simulator.rig import make_rig
    from octoprint_printwatch.simulator.scenario import Scenario
    from octoprint_printwatch.simulator.scene import PrintSimulator

    kind, _, count = rig.partition(":")
    the_rig = make_rig(kind, n_cameras=int(count) if count else None, seed=seed)
    return PrintSimulator(part, rig=the_rig, look=look, scenario=Scenario(scenario, onset_layer=onset_layer), seed=seed)


def calibrations(part: str, rig: str, seed: int) -> dict:
    """The calibrated cameras of the rig (what a user's calibration gives), as plugin settings."""
    sim = build_simulator(part, rig, seed, "normal", None, None)
    return {name: sim.rig.calibrated(name).to_dict() for name in sim.camera_names}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, required=True)
    parser.add_argument("--octoprint", required=True)
    parser.add_argument("--apikey", required=True)
    parser.add_argument("--part", default="cube")
    parser.add_argument("--rig", default="ring:2", help="make_rig kind[:n_cameras]")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--look", default=None)
    parser.add_argument("--scenario", default="normal")
    parser.add_argument("--onset-layer", type=int, default=None)
    parser.add_argument("--dead", action="append", default=[])
    args = parser.parse_args(argv)
    sim = build_simulator(args.part, args.rig, args.seed, args.scenario, args.onset_layer, args.look)
    follower = PrintFollower(args.octoprint, args.apikey)
    threading.Thread(target=follower.poll_forever, daemon=True).start()
    for name in sim.camera_names:  # one-time per-camera set-up now, not during the first check
        sim.background(name)
    app = WebcamApp(sim, follower, set(args.dead))
    server = ThreadingHTTPServer(("127.0.0.1", args.port), make_handler(app))
    server.daemon_threads = True
    print(f"webcams {', '.join(sim.camera_names)} on http://127.0.0.1:{args.port}/<camera>.jpg", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    return 0


if __name__ == "__main__":
    sys.exit(main())
