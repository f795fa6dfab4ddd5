"""``printwatch evaluate SESSION_DIR``: replay a recording through the plugin's check path."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from ..core.errors import PrintWatchError
from ..core.settings import DetectionSettings, parse_camera_threshold


def add_parser(subparsers) -> argparse.ArgumentParser:
    parser = subparsers.add_parser(
        "evaluate",
        help="replay a recording with the current (or given) settings and print the verdicts as JSON",
        description="Replays one recording (docs/recording-format.md) through exactly the code path the "
                    "plugin runs at each check and writes the evaluate JSON document.",
    )
    parser.add_argument("session", metavar="SESSION_DIR", help="recording folder (holds session.json)")
    parser.add_argument("--json", metavar="OUT", help="write the JSON here instead of standard output")
    parser.add_argument("--settings", metavar="FILE", help="detection settings JSON (DetectionSettings keys)")
    parser.add_argument("--shape-threshold", type=float, metavar="PCT",
                        help="shape error threshold in percent for every camera (default 7)")
    parser.add_argument("--camera-threshold", action="append", default=[], metavar="CAM=PCT",
                        help="shape threshold for one camera (repeatable)")
    parser.add_argument("--band-threshold", type=float, metavar="PCT",
                        help="threshold for the newest layer band error in percent (default 50)")
    parser.add_argument("--size-threshold", type=float, metavar="PCT",
                        help="stereo size error threshold in percent (default 10)")
    parser.add_argument("--min-failing-cameras", type=int, metavar="N",
                        help="pause only when at least N cameras fail at the same check (default 1)")
    parser.add_argument("--overlays", metavar="DIR", help="also write one overlay picture per camera per check")
    parser.add_argument("--cache", metavar="DIR", help="cache rendered expected views here")
    return parser


def load_settings(args) -> DetectionSettings:
    base = DetectionSettings()
    if args.settings:
        path = Path(args.settings)
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise PrintWatchError(f"{path}: no such settings file") from None
        except (OSError, ValueError) as exc:
            raise PrintWatchError(f"{path}: not a readable JSON settings file ({exc})") from None
        base = DetectionSettings.from_dict(data)
    cameras = dict(base.camera_thresholds)
    cameras.update(dict(parse_camera_threshold(text) for text in args.camera_threshold))
    return base.with_overrides(shape_threshold_pct=args.shape_threshold, band_threshold_pct=args.band_threshold,
                               size_threshold_pct=args.size_threshold,
                               min_failing_cameras=args.min_failing_cameras, camera_thresholds=cameras)


def run(args) -> int:
    from ..core.pipeline import evaluate_recording
    from ..core.recording import load_recording

    settings = load_settings(args)
    recording = load_recording(args.session)
    unknown = sorted(set(settings.camera_thresholds) - set(recording.cameras))
    if unknown:
        raise PrintWatchError(f"--camera-threshold names camera(s) not in {args.session}: {', '.join(unknown)}")
    doc = evaluate_recording(recording, settings, session_label=args.session, cache_dir=args.cache,
                             overlay_dir=args.overlays)
    text = json.dumps(doc, indent=2)
    if args.json:
        out = Path(args.json)
        try:
            out.parent.mkdir(parents=True, exist_ok=True)
            tmp = out.with_name(out.name + ".tmp")
            tmp.write_text(text + "\n", encoding="utf-8")
            tmp.replace(out)
        except OSError as exc:
            raise PrintWatchError(f"{out}: cannot write ({exc.strerror})") from None
    else:
        sys.stdout.write(text + "\n")
    return 0
