"""Camera views of calibration boards (and of a printed first layer) for tests and demos.

Renders what a webcam sees: a printed board lying on the bed at a known
placement, or held in front of the camera at a known pose, with the nuisances
that make real calibration hard: uneven light, vignetting, exposure, lens
distortion, defocus blur, sensor noise and JPEG compression. The geometry is
exact (plane-to-image homographies at 3x supersampling, then area-averaged),
so a calibration on these frames can be compared with the true camera.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import cv2
import numpy as np

from ..core.boards import Board, render_board_image
from ..core.calibration.bed import BoardPlacement
from ..core.camera import Camera


@dataclass(frozen=True)
class Nuisances:
    """Image degradations, applied in the order a camera applies them.

    ``light_gradient``: brightness change across the frame (0.3 = +-15 %); ``vignetting``:
    darkening at the corners; ``exposure``: overall gain; ``blur_sigma_px``: defocus;
    ``noise_sigma``: sensor noise (grey levels); ``jpeg_quality``: None for lossless.
    """

    exposure: float = 1.0
    light_gradient: float = 0.25
    light_angle_deg: float = 30.0
    vignetting: float = 0.25
    blur_sigma_px: float = 0.7
    noise_sigma: float = 2.0
    jpeg_quality: int | None = 85
    seed: int = 0


#: Albedos (BGR, 0..1).
PAPER = (0.86, 0.88, 0.90)
INK = (0.07, 0.07, 0.08)
BED = (0.18, 0.17, 0.16)  # dark PEI sheet
SURROUNDINGS = (0.35, 0.38, 0.40)


def board_pose_in_camera(camera: Camera, board: Board, placement: BoardPlacement) -> tuple[np.ndarray, np.ndarray]:
    """(R (3, 3), t (3,)) mapping board-frame mm to the camera frame for a board on the bed."""
    R_bp, t_bp = placement.board_to_printer(board)
    return camera.R @ R_bp, camera.R @ t_bp + camera.tvec


def render_board_on_bed(camera: Camera, board: Board, placement: BoardPlacement, *,
                        bed_mm: tuple[float, float] = (220.0, 220.0), nuisances: Nuisances = Nuisances(),
                        supersample: int = 3, page_margin_mm: float | None = None) -> np.ndarray:
    """(H, W, 3) uint8 frame of the board lying on the bed, seen by ``camera`` (true pose)."""
    R, t = board_pose_in_camera(camera, board, placement)
    ideal = _render_ideal(_padded(camera), supersample, bed_mm=bed_mm, board=board, board_pose=(R, t),
                          page_margin_mm=board.margin_mm if page_margin_mm is None else page_margin_mm,
                          seed=nuisances.seed)
    return _degrade(camera, ideal, nuisances)


def render_empty_bed(camera: Camera, *, bed_mm: tuple[float, float] = (220.0, 220.0),
                     nuisances: Nuisances = Nuisances(), supersample: int = 3) -> np.ndarray:
    """(H, W, 3) uint8 frame of the empty bed (the background frame of a print)."""
    return _degrade(camera, _render_ideal(_padded(camera), supersample, bed_mm=bed_mm, seed=nuisances.seed),
                    nuisances)


def render_board_held(camera: Camera, board: Board, rvec: Sequence[float], tvec: Sequence[float], *,
                      nuisances: Nuisances = Nuisances(), supersample: int = 3,
                      page_margin_mm: float = 8.0) -> np.ndarray:
    """(H, W, 3) uint8 frame of the board held at ``rvec``/``tvec`` (board frame -> camera frame,
    mm) in front of a cluttered room."""
    R = cv2.Rodrigues(np.asarray(rvec, dtype=np.float64))[0]
    ideal = _render_ideal(_padded(camera), supersample, board=board,
                          board_pose=(R, np.asarray(tvec, dtype=np.float64)),
                          page_margin_mm=page_margin_mm, seed=nuisances.seed)
    return _degrade(camera, ideal, nuisances)


def random_held_poses(camera: Camera, board: Board, count: int, *, seed: int = 0, max_tilt_deg: float = 40.0,
                      fill: tuple[float, float] = (0.35, 0.7)) -> list[tuple[np.ndarray, np.ndarray]]:
    """``count`` (rvec, tvec) poses of a hand-held board as a careful user takes them: the whole
    board in view, filling ``fill`` of the frame width, tilted up to ``max_tilt_deg``, its centre
    spread over the frame (corners included)."""
    rng = np.random.default_rng(seed)
    w_mm, h_mm = board.size_mm
    corners = np.array([[0, 0, 0], [w_mm, 0, 0], [w_mm, h_mm, 0], [0, h_mm, 0]], dtype=np.float64)
    centre = np.array([w_mm / 2, h_mm / 2, 0.0])
    # Cycle the target through the frame's corners and edges so every run covers the frame.
    targets = [(0.2, 0.2), (0.8, 0.2), (0.8, 0.8), (0.2, 0.8), (0.5, 0.5), (0.5, 0.2), (0.8, 0.5),
               (0.5, 0.8), (0.2, 0.5)]
    poses = []
    attempts = 0
    while len(poses) < count and attempts < 200 * count:
        attempts += 1
        tu, tv = targets[len(poses) % len(targets)]
        target = np.array([tu * camera.width, tv * camera.height]) + rng.normal(0, 0.04, 2) * camera.width
        fraction = rng.uniform(*fill)
        distance = camera.K[0, 0] * w_mm / (fraction * camera.width)
        tilt = np.radians(rng.uniform(10.0, max_tilt_deg))
        axis_angle = rng.uniform(0, 2 * np.pi)
        tilt_vec = np.array([np.cos(axis_angle), np.sin(axis_angle), 0.0]) * tilt
        spin = np.array([0.0, 0.0, np.radians(rng.uniform(-20, 20))])
        R = cv2.Rodrigues(tilt_vec)[0] @ cv2.Rodrigues(spin)[0]
        ray = np.linalg.inv(camera.K) @ np.array([target[0], target[1], 1.0])
        t = ray / ray[2] * distance - R @ centre
        px = cv2.projectPoints(corners, cv2.Rodrigues(R)[0], t, camera.K, camera.dist)[0].reshape(-1, 2)
        cam_z = (corners @ R.T + t)[:, 2]
        margin = 0.02 * camera.width
        if (cam_z > 10).all() and (px >= margin).all() and (px[:, 0] < camera.width - margin).all() \
                and (px[:, 1] < camera.height - margin).all():
            poses.append((cv2.Rodrigues(R)[0].ravel(), t))
    return poses


def render_first_layer(camera: Camera, background: np.ndarray, paths_mm: Sequence[np.ndarray], *,
                       line_width_mm: float = 0.45, z_mm: float = 0.2, colour_bgr: Sequence[int] = (40, 60, 220),
                       supersample: int = 3, noise_sigma: float = 1.5, seed: int = 0) -> np.ndarray:
    """(H, W, 3) uint8: ``background`` (the empty bed seen by this camera) with extruded lines along
    ``paths_mm`` (each (n, 2|3) printer mm) drawn as ``camera`` sees them, anti-aliased."""
    from ..core.calibration.selfcheck import first_layer_mask

    s = supersample
    big = camera.scaled(camera.width * s, camera.height * s)
    big.K[0, 2] += (s - 1) / 2.0  # pixel centres of the finer grid
    big.K[1, 2] += (s - 1) / 2.0
    mask = first_layer_mask(big, paths_mm, line_width_mm, z_mm).astype(np.float32)
    cover = cv2.resize(mask, camera.size, interpolation=cv2.INTER_AREA)[:, :, None]
    shade = background.astype(np.float32).mean(axis=2, keepdims=True) / 255.0 * 0.6 + 0.55
    line = np.asarray(colour_bgr, dtype=np.float32)[None, None, :] * shade
    out = background.astype(np.float32) * (1 - cover) + line * cover
    out += np.random.default_rng(seed).normal(0, noise_sigma, out.shape)
    return np.clip(out, 0, 255).astype(np.uint8)


# ---------------------------------------------------------------- internals
def _supersampled_K(camera: Camera, s: int) -> np.ndarray:
    K = camera.K.copy()
    K[:2] *= s
    K[0, 2] += (s - 1) / 2.0
    K[1, 2] += (s - 1) / 2.0
    return K


def _plane_homography(K: np.ndarray, R: np.ndarray, t: np.ndarray, texture_to_plane: np.ndarray) -> np.ndarray:
    """Homography from texture pixels to image pixels for a plane z = 0 (plane frame -> camera by R, t)."""
    H = K @ np.column_stack([R[:, 0], R[:, 1], t])
    return H @ texture_to_plane


def _render_ideal(camera: Camera, s: int, *, bed_mm: tuple[float, float] | None = None, board: Board | None = None,
                  board_pose: tuple[np.ndarray, np.ndarray] | None = None, page_margin_mm: float = 8.0,
                  seed: int = 0) -> np.ndarray:
    """Float32 (H, W, 3) albedo image (0..1) of an ideal pinhole camera with ``camera``'s K.

    Planes are warped at ``s`` x supersampling in one channel and area-averaged before
    being coloured and composited: colouring is linear, so the order does not matter.
    """
    rng = np.random.default_rng(seed + 1)
    size = (camera.width * s, camera.height * s)
    K = _supersampled_K(camera, s)
    # Surroundings: smooth random clutter.
    low = rng.uniform(0.6, 1.4, (6, 8, 3)).astype(np.float32)
    image = cv2.resize(low, camera.size, interpolation=cv2.INTER_CUBIC) * np.array(SURROUNDINGS, np.float32)
    if bed_mm is not None:
        ppm = 2.0
        tex_h, tex_w = int(bed_mm[1] * ppm), int(bed_mm[0] * ppm)
        grain = cv2.GaussianBlur(rng.normal(1.0, 0.06, (tex_h, tex_w)).astype(np.float32), (0, 0), 1.0)
        # Texture row 0 is the back of the bed (y = depth), so the image is not mirrored.
        tex_to_bed = np.array([[1 / ppm, 0, 0.5 / ppm], [0, -1 / ppm, bed_mm[1] - 0.5 / ppm], [0, 0, 1]])
        H = _plane_homography(K, camera.R, camera.tvec, tex_to_bed)
        value, cover = _warp_down(grain, H, size, camera.size)
        image = image * (1 - cover[:, :, None]) + value[:, :, None] * np.array(BED, np.float32)
    if board is not None and board_pose is not None:
        ppm = 8.0
        tex = render_board_image(board, ppm, margin_mm=page_margin_mm).astype(np.float32) / 255.0
        tex_to_board = np.array([[1 / ppm, 0, 0.5 / ppm - page_margin_mm], [0, 1 / ppm, 0.5 / ppm - page_margin_mm],
                                 [0, 0, 1]])
        H = _plane_homography(K, board_pose[0], board_pose[1], tex_to_board)
        value, cover = _warp_down(tex, H, size, camera.size)
        ink, paper = np.array(INK, np.float32), np.array(PAPER, np.float32)
        image = image * (1 - cover[:, :, None]) + cover[:, :, None] * ink + value[:, :, None] * (paper - ink)
    return image


def _warp_down(texture: np.ndarray, H: np.ndarray, big: tuple[int, int], final: tuple[int, int]
               ) -> tuple[np.ndarray, np.ndarray]:
    """(value x coverage, coverage) of a one-channel plane texture, each (H, W) float32 at ``final`` size."""
    warped = cv2.warpPerspective(texture, H, big, flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_CONSTANT)
    cover = cv2.warpPerspective(np.ones(texture.shape[:2], np.float32), H, big, flags=cv2.INTER_LINEAR,
                                borderMode=cv2.BORDER_CONSTANT)
    return (cv2.resize(warped, final, interpolation=cv2.INTER_AREA),
            cv2.resize(cover, final, interpolation=cv2.INTER_AREA))


def _lens_maps(camera: Camera) -> tuple[int, np.ndarray, np.ndarray]:
    """(pad, map_x, map_y): each pixel of the distorted frame samples the ideal image, which is
    rendered ``pad`` pixels larger on every side so barrel distortion never reaches past its edge."""
    key = (camera.width, camera.height, tuple(np.round(camera.K.ravel(), 9)), tuple(np.round(camera.dist, 12)))
    if key not in _LENS_CACHE:
        u, v = np.meshgrid(np.arange(camera.width, dtype=np.float64), np.arange(camera.height, dtype=np.float64))
        ideal = camera.undistort_points(np.column_stack([u.ravel(), v.ravel()]))
        overshoot = max(0.0, -ideal.min(), (ideal[:, 0] - camera.width + 1).max(), (ideal[:, 1] - camera.height + 1).max())
        pad = int(np.ceil(overshoot)) + 2
        map_x = (ideal[:, 0] + pad).reshape(camera.height, camera.width).astype(np.float32)
        map_y = (ideal[:, 1] + pad).reshape(camera.height, camera.width).astype(np.float32)
        if len(_LENS_CACHE) > 8:
            _LENS_CACHE.clear()
        _LENS_CACHE[key] = (pad, map_x, map_y)
    return _LENS_CACHE[key]


_LENS_CACHE: dict = {}


def _padded(camera: Camera) -> Camera:
    """The same pinhole camera with a frame ``pad`` pixels larger on every side."""
    pad = _lens_maps(camera)[0]
    K = camera.K.copy()
    K[0, 2] += pad
    K[1, 2] += pad
    return Camera(camera.name, camera.width + 2 * pad, camera.height + 2 * pad, K, np.zeros(5),
                  camera.rvec.copy(), camera.tvec.copy())


def _degrade(camera: Camera, ideal: np.ndarray, n: Nuisances) -> np.ndarray:
    rng = np.random.default_rng(n.seed)
    _, map_x, map_y = _lens_maps(camera)
    image = cv2.remap(ideal, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    h, w = image.shape[:2]
    v, u = np.mgrid[0:h, 0:w].astype(np.float32)
    un, vn = (u - w / 2) / (w / 2), (v - h / 2) / (h / 2)
    a = np.radians(n.light_angle_deg)
    light = 1.0 + 0.5 * n.light_gradient * (np.cos(a) * un + np.sin(a) * vn)
    light *= 1.0 - n.vignetting * 0.5 * (un ** 2 + vn ** 2)
    image = image * (light * n.exposure * 235.0)[:, :, None]
    if n.blur_sigma_px > 0:
        image = cv2.GaussianBlur(image, (0, 0), n.blur_sigma_px)
    if n.noise_sigma > 0:
        # Shot noise grows with brightness; read noise does not.
        sigma = n.noise_sigma * np.sqrt(0.3 + 0.7 * np.clip(image, 0, 255) / 255.0)
        image = image + rng.normal(0, 1, image.shape).astype(np.float32) * sigma
    image = np.clip(image, 0, 255).astype(np.uint8)
    if n.jpeg_quality is not None:
        ok, data = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(n.jpeg_quality)])
        image = cv2.imdecode(data, cv2.IMREAD_COLOR)
    return image
