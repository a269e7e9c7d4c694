"""The same 2D lifted with a wrong focal length: how far the pose's shape (PA-MPJPE) moves as the focal length
given departs from the true one. Not the focal sweep of ``poselifter evaluate --focal-scales`` (there the 3D is
re-projected with each focal, so the 2D changes with it); here the image stays and only the focal told changes,
as with the app's focal slider.

A second table: how well paper Eq. 5-6 recovers the metric depth afterwards. With a wrong focal f_used, the root
depth rescaled by the true focal, ``Z * f_true / f_used``, against the Z lifted with the true focal (median ratio;
exactly 1 for the paper's pixel-space models, whose input does not depend on the focal length).

Protocol 1 test frames (S9, S11, every ``--stride``-th frame, 4 cameras), ground-truth 2D as ``source="clean"``,
true principal point; the focal given is the camera's times each factor. PA-MPJPE (mm) against the true pose.
Each camera's lens is undone at its own focal first for a network that learned pinhole 2D (the lens belongs to
that calibration; as the app does for its slider, ``app.core.lens_free_2d``); a network that learned H36M's
distorted 2D (``gt``) is given the 2D as it is.

    python scripts/wrong_focal.py [--stride 250] [--models default,gt] [--factors 0.1,0.25,0.5,1,2,4,6]
"""

from __future__ import annotations

import argparse
import warnings

import numpy as np

from lifter import Lifter, PoseLifterWarning
from lifter.cli._help import add_h36m_arguments
from lifter.data import H36M, default_h36m_dir
from lifter.metrics import pa_mpjpe


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    add_h36m_arguments(ap, stride=250)
    ap.add_argument("--models", default="default,gt")
    ap.add_argument("--factors", default="0.1,0.25,0.5,1,2,4,6")
    args = ap.parse_args()
    warnings.simplefilter("ignore", PoseLifterWarning)  # (the focal lengths are wrong on purpose)
    factors = [float(x) for x in args.factors.split(",")]
    s = H36M(args.h36m or default_h36m_dir()).load_protocol(1, "test", stride=args.stride)
    print(f"{len(s)} test samples (every {args.stride}th frame, 4 cameras); ground-truth 2D, source='clean'; "
          "PA-MPJPE mm with the focal length given = true focal x factor")
    print("| model | " + " | ".join(f"x{f:g}" for f in factors) + " |")
    print("|---|" + "---|" * len(factors))
    ratios: dict[str, list[str]] = {}
    for name in args.models.split(","):
        lifter = Lifter.load(name)
        kp = s.undistort(s.keypoints_2d) if lifter.lens == "pinhole" else s.keypoints_2d
        row = []
        for source in ("clean", "detected"):
            ratios[f"{lifter.name}, source={source!r}"] = []
        z_true = {source: lifter.lift(kp, focal=s.focal, principal_point=s.principal_point,
                                      source=source).root[:, 2] for source in ("clean", "detected")}
        for k in factors:
            for source in ("clean", "detected"):
                res = lifter.lift(kp, focal=s.focal * k, principal_point=s.principal_point, source=source)
                if source == "clean":
                    row.append(float(pa_mpjpe(res.absolute, s.pose_3d).mean()))
                ratios[f"{lifter.name}, source={source!r}"].append(
                    f"{float(np.median(res.root[:, 2] / k / z_true[source])):.3f}")
        print(f"| {lifter.name} | " + " | ".join(f"{v:.1f}" for v in row) + " |")
    print()
    print("Z * f_true / f_used over the Z lifted with the true focal (median; 1 = Eq. 5-6 exact)")
    print("| model | " + " | ".join(f"x{f:g}" for f in factors) + " |")
    print("|---|" + "---|" * len(factors))
    for label, row_r in ratios.items():
        print(f"| {label} | " + " | ".join(row_r) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
