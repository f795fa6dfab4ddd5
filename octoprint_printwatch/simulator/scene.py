"""The print simulator: webcam frames of a part being printed, normally or failing.

``PrintSimulator(part, rig, look, scenario, seed).frame(camera, z, check)``
renders what camera ``camera`` sees when the G-code says the top is at ``z``.
Per-camera work (rays, bed texture lookups, lighting of the bed) and per-height
work (the partial solid, shadows and skirt on the bed) are cached, so a frame
costs a rasterisation of the part and shading of its pixels.
"""
from __future__ import annotations

import math
import zlib
from collections import OrderedDict
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import cv2
import numpy as np
import trimesh

from ..core import geometry
from ..core.camera import Camera
from ..core.errors import GeometryError, PrintWatchError
from . import raster
from .look import Look, Nuisances, random_look  # noqa: F401  (re-exported)
from .parts import GCODE_CENTER, LIBRARY_PARTS, library_gcode, library_part
from .rig import Rig, make_rig  # noqa: F401  (re-exported)
from .scenario import Scenario, should_flag, spaghetti_path, tube_mesh
from .textures import BED_TEXEL_MM, backdrop_panorama, bed_surface, srgb_to_linear
from .webcam import distortion_maps, draw_hotend, expose, vignette

__all__ = ["Look", "Nuisances", "Rig", "make_rig", "Scenario", "PrintSimulator", "load_part", "random_look",
           "library_part", "write_recording"]

# Materials of rendered faces.
_PART, _SPAGHETTI = 0, 1
#: Filament strands per mm of nominal height after the failure (points of the nozzle path).
_SPAGHETTI_POINTS_PER_MM = 160
_FILAMENT_RADIUS = 0.25
_CROSS = cv2.getStructuringElement(cv2.MORPH_CROSS, (3, 3))
#: Longest triangle edge drawn (mm); see _state.
_MAX_EDGE_MM = 5.0


# --------------------------------------------------------------------------- geometry
def _manifold_arrays(solid) -> tuple[np.ndarray, np.ndarray]:
    mesh = solid.to_mesh()
    return (np.asarray(mesh.vert_properties, dtype=np.float64)[:, :3].copy(),
            np.asarray(mesh.tri_verts, dtype=np.int64).copy())


def _below(solid, z: float):
    """The part of ``solid`` under the plane Z = z."""
    return solid.trim_by_plane((0.0, 0.0, -1.0), -float(z))


def load_part(part: Any, bed: tuple[float, float]):
    """(PartModel in printer coordinates, matching G-code or None, display name) for a part argument.

    ``part`` is a library name, a mesh path (STL/OBJ/PLY/3MF), a G-code path
    (the solid rebuilt from its extrusions by ``core.geometry``), a
    ``trimesh.Trimesh`` or a ``PartModel``. Meshes that do not lie on the bed
    (e.g. centred on the origin) are moved to the bed centre, where the shipped
    G-code of library parts was sliced; the base is put on Z = 0.
    """
    gcode = None
    if isinstance(part, str) and part in LIBRARY_PARTS:
        name = part
        mesh = geometry.load_mesh(library_part(part))
        centre = np.array([bed[0] / 2.0, bed[1] / 2.0])
        if np.allclose(centre, GCODE_CENTER):
            gcode = library_gcode(part)
        mesh.apply_translation([centre[0], centre[1], 0.0])
    elif isinstance(part, (str, Path)):
        path = Path(part)
        name = path.stem
        if not path.exists():
            raise GeometryError(f"{path}: no such file (and not a library part: {', '.join(LIBRARY_PARTS)})")
        if path.suffix.lower() in (".gcode", ".gco", ".g"):
            gcode = path
            mesh = geometry.part_from_gcode(path).mesh.copy()
        else:
            mesh = geometry.load_mesh(path)
    elif isinstance(part, trimesh.Trimesh):
        name, mesh = "mesh", part.copy()
    elif isinstance(part, geometry.PartModel):
        name, mesh = "part", part.mesh.copy()
    else:
        raise GeometryError(f"cannot simulate a part given as {type(part).__name__}")
    lo, hi = mesh.bounds
    if gcode is None and not (lo[0] >= 0 and lo[1] >= 0 and hi[0] <= bed[0] and hi[1] <= bed[1]):
        mesh.apply_translation([bed[0] / 2.0 - (lo[0] + hi[0]) / 2.0, bed[1] / 2.0 - (lo[1] + hi[1]) / 2.0, 0.0])
    mesh.apply_translation([0.0, 0.0, -mesh.bounds[0][2]])
    model = geometry.part_from_mesh(mesh)
    if model.manifold() is None:
        where = str(part) if isinstance(part, (str, Path)) else name
        raise GeometryError(f"{where}: the mesh is not a closed solid and could not be repaired")
    return model, gcode, name


def _inside_polygon(points: np.ndarray, polygon: np.ndarray) -> np.ndarray:
    """(n,) bool: points (n, 2) inside a closed (k, 2) polygon (even-odd rule)."""
    contour = np.asarray(polygon, dtype=np.float32).reshape(-1, 1, 2)
    return np.array([cv2.pointPolygonTest(contour, (float(x), float(y)), False) >= 0 for x, y in points])


