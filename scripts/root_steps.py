"""How often :func:`lifter.video.track_root_steps` names a step of a track's root on one person's real 2D: the
Stacked-Hourglass detections of the test subjects (S9, S11; every frame), each sequence seen by each camera one track,
lifted by the default (source="detected", each camera's own intrinsics and lens), at 50 and 25 frames/s. The
measurement behind :data:`lifter.video.ROOT_STEP_MM` (a user trial's keypoint sequence gave one id to a second person
0.96 m deeper, and the track's root stepped without a word).

    python scripts/root_steps.py [--model default] [--out docs/results/root_steps.txt]

Sequences with a frame the detector missed are left out (a step is judged over consecutive frames only).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import emit  # noqa: E402  (scripts/_report.py)

from lifter import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detections import SH_DETECTIONS_FILE  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.video import ROOT_STEP_MM, ROOT_STEP_WINDOW_S, FrameResult, PersonState, track_root_steps  # noqa: E402

FPS = 50.0


def _track(root: np.ndarray, fps: float) -> list[FrameResult]:
    zero2, zero3 = np.zeros((17, 2)), np.zeros((17, 3))
    return [FrameResult(index=i, time_s=i / fps, people=[PersonState(
        track_id=1, keypoints_2d=zero2, root=r, relative=zero3, root_raw=r, relative_raw=zero3,
        canonical_depth=float(r[2]))]) for i, r in enumerate(root)]


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--model", default="default")
    ap.add_argument("--subjects", type=int, nargs="+", default=[9, 11])
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    data = H36M(args.h36m or default_h36m_dir())
    lifter = Lifter.load(args.model)
    with np.load(Path(data.root) / SH_DETECTIONS_FILE) as d:
        keys = [k for k in d.files if int(k.split("/")[0][1:]) in args.subjects]
        dets = {k: d[k] for k in keys}
    frames = {1: 0, 2: 0}
    hits: dict[int, list[tuple[str, float]]] = {1: [], 2: []}
    skipped = 0
    for k in tqdm(sorted(dets), desc="sequences x cameras"):
        s, _, cam_id = k.split("/")
        kp = convert(dets[k].astype(np.float64), src="sh16", warn=False)
        if not np.isfinite(kp).all():
            skipped += 1
            continue
        cam = data.camera(int(s[1:]), cam_id)
        root = np.asarray(lifter.lift(kp, focal=cam.focal, principal_point=cam.principal_point,
                                      distortion=[*cam.k, *cam.p], warn=False).root)
        for stride in (1, 2):
            r = root[::stride]
            frames[stride] += len(r)
            for found in track_root_steps(_track(r, FPS / stride), fps=FPS / stride).values():
                hits[stride] += [(k, step) for _, _, step in found]
    who = ", ".join(f"S{s}" for s in args.subjects)
    lines = [f"Root steps (lifter.video.track_root_steps: > {ROOT_STEP_MM:g} mm between the medians of the "
             f"{ROOT_STEP_WINDOW_S:g} s either side) on the real SH detections of {who}, lifted by "
             f"{lifter.name}; {len(dets) - skipped} sequence x camera tracks ({skipped} with a missed frame left out)",
             "", "| frames/s | frames | steps named | one per | largest step (mm) |", "|---|---|---|---|---|"]
    for stride in (1, 2):
        fps, n, found = FPS / stride, frames[stride], hits[stride]
        per = f"{n / max(len(found), 1) / fps / 60:.1f} min" if found else "-"
        top = f"{max(s for _, s in found):.0f}" if found else "-"
        lines.append(f"| {fps:g} | {n} | {len(found)} | {per} | {top} |")
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
