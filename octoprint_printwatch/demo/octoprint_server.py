"""Starts a real ``octoprint serve`` in a throwaway base folder, for integration tests.

The server runs with the first-run wizard off, access control on (an admin and
a viewer, each with an API key in ``users.yaml``), the virtual printer on the
``VIRTUAL`` port with autoconnect, and every bundled plugin that fetches from
the network disabled, so a test machine without internet gives the same run
every time. Used by the integration tests, the browser tests and
``benchmarks/bench_plugin.py``.
"""
from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import requests
import yaml

ADMIN_USER, ADMIN_PASSWORD, ADMIN_KEY = "admin", "printwatch-admin", "PWADMINKEY0123456789ABCDEF0123456"
VIEWER_USER, VIEWER_PASSWORD, VIEWER_KEY = "viewer", "printwatch-viewer", "PWVIEWERKEY0123456789ABCDEF01234"

#: Bundled plugins that phone home (or that we do not need and that would slow the start).
NETWORK_PLUGINS = [
    "announcements",
    "tracking",
    "errortracking",
    "softwareupdate",
    "backup",
    "achievements",
    "discovery",
    "health_check",
    "gcodeviewer",
]


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def _users_yaml() -> dict:
    from octoprint.access.users import UserManager

    def user(password: str, key: str, groups: list[str]) -> dict:
        return {
            "password": UserManager.create_password_hash(password),
            "active": True,
            "groups": groups,
            "permissions": [],
            "apikey": key,
            "settings": {},
        }

    return {
        "_version": 2,
        ADMIN_USER: user(ADMIN_PASSWORD, ADMIN_KEY, ["admins", "users"]),
        VIEWER_USER: user(VIEWER_PASSWORD, VIEWER_KEY, ["users"]),
    }


def base_config(port: int, printwatch: dict | None = None, extra_disabled: list[str] = ()) -> dict:
    """config.yaml for a quiet, offline, auto-connecting OctoPrint."""
    return {
        "server": {
            "firstRun": False,
            "onlineCheck": {"enabled": False},
            "pluginBlacklist": {"enabled": False},
            "host": "127.0.0.1",
            "port": port,
        },
        "accessControl": {"autologinLocal": False},
        "serial": {
            "port": "VIRTUAL",
            "baudrate": 115200,
            "autoconnect": True,
            "log": False,
            # the virtual printer answers at once; keep timeouts short so a hang shows
            "timeout": {"communication": 5, "detection": 1},
        },
        "webcam": {"webcamEnabled": True},
        "plugins": {
            "_disabled": NETWORK_PLUGINS + list(extra_disabled),
            "virtual_printer": {
                "enabled": True,
                # A "room" at 215 degC: the hot end and bed start at or above the targets of the
                # test files, so M109/M190 return at once (the tests are about the checks, not
                # about 20 s of simulated heating; OctoPrint turns pinnedExtruders' keys into
                # strings, which the virtual printer then ignores).
                "ambientTemperature": 215.0,
                "sendWait": False,
                # No simulated line errors: OctoPrint's resend handling is not under test, and
                # "resend_with_timeout" would add a communication timeout to every run.
                "simulated_errors": [],
            },
            # nothing listens on port 9: the repository and notices fetches fail at once, offline
            "pluginmanager": {"repository": "http://127.0.0.1:9/plugins.json",
                              "notices": "http://127.0.0.1:9/notices.json"},
            "printwatch": printwatch or {},
        },
        "printerProfiles": {"default": "_default"},
    }


