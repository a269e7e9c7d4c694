"""Training loop for PoseLifter on Human3.6M (CPU-friendly).

Recipe (defaults of :class:`TrainConfig`; see the README for the measured learning curve):

* data: Protocol-1 training subjects, every ``train_stride``-th 50-fps frame, 4 cameras, GT 2D
  (distorted projection); random horizontal flip p = 0.5 done correctly (x -> W - x, cx -> W - cx,
  L/R swap, X negated), vectorized per batch;
* model: :class:`~lifter.model.PoseLifterNet` with standardized outputs (mean/std of the targets,
  flipped copies included) and the head's initial output at the target mean;
* loss: :func:`~lifter.loss.poselifter_loss` in mm (48 pose terms + 1 x canonical depth);
* optional: zoom augmentation (``zoom_aug``) and 2D noise (``augment_2d``, e.g. the fitted error model
  of :mod:`lifter.noise`), applied after the flip in that order, so noise follows the zoomed size;
* optimizer: AdamW, ``lr`` with linear warm-up then cosine decay to ``lr * final_lr_fraction``.
  Schedule progress is ``max(step / steps, elapsed / max_minutes)``, so a wall-clock limit ends
  training with a fully decayed learning rate instead of cutting it off mid-schedule.
"""

from __future__ import annotations

import copy
import json
import math
import time
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch
from tqdm.auto import tqdm

from ._checks import PoseLifterError
from .camera import backproject, root_from_canonical_depth
from .checkpoint import save_checkpoint
from .data import H36M, PoseSamples
from .loss import poselifter_loss
from .model import ModelConfig, PoseLifterNet, pack_targets
from .skeleton import FLIP_PERMUTATION

Augment2D = Callable[[torch.Tensor, torch.Tensor, torch.Generator], torch.Tensor]
"""``f(keypoints (B,17,2) px, principal_point (B,2) px, generator) -> noisy keypoints``."""


@dataclass(frozen=True)
class TrainConfig:
    model: ModelConfig = field(default_factory=ModelConfig)
    protocol: int = 1
    train_stride: int = 5
    batch_size: int = 512
    epochs: float = 30.0
    lr: float = 1e-3
    weight_decay: float = 1e-4
    warmup_fraction: float = 0.02
    final_lr_fraction: float = 0.01
    depth_weight: float = 1.0
    flip_prob: float = 0.5
    max_minutes: float | None = None
    seed: int = 0
    threads: int | None = None
    val_stride: int = 100
    eval_every: int = 500
    max_frames_per_sequence: int | None = None
    zoom_aug: bool = False
    """Zoom augmentation (spec §6): scale 2D pose, principal point and focal by
    ``s = 2 ** clip(zoom_sigma * N(0, 1), -zoom_clip, zoom_clip)``; the canonical target becomes ``Z*F0/(s*alpha)``."""
    zoom_sigma: float = 0.25
    zoom_clip: float = 0.5
    real_2d_prob: float = 0.5
    """With ``train(real_keypoints_2d=...)``: probability that a sample is fed its real detection (where it
    has one) instead of its GT 2D (+ ``augment_2d`` noise). Ignored without real keypoints."""
    ema_decay: float | None = None
    """Exponential moving average of the weights (and BatchNorm statistics), e.g. 0.999; validation and the
    returned network use the average. ``None``: plain weights."""

    def __post_init__(self) -> None:
        if not 0.0 <= self.real_2d_prob <= 1.0:
            raise PoseLifterError(f"real_2d_prob (--real-prob) must be in [0, 1], got {self.real_2d_prob}")
        if self.ema_decay is not None and not 0.0 <= self.ema_decay < 1.0:
            raise PoseLifterError(f"ema_decay (--ema) must be in [0, 1), got {self.ema_decay}")

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["model"] = self.model.to_dict()
        return d


@dataclass(frozen=True)
class TrainResult:
    net: PoseLifterNet
    curve: list[dict[str, float]]
    steps: int
    samples_seen: int
    minutes: float


