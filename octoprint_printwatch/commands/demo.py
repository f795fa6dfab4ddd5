"""``printwatch demo``: a real OctoPrint with PrintWatch, the virtual printer and simulated webcams."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "demo",
        help="watch PrintWatch catch a failing print on a real OctoPrint with simulated webcams",
        description="Start OctoPrint with PrintWatch, its virtual printer and simulated webcams (three stations "
                    "of stereo pairs), upload a library part (PrintWatch injects the checks), print it ten "
                    "times faster with a failure injected part-way, and watch the checks in the PrintWatch "
                    "tab until the print is paused. --headless runs it to the end without a browser, prints a "
                    "summary and exits 1 if the failure was missed (or a normal print was paused).",
    )
    from ..simulator.parts import LIBRARY_PARTS

    p.add_argument("--part", default="twisted_vase", metavar="NAME",
                   help=f"library part: {', '.join(sorted(LIBRARY_PARTS))} (default: twisted_vase)")
    p.add_argument("--failure", default="runout", metavar="KIND",
                   help="runout, detach, spaghetti, layer_shift, under_extrusion, or none for a normal print "
                        "(default: runout)")
    p.add_argument("--onset-layer", type=int, default=None, metavar="N",
                   help="1-based layer where the failure starts (default: part-way, just after a check)")
    p.add_argument("--cameras", type=int, default=6, metavar="N",
                   help="simulated cameras, 1 to 6: the first N of three stations of stereo pairs (default 6)")
    p.add_argument("--every", type=int, default=None, metavar="N",
                   help="check every N layers (default: about eight checks over the part)")
    p.add_argument("--headless", action="store_true",
                   help="no visitor: run to the end, print a summary, stop everything; exit 1 on a wrong outcome")
    p.add_argument("--port", type=int, default=None, metavar="P",
                   help="OctoPrint's port on 127.0.0.1 (default: 5000, or a free one when 5000 is taken)")
    p.add_argument("--basedir", default=None, metavar="DIR",
                   help="keep OctoPrint's files (config, logs, PrintWatch history) in this new or empty folder "
                        "(default: a temporary folder, removed at the end)")
    p.add_argument("--seed", type=int, default=7, help="camera placement, calibration error and look (default 7)")
    return p


def run(args) -> int:
    from ..demo.run import DemoOptions, run_demo

    options = DemoOptions(part=args.part, failure=args.failure, onset_layer=args.onset_layer, cameras=args.cameras,
                          every_layers=args.every, headless=args.headless, port=args.port,
                          basedir=Path(args.basedir) if args.basedir else None, seed=args.seed)

    def say(text: str) -> None:
        print(text, flush=True)

    wait = None
    if not args.headless and sys.stdin.isatty():
        def wait() -> None:
            input("Open the URL above, then press Enter to start the print ... ")

    result = run_demo(options, say=say, wait_for_visitor=wait)
    return 0 if result.ok else 1
