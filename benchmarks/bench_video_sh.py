"""Temporal smoothing measured on real 2D detector jitter at full frame rate: the Stacked-Hourglass detections
of S9 and S11 (every frame, 50 fps, all four cameras; S9 "Discussion 1" has no 3D) go through the same tracker
and One-Euro filter as ``poselifter lift`` on a keypoint sequence (:func:`lifter.video.track_lifted`).

    python benchmarks/bench_video_sh.py [--model default] [--strengths 0 0.5 1 2] [--subjects 9 11] [--json out.json]

Per frame, each sequence lifted frame by frame (``source="detected"``, true camera), then tracked and smoothed
causally. Reported per strength (0 = no smoothing = lifting each frame on its own): MPJPE (root-aligned),
MRPE (mm), and the acceleration error (mm/frame^2 at 50 fps: the norm of the difference between predicted and
true second differences) of the root (absolute) and of the joints (root-relative), all frames where the
sequence's detections exist, plus the fraction of frames whose person kept track id 1 (tracker stability).
Nothing from H36M is written; only the numbers.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter import Lifter  # noqa: E402
from lifter.camera import world_to_camera  # noqa: E402
from lifter.data import CAMERA_IDS, H36M  # noqa: E402
from lifter.detections import SH_DETECTIONS_FILE  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.video import track_lifted  # noqa: E402

FPS = 50.0


def accel(x: np.ndarray) -> np.ndarray:
    return x[2:] - 2 * x[1:-1] + x[:-2]


def sequences(data: H36M, subjects: list[int], cameras: list[str]):
    det = np.load(Path(data.root) / SH_DETECTIONS_FILE)
    for seq in data.sequences_of(subjects):
        subject = int(seq.split("/")[0][1:])
        world = data.poses_world(seq)
        for cam_id in cameras:
            key = f"{seq}/{cam_id}"
            if key not in det.files:
                continue
            kp = det[key].astype(np.float64)
            if len(kp) != len(world):
                continue
            cam = data.camera(subject, cam_id)
            yield key, convert(kp, src="sh16"), world_to_camera(world, cam.R, cam.t), cam


def run(lifter: Lifter, data: H36M, subjects: list[int], cameras: list[str], strengths: list[float],
        max_frames: int | None = None) -> dict[str, dict[str, float]]:
    acc: dict[float, dict[str, list[float]]] = {s: {k: [] for k in ("mpjpe", "mrpe", "acc_root", "acc_joints")}
                                                for s in strengths}
    stable, n_frames, t_track = [], 0, 0.0
    for _key, kp, gt, cam in sequences(data, subjects, cameras):
        if max_frames is not None:
            kp, gt = kp[:max_frames], gt[:max_frames]
        f = np.asarray(cam.focal)
        res = lifter.lift(kp, focal=f, principal_point=np.asarray(cam.principal_point), source="detected")
        root, rel = np.asarray(res.root), np.asarray(res.relative)
        T = len(kp)
        n_frames += T
        gt_rel = gt - gt[:, :1]
        for s in strengths:
            t0 = time.perf_counter()
            frames = track_lifted([(i, i / FPS, kp[i:i + 1], root[i:i + 1], rel[i:i + 1], None) for i in range(T)],
                                  fps=FPS, focal=f, smoothing=s)
            t_track += time.perf_counter() - t0
            r = np.stack([fr.people[0].root for fr in frames])
            q = np.stack([fr.people[0].relative for fr in frames])
            if s == strengths[0]:
                stable.append(np.mean([fr.people[0].track_id == 1 for fr in frames]))
            a = acc[s]
            a["mpjpe"].append(np.linalg.norm(q - gt_rel, axis=-1).mean(-1).sum())
            a["mrpe"].append(np.linalg.norm(r - gt[:, 0], axis=-1).sum())
            a["acc_root"].append(np.linalg.norm(accel(r) - accel(gt[:, 0]), axis=-1).sum())
            a["acc_joints"].append(np.linalg.norm(accel(q) - accel(gt_rel), axis=-1).mean(-1).sum())
    out: dict[str, dict[str, float]] = {}
    for s, a in acc.items():
        out[f"strength {s:g}"] = {"mpjpe": sum(a["mpjpe"]) / n_frames, "mrpe": sum(a["mrpe"]) / n_frames,
                                  "accel_root": sum(a["acc_root"]) / (n_frames - 2 * len(a["mpjpe"])),
                                  "accel_joints": sum(a["acc_joints"]) / (n_frames - 2 * len(a["mpjpe"]))}
    out["_info"] = {"frames": n_frames, "sequences_x_cameras": len(stable),
                    "frames_on_track_1": float(np.mean(stable)),
                    "track_and_smooth_ms_per_frame": 1e3 * t_track / max(n_frames * len(strengths), 1)}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--model", default="default")
    ap.add_argument("--strengths", type=float, nargs="+", default=[0.0, 0.5, 1.0, 2.0])
    ap.add_argument("--subjects", type=int, nargs="+", default=[9, 11])
    ap.add_argument("--cameras", nargs="+", default=list(CAMERA_IDS))
    ap.add_argument("--max-frames", type=int, default=None, help="first frames of each sequence only (quick runs)")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    lifter, data = Lifter.load(args.model), H36M()
    results = {}
    for s in args.subjects:
        results[f"S{s}"] = run(lifter, data, [s], args.cameras, args.strengths, args.max_frames)
        info = results[f"S{s}"]["_info"]
        print(f"S{s}: {info['frames']} frames ({info['sequences_x_cameras']} sequence x camera), lifter {lifter.name}, "
              f"track id kept on {100 * info['frames_on_track_1']:.2f} % of frames")
        print("| smoothing strength | MPJPE | MRPE | accel. error root | accel. error joints |\n|---|---|---|---|---|")
        for k, m in results[f"S{s}"].items():
            if not k.startswith("_"):
                print(f"| {k.split()[1]} | {m['mpjpe']:.1f} | {m['mrpe']:.1f} | {m['accel_root']:.2f} | "
                      f"{m['accel_joints']:.2f} |")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"model": lifter.name, "fps": FPS, "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
