"""A failing view that never saw the part whole is set aside where a view that did passes
(verdict.without_views_never_seen_whole, CheckRunner.decide_again).

What a user would notice: a normal print paused because one camera, looking at filament the colour of the bed or the
backdrop, laid the part's outline beside the part. Such a view separates only some faces of the part (the rest pass
for the bed), and the alignment lays the outline where it takes those in: on the dark side or the cast shadow, 5-26 px
off the part (cross-check seeds 30-33, ``benchmarks/outline_residual.py``). Held there, the view then reads the part
beside its outline as missing, extra, a displaced band or a layer shift, on its own, for the rest of the print: seed 31
``033_detach`` (a slim polygon in the bed's colour, two cameras) paused at eleven checks before its onset on s1 alone,
whose passing looks covered at most 0.34 of the part, while s0, which saw it whole, passed with nothing missing or
extra. A view that saw the part whole laid its outline where the part is, so a failure of the part shows there too;
a failure only such views read, a view's first look, and a rig with no view that saw the part whole fail as before."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from octoprint_printwatch.core.pipeline import evaluate_recording
from octoprint_printwatch.core.recording import load_recording
from octoprint_printwatch.core.settings import DetectionSettings
from octoprint_printwatch.core.shape_check import ShapeResult
from octoprint_printwatch.core.verdict import decide, without_views_never_seen_whole


def view(name: str, *, missing: float = 0.0, extra: float = 0.0) -> ShapeResult:
    """A view at its tenth look or so; failing decisively (missing AND extra: the part moved) where both are given."""
    failed = missing + extra > 7.0
    return ShapeResult(name, missing + extra, missing + extra, missing, extra, 0.0, 0.0, 500, 5000, 100.0, (0, 0),
                       7.0, 50.0, passed=not failed, usable=True, decisive=failed and missing > 0 and extra > 0,
                       reasons=[f"{name}: shape differs from the model"] if failed else [])


def checks_by_layer(recording: str) -> dict[int, dict]:
    """{layer: the check's evaluate document} of a cut recording in tests/data/recordings."""
    folder = Path(__file__).resolve().parent.parent / "data" / "recordings" / recording
    return {c["layer"]: c for c in evaluate_recording(load_recording(folder))["checks"]}


def decided(shape: dict[str, ShapeResult], seen: dict[str, float | None]) -> tuple[str, list[str]]:
    decision = dict(shape=shape, size={}, settings=DetectionSettings())
    verdict, reasons = decide(**decision)
    assert verdict == "fail"   # (each case below is a failing check before the rule)
    return without_views_never_seen_whole(decision, seen) or (verdict, reasons)


def test_a_view_that_saw_only_part_of_the_part_does_not_pause_the_print_alone():
    # seed 31 033_detach check 21: s1 reads the part beside its outline (missing on one side, extra on the other),
    # s0 passes with nothing missing or extra
    shape = {"s0": view("s0"), "s1": view("s1", missing=6.0, extra=9.3)}
    verdict, reasons = decided(shape, {"s0": 0.95, "s1": 0.34})
    assert verdict == "ok"
    assert any("s1: never saw the part whole" in r and "failing while s0 did and passes" in r for r in reasons)


def test_a_view_that_saw_the_part_whole_still_pauses_the_print():
    shape = {"s0": view("s0"), "s1": view("s1", missing=6.0, extra=9.3)}
    assert decided(shape, {"s0": 0.95, "s1": 0.9})[0] == "fail"
    # ... nor is a view set aside at its first look (no history: a part that detached before the first check)
    assert decided({**shape, "s1": replace(shape["s1"], first_look=True)}, {"s0": 0.95, "s1": None})[0] == "fail"


def test_without_a_view_that_saw_the_part_whole_and_passes_the_failure_stands():
    failing = view("s1", missing=6.0, extra=9.3)
    # a one-camera rig has no other view to ask
    assert decided({"s1": failing}, {"s1": 0.3})[0] == "fail"
    # the only passing view saw part of the part too
    assert decided({"s0": view("s0"), "s1": failing}, {"s0": 0.4, "s1": 0.3})[0] == "fail"
    # the view that saw the part whole passes against a relit background: no witness
    assert decided({"s0": replace(view("s0"), relit=True), "s1": failing}, {"s0": 0.95, "s1": 0.3})[0] == "fail"


def test_a_failure_the_views_that_saw_the_part_whole_read_too_stands():
    # three cameras: s1 never saw the part whole, s2 did, and both fail: the part moved, as s2 reads it
    shape = {"s0": view("s0"), "s1": view("s1", missing=6.0, extra=9.3), "s2": view("s2", missing=12.0, extra=8.0)}
    assert decided(shape, {"s0": 0.9, "s1": 0.3, "s2": 0.9})[0] == "fail"


def test_a_print_seen_partly_by_one_camera_is_not_paused_and_its_spaghetti_is():
    """Seed 30 ``042_spaghetti`` cut to s1 and s2 at layers 60, 80, 100, 120 and 200 (tests/data/SOURCES.md): a box in
    the bed's colour on glass. s1 sees only the part's own cast shadow on the lit glass beside its upper faces, lays
    the outline 24 px down on it and at layer 120 reads the part above it as 18 % "unexpected material"; s2 saw the
    part whole and passes. The spaghetti has begun by layer 200, and s2 reads it."""
    checks = checks_by_layer("box_like_bed_glass_shadow_pair")
    assert [checks[layer]["verdict"] for layer in (60, 80, 100, 120)] == ["ok"] * 4
    assert any("s1: never saw the part whole" in r for r in checks[120]["reasons"])
    assert checks[200]["verdict"] == "fail"


def test_a_stop_the_partial_view_reads_with_the_others_still_pauses_the_print():
    # the part stopped: no view reads it rising; s1 (never saw it whole) misses the newest layers the model expects,
    # s0 passes its shape check. The stall rule reads every view's rise and the missing material that corroborates
    # it, which rest on the part's own outline, not on where s1 laid the expected one.
    stopped = {"s0": replace(view("s0"), growth_pct=0.0), "s1": replace(view("s1", missing=10.0), growth_pct=0.0)}
    verdict, reasons = decided(stopped, {"s0": 0.95, "s1": 0.3})
    assert verdict == "fail" and any("has not grown" in r for r in reasons)


def test_a_layer_shift_read_only_by_a_view_that_never_saw_the_part_whole_does_not_pause_the_print():
    """Seed 27 ``001_normal`` cut to s1 at layers 11-55 (tests/data/SOURCES.md): a stack in the bed's colour on kapton.
    s1 cannot tell the part apart at its first two looks and sees only part of it after; at layer 55 it reads the
    newest layers "10.6 mm sideways" on the older ones, alone: the offset of the outline it laid by the faces it saw,
    not of the layers (8d1777c pauses this normal print there). A layer-shift reading is the newest band against the
    view's own outline, so a view that never saw the part whole gives none, with or without another view."""
    checks = checks_by_layer("stack_like_bed_kapton_one_view")
    assert checks[55]["verdict"] == "ok"
    assert any("s1: never saw the part whole" in r and "no layer-shift reading" in r for r in checks[55]["reasons"])


def test_a_layer_shift_read_only_by_a_view_a_partial_look_anchored_does_not_pause_the_print():
    """Seed 33 ``002_normal`` cut to s0 at layers 25-200 (tests/data/SOURCES.md): an L in the bed's colour on kapton.
    s0's first look separates 38 % of the part and lays the outline 7 px beside it, where the anchor then holds it; its
    later looks see up to 79 % of the part, so the view "saw it whole", but the outline stays where the first look put
    it. At layer 150 it reads the newest layers "3.6 mm sideways" on the older ones, alone: the offset of its outline,
    not of the layers (b612c46 pauses this normal print there). A layer-shift reading is the newest band against the
    view's own outline, so a view whose anchor a partial look laid gives none. The view is the only one reading a
    shift: the check decided again without it reads none, and must not read it back from every view."""
    checks = checks_by_layer("L_like_bed_kapton_partly_anchored")
    assert [c["verdict"] for c in checks.values()] == ["ok"] * 8
    assert any("s0: its outline was anchored by a look that saw under" in r and "no layer-shift reading" in r
               for r in checks[150]["reasons"])
