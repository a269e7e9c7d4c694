"""Several people in one photo, with known 3D: two-person composites of real H36M frames.

    python benchmarks/bench_multi_person.py [--models blazepose default] [--multi mask tasks] [--json out.json]

Each composite is a real H36M demo frame A with the person of another frame B of the **same camera** pasted in
(B's ground-truth 2D box grown by 10 % per side, copied from B's image onto A at the same place; only pairs whose
grown boxes do not overlap). The intrinsics of a camera id are identical for every subject in H36M's
calibration, and the backdrop is the same studio seen by the same camera, so the composite is a photo of two
people whose 3D in that camera's frame is known exactly: A's and B's ground truth. Built at run time from
``../shared/data/h36m/demo`` into the git-ignored ``runs/cache/two_person/`` (H36M-derived, never committed).

Each composite goes through ``lifter.pipeline.lift_image`` (BlazePose, everyone found, lifted into one camera
space with the true focal length and principal point). A person counts as **found** when a detected person's 2D
pelvis is within 40 px of their true 2D pelvis. Reported: the share of photos with both found, detection recall
(per person), per-person MPJPE (root-aligned) and MRPE (mm) of the found people, the same people lifted from
their own single-person photo (``lift_image`` on frame A or B alone) for comparison, and the time per photo.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detect import BlazePoseEstimator, image_from_array, load_image  # noqa: E402
from lifter.pipeline import lift_image  # noqa: E402
from lifter.video import limit_blas_threads  # noqa: E402

FOUND_PX = 40.0
GROW = 0.10


def grown_box(kp: np.ndarray, W: int, H: int) -> tuple[int, int, int, int]:
    lo, hi = kp.min(0), kp.max(0)
    w = hi - lo
    x0, y0 = np.floor(lo - GROW * w).astype(int)
    x1, y1 = np.ceil(hi + GROW * w).astype(int)
    return max(0, x0), max(0, y0), min(W, x1), min(H, y1)


def composites(demo: Path, ann: Any, cache: Path) -> list[dict[str, Any]]:
    """The two-person composites (written to ``cache`` once) with both people's ground truth."""
    cache.mkdir(parents=True, exist_ok=True)
    out = []
    for cam in sorted(set(ann["camera"].tolist())):
        idx = [i for i in range(len(ann["image"])) if ann["camera"][i] == cam]
        for i, j in itertools.combinations(idx, 2):
            ka, kb = ann["p2d_gt"][i], ann["p2d_gt"][j]
            path = cache / f"pair_{i:02d}_{j:02d}.jpg"
            if not path.is_file():
                a = load_image(demo / str(ann["image"][i])).rgb
                b = load_image(demo / str(ann["image"][j])).rgb
                if a.shape != b.shape:
                    continue
                H, W = a.shape[:2]
                ba, bb = grown_box(ka, W, H), grown_box(kb, W, H)
                if not (ba[2] < bb[0] or bb[2] < ba[0]):
                    continue
                from PIL import Image

                c = a.copy()
                c[bb[1]:bb[3], bb[0]:bb[2]] = b[bb[1]:bb[3], bb[0]:bb[2]]
                Image.fromarray(c).save(path, quality=95)
            out.append({"path": path, "a": i, "b": j})
    return out


def evaluate(lifter: Lifter, est: BlazePoseEstimator, pairs: list[dict[str, Any]], ann: Any, focal: np.ndarray,
             pp: np.ndarray) -> dict[str, Any]:
    both, found_n, total_n, secs = 0, 0, 0, []
    root_err, mpjpe, n_people = [], [], []
    for pr in pairs:
        img = load_image(pr["path"])
        t0 = time.perf_counter()
        try:
            rec = lift_image(img, lifter=lifter, estimator=est, focal=focal[pr["a"]], principal_point=pp[pr["a"]])
            people = rec.people
        except Exception:  # noqa: BLE001 -- NoPersonError: nobody found counts as misses
            people = ()
        secs.append(time.perf_counter() - t0)
        n_people.append(len(people))
        ok = 0
        for k in (pr["a"], pr["b"]):
            total_n += 1
            gt2, gt3 = ann["p2d_gt"][k], ann["p3d_cam"][k].astype(np.float64)
            d = [float(np.linalg.norm(q.keypoints_2d[0] - gt2[0])) for q in people]
            if not d or min(d) > FOUND_PX:
                continue
            q = people[int(np.argmin(d))]
            ok += 1
            found_n += 1
            root_err.append(float(np.linalg.norm(q.root - gt3[0])))
            mpjpe.append(float(np.linalg.norm(q.relative - (gt3 - gt3[:1]), axis=-1).mean()))
        both += ok == 2
    return {"photos": len(pairs), "both_found": both / len(pairs), "recall": found_n / total_n,
            "people_found_per_photo": float(np.mean(n_people)), "mrpe": float(np.mean(root_err)),
            "mrpe_median": float(np.median(root_err)), "mpjpe": float(np.mean(mpjpe)),
            "share_roots_within_200mm": float(np.mean(np.array(root_err) < 200)),
            "ms_per_photo": 1e3 * float(np.median(secs)), "n_found": found_n}


