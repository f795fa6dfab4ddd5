"""``printwatch inject FILE.gcode -o OUT.gcode``: add check blocks (or remove them with --strip)."""
from __future__ import annotations

import argparse

def _pair(text: str, what: str) -> tuple:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--{what} must be two numbers like 10,10, got {text!r}") from None
    if len(values) != 2:
        raise argparse.ArgumentTypeError(f"--{what} must be two numbers like 10,10, got {text!r}")
    return values


def _heights(text: str) -> list:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--heights must be numbers in mm like 2,5.5,10, got {text!r}") from None
    if not values:
        raise argparse.ArgumentTypeError("--heights needs at least one height")
    return values


def add_parser(subparsers) -> argparse.ArgumentParser:
    from ..core import inject

    parser = subparsers.add_parser(
        "inject",
        help="insert camera-check blocks between layers",
        description="Copy a G-code file, inserting after every Nth layer (and the final layer) a block that "
                    "retracts, lifts, parks the head, emits '@PRINTWATCH_CHECK layer=<n> z=<z>' for the "
                    "OctoPrint plugin, and returns exactly to where it was. The output is written to a "
                    "temporary file and renamed; on error no output file is left.",
    )
    parser.add_argument("file", metavar="FILE.gcode", help="G-code file to read")
    parser.add_argument("-o", "--output", required=True, metavar="OUT.gcode", help="file to write")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--every", type=int, metavar="N",
                       help=f"check after every Nth layer (default {inject.DEFAULT_EVERY})")
    group.add_argument("--heights", type=_heights, metavar="Z1,Z2,...",
                       help="check after the first layer reaching each height (mm)")
    group.add_argument("--strip", action="store_true",
                       help="remove PrintWatch blocks instead, restoring the original byte for byte")
    parser.add_argument("--lift", type=float, default=inject.DEFAULT_LIFT, metavar="MM",
                        help=f"lift above the highest printed point while parked (default {inject.DEFAULT_LIFT:g})")
    parser.add_argument("--park", type=lambda t: _pair(t, "park"), metavar="X,Y",
                        help=f"park position (default: front-left corner, {inject.PARK_MARGIN:g} mm in)")
    parser.add_argument("--max-z", type=float, metavar="MM",
                        help="printer's maximum Z (default: slicer comment, else the highest Z the file reaches)")
    parser.add_argument("--bed", type=lambda t: _pair(t, "bed"), metavar="W,D",
                        help="bed width and depth in mm (default: slicer comment, else the file's XY range)")
    parser.add_argument("--background", action="store_true",
                        help="also park before the first layer for a background frame (@PRINTWATCH_BACKGROUND)")
    return parser


def run(args) -> int:
    from ..core.inject import inject_checks, strip_file

    if args.strip:
        written = strip_file(args.file, args.output)
        print(f"{args.output}: PrintWatch blocks removed ({written} bytes)")
        return 0
    result = inject_checks(args.file, args.output, every=args.every, heights=args.heights, lift=args.lift,
                           park=args.park, max_z=args.max_z, bed=args.bed, background=args.background)
    for warning in result.warnings:
        print(f"warning: {warning}")
    layers = ", ".join(str(check.layer) for check in result.checks)
    print(f"{args.output}: {len(result.checks)} checks after layers {layers} of {result.layers}; "
          f"park {result.park[0]:g},{result.park[1]:g}, max Z {result.max_z:g} mm"
          + (f"; background frame at line {result.background_line}" if result.background_line else ""))
    print(f"{result.bytes_in / 1e6:.2f} MB in, {result.bytes_out / 1e6:.2f} MB out, "
          f"{result.seconds:.2f} s ({result.megabytes_per_second:.1f} MB/s)")
    return 0
