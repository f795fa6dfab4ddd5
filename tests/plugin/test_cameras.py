"""Snapshots: a slow or broken camera is reported within the timeout and never takes the others down."""
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import cv2
import numpy as np
import pytest

from octoprint_printwatch.plugin.cameras import (CameraHealth, DeviceCamera, UrlCamera, grab_all, own_cameras)


@pytest.fixture(scope="module")
def camera_server():
    image = np.zeros((48, 64, 3), np.uint8)
    image[10:30, 20:40] = (0, 0, 255)
    jpeg = cv2.imencode(".jpg", image)[1].tobytes()
    stop = threading.Event()

    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args):
            pass

        def do_GET(self):
            if self.path == "/hang":
                stop.wait(10)
                return
            body = jpeg if self.path == "/good.jpg" else b"<html>not a picture</html>"
            self.send_response(200)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

    server = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    server.daemon_threads = True
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}"
    stop.set()
    server.shutdown()


def test_good_hanging_and_broken_cameras_in_one_grab(camera_server):
    cameras = [
        UrlCamera("good", url=camera_server + "/good.jpg"),
        UrlCamera("hung", url=camera_server + "/hang"),
        UrlCamera("html", url=camera_server + "/page"),
        UrlCamera("gone", url="http://127.0.0.1:9/none.jpg"),
    ]
    started = time.monotonic()
    snaps = grab_all(cameras, timeout=1.0)
    elapsed = time.monotonic() - started
    assert elapsed < 2.0  # the hanging camera costs the timeout, not more
    assert snaps["good"].ok and snaps["good"].image.shape == (48, 64, 3)
    assert snaps["good"].image[20, 30, 2] > 200  # really decoded: red square
    assert snaps["hung"].status in ("timeout", "error") and snaps["hung"].image is None
    assert "hung" in snaps["hung"].error
    assert snaps["html"].status == "error" and "not a JPEG or PNG" in snaps["html"].error
    assert snaps["gone"].status == "error" and "gone" in snaps["gone"].error


def test_missing_video_device_is_an_error_naming_the_camera():
    snap = grab_all([DeviceCamera("usb", source="device", device="/dev/video-printwatch-none")], timeout=3.0)["usb"]
    assert not snap.ok
    assert "usb" in snap.error


def test_disabled_cameras_are_not_asked():
    cameras = own_cameras([
        {"name": "a", "type": "url", "url": "http://127.0.0.1:9/a.jpg", "enabled": False},
        {"name": "b", "type": "device", "device": 3},
        {"type": "url"},  # no name: ignored
    ])
    assert [(c.name, c.source, c.enabled) for c in cameras] == [("a", "url", False), ("b", "device", True)]
    assert list(grab_all(cameras[:1], timeout=0.5)) == []


def test_health_changes_only_when_a_camera_goes_down_or_comes_back(camera_server):
    health = CameraHealth()
    good = grab_all([UrlCamera("c", url=camera_server + "/good.jpg")], 2.0)["c"]
    bad = grab_all([UrlCamera("c", url="http://127.0.0.1:9/x.jpg")], 2.0)["c"]
    assert health.update(good, "t1") is True and health.health == "ok"
    assert health.update(good, "t2") is False
    assert health.update(bad, "t3") is True and health.health == "error" and health.last_ok == "t2"
    assert health.update(good, "t4") is True and health.last_error is None
