"""How far Human3.6M's lens distortion moves its 2D: each joint's distance (px) between H36M's own 2D and the ideal
pinhole projection of the same 3D, Protocol 1, every 5th frame, all four cameras, training and test subjects.

    python scripts/lens_px.py [--h36m PATH]
"""

from __future__ import annotations

import argparse

import numpy as np

from lifter.data import H36M


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--h36m", default=None, help="Human3.6M folder (default: lifter.data's)")
    args = ap.parse_args()
    data = H36M(args.h36m)
    for split in ("train", "test"):
        own = data.load_protocol(1, split, stride=5, lens="h36m")
        pinhole = data.load_protocol(1, split, stride=5, lens="pinhole")
        e = np.linalg.norm(own.keypoints_2d - pinhole.keypoints_2d, axis=-1)
        print(f"{split}: {len(own)} samples, per joint mean {e.mean():.2f} px, 99th percentile "
              f"{np.percentile(e, 99):.2f} px, max {e.max():.2f} px")


if __name__ == "__main__":
    main()
