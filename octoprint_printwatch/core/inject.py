"""Check-block injection: park the head between layers so the cameras see the part.

After the last line of every Nth layer (and of the final layer) a block is
inserted that waits for the moves to finish, retracts, lifts, parks, announces
the check to the host and then undoes all of it::

    ; printwatch check block begin
    M400                                  ; let queued moves finish
    G1 E41.6 F2400                        ; retract (G10 when the file uses firmware retraction)
    G1 Z16.4 F300                         ; lift above the highest printed point, clamped to max Z
    G1 X10 Y10 F3000                      ; park (inside the bed, clamped with a margin)
    M400
    @PRINTWATCH_CHECK layer=30 z=6.4      ; OctoPrint swallows @-commands; the plugin acts on it
    G1 X87.55 Y96.418 F3000               ; back ...
    G1 Z6.4 F300                          ; ... down ...
    G1 E43.6 F2400                        ; ... un-retract
    G1 F1800                              ; feed rate as it was
    ; printwatch check block end

The block uses absolute coordinates computed from the interpreter's state; if
the file was in G91 at that point, it switches with ``M400``/``G90`` and back
with ``M400``/``G91`` (some firmware and OctoPrint's virtual printer apply
modes before queued moves finish). Values are written in the file's units.
Every block sits between comment lines that :func:`strip_injected` recognises,
so the original file comes back byte for byte.
"""
from __future__ import annotations

import math
import os
import shutil
import tempfile
import time
from dataclasses import dataclass, field
from typing import Iterator, Sequence

from .errors import GcodeError
from .gcode import GcodeInfo, MachineState, analyse, BLOCK_BEGIN_PREFIX, BLOCK_BEGIN_SUFFIX, BLOCK_END_SUFFIX

CHECK_MARKER = "@PRINTWATCH_CHECK"
BACKGROUND_MARKER = "@PRINTWATCH_BACKGROUND"
CHECK_BEGIN = BLOCK_BEGIN_PREFIX + "check" + BLOCK_BEGIN_SUFFIX
CHECK_END = BLOCK_BEGIN_PREFIX + "check" + BLOCK_END_SUFFIX
BACKGROUND_BEGIN = BLOCK_BEGIN_PREFIX + "background" + BLOCK_BEGIN_SUFFIX
BACKGROUND_END = BLOCK_BEGIN_PREFIX + "background" + BLOCK_END_SUFFIX

DEFAULT_EVERY = 10
DEFAULT_LIFT = 10.0
#: Park positions stay this far inside the bed edges (mm).
PARK_MARGIN = 10.0
DEFAULT_TRAVEL_FEEDRATE = 3000.0  # mm/min
DEFAULT_Z_FEEDRATE = 300.0  # mm/min: the slowest common Z axis (Ender-3: 5 mm/s)
DEFAULT_RETRACT = 1.0  # mm, when the file shows no retraction
DEFAULT_RETRACT_FEEDRATE = 2100.0  # mm/min
MAX_RETRACT = 10.0
#: Less head clearance than this over the printed part is reported.
MIN_CLEARANCE = 1.0


@dataclass(frozen=True)
class Check:
    """One injected check: after ``source_line`` of the original, marker on ``line`` of the output."""

    layer: int
    z: float
    line: int
    source_line: int


@dataclass
class InjectionResult:
    checks: list
    warnings: list = field(default_factory=list)
    bytes_in: int = 0
    bytes_out: int = 0
    seconds: float = 0.0
    layers: int = 0
    background_line: "int | None" = None  # output line of @PRINTWATCH_BACKGROUND
    park: "tuple | None" = None
    max_z: "float | None" = None
    bed: "tuple | None" = None  # ((x0, y0), (x1, y1)) the volume the blocks stay in

    @property
    def megabytes_per_second(self) -> float:
        return self.bytes_in / 1e6 / self.seconds if self.seconds > 0 else math.inf


def fmt(value: float) -> str:
    """A number as G-code: at most 5 decimals, no trailing zeros (``87.55``, ``-2``)."""
    text = f"{value:.5f}".rstrip("0").rstrip(".")
    return "0" if text in ("-0", "") else text


