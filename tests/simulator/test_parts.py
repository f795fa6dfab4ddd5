"""The built-in test parts: closed solids, and G-code sliced where the model says the part is."""
import re

import numpy as np
import pytest
import trimesh

from octoprint_printwatch.core.errors import GeometryError
from octoprint_printwatch.simulator.parts import GCODE_CENTER, LIBRARY_PARTS, library_gcode, library_part


@pytest.mark.parametrize("name", LIBRARY_PARTS)
def test_library_part_is_a_closed_solid_on_the_bed_centred_on_the_origin(name):
    mesh = trimesh.load(library_part(name), force="mesh")
    assert mesh.is_watertight and mesh.volume > 0
    lo, hi = mesh.bounds
    assert lo[2] == pytest.approx(0.0, abs=1e-4)
    assert 8.0 <= hi[2] <= 60.0
    assert np.allclose((lo[:2] + hi[:2]) / 2, 0.0, atol=1.5)  # gears with odd teeth are not symmetric


def extrusion_xy_at(gcode_text: str, z_target: float) -> np.ndarray:
    """(n, 2) end points of extruding moves on the layer at z_target (absolute or relative E)."""
    z = None
    points = []
    for line in gcode_text.splitlines():
        line = line.split(";")[0]
        if not line.startswith("G1"):
            continue
        zm = re.search(r"Z([-\d.]+)", line)
        if zm:
            z = float(zm.group(1))
        xm, ym, em = re.search(r"X([-\d.]+)", line), re.search(r"Y([-\d.]+)", line), re.search(r"E([-\d.]+)", line)
        if z is not None and abs(z - z_target) < 1e-3 and xm and ym and em and float(em.group(1)) > 0:
            points.append((float(xm.group(1)), float(ym.group(1))))
    return np.array(points)


@pytest.mark.parametrize("name", ["cube", "gear", "prism"])
def test_shipped_gcode_prints_the_part_where_the_placed_model_is(name):
    mesh = trimesh.load(library_part(name), force="mesh")
    mesh.apply_translation([GCODE_CENTER[0], GCODE_CENTER[1], 0])
    z = round(mesh.bounds[1][2] / 2 / 0.2) * 0.2
    xy = extrusion_xy_at(library_gcode(name).read_text(), z)
    assert len(xy) > 20
    section = mesh.section(plane_origin=[0, 0, z - 0.1], plane_normal=[0, 0, 1])
    lo, hi = section.bounds[0][:2], section.bounds[1][:2]
    # Perimeter centre lines sit half an extrusion width inside the model's outline.
    assert np.all(np.abs(xy.min(axis=0) - lo) < 0.6)
    assert np.all(np.abs(xy.max(axis=0) - hi) < 0.6)


def test_unknown_library_part_is_a_one_line_error():
    with pytest.raises(GeometryError, match="unknown library part 'boat'.*gear"):
        library_part("boat")
