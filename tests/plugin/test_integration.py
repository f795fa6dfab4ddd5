"""A real OctoPrint, the virtual printer, simulated webcams following the real job: the plugin end to end.

Each test starts ``octoprint serve`` in a throwaway base folder (see
``octoprint_printwatch/demo/octoprint_server.py``) with PrintWatch configured for two simulated webcams
(``octoprint_printwatch/demo/webcam_server.py``), uploads a real PrusaSlicer file (PrintWatch injects the
checks on upload) and prints it on the virtual printer, sped up with ``M220``.
"""
from __future__ import annotations

import io
import time
import zipfile
from pathlib import Path

import pytest
import requests

from octoprint_printwatch.demo.octoprint_server import VIEWER_KEY, PushListener
from stack import PART, printwatch_stack, start_print, wait_print_end

pytestmark = [pytest.mark.integration, pytest.mark.slow]

GCODE = Path(__file__).resolve().parents[2] / "octoprint_printwatch" / "data" / "parts" / f"{PART}.gcode"
SPEED = 2000  # percent: the virtual printer at 20x; holds and vision are real time
API = "/plugin/printwatch"


def print_detail(server, print_id=None):
    """The print's history entry once PrintWatch has closed it (a moment after OctoPrint's own state)."""
    prints = server.get(f"{API}/prints")["prints"]
    assert prints, "no print in the history"
    url = f"{API}/prints/{print_id or prints[0]['id']}"

    def settled():
        detail = server.get(url)
        return detail if detail["result"] != "running" else None

    return server.wait_for(settled, 30, "PrintWatch to close the print in its history")


def test_normal_print_completes_with_every_check_passing(tmp_path):
    with printwatch_stack(tmp_path) as (server, _):
        uploaded = start_print(server, GCODE, speed_percent=SPEED)
        path = uploaded["files"]["local"]["path"]
        planned = server.get(f"{API}/files/local/{path}")
        assert planned["injected"] and [c["layer"] for c in planned["checks"]] == [20, 40, 60, 80, 100]

        assert wait_print_end(server, timeout=240) == "Operational"
        detail = print_detail(server)
        assert detail["result"] == "done", detail
        checks = detail["checks"]
        assert [c["layer"] for c in checks] == [20, 40, 60, 80, 100]
        for check in checks:
            assert check["verdict"] == "ok", check
            assert check["action"] == "none"
            assert set(check["shape_error_pct"]) == {"classic", "cam1"}
            assert all(pct is not None and pct < 7.0 for pct in check["shape_error_pct"].values()), check
            assert {c["status"] for c in check["cameras"].values()} == {"ok"}
        # the frames and overlays the UI shows are served
        last = checks[-1]["cameras"]["classic"]
        for url, kind in ((last["frame_url"], b"\xff\xd8"), (last["overlay_url"], b"\x89PNG")):
            response = server.request("GET", f"{API}/{url}")
            assert response.status_code == 200 and response.content[:2] == kind[:2]

        # the recording downloads as a zip that the core reads back
        response = server.request("GET", f"{API}/{detail['recording']['url']}")
        assert response.status_code == 200 and response.headers["Content-Type"] == "application/zip"
        with zipfile.ZipFile(io.BytesIO(response.content)) as archive:
            archive.extractall(tmp_path / "download")
        from octoprint_printwatch.core.recording import load_recording

        recording = load_recording(next((tmp_path / "download").iterdir()))
        assert [c.layer for c in recording.checks] == [20, 40, 60, 80, 100]
        assert set(recording.backgrounds) == {"classic", "cam1"}
        assert recording.gcode.read_bytes() == GCODE.read_bytes()  # the upload, not the injected file

        # re-running the recording with the same settings gives the verdicts the print got
        rerun = server.post(f"{API}/prints/{detail['id']}/evaluate", {"settings": {}}, timeout=300)
        assert rerun.status_code == 200, rerun.text
        assert [(c["layer"], c["verdict"]) for c in rerun.json()["checks"]] == [(c["layer"], "ok") for c in checks]

        # a viewer sees everything but may not change or re-run; nobody anonymous gets in
        assert server.request("GET", f"{API}/status", key=VIEWER_KEY).status_code == 200
        assert server.request("POST", f"{API}/prints/{detail['id']}/evaluate", key=VIEWER_KEY,
                              json={}).status_code == 403
        assert requests.get(server.url + f"{API}/status", timeout=10).status_code == 403


