"""Print failures the simulator can inject, their geometry, and their ground truth."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.errors import PrintWatchError

SCENARIOS = ("normal", "runout", "detach", "spaghetti", "layer_shift", "under_extrusion")


@dataclass
class Scenario:
    """What happens to the print.

    ``onset_layer`` is the 1-based layer at which the failure starts (the last
    good layer is ``onset_layer - 1``); None picks one from the seed at 35-60 %
    of the part's height. Kind-specific parameters left None are drawn from the
    seed: ``shift_mm`` (dx, dy) for layer shifts, ``detach_mode``
    (``"shifted"`` or ``"tipped"``), ``under_extrusion`` (fraction of missing
    material, 0..1).
    """

    kind: str = "normal"
    onset_layer: int | None = None
    shift_mm: tuple[float, float] | None = None
    detach_mode: str | None = None
    under_extrusion: float | None = None
    params: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.kind not in SCENARIOS:
            raise PrintWatchError(f"unknown scenario {self.kind!r}; choose from {', '.join(SCENARIOS)}")
        if self.onset_layer is not None and int(self.onset_layer) < 1:
            raise PrintWatchError(f"onset layer must be 1 or more, got {self.onset_layer}")
        if self.detach_mode not in (None, "shifted", "tipped"):
            raise PrintWatchError(f"detach mode must be 'shifted' or 'tipped', got {self.detach_mode!r}")

    def resolved(self, n_layers: int, seed: int) -> "Scenario":
        """A copy with every random parameter fixed for this part and seed."""
        rng = np.random.default_rng([seed, 0x5CE])
        onset = self.onset_layer
        if self.kind == "normal":
            onset = None
        elif onset is None:
            onset = int(max(2, round(n_layers * rng.uniform(0.35, 0.6))))
        elif onset > n_layers:
            raise PrintWatchError(f"onset layer {onset} is beyond the part's last layer {n_layers}")
        shift = self.shift_mm
        if self.kind == "layer_shift" and shift is None:
            a = rng.uniform(0, 2 * np.pi)
            r = rng.uniform(2.0, 6.0)
            shift = (float(r * np.cos(a)), float(r * np.sin(a)))
        mode = self.detach_mode or (str(rng.choice(["shifted", "tipped"])) if self.kind == "detach" else None)
        under = self.under_extrusion
        if self.kind == "under_extrusion" and under is None:
            under = float(rng.uniform(0.35, 0.7))
        return Scenario(self.kind, onset, shift, mode, under, dict(self.params))

    def to_dict(self) -> dict:
        return {"kind": self.kind, "onset_layer": self.onset_layer,
                "shift_mm": list(self.shift_mm) if self.shift_mm else None,
                "detach_mode": self.detach_mode, "under_extrusion": self.under_extrusion, **self.params}


def should_flag(kind: str, onset_z: float | None, z: float, true_top: float) -> tuple[bool, bool]:
    """(failure has started, a working detector must flag it by now).

    A failure is "due" once it is big enough to see: 2 mm or 8 % of the height
    missing for runout, 2 mm of spaghetti / shifted / under-extruded layers,
    any check after the part came loose.
    """
    if kind == "normal" or onset_z is None or z <= onset_z + 1e-6:
        return False, False
    grown = z - onset_z
    if kind == "runout":
        due = (z - true_top) >= max(2.0, 0.08 * z)
    elif kind == "detach":
        due = True
    elif kind == "under_extrusion":
        due = grown >= 3.0
    else:
        due = grown >= 2.0
    return True, bool(due)


def tube_mesh(points: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """A square-section tube along a polyline: ((4n, 3) vertices, (8(n-1), 3) faces), outward-facing."""
    points = np.asarray(points, dtype=np.float64)
    n = len(points)
    if n < 2:
        return np.zeros((0, 3)), np.zeros((0, 3), np.int64)
    tangent = np.gradient(points, axis=0)
    tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-9)
    side = np.cross(tangent, [0.0, 0.0, 1.0])
    bad = np.linalg.norm(side, axis=1) < 1e-6
    side[bad] = np.cross(tangent[bad], [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    up = np.cross(side, tangent)
    ring = [side, up, -side, -up]
    vertices = np.concatenate([points[:, None, :] + radius * np.stack(ring, axis=1)], axis=0).reshape(-1, 3)
    faces = []
    base = np.arange(n - 1) * 4
    for k in range(4):
        a, b = base + k, base + (k + 1) % 4
        c, d = a + 4, b + 4
        faces.append(np.stack([a, c, b], axis=1))
        faces.append(np.stack([b, c, d], axis=1))
    return vertices, np.concatenate(faces).astype(np.int64)


def _smooth(values: np.ndarray, width: int) -> np.ndarray:
    """Moving average rescaled to 0..1: slowly varying noise from white noise."""
    kernel = np.ones(width) / width
    out = np.convolve(np.pad(values, width, mode="reflect"), kernel, mode="same")[width:-width]
    return (out - out.min()) / max(out.max() - out.min(), 1e-9)


def spaghetti_path(rng: np.random.Generator, centre: np.ndarray, radius: float, base_z: float,
                   n_points: int = 2400) -> np.ndarray:
    """(n, 3) a nozzle's extrusion path after the print went wrong, in deposition order.

    The nozzle keeps tracing roughly the part's outline; the filament it
    extrudes lands loosely, curling and drifting, and the tangle builds up.
    """
    t = np.arange(n_points, dtype=np.float64)
    loops = t / 90.0  # one lap of the outline every ~90 points
    angle = 2 * np.pi * loops + rng.uniform(0, 2 * np.pi)
    wobble = np.cumsum(rng.normal(0, 0.35, (n_points, 2)), axis=0)
    wobble -= np.linspace(0, 1, n_points)[:, None] * wobble[-1]  # stay near the outline
    curl_phase = np.cumsum(rng.uniform(0.25, 0.6, n_points))
    curl_r = 1.0 + 3.0 * _smooth(rng.uniform(0, 1, n_points), 40)
    ring_r = radius * (0.7 + 0.3 * np.sin(0.37 * loops + rng.uniform(0, 6)))
    x = centre[0] + ring_r * np.cos(angle) + wobble[:, 0] + curl_r * np.cos(curl_phase)
    y = centre[1] + ring_r * np.sin(angle) + wobble[:, 1] + curl_r * np.sin(curl_phase)
    # The pile rises slowly and unevenly; single loops droop below its top.
    # Loops standing up from the pile.
    lift = np.abs(np.sin(curl_phase * 0.45)) * (0.5 + 2.5 * _smooth(rng.uniform(0, 1, n_points), 60))
    height = base_z + 0.004 * t + lift + rng.normal(0, 0.15, n_points).cumsum() * 0.02
    return np.column_stack([x, y, np.maximum(height, base_z + 0.2)])
