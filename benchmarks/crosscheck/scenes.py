"""Random parts, rigs, looks and failures for the cross-check simulator, and the recording writer.

Independent of ``octoprint_printwatch`` (never imported here): parts are manifold3d primitives and
extrusions, not the project's part library; the recording is written from docs/recording-format.md.
Everything is drawn from one ``numpy.random.Generator`` per recording, so a seed reproduces it.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import trimesh
from manifold3d import CrossSection, JoinType, Manifold

from .render import (LAYER_HEIGHT_MM, BedLook, Camera, Light, Mesh, Sensor, Strand, clear_caches, expose, look_at,
                     render_view, shadow_map, write_image)

BED_MM = 220.0
KINDS = ("normal", "runout", "detach", "spaghetti", "layer_shift")
SEGMENTS = 48


# ------------------------------------------------------------------------------------------------ parts

def _polygon_star(rng, radius):
    n = int(rng.integers(5, 9))
    inner = radius * rng.uniform(0.45, 0.7)
    a = np.arange(2 * n) * np.pi / n
    r = np.where(np.arange(2 * n) % 2 == 0, radius, inner)
    return np.stack([r * np.cos(a), r * np.sin(a)], 1)


def _polygon_blob(rng, radius):
    """A random star-shaped polygon (sorted angles, random radii): mostly irregular convex-ish outlines."""
    n = int(rng.integers(5, 10))
    a = np.sort(rng.uniform(0, 2 * np.pi, n))
    r = radius * rng.uniform(0.6, 1.0, n)
    return np.stack([r * np.cos(a), r * np.sin(a)], 1)


def _polygon_l(rng, size):
    w, d = size, size * rng.uniform(0.6, 1.0)
    t1, t2 = w * rng.uniform(0.3, 0.5), d * rng.uniform(0.3, 0.5)
    pts = np.array([[0, 0], [w, 0], [w, t2], [t1, t2], [t1, d], [0, d]], float)
    return pts - [w / 2, d / 2]


def random_part(rng: np.random.Generator) -> tuple[Manifold, dict]:
    """A part centred on (0, 0), standing on z = 0: 8-60 mm footprint, 8-60 mm tall (a multiple of 0.2)."""
    foot = float(rng.uniform(8, 60))
    height = round(float(rng.uniform(8, 60)) / LAYER_HEIGHT_MM) * LAYER_HEIGHT_MM
    shape = str(rng.choice(["box", "cylinder", "frustum", "cone", "star", "L", "ring", "frame", "polygon",
                            "stack", "stack"]))
    taper = 1.0 if rng.random() < 0.6 else float(rng.uniform(0.55, 0.95))

    def prism(cross: CrossSection, h, scale=1.0):
        return cross.extrude(h, scale_top=(scale, scale))

    if shape == "box":
        d = max(8.0, foot * rng.uniform(0.3, 1.0))
        part = Manifold.cube([foot, d, height]).translate([-foot / 2, -d / 2, 0])
    elif shape == "cylinder":
        part = Manifold.cylinder(height, foot / 2, foot / 2, SEGMENTS)
    elif shape == "frustum":
        part = Manifold.cylinder(height, foot / 2, foot / 2 * rng.uniform(0.4, 0.9), SEGMENTS)
    elif shape == "cone":
        part = Manifold.cylinder(height, foot / 2, foot / 2 * rng.uniform(0.05, 0.25), SEGMENTS)
    elif shape == "star":
        part = prism(CrossSection([_polygon_star(rng, foot / 2)]), height, taper)
    elif shape == "L":
        part = prism(CrossSection([_polygon_l(rng, foot)]), height, 1.0)
    elif shape == "ring":
        outer = foot / 2
        inner = outer * rng.uniform(0.35, 0.7)
        part = prism(CrossSection.circle(outer, SEGMENTS) - CrossSection.circle(inner, SEGMENTS), height, taper)
    elif shape == "frame":
        outer = CrossSection.square([foot, foot], center=True)
        inner = CrossSection.square([foot * rng.uniform(0.4, 0.7)] * 2, center=True)
        part = prism(outer - inner, height, 1.0)
    elif shape == "polygon":
        part = prism(CrossSection([_polygon_blob(rng, foot / 2)]), height, taper)
    else:  # stack: a base and a narrower piece on top (no overhang)
        h1 = round(height * rng.uniform(0.3, 0.7) / LAYER_HEIGHT_MM) * LAYER_HEIGHT_MM
        h2 = height - h1
        if rng.random() < 0.5:
            d = max(8.0, foot * rng.uniform(0.5, 1.0))
            base = Manifold.cube([foot, d, h1]).translate([-foot / 2, -d / 2, 0])
            top_r = min(foot, d) / 2 * rng.uniform(0.35, 0.8)
        else:
            base = Manifold.cylinder(h1, foot / 2, foot / 2, SEGMENTS)
            top_r = foot / 2 * rng.uniform(0.35, 0.75)
        off = rng.uniform(-0.5, 0.5, 2) * (foot / 2 - top_r) * 0.8
        if rng.random() < 0.5:
            top = Manifold.cylinder(h2, top_r, top_r * rng.uniform(0.5, 1.0), SEGMENTS)
        else:
            top = Manifold.cube([2 * top_r, 2 * top_r, h2]).translate([-top_r, -top_r, 0])
        part = base + top.translate([off[0], off[1], h1])
        shape = "stack"
    yaw = float(rng.uniform(0, 360))
    part = part.rotate((0, 0, yaw))
    return part, {"shape": shape, "footprint_mm": round(foot, 1), "height_mm": round(height, 2),
                  "taper": round(taper, 2), "yaw_deg": round(yaw, 1)}


def to_mesh(part: Manifold, colour, **look) -> Mesh:
    m = part.to_mesh()
    return Mesh(np.asarray(m.vert_properties, float)[:, :3], np.asarray(m.tri_verts, np.int64), colour, **look)


def below(part: Manifold, z: float) -> Manifold:
    """The part as printed up to height z."""
    return part.trim_by_plane((0, 0, -1), -z)


def above(part: Manifold, z: float) -> Manifold:
    return part.trim_by_plane((0, 0, 1), z)


def cross_section(part: Manifold, z: float) -> list[np.ndarray]:
    return [np.asarray(p, float) for p in part.slice(z).to_polygons()]


def inside(polygons: list[np.ndarray], xy: np.ndarray) -> bool:
    """Even-odd point-in-polygon over every contour (holes included)."""
    x, y = float(xy[0]), float(xy[1])
    count = 0
    for poly in polygons:
        xs, ys = poly[:, 0], poly[:, 1]
        xn, yn = np.roll(xs, -1), np.roll(ys, -1)
        crosses = ((ys > y) != (yn > y)) & (x < (xn - xs) * (y - ys) / np.where(yn == ys, 1e-12, yn - ys) + xs)
        count += int(crosses.sum())
    return count % 2 == 1


# ------------------------------------------------------------------------------------------------ looks

def srgb_to_linear(c):
    c = np.asarray(c, float)
    return np.where(c <= 0.04045, c / 12.92, ((c + 0.055) / 1.055) ** 2.4)


FILAMENTS = {  # sRGB-ish paint colours, converted to linear albedo
    "black": (0.09, 0.09, 0.10), "white": (0.93, 0.93, 0.91), "grey": (0.48, 0.49, 0.50),
    "light grey": (0.72, 0.72, 0.72), "red": (0.80, 0.10, 0.10), "orange": (0.95, 0.45, 0.08),
    "yellow": (0.92, 0.82, 0.15), "green": (0.15, 0.62, 0.22), "blue": (0.10, 0.30, 0.78),
    "purple": (0.45, 0.20, 0.62), "natural": (0.82, 0.83, 0.78), "translucent blue": (0.40, 0.62, 0.85),
    "silver": (0.70, 0.71, 0.74),
}


def random_bed(rng) -> tuple[str, np.ndarray, dict]:
    """(kind, (T, T, 3) linear albedo texture at 0.2 mm/texel, extra look params)."""
    n = int(BED_MM / 0.2)
    kind = str(rng.choice(["pei gold", "pei black", "smooth pei", "glass", "blue tape", "kapton", "random"]))
    extra = {"specular": 0.0, "reflectivity": 0.0}
    fine = rng.standard_normal((n, n, 1)).astype(np.float32)
    coarse = cv2.resize(rng.standard_normal((n // 20, n // 20)).astype(np.float32), (n, n),
                        interpolation=cv2.INTER_CUBIC)[:, :, None]
    if kind == "pei gold":
        base, grain = srgb_to_linear((0.72, 0.52, 0.25)) * rng.uniform(0.85, 1.15), 0.12
    elif kind == "pei black":
        base, grain = srgb_to_linear((0.14, 0.14, 0.15)) * rng.uniform(0.8, 1.3), 0.25
    elif kind == "smooth pei":
        base, grain = srgb_to_linear((0.80, 0.62, 0.30)), 0.03
        extra["specular"] = float(rng.uniform(0.1, 0.4))
    elif kind == "glass":
        base, grain = srgb_to_linear((0.12, 0.13, 0.13)) * rng.uniform(0.7, 1.5), 0.01
        extra["specular"] = float(rng.uniform(0.6, 2.5))
        extra["reflectivity"] = float(rng.uniform(0.08, 0.3))
    elif kind == "blue tape":
        base, grain = srgb_to_linear((0.25, 0.50, 0.85)), 0.05
    elif kind == "kapton":
        base, grain = srgb_to_linear((0.75, 0.45, 0.12)), 0.03
        extra["specular"] = float(rng.uniform(0.2, 0.6))
    else:
        base, grain = srgb_to_linear(rng.uniform(0.1, 0.9, 3)), float(rng.uniform(0.02, 0.15))
    tex = base[None, None] * (1 + grain * fine + 0.04 * coarse)
    if kind in ("blue tape", "kapton"):
        # strips about 48 mm wide with darker seams and a slightly different shade each
        width = rng.uniform(40, 55) / 0.2
        horizontal = rng.random() < 0.5
        idx = np.arange(n)
        strip = (idx // width).astype(int)
        shade = 1 + 0.06 * rng.standard_normal(strip.max() + 1)
        seam = (idx % width) < 2
        f = shade[strip] * np.where(seam, 0.7, 1.0)
        tex = tex * (f[:, None, None] if horizontal else f[None, :, None])
    return kind, np.clip(tex, 0, 1).astype(np.float32), extra


def random_backdrop(rng) -> np.ndarray:
    """(256, 512, 3) linear albedo by ray azimuth (columns) and elevation (rows): walls, shelves, clutter."""
    h, w = 256, 512
    base = srgb_to_linear(rng.uniform(0.15, 0.85, 3))
    img = np.tile(base.astype(np.float32), (h, w, 1))
    low = cv2.resize(rng.standard_normal((4, 8, 3)).astype(np.float32), (w, h), interpolation=cv2.INTER_CUBIC)
    img *= 1 + 0.25 * low
    for _ in range(int(rng.integers(3, 12))):
        x0, y0 = int(rng.integers(0, w)), int(rng.integers(h // 4, h))
        ww, hh = int(rng.integers(10, 120)), int(rng.integers(5, 60))
        img[y0:y0 + hh, x0:x0 + ww] = srgb_to_linear(rng.uniform(0.02, 0.95, 3))
    return np.clip(img, 0, 1).astype(np.float32)


def random_sensor(rng) -> Sensor:
    return Sensor(vignetting=float(rng.uniform(0.05, 0.45)), blur_sigma=float(rng.uniform(0.3, 1.1)),
                  full_well=float(rng.uniform(250, 2500)), read_noise=float(rng.uniform(0.002, 0.012)),
                  gamma=float(rng.uniform(2.0, 2.5)), sharpen=float(rng.uniform(0.0, 0.8)))


# ------------------------------------------------------------------------------------------------- rigs

def _camera_for(rng, name, eye, target, focal, size, roll):
    w, h = size
    K = np.array([[focal, 0, w / 2 + rng.normal(0, 6)], [0, focal * (1 + rng.normal(0, 0.002)), h / 2 + rng.normal(0, 6)],
                  [0, 0, 1.0]])
    dist = np.array([rng.uniform(-0.2, 0.03), rng.uniform(-0.02, 0.08), rng.normal(0, 0.0007),
                     rng.normal(0, 0.0007), 0.0])
    rvec, tvec = look_at(eye, target, roll)
    return Camera(name, w, h, K, dist, rvec, tvec)


def _fits(cam: Camera, corners: np.ndarray, margin: float = 0.08) -> bool:
    uv = cam.project(corners)
    w, h = cam.width, cam.height
    depth = (corners @ cam.R.T + cam.tvec)[:, 2]
    return bool((depth > 20).all() and (uv[:, 0] > margin * w).all() and (uv[:, 0] < (1 - margin) * w).all()
                and (uv[:, 1] > margin * h).all() and (uv[:, 1] < (1 - margin) * h).all())


def random_rig(rng, centre: np.ndarray, half_extent: float, height: float,
               size: tuple[int, int] | None = None) -> tuple[list[Camera], list[list[str]], dict]:
    """1-4 cameras (sometimes a relaxed stereo pair) looking at the part; true cameras."""
    if size is None:
        r = rng.random()
        size = (640, 480) if r < 0.7 else (800, 600) if r < 0.85 else (1280, 720)
    layout = str(rng.choice(["1", "2", "pair", "pair+1", "3", "4", "2pairs"], p=[0.15, 0.2, 0.15, 0.15, 0.15, 0.1, 0.1]))
    stations = {"1": [1], "2": [1, 1], "pair": [2], "pair+1": [2, 1], "3": [1, 1, 1], "4": [1, 1, 1, 1],
                "2pairs": [2, 2]}[layout]
    corners = np.array([[centre[0] + sx * half_extent, centre[1] + sy * half_extent, z]
                        for sx in (-1, 1) for sy in (-1, 1) for z in (0.0, height)])
    cams, pairs = [], []
    az0 = rng.uniform(0, 360)
    scale = size[0] / 640
    for s, n in enumerate(stations):
        az = np.radians(az0 + s * 360 / len(stations) + rng.uniform(-25, 25))
        el = np.radians(rng.uniform(10, 50))
        focal = rng.uniform(500, 1000) * scale
        dist = rng.uniform(150, 400)
        target = np.array([centre[0], centre[1], height * rng.uniform(0.3, 0.6)]) + rng.normal(0, 3, 3)
        roll = rng.normal(0, 2)
        for _ in range(40):  # back off (then widen) until the whole part is in view
            eye = target + dist * np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
            cam = _camera_for(rng, f"s{s}" if n == 1 else f"s{s}L", eye, target, focal, size, roll)
            if _fits(cam, corners):
                break
            if dist < 400:
                dist = min(400, dist * 1.1)
            else:
                focal *= 0.92
        cams.append(cam)
        if n == 2:
            baseline = rng.uniform(40, 90)
            right = cam.R[0]
            eye2 = eye + baseline * right + rng.uniform(-20, 20) * (target - eye) / np.linalg.norm(target - eye)
            target2 = target + rng.normal(0, 4, 3)                     # a few degrees of relative yaw/pitch
            cam2 = _camera_for(rng, f"s{s}R", eye2, target2, focal * rng.uniform(0.95, 1.05), size, roll + rng.normal(0, 1))
            if not _fits(cam2, corners, 0.02):
                cam2 = _camera_for(rng, f"s{s}R", eye2, target, focal * 0.9, size, roll)
            cams.append(cam2)
            pairs.append([cam.name, cam2.name])
    return cams, pairs, {"layout": layout, "size": list(size)}


def with_calibration_error(rng, cam: Camera, scale: float = 1.0) -> Camera:
    """The camera as a user's calibration states it: ~1 % focal, ~0.5 deg rotation, ~1 mm position."""
    K = cam.K.copy()
    f = 1 + rng.normal(0, 0.01 * scale)
    K[0, 0] *= f
    K[1, 1] *= f
    K[:2, 2] += rng.normal(0, 1.5 * scale, 2)
    dist = cam.dist + np.array([rng.normal(0, 0.01 * scale), rng.normal(0, 0.01 * scale), 0, 0, 0])
    dR = cv2.Rodrigues(np.radians(rng.normal(0, 0.3 * scale, 3)).reshape(3, 1))[0]
    R = dR @ cam.R
    centre = cam.centre + rng.normal(0, 0.6 * scale, 3)
    return Camera(cam.name, cam.width, cam.height, K, dist, cv2.Rodrigues(R)[0].ravel(), -R @ centre)


