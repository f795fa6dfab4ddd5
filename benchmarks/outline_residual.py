"""How far each camera's aligned outline lies off the part: the shift the alignment chose less the true one.

    # replay seed 30's recordings 039 and 042 with this code tree, every check and camera
    .venv/bin/python benchmarks/outline_residual.py --root /tmp/pw --seeds 30 --only 039_layer_shift,042
    # read an earlier replay instead (crosscheck_sets.py replay's RESULTS/TAG_sN.json), summary only
    .venv/bin/python benchmarks/outline_residual.py --seeds 30-33 --results /tmp/pw/res --tag b27 --summary

The cross-check recordings (docs/crosscheck.md) state a calibration the detector uses (``session.json``) and keep
the cameras that rendered the frames (``truth.json`` ``cameras_true``). The image offset between the two at the part
is where a calibrated alignment would lay the outline: the part's centre (``truth.json`` part centre, at
:data:`CENTRE_HEIGHT_SHARE` of the check's height) projected through the true camera less through the stated one,
both at the detector's working size (``pipeline.working_camera``). The **residual** is the camera's
``shift_px`` (ShapeResult) less that offset: within 1-2 px for a calibrated outline (the offset varies over the
part's height and the alignment is whole pixels), larger where the outline slid off the part. The part's centre
is where it stood before any failure: after an onset a detached or shifted part is elsewhere, so the summary
splits by the onset.

Printed per recording, check and camera: the shift, the true offset, the residual, pass/fail, missing / extra %,
``like-bed`` where the filament is the bed's colour (``truth.json`` look); then the share of usable camera-checks
with a residual over :data:`FAR_PX`, split by filament (like the bed or not), by verdict and by the onset.
"""
from __future__ import annotations

import argparse
import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE / "benchmarks"))

from octoprint_printwatch.core.camera import Camera  # noqa: E402
from octoprint_printwatch.core.pipeline import working_camera  # noqa: E402
from octoprint_printwatch.core.settings import DetectionSettings  # noqa: E402

from crosscheck_sets import parse_seeds  # noqa: E402  (the same seed lists as the replays)

#: the point whose image offset stands for the whole outline's: the part's centre at this share of the check's
#: height (the alignment fits the whole visible part, whose middle lies about there for a part seen from the side)
CENTRE_HEIGHT_SHARE = 0.7
#: a residual over this many pixels is an outline laid off the part (the method's own noise is 1-2 px; the
#: twenty-sixth session's trace: calibrated views within 3 px, misplaced ones 5-26 px)
FAR_PX = 8.0


@dataclass
class Row:
    """One camera at one check of one recording."""
    seed: str
    name: str
    check: int
    camera: str
    like_bed: bool
    after_onset: bool
    usable: bool
    passed: bool
    shift: tuple[int, int] | None
    truth: tuple[float, float] | None
    missing: float | None
    extra: float | None

    @property
    def residual(self) -> tuple[float, float] | None:
        if self.shift is None or self.truth is None:
            return None
        return self.shift[0] - self.truth[0], self.shift[1] - self.truth[1]

    @property
    def residual_px(self) -> float | None:
        r = self.residual
        return None if r is None else float(np.hypot(*r))


def true_offset(stated: Camera, true: Camera, point: np.ndarray, working_width: int) -> tuple[float, float] | None:
    """(dx, dy) px at the detector's working size by which ``point`` (3,) mm appears moved in the ``true`` camera
    against the ``stated`` one: where a calibrated alignment lays the outline. None where either projection fails."""
    a = working_camera(stated, working_width).project(point[None, :])[0]
    b = working_camera(true, working_width).project(point[None, :])[0]
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b))):
        return None
    return float(b[0] - a[0]), float(b[1] - a[1])


def recording_rows(folder: Path, checks: list[dict], seed: str = "",
                   working_width: int | None = None) -> list[Row]:
    """Every camera's row at every check of one recording (``checks``: the evaluation's per-check documents,
    ``evaluate_recording(...)["checks"]`` or a replay's)."""
    truth = json.loads((folder / "truth.json").read_text())
    session = json.loads((folder / "session.json").read_text())
    width = DetectionSettings().working_width if working_width is None else working_width
    stated = {n: Camera.from_dict(n, d) for n, d in session["cameras"].items()}
    true = {n: Camera.from_dict(n, {**session["cameras"][n], **d}) for n, d in truth.get("cameras_true", {}).items()
            if n in session["cameras"]}
    like_bed = truth.get("look", {}).get("filament") == "like bed"
    centre = truth["part"]["centre"]
    truth_checks = truth.get("checks", [])
    rows = []
    for i, check in enumerate(checks):
        z = float(check.get("z") or (truth_checks[i]["z"] if i < len(truth_checks) else 0.0))
        point = np.array([centre[0], centre[1], CENTRE_HEIGHT_SHARE * z], np.float64)
        after = bool(truth_checks[i].get("failure_started")) if i < len(truth_checks) else False
        for cam, fig in sorted((check.get("shape") or {}).items()):
            offset = true_offset(stated[cam], true[cam], point, width) if cam in true and cam in stated else None
            shift = fig.get("shift_px")
            rows.append(Row(seed, folder.name, i, cam, like_bed, after, bool(fig.get("usable", True)),
                            bool(fig.get("passed", True)), tuple(shift) if shift is not None else None, offset,
                            fig.get("missing_pct"), fig.get("extra_pct")))
    return rows