def _hash_seed(*parts: Any) -> list[int]:
    return [zlib.crc32(repr(p).encode()) for p in parts]


# --------------------------------------------------------------------------- caches
@dataclass
class _CameraView:
    """Everything about one camera that does not change during the print."""

    camera: Camera
    rays: raster.PixelRays
    bed_mask: np.ndarray            # (h, w) bool: the ray meets the bed sheet
    tex_x: np.ndarray               # (h, w) float32 bed texel column of each pixel (-1 off the bed)
    tex_y: np.ndarray
    albedo: np.ndarray              # (h, w, 3) bed albedo (linear)
    irradiance: np.ndarray          # (n_lights, h, w) direct light reaching the bed point
    specular: np.ndarray            # (n_lights, h, w) highlight toward this camera
    reflectivity: np.ndarray        # (h, w)
    static: np.ndarray              # (h, w, 3) linear radiance of the empty scene, no shadows
    maps: Any
    vignetting: np.ndarray | None
    gain: float


@dataclass
class _PrintState:
    """The print at one nominal height: meshes to draw, decals on the bed, ground truth."""

    z: float
    vertices: np.ndarray            # (n, 3)
    faces: np.ndarray               # (m, 3)
    material: np.ndarray            # (m,) int
    cut_z: float | None             # in-progress top (shows infill) or None
    infill: tuple | None            # (texture (r, c) float32, x0, y0) around the top section
    decals: np.ndarray              # (rows, cols, 4) float32: shadow per light (3) + filament on bed
    truth: dict
    strings: list = field(default_factory=list)  # [(points (k, 3), alpha)]


