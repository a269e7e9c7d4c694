"""How often the app's bone caution (``app.core.bone_caution``: a lifted bone outside 0.4-2x the demo body's) fires on
the default's lifts of Human3.6M test frames, and how good those lifts are.

    python scripts/bone_caution.py [--stride 50] [--h36m DIR]
"""

from __future__ import annotations

import argparse

import numpy as np
from poselifter_app.core import bone_caution

from lifter import Lifter
from lifter.cli._help import add_h36m_arguments
from lifter.data import H36M
from lifter.detections import with_sh_detections
from lifter.metrics import mpjpe


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_h36m_arguments(ap, stride=50)
    args = ap.parse_args()
    lf = Lifter.from_pretrained()
    data = H36M(args.h36m)
    clean = data.load_protocol(1, "test", stride=args.stride)
    detected, _ = with_sh_detections(clean, data=data)
    for name, s, source in (("exact 2D", clean, "clean"), ("SH detections", detected, "detected")):
        res = lf.lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point, distortion=s.distortion,
                      source=source, warn=False)
        flagged = np.array([bool(bone_caution(r)) for r in res.relative])
        gt = s.pose_3d - s.pose_3d[:, :1]
        err = mpjpe(res.relative, gt)
        print(f"{name}: {int(flagged.sum())} of {len(flagged)} lifts cautioned; MPJPE median "
              f"{np.median(err[flagged]):.1f} mm for those, {np.median(err):.1f} mm for all (Protocol 1, S9 + S11, "
              f"stride {args.stride})")


if __name__ == "__main__":
    main()
