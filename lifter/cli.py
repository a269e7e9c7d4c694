"""``poselifter`` command line: train, evaluate (more sub-commands are registered by other modules)."""

from __future__ import annotations

import argparse
from dataclasses import replace
import json
import sys
from pathlib import Path
from typing import Sequence

import numpy as np

from ._checks import PoseLifterError


def _positive_int(text: str) -> int:
    """argparse ``type=``: an integer >= 1 (the option name is added by argparse)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


def _finite_floats(text: str) -> list[float]:
    parts = [v.strip() for v in text.split(",")]
    if not text.strip() or any(not v for v in parts):
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}")
    try:
        values = [float(v) for v in parts]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None
    if not all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"values must be finite, got {text!r}")
    return values


def _focal_scales(text: str) -> list[float]:
    """argparse ``type=`` for ``--focal-scales``: comma-separated finite factors > 0 (e.g. ``0.5,1,2``)."""
    values = _finite_floats(text)
    if any(v <= 0 for v in values):
        raise argparse.ArgumentTypeError(f"focal factors must be > 0, got {text!r}")
    return values


def _pp_shift(text: str) -> tuple[float, float]:
    """argparse ``type=`` for ``--pp-shift``: exactly two finite numbers ``dx,dy`` (px)."""
    values = _finite_floats(text)
    if len(values) != 2:
        raise argparse.ArgumentTypeError(f"expected two numbers 'dx,dy' (px), got {len(values)} value(s) in {text!r}")
    return (values[0], values[1])


def _add_train(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("train", help="train a lifter on Human3.6M", formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("--out", type=Path, required=True, help="checkpoint path to write (.pt)")
    p.add_argument("--h36m", type=Path, default=None, help="Human3.6M folder (default ../shared/data/h36m)")
    p.add_argument("--protocol", type=int, default=1, choices=(1, 2))
    p.add_argument("--mode", default="both", choices=("baseline", "location", "scale", "both"),
                   help="normalization-layer features (paper Table 2 ablation)")
    p.add_argument("--depth-target", default="canonical", choices=("canonical", "absolute"))
    p.add_argument("--scale-definition", default="paper", choices=("paper", "repo"))
    p.add_argument("--width", type=int, default=1024)
    p.add_argument("--blocks", type=int, default=2)
    p.add_argument("--dropout", type=float, default=0.25)
    p.add_argument("--epochs", type=float, default=30.0)
    p.add_argument("--batch-size", type=int, default=512)
    p.add_argument("--lr", type=float, default=1e-3)
    p.add_argument("--weight-decay", type=float, default=1e-4)
    p.add_argument("--train-stride", type=_positive_int, default=5)
    p.add_argument("--max-minutes", type=float, default=None, help="wall-clock budget; the lr schedule follows it")
    p.add_argument("--threads", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--eval-every", type=int, default=500)
    p.add_argument("--max-frames-per-sequence", type=_positive_int, default=None, help="tiny runs for tests")
    p.add_argument("--fp32", action="store_true", help="store float32 weights (default float16)")
    p.add_argument("--inputs", default="gt", choices=("gt", "sh", "mix"),
                   help="2D training inputs: GT projection, the real Stacked-Hourglass detections, or 'mix': each sample "
                        "gets its real detection with probability --real-prob, else GT 2D (+ --noise) (sh, mix: "
                        "train-stride a multiple of 5)")
    p.add_argument("--real-prob", type=float, default=0.5, help="--inputs mix: probability of the real detection")
    p.add_argument("--noise", default="none", choices=("none", "gaussian", "mixture"),
                   help="synthesize noisy 2D from the fitted error model (assets/error_model)")
    p.add_argument("--error-model", type=Path, default=None,
                   help="error-model JSON for --noise (default: the shipped SH fit, assets/error_model/sh_mixture.json)")
    p.add_argument("--init", default=None,
                   help="fine-tune: start from this checkpoint or shipped model name (keeps its architecture)")
    p.add_argument("--ema", type=float, default=None, help="keep an exponential moving average of the weights (e.g. 0.999)")
    p.add_argument("--noise-level", type=float, default=1.0)
    p.add_argument("--no-outliers", action="store_true", help="mixture noise without sampling the uniform outliers (authors' code)")
    p.add_argument("--zoom-aug", action="store_true", help="zoom augmentation: random focal/resolution scale (spec §6)")
    p.add_argument("--zoom-sigma", type=float, default=0.25, help="zoom: std of log2(scale)")
    p.add_argument("--zoom-clip", type=float, default=0.5, help="zoom: |log2(scale)| limit (0.5: x0.71..x1.41)")
    p.set_defaults(func=_run_train)


def _run_train(args: argparse.Namespace) -> int:
    from .data import H36M
    from .model import ModelConfig
    from .train import TrainConfig, save_training_outputs, train

    model = ModelConfig(width=args.width, num_blocks=args.blocks, dropout=args.dropout, mode=args.mode,
                        scale_definition=args.scale_definition, depth_target=args.depth_target)
    cfg = TrainConfig(model=model, protocol=args.protocol, train_stride=args.train_stride, batch_size=args.batch_size,
                      epochs=args.epochs, lr=args.lr, weight_decay=args.weight_decay, max_minutes=args.max_minutes,
                      seed=args.seed, threads=args.threads, eval_every=args.eval_every,
                      max_frames_per_sequence=args.max_frames_per_sequence, zoom_aug=args.zoom_aug,
                      zoom_sigma=args.zoom_sigma, zoom_clip=args.zoom_clip, real_2d_prob=args.real_prob,
                      ema_decay=args.ema)
    init = None
    if args.init is not None:
        from .api import Lifter

        init_lifter = Lifter.load(args.init)
        init = init_lifter.net
        ignored = {k: v for k, v in model.to_dict().items() if v != init.config.to_dict().get(k)}
        if ignored:
            print(f"note: --init {args.init}: keeping its architecture; ignored {ignored}")
    data = H36M(args.h36m)
    train_samples = real = None
    if args.inputs in ("sh", "mix"):
        from .noise import load_sh_detections, with_sh_detections

        if args.train_stride % 5:
            raise PoseLifterError(f"--inputs {args.inputs} needs --train-stride a multiple of 5 "
                                  "(detections exist every 5th frame)")
        train_samples = data.load_protocol(args.protocol, "train", stride=args.train_stride,
                                           max_frames_per_sequence=args.max_frames_per_sequence)
        if args.inputs == "sh":
            train_samples, dropped = with_sh_detections(train_samples, data=data)
            print(f"training on real SH detections: {len(train_samples)} samples ({dropped} without one dropped)")
        else:
            real, _ = load_sh_detections(train_samples, data=data)  # NaN rows (no detection) stay GT 2D
    augment = None
    if args.noise != "none":
        from .noise import ErrorModel

        em = ErrorModel.load(args.error_model) if args.error_model else ErrorModel.default()
        if args.noise == "gaussian":
            em = em.baseline()
        augment = em.torch_augmenter(level=args.noise_level, outliers=not args.no_outliers)
    result = train(cfg, data=data, train_samples=train_samples, augment_2d=augment, real_keypoints_2d=real, init=init)
    cfg = replace(cfg, model=result.net.config)
    meta = {"command": "poselifter " + " ".join(sys.argv[1:]), "inputs": args.inputs, "noise": args.noise,
            "noise_level": args.noise_level, "noise_outliers": not args.no_outliers,
            "error_model": str(args.error_model) if args.error_model else "default",
            "init": None if init is None else f"{args.init} ({init_lifter.name})"}
    out = save_training_outputs(result, cfg, args.out, half=not args.fp32, extra_meta=meta)
    print(f"wrote {out} (+ .curve.json, .curve.png); final {json.dumps(result.curve[-1])}")
    return 0


def _add_evaluate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("evaluate", help="evaluate lifters on Human3.6M and print the results table",
                       formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("weights", nargs="*", default=["default"],
                   help="checkpoint paths or shipped model names; LABEL=PATH to name a row")
    p.add_argument("--h36m", type=Path, default=None)
    p.add_argument("--protocol", type=int, default=1, choices=(1, 2))
    p.add_argument("--stride", type=_positive_int, default=5, help="test frame stride at 50 fps")
    p.add_argument("--inputs", default="gt", choices=("gt", "sh"),
                   help="2D inputs: ground-truth (distorted) projection, or the real Stacked-Hourglass detections")
    p.add_argument("--focal-scales", type=_focal_scales, default=None,
                   help="comma-separated focal factors (e.g. 0.5,0.7,1,1.4,2): re-project the test poses through "
                        "virtual pinhole cameras with focal x factor and report MRPE per factor (GT 2D inputs only; "
                        "not with --analytic-root, --per-action, --pck-plot)")
    p.add_argument("--pp-shift", type=_pp_shift, default="0,0",
                   help="principal-point shift (px) of the virtual cameras, 'dx,dy' (with --focal-scales)")
    p.add_argument("--flip-test", action="store_true", help="average with the mirrored input's prediction")
    p.add_argument("--analytic-root", action="store_true", help="add the weak-perspective root row for each model")
    p.add_argument("--per-action", action="store_true", help="also print per-action MPJPE")
    p.add_argument("--max-frames-per-sequence", type=_positive_int, default=None)
    p.add_argument("--json", type=Path, default=None, help="write all numbers to this JSON file")
    p.add_argument("--pck-plot", type=Path, default=None, help="write the 3DPCK-vs-threshold curves to this PNG")
    p.add_argument("--quantize", action="store_true", help="also evaluate each model with int8 block weights (Lifter.quantized)")
    p.add_argument("--threads", type=_positive_int, default=2)
    p.set_defaults(func=_run_evaluate)


def check_evaluate_options(args: argparse.Namespace) -> None:
    """Reject ``evaluate`` option combinations that would be silently ignored or misleading (before any
    weights or data are loaded). Raises :class:`PoseLifterError` naming the options."""
    if args.focal_scales is None:
        if tuple(args.pp_shift) != (0.0, 0.0):
            raise PoseLifterError("--pp-shift only applies to the virtual cameras of --focal-scales; "
                                  "pass --focal-scales too")
        return
    if args.inputs != "gt":
        raise PoseLifterError(f"--focal-scales cannot be combined with --inputs {args.inputs}: the focal sweep "
                              "re-projects the ground-truth 3D poses through virtual cameras, so there are no "
                              "detections for them (use --inputs gt)")
    ignored = [opt for opt, on in (("--analytic-root", args.analytic_root), ("--per-action", args.per_action),
                                   ("--pck-plot", args.pck_plot is not None)) if on]
    if ignored:
        raise PoseLifterError(f"{', '.join(ignored)} cannot be combined with --focal-scales: the focal sweep "
                              "reports only the learned-root MRPE per focal factor; run those without --focal-scales")


def _run_evaluate(args: argparse.Namespace) -> int:
    check_evaluate_options(args)
    import torch

    from .api import Lifter
    from .data import H36M
    from .evaluate import evaluate_lifter, format_per_action, format_table

    torch.set_num_threads(args.threads)
    lifters = []
    for spec in args.weights:
        label, _, ref = spec.rpartition("=")
        lifter = Lifter.load(ref)
        lifters.append((label or ref, lifter))
        if args.quantize:
            lifters.append(((label or ref) + " (int8)", lifter.quantized()))
    data = H36M(args.h36m)
    samples = data.load_protocol(args.protocol, "test", stride=args.stride,
                                 max_frames_per_sequence=args.max_frames_per_sequence)
    note = ""
    if args.inputs == "sh":
        from .noise import with_sh_detections

        samples, dropped = with_sh_detections(samples, data=data)
        note = f"; real SH detections, {dropped} samples without a detection dropped"
    print(f"Protocol {args.protocol}, test subjects {sorted(set(samples.subject.tolist()))}, stride {args.stride} "
          f"({len(samples)} samples, 4 cameras; S9 'Discussion 1' has no 3D in the data and is missing{note})")
    if args.focal_scales:
        from .evaluate import focal_sweep, format_focal_table

        factors = list(args.focal_scales)
        shift = tuple(args.pp_shift)
        sweep = {label: focal_sweep(lifter, samples, factors=factors, principal_shift=shift, flip_test=args.flip_test)
                 for label, lifter in lifters}
        print(format_focal_table(sweep, principal_shift=shift))
        if args.json:
            args.json.parent.mkdir(parents=True, exist_ok=True)
            args.json.write_text(json.dumps({k: [r.to_dict() for r in v] for k, v in sweep.items()}, indent=1))
        return 0
    rows = []
    for label, lifter in lifters:
        rows.extend(evaluate_lifter(lifter, samples, label=label, flip_test=args.flip_test,
                                    analytic_root=args.analytic_root))
    print(format_table(rows))
    if args.per_action:
        print(format_per_action(rows))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps([r.to_dict() for r in rows], indent=1))
    if args.pck_plot:
        from .metrics import AUC_THRESHOLDS_MM
        from .plots import plot_pck_curves

        plot_pck_curves({r.label: (AUC_THRESHOLDS_MM, np.asarray(r.pck_curve)) for r in rows if r.root == "learned"},
                        args.pck_plot)
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="poselifter", description="PoseLifter: absolute 3D pose from 2D keypoints")
    sub = parser.add_subparsers(dest="command", required=True)
    _add_train(sub)
    _add_evaluate(sub)
    from .noise_cli import add_parser as _add_fit_noise

    _add_fit_noise(sub)
    from .lift_cli import add_parser as _add_lift

    _add_lift(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (PoseLifterError, FileNotFoundError) as exc:
        print(f"poselifter {args.command}: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