def fmt_exact(value: float) -> str:
    """A number as G-code that reads back as exactly ``value`` (no exponent notation):
    restored positions, E and feed rates must be the very values the file had."""
    for decimals in range(5, 18):
        text = f"{value:.{decimals}f}"
        if float(text) == value:
            break
    text = text.rstrip("0").rstrip(".") if "." in text else text
    return "0" if text in ("-0", "") else text


# --------------------------------------------------------------------------- planning

def plan_layers(info: GcodeInfo, every: "int | None" = None,
                heights: "Sequence[float] | None" = None, warnings: "list | None" = None) -> list:
    """1-based indices of the layers to check after: every Nth (or the first layer
    reaching each height), always including the final layer."""
    warnings = warnings if warnings is not None else []
    count = len(info.layers)
    if every is not None and heights is not None:
        raise GcodeError("give either every N layers or heights, not both")
    chosen = set()
    if heights is not None:
        for height in heights:
            if not (isinstance(height, (int, float)) and math.isfinite(height) and height > 0):
                raise GcodeError(f"check height {height!r} is not a positive number of mm")
            index = next((layer.index for layer in info.layers if layer.z >= height - 1e-6), None)
            if index is None:
                warnings.append(f"height {fmt(height)} mm is above the top of the print "
                                f"({fmt(info.layers[-1].z)} mm): checked at the final layer")
                index = count
            chosen.add(index)
    else:
        every = DEFAULT_EVERY if every is None else every
        if not isinstance(every, int) or every < 1:
            raise GcodeError(f"every must be a whole number of layers >= 1, got {every!r}")
        chosen.update(range(every, count + 1, every))
    chosen.add(count)
    return sorted(chosen)


def _volume(info: GcodeInfo, bed, max_z, warnings: list):
    """((x0, y0), (x1, y1)) and max Z that the blocks must stay in."""
    if bed is not None:
        try:
            values = [float(v) for v in bed]
        except (TypeError, ValueError):
            raise GcodeError(f"bed must be (width, depth) or (x_min, x_max, y_min, y_max) in mm, got {bed!r}") from None
        if len(values) == 2:
            values = [0.0, values[0], 0.0, values[1]]
        if len(values) != 4 or not all(math.isfinite(v) for v in values) or not (
                values[1] > values[0] and values[3] > values[2]):
            raise GcodeError(f"bed must be (width, depth) or (x_min, x_max, y_min, y_max) in mm, got {bed!r}")
        area = ((values[0], values[2]), (values[1], values[3]))
    elif info.bed_size is not None:
        (x0, y0), (width, depth) = info.bed_origin, info.bed_size
        area = ((x0, y0), (x0 + width, y0 + depth))
    else:
        (x0, y0, _), (x1, y1, _) = info.move_bounds
        area = ((x0, y0), (x1, y1))
        warnings.append(f"bed size not given: parking within the XY range the file itself visits "
                        f"(X {fmt(x0)}..{fmt(x1)}, Y {fmt(y0)}..{fmt(y1)})")
    if max_z is not None:
        if not (math.isfinite(max_z) and max_z > 0):
            raise GcodeError(f"max Z must be a positive number of mm, got {max_z!r}")
        top = float(max_z)
    elif info.max_z is not None:
        top = info.max_z
    else:
        top = info.move_bounds[1][2]
        warnings.append(f"max Z not given: lifts stay below the highest Z the file reaches ({fmt(top)} mm)")
    return area, top


def _park(area, park, warnings: list) -> tuple:
    (x0, y0), (x1, y1) = area
    margin_x = min(PARK_MARGIN, (x1 - x0) / 2)
    margin_y = min(PARK_MARGIN, (y1 - y0) / 2)
    low_x, high_x, low_y, high_y = x0 + margin_x, x1 - margin_x, y0 + margin_y, y1 - margin_y
    if park is None:
        return (low_x, low_y)  # front-left corner
    px, py = (float(v) for v in park)
    if not (math.isfinite(px) and math.isfinite(py)):
        raise GcodeError(f"park position must be two numbers of mm, got {park!r}")
    cx, cy = min(max(px, low_x), high_x), min(max(py, low_y), high_y)
    if (cx, cy) != (px, py):
        warnings.append(f"park position {fmt(px)},{fmt(py)} is outside the bed (less than "
                        f"{fmt(PARK_MARGIN)} mm from an edge): using {fmt(cx)},{fmt(cy)}")
    return (cx, cy)


