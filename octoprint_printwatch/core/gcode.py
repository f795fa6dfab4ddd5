"""Streaming G-code interpreter and layer table.

The file is read once, line by line, in constant memory (only the layer table
grows, with the number of layers). Positions are printer coordinates in mm
whatever the file's units (``G20`` inches are converted). Modes follow Marlin 2:
G90/G91 set the extrusion mode too, and a later M82/M83 overrides it.

What a *layer* is: a run of extruding moves at one top height. A Z move without
extrusion (a Z-hop, a lift at the end) is not a layer; purge or prime lines a
start script draws before the slicer's first layer comment are not a layer
either. Slicer layer comments (``;LAYER_CHANGE``, ``;LAYER:n``, ``; layer n``,
``;Z:``) only place the boundary between two layers (so a check block goes
where the slicer changes layer); they never create or hide a layer, so files
with no comments at all (old Slic3r) get the same table as commented ones.

Spiral vase mode (Z rising during extrusion): one layer per slicer layer
comment, i.e. per revolution; without comments, one layer each time Z has risen
by the nominal layer height. The layer's ``z`` is the highest Z it reaches.

Injected PrintWatch blocks (see :mod:`.inject`) are skipped, so the table of an
injected file equals the table of the original (line numbers aside).
"""
from __future__ import annotations

import math
import os
import re
from collections import Counter
from itertools import chain
from dataclasses import dataclass, field
from typing import Iterator

from .errors import GcodeError

#: Comment lines that open and close an injected block (see :mod:`.inject`).
BLOCK_BEGIN_PREFIX = "; printwatch "
BLOCK_BEGIN_SUFFIX = " block begin"
BLOCK_END_SUFFIX = " block end"

DEFAULT_FILAMENT_DIAMETER = 1.75
#: Z values closer than this are the same height (slicers print Z to 0.001 mm at best).
Z_EPS = 5e-5
#: A first layer at most this much above what was extruded before the slicer's first
#: layer comment means that extrusion was a purge line, not a layer (mm).
PURGE_Z_MARGIN = 0.06
#: A line longer than this is not G-code (the issue's bad-input cases go up to 100 kB).
MAX_LINE_BYTES = 1 << 20
_CHUNK = 1 << 20
#: Arcs are split into chords that deviate at most this much from the true arc (mm).
ARC_TOLERANCE = 0.005
ARC_MAX_SEGMENT = 1.0

# Slicer comments that mark a layer change; only the first after a layer's last
# extrusion is used, as the place where that layer ends.
_LAYER_MARKER = re.compile(
    r";\s*(?:LAYER_CHANGE|CHANGE_LAYER|BEGIN_LAYER|LAYER\s*:\s*-?\d|Z\s*:\s*-?\.?\d|layer\s+-?\d)",
    re.IGNORECASE,
)
_SETTING = re.compile(r";\s*([A-Za-z_ #0-9]+?)\s*[=:,]\s*(.*)$")
_TOKEN = re.compile(r"([A-Z])\s*([-+]?(?:\d+\.?\d*|\.\d+))?")

_FEATURE_NAMES = {
    # Cura / ideaMaker
    "wall-outer": "external perimeter",
    "wall-inner": "perimeter",
    "skin": "solid infill",
    "solid-fill": "solid infill",
    "fill": "infill",
    "skirt": "skirt",
    "support-interface": "support",
    "support-infill": "support",
    "prime-tower": "prime tower",
    "raft": "raft",
    # PrusaSlicer / Slic3r / SuperSlicer
    "skirt/brim": "skirt",
    "internal infill": "infill",
    "support material": "support",
    "support material interface": "support",
    "wipe tower": "prime tower",
    "overhang perimeter": "external perimeter",
    # Simplify3D "; feature ..."
    "outer perimeter": "external perimeter",
    "inner perimeter": "perimeter",
    "solid layer": "solid infill",
    "prime pillar": "prime tower",
    "dense support": "support",
}


def normalise_feature(name: str) -> str:
    """Slicer feature name (``;TYPE:WALL-OUTER``, ``;TYPE:External perimeter`` ...) in one vocabulary."""
    key = name.strip().lower()
    return _FEATURE_NAMES.get(key, key)


@dataclass(frozen=True)
class Move:
    """One linear segment in printer coordinates (mm); arcs are split into chords.

    ``start``/``end`` are (3,) tuples (x, y, z). ``e`` is the filament length pushed
    by this move (mm; negative = retraction) after resolving M82/M83/G92.
    """

    line_no: int
    start: tuple
    end: tuple
    e: float
    feedrate: float
    tool: int
    width: "float | None" = None
    feature: "str | None" = None

    @property
    def extruding(self) -> bool:
        return self.e > 0 and (self.end[0] != self.start[0] or self.end[1] != self.start[1])

    @property
    def length_xy(self) -> float:
        return math.hypot(self.end[0] - self.start[0], self.end[1] - self.start[1])


