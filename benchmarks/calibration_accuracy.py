"""Accuracy of calibration: intrinsics and stereo on OpenCV's real pairs; bed pose, intrinsics and
the first-layer self-check on simulator frames with known truth.

Run: .venv/bin/python benchmarks/calibration_accuracy.py  (about a minute). Prints tables quoted in
docs/calibration.md. Scenes are random (fixed seed): camera distance 250-420 mm, azimuth +-70 deg,
elevation 20-50 deg, 640x480 to 1280x720, lens distortion, blur, noise, JPEG 50-95, uneven light.
"""
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from octoprint_printwatch.core.boards import Board, board_for_bed
from octoprint_printwatch.core.calibration import (BoardPlacement, calibrate_bed_pose, calibrate_intrinsics,
                                                   calibrate_pair, load_images)
from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.errors import CalibrationError
from octoprint_printwatch.simulator.board_scene import (Nuisances, random_held_poses, render_board_held,
                                                        render_board_on_bed)

PAIRS = Path(__file__).resolve().parents[1] / "tests" / "data" / "stereo" / "opencv_chessboard_pairs"


def bed_pose_table(kind: str, scenes: int = 12) -> None:
    board = board_for_bed((220, 220), kind=kind)
    rng = np.random.default_rng(5)
    pos, rot, sig, missed, times = [], [], [], 0, []
    for k in range(scenes):
        az, dist, elev = rng.uniform(-70, 70), rng.uniform(250, 420), rng.uniform(20, 50)
        target = np.array([110, 110, 0]) + rng.normal(0, 15, 3) * [1, 1, 0]
        eye = target + dist * np.array([np.sin(np.radians(az)) * np.cos(np.radians(elev)),
                                        -np.cos(np.radians(az)) * np.cos(np.radians(elev)), np.sin(np.radians(elev))])
        size = [(640, 480), (1280, 720), (800, 600)][k % 3]
        cam = Camera.look_at("c", eye, target, width=size[0], height=size[1], hfov_deg=rng.uniform(55, 75),
                             dist=[rng.uniform(-0.25, 0), rng.uniform(0, 0.1), 0, 0, 0], roll_deg=rng.uniform(-5, 5))
        placement = BoardPlacement.centred(board, (220, 220), angle_deg=rng.uniform(-20, 20))
        nuisances = Nuisances(seed=k, blur_sigma_px=rng.uniform(0.5, 1.5), noise_sigma=rng.uniform(1, 5),
                              jpeg_quality=int(rng.uniform(50, 95)), exposure=rng.uniform(0.6, 1.2),
                              light_gradient=rng.uniform(0, 0.6))
        frame = render_board_on_bed(cam, board, placement, nuisances=nuisances)
        start = time.perf_counter()
        try:
            result = calibrate_bed_pose(frame, cam, board, placement)
        except CalibrationError:
            missed += 1
            continue
        times.append(time.perf_counter() - start)
        pos.append(np.linalg.norm(result.center_mm - cam.center))
        rot.append(np.degrees(np.linalg.norm(cv2.Rodrigues(result.camera.R @ cam.R.T)[0])))
        sig.append(result.position_sigma_mm)
    print(f"| {board.describe()} | {len(pos)}/{scenes} | {np.median(pos):.2f} / {max(pos):.2f} | "
          f"{np.median(rot):.3f} / {max(rot):.3f} | {np.median(sig):.2f} | {1000 * np.median(times):.0f} ms |")


def opencv_pairs_table() -> None:
    board = Board("chessboard", 10, 7, 1.0)
    left = sorted(PAIRS.glob("left*.jpg"))
    right = [PAIRS / p.name.replace("left", "right") for p in left]
    start = time.perf_counter()
    il = calibrate_intrinsics(load_images(left), board)
    ir = calibrate_intrinsics(load_images(right), board)
    pair = calibrate_pair(load_images(left), load_images(right), board, left_camera=il.camera, right_camera=ir.camera)
    took = time.perf_counter() - start
    print("| left RMS | right RMS | stereo RMS | epipolar RMS | baseline (squares) | per-view spread | time |")
    print("|---|---|---|---|---|---|---|")
    print(f"| {il.rms_px:.3f} px | {ir.rms_px:.3f} px | {pair.rms_px:.3f} px | {pair.epipolar_rms_px:.3f} px | "
          f"{pair.baseline_mm:.3f} | {pair.baseline_spread_mm:.3f} ({pair.baseline_spread_mm / pair.baseline_mm:.1%}) "
          f"| {took:.1f} s |")


