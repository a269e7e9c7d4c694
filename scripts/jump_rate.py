"""How often :func:`lifter.video.track_jumps` names a frame: on Human3.6M's ground-truth 2D (people's own motion,
which should never jump) at several frame rates, and on the real Stacked-Hourglass detections (where a jump is the
detector's mistake). The measurement behind :data:`lifter.video.JUMP_FRACTION` (a user trial's video frame put the
head below the pelvis and was lifted 535 mm off, with no word).

    python scripts/jump_rate.py [--h36m ../shared/data/h36m] [--subjects 9 11] [--out docs/results/jump_rate.txt]

Each sequence seen by each camera is one track (``FrameResult``s of one person); ground truth at 50, 25, 10, 5 and 2
frames/s (every 1st, 2nd, 5th, 10th, 25th frame); the detections at 50 and 25 frames/s where the file has every
frame (S9, S11), converted to H36M's 17 joints by the library's ``sh16`` rule, each named frame checked against the
ground truth.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import emit  # noqa: E402  (scripts/_report.py)

from lifter.data import CAMERA_IDS, H36M, default_h36m_dir  # noqa: E402
from lifter.detections import SH_DETECTIONS_FILE  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.skeleton import JOINT_NAMES  # noqa: E402
from lifter.video import (  # noqa: E402
    JUMP_END_MAX_SPAN_S,
    JUMP_FRACTION,
    JUMP_LIMB_MAX_SPAN_S,
    JUMP_LIMBS,
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


def _rate(tracks: list[np.ndarray], fps: float, truth: list[np.ndarray] | None = None) -> dict[str, Any]:
    """Frames named as a whole pose, by a limb, and at a track's end (each ``None`` where that check never runs at
    ``fps``), inner frames judged, the largest whole-pose jump (median joint px), and with the ``truth`` 2D of each
    track: how many named frames have the part named more than half :data:`JUMP_FRACTION` of the box diagonal off
    the truth (the detector's mistake there, not its neighbours')."""
    span = 2 / fps
    out: dict[str, Any] = {
        "whole": 0 if span <= JUMP_MAX_SPAN_S + 1e-9 else None,
        "limb": 0 if span <= JUMP_LIMB_MAX_SPAN_S + 1e-9 else None,
        "end": 0 if 3 / fps <= JUMP_END_MAX_SPAN_S + 1e-9 else None, "judged": 0, "worst": 0.0, "wrong": 0}
    parts = {"2D": slice(None), **{name: [JOINT_NAMES.index(j) for j in js] for name, js in JUMP_LIMBS}}
    for t, kp in enumerate(tracks):
        hits = track_jumps(_track(kp, fps), fps=fps).get(1, [])
        for h in hits:
            kind = "end" if h.end is not None else "whole" if h.part == "2D" else "limb"
            out[kind] += 1
            if h.part == "2D" and h.end is None:
                out["worst"] = max(out["worst"], h.off_px)
            if truth is not None:
                js = parts[h.part]
                size = float(np.hypot(*np.ptp(truth[t][h.frame], axis=0)))
                off = float(np.median(np.linalg.norm(kp[h.frame][js] - truth[t][h.frame][js], axis=-1)))
                out["wrong"] += off > 0.5 * JUMP_FRACTION * size
        out["judged"] += max(0, len(kp) - 2) if out["whole"] is not None else 0
    return out


def _cell(n: int | None) -> str:
    return "not judged" if n is None else str(n)


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
             "", "| 2D | frames/s | inner frames judged | named as a whole | by a limb | track ends named (of 2 per "
             "track) | named, per 10,000 inner frames | of those named, the part > half the threshold off the truth |",
             "|---|---|---|---|---|---|---|---|"]
    gt: dict[int, list[np.ndarray]] = {1: [], 2: [], 5: [], 10: [], 25: []}
    truth: dict[str, np.ndarray] = {}
    for seq in tqdm(seqs, desc="ground truth", disable=not sys.stderr.isatty()):
        world = data.poses_world(seq)
        for cam_id in CAMERA_IDS:
            cam = data.camera(int(seq.split("/")[0][1:]), cam_id)
            kp = cam.project(cam.world_to_camera(world))
            truth[f"{seq}/{cam_id}"] = kp
            for stride in gt:
                gt[stride].append(kp[::stride])

    def row(name: str, fps: float, r: dict[str, Any], n_tracks: int, checked: bool) -> str:
        named = sum(r[k] or 0 for k in ("whole", "limb"))
        per = f"{1e4 * named / r['judged']:.2f}" if r["judged"] else "not judged"
        all_named = named + (r["end"] or 0)
        ok = f"{r['wrong']} of {all_named}" if checked else "(the truth itself)"
        end = "not judged" if r["end"] is None else f"{r['end']} of {2 * n_tracks}"
        return (f"| {name} | {fps:g} | {r['judged']} | {_cell(r['whole'])} | {_cell(r['limb'])} | {end} | {per} | "
                f"{ok} |")

    for stride, tracks in gt.items():
        lines.append(row("ground truth", FPS / stride, _rate(tracks, FPS / stride), len(tracks), False))
    det_path = Path(data.root) / SH_DETECTIONS_FILE
    worst = None
    if det_path.is_file():
        with np.load(det_path) as d:
            keys = [k for k in d.files if k.split("/")[0] in {f"S{s}" for s in args.subjects} and k in truth]
            tracks = [convert(d[k].astype(np.float64), src="sh16", warn=False) for k in keys]
        true = [truth[k][:len(t)] for k, t in zip(keys, tracks)]
        tracks = [t[:len(g)] for t, g in zip(tracks, true)]
        for stride in (1, 2):
            r = _rate([t[::stride] for t in tracks], FPS / stride, [g[::stride] for g in true])
            lines.append(row("SH detections", FPS / stride, r, len(tracks), True))
            worst = r["worst"] if stride == 1 else worst
        lines += ["", "The largest whole-pose jump named in the detections at 50 frames/s: median joint "
                      f"{worst:.0f} px off the line between the frames either side."]
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