def test_runout_mid_print_pauses_at_the_first_check_after_it(tmp_path):
    with printwatch_stack(tmp_path, scenario="runout", onset_layer=45) as (server, webcam_port):
        with PushListener(server) as pushes:
            start_print(server, GCODE, speed_percent=SPEED)
            assert wait_print_end(server, timeout=240) == "Paused"
            time.sleep(0.5)
        # what a browser got: the popup's message and the events other plugins react to
        failures = [m for m in pushes.plugin_messages() if m["type"] == "failure"]
        assert len(failures) == 1 and failures[0]["check"]["layer"] == 60 and failures[0]["action"] == "pause"
        assert [m["check"]["layer"] for m in pushes.plugin_messages() if m["type"] == "check"] == [20, 40, 60]
        assert "paused" in [m["status"]["state"] for m in pushes.plugin_messages() if m["type"] == "status"]
        events = pushes.events("plugin_printwatch_")
        assert [e["payload"]["layer"] for e in events if e["type"] == "plugin_printwatch_check_done"] == [20, 40, 60]
        detected = [e for e in events if e["type"] == "plugin_printwatch_failure_detected"]
        assert len(detected) == 1 and detected[0]["payload"]["message"] == failures[0]["message"]
        status = server.get(f"{API}/status")
        assert status["state"] == "paused"
        failure = status["last_failure"]
        assert failure["layer"] == 60 and failure["action"] == "pause"
        assert "layer 60" in failure["reason"]

        detail = print_detail(server)
        assert [(c["layer"], c["verdict"]) for c in detail["checks"]] == [(20, "ok"), (40, "ok"), (60, "fail")]
        assert detail["result"] == "paused" and detail["first_failure_layer"] == 60
        assert detail["failure_reason"] and detail["failure_reason"] in failure["reason"]
        # re-run with other settings: they reach the detector (the UI redraws the chart from this answer),
        # and with the print's own settings the verdicts are the print's
        other = {"shape_threshold_pct": 50.0, "detection": {"min_failing_cameras": 2, "band_threshold_pct": 20.0}}
        rerun = server.post(f"{API}/prints/{detail['id']}/evaluate", {"settings": other}, timeout=300)
        assert rerun.status_code == 200, rerun.text
        rerun = rerun.json()
        assert rerun["settings"]["shape_threshold_pct"] == 50.0 and rerun["settings"]["min_failing_cameras"] == 2
        assert rerun["settings"]["band_threshold_pct"] == 20.0
        assert rerun["checks"][2]["thresholds"]["shape_pct"] == {"classic": 50.0, "cam1": 50.0}
        assert rerun["checks"][2]["shape_error_pct"] == detail["checks"][2]["shape_error_pct"]
        same = server.post(f"{API}/prints/{detail['id']}/evaluate", {"settings": {}}, timeout=300).json()
        assert [c["verdict"] for c in same["checks"]] == ["ok", "ok", "fail"]
        bad = server.post(f"{API}/prints/{detail['id']}/evaluate", {"settings": {"shape_threshold_pct": -3}})
        assert bad.status_code == 400 and "shape_threshold_pct" in bad.json()["error"]

        # nothing was printed after the failing check: the job stopped right at its marker
        time.sleep(1.0)
        job = server.job()
        assert job["state"] == "Paused"
        injected = server.request("GET", f"/downloads/files/local/{job['job']['file']['path']}").content
        marker_end = injected.index(b"\n", injected.index(b"@PRINTWATCH_CHECK layer=60")) + 1
        assert job["progress"]["filepos"] == marker_end
        served = requests.get(f"http://127.0.0.1:{webcam_port}/served", timeout=5).json()
        assert max(item["z"] for item in served) == pytest.approx(12.0)  # the webcams saw layer 60, no later