@dataclass
class OctoPrintServer:
    """One ``octoprint serve`` process. Use as a context manager."""

    basedir: Path
    printwatch_settings: dict = field(default_factory=dict)
    python: str = sys.executable
    port: int = field(default_factory=free_port)
    extra_disabled: list = field(default_factory=list)
    env: dict = field(default_factory=dict)
    process: subprocess.Popen | None = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"

    def write_config(self) -> None:
        self.basedir.mkdir(parents=True, exist_ok=True)
        config = base_config(self.port, self.printwatch_settings, self.extra_disabled)
        (self.basedir / "config.yaml").write_text(yaml.safe_dump(config))
        (self.basedir / "users.yaml").write_text(yaml.safe_dump(_users_yaml()))

    def start(self, timeout: float = 90.0) -> "OctoPrintServer":
        if not (self.basedir / "config.yaml").exists():
            self.write_config()
        log = open(self.basedir / "serve.log", "ab")
        env = {**os.environ, "PYTHONUNBUFFERED": "1", **self.env}
        self.process = subprocess.Popen(
            [self.python, "-m", "octoprint", "serve", "--iknowwhatimdoing",
             "--host", "127.0.0.1", "--port", str(self.port), "--basedir", str(self.basedir)],
            stdout=log, stderr=subprocess.STDOUT, env=env,
            cwd=str(self.basedir),  # not the repository: "python -m" puts the cwd on sys.path
        )
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                raise RuntimeError(f"octoprint exited with {self.process.returncode}; see {self.basedir / 'serve.log'}")
            try:
                if requests.get(self.url + "/api/version", headers=self.headers(), timeout=2).status_code == 200:
                    return self
            except requests.RequestException:
                pass
            time.sleep(0.3)
        self.stop()
        raise RuntimeError(f"octoprint did not answer within {timeout} s; see {self.basedir / 'serve.log'}")

    def stop(self) -> None:
        if self.process is None or self.process.poll() is not None:
            return
        self.process.terminate()
        try:
            self.process.wait(timeout=20)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=10)

    def __enter__(self) -> "OctoPrintServer":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # ------------------------------------------------------------------ HTTP
    @staticmethod
    def headers(key: str = ADMIN_KEY) -> dict:
        return {"X-Api-Key": key}

    def request(self, method: str, path: str, *, key: str = ADMIN_KEY, timeout: float = 30, **kwargs) -> requests.Response:
        return requests.request(method, self.url + path, headers=self.headers(key), timeout=timeout, **kwargs)

    def get(self, path: str, **kwargs) -> Any:
        response = self.request("GET", path, **kwargs)
        response.raise_for_status()
        return response.json()

    def post(self, path: str, payload: dict | None = None, **kwargs) -> requests.Response:
        return self.request("POST", path, json=payload, **kwargs)

    def wait_for(self, predicate, timeout: float, what: str, interval: float = 0.25):
        """Poll ``predicate()`` until it returns something truthy; fail naming ``what``."""
        deadline = time.monotonic() + timeout
        last = None
        while time.monotonic() < deadline:
            last = predicate()
            if last:
                return last
            if self.process is not None and self.process.poll() is not None:
                raise RuntimeError(f"octoprint died while waiting for {what}")
            time.sleep(interval)
        raise TimeoutError(f"timed out after {timeout} s waiting for {what} (last: {last!r})")

    def wait_operational(self, timeout: float = 60) -> None:
        def operational():
            state = self.get("/api/connection")["current"]["state"]
            if state in ("Closed", "Offline", "Error") or state.startswith("Offline"):
                self.post("/api/connection", {"command": "connect", "port": "VIRTUAL", "autoconnect": True})
            return state == "Operational"

        self.wait_for(operational, timeout, "the virtual printer to be Operational", interval=0.5)

    def upload(self, path: Path, name: str | None = None) -> dict:
        with open(path, "rb") as handle:
            response = self.request(
                "POST", "/api/files/local", files={"file": (name or path.name, handle)}, timeout=120
            )
        response.raise_for_status()
        return response.json()

    def job(self) -> dict:
        return self.get("/api/job")

    def log_text(self) -> str:
        path = self.basedir / "logs" / "octoprint.log"
        return path.read_text(errors="replace") if path.exists() else ""


def dump(data: Any) -> str:
    return json.dumps(data, indent=1, sort_keys=True)[:4000]


class PushListener:
    """What a logged-in browser receives over OctoPrint's websocket: plugin messages and events.

    Runs a tornado websocket client in its own thread; ``messages`` collects every
    decoded message. Use as a context manager around the part of a test that
    should produce pushes.
    """

    def __init__(self, server: OctoPrintServer) -> None:
        import threading

        self.server = server
        self.messages: list[dict] = []
        self._ready = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> "PushListener":
        self._thread.start()
        if not self._ready.wait(20):
            raise RuntimeError("websocket did not authenticate within 20 s")
        return self

    def __exit__(self, *exc) -> None:
        self._stop.set()
        self._thread.join(10)

    def _run(self) -> None:
        import asyncio

        from tornado.websocket import websocket_connect

        login = self.server.post("/api/login", {"passive": True}).json()

        async def listen():
            ws = await websocket_connect(self.server.url.replace("http", "ws", 1) + "/sockjs/websocket")
            await ws.read_message()  # "connected"
            await ws.write_message(json.dumps({"auth": f"{login['name']}:{login['session']}"}))
            self._ready.set()
            while not self._stop.is_set():
                try:
                    raw = await asyncio.wait_for(ws.read_message(), 0.5)
                except asyncio.TimeoutError:
                    continue
                if raw is None:
                    break
                self.messages.append(json.loads(raw))
            ws.close()

        asyncio.run(listen())

    def plugin_messages(self, plugin: str = "printwatch") -> list[dict]:
        return [m["plugin"]["data"] for m in self.messages if "plugin" in m and m["plugin"].get("plugin") == plugin]

    def events(self, prefix: str = "") -> list[dict]:
        return [m["event"] for m in self.messages if "event" in m and m["event"].get("type", "").startswith(prefix)]
