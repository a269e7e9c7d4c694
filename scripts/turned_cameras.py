"""Lifters on cameras turned away from Human3.6M's (another camera height and tilt than the training cameras').

Human3.6M's four cameras stand at one height and tilt, in training and test alike, so a network can read a
person's depth from where they stand in the image (lower in the image: nearer) and be rewarded for it on the test
subjects. A photo from another camera pose breaks that cue. This turns each test camera about its centre
(:func:`lifter.evaluate.turned_camera_samples`: the 3D turned, the 2D moved by ``K R K^-1``, the same people and
the same detector errors), and also tilts each camera level ("level"), and evaluates every model on the
turned views: ground-truth 2D told ``--source`` and the real SH detections told "detected", MPJPE / MRPE (mm),
S9 + S11, every ``--stride``-th frame. A third angle turns the camera about its optical axis (roll: the picture
turned in its plane, as a hand-held phone often is).

    python scripts/turned_cameras.py [MODEL ...] [--turns 0:0,0:-10,0:10,0:-20,0:20,20:0] [--stride 50]
    python scripts/turned_cameras.py universal_turn --turns 0:0:0,0:0:5,0:0:-10,0:0:10,0:0:20,0:0:45
    python scripts/turned_cameras.py universal_turn pair=A.pt+B.pt --flip-test   # checkpoints, with the flip test
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from lifter import Lifter
from lifter.cli._help import add_h36m_arguments
from lifter.cli.evaluate import split_label
from lifter.data import CAMERA_IDS, H36M, PoseSamples
from lifter.detections import with_sh_detections
from lifter.evaluate import evaluate_lifter, turned_camera_samples


def _turns(text: str) -> list[tuple[float, float, float]]:
    out = []
    for item in text.split(","):
        parts = [float(a) for a in item.split(":")]
        if not 2 <= len(parts) <= 3:
            raise argparse.ArgumentTypeError(f"a turn is pan:tilt or pan:tilt:roll degrees, got {item!r}")
        out.append((parts[0], parts[1], parts[2] if len(parts) == 3 else 0.0))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("models", nargs="*", default=["default"])
    ap.add_argument("--turns", type=_turns, default=_turns("0:0,0:-10,0:10,0:-20,0:20,20:0"),
                    help="pan:tilt or pan:tilt:roll in degrees (+ pan: right, + tilt: up, + roll: clockwise seen from "
                    "behind the camera), comma-separated")
    ap.add_argument("--source", choices=["detected", "clean"], default="detected",
                    help="what the ground-truth 2D is told (the SH detections are told 'detected')")
    ap.add_argument("--flip-test", action=argparse.BooleanOptionalAction, default=None,
                    help="average each pose with its mirror image's lift in every network (on) or in none (off); "
                    "default: each model's own setting (on for the shipped default's width-1024 networks, off for a "
                    "checkpoint that does not say)")
    add_h36m_arguments(ap, stride=50)
    args = ap.parse_args()
    data = H36M(args.h36m)
    gt = data.load_protocol(1, "test", stride=args.stride)
    sh, dropped = with_sh_detections(gt, data=data)
    models = [(label, Lifter.load(ref)) for label, ref in (split_label(m) for m in args.models)]
    print(f"Protocol 1 test, stride {args.stride}: {len(gt)} poses (GT 2D, told {args.source!r}), {len(sh)} with SH "
          f"detections ({dropped} without); cameras turned by pan:tilt[:roll] degrees (+ right, + up, + clockwise "
          "seen from behind); MPJPE / MRPE mm")
    pitch = camera_pitch_deg(data)
    print("'level': each test camera tilted up by its own downward pitch (" + ", ".join(
        f"{cam} {p:.1f}" for cam, p in sorted(pitch.items())) + " deg, mean over subjects), so its axis is "
        "horizontal: a camera at Human3.6M's height (about 1.5 m) held level, as a photo is usually taken")
    head = " | ".join(f"{p:+g}:{t:+g}" + (f":{r:+g}" if r else "") for p, t, r in args.turns) + " | level"
    for kind, samples, source in (("GT 2D", gt, args.source), ("SH detections", sh, "detected")):
        print(f"\n{kind}\n| model | {head} |\n|---|" + "---|" * (len(args.turns) + 1))
        views = [turned_camera_samples(samples, pan_deg=p, tilt_deg=t, roll_deg=r) for p, t, r in args.turns]
        views.append(level_samples(samples, pitch))
        for label, m in models:
            rows = [evaluate_lifter(m, v, label=label, progress=False, source=source, flip_test=args.flip_test)[0]
                    for v in views]
            print(f"| {label} | " + " | ".join(f"{r.mpjpe:.1f} / {r.mrpe:.1f}" for r in rows) + " |")


def camera_pitch_deg(data: H36M) -> dict[str, float]:
    """Each camera's downward pitch (degrees below the horizon, world +z up), the mean over the subjects."""
    cams = json.loads((Path(data.root) / "cameras.json").read_text())["cameras"]
    out: dict[str, list[float]] = {}
    for key, cam in cams.items():
        axis = np.asarray(cam["R"], np.float64)[2]  # the optical axis in world coordinates
        out.setdefault(key.split("/")[1], []).append(float(np.degrees(np.arcsin(-axis[2]))))
    return {k: float(np.mean(v)) for k, v in out.items()}


def level_samples(samples: PoseSamples, pitch: dict[str, float]) -> PoseSamples:
    """The samples with each camera tilted up by its own pitch (:func:`camera_pitch_deg`)."""
    tilt = np.array([pitch[CAMERA_IDS[c]] for c in samples.camera])
    return turned_camera_samples(samples, pan_deg=0.0, tilt_deg=tilt)


if __name__ == "__main__":
    main()