@dataclass(frozen=True)
class MachineState:
    """What the printer's G-code state is at one point of the file.

    Positions in mm (logical coordinates, as G92 set them); ``feedrate`` mm/min or
    None if never set; ``e_mode`` is 'absolute'/'relative' when M82/M83 came after the
    last G90/G91, or None when E follows G90/G91 (Marlin 2 semantics: G90/G91 set
    E as well); ``known`` is False while some axis is unknown
    (after G28, before the first absolute move).
    """

    x: float
    y: float
    z: float
    e: float
    feedrate: "float | None"
    absolute: bool
    e_mode: "str | None"
    e_relative: bool
    e_known: bool
    inches: bool
    tool: int
    retracted: bool
    known: bool
    top_z: float  # highest Z extruded so far (what the head must clear)


@dataclass(frozen=True)
class Layer:
    """One layer. ``z`` is its top (mm); the injection point is after ``last_line``."""

    index: int
    z: float
    height: float
    first_line: int
    last_line: int
    extrudes: bool


@dataclass
class GcodeInfo:
    """What :func:`analyse` found in a G-code file.

    ``extrusion_bounds``/``move_bounds`` are ((3,), (3,)) min/max corners of the
    extruding moves / of every position the file visits with known coordinates.
    ``bed_size`` is (width, depth) and ``max_z`` the printer height when slicer
    comments give them. ``end_offsets``/``states`` are aligned with ``layers``:
    the byte offset right after each layer's ``last_line`` and the machine state
    there (used by injection).
    """

    layers: list
    total_lines: int = 0
    total_bytes: int = 0
    slicer: "str | None" = None
    filament_diameter: float = DEFAULT_FILAMENT_DIAMETER
    filament_diameter_source: str = "default"  # 'comment' or 'default'
    #: 1.75 or 2.85 judged from E per mm of extrusion, when no comment gives the diameter.
    filament_diameter_estimate: "float | None" = None
    nominal_layer_height: "float | None" = None
    extrusion_mode: str = "absolute"  # 'absolute', 'relative' or 'mixed' (of the extruding moves)
    positioning: str = "absolute"  # 'absolute', 'relative' or 'mixed'
    units: str = "mm"  # 'mm', 'inch' or 'mixed' (all values are converted to mm)
    firmware_retraction: bool = False
    spiral_vase: bool = False
    tools: list = field(default_factory=list)
    retract_length: "float | None" = None
    retract_feedrate: "float | None" = None
    bed_size: "tuple | None" = None
    bed_origin: tuple = (0.0, 0.0)
    max_z: "float | None" = None
    extrusion_bounds: "tuple | None" = None
    move_bounds: "tuple | None" = None
    slicer_layer_count: "int | None" = None
    layer_markers: int = 0
    line_ending: str = "\n"
    has_injected_blocks: bool = False
    warnings: list = field(default_factory=list)
    # Injection support: one entry per layer.
    end_offsets: list = field(default_factory=list, repr=False)
    states: list = field(default_factory=list, repr=False)
    # Where the first layer's first extrusion starts (for the background block).
    first_extrusion_line: "int | None" = None
    first_extrusion_offset: "int | None" = None
    first_extrusion_state: "MachineState | None" = field(default=None, repr=False)


# --------------------------------------------------------------------------- reading

def _source_name(source) -> str:
    if isinstance(source, (str, os.PathLike)):
        return os.fspath(source)
    return "<lines>"


def _read_chunks(source, tail: list) -> Iterator[list]:
    """Complete lines (without line ends) in lists of about a megabyte, for
    ``itertools.chain``; a last line with no line end is appended to ``tail``."""
    name = _source_name(source)
    if not isinstance(source, (str, os.PathLike)):
        batch = []
        for item in source:
            if isinstance(item, bytes):
                item = item.decode("latin-1")
            batch.append(item[:-1] if item.endswith("\n") else item)
            if len(batch) >= 20000:
                yield batch
                batch = []
        yield batch
        return
    try:
        handle = open(source, "rb")
    except FileNotFoundError:
        raise GcodeError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise GcodeError(f"{name}: is a directory, not a G-code file") from None
    except OSError as exc:
        raise GcodeError(f"{name}: cannot read ({exc.strerror})") from None
    with handle:
        rest = ""
        line_no = 0
        while True:
            chunk = handle.read(_CHUNK)
            if not chunk:
                break
            lines = (rest + chunk.decode("latin-1")).split("\n")
            rest = lines.pop()
            line_no += len(lines)
            if len(rest) > MAX_LINE_BYTES:
                raise GcodeError(f"{name}: line {line_no + 1} is longer than "
                                 f"{MAX_LINE_BYTES // 1024} kB: not a G-code text file")
            yield lines
    if rest:
        tail.append(rest)


# --------------------------------------------------------------------------- interpreter

_HEAD_ALIASES = {"G00": "G0", "G01": "G1", "G02": "G2", "G03": "G3", "G0": "G0", "G1": "G1"}


