"""How far half a pixel of principal point moves the lift (the README's "Pixel coordinates" convention note).

Mixing OpenCV's pixel-centre convention (centres at integers) with the photo path's (centres at i + 0.5) puts the
principal point 0.5 px off in x and y. This lifts the five embedded demo poses (``assets/demo/samples.npz``, exact
2D, their true focal and principal point) with the principal point as given and moved by (+-0.5, +-0.5) px, for
``source="clean"`` and ``source="detected"``, and prints how far the root (mm, camera frame) and the farthest joint
(mm, absolute) move. No Human3.6M data is read.

    python scripts/pixel_convention.py [--model universal_turn]
"""

from __future__ import annotations

import argparse

import numpy as np

from lifter import Lifter
from lifter.resources import asset


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--model", default="default", help="a shipped model name or a checkpoint (default: the default)")
    args = ap.parse_args()
    lifter = Lifter.load(args.model) if args.model != "default" else Lifter.from_pretrained()
    d = np.load(asset("demo/samples.npz"), allow_pickle=False)
    shifts = [(sx, sy) for sx in (-0.5, 0.5) for sy in (-0.5, 0.5)]
    print(f"model {lifter.name}: the five demo poses, exact 2D, true focal; principal point moved by (+-0.5, +-0.5) px")
    print(f"{'source':10s} {'root moved mm (min-max)':>24s} {'joint moved mm (max)':>22s}")
    for source in ("clean", "detected"):
        roots, joints = [], []
        for i in range(len(d["names"])):
            kp, f, c = d["keypoints_2d"][i], d["focal"][i], d["principal_point"][i]
            base = lifter.lift(kp, focal=f, principal_point=c, source=source, warn=False).absolute
            for s in shifts:
                moved = lifter.lift(kp, focal=f, principal_point=c + np.asarray(s), source=source,
                                    warn=False).absolute
                roots.append(float(np.linalg.norm(moved[0] - base[0])))
                joints.append(float(np.linalg.norm(moved - base, axis=-1).max()))
        print(f"{source:10s} {min(roots):11.1f} - {max(roots):<10.1f} {max(joints):22.1f}")


if __name__ == "__main__":
    main()
