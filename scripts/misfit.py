"""How well a lift fits the 2D it came from, and the limit past which detected 2D gets a note.

``lifter.camera.reprojection_misfit``: the lifted pose projected back, centred, against the centred 2D, median joint,
as a share of the 2D pose's size. Printed for the default (``universal_far``), whose registry entry sets the note's
limit (``misfit_limit``, :data:`lifter.camera.MAX_DETECTED_MISFIT`):

1. the real Stacked-Hourglass detections of S9 and S11 (all cameras, every ``--stride``-th frame, undistorted):
   percentiles, the share above the limit and those samples' MPJPE against all;
2. the 84 demo photos through BlazePose (the ``detect`` extra), lifted with each camera's focal, principal point
   and lens: percentiles and the worst photos;
3. a user trial's case: a photo scaled up about 3x and padded to a 3024 x 4032 portrait frame, where BlazePose
   collapses the person (joints bunched, with high scores); the same photo padded to landscape for comparison;
4. clean 2D through the clean network, whose limit is ``clean_misfit_limit`` (:data:`lifter.camera.MAX_CLEAN_MISFIT`):
   the exact (undistorted) 2D of the training subjects, every 5th frame, and of S9 and S11; the test subjects' with
   Gaussian noise of 5 and 10 px (2D placed by hand); and the test subjects' exact 2D with joints in another order.

Nothing from Human3.6M is written.

    python scripts/misfit.py [--stride 10] [--h36m DIR]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_cascade import demo_cameras, demo_intrinsics  # noqa: E402

from lifter import Lifter  # noqa: E402
from lifter.camera import reprojection_misfit  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detections import load_sh_detections  # noqa: E402
from lifter.metrics import mpjpe  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--stride", type=int, default=10)
    ap.add_argument("--h36m", type=Path, default=None)
    args = ap.parse_args()
    data = H36M(args.h36m or default_h36m_dir())
    lf = Lifter.from_pretrained()
    limit = lf.network_for("detected").misfit_limit
    print(f"model {lf.name}: misfit_limit {limit}")

    s = data.load([9, 11], stride=args.stride, lens="pinhole")
    det, ok = load_sh_detections(s, data=data, lens="pinhole")
    res = lf.lift(det[ok], focal=s.focal[ok], principal_point=s.principal_point[ok], warn=False)
    m = reprojection_misfit(res.keypoints_2d, res.absolute, focal=res.focal, principal_point=res.principal_point)
    e = mpjpe(res.relative, s.pose_3d[ok])
    above = m > limit
    print(f"1. SH detections, S9+S11, stride {args.stride}: {len(m)} samples; misfit median / 99th / 99.9th "
          f"percentile / max {np.median(m):.3f} / {np.percentile(m, 99):.3f} / {np.percentile(m, 99.9):.3f} / "
          f"{m.max():.3f}; above {limit}: {above.mean():.1%} (their MPJPE median {np.median(e[above]):.0f} mm; "
          f"all {np.median(e):.0f} mm)")

    from PIL import Image

    from lifter.detect import detect_people, get_estimator, image_from_array

    demo = Path(data.root) / "demo"
    ann = np.load(demo / "annotations.npz")
    f, c, dist = demo_intrinsics(demo_cameras(data, ann))
    est = get_estimator("blazepose", max_people=2)
    rows = []
    for i, name in enumerate(ann["image"]):
        rgb = np.asarray(Image.open(demo / str(name)).convert("RGB"))
        try:
            kp = detect_people(image_from_array(rgb), estimator=est, max_people=1)[0].keypoints_2d
        except Exception:  # noqa: BLE001 - a photo where nobody is found is left out (counted below)
            continue
        r = lf.lift(kp, focal=f[i], principal_point=c[i], distortion=dist[i], warn=False)
        mi = float(reprojection_misfit(r.keypoints_2d, r.absolute, focal=r.focal, principal_point=r.principal_point))
        rows.append((mi, float(mpjpe(r.relative, ann["p3d_cam"][i])), Path(str(name)).stem))
    ms = np.array([r[0] for r in rows])
    print(f"2. {len(rows)} of {len(ann['image'])} demo photos through BlazePose: misfit median {np.median(ms):.3f}, "
          f"90th percentile {np.percentile(ms, 90):.3f}, max {ms.max():.3f}; above {limit}: {int((ms > limit).sum())}; "
          "worst: " + ", ".join(f"{n} {mi:.3f} (MPJPE {mp:.0f})" for mi, mp, n in sorted(rows)[-3:]))

    i = next(k for k, n in enumerate(ann["image"]) if "S8_WalkDog" in str(n))
    rgb = np.asarray(Image.open(demo / str(ann["image"][i])).convert("RGB"))
    k = 3.024
    up = np.asarray(Image.fromarray(rgb).resize((round(rgb.shape[1] * k), round(rgb.shape[0] * k))))
    for layout, shape in (("portrait", (4032, up.shape[1])), ("landscape", (up.shape[0], 4032))):
        canvas = np.zeros((*shape, 3), np.uint8)
        y0, x0 = (shape[0] - up.shape[0]) // 2, (shape[1] - up.shape[1]) // 2
        canvas[y0:y0 + up.shape[0], x0:x0 + up.shape[1]] = up
        d = detect_people(image_from_array(canvas), estimator=est, max_people=1)[0]
        cc = (c[i] * k + [x0, y0])
        r = lf.lift(d.keypoints_2d, focal=f[i] * k, principal_point=cc, distortion=dist[i], warn=False)
        mi = float(reprojection_misfit(r.keypoints_2d, r.absolute, focal=r.focal, principal_point=r.principal_point))
        err2d = np.linalg.norm(d.keypoints_2d - (ann["p2d_gt"][i] * k + [x0, y0]), axis=-1)
        print(f"3. {Path(str(ann['image'][i])).stem} x{k} padded to {layout} {shape[1]} x {shape[0]}: 2D error median "
              f"{np.median(err2d):.0f} px (mean score {np.mean(d.scores):.2f}), misfit {mi:.3f}, MPJPE "
              f"{float(mpjpe(r.relative, ann['p3d_cam'][i])):.0f} mm; noted: "
              f"{any(getattr(w, 'kind', '') == 'misfit' for w in r.warnings)}")

    clean_limit = lf.network_for("clean").misfit_limit
    print(f"4. clean 2D, clean network: clean_misfit_limit {clean_limit}")
    rng = np.random.default_rng(0)
    for label, subjects, stride in (("training subjects' exact 2D", [1, 5, 6, 7, 8], 5),
                                    ("S9 + S11 exact 2D", [9, 11], args.stride)):
        t = data.load(subjects, stride=stride, lens="pinhole")
        rc = lf.lift(t.keypoints_2d, focal=t.focal, principal_point=t.principal_point, source="clean", warn=False)
        mc = reprojection_misfit(rc.keypoints_2d, rc.absolute, focal=rc.focal, principal_point=rc.principal_point)
        print(f"   {label}, stride {stride}: {len(mc)} samples; misfit median / 99.9th / 99.99th percentile / max "
              f"{np.median(mc):.4f} / {np.percentile(mc, 99.9):.4f} / {np.percentile(mc, 99.99):.4f} / "
              f"{mc.max():.4f}; above {clean_limit}: {int((mc > clean_limit).sum())}")
    for sigma in (5.0, 10.0):
        kp = s.keypoints_2d + rng.normal(0.0, sigma, s.keypoints_2d.shape)
        rc = lf.lift(kp, focal=s.focal, principal_point=s.principal_point, source="clean", warn=False)
        mc = reprojection_misfit(rc.keypoints_2d, rc.absolute, focal=rc.focal, principal_point=rc.principal_point)
        print(f"   S9 + S11 exact 2D with {sigma:g}-px Gaussian noise: above {clean_limit}: "
              f"{np.mean(mc > clean_limit):.2%}")
    orders = {"knees <-> elbows": [0, 1, 15, 3, 4, 12, 6, 7, 8, 9, 10, 11, 5, 13, 14, 2, 16],
              "wrists <-> feet": [0, 1, 2, 16, 4, 5, 13, 7, 8, 9, 10, 11, 12, 6, 14, 15, 3],
              "left <-> right legs": [0, 4, 5, 6, 1, 2, 3, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16]}
    for label, order in orders.items():
        rc = lf.lift(s.keypoints_2d[:, order], focal=s.focal, principal_point=s.principal_point, source="clean",
                     warn=False)
        mc = reprojection_misfit(rc.keypoints_2d, rc.absolute, focal=rc.focal, principal_point=rc.principal_point)
        noted = (mc > clean_limit) | np.isnan(mc)  # (NaN: a joint behind the camera, noted as such)
        print(f"   S9 + S11, {label}: noted {np.mean(noted):.1%} (misfit median {np.nanmedian(mc):.3f})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
