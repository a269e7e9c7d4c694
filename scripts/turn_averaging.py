"""Test-time averaging over turned cameras: does it move the SH-detection line of issue 11 (MPJPE <= 66 mm)?

    python scripts/turn_averaging.py [--stride 25] [--deg 5] [--roll] [--model default] [--h36m ../shared/data/h36m]

A camera turned about its centre sees the same rays (:func:`lifter.evaluate.turned_camera_samples`: the 3D turned,
the 2D, detections included, moved by the homography ``K R K^-1``), so lifting each turned view and turning its 3D
back is an exact symmetry of the physics, and averaging the absolute 3D over the views is a test-time ensemble. The
default's networks were trained with the camera turned by up to +-20 deg of pan and tilt. Views: the camera as
recorded, then pan +-``deg`` and tilt +-``deg`` (``--roll``: roll +-``deg`` about the optical axis and pan +-``deg``).
Prints MPJPE / PA-MPJPE / MRPE (mm) and the mean signed root-depth error of the average over the first 1, 3 and 5
views, on the SH detections (told detected) and the ground-truth 2D (told clean), S9 + S11, Protocol 1.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter import Lifter  # noqa: E402
from lifter.camera import camera_turn  # noqa: E402
from lifter.cli._help import add_h36m_arguments  # noqa: E402
from lifter.data import H36M  # noqa: E402
from lifter.detections import with_sh_detections  # noqa: E402
from lifter.evaluate import predict, score, turned_camera_samples  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--deg", type=float, default=5.0, help="the turn of each view, degrees")
    ap.add_argument("--roll", action="store_true", help="roll and pan views instead of pan and tilt")
    ap.add_argument("--model", default="default")
    add_h36m_arguments(ap, stride=25)
    args = ap.parse_args()
    data = H36M(args.h36m)
    gt = data.load_protocol(1, "test", stride=args.stride)
    sh, _ = with_sh_detections(gt, data=data)
    m = Lifter.load(args.model)
    d = args.deg
    turns = ([(0, 0, 0), (0, 0, d), (0, 0, -d), (d, 0, 0), (-d, 0, 0)] if args.roll else
             [(0, 0, 0), (d, 0, 0), (-d, 0, 0), (0, d, 0), (0, -d, 0)])
    print(f"{m.name}, Protocol 1 test, stride {args.stride}; views (pan, tilt, roll deg): {turns}")
    for name, samples, source in (("SH detections", sh, "detected"), ("GT 2D, told clean", gt, "clean")):
        base = turned_camera_samples(samples, pan_deg=0, tilt_deg=0)
        views = []
        for pan, tilt, roll in turns:
            v = turned_camera_samples(samples, pan_deg=pan, tilt_deg=tilt, roll_deg=roll)
            r = camera_turn(*(np.deg2rad(np.float64(a)) for a in (pan, tilt, roll)))
            pr = predict(m, v, progress=False, source=source)
            views.append((pr.relative + pr.root[:, None, :]) @ r)  # (turned = R X, so X = R^T turned: rows @ R)
        print(f"\n{name} ({len(samples)} poses): views averaged | MPJPE | PA-MPJPE | MRPE | Z bias")
        for k in (1, 3, 5):
            a = np.mean(views[:k], axis=0)
            row = score(f"{k}", "learned", a - a[:, :1], a[:, 0], base)
            print(f"  {k} | {row.mpjpe:.2f} | {row.pa_mpjpe:.2f} | {row.mrpe:.2f} | {row.depth_bias:+.1f}")


if __name__ == "__main__":
    main()
