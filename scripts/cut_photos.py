"""People cut off by the photo's edge: how far off is the lift, and does the record say so? Measured on the 84
Human3.6M demo photos with the default lifter.

    python scripts/cut_photos.py [--h36m ../shared/data/h36m] [--model default]

Each photo is lifted whole, then cut at the bottom (rows kept from the top, so the pixel coordinates, focal length
and principal point are unchanged) through the person's shins (halfway between the knees and ankles of the
ground-truth 2D) and through the thighs (halfway between the hips and knees), as a photo framed above the feet or
the knees would be. Each goes through :func:`lifter.pipeline.lift_image` (BlazePose, the detector's flip test, true
focal, principal point and lens), the person nearest the ground truth is kept, and the default's MPJPE, MRPE and
mean signed root-depth error (mm; + = too far) are printed, with the share of photos whose record has the
cut-off note (:func:`lifter.pipeline.detected_edge_notes`), that or the note naming joints the detector is unsure of
(:func:`lifter.pipeline.joint_doubt_notes`: legs it cannot see are often put inside the image, bunched, with low
scores), the misfit note, and any note at all (a cut through the thighs also leaves the principal point near or
outside the image's edge, which is noted). Nothing from Human3.6M is
written (the images stay in memory).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_cascade import demo_frames  # noqa: E402

from lifter.api import Lifter  # noqa: E402
from lifter.detect import NoPersonError, get_estimator, image_from_array  # noqa: E402
from lifter.metrics import mpjpe, root_errors  # noqa: E402
from lifter.pipeline import lift_image  # noqa: E402

CUTS = ("whole", "shins", "thighs")


def cut_row(gt2d: np.ndarray, cut: str, height: int) -> int:
    """The number of image rows kept for ``cut`` (``CUTS``), from the ground-truth 2D ``(17, 2)`` px."""
    hips, knees, ankles = (float(gt2d[[a, b], 1].mean()) for a, b in ((1, 4), (2, 5), (3, 6)))
    y = {"whole": float(height), "shins": (knees + ankles) / 2, "thighs": (hips + knees) / 2}[cut]
    return int(round(min(height, y)))


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--model", default="default")
    args = ap.parse_args()
    import torch
    from PIL import Image

    torch.set_num_threads(1)
    demo, ann, focal, pp, dist = demo_frames(args.h36m)
    gt2d, gt3d = ann["p2d_gt"].astype(np.float64), ann["p3d_cam"].astype(np.float64)
    lifter = Lifter.load(args.model)
    n = len(ann["image"])
    pred = {c: np.full((n, 17, 3), np.nan) for c in CUTS}
    noted = {c: np.zeros((n, 4), bool) for c in CUTS}  # cut-off note, cut-off or unsure-joint note, misfit, any
    t0 = time.perf_counter()
    with get_estimator("blazepose", max_people=3) as est:  # type: ignore[attr-defined]
        for i, rel in enumerate(ann["image"]):
            rgb = np.asarray(Image.open(demo / str(rel)).convert("RGB"))
            for c in CUTS:
                rows = cut_row(gt2d[i], c, rgb.shape[0])
                try:
                    rec = lift_image(image_from_array(rgb[:rows]), lifter=lifter, estimator=est, focal=focal[i],
                                     principal_point=pp[i], distortion=dist[i])
                except NoPersonError as exc:  # (nobody found: left out, counted)
                    print(f"  {rel} {c}: {type(exc).__name__}: {str(exc)[:80]}")
                    continue
                near = int(np.argmin([np.nanmedian(np.linalg.norm(q.keypoints_2d - gt2d[i], axis=-1))
                                      for q in rec.people]))
                pred[c][i] = rec.people[near].absolute
                w = list(rec.warnings)
                cut_off = any("cut off by the image's edge" in x for x in w)
                noted[c][i] = (cut_off, cut_off or any("the detector is unsure of" in x for x in w),
                               any("do not fit their 2D" in x for x in w), bool(w))
            if (i + 1) % 21 == 0:
                print(f"  {i + 1} of {n} photos, {time.perf_counter() - t0:.0f} s", flush=True)
    print(f"\n{n} Human3.6M demo photos, model {lifter.name}, BlazePose (flip test), true focal, principal point and "
          "lens; mm; 'paired': the photos found in every cut only")
    print(f"{'cut':15s} {'found':>5s} {'MPJPE':>6s} {'MRPE':>6s} {'Z bias':>7s} {'cut-off note':>12s} "
          f"{'or unsure joints':>16s} {'misfit note':>11s} {'any note':>8s}")
    every = np.all([~np.isnan(pred[c][:, 0, 0]) for c in CUTS], axis=0)  # (found in every cut: paired rows)
    rows = [(c, c, ~np.isnan(pred[c][:, 0, 0])) for c in CUTS] + [(c, f"{c}, paired", every) for c in CUTS]
    for c, label, ok in rows:
        m = float(np.mean(mpjpe(pred[c][ok], gt3d[ok])))
        mrpe = float(np.mean(root_errors(pred[c][ok, 0], gt3d[ok, 0])[0]))
        bias = float(np.mean(pred[c][ok, 0, 2] - gt3d[ok, 0, 2]))
        share = [f"{100 * float(np.mean(noted[c][ok, k])):.0f} %" for k in range(4)]
        print(f"{label:15s} {int(ok.sum()):5d} {m:6.1f} {mrpe:6.1f} {bias:+7.0f} {share[0]:>12s} "
              f"{share[1]:>16s} {share[2]:>11s} {share[3]:>8s}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
