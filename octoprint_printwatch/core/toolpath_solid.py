"""The printed solid rebuilt from G-code extrusion moves.

Each extruding segment is swept with its extrusion width (the slicer's
``;WIDTH:`` comment, else derived from E, the filament diameter and the layer
height, cross-checked with the spacing of nested perimeters) into a rectangle
with square caps (so consecutive segments join without notches); rectangles
are unioned in one Clipper call (manifold3d ``CrossSection``, positive fill
rule), the layer's region is extruded by the layer height and the layers are
stacked. Consecutive layers with the same outline become one slab, which keeps
the mesh small; slabs only touch, so they are concatenated as closed shells.

Sparse infill leaves gaps that are not part of the part's shape: the region
enclosed by the external perimeters (even-odd of their closed centre-lines, so
real holes stay holes) is filled. Slicers tag external perimeters; in files
without feature tags they are recognised by how the closed loops nest (a chain
of loops one width apart is one wall; its outermost loop bounds the part, or
its innermost a hole).

Not part of the part (kept apart, as :attr:`PartModel.apart`): moves tagged
skirt/brim or prime/wipe tower, extrusion before the first layer (purge lines
of start scripts), and, in untagged files, flat extrusions in the first
millimetre that touch nothing above it (a skirt, a purge line) or reach more
than 0.6 mm beyond everything above it (a brim).
"""
from __future__ import annotations

import math
from array import array
from dataclasses import dataclass, field
from pathlib import Path

import manifold3d as mf
import numpy as np
import trimesh

from .errors import GeometryError
from .gcode import analyse, iter_moves
from .geometry import TOP_EPSILON_MM, PartModel, polygons_area, polygons_of

#: Features that are never the part.
APART_FEATURES = frozenset({"skirt", "brim", "prime tower", "wipe tower", "purge"})
#: Features whose closed loops outline the part (holes included).
OUTLINE_FEATURES = frozenset({"external perimeter"})
#: Features always inside the outline: not needed to build it when the outline is known.
INSIDE_FEATURES = frozenset({"perimeter", "infill", "solid infill", "top solid infill", "bridge infill",
                             "gap fill", "ironing"})
#: Extrusion widths outside this range (mm) come from odd E values (priming, blobs): clamped.
WIDTH_RANGE_MM = (0.1, 2.5)
#: In untagged files, extrusion up to this height touching nothing above it is a skirt or purge.
FLAT_APART_MM = 1.0
#: In untagged files, first-millimetre extrusion this far beyond everything above it is a brim
#: (sloped walls flare less than this over the first millimetre).
BRIM_MARGIN_MM = 0.6
#: Outlines are simplified to this tolerance (mm), well under a camera pixel on the part.
SIMPLIFY_MM = 0.02
#: Consecutive layers whose outlines differ by less than this fraction of their area share a slab.
SAME_OUTLINE_FRACTION = 0.002


@dataclass
class LayerSection:
    """One printed layer: the region (printer XY, mm) between ``z_bottom`` and ``z_top``."""

    index: int
    z_bottom: float
    z_top: float
    section: mf.CrossSection

    @property
    def area(self) -> float:
        return float(self.section.area())


