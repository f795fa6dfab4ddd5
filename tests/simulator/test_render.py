"""The renderer against geometry, determinism, and nuisances that change only what they claim."""
import numpy as np
import pytest
import trimesh

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.simulator.parts import library_part
from octoprint_printwatch.simulator.rig import make_rig
from octoprint_printwatch.simulator.scene import PrintSimulator

from .helpers import clean_look, iou, part_mask, reference_silhouette, rig_of


def placed(name):
    mesh = trimesh.load(library_part(name), force="mesh")
    mesh.apply_translation([100.0, 100.0, 0.0])
    return mesh


@pytest.mark.parametrize("name,z", [("gear", 6.0), ("twisted_vase", 23.4), ("prism", 18.0)])
def test_clean_frame_shows_exactly_the_partial_solid_through_a_distorting_lens(name, z):
    rig = make_rig("pair", seed=5, width=320, height=240, target_z=8.0)
    sim = PrintSimulator(name, rig, clean_look(), "normal", seed=5)
    mesh = placed(name)
    for camera in rig.cameras_true:
        assert np.any(camera.dist)  # real barrel distortion is on
        got = part_mask(sim.frame(camera.name, z), sim.background(camera.name))
        want = reference_silhouette(camera, mesh, z)
        assert want.sum() > 1500
        assert iou(got, want) > 0.96, camera.name
        # The height of the silhouette, not only its area: top rows agree within a pixel.
        assert abs(np.argmax(got.any(axis=1)) - np.argmax(want.any(axis=1))) <= 1


def test_partial_solid_is_the_part_below_the_nominal_height(side_camera):
    sim = PrintSimulator("cube", rig_of(side_camera), clean_look(), "normal", seed=1)
    bg = sim.background("side")
    for z in (4.0, 10.0, 16.0):
        rows = np.flatnonzero(part_mask(sim.frame("side", z), bg).any(axis=1))
        # The 20 mm cube spans y 90..110; the highest visible edge is the front or back top edge.
        edges = side_camera.project([[100, 90, z], [100, 110, z], [100, 90, 0.0]])
        top, bottom = min(edges[0, 1], edges[1, 1]), edges[2, 1]
        assert rows.min() == pytest.approx(top, abs=1.0), z
        assert rows.max() == pytest.approx(bottom, abs=1.0), z


def test_same_seed_same_frames_other_seed_other_frames():
    a = PrintSimulator("gear", make_rig("single", seed=2, width=320, height=240), None, "spaghetti", seed=2)
    b = PrintSimulator("gear", make_rig("single", seed=2, width=320, height=240), None, "spaghetti", seed=2)
    c = PrintSimulator("gear", make_rig("single", seed=3, width=320, height=240), None, "spaghetti", seed=3)
    z = 9.0
    fa, fb = a.frame("cam0", z, 4), b.frame("cam0", z, 4)
    assert np.array_equal(fa, fb)
    assert np.array_equal(a.background("cam0"), b.background("cam0"))
    assert not np.array_equal(fa, c.frame("cam0", z, 4))
    assert a.truth(z) == b.truth(z)


def test_webcam_frames_drift_between_checks_of_an_unchanged_scene():
    sim = PrintSimulator("cube", make_rig("single", seed=4, width=320, height=240), "seed", "normal", seed=4)
    f1 = sim.frame("cam0", 6.0, 1).astype(float)
    f2 = sim.frame("cam0", 6.0, 2).astype(float)
    diff = np.abs(f1 - f2)
    assert diff.mean() > 1.0          # noise, exposure, white balance, shake
    assert np.median(diff) < 40       # ... but still the same scene


