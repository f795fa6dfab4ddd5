"""Edited copies of the test recordings (``tests/data/recordings``): the same view with a failure or a lost
file made from it, so a test can show a rule both ways. Each copy's paths come from its own session.json."""
from __future__ import annotations

import json
import shutil
from pathlib import Path


def _copy(source: Path, tmp_path: Path, label: str) -> tuple[Path, dict]:
    copy = tmp_path / f"{source.name}_{label}"
    shutil.copytree(source, copy)
    return copy, json.loads((copy / "session.json").read_text(encoding="utf-8"))


def empty_bed_at(source: Path, camera: str, index: int, tmp_path: Path) -> Path:
    """A copy of recording ``source`` whose ``camera`` sees the empty bed (its background frame) at the check
    ``index`` (in session.json's order): the part knocked off before that check."""
    copy, session = _copy(source, tmp_path, f"{camera}_empty_at_{index}")
    shutil.copy(copy / session["background"][camera], copy / session["checks"][index]["frames"][camera])
    return copy


def stopped_after(source: Path, camera: str, index: int, tmp_path: Path) -> Path:
    """A copy of recording ``source`` whose ``camera`` sees the frame of check ``index`` again at every later
    check: the print stopped there."""
    copy, session = _copy(source, tmp_path, f"{camera}_stopped_after_{index}")
    held = copy / session["checks"][index]["frames"][camera]
    for check in session["checks"][index + 1:]:
        shutil.copy(held, copy / check["frames"][camera])
    return copy


def without_background(source: Path, camera: str, tmp_path: Path) -> Path:
    """A copy of recording ``source`` whose ``camera`` has no empty-bed frame (the writer lost it)."""
    copy, session = _copy(source, tmp_path, f"no_{camera}_background")
    (copy / session["background"].pop(camera)).unlink()
    (copy / "session.json").write_text(json.dumps(session, indent=1), encoding="utf-8")
    return copy
