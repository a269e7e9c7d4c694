"""How much of the lifter's error on the real SH detections is the detector's? (issue 3's 60 mm bar)

    python scripts/sh_error_scaling.py [--stride 50] [--models sh_mix,mixture,gt] [--out docs/results/sh_error_scaling]

Protocol 1 test frames (S9, S11, every ``--stride``-th frame, 4 cameras) with their real
Stacked-Hourglass detections (converted to h36m17). Two measurements, with each model unchanged:

1. **Scaled detector error.** The 2D input is ``gt + alpha * (det - gt)``: alpha = 1 is the real
   detections, alpha = 0 the ground-truth 2D, alpha = 0.5 a detector with the same error *pattern*
   (swaps, misses, biases) at half the size. Reports the mean 2D error (px, 17 joints) and
   MPJPE / PA-MPJPE / MRPE (mm) per alpha.
2. **By frame.** MPJPE of the real detections, grouped by the frame's mean 2D detection error (quintiles).
3. **Training against test subjects.** MPJPE with GT 2D and with the real detections on the training
   subjects' frames (every ``--stride``-th, those with a detection) and on the test subjects': does the
   detection penalty (detections minus GT 2D) grow from the subjects a model was trained on to new ones?

Writes ``<out>.json`` and ``<out>.png`` (MPJPE against mean 2D error) and prints markdown tables.
Nothing from H36M is written: only measured numbers.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter import Lifter  # noqa: E402
from lifter.cli._help import add_h36m_arguments  # noqa: E402
from lifter.data import H36M  # noqa: E402
from lifter.detections import load_sh_detections  # noqa: E402
from lifter.evaluate import predict  # noqa: E402
from lifter.metrics import mpjpe, pa_mpjpe, root_errors  # noqa: E402

ALPHAS = (0.0, 0.25, 0.5, 0.75, 1.0)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_h36m_arguments(ap, stride=50)
    ap.add_argument("--models", default="sh_mix,mixture,gt")
    ap.add_argument("--out", default=str(ROOT / "docs/results/sh_error_scaling"))
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()

    import torch

    torch.set_num_threads(args.threads)
    data = H36M(args.h36m)
    samples = data.load_protocol(1, "test", stride=args.stride)
    det, ok = load_sh_detections(samples, data=data)
    samples = samples.subset(np.flatnonzero(ok))
    det = det[ok]
    gt2d = samples.keypoints_2d.astype(np.float64)
    frame_err = np.linalg.norm(det - gt2d, axis=-1).mean(-1)  # (N,) px
    gt_rel = samples.relative.astype(np.float64)
    models = [m for m in args.models.split(",") if m]
    print(f"Protocol 1 test, stride {args.stride}: {len(samples)} samples with a detection "
          f"(S9 'Discussion 1' has no 3D in the data); mean 2D error of the detections {frame_err.mean():.1f} px")

    train = data.load_protocol(1, "train", stride=args.stride)
    train_det, train_ok = load_sh_detections(train, data=data)
    train = train.subset(np.flatnonzero(train_ok))
    train_det = train_det[train_ok]
    train_gt2d = train.keypoints_2d.astype(np.float64)
    print(f"Protocol 1 train, stride {args.stride}: {len(train)} samples with a detection; mean 2D error "
          f"{np.linalg.norm(train_det - train_gt2d, axis=-1).mean():.1f} px")

    result: dict = {"stride": args.stride, "num_samples": len(samples), "alphas": list(ALPHAS), "models": {}}
    quint = np.quantile(frame_err, np.linspace(0, 1, 6))
    bins = np.clip(np.searchsorted(quint, frame_err, side="right") - 1, 0, 4)
    result["frame_error_quintiles_px"] = quint.tolist()
    for name in models:
        lifter = Lifter.load(name)
        rows = []
        for a in ALPHAS:
            kp = gt2d + a * (det - gt2d)
            pred = predict(lifter, samples.with_keypoints(kp.astype(np.float32)), progress=False)
            e = mpjpe(pred.relative, gt_rel)
            r, _ = root_errors(pred.root, samples.root)
            rows.append({"alpha": a, "mean_2d_error_px": float(np.linalg.norm(kp - gt2d, axis=-1).mean()),
                         "mpjpe": float(e.mean()), "pa_mpjpe": float(pa_mpjpe(pred.relative, gt_rel).mean()),
                         "mrpe": float(r.mean())})
            if a == 1.0:
                by_frame = [{"error_px_lo": float(quint[b]), "error_px_hi": float(quint[b + 1]),
                             "mpjpe": float(e[bins == b].mean()), "n": int((bins == b).sum())} for b in range(5)]
        result["models"][name] = {"scaled": rows, "by_frame_quintile": by_frame}
        split_rows = {"test": {"gt_2d": rows[0]["mpjpe"], "detections": rows[-1]["mpjpe"]}}
        for inputs, kp in (("gt_2d", train_gt2d), ("detections", train_det)):
            pred = predict(lifter, train.with_keypoints(kp.astype(np.float32)), progress=False)
            split_rows.setdefault("train", {})[inputs] = float(mpjpe(pred.relative, train.relative).mean())
        result["models"][name]["by_split"] = split_rows

    print("\n| model | " + " | ".join(f"α = {a:g}" for a in ALPHAS) + " |")
    print("|---|" + "---|" * len(ALPHAS))
    first = result["models"][models[0]]["scaled"]
    print("| mean 2D error (px) | " + " | ".join(f"{r['mean_2d_error_px']:.1f}" for r in first) + " |")
    for name in models:
        rows = result["models"][name]["scaled"]
        print(f"| `{name}` MPJPE / MRPE (mm) | "
              + " | ".join(f"{r['mpjpe']:.1f} / {r['mrpe']:.0f}" for r in rows) + " |")
    print("\n| frame's mean 2D error (px) | " + " | ".join(models) + " |")
    print("|---|" + "---|" * len(models))
    for b in range(5):
        cells = [f"{result['models'][m]['by_frame_quintile'][b]['mpjpe']:.1f}" for m in models]
        print(f"| {quint[b]:.1f}–{quint[b + 1]:.1f} | " + " | ".join(cells) + " |")

    print("\n| MPJPE (mm) | " + " | ".join(f"`{m}` GT 2D / detections (penalty)" for m in models) + " |")
    print("|---|" + "---|" * len(models))
    for split, label in (("train", "training subjects (S1, S5–S8)"), ("test", "test subjects (S9, S11)")):
        cells = []
        for m in models:
            r = result["models"][m]["by_split"][split]
            cells.append(f"{r['gt_2d']:.1f} / {r['detections']:.1f} (+{r['detections'] - r['gt_2d']:.1f})")
        print(f"| {label} | " + " | ".join(cells) + " |")
    result["train_num_samples"] = len(train)

    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(result, indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for name in models:
        rows = result["models"][name]["scaled"]
        ax.plot([r["mean_2d_error_px"] for r in rows], [r["mpjpe"] for r in rows], "o-", label=name)
    ax.axhline(60.0, color="gray", ls="--", lw=1, label="issue 3 bar (60 mm)")
    ax.set_xlabel("mean 2D error of the input (px): gt + α (SH detection − gt), α = 0 … 1")
    ax.set_ylabel("MPJPE (mm), Protocol 1")
    ax.set_title(f"Lifter error against detector error (S9/S11, stride {args.stride})")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(out.with_suffix(".png"), dpi=110)
    print(f"\nwrote {out.with_suffix('.json')} and {out.with_suffix('.png')}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
