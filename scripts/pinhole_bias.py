"""Why the focal table's x1 column (118 mm MRPE) is worse than the headline clean-2D row (91 mm): the virtual
cameras are ideal pinholes, while Human3.6M's own 2D (what every shipped network was trained on) carries its
cameras' lens distortion, which makes the 2D poses slightly smaller. A network that learned distorted sizes places
pinhole 2D (an undistorted photo, the app's rendered demo samples) nearer than the truth.

Prints, for Protocol 1's test frames (every ``--stride``-th): how the distorted 2D differs from the pinhole
re-projection of the same 3D (mean joint distance, median pose-scale ratio), and the default model's MPJPE, MRPE
and mean signed root-depth error on each, told ``source="clean"`` and ``"detected"``.

    python scripts/pinhole_bias.py [--h36m PATH] [--stride 50]
"""

from __future__ import annotations

import argparse

import numpy as np

from lifter import Lifter
from lifter.cli._help import add_h36m_arguments
from lifter.codec import Source
from lifter.data import H36M, default_h36m_dir
from lifter.evaluate import virtual_camera_samples
from lifter.metrics import mpjpe
from lifter.normalization import pose_scale


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    add_h36m_arguments(ap, stride=50)
    args = ap.parse_args()
    data = H36M(args.h36m or default_h36m_dir())
    lifter = Lifter.from_pretrained()
    s = data.load_protocol(1, "test", stride=args.stride)
    v = virtual_camera_samples(s, focal_scale=1.0)
    gt = s.pose_3d.astype(np.float64)
    dist, pin = s.keypoints_2d.astype(np.float64), v.keypoints_2d.astype(np.float64)
    print(f"{len(s)} test samples (every {args.stride}th frame): H36M's 2D vs the pinhole re-projection of the same "
          f"3D: mean joint distance {np.linalg.norm(dist - pin, axis=-1).mean():.2f} px, median pose-scale ratio "
          f"{np.median(pose_scale(dist) / pose_scale(pin)):.4f}")
    print(f"{'2D':26s} {'source':9s} {'MPJPE':>6s} {'MRPE':>6s}  mean signed root-depth error ({lifter.name!r})")
    sources: tuple[Source, ...] = ("clean", "detected")
    for name, kp, lens in (("H36M's (lens distortion)", dist, None),
                           ("H36M's, distortion given", dist, s.distortion),
                           ("pinhole re-projection", pin, None)):
        for src in sources:
            r = lifter.lift(kp, focal=s.focal, principal_point=s.principal_point, source=src, distortion=lens)
            dz = r.root[:, 2] - gt[:, 0, 2]
            print(f"{name:26s} {src:9s} {mpjpe(r.absolute, gt).mean():6.1f} "
                  f"{np.linalg.norm(r.root - gt[:, 0], axis=-1).mean():6.1f}  {dz.mean():+.0f} mm "
                  f"({100 * (dz / gt[:, 0, 2]).mean():+.2f} %)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
