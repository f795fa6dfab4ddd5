"""Contact sheets: a grid of simulated frames, so a reader sees at a glance what the simulator renders.

``python -m octoprint_printwatch.simulator.sheets docs/img`` writes ``sim_<scenario>.jpg`` for every
scenario and ``sim_looks.jpg`` (beds, filaments, backdrops, lights side by side).
"""
from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np

from .look import PRESETS, random_look
from .recording import default_check_layers
from .rig import make_rig
from .scenario import SCENARIOS, Scenario
from .scene import PrintSimulator

TILE = (320, 240)


def _label(tile: np.ndarray, text: str, colour=(255, 255, 255)) -> np.ndarray:
    out = tile.copy()
    cv2.rectangle(out, (0, 0), (out.shape[1], 18), (0, 0, 0), -1)
    cv2.putText(out, text, (4, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.42, colour, 1, cv2.LINE_AA)
    return out


def scenario_sheet(sim: PrintSimulator, cameras: list[str], n_checks: int = 4) -> np.ndarray:
    """Rows: the empty bed, then checks through the print; columns: cameras. BGR uint8."""
    layers = default_check_layers(sim.n_layers)
    if len(layers) > n_checks:
        picks = np.linspace(0, len(layers) - 1, n_checks).round().astype(int)
        layers = [layers[i] for i in picks]
    rows = [np.hstack([_label(cv2.resize(sim.background(c), TILE, interpolation=cv2.INTER_AREA),
                              f"{c} background") for c in cameras])]
    for index, layer in enumerate(layers):
        z = sim.layer_z(layer)
        truth = sim.truth(z)
        flag = truth["should_flag"]
        text = f"layer {layer} z={z:.1f} top={truth['true_top_z']:.1f}" + ("  FAIL" if flag else "")
        tiles = [_label(cv2.resize(sim.frame(c, z, index), TILE, interpolation=cv2.INTER_AREA), f"{c} {text}",
                        (80, 80, 255) if flag else (255, 255, 255)) for c in cameras]
        rows.append(np.hstack(tiles))
    return np.vstack(rows)


def looks_sheet(part: str = "gear", seed: int = 0) -> np.ndarray:
    """Every named look plus random ones, one frame each, for the same part and height."""
    tiles = []
    names = list(PRESETS) + [f"random {k}" for k in range(6)]
    for k, name in enumerate(names):
        rig = make_rig("stations3", seed=seed + k)
        look = PRESETS[name] if name in PRESETS else random_look(seed + 100 + k, rig.bed)
        sim = PrintSimulator(part if k % 3 else "twisted_vase", rig, look, "normal", seed=seed + k)
        z = sim.layer_z(int(sim.n_layers * 0.7))
        cam = rig.names[k % len(rig.names)]
        label = f"{name}: {look.filament.name} on {look.bed}, {look.backdrop}"
        tiles.append(_label(cv2.resize(sim.frame(cam, z, k), TILE, interpolation=cv2.INTER_AREA), label))
    rows = [np.hstack(tiles[i:i + 4]) for i in range(0, len(tiles), 4)]
    return np.vstack(rows)


#: (part, look) shown for each scenario's sheet: different parts and looks, hard cases included.
SHEET_SETUPS = {
    "normal": ("twisted_vase", "seed"),
    "runout": ("sun_gear", "black_on_black"),
    "detach": ("pyramid", "orange_on_gold"),
    "spaghetti": ("cylinder", "white_on_glass"),
    "layer_shift": ("cube", "blue_on_blue_tape"),
    "under_extrusion": ("prism", "glow"),
}


def write_sheets(out_dir: Path, seed: int = 1) -> list[Path]:
    out_dir.mkdir(parents=True, exist_ok=True)
    written = []
    for kind in SCENARIOS:
        part, look = SHEET_SETUPS[kind]
        sim = PrintSimulator(part, make_rig("stations3", seed=seed), look, Scenario(kind), seed=seed)
        path = out_dir / f"sim_{kind}.jpg"
        cv2.imwrite(str(path), scenario_sheet(sim, ["cam0L", "cam0R", "cam1L", "cam2R"]),
                    [cv2.IMWRITE_JPEG_QUALITY, 85])
        written.append(path)
    path = out_dir / "sim_looks.jpg"
    cv2.imwrite(str(path), looks_sheet(seed=seed), [cv2.IMWRITE_JPEG_QUALITY, 85])
    written.append(path)
    return written


if __name__ == "__main__":  # pragma: no cover
    for p in write_sheets(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/img")):
        print(p)
