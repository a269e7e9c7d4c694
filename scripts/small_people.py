"""How the photo path fares as people get small in pixels: the 84 Human3.6M demo photos downscaled (the camera's
focal length and principal point scaled with them, its lens as it is), lifted by ``lift_image`` as ``poselifter
lift`` does. The measurement behind :data:`lifter.detect.SMALL_PERSON_PX` (a person shorter than that gets a
note: a browser trial's 300-px photo lifted 73 mm off the same photo at 1000 px, without a word).

    python scripts/small_people.py [--h36m ../shared/data/h36m] [--scales 1 0.6 0.4 0.3 0.2 0.15]
                                   [--min-score 0.3] [--out docs/results/small_people.txt]

Per scale: the person's size in the image (px, the longer side of the ground-truth 2D's box: their height here),
the detector's 2D error (px of the full-size photo, median over joints and photos), MPJPE / MRPE (mm) against the
ground truth, and the people found (detections scored below ``--min-score``, :data:`lifter.detect.MIN_PERSON_SCORE`
by default, are no person, as in ``poselifter lift``).
The downscaled photos are written to a temporary folder and deleted (Human3.6M-derived: never kept).
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import emit  # noqa: E402  (scripts/_report.py)

from lifter import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detect import MIN_PERSON_SCORE, SMALL_PERSON_PX, BlazePoseEstimator, NoPersonError  # noqa: E402
from lifter.metrics import mpjpe  # noqa: E402
from lifter.pipeline import lift_image  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--scales", type=float, nargs="+", default=[1.0, 0.6, 0.4, 0.3, 0.2, 0.15])
    ap.add_argument("--min-score", type=float, default=MIN_PERSON_SCORE, help="the detections' score floor")
    ap.add_argument("--out", type=Path, default=None, help="also write the report here")
    args = ap.parse_args()
    root = args.h36m or default_h36m_dir()
    demo = root / "demo"
    ann = np.load(demo / "annotations.npz")
    data = H36M(root)
    lifter = Lifter.from_pretrained()
    n = len(ann["image"])
    tmp = Path(tempfile.mkdtemp(prefix="small_people_"))
    lines = [f"84 demo photos downscaled, intrinsics scaled, lens kept; the default model {lifter.name}; the note "
             f"below {SMALL_PERSON_PX:g} px; detections scored below {args.min_score:g} are no person",
             "| scale | person size px (median) | found | 2D error px at full size (median) | MPJPE mm | MRPE mm | "
             "noted small |", "|---|---|---|---|---|---|---|"]
    try:
        with BlazePoseEstimator(max_people=3) as est:
            for s in args.scales:
                heights, err2d, mp, rp, noted, found = [], [], [], [], 0, 0
                for i in tqdm(range(n), desc=f"scale {s:g}", unit="photo"):
                    name = str(ann["image"][i])
                    path = next(p for p in (demo / "images" / os.path.basename(name), demo / name) if p.is_file())
                    img = cv2.imread(str(path))
                    if s != 1.0:
                        img = cv2.resize(img, None, fx=s, fy=s, interpolation=cv2.INTER_AREA)
                    tmp_path = tmp / "photo.jpg"
                    cv2.imwrite(str(tmp_path), img, [cv2.IMWRITE_JPEG_QUALITY, 95])
                    cam = data.camera(int(str(ann["subject"][i]).lstrip("S")), str(ann["camera"][i]))
                    gt2 = ann["p2d_gt"][i].astype(np.float64)
                    heights.append(s * float(np.ptp(gt2, axis=0).max()))  # (the box's longer side, as the note)
                    try:
                        rec = lift_image(tmp_path, lifter=lifter, estimator=est, min_score=args.min_score,
                                         focal=s * np.asarray(cam.focal, np.float64),
                                         principal_point=s * np.asarray(cam.principal_point, np.float64),
                                         distortion=cam.distortion)
                    except NoPersonError:
                        continue
                    found += 1
                    noted += any("small in the image" in w for w in rec.warnings)
                    err2d.append(float(np.median(np.linalg.norm(rec.keypoints_2d / s - gt2, axis=-1))))
                    gt3 = ann["p3d_cam"][i].astype(np.float64)
                    mp.append(float(mpjpe(rec.absolute, gt3)))
                    rp.append(float(np.linalg.norm(rec.root - gt3[0])))
                lines.append(f"| {s:g} | {np.median(heights):.0f} | {found} of {n} | {np.median(err2d):.1f} | "
                             f"{np.mean(mp):.1f} | {np.mean(rp):.1f} | {noted} |")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