@dataclass
class GcodePart(PartModel):
    """A :class:`PartModel` from G-code, answering cross-sections from its layers exactly.

    ``layers`` are in print order. In sequential printing ("complete objects")
    Z goes back down for the next object: then :meth:`solid_below` and
    :meth:`cross_section` describe the finished part cut at a height (all
    objects), and :meth:`solid_through_layer` the state after a given layer.
    """

    layers: list = field(default_factory=list, repr=False)
    slabs: list = field(default_factory=list, repr=False)  # (section, z0, z1, (vertices, faces), first, last layer)

    @property
    def sequential(self) -> bool:
        """True when Z goes down between layers (objects printed one after another)."""
        tops = self.layer_tops()
        return any(b < a - 1e-6 for a, b in zip(tops, tops[1:]))

    def _trim(self, z: float) -> trimesh.Trimesh:
        """The slabs below ``z``, those crossing ``z`` cut at ``z`` (exact, no booleans)."""
        parts = [mesh if z1 <= z + 1e-9 else _slab_mesh(section, z0, z)
                 for section, z0, z1, mesh, _, _ in self.slabs if z0 < z]
        return _concatenate(parts)

    def solid_through_layer(self, index: int) -> trimesh.Trimesh:
        """The part as printed after layer ``index`` (1-based, as in the layer table), in print order."""
        parts = []
        for section, z0, z1, mesh, first, last in self.slabs:
            if first > index:
                continue
            if last <= index:
                parts.append(mesh)
            else:  # the slab is printed up to the top of layer ``index``
                top = next(layer.z_top for layer in self.layers if layer.index == index)
                parts.append(_slab_mesh(section, z0, top))
        return _concatenate(parts)

    def layer_tops(self) -> list[float]:
        return [layer.z_top for layer in self.layers]

    def height(self) -> float:
        return max(self.layer_tops(), default=0.0)

    def bottom(self) -> float:
        return 0.0

    def layers_at(self, z: float) -> list[LayerSection]:
        """The layers containing height ``z`` (a layer's top counts as inside); several in sequential prints."""
        z = float(z)
        return [layer for layer in self.layers if layer.z_bottom + 1e-6 < z <= layer.z_top + 1e-6]

    def layer_at(self, z: float) -> LayerSection | None:
        """The (first printed) layer containing height ``z``."""
        found = self.layers_at(z)
        return found[0] if found else None

    def cross_section(self, z: float) -> list[np.ndarray]:
        z = min(float(z), self.height() - TOP_EPSILON_MM)
        found = self.layers_at(z)
        if not found:
            return []
        if len(found) == 1:
            return polygons_of(found[0].section)
        return polygons_of(mf.CrossSection.batch_boolean([layer.section for layer in found], mf.OpType.Add))


# --------------------------------------------------------------------- paths
@dataclass
class _LayerMoves:
    """Extruding segments of one layer: (n, 4) x0 y0 x1 y1, widths (n,), path ids (n,), outline and inside flags (n,)."""

    segments: np.ndarray
    widths: np.ndarray
    paths: np.ndarray
    outline: np.ndarray
    infill: np.ndarray