# --------------------------------------------------------------------------- blocks

@dataclass(frozen=True)
class BlockSettings:
    park: tuple
    max_z: float
    lift: float
    retract: float
    retract_feedrate: float
    firmware_retraction: bool
    travel_feedrate: float = DEFAULT_TRAVEL_FEEDRATE
    z_feedrate: float = DEFAULT_Z_FEEDRATE


def build_block(state: MachineState, marker: str, settings: BlockSettings, kind: str = "check") -> tuple:
    """The lines of one block (without line ends) and a list of notes about it.

    ``state`` is the machine state where the block goes; the block leaves the
    position, E, feed rate, positioning, extrusion mode and units as they were.
    """
    notes = []
    unit = 25.4 if state.inches else 1.0

    def num(mm):
        return fmt(mm / unit)

    def exact(mm):  # values the block restores
        return fmt_exact(mm / unit)

    top = max(state.top_z, state.z)
    lift_z = top + settings.lift
    if lift_z > settings.max_z:
        lift_z = settings.max_z
        notes.append("lift clamped at max Z")
    lift_z = max(lift_z, state.z)
    if lift_z - top < MIN_CLEARANCE and settings.lift >= MIN_CLEARANCE:
        notes.append(f"only {fmt(max(lift_z - top, 0))} mm above the part while parking")
    px, py = settings.park
    travel, zfeed = num(settings.travel_feedrate), num(settings.z_feedrate)
    r, rfeed = settings.retract, num(settings.retract_feedrate)

    lines = [BLOCK_BEGIN_PREFIX + kind + BLOCK_BEGIN_SUFFIX, "M400"]
    retract, unretract = [], []
    if state.retracted or r <= 0:
        pass
    elif settings.firmware_retraction:
        retract, unretract = ["G10"], ["G11"]
    elif state.e_relative:
        retract, unretract = [f"G1 E-{num(r)} F{rfeed}"], [f"G1 E{num(r)} F{rfeed}"]
    elif state.e_known:
        retract = [f"G1 E{exact(state.e - r)} F{rfeed}"]
        unretract = [f"G1 E{exact(state.e)} F{rfeed}"]
    else:  # absolute E whose origin the file never set (no G92 E): do not touch E
        notes.append("no retraction: the file never sets the E position (G92 E)")
    lines += retract
    if not state.absolute:
        lines += ["M400", "G90"]
    if lift_z != state.z:
        lines.append(f"G1 Z{num(lift_z)} F{zfeed}")
    lines += [f"G1 X{num(px)} Y{num(py)} F{travel}", "M400", marker,
              f"G1 X{exact(state.x)} Y{exact(state.y)} F{travel}"]
    if unretract == ["G11"]:
        # Before the absolute move down: G11 undoes any firmware Z-hop (M207 Z) the
        # G10 added, however the firmware accounts for it, so the Z below is exact.
        lines += unretract
        unretract = []
    if lift_z != state.z:
        lines.append(f"G1 Z{exact(state.z)} F{zfeed}")
    if not state.absolute:
        lines += ["M400", "G91"]
        if state.e_mode is not None:  # G91 reset the E mode (Marlin 2); set it back
            lines.append("M83" if state.e_mode == "relative" else "M82")
    lines += unretract
    if state.feedrate is not None:
        lines.append(f"G1 F{exact(state.feedrate)}")
    lines.append(BLOCK_BEGIN_PREFIX + kind + BLOCK_END_SUFFIX)
    return lines, notes


# --------------------------------------------------------------------------- injection

