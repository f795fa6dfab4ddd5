"""``printwatch simulate OUT_DIR``: render a simulated print (normal or failing) as a recording + truth.json."""
from __future__ import annotations

import argparse
from pathlib import Path

from ..core.errors import PrintWatchError


def add_parser(subparsers) -> argparse.ArgumentParser:
    from ..simulator.look import PRESETS
    from ..simulator.parts import LIBRARY_PARTS
    from ..simulator.rig import RIG_KINDS
    from ..simulator.scenario import SCENARIOS

    p = subparsers.add_parser(
        "simulate",
        help="render a simulated print as a recording (with truth.json)",
        description="Render webcam frames of a simulated print, normal or failing, into a recording folder "
                    "(docs/recording-format.md) with the ground truth in truth.json beside session.json.",
    )
    p.add_argument("out_dir", metavar="OUT_DIR", help="recording folder to write (created)")
    p.add_argument("--part", default="gear",
                   help=f"library part ({', '.join(LIBRARY_PARTS)}) or a mesh/G-code file (default: gear)")
    p.add_argument("--scenario", default="normal", choices=SCENARIOS, help="what happens to the print")
    p.add_argument("--onset-layer", type=int, default=None, help="1-based layer where the failure starts")
    p.add_argument("--rig", default="stations3", choices=RIG_KINDS, help="camera layout (default: stations3)")
    p.add_argument("--cameras", type=int, default=None, help="number of cameras for --rig ring (1..6)")
    p.add_argument("--look", default=None,
                   help=f"appearance preset ({', '.join(PRESETS)}) or 'random' (default: random from the seed)")
    p.add_argument("--seed", type=int, default=0, help="random seed: same seed, same recording")
    p.add_argument("--every", type=int, default=None, metavar="N", help="check every N layers (default: seed-like)")
    p.add_argument("--layer-height", type=float, default=0.2, help="layer height in mm (default 0.2)")
    p.add_argument("--size", default="640x480", help="frame size WxH (default 640x480)")
    p.add_argument("--png", action="store_true", help="write PNG frames instead of JPEG")
    p.add_argument("--clean", action="store_true", help="no nuisances: ideal camera, no shadows or skirt")
    return p


def run(args) -> int:
    from ..simulator.look import PRESETS, random_look
    from ..simulator.recording import write_recording
    from ..simulator.rig import make_rig
    from ..simulator.scenario import Scenario
    from ..simulator.scene import PrintSimulator

    try:
        width, height = (int(v) for v in str(args.size).lower().split("x"))
    except ValueError:
        raise PrintWatchError(f"--size must look like 640x480, got {args.size!r}") from None
    if width < 64 or height < 48:
        raise PrintWatchError(f"--size {args.size} is too small (at least 64x48)")
    out = Path(args.out_dir)
    if out.exists() and not out.is_dir():
        raise PrintWatchError(f"{out}: exists and is not a folder")
    if out.is_dir() and (out / "session.json").exists():
        raise PrintWatchError(f"{out}: already holds a recording; choose a new folder")
    rig = make_rig(args.rig, n_cameras=args.cameras, seed=args.seed, width=width, height=height)
    if args.look in (None, "random"):
        look = random_look(args.seed, rig.bed)
    elif args.look in PRESETS:
        look = PRESETS[args.look]
    else:
        raise PrintWatchError(f"unknown --look {args.look!r}; choose from random, {', '.join(PRESETS)}")
    if args.clean:
        look = look.plain()
    if args.every is not None and args.every < 1:
        raise PrintWatchError(f"--every must be 1 or more layers, got {args.every}")
    if args.onset_layer is not None and args.scenario == "normal":
        raise PrintWatchError("--onset-layer needs a failing --scenario (runout, detach, ...)")
    scenario = Scenario(args.scenario, onset_layer=args.onset_layer)
    sim = PrintSimulator(args.part, rig, look, scenario, seed=args.seed, layer_height=args.layer_height)
    session = write_recording(out, sim, every_n_layers=args.every, image_format="png" if args.png else "jpg")
    truth = sim.scenario
    onset = f", failure at layer {truth.onset_layer}" if truth.onset_layer else ""
    n = len(rig.names)
    print(f"wrote {session} ({sim.part_name}, {args.scenario}{onset}, {n} camera{'s' if n != 1 else ''})")
    return 0
