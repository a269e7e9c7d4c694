"""Fitting the 2D error model to the real Stacked-Hourglass detections of H36M, and its report and figures.

The workflow behind ``poselifter fit-noise`` (:mod:`lifter.cli.fit_noise` only parses the arguments and
calls :func:`fit_sh_error_model`, :func:`describe_fit`, :func:`format_error_table` and the two figures). It
loads the training subjects of a protocol (every 5th frame, 4 cameras; the detections file holds exactly
those frames for them), converts the sh16 detections with :func:`lifter.keypoints.convert`, measures the
converter's interpolation rules, and fits the mixture and the single Gaussian per joint
(:func:`lifter.noise.fit_error_model`). The error model itself (:mod:`lifter.noise`) knows nothing of the
dataset; this module is where the two meet.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import PoseLifterError
from .api import Lifter
from .data import H36M, PROTOCOLS, PoseSamples
from .detections import SH_DETECTIONS_FILE, detection_alignment_check, load_sh_detections
from .keypoints import SH16_HEAD_WEIGHT, SH16_NECK_WEIGHT, SH16_SPINE_WEIGHT, convert, fit_line_weight
from .noise import ErrorModel, fit_error_model
from .normalization import pose_scale
from .skeleton import JOINT_NAMES, NUM_JOINTS


class SkipFigure(RuntimeError):
    """A figure cannot be drawn (e.g. no such lifter weights)."""


@dataclass(frozen=True)
class SHNoiseFit:
    """The result of :func:`fit_sh_error_model`.

    model: the fitted :class:`~lifter.noise.ErrorModel`. errors: ``(N, 17, 2)`` px, the detection errors
    rescaled to the model's reference 2D scale (what was fitted). scale: ``(N,)`` px, each sample's GT 2D
    scale. subjects: the training subjects. skipped: samples without a detection. alignment: median limb
    error (px) by frame offset of the detections (empty when not checked). converter: the sh16 rules'
    measured errors (:func:`converter_report`). scale_dependence: :func:`scale_dependence`.
    """

    model: ErrorModel
    errors: np.ndarray
    scale: np.ndarray
    subjects: tuple[int, ...]
    skipped: int
    alignment: dict[int, float]
    converter: dict[str, Any]
    scale_dependence: list[dict[str, float]]


def _line(target: np.ndarray, a: np.ndarray, b: np.ndarray, w: float) -> tuple[float, float]:
    e = np.linalg.norm(a + w * (b - a) - target, axis=-1)
    return float(e.mean()), float(np.median(e))


def converter_report(gt: np.ndarray, det16: np.ndarray) -> dict[str, Any]:
    """Re-fit and measure the sh16 interpolation rules: GT ``(N, 17, 2)``, raw sh16 detections ``(N, 16, 2)``."""
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


def fit_sh_error_model(data: H36M, *, protocol: int = 1, tol: float = 1e-7, max_iter: int = 1000,
                       alignment_check: bool = True, progress: bool = True) -> SHNoiseFit:
    """Fit the error model to the SH detections of ``protocol``'s training subjects (module docstring)."""
    subjects = tuple(PROTOCOLS[protocol][0])
    chk = detection_alignment_check(data, subject=subjects[0]) if alignment_check else {}
    samples = data.load(list(subjects), stride=5)
    det16, valid = load_sh_detections(samples, data=data, dst="sh16")  # raw detector joints
    samples = samples.subset(valid)
    det16 = det16[valid]
    det17 = convert(det16, src="sh16")
    gt = samples.keypoints_2d.astype(np.float64)
    scale = pose_scale(gt)
    conv = converter_report(gt, det16)
    dep = scale_dependence(det17 - gt, scale)
    meta = {"data": {"detections": SH_DETECTIONS_FILE, "subjects": list(subjects), "protocol": protocol,
                     "frames": "every 5th (row i = frame 5 i)", "cameras": 4, "n_samples": int(len(samples))},
            "alignment_check_median_px_by_offset": {str(k): v for k, v in chk.items()},
            "converter": conv, "scale_dependence": dep,
            "error_definition": "convert(sh16 detection) - distorted GT projection, px, rescaled by "
                                "reference_scale / sigma_gt"}
    source = ("Stacked-Hourglass (MPII-pretrained) detections vs distorted GT projection, H36M "
              + ", ".join(f"S{s}" for s in subjects) + ", every 5th frame, 4 cameras")
    model = fit_error_model(det17, gt, source=source, tol=tol, max_iter=max_iter, progress=progress, meta=meta)
    errors = (det17 - gt) * (model.reference_scale / scale)[:, None, None]
    return SHNoiseFit(model=model, errors=errors, scale=scale, subjects=subjects, skipped=int((~valid).sum()),
                      alignment=chk, converter=conv, scale_dependence=dep)


