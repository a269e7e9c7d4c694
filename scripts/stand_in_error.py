"""What a stood-in joint costs (:data:`lifter.keypoints.STAND_INS`): the 84 Human3.6M demo photos' BlazePose
detections (``scripts/eval_cascade.py``'s cache), written as COCO-17 joints, lifted by the default with every joint
given and with one kind of joint removed and stood in for, as a keypoint file missing it would be (:data:`CASES`).
Per case: the pixel error of the two head joints made from the face (neck_nose, head_top) against the ground-truth
2D, and MPJPE / MRPE (mm) against the ground-truth 3D, true camera, ``source="detected"``.

Only BlazePose runs offline here, so the joints are BlazePose's in COCO's names; a real COCO network places its face
joints a little differently.

    python scripts/stand_in_error.py [--model universal_turn]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from eval_cascade import blazepose_as, demo_frames, detect_demo, pose_metrics  # noqa: E402

from lifter.api import Lifter  # noqa: E402
from lifter.keypoints import convert, get_format, stand_in_missing  # noqa: E402
from lifter.skeleton import JOINT_NAMES  # noqa: E402

CASES: dict[str, dict[str, tuple[str, ...]]] = {
    "coco17": {"all given": (), "r_ear": ("r_ear",), "l_ear": ("l_ear",), "both ears": ("l_ear", "r_ear"),
               "nose": ("nose",), "nose and r_ear": ("nose", "r_ear")},
}
"""COCO-17 only: OpenPose's Neck and MidHip are made here from BlazePose's shoulders and hips as exactly the
midpoints their stand-ins are (``eval_cascade.blazepose_as``), so removing them would measure nothing; its face
joints are COCO's."""
HEAD = [JOINT_NAMES.index("neck_nose"), JOINT_NAMES.index("head_top")]


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--model", default="default", help="a shipped model name or checkpoint (default: the default)")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    demo, ann, focal, pp, dist = demo_frames(args.h36m)
    det = detect_demo(demo, ann["image"])
    ok = det["people"] > 0
    kp33 = det["kp33"][ok]
    gt2d, gt3d = ann["p2d_gt"].astype(np.float64)[ok], ann["p3d_cam"].astype(np.float64)[ok]
    lifter = Lifter.from_pretrained() if args.model == "default" else Lifter.load(args.model)
    print(f"{int(ok.sum())} of {len(ok)} demo photos with a BlazePose person; lifter {lifter.name}, source='detected', "
          "true camera")
    print("| joint set | removed and stood in for | neck_nose / head_top 2D error px (mean) | MPJPE | MRPE |")
    print("|---|---|---|---|---|")
    for fmt, cases in CASES.items():
        given = blazepose_as(fmt, kp33)
        names = get_format(fmt).joint_names
        for label, removed in cases.items():
            kp = given.copy()
            if removed:
                missing = np.isin(np.array(names), removed)
                kp = np.stack([stand_in_missing(p, missing, src=fmt)[0] for p in kp])
            kp17 = convert(kp, src=fmt, warn=False)
            head = np.linalg.norm(kp17[:, HEAD] - gt2d[:, HEAD], axis=-1).mean(0)
            m = pose_metrics(lifter.lift(kp17, focal=focal[ok], principal_point=pp[ok], distortion=dist[ok],
                                         warn=False).absolute, gt3d)
            print(f"| {fmt} | {label} | {head[0]:.1f} / {head[1]:.1f} | {m['mpjpe']:.1f} | {m['mrpe']:.1f} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
