"""``poselifter evaluate``: lifters on Human3.6M (GT 2D or the real SH detections), as a results table.

With no model it evaluates the shipped default on GT 2D told ``source="clean"``, Protocol 1, S9 + S11, every
5th frame, all four cameras. ``--inputs sh`` uses the real Stacked-Hourglass detections, told "detected".
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

from .._checks import PoseLifterError, plot_format
from ..api import Lifter, ensemble_parts
from ..data import CAMERA_IDS, H36M, MISSING_TEST_SEQUENCES, PROTOCOLS, trained_protocol
from ..detections import detected_subset, load_sh_detections, missing_detection_note
from ..evaluate import evaluate_lifter, focal_sweep, format_focal_table, format_per_action, format_table
from ..io import check_writable, write_json_atomic
from ..metrics import AUC_THRESHOLDS_MM
from ..resources import model_names
from . import COMMANDS
from ._help import HelpFormatter, h36m_help, positive_int


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


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("evaluate", help=COMMANDS["evaluate"][1],
                       formatter_class=HelpFormatter)
    p.add_argument("weights", nargs="*", default=["default"],
                   help="checkpoint paths or shipped model names; LABEL=PATH to name a row; A.pt+B.pt: the "
                        "checkpoints' lifts of detected 2D averaged (an ensemble)")
    p.add_argument("--h36m", type=Path, default=None, help=h36m_help())
    p.add_argument("--protocol", type=int, default=1, choices=(1, 2),
                   help="test subjects: 1 = S9 and S11 (trained on S1, 5, 6, 7, 8), "
                   "2 = S11 (trained on S1, 5, 6, 7, 8, 9)")
    p.add_argument("--stride", type=positive_int, default=5, help="test frame stride at 50 fps")
    p.add_argument("--inputs", default="gt", choices=("gt", "sh"),
                   help="2D inputs: H36M's ground-truth 2D, or the real Stacked-Hourglass detections; both as seen "
                        "through each camera's lens, which is passed to the lifter (Lifter.lift distortion=): a "
                        "network that learned pinhole 2D undistorts them")
    p.add_argument("--focal-scales", type=_focal_scales, default=None,
                   help="comma-separated focal factors (e.g. 0.5,0.7,1,1.4,2): re-project the test poses through "
                        "virtual pinhole cameras with focal x factor and report MRPE per factor (GT 2D inputs only; "
                        "not with --analytic-root, --per-action, --pck-plot)")
    p.add_argument("--pp-shift", type=_pp_shift, default="0,0",
                   help="principal-point shift (px) of the virtual cameras, 'dx,dy' (with --focal-scales)")
    p.add_argument("--flip-test", action=argparse.BooleanOptionalAction, default=None,
                   help="average each pose with its mirror image's lift (default: the model's own setting; on for the "
                        "shipped default)")
    p.add_argument("--analytic-root", action="store_true", help="add the weak-perspective root row for each model")
    p.add_argument("--per-action", action="store_true", help="also print per-action MPJPE")
    p.add_argument("--max-frames-per-sequence", type=positive_int, default=None,
                   help="only the first this many frames of each sequence (after --stride; default all)")
    p.add_argument("--json", type=Path, default=None, help="write all numbers to this JSON file")
    p.add_argument("--pck-plot", type=Path, default=None,
                   help="write the 3DPCK-vs-threshold curves to this .png (or .pdf, .svg)")
    p.add_argument("--quantize", action="store_true",
                   help="also evaluate each model with int8 block weights (Lifter.quantized)")
    p.add_argument("--source", default=None, choices=("clean", "detected"),
                   help="what the lifter is told the 2D is (default: clean for --inputs gt, detected for --inputs sh)")
    p.add_argument("--threads", type=positive_int, default=2, help="torch threads")
    p.set_defaults(func=run)
    return p


def check_evaluate_options(args: argparse.Namespace) -> None:
    """Reject ``evaluate`` option combinations that would be silently ignored or misleading, and output paths
    that could not be written (before any weights or data are loaded). Raises :class:`PoseLifterError` naming
    the options."""
    for option, path in (("--json", args.json), ("--pck-plot", args.pck_plot)):
        if path is not None:
            check_writable(path, option=option)
    if args.pck_plot is not None:
        plot_format(args.pck_plot, option="--pck-plot")
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


def split_label(spec: str) -> tuple[str, str]:
    """``LABEL=REF`` -> ``(LABEL, REF)``. A spec that is itself a model (a shipped name, an existing file, whose path
    may hold '=', or files joined by '+') is its own label; else the first '=' followed by one splits it, else the
    last '=' (and :meth:`lifter.Lifter.load` names what it cannot find)."""

    shipped = model_names()

    def known(ref: str) -> bool:
        return ref == "default" or ref in shipped or all(Path(part).is_file() for part in ensemble_parts(ref))

    if known(spec):
        return spec, spec
    for i, ch in enumerate(spec):
        if ch == "=" and known(spec[i + 1:]):
            return spec[:i], spec[i + 1:]
    label, _, ref = spec.rpartition("=")
    return label or ref, ref


def flip_test_used(lifter: Lifter, flip_test: bool | None, source: str) -> tuple[bool, str]:
    """Whether ``lifter`` averaged each pose with its mirror image's lift for 2D told ``source`` (``flip_test``: the
    command's ``--flip-test`` / ``--no-flip-test``, None for each network's own setting): True when every network
    did (a mirror-equivariant one's single pass is that average), and each network's way, named ("on (NAME), built
    in (NAME)"). The results JSON keeps both, ``flip_test`` (always a bool: a researcher trial's scripts met a bool
    for one model and this string for the default) and ``flip_test_detail``."""
    net = lifter.network_for(source)  # type: ignore[arg-type]
    members = [net, *net.ensemble]

    def one(m: Lifter) -> str:
        return "built in" if m.config.symmetry == "mirror" else "on" if m.network_rows(flip_test) == 2 else "off"

    said = [one(m) for m in members]
    return all(w != "off" for w in said), ", ".join(f"{w} ({m.name})" for w, m in zip(said, members))


def training_subject_notes(label: str, lifter: Lifter, protocol: int) -> list[str]:
    """Where a model's training subjects (its stored training config's protocol) do not match ``protocol``'s:
    trained on a subject this protocol tests on (seen data), or on fewer subjects than it trains on (not the
    paper's setting for that protocol). Nothing for a model whose checkpoint does not say how it was trained."""
    train_subjects, test_subjects = PROTOCOLS[protocol]
    out = []
    trained = {p for p in (trained_protocol(m) for m in lifter.networks().values()) if p is not None}
    for p in sorted(trained):
        seen = sorted(set(PROTOCOLS[p][0]) & set(test_subjects))
        if seen:
            out.append(f"{label}: trained on Protocol {p}'s subjects, which include the test subject(s) "
                       f"{', '.join(f'S{s}' for s in seen)}: these numbers are on seen people")
        elif set(PROTOCOLS[p][0]) != set(train_subjects):
            out.append(f"{label}: trained on Protocol {p}'s subjects ({', '.join(f'S{s}' for s in PROTOCOLS[p][0])}), "
                       f"not Protocol {protocol}'s ({', '.join(f'S{s}' for s in train_subjects)}): the test "
                       f"subjects are unseen, but this is not the paper's Protocol {protocol} setting")
    return out


def run(args: argparse.Namespace) -> int:
    check_evaluate_options(args)
    torch.set_num_threads(args.threads)
    lifters = []
    specs = [split_label(spec) for spec in args.weights]
    labels = [label for label, _ in specs]
    twice = [la for la in dict.fromkeys(labels) if labels.count(la) > 1]
    if twice:  # (a researcher trial: two rows "x", their JSON objects not told apart, one's provenance lost)
        refs = [ref for label, ref in specs if label == twice[0]]
        raise PoseLifterError(f"two models are labelled {twice[0]!r}: give each row its own label (LABEL=MODEL, e.g. "
                              + " ".join(f"{chr(ord('a') + k)}={ref}" for k, ref in enumerate(refs[:3])) + ")")
    for label, ref in specs:
        lifter = Lifter.load(ref)
        lifters.append((label, lifter))
        if args.quantize:
            lifters.append((label + " (int8)", lifter.quantized()))
    data = H36M(args.h36m)
    samples = data.load_protocol(args.protocol, "test", stride=args.stride,
                                 max_frames_per_sequence=args.max_frames_per_sequence)
    note = ""
    if args.inputs == "sh":
        det, ok = load_sh_detections(samples, data=data)  # (once: the note and the subset)
        missing = missing_detection_note(samples, ok)
        samples = detected_subset(samples, det, ok)
        note = "; real SH detections" + (f", {missing}" if missing else "")
    source = args.source or ("clean" if args.inputs == "gt" else "detected")
    if args.inputs == "sh" and source == "clean":
        print("note: --source clean with --inputs sh tells the lifter that detector output is exact 2D (the clean "
              "network lifts it): a what-if, not how the default is meant to be used", file=sys.stderr)
    for label, lifter in lifters:
        for line in training_subject_notes(label, lifter, args.protocol):
            print(f"note: {line}", file=sys.stderr)
    subjects = sorted({int(x) for x in samples.subject.tolist()})
    cameras = sorted({int(x) for x in samples.camera.tolist()})
    sequences = len({(int(a), int(b)) for a, b in zip(samples.subject.tolist(), samples.sequence.tolist())})
    missing = [m for m in MISSING_TEST_SEQUENCES if int(m.split("/")[0][1:]) in subjects]
    how = {"protocol": args.protocol, "test_subjects": subjects, "stride": args.stride,
           "max_frames_per_sequence": args.max_frames_per_sequence, "cameras": [CAMERA_IDS[c] for c in cameras],
           "sequences": sequences, "missing_sequences": missing, "inputs": args.inputs, "source": source,
           "units": "mm; pck150 and auc as fractions",  # (in every row of --json: each says how it was measured)
           "pck_curve_thresholds_mm": [float(t) for t in AUC_THRESHOLDS_MM]}
    gone = "".join(f"; {s} '{q}' has no 3D in the data and is missing" for s, q in (m.split("/", 1) for m in missing))
    cut = (f"; ONLY THE FIRST {args.max_frames_per_sequence} FRAMES OF EACH SEQUENCE (--max-frames-per-sequence): not "
           "a full evaluation" if args.max_frames_per_sequence is not None else "")
    print(f"Protocol {args.protocol}, test subjects {subjects}, stride {args.stride} ({len(samples)} samples, "
          f"{sequences} sequences{' of ' + str(sequences + len(missing)) if missing else ''}, {len(cameras)} "
          f"camera{'s' if len(cameras) != 1 else ''}{gone}{note}{cut}); source={source!r}")
    # what each row's lift did: the flip test as given, else each network's own (a mirror-equivariant network's
    # single pass already is one)
    flip_used = {label: flip_test_used(lifter, args.flip_test, source) for label, lifter in lifters}
    info = {label: lifter.provenance(source=source, flip_test=args.flip_test) for label, lifter in lifters}
    if args.focal_scales:
        factors = list(args.focal_scales)
        shift = tuple(args.pp_shift)
        sweep = {label: focal_sweep(lifter, samples, factors=factors, principal_shift=shift, flip_test=args.flip_test,
                                   source=source)
                 for label, lifter in lifters}
        print(format_focal_table(sweep, principal_shift=shift))
        if args.json:  # (rows as without --focal-scales, each with its model and factor: a researcher trial's
            # scripts met a dict keyed by model here, and the factor only as the label "x0.5")
            write_json_atomic(args.json, [{**r.to_dict(), **how, "model": k, "focal_scale": f,
                                           "flip_test": flip_used[k][0], "flip_test_detail": flip_used[k][1],
                                           "principal_shift_px": list(shift), "model_info": info[k]}
                                          for k, v in sweep.items() for f, r in zip(factors, v)])
        return 0
    rows, row_how = [], []
    for label, lifter in lifters:
        got = evaluate_lifter(lifter, samples, label=label, flip_test=args.flip_test,
                              analytic_root=args.analytic_root, source=source)
        rows.extend(got)
        row_how += [{**how, "model": label, "flip_test": flip_used[label][0], "flip_test_detail": flip_used[label][1],
                     "model_info": info[label]}] * len(got)
    print(format_table(rows))
    if args.per_action:
        print(format_per_action(rows))
    if args.json:
        write_json_atomic(args.json, [{**r.to_dict(), **h} for r, h in zip(rows, row_how)])
    if args.pck_plot:
        from ..plots import plot_pck_curves  # matplotlib only when a figure is asked for (~0.5 s to import)

        plot_pck_curves({r.label: (AUC_THRESHOLDS_MM, np.asarray(r.pck_curve)) for r in rows if r.root == "learned"},
                        args.pck_plot)
    return 0


