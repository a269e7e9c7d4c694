"""How often :func:`lifter.video.track_root_steps` names a step of a track's root on one person's real 2D: the
Stacked-Hourglass detections of the test subjects (S9, S11; every frame), each sequence seen by each camera one track,
lifted by the default (source="detected", each camera's own intrinsics and lens), at 50 and 25 frames/s. The
measurement behind :data:`lifter.video.ROOT_STEP_MM` (a user trial's keypoint sequence gave one id to a second person
0.96 m deeper, and the track's root stepped without a word) and :data:`lifter.video.ROOT_STEP_DEPTH_SHARE` (a developer
trial's still people 20 m away were named over and over).

    python scripts/root_steps.py [--model default] [--farther 1,2,4] [--out docs/results/root_steps.txt]

``--farther K`` moves each person along their rays to K times their depth (every joint by K - 1 times the root) and
shrinks the detector's error with them: the 2D is the farther pose's projection (the camera's lens included) plus the
detection's own error against the ground truth's projection, divided by K (a detector reads a person at its own
scale); sequences without 3D are left out of K != 1. Each step is judged twice: by the rule shipped and by
:data:`lifter.video.ROOT_STEP_MM` alone. Sequences with a frame the detector missed are left out (a step is judged
over consecutive frames only).
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
from lifter.camera import project, world_to_camera  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detections import SH_DETECTIONS_FILE  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.video import (  # noqa: E402
    ROOT_STEP_DEPTH_SHARE,
    ROOT_STEP_MM,
    ROOT_STEP_WINDOW_S,
    FrameResult,
    PersonState,
    track_root_steps,
)

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
    ap.add_argument("--farther", default="1",
                    help="depth factors, comma-separated (default 1: the detections as they are)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    farther = [float(v) for v in args.farther.split(",")]
    data = H36M(args.h36m or default_h36m_dir())
    lifter = Lifter.load(args.model)
    with np.load(Path(data.root) / SH_DETECTIONS_FILE) as d:
        keys = [k for k in d.files if int(k.split("/")[0][1:]) in args.subjects]
        dets = {k: d[k] for k in keys}
    rules = {"shipped": ROOT_STEP_DEPTH_SHARE, "800 mm alone": 0.0}
    rows = [(k, stride) for k in farther for stride in (1, 2)]
    frames = dict.fromkeys(rows, 0)
    hits: dict[tuple[float, int, str], list[float]] = {(*r, rule): [] for r in rows for rule in rules}
    depth: dict[float, list[float]] = {k: [] for k in farther}
    tracks = dict.fromkeys(farther, 0)
    skipped = 0
    for key in tqdm(sorted(dets), desc="sequences x cameras"):
        s, seq, cam_id = key.split("/")
        det = convert(dets[key].astype(np.float64), src="sh16", warn=False)
        if not np.isfinite(det).all():
            skipped += 1
            continue
        cam = data.camera(int(s[1:]), cam_id)
        lens = {"k": cam.k, "p": cam.p}
        for k in farther:
            if k == 1:
                kp = det
            elif f"{s}/{seq}" not in data.sequences:
                continue
            else:
                X = world_to_camera(data.poses_world(f"{s}/{seq}"), cam.R, cam.t)[:len(det)]
                far = X + (k - 1) * X[:, :1]
                kp = project(far, focal=cam.focal, principal_point=cam.principal_point, **lens) + (
                    det[:len(X)] - project(X, focal=cam.focal, principal_point=cam.principal_point, **lens)) / k
            root = np.asarray(lifter.lift(kp, focal=cam.focal, principal_point=cam.principal_point,
                                          distortion=[*cam.k, *cam.p], warn=False).root)
            tracks[k] += 1
            depth[k].append(float(np.median(root[:, 2])))
            for stride in (1, 2):
                r = root[::stride]
                frames[k, stride] += len(r)
                for rule, share in rules.items():
                    found = track_root_steps(_track(r, FPS / stride), fps=FPS / stride, depth_share=share)
                    hits[k, stride, rule] += [step for one in found.values() for _, _, step in one]
    who = ", ".join(f"S{s}" for s in args.subjects)
    lines = [f"Root steps (lifter.video.track_root_steps: > {ROOT_STEP_MM:g} mm and > {ROOT_STEP_DEPTH_SHARE:g} x the "
             f"nearer median's depth, between the medians of the {ROOT_STEP_WINDOW_S:g} s either side) on the real SH "
             f"detections of {who}, lifted by {lifter.name}; {skipped} sequence x camera tracks with a missed frame "
             "left out; 'farther': people moved along their rays to that many times their depth, the detector's "
             "error shrunk with them", "",
             "| farther | tracks | median root depth (m) | frames/s | frames | rule | steps named | one per | "
             "largest step (mm) |", "|---|---|---|---|---|---|---|---|---|"]
    for k, stride in rows:
        for rule in rules:
            fps, n, found = FPS / stride, frames[k, stride], hits[k, stride, rule]
            per = f"{n / max(len(found), 1) / fps / 60:.1f} min" if found else "-"
            per = per if not found or n / len(found) / fps >= 60 else f"{n / len(found) / fps:.1f} s"
            top = f"{max(found):.0f}" if found else "-"
            lines.append(f"| {k:g} | {tracks[k]} | {np.median(depth[k]) / 1000:.1f} | {fps:g} | {n} | {rule} | "
                         f"{len(found)} | {per} | {top} |")
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
