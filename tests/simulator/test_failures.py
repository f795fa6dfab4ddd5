"""Each injected failure changes what it claims, and its ground truth says so."""
import numpy as np
import pytest

from octoprint_printwatch.core.camera import Camera
from octoprint_printwatch.core.errors import PrintWatchError
from octoprint_printwatch.simulator.scenario import Scenario
from octoprint_printwatch.simulator.scene import PrintSimulator

from .helpers import clean_look, iou, part_mask, rig_of


def masks(sim, camera, heights):
    bg = sim.background(camera)
    return [part_mask(sim.frame(camera, z), bg) for z in heights]


def test_runout_part_stops_growing_at_the_onset_while_a_normal_print_grows(side_camera):
    rig = rig_of(side_camera)
    normal = PrintSimulator("cube", rig, clean_look(), "normal", seed=1)
    runout = PrintSimulator("cube", rig, clean_look(), Scenario("runout", onset_layer=41), seed=1)
    assert runout.onset_z == pytest.approx(8.0)
    at_onset, later, much_later = masks(runout, "side", [8.0, 12.0, 18.0])
    assert np.array_equal(at_onset, later) and np.array_equal(later, much_later)
    grown = masks(normal, "side", [18.0])[0]
    assert grown.sum() > 1.8 * much_later.sum()
    t = runout.truth(18.0)
    assert t["true_top_z"] == pytest.approx(8.0) and t["failure_started"] and t["should_flag"]
    assert not runout.truth(8.0)["failure_started"]
    # Just after the onset too little is missing to demand a flag.
    assert runout.truth(8.4) == {**runout.truth(8.4), "failure_started": True, "should_flag": False}


@pytest.mark.parametrize("dx,dy", [(4.0, 0.0), (-3.0, 2.0)])
def test_layer_shift_moves_everything_above_the_onset_by_the_given_millimetres(side_camera, dx, dy):
    sim = PrintSimulator("cube", rig_of(side_camera), clean_look(), Scenario("layer_shift", 31, shift_mm=(dx, dy)),
                         seed=1)
    mask = masks(sim, "side", [16.0])[0]
    low_row = side_camera.project([[100, 90, 3.0]])[0, 1]
    high_row = side_camera.project([[100, 90 + dy, 14.0]])[0, 1]  # above the horizon: backdrop behind
    low_cols = np.flatnonzero(mask[int(round(low_row))])
    high_cols = np.flatnonzero(mask[int(round(high_row))])
    # Image columns map to X: the upper part's left edge moved by dx (scaled by its distance).
    px_per_mm = side_camera.K[0, 0] / (390.0 + dy)
    assert (high_cols.min() - low_cols.min()) / px_per_mm == pytest.approx(dx, abs=0.3)
    assert (high_cols.max() - low_cols.max()) / px_per_mm == pytest.approx(dx, abs=0.3)
    assert sim.truth(16.0)["should_flag"] and not sim.truth(5.0)["failure_started"]


def test_detach_moves_the_part_and_leaves_spaghetti_where_it_was():
    camera = Camera.look_at("c", [100.0, 20.0, 150.0], [100.0, 100.0, 0.0], width=320, height=240, focal_px=420)
    rig = rig_of(camera)
    normal = PrintSimulator("gear", rig, clean_look(), "normal", seed=2)
    for mode in ("shifted", "tipped"):
        sim = PrintSimulator("gear", rig, clean_look(), Scenario("detach", 26, detach_mode=mode), seed=2)
        onset_z = sim.onset_z
        expected = masks(normal, "c", [onset_z])[0]
        before = masks(sim, "c", [onset_z])[0]
        assert np.array_equal(before, expected)
        after = masks(sim, "c", [onset_z + 0.4])[0]
        assert iou(after, expected) < 0.6, mode
        t = sim.truth(onset_z + 0.4)
        assert t["part_moved"] and t["should_flag"]
        # The nozzle keeps extruding into the air: the tangle on the bed grows.
        later = masks(sim, "c", [onset_z + 3.0])[0]
        assert (later & ~after).sum() > 200, mode


def test_spaghetti_grows_a_tangle_above_a_part_that_stopped():
    camera = Camera.look_at("c", [100.0, -80.0, 90.0], [100.0, 100.0, 8.0], width=320, height=240, focal_px=520)
    rig = rig_of(camera)
    sim = PrintSimulator("cylinder", rig, clean_look(), Scenario("spaghetti", 41), seed=3)
    normal = PrintSimulator("cylinder", rig, clean_look(), "normal", seed=3)
    stopped = masks(normal, "c", [8.0])[0]
    tangle_small, tangle_big = masks(sim, "c", [10.0, 16.0])
    assert (stopped & ~tangle_small).sum() < 0.02 * stopped.sum()  # the part is still there
    assert (tangle_small & ~stopped).sum() > 100
    assert (tangle_big & ~stopped).sum() > 2 * (tangle_small & ~stopped).sum()
    assert sim.truth(16.0)["true_top_z"] == pytest.approx(8.0)
    assert sim.truth(16.0)["should_flag"]


def test_under_extrusion_leaves_gaps_in_the_layers_above_the_onset(side_camera):
    rig = rig_of(side_camera)
    normal = PrintSimulator("cube", rig, clean_look(), "normal", seed=1)
    under = PrintSimulator("cube", rig, clean_look(), Scenario("under_extrusion", 51, under_extrusion=0.6), seed=1)
    z = 18.0
    a = normal.frame("side", z).astype(int).sum(axis=2)
    b = under.frame("side", z).astype(int).sum(axis=2)
    mask = masks(normal, "side", [z])[0]
    def rows(z_high, z_low):
        return slice(*(int(side_camera.project([[100, 90, z]])[0, 1]) for z in (z_high, z_low)))

    rows_above, rows_below = rows(17.0, 11.0), rows(9.0, 1.0)
    changed = np.abs(a - b) > 60
    assert changed[rows_above][mask[rows_above]].mean() > 0.10   # gaps in the upper walls
    assert changed[rows_below][mask[rows_below]].mean() < 0.01   # lower layers untouched
    assert under.truth(z)["should_flag"] and under.truth(z)["true_top_z"] == pytest.approx(z)


def test_bad_scenarios_are_one_line_errors():
    with pytest.raises(PrintWatchError, match="unknown scenario 'melt'"):
        Scenario("melt")
    with pytest.raises(PrintWatchError, match="beyond the part's last layer 100"):
        PrintSimulator("cube", None, None, Scenario("runout", onset_layer=500))
