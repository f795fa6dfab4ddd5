"""The part as it should be: loading and repairing meshes, placing them, slicing them.

A :class:`PartModel` is the expected part in printer coordinates (mm, Z up, bed
top at z = 0), however it was obtained: from a mesh the user uploaded
(:func:`part_from_mesh`, placed on the G-code's footprint with
:func:`place_mesh_on_gcode` when needed) or rebuilt from the G-code's extrusion
moves (:func:`part_from_gcode`). It answers what the checks ask: the solid
printed up to height z, its cross-section at z, its width across a direction.

Cross-sections are lists of ``(n, 2)`` float arrays of XY points in mm: outer
contours counter-clockwise, holes clockwise (manifold3d's convention); filled
with the non-zero (or even-odd) rule they give the region.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Sequence

import cv2
import manifold3d as mf
import numpy as np
import trimesh

from .errors import GeometryError

#: Mesh formats trimesh reads for us.
MESH_SUFFIXES = (".stl", ".obj", ".ply", ".3mf", ".off", ".glb", ".gltf")

#: Slices taken this far below a flat top, since a plane exactly on it is empty.
TOP_EPSILON_MM = 1e-3


# --------------------------------------------------------------- conversions
def manifold_from_trimesh(mesh: trimesh.Trimesh) -> mf.Manifold:
    """A manifold3d solid from a trimesh; its ``status()`` says whether it is a valid solid."""
    vertices = np.ascontiguousarray(mesh.vertices, dtype=np.float32)
    faces = np.ascontiguousarray(mesh.faces, dtype=np.uint32)
    data = mf.Mesh(vert_properties=vertices, tri_verts=faces)
    data.merge()  # STL stores every triangle's corners separately: weld them
    return mf.Manifold(data)


def trimesh_from_manifold(solid: mf.Manifold) -> trimesh.Trimesh:
    data = solid.to_mesh()
    vertices = np.asarray(data.vert_properties, dtype=np.float64)[:, :3]
    faces = np.asarray(data.tri_verts, dtype=np.int64)
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def polygons_of(section: mf.CrossSection) -> list[np.ndarray]:
    """CrossSection -> list of (n, 2) float64 contours (outer CCW, holes CW)."""
    return [np.asarray(contour, dtype=np.float64).reshape(-1, 2) for contour in section.to_polygons()]


def grown_polygons(polygons: Sequence[np.ndarray], margin_mm: float) -> list[np.ndarray]:
    """Contours ((n, 2) mm, outer CCW, holes CW) grown outwards by ``margin_mm`` with round corners (holes shrink)."""
    if not len(polygons):
        return []
    section = mf.CrossSection([np.asarray(p, np.float64) for p in polygons], mf.FillRule.Positive)
    return polygons_of(section.offset(float(margin_mm), mf.JoinType.Round, 2.0, 32))


def polygons_area(polygons: Sequence[np.ndarray]) -> float:
    """Signed-sum area of contours (holes are clockwise, so they subtract), mm²."""
    total = 0.0
    for poly in polygons:
        x, y = poly[:, 0], poly[:, 1]
        total += 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    return total


# ------------------------------------------------------------------- loading
def load_mesh(path: str | Path) -> trimesh.Trimesh:
    """Read STL/OBJ/PLY/3MF (and other formats trimesh knows) as one triangle mesh, in mm.

    Raises :class:`GeometryError` naming the file when it is missing, unreadable,
    or holds no triangles.
    """
    path = Path(path)
    if not path.is_file():
        raise GeometryError(f"{path}: no such mesh file")
    suffix = path.suffix.lower()
    if suffix not in MESH_SUFFIXES:
        raise GeometryError(f"{path}: unsupported mesh format {suffix or '(none)'}; use one of {', '.join(MESH_SUFFIXES)}")
    if suffix[1:] not in trimesh.available_formats():  # 3MF needs lxml and networkx
        raise GeometryError(f"{path}: reading {suffix} files needs the lxml and networkx packages "
                            f"(pip install lxml networkx)")
    try:
        loaded = trimesh.load(str(path), force="mesh", process=True)
    except ImportError as exc:  # 3MF needs lxml/networkx
        raise GeometryError(f"{path}: reading {suffix} needs an extra package ({exc.name or exc})") from None
    except Exception as exc:  # trimesh raises many types on garbage input
        raise GeometryError(f"{path}: not a readable {suffix[1:].upper()} mesh ({type(exc).__name__}: {exc})") from None
    if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
        raise GeometryError(f"{path}: the file holds no triangles")
    if not np.all(np.isfinite(loaded.vertices)):
        raise GeometryError(f"{path}: the mesh has NaN or infinite coordinates")
    return loaded


def repair_mesh(mesh: trimesh.Trimesh) -> tuple[trimesh.Trimesh, mf.Manifold | None, list[str]]:
    """Try to make ``mesh`` a valid solid: ``(mesh, manifold or None, notes)``.

    Steps, each only when still needed: weld vertices, drop degenerate and
    duplicate faces, fix winding/normals, fill holes. ``manifold`` is None when
    no step gave a valid closed solid.
    """
    notes: list[str] = []
    solid = manifold_from_trimesh(mesh)
    if solid.status() == mf.Error.NoError and not solid.is_empty():
        if not mesh.is_winding_consistent or mesh.volume < 0:
            notes.append("mesh had inverted or inconsistent normals: fixed")
        return trimesh_from_manifold(solid), solid, notes
    fixed = mesh.copy()
    fixed.merge_vertices()
    fixed.update_faces(fixed.nondegenerate_faces())
    fixed.update_faces(fixed.unique_faces())
    fixed.remove_unreferenced_vertices()
    trimesh.repair.fix_normals(fixed)
    trimesh.repair.fill_holes(fixed)
    trimesh.repair.fix_normals(fixed)
    solid = manifold_from_trimesh(fixed)
    if solid.status() == mf.Error.NoError and not solid.is_empty():
        notes.append("mesh was not watertight: repaired (holes filled)")
        return trimesh_from_manifold(solid), solid, notes
    return fixed, None, ["mesh is not watertight and could not be repaired"]


# ----------------------------------------------------------------- the part
@dataclass
class PartModel:
    """The expected part, in printer coordinates (mm, bed top at z = 0).

    Attributes
    ----------
    mesh : trimesh.Trimesh
        The whole part, watertight whenever possible.
    source : str
        ``'mesh'`` or ``'gcode'``.
    notes : list of str
        What was done to obtain it, for the user (repairs, fall-backs).
    apart : trimesh.Trimesh or None
        Flat extrusions that are not the part (skirt, brim, purge line), for a
        G-code part: kept for display and simulation, never in a silhouette.
    """

    mesh: trimesh.Trimesh
    source: str = "mesh"
    notes: list[str] = field(default_factory=list)
    apart: trimesh.Trimesh | None = None
    _solid: mf.Manifold | None = field(default=None, repr=False)
    _below_cache: dict = field(default_factory=dict, repr=False)

    # A G-code part overrides these through its layer stack (toolpath_solid.GcodePart).
    def manifold(self) -> mf.Manifold | None:
        if self._solid is None and self.mesh.is_watertight:
            solid = manifold_from_trimesh(self.mesh)
            if solid.status() == mf.Error.NoError:
                self._solid = solid
        return self._solid

    def height(self) -> float:
        """Top of the part above the bed, mm."""
        return float(self.mesh.bounds[1, 2])

    def bottom(self) -> float:
        return float(self.mesh.bounds[0, 2])

    def solid_below(self, z: float) -> trimesh.Trimesh:
        """The part as printed up to height ``z``: the mesh trimmed by the plane Z = z.

        Returns an empty mesh below the bed and the whole part at or above its top.
        """
        z = float(z)
        if z >= self.height():
            return self.mesh
        key = round(z, 4)
        if key not in self._below_cache:
            self._below_cache[key] = self._trim(z)
            # bounded and small: renderers take every camera at one height before the next, and a trimmed
            # mesh carries its edge tables (tens of MB for a detailed part)
            if len(self._below_cache) > 4:
                self._below_cache.pop(next(iter(self._below_cache)))
        return self._below_cache[key]

    def _trim(self, z: float) -> trimesh.Trimesh:
        if z <= self.bottom():
            return trimesh.Trimesh()
        solid = self.manifold()
        if solid is not None:
            return trimesh_from_manifold(solid.trim_by_plane((0.0, 0.0, -1.0), -z))
        # Not a solid: keep whole triangles below z (good enough for silhouettes).
        below = self.mesh.vertices[self.mesh.faces][:, :, 2].min(axis=1) < z
        part = self.mesh.submesh([np.nonzero(below)[0]], append=True)
        part.vertices[:, 2] = np.minimum(part.vertices[:, 2], z)
        return part

    def cross_section(self, z: float) -> list[np.ndarray]:
        """Contours of the part at height ``z`` (list of (n, 2) mm; outer CCW, holes CW).

        At exactly the top face (a check at the last layer's top) the section is
        taken just below it, so a finished part still has a cross-section.
        """
        z = min(float(z), self.height() - TOP_EPSILON_MM)
        if z <= self.bottom():
            return []
        solid = self.manifold()
        if solid is not None:
            return polygons_of(solid.slice(z))
        section = self.mesh.section(plane_origin=(0, 0, z), plane_normal=(0, 0, 1))
        if section is None:
            return []
        return [np.asarray(d, dtype=np.float64)[:, :2] for d in section.discrete]

    def cross_section_area(self, z: float) -> float:
        return abs(polygons_area(self.cross_section(z)))

    def footprint(self, z: float) -> list[np.ndarray]:
        """Alias of :meth:`cross_section` used for placement."""
        return self.cross_section(z)


def expected_width(part: PartModel, z: float, direction_xy: Sequence[float], *, layer_height: float = 0.2) -> float:
    """Extent (mm) of the part's cross-section at height ``z`` along a horizontal direction.

    The section is taken half a layer below ``z`` (the middle of the newest
    layer), which is also what a camera sees as the top edge. 0 when nothing
    is there.
    """
    direction = np.asarray(direction_xy, dtype=np.float64).ravel()[:2]
    norm = np.linalg.norm(direction)
    if norm == 0 or not np.isfinite(norm):
        raise GeometryError(f"expected_width: direction {direction_xy!r} is not a horizontal direction")
    direction /= norm
    polygons = part.cross_section(max(float(z) - layer_height / 2.0, part.bottom() + TOP_EPSILON_MM))
    if not polygons:
        return 0.0
    along = np.concatenate(polygons) @ direction
    return float(along.max() - along.min())


def part_from_mesh(path_or_mesh: Any) -> PartModel:
    """The part from a mesh file or a trimesh already in printer coordinates.

    Non-watertight meshes are repaired when possible (the notes say so); a mesh
    that cannot be repaired is still usable for silhouettes (triangles are
    trimmed whole), which the notes also say. Use :func:`part_for_job` to fall
    back to the G-code solid instead.
    """
    if isinstance(path_or_mesh, trimesh.Trimesh):
        mesh, name = path_or_mesh, "mesh"
        if len(mesh.faces) == 0:
            raise GeometryError("mesh: no triangles")
    else:
        mesh, name = load_mesh(path_or_mesh), str(path_or_mesh)
    repaired, solid, notes = repair_mesh(mesh)
    lo, hi = repaired.bounds
    if lo[2] < -0.5:
        notes.append(f"{name}: part extends {-lo[2]:.1f} mm below the bed (z < 0)")
    elif lo[2] > 0.5:
        notes.append(f"{name}: part floats {lo[2]:.1f} mm above the bed")
    size = float(np.max(hi - lo))
    if size < 1.0 or size > 2000.0:
        notes.append(f"{name}: part is {size:g} mm across: is the mesh in millimetres?")
    return PartModel(mesh=repaired, source="mesh", notes=notes, _solid=solid)


def part_from_gcode(path: str | Path) -> PartModel:
    """The printed solid rebuilt from the G-code's extrusion moves (see :mod:`.toolpath_solid`)."""
    from .toolpath_solid import build_gcode_part

    return build_gcode_part(path)


def part_for_job(model: str | Path | trimesh.Trimesh | None = None, gcode: str | Path | None = None,
                 *, place: bool = False) -> PartModel:
    """The part for a print job from what the user gave.

    Mesh only: the mesh. G-code only: the G-code solid. Both: the mesh (placed on
    the G-code's footprint when ``place``); when the mesh cannot be repaired into
    a solid, the G-code solid, with a note saying so.
    """
    if model is None and gcode is None:
        raise GeometryError("neither a model nor a G-code file was given")
    if model is None:
        return part_from_gcode(gcode)
    part = part_from_mesh(model)
    if gcode is None:
        return part
    if part.manifold() is None:
        fallback = part_from_gcode(gcode)  # shared (cached): give the note to a copy
        return dataclasses.replace(fallback, notes=["mesh could not be repaired: fell back to the G-code solid"]
                                   + fallback.notes)
    if place:
        placement = place_mesh_on_gcode(part.mesh, gcode)
        placed = part_from_mesh(placement.mesh)
        placed.notes = part.notes + [
            f"mesh placed on the G-code footprint: moved {placement.dx:+.2f}, {placement.dy:+.2f} mm, "
            f"rotated {placement.rotation_deg:.1f} deg, residual {placement.residual_mm:.2f} mm"]
        return placed
    return part


# ---------------------------------------------------------------- placement
@dataclass
class Placement:
    """How a mesh was moved onto the G-code's footprint.

    ``mesh`` is the placed copy: rotated by ``rotation_deg`` about Z around the
    mesh's own footprint centroid, then translated by (``dx``, ``dy``) mm.
    ``residual_mm`` is the mean distance between the placed mesh's outline and
    the G-code's (symmetric-difference area / perimeter, over the compared layers).
    """

    dx: float
    dy: float
    rotation_deg: float
    residual_mm: float
    mesh: trimesh.Trimesh


#: Largest residual accepted as "the same part" (mm of average outline distance).
PLACEMENT_MAX_RESIDUAL_MM = 0.6
#: Pixel size of the rasters placement compares (mm).
_PLACEMENT_PIXEL_MM = 0.1


def _raster(polygons: Sequence[np.ndarray], origin: np.ndarray, shape: tuple[int, int],
            pixel_mm: float = _PLACEMENT_PIXEL_MM) -> np.ndarray:
    image = np.zeros(shape, np.uint8)
    pts = [np.round((p - origin) / pixel_mm * 16).astype(np.int32) for p in polygons if len(p) >= 3]
    if pts:
        cv2.fillPoly(image, pts, 1, lineType=cv2.LINE_8, shift=4)
    return image


def _outer_contours(polygons: Sequence[np.ndarray]) -> list[np.ndarray]:
    """The counter-clockwise (outer) contours: the region with every hole filled."""
    return [p for p in polygons if polygons_area([p]) > 0]


def _perimeter(polygons: Sequence[np.ndarray]) -> float:
    return float(sum(np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1).sum() for p in polygons))


