"""Fixtures for the geometry area: corpus files and parts built once per session."""
from pathlib import Path

import pytest

GCODE = Path(__file__).resolve().parents[1] / "data" / "gcode"

#: G-code files of the corpus and the STL each was sliced from (tests/data/gcode/README.md).
SLICED_FROM = {
    "prusa25_cylinder.gcode": "cylinder.stl",
    "prusa25_pyramid_fwretract.gcode": "pyramid.stl",
    "prusa25_sun_gear_zhop_relative_e.gcode": "sun_gear.stl",
    "prusa25_twisted_vase_spiral.gcode": "twisted_vase.stl",
    "prusa25_two_cubes.gcode": "cube.stl",
    "slic3r13_cube.gcode": "cube.stl",
    "cura413_ender3_sun_gear.gcode": "sun_gear.stl",
    "cura413_ender3_t55_gear_relative_e_zhop.gcode": "t55_gear.stl",
    "cura413_ender3_pyramid_adaptive_layers.gcode": "pyramid.stl",
}


@pytest.fixture(scope="session")
def corpus() -> Path:
    return GCODE


@pytest.fixture(scope="session")
def gcode_part():
    """build(name) -> GcodePart, memoised for the session (building takes seconds)."""
    from octoprint_printwatch.core.toolpath_solid import build_gcode_part

    built = {}

    def build(name: str):
        if name not in built:
            built[name] = build_gcode_part(GCODE / name)
        return built[name]

    return build
