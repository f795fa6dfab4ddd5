"""A test recording's checks run one at a time through one CheckRunner, bottom up, as ``evaluate`` runs them, so a
test can change what the runner remembers between two checks and show which memory a rule rests on."""
from __future__ import annotations

from pathlib import Path
from typing import Callable

from octoprint_printwatch.core.pipeline import CheckResult, CheckRunner, prepare_job
from octoprint_printwatch.core.recording import load_recording
from octoprint_printwatch.core.settings import DetectionSettings


def run_checks(folder: Path,
               before_check: Callable[[CheckRunner, list[CheckResult]], None] | None = None) -> list[CheckResult]:
    """Every check of the recording in ``folder``; ``before_check(runner, results)`` runs before each one, ``results``
    those of the checks before it."""
    recording = load_recording(folder)
    settings = DetectionSettings()
    checks = sorted(recording.checks, key=lambda c: (c.z, c.layer))
    plan = prepare_job(gcode_path=recording.gcode, model_path=recording.model, cameras=recording.cameras,
                       pairs=recording.pairs, check_heights=[(c.layer, c.z) for c in checks], settings=settings)
    runner = CheckRunner(plan, settings, {name: recording.read_background(name) for name in recording.cameras})
    results: list[CheckResult] = []
    for check in checks:
        if before_check is not None:
            before_check(runner, results)
        results.append(runner.run_check(check.layer, check.z,
                                        {name: recording.read_frame(check, name) for name in recording.cameras}))
    return results