def _centroid(polygons: Sequence[np.ndarray]) -> np.ndarray:
    area, cx, cy = 0.0, 0.0, 0.0
    for p in polygons:
        x, y = p[:, 0], p[:, 1]
        xn, yn = np.roll(x, -1), np.roll(y, -1)
        cross = x * yn - xn * y
        area += cross.sum() / 2
        cx += ((x + xn) * cross).sum() / 6
        cy += ((y + yn) * cross).sum() / 6
    if abs(area) < 1e-12:
        pts = np.concatenate(polygons)
        return pts.mean(axis=0)
    return np.array([cx / area, cy / area])


def _rotate(polygons: Sequence[np.ndarray], angle_deg: float, center: np.ndarray) -> list[np.ndarray]:
    a = np.radians(angle_deg)
    rot = np.array([[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]])
    return [(p - center) @ rot.T + center for p in polygons]


def place_mesh_on_gcode(mesh: trimesh.Trimesh | str | Path, gcode_path: str | Path, *,
                        max_residual_mm: float = PLACEMENT_MAX_RESIDUAL_MM) -> Placement:
    """Move a mesh where the slicer put it: match its sections with the G-code's extrusion footprint.

    Compares the mesh's cross-sections with the G-code part's at a few heights
    (first layers, a quarter and half of the height), finds the Z rotation (2°
    steps, refined to 0.25°) and XY translation that match best, and raises
    :class:`GeometryError` when the heights differ or the outlines do not match
    (the wrong mesh for this G-code).
    """
    from .toolpath_solid import build_gcode_part

    if not isinstance(mesh, trimesh.Trimesh):
        mesh = load_mesh(mesh)
    mesh_part = part_from_mesh(mesh)
    gcode_part = build_gcode_part(gcode_path)
    mesh_h = mesh_part.height() - mesh_part.bottom()
    gcode_h = gcode_part.height()
    if abs(mesh_h - gcode_h) > max(1.0, 0.05 * gcode_h):
        raise GeometryError(
            f"{gcode_path}: the mesh is {mesh_h:.1f} mm tall but the G-code prints {gcode_h:.1f} mm: wrong model for this G-code")
    first_top = gcode_part.layer_tops()[0]
    heights = sorted({first_top * 1.5, first_top + 0.25 * (gcode_h - first_top), first_top + 0.5 * (gcode_h - first_top)})
    heights = [z for z in heights if z < gcode_h]
    pairs = []
    for z in heights:
        # Outer contours only: G-code without perimeter tags keeps infill gaps as holes.
        target = _outer_contours(gcode_part.cross_section(z))
        source = _outer_contours(mesh_part.cross_section(mesh_part.bottom() + z))
        if target and source:
            pairs.append((source, target))
    if not pairs:
        raise GeometryError(f"{gcode_path}: the G-code and the mesh have no cross-sections to compare")
    source_center = _centroid(pairs[0][0])
    target_center = _centroid(pairs[0][1])
    all_pts = np.concatenate([np.concatenate(t) for _, t in pairs])
    radius = float(np.max(np.linalg.norm(all_pts - target_center, axis=1))) + 2.0
    for s, _ in pairs:
        radius = max(radius, float(np.max(np.linalg.norm(np.concatenate(s) - source_center, axis=1))) + 2.0)
    origin = target_center - radius

    def mismatch_function(pixel_mm: float):
        size = int(np.ceil(2 * radius / pixel_mm))
        targets = [_raster(t, origin, (size, size), pixel_mm) for _, t in pairs]

        def mismatch(angle: float) -> float:
            """Area (mm²) where the rotated, centred mesh sections and the G-code's differ."""
            total = 0
            for (s, _), t_img in zip(pairs, targets):
                moved = [p - source_center + target_center for p in _rotate(s, angle, source_center)]
                total += int(np.count_nonzero(_raster(moved, origin, (size, size), pixel_mm) != t_img))
            return total * pixel_mm ** 2
        return mismatch

    coarse = mismatch_function(max(_PLACEMENT_PIXEL_MM, radius / 100.0))
    coarse_scores = {float(a): coarse(float(a)) for a in np.arange(0.0, 360.0, 2.0)}
    fine = mismatch_function(_PLACEMENT_PIXEL_MM)
    candidates = {0.0: fine(0.0)}
    # Refine around the few best coarse angles (symmetric parts have several).
    for start in sorted(coarse_scores, key=coarse_scores.get)[:3]:
        for angle in np.arange(start - 2.0, start + 2.0001, 0.25):
            candidates.setdefault(round(float(angle) % 360.0, 3), fine(float(angle)))
    best = min(candidates, key=candidates.get)
    perimeter = sum(_perimeter(t) for _, t in pairs)
    # Symmetric parts match at several angles: prefer no rotation when it is as good (within 0.05 mm).
    if (candidates[0.0] - candidates[best]) / max(perimeter, 1e-9) < 0.05:
        best = 0.0
    residual = candidates[best] / max(perimeter, 1e-9)
    if residual > max_residual_mm:
        raise GeometryError(
            f"{gcode_path}: the mesh does not match the G-code's footprint "
            f"(best residual {residual:.2f} mm > {max_residual_mm:.2f} mm): wrong model for this G-code")
    placed = mesh.copy()
    rotation = trimesh.transformations.rotation_matrix(np.radians(best), (0, 0, 1),
                                                       point=(source_center[0], source_center[1], 0))
    placed.apply_transform(rotation)
    shift = target_center - source_center
    placed.apply_translation((shift[0], shift[1], -mesh_part.bottom()))
    return Placement(dx=float(shift[0]), dy=float(shift[1]), rotation_deg=float(best),
                     residual_mm=float(residual), mesh=placed)
