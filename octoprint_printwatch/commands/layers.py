"""``printwatch layers FILE.gcode``: print the layer table the analysis finds."""
from __future__ import annotations

import argparse
import json



def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "layers",
        help="print the layer table of a G-code file",
        description="Read a G-code file once and print its layers: index, top z, layer height, "
                    "first and last line, and whether the layer extrudes. Works on any slicer's "
                    "output, with or without layer comments.",
    )
    parser.add_argument("file", metavar="FILE.gcode", help="G-code file to analyse")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")
    return parser


def run(args) -> int:
    from ..core.gcode import analyse

    info = analyse(args.file)
    if args.json:
        print(json.dumps(_as_json(info), indent=1))
        return 0
    print(f"# {args.file}: {len(info.layers)} layers, slicer {info.slicer or 'unknown'}, "
          f"filament {info.filament_diameter:g} mm ({info.filament_diameter_source}), "
          f"E {info.extrusion_mode}, positioning {info.positioning}, units {info.units}"
          + (", firmware retraction" if info.firmware_retraction else "")
          + (", spiral vase" if info.spiral_vase else "")
          + (f", tools {','.join(map(str, info.tools))}" if len(info.tools) > 1 else ""))
    for warning in info.warnings:
        print(f"# warning: {warning}")
    print(f"{'layer':>5} {'z':>9} {'height':>7} {'first':>9} {'last':>9} extrudes")
    for layer in info.layers:
        print(f"{layer.index:>5} {layer.z:>9.3f} {layer.height:>7.3f} {layer.first_line:>9} "
              f"{layer.last_line:>9} {'yes' if layer.extrudes else 'no'}")
    return 0


def _as_json(info) -> dict:
    return {
        "layers": [{"index": l.index, "z": round(l.z, 6), "height": round(l.height, 6),
                    "first_line": l.first_line, "last_line": l.last_line, "extrudes": l.extrudes}
                   for l in info.layers],
        "slicer": info.slicer,
        "filament_diameter": info.filament_diameter,
        "filament_diameter_source": info.filament_diameter_source,
        "nominal_layer_height": info.nominal_layer_height,
        "extrusion_mode": info.extrusion_mode,
        "positioning": info.positioning,
        "units": info.units,
        "firmware_retraction": info.firmware_retraction,
        "spiral_vase": info.spiral_vase,
        "tools": info.tools,
        "total_lines": info.total_lines,
        "warnings": info.warnings,
    }