def describe_fit(fit: SHNoiseFit) -> list[str]:
    """What the fit measured besides the model, as lines of text: frame alignment, samples, converter rules,
    scale dependence."""
    lines: list[str] = []
    if fit.alignment:
        chk = fit.alignment
        best = min(chk, key=lambda o: chk[o])
        lines.append(f"alignment check (S{fit.subjects[0]}, camera 0, limbs): median error px by frame offset "
                     + ", ".join(f"{o:+d}: {v:.2f}" for o, v in chk.items()) + f" -> best offset {best:+d}")
        if best != 0:
            lines.append("WARNING: detections are not aligned with frame 5*i; check the data")
    if fit.skipped:
        lines.append(f"note: {fit.skipped} training samples have no detection and are skipped")
    lines.append(f"training subjects {list(fit.subjects)}: {len(fit.errors)} samples (every 5th frame, 4 cameras)")
    conv = fit.converter
    nn, gt_only = conv["neck_nose"], conv["neck_nose_gt_only"]
    lines.append(f"converter sh16 -> h36m17: neck_nose = thorax + {nn['w_shipped']:.3f} (head - thorax): "
                 f"error {nn['mean_px_median_px'][0]:.1f} px mean / {nn['mean_px_median_px'][1]:.1f} px median "
                 f"(re-fitted w {nn['w_refit']:.3f}); on GT alone (w {gt_only['w']:.3f}): "
                 f"{gt_only['mean_px_median_px'][0]:.1f} / {gt_only['mean_px_median_px'][1]:.1f} px")
    for name in ("spine", "head_top"):
        c = conv[name]
        lines.append(f"  {name}: w {c['w_shipped']:.3f} (re-fit {c['w_refit']:.3f}): {c['mean_px_median_px'][0]:.1f} / "
                     f"{c['mean_px_median_px'][1]:.1f} px mean/median; direct mapping: "
                     f"{c['direct_mean_px_median_px'][0]:.1f} / {c['direct_mean_px_median_px'][1]:.1f} px")
    lines.append("scale dependence (median over samples of the per-pose median joint error, by GT 2D scale quintile): "
                 + ", ".join(f"{d['median_scale_px']:.0f} px -> {d['median_error_px']:.1f} px"
                             for d in fit.scale_dependence))
    return lines


def format_error_table(model: ErrorModel) -> str:
    """Per-joint table: gamma, inlier mu and sigma (px), baseline sigma, NLLs, EM iterations."""
    if model.gaussian_sigma is None or model.nll_mixture is None or model.nll_gaussian is None \
            or model.iterations is None:
        raise ValueError("the table needs a fitted model (baseline fit, NLLs and iterations)")
    gs, nm, ng, it = model.gaussian_sigma, model.nll_mixture, model.nll_gaussian, model.iterations
    rows = [f"{'joint':<11} {'gamma':>6} {'mu_x':>6} {'mu_y':>6} {'sig_x':>6} {'sig_y':>6} {'gsig_x':>7} {'gsig_y':>7} "
            f"{'NLL_mix':>8} {'NLL_gau':>8} {'iters':>5}"]
    for j, name in enumerate(JOINT_NAMES):
        rows.append(f"{name:<11} {model.gamma[j]:6.3f} {model.mu[j, 0]:6.2f} {model.mu[j, 1]:6.2f} "
                    f"{model.sigma[j, 0]:6.2f} {model.sigma[j, 1]:6.2f} {gs[j, 0]:7.2f} {gs[j, 1]:7.2f} "
                    f"{nm[j]:8.3f} {ng[j]:8.3f} {int(it[j]):5d}")
    rows.append(f"{'mean':<11} {model.gamma.mean():6.3f} {'':6} {'':6} {model.sigma[:, 0].mean():6.2f} "
                f"{model.sigma[:, 1].mean():6.2f} {gs[:, 0].mean():7.2f} {gs[:, 1].mean():7.2f} {nm.mean():8.3f} "
                f"{ng.mean():8.3f} {it.mean():5.1f}")
    rows.append(f"(px at reference 2D scale {model.reference_scale:.1f} px; NLL nats per 2D error; "
                f"n = {model.n_samples} per joint)")
    return "\n".join(rows)


def _pyplot() -> Any:
    # matplotlib (through lifter.plots, which selects the Agg backend) only when a figure is drawn: it adds
    # about half a second to every `poselifter` start otherwise, and the fit itself does not need it.
    from .plots import plt

    return plt


