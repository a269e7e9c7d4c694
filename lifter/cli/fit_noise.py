"""``poselifter fit-noise``: fit the 2D error model to the real Stacked-Hourglass detections.

Wire it into :mod:`lifter.cli` with ``from .noise_cli import add_parser`` and ``add_parser(sub)``.
It loads the training subjects of a protocol (every 5th frame, 4 cameras; the detections file holds
exactly those frames for them), converts the sh16 detections with :func:`lifter.keypoints.convert`,
fits the mixture and the single Gaussian per joint (:func:`lifter.noise.fit_error_model`), writes the
JSON and the figures, and prints the converter's measured errors and the per-joint table.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

import numpy as np

DEFAULT_JSON = Path("assets/error_model/sh_mixture.json")
DEFAULT_PLOT_DIR = Path("docs/noise")


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``fit-noise`` sub-command on an ``add_subparsers()`` object."""
    p = sub.add_parser("fit-noise", help="fit the Gaussian + uniform 2D error model to real SH detections",
                       formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--h36m", type=Path, default=None, help="Human3.6M folder (default ../shared/data/h36m)")
    p.add_argument("--protocol", type=int, default=1, choices=(1, 2), help="fit on this protocol's training subjects")
    p.add_argument("--out", type=Path, default=None,
                   help=f"JSON to write (default <assets>/error_model/sh_mixture.json, i.e. {DEFAULT_JSON})")
    p.add_argument("--plots", type=Path, default=DEFAULT_PLOT_DIR, help="folder for the PNG figures")
    p.add_argument("--tol", type=float, default=1e-7, help="EM stops when the mean log-lik gains less (nats/sample)")
    p.add_argument("--max-iter", type=int, default=1000, help="EM iteration cap")
    p.add_argument("--weights", default="default",
                   help="lifter for the depth-vs-scale figure: shipped model name or checkpoint .pt")
    p.add_argument("--depth-stride", type=int, default=10, help="test frame stride for the depth-vs-scale figure")
    p.add_argument("--no-alignment-check", action="store_true", help="skip the frame-alignment check (~20 s)")
    p.add_argument("--threads", type=int, default=2)
    p.set_defaults(func=run_fit_noise)
    return p


def _line(target: np.ndarray, a: np.ndarray, b: np.ndarray, w: float) -> tuple[float, float]:
    e = np.linalg.norm(a + w * (b - a) - target, axis=-1)
    return float(e.mean()), float(np.median(e))


def converter_report(gt: np.ndarray, det16: np.ndarray) -> dict[str, Any]:
    """Re-fit and measure the sh16 interpolation rules: GT ``(N, 17, 2)``, raw sh16 detections ``(N, 16, 2)``."""
    from ..keypoints import SH16_HEAD_WEIGHT, SH16_NECK_WEIGHT, SH16_SPINE_WEIGHT, fit_line_weight

    P, S, T, N, H = (gt[:, j] for j in (0, 7, 8, 9, 10))
    dP, dS, dT, dH = (det16[:, j] for j in (6, 7, 8, 9))
    w_gt = fit_line_weight(N, T, H)
    rep: dict[str, Any] = {
        "neck_nose_gt_only": {"rule": "GT thorax + w (GT head_top - GT thorax)", "w": w_gt,
                              "mean_px_median_px": _line(N, T, H, w_gt)},
    }
    for name, tgt, a, b, w in (("spine", S, dP, dS, SH16_SPINE_WEIGHT), ("neck_nose", N, dT, dH, SH16_NECK_WEIGHT),
                               ("head_top", H, dT, dH, SH16_HEAD_WEIGHT)):
        rep[name] = {"w_shipped": w, "w_refit": fit_line_weight(tgt, a, b), "mean_px_median_px": _line(tgt, a, b, w)}
    rep["spine"]["direct_mean_px_median_px"] = _line(S, dP, dS, 1.0)
    rep["head_top"]["direct_mean_px_median_px"] = _line(H, dT, dH, 1.0)
    rep["neck_nose"]["with_gt_only_w_mean_px_median_px"] = _line(N, dT, dH, w_gt)
    return rep


def scale_dependence(errors_px: np.ndarray, scale: np.ndarray, *, bins: int = 5) -> list[dict[str, float]]:
    """Median raw error norm (px, all joints) in quantile bins of the GT 2D scale: evidence for the scale rule."""
    norms = np.median(np.linalg.norm(errors_px, axis=-1), axis=1)
    edges = np.quantile(scale, np.linspace(0, 1, bins + 1))
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (scale >= lo) & (scale <= hi)
        out.append({"scale_lo_px": float(lo), "scale_hi_px": float(hi), "median_scale_px": float(np.median(scale[m])),
                    "median_error_px": float(np.median(norms[m]))})
    return out


def run_fit_noise(args: argparse.Namespace) -> int:
    import torch

    from ..data import H36M, PROTOCOLS
    from ..detections import SH_DETECTIONS_FILE, detection_alignment_check, load_sh_detections
    from ..keypoints import convert
    from ..noise import fit_error_model

    torch.set_num_threads(args.threads)
    data = H36M(args.h36m)
    subjects = PROTOCOLS[args.protocol][0]
    if not args.no_alignment_check:
        chk = detection_alignment_check(data, subject=subjects[0])
        best = min(chk, key=lambda o: chk[o])
        print(f"alignment check (S{subjects[0]}, camera 0, limbs): median error px by frame offset "
              + ", ".join(f"{o:+d}: {v:.2f}" for o, v in chk.items()) + f" -> best offset {best:+d}")
        if best != 0:
            print("WARNING: detections are not aligned with frame 5*i; check the data")
    else:
        chk = {}
    samples = data.load(subjects, stride=5)
    det16, valid = load_sh_detections(samples, data=data, dst="sh16")  # raw detector joints
    if not valid.all():
        print(f"note: {int((~valid).sum())} of {len(valid)} training samples have no detection and are skipped")
    samples = samples.subset(valid)
    det16 = det16[valid]
    det17 = convert(det16, src="sh16")
    gt = samples.keypoints_2d.astype(np.float64)
    print(f"training subjects {list(subjects)}: {len(samples)} samples (every 5th frame, 4 cameras)")

    conv = converter_report(gt, det16)
    nn = conv["neck_nose"]
    print(f"converter sh16 -> h36m17: neck_nose = thorax + {nn['w_shipped']:.3f} (head - thorax): "
          f"error {nn['mean_px_median_px'][0]:.1f} px mean / {nn['mean_px_median_px'][1]:.1f} px median "
          f"(re-fitted w {nn['w_refit']:.3f}); on GT alone (w {conv['neck_nose_gt_only']['w']:.3f}): "
          f"{conv['neck_nose_gt_only']['mean_px_median_px'][0]:.1f} / {conv['neck_nose_gt_only']['mean_px_median_px'][1]:.1f} px")
    for name in ("spine", "head_top"):
        c = conv[name]
        print(f"  {name}: w {c['w_shipped']:.3f} (re-fit {c['w_refit']:.3f}): {c['mean_px_median_px'][0]:.1f} / "
              f"{c['mean_px_median_px'][1]:.1f} px mean/median; direct mapping: {c['direct_mean_px_median_px'][0]:.1f} / "
              f"{c['direct_mean_px_median_px'][1]:.1f} px")

    from ..normalization import pose_scale

    scale = pose_scale(gt)
    dep = scale_dependence(det17 - gt, scale)
    print("scale dependence (median over samples of the per-pose median joint error, by GT 2D scale quintile): "
          + ", ".join(f"{d['median_scale_px']:.0f} px -> {d['median_error_px']:.1f} px" for d in dep))

    meta = {"data": {"detections": SH_DETECTIONS_FILE, "subjects": list(subjects), "protocol": args.protocol,
                     "frames": "every 5th (row i = frame 5 i)", "cameras": 4, "n_samples": int(len(samples))},
            "alignment_check_median_px_by_offset": {str(k): v for k, v in chk.items()},
            "converter": conv, "scale_dependence": dep,
            "error_definition": "convert(sh16 detection) - distorted GT projection, px, rescaled by reference_scale / sigma_gt"}
    model = fit_error_model(det17, gt, source="Stacked-Hourglass (MPII-pretrained) detections vs distorted GT projection, H36M "
                            + ", ".join(f"S{s}" for s in subjects) + ", every 5th frame, 4 cameras", tol=args.tol, max_iter=args.max_iter, meta=meta)
    out = args.out or DEFAULT_JSON
    model.save(out)
    print(f"reference 2D scale {model.reference_scale:.1f} px; wrote {out}")
    print(format_table(model))

    from ..plots import plt  # noqa: F401  (Agg backend)

    e = (det17 - gt) * (model.reference_scale / scale)[:, None, None]
    hist = plot_error_histograms(e, model, Path(args.plots) / "error_histograms.png")
    print(f"wrote {hist}")
    try:
        test = data.load_protocol(args.protocol, "test", stride=args.depth_stride)
        path = plot_depth_vs_scale(test, Path(args.plots) / "depth_vs_scale.png", weights=args.weights)
        print(f"wrote {path}")
    except SkipFigure as exc:
        print(f"skipped depth_vs_scale.png: {exc}")
    return 0


def format_table(model: Any) -> str:
    """Per-joint table: gamma, inlier mu and sigma (px), baseline sigma, NLLs, EM iterations."""
    from ..skeleton import JOINT_NAMES

    rows = [f"{'joint':<11} {'gamma':>6} {'mu_x':>6} {'mu_y':>6} {'sig_x':>6} {'sig_y':>6} {'gsig_x':>7} {'gsig_y':>7} "
            f"{'NLL_mix':>8} {'NLL_gau':>8} {'iters':>5}"]
    for j, name in enumerate(JOINT_NAMES):
        rows.append(f"{name:<11} {model.gamma[j]:6.3f} {model.mu[j, 0]:6.2f} {model.mu[j, 1]:6.2f} "
                    f"{model.sigma[j, 0]:6.2f} {model.sigma[j, 1]:6.2f} {model.gaussian_sigma[j, 0]:7.2f} "
                    f"{model.gaussian_sigma[j, 1]:7.2f} {model.nll_mixture[j]:8.3f} {model.nll_gaussian[j]:8.3f} "
                    f"{int(model.iterations[j]):5d}")
    rows.append(f"{'mean':<11} {model.gamma.mean():6.3f} {'':6} {'':6} {model.sigma[:, 0].mean():6.2f} "
                f"{model.sigma[:, 1].mean():6.2f} {model.gaussian_sigma[:, 0].mean():7.2f} "
                f"{model.gaussian_sigma[:, 1].mean():7.2f} {model.nll_mixture.mean():8.3f} "
                f"{model.nll_gaussian.mean():8.3f} {int(model.iterations.max()):5d}")
    rows.append(f"(px at reference 2D scale {model.reference_scale:.1f} px; NLL nats per 2D error; "
                f"n = {model.n_samples} per joint)")
    return "\n".join(rows)


class SkipFigure(RuntimeError):
    """A figure cannot be drawn (e.g. no shipped weights yet)."""


def plot_error_histograms(errors: np.ndarray, model: Any, path: Path, *, lim: float = 60.0,
                          bins: int = 121, dpi: int = 80) -> Path:
    """Paper Fig. 5: per joint and axis, the histogram of errors ``(N, 17, 2)`` px (at the reference scale)
    with the fitted single Gaussian and the mixture's marginal density overlaid (log density axis).
    The mixture's x (or y) marginal is ``gamma N(mu, sigma^2) + (1 - gamma) / 100`` inside the box."""
    import matplotlib.pyplot as plt

    from ..skeleton import JOINT_NAMES

    x = np.linspace(-lim, lim, 600)
    side = np.sqrt(model.v)

    def npdf(x: np.ndarray, m: float, s: float) -> np.ndarray:
        return np.exp(-0.5 * ((x - m) / s) ** 2) / (np.sqrt(2 * np.pi) * s)

    fig, axes = plt.subplots(6, 6, figsize=(18, 15))
    axes = axes.ravel()
    for j in range(17):
        for a, axname in enumerate("xy"):
            ax = axes[2 * j + a]
            ej = np.clip(errors[:, j, a], -lim, lim)
            ax.hist(ej, bins=bins, range=(-lim, lim), density=True, color="0.7", label="SH errors")
            g = model.gaussian_mu[j, a], model.gaussian_sigma[j, a]
            ax.plot(x, npdf(x, *g), color="C0", lw=1.2, label="single Gaussian")
            mix = model.gamma[j] * npdf(x, model.mu[j, a], model.sigma[j, a]) + \
                (1 - model.gamma[j]) / side * (np.abs(x) <= side / 2)
            ax.plot(x, mix, color="C3", lw=1.2, label="mixture")
            ax.set_yscale("log")
            ax.set_ylim(1e-5, 0.3)
            ax.set_title(f"{JOINT_NAMES[j]} {axname}: γ={model.gamma[j]:.2f} σ={model.sigma[j, a]:.1f}", fontsize=9)
            ax.tick_params(labelsize=7)
    for ax in axes[34:]:
        ax.axis("off")
    axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"2D errors of the Stacked-Hourglass detections (px at 2D scale {model.reference_scale:.0f} px; "
                 f"|e| > {lim:.0f} px shown at the edges); n = {model.n_samples} per joint", fontsize=12)
    fig.subplots_adjust(left=0.03, right=0.99, bottom=0.03, top=0.94, wspace=0.3, hspace=0.45)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def plot_depth_vs_scale(samples: Any, path: Path, *, weights: str = "default") -> Path:
    """Paper Fig. 6: the lifter's predicted canonical depth (m) against the 2D scale sigma (px) of the GT
    2D test inputs, with the ground-truth canonical depth for reference. Raises :class:`SkipFigure` when
    no such weights exist."""
    import matplotlib.pyplot as plt

    from .._checks import PoseLifterError
    from ..api import Lifter
    from ..normalization import pose_scale

    try:
        lifter = Lifter.load(weights)
    except (PoseLifterError, FileNotFoundError) as exc:
        raise SkipFigure(f"no lifter weights ({exc})") from None
    kp = samples.keypoints_2d.astype(np.float64)
    res = lifter.lift(kp, focal=samples.focal, principal_point=samples.principal_point, source="clean")
    sigma = pose_scale(kp)
    pred, true = res.canonical_depth / 1000.0, samples.canonical_depth / 1000.0
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    axes[0].scatter(sigma, true, s=2, alpha=0.15, color="0.5", label="ground truth", rasterized=True)
    axes[0].scatter(sigma, pred, s=2, alpha=0.15, color="C3", label=f"predicted ({lifter.name})", rasterized=True)
    axes[0].set_xlabel("2D scale σ (px)")
    axes[0].set_ylabel("canonical depth (m, at f = 1000 px)")
    axes[0].legend(markerscale=6)
    inv = 1.0 / sigma
    axes[1].scatter(inv * 1e3, pred, s=2, alpha=0.15, color="C3", rasterized=True)
    k = float(np.sum(inv * pred) / np.sum(inv * inv))
    axes[1].plot(np.sort(inv) * 1e3, k * np.sort(inv), color="k", lw=1, label=f"depth = {k:.0f} m·px / σ")
    axes[1].set_xlabel("1000 / σ (1/px)")
    axes[1].set_ylabel("predicted canonical depth (m)")
    axes[1].legend()
    for ax in axes:
        ax.grid(alpha=0.3)
    corr = float(np.corrcoef(inv, pred)[0, 1])
    fig.suptitle(f"Predicted canonical depth vs 2D scale, H36M test set, GT 2D inputs (n = {len(kp)}; "
                 f"corr(depth, 1/σ) = {corr:.3f})", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
