"""``poselifter train``: train a lifter on Human3.6M, on one process or under ``torchrun``.

Every field of :class:`lifter.config.TrainConfig` is an option (``--width``, ``--clean-prob``, ``--epochs``,
...); ``--config FILE`` starts from a saved run (a JSON config, a ``.curve.json`` or a checkpoint), and the
options given override it. The resolved config is stored in the checkpoint, so
``poselifter train --config runs/x.pt --out runs/x_again.pt`` repeats a run.

Distributed: ``torchrun --nproc_per_node N -m lifter train ...`` (gloo on CPU, NCCL on GPU); the global
batch is split across the processes and rank 0 writes the checkpoint (:mod:`lifter.train`).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import torch
import torch.distributed as dist

from .. import resources
from .._checks import PoseLifterError
from ..api import Lifter
from ..checkpoint import load_checkpoint, sha256_file
from ..codec import PoseCodec
from ..config import TrainConfig, add_config_arguments, config_from_args
from ..data import H36M
from ..detections import SH_DETECTIONS_FILE, load_sh_detections
from ..io import check_writable
from ..noise import ErrorModel
from ..resume import ResumeState
from ..train import (
    check_resume,
    check_teacher,
    init_distributed,
    load_fit,
    minutes_text,
    save_training_outputs,
    train,
    validation_sets,
)
from . import COMMANDS
from ._help import h36m_help, plain_text


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    p = sub.add_parser("train", help=COMMANDS["train"][1],
                       description=plain_text(__doc__), formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-o", "--out", type=Path, help="checkpoint path to write (.pt); required unless --print-config")
    p.add_argument("--config", type=Path, default=None, help="start from this run's config (JSON, .curve.json or .pt)")
    p.add_argument("--resume", type=Path, default=None, metavar="RUN.resume.pt",
                   help="go on with a run stopped with Ctrl-C where it stopped (the NAME.resume.pt it wrote beside its "
                        "--out): its config, weights, optimizer, schedule and random draws; --out defaults to the "
                        "run's own")
    p.add_argument("--print-config", action="store_true", help="print the resolved config as JSON and exit")
    p.add_argument("--h36m", type=Path, default=None, help=h36m_help())
    p.add_argument("--threads", type=int, default=None, help="torch threads per process (default: torch's)")
    p.add_argument("--fp32-weights", action="store_true", help="store float32 weights (default float16)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    add_config_arguments(p)
    p.set_defaults(func=run)
    return p


def run(args: argparse.Namespace) -> int:
    if args.resume is not None:
        return run_resume(args)
    base = TrainConfig.load(args.config) if args.config is not None else None
    cfg = config_from_args(args, base)
    if getattr(args, "cfg__optim__distill_weight", None) is not None and cfg.teacher is None:
        raise PoseLifterError("--distill-weight weighs the loss against a teacher's outputs, and no --teacher is "
                              "given: add --teacher MODEL (a shipped name or checkpoint), or drop --distill-weight")
    if getattr(args, "cfg__data__error_model", None) is not None and cfg.data.noise_prob <= 0:
        # (a security trial: a file that is not a fit was accepted unread, and failed later in a --config repeat; a
        # researcher trial: a name that is no fit was stored in the run's config all the same)
        try:
            ErrorModel.resolve(cfg.data.error_model)
        except PoseLifterError as exc:
            raise PoseLifterError(f"{exc}; this run would not read it either (no sample gets synthetic noise): drop "
                                  "--error-model") from None
        print(f"note: --error-model {cfg.data.error_model} is not read: no sample gets synthetic noise "
              f"(--clean-prob {cfg.data.clean_prob:g} + --real-prob {cfg.data.real_prob:g} = 1)", file=sys.stderr)
    init, init_sha, init_notes, init_name = None, None, [], ""
    if cfg.init is not None:  # (before --print-config: it prints the config the fine-tune runs with)
        try:
            lifter = load_option("--init", cfg.init, args)
        except PoseLifterError as exc:
            if not args.print_config:
                raise
            # (a review: the shipped `universal` stores an --init that is not shipped, and printing its config
            # failed where it had worked before the fine-tune's config was resolved here)
            init_notes = [f"{exc}; the config is printed as stored: a fine-tune keeps its --init network's model "
                          "config and lens"]
        else:
            init, init_name = (lifter.net, lifter.codec), lifter.name
            init_sha = weights_sha256(cfg.init)
            cfg, init_notes = fine_tune_config(cfg, lifter, args)
    if args.print_config:
        for line in init_notes:
            print(f"note: {line}", file=sys.stderr)
        print(cfg.to_json())
        return 0
    if args.out is None:
        raise PoseLifterError("--out is required: the checkpoint path to write")
    _check_out(Path(args.out), cfg, args.config)  # (first: check_writable creates --out's folder)
    check_writable(args.out, option="--out")  # before training, not after it: a run not saved is lost
    if args.threads is not None and args.threads < 1:
        raise PoseLifterError(f"--threads must be >= 1, got {args.threads}")

    ctx = init_distributed()
    if args.threads:
        torch.set_num_threads(args.threads)
    if init_sha is not None and ctx.main:
        print(f"fine-tuning from --init {cfg.init} (sha256 {init_sha[:12]}; {init_name})", file=sys.stderr)
        for line in init_notes:
            print(f"note: {line}", file=sys.stderr)
    teacher, teacher_sha = None, None
    if cfg.teacher is not None:  # (refused before the data is read)
        teacher = load_option("--teacher", cfg.teacher, args)
        check_teacher(teacher, init[1] if init is not None else PoseCodec(cfg.model), lens=cfg.data.lens)
        teacher_sha = weights_sha256(cfg.teacher, every_network=True)
    try:
        fit = load_fit(cfg)  # (before the data is read: a fit that cannot be read is refused at once)
    except PoseLifterError as exc:
        raise PoseLifterError(f"{exc}{_stored_fit_hint(args)}") from None
    if ctx.main:
        for line in repeat_notes(args.config, init=None if init_sha is None else (str(cfg.init), init_sha),
                                 teacher=None if teacher_sha is None else (str(cfg.teacher), teacher_sha),
                                 error_model=None if fit is None else (cfg.data.error_model, fit.sha256())):
            print(f"note: {line}", file=sys.stderr)
    meta: dict[str, Any] = {"command": "poselifter " + " ".join(sys.argv[1:]), "world_size": ctx.world}
    if init_sha is not None:
        meta["init_sha256"] = init_sha
    if teacher_sha is not None:
        meta["teacher_sha256"] = teacher_sha
    return _train_and_write(args, cfg, ctx=ctx, init=init, teacher=teacher, meta=meta)


def _train_and_write(args: argparse.Namespace, cfg: TrainConfig, *, ctx: Any, init: tuple[Any, PoseCodec] | None,
                     teacher: Lifter | None, meta: dict[str, Any], resume: ResumeState | None = None) -> int:
    """Read the data, train, and write ``args.out`` (or, stopped with Ctrl-C, the weights so far and the run's
    resume state beside it); ``meta`` goes into the checkpoint."""
    data = H36M(args.h36m)
    d = cfg.data
    samples = data.load_protocol(d.protocol, "train", stride=d.train_stride,
                                 max_frames_per_sequence=d.max_frames_per_sequence, lens=d.lens)
    real = load_sh_detections(samples, data=data, lens=d.lens)[0] if d.real_prob > 0 else None
    val = data.load_protocol(d.protocol, "test", stride=d.val_stride, max_frames_per_sequence=d.max_frames_per_sequence,
                             lens=d.lens)
    val_det = (load_sh_detections(val, data=data, lens=d.lens)[0] if (Path(data.root) / SH_DETECTIONS_FILE).is_file()
               else None)
    data_root = data.root
    result = train(cfg, data=data, train_samples=samples, real_keypoints_2d=real,
                   val_sets=validation_sets(val, val_det), init=init, teacher=teacher, progress=not args.no_progress,
                   ctx=ctx, resume=resume)
    if ctx.main:
        if result.interrupted:
            if ctx.active:  # (not reached: train() re-raises under torchrun)
                raise KeyboardInterrupt
            if result.steps == 0:
                print("poselifter train: interrupted before the first step: nothing written", file=sys.stderr)
                return 130
            # (a researcher trial: a run stopped with Ctrl-C wrote nothing, an hour's CPU run lost; the weights so
            # far go beside --out, never over it: Ctrl-C is also how a run started with a wrong option is stopped)
            partial = interrupted_path(args.out)
            meta["interrupted"] = True
            _save_outputs(result, partial, half=not args.fp32_weights, meta=meta)
            go_on = ""
            state_file = resume_path(args.out)
            if result.resume is not None:  # (after the weights: a Ctrl-C while the state is written keeps them)
                run_meta = meta.get("resumed", {}).get("run") or {k: v for k, v in meta.items() if k in _RUN_KEYS}
                state_meta = {**run_meta, "out": str(Path(args.out).resolve()), "fp32_weights": bool(args.fp32_weights),
                              "threads": torch.get_num_threads(), "h36m": str(Path(data_root).resolve())}
                try:
                    written = replace(result.resume, meta=state_meta).save(state_file)
                except KeyboardInterrupt:
                    print(f"poselifter train: interrupted at step {result.steps} while its resume state was written: "
                          f"the weights so far are in {partial} (not {args.out}); no resume state was written; "
                          f"--init {partial} starts a new run from them", file=sys.stderr)
                    raise SystemExit(130) from None
                go_on = (f"; poselifter train --resume {written} goes on where it stopped (its schedule, optimizer, "
                         "weight average and random draws)")
            elif state_file.is_file():  # (a state left by an earlier run would go on with that run, not this one)
                go_on = (f"; {state_file} beside it is an earlier stop's state (this stop, a second Ctrl-C inside a "
                         "step, left none): --resume it only to go on with that earlier run")
            print(f"poselifter train: interrupted at step {result.steps} ({minutes_text(result.minutes)}): the weights "
                  f"so far are in {partial} (meta 'interrupted'; not {args.out}){go_on}; --init {partial} starts a new "
                  "run from them (its schedule and EMA start again)",
                  file=sys.stderr)
            return 130
        out = _save_outputs(result, args.out, half=not args.fp32_weights, meta=meta)
        print(f"wrote {out} (+ .curve.json, .curve.png); final {json.dumps(result.curve[-1])}")
        if resume is not None and resume_path(args.out).is_file():
            print(f"note: {resume_path(args.out)} is the state the run went on from; not needed now that it has "
                  "finished", file=sys.stderr)
    if ctx.active:
        dist.barrier()
        dist.destroy_process_group()
    return 0


def _save_outputs(result: Any, out: Path, *, half: bool, meta: dict[str, Any]) -> Path:
    """:func:`save_training_outputs`; a Ctrl-C while it writes says which of its files are written whole (each is
    written atomically: a security trial's interrupt there was told "no checkpoint was written" while the new
    checkpoint was on disk, replacing the one before)."""
    import time

    t0 = time.time()
    try:
        return save_training_outputs(result, out, half=half, extra_meta=meta)
    except KeyboardInterrupt:
        new = [p for p in (out, out.with_suffix(".curve.json"), out.with_suffix(".curve.png"))
               if p.is_file() and p.stat().st_mtime >= t0 - 1.0]
        done = ", ".join(str(p) for p in new) if new else "none"
        print(f"poselifter train: interrupted while writing the run's outputs; written whole: {done} (the others "
              "were not written)", file=sys.stderr)
        raise SystemExit(130) from None


_RUN_KEYS = ("command", "init_sha256", "teacher_sha256")
"""A run's meta that its resume state keeps, and a resumed run's checkpoint carries on (``resumed.run``)."""


def resume_path(out: Path) -> Path:
    """Where a run stopped with Ctrl-C writes its whole state for ``--resume``: beside ``out``, ``NAME.resume.pt``."""
    return out.with_name(f"{out.stem}.resume{out.suffix or '.pt'}")


def run_resume(args: argparse.Namespace) -> int:
    """``--resume RUN.resume.pt``: the stopped run goes on with its own config, weights and draws (refusing the
    options that would change them), written to its own ``--out`` unless another is given."""
    given = sorted("--" + k.split("__", 2)[2].replace("_", "-") for k, v in vars(args).items()
                   if k.startswith("cfg__") and v is not None)
    if args.config is not None:
        given.insert(0, "--config")
    if given:
        raise PoseLifterError(f"--resume goes on with the stopped run's own config: drop {', '.join(given)} (or start "
                              "a new run from its weights: --init NAME.interrupted.pt with the options)")
    if int(os.environ.get("WORLD_SIZE", "1")) > 1:
        raise PoseLifterError("--resume goes on with one process's run: start it without torchrun")
    state = ResumeState.load(args.resume)
    cfg = TrainConfig.from_dict(state.train_config)
    if args.print_config:
        print(cfg.to_json())
        return 0
    stored_out = state.meta.get("out")
    if args.out is None:
        if not isinstance(stored_out, str):
            raise PoseLifterError(f"--resume {args.resume} names no --out: give --out")
        args.out = Path(stored_out)
    _check_out(Path(args.out), cfg, None)
    if Path(args.out).resolve() == Path(args.resume).resolve():
        raise PoseLifterError(f"--out {args.out} is the --resume file: give another --out")
    check_writable(args.out, option="--out")
    if args.threads is not None and args.threads < 1:
        raise PoseLifterError(f"--threads must be >= 1, got {args.threads}")
    if not args.fp32_weights and state.meta.get("fp32_weights") is True:
        args.fp32_weights = True
    ctx = init_distributed()
    check_resume(state, cfg, ctx=ctx)  # (before the data is read)
    threads = state.meta.get("threads")
    if args.threads is None and isinstance(threads, int) and threads >= 1:
        args.threads = threads  # (another count sums in another order: other weights)
        print(f"note: {threads} torch thread(s), as the run had (--threads to change it)", file=sys.stderr)
    elif isinstance(threads, int) and args.threads != threads:
        print(f"note: the run trained with {threads} torch thread(s), this goes on with {args.threads}: the weights "
              "will differ slightly from those of the run never stopped", file=sys.stderr)
    stored_h36m = state.meta.get("h36m")
    if args.h36m is None and isinstance(stored_h36m, str) and Path(stored_h36m).is_dir():
        args.h36m = Path(stored_h36m)
    if args.threads:
        torch.set_num_threads(args.threads)
    meta: dict[str, Any] = {"command": "poselifter " + " ".join(sys.argv[1:]), "world_size": 1,
                            "resumed": {"from": str(Path(args.resume).resolve()), "sha256": sha256_file(args.resume),
                                        "step": state.step,
                                        "run": {k: v for k, v in state.meta.items() if k in _RUN_KEYS}}}
    meta.update({k: v for k, v in state.meta.items() if k in _RUN_KEYS and k != "command"})
    teacher = None
    if cfg.teacher is not None:
        teacher = load_option("--teacher", cfg.teacher, args)
        sha, stored = weights_sha256(cfg.teacher, every_network=True), state.meta.get("teacher_sha256")
        if isinstance(stored, str) and sha != stored:
            raise PoseLifterError(f"--resume {args.resume}: the run's teacher {cfg.teacher} is not the network it "
                                  f"distilled (sha256 {sha[:12]}, the run's {stored[:12]}): put that teacher back")
    print(f"resuming {args.resume} at step {state.step} ({minutes_text(state.minutes)} trained), writing {args.out}",
          file=sys.stderr)
    return _train_and_write(args, cfg, ctx=ctx, init=None, teacher=teacher, meta=meta, resume=state)


def interrupted_path(out: Path) -> Path:
    """Where a run stopped with Ctrl-C writes its weights so far: beside ``out``, ``NAME.interrupted.pt``."""
    return out.with_name(f"{out.stem}.interrupted{out.suffix or '.pt'}")


def fine_tune_config(cfg: TrainConfig, init: Lifter, args: argparse.Namespace) -> tuple[TrainConfig, list[str]]:
    """``cfg`` as a fine-tune from ``init`` (``--init``) runs it, and notes saying what changed: the network's own
    model config (a fine-tune keeps it; a model option given on the command line that asks for another is refused,
    naming it), and the 2D it learned (``data.lens``) unless ``--lens`` or a ``--config`` run says which (a researcher
    trial: fine-tuning the pinhole default without ``--lens`` trained it on distorted 2D without a word, where
    ``--teacher`` refuses the same mismatch)."""
    notes: list[str] = []
    given = {k.split("__", 2)[2]: v for k, v in vars(args).items() if k.startswith("cfg__model__") and v is not None}
    clash = [f"--{k.replace('_', '-')} {v!r} (the network's: {getattr(init.config, k)!r})" for k, v in given.items()
             if getattr(init.config, k) != v]
    if clash:
        which = "that option" if len(clash) == 1 else "those options"
        raise PoseLifterError(f"--init {cfg.init}: a fine-tune keeps the network's model config, and "
                              f"{', '.join(clash)} asks for another; drop {which}, or train a new network without "
                              "--init")
    if init.config != cfg.model:
        notes.append(f"--init {cfg.init}: keeping its model config {init.config}")
    lens = cfg.data.lens
    if init.lens != lens:
        if getattr(args, "cfg__data__lens", None) is None and args.config is None:
            lens = init.lens
            notes.append(f"--init {cfg.init} learned {init.lens!r} 2D: training on it too (--lens {init.lens}; give "
                         "--lens to train it on the other)")
        else:
            notes.append(f"--init {cfg.init} learned {init.lens!r} 2D, and this run trains it on {lens!r} (--lens"
                         f"{'' if getattr(args, 'cfg__data__lens', None) is not None else ', from --config'})")
    return replace(cfg, model=init.config, data=replace(cfg.data, lens=lens)), notes


def load_option(option: str, ref: str, args: argparse.Namespace) -> Lifter:
    """The model ``--init`` / ``--teacher`` names, its load errors naming the option (and the ``--config`` run it came
    from, when not given on the command line)."""
    try:
        return Lifter.load(ref)
    except (PoseLifterError, OSError) as exc:
        given = getattr(args, f"cfg____{option.lstrip('-')}", None) is not None
        where = "" if given or args.config is None else f" (from the --config run {args.config}; relative paths are " \
            "read from the current folder: give the option again to replace it)"
        raise PoseLifterError(f"{option} {ref}{where}: {exc}") from None


def weights_sha256(ref: str, *, every_network: bool = False) -> str:
    """The sha256 of the weights ``ref`` names: a checkpoint file's own; for a shipped model, its registry entry's
    sha256 of the network ``--init`` starts from (its first detected network), or with ``every_network`` (what
    ``--teacher`` runs) the sha256 of the entry's sha256 of every network file (detected, ensemble members,
    clean-2D)."""
    if ref != "default" and ref not in resources.model_names():
        return sha256_file(ref)
    entry = resources.model_entry(ref)
    if not every_network:
        return str(entry.get("sha256", ""))
    sums = [entry.get("sha256", ""), *entry.get("ensemble_sha256", []), entry.get("clean_sha256", "")]
    return hashlib.sha256(" ".join(str(x) for x in sums).encode()).hexdigest()


def _check_out(out: Path, cfg: TrainConfig, config: str | None) -> None:
    """Refuse an ``--out`` that is not a ``.pt`` file (a run's learning curve is written beside it as
    ``<name>.curve.json``: a researcher trial's ``--out x.curve.json`` wrote a checkpoint over run x's curve) or that
    is a file this run reads: its ``--config``, ``--init``, ``--teacher`` or ``--error-model`` (which a finished run
    replaced)."""
    if out.suffix.lower() != ".pt":
        raise PoseLifterError(f"--out {out}: a checkpoint's name ends in .pt (the learning curve is written beside it "
                              "as NAME.curve.json): e.g. --out runs/my.pt")
    for option, ref in (("--config", config), ("--init", cfg.init), ("--teacher", cfg.teacher),
                        ("--error-model", cfg.data.error_model)):
        if ref is not None and Path(ref).is_file() and Path(ref).resolve() == out.resolve():
            raise PoseLifterError(f"--out {out} is this run's {option}: the finished run would replace it; give "
                                  "another --out")


def _stored_fit_hint(args: argparse.Namespace) -> str:
    """For a fit that cannot be read: where ``--config RUN.pt`` names it (not ``--error-model``) and the run stores
    the fit it trained with, how to take that (a researcher trial: a run's relative path to its fit, stored as typed,
    failed from another folder)."""
    config = getattr(args, "config", None)
    if config is None or Path(config).suffix != ".pt" or getattr(args, "cfg__data__error_model", None) is not None:
        return ""
    try:
        stored = load_checkpoint(config).meta.get("error_model")  # (the run ends with this message: no seed to keep)
    except PoseLifterError:
        return ""
    return (f"; {config} stores the fit it trained with: add --error-model {config}" if isinstance(stored, dict)
            else "")


def repeat_notes(config: Path | None, *, init: tuple[str, str] | None = None,
                 teacher: tuple[str, str] | None = None, error_model: tuple[str, str] | None = None) -> list[str]:
    """Why ``--config RUN.pt`` with this ``init`` / ``teacher`` / ``error_model`` (``(ref, sha256)``) would not repeat
    that run: the init weights are that run's own result, or not the weights it started from
    (``meta["init_sha256"]``); the teacher is not the one it distilled (``meta["teacher_sha256"]``); the error-model
    fit is not the one its noise was drawn from (``meta["error_model_sha256"]``). The checkpoint is read once."""
    if config is None or config.suffix != ".pt" or (init is None and teacher is None and error_model is None):
        return []
    notes: list[str] = []
    meta = load_checkpoint(config).meta
    if init is not None:
        ref, sha = init
        stored = meta.get("init_sha256")
        if sha256_file(config) == sha:
            notes.append(f"--init {ref} is the --config checkpoint itself: this fine-tunes that run's result again, "
                         "it does not repeat the run (give --init the weights it started from)")
        elif isinstance(stored, str) and stored != sha:
            notes.append(f"--init {ref} (sha256 {sha[:12]}) is not what {config} started from ({stored[:12]}): this "
                         "does not repeat that run")
    if teacher is not None:
        ref, sha = teacher
        stored = meta.get("teacher_sha256")
        if isinstance(stored, str) and stored != sha:
            notes.append(f"--teacher {ref} (sha256 {sha[:12]}) is not what {config} distilled ({stored[:12]}): this "
                         "does not repeat that run")
    if error_model is not None:
        ref, sha = error_model
        stored = meta.get("error_model_sha256")
        if isinstance(stored, str) and stored != sha:
            notes.append(f"the error model {ref} (sha256 {sha[:12]}) is not the fit {config} drew its noise from "
                         f"({stored[:12]}): this does not repeat that run (--error-model {config} takes the fit it "
                         "stored)")
    return notes