# --------------------------------------------------------------------------------------- hotend, strands

def hotend_meshes(tip: np.ndarray, gantry: bool) -> list[Mesh]:
    """Nozzle, heater block, heat sink, fan shroud and carriage with the nozzle tip at ``tip`` (3,)."""
    brass, alu, black = srgb_to_linear((0.75, 0.6, 0.3)), srgb_to_linear((0.7, 0.7, 0.72)), srgb_to_linear((0.1, 0.1, 0.11))
    parts = [
        (Manifold.cylinder(5, 0.6, 3.5, 16), brass, 0.4),
        (Manifold.cube([20, 12, 10]).translate([-8, -6, 5]), alu, 0.5),
        (Manifold.cylinder(28, 11, 11, 24).translate([0, 0, 15]), alu, 0.3),
        (Manifold.cube([44, 16, 48]).translate([-22, -26, 12]), black, 0.1),
        (Manifold.cube([60, 10, 70]).translate([-30, 14, 10]), black, 0.1),
    ]
    out = []
    for m, colour, spec in parts:
        out.append(to_mesh(m.translate(tuple(tip)), colour, specular=spec))
    if gantry:
        for dz in (30.0, 65.0):
            rod = Manifold.cylinder(300, 4, 4, 16).rotate((0, 90, 0)).translate([-40, tip[1] + 19, tip[2] + dz])
            out.append(to_mesh(rod, alu, specular=0.5))
    return out


