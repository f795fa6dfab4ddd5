"""Install test: the wheel installs through OctoPrint's Plugin Manager, offline, and the plugin loads.

A clean OctoPrint needs an environment without our editable install. Installing
OctoPrint into a fresh venv is slow and needs the network, so the test builds a
venv whose site-packages *links* to the project venv's packages, leaving out
PrintWatch's own. The Plugin Manager's pip then installs the wheel (served by a
local HTTP server) into that venv; ``--no-deps`` (its ``pip_args`` setting)
keeps pip from ever touching the linked packages.
"""
from __future__ import annotations

import functools
import shutil
import subprocess
import sys
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import pytest

from octoprint_printwatch.demo.octoprint_server import OctoPrintServer

pytestmark = [pytest.mark.integration, pytest.mark.slow]

ROOT = Path(__file__).resolve().parents[2]


def build_wheel(out: Path) -> Path:
    """``pip wheel --no-deps`` from a copy of the sources (the shared tree gets no build/ or egg-info)."""
    src = out / "src"
    shutil.copytree(ROOT / "octoprint_printwatch", src / "octoprint_printwatch",
                    ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        if (ROOT / name).exists():
            shutil.copy(ROOT / name, src / name)
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "--no-index",
                    "-q", "-w", str(out / "dist"), str(src)], check=True, timeout=300,
                   capture_output=True, cwd=str(out))
    return next((out / "dist").glob("octoprint_printwatch-*.whl"))


def clean_environment(target: Path) -> Path:
    """A venv that sees every package of ours except PrintWatch itself; returns its python."""
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(target)], check=True, timeout=120)
    ours = Path(next(p for p in sys.path if p.endswith("site-packages") and Path(p).is_dir()))
    theirs = next((target / "lib").glob("python*/site-packages"))
    for entry in ours.iterdir():
        lowered = entry.name.lower()
        if "printwatch" in lowered or lowered.startswith("__editable__"):
            continue
        link = theirs / entry.name
        if not link.exists():
            link.symlink_to(entry)
    return target / "bin" / "python"


@pytest.fixture
def wheel_url(tmp_path):
    wheel = build_wheel(tmp_path / "wheel")
    handler = functools.partial(SimpleHTTPRequestHandler, directory=str(wheel.parent))
    handler.log_message = lambda *args: None
    server = ThreadingHTTPServer(("127.0.0.1", 0), handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield f"http://127.0.0.1:{server.server_address[1]}/{wheel.name}"
    server.shutdown()


def plugin_entry(server: OctoPrintServer):
    plugins = server.get("/plugin/pluginmanager/plugins")["plugins"]
    return next((p for p in plugins if p["key"] == "printwatch"), None)


def test_the_wheel_installs_through_the_plugin_manager_and_loads(tmp_path, wheel_url):
    python = clean_environment(tmp_path / "venv")
    check = subprocess.run([str(python), "-c", "import octoprint_printwatch"], capture_output=True, cwd=str(tmp_path))
    assert check.returncode != 0, "the clean environment must not see the editable install"

    server = OctoPrintServer(tmp_path / "octoprint", python=str(python))
    server.write_config()
    import yaml

    config = yaml.safe_load((server.basedir / "config.yaml").read_text())
    config["plugins"]["pluginmanager"]["pip_args"] = "--no-deps"  # one argument only
    (server.basedir / "config.yaml").write_text(yaml.safe_dump(config))

    with server:
        assert plugin_entry(server) is None
        response = server.post("/api/plugin/pluginmanager", {"command": "install", "url": wheel_url}, timeout=300)
        assert response.status_code == 200, response.text
        assert response.json().get("in_progress") is True  # pip runs in the background; the list tells


        def installed():
            entry = plugin_entry(server)
            return entry if entry else None

        entry = server.wait_for(installed, 120, "PrintWatch to appear in the Plugin Manager", interval=1.0)
        assert entry["name"] == "PrintWatch"
    assert list((tmp_path / "venv").glob("lib/python*/site-packages/octoprint_printwatch/plugin/__init__.py"))

    # BlueprintPlugin needs a restart to mount its routes: start again and use the plugin
    with server:
        entry = plugin_entry(server)
        assert entry is not None and entry["enabled"] and entry.get("safe_mode_victim") is False
        status = server.get("/plugin/printwatch/status")
        assert status["api"] == "printwatch-api/1" and status["state"] == "idle"
        assert "PrintWatch ready" in server.log_text()
