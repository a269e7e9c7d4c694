"""People standing in a row: how many the detector finds in wide group photos, built from real H36M frames.

    python benchmarks/bench_people_row.py [--rows 10] [--people 3 4 5] [--json out.json]

Each photo is N full-height strips of different Human3.6M demo frames side by side (each strip: the person's
ground-truth 2D box grown by 30 % sideways, the frame's full height), with 16-px grey gaps, in three variants:
**same size**; **mixed sizes** (each strip scaled by a random factor in [0.55, 1], standing on a common floor
line); and **panorama** (every strip at 0.6 and grown by 100 % sideways, so 4 or 5 people make a photo wider
than 2:1, like a 1826 x 695 px test photo of a user trial). Built at run time from ``../shared/data/h36m/demo``
(H36M-derived, never written to the repo). A person counts as **found** when a detected 2D pelvis lies within
40 px (times the strip's scale) of their true pelvis.

Compared, in one run on the same photos: BlazePose's window search with windows at most as wide as the image is
high (``window_aspect=1``, the default) and the earlier rule (``window_aspect=None``: 3 windows, half the longer
side wide, in any landscape photo). Reported per N and variant: recall, photos with everyone found, people
reported that are nobody (a detected pelvis near no true one), and the median time per photo.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter.data import default_h36m_dir  # noqa: E402
from lifter.detect import BlazePoseEstimator, load_image  # noqa: E402
from lifter.keypoints import convert  # noqa: E402

FOUND_PX = 40.0
GREY = 128
RULES: dict[str, float | None] = {"windows <= image height (default)": 1.0, "3 windows (earlier rule)": None}


def row_photo(ann: Any, demo: Path, frames: list[int], scales: list[float], *, margin: float = 0.3
              ) -> tuple[np.ndarray, np.ndarray]:
    """The photo ``(H, W, 3)`` uint8 and the true 2D pelvis ``(N, 2)`` px of each person in it; each strip is the
    person's box grown by ``margin`` times its width on each side."""
    from PIL import Image

    strips, pelvis = [], []
    for i, s in zip(frames, scales):
        rgb = load_image(demo / str(ann["image"][i])).rgb
        kp = ann["p2d_gt"][i]
        H, W = rgb.shape[:2]
        lo, hi = kp[:, 0].min(), kp[:, 0].max()
        x0, x1 = int(max(0, lo - margin * (hi - lo))), int(min(W, hi + margin * (hi - lo)))
        strip = Image.fromarray(np.ascontiguousarray(rgb[:, x0:x1]))
        if s != 1.0:
            size = (max(1, round(strip.width * s)), max(1, round(strip.height * s)))
            strip = strip.resize(size, Image.Resampling.LANCZOS)
        strips.append(np.asarray(strip))
        pelvis.append((kp[0] - [x0, 0]) * s)
    gap = 16
    Hc = max(a.shape[0] for a in strips)
    Wc = sum(a.shape[1] for a in strips) + gap * (len(strips) + 1)
    out = np.full((Hc, Wc, 3), GREY, np.uint8)
    x, truth = gap, []
    for a, p in zip(strips, pelvis):
        y = Hc - a.shape[0]  # a common floor line
        out[y:, x:x + a.shape[1]] = a
        truth.append(p + [x, y])
        x += a.shape[1] + gap
    return out, np.array(truth)


def score(dets: list[Any], truth: np.ndarray, scales: list[float]) -> tuple[int, int]:
    """(people found, detections that are nobody)."""
    pel = [convert(d.keypoints, src=d.keypoint_format)[0] for d in dets]
    found = sum(any(np.linalg.norm(p - t) < FOUND_PX * s for p in pel) for t, s in zip(truth, scales))
    nobody = sum(not any(np.linalg.norm(p - t) < FOUND_PX * s for t, s in zip(truth, scales)) for p in pel)
    return int(found), int(nobody)


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--rows", type=int, default=10, help="photos per number of people and variant")
    ap.add_argument("--people", type=int, nargs="+", default=[3, 4, 5])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    demo = default_h36m_dir() / "demo"
    if not (demo / "annotations.npz").is_file():
        print(f"needs the Human3.6M demo frames at {demo}", file=sys.stderr)
        return 1
    ann = np.load(demo / "annotations.npz")
    rng = np.random.default_rng(args.seed)
    estimators = {name: BlazePoseEstimator(max_people=max(args.people) + 1, window_aspect=a)
                  for name, a in RULES.items()}
    results: list[dict[str, Any]] = []
    print(f"{'people':>6}  {'variant':<11}  {'search':<34} {'recall':>7}  {'all found':>9}  {'nobody':>6}  "
          f"{'ms/photo':>8}  size (median)")
    for n in args.people:
        for variant in ("same size", "mixed sizes", "panorama"):
            photos = []
            for _ in range(args.rows):
                frames = [int(i) for i in rng.choice(len(ann["image"]), n, replace=False)]
                scales = ([1.0] * n if variant == "same size" else [0.6] * n if variant == "panorama"
                          else [float(v) for v in rng.uniform(0.55, 1.0, n)])
                photos.append((*row_photo(ann, demo, frames, scales, margin=1.0 if variant == "panorama" else 0.3),
                               scales))
            for name, est in estimators.items():
                found = nobody = complete = 0
                ms = []
                for img, truth, scales in photos:
                    t0 = time.perf_counter()
                    dets = est.detect(img)
                    ms.append(1000 * (time.perf_counter() - t0))
                    f, z = score(dets, truth, scales)
                    found, nobody, complete = found + f, nobody + z, complete + (f == n)
                size = np.median([img.shape[1] for img, _, _ in photos]), photos[0][0].shape[0]
                row = {"people": n, "variant": variant, "search": name, "recall": found / (n * len(photos)),
                       "all_found": complete, "photos": len(photos), "nobody": nobody,
                       "ms_per_photo": float(np.median(ms)), "median_size": [int(size[0]), int(size[1])]}
                results.append(row)
                print(f"{n:>6}  {variant:<11}  {name:<34} {100 * row['recall']:6.1f}%  {complete:>4} / {len(photos):<3}"
                      f"  {nobody:>6}  {row['ms_per_photo']:8.0f}  {size[0]:.0f} x {size[1]}")
    for est in estimators.values():
        est.close()
    if args.json:
        args.json.write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