class Machine:
    """A Marlin 2 style G-code interpreter: feed it code (comment removed), read its state.

    After :meth:`step` returns True (a move), ``de`` is the filament pushed,
    ``moved_xy``/``moved_z`` say which axes changed and ``start`` the position before.
    """

    def __init__(self, name: str = "<lines>"):
        self.name = name
        self.x = self.y = self.z = 0.0
        self.e = 0.0
        self.feedrate = None
        self.absolute = True
        self.e_mode = None
        self.e_relative = False
        self.e_known = False
        self.scale = 1.0
        self.tool = 0
        self.retracted = False
        self.unknown = {"X", "Y", "Z"}
        self.top_z = 0.0
        self.firmware_retraction = False
        self.used_relative_positioning = False
        self.used_inches = False
        self.tools_used = {0}
        self.line_no = 0
        self.warnings = []
        # Per move.
        self.de = 0.0
        self.start = (0.0, 0.0, 0.0)
        self.moved_xy = False
        self.moved_z = False
        self.arc = None  # (cx, cy, clockwise) for G2/G3
        self.before = (None, False, 0.0)  # feedrate, retracted, top_z before the last move

    def state(self) -> MachineState:
        return MachineState(
            self.x, self.y, self.z, self.e, self.feedrate, self.absolute, self.e_mode,
            self.e_relative, self.e_known, self.scale != 1.0, self.tool, self.retracted,
            not self.unknown, self.top_z,
        )

    def _bad(self, what: str) -> GcodeError:
        return GcodeError(f"{self.name}: line {self.line_no}: {what}")

    def step(self, code: str) -> bool:
        """Apply one command (upper case, no comment). True when it was a move."""
        parts = code.split()
        head = parts[0]
        if head == "G1" or head == "G0":
            return self._linear(parts)
        if head[0] == "N" or not _simple_head(head):
            parts = self._tokenise(code)
            if not parts:
                return False
            head = parts[0]
            if head == "G1" or head == "G0":
                return self._linear(parts)
        head = _HEAD_ALIASES.get(head, head)
        if head == "G0" or head == "G1":
            return self._linear(parts)
        if head == "G2" or head == "G3":
            return self._arc(parts, clockwise=head == "G2")
        if head == "G92":
            self._set_position(parts)
        elif head == "G90" or head == "G91":
            # Marlin 2 semantics: G90/G91 set E too; a later M82/M83 overrides E only.
            self.absolute = head == "G90"
            self.e_mode = None
            if not self.absolute:
                self.used_relative_positioning = True
            self._update_e_relative()
        elif head == "M82":
            self.e_mode = "absolute"
            self._update_e_relative()
        elif head == "M83":
            self.e_mode = "relative"
            self._update_e_relative()
        elif head == "G10":
            # G10 with P/L sets tool or work offsets; bare G10 is firmware retraction.
            if not any(p[0] in "PL" for p in parts[1:]):
                self.retracted = True
                self.firmware_retraction = True
        elif head == "G11":
            self.retracted = False
            self.firmware_retraction = True
        elif head == "G20":
            self.scale = 25.4
            self.used_inches = True
        elif head == "G21":
            self.scale = 1.0
        elif head == "G28":
            axes = [p[0] for p in parts[1:] if p[0] in "XYZ"] or ["X", "Y", "Z"]
            for axis in axes:
                setattr(self, axis.lower(), 0.0)
                self.unknown.add(axis)
        elif head[0] == "T" and head[1:].isdigit():
            self.tool = int(head[1:])
            self.tools_used.add(self.tool)
        elif head in ("G17",):
            pass
        elif head in ("G18", "G19"):
            raise self._bad(f"{head}: arcs outside the XY plane are not supported")
        return False

    def _tokenise(self, code: str) -> list:
        """Split ``N12 G1X1Y2*71`` style code into ['G1', 'X1', 'Y2']."""
        if "*" in code:
            code = code[: code.index("*")]
        words = [letter + (value or "") for letter, value in _TOKEN.findall(code)]
        if words and words[0][0] == "N":
            words.pop(0)
        if words:
            words[0] = _HEAD_ALIASES.get(words[0], words[0])
        return words

    def _update_e_relative(self) -> None:
        mode = self.e_mode
        self.e_relative = (mode == "relative") or (mode is None and not self.absolute)

    def _unparsable(self, word: str) -> None:
        """A word like ``Y{MACHINE_DEPTH}`` (an unexpanded slicer placeholder): the
        printer cannot use it either; the axis becomes unknown and a warning is kept."""
        if len(self.warnings) < 20:
            self.warnings.append(f"line {self.line_no}: {word[:40]!r} is not a number: ignored")
        if word[0] in "XYZ":
            self.unknown.add(word[0])
        elif word[0] == "E":
            self.e_known = False

    def _number(self, word: str) -> float:
        try:
            value = float(word[1:])
        except ValueError:
            raise self._bad(f"bad number {word[:40]!r}") from None
        if value != value or value in (math.inf, -math.inf):
            raise self._bad(f"bad number {word[:40]!r}")
        return value

    def _set_position(self, parts: list) -> None:
        words = parts[1:]
        if not words:
            self.x = self.y = self.z = self.e = 0.0
            self.unknown.clear()
            self.e_known = True
            return
        for word in words:
            axis = word[0]
            if axis in "XYZE":
                value = self._number(word) * self.scale if len(word) > 1 else 0.0
                setattr(self, axis.lower(), value)
                if axis == "E":
                    self.e_known = True
                else:
                    self.unknown.discard(axis)

    def _linear(self, parts: list) -> bool:
        self.before = (self.feedrate, self.retracted, self.top_z)
        x, y, z = self.x, self.y, self.z
        nx, ny, nz = x, y, z
        de = 0.0
        scale = self.scale
        absolute = self.absolute
        moved = False
        for word in parts[1:]:
            axis = word[0]
            if axis not in "XYZEF":
                continue
            try:
                value = float(word[1:])
            except ValueError:
                if len(word) > 1:
                    self._unparsable(word)
                continue
            if scale != 1.0:
                value *= scale
            if axis == "X":
                nx = value if absolute else x + value
                moved = True
            elif axis == "Y":
                ny = value if absolute else y + value
                moved = True
            elif axis == "Z":
                nz = value if absolute else z + value
                moved = True
            elif axis == "E":
                if self.e_relative:
                    de = value
                    self.e += value
                else:
                    de = value - self.e
                    self.e = value
                moved = True
            else:
                self.feedrate = value
        if absolute and self.unknown:
            for word in parts[1:]:
                self.unknown.discard(word[0])
        if not moved:
            return False
        self.start = (x, y, z)
        self.x, self.y, self.z = nx, ny, nz
        self.de = de
        self.moved_xy = nx != x or ny != y
        self.moved_z = nz != z
        self.arc = None
        if de < 0:
            self.retracted = True
        elif de > 0:
            self.retracted = False
            if self.moved_xy and nz > self.top_z:
                self.top_z = nz
        return True

    def _arc(self, parts: list, clockwise: bool) -> bool:
        self.before = (self.feedrate, self.retracted, self.top_z)
        values = {}
        for word in parts[1:]:
            if len(word) > 1 and word[0] in "XYZEFIJR":
                values[word[0]] = self._number(word) * self.scale
        if "F" in values:
            self.feedrate = values["F"]
        x, y, z = self.x, self.y, self.z
        absolute = self.absolute
        nx = values.get("X", x if absolute else 0.0) if absolute else x + values.get("X", 0.0)
        ny = values.get("Y", y if absolute else 0.0) if absolute else y + values.get("Y", 0.0)
        nz = values.get("Z", z if absolute else 0.0) if absolute else z + values.get("Z", 0.0)
        if "R" in values:
            cx, cy = _centre_from_radius(x, y, nx, ny, values["R"], clockwise)
            if cx is None:
                raise self._bad("arc radius R is smaller than half the chord")
        elif "I" in values or "J" in values:
            cx, cy = x + values.get("I", 0.0), y + values.get("J", 0.0)
        else:
            raise self._bad("arc without I/J or R")
        de = 0.0
        if "E" in values:
            if self.e_relative:
                de = values["E"]
                self.e += de
            else:
                de = values["E"] - self.e
                self.e = values["E"]
        if absolute and self.unknown:
            for axis in "XYZ":
                if axis in values:
                    self.unknown.discard(axis)
        self.start = (x, y, z)
        self.x, self.y, self.z = nx, ny, nz
        self.de = de
        self.moved_xy = True
        self.moved_z = nz != z
        self.arc = (cx, cy, clockwise)
        if de < 0:
            self.retracted = True
        elif de > 0:
            self.retracted = False
            self.top_z = max(self.top_z, nz)
        return True