def intrinsics_table(cameras: int = 3, views: int = 12) -> None:
    rng = np.random.default_rng(11)
    print("| board | camera | views | RMS px | focal error | principal point error px | corner distortion error px | verdict |")
    print("|---|---|---|---|---|---|---|---|")
    for kind in ("charuco", "chessboard"):
        board = board_for_bed((220, 220), kind=kind)
        for k in range(cameras):
            size = [(640, 480), (1280, 720), (800, 600)][k % 3]
            cam = Camera.look_at("c", (0, -300, 200), (0, 0, 0), width=size[0], height=size[1],
                                 hfov_deg=rng.uniform(55, 80), dist=[rng.uniform(-0.3, 0), rng.uniform(0, 0.12),
                                                                     0, 0, 0])
            poses = random_held_poses(cam, board, views, seed=k)
            frames = [render_board_held(cam, board, r, t, nuisances=Nuisances(
                seed=100 * k + i, blur_sigma_px=rng.uniform(0.5, 1.2), noise_sigma=rng.uniform(1, 4),
                jpeg_quality=int(rng.uniform(60, 95)))) for i, (r, t) in enumerate(poses)]
            result = calibrate_intrinsics(frames, board)
            K, Kt = result.camera.K, cam.K
            corner = np.array([[5.0, 5.0], [size[0] - 6.0, size[1] - 6.0]])
            dist_err = np.linalg.norm(result.camera.undistort_points(corner) - cam.undistort_points(corner), axis=1).max()
            print(f"| {kind} | {size[0]}x{size[1]}, k1 {cam.dist[0]:.2f} | {len(result.views_used)} | {result.rms_px:.3f} | "
                  f"{abs(K[0, 0] / Kt[0, 0] - 1):.2%} | {np.linalg.norm(K[:2, 2] - Kt[:2, 2]):.2f} | {dist_err:.2f} | "
                  f"{result.verdict}{(': ' + '; '.join(r.split(';')[0] for r in result.reasons)) if result.reasons else ''} |")


def selfcheck_table(trials: int = 10) -> None:
    from octoprint_printwatch.core.calibration import check_pose_against_first_layer, first_layer_mask, first_layer_paths
    from octoprint_printwatch.simulator.board_scene import render_empty_bed, render_first_layer

    gcode = Path(__file__).resolve().parents[1] / "tests" / "data" / "gcode" / "prusa25_sun_gear_zhop_relative_e.gcode"
    paths, width, z = first_layer_paths(gcode)
    rng = np.random.default_rng(3)
    errors, right, times = [], 0, []
    for k in range(trials):
        az, elev = rng.uniform(-60, 60), rng.uniform(25, 45)
        eye = np.array([100, 100, 0]) + 280 * np.array([np.sin(np.radians(az)) * np.cos(np.radians(elev)),
                                                         -np.cos(np.radians(az)) * np.cos(np.radians(elev)),
                                                         np.sin(np.radians(elev))])
        cam = Camera.look_at("c", eye, (100, 100, 0), hfov_deg=60, dist=[-0.1, 0.02, 0, 0, 0])
        bump = rng.uniform(-1.5, 1.5, 2) if k % 2 else np.zeros(2)  # half the trials: not bumped
        turn = cv2.Rodrigues(np.radians([bump[1], bump[0], 0.0]))[0]
        moved = cam.with_pose(cv2.Rodrigues(turn @ cam.R)[0].ravel(), turn @ cam.tvec)
        background = render_empty_bed(cam, nuisances=Nuisances(seed=k))
        frame = render_first_layer(moved, render_empty_bed(moved, nuisances=Nuisances(seed=k)), paths,
                                   line_width_mm=width, z_mm=z, colour_bgr=tuple(int(c) for c in rng.integers(40, 255, 3)),
                                   seed=k)
        expected = first_layer_mask(cam, paths, width, z)
        start = time.perf_counter()
        check = check_pose_against_first_layer(cam, frame, background, expected)
        times.append(time.perf_counter() - start)
        centre = np.array([[100.0, 100.0, z]])
        true_shift = (moved.project(centre) - cam.project(centre))[0]
        truly_moved = np.linalg.norm(true_shift) > 3.0
        right += check.status == ("moved" if truly_moved else "ok")
        if check.shift_px is not None:
            errors.append(np.linalg.norm(check.shift_px - true_shift))
    print("| trials | right verdict | shift error px (median / max) | time per check |")
    print("|---|---|---|---|")
    print(f"| {trials} | {right}/{trials} | {np.median(errors):.2f} / {max(errors):.2f} | {1000 * np.median(times):.0f} ms |")


if __name__ == "__main__":
    opencv_pairs_table()
    print()
    print("| bed board | found | position error mm (median / max) | rotation error deg (median / max) "
          "| stated sigma mm (median) | solve time |")
    print("|---|---|---|---|---|---|")
    for kind in ("chessboard", "charuco"):
        bed_pose_table(kind)
    print()
    intrinsics_table()
    print()
    selfcheck_table()
    sys.exit(0)
