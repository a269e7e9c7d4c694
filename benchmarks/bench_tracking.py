"""Track ids of two people who pass each other, on real detector 2D: how often the tracker swaps or loses them.

    python benchmarks/bench_tracking.py [--model default] [--fps 10] [--behind 0 1000 2000] [--hide 0.5]
        [--cameras ...] [--max-pairs N] [--json out.json]

Two-person sequences are assembled at run time from Human3.6M's Stacked-Hourglass detections: S9's and S11's
sequences of the same action (same name), seen by the same camera (Human3.6M's intrinsics are per camera, so both
people's 2D are in one image), overlaid frame by frame, at ``--fps`` (every 50 / fps-th frame of the 50-fps
detections), as long as the shorter of the two, with S11 moved ``--behind`` mm farther from the camera (one run per
value; at 0 the two share the capture area and stand at the same depths). As the two move about the same area they
pass each other again and again. Where one person's keypoint box hides most of the other's (at least ``--hide`` of the
farther one's box, by ground-truth depth, lies inside the nearer one's), the farther one is left out of that frame,
as a detector misses a person hidden behind another. Each frame's people are lifted (``source="detected"``, the true
camera) and tracked as ``poselifter lift`` tracks a keypoint sequence without names
(:func:`lifter.video.track_lifted`, then :func:`lifter.video.rejoin_tracks`).

Reported per run, summed over the clips: identity switches (a person's track id differs from the one they had when
last seen), person-frames under a track that mostly follows the other person (each track given to the person it
follows most: a swap), and tracks (two per clip would be ideal; more: a person hidden longer than the tracker's
timeout and not taken up again comes back under a new id). Nothing from Human3.6M is written; only the numbers.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from tqdm import tqdm

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter import Lifter, PoseLifterWarning  # noqa: E402
from lifter.camera import world_to_camera  # noqa: E402
from lifter.data import CAMERA_IDS, H36M  # noqa: E402
from lifter.detections import SH_DETECTIONS_FILE  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.video import rejoin_tracks, track_lifted  # noqa: E402

SOURCE_FPS = 50.0


def box(kp: np.ndarray) -> np.ndarray:
    """``(4,)`` x0, y0, x1, y1 px of one person's keypoints ``(17, 2)``."""
    return np.concatenate([kp.min(0), kp.max(0)])


def hidden_share(far: np.ndarray, near: np.ndarray) -> float:
    """The share of box ``far``'s area inside box ``near``."""
    w = max(0.0, min(far[2], near[2]) - max(far[0], near[0]))
    h = max(0.0, min(far[3], near[3]) - max(far[1], near[1]))
    area = max((far[2] - far[0]) * (far[3] - far[1]), 1e-9)
    return w * h / area


def clips(data: H36M, cameras: list[str], step: int, max_pairs: int | None, behind: float):
    """``(name, kp (T, 2, 17, 2) px, gt root (T, 2, 3) mm, camera)`` per pair of same-named sequences and camera,
    S11 moved ``behind`` mm farther along the camera's axis: each joint's 2D offset from the principal point scaled
    by ``Z / (Z + behind)`` with its true depth Z (exact for the true 3D; the detector's error shrinks with it)."""
    det = np.load(Path(data.root) / SH_DETECTIONS_FILE)
    s9 = {s.split("/", 1)[1]: s for s in data.sequences_of([9])}
    s11 = {s.split("/", 1)[1]: s for s in data.sequences_of([11])}
    names = sorted(set(s9) & set(s11))[:max_pairs]
    for name in names:
        for cam_id in cameras:
            kps, roots = [], []
            for subject, seq in ((9, s9[name]), (11, s11[name])):
                key = f"{seq}/{cam_id}"
                world = data.poses_world(seq)
                if key not in det.files or len(det[key]) != len(world):
                    break
                cam = data.camera(subject, cam_id)
                kp = convert(det[key].astype(np.float64), src="sh16")[::step]
                pose = world_to_camera(world, cam.R, cam.t)[::step]
                if subject == 11 and behind:
                    c = np.asarray(cam.principal_point, np.float64)
                    kp = c + (kp - c) * (pose[..., 2:] / (pose[..., 2:] + behind))
                    pose = pose + np.array([0.0, 0.0, behind])
                kps.append(kp)
                roots.append(pose[:, 0])
            if len(kps) != 2:
                continue
            T = min(len(kps[0]), len(kps[1]))
            yield (f"{name} / {cam_id}", np.stack([kps[0][:T], kps[1][:T]], 1),
                   np.stack([roots[0][:T], roots[1][:T]], 1), data.camera(9, cam_id))


