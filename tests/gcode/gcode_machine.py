"""A small G-code simulator used only by the tests.

It is written independently of ``octoprint_printwatch.core.gcode`` (its own
tokeniser, its own mode rules) so that injection is checked against a second
reading of the file, not against the code that produced it. Marlin semantics:
the relative-mode bits of Marlin 2 (``axis_relative``): G90/G91 set or clear the
X, Y, Z and E bits and clear the E-mode overrides; M82/M83 set an override that
decides for E until the next G90/G91.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field

_WORD = re.compile(r"([A-Za-z])\s*([-+]?[0-9]*\.?[0-9]+)?")
BLOCK_BEGIN = re.compile(r"^; printwatch (\w+) block begin\s*$")
BLOCK_END = re.compile(r"^; printwatch (\w+) block end\s*$")


@dataclass(frozen=True)
class State:
    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    e: float = 0.0
    feedrate: float | None = None
    relative_xyz: bool = False
    relative_e_bit: bool = False  # set by G91 along with X/Y/Z
    e_mode: str | None = None  # override: 'M82', 'M83', cleared by G90/G91
    inches: bool = False
    tool: int = 0
    fw_retracted: bool = False

    @property
    def relative_e(self) -> bool:
        if self.e_mode == "M82":
            return False
        if self.e_mode == "M83":
            return True
        return self.relative_e_bit


@dataclass
class Block:
    kind: str
    begin_line: int
    before: State
    after: State | None = None
    lines: list = field(default_factory=list)  # code lines inside the block
    positions: list = field(default_factory=list)  # (x, y, z) after each move inside the block
    extruding_moves: int = 0
    markers: list = field(default_factory=list)


@dataclass
class Trace:
    segments: list = field(default_factory=list)  # (start xyz, end xyz, e) of extruding moves outside blocks
    blocks: list = field(default_factory=list)
    markers: list = field(default_factory=list)  # (line number, text) of every @ line
    final: State | None = None


def run(path) -> Trace:
    """Interpret a whole file; extruding segments outside blocks, and what each block did."""
    machine = _Machine()
    trace = Trace()
    block = None
    with open(path, "rb") as handle:
        for number, raw in enumerate(handle, 1):
            text = raw.decode("latin-1").strip()
            if text.startswith("; printwatch "):
                if BLOCK_BEGIN.match(text):
                    assert block is None, f"line {number}: nested block"
                    block = Block(BLOCK_BEGIN.match(text).group(1), number, machine.snapshot())
                    continue
                if BLOCK_END.match(text):
                    assert block is not None, f"line {number}: block end without begin"
                    block.after = machine.snapshot()
                    trace.blocks.append(block)
                    block = None
                    continue
            if text.startswith("@"):
                trace.markers.append((number, text))
                if block is not None:
                    block.markers.append(text)
                continue
            code = text.split(";", 1)[0].strip()
            if not code:
                continue
            if block is not None:
                block.lines.append(code)
            segment = machine.execute(code)
            if segment is None:
                continue
            start, end, pushed = segment
            extruding = pushed > 0 and start[:2] != end[:2]
            if block is not None:
                block.positions.append(end)
                block.extruding_moves += extruding
            elif extruding:
                trace.segments.append(segment)
    assert block is None, "file ends inside a block"
    trace.final = machine.snapshot()
    return trace


class _Machine:
    """Mutable state while a file runs; snapshots are :class:`State`."""

    def __init__(self):
        self.__dict__.update(vars(State()))

    def snapshot(self) -> State:
        return State(**{name: getattr(self, name) for name in State.__dataclass_fields__})

    @property
    def relative_e(self) -> bool:
        return State.relative_e.fget(self)

    def execute(self, code: str):
        words = [(letter.upper(), value) for letter, value in _WORD.findall(code)]
        if not words:
            return None
        if words[0][0] == "N":
            words = words[1:]
        letter, value = words[0]
        command = f"{letter}{int(float(value))}" if value and letter in "GMT" else letter
        params = {key: (float(val) if val else None) for key, val in words[1:]}
        unit = 25.4 if self.inches else 1.0

        if command in ("G0", "G1", "G2", "G3"):
            start = (self.x, self.y, self.z)
            position = list(start)
            for index, axis in enumerate("XYZ"):
                if params.get(axis) is not None:
                    value_mm = params[axis] * unit
                    position[index] = position[index] + value_mm if self.relative_xyz else value_mm
            pushed = 0.0
            if params.get("E") is not None:
                value_mm = params["E"] * unit
                if self.relative_e:
                    pushed, self.e = value_mm, self.e + value_mm
                else:
                    pushed, self.e = value_mm - self.e, value_mm
            if params.get("F") is not None:
                self.feedrate = params["F"] * unit
            self.x, self.y, self.z = position
            if not any(params.get(axis) is not None for axis in "XYZE"):
                return None
            return start, tuple(position), pushed
        if command == "G90":
            self.relative_xyz = self.relative_e_bit = False
            self.e_mode = None
        elif command == "G91":
            self.relative_xyz = self.relative_e_bit = True
            self.e_mode = None
        elif command in ("M82", "M83"):
            self.e_mode = command
        elif command in ("G20", "G21"):
            self.inches = command == "G20"
        elif command == "G92":
            if not params:
                self.x = self.y = self.z = self.e = 0.0
            for axis in "XYZE":
                if axis in params:
                    setattr(self, axis.lower(), (params[axis] or 0.0) * unit)
        elif command == "G28":
            for axis in [axis for axis in "XYZ" if axis in params] or ["X", "Y", "Z"]:
                setattr(self, axis.lower(), 0.0)
        elif command == "G10" and not ({"P", "L"} & set(params)):
            self.fw_retracted = True
        elif command == "G11":
            self.fw_retracted = False
        elif letter == "T" and value:
            self.tool = int(float(value))
        return None


def states_equal(a: State, b: State, tolerance: float = 1e-6) -> bool:
    """Equal, with floats compared to ``tolerance`` mm (blocks write 5 decimals)."""
    for name in ("x", "y", "z", "e"):
        if abs(getattr(a, name) - getattr(b, name)) > tolerance:
            return False
    if (a.feedrate is None) != (b.feedrate is None):
        return False
    if a.feedrate is not None and abs(a.feedrate - b.feedrate) > tolerance:
        return False
    return (a.relative_xyz, a.relative_e, a.e_mode, a.inches, a.tool, a.fw_retracted) == (
        b.relative_xyz, b.relative_e, b.e_mode, b.inches, b.tool, b.fw_retracted)
