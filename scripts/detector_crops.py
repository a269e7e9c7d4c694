"""Does a second BlazePose pass on a crop around the person found help the photos line? Measured on the 84 Human3.6M
demo photos with the default lifter.

    python scripts/detector_crops.py [--h36m ../shared/data/h36m] [--grows 0.1 0.2 0.35]

For each photo the default detector (``get_estimator("blazepose")``: whole image and windows, the detector's flip
test) finds the largest person; a one-person detector (flip test too) then runs again on a square crop around that
person's landmark box, grown by each ``--grows`` fraction per side, so the person fills more of the detector's
input. Each variant's H36M-17 2D error (px, against the ground truth projected with the lens) and the default's
MPJPE / MRPE and mean signed root-depth error (mm; true focal, principal point and lens; ``source="detected"``) are
printed, with the first pass, each crop pass, each crop pass averaged with the first, and all passes averaged.
Nothing from Human3.6M is written (the detections stay in memory).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

sys.path.insert(0, str(Path(__file__).resolve().parent))
from eval_cascade import demo_frames  # noqa: E402

from lifter.api import Lifter  # noqa: E402
from lifter.detect import get_estimator, load_image  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.metrics import mpjpe, root_errors  # noqa: E402


def crop_box(box_xywh: np.ndarray, grow: float, width: int, height: int) -> tuple[int, int, int, int]:
    """A square around ``box_xywh`` (px), its side the box's longer side grown by ``grow`` per side, clipped to the
    image: ``(x0, y0, x1, y1)``."""
    x, y, w, h = (float(v) for v in box_xywh)
    side = max(w, h) * (1 + 2 * grow)
    cx, cy = x + w / 2, y + h / 2
    return (int(max(0, cx - side / 2)), int(max(0, cy - side / 2)),
            int(min(width, cx + side / 2)), int(min(height, cy + side / 2)))


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--grows", type=float, nargs="+", default=[0.1, 0.2, 0.35])
    ap.add_argument("--model", default="default")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    demo, ann, focal, pp, dist = demo_frames(args.h36m)
    gt2d, gt3d = ann["p2d_gt"].astype(np.float64), ann["p3d_cam"].astype(np.float64)
    n = len(ann["image"])
    names = ["first pass"] + [f"crop grown {g:g}" for g in args.grows]
    kp = {k: np.full((n, 33, 2), np.nan) for k in names}
    t0 = time.perf_counter()
    with get_estimator("blazepose", max_people=3) as full, get_estimator("blazepose", max_people=1) as one:  # type: ignore[attr-defined]
        for i, rel in enumerate(ann["image"]):
            img = load_image(demo / str(rel))
            found = full.detect(img.rgb)
            if not found:
                continue
            d = max(found, key=lambda d: d.area)
            kp["first pass"][i] = d.keypoints / img.scale
            H, W = img.rgb.shape[:2]
            for g, name in zip(args.grows, names[1:]):
                x0, y0, x1, y1 = crop_box(d.bbox_xywh, g, W, H)
                again = one.detect(np.ascontiguousarray(img.rgb[y0:y1, x0:x1]))
                if again:
                    e = max(again, key=lambda d: d.area)
                    kp[name][i] = (e.keypoints + [x0, y0]) / img.scale
    print(f"{n} photos, {len(names)} passes each in {time.perf_counter() - t0:.0f} s; model {args.model}; true "
          "focal, principal point and lens; MPJPE / MRPE / mean signed root-depth error (mm; + = too far)\n")
    lifter = Lifter.load(args.model)
    first = kp["first pass"]
    rows = [(k, kp[k]) for k in names]
    rows += [(f"first pass + {k}, averaged", np.where(np.isnan(kp[k]), first, 0.5 * (first + kp[k])))
             for k in names[1:]]
    rows.append(("all passes averaged", np.nanmean(np.stack([kp[k] for k in names]), 0)))
    print("| 2D | photos | 2D error px | MPJPE | MRPE | root Z bias |\n|---|---|---|---|---|---|")
    for label, k33 in rows:
        ok = ~np.isnan(k33).any((1, 2))
        k17 = convert(k33[ok], src="blazepose33", warn=False)
        e2 = float(np.linalg.norm(k17 - gt2d[ok], axis=-1).mean())
        pred = lifter.lift(k17, focal=focal[ok], principal_point=pp[ok], source="detected",
                           distortion=dist[ok]).absolute
        mrpe, _ = root_errors(pred[:, 0], gt3d[ok][:, 0])
        bias = float((pred[:, 0, 2] - gt3d[ok][:, 0, 2]).mean())
        print(f"| {label} | {int(ok.sum())} | {e2:.2f} | {float(mpjpe(pred, gt3d[ok]).mean()):.1f} | "
              f"{float(mrpe.mean()):.1f} | {bias:+.0f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