# Commands after a layer's last extrusion that do not end it (travel, retraction, E reset).
_QUIET = re.compile(r"G0*[0-3](?![0-9.])|G92|G1[01](?![0-9])")
_SIMPLE_HEAD = re.compile(r"[GMT]\d+(?:\.\d+)?$")


def _simple_head(head: str) -> bool:
    return _SIMPLE_HEAD.match(head) is not None


def _centre_from_radius(x0, y0, x1, y1, radius, clockwise):
    dx, dy = x1 - x0, y1 - y0
    chord = math.hypot(dx, dy)
    if chord == 0 or abs(radius) < chord / 2 - 1e-9:
        return None, None
    h = math.sqrt(max(radius * radius - chord * chord / 4, 0.0))
    mx, my = (x0 + x1) / 2, (y0 + y1) / 2
    # Centre to the right of the chord for clockwise short arcs; negative R = long arc.
    sign = -1.0 if clockwise else 1.0
    if radius < 0:
        sign = -sign
    return mx - sign * h * dy / chord, my + sign * h * dx / chord


def arc_points(start, end, centre, clockwise) -> list:
    """Points along an XY arc (helical in Z), excluding ``start``: list of (x, y, z, fraction)."""
    x0, y0, z0 = start
    x1, y1, z1 = end
    cx, cy = centre
    radius = math.hypot(x0 - cx, y0 - cy)
    a0 = math.atan2(y0 - cy, x0 - cx)
    a1 = math.atan2(y1 - cy, x1 - cx)
    sweep = a1 - a0
    if clockwise:
        if sweep >= -1e-12:
            sweep -= 2 * math.pi
    elif sweep <= 1e-12:
        sweep += 2 * math.pi
    if radius < 1e-9:
        return [(x1, y1, z1, 1.0)]
    step = 2 * math.acos(max(-1.0, 1 - ARC_TOLERANCE / radius)) if radius > ARC_TOLERANCE else math.pi
    step = min(step, ARC_MAX_SEGMENT / radius)
    count = max(1, int(math.ceil(abs(sweep) / step)))
    points = []
    for i in range(1, count):
        t = i / count
        angle = a0 + sweep * t
        points.append((cx + radius * math.cos(angle), cy + radius * math.sin(angle), z0 + (z1 - z0) * t, t))
    points.append((x1, y1, z1, 1.0))
    return points


# --------------------------------------------------------------------------- comments

