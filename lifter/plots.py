"""Matplotlib figures (Agg backend, PNG files). Imported lazily by the CLI."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def plot_learning_curve(curve: Sequence[dict[str, float]], path: str | Path, *, title: str = "") -> Path:
    """Train loss and validation MPJPE / MRPE (mm) against training samples seen."""
    path = Path(path)
    x = np.array([c["samples"] for c in curve]) / 1e6
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    axes[0].plot(x, [c["train_loss"] for c in curve])
    axes[0].set_ylabel("train loss (mm, sum of 48 + depth)")
    axes[1].plot(x, [c["val_mpjpe"] for c in curve], color="C1")
    axes[1].set_ylabel("val MPJPE (mm)")
    axes[2].plot(x, [c["val_mrpe"] for c in curve], color="C2")
    axes[2].set_ylabel("val MRPE (mm)")
    for ax in axes:
        ax.set_xlabel("samples seen (millions)")
        ax.grid(alpha=0.3)
    for ax, key in ((axes[1], "val_mpjpe"), (axes[2], "val_mrpe")):
        vals = [c[key] for c in curve]
        lo = min(vals)
        ax.set_ylim(lo * 0.9, min(max(vals), lo * 2.5))
    fig.suptitle(title)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
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
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