def inject_checks(src_path, dst_path, *, every: "int | None" = None, heights: "Sequence[float] | None" = None,
                  lift: float = DEFAULT_LIFT, park: "tuple | None" = None, max_z: "float | None" = None,
                  bed: "tuple | None" = None, background: bool = False,
                  travel_feedrate: float = DEFAULT_TRAVEL_FEEDRATE, z_feedrate: float = DEFAULT_Z_FEEDRATE,
                  info: "GcodeInfo | None" = None) -> InjectionResult:
    """Copy ``src_path`` to ``dst_path`` with check blocks (see the module doc).

    ``every``: check after every Nth layer (default 10); ``heights``: check after
    the first layer reaching each height (mm) instead. The final layer is always
    checked. ``park`` (x, y) defaults to the front-left bed corner; ``bed``
    (width, depth) and ``max_z`` default to the slicer's comments, else to the
    range the file itself moves in (with a warning). ``background`` adds an
    ``@PRINTWATCH_BACKGROUND`` block before the first layer's first extrusion.
    Output is written to a temporary file and renamed: on error there is no
    output file. Raises :class:`GcodeError` on bad input.
    """
    started = time.perf_counter()
    src, dst = os.fspath(src_path), os.fspath(dst_path)
    if not (isinstance(lift, (int, float)) and math.isfinite(lift) and lift >= 0):
        raise GcodeError(f"lift must be a number of mm >= 0, got {lift!r}")
    for what, value in (("travel feed rate", travel_feedrate), ("Z feed rate", z_feedrate)):
        if not (math.isfinite(value) and value > 0):
            raise GcodeError(f"{what} must be positive, got {value!r}")
    if info is None:
        info = analyse(src)
    if info.has_injected_blocks:
        raise GcodeError(f"{src}: already contains PrintWatch blocks; inject into the original file "
                         f"(printwatch inject --strip removes them)")
    warnings = list(info.warnings)
    chosen = plan_layers(info, every=every, heights=heights, warnings=warnings)
    area, top_z = _volume(info, bed, max_z, warnings)
    park_xy = _park(area, park, warnings)
    retract = min(info.retract_length or DEFAULT_RETRACT, MAX_RETRACT)
    settings = BlockSettings(park=park_xy, max_z=top_z, lift=float(lift), retract=retract,
                             retract_feedrate=info.retract_feedrate or DEFAULT_RETRACT_FEEDRATE,
                             firmware_retraction=info.firmware_retraction,
                             travel_feedrate=float(travel_feedrate), z_feedrate=float(z_feedrate))
    eol = info.line_ending

    # (byte offset in the source, source lines before it, block lines, check or None)
    inserts = []
    if background:
        state = info.first_extrusion_state
        if state is None or not state.known:
            warnings.append("no background block: the head position before the first layer is unknown")
        else:
            lines, notes = build_block(state, BACKGROUND_MARKER, settings, kind="background")
            warnings.extend(f"background: {note}" for note in notes)
            inserts.append((info.first_extrusion_offset, info.first_extrusion_line - 1, lines, None))
    clamped = []
    noted: dict = {}  # note -> layers it applies to
    for index in chosen:
        layer = info.layers[index - 1]
        state = info.states[index - 1]
        if state is None or not state.known:
            warnings.append(f"layer {index}: head position unknown at the end of the layer: no check there")
            continue
        marker = f"{CHECK_MARKER} layer={index} z={fmt(layer.z)}"
        lines, notes = build_block(state, marker, settings)
        for note in notes:
            if note == "lift clamped at max Z":
                clamped.append(index)
            else:
                noted.setdefault(note, []).append(index)
        inserts.append((info.end_offsets[index - 1], layer.last_line, lines, (index, layer.z)))
    for note, where in noted.items():
        warnings.append(f"layer {where[0]}: {note}" if len(where) == 1 else
                        f"{note} ({len(where)} checks, layers {where[0]}..{where[-1]})")
    if clamped:
        warnings.append(f"lift clamped at max Z {fmt(top_z)} mm for {len(clamped)} check(s), "
                        f"from layer {clamped[0]}")
    inserts.sort(key=lambda item: item[0])

    checks = []
    background_line = None
    added_lines = 0
    blocks = []
    for offset, lines_before, lines, check in inserts:
        marker_at = next(i for i, text in enumerate(lines) if text.startswith("@"))
        out_line = lines_before + added_lines + marker_at + 1
        if check is None:
            background_line = out_line
        else:
            checks.append(Check(layer=check[0], z=check[1], line=out_line, source_line=lines_before))
        added_lines += len(lines)
        blocks.append((offset, (eol.join(lines) + eol).encode("ascii")))

    bytes_out = _write_with_blocks(src, dst, blocks, info.total_bytes)
    return InjectionResult(checks=checks, warnings=warnings, bytes_in=info.total_bytes, bytes_out=bytes_out,
                           seconds=time.perf_counter() - started, layers=len(info.layers),
                           background_line=background_line, park=park_xy, max_z=top_z, bed=area)