class _Annotations:
    """Slicer comments: feature type, extrusion width, header settings, layer markers."""

    def __init__(self):
        self.feature = None
        self.width = None
        self.settings = {}
        self.slicer = None
        self.layer_count = None

    def comment(self, text: str) -> bool:
        """Read one comment line (starting with ';'); True when it marks a layer change."""
        head = text[1:16].lstrip().upper()
        if head.startswith("TYPE:"):
            self.feature = normalise_feature(text.split(":", 1)[1])
            return False
        if head.startswith("WIDTH:"):
            try:
                self.width = float(text.split(":", 1)[1])
            except ValueError:
                pass
            return False
        if head.startswith("FEATURE"):
            self.feature = normalise_feature(text.lstrip("; \t")[7:])
            return False
        if head.startswith("TOOL H"):  # Simplify3D "; tool H0.200 W0.480"
            match = re.search(r"W\s*([0-9.]+)", text)
            if match:
                try:
                    self.width = float(match.group(1))
                except ValueError:
                    pass
            return False
        if _LAYER_MARKER.match(text):
            return True
        if head.startswith("LAYER_C"):
            value = text.split(":", 1)[1].strip() if ":" in text else ""
            if value.isdigit():
                self.layer_count = int(value)
            return False
        self._setting(text)
        return False

    def _setting(self, text: str) -> None:
        lowered = text.lower()
        if self.slicer is None and ("generated" in lowered or "sliced by" in lowered):
            match = re.search(r"(?:generated (?:by|with)|sliced by)\s+([^\r\n]+)", text, re.IGNORECASE)
            if match:
                self.slicer = match.group(1).strip().split(" on ")[0][:80]
        match = _SETTING.match(text)
        if match and len(self.settings) < 4096:
            key = match.group(1).strip().lower()
            self.settings.setdefault(key, match.group(2).strip()[:400])


def _first_number(text):
    if text is None:
        return None
    match = re.search(r"[-+]?\d*\.?\d+", text)
    return float(match.group(0)) if match else None


# --------------------------------------------------------------------------- moves

def iter_moves(source) -> Iterator[Move]:
    """Every motion of the file as :class:`Move` segments, in file order (constant memory).

    ``source`` is a path or an iterable of lines. Pure feed-rate lines produce
    no move; G2/G3 arcs become chords within :data:`ARC_TOLERANCE` of the arc.
    Moves inside injected PrintWatch blocks are skipped.
    """
    name = _source_name(source)
    machine = Machine(name)
    notes = _Annotations()
    in_block = False
    # A last line without line end (a truncated file) is left out, as analyse() does.
    for line_no, text in enumerate(chain.from_iterable(_read_chunks(source, [])), 1):
        stripped = text.strip()
        if not stripped:
            continue
        if stripped[0] == ";":
            if stripped.startswith(BLOCK_BEGIN_PREFIX):
                in_block = _block_edge(stripped, in_block)
            elif not in_block:
                notes.comment(stripped)
            continue
        if in_block or stripped[0] == "@":
            continue
        if "\x00" in stripped:
            raise GcodeError(f"{name}: line {line_no}: binary data: not a G-code text file")
        code = stripped.split(";", 1)[0].strip().upper() if ";" in stripped else stripped.upper()
        if not code:
            continue
        machine.line_no = line_no
        if not machine.step(code):
            continue
        feed = machine.feedrate or 0.0
        end = (machine.x, machine.y, machine.z)
        if machine.arc is None:
            yield Move(line_no, machine.start, end, machine.de, feed, machine.tool, notes.width, notes.feature)
            continue
        cx, cy, clockwise = machine.arc
        previous, done = machine.start, 0.0
        for px, py, pz, fraction in arc_points(machine.start, end, (cx, cy), clockwise):
            point = end if fraction == 1.0 else (px, py, pz)
            yield Move(line_no, previous, point, machine.de * (fraction - done), feed, machine.tool,
                       notes.width, notes.feature)
            previous, done = point, fraction


def _block_edge(stripped: str, in_block: bool) -> bool:
    if stripped.endswith(BLOCK_BEGIN_SUFFIX):
        return True
    if stripped.endswith(BLOCK_END_SUFFIX):
        return False
    return in_block


# --------------------------------------------------------------------------- analysis

def _state(m: Machine, x, y, z, e, feedrate, retracted, top_z) -> MachineState:
    """A :class:`MachineState` from position values and the machine's modes."""
    return MachineState(x, y, z, e, feedrate, m.absolute, m.e_mode, m.e_relative, m.e_known,
                        m.scale != 1.0, m.tool, retracted, not m.unknown, top_z)


def _open_layer(layers: list, z: float, line: int, offset_before: int, candidate, state_before,
                first_marker_line) -> None:
    """Start a layer at the extruding move on ``line``; close the previous one."""
    if layers:
        previous = layers[-1]
        if candidate is not None:
            previous[2], previous[3], previous[4] = candidate
        else:  # nothing between the two layers: end right before this move
            previous[2], previous[3], previous[4] = line, offset_before, state_before
        previous[2] -= 1
        first = previous[2] + 1
    else:
        first = first_marker_line or 1
    layers.append([z, first, None, None, None, layers[-1][0] if layers else 0.0])


