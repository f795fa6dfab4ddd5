"""``printwatch render OUT_DIR``: write the expected views of a part for some cameras as PNG files."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..core.errors import PrintWatchError


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "render",
        help="write the expected silhouettes, depth maps and layer bands as PNGs",
        description="Build the expected part from a mesh or a G-code file (or the model/G-code of a recording) "
                    "and write, for every camera and check height, what the camera should see: "
                    "silhouette (distorted and undistorted), depth map and newest layer band.",
    )
    p.add_argument("out_dir", metavar="OUT_DIR", help="folder for the PNG files (created)")
    p.add_argument("--gcode", metavar="FILE.gcode", help="G-code file: the part is rebuilt from its extrusion moves")
    p.add_argument("--model", metavar="MESH", help="mesh (STL/OBJ/PLY/3MF) in printer coordinates")
    p.add_argument("--place", action="store_true",
                   help="with --model and --gcode: move the mesh where the slicer put it (else the mesh is used as is)")
    p.add_argument("--session", metavar="DIR",
                   help="recording folder: its cameras, model/G-code and check heights (options given here win)")
    p.add_argument("--camera", action="append", default=[], metavar="CAM.json",
                   help="camera file (printwatch-camera/1, e.g. from printwatch calibrate); repeatable")
    p.add_argument("--z", action="append", type=float, default=[], metavar="MM",
                   help="check height in mm; repeatable (default: the recording's checks, else 5 heights)")
    p.add_argument("--every", type=float, metavar="MM", help="a check height every MM millimetres up to the top")
    return p


def _heights(args, part, session) -> list[float]:
    if args.z:
        heights = list(args.z)
    elif args.every:
        if args.every <= 0:
            raise PrintWatchError(f"--every must be positive, got {args.every:g}")
        count = int(part.height() // args.every)
        heights = [args.every * (k + 1) for k in range(count)] or [part.height()]
    elif session is not None and session.checks:
        heights = [check.z for check in session.checks]
    else:
        heights = [part.height() * k / 5.0 for k in range(1, 6)]
    bad = [z for z in heights if not z > 0]
    if bad:
        raise PrintWatchError(f"check heights must be above the bed (z > 0), got {bad[0]:g}")
    return heights


def run(args) -> int:
    import cv2
    import numpy as np

    from ..core.camera import Camera, CameraError
    from ..core.geometry import part_for_job
    from ..core.render import render_expected_views

    session = None
    if args.session:
        from ..core.recording import load_recording

        session = load_recording(args.session)
    model = args.model or (session.model if session is not None and not args.gcode else None)
    gcode = args.gcode or (session.gcode if session is not None else None)
    if model is None and gcode is None:
        raise PrintWatchError("give --model, --gcode or --session: the part to render is unknown")
    cameras = []
    try:
        for path in args.camera:
            cameras.append(Camera.load(path))
    except CameraError as exc:
        raise PrintWatchError(str(exc)) from None
    if not cameras and session is not None:
        cameras = list(session.cameras.values())
    if not cameras:
        raise PrintWatchError("give at least one --camera CAM.json (or a --session with cameras)")
    names = [camera.name for camera in cameras]
    if len(set(names)) != len(names):
        raise PrintWatchError(f"two cameras share a name ({', '.join(names)}): rename one in its file")

    part = part_for_job(model, gcode, place=bool(args.place and model and gcode))
    heights = _heights(args, part, session)
    out = Path(args.out_dir)
    if out.exists() and not out.is_dir():
        raise PrintWatchError(f"{out}: exists and is not a folder")
    out.mkdir(parents=True, exist_ok=True)
    if (session is not None and session.checks and not args.z and not args.every
            and getattr(part, "sequential", False)):
        # Objects printed one after another: each check's state is "after its layer", not "below z".
        from ..core.render import render_expected_views_by_layer

        by_layer = render_expected_views_by_layer(part, cameras, [(c.layer, c.z) for c in session.checks])
        views = {(camera, view.z): view for (camera, _), view in by_layer.items()}
        print("note: sequential printing: views follow the print order (state after each check's layer)")
    else:
        views = render_expected_views(part, cameras, heights)
    summary = {"part": {"source": part.source, "height_mm": part.height(), "notes": part.notes}, "views": []}
    for note in part.notes:
        print(f"note: {note}")
    for (camera, z), view in sorted(views.items()):
        stem = f"{camera}_z{z:07.3f}"
        cv2.imwrite(str(out / f"{stem}_silhouette.png"), view.silhouette.astype(np.uint8) * 255)
        cv2.imwrite(str(out / f"{stem}_silhouette_undistorted.png"), view.silhouette_undistorted.astype(np.uint8) * 255)
        cv2.imwrite(str(out / f"{stem}_band.png"), view.new_band.astype(np.uint8) * 255)
        cv2.imwrite(str(out / f"{stem}_depth.png"), _depth_image(view.depth))
        summary["views"].append({
            "camera": camera, "z": z, "previous_z": view.z_previous, "files": stem + "_*.png",
            "silhouette_px": int(view.silhouette.sum()), "band_px": int(view.new_band.sum()),
            "depth_mm": ([round(float(np.min(view.depth[np.isfinite(view.depth)])), 2),
                          round(float(np.max(view.depth[np.isfinite(view.depth)])), 2)]
                         if np.isfinite(view.depth).any() else None),
        })
        print(f"{camera} z={z:.3f} mm: silhouette {int(view.silhouette.sum())} px, "
              f"new band {int(view.new_band.sum())} px -> {out / stem}_*.png")
    (out / "views.json").write_text(json.dumps(summary, indent=1))
    return 0


def _depth_image(depth):
    """Depth as 8-bit grey: near is bright, far dark, empty black (scaled to this view's range)."""
    import numpy as np

    finite = np.isfinite(depth)
    image = np.zeros(depth.shape, np.uint8)
    if finite.any():
        near, far = float(depth[finite].min()), float(depth[finite].max())
        scale = 200.0 / max(far - near, 1e-6)
        image[finite] = (255.0 - (depth[finite] - near) * scale).astype(np.uint8)
    return image