def test_dead_camera_is_reported_and_never_pauses(tmp_path):
    with printwatch_stack(tmp_path, dead=["cam1"]) as (server, _):
        start_print(server, GCODE, speed_percent=SPEED)
        assert wait_print_end(server, timeout=300) == "Operational"
        detail = print_detail(server)
        assert detail["result"] == "done"
        assert len(detail["checks"]) == 5
        for check in detail["checks"]:
            assert check["verdict"] == "ok", check
            assert check["cameras"]["cam1"]["status"] in ("timeout", "error")
            assert "cam1" in check["cameras"]["cam1"]["error"]
            assert check["cameras"]["classic"]["status"] == "ok"
            assert check["hold_seconds"] < 3.0 + 2.5  # camera timeout plus vision, never the camera's hang
        cameras = {c["name"]: c for c in server.get(f"{API}/status")["cameras"]}
        assert cameras["cam1"]["health"] == "error" and cameras["classic"]["health"] == "ok"

        # on-demand snapshots: the dead camera is a one-line 503, the live one a JPEG
        dead = server.request("GET", f"{API}/cameras/cam1/snapshot")
        assert dead.status_code == 503 and "cam1" in dead.json()["error"]
        live = server.request("GET", f"{API}/cameras/classic/snapshot")
        assert live.status_code == 200 and live.content[:2] == b"\xff\xd8"
        assert server.request("GET", f"{API}/cameras/nope/snapshot").status_code == 404
        assert server.request("GET", f"{API}/cameras/classic/snapshot", key=VIEWER_KEY).status_code == 403
        # the wizard over HTTP: no board in view is said plainly, never a traceback
        session = server.post(f"{API}/calibration/classic/capture").json()
        assert session["frames"][0]["detected"] is False
        refused = server.post(f"{API}/calibration/classic/compute")
        assert refused.status_code == 400 and "capture at least" in refused.json()["error"]
        assert server.request("GET", f"{API}/prints/999").status_code == 404
        # settings through OctoPrint's own API: a good value is kept, one that would break the checks is not
        server.post("/api/settings", {"plugins": {"printwatch": {"shape_threshold_pct": 6.5}}}).raise_for_status()
        server.post("/api/settings", {"plugins": {"printwatch": {"shape_threshold_pct": -5}}})
        assert server.get("/api/settings")["plugins"]["printwatch"]["shape_threshold_pct"] == 6.5
        assert server.request("GET", f"{API}/prints/1/checks/0/../../../x/frame.jpg").status_code in (400, 404)


def test_history_survives_a_restart_mid_print_and_checks_can_be_switched_off_per_file(tmp_path):
    with printwatch_stack(tmp_path) as (server, _):
        uploaded = start_print(server, GCODE, speed_percent=200)  # slow: stop it between checks
        path = uploaded["files"]["local"]["path"]
        server.wait_for(lambda: server.get(f"{API}/status")["checks_done"] >= 1, 120, "the first check")
        server.stop()  # OctoPrint goes away mid-print
        server.start()
        detail = print_detail(server)
        assert detail["result"] == "interrupted"
        assert detail["checks"][0]["layer"] == 20

        # "print without checks": the exact upload comes back, and the checks can be put back
        server.wait_operational()
        off = server.post(f"{API}/files/local/{path}", {"checks_enabled": False})
        assert off.status_code == 200, off.text
        assert off.json()["injected"] is False and off.json()["checks"] == []
        download = server.request("GET", f"/downloads/files/local/{path}")
        assert download.content == GCODE.read_bytes()
        on = server.post(f"{API}/files/local/{path}", {"checks_enabled": True})
        assert on.status_code == 200 and [c["layer"] for c in on.json()["checks"]] == [20, 40, 60, 80, 100]
        bad = server.post(f"{API}/files/local/{path}", {"checks_enabled": "maybe"})
        assert bad.status_code == 400 and "checks_enabled" in bad.json()["error"]
        assert server.request("GET", f"{API}/files/local/nothing.gcode").status_code == 404