def occludes(cam: Camera, meshes: list[Mesh], centre: np.ndarray, half: float, height: float) -> bool:
    """Does any mesh stand between ``cam`` and the part's box (centre +- half mm, 0..height) in its view?"""
    box = np.array([[centre[0] + sx * half, centre[1] + sy * half, z] for sx in (-1, 1) for sy in (-1, 1)
                    for z in (0.0, height)])
    part_depth = float(((box @ cam.R.T) + cam.tvec)[:, 2].min())
    uv = cam.project(box)
    lo, hi = uv.min(0), uv.max(0)
    for mesh in meshes:
        v = np.asarray(mesh.vertices)
        depth = (v @ cam.R.T + cam.tvec)[:, 2]
        if depth.max() <= 1 or depth.min() >= part_depth:
            continue
        front = v[depth > 1]
        m_uv = cam.project(front)
        mlo, mhi = m_uv.min(0), m_uv.max(0)
        if (mlo < hi).all() and (mhi > lo).all():
            return True
    return False


def _walk(rng, start, steps, step_mm, heading, curl):
    pts = [np.asarray(start, float)]
    for _ in range(steps):
        heading += rng.normal(0, curl)
        p = pts[-1] + step_mm * np.array([np.cos(heading), np.sin(heading), 0.0])
        pts.append(p)
    return np.array(pts), heading