def analyse(source) -> GcodeInfo:
    """Read a G-code file once and return its :class:`GcodeInfo` (layer table and hints).

    Raises :class:`GcodeError` (one line naming the file and line) on an empty
    file, binary data, malformed numbers, or a file with no extruding moves.
    """
    name = _source_name(source)
    m = Machine(name)
    notes = _Annotations()
    info = GcodeInfo(layers=[])

    layers: list = []  # [top z, first_line, last_line, end_offset, state there, base z]
    purge_check = False  # set at the first slicer layer comment if something extruded before it
    markers_seen = 0
    marker_since_extrusion = False
    candidate = None  # (line, offset, state): where the current layer ends if no extrusion follows
    last_extrusion = 0  # line of the latest extruding move
    first_marker_line = None
    first_extrusion = None  # (line, offset, state) of the first layer's first extrusion
    offset = line_no = 0
    in_block = False
    block_line = 0
    retractions: Counter = Counter()
    retract_feeds: dict = {}
    seen_relative = seen_absolute = False
    spiral = False
    spiral_height = None  # layer height of a comment-less spiral, fixed where it starts
    sampled, sample_e, sample_length = 0, 0.0, 0.0  # E per mm, to tell 1.75 from 2.85 mm filament
    previous_extruded = False
    # Bounds in plain locals (list indexing per move costs more). Moves start from
    # home, a real position; seeding both corners with it makes if/elif updates exact.
    mx0 = mx1 = my0 = my1 = mz1 = 0.0
    inf = math.inf
    ex0, ex1, ey0, ey1, ez0, ez1 = inf, -inf, inf, -inf, inf, -inf

    # The machine state lives in locals while G0/G1 lines are interpreted inline
    # (this loop is the whole cost of analysis); other commands go through
    # Machine.step with the locals pushed before and pulled after.
    x = y = z = e = 0.0
    feed = None
    retracted = False
    top_z = 0.0
    absolute, e_rel, scale = True, False, 1.0
    unknown = m.unknown

    tail: list = []
    for text in chain.from_iterable(_read_chunks(source, tail)):
        line_no += 1
        line_offset = offset
        offset += len(text) + 1
        stripped = text.strip()
        if not stripped:
            continue
        first_char = stripped[0]
        if first_char == ";":
            if stripped.startswith(BLOCK_BEGIN_PREFIX) and stripped.endswith(
                    (BLOCK_BEGIN_SUFFIX, BLOCK_END_SUFFIX)):
                info.has_injected_blocks = True
                in_block = _block_edge(stripped, in_block)
                block_line = line_no
            elif not in_block and notes.comment(stripped):
                markers_seen += 1
                if first_marker_line is None:
                    first_marker_line = line_no
                    # Extrusion before the slicer's first layer comment may be a purge line:
                    # decided at the next extrusion.
                    purge_check = 0 < len(layers) <= 2
                marker_since_extrusion = True
                if candidate is None and last_extrusion:
                    candidate = (line_no, line_offset, _state(m, x, y, z, e, feed, retracted, top_z))
            elif line_no == 1 and text.endswith("\r"):
                info.line_ending = "\r\n"
            continue
        if in_block or first_char == "@":
            continue
        if line_no == 1 and text.endswith("\r"):
            info.line_ending = "\r\n"  # blocks are written with the file's own line ends
        code = stripped[: stripped.index(";")].rstrip() if ";" in stripped else stripped
        if not code:
            continue
        head = code[:3]
        if head == "G1 " or head == "G0 " or head == "g1 " or head == "g0 ":
            parts = code.split()
            nx, ny, nz = x, y, z
            de = 0.0
            feed_before = feed
            moved = False
            for word in parts[1:]:
                axis = word[0]
                if axis not in "XYZEF":
                    if axis not in "xyzef":
                        continue
                    axis = axis.upper()  # rare lower-case words: no upper() on every line
                try:
                    value = float(word[1:])
                except ValueError:
                    if len(word) > 1:
                        m.line_no = line_no
                        m._unparsable(word)
                    continue
                if scale != 1.0:
                    value *= scale
                if axis == "X":
                    nx = value if absolute else x + value
                    moved = True
                elif axis == "Y":
                    ny = value if absolute else y + value
                    moved = True
                elif axis == "Z":
                    nz = value if absolute else z + value
                    moved = True
                elif axis == "E":
                    if e_rel:
                        de = value
                        e += value
                    else:
                        de = value - e
                        e = value
                    moved = True
                else:
                    feed = value
            if absolute and unknown:
                for word in parts[1:]:
                    unknown.discard(word[0].upper())
            if not moved:
                continue
            sx, sy, sz = x, y, z
            x, y, z = nx, ny, nz
            retracted_before, top_before = retracted, top_z
        else:
            if "\x00" in code:
                raise GcodeError(f"{name}: line {line_no}: binary data: not a G-code text file")
            code = code.upper()
            if candidate is None and last_extrusion and not _QUIET.match(code):
                # Any other command (fan, heater, tool change, mode switch) after a
                # layer's last extrusion ends that layer: the block goes before it.
                candidate = (line_no, line_offset, _state(m, x, y, z, e, feed, retracted, top_z))
            m.x, m.y, m.z, m.e, m.feedrate, m.retracted, m.top_z = x, y, z, e, feed, retracted, top_z
            m.line_no = line_no
            is_move = m.step(code)
            x, y, z, e, feed, retracted, top_z = m.x, m.y, m.z, m.e, m.feedrate, m.retracted, m.top_z
            absolute, e_rel, scale = m.absolute, m.e_relative, m.scale
            if not is_move:
                continue
            de = m.de
            sx, sy, sz = m.start
            feed_before, retracted_before, top_before = m.before
        # ---- a move from (sx, sy, sz) to (x, y, z) pushing de mm of filament
        if x < mx0:
            mx0 = x
        elif x > mx1:
            mx1 = x
        if y < my0:
            my0 = y
        elif y > my1:
            my1 = y
        if z > mz1:
            mz1 = z
        if de <= 0 or (x == sx and y == sy):
            previous_extruded = False
            if z != sz and candidate is None and last_extrusion:
                candidate = (line_no, line_offset,
                             _state(m, sx, sy, sz, e - de, feed_before, retracted_before, top_before))
            if de < 0:
                retracted = True
                if x == sx and y == sy and z == sz:
                    amount = round(-de, 2)
                    retractions[amount] += 1
                    retract_feeds.setdefault(amount, feed)
            elif de > 0:
                retracted = False
            continue
        # ---- an extruding move
        retracted = False
        if z > top_z:
            top_z = z
        if e_rel:
            seen_relative = True
        else:
            seen_absolute = True
        if not previous_extruded:  # the start of a run of extrusions
            ex0, ex1, ey0, ey1 = min(ex0, sx), max(ex1, sx), min(ey0, sy), max(ey1, sy)
            ez0, ez1 = min(ez0, sz), max(ez1, sz)
            previous_extruded = True
        if x < ex0:
            ex0 = x
        elif x > ex1:
            ex1 = x
        if y < ey0:
            ey0 = y
        elif y > ey1:
            ey1 = y
        if z > ez1:
            ez1 = z
        elif z < ez0:
            ez0 = z
        sampled += 1
        if not sampled & 7 and len(layers) > 1:  # every 8th extrusion above the first layer
            sample_e += de
            sample_length += math.hypot(x - sx, y - sy)
        if purge_check:
            purge_check = False
            if z <= layers[-1][0] + PURGE_Z_MARGIN:
                # The slicer's first layer starts at (about) the height of what came before
                # its first comment: that was the start script's purge or prime line.
                layers.clear()
                first_extrusion = None
                seen_relative = seen_absolute = False
                ex0, ex1, ey0, ey1, ez0, ez1 = min(sx, x), max(sx, x), min(sy, y), max(sy, y), min(sz, z), max(sz, z)
        new_layer = False
        if not layers:
            new_layer = True
        else:
            top = layers[-1][0]
            sloped = z - sz > Z_EPS or sz - z > Z_EPS
            if z > top + Z_EPS:
                if not sloped:
                    new_layer = True
                else:
                    spiral = True
                    if markers_seen:
                        new_layer = marker_since_extrusion
                    else:  # no comments: a new layer per nominal height of rise
                        if spiral_height is None:
                            spiral_height = _nominal(notes, layers)
                        new_layer = z > layers[-1][5] + spiral_height + Z_EPS
                    if not new_layer:
                        layers[-1][0] = z
            elif z < top - Z_EPS and not sloped:
                new_layer = True  # sequential printing: the next object
            elif spiral and marker_since_extrusion:
                new_layer = True  # spiral vase: a revolution may start flat at the old top
        if new_layer:
            state_before = _state(m, sx, sy, sz, e - de, feed_before, retracted_before, top_before)
            _open_layer(layers, z, line_no, line_offset, candidate, state_before, first_marker_line)
            if len(layers) == 1:
                first_extrusion = (line_no, line_offset, state_before)
        last_extrusion = line_no
        candidate = None
        marker_since_extrusion = False

    complete_lines, complete_bytes = line_no, offset
    if tail:
        line_no += 1
        offset += len(tail[0])
        if "\x00" in tail[0]:
            raise GcodeError(f"{name}: line {line_no}: binary data: not a G-code text file")
        info.warnings.append(f"line {line_no} has no line end (file truncated?): ignored")
    if in_block:
        raise GcodeError(f"{name}: line {block_line}: PrintWatch block is not closed (file truncated?)")
    info.total_lines = line_no
    info.total_bytes = offset
    if line_no == 0 or offset == 0:
        raise GcodeError(f"{name}: file is empty")
    if not layers:
        raise GcodeError(f"{name}: no extruding moves in {line_no} lines: not a print (no layers)")
    m.x, m.y, m.z, m.e, m.feedrate, m.retracted, m.top_z = x, y, z, e, feed, retracted, top_z
    last = layers[-1]
    if candidate is not None:
        last[2], last[3], last[4] = candidate
        last[2] -= 1
    else:  # only travel after the last extrusion: the final check goes at the end
        last[2], last[3], last[4] = complete_lines, complete_bytes, m.state()

    previous_z = 0.0
    for index, (top, first, last_line, end_offset, state, _base) in enumerate(layers, 1):
        # Below the previous layer (sequential printing: the next object) it starts on the bed.
        height = top - previous_z if top > previous_z else top
        info.layers.append(Layer(index, top, height, first, last_line, True))
        info.end_offsets.append(end_offset)
        info.states.append(state)
        previous_z = top
    if first_extrusion is not None:
        info.first_extrusion_line, info.first_extrusion_offset, info.first_extrusion_state = first_extrusion

    _fill_hints(info, notes, m, retractions, retract_feeds)
    if info.filament_diameter_source == "default" and sample_length > 0 and info.nominal_layer_height:
        _estimate_filament(info, sample_e / sample_length)
    info.layer_markers = markers_seen
    info.spiral_vase = spiral or _truthy(notes.settings.get("spiral_vase")) or _truthy(
        notes.settings.get("magic_spiralize"))
    info.extrusion_mode = "mixed" if seen_relative and seen_absolute else (
        "relative" if seen_relative else "absolute")
    info.positioning = "mixed" if m.used_relative_positioning else "absolute"
    info.units = ("inch" if m.scale != 1.0 else "mixed") if m.used_inches else "mm"
    info.firmware_retraction = m.firmware_retraction
    info.warnings.extend(m.warnings)
    info.tools = sorted(m.tools_used)
    info.extrusion_bounds = ((ex0, ey0, ez0), (ex1, ey1, ez1))
    info.move_bounds = ((mx0, my0, 0.0), (mx1, my1, mz1))
    return info


