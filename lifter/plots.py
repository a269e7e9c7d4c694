"""Matplotlib figures (Agg backend, PNG files). Imported lazily by the CLI."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_learning_curve(curve: Sequence[dict[str, float]], path: str | Path, *, title: str = "") -> Path:
    """Train loss, and validation MPJPE / MRPE (mm) per validation set (``val_mpjpe_<set>``; older curves:
    ``val_mpjpe``), against training samples seen. Written atomically."""
    path = Path(path)
    x = np.array([c["samples"] for c in curve]) / 1e6
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    axes[0].plot(x, [c["train_loss"] for c in curve])
    axes[0].set_ylabel("train loss (mm, sum of 48 + depth)")
    for ax, metric in ((axes[1], "mpjpe"), (axes[2], "mrpe")):
        keys = sorted(k for k in curve[0] if k == f"val_{metric}" or k.startswith(f"val_{metric}_")) if curve else []
        lo, hi = math.inf, 0.0
        for i, key in enumerate(keys):
            vals = [c[key] for c in curve]
            label = key.split("_", 2)[2] if key.count("_") >= 2 else "val"
            ax.plot(x, vals, color=f"C{i + 1}", label=f"{label} 2D")
            lo, hi = min(lo, min(vals)), max(hi, max(vals))
        ax.set_ylabel(f"val {metric.upper()} (mm)")
        if keys:
            ax.set_ylim(lo * 0.9, min(hi, lo * 2.5) * 1.02)
            ax.legend(fontsize=8)
    for ax in axes:
        ax.set_xlabel("samples seen (millions)")
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return _save(fig, path)


def _save(fig: Any, path: Path) -> Path:
    """Save a figure as PNG through a temporary file and a rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{path.name}.tmp")
    fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    os.replace(tmp, path)
    return path


def plot_pck_curves(curves: dict[str, tuple[np.ndarray, np.ndarray]], path: str | Path) -> Path:
    """3DPCK (%) against threshold (mm) for several models: ``{label: (thresholds, pck)}``."""
    path = Path(path)
    fig, ax = plt.subplots(figsize=(5.5, 4))
    for label, (t, p) in curves.items():
        ax.plot(t, 100 * np.asarray(p), label=label)
    ax.set_xlabel("threshold (mm)")
    ax.set_ylabel("3DPCK (%)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return _save(fig, path)
