"""Matplotlib figures (Agg backend, PNG files). Imported lazily by the CLI."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from ._checks import plot_format  # noqa: E402


def curve_y_range(series: Sequence[Sequence[float]]) -> tuple[float, float]:
    """The y range of a validation panel: from 0.9x the lowest value to at most 2.5x it (the untrained first
    points are cut off), but always above every curve's last point, so no curve leaves the plot."""
    lo = min(min(v) for v in series)
    hi = max(max(v) for v in series)
    last = max(v[-1] for v in series)
    return lo * 0.9, max(min(hi, lo * 2.5), last) * 1.02


def plot_learning_curve(curve: Sequence[dict[str, float]], path: str | Path, *, title: str = "") -> Path:
    """Train loss, and validation MPJPE / MRPE (mm) per validation set (``val_mpjpe_<set>``; older curves:
    ``val_mpjpe``), against training samples seen. Written atomically."""
    path = Path(path)
    x = np.array([c["samples"] for c in curve]) / 1e6
    fig, axes = plt.subplots(1, 3, figsize=(13, 3.6))
    axes[0].plot(x, [c["train_loss"] for c in curve], marker="o" if len(curve) < 5 else None)
    axes[0].set_ylabel("train loss (mm, sum of 48 + depth)")
    for ax, metric in ((axes[1], "mpjpe"), (axes[2], "mrpe")):
        keys = sorted(k for k in curve[0] if k == f"val_{metric}" or k.startswith(f"val_{metric}_")) if curve else []
        series = []
        for i, key in enumerate(keys):
            vals = [c[key] for c in curve]
            label = key.split("_", 2)[2] if key.count("_") >= 2 else "val"
            ax.plot(x, vals, color=f"C{i + 1}", label=f"{label} 2D", marker="o" if len(vals) < 5 else None)
            series.append(vals)
        ax.set_ylabel(f"val {metric.upper()} (mm)")
        if keys:
            ax.set_ylim(*curve_y_range(series))
            ax.legend(fontsize=8)
    for ax in axes:
        ax.set_xlabel("samples seen (millions)")
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return save_figure(fig, path)


def save_figure(fig: Any, path: Path, *, dpi: int = 110) -> Path:
    """Save a figure in the format of its suffix (:func:`plot_format`) with :func:`lifter.io.write_atomic` (a
    temporary file of its own, fsync, a rename; never through a symbolic link: a security trial's link at the fixed
    temporary name ``.NAME.tmp`` redirected the write) and close it."""
    import io

    from .io import write_atomic

    try:
        fmt = plot_format(path)
        buf = io.BytesIO()
        fig.savefig(buf, dpi=dpi, format=fmt)
    finally:
        plt.close(fig)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_atomic(path, buf.getbuffer())



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
    return save_figure(fig, path)