class SectionCache:
    """Cross-sections of a manifold by 0.5-mm height, for strands that must lie outside the part."""

    def __init__(self, part: Manifold):
        self.part, self.cache = part, {}

    def at(self, z):
        key = round(max(z, 0.1) * 2) / 2
        if key not in self.cache:
            self.cache[key] = cross_section(self.part, max(key, 0.1))
        return self.cache[key]


def drape_strand(rng, start, top_z, sections: SectionCache, centre, colour, width=0.4, pile=0.0) -> Strand:
    """A strand that wanders over the top of the part (up to ``pile`` mm above it) and, where it leaves
    the top, falls down the side (kept just outside the part) to the bed and lies there a little."""
    top_poly = sections.at(top_z - 0.1)
    p = np.array([start[0], start[1], top_z + rng.uniform(0, pile + 0.3)])
    heading = rng.uniform(0, 2 * np.pi)
    pts = [p.copy()]
    falling = False
    for _ in range(int(rng.integers(15, 45))):
        if not falling:
            heading += rng.normal(0, 0.7)
            p = p + 1.5 * np.array([np.cos(heading), np.sin(heading), 0.0])
            p[2] = top_z + 0.3 + rng.uniform(0, pile + 0.2)
            if not inside(top_poly, p[:2]) and top_poly:
                falling = rng.random() < 0.8
                if not falling:                                   # a loop sticking out: turn back
                    heading += np.pi
        else:
            out = p[:2] - centre
            out /= max(np.linalg.norm(out), 1e-6)
            p = p + np.array([out[0] * 0.4 + rng.normal(0, 0.3), out[1] * 0.4 + rng.normal(0, 0.3), -2.5])
            if p[2] <= 0.3:
                p[2] = 0.3
                for _ in range(int(rng.integers(2, 8))):
                    heading += rng.normal(0, 0.6)
                    p = p + np.array([np.cos(heading), np.sin(heading), 0.0]) * 1.5
                    pts.append(p.copy())
                break
            for _ in range(12):                                  # keep it on the outside of the part
                if not inside(sections.at(p[2]), p[:2]):
                    break
                p[:2] += out * 0.8
        pts.append(p.copy())
    return Strand(np.array(pts), width, colour)