def flip_batch(
    kp: torch.Tensor, pp: torch.Tensor, width: torch.Tensor, rel: torch.Tensor, mask: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Flip the samples where ``mask`` is true. kp ``(B,17,2)`` px, pp ``(B,2)``, width ``(B,)``,
    rel ``(B,17,3)`` mm root-relative. The canonical depth is unchanged by a flip."""
    perm = torch.as_tensor(FLIP_PERMUTATION)
    kp_f = kp[:, perm].clone()
    kp_f[..., 0] = width[:, None] - kp_f[..., 0]
    pp_f = pp.clone()
    pp_f[:, 0] = width - pp_f[:, 0]
    rel_f = rel[:, perm].clone()
    rel_f[..., 0] = -rel_f[..., 0]
    m = mask[:, None, None]
    return torch.where(m, kp_f, kp), torch.where(mask[:, None], pp_f, pp), torch.where(m, rel_f, rel)


def zoom_batch(kp: torch.Tensor, pp: torch.Tensor, depth: torch.Tensor, s: torch.Tensor, *,
               canonical: bool) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Zoom by ``s`` ``(B,)``: the same 3D seen by a camera with focal and principal point (and image) x s.
    2D keypoints and principal point scale by ``s``; the canonical depth ``Z F0 / (s alpha)`` scales by
    ``1/s``; an absolute depth target is unchanged (which is why it cannot be learned from zoomed data)."""
    return kp * s[:, None, None], pp * s[:, None], (depth / s if canonical else depth)


def make_batch(T: dict[str, torch.Tensor], idx: torch.Tensor, cfg: TrainConfig, gen: torch.Generator, *,
               augment_2d: Augment2D | None = None) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
    """One training batch ``(kp (B,17,2) px, pp (B,2) px, rel (B,17,3) mm, depth (B,))`` from the tensors ``T``.

    Order: 2D source (the real detection ``T["real"]`` with probability ``cfg.real_2d_prob`` where
    ``T["has_real"]``, else the GT 2D) -> flip -> zoom -> ``augment_2d`` noise on the GT-sourced rows only
    (a real detection already carries real errors)."""
    kp, pp, w, rel, depth = T["kp"][idx], T["pp"][idx], T["w"][idx], T["rel"][idx], T["depth"][idx]
    bs = len(idx)
    use_real = None
    if "has_real" in T:
        use_real = T["has_real"][idx] & (torch.rand(bs, generator=gen) < cfg.real_2d_prob)
        kp = torch.where(use_real[:, None, None], T["real"][idx], kp)
    if cfg.flip_prob > 0:
        mask = torch.rand(bs, generator=gen) < cfg.flip_prob
        kp, pp, rel = flip_batch(kp, pp, w, rel, mask)
    if cfg.zoom_aug:
        s = torch.exp2((cfg.zoom_sigma * torch.randn(bs, generator=gen)).clamp(-cfg.zoom_clip, cfg.zoom_clip))
        kp, pp, depth = zoom_batch(kp, pp, depth, s, canonical=cfg.model.depth_target == "canonical")
    if augment_2d is not None:
        noisy = augment_2d(kp, pp, gen)
        kp = noisy if use_real is None else torch.where(use_real[:, None, None], kp, noisy)
    return kp, pp, rel, depth


class WeightAverage:
    """Exponential moving average of a network's state: ``avg <- decay * avg + (1 - decay) * current`` for
    every floating-point parameter and buffer (BatchNorm statistics included); integer buffers are copied.
    ``module`` is the averaged copy (starts equal to the network)."""

    def __init__(self, net: torch.nn.Module, *, decay: float) -> None:
        if not 0.0 <= decay < 1.0:
            raise ValueError(f"EMA decay must be in [0, 1); got {decay}")
        self.decay = float(decay)
        self.module = copy.deepcopy(net)

    @torch.no_grad()
    def update(self, net: torch.nn.Module) -> None:
        for avg, cur in zip(self.module.state_dict().values(), net.state_dict().values()):
            if avg.is_floating_point():
                avg.lerp_(cur, 1.0 - self.decay)
            else:
                avg.copy_(cur)


def target_statistics(rel: torch.Tensor, depth: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Mean and std ``(49,)`` of the packed targets over the samples and their mirror images."""
    perm = torch.as_tensor(FLIP_PERMUTATION)
    rel_f = rel[:, perm].clone()
    rel_f[..., 0] = -rel_f[..., 0]
    y = torch.cat([pack_targets(rel, depth), pack_targets(rel_f, depth)])
    return y.mean(0), y.std(0)


def _lr_factor(progress: float, cfg: TrainConfig) -> float:
    if progress < cfg.warmup_fraction:
        return max(progress / cfg.warmup_fraction, 1e-3)
    t = (progress - cfg.warmup_fraction) / max(1e-9, 1.0 - cfg.warmup_fraction)
    t = min(max(t, 0.0), 1.0)
    lo = cfg.final_lr_fraction
    return lo + (1 - lo) * 0.5 * (1 + math.cos(math.pi * t))


def _as_tensors(samples: PoseSamples, depth_target: str) -> dict[str, torch.Tensor]:
    depth = samples.canonical_depth if depth_target == "canonical" else samples.pose_3d[:, 0, 2]
    return {
        "kp": torch.from_numpy(np.ascontiguousarray(samples.keypoints_2d, np.float32)),
        "pp": torch.from_numpy(np.ascontiguousarray(samples.principal_point, np.float32)),
        "w": torch.from_numpy(samples.image_size[:, 0].astype(np.float32)),
        "rel": torch.from_numpy(np.ascontiguousarray(samples.relative, np.float32)),
        "depth": torch.from_numpy(np.asarray(depth, np.float32)),
    }


@torch.inference_mode()
def _validate(net: PoseLifterNet, val: dict[str, torch.Tensor], val_root: np.ndarray, focal: np.ndarray) -> dict[str, float]:
    was_training = net.training
    net.eval()
    out = net(val["kp"], val["pp"])
    net.train(was_training)
    mpjpe = (out.relative - val["rel"]).norm(dim=-1).mean().item()
    root_2d, pp, depth = val["kp"][:, 0].numpy(), val["pp"].numpy(), out.depth.numpy().astype(np.float64)
    if net.config.depth_target == "canonical":
        root = root_from_canonical_depth(root_2d, depth, focal=focal, principal_point=pp)
    else:
        root = backproject(root_2d, depth, focal=focal, principal_point=pp)
    mrpe = float(np.linalg.norm(root - val_root, axis=-1).mean())
    return {"val_mpjpe": mpjpe, "val_mrpe": mrpe}


def train(
    cfg: TrainConfig,
    *,
    data: H36M | None = None,
    train_samples: PoseSamples | None = None,
    val_samples: PoseSamples | None = None,
    augment_2d: Augment2D | None = None,
    real_keypoints_2d: np.ndarray | None = None,
    init: PoseLifterNet | None = None,
    progress: bool = True,
    log: Callable[[str], None] = print,
) -> TrainResult:
    """Train a PoseLifter network. Pass ``train_samples`` to train on custom data (e.g. detections);
    otherwise the protocol's training subjects are loaded from ``data`` (default folder).

    ``real_keypoints_2d`` ``(N, 17, 2)`` px, aligned with the training samples (NaN rows: no detection), mixes
    real detections into training: each sample gets its detection with probability ``cfg.real_2d_prob``, else
    its GT 2D with ``augment_2d`` noise. Flip and zoom apply to both. ``init`` fine-tunes a copy of that network
    (its architecture and output statistics are kept; ``cfg.model`` is ignored)."""
    if cfg.threads:
        torch.set_num_threads(cfg.threads)
    torch.manual_seed(cfg.seed)
    gen = torch.Generator().manual_seed(cfg.seed)
    if train_samples is None or val_samples is None:
        data = data or H36M()
    if train_samples is None:
        train_samples = data.load_protocol(cfg.protocol, "train", stride=cfg.train_stride,
                                           max_frames_per_sequence=cfg.max_frames_per_sequence)
    if val_samples is None:
        val_samples = data.load_protocol(cfg.protocol, "test", stride=cfg.val_stride,
                                         max_frames_per_sequence=cfg.max_frames_per_sequence)
    if init is not None:
        cfg = replace(cfg, model=init.config)  # before the targets: the depth target is the initial network's
    T = _as_tensors(train_samples, cfg.model.depth_target)
    V = _as_tensors(val_samples, cfg.model.depth_target)
    val_root, val_focal = val_samples.root, val_samples.focal

    if real_keypoints_2d is not None:
        real = np.asarray(real_keypoints_2d, np.float32)
        if real.shape != train_samples.keypoints_2d.shape:
            raise ValueError(f"real_keypoints_2d has shape {real.shape}; expected {train_samples.keypoints_2d.shape} "
                             "(one row per training sample)")
        ok = np.isfinite(real).all(axis=(1, 2))
        T["real"] = torch.from_numpy(np.where(ok[:, None, None], real, 0.0).astype(np.float32))
        T["has_real"] = torch.from_numpy(ok)
        log(f"mixing real detections: {int(ok.sum())} of {len(ok)} samples have one, used with p = {cfg.real_2d_prob:g}")

    if init is not None:
        net = copy.deepcopy(init)
    else:
        net = PoseLifterNet(cfg.model)
        mean, std = target_statistics(T["rel"], T["depth"])
        net.set_target_statistics(mean, std)
    net.train()
    opt = torch.optim.AdamW(net.parameters(), lr=cfg.lr, weight_decay=cfg.weight_decay)
    ema = WeightAverage(net, decay=cfg.ema_decay) if cfg.ema_decay is not None else None
    eval_net = ema.module if ema is not None else net  # what validation and the result use

    n = len(train_samples)
    bs = min(cfg.batch_size, n)
    steps = max(1, int(round(cfg.epochs * n / bs)))
    log(f"training on {n} samples, batch {bs}, {steps} steps ({cfg.epochs:g} epochs), "
        f"max {cfg.max_minutes or 'inf'} min, model {cfg.model}")
    curve: list[dict[str, float]] = []
    perm = torch.randperm(n, generator=gen)
    pos = 0
    t0 = time.perf_counter()
    running = None
    bar = tqdm(total=steps, disable=not progress, unit="step", dynamic_ncols=True, mininterval=2.0)
    step = 0
    while True:
        elapsed = (time.perf_counter() - t0) / 60.0
        prog = step / steps
        if cfg.max_minutes is not None:
            prog = max(prog, elapsed / cfg.max_minutes)
        if prog >= 1.0:
            break
        for g in opt.param_groups:
            g["lr"] = cfg.lr * _lr_factor(prog, cfg)
        if pos + bs > n:
            perm = torch.randperm(n, generator=gen)
            pos = 0
        idx = perm[pos : pos + bs]
        pos += bs
        kp, pp, rel, depth = make_batch(T, idx, cfg, gen, augment_2d=augment_2d)
        pred = net.forward_flat(kp, pp)
        loss = poselifter_loss(pred, pack_targets(rel, depth), depth_weight=cfg.depth_weight)
        if not torch.isfinite(loss):
            raise FloatingPointError(f"loss became {loss.item()} at step {step}")
        opt.zero_grad(set_to_none=True)
        loss.backward()
        opt.step()
        if ema is not None:
            ema.update(net)
        step += 1
        running = loss.item() if running is None else 0.98 * running + 0.02 * loss.item()
        if step % cfg.eval_every == 0 or step == steps:
            rec = {"step": step, "samples": step * bs, "minutes": (time.perf_counter() - t0) / 60.0,
                   "lr": opt.param_groups[0]["lr"], "train_loss": running}
            rec.update(_validate(eval_net, V, val_root, val_focal))
            curve.append(rec)
            bar.set_postfix(loss=f"{running:.1f}", val_mpjpe=f"{rec['val_mpjpe']:.1f}", val_mrpe=f"{rec['val_mrpe']:.0f}")
        bar.update(1)
    bar.close()
    minutes = (time.perf_counter() - t0) / 60.0
    if not curve or curve[-1]["step"] != step:
        rec = {"step": step, "samples": step * bs, "minutes": minutes, "lr": opt.param_groups[0]["lr"],
               "train_loss": float(running or 0.0)}
        rec.update(_validate(eval_net, V, val_root, val_focal))
        curve.append(rec)
    net = eval_net
    net.eval()
    log(f"done: {step} steps, {step * bs} samples in {minutes:.1f} min ({step * bs / max(minutes * 60, 1e-9):.0f} samples/s)")
    return TrainResult(net=net, curve=curve, steps=step, samples_seen=step * bs, minutes=minutes)


def save_training_outputs(result: TrainResult, cfg: TrainConfig, out: str | Path, *, half: bool = True,
                          extra_meta: dict[str, Any] | None = None) -> Path:
    """Write ``out`` (checkpoint), ``out`` with ``.curve.json`` and a learning-curve PNG beside it."""
    out = Path(out)
    meta = {"train_config": cfg.to_dict(), "steps": result.steps, "samples_seen": result.samples_seen,
            "minutes": result.minutes, "final_val": result.curve[-1] if result.curve else {}}
    meta.update(extra_meta or {})
    save_checkpoint(out, result.net, meta=meta, half=half)
    curve_path = out.with_suffix(".curve.json")
    curve_path.write_text(json.dumps({"config": cfg.to_dict(), "curve": result.curve}, indent=1))
    try:
        from .plots import plot_learning_curve

        plot_learning_curve(result.curve, out.with_suffix(".curve.png"), title=out.stem)
    except ImportError:
        pass
    return out