def _rectangles(seg: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """(n, 4) segments and (n,) widths -> (n, 4, 2) counter-clockwise rectangles with square caps."""
    p0, p1 = seg[:, :2], seg[:, 2:]
    d = p1 - p0
    length = np.linalg.norm(d, axis=1, keepdims=True)
    d = d / np.maximum(length, 1e-12)
    half = widths[:, None] / 2.0
    along = d * half
    normal = np.column_stack([-d[:, 1], d[:, 0]]) * half
    a, b = p0 - along, p1 + along
    return np.stack([a - normal, b - normal, b + normal, a + normal], axis=1)


def _closed_loops(seg: np.ndarray, widths: np.ndarray, paths: np.ndarray) -> tuple[list[np.ndarray], np.ndarray]:
    """Centre-lines (m, 2) of the continuous paths that end where they started, and (n,) which segments they use."""
    loops = []
    used = np.zeros(len(seg), bool)
    if len(seg) == 0:
        return loops, used
    breaks = np.nonzero(np.diff(paths))[0] + 1
    for start, stop in zip(np.r_[0, breaks], np.r_[breaks, len(seg)]):
        if stop - start < 3:
            continue
        pts = np.vstack([seg[start:stop, :2], seg[stop - 1, 2:]])
        gap = np.linalg.norm(pts[-1] - pts[0])
        if gap <= max(2.5 * float(widths[start:stop].mean()), 0.5):
            loops.append(pts)
            used[start:stop] = True
    return loops, used


def _inside_fraction(points: np.ndarray, region: mf.CrossSection) -> float:
    """Fraction of (n, 2) points inside ``region`` (tested as tiny squares)."""
    if len(points) == 0:
        return 1.0
    size = 1e-3
    squares = [np.array([[x, y], [x + size, y], [x + size, y + size], [x, y + size]]) for x, y in points]
    return float((mf.CrossSection(squares) ^ region).area() / (len(points) * size * size))  # ^ is intersection


def _union(seg: np.ndarray, widths: np.ndarray) -> mf.CrossSection:
    if len(seg) == 0:
        return mf.CrossSection()
    return mf.CrossSection(list(_rectangles(seg, widths)), mf.FillRule.Positive)


def _point_in_polygon(point: np.ndarray, polygon: np.ndarray) -> bool:
    """Even-odd test of one (2,) point against one (n, 2) closed polygon."""
    x, y = point
    xs, ys = polygon[:, 0], polygon[:, 1]
    xn, yn = np.roll(xs, -1), np.roll(ys, -1)
    crosses = (ys > y) != (yn > y)
    with np.errstate(divide="ignore", invalid="ignore"):
        x_at = xs + (y - ys) * (xn - xs) / (yn - ys)
    return bool(np.count_nonzero(crosses & (x < x_at)) % 2)


def _external_loops(loops: list[np.ndarray], width: float) -> list[np.ndarray]:
    """Which closed loops of an untagged layer are external perimeters.

    Loops nest; a loop about one extrusion width inside its parent is the next
    perimeter of the same wall (a chain). Chains alternate between part
    boundaries and hole boundaries: for a boundary chain the outermost loop is
    the external one, for a hole chain the innermost.
    """
    areas = np.array([abs(polygons_area([loop])) for loop in loops])
    perimeters = np.array([np.linalg.norm(np.diff(np.vstack([loop, loop[:1]]), axis=0), axis=1).sum()
                           for loop in loops])
    order = np.argsort(-areas)
    parent = {}
    for rank, j in enumerate(order):
        parent[j] = -1
        for i in order[:rank][::-1]:  # smallest enclosing candidates first
            if areas[i] > areas[j] and _point_in_polygon(loops[j][0], loops[i]):
                parent[j] = i
                break
    root, level, has_child = {}, {}, set()
    for j in order:
        p = parent[j]
        spacing = (areas[p] - areas[j]) / max((perimeters[p] + perimeters[j]) / 2, 1e-9) if p >= 0 else np.inf
        if p >= 0 and spacing <= 1.6 * width:
            root[j] = root[p]
            has_child.add(p)
        else:
            root[j] = j
            level[j] = 0 if p < 0 else level[root[p]] + 1
    external = []
    for j in order:
        r = root[j]
        if (level[r] % 2 == 0 and j == r) or (level[r] % 2 == 1 and j not in has_child):
            external.append(loops[j])
    return external


def _filled(loops: list[np.ndarray], half_width: float) -> mf.CrossSection:
    """Region enclosed by external-perimeter centre-lines (even-odd), grown by half a width."""
    return mf.CrossSection(loops, mf.FillRule.EvenOdd).offset(half_width, mf.JoinType.Round, 2.0, 16)


def _add_unless_inside(region: mf.CrossSection, seg: np.ndarray, widths: np.ndarray) -> mf.CrossSection:
    """``region`` plus these segments, unless a sample of their midpoints shows they all lie inside it."""
    if len(seg) == 0:
        return region
    sample = seg[:: max(1, len(seg) // 200)]
    if _inside_fraction((sample[:, :2] + sample[:, 2:]) / 2.0, region.offset(0.05)) < 0.98:
        return region + _union(seg, widths)
    return region


def _layer_region(moves: _LayerMoves) -> tuple[mf.CrossSection, mf.CrossSection]:
    """(material region, outline-filled region) of one layer's part extrusion.

    When closed external-perimeter loops outline the layer, the region is what
    they enclose (even-odd of their centre-lines: holes stay holes) grown by
    half their width; other extrusion is added only where it is not known to
    lie inside (infill and inner perimeters always do; a sample of their
    midpoints checks it). That skips unioning most segments, the costly part.
    """
    if len(moves.segments) == 0:
        return mf.CrossSection(), mf.CrossSection()
    seg = np.asarray(moves.segments, dtype=np.float64)
    widths = np.asarray(moves.widths, dtype=np.float64)
    outline_mask = np.asarray(moves.outline, dtype=bool)
    loops = []
    if outline_mask.any():
        loops, used = _closed_loops(seg[outline_mask], widths[outline_mask], np.asarray(moves.paths)[outline_mask])
    if not loops:
        material = _union(seg, widths)
        return material, material
    in_loop = np.zeros(len(seg), bool)
    in_loop[np.nonzero(outline_mask)[0][used]] = True
    region = _filled(loops, float(np.median(widths[in_loop])) / 2.0)
    inside = np.asarray(moves.infill, dtype=bool) & ~in_loop
    others = ~inside & ~in_loop
    if others.any():
        region = region + _union(seg[others], widths[others])
    return region, _add_unless_inside(region, seg[inside], widths[inside])


def _untagged_region(moves: _LayerMoves, material: mf.CrossSection) -> mf.CrossSection:
    """Outline-filled region of a layer without feature tags, from its material region.

    External perimeters are recognised by how the closed loops nest
    (:func:`_external_loops`); only loops lying in ``material`` count (a skirt
    already moved apart does not).
    """
    if len(moves.segments) == 0 or material.is_empty():
        return material
    seg = np.asarray(moves.segments, dtype=np.float64)
    widths = np.asarray(moves.widths, dtype=np.float64)
    loops, used = _closed_loops(seg, widths, np.asarray(moves.paths))
    loops = [loop for loop in loops if _inside_fraction(loop[:1], material) > 0.5]
    if not loops:
        return material
    width = float(np.median(widths[used]))
    return material + _filled(_external_loops(loops, width), width / 2.0)


def _perimeter_spacing(seg, widths, paths, index, in_layer, layer_count) -> tuple[float, float] | None:
    """(median spacing of nested closed loops, median width of their segments) over a few layers, mm.

    A loop's spacing to the loop immediately enclosing it is (area difference) /
    (mean perimeter); between perimeters of one wall that is the line width.
    None when no layer has nested loops (single perimeters, vase mode).
    """
    spacings, loop_widths = [], []
    for k in np.unique(np.linspace(layer_count * 0.3, layer_count * 0.7, 5).astype(int)):
        rows = np.nonzero(in_layer & (index == k))[0]
        if len(rows) < 6:
            continue
        loops, used = _closed_loops(seg[rows], widths[rows], paths[rows])
        if len(loops) < 2:
            continue
        loop_widths.extend(widths[rows][used])
        areas = [abs(polygons_area([loop])) for loop in loops]
        perimeters = [np.linalg.norm(np.diff(np.vstack([loop, loop[:1]]), axis=0), axis=1).sum() for loop in loops]
        for j, loop in enumerate(loops):
            enclosing = [i for i in range(len(loops)) if areas[i] > areas[j] and _point_in_polygon(loop[0], loops[i])]
            if enclosing:
                i = min(enclosing, key=lambda i: areas[i])
                spacing = (areas[i] - areas[j]) / ((perimeters[i] + perimeters[j]) / 2)
                if 0.1 <= spacing <= 1.5:
                    spacings.append(spacing)
    if len(spacings) < 2 or not loop_widths:
        return None
    return float(np.median(spacings)), float(np.median(loop_widths))


def collect_moves(path: str | Path):
    """Read the G-code once: per-layer part segments, apart segments, layer table, notes.

    The per-move loop only appends raw numbers; widths, layers and paths are
    then computed with numpy (this loop is, after the parser, the cost of a solid).
    """
    info = analyse(path)
    layers = [layer for layer in info.layers if layer.extrudes]
    if not layers:
        raise GeometryError(f"{path}: no extruding layers: nothing to rebuild")
    feature_codes: dict = {}
    # Compact typed arrays: a 50 MB file has millions of moves (lists of tuples would take GBs).
    lines, coords, extrusion, given_width = array("q"), array("d"), array("d"), array("d")
    features, breaks = array("i"), array("b")
    previous_end = None
    for move in iter_moves(path):
        if not (move.e > 0 and (move.end[0] != move.start[0] or move.end[1] != move.start[1])):
            previous_end = None
            continue
        start, end = move.start, move.end
        breaks.append(previous_end is None or abs(previous_end[0] - start[0]) > 1e-4
                      or abs(previous_end[1] - start[1]) > 1e-4)
        previous_end = end
        lines.append(move.line_no)
        coords.extend((start[0], start[1], end[0], end[1]))
        extrusion.append(move.e)
        given_width.append(move.width or 0.0)
        code = feature_codes.get(move.feature)
        if code is None:
            code = feature_codes[move.feature] = len(feature_codes)
        features.append(code)
    if not lines:
        raise GeometryError(f"{path}: no extruding moves: nothing to rebuild")
    lines = np.frombuffer(lines, dtype=np.int64)
    seg = np.frombuffer(coords, dtype=np.float64).reshape(-1, 4)
    features = np.frombuffer(features, dtype=np.int32)
    breaks = np.frombuffer(breaks, dtype=np.int8)
    names = {code: name for name, code in feature_codes.items()}

    def flag(kinds) -> np.ndarray:
        table = np.array([names[c] in kinds for c in range(len(names))])
        return table[features]

    firsts = np.array([layer.first_line for layer in layers])
    lasts = np.array([layer.last_line for layer in layers])
    index = np.searchsorted(firsts, lines, side="right") - 1
    in_layer = (index >= 0) & (lines <= lasts[np.maximum(index, 0)])
    nominal = info.nominal_layer_height or 0.2
    heights = np.array([layer.height if layer.height > 0 else nominal for layer in layers])
    height = np.where(in_layer, heights[np.maximum(index, 0)], nominal)
    length = np.hypot(seg[:, 2] - seg[:, 0], seg[:, 3] - seg[:, 1])
    filament_area = math.pi * (info.filament_diameter / 2.0) ** 2
    # Slic3r's flow model: a rectangle with semicircular ends of height h, A = (w - h) h + pi h^2 / 4.
    from_e = np.asarray(extrusion) * filament_area / np.maximum(length, 1e-9) / height + height * (1 - math.pi / 4)
    given = np.asarray(given_width)
    paths = np.cumsum(breaks)
    width_note = None
    if not np.any(given > 0):
        # No width comments: E gives widths only as right as the filament diameter we assume
        # (Cura writes none; its Ender-3 profile extrudes for 2.85 mm). The spacing of nested
        # perimeters is the slicer's own line width: trust it when the two disagree.
        measured = _perimeter_spacing(seg, from_e, paths, index, in_layer, len(layers))
        if measured is not None:
            spacing, from_e_median = measured
            ratio = spacing / max(from_e_median, 1e-9)
            if not 0.8 <= ratio <= 1.25:
                from_e = from_e * ratio
                width_note = (f"extrusion widths from E disagree with the perimeter spacing ({from_e_median:.2f} vs "
                              f"{spacing:.2f} mm; filament diameter {info.filament_diameter:g} mm assumed): "
                              f"using the spacing")
    widths = np.clip(np.where(given > 0, given, from_e), *WIDTH_RANGE_MM)
    apart = flag(APART_FEATURES)
    outline = flag(OUTLINE_FEATURES)
    inside = flag(INSIDE_FEATURES)

    def group(mask: np.ndarray) -> _LayerMoves:
        return _LayerMoves(seg[mask], widths[mask], paths[mask], outline[mask], inside[mask])

    part_moves, apart_moves = [], []
    order = np.argsort(np.where(in_layer, index, -1), kind="stable")
    sorted_index = np.where(in_layer, index, -1)[order]
    bounds = np.searchsorted(sorted_index, np.arange(-1, len(layers) + 1))
    for k in range(len(layers)):
        rows = order[bounds[k + 1]:bounds[k + 2]]
        mask = np.zeros(len(seg), bool)
        mask[rows] = True
        part_moves.append(group(mask & ~apart))
        apart_moves.append(group(mask & apart))
    before_first = group(~in_layer)
    if width_note:
        info.warnings.append(width_note)
    return info, layers, part_moves, apart_moves, before_first, bool(apart.any()), bool(outline.any())


def _split_flat_apart(regions: list, layers: list) -> list:
    """Untagged skirts, brims, purges: extrusion of the first millimetre beyond everything above it.

    Components touching nothing above are apart (skirt, purge line); of the
    rest, what reaches more than :data:`BRIM_MARGIN_MM` beyond the footprint of
    the layers above 1 mm is apart too (a brim). A flange thinner than 1 mm
    would be taken for a brim: only untagged files are treated this way.

    Returns, per layer, the region moved apart (``regions`` is updated in place).
    """
    moved = [mf.CrossSection() for _ in regions]
    above = [r for r, layer in zip(regions, layers) if layer.z - layer.height >= FLAT_APART_MM - 1e-6]
    if not above:  # a flat part: nothing tells skirt from part
        return moved
    above_union = mf.CrossSection.batch_boolean(above[:: max(1, len(above) // 40)], mf.OpType.Add)
    footprint = above_union.offset(1.0)
    brim_limit = above_union.offset(BRIM_MARGIN_MM)
    for k, layer in enumerate(layers):
        if layer.z > FLAT_APART_MM + 1e-6:
            continue  # not break: in sequential prints later objects start low again
        keep, drop = [], []
        for component in regions[k].decompose():
            touching = (component ^ footprint).area() > 1e-9  # ^ is intersection
            (keep if touching else drop).append(component)
        kept = mf.CrossSection.batch_boolean(keep, mf.OpType.Add) if keep else mf.CrossSection()
        # A brim touches the part: what reaches beyond everything above (by more than the margin) is apart too.
        beyond = kept - brim_limit
        if beyond.area() > 1.0:
            kept = kept ^ brim_limit  # ^ is intersection
            drop.append(beyond)
        if drop:
            regions[k] = kept
            moved[k] = mf.CrossSection.batch_boolean(drop, mf.OpType.Add)
    return moved


def _slabs(layers: list[LayerSection]) -> list[tuple]:
    """(section, z_bottom, z_top, first index, last index) runs of consecutive, stacked layers
    with (nearly) the same outline."""
    slabs = []
    start = None
    for layer in layers:
        if layer.section.is_empty():
            if start is not None:
                slabs.append(start)
                start = None
            continue
        if start is not None:
            section, z0, z1, first, _ = start
            stacked = abs(layer.z_bottom - z1) < 1e-3
            difference = (section - layer.section).area() + (layer.section - section).area()
            if stacked and difference <= SAME_OUTLINE_FRACTION * max(section.area(), 1e-9):
                start = (section, z0, layer.z_top, first, layer.index)
                continue
            slabs.append(start)
        start = (layer.section, layer.z_bottom, layer.z_top, layer.index, layer.index)
    if start is not None:
        slabs.append(start)
    return [slab for slab in slabs if slab[2] > slab[1]]


def _slab_mesh(section: mf.CrossSection, z0: float, z1: float) -> tuple[np.ndarray, np.ndarray]:
    """(v, 3) vertices and (f, 3) faces of one extruded slab (a closed shell)."""
    data = mf.Manifold.extrude(section, z1 - z0).to_mesh()
    vertices = np.asarray(data.vert_properties, dtype=np.float64)[:, :3]
    vertices[:, 2] += z0
    return vertices, np.asarray(data.tri_verts, dtype=np.int64)


def _concatenate(parts: list[tuple[np.ndarray, np.ndarray]]) -> trimesh.Trimesh:
    """One mesh of touching closed shells. Concatenated, not unioned: manifold3d's
    compose/union of a few hundred stacked slabs takes seconds (spiral vases)."""
    if not parts:
        return trimesh.Trimesh()
    offsets = np.cumsum([0] + [len(v) for v, _ in parts[:-1]])
    vertices = np.concatenate([v for v, _ in parts])
    faces = np.concatenate([f + o for (_, f), o in zip(parts, offsets)])
    return trimesh.Trimesh(vertices=vertices, faces=faces, process=False)


def _stack(layers: list[LayerSection]) -> tuple[trimesh.Trimesh, list]:
    """The layer stack as one mesh of slabs, and the slabs (section, z0, z1, (vertices, faces))."""
    slabs = [(section, z0, z1, _slab_mesh(section, z0, z1), first, last)
             for section, z0, z1, first, last in _slabs(layers)]
    return _concatenate([slab[3] for slab in slabs]), slabs


_PART_CACHE: dict = {}


def build_gcode_part(path: str | Path) -> GcodePart:
    """The part a G-code file prints, as a :class:`GcodePart` (mesh, layers, apart extrusion, notes).

    Results are kept in memory per (path, size, mtime) for the few latest files;
    treat the returned part as read-only.
    """
    path = Path(path)
    if not path.is_file():
        raise GeometryError(f"{path}: no such G-code file")
    stat = path.stat()
    key = (str(path.resolve()), stat.st_size, stat.st_mtime_ns)
    if key not in _PART_CACHE:
        if len(_PART_CACHE) >= 4:
            _PART_CACHE.pop(next(iter(_PART_CACHE)))
        _PART_CACHE[key] = _build_gcode_part(path)
    return _PART_CACHE[key]


def _build_gcode_part(path: Path) -> GcodePart:
    info, layers, part_moves, apart_moves, before_first, tagged_apart, tagged_outline = collect_moves(path)
    notes = [w for w in info.warnings if w.startswith("extrusion widths from E")]
    materials, regions = [], []
    for moves in part_moves:
        material, region = _layer_region(moves)
        materials.append(material)
        regions.append(region.simplify(SIMPLIFY_MM))
    apart = [_layer_region(moves)[0] for moves in apart_moves]
    if not tagged_apart:
        flat = _split_flat_apart(regions, layers)
        if any(not f.is_empty() for f in flat):
            notes.append("untagged flat extrusion around the part's base treated as skirt")
        apart = [a + f for a, f in zip(apart, flat)]
    if not tagged_outline:
        regions = [_untagged_region(moves, region).simplify(SIMPLIFY_MM) for moves, region in zip(part_moves, regions)]
        notes.append("no feature tags: external perimeters recognised by how the loops nest")
    sections = []
    bottom = 0.0
    for k, layer in enumerate(layers):
        z_bottom = max(layer.z - layer.height, 0.0) if layer.height > 0 else bottom
        sections.append(LayerSection(layer.index, z_bottom, layer.z, regions[k]))
        bottom = layer.z
    # Layers with nothing of the part (e.g. only a skirt) do not count for the part's height.
    while sections and sections[-1].section.is_empty():
        sections.pop()
    if not sections:
        raise GeometryError(f"{path}: the G-code extrudes only skirt, brim or purge lines: no part to rebuild")
    mesh, slabs = _stack(sections)
    apart_layers = [LayerSection(layer.index, max(layer.z - layer.height, 0.0), layer.z, a)
                    for layer, a in zip(layers, apart)]
    if len(before_first.segments):
        first = layers[0]
        purge = _layer_region(before_first)[0]
        apart_layers.insert(0, LayerSection(0, max(first.z - first.height, 0.0), first.z, purge))
    apart_mesh = _stack_disjoint(apart_layers)
    return GcodePart(mesh=mesh, source="gcode", notes=notes, apart=apart_mesh, layers=sections, slabs=slabs)


def _stack_disjoint(layers: list[LayerSection]) -> trimesh.Trimesh | None:
    parts = [_slab_mesh(layer.section, layer.z_bottom, layer.z_top)
             for layer in layers if not layer.section.is_empty() and layer.z_top > layer.z_bottom]
    return _concatenate(parts) if parts else None


def layer_area_profile(part: GcodePart) -> list[tuple[float, float]]:
    """(z_top, area mm²) per layer, for reports and tests."""
    return [(layer.z_top, abs(polygons_area(polygons_of(layer.section)))) for layer in part.layers]
