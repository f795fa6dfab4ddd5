"""``printwatch calibrate intrinsics|bed|pair|check|quick``: camera calibration from board photos."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from ..core.boards import Board
from ..core.camera import Camera, CameraError
from ..core.calibration import (BoardPlacement, calibrate_bed_pose, calibrate_intrinsics, calibrate_pair,
                                check_pose_against_first_layer, estimate_focal_from_image, first_layer_mask,
                                first_layer_paths, focal_px_from_fov, load_image, load_images, quick_camera,
                                refine_pose_from_shift)
from ..core.errors import CalibrationError
from .board import parse_pair

IMAGE_SUFFIXES = (".jpg", ".jpeg", ".png", ".bmp")


def add_parser(subparsers):
    parser = subparsers.add_parser(
        "calibrate", help="calibrate cameras from photos of a printed board",
        description="Calibrate cameras from photos of a board made with 'printwatch board'.")
    sub = parser.add_subparsers(dest="step", metavar="STEP")
    sub.required = True

    p = sub.add_parser("intrinsics", help="lens (K, distortion) from 10-15 views of the board",
                       description="Lens calibration. Exit status 0 when the result is good, 1 when a retake is "
                                   "advised (the file is written either way).")
    p.add_argument("images", nargs="+", help="image files or folders of images")
    _board_arg(p)
    p.add_argument("-o", "--out", required=True, help="camera JSON to write")
    p.add_argument("--name", help="camera name (default: the output file's stem)")

    p = sub.add_parser("bed", help="camera pose in printer coordinates from the board lying on the bed")
    p.add_argument("images", nargs="+", help="one frame (or several of the same, unmoved board)")
    _board_arg(p)
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--intrinsics", help="camera JSON from 'calibrate intrinsics'")
    source.add_argument("--focal-px", type=float, help="quick estimate: focal length in pixels")
    source.add_argument("--hfov", type=float, help="quick estimate: horizontal field of view in degrees")
    p.add_argument("--at", default="front-left",
                   help="where the board lies: front-left (page in the bed's front-left corner), centre, or "
                        "X,Y[,ANGLE] of the grid's front-left corner in mm (default front-left)")
    p.add_argument("--bed", metavar="W,D", help="bed size in mm (for --at centre)")
    p.add_argument("--board-z", type=float, default=0.0, help="height of the board's top surface, mm")
    p.add_argument("--tilt", type=float, default=0.0,
                   help="board stood up about its front edge by this many degrees (90 = upright, for low cameras)")
    p.add_argument("-o", "--out", required=True, help="camera JSON to write (may be the intrinsics file)")
    p.add_argument("--name", help="camera name (default: from the intrinsics file or the output file)")

    p = sub.add_parser("pair", help="relative pose of two cameras from simultaneous board views")
    p.add_argument("--left", nargs="+", required=True, help="left camera's images (or a folder)")
    p.add_argument("--right", nargs="+", required=True, help="right camera's images, same order")
    _board_arg(p)
    p.add_argument("--left-camera", help="left camera JSON (intrinsics, optionally bed pose)")
    p.add_argument("--right-camera", help="right camera JSON (intrinsics, optionally bed pose)")
    p.add_argument("-o", "--out", required=True, help="pair JSON to write (R, T, errors, consistency)")
    p.add_argument("--out-right", help="also write the right camera JSON, posed from the left camera's bed pose")

    p = sub.add_parser("check", help="has the camera moved? compare a frame of the printed first layer with "
                                     "where the calibration puts it",
                       description="Exit status 0 when the first layer is where expected (or cannot be seen), "
                                   "1 when the camera seems to have moved.")
    p.add_argument("frame", help="frame taken after the first layer (or skirt) was printed")
    p.add_argument("--camera", required=True, help="camera JSON")
    p.add_argument("--background", required=True, help="frame of the empty bed from the same camera")
    p.add_argument("--gcode", required=True, help="the print's G-code (its first layer is what is looked for)")
    p.add_argument("--tolerance-px", type=float, default=3.0)
    p.add_argument("--refine-out", help="if moved: write the camera turned to follow the shift (at most 2 deg)")

    p = sub.add_parser("quick", help="rough intrinsics without a calibration (seed Eq. 5.3, or field of view)")
    p.add_argument("image", nargs="?", help="the board held square to the camera at --distance-mm")
    p.add_argument("--board", help="board JSON or spec (with IMAGE)")
    p.add_argument("--distance-mm", type=float, help="distance from the lens to the board (with IMAGE)")
    p.add_argument("--hfov", type=float, help="horizontal field of view in degrees (instead of IMAGE)")
    p.add_argument("--size", metavar="WxH", help="frame size (with --hfov), e.g. 640x480")
    p.add_argument("-o", "--out", required=True)
    p.add_argument("--name")
    return parser


def _board_arg(parser):
    parser.add_argument("--board", required=True,
                        help="board JSON from 'printwatch board', or KIND:COLSxROWS:SQUARE_MM[:MARKER_MM] "
                             "(squares, not inner corners), e.g. chessboard:10x7:25")


def expand_images(items: list[str]) -> list[Path]:
    """Files as given; folders expanded to their images in name order."""
    paths: list[Path] = []
    for item in items:
        path = Path(item)
        if path.is_dir():
            found = sorted(p for p in path.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES)
            if not found:
                raise CalibrationError(f"{path}: folder holds no JPEG or PNG images")
            paths.extend(found)
        else:
            paths.append(path)
    return paths


def _load_camera(path: str, name: str | None = None) -> tuple[Camera, dict]:
    try:
        camera = Camera.load(path, name)
    except CameraError as exc:
        raise CalibrationError(str(exc)) from None
    doc = json.loads(Path(path).read_text())
    extras = {k: v for k, v in doc.items() if k not in ("format", "name", "width", "height", "K", "dist",
                                                        "rvec", "tvec")}
    return camera, extras


def _write_json(path: str | Path, doc: dict) -> None:
    try:
        Path(path).write_text(json.dumps(doc, indent=2))
    except OSError as exc:
        raise CalibrationError(f"{path}: cannot write ({exc.strerror})") from None


def _save_camera(camera: Camera, path: str | Path, **extra) -> None:
    try:
        camera.save(path, **extra)
    except OSError as exc:
        raise CalibrationError(f"{path}: cannot write ({exc.strerror})") from None


def run(args: argparse.Namespace) -> int:
    return {"intrinsics": _intrinsics, "bed": _bed, "pair": _pair, "check": _check,
            "quick": _quick}[args.step](args)


def _intrinsics(args) -> int:
    board = Board.parse(args.board)
    paths = expand_images(args.images)
    images = load_images(paths)
    name = args.name or Path(args.out).stem
    result = calibrate_intrinsics(images, board, labels=[p.name for p in paths], name=name)
    _save_camera(result.camera, args.out, board=board.to_dict(), **result.summary())
    K = result.camera.K
    print(f"{name}: {len(result.views_used)} views used, RMS reprojection error {result.rms_px:.3f} px, "
          f"focal {K[0, 0]:.1f} px (+-{result.focal_uncertainty:.2%}), principal point ({K[0, 2]:.1f}, {K[1, 2]:.1f}), "
          f"board covered {result.coverage:.0%} of the frame")
    for label, why in result.views_skipped.items():
        print(f"  skipped {label}: {why}")
    print(f"verdict: {result.verdict.upper()}")
    for reason in result.reasons:
        print(f"  - {reason}")
    print(f"wrote {args.out}")
    return 0 if result.verdict == "good" else 1


def _bed(args) -> int:
    board = Board.parse(args.board)
    paths = expand_images(args.images)
    images = load_images(paths)
    height, width = images[0].shape[:2]
    extras: dict = {}
    if args.intrinsics:
        camera, extras = _load_camera(args.intrinsics, args.name)
    else:
        focal = args.focal_px if args.focal_px else focal_px_from_fov(width, args.hfov)
        camera = quick_camera(width, height, focal, args.name or Path(args.out).stem)
        extras["intrinsics"] = "quick estimate"
    if args.name:
        camera.name = args.name
    bed = parse_pair(args.bed, "--bed") if args.bed else None
    placement = BoardPlacement.parse(args.at, board, bed, z_mm=args.board_z, tilt_deg=args.tilt)
    result = calibrate_bed_pose(images, camera, board, placement, labels=[str(p) for p in paths])
    extras.update(result.summary())
    extras["bed_board"] = board.to_dict()
    extras["placement"] = {"x_mm": placement.x_mm, "y_mm": placement.y_mm, "angle_deg": placement.angle_deg,
                           "z_mm": placement.z_mm, "tilt_deg": placement.tilt_deg}
    _save_camera(result.camera, args.out, **extras)
    c = result.center_mm
    print(f"{result.camera.name}: camera at X {c[0]:.1f}, Y {c[1]:.1f}, Z {c[2]:.1f} mm "
          f"(+-{result.position_sigma_mm:.2f} mm), {result.corners_used} corners, "
          f"RMS {result.reprojection_px:.3f} px")
    for warning in result.warnings:
        print(f"  warning: {warning}")
    print(f"wrote {args.out}")
    return 0


def _pair(args) -> int:
    board = Board.parse(args.board)
    left_paths, right_paths = expand_images(args.left), expand_images(args.right)
    left_cam = _load_camera(args.left_camera)[0] if args.left_camera else None
    right_cam = _load_camera(args.right_camera)[0] if args.right_camera else None
    result = calibrate_pair(load_images(left_paths), load_images(right_paths), board,
                            left_camera=left_cam, right_camera=right_cam,
                            left_labels=[p.name for p in left_paths], right_labels=[p.name for p in right_paths],
                            names=(left_cam.name if left_cam else "left", right_cam.name if right_cam else "right"))
    doc = result.summary()
    doc["left_camera"] = result.left.to_dict()
    doc["right_camera"] = result.right.to_dict()
    _write_json(args.out, doc)
    print(f"{result.left.name}/{result.right.name}: {len(result.views_used)} pairs used, stereo RMS "
          f"{result.rms_px:.3f} px, baseline {result.baseline_mm:.2f} (+-{result.baseline_spread_mm:.2f} across "
          f"views), epipolar error {result.epipolar_rms_px:.3f} px")
    if result.consistency is not None:
        print(("  " if result.consistency.ok else "  warning: ") + result.consistency.message)
    if args.out_right:
        _save_camera(result.right, args.out_right, pair_rms_px=round(result.rms_px, 4))
        print(f"wrote {args.out_right}")
    print(f"wrote {args.out}")
    return 0 if result.consistency is None or result.consistency.ok else 1


def _check(args) -> int:
    camera, extras = _load_camera(args.camera)
    frame, background = load_image(args.frame), load_image(args.background)
    paths, width, z = first_layer_paths(args.gcode)
    if (frame.shape[1], frame.shape[0]) != camera.size:
        camera = camera.scaled(frame.shape[1], frame.shape[0])
    expected = first_layer_mask(camera, paths, width, z)
    check = check_pose_against_first_layer(camera, frame, background, expected, tolerance_px=args.tolerance_px)
    print(check.message)
    if check.status == "moved" and args.refine_out:
        centre = np.concatenate(paths)[:, :3].mean(axis=0)
        refined, note = refine_pose_from_shift(camera, check.shift_px, at_px=camera.project(centre[None])[0])
        _save_camera(refined, args.refine_out, **{**extras, "refined": note})
        print(f"{note}; wrote {args.refine_out}")
    return 1 if check.status == "moved" else 0


def _quick(args) -> int:
    if args.image:
        if not (args.board and args.distance_mm):
            raise CalibrationError("quick estimate from an image needs --board and --distance-mm")
        board = Board.parse(args.board)
        estimate = estimate_focal_from_image(load_image(args.image), board, args.distance_mm,
                                             name=args.name or Path(args.out).stem, label=args.image)
        camera = estimate.camera
        how = f"Eq. 5.3: squares {estimate.square_px:.1f} px at {args.distance_mm:g} mm"
    elif args.hfov and args.size:
        width, height = (int(v) for v in parse_pair(args.size, "--size"))
        camera = quick_camera(width, height, focal_px_from_fov(width, args.hfov), args.name or Path(args.out).stem)
        how = f"horizontal field of view {args.hfov:g} deg"
    else:
        raise CalibrationError("quick estimate needs IMAGE with --board and --distance-mm, or --hfov with --size")
    _save_camera(camera, args.out, intrinsics="quick estimate", method=how)
    print(f"{camera.name}: focal length {camera.K[0, 0]:.1f} px ({how}); no distortion model. "
          f"wrote {args.out}")
    return 0
