"""How the default places people farther away than Human3.6M's (a user trial: people in the background of a group
photo were placed far too near, with no word).

Protocol 1 test poses (S9, S11, every ``--stride``-th frame, 4 cameras), ground-truth 3D moved along the camera's
optical axis so that the root stands at each depth Z (mm), projected through an ideal pinhole of the camera's focal
length and principal point (exact 2D, no lens), and lifted with the true focal by the default as
``source="detected"`` and ``source="clean"``. Prints the median and mean signed root-depth error (% of Z, + = too
far) per depth, and the training subjects' root depths for comparison. (The default reads the 2D through the
focal length, as seen by a 1000-px reference camera from the true distance: the distance, not the image size or
focal, is what its training covers.)

    python scripts/far_people.py [--stride 100] [--depths 4000,...,50000] [--model universal_turn]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter.api import Lifter  # noqa: E402
from lifter.camera import project  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--stride", type=int, default=100)
    ap.add_argument("--depths", default="4000,5500,7000,9000,12000,16000,25000,38000,50000", help="root depths Z, mm")
    ap.add_argument("--model", default="default")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    data = H36M(args.h36m or default_h36m_dir())
    lifter = Lifter.from_pretrained(args.model)
    train = data.load_protocol(1, "train", stride=50)
    z_train = train.pose_3d[:, 0, 2].astype(np.float64)
    print(f"training subjects' root depth Z, every 50th frame: median {np.median(z_train):.0f} mm, 1-99 % "
          f"{np.percentile(z_train, 1):.0f}-{np.percentile(z_train, 99):.0f} mm, max {z_train.max():.0f} mm")
    test = data.load_protocol(1, "test", stride=args.stride)
    p3 = test.pose_3d.astype(np.float64)
    f, c = test.focal.astype(np.float64), test.principal_point.astype(np.float64)
    print(f"{lifter.name}: {len(p3)} test poses (stride {args.stride}), exact pinhole 2D, true focal; signed root-depth"
          " error, % of Z (+ = too far): median / mean")
    print("| Z (m) | source='detected' | source='clean' |")
    print("|---|---|---|")
    for z in (float(v) for v in args.depths.split(",")):
        moved = p3 - p3[:, :1] + np.array([0.0, 0.0, z])  # the root on the optical axis at depth z
        kp = project(moved, focal=f, principal_point=c)
        cells = []
        for source in ("detected", "clean"):
            r = lifter.lift(kp, focal=f, principal_point=c, source=source, warn=False)
            e = 100.0 * (r.root[:, 2] - z) / z
            cells.append(f"{np.median(e):+.1f} / {np.mean(e):+.1f}")
        print(f"| {z / 1000:.1f} | {cells[0]} | {cells[1]} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
