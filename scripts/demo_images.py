"""The five shipped demo images (a rendered mannequin, ``lifter.demo_sample(name)``: exact 2D and 3D) through the
cascade ``poselifter lift`` runs: BlazePose, then the default lifter, with each image's true focal length and
principal point. Needs the ``detect`` extra (mediapipe); no Human3.6M data.

    python scripts/demo_images.py [--out docs/results/demo_images.txt]

Per image: the detector's 2D error against the rendered truth (px, median over the 17 joints; and with the
detection's left and right swapped, which is lower when the detector took the figure's left for its right),
MPJPE / PA-MPJPE / MRPE (mm) of the lift, and the notes the record carries. The mannequin has no face, so its
facing direction is a guess for the detector.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import emit  # noqa: E402  (scripts/_report.py)

NAMES = ("walking", "standing", "sitting", "crouching", "reaching")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=None, help="also write the report here")
    args = ap.parse_args(argv)

    import lifter
    from lifter.detect import get_estimator
    from lifter.metrics import mpjpe, pa_mpjpe
    from lifter.pipeline import lift_image
    from lifter.resources import asset
    from lifter.skeleton import FLIP_PERMUTATION

    lf = lifter.Lifter.from_pretrained()
    est = get_estimator("blazepose")
    rows = ["| image | focal px | 2D error px (median) | with left / right swapped | MPJPE | PA-MPJPE | MRPE | notes |",
            "|---|---|---|---|---|---|---|---|"]
    for name in NAMES:
        s = lifter.demo_sample(name)
        rec = lift_image(asset(f"demo/{name}.jpg"), lifter=lf, estimator=est, focal=s.focal,
                         principal_point=s.principal_point, max_people=1)
        kp, gt2 = np.asarray(rec.keypoints_2d), np.asarray(s.keypoints_2d)
        e2 = float(np.median(np.linalg.norm(kp - gt2, axis=-1)))
        e2_swap = float(np.median(np.linalg.norm(kp[list(FLIP_PERMUTATION)] - gt2, axis=-1)))
        gt = np.asarray(s.pose_3d)
        pred = np.asarray(rec.absolute)
        rel, rel_gt = pred - pred[:1], gt - gt[:1]
        m, pa = float(mpjpe(rel, rel_gt)), float(pa_mpjpe(rel, rel_gt))
        mrpe = float(np.linalg.norm(np.asarray(rec.root) - gt[0]))
        notes = "; ".join(w.split(":")[0] for w in rec.warnings) or "none"
        rows.append(f"| {name} | {float(np.mean(s.focal)):.0f} | {e2:.1f} | {e2_swap:.1f} | {m:.1f} | {pa:.1f} | "
                    f"{mrpe:.1f} | {notes} |")
    emit("\n".join(["Demo images through BlazePose and the default lifter (true focal and principal point); mm, px:",
                    "", *rows]), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