def row_text(row: Row) -> str:
    def pair(p):
        return "-" if p is None else f"({p[0]:+.1f}, {p[1]:+.1f})"
    if not row.usable:
        return f"  {row.check:2d} {row.camera:4s} unusable"
    far = row.residual_px is not None and row.residual_px > FAR_PX
    return (f"  {row.check:2d} {row.camera:4s} shift {pair(row.shift):16s} truth {pair(row.truth):16s} "
            f"residual {pair(row.residual):16s}{' FAR' if far else '    '} {'pass' if row.passed else 'FAIL'} "
            f"miss {row.missing} extra {row.extra}{'  like-bed' if row.like_bed else ''}"
            f"{'  after onset' if row.after_onset else ''}")


def summary(rows: list[Row]) -> str:
    """The share of usable camera-checks with a residual over FAR_PX, by filament, verdict and onset."""
    lines = [f"usable camera-checks with a residual over {FAR_PX:.0f} px (share):"]
    usable = [r for r in rows if r.usable and r.residual_px is not None]
    for onset_label, after in (("before onset", False), ("after onset", True)):
        for bed_label, like in (("like-bed", True), ("others", False)):
            cells = []
            for verdict_label, passed in (("pass", True), ("fail", False), ("all", None)):
                sel = [r for r in usable if r.after_onset == after and r.like_bed == like
                       and (passed is None or r.passed == passed)]
                far = sum(r.residual_px > FAR_PX for r in sel)
                cells.append(f"{verdict_label} {far}/{len(sel)}"
                             + (f" ({100.0 * far / len(sel):.1f} %)" if sel else ""))
            lines.append(f"  {onset_label:12s} {bed_label:8s} " + "; ".join(cells))
    sel = [r.residual_px for r in usable if not r.after_onset]
    if sel:
        lines.append(f"  before onset, all: median {np.median(sel):.1f} px, 90th percentile "
                     f"{np.percentile(sel, 90):.1f} px, over {FAR_PX:.0f} px {sum(v > FAR_PX for v in sel)}/{len(sel)}")
    return "\n".join(lines)


def _evaluate(folder: Path) -> list[dict]:
    from octoprint_printwatch.core.pipeline import evaluate_recording
    from octoprint_printwatch.core.recording import load_recording
    return evaluate_recording(load_recording(folder))["checks"]


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--root", default="/tmp/pw", help="recordings in ROOT/sN/<name>/")
    p.add_argument("--seeds", required=True, help="e.g. 30,31 or 30-33")
    p.add_argument("--only", default="", help="comma-separated name prefixes (e.g. 039,042_spaghetti)")
    p.add_argument("--results", default="", help="read crosscheck_sets.py replay results RESULTS/TAG_sN.json "
                   "instead of evaluating with this code tree")
    p.add_argument("--tag", default="", help="with --results: the replay's tag")
    p.add_argument("--summary", action="store_true", help="print the summary only")
    p.add_argument("--far-only", action="store_true", help="print only recordings with a residual over FAR_PX")
    args = p.parse_args(argv)
    only = [o for o in args.only.split(",") if o]
    rows: list[Row] = []
    for seed in parse_seeds(args.seeds):
        base = Path(args.root) / f"s{seed}"
        if args.results:
            replay = json.loads((Path(args.results) / f"{args.tag}_s{seed}.json").read_text())
            checks_of = {r["name"]: r["checks"] for r in replay if "checks" in r}
        else:
            checks_of = None
        for folder in sorted(f for f in base.iterdir() if (f / "truth.json").exists()):
            if only and not any(folder.name.startswith(o) for o in only):
                continue
            checks = checks_of.get(folder.name) if checks_of is not None else _evaluate(folder)
            if checks is None:
                continue
            these = recording_rows(folder, checks, seed)
            rows += these
            if args.summary:
                continue
            if args.far_only and not any(r.usable and (r.residual_px or 0) > FAR_PX for r in these):
                continue
            print(f"s{seed} {folder.name}")
            for r in these:
                print(row_text(r))
            sys.stdout.flush()
    print(summary(rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
