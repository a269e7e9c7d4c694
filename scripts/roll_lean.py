"""Does the lean note say so when the camera was rolled? Human3.6M's test subjects (S9 + S11) seen through their own
cameras rolled about the optical axis (``lifter.camera.camera_turn``'s third angle, + clockwise seen from behind the
camera), exact pinhole 2D, lifted by the default as detected 2D (what a photo's detections are lifted as). Per roll:
MPJPE and MRPE; the share of poses the note names (:func:`lifter._checks.leaning_people`, legs and torso leaning more
than :data:`lifter._checks.LEAN_NOTE_DEG`, within :data:`lifter._checks.LEAN_STRAIGHT_DEG` of each
other) and the median lean (:func:`lifter._checks.body_lean_deg`); and the MRPE
of the poses it names, as given and with the note's advice taken: each turned upright by its own lean, lifted, and
turned back (the README's "Camera roll" recipe).

    python scripts/roll_lean.py [--h36m ../shared/data/h36m] [--stride 50] [--rolls 0,10,20,30,45,60]
                                [--out docs/results/roll_lean.txt]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _report import emit  # noqa: E402  (scripts/_report.py)

from lifter import Lifter  # noqa: E402
from lifter._checks import LEAN_NOTE_DEG, LEAN_STRAIGHT_DEG, body_lean_deg, leaning_people  # noqa: E402
from lifter.camera import camera_turn, project, turn_pixels  # noqa: E402
from lifter.data import H36M  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--stride", type=int, default=50)
    ap.add_argument("--rolls", default="0,10,20,30,45,60", help="camera rolls, deg, comma-separated")
    ap.add_argument("--out", type=Path, default=None, help="also write the report here")
    args = ap.parse_args()
    rolls = [float(r) for r in args.rolls.split(",")]
    samples = H36M(args.h36m).load([9, 11], stride=args.stride, lens="pinhole")
    model = Lifter.from_pretrained()
    p3 = samples.pose_3d.astype(np.float64)
    f, c = samples.focal.astype(np.float64), samples.principal_point.astype(np.float64)
    n = len(p3)
    lines = [f"S9 + S11, every {args.stride}th frame, 4 cameras: {n} poses, exact pinhole 2D, lifted by {model.name} "
             f"as detected 2D; the note at a lean of more than {LEAN_NOTE_DEG:g} deg (legs and torso alike, within "
             f"{LEAN_STRAIGHT_DEG:g} deg of each other)",
             f"{'roll':>6} {'MPJPE':>7} {'MRPE':>7} {'noted':>7} {'median lean':>12} "
             f"{'MRPE of those noted: as given':>30} {'turned upright by their lean':>29}"]
    for roll in rolls:
        turn = camera_turn(np.array(0.0), np.array(0.0), np.deg2rad(np.array(roll)))
        truth = p3 @ turn.T  # mm, in the rolled camera's frame
        kp = project(truth, focal=f, principal_point=c)
        res = model.lift(kp, focal=f, principal_point=c, warn=False)
        mrpe = float(np.linalg.norm(res.root - truth[:, 0], axis=-1).mean())
        mpjpe = float(np.linalg.norm(res.relative - (truth - truth[:, :1]), axis=-1).mean())
        noted = leaning_people(kp)
        lean = body_lean_deg(kp)
        undo = camera_turn(np.zeros(n), np.zeros(n), np.deg2rad(np.where(noted, lean, 0.0)))  # (n, 3, 3)
        up = model.lift(turn_pixels(kp, np.swapaxes(undo, -1, -2), f, c), focal=f, principal_point=c, warn=False)
        err = np.linalg.norm(res.root - truth[:, 0], axis=-1)[noted]
        err_up = np.linalg.norm(np.einsum("nij,nj->ni", undo, up.root) - truth[:, 0], axis=-1)[noted]
        given, upright = (f"{err.mean():.1f}", f"{err_up.mean():.1f}") if noted.any() else ("-", "-")
        lines.append(f"{roll:>6g} {mpjpe:>7.1f} {mrpe:>7.1f} {100 * noted.mean():>6.1f}% {np.median(lean):>12.1f} "
                     f"{given:>30} {upright:>29}")
    lines.append("mm; roll in deg (+ clockwise seen from behind the camera); 'noted': the share of poses the lean note "
                 "names")
    emit("\n".join(lines), args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