class PrintSimulator:
    """A printer with webcams printing one part.

    Parameters
    ----------
    part : library name, mesh/G-code path, trimesh.Trimesh or PartModel
    rig : Rig, or a rig kind for :func:`make_rig`
    look : Look, a preset name, or None for :func:`random_look` of the seed
    scenario : Scenario, a scenario kind, or None for a normal print
    """

    def __init__(self, part: Any = "gear", rig: Rig | str | None = None, look: Look | str | None = None,
                 scenario: Scenario | str | None = None, seed: int = 0, layer_height: float = 0.2,
                 hollow: bool | None = None) -> None:
        from .look import PRESETS

        self.seed = int(seed)
        self.layer_height = float(layer_height)
        if layer_height <= 0:
            raise PrintWatchError(f"layer height must be positive, got {layer_height}")
        self.rig = make_rig(rig or "stations3", seed=self.seed) if not isinstance(rig, Rig) else rig
        bed = self.rig.bed
        if isinstance(look, str):
            if look not in PRESETS:
                raise PrintWatchError(f"unknown look {look!r}; choose from {', '.join(PRESETS)}")
            look = PRESETS[look]
        self.look = look if look is not None else random_look(self.seed, bed)
        self.part, self.gcode_path, self.part_name = load_part(part, bed)
        if isinstance(part, str) and part in LIBRARY_PARTS and abs(self.layer_height - 0.2) > 1e-9:
            self.gcode_path = None  # the shipped G-code has 0.2 mm layers; it would contradict the frames
        self.mesh = self.part.mesh
        self._solid = self.part.manifold()
        # Spiral-vase prints are one wall thick: from above you look into a dark, open cup.
        self.hollow = (self.part_name == "twisted_vase") if hollow is None else bool(hollow)
        self.height = float(self.mesh.bounds[1][2])
        self.n_layers = max(1, int(math.ceil(self.height / self.layer_height - 1e-6)))
        if isinstance(scenario, str):
            scenario = Scenario(scenario)
        self.scenario = (scenario or Scenario()).resolved(self.n_layers, self.seed)
        onset = self.scenario.onset_layer
        self.onset_z = None if onset is None else (onset - 1) * self.layer_height
        self.lights = self.look.lights_for(bed)[:3]
        self._views: dict[str, _CameraView] = {}
        self._states: OrderedDict[float, _PrintState] = OrderedDict()
        self._surface = None
        self._panorama = None
        self._footprint = self._section_polygons(self._solid, min(0.1, self.height / 2))
        centre = self.mesh.bounds.mean(axis=0)
        self._centre = np.array([centre[0], centre[1]])
        self._radius = float(np.max(np.linalg.norm(self.mesh.vertices[:, :2] - self._centre, axis=1)))
        self._layer_jitter = np.random.default_rng(_hash_seed(self.seed, "layers")).normal(0, 1, self.n_layers + 64)
        self._seam_angle = float(np.random.default_rng(_hash_seed(self.seed, "seam")).uniform(-np.pi, np.pi))
        self._detach_transform = self._make_detach_transform() if self.scenario.kind == "detach" else None
        self._spaghetti = None
        if self.scenario.kind in ("detach", "spaghetti"):
            rng = np.random.default_rng(_hash_seed(self.seed, "spaghetti"))
            base = 0.0 if self.scenario.kind == "detach" else self.onset_z
            path = spaghetti_path(rng, self._centre, max(self._radius * 0.8, 4.0), base)
            if self.scenario.kind == "spaghetti":
                # Off the top of the part, strands hang down its sides toward the bed.
                section = self._section_polygons(self._solid, max(base - 0.1, 0.05))
                inside = np.zeros(len(path), bool)
                for poly in section:
                    inside ^= _inside_polygon(path[:, :2], poly)
                reach = np.linalg.norm(path[:, :2] - self._centre, axis=1) - self._radius * 0.9
                drop = np.where(inside, 0.0, 1.5 + 2.0 * np.clip(reach, 0, None))
                path[:, 2] = np.maximum(path[:, 2] - drop, 0.2)
            self._spaghetti = path

    # ------------------------------------------------------------------ public API
    @property
    def camera_names(self) -> list[str]:
        return self.rig.names

    def layer_z(self, layer: int) -> float:
        """Top height (mm) of 1-based layer ``layer``."""
        return round(layer * self.layer_height, 6)

    def background(self, camera_name: str) -> np.ndarray:
        """(h, w, 3) uint8 BGR: the empty bed before the print (no skirt, no part)."""
        view = self._view(camera_name)
        rng = np.random.default_rng(_hash_seed(self.seed, camera_name, "background"))
        linear = view.static.copy()
        if rng.random() < self.look.nuisances.hotend_probability:  # it may be parked in view before the print too
            draw_hotend(linear, rng)
        return self._finish(view, linear, rng)

    def frame(self, camera_name: str, z_printed: float, check_index: int = 0) -> np.ndarray:
        """(h, w, 3) uint8 BGR: what the webcam sees when the G-code's top is at ``z_printed`` (mm)."""
        view = self._view(camera_name)
        state = self._state(float(z_printed))
        rng = np.random.default_rng(_hash_seed(self.seed, camera_name, int(check_index), round(float(z_printed), 4)))
        linear = self._render(view, state, rng)
        # Auto exposure reacts a little to what entered the picture (a bright part darkens the rest).
        adapt = (float(view.static.mean()) / max(float(linear.mean()), 1e-4)) ** 0.3
        return self._finish(view, linear, rng, float(np.clip(adapt, 0.7, 1.4)))

    def truth(self, z: float) -> dict:
        """Ground truth at nominal height ``z``: true top, whether the failure started, whether checks must flag."""
        return dict(self._state(float(z)).truth)

    def model_in_printer_coordinates(self) -> trimesh.Trimesh:
        return self.mesh.copy()

    # ------------------------------------------------------------------ geometry per height
    @staticmethod
    def _section_polygons(solid, z: float) -> list[np.ndarray]:
        try:
            return [np.asarray(p, dtype=np.float64) for p in solid.slice(float(z)).to_polygons()]
        except Exception:  # an empty section
            return []

    def _make_detach_transform(self) -> np.ndarray:
        rng = np.random.default_rng(_hash_seed(self.seed, "detach"))
        piece = _below(self._solid, max(self.onset_z, self.layer_height))
        v, _ = _manifold_arrays(piece)
        centre = np.array([self._centre[0], self._centre[1], 0.0])
        direction = rng.uniform(0, 2 * np.pi)
        push = np.array([np.cos(direction), np.sin(direction), 0.0])
        if self.scenario.detach_mode == "tipped" and len(v):
            # Knocked onto its side: rotate 90 degrees about a horizontal axis, rest on the bed.
            axis = np.cross(push, [0, 0, 1.0])
            rot = trimesh.transformations.rotation_matrix(np.pi / 2, axis, centre)
            moved = trimesh.transform_points(v, rot)
            shift = push * rng.uniform(6, 18)
            shift[2] = -moved[:, 2].min()
            return trimesh.transformations.translation_matrix(shift) @ rot
        spin = trimesh.transformations.rotation_matrix(np.radians(rng.uniform(15, 70)), [0, 0, 1], centre)
        return trimesh.transformations.translation_matrix(push * rng.uniform(12, 30)) @ spin

    def _geometry(self, z: float):
        """(pieces [(vertices, faces, material)], cut_z, true top, moved) at nominal height z."""
        sc, lh = self.scenario, self.layer_height
        onset = self.onset_z
        z = min(max(z, 0.0), self.height)
        failed = onset is not None and z > onset + 1e-6
        pieces: list = []
        cut_z = z if z < self.height - 1e-6 else None
        moved = False
        if not failed or sc.kind == "under_extrusion":
            top = z
            if failed:  # thin, sagging walls above the onset
                lower = _below(self._solid, onset)
                upper = _below(self._solid, z) - lower
                s = 1.0 - 0.06 * sc.under_extrusion
                cx, cy = self._centre
                upper = upper.translate((-cx, -cy, 0)).scale((s, s, 1.0)).translate((cx, cy, 0))
                pieces.append((*_manifold_arrays(lower + upper), _PART))
            else:
                below = self.part.solid_below(z)
                pieces.append((np.asarray(below.vertices, dtype=np.float64), np.asarray(below.faces, dtype=np.int64),
                               _PART))
        elif sc.kind == "runout":
            top = onset
            pieces.append((*_manifold_arrays(_below(self._solid, onset)), _PART))
            cut_z = onset
        elif sc.kind == "layer_shift":
            top = z
            lower = _below(self._solid, onset)
            upper = _below(self._solid, z) - lower
            dx, dy = sc.shift_mm
            pieces.append((*_manifold_arrays(lower + upper.translate((dx, dy, 0.0))), _PART))
        elif sc.kind == "spaghetti":
            top = onset
            cut_z = onset
            pieces.append((*_manifold_arrays(_below(self._solid, onset)), _PART))
        elif sc.kind == "detach":
            moved = True
            v, f = _manifold_arrays(_below(self._solid, max(onset, lh)))
            v = trimesh.transform_points(v, self._detach_transform)
            pieces.append((v, f, _PART))
            cut_z = None
            top = 0.0
        else:  # pragma: no cover - Scenario validates kinds
            raise PrintWatchError(f"unhandled scenario {sc.kind}")
        if failed and self._spaghetti is not None:
            n = int(min(len(self._spaghetti), 12 + _SPAGHETTI_POINTS_PER_MM * (z - onset)))
            path = self._spaghetti[:n]
            v, f = tube_mesh(path, _FILAMENT_RADIUS)
            pieces.append((v, f, _SPAGHETTI))
            if sc.kind == "detach":
                top = float(path[:, 2].max()) if len(path) else 0.0
        return pieces, cut_z, float(top), moved

    def _state(self, z: float) -> _PrintState:
        key = round(z, 4)
        if key in self._states:
            self._states.move_to_end(key)
            return self._states[key]
        pieces, cut_z, top, moved = self._geometry(z)
        # Painter's algorithm sorts whole triangles: split the big ones (caps, flat walls) so a strand
        # lying on a top face, or a tooth behind another, is ordered right.
        pieces = [(*trimesh.remesh.subdivide_to_size(v, f, max_edge=_MAX_EDGE_MM), m) if m == _PART and len(f) else
                  (v, f, m) for v, f, m in pieces]
        grow = self.look.nuisances.over_extrusion_mm
        if grow and not moved:
            # Slight over-extrusion: the walls stand a little proud of the model (about the part's centre).
            scale = 1.0 + grow / max(self._radius, 1.0)
            centre = np.array([self._centre[0], self._centre[1], 0.0])
            pieces = [((v - centre) * np.array([scale, scale, 1.0]) + centre if m == _PART else v, f, m)
                      for v, f, m in pieces]
        offsets = np.cumsum([0] + [len(p[0]) for p in pieces])
        vertices = np.concatenate([p[0] for p in pieces]) if pieces else np.zeros((0, 3))
        faces = np.concatenate([p[1] + o for p, o in zip(pieces, offsets)]) if pieces else np.zeros((0, 3), int)
        material = np.concatenate([np.full(len(p[1]), p[2]) for p in pieces]) if pieces else np.zeros(0, int)
        started, due = should_flag(self.scenario.kind, self.onset_z, z, top)
        layer = int(round(z / self.layer_height))
        truth = {"z": round(z, 4), "layer": layer, "true_top_z": round(top, 4), "part_moved": moved,
                 "failure_started": started, "should_flag": due, "kind": self.scenario.kind}
        infill = None
        nz = self.look.nuisances
        if self.hollow and cut_z is None and not moved and z >= self.height - 1e-6:
            cut_z = self.height  # a vase has no top
        if cut_z is not None and nz.top_infill and (0.8 < cut_z < self.height - 0.8 or self.hollow and cut_z > 0.8):
            infill = self._infill_texture(cut_z)
        state = _PrintState(z, vertices, faces, material, cut_z, infill,
                            self._decals(vertices, faces, material, z, moved), truth)
        state.strings = self._strings(z, cut_z, top)
        self._states[key] = state
        while len(self._states) > 6:
            self._states.popitem(last=False)
        return state

    def _infill_texture(self, cut_z: float):
        """Top of an unfinished print: two perimeters, then sparse infill over dark cavities."""
        import manifold3d as m3d

        section = self._solid.slice(cut_z - 0.05)
        if self.scenario.kind == "layer_shift" and self.onset_z is not None and cut_z > self.onset_z:
            section = section.translate(self.scenario.shift_mm)
        polys = [np.asarray(p) for p in section.to_polygons()]
        if not polys:
            return None
        wall = 0.45 if self.hollow else 0.9
        inner = [np.asarray(p) for p in section.offset(-wall, m3d.JoinType.Miter).to_polygons()]
        allpts = np.concatenate(polys)
        x0, y0 = allpts.min(axis=0) - 1.0
        x1, y1 = allpts.max(axis=0) + 1.0
        res = 0.1
        shape = (int((y1 - y0) / res) + 1, int((x1 - x0) / res) + 1)
        to_px = lambda p: np.round((p - (x0, y0)) / res * 16).astype(np.int32)  # noqa: E731
        tex = np.ones(shape, np.float32)
        if inner:
            cavity = np.zeros(shape, np.uint8)
            cv2.fillPoly(cavity, [to_px(p) for p in inner], 1, cv2.LINE_8, 4)
            lines = np.zeros(shape, np.uint8)
            spacing = 3.0 / res
            sign = 1 if int(round(cut_z / self.layer_height)) % 2 else -1
            for k in range(-shape[0] - shape[1], shape[0] + shape[1], max(1, int(spacing))):
                cv2.line(lines, (0, k), (shape[1], k + sign * shape[1]), 1, max(1, int(0.45 / res)))
                cv2.line(lines, (0, k), (shape[1], k - sign * shape[1]), 1, max(1, int(0.45 / res)))
            if self.hollow:
                tex[cavity > 0] = 0.12
            else:
                tex[(cavity > 0) & (lines == 0)] = 0.25
        return tex, float(x0), float(y0), res

    def _decals(self, vertices, faces, material, z, moved) -> np.ndarray:
        """Bed-space layers: the part's shadow for each light, and filament lying on the bed."""
        bed = self.rig.bed
        rows, cols = int(round(bed[1] / BED_TEXEL_MM)), int(round(bed[0] / BED_TEXEL_MM))
        decals = np.zeros((rows, cols, 4), np.float32)
        nz = self.look.nuisances
        scale = 16.0 / BED_TEXEL_MM
        if nz.shadows and len(faces):
            tri = vertices[faces]
            for i, light in enumerate(self.lights):
                lpos = np.asarray(light.position, dtype=np.float64)
                normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
                facing = np.einsum("ij,ij->i", normals, lpos - tri[:, 0]) > 0
                pts = tri[facing].reshape(-1, 3)
                h = np.minimum(pts[:, 2], lpos[2] - 1.0)
                k = lpos[2] / (lpos[2] - h)
                ground = lpos[:2] + (pts[:, :2] - lpos[:2]) * k[:, None]
                ground = np.round(ground.reshape(-1, 3, 2) * scale).astype(np.int32)
                channel = np.zeros((rows, cols), np.uint8)
                for poly in ground:
                    cv2.fillConvexPoly(channel, poly, 1, cv2.LINE_8, 4)
                # Penumbra: LED panels are not points; the shadow edge softens with height.
                decals[..., i] = cv2.GaussianBlur(channel.astype(np.float32), (0, 0), 1.2 / BED_TEXEL_MM)
        if nz.skirt and z > 0:
            layer = np.zeros((rows, cols), np.float32)
            skirt_rng = np.random.default_rng(_hash_seed(self.seed, "skirt"))
            import manifold3d as m3d

            section = m3d.CrossSection([p for p in self._footprint]) if self._footprint else None
            if section is not None:
                # Slicers run the skirt around the convex hull of the whole first layer.
                hull = section.hull().offset(float(skirt_rng.uniform(3.0, 6.0)))
                ring = [np.round(np.asarray(p) * scale).astype(np.int32) for p in hull.to_polygons()]
                cv2.polylines(layer, ring, True, 1.0, max(1, int(round(0.45 / BED_TEXEL_MM))), cv2.LINE_AA, 4)
                if self.look.brim_mm > 0:
                    for step in np.arange(0.45, self.look.brim_mm, 0.45):
                        ring = [np.round(np.asarray(p) * scale).astype(np.int32)
                                for p in section.offset(float(step)).to_polygons()]
                        cv2.polylines(layer, ring, True, 0.9, 2, cv2.LINE_AA, 4)
                if not moved:  # elephant's foot: the squashed first layer sticks out a little
                    foot = [np.round(np.asarray(p) * scale).astype(np.int32) for p in section.offset(0.3).to_polygons()]
                    cv2.fillPoly(layer, foot, 1.0, cv2.LINE_AA, 4)
            # Purge line along the front edge of the bed, as most start G-codes draw it.
            y = 4.0 + skirt_rng.uniform(-1, 1)
            for dy in (0.0, 0.5):
                cv2.line(layer, (int(10 * scale), int((y + dy) * scale)), (int(110 * scale), int((y + dy) * scale)),
                         1.0, 2, cv2.LINE_AA, 4)
            decals[..., 3] = layer
        return decals

    def _strings(self, z: float, cut_z: float | None, top: float) -> list:
        """Thin wisps of filament: a few on normal prints, more (reaching up to the nozzle) after a runout."""
        if not self.look.nuisances.stringing or top <= 0.4:
            return []
        rng = np.random.default_rng(_hash_seed(self.seed, "strings", round(top, 3)))
        section = self._section_polygons(self._solid, max(min(top, self.height) - 0.1, 0.05))
        if not section:
            return []
        pts = np.concatenate(section)
        strings = []
        n = int(rng.integers(0, 3))
        runout = self.scenario.kind == "runout" and self.onset_z is not None and z > self.onset_z
        if runout:
            n += int(rng.integers(2, 5))
        for _ in range(n):
            a = pts[rng.integers(len(pts))]
            if runout:  # strands pulled up toward the nozzle as it rose away from the part
                end = np.array([a[0] + rng.normal(0, 3), a[1] + rng.normal(0, 3), top + rng.uniform(8, 25)])
                t = np.linspace(0, 1, 24)[:, None]
                curve = np.array([a[0], a[1], top]) * (1 - t) + end * t
                curve[:, :2] += np.sin(t * np.pi * rng.uniform(1, 3)) * rng.normal(0, 1.5, 2)
            else:  # a travel-move string between two points of the top, sagging
                b = pts[rng.integers(len(pts))]
                t = np.linspace(0, 1, 24)[:, None]
                curve = np.column_stack([a * (1 - t[:, 0:1]) + b * t[:, 0:1], np.full(len(t), top + 0.3)])
                curve[:, 2] -= np.sin(t[:, 0] * np.pi) * rng.uniform(0.5, 3.0)
            strings.append((curve, float(rng.uniform(0.25, 0.6))))
        return strings

    # ------------------------------------------------------------------ per camera
    def _view(self, name: str) -> _CameraView:
        if name in self._views:
            return self._views[name]
        camera = self.rig.true(name)
        ideal = Camera(camera.name, camera.width, camera.height, camera.K, np.zeros(5), camera.rvec, camera.tvec)
        rays = raster.PixelRays.of(ideal)
        bed = self.rig.bed
        if self._surface is None:
            self._surface = bed_surface(self.look.bed, bed, self.seed)
            self._panorama = backdrop_panorama(self.look.backdrop, self.seed)
        surface = self._surface
        d = rays.directions
        origin = rays.origin
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -origin[2] / d[..., 2]
        hit = np.isfinite(t) & (t > 0)
        t = np.where(hit, t, 0.0).astype(np.float32)
        px = origin[0] + d[..., 0] * t
        py = origin[1] + d[..., 1] * t
        on_bed = hit & (px >= 0) & (px <= bed[0]) & (py >= 0) & (py <= bed[1])
        frame_ring = hit & ~on_bed & (px > -25) & (px < bed[0] + 25) & (py > -25) & (py < bed[1] + 25)
        tex_x = np.where(on_bed, px / BED_TEXEL_MM, -1).astype(np.float32)
        tex_y = np.where(on_bed, py / BED_TEXEL_MM, -1).astype(np.float32)
        albedo = cv2.remap(surface.albedo, tex_x, tex_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
        reflectivity = cv2.remap(surface.reflectivity, tex_x, tex_y, cv2.INTER_LINEAR,
                                 borderMode=cv2.BORDER_REPLICATE) if self.look.nuisances.reflections else \
            np.zeros(d.shape[:2], np.float32)
        bed_pts = np.stack([px, py, np.zeros_like(px)], axis=-1)
        irr, spec = self._light_bed(bed_pts, origin, surface)
        # Backdrop: the room seen past the bed, looked up by ray direction.
        azimuth = (np.degrees(np.arctan2(d[..., 1], d[..., 0])) % 360.0) / 360.0 * self._panorama.shape[1]
        elevation = (70.0 - np.degrees(np.arcsin(np.clip(d[..., 2], -1, 1)))) / 110.0 * self._panorama.shape[0]
        static = cv2.remap(self._panorama, azimuth.astype(np.float32), elevation.astype(np.float32),
                           cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
        static[frame_ring] = srgb_to_linear((22, 22, 24))  # bed carrier / frame around the sheet
        amb = self.look.ambient
        bed_lin = albedo * (amb + irr.sum(axis=0))[..., None] + spec.sum(axis=0)[..., None] * 0.9
        static[on_bed] = bed_lin[on_bed]
        nz = self.look.nuisances
        vig = vignette(camera, nz.vignetting) if nz.vignetting else None
        # Auto exposure settles on the empty scene: middle grey ends up near 45 % in sRGB.
        luminance = float(np.mean(static))
        # Real auto exposure only partly brightens a dark scene (a black bed stays dark grey, and noisier).
        gain = float(np.clip((0.16 / max(luminance, 1e-4)) ** 0.6, 0.3, 3.0))
        view = _CameraView(camera, rays, on_bed, tex_x, tex_y, albedo, irr, spec, reflectivity, static,
                           distortion_maps(camera), vig, gain)
        self._views[name] = view
        return view

    def _light_bed(self, pts: np.ndarray, eye: np.ndarray, surface) -> tuple[np.ndarray, np.ndarray]:
        """Direct light on bed points (h, w, 3): (n_lights, h, w) irradiance and specular."""
        h, w = pts.shape[:2]
        n = len(self.lights)
        irr = np.zeros((max(n, 1), h, w), np.float32)
        spec = np.zeros_like(irr)
        bed_centre = np.array([self.rig.bed[0] / 2, self.rig.bed[1] / 2, 0.0])
        view = eye - pts
        view /= np.linalg.norm(view, axis=-1, keepdims=True)
        for i, light in enumerate(self.lights):
            lpos = np.asarray(light.position, dtype=np.float64)
            to_l = lpos - pts
            dist = np.linalg.norm(to_l, axis=-1)
            to_l /= dist[..., None]
            falloff = (np.linalg.norm(lpos - bed_centre) / dist) ** 2
            irr[i] = light.intensity * np.clip(to_l[..., 2], 0, 1) * falloff
            half = to_l + view
            half /= np.linalg.norm(half, axis=-1, keepdims=True)
            spec[i] = surface.specular * light.intensity * np.clip(half[..., 2], 0, 1) ** surface.shininess
        return irr, spec

    # ------------------------------------------------------------------ rendering
    def _render(self, view: _CameraView, state: _PrintState, rng: np.random.Generator) -> np.ndarray:
        cam = view.camera
        ideal = Camera(cam.name, cam.width, cam.height, cam.K, np.zeros(5), cam.rvec, cam.tvec)
        h, w = cam.height, cam.width
        # Bed with shadows and filament on it.
        decal = cv2.remap(state.decals, view.tex_x, view.tex_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
        lit = np.full((h, w), self.look.ambient, np.float32)
        spec = np.zeros((h, w), np.float32)
        for i in range(len(self.lights)):
            vis = 1.0 - np.clip(decal[..., i], 0, 1)
            lit += view.irradiance[i] * vis
            spec += view.specular[i] * vis
        filament = srgb_to_linear(self.look.filament.rgb)
        cover = np.clip(decal[..., 3], 0, 1)[..., None]
        albedo = view.albedo * (1 - cover) + filament[None, None, :] * cover
        bed_lin = albedo * lit[..., None] + spec[..., None] * 0.9 * (1 - cover)
        linear = view.static.copy()
        linear[view.bed_mask] = bed_lin[view.bed_mask]
        if len(state.faces) == 0:
            return linear
        background = linear.copy() if (self.look.filament.translucent or self.scenario.kind == "under_extrusion") \
            else linear
        ids = raster.face_ids(ideal, state.vertices, state.faces)
        # Mirror image of the part in a glossy bed (glass, smooth PEI).
        if self.look.nuisances.reflections and np.any(view.reflectivity > 0):
            mirrored = state.vertices * np.array([1.0, 1.0, -1.0])
            flipped = state.faces[:, ::-1]
            rids = raster.face_ids(ideal, mirrored, flipped)
            spots = np.flatnonzero((rids.ravel() >= 0) & view.bed_mask.ravel() & (ids.ravel() < 0))
            if len(spots):
                pts, normals = raster.hit_points(view.rays, rids, mirrored, flipped, spots)
                pts = pts * np.array([1.0, 1.0, -1.0])
                normals = normals * np.array([1.0, 1.0, -1.0])
                colour = self._shade(pts, normals, state.material[rids.ravel()[spots]], state, view, background, spots)
                r = view.reflectivity.ravel()[spots][:, None]
                flat = linear.reshape(-1, 3)
                flat[spots] = flat[spots] * (1 - r) + colour * r
        pixels = np.flatnonzero(ids.ravel() >= 0)
        pts, normals = raster.hit_points(view.rays, ids, state.vertices, state.faces, pixels)
        material = state.material[ids.ravel()[pixels]]
        colour = self._shade(pts, normals, material, state, view, background, pixels)
        # The rasterizer marks every pixel an edge touches; real pixels integrate light over their area.
        # Half-covering the outline pixels removes that half-pixel bias and anti-aliases the silhouette.
        mask = (ids >= 0).astype(np.uint8)
        outline = (mask - cv2.erode(mask, _CROSS)).ravel()[pixels] > 0
        behind = linear.reshape(-1, 3)[pixels[outline]].copy()
        linear.reshape(-1, 3)[pixels] = colour
        linear.reshape(-1, 3)[pixels[outline]] = 0.5 * (colour[outline] + behind)
        self._draw_strings(linear, ideal, state)
        if rng.random() < self.look.nuisances.hotend_probability:
            draw_hotend(linear, rng)
        return linear

    def _shade(self, pts, normals, material, state: _PrintState, view: _CameraView, background, pixels):
        """Linear RGB of part pixels: Lambert + Blinn-Phong from each light, layer lines, top infill."""
        look, nz = self.look, self.look.nuisances
        fil = look.filament
        base = srgb_to_linear(fil.rgb).astype(np.float64)
        eye = view.rays.origin
        to_eye = eye - pts
        dist_eye = np.linalg.norm(to_eye, axis=1)
        to_eye /= dist_eye[:, None]
        # Faces seen from inside (open spaghetti tube ends, painter's errors) shade as if outward.
        flip = np.einsum("ij,ij->i", normals, to_eye) < 0
        normals = np.where(flip[:, None], -normals, normals)
        albedo = np.tile(base, (len(pts), 1))
        lh = self.layer_height
        layer = np.clip((pts[:, 2] / lh).astype(int), 0, len(self._layer_jitter) - 1)
        wall = 1.0 - np.abs(normals[:, 2])
        if nz.layer_lines:
            # Each layer a slightly different shade; the ridges only where a pixel is smaller than a layer.
            footprint = dist_eye / view.camera.K[0, 0]
            ridge = np.cos(2 * np.pi * (pts[:, 2] % lh) / lh) * np.exp(-2.0 * (footprint / lh) ** 2)
            albedo *= (1 + (0.035 * self._layer_jitter[layer] + 0.12 * ridge) * wall)[:, None]
        if nz.over_extrusion_mm:
            # The z-seam: where each layer's perimeter starts and ends, a vertical line of small blobs.
            angle = np.arctan2(pts[:, 1] - self._centre[1], pts[:, 0] - self._centre[0])
            off = np.angle(np.exp(1j * (angle - self._seam_angle)))
            blob = 0.5 + 0.5 * np.cos(2 * np.pi * pts[:, 2] / lh * 0.5 + self._layer_jitter[layer])
            seam = (np.abs(off) * self._radius < 0.6) & (wall > 0.5)
            albedo[seam] *= (1.12 + 0.12 * blob[seam])[:, None]
        sc = self.scenario
        gap = np.zeros(len(pts), bool)
        if sc.kind == "under_extrusion" and self.onset_z is not None:
            upper = (pts[:, 2] > self.onset_z) & (material == _PART)
            angle = np.arctan2(pts[:, 1] - self._centre[1], pts[:, 0] - self._centre[0])
            phase = self._layer_jitter[layer] * 3.0
            wave = np.sin(angle * 7 + phase) + np.sin(angle * 13 - 2 * phase) + 0.5 * np.sin(pts[:, 2] * 9.0)
            gap = upper & (wave > 2.2 - 3.0 * sc.under_extrusion) & (wall > 0.5)
        top_cap = np.zeros(len(pts), bool)
        if state.infill is not None and state.cut_z is not None:
            top_cap = (normals[:, 2] > 0.98) & (np.abs(pts[:, 2] - state.cut_z) < 0.02) & (material == _PART)
            if np.any(top_cap):
                tex, x0, y0, res = state.infill
                col = np.clip(((pts[top_cap, 0] - x0) / res).astype(int), 0, tex.shape[1] - 1)
                row = np.clip(((pts[top_cap, 1] - y0) / res).astype(int), 0, tex.shape[0] - 1)
                shade = tex[row, col]
                if sc.kind == "under_extrusion" and self.onset_z is not None and state.cut_z > self.onset_z:
                    # Starved infill: most lines broken, the cavity shows through.
                    wave = np.sin(pts[top_cap, 0] * 2.1) + np.sin(pts[top_cap, 1] * 1.7 + 1.0)
                    broken = wave > 1.6 - 2.0 * sc.under_extrusion
                    shade = np.where(broken, 0.25, shade)
                albedo[top_cap] *= shade[:, None]
        light_sum = np.full(len(pts), look.ambient * (0.75 + 0.25 * normals[:, 2].clip(-1, 1) ** 2))
        spec_sum = np.zeros(len(pts))
        shininess = 10 + 60 * fil.gloss
        # Thin strands catch highlights from every direction; keep them from turning everything white.
        gloss = np.where(material == _SPAGHETTI, 0.3 * fil.gloss, fil.gloss)
        bed_centre = np.array([self.rig.bed[0] / 2, self.rig.bed[1] / 2, 0.0])
        for light in self.lights:
            lpos = np.asarray(light.position, dtype=np.float64)
            to_l = lpos - pts
            dist = np.linalg.norm(to_l, axis=1)
            to_l /= dist[:, None]
            falloff = (np.linalg.norm(lpos - bed_centre) / dist) ** 2
            lambert = np.clip(np.einsum("ij,ij->i", normals, to_l), 0, 1)
            light_sum += light.intensity * lambert * falloff
            half = to_l + to_eye
            half /= np.linalg.norm(half, axis=1, keepdims=True)
            spec_sum += light.intensity * gloss * np.clip(np.einsum("ij,ij->i", normals, half), 0, 1) ** shininess
        if fil.translucent:  # light scatters inside: flatter shading, a glow from within
            light_sum = 0.55 * light_sum + 0.45 * (look.ambient + 0.6)
        colour = albedo * light_sum[:, None] + spec_sum[:, None] * 0.6
        if fil.glow:
            colour += base * 0.08
        if fil.translucent:  # thin plastic lets some of what is behind show through
            colour = 0.85 * colour + 0.15 * background.reshape(-1, 3)[pixels]
        if np.any(gap):
            behind = background.reshape(-1, 3)[pixels[gap]]
            see_through = (np.sin(pts[gap, 2] * 31.0 + pts[gap, 0]) > 0.3)[:, None]
            colour[gap] = np.where(see_through, behind, colour[gap] * 0.18)
        return colour.astype(np.float32)

    def _draw_strings(self, linear: np.ndarray, ideal: Camera, state: _PrintState) -> None:
        if not state.strings:
            return
        colour = srgb_to_linear(self.look.filament.rgb)
        h, w = linear.shape[:2]
        for curve, alpha in state.strings:
            uv, depth = raster.project_pinhole(ideal, curve)
            if np.any(depth <= 1) or not np.all(np.isfinite(uv)):
                continue
            x0, y0 = np.clip(np.floor(uv.min(axis=0)).astype(int) - 2, 0, (w, h))
            x1, y1 = np.clip(np.ceil(uv.max(axis=0)).astype(int) + 2, 0, (w, h))
            if x1 <= x0 or y1 <= y0:
                continue
            layer = np.zeros((y1 - y0, x1 - x0), np.float32)
            local = np.round((uv - (x0, y0)) * 16).astype(np.int32)
            cv2.polylines(layer, [local], False, float(alpha), 1, cv2.LINE_AA, 4)
            roi = linear[y0:y1, x0:x1]
            roi[:] = roi * (1 - layer[..., None]) + colour[None, None, :] * layer[..., None]

    def _finish(self, view: _CameraView, linear: np.ndarray, rng: np.random.Generator, adapt: float = 1.0):
        if not self.look.nuisances.exposure_drift:
            adapt = 1.0
        return expose(linear, view.camera, self.look.nuisances, rng, base_gain=view.gain * adapt, maps=view.maps,
                      vignetting=view.vignetting)


def write_recording(out_dir, simulator: PrintSimulator, check_heights=None, **options):
    """Render a whole simulated print as a recording; see :func:`.recording.write_recording`."""
    from .recording import write_recording as write

    return write(out_dir, simulator, check_heights, **options)