def test_skirt_is_in_print_frames_and_never_in_the_background():
    camera = Camera.look_at("top", [100.0, 60.0, 220.0], [100.0, 100.0, 0.0], width=320, height=240, focal_px=500)
    plain = PrintSimulator("cube", rig_of(camera), clean_look(), "normal", seed=1)
    skirted = PrintSimulator("cube", rig_of(camera), clean_look(skirt=True), "normal", seed=1)
    bg = skirted.background("top")
    assert np.array_equal(bg, plain.background("top"))
    part = part_mask(plain.frame("top", 5.0), bg)
    extra = part_mask(skirted.frame("top", 5.0), bg) & ~part
    assert extra.sum() > 150  # the skirt ring and the purge line


def test_shadows_darken_the_bed_beside_the_part_only():
    camera = Camera.look_at("c", [100.0, -60.0, 160.0], [100.0, 100.0, 0.0], width=320, height=240, focal_px=420)
    lit = PrintSimulator("tower", rig_of(camera), clean_look(), "normal", seed=1)
    shaded = PrintSimulator("tower", rig_of(camera), clean_look(shadows=True), "normal", seed=1)
    bg = lit.background("c")
    part = part_mask(lit.frame("c", 40.0), bg)
    frame = shaded.frame("c", 40.0).astype(int)
    darker = (bg.astype(int).sum(axis=2) - frame.sum(axis=2) > 20) & ~part
    assert darker.sum() > 300
    assert np.array_equal(shaded.background("c"), bg)  # no part, no shadow


def test_a_gcode_part_renders_like_the_mesh_it_was_sliced_from():
    from octoprint_printwatch.simulator.parts import library_gcode

    rig = make_rig("single", seed=6, width=320, height=240)
    from_mesh = PrintSimulator("prism", rig, clean_look(), "normal", seed=6)
    from_gcode = PrintSimulator(str(library_gcode("prism")), rig, clean_look(), "normal", seed=6)
    assert from_gcode.gcode_path == library_gcode("prism")
    bg = from_mesh.background("cam0")
    for z in (5.0, 12.0):
        a = part_mask(from_mesh.frame("cam0", z), bg)
        b = part_mask(from_gcode.frame("cam0", z), bg)
        assert iou(a, b) > 0.93


def test_clean_frame_matches_the_detectors_expected_silhouette():
    """The simulator and core.render (what the checks compare against) agree on what a camera sees."""
    from octoprint_printwatch.core.geometry import part_from_mesh
    from octoprint_printwatch.core.render import render_silhouette

    rig = make_rig("stations3", seed=9, width=320, height=240)
    sim = PrintSimulator("sun_gear", rig, clean_look(), "normal", seed=9)
    part = part_from_mesh(placed("sun_gear"))
    for name in ("cam0L", "cam1R", "cam2L"):
        camera = rig.true(name)
        for z in (4.0, 11.0):
            got = part_mask(sim.frame(name, z), sim.background(name))
            want = render_silhouette(part, camera, z).astype(bool)
            assert iou(got, want) > 0.95, (name, z)


@pytest.mark.parametrize("look", ["seed", "black_on_black", "white_on_glass", "blue_on_blue_tape"])
def test_with_every_nuisance_on_the_part_still_stands_out_from_the_background(look):
    """Hostile, not absurd: the printed part changes its pixels far more than noise, drift and shadows do."""
    rig = make_rig("single", seed=8, width=320, height=240)
    sim = PrintSimulator("cylinder", rig, look, "normal", seed=8)
    camera = rig.true("cam0")
    frame, bg = sim.frame("cam0", 15.0, 3).astype(int), sim.background("cam0").astype(int)
    diff = np.abs(frame - bg).sum(axis=2)
    inside = reference_silhouette(camera, placed("cylinder"), 15.0)
    near = np.zeros_like(inside)
    ys, xs = np.nonzero(inside)
    near[max(ys.min() - 40, 0):ys.max() + 40, max(xs.min() - 60, 0):xs.max() + 60] = True
    outside = near & ~inside
    assert np.median(diff[inside]) > 2.5 * np.median(diff[outside]) + 10
    assert np.median(diff[outside]) > 0  # ... and the rest is not a perfect copy of the background