def single_baseline(lifter: Lifter, est: BlazePoseEstimator, demo: Path, ann: Any, frames: list[int],
                    focal: np.ndarray, pp: np.ndarray) -> dict[str, Any]:
    """The same people lifted from their own (one-person) photo."""
    root_err, mpjpe, secs = [], [], []
    for k in frames:
        img = load_image(demo / str(ann["image"][k]))
        t0 = time.perf_counter()
        try:
            rec = lift_image(img, lifter=lifter, estimator=est, focal=focal[k], principal_point=pp[k])
        except Exception:  # noqa: BLE001
            continue
        secs.append(time.perf_counter() - t0)
        gt2, gt3 = ann["p2d_gt"][k], ann["p3d_cam"][k].astype(np.float64)
        if np.linalg.norm(rec.keypoints_2d[0] - gt2[0]) > FOUND_PX:
            continue
        root_err.append(float(np.linalg.norm(rec.root - gt3[0])))
        mpjpe.append(float(np.linalg.norm(rec.relative - (gt3 - gt3[:1]), axis=-1).mean()))
    return {"people": len(frames), "found": len(root_err), "mrpe": float(np.mean(root_err)),
            "mpjpe": float(np.mean(mpjpe)), "ms_per_photo": 1e3 * float(np.median(secs))}


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--models", nargs="+", default=["blazepose", "default"])
    ap.add_argument("--multi", nargs="+", default=["windows", "mask", "tasks"], choices=["windows", "mask", "tasks"])
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    h36m = default_h36m_dir()
    demo = h36m / "demo"
    ann = np.load(demo / "annotations.npz")
    data = H36M(h36m)
    cams = [data.camera(int(str(s).lstrip("S")), str(c)) for s, c in zip(ann["subject"], ann["camera"])]
    focal = np.array([c.focal for c in cams])
    pp = np.array([c.principal_point for c in cams])
    pairs = composites(demo, ann, ROOT / "runs" / "cache" / "two_person")
    people = sorted({k for pr in pairs for k in (pr["a"], pr["b"])})
    print(f"{len(pairs)} two-person composites from {len(people)} H36M demo frames (same camera per pair)")
    results: dict[str, Any] = {"photos": len(pairs), "found_px": FOUND_PX, "rows": {}}
    image_from_array(np.zeros((8, 8, 3), np.uint8))
    for multi in args.multi:
        with BlazePoseEstimator(max_people=3, multi=multi) as est, limit_blas_threads(1):  # as poselifter lift
            est.detect(np.zeros((64, 64, 3), np.uint8))
            for name in args.models:
                lf = Lifter.load(name)
                r = evaluate(lf, est, pairs, ann, focal, pp)
                b = single_baseline(lf, est, demo, ann, people, focal, pp)
                results["rows"][f"{multi} / {lf.name}"] = {"two_person": r, "single_photo_same_people": b}
                print(f"multi={multi} lifter={lf.name}: both found in {100 * r['both_found']:.1f} % of {r['photos']} "
                      f"photos, recall {100 * r['recall']:.1f} %, {r['people_found_per_photo']:.2f} people/photo; "
                      f"found people: MRPE {r['mrpe']:.1f} mm (median {r['mrpe_median']:.1f}, "
                      f"{100 * r['share_roots_within_200mm']:.0f} % < 200 mm), MPJPE {r['mpjpe']:.1f} mm; "
                      f"{r['ms_per_photo']:.0f} ms/photo | same people alone: MRPE {b['mrpe']:.1f}, MPJPE "
                      f"{b['mpjpe']:.1f} ({b['found']}/{b['people']} found, {b['ms_per_photo']:.0f} ms/photo)")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