def _nominal(notes: _Annotations, layers: list) -> float:
    """Layer height from the slicer's settings, else the height of the latest layer."""
    for key in ("layer_height", "layerheight", "layer height"):
        value = _first_number(notes.settings.get(key))
        if value and value > 0:
            return value
    if layers and layers[-1][0] - layers[-1][5] > 0.02:
        return layers[-1][0] - layers[-1][5]
    return 0.2


#: Extrusion width / layer height of ordinary slicer settings (0.45 / 0.2).
_TYPICAL_WIDTH_TO_HEIGHT = 2.2


def _estimate_filament(info: GcodeInfo, e_per_mm: float) -> None:
    """No diameter in the comments (Cura, Simplify3D without settings): 1.75 or 2.85 mm,
    whichever makes the extrusion width / layer height ratio the more ordinary one;
    they differ by 2.65x, so the choice is clear on real files. Reported beside the
    default (``filament_diameter`` stays 1.75 unless a comment says otherwise)."""
    ratios = {}
    for diameter in (1.75, 2.85):
        width = e_per_mm * math.pi * (diameter / 2) ** 2 / info.nominal_layer_height
        ratios[diameter] = abs(math.log(max(width, 1e-9) / info.nominal_layer_height / _TYPICAL_WIDTH_TO_HEIGHT))
    info.filament_diameter_estimate = min(ratios, key=ratios.get)