# -------------------------------------------------------------------------------------------- scenarios

@dataclass
class Recipe:
    seed: int
    kind: str
    size: tuple | None = None
    supersample: int = 2
    max_checks_after_flag: int = 4
    quick: bool = False          # tests: tiny frames, one camera
    calibration_error: float = 1.0   # scales every stated-calibration error (same draws, same order)


@dataclass
class Scene:
    part: Manifold
    part_info: dict
    centre: np.ndarray
    n_layers: int
    every: int
    check_layers: list
    kind: str
    onset_layer: int | None
    look: dict
    shift: np.ndarray | None = None
    detach_pose: dict | None = None


def _top_area(part: Manifold, z: float) -> float:
    return float(part.slice(max(z - 0.1, 0.1)).area())


def plan_scene(rng, recipe: Recipe) -> Scene:
    part, info = random_part(rng)
    foot = info["footprint_mm"]
    margin = foot / 2 + 25
    centre = rng.uniform(margin, BED_MM - margin, 2)
    part = part.translate((float(centre[0]), float(centre[1]), 0.0))
    n_layers = int(round(info["height_mm"] / LAYER_HEIGHT_MM))
    every = int(rng.integers(8, 26))
    layers = list(range(every, n_layers + 1, every))
    if not layers or layers[-1] != n_layers and n_layers - layers[-1] > every // 2:
        layers.append(n_layers)
    kind = recipe.kind
    onset = None
    if kind != "normal":
        # onset after ~20 % of the height, leaving room for at least two checks after it
        lo = max(int(0.2 * n_layers), 2)
        later = [l for l in layers if l > lo]
        hi = later[-3] if len(later) >= 3 else max(lo + 1, n_layers - 2 * every)
        onset = int(rng.integers(lo, max(hi, lo + 1)))
    fil_name = str(rng.choice(list(FILAMENTS) + ["random", "like bed"], p=None))
    look = {"filament": fil_name}
    return Scene(part, info, centre, n_layers, every, layers, kind, onset, look)


