"""Does the detector of the ``detect`` extra (mediapipe 0.10.31, Tasks ``PoseLandmarker`` on the bundle built
from the 0.10.21 wheel's models) give the same BlazePose as the legacy ``mediapipe.solutions.pose`` graph of
mediapipe 0.10.21 (which needs numpy < 2, hence a separate interpreter)?

    python3 -m venv /tmp/mp21 && /tmp/mp21/bin/pip install mediapipe==0.10.21 "numpy<2" pillow
    python benchmarks/compare_legacy_blazepose.py --legacy-python /tmp/mp21/bin/python

Runs both on the 84 H36M demo photos (one pass each, full model, detection confidence 0.5, one person) and
prints how many photos each finds a person in and the landmark distances (px) between the two. The legacy
landmarks are kept in the git-ignored ``runs/cache/`` (H36M-derived, never committed).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter.data import default_h36m_dir  # noqa: E402
from lifter.detect import BlazePoseEstimator, load_image  # noqa: E402

LEGACY = r"""
import json, sys
import numpy as np
from PIL import Image, ImageOps
from mediapipe.python.solutions import pose as mp_pose
paths, out = json.loads(sys.argv[1]), sys.argv[2]
P = mp_pose.Pose(static_image_mode=True, model_complexity=1, enable_segmentation=False, min_detection_confidence=0.5)
kp = np.full((len(paths), 33, 2), np.nan)
for i, p in enumerate(paths):
    a = np.asarray(ImageOps.exif_transpose(Image.open(p)).convert("RGB"))
    r = P.process(a)
    if r.pose_landmarks is not None:
        kp[i] = [[q.x * a.shape[1], q.y * a.shape[0]] for q in r.pose_landmarks.landmark]
np.save(out, kp)
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--legacy-python", required=True, help="a python with mediapipe==0.10.21 (and numpy<2)")
    args = ap.parse_args()
    demo = default_h36m_dir() / "demo"
    ann = np.load(demo / "annotations.npz")
    paths = [str(demo / str(p)) for p in ann["image"]]
    cache = ROOT / "runs" / "cache" / "legacy_blazepose_demo.npy"
    cache.parent.mkdir(parents=True, exist_ok=True)
    proc = subprocess.run([args.legacy_python, "-c", LEGACY, json.dumps(paths), str(cache)], capture_output=True,
                          text=True)
    if proc.returncode != 0:
        raise SystemExit(f"the legacy run failed:\n{proc.stderr[-2000:]}")
    legacy = np.load(cache)
    new = np.full_like(legacy, np.nan)
    with BlazePoseEstimator(max_people=1) as est:  # one pass over the whole image, as the legacy graph
        for i, p in enumerate(paths):
            d = est.detect(load_image(p).rgb)
            if d:
                new[i] = d[0].keypoints
    a, b = ~np.isnan(legacy[:, 0, 0]), ~np.isnan(new[:, 0, 0])
    both = a & b
    dist = np.linalg.norm(legacy[both] - new[both], axis=-1)
    print(f"{len(paths)} photos: legacy found {a.sum()}, Tasks found {b.sum()}, both {both.sum()}, "
          f"only one of them {(a ^ b).sum()}")
    print(f"landmark distance over the {both.sum()} photos, 33 landmarks each: max {dist.max():.2f} px, "
          f"mean {dist.mean():.3f} px, median {np.median(dist):.3f} px, 99th percentile "
          f"{np.percentile(dist, 99):.2f} px")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
