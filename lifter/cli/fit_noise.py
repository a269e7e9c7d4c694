"""``poselifter fit-noise``: fit the 2D error model to the real Stacked-Hourglass detections.

Parses the arguments and calls :mod:`lifter.noise_fit` (the fit, its report and the figures); writes the JSON
and the figures and prints what was measured.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

from ..data import H36M
from ..noise import check_em_settings, em_not_converged
from ..noise_fit import (
    SkipFigure,
    describe_fit,
    fit_sh_error_model,
    format_error_table,
    plot_depth_vs_scale,
    plot_error_histograms,
)
from . import COMMANDS
from ._help import HelpFormatter, h36m_help

DEFAULT_JSON = Path("assets/error_model/sh_mixture.json")
DEFAULT_PLOT_DIR = Path("docs/noise")


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``fit-noise`` sub-command on an ``add_subparsers()`` object."""
    p = sub.add_parser("fit-noise", help=COMMANDS["fit-noise"][1],
                       formatter_class=HelpFormatter)
    p.add_argument("--h36m", type=Path, default=None, help=h36m_help())
    p.add_argument("--protocol", type=int, default=1, choices=(1, 2), help="fit on this protocol's training subjects")
    p.add_argument("-o", "--out", type=Path, default=None,
                   help=f"JSON to write (default {DEFAULT_JSON}, relative to the current folder: run from a checkout's "
                   "root, that replaces the shipped fit, which is how it is reproduced; elsewhere, give --out)")
    p.add_argument("--plots", type=Path, default=DEFAULT_PLOT_DIR,
                   help=f"folder for the PNG figures (default {DEFAULT_PLOT_DIR}, relative to the current folder)")
    p.add_argument("--tol", type=float, default=1e-7, help="EM stops when the mean log-lik gains less (nats/sample)")
    p.add_argument("--max-iter", type=int, default=1000, help="EM iteration cap")
    p.add_argument("--weights", default="default",
                   help="lifter for the depth-vs-scale figure: shipped model name or checkpoint .pt")
    p.add_argument("--depth-stride", type=int, default=10, help="test frame stride for the depth-vs-scale figure")
    p.add_argument("--no-alignment-check", action="store_true", help="skip the frame-alignment check (~20 s)")
    p.add_argument("--threads", type=int, default=2)
    p.set_defaults(func=run_fit_noise)
    return p


def run_fit_noise(args: argparse.Namespace) -> int:
    check_em_settings(args.tol, args.max_iter)  # (before the data is read)
    torch.set_num_threads(args.threads)
    data = H36M(args.h36m)
    fit = fit_sh_error_model(data, protocol=args.protocol, tol=args.tol, max_iter=args.max_iter,
                             alignment_check=not args.no_alignment_check)
    for line in describe_fit(fit):
        print(line)
    out = args.out or DEFAULT_JSON
    fit.model.save(out)
    print(f"reference 2D scale {fit.model.reference_scale:.1f} px; wrote {out}")
    print(format_error_table(fit.model))
    stuck = em_not_converged(fit.model)
    if stuck:
        print(f"WARNING: EM stopped at --max-iter {args.max_iter} before converging (--tol {args.tol:g}) for "
              f"{len(stuck)} of 17 joints ({', '.join(stuck)}): their parameters are not the maximum-likelihood fit "
              "(the JSON's meta.em.converged says which); raise --max-iter", file=sys.stderr)
    print(f"wrote {plot_error_histograms(fit.errors, fit.model, Path(args.plots) / 'error_histograms.png')}")
    try:
        test = data.load_protocol(args.protocol, "test", stride=args.depth_stride)
        print(f"wrote {plot_depth_vs_scale(test, Path(args.plots) / 'depth_vs_scale.png', weights=args.weights)}")
    except SkipFigure as exc:
        print(f"skipped depth_vs_scale.png: {exc}")
    return 0
