"""What the printer, the filament, the lights and the webcam look like.

A :class:`Look` is plain data; :func:`random_look` draws a varied one for a seed
so benchmarks cover beds, colours and lighting the detector was not tuned on.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

BEDS = ("blue_tape", "black_pei", "gold_pei", "glass", "aluminium", "green_pei")
BACKDROPS = ("black", "grey", "white_wall", "frame", "cluttered")


@dataclass
class Filament:
    """Filament colour (sRGB 0..255) and optical character."""

    name: str = "red"
    rgb: tuple[int, int, int] = (200, 35, 30)
    glow: bool = False          # glow-in-the-dark PLA: pale, faintly emissive, translucent
    translucent: bool = False   # light passes through thin walls; edges look washed out
    gloss: float = 0.35         # specular strength (silk PLA ~0.8, matte PLA ~0.1)


FILAMENTS = {
    "red": Filament("red", (196, 30, 28)),
    "pink": Filament("pink", (236, 120, 170)),
    "orange": Filament("orange", (240, 110, 20)),
    "black": Filament("black", (28, 28, 30), gloss=0.45),
    "white": Filament("white", (232, 232, 226), gloss=0.25),
    "blue": Filament("blue", (40, 90, 200)),
    "grey": Filament("grey", (128, 130, 132)),
    "green": Filament("green", (40, 150, 60)),
    "glow": Filament("glow", (190, 225, 130), glow=True, translucent=True, gloss=0.2),
    "clear": Filament("clear", (210, 220, 225), translucent=True, gloss=0.6),
    "silk_gold": Filament("silk_gold", (205, 160, 60), gloss=0.9),
}


@dataclass
class Light:
    """A point light (an LED strip or a room lamp): position (mm, printer frame), strength, colour."""

    position: tuple[float, float, float]
    intensity: float = 1.0
    rgb: tuple[float, float, float] = (1.0, 1.0, 1.0)


@dataclass
class Nuisances:
    """Everything that makes a webcam frame differ from the ideal rendering. All on by default."""

    shadows: bool = True
    reflections: bool = True       # mirror image of the part on glossy beds
    skirt: bool = True             # skirt / brim / purge line / elephant's foot on the bed
    layer_lines: bool = True
    stringing: bool = True
    top_infill: bool = True        # the in-progress top shows perimeters and sparse infill
    over_extrusion_mm: float = 0.15  # walls stand this far proud of the model (plus a z-seam of blobs)
    hotend_probability: float = 0.2  # chance per frame that the parked hotend enters the top
    exposure_drift: float = 0.08   # relative auto-exposure change between frames (1 sigma)
    white_balance_drift: float = 0.04
    noise: float = 3.0             # sensor noise, 1 sigma in 8-bit units at mid grey
    blur: float = 0.8              # optics/focus blur, Gaussian sigma in pixels
    vignetting: float = 0.25       # corner darkening
    shake_px: float = 1.0          # frame-to-frame jitter of the whole image
    banding: float = 0.02          # PWM-dimmed LEDs beat with the rolling shutter: faint horizontal bands
    jpeg_quality: int = 80         # 0 = no JPEG round trip

    @classmethod
    def off(cls) -> "Nuisances":
        """Ideal camera and a clean print: for checking the renderer against geometry."""
        return cls(shadows=False, reflections=False, skirt=False, layer_lines=False, stringing=False,
                   top_infill=False, over_extrusion_mm=0.0, hotend_probability=0.0, exposure_drift=0.0,
                   white_balance_drift=0.0, noise=0.0, blur=0.0, vignetting=0.0, shake_px=0.0, banding=0.0,
                   jpeg_quality=0)


def seed_lights(bed: tuple[float, float] = (200.0, 200.0)) -> list[Light]:
    """The dissertation's three LED lights, one beside each camera station, 120 degrees apart."""
    cx, cy = bed[0] / 2.0, bed[1] / 2.0
    lights = []
    for k, strength in enumerate((1.0, 0.8, 0.9)):
        a = np.radians(-90.0 + 120.0 * k + 25.0)
        lights.append(Light((cx + 260 * np.cos(a), cy + 260 * np.sin(a), 180.0), strength))
    return lights


@dataclass
class Look:
    """Appearance of one print: bed surface, backdrop, filament, lights and webcam nuisances."""

    bed: str = "blue_tape"
    backdrop: str = "black"
    filament: Filament = field(default_factory=lambda: FILAMENTS["red"])
    lights: list[Light] | None = None   # None: the seed's three LEDs
    ambient: float = 0.35
    brim_mm: float = 0.0
    nuisances: Nuisances = field(default_factory=Nuisances)

    def lights_for(self, bed: tuple[float, float]) -> list[Light]:
        return self.lights if self.lights is not None else seed_lights(bed)

    def plain(self) -> "Look":
        """The same look with every nuisance off."""
        return replace(self, nuisances=Nuisances.off())


#: Named looks, including the hard cases the issue lists.
PRESETS = {
    "seed": Look(bed="blue_tape", backdrop="black", filament=FILAMENTS["pink"]),
    "black_on_black": Look(bed="black_pei", backdrop="black", filament=FILAMENTS["black"]),
    "white_on_glass": Look(bed="glass", backdrop="white_wall", filament=FILAMENTS["white"]),
    "blue_on_blue_tape": Look(bed="blue_tape", backdrop="grey", filament=FILAMENTS["blue"]),
    "glow": Look(bed="black_pei", backdrop="frame", filament=FILAMENTS["glow"]),
    "orange_on_gold": Look(bed="gold_pei", backdrop="cluttered", filament=FILAMENTS["orange"], brim_mm=4.0),
}


def random_look(seed: int, bed: tuple[float, float] = (200.0, 200.0)) -> Look:
    """A varied look for benchmarks: bed, backdrop, filament, light layout and strengths all drawn."""
    rng = np.random.default_rng([seed, 0x100C])
    cx, cy = bed[0] / 2.0, bed[1] / 2.0
    n_lights = int(rng.integers(1, 4))
    lights = []
    for _ in range(n_lights):
        a = rng.uniform(0, 2 * np.pi)
        r = rng.uniform(120, 350)
        lights.append(Light((cx + r * np.cos(a), cy + r * np.sin(a), float(rng.uniform(60, 400))),
                            float(rng.uniform(0.5, 1.3)),
                            tuple(float(c) for c in (1.0, rng.uniform(0.85, 1.0), rng.uniform(0.7, 1.05)))))
    return Look(
        bed=str(rng.choice(BEDS)),
        backdrop=str(rng.choice(BACKDROPS)),
        filament=FILAMENTS[str(rng.choice(sorted(FILAMENTS)))],
        lights=lights,
        ambient=float(rng.uniform(0.15, 0.55)),
        brim_mm=float(rng.choice([0.0, 0.0, 3.0, 5.0])),
        nuisances=Nuisances(noise=float(rng.uniform(1.5, 6.0)), blur=float(rng.uniform(0.5, 1.3)),
                            jpeg_quality=int(rng.integers(55, 92)),
                            exposure_drift=float(rng.uniform(0.03, 0.12)),
                            hotend_probability=float(rng.uniform(0.0, 0.35)),
                            banding=float(rng.choice([0.0, 0.0, 0.02, 0.05]))),
    )
