"""A real OctoPrint with PrintWatch and simulated webcams: what the integration tests and the benchmark run.

:func:`printwatch_stack` starts the webcam server (``octoprint_printwatch/demo/webcam_server.py``) and an
``octoprint serve`` configured to use it: camera ``classic`` through
OctoPrint's bundled classic webcam (the OctoPrint-webcam path) and ``cam1`` as
one of PrintWatch's own snapshot-URL cameras, both calibrated with the rig's
calibrated cameras (calibration error included, as a user's would be).
"""
from __future__ import annotations

import contextlib
import time
from pathlib import Path

from octoprint_printwatch.demo.octoprint_server import ADMIN_KEY, OctoPrintServer, free_port
from octoprint_printwatch.demo.run import launch_webcam_server, stop_process

PART = "cube"
RIG = "ring:2"
SEED = 3
#: simulator camera -> name under which OctoPrint/PrintWatch know it
CAMERA_NAMES = {"cam0": "classic", "cam1": "cam1"}


def printwatch_settings(webcam_port: int, *, every_layers: int = 20, timeout_s: float = 3.0, extra=None) -> dict:
    from octoprint_printwatch.demo.webcam_server import calibrations

    calib = calibrations(PART, RIG, SEED)
    settings = {
        "every_layers": every_layers,
        "camera_timeout_s": timeout_s,
        "use_octoprint_webcams": True,
        "cameras": [{"name": "cam1", "type": "url", "url": f"http://127.0.0.1:{webcam_port}/cam1.jpg"}],
        "calibrations": {CAMERA_NAMES[name]: data for name, data in calib.items()},
        "lift_mm": 10.0,
    }
    settings.update(extra or {})
    return settings


@contextlib.contextmanager
def webcam_server(port: int, octoprint_url: str, *, scenario: str = "normal", onset_layer: int | None = None,
                  dead: list[str] = (), log: Path | None = None):
    process = launch_webcam_server(port, octoprint_url, ADMIN_KEY, part=PART, rig=RIG, seed=SEED,
                                   scenario=scenario, onset_layer=onset_layer, dead=dead, log=log)
    try:
        yield process
    finally:
        stop_process(process)


@contextlib.contextmanager
def printwatch_stack(basedir: Path, *, scenario: str = "normal", onset_layer: int | None = None,
                     dead: list[str] = (), settings: dict | None = None):
    """(server, webcam_port) with the virtual printer Operational."""
    webcam_port = free_port()
    server = OctoPrintServer(Path(basedir), printwatch_settings(webcam_port, extra=settings))
    server.write_config()
    _point_classic_webcam(server, webcam_port)
    with server:
        with webcam_server(webcam_port, server.url, scenario=scenario, onset_layer=onset_layer, dead=dead,
                           log=Path(basedir) / "webcams.log"):
            server.wait_operational()
            yield server, webcam_port


def _point_classic_webcam(server: OctoPrintServer, port: int) -> None:
    import yaml

    path = server.basedir / "config.yaml"
    config = yaml.safe_load(path.read_text())
    config["plugins"]["classicwebcam"] = {
        "snapshot": f"http://127.0.0.1:{port}/cam0.jpg",
        "stream": f"http://127.0.0.1:{port}/cam0.jpg",
        "snapshotTimeout": 5,
        # a version stops the plugin from "migrating" (overwriting) these from the legacy webcam section
        "_config_version": 1,
    }
    path.write_text(yaml.safe_dump(config))


def start_print(server: OctoPrintServer, gcode: Path, *, speed_percent: int = 1000, name: str | None = None) -> dict:
    """Upload (PrintWatch injects), speed the virtual printer up, select and print; returns the upload answer."""
    uploaded = server.upload(gcode, name=name)
    path = uploaded["files"]["local"]["path"]
    response = server.post("/api/printer/command", {"commands": [f"M220 S{int(speed_percent)}"]})
    response.raise_for_status()
    response = server.post(f"/api/files/local/{path}", {"command": "select", "print": True})
    response.raise_for_status()
    return uploaded


def wait_print_end(server: OctoPrintServer, timeout: float = 300) -> str:
    """Wait until the job is no longer printing; returns the final state text (Operational, Paused ...)."""
    def ended():
        state = server.job()["state"]
        started = state.startswith(("Printing", "Starting", "Pausing", "Cancelling", "Resuming", "Finishing"))
        return None if started else state

    time.sleep(1.0)
    return server.wait_for(ended, timeout, "the print to end or pause", interval=0.5)
