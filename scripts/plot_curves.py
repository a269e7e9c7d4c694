"""Learning curves of several training runs in one figure, against samples seen: validation MPJPE and MRPE
(mm) of each ``.curve.json`` (written by ``poselifter train``) on the detected and the clean validation set.

    python scripts/plot_curves.py LABEL=run.curve.json ... --out curves.png [--title TEXT] [--inputs clean]

``--inputs clean`` (or ``detected``) draws only that validation set's two panels (a clean-2D network's error on the
detections says nothing about it).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

PANELS = (("val_mpjpe_detected", "MPJPE, SH detections (mm)"), ("val_mrpe_detected", "MRPE, SH detections (mm)"),
          ("val_mpjpe_clean", "MPJPE, GT 2D (mm)"), ("val_mrpe_clean", "MRPE, GT 2D (mm)"))


def main() -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("runs", nargs="+", help="LABEL=path/to/run.curve.json")
    p.add_argument("--out", type=Path, required=True, help="PNG to write")
    p.add_argument("--title", default="")
    p.add_argument("--inputs", choices=("all", "clean", "detected"), default="all",
                   help="which validation set's panels to draw (default all)")
    args = p.parse_args()
    panels = [(k, t) for k, t in PANELS if args.inputs == "all" or k.endswith(args.inputs)]
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.6 + 0.3 * len(args.runs)))
    for spec in args.runs:
        label, sep, path = spec.partition("=")
        if not sep:
            p.error(f"{spec!r}: give LABEL=path/to/run.curve.json")
        try:
            curve = json.loads(Path(path).read_text())["curve"]
        except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as exc:
            p.error(f"{path}: not a learning curve ({type(exc).__name__}: {exc}); give the .curve.json that "
                    "poselifter train writes beside its checkpoint")
        x = [c["samples"] / 1e6 for c in curve]
        for ax, (key, _) in zip(axes, panels):
            pts = [(xi, c[key]) for xi, c in zip(x, curve) if key in c]
            if pts:  # (a run with a few points gets markers: one point alone draws no line)
                ax.plot(*zip(*pts), label=label, lw=1.4, marker="o" if len(pts) < 5 else None)
    for ax, (_, name) in zip(axes, panels):
        ax.set_xlabel("samples seen (millions)")
        ax.set_title(name, fontsize=10)
        vals = [ln.get_ydata() for ln in ax.get_lines()]
        if vals:  # the first points (untrained) are off the scale; show the range where the runs differ
            finals = [v[-1] for v in vals]
            lo, hi = min(min(v) for v in vals), max(finals)
            ax.set_ylim(lo - 0.1 * (hi - lo + 1), hi + 0.6 * (hi - lo + 1))
        ax.grid(alpha=0.3)
    handles, labels = axes[0].get_legend_handles_labels()
    rows = (len(labels) + 1) // 2
    fig.legend(handles, labels, loc="lower center", ncol=2, fontsize=9, frameon=False)
    if args.title:
        fig.suptitle(args.title, fontsize=11)
    fig.tight_layout(rect=(0, 0.07 * rows, 1, 1))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    tmp = args.out.with_suffix(".tmp.png")
    fig.savefig(tmp, dpi=110)
    tmp.replace(args.out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
