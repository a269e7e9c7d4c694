"""Does a model's absolute root survive a change of image resolution? (issue 11: "resolution x0.25 ... x8").

Scaling an image by ``k`` scales the 2D keypoints, the focal length and the principal point by ``k``; the
physical camera, and so the true 3D pose, do not change. A lifter should give the same root. For each model
this script lifts the S9 + S11 test poses (Protocol 1, every ``--stride``-th frame, GT 2D told ``source``)
at each ``k`` and reports, against ``k = 1``:

* the largest and the median relative change of the root, ``|root_k - root_1| / |root_1|``;
* the MRPE (mm) at each ``k``;
* how many roots came out behind the camera (``Z <= 0``).

The same is done with the focal length unknown (``focal=None``, ``image_size`` given): the default field of view
then sets the focal from the image size, so a scaled image must again give the same result.

    python benchmarks/bench_invariance.py --models universal,sh_mix --json docs/results/bench_invariance.json

Units: mm and px; camera frame OpenCV. Needs Human3.6M (``--h36m`` or ``../shared/data/h36m``).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import torch

from lifter.api import Lifter
from lifter.data import H36M
from lifter.metrics import root_errors

SCALES = (0.1, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 10.0)


def lift_roots(model: Lifter, kp: np.ndarray, focal: np.ndarray | None, pp: np.ndarray, size: np.ndarray,
               *, source: str, distortion: np.ndarray) -> np.ndarray:
    """Roots ``(N, 3)`` mm; with ``focal=None`` the image size (one per group of equal sizes) sets the focal. With
    the focal given the cameras' lens is given too (its coefficients act on px / focal, unchanged by scaling); with
    the focal assumed it cannot be, as for a photo of unknown camera."""
    if focal is not None:
        res = model.lift(kp, focal=focal, principal_point=pp, source=source,  # type: ignore[arg-type]
                         distortion=distortion)
        return np.asarray(res.root, np.float64)
    root = np.empty(kp.shape[:-2] + (3,))
    for wh in np.unique(size, axis=0):
        sel = np.all(size == wh, axis=-1)
        res = model.lift(kp[sel], image_size=tuple(wh), source=source)  # type: ignore[arg-type]
        root[sel] = res.root
    return root


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--models", default="default", help="comma-separated shipped names or checkpoint paths")
    ap.add_argument("--stride", type=int, default=50)
    ap.add_argument("--source", choices=("clean", "detected"), default="clean")
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(args.threads)

    data = H36M(args.h36m) if args.h36m else H36M()
    s = data.load_protocol(1, "test", stride=args.stride)
    kp = s.keypoints_2d.astype(np.float64)
    f = s.focal.astype(np.float64)
    c = s.principal_point.astype(np.float64)
    size = s.image_size.astype(np.float64)
    print(f"{len(kp)} test poses (S9 + S11, stride {args.stride}), GT 2D told source={args.source!r}")
    out: dict = {"stride": args.stride, "source": args.source, "num_poses": len(kp), "scales": list(SCALES),
                 "models": {}}
    for name in args.models.split(","):
        model = Lifter.from_pretrained(name)
        rows = {}
        for focal_known in (True, False):
            ref = None
            per_k = {}
            for k in SCALES:
                root = lift_roots(model, kp * k, f * k if focal_known else None, c * k, size * k, source=args.source,
                                  distortion=s.distortion)
                if k == 1.0:
                    ref = root
                per_k[k] = root
            assert ref is not None
            table = {}
            for k, root in per_k.items():
                rel = np.linalg.norm(root - ref, axis=-1) / np.linalg.norm(ref, axis=-1)
                table[str(k)] = {"max_rel_change": float(rel.max()), "median_rel_change": float(np.median(rel)),
                                 "mrpe_mm": float(root_errors(root, s.pose_3d[:, 0]).__getitem__(0).mean()),
                                 "behind_camera": int((root[:, 2] <= 0).sum())}
            rows["focal_given" if focal_known else "focal_unknown"] = table
        out["models"][model.name] = rows
        for key, table in rows.items():
            print(f"\n{model.name} ({key.replace('_', ' ')})")
            print(f"{'k':>6} {'max |d root|/|root|':>20} {'median':>9} {'MRPE mm':>9} {'Z<=0':>6}")
            for k, r in table.items():
                print(f"{float(k):6.2f} {100 * r['max_rel_change']:19.4f}% {100 * r['median_rel_change']:8.4f}% "
                      f"{r['mrpe_mm']:9.1f} {r['behind_camera']:6d}")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        tmp = args.json.with_suffix(".json.tmp")
        tmp.write_text(json.dumps(out, indent=1))
        tmp.replace(args.json)


if __name__ == "__main__":
    main()
