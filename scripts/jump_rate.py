"""How often :func:`lifter.video.track_jumps` names a frame: on Human3.6M's ground-truth 2D (people's own motion,
which should never jump) at several frame rates, and on the real Stacked-Hourglass detections (where a jump is the
detector's mistake). The measurement behind :data:`lifter.video.JUMP_FRACTION` (a user trial's video frame put the
head below the pelvis and was lifted 535 mm off, with no word).

    python scripts/jump_rate.py [--h36m ../shared/data/h36m] [--subjects 9 11] [--out docs/results/jump_rate.txt]

Each sequence seen by each camera is one track (``FrameResult``s of one person); ground truth at 50, 10, 5 and 2
frames/s (every 1st, 5th, 10th, 25th frame); the detections at 50 frames/s where the file has every frame (S9, S11),
converted to H36M's 17 joints by the library's ``sh16`` rule.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import emit  # noqa: E402  (scripts/_report.py)

from lifter.data import CAMERA_IDS, H36M, default_h36m_dir  # noqa: E402
from lifter.detections import SH_DETECTIONS_FILE  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.video import (  # noqa: E402
    JUMP_END_MAX_SPAN_S,
    JUMP_FRACTION,
    JUMP_LIMB_MAX_SPAN_S,
    JUMP_MAX_SPAN_S,
    FrameResult,
    PersonState,
    track_jumps,
)

FPS = 50.0


def _track(kp: np.ndarray, fps: float) -> list[FrameResult]:
    zero, root = np.zeros((17, 3)), np.array([0.0, 0.0, 3000.0])
    return [FrameResult(index=i, time_s=i / fps, people=[PersonState(
        track_id=1, keypoints_2d=k, root=root, relative=zero, root_raw=root, relative_raw=zero,
        canonical_depth=3000.0)]) for i, k in enumerate(kp)]


def _rate(tracks: list[np.ndarray], fps: float) -> tuple[int, int, int, int, float]:
    """Frames named as a whole pose, by a limb, and at a track's end; frames judged (each track's inner frames); and
    the largest jump's median joint px."""
    whole = limb = end = judged = 0
    worst = 0.0
    for kp in tracks:
        hits = track_jumps(_track(kp, fps), fps=fps).get(1, [])
        end += sum(h.at_end for h in hits)
        whole += sum(not h.at_end and h.part == "2D" for h in hits)
        limb += sum(not h.at_end and h.part != "2D" for h in hits)
        judged += max(0, len(kp) - 2) if 2 / fps <= JUMP_MAX_SPAN_S + 1e-9 else 0
        worst = max([worst, *(h.off_px for h in hits)])
    return whole, limb, end, judged, worst


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--subjects", type=int, nargs="+", default=[9, 11])
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    data = H36M(args.h36m or default_h36m_dir())
    seqs = data.sequences_of(args.subjects)
    lines = [f"# track_jumps: JUMP_FRACTION {JUMP_FRACTION}, JUMP_MAX_SPAN_S {JUMP_MAX_SPAN_S} s, "
             f"JUMP_LIMB_MAX_SPAN_S {JUMP_LIMB_MAX_SPAN_S} s, JUMP_END_MAX_SPAN_S {JUMP_END_MAX_SPAN_S} s; subjects "
             f"{args.subjects}, {len(seqs)} sequences x {len(CAMERA_IDS)} cameras, each one track",
             "", "| 2D | frames/s | inner frames judged | named as a whole | by a limb | per 10,000 | "
             "track ends named (of 2 per track) |", "|---|---|---|---|---|---|---|"]
    gt: dict[int, list[np.ndarray]] = {1: [], 5: [], 10: [], 25: []}
    for seq in tqdm(seqs, desc="ground truth", disable=not sys.stderr.isatty()):
        world = data.poses_world(seq)
        for cam_id in CAMERA_IDS:
            cam = data.camera(int(seq.split("/")[0][1:]), cam_id)
            kp = cam.project(cam.world_to_camera(world))
            for stride in gt:
                gt[stride].append(kp[::stride])
    for stride, tracks in gt.items():
        fps = FPS / stride
        whole, limb, end, judged, _ = _rate(tracks, fps)
        per = f"{1e4 * (whole + limb) / judged:.2f}" if judged else "not judged (over 0.4 s)"
        lines.append(f"| ground truth | {fps:g} | {judged} | {whole} | {limb} | {per} | {end} of {2 * len(tracks)} |")
    det_path = Path(data.root) / SH_DETECTIONS_FILE
    if det_path.is_file():
        with np.load(det_path) as d:
            tracks = [convert(d[k].astype(np.float64), src="sh16", warn=False) for k in d.files
                      if k.split("/")[0] in {f"S{s}" for s in args.subjects}]
        for stride in (1, 2):
            whole, limb, end, judged, worst = _rate([t[::stride] for t in tracks], FPS / stride)
            lines.append(f"| SH detections | {FPS / stride:g} | {judged} | {whole} | {limb} | "
                         f"{1e4 * (whole + limb) / judged:.2f} | {end} of {2 * len(tracks)} |")
        lines += ["", f"The largest jump named in the detections at 25 frames/s: median joint {worst:.0f} px off "
                      "where the frames next to it put it."]
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
