"""Copy a trained checkpoint into assets/weights/ and record its measured metrics in assets/models.json.

    python scripts/ship_model.py runs/gt_main.pt --name gt --default --description "..."

Metrics recorded (GT 2D, Protocol 1, S9 + S11, 4 cameras; S9 'Discussion 1' is missing from the data):
``full``: every 5th frame (the README's numbers); ``slice``: every 50th frame (what the test suite
re-evaluates to check the shipped weights reproduce the README).
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import torch

from lifter.api import ASSETS_DIR, Lifter
from lifter.data import H36M
from lifter.evaluate import evaluate_lifter

SLICE_STRIDE = 50
FULL_STRIDE = 5


def summary(row) -> dict:
    return {k: round(getattr(row, k), 3) for k in ("mpjpe", "pa_mpjpe", "mrpe", "mrpe_x", "mrpe_y", "mrpe_z", "pck150", "auc")} | {
        "num_samples": row.num_samples}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("checkpoint", type=Path)
    ap.add_argument("--name", required=True)
    ap.add_argument("--description", default="")
    ap.add_argument("--default", action="store_true")
    ap.add_argument("--detector", default=None,
                    help="the 2D detector whose errors this model was trained for (poselifter lift picks it for images)")
    ap.add_argument("--h36m", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(2)
    dst = ASSETS_DIR / "weights" / f"{args.name}.pt"
    dst.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(args.checkpoint, dst)
    for ext in (".curve.json", ".curve.png"):
        src = args.checkpoint.with_suffix(ext)
        if src.is_file():
            shutil.copyfile(src, dst.with_suffix(ext))
    lifter = Lifter.from_checkpoint(dst, name=args.name)
    data = H36M(args.h36m)
    metrics = {}
    for key, stride in (("full", FULL_STRIDE), ("slice", SLICE_STRIDE)):
        s = data.load_protocol(1, "test", stride=stride)
        rows = evaluate_lifter(lifter, s, analytic_root=True)
        metrics[key] = {"stride": stride, "learned": summary(rows[0]), "analytic_root": summary(rows[1])}
        print(key, json.dumps(metrics[key]))
    reg_path = ASSETS_DIR / "models.json"
    reg = json.loads(reg_path.read_text()) if reg_path.is_file() else {"default": args.name, "models": {}}
    previous = reg["models"].get(args.name, {})
    reg["models"][args.name] = {
        "file": f"weights/{args.name}.pt",
        "description": args.description,
        "train_command": lifter.meta.get("command", ""),
        "train_minutes": round(float(lifter.meta.get("minutes", 0.0)), 1),
        "samples_seen": lifter.meta.get("samples_seen"),
        "metrics_gt2d_protocol1": metrics,
    }
    detector = args.detector or previous.get("detector")  # re-shipping keeps the model's detector
    if detector:
        for other in reg["models"].values():  # one model per detector
            if other.get("detector") == detector:
                other.pop("detector")
        reg["models"][args.name]["detector"] = detector
    if args.default:
        reg["default"] = args.name
    reg_path.write_text(json.dumps(reg, indent=1) + "\n")
    print(f"shipped {dst} ({dst.stat().st_size / 1e6:.1f} MB); registry {reg_path}")


if __name__ == "__main__":
    main()