def _truthy(value) -> bool:
    return value is not None and value.strip().lower() in ("1", "true", "yes")


def _fill_hints(info: GcodeInfo, notes: _Annotations, machine: Machine, retractions: Counter,
                retract_feeds: dict) -> None:
    settings = notes.settings
    info.slicer = notes.slicer
    info.slicer_layer_count = notes.layer_count
    for key in ("filament_diameter", "filamentdiameter", "filament diameter #1", "material_diameter",
                "filamentdiameters"):
        value = _first_number(settings.get(key))
        if value and 0.5 < value < 5:
            info.filament_diameter = value
            info.filament_diameter_source = "comment"
            break
    # The heights the file really prints (a header can disagree: the LulzBot Cura file
    # says 0.22 and prints 0.32); the header only when there is a single layer.
    heights = sorted(layer.height for layer in info.layers[1:])
    nominal = heights[len(heights) // 2] if heights else None
    if not nominal:
        for key in ("layer_height", "layerheight", "layer height"):
            nominal = _first_number(settings.get(key))
            if nominal and nominal > 0:
                break
    info.nominal_layer_height = round(nominal, 4) if nominal else None
    bed_shape = settings.get("bed_shape")
    if bed_shape:
        try:
            points = [tuple(float(v) for v in p.split("x")) for p in bed_shape.split(",")]
            xs, ys = [p[0] for p in points], [p[1] for p in points]
            info.bed_origin = (min(xs), min(ys))
            info.bed_size = (max(xs) - min(xs), max(ys) - min(ys))
        except (ValueError, IndexError):
            info.warnings.append(f"bed_shape comment not understood: {bed_shape[:60]!r}")
    dimension = settings.get("dimension")  # ideaMaker ";Dimension: 225.000 225.000 240.000 0.400"
    if dimension and info.bed_size is None:
        numbers = dimension.split()
        try:
            info.bed_size = (float(numbers[0]), float(numbers[1]))
            info.max_z = float(numbers[2])
        except (ValueError, IndexError):
            pass
    for key in ("max_print_height", "machine_height"):
        value = _first_number(settings.get(key))
        if value and value > 0:
            info.max_z = value
            break
    width, depth = _first_number(settings.get("machine_width")), _first_number(settings.get("machine_depth"))
    if info.bed_size is None and width and depth:
        info.bed_size = (width, depth)
    length = None
    for key in ("retract_length", "retraction_amount", "extruderretractiondistance"):
        length = _first_number(settings.get(key))
        if length and length > 0:
            break
    if retractions:
        common = retractions.most_common(1)[0][0]
        info.retract_length = length if length and length > 0 else common
        info.retract_feedrate = retract_feeds.get(common)
    elif length and length > 0:
        info.retract_length = length
