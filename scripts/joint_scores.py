"""How far off BlazePose's H36M joints are on the 84 Human3.6M demo photos, by the detector's own joint score: the
measurement behind :data:`lifter.detect.UNSURE_JOINT_SCORE` (the joints below it are named in a note).

    python scripts/joint_scores.py [--h36m ../shared/data/h36m] [--redetect]

Uses ``scripts/eval_cascade.py``'s detections (cached in ``runs/cache/``); 2D error in px against the ground truth's
projection with the lens (the photos' own pixels), H36M-17 joints of the largest person.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_cascade import detect_demo  # noqa: E402

from lifter import convert  # noqa: E402
from lifter.data import default_h36m_dir  # noqa: E402
from lifter.detect import UNSURE_JOINT_SCORE, h36m_joint_scores  # noqa: E402
from lifter.skeleton import JOINT_NAMES  # noqa: E402

BINS = (0.0, 0.2, UNSURE_JOINT_SCORE, 0.5, 0.8, 1.01)


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--redetect", action="store_true", help="run BlazePose again instead of using the cache")
    args = ap.parse_args()
    demo = (args.h36m or default_h36m_dir()) / "demo"
    ann = np.load(demo / "annotations.npz")
    det = detect_demo(demo, ann["image"], redetect=args.redetect)
    ok = det["people"] > 0
    kp17 = convert(det["kp33"][ok], src="blazepose33", warn=False)
    scores = h36m_joint_scores(det["scores"][ok], "blazepose33")
    err = np.linalg.norm(kp17 - ann["p2d_gt"][ok].astype(np.float64), axis=-1)
    print(f"{int(ok.sum())} photos with a person, {scores.size} H36M joints; 2D error (px) by the joint's score\n")
    print("| score | joints | median | mean | 90th pct |\n|---|---|---|---|---|")
    for lo, hi in zip(BINS[:-1], BINS[1:]):
        m = (scores >= lo) & (scores < hi)
        if m.any():
            e = err[m]
            print(f"| {lo:g}-{min(hi, 1):g} | {int(m.sum())} | {np.median(e):.1f} | {e.mean():.1f} | "
                  f"{np.quantile(e, 0.9):.1f} |")
    low = scores < UNSURE_JOINT_SCORE
    names = ", ".join(f"{JOINT_NAMES[j]} {int(low[:, j].sum())}" for j in np.flatnonzero(low.any(0)))
    print(f"\nbelow {UNSURE_JOINT_SCORE:g} (named in a note): {int(low.sum())} joints in {int(low.any(1).sum())} "
          f"photos ({names})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
