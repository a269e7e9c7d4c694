"""Real photos of people farther away: the 84 Human3.6M demo photos shrunk about the person, through BlazePose.

A person k times farther along the same viewing ray looks, to first order (weak perspective about the root), like
the same picture shrunk by 1/k about the root's 2D. Each demo photo is shrunk so (Lanczos, pasted into a canvas of
the photo's size filled with its mean colour, the root's 2D kept) and BlazePose (the ``detect`` extra, flip test;
``--max-people`` above 1 also searches windows, which is what finds small people) looks for people in it; the one
whose root is nearest the true root's 2D, within 40 px, counts as found. Each lifter lifts its converted 2D told
``source="detected"`` with the photo's focal and principal point (no lens: shrinking the picture does not shrink
the lens). The truth is the ground-truth pose moved along its root's ray to k times its depth (what
``lifter.train.move_batch`` trains on); the shrunk picture differs from its exact projection by the body's own
depth (a few px at k = 3). Prints per k the photos where the person was found, BlazePose's 2D error against the
ground truth shrunk with the picture, the signed root-depth error (% of the true depth, median / mean, + = too far),
MRPE and MPJPE (mm).
Nothing from Human3.6M is written.

    python scripts/far_photos.py [--models universal_turn,default] [--factors 1,1.5,2,3]
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

from lifter.api import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detect import get_estimator  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.metrics import mpjpe  # noqa: E402

ROOT_MATCH_PX = 40.0
"""A person counts as found when a detection's root (pelvis) 2D is within this of the true root's (px), as in
``benchmarks/bench_multi_person.py``."""


def shrunk(path: Path, root_2d: np.ndarray, k: float) -> np.ndarray:
    """The photo at ``path`` shrunk by ``1/k`` about ``root_2d`` (px) on a canvas of its size: RGB ``(H, W, 3)``."""
    from PIL import Image

    with Image.open(path) as im:
        img = im.convert("RGB")
    if k == 1:
        return np.asarray(img)
    w, h = img.size
    small = img.resize((max(1, round(w / k)), max(1, round(h / k))), Image.Resampling.LANCZOS)
    fill = tuple(int(v) for v in np.asarray(img).reshape(-1, 3).mean(0))
    canvas = Image.new("RGB", (w, h), fill)
    offset = np.round(root_2d - root_2d / k).astype(int)  # the root's 2D stays where it was
    canvas.paste(small, (int(offset[0]), int(offset[1])))
    return np.asarray(canvas)


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--models", default="universal_turn,default")
    ap.add_argument("--factors", default="1,1.5,2,3", help="distance factors k (the picture shrunk by 1/k)")
    ap.add_argument("--max-people", type=int, default=3,
                    help="BlazePose's people per photo (above 1 it also searches windows, which finds small people)")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    h36m_dir = args.h36m or default_h36m_dir()
    demo = h36m_dir / "demo"
    ann = np.load(demo / "annotations.npz")
    data = H36M(h36m_dir)
    focal, pp, _ = demo_intrinsics(demo_cameras(data, ann))  # (no lens: see the module docstring)
    gt3d = ann["p3d_cam"].astype(np.float64)
    gt2d = ann["p2d_gt"].astype(np.float64)
    lifters = [Lifter.from_pretrained(m) for m in args.models.split(",")]
    n = len(ann["image"])
    print(f"{n} Human3.6M demo photos shrunk by 1/k about the root's 2D, BlazePose (flip test, max_people "
          f"{args.max_people}, the person nearest the true root), lifted told 'detected' with the true focal and "
          "principal point, no lens; truth: the pose moved along its root's ray to k x its depth (the photos' roots: "
          f"{gt3d[:, 0, 2].min() / 1000:.1f}-{gt3d[:, 0, 2].max() / 1000:.1f} m)")
    print("signed root-depth error % of the true depth (median / mean, + = too far), MRPE / MPJPE mm")
    print("| k | photos with the person found | their 2D error, px (median of the mean per photo) | "
          + " | ".join(f"`{lf.name}`" for lf in lifters) + " |")
    print("|---|---|---|" + "---|" * len(lifters))
    with get_estimator("blazepose", max_people=args.max_people) as est:  # type: ignore[attr-defined]
        for k in (float(v) for v in args.factors.split(",")):
            kp = np.full((n, 17, 2), np.nan)
            for i, rel in enumerate(ann["image"]):
                people = [convert(d.keypoints, src="blazepose33")
                          for d in est.detect(shrunk(demo / str(rel), gt2d[i, 0], k))]
                if people:  # the person found nearest the true root, if within ROOT_MATCH_PX of it
                    best = min(people, key=lambda p: float(np.linalg.norm(p[0] - gt2d[i, 0])))
                    if np.linalg.norm(best[0] - gt2d[i, 0]) <= ROOT_MATCH_PX:
                        kp[i] = best
            ok = np.isfinite(kp).all(axis=(1, 2))
            truth = gt3d - gt3d[:, :1] + k * gt3d[:, :1]
            shrunk_2d = gt2d[:, :1] + (gt2d - gt2d[:, :1]) / k  # the ground-truth 2D as shrunk with the picture
            err_2d = float(np.median(np.linalg.norm(kp[ok] - shrunk_2d[ok], axis=-1).mean(-1))) if ok.any() else np.nan
            cells = []
            for lf in lifters:
                r = lf.lift(kp[ok], focal=focal[ok], principal_point=pp[ok], source="detected", warn=False)
                e = 100.0 * (r.root[:, 2] - truth[ok, 0, 2]) / truth[ok, 0, 2]
                mrpe = float(np.linalg.norm(r.root - truth[ok, 0], axis=-1).mean())
                pose = float(mpjpe(r.absolute, truth[ok]).mean())
                cells.append(f"{np.median(e):+.1f} / {np.mean(e):+.1f} %, {mrpe:.0f} / {pose:.1f}")
            print(f"| {k:g} | {int(ok.sum())} of {n} | {err_2d:.1f} | " + " | ".join(cells) + " |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
