"""Background removal, measured: which way of telling the part from the bed is right most often?

    .venv/bin/python benchmarks/bench_background.py [--data DIR] [--limit N]

Uses the normal (no failure) recordings that ``bench_detection.py`` renders (run it, or its
``--generate-only``, first). For every check and camera, the truth is the part's silhouette
rendered with the TRUE camera (``truth.json``) at the true printed height; each method's
material mask is compared with it inside the shape check's search region:

* part missed = truth pixels not marked (what would look like missing material),
* bed marked = non-part pixels marked, outside the bed-marks zone where skirt, brim and
  reflections are expected (what would look like extra material: shadows, exposure drift,
  strings, the hotend),
* IoU.

Methods: the seed's grey difference (threshold 30), a plain RGB distance with a threshold
from the measured noise, the same after exposure/white-balance normalisation, and
PrintWatch's :func:`~octoprint_printwatch.core.shape_check.material_evidence` (colour with
shading divided out, 1-px shake tolerance, darkening/texture trusted only near the
expected part) before and after the shape check's own clean-up (``check_shape``'s observed
mask, which also drops flat bed marks only when computing extra material, so it is not
used here). Prints a Markdown table.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from octoprint_printwatch.core.camera import Camera  # noqa: E402
from octoprint_printwatch.core.pipeline import prepare_job  # noqa: E402
from octoprint_printwatch.core.recording import load_recording  # noqa: E402
from octoprint_printwatch.core.render import render_silhouette  # noqa: E402
from octoprint_printwatch.core.settings import DetectionSettings  # noqa: E402
from octoprint_printwatch.core.masks import bounding_box  # noqa: E402
from octoprint_printwatch.core.material import clean_mask, material_evidence  # noqa: E402


def rgb_distance_mask(bg, fr, sample, gains=False):
    b, f = bg.astype(np.float32), fr.astype(np.float32)
    if gains:
        s_b, s_f = b[sample], f[sample]
        ok = s_b.min(axis=1) > 8
        if ok.sum() > 50:
            b = b * np.median(s_f[ok] / s_b[ok], axis=0)
    d = np.linalg.norm(f - b, axis=2)
    noise = max(2.0, float(np.percentile(d[sample], 90)))
    return d > 5.0 * noise


def methods(bg, fr, prior, sample):
    grey = cv2.absdiff(cv2.cvtColor(fr, cv2.COLOR_BGR2GRAY), cv2.cvtColor(bg, cv2.COLOR_BGR2GRAY)) > 30
    ev = material_evidence(bg, fr, prior, sample)
    return {
        "seed: grey difference > 30": grey,
        "RGB distance > 5x noise": rgb_distance_mask(bg, fr, sample),
        "RGB distance after exposure normalisation": rgb_distance_mask(bg, fr, sample, gains=True),
        "PrintWatch cues (chromaticity, shake-tolerant, prior)": ev.material,
        "PrintWatch cues + clean-up (morphology, hole filling)": clean_mask(ev.material, fill_like=prior),
        "PrintWatch strong cues only (what counts as extra)": clean_mask(ev.strong),
    }


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--data", default="/tmp/printwatch-bench-detection")
    parser.add_argument("--limit", type=int, default=18, help="normal recordings to use")
    args = parser.parse_args(argv)
    folders = sorted(p for p in Path(args.data).glob("normal_*") if (p / "truth.json").exists())[: args.limit]
    if not folders:
        print(f"no normal recordings in {args.data}: run benchmarks/bench_detection.py --generate-only first")
        return 1
    settings = DetectionSettings()
    totals: dict[str, list[float]] = {}
    looks = []
    n_views = 0
    for folder in folders:
        rec = load_recording(folder)
        truth = json.loads((folder / "truth.json").read_text())
        looks.append(truth["look"]["bed"] + "/" + truth["look"]["filament"])
        plan = prepare_job(gcode_path=rec.gcode, model_path=rec.model, cameras=rec.cameras,
                           check_heights=[(c.layer, c.z) for c in rec.checks], settings=settings)
        for check, t in zip(rec.checks, truth["checks"]):
            for name, cam in rec.cameras.items():
                bg, fr = rec.read_background(name), rec.read_frame(check, name)
                if bg is None or fr is None:
                    continue
                true_cam = Camera.from_dict(name, truth["cameras_true"][name])
                true_sil = render_silhouette(plan.part, true_cam, t["true_top_z"])
                regions = plan.regions(name, check.z, settings)
                box = bounding_box(regions.search | regions.silhouette, pad=10)
                if box is None or not true_sil.any():
                    continue
                crop = (slice(box[0], box[1]), slice(box[2], box[3]))
                exp = regions.silhouette[crop]
                dist = cv2.distanceTransform((~exp).astype(np.uint8), cv2.DIST_L2, 3)
                prior = dist <= regions.max_shift_px + regions.tolerance_px + 1
                sample = (dist > regions.max_shift_px + 2 * regions.tolerance_px + 4) & ~regions.dont_care[crop]
                part = true_sil[crop]
                # flat bed marks and reflections are judged separately (the bed-marks zone): leave them out
                judged = ~(regions.dont_care | regions.reflection)[crop] | part
                # one pixel either side of the true outline is blur, not a mistake of either kind
                edge = cv2.morphologyEx(part.astype(np.uint8), cv2.MORPH_GRADIENT, np.ones((3, 3), np.uint8)) > 0
                n_views += 1
                for label, mask in methods(bg[crop], fr[crop], prior, sample).items():
                    inter = np.count_nonzero(mask & part & ~edge)
                    union = np.count_nonzero((mask | part) & ~edge & judged)
                    missed = np.count_nonzero(part & ~mask & ~edge) / max(1, np.count_nonzero(part & ~edge))
                    false = (np.count_nonzero(mask & ~part & ~edge & judged)
                             / max(1, np.count_nonzero(~part & ~edge & judged)))
                    totals.setdefault(label, []).append((inter / max(union, 1), missed, false))
    print(f"# Background removal: {n_views} camera views from {len(folders)} normal recordings "
          f"({', '.join(sorted(set(looks)))})\n")
    print("| method | median IoU | p10 IoU | part missed (mean) | bed marked as material (mean) | "
          "views with > 5 % bed marked |")
    print("|---|---|---|---|---|---|")
    for label, values in totals.items():
        v = np.array(values)
        print(f"| {label} | {np.median(v[:, 0]):.3f} | {np.percentile(v[:, 0], 10):.3f} | "
              f"{v[:, 1].mean():.1%} | {v[:, 2].mean():.2%} | {np.mean(v[:, 2] > 0.05):.0%} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
