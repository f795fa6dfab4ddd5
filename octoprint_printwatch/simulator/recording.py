"""Write a simulated print as a recording (``docs/recording-format.md``) plus its ``truth.json``."""
from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Sequence

from ..core.recording import RecordingWriter
from .scene import PrintSimulator

TRUTH_FORMAT = "printwatch-truth/1"


def default_check_layers(n_layers: int, every: int | None = None) -> list[int]:
    """The seed's schedule: every N layers (N = 30 for tall parts, fewer for short ones), and the last layer."""
    if every is None:
        every = max(5, min(30, n_layers // 6))
    layers = list(range(every, n_layers, every))
    if not layers or layers[-1] != n_layers:
        layers.append(n_layers)
    return layers


def write_recording(out_dir: str | Path, simulator: PrintSimulator, check_heights: Sequence[float] | None = None, *,
                    every_n_layers: int | None = None, image_format: str = "jpg", jpeg_quality: int = 95,
                    cameras: Sequence[str] | None = None) -> Path:
    """Render a whole simulated print into ``out_dir``; returns the path of ``session.json``.

    ``check_heights`` (mm) default to :func:`default_check_layers`. Cameras and
    pairs in ``session.json`` are the rig's *calibrated* estimates (what a user
    would have); the true ones go to ``truth.json`` with the ground truth of
    every check.
    """
    out = Path(out_dir)
    lh = simulator.layer_height
    if check_heights is None:
        layers = default_check_layers(simulator.n_layers, every_n_layers)
    else:
        layers = sorted({max(1, int(round(float(z) / lh))) for z in check_heights})
    names = list(cameras) if cameras else simulator.camera_names
    rig = simulator.rig
    calibrated = {n: rig.calibrated(n) for n in names}
    pairs = [p for p in rig.pairs if p[0] in calibrated and p[1] in calibrated]
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        model = Path(tmp) / "model.stl"
        simulator.model_in_printer_coordinates().export(model)
        writer = RecordingWriter(out, calibrated, pairs=pairs, model=model, gcode=simulator.gcode_path,
                                 layer_height=lh, image_format=image_format, jpeg_quality=jpeg_quality)
    for name in names:
        writer.add_background(name, simulator.background(name))
    checks = []
    for index, layer in enumerate(layers):
        z = simulator.layer_z(layer)
        writer.add_check(layer, z, {name: simulator.frame(name, z, index) for name in names})
        checks.append(simulator.truth(z))
    flagged = [c["layer"] for c in checks if c["should_flag"]]
    truth = {
        "format": TRUTH_FORMAT,
        "part": simulator.part_name,
        "seed": simulator.seed,
        "scenario": simulator.scenario.to_dict(),
        "onset_z": simulator.onset_z,
        "part_height": round(simulator.height, 4),
        "n_layers": simulator.n_layers,
        "first_flag_layer": flagged[0] if flagged else None,
        "look": {"bed": simulator.look.bed, "backdrop": simulator.look.backdrop,
                 "filament": simulator.look.filament.name},
        "cameras_true": {n: rig.true(n).to_dict() for n in names},
        "checks": checks,
    }
    tmp_truth = out / "truth.json.tmp"
    tmp_truth.write_text(json.dumps(truth, indent=1))
    tmp_truth.replace(out / "truth.json")
    return writer.session_path
