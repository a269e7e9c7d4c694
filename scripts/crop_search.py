"""The video tracker's crop search against a full search, on the 84 Human3.6M demo photos.

    python scripts/crop_search.py [--model default]

Between full searches (every 0.5 s), ``lift_video`` finds each tracked person with
:meth:`lifter.detect.BlazePoseEstimator.detect_near`: BlazePose on a crop around the person's box in the frame
before. Here each photo is a still frame: the full search (``detect``) finds the person, and the crop search then
looks again around that box in the same photo. Both run with and without the detector's flip test (a second pass
on the mirror image or mirrored crop, combined with the first). Reported per search: the mean 2D error of the
H36M-17 joints against the ground-truth 2D (px), the lift's MPJPE / PA-MPJPE / MRPE and mean signed root-depth
error (mm) with each photo's true camera (focal length, principal point and lens distortion), and the median time
of one search (ms). Photos where a search finds nobody are left out of every row (the count is printed).
Nothing from Human3.6M is written.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
sys.path.insert(0, str(ROOT))

import eval_cascade as ec  # noqa: E402

from lifter import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detect import BlazePoseEstimator, load_image, people_h36m  # noqa: E402
from lifter.video import limit_blas_threads  # noqa: E402

SEARCHES = ("full search, flip test", "full search, one pass", "crop search, flip test", "crop search, one pass")


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--model", default="default")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    h36m = default_h36m_dir()
    ann = np.load(h36m / "demo" / "annotations.npz")
    focal, pp, dist = ec.demo_intrinsics(ec.demo_cameras(H36M(h36m), ann))
    lifter = Lifter.load(args.model)
    kps: dict[str, list[np.ndarray]] = {k: [] for k in SEARCHES}
    times: dict[str, list[float]] = {k: [] for k in SEARCHES}
    kept: list[int] = []
    with BlazePoseEstimator() as flip, BlazePoseEstimator(flip_test=False) as one, limit_blas_threads(1):
        flip.detect(np.zeros((64, 64, 3), np.uint8))
        one.detect(np.zeros((64, 64, 3), np.uint8))
        for i, rel in enumerate(ann["image"]):
            img = load_image(h36m / "demo" / str(rel))
            got = {}
            for name, est, near in ((SEARCHES[0], flip, False), (SEARCHES[1], one, False),
                                    (SEARCHES[2], flip, True), (SEARCHES[3], one, True)):
                box = got[SEARCHES[0]].raw.bbox_xywh if near and SEARCHES[0] in got else None
                if near and box is None:
                    break
                t0 = time.perf_counter()
                people = people_h36m(img, estimator=est, near=[box] if near else None)
                times[name].append(time.perf_counter() - t0)
                if not people:
                    break
                got[name] = max(people, key=lambda q: q.raw.area)
            if len(got) == len(SEARCHES):
                kept.append(i)
                for name in SEARCHES:
                    kps[name].append(got[name].keypoints_2d)
    idx = np.array(kept)
    gt3, gt2 = ann["p3d_cam"][idx].astype(np.float64), ann["p2d_gt"][idx]
    print(f"{len(idx)} of {len(ann['image'])} demo photos found by every search; lifter {lifter.name}, true camera")
    print("| search | 2D error (px) | MPJPE | PA-MPJPE | MRPE | root Z bias | ms per search (median) |")
    print("|---|---|---|---|---|---|---|")
    for name in SEARCHES:
        kp = np.stack(kps[name])
        res = lifter.lift(kp, focal=focal[idx], principal_point=pp[idx], distortion=dist[idx], warn=False)
        m = ec.pose_metrics(np.asarray(res.absolute), gt3)
        err2 = float(np.linalg.norm(kp - gt2, axis=-1).mean())
        print(f"| {name} | {err2:.2f} | {m['mpjpe']} | {m['pa_mpjpe']} | {m['mrpe']} | {m['root_z_bias']} | "
              f"{1e3 * float(np.median(times[name])):.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