def score(frames, who: list[list[int]]) -> dict[str, int]:
    """Identity switches, frames under a track that mostly follows the other person, tracks per person, summed."""
    pairs = [(fr.people[k].track_id, who[i][k]) for i, fr in enumerate(frames) for k in range(len(fr.people))]
    counts: dict[int, np.ndarray] = {}
    for tid, p in pairs:
        counts.setdefault(tid, np.zeros(2, int))[p] += 1
    owner = {tid: int(np.argmax(c)) for tid, c in counts.items()}
    last: dict[int, int] = {}
    switches = 0
    for tid, p in pairs:
        if p in last and last[p] != tid:
            switches += 1
        last[p] = tid
    return {"switches": switches, "wrong_frames": sum(owner[tid] != p for tid, p in pairs),
            "person_frames": len(pairs), "tracks": len(counts)}


def run(model: Lifter, data: H36M, cameras: list[str], fps: float, hide: float,
        max_pairs: int | None, behind: float) -> dict[str, dict[str, float]]:
    step = max(int(round(SOURCE_FPS / fps)), 1)
    total = {"switches": 0, "wrong_frames": 0, "person_frames": 0, "tracks": 0}
    n_clips, n_hidden, n_frames, n_close, t_track = 0, 0, 0, 0, 0.0
    for _name, kp, gt_root, cam in tqdm(list(clips(data, cameras, step, max_pairs, behind)), desc="clips", unit="clip"):
        T = len(kp)
        res = model.lift(kp.reshape(-1, 17, 2), focal=np.asarray(cam.focal),
                         principal_point=np.asarray(cam.principal_point), source="detected")
        root = np.asarray(res.root).reshape(T, 2, 3)
        rel = np.asarray(res.relative).reshape(T, 2, 17, 3)
        lifted, who = [], []
        for t in range(T):
            b = [box(kp[t, 0]), box(kp[t, 1])]
            far = int(gt_root[t, 1, 2] > gt_root[t, 0, 2])
            keep = [0, 1]
            share = hidden_share(b[far], b[1 - far])
            n_close += int(share > 0)
            if share >= hide:
                keep = [1 - far]
                n_hidden += 1
            lifted.append((t, t / fps, kp[t, keep], root[t, keep], rel[t, keep], None))
            who.append(keep)
        n_clips, n_frames = n_clips + 1, n_frames + T
        t0 = time.perf_counter()
        frames = track_lifted(lifted, fps=fps, focal=np.asarray(cam.focal), smoothing=0.0)
        rejoin_tracks(frames, fps=fps)
        t_track += time.perf_counter() - t0
        for k, v in score(frames, who).items():
            total[k] += v
    out: dict[str, dict[str, float]] = {"tracker": dict(total)}
    out["_info"] = {"behind_mm": behind, "clips": n_clips, "frames": n_frames, "frames_with_boxes_overlapping": n_close,
                    "frames_with_one_hidden": n_hidden, "fps": fps, "hide": hide,
                    "track_ms_per_frame": 1e3 * t_track / max(n_frames, 1)}
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--model", default="default")
    ap.add_argument("--fps", type=float, default=10.0, help="frame rate of the clips (the detections are 50 fps)")
    ap.add_argument("--hide", type=float, default=0.5,
                    help="leave the farther person out where this share of their box lies in the nearer one's")
    ap.add_argument("--cameras", nargs="+", default=list(CAMERA_IDS))
    ap.add_argument("--behind", type=float, nargs="+", default=[0.0, 1000.0, 2000.0],
                    help="S11 this far behind where they were (mm along the camera's axis), one run each")
    ap.add_argument("--max-pairs", type=int, default=None, help="the first N action names only (quick runs)")
    ap.add_argument("--json", type=Path, default=None)
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    warnings.filterwarnings("ignore", category=PoseLifterWarning)  # (the lifts' own notes: not what is measured)
    model, data = Lifter.load(args.model), H36M()
    results = {}
    print(f"lifter {model.name}, {args.fps:g} fps, the farther person left out where >= {args.hide:g} of their box "
          "is inside the nearer one's\n")
    print("| S11 moved back | clips, frames | frames one is hidden | identity switches | person-frames "
          "under the other's track | tracks (2 per clip ideal) |\n|---|---|---|---|---|---|")
    for behind in args.behind:
        out = results[f"behind {behind:g} mm"] = run(model, data, args.cameras, args.fps, args.hide, args.max_pairs,
                                                     behind)
        info = out["_info"]
        m = out["tracker"]
        print(f"| {behind / 1000:g} m | {info['clips']}, {info['frames']} | {info['frames_with_one_hidden']} | "
              f"{m['switches']} | {m['wrong_frames']} of {m['person_frames']} "
              f"({100 * m['wrong_frames'] / max(m['person_frames'], 1):.2f} %) | {m['tracks']} "
              f"(for {2 * info['clips']}) |")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps({"model": model.name, "fps": args.fps, "hide": args.hide,
                                         "results": results}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
