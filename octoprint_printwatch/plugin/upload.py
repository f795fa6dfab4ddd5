"""Upload side: inject check blocks into uploaded G-code, keep the original, render expected views early.

- :func:`inject_upload` is what the ``octoprint.filemanager.preprocessor`` hook
  runs: the core's ``inject_checks`` writes the injected copy; the exact upload
  is kept in ``<data>/originals/<sha256 of the injected file>.gcode`` (and the
  injection is exactly removable with ``strip_injected`` besides), so "print
  without checks" restores the upload byte for byte.
- :class:`Preparer` renders the expected views of a file in one background
  thread (two cores are shared with OctoPrint), cached per original-file hash
  and calibrated camera set; a check asks :meth:`Preparer.wait` with a short
  timeout and never waits for rendering longer than that.

No OctoPrint import.
"""
from __future__ import annotations

import hashlib
import logging
import re
import shutil
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from ..core.errors import PrintWatchError
from . import settings as plugin_settings

CHECK_LINE = re.compile(rb"^@PRINTWATCH_CHECK\b([^\r\n]*)", re.MULTILINE)
_PARAM = re.compile(rb"(\w+)=([^\s]+)")


def sha256_of(path: str | Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            digest.update(chunk)
    return digest.hexdigest()


def planned_checks(path: str | Path) -> list[tuple[int, float]]:
    """(layer, z) of every ``@PRINTWATCH_CHECK`` marker in a G-code file, in file order."""
    data = Path(path).read_bytes()
    checks = []
    for match in CHECK_LINE.finditer(data):
        params = {k.decode().lower(): v.decode() for k, v in _PARAM.findall(match.group(1))}
        try:
            checks.append((int(params["layer"]), float(params["z"])))
        except (KeyError, ValueError):
            continue
    return checks


def is_injected(path: str | Path) -> bool:
    """True when the file holds PrintWatch markers (read in chunks; stops at the first)."""
    needle = b"@PRINTWATCH_"
    tail = b""
    with open(path, "rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            if needle in tail + chunk:
                return True
            tail = chunk[-len(needle):]
    return False


def injection_options(values: Mapping[str, Any], profile: Mapping[str, Any] | None) -> dict:
    """Keyword arguments of ``core.inject.inject_checks`` from the plugin settings and the printer profile."""
    x_min, x_max, y_min, y_max, max_z = plugin_settings.bed_from_profile(profile)
    options: dict[str, Any] = {
        "lift": float(values.get("lift_mm", 20.0)),
        "park": plugin_settings.park_position(values, profile),  # None: injector's default
        "max_z": max_z,
        "bed": (x_min, x_max, y_min, y_max),
        "background": True,
    }
    if values.get("interval_mode", "layers") == "mm":
        options["every_mm"] = float(values.get("every_mm", 5.0))
    else:
        options["every"] = int(values.get("every_layers", 30))
    return options


class OriginalStore:
    """Exact copies of uploads, by the SHA-256 of the injected file they became."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)

    def path_for(self, injected_sha: str) -> Path:
        return self.folder / f"{injected_sha}.gcode"

    def keep(self, original: Path, injected: Path) -> Path:
        target = self.path_for(sha256_of(injected))
        if not target.exists():
            tmp = target.with_suffix(".tmp")
            shutil.copyfile(original, tmp)
            tmp.replace(target)
        return target

    def prune(self, files_in_storage) -> list[str]:
        """Delete kept originals whose injected file is no longer in OctoPrint's storage.

        ``files_in_storage``: paths of the G-code files OctoPrint has now. Returns the removed names.
        """
        alive = {sha256_of(path) for path in files_in_storage if Path(path).is_file() and is_injected(path)}
        removed = []
        for kept in self.folder.glob("*.gcode"):
            sha = kept.name.split(".", 1)[0]
            if sha not in alive:
                kept.unlink(missing_ok=True)
                removed.append(kept.name)
        return removed

    def original_of(self, gcode_path: str | Path) -> Path | None:
        """The exact upload behind a file on disk: the kept copy, else the file with the injection stripped."""
        gcode_path = Path(gcode_path)
        if not gcode_path.is_file():
            return None
        if not is_injected(gcode_path):
            return gcode_path
        sha = sha256_of(gcode_path)
        kept = self.path_for(sha)
        if kept.exists():
            return kept
        from ..core.inject import strip_injected

        stripped = self.folder / f"{sha}.stripped.gcode"
        if not stripped.exists():
            tmp = stripped.with_suffix(".tmp")
            with open(tmp, "wb") as out:
                for line in strip_injected(str(gcode_path)):
                    out.write(line)
            tmp.replace(stripped)
        return stripped


def inject_upload(src: Path, dst: Path, values: Mapping[str, Any], profile: Mapping[str, Any] | None,
                  store: OriginalStore):
    """Inject ``src`` into ``dst`` and keep the original; returns the core's InjectionResult.

    Raises PrintWatchError (one line) for a file the injector cannot handle; the caller then
    stores the upload unchanged.
    """
    from ..core.inject import inject_checks

    options = injection_options(values, profile)
    if "every_mm" in options:
        every_mm = options.pop("every_mm")
        from ..core.gcode import analyse

        top = max((layer.z for layer in analyse(src).layers), default=0.0)
        heights = []
        z = every_mm
        while z < top - 1e-6:
            heights.append(round(z, 4))
            z += every_mm
        options["heights"] = heights
    result = inject_checks(src, dst, **options)
    store.keep(src, dst)
    return result


# ---------------------------------------------------------------------- preparation
@dataclass
class Preparation:
    key: str
    state: str = "queued"  # queued | rendering | ready | failed
    progress: float = 0.0
    message: str = ""
    plan: Any = None
    started: float = 0.0
    seconds: float | None = None
    done: threading.Event = field(default_factory=threading.Event)

    def as_json(self) -> dict:
        return {"state": self.state, "progress": round(self.progress, 3), "message": self.message,
                "seconds": None if self.seconds is None else round(self.seconds, 2)}


class Preparer:
    """Renders expected views in one background thread; results kept in memory by key."""

    def __init__(self, prepare: Callable[..., Any], on_change: Callable[[str, dict], None] | None = None,
                 logger: logging.Logger | None = None, keep: int = 8) -> None:
        self._prepare = prepare
        self._on_change = on_change or (lambda key, status: None)
        self._log = logger or logging.getLogger(__name__)
        self._lock = threading.Lock()
        self._jobs: dict[str, Preparation] = {}
        self._queue: list[tuple[Preparation, dict]] = []
        self._wake = threading.Condition(self._lock)
        self._keep = keep
        self._stopped = False
        self._thread = threading.Thread(target=self._loop, name="printwatch-prepare", daemon=True)
        self._thread.start()

    @staticmethod
    def key_for(original_sha: str, camera_key: str, planned) -> str:
        heights = hashlib.sha256(repr([(int(l), round(float(z), 4)) for l, z in planned]).encode()).hexdigest()[:8]
        return f"{original_sha[:16]}-{camera_key}-{heights}"

    def request(self, key: str, **kwargs: Any) -> Preparation:
        """Queue ``prepare(**kwargs)`` under ``key`` unless it is queued, running or done."""
        with self._lock:
            job = self._jobs.get(key)
            if job is not None and job.state != "failed":
                return job
            job = Preparation(key)
            self._jobs[key] = job
            self._queue.append((job, kwargs))
            self._wake.notify()
        self._on_change(key, job.as_json())
        return job

    def wait(self, key: str | None, timeout: float):
        """The plan of ``key`` if it is ready within ``timeout`` seconds, else None."""
        job = self._jobs.get(key) if key else None
        if job is None:
            return None
        job.done.wait(max(0.0, timeout))
        return job.plan if job.state == "ready" else None

    def status(self, key: str | None) -> dict:
        job = self._jobs.get(key) if key else None
        return job.as_json() if job else {"state": "none", "progress": 0.0, "message": "", "seconds": None}

    def stop(self) -> None:
        with self._lock:
            self._stopped = True
            self._wake.notify()

    def _loop(self) -> None:
        while True:
            with self._lock:
                while not self._queue and not self._stopped:
                    self._wake.wait()
                if self._stopped:
                    return
                job, kwargs = self._queue.pop(0)
                job.state, job.started = "rendering", time.monotonic()
            self._on_change(job.key, job.as_json())
            try:
                job.plan = self._prepare(**kwargs)
                job.state, job.progress, job.message = "ready", 1.0, ""
            except PrintWatchError as exc:
                job.state, job.message = "failed", str(exc)
                self._log.warning("PrintWatch: preparing %s failed: %s", job.key, exc)
            except Exception as exc:
                job.state, job.message = "failed", f"{type(exc).__name__}: {exc}"
                self._log.exception("PrintWatch: preparing %s failed", job.key)
            job.seconds = time.monotonic() - job.started
            job.done.set()
            self._on_change(job.key, job.as_json())
            self._forget_old()

    def _forget_old(self) -> None:
        with self._lock:
            finished = [k for k, j in self._jobs.items() if j.done.is_set()]
            for key in finished[: max(0, len(finished) - self._keep)]:
                del self._jobs[key]