def generate(out: Path, recipe: Recipe) -> dict:
    """Write one recording to ``out`` (created) and return its truth."""
    rng = np.random.default_rng(recipe.seed)
    out = Path(out)
    clear_caches()                         # one recording's frames never depend on what was rendered before
    (out / "background").mkdir(parents=True, exist_ok=True)
    scene = plan_scene(rng, recipe)
    part, centre = scene.part, scene.centre

    # --- look
    bed_kind, bed_tex, bed_extra = random_bed(rng)
    if scene.look["filament"] == "random":
        colour = srgb_to_linear(rng.uniform(0.05, 0.95, 3))
    elif scene.look["filament"] == "like bed":
        colour = np.clip(bed_tex.reshape(-1, 3).mean(0) * rng.uniform(0.8, 1.25, 3), 0, 1)
    else:
        colour = srgb_to_linear(FILAMENTS[scene.look["filament"]])
    translucent = scene.look["filament"] in ("natural", "translucent blue")
    part_look = {"layer_lines": float(rng.uniform(0.02, 0.12)), "specular": float(rng.uniform(0.0, 0.25)),
                 "flat": 0.6 if translucent else float(rng.uniform(0, 0.2))}
    el = np.radians(rng.uniform(25, 80))
    az = rng.uniform(0, 2 * np.pi)
    ambient = float(rng.uniform(0.25, 0.6))
    light_colour = np.array([1.0, rng.uniform(0.93, 1.03), rng.uniform(0.8, 1.1)], np.float32)
    base_light = Light(np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)]), ambient,
                       float(rng.uniform(0.5, 1.0)), light_colour, float(rng.uniform(0.5, 3.0)))
    backdrop = random_backdrop(rng)
    bed = BedLook(bed_tex, BED_MM, srgb_to_linear(rng.uniform(0.03, 0.3, 3)), backdrop,
                  specular=bed_extra["specular"], streak_axis_deg=float(rng.uniform(0, 180)),
                  reflectivity=bed_extra["reflectivity"])
    jpeg_quality = None if rng.random() < 0.1 else int(rng.integers(60, 96))
    suffix = ".png" if jpeg_quality is None else ".jpg"

    # --- rig
    half = scene.part_info["footprint_mm"] / 2 * 1.05
    size = (160, 120) if recipe.quick else recipe.size
    cams, pairs, rig = random_rig(rng, centre, half, scene.part_info["height_mm"], size)
    if recipe.quick:
        cams, pairs = cams[:1], []
    stated = {c.name: with_calibration_error(rng, c, recipe.calibration_error) for c in cams}
    sensors = {c.name: random_sensor(rng) for c in cams}
    auto_exposure = {c.name: bool(rng.random() < 0.7) for c in cams}

    # --- nuisances
    lift = float(rng.uniform(5, 25))
    gantry = bool(rng.random() < 0.25)
    parks = [(5.0, 5.0), (215.0, 5.0), (5.0, 215.0), (215.0, 215.0), (110.0, 225.0), (-60.0, 240.0)]
    park = (-250.0, 450.0)                 # far out of every view when no corner suits
    top_mm = scene.part_info["height_mm"]
    for k in rng.permutation(len(parks)):
        # a user parks the head where no camera sees it in front of the part (it may stand behind it)
        if not any(occludes(c, hotend_meshes(np.array([*parks[k], z]), gantry), centre, half + 30, top_mm)
                   for c in cams for z in (lift, top_mm + lift)):
            park = parks[k]
            break
    skirt = rng.random() < 0.5
    brim = (not skirt) and rng.random() < 0.2
    stringing = bool(rng.random() < 0.4)
    light_jitter = float(rng.uniform(0.0, 0.12))
    decals = None
    if skirt or brim:
        n = bed_tex.shape[0]
        alpha = np.zeros((n, n), np.uint8)
        foot_cs = part.slice(0.1)
        if skirt:   # one 0.4-mm line (2 texels) a few mm around the footprint's hull
            ring = foot_cs.offset(float(rng.uniform(3, 8)), JoinType.Round, 2.0, 64).hull()
            polys = [np.round((np.asarray(p) / 0.2 - 0.5) * 16).astype(np.int32) for p in ring.to_polygons()]
            cv2.polylines(alpha, polys, True, 255, 2, cv2.LINE_AA, 4)
        else:       # a brim: a filled band around the footprint
            band = foot_cs.offset(float(rng.uniform(3, 6)), JoinType.Round, 2.0, 64)
            polys = [np.round((np.asarray(p) / 0.2 - 0.5) * 16).astype(np.int32) for p in band.to_polygons()]
            cv2.fillPoly(alpha, polys, 255, cv2.LINE_AA, 4)
        decals = np.concatenate([np.broadcast_to(colour.astype(np.float32), (n, n, 3)),
                                 (alpha.astype(np.float32) / 255)[:, :, None]], axis=2)

    # --- failure geometry
    kind, onset = scene.kind, scene.onset_layer
    z_on = onset * LAYER_HEIGHT_MM if onset else None
    shift = None
    moved = None
    tangle: list[tuple[int, Strand]] = []
    hairs: list[tuple[int, Strand]] = []
    blob_centres = None
    sections = SectionCache(part)
    if kind == "layer_shift":
        mag = rng.uniform(2, 8)
        ang = rng.uniform(0, 2 * np.pi)
        shift = np.array([mag * np.cos(ang), mag * np.sin(ang)])
    elif kind == "detach":
        piece = below(part, z_on)
        dist = rng.uniform(5, 30) if rng.random() < 0.8 else 0.0
        tip = float(rng.uniform(10, 80)) if (dist == 0.0 or rng.random() < 0.4) else 0.0
        ang = rng.uniform(0, 2 * np.pi)
        axis_ang = float(rng.uniform(0, 360))
        m = piece.translate((-centre[0], -centre[1], 0))
        if tip:
            m = m.rotate((0, 0, -axis_ang)).rotate((tip, 0, 0)).rotate((0, 0, axis_ang))
        m = m.translate((centre[0] + dist * np.cos(ang), centre[1] + dist * np.sin(ang), 0))
        zmin = m.bounding_box()[2]
        moved = m.translate((0, 0, -zmin))
        scene.detach_pose = {"moved_mm": round(float(dist), 1), "tipped_deg": round(tip, 1)}
        blob_centres = centre + rng.normal(0, scene.part_info["footprint_mm"] * 0.15, (int(rng.integers(2, 6)), 2))
        blob_sizes = rng.uniform(0.7, 1.2, len(blob_centres))
        onset_area = _top_area(part, z_on)
        for i in range(int(rng.integers(6, 20))):
            birth = onset + int(rng.integers(1, max(2, 3 * scene.every)))
            start = blob_centres[i % len(blob_centres)]
            pts, _ = _walk(rng, [start[0], start[1], 0.3], int(rng.integers(8, 30)), 1.5, rng.uniform(0, 2 * np.pi), 0.5)
            pts[:, 2] = 0.3 + np.abs(rng.normal(0, 1.5, len(pts))) * np.exp(-np.arange(len(pts)) / 6)
            tangle.append((birth, Strand(pts, 0.4, colour)))
    elif kind == "spaghetti":
        top = z_on
        polys = sections.at(top - 0.1)
        allp = np.concatenate(polys) if polys else np.array([centre])
        lo, hi = allp.min(0), allp.max(0)
        for i in range(60):
            birth = onset + 1 + i // 2                             # two strands a layer
            for _ in range(50):
                start = rng.uniform(lo, hi)
                if inside(polys, start):
                    break
            pile = min(10.0, 0.1 * (birth - onset))
            tangle.append((birth, drape_strand(rng, start, top, sections, centre, colour, 0.4, pile)))
    if stringing:
        # now and then a hair: a wisp 0.05-0.12 mm thick left by a travel move, drooping from the top
        # edge down the side (it stays on the part: later layers print over its root)
        for layer in scene.check_layers:
            if rng.random() >= 0.5:
                continue
            z = layer * LAYER_HEIGHT_MM
            polys = sections.at(z - 0.1)
            if not polys:
                continue
            edge = polys[0][int(rng.integers(0, len(polys[0])))]
            out_dir = edge - centre
            out_dir /= max(np.linalg.norm(out_dir), 1e-6)
            reach, drop = rng.uniform(1, 4), rng.uniform(2, 8)
            s = np.linspace(0, 1, 8)[:, None]
            pts = np.concatenate([edge + out_dir * (0.3 + reach * np.sin(np.pi * s / 2)),
                                  z - 0.1 - drop * s ** 1.5], 1)
            pts[:, 2] = np.maximum(pts[:, 2], 0.2)
            hairs.append((layer, Strand(pts, float(rng.uniform(0.05, 0.12)), colour)))

    # --- truth per check and the checks to write
    checks_truth = []
    flag_idx = None
    for i, layer in enumerate(scene.check_layers):
        started = onset is not None and layer > onset
        printed_above = (layer - onset) * LAYER_HEIGHT_MM if started else 0.0
        if kind == "runout":
            visible = started and printed_above >= 1.0
        elif kind == "detach":
            visible = started
        elif kind == "spaghetti":
            visible = started and sum(b <= layer for b, _ in tangle) >= 4
        elif kind == "layer_shift":
            visible = started and printed_above >= 1.0 and z_on < scene.part_info["height_mm"]
        else:
            visible = False
        if visible and flag_idx is None:
            flag_idx = i
        checks_truth.append({"layer": layer, "z": round(layer * LAYER_HEIGHT_MM, 4), "failure_started": started,
                             "visible": visible})
    if flag_idx is not None:
        checks_truth = checks_truth[:flag_idx + 1 + recipe.max_checks_after_flag]
    n_checks = len(checks_truth)

    # --- frames
    def scene_at(layer: int | None, rng_check) -> tuple[list[Mesh], list[Strand], float]:
        """Meshes and strands at a check (None: the empty bed) and the highest point printed."""
        meshes, strands = [], []
        top = 0.0
        if layer is not None:
            z = layer * LAYER_HEIGHT_MM
            look = dict(part_look)
            if kind in ("runout", "spaghetti") and layer > onset:
                meshes.append(to_mesh(below(part, z_on), colour, **look))
                top = z_on
            elif kind == "detach" and layer > onset:
                meshes.append(to_mesh(moved, colour, **look))
                grown = (layer - onset) * LAYER_HEIGHT_MM
                volume = onset_area * grown * 0.35                  # sparse infill: a third of the solid
                r = (3 * volume / (4 * np.pi * len(blob_centres))) ** (1 / 3)
                blob = Manifold()
                for c, f in zip(blob_centres, blob_sizes):
                    rr = r * f
                    blob = blob + Manifold.sphere(rr, 24).scale((1, 1, 0.55)).translate((c[0], c[1], rr * 0.3))
                meshes.append(to_mesh(blob, colour, **look))
                top = max(moved.bounding_box()[5], r)
            elif kind == "layer_shift" and layer > onset:
                meshes.append(to_mesh(below(part, z_on), colour, **look))
                upper = below(above(part, z_on), z)
                meshes.append(to_mesh(upper.translate((shift[0], shift[1], 0)), colour, **look))
                top = z
            else:
                meshes.append(to_mesh(below(part, z), colour, **look))
                top = z
            strands += [s for b, s in tangle if b <= layer]
            strands += [s for b, s in hairs if b <= layer]
        # the G-code goes on climbing whatever happened to the part: the head parks above the nominal top
        head_z = (layer * LAYER_HEIGHT_MM if layer is not None else 0.0) + lift
        meshes += hotend_meshes(np.array([park[0], park[1], head_z]), gantry)
        return meshes, strands, top

    truth_cams = {c.name: c.to_json() for c in cams}
    session = {"format": "printwatch-recording/1", "units": "mm", "model": "model.stl",
               "layer_height": LAYER_HEIGHT_MM,
               "cameras": {n: c.to_json() for n, c in stated.items()}, "pairs": pairs,
               "background": {}, "checks": []}
    base_gain = {c.name: float(rng.uniform(0.8, 1.6)) for c in cams}

    def shoot(name_dir: Path, layer, check_index):
        rng_check = np.random.default_rng([recipe.seed, 7, check_index + 1])
        light = Light(base_light.direction, base_light.ambient, base_light.diffuse, base_light.colour,
                      base_light.penumbra_mm)
        if check_index >= 0 and light_jitter > 0:
            d = light.direction + rng_check.normal(0, light_jitter * 0.25, 3)   # a lamp nudged, daylight moving
            d[2] = abs(d[2]) + 0.1
            light = Light(d / np.linalg.norm(d), ambient * (1 + rng_check.normal(0, light_jitter)),
                          base_light.diffuse * (1 + rng_check.normal(0, light_jitter)), light_colour,
                          base_light.penumbra_mm)
        meshes, strands, _ = scene_at(layer, rng_check)
        shadow = shadow_map(meshes, strands, light, -60.0, 280.0, 0.5)
        frames = {}
        for cam in cams:
            radiance = render_view(cam, meshes, strands, light, bed, decals if layer is not None else None,
                                   recipe.supersample if cam.width <= 800 else 1, shadow)
            if auto_exposure[cam.name]:
                gain = 0.2 / max(float(np.median(radiance.mean(2))), 1e-3)
                gray = radiance.reshape(-1, 3).mean(0) + 1e-4
                wb = (gray.mean() / gray) ** 0.5
            else:
                gain, wb = base_gain[cam.name], np.ones(3)
            gain = float(np.clip(gain, 0.3, 8.0)) * (1 + rng_check.normal(0, 0.04))
            wb = wb * (1 + rng_check.normal(0, 0.02, 3))
            img = expose(radiance, sensors[cam.name], gain, wb, rng_check)
            path = name_dir / f"{cam.name}{suffix}"
            write_image(path, img, jpeg_quality)
            frames[cam.name] = path.relative_to(out).as_posix()
        return frames

    session["background"] = shoot(out / "background", None, -1)
    for i, ct in enumerate(checks_truth):
        d = out / "checks" / f"{i:03d}"
        d.mkdir(parents=True, exist_ok=True)
        session["checks"].append({"layer": ct["layer"], "z": ct["z"], "frames": shoot(d, ct["layer"], i)})

    m = part.to_mesh()
    trimesh.Trimesh(np.asarray(m.vert_properties)[:, :3], np.asarray(m.tri_verts), process=False).export(out / "model.stl")
    (out / "session.json").write_text(json.dumps(session, indent=1))
    truth = {
        "generator": "crosscheck/1", "seed": recipe.seed, "kind": kind, "onset_layer": onset,
        "shift_mm": None if shift is None else [round(float(v), 2) for v in shift],
        "detach": scene.detach_pose,
        "part": {**scene.part_info, "centre": [round(float(v), 1) for v in centre], "layers": scene.n_layers},
        "every": scene.every,
        "look": {"filament": scene.look["filament"], "calibration_error": recipe.calibration_error,
                 "filament_linear": [round(float(v), 3) for v in colour],
                 "bed": bed_kind, "light_elevation_deg": round(float(np.degrees(el)), 1),
                 "ambient": round(ambient, 2), "jpeg_quality": jpeg_quality, "park": list(park),
                 "gantry": gantry, "skirt": bool(skirt), "brim": bool(brim), "stringing": stringing,
                 "light_jitter": round(light_jitter, 3), "auto_exposure": auto_exposure, **rig},
        "checks": checks_truth,
        "onset_check": next((i for i, c in enumerate(checks_truth) if c["failure_started"]), None),
        "flag_check": flag_idx,
        "cameras_true": truth_cams, "pairs": pairs,
    }
    (out / "truth.json").write_text(json.dumps(truth, indent=1))
    return truth


def plan_kinds(count: int) -> list[str]:
    """A third normal prints, the rest spread evenly over the four failure kinds."""
    n_normal = round(count / 3)
    rest = count - n_normal
    kinds = ["normal"] * n_normal
    for i in range(rest):
        kinds.append(KINDS[1 + i % 4])
    return kinds