def _write_with_blocks(src: str, dst: str, blocks: list, expected_size: int) -> int:
    """Copy src to dst inserting each (offset, bytes); temporary file + rename."""
    directory = os.path.dirname(os.path.abspath(dst))
    if not os.path.isdir(directory):
        raise GcodeError(f"{dst}: folder {directory} does not exist")
    try:
        handle = tempfile.NamedTemporaryFile(dir=directory, prefix="." + os.path.basename(dst) + ".",
                                             suffix=".tmp", delete=False)
    except OSError as exc:
        raise GcodeError(f"{dst}: cannot write ({exc.strerror})") from None
    written = 0
    try:
        with handle as out, open(src, "rb") as source:
            position = 0
            for offset, block in blocks:
                written += _copy(source, out, offset - position)
                out.write(block)
                written += len(block)
                position = offset
            rest = _copy(source, out, None)
            written += rest
            if position + rest != expected_size:
                raise GcodeError(f"{src}: file changed while it was being injected")
        os.replace(handle.name, dst)
    except BaseException as exc:
        try:
            os.unlink(handle.name)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise GcodeError(f"{dst}: cannot write ({exc.strerror or exc})") from None
        raise
    return written


def _copy(source, out, count) -> int:
    if count is None:
        before = source.tell()
        shutil.copyfileobj(source, out, 1 << 20)
        return source.tell() - before
    left = count
    while left > 0:
        chunk = source.read(min(left, 1 << 20))
        if not chunk:
            break
        out.write(chunk)
        left -= len(chunk)
    return count - left


# --------------------------------------------------------------------------- stripping

def _is_edge(line, suffix: str) -> bool:
    if isinstance(line, bytes):
        line = line.decode("latin-1")
    text = line.rstrip("\r\n")
    return text.startswith(BLOCK_BEGIN_PREFIX) and text.endswith(suffix)


def strip_injected(source):
    """The lines of a file with every PrintWatch block removed, as bytes with their
    line ends: joined, they are the original file byte for byte.

    ``source`` is a path or an iterable of lines with their line ends (bytes or
    str; str lines come back as str). Given the whole G-code text as one str
    (anything containing a line end, which no path does), returns the stripped
    text as one str.
    """
    if isinstance(source, str) and ("\n" in source or "\r" in source):
        return "".join(_strip(source.splitlines(keepends=True), "<text>"))
    return _strip_lines(source)


def _strip_lines(source) -> Iterator[bytes]:
    name = os.fspath(source) if isinstance(source, (str, os.PathLike)) else "<lines>"
    if isinstance(source, (str, os.PathLike)):
        try:
            handle = open(source, "rb")
        except OSError as exc:
            raise GcodeError(f"{name}: cannot read ({exc.strerror})") from None
        with handle:
            yield from _strip(handle, name)
    else:
        yield from _strip(source, name)


def _strip(lines, name) -> Iterator[bytes]:
    begin_line = None
    for number, line in enumerate(lines, 1):
        if begin_line is None:
            if line[:2] in (b"; ", "; ") and _is_edge(line, BLOCK_BEGIN_SUFFIX):
                begin_line = number
            else:
                yield line
        elif _is_edge(line, BLOCK_END_SUFFIX):
            begin_line = None
    if begin_line is not None:
        raise GcodeError(f"{name}: line {begin_line}: PrintWatch block is not closed (file truncated?)")


def strip_file(src_path, dst_path) -> int:
    """Write ``src_path`` without PrintWatch blocks to ``dst_path`` (temporary file + rename).
    Returns the number of bytes written."""
    dst = os.fspath(dst_path)
    directory = os.path.dirname(os.path.abspath(dst))
    handle = tempfile.NamedTemporaryFile(dir=directory, prefix="." + os.path.basename(dst) + ".",
                                         suffix=".tmp", delete=False)
    written = 0
    try:
        with handle as out:
            for line in strip_injected(src_path):
                out.write(line)
                written += len(line)
        os.replace(handle.name, dst)
    except BaseException:
        try:
            os.unlink(handle.name)
        except OSError:
            pass
        raise
    return written
