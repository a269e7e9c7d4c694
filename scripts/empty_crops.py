"""Does the photo path say so when BlazePose invents a person? Crops of the 84 Human3.6M demo photos that leave the
subject out (the wall, the mocap cameras, the floor), blown up to 800 x 800 px, lifted by ``lift_image`` as
``poselifter lift`` does; and the 84 photos themselves. The measurement behind :data:`lifter.detect.DOUBTFUL_SCORE`
being read on the 17 joints lifted (:func:`lifter.pipeline.detector_doubt_notes`), and behind
:data:`lifter.detect.MIN_PERSON_SCORE`, below which a detection is left out as no person (everyone is kept here,
``min_score=0``, to be counted).

    python scripts/empty_crops.py [--h36m ../shared/data/h36m] [--crops 240] [--seed 0]
                                  [--out docs/results/empty_crops.txt]

The crops are written to a temporary folder and deleted (Human3.6M-derived: never kept); only numbers are printed.
A crop is square, 150-500 px of the 1000-px photo, at a random place that does not touch the subject's box.
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
from lifter.data import default_h36m_dir  # noqa: E402
from lifter.detect import (  # noqa: E402
    DOUBTFUL_SCORE,
    MIN_PERSON_SCORE,
    BlazePoseEstimator,
    NoPersonError,
    detect_people,
    load_image,
)
from lifter.pipeline import lift_image  # noqa: E402

WHOLE_PERSON_NOTES = {"score": "mean joint score", "misfit": "do not fit their 2D",
                      "upside down": "upside down", "outside": "placed most joints of"}


def _photo_path(demo: Path, name: str) -> Path:
    for p in (demo / "images" / os.path.basename(name), demo / name):
        if p.is_file():
            return p
    raise SystemExit(f"cannot find the demo photo {name} under {demo}")


def _photo(demo: Path, name: str) -> np.ndarray:
    img = cv2.imread(str(_photo_path(demo, name)))
    if img is None:
        raise SystemExit(f"cannot read the demo photo {name} under {demo}")
    return img


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--crops", type=int, default=240)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=None, help="also write the report here")
    args = ap.parse_args()
    demo = (args.h36m or default_h36m_dir()) / "demo"
    ann = np.load(demo / "annotations.npz")
    lifter = Lifter.from_pretrained()
    rng = np.random.default_rng(args.seed)
    tmp = Path(tempfile.mkdtemp(prefix="empty_crops_"))
    fakes: list[tuple[float, float, list[str]]] = []  # (mean of 33 landmarks, mean of 17 joints, whole-person notes)
    real17: list[float] = []
    per_crop: list[list[float]] = []  # (each crop's people: the mean score of their 17 joints)
    crops_with = 0
    try:
        with BlazePoseEstimator(max_people=3) as est:
            done = 0
            bar = tqdm(total=args.crops, desc="empty crops", unit="crop")
            while done < args.crops:
                i = int(rng.integers(len(ann["image"])))
                img = _photo(demo, str(ann["image"][i]))
                H, W = img.shape[:2]
                x, y, w, h = ann["bbox_xywh"][i]
                side = int(rng.integers(150, 500))
                cx, cy = int(rng.integers(0, W - side)), int(rng.integers(0, H - side))
                if not (cx + side < x or cx > x + w or cy + side < y or cy > y + h):
                    continue  # (touches the subject)
                done += 1
                bar.update()
                crop = cv2.resize(img[cy:cy + side, cx:cx + side], (800, 800), interpolation=cv2.INTER_CUBIC)
                path = tmp / "crop.jpg"
                cv2.imwrite(str(path), crop)
                try:
                    rec = lift_image(path, lifter=lifter, estimator=est, min_score=0)
                except NoPersonError:
                    continue
                said = [k for k, text in WHOLE_PERSON_NOTES.items() if any(text in ww for ww in rec.warnings)]
                dets = detect_people(load_image(path), estimator=est, min_score=0)  # (as lift_image found them)
                crops_with += 1
                per_crop.append([float(np.mean(d.scores)) for d in dets])
                for d in dets:
                    fakes.append((float(np.mean(d.raw.scores)), float(np.mean(d.scores)), said))
            bar.close()
            for i in tqdm(range(len(ann["image"])), desc="demo photos", unit="photo"):
                d = detect_people(load_image(_photo_path(demo, str(ann["image"][i]))), estimator=est, min_score=0)[0]
                real17.append(float(np.mean(d.scores)))
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    s33, s17 = np.array([f[0] for f in fakes]), np.array([f[1] for f in fakes])
    noted = [f for f in fakes if f[2]]
    lines = [
        f"{args.crops} crops without the subject (seed {args.seed}), 800 x 800 px; the default model {lifter.name}",
        f"BlazePose found {len(fakes)} 'people' in {crops_with} of the crops",
        f"  mean score of the 17 joints lifted: below {DOUBTFUL_SCORE:g} in {int((s17 < DOUBTFUL_SCORE).sum())}, "
        f"quartiles {np.percentile(s17, 25):.2f} / {np.median(s17):.2f} / {np.percentile(s17, 75):.2f}"
        if len(fakes) else "  (none)",
        f"  below {MIN_PERSON_SCORE:g} (left out as no person by default, MIN_PERSON_SCORE): "
        f"{int((s17 < MIN_PERSON_SCORE).sum())} of {len(fakes)}; crops with nobody left: "
        f"{sum(all(v < MIN_PERSON_SCORE for v in c) for c in per_crop)} of {crops_with}",
        f"  mean of BlazePose's 33 landmarks (the rule before): below {DOUBTFUL_SCORE:g} in "
        f"{int((s33 < DOUBTFUL_SCORE).sum())}; one but not the other: 17 joints only "
        f"{int(((s17 < DOUBTFUL_SCORE) & (s33 >= DOUBTFUL_SCORE)).sum())}, 33 landmarks only "
        f"{int(((s33 < DOUBTFUL_SCORE) & (s17 >= DOUBTFUL_SCORE)).sum())}",
        f"  with a whole-person note (score, misfit, upside down, outside the image): {len(noted)} of {len(fakes)}",
        "  by note: " + ", ".join(f"{k} {sum(k in f[2] for f in fakes)}" for k in WHOLE_PERSON_NOTES),
        "  without a whole-person note, mean score of the 17 joints: "
        + (f"{min(f[1] for f in fakes if not f[2]):.2f}-{max(f[1] for f in fakes if not f[2]):.2f}"
           if any(not f[2] for f in fakes) else "(none)"),
        f"the 84 demo photos' largest person, mean score of the 17 joints: min {min(real17):.2f}, median "
        f"{np.median(real17):.2f}, below {DOUBTFUL_SCORE:g} in {sum(v < DOUBTFUL_SCORE for v in real17)}",
    ]
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