def plot_error_histograms(errors: np.ndarray, model: ErrorModel, path: Path, *, lim: float = 60.0,
                          bins: int = 121, dpi: int = 80) -> Path:
    """Paper Fig. 5: per joint and axis, the histogram of errors ``(N, 17, 2)`` px (at the reference scale)
    with the fitted single Gaussian and the mixture's marginal density overlaid (log density axis).
    The mixture's x (or y) marginal is ``gamma N(mu, sigma^2) + (1 - gamma) / 100`` inside the box."""
    if model.gaussian_mu is None or model.gaussian_sigma is None:
        raise ValueError("the histograms need the single-Gaussian baseline fit")
    plt = _pyplot()
    x = np.linspace(-lim, lim, 600)
    side = np.sqrt(model.v)

    def npdf(x: np.ndarray, m: float, s: float) -> np.ndarray:
        return np.exp(-0.5 * ((x - m) / s) ** 2) / (np.sqrt(2 * np.pi) * s)

    fig, axes = plt.subplots(6, 6, figsize=(18, 15))
    axes = axes.ravel()
    for j in range(NUM_JOINTS):
        for a, axname in enumerate("xy"):
            ax = axes[2 * j + a]
            ej = np.clip(errors[:, j, a], -lim, lim)
            ax.hist(ej, bins=bins, range=(-lim, lim), density=True, color="0.7", label="SH errors")
            ax.plot(x, npdf(x, model.gaussian_mu[j, a], model.gaussian_sigma[j, a]), color="C0", lw=1.2,
                    label="single Gaussian")
            mix = model.gamma[j] * npdf(x, model.mu[j, a], model.sigma[j, a]) + \
                (1 - model.gamma[j]) / side * (np.abs(x) <= side / 2)
            ax.plot(x, mix, color="C3", lw=1.2, label="mixture")
            ax.set_yscale("log")
            ax.set_ylim(1e-5, 0.3)
            ax.set_title(f"{JOINT_NAMES[j]} {axname}: γ={model.gamma[j]:.2f} σ={model.sigma[j, a]:.1f}", fontsize=9)
            ax.tick_params(labelsize=7)
    for ax in axes[2 * NUM_JOINTS:]:
        ax.axis("off")
    axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle(f"2D errors of the Stacked-Hourglass detections (px at 2D scale {model.reference_scale:.0f} px; "
                 f"|e| > {lim:.0f} px shown at the edges); n = {model.n_samples} per joint", fontsize=12)
    fig.subplots_adjust(left=0.03, right=0.99, bottom=0.03, top=0.94, wspace=0.3, hspace=0.45)
    from .plots import save_figure

    return save_figure(fig, path, dpi=dpi)


def plot_depth_vs_scale(samples: PoseSamples, path: Path, *, weights: str = "default") -> Path:
    """Paper Fig. 6: the lifter's predicted canonical depth (m) against the 2D scale sigma (px) of the GT
    2D test inputs, with the ground-truth canonical depth for reference. Raises :class:`SkipFigure` when
    no such weights exist."""
    try:
        lifter = Lifter.load(weights)
    except (PoseLifterError, FileNotFoundError) as exc:  # CheckpointError is a PoseLifterError
        raise SkipFigure(f"no lifter weights ({exc})") from None
    plt = _pyplot()
    kp = samples.keypoints_2d.astype(np.float64)
    res = lifter.lift(kp, focal=samples.focal, principal_point=samples.principal_point, source="clean",
                      distortion=samples.input_distortion)
    sigma = pose_scale(kp)
    pred, true = res.canonical_depth / 1000.0, samples.canonical_depth / 1000.0
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    axes[0].scatter(sigma, true, s=2, alpha=0.15, color="0.5", label="ground truth", rasterized=True)
    axes[0].scatter(sigma, pred, s=2, alpha=0.15, color="C3", label=f"predicted ({lifter.name})", rasterized=True)
    axes[0].set_xlabel("2D scale σ (px)")
    axes[0].set_ylabel("canonical depth (m, at f = 1000 px)")
    axes[0].legend(markerscale=6)
    inv = 1.0 / sigma
    # Under weak perspective sigma = f s / Z, with s the 3D pose's own size across the view (the RMS radius of its
    # X, Y about their mean, mm), so the canonical depth (f = 1000 px) is s / sigma: a ray through the origin per
    # body size and posture. Points coloured by s, with the rays of its 10th and 90th percentiles (a researcher
    # trial read one least-squares line through all points as a misfit: sitting people, small in 2D for their
    # depth, make a second branch).
    size = pose_scale(samples.pose_3d[..., :2].astype(np.float64))
    dots = axes[1].scatter(inv * 1e3, pred, s=2, alpha=0.3, c=size, cmap="viridis", rasterized=True)
    fig.colorbar(dots, ax=axes[1], label="3D pose size s (mm, RMS radius across the view)")
    x = np.percentile(inv, [0.5, 99.5])
    for q in (10, 90):
        s_q = float(np.percentile(size, q))
        axes[1].plot(x * 1e3, s_q * x, color="k", lw=1, ls="--" if q == 10 else "-",
                     label=f"depth = s / σ, s = {s_q:.0f} mm ({q}th percentile)")
    axes[1].set_ylim(*np.percentile(pred, [0.1, 99.9]) + np.array([-0.3, 0.3]))
    axes[1].set_xlabel("1000 / σ (1/px)")
    axes[1].set_ylabel("predicted canonical depth (m)")
    axes[1].legend(loc="upper left", fontsize=8)
    for ax in axes:
        ax.grid(alpha=0.3)
    corr = float(np.corrcoef(inv, pred)[0, 1])
    fig.suptitle(f"Predicted canonical depth vs 2D scale, H36M test set, GT 2D inputs (n = {len(kp)}; "
                 f"corr(depth, 1/σ) = {corr:.3f})", fontsize=10)
    fig.tight_layout()
    from .plots import save_figure

    return save_figure(fig, path, dpi=100)
