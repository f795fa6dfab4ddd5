"""Helpers for the simulator tests: clean looks, simple rigs, an independent silhouette reference."""
from __future__ import annotations

import cv2
import numpy as np
import trimesh

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.simulator.look import FILAMENTS, Look, Nuisances
from octoprint_printwatch.simulator.rig import Rig


def clean_look(**nuisances) -> Look:
    """Red part on blue tape, matte light, every nuisance off except those named."""
    base = Nuisances.off()
    for key, value in nuisances.items():
        setattr(base, key, value)
    return Look(bed="blue_tape", backdrop="grey", filament=FILAMENTS["red"], nuisances=base)


def rig_of(*cameras: Camera, pairs=()) -> Rig:
    return Rig(list(cameras), list(cameras), list(pairs), (200.0, 200.0))


def part_mask(frame: np.ndarray, background: np.ndarray, threshold: int = 12) -> np.ndarray:
    """(h, w) bool: pixels where a clean frame differs from the clean background (outline pixels included)."""
    diff = np.abs(frame.astype(np.int16) - background.astype(np.int16)).max(axis=2)
    return diff > threshold


def _clip_polygon_below(poly: np.ndarray, z: float) -> np.ndarray:
    """Sutherland-Hodgman clip of a (k, 3) polygon to the half-space Z <= z."""
    out = []
    for i in range(len(poly)):
        a, b = poly[i], poly[(i + 1) % len(poly)]
        ina, inb = a[2] <= z, b[2] <= z
        if ina:
            out.append(a)
        if ina != inb:
            t = (z - a[2]) / (b[2] - a[2])
            out.append(a + t * (b - a))
    return np.array(out)


def reference_silhouette(camera: Camera, mesh: trimesh.Trimesh, z: float) -> np.ndarray:
    """(h, w) bool silhouette of the part below ``z`` seen by ``camera`` including lens distortion.

    Independent of the simulator's rasterizer: every face is clipped at ``z``
    (the walls and the bottom of a clipped solid cover its cap), edges are
    subdivided so distortion can bend them, OpenCV projects them, and the
    polygons are filled at 4x resolution and averaged to half coverage.
    """
    up = 4  # 4x supersampling, then half coverage: a pixel belongs to the part when its centre area does
    mask = np.zeros((camera.height * up, camera.width * up), np.uint8)
    for tri in mesh.vertices[mesh.faces]:
        poly = _clip_polygon_below(tri, z)
        if len(poly) < 3:
            continue
        dense = np.concatenate([a + np.linspace(0, 1, 8, endpoint=False)[:, None] * (b - a)
                                for a, b in zip(poly, np.roll(poly, -1, axis=0))])
        uv = (camera.project(dense) + 0.5) * up - 0.5
        cv2.fillPoly(mask, [np.round(uv * 16).astype(np.int32)], 255, cv2.LINE_8, 4)
    coverage = cv2.resize(mask, (camera.width, camera.height), interpolation=cv2.INTER_AREA)
    return coverage >= 128


def iou(a: np.ndarray, b: np.ndarray) -> float:
    return float((a & b).sum() / max((a | b).sum(), 1))
