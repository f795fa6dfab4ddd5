"""Camera snapshots: OctoPrint's webcams and our own (snapshot URLs, local video devices).

A check grabs one frame from every camera at once, each in its own thread,
and waits at most ``timeout`` seconds in total: a camera that does not answer
by then is reported (``status: timeout``) and left out, it never fails a
check. Nothing here blocks OctoPrint's threads; the coordinator calls
:func:`grab_all` from its worker thread.

OctoPrint imports are limited to the webcam adapter (``OctoPrintWebcam``),
which receives the provider object from the plugin.
"""
from __future__ import annotations

import threading
import time
import urllib.request
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Mapping

import cv2
import numpy as np


class SnapshotError(Exception):
    """A camera gave no usable frame; the message says which camera and why."""


@dataclass
class Snapshot:
    """The answer of one camera: ``image`` (h, w, 3) uint8 BGR, or None with ``error``."""

    name: str
    image: np.ndarray | None
    status: str  # "ok" | "timeout" | "error"
    error: str | None
    seconds: float
    encoded: bytes | None = None  # the bytes the camera sent (JPEG/PNG), for the API

    @property
    def ok(self) -> bool:
        return self.image is not None


def decode_image(data: bytes, what: str) -> np.ndarray:
    """(h, w, 3) uint8 BGR from JPEG/PNG bytes; raises SnapshotError naming ``what``."""
    if not data:
        raise SnapshotError(f"{what}: empty answer")
    image = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_COLOR)
    if image is None:
        raise SnapshotError(f"{what}: answer is not a JPEG or PNG image ({len(data)} bytes)")
    return image


@dataclass
class CameraSource:
    """A camera the plugin can take snapshots from."""

    name: str
    label: str = ""
    source: str = "url"  # "octoprint" | "url" | "device"
    enabled: bool = True

    def fetch(self, timeout: float) -> bytes:  # pragma: no cover - interface
        raise NotImplementedError

    def describe(self) -> str:
        return self.name


@dataclass
class UrlCamera(CameraSource):
    """A camera with an HTTP snapshot URL (mjpg-streamer, ustreamer, ESP32-CAM ...)."""

    url: str = ""

    def fetch(self, timeout: float) -> bytes:
        if not self.url:
            raise SnapshotError(f"camera {self.name}: no snapshot URL configured")
        try:
            with urllib.request.urlopen(self.url, timeout=timeout) as response:
                return response.read()
        except Exception as exc:  # URLError, timeout, HTTP errors: all mean "no frame"
            raise SnapshotError(f"camera {self.name}: {self.url}: {getattr(exc, 'reason', exc)}") from None

    def describe(self) -> str:
        return self.url


@dataclass
class DeviceCamera(CameraSource):
    """A local video device opened through OpenCV (``/dev/videoN`` or its index)."""

    device: Any = 0
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    def fetch(self, timeout: float) -> bytes:
        with self._lock:  # one V4L2 open at a time per device
            capture = cv2.VideoCapture(int(self.device) if str(self.device).isdigit() else str(self.device))
            try:
                if not capture.isOpened():
                    raise SnapshotError(f"camera {self.name}: cannot open video device {self.device}")
                # Drivers hand out a few stale buffered frames first; drop them.
                for _ in range(3):
                    capture.grab()
                ok, image = capture.read()
                if not ok or image is None:
                    raise SnapshotError(f"camera {self.name}: video device {self.device} gave no frame")
                ok, buf = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, 92])
                return buf.tobytes()
            finally:
                capture.release()

    def describe(self) -> str:
        return f"video device {self.device}"


@dataclass
class OctoPrintWebcam(CameraSource):
    """A webcam another OctoPrint plugin provides; ``snapshot`` is its provider's ``take_webcam_snapshot``."""

    snapshot: Callable[[str], Iterable[bytes]] | None = None

    def fetch(self, timeout: float) -> bytes:
        if self.snapshot is None:
            raise SnapshotError(f"camera {self.name}: its provider cannot take snapshots")
        try:
            return b"".join(self.snapshot(self.name))
        except Exception as exc:
            raise SnapshotError(f"camera {self.name}: snapshot failed: {exc}") from None

    def describe(self) -> str:
        return f"OctoPrint webcam {self.name}"


def own_cameras(entries: Iterable[Mapping[str, Any]]) -> list[CameraSource]:
    """Cameras from the ``cameras`` setting ([{name, type, url | device, label, enabled}])."""
    cameras: list[CameraSource] = []
    for entry in entries or []:
        if not isinstance(entry, Mapping) or not entry.get("name"):
            continue
        kind = str(entry.get("type", "url"))
        common = dict(name=str(entry["name"]), label=str(entry.get("label") or ""), enabled=bool(entry.get("enabled", True)))
        if kind == "device":
            cameras.append(DeviceCamera(source="device", device=entry.get("device", 0), **common))
        else:
            cameras.append(UrlCamera(source="url", url=str(entry.get("url") or ""), **common))
    return cameras


def grab_one(camera: CameraSource, timeout: float) -> Snapshot:
    start = time.monotonic()
    try:
        data = camera.fetch(timeout)
        image = decode_image(data, f"camera {camera.name}")
        return Snapshot(camera.name, image, "ok", None, time.monotonic() - start, data)
    except SnapshotError as exc:
        return Snapshot(camera.name, None, "error", str(exc), time.monotonic() - start)
    except Exception as exc:  # a driver bug must not take the check down with it
        return Snapshot(camera.name, None, "error", f"camera {camera.name}: {type(exc).__name__}: {exc}",
                        time.monotonic() - start)


def grab_all(cameras: Iterable[CameraSource], timeout: float) -> dict[str, Snapshot]:
    """One snapshot per enabled camera, in parallel, within ``timeout`` seconds in total."""
    cameras = [c for c in cameras if c.enabled]
    results: dict[str, Snapshot] = {}
    lock = threading.Lock()

    def work(camera: CameraSource) -> None:
        snap = grab_one(camera, timeout)
        with lock:
            results.setdefault(camera.name, snap)

    start = time.monotonic()
    threads = []
    for camera in cameras:
        # Daemon threads: a camera that hangs past its own timeout is abandoned, not waited for.
        thread = threading.Thread(target=work, args=(camera,), name=f"printwatch-snap-{camera.name}", daemon=True)
        thread.start()
        threads.append(thread)
    for thread in threads:
        thread.join(max(0.0, timeout - (time.monotonic() - start)))
    with lock:
        for camera in cameras:
            if camera.name not in results:
                results[camera.name] = Snapshot(
                    camera.name, None, "timeout",
                    f"camera {camera.name}: no answer from {camera.describe()} within {timeout:g} s",
                    time.monotonic() - start,
                )
        return {c.name: results[c.name] for c in cameras}


@dataclass
class CameraHealth:
    """What the UI shows about a camera between checks."""

    health: str = "unknown"
    last_error: str | None = None
    last_ok: str | None = None
    last_seconds: float | None = None

    def update(self, snap: Snapshot, now: str) -> bool:
        """Record a snapshot result; True when the health changed (worth a status push)."""
        before = self.health
        if snap.ok:
            self.health, self.last_error, self.last_ok = "ok", None, now
        else:
            self.health, self.last_error = "error", snap.error
        self.last_seconds = round(snap.seconds, 3)
        return before != self.health
