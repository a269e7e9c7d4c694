"""Copy a trained checkpoint into assets/weights/ and record its sha256 and measured metrics in assets/models.json.

    python scripts/ship_model.py runs/default.pt --name default_v2 --default --description "..."
    python scripts/ship_model.py runs/detected.pt --clean runs/clean.pt --flip-test --name pair --default

``--ensemble A.pt [B.pt ...]`` ships more networks for detected 2D whose lifts are averaged with the first
(registry ``ensemble_files`` / ``ensemble_sha256``; :attr:`lifter.Lifter.ensemble`). ``--clean`` ships a second
checkpoint that serves ``source="clean"`` (registry ``clean_file`` / ``clean_sha256``; the first then serves
detected 2D); ``--flip-test`` makes flip averaging the model's default (registry
``flip_test``), and the metrics are then measured with it.

Metrics recorded (Protocol 1, S9 + S11, 4 cameras; S9 'Discussion 1' is missing from the data), each as
``metrics[KEY] = {"inputs", "source", "stride", "learned": {...}, "analytic_root": {...}}``:

* ``gt_clean_s5`` / ``gt_clean_s50``: GT 2D told ``source="clean"``, every 5th / 50th frame;
* ``sh_detected_s50``: the real Stacked-Hourglass detections told ``source="detected"``, every 50th frame.

The every-50th-frame entries are what ``tests/test_shipped.py`` re-evaluates to check that the shipped weights
reproduce the README. ``--skip-full`` leaves out the every-5th-frame evaluation (slow on a CPU).
``--keep-earlier-stages`` (for a fine-tuned re-ship of a model under the same name) keeps the registry entry being
replaced, without its metrics, as the last item of the new entry's ``earlier_stages`` (its own earlier stages before
it), so the commands of every training stage stay on record.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

import torch

from lifter.api import Lifter
from lifter.checkpoint import sha256_file
from lifter.data import H36M
from lifter.detections import with_sh_detections
from lifter.evaluate import evaluate_lifter
from lifter.io import write_atomic
from lifter.resources import assets_root

EVALUATIONS = {"gt_clean_s5": ("gt", "clean", 5), "gt_clean_s50": ("gt", "clean", 50),
               "sh_detected_s50": ("sh", "detected", 50)}


def summary(row) -> dict:
    keys = ("mpjpe", "pa_mpjpe", "mrpe", "mrpe_x", "mrpe_y", "mrpe_z", "pck150", "auc")
    return {k: round(getattr(row, k), 3) for k in keys} | {"num_samples": row.num_samples}


def measure(lifter: Lifter, data: H36M, *, keys: list[str], flip_test: bool | None = None) -> dict:
    """Evaluate ``keys`` of :data:`EVALUATIONS`; ``flip_test=None`` uses the model's own default."""
    out = {}
    for key in keys:
        inputs, source, stride = EVALUATIONS[key]
        s = data.load_protocol(1, "test", stride=stride)
        if inputs == "sh":
            s, _ = with_sh_detections(s, data=data)
        learned, analytic = evaluate_lifter(lifter, s, analytic_root=True, source=source, flip_test=flip_test)
        used_flip = lifter.flip_test if flip_test is None else flip_test
        out[key] = {"inputs": inputs, "source": source, "stride": stride, "flip_test": used_flip,
                    "learned": summary(learned), "analytic_root": summary(analytic)}
        print(key, json.dumps(out[key]["learned"]))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("checkpoint", type=Path)
    ap.add_argument("--name", required=True)
    ap.add_argument("--description", default="")
    ap.add_argument("--default", action="store_true", help="make it the default model")
    ap.add_argument("--clean", type=Path, default=None, help="a second checkpoint that serves source='clean'")
    ap.add_argument("--flip-test", action="store_true", help="flip averaging on by default for this model")
    ap.add_argument("--ensemble", type=Path, nargs="*", default=[],
                    help="more checkpoints for detected 2D, averaged with the first (registry ensemble_files)")
    ap.add_argument("--skip-full", action="store_true", help="do not evaluate every 5th frame")
    ap.add_argument("--keep-earlier-stages", action="store_true",
                    help="keep the entry being replaced (without metrics) in the new entry's earlier_stages")
    ap.add_argument("--h36m", type=Path, default=None)
    args = ap.parse_args()
    torch.set_num_threads(2)
    root = Path(str(assets_root()))
    weights = root / "weights"
    weights.mkdir(parents=True, exist_ok=True)

    def ship(src: Path, dst: Path) -> Path:
        """Copy a checkpoint and its learning curve (``.curve.json`` / ``.curve.png`` beside it, if any)."""
        write_atomic(dst, src.read_bytes())
        for ext in (".curve.json", ".curve.png"):
            if src.with_suffix(ext).is_file():
                write_atomic(dst.with_suffix(ext), src.with_suffix(ext).read_bytes())
        return dst

    dst = ship(args.checkpoint, weights / f"{args.name}.pt")
    dst_clean = None if args.clean is None else ship(args.clean, weights / f"{args.name}_clean.pt")
    dst_members = [ship(m, weights / f"{args.name}_member{i + 2}.pt") for i, m in enumerate(args.ensemble)]
    lifter = Lifter.from_checkpoint(dst, name=args.name, clean=dst_clean, ensemble=dst_members)
    if args.flip_test:
        lifter.flip_test = True
        if lifter.clean is not None:
            lifter.clean.flip_test = True
        for m in lifter.ensemble:
            m.flip_test = True
    keys = [k for k in EVALUATIONS if not (args.skip_full and EVALUATIONS[k][2] == 5)]
    metrics = measure(lifter, H36M(args.h36m), keys=keys)
    reg_path = root / "models.json"
    reg = json.loads(reg_path.read_text()) if reg_path.is_file() else {"default": args.name, "models": {}}
    entry = {
        "file": f"weights/{args.name}.pt",
        "sha256": sha256_file(dst),
        "description": args.description,
        "train_command": lifter.meta.get("command", ""),
        "train_minutes": round(float(lifter.meta.get("minutes", 0.0)), 1),
        "samples_seen": lifter.meta.get("samples_seen"),
    }
    if dst_clean is not None and lifter.clean is not None:
        entry |= {"clean_file": f"weights/{dst_clean.name}", "clean_sha256": sha256_file(dst_clean),
                  "clean_train_command": lifter.clean.meta.get("command", ""),
                  "clean_train_minutes": round(float(lifter.clean.meta.get("minutes", 0.0)), 1),
                  "clean_samples_seen": lifter.clean.meta.get("samples_seen")}
    if lifter.meta.get("init_sha256"):  # fine-tuned (--init): the weights it started from
        entry["train_init_sha256"] = lifter.meta["init_sha256"]
    if lifter.clean is not None and lifter.clean.meta.get("init_sha256"):
        entry["clean_train_init_sha256"] = lifter.clean.meta["init_sha256"]
    if any(m.meta.get("init_sha256") for m in lifter.ensemble):
        entry["ensemble_train_init_sha256"] = [m.meta.get("init_sha256") for m in lifter.ensemble]
    if args.flip_test:
        entry["flip_test"] = True
    if dst_members:
        entry |= {"ensemble_files": [f"weights/{m.name}" for m in dst_members],
                  "ensemble_sha256": [sha256_file(m) for m in dst_members],
                  "ensemble_train_commands": [m.meta.get("command", "") for m in lifter.ensemble],
                  "ensemble_train_minutes": [round(float(m.meta.get("minutes", 0.0)), 1) for m in lifter.ensemble]}
    previous = reg["models"].get(args.name)
    if args.keep_earlier_stages and previous is not None:
        earlier = list(previous.get("earlier_stages", []))
        earlier.append({k: v for k, v in previous.items() if k not in ("metrics", "earlier_stages")})
        entry["earlier_stages"] = earlier
    reg["models"][args.name] = entry | {"metrics": metrics}
    if args.default:
        reg["default"] = args.name
    tmp = reg_path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(reg, indent=1) + "\n")
    os.replace(tmp, reg_path)
    print(f"shipped {dst} ({dst.stat().st_size / 1e6:.1f} MB, sha256 {reg['models'][args.name]['sha256'][:12]}); "
          f"registry {reg_path}")


if __name__ == "__main__":
    main()
