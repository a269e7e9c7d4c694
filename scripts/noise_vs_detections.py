"""The app's noise slider against real detections: how the default lifts 2D drawn from the fitted Gaussian + uniform
mixture, next to the real Stacked-Hourglass detections of the same frames.

    python scripts/noise_vs_detections.py [--h36m ../shared/data/h36m] [--stride 100] [--seed 0]

S9 + S11, all four cameras, every ``--stride``-th frame with an SH detection. For each 2D input: its mean and median
2D error (px, against the ground-truth 2D), its 2D spread relative to the ground truth's (RMS distance of the joints
from their mean), and the default's MPJPE, MRPE (mean and median) and mean signed root-depth error (mm, + = too far),
each frame with its true focal length, principal point and lens. The noisy inputs are the ground-truth 2D with draws
from the shipped error models (``lifter.noise.ErrorModel.shipped``) at the slider's levels, lifted as the app lifts
them (``source="detected"``), the SH mixture's draws without their uniform outliers (the authors' sampling), and the
ground truth itself, lifted as detected 2D, as it is and scaled about its mean to the size of each frame's detection
(the 2D spread's ratio): the detection's size without its errors.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter.api import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detections import load_sh_detections  # noqa: E402
from lifter.metrics import mpjpe  # noqa: E402
from lifter.noise import ErrorModel  # noqa: E402


def spread(kp: np.ndarray) -> np.ndarray:
    """RMS distance of the joints from their mean, ``(..., 17, 2)`` px -> ``(...)`` px."""
    return np.sqrt(((kp - kp.mean(-2, keepdims=True)) ** 2).sum(-1).mean(-1))


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--stride", type=int, default=100)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--model", default="default")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    data = H36M(args.h36m or default_h36m_dir())
    s = data.load([9, 11], stride=args.stride)
    det, ok = load_sh_detections(s, data=data)
    s, det = s.subset(np.flatnonzero(ok)), det[ok]
    lifter = Lifter.load(args.model)
    gt2, gt3 = s.keypoints_2d.astype(np.float64), s.pose_3d.astype(np.float64)
    rng = np.random.default_rng(args.seed)
    ratio = spread(det) / spread(gt2)  # each detection's 2D size against its ground truth's
    mean = gt2.mean(-2, keepdims=True)
    rows: list[tuple[str, np.ndarray]] = [("real SH detections", det), ("ground truth, no noise", gt2),
                                          ("ground truth scaled to each detection's 2D size, no noise",
                                           mean + (gt2 - mean) * ratio[:, None, None])]
    for name in ("sh_mixture", "blazepose_demo_train"):
        model = ErrorModel.shipped(name)
        for level in (0.5, 1.0):
            rows.append((f"ground truth + `{name}` draws, level {level:g}", model.sample(gt2, level=level, rng=rng)))
        if name == "sh_mixture":
            rows.append((f"ground truth + `{name}` draws, level 1, no outliers",
                         model.sample(gt2, level=1.0, rng=rng, outliers=False)))
    print(f"S9 + S11, every {args.stride}th frame with an SH detection, 4 cameras: {len(s)} samples; model "
          f"{lifter.name}, source=\"detected\"; seed {args.seed}\n")
    print("| 2D | 2D error px, mean / median | 2D spread / truth's | MPJPE mm | MRPE mm, mean / median "
          "| root Z bias mm |")
    print("|---|---|---|---|---|---|")
    for label, kp in rows:
        pred = lifter.lift(kp, focal=s.focal, principal_point=s.principal_point, source="detected",
                           distortion=s.distortion).absolute
        e2 = np.linalg.norm(kp - gt2, axis=-1)
        re = np.linalg.norm(pred[:, 0] - gt3[:, 0], axis=-1)
        print(f"| {label} | {e2.mean():.1f} / {np.median(e2):.1f} | {float(np.mean(spread(kp) / spread(gt2))):.3f} | "
              f"{float(mpjpe(pred, gt3).mean()):.1f} | {re.mean():.1f} / {np.median(re):.1f} | "
              f"{float((pred[:, 0, 2] - gt3[:, 0, 2]).mean()):+.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
