"""Training PoseLifter on Human3.6M, on one process or under ``torchrun`` (DistributedDataParallel).

Recipe: :class:`lifter.config.TrainConfig`. Per step:

* a batch of training samples (:func:`make_batch`): each gets its exact GT 2D (source "clean"), its real
  detection, or its GT 2D plus error-model noise at a random level (source "detected"); then the
  horizontal flip (about the principal point: :func:`lifter.skeleton.mirror` of 2D and 3D), optionally a move
  along the root's viewing ray (:func:`move_batch`) and a camera turn (:func:`rotate_batch`) and, for the pixel
  input space, zoom;
* the codec (:class:`lifter.codec.PoseCodec`) encodes inputs and targets; the network predicts
  standardized outputs; the loss (:func:`lifter.loss.poselifter_loss`) is in mm;
* AdamW with linear warm-up then cosine decay, driven by ``max(step / steps, elapsed / max_minutes)`` so a
  wall-clock limit still ends fully decayed; optional weight EMA and bf16 autocast of the residual blocks.

Device: the training tensors are moved once to the training device (the GPU under CUDA) and every batch is
drawn there, so no batch is built on the host and copied; the loss is read back only every
:data:`FINITE_CHECK_EVERY` steps (a non-finite loss on any process stops every process with a
:class:`FloatingPointError`).

Distributed: under ``torchrun`` (``WORLD_SIZE > 1``) every process loads the data, builds the same
network from the same seed and trains a shard of every global batch (``batch_size / world`` samples,
disjoint slices of one shared permutation) through :class:`torch.nn.parallel.DistributedDataParallel`
(gloo on CPU, NCCL on CUDA). Gradients are averaged, BatchNorm statistics are broadcast from rank 0 after
every step, and the wall-clock schedule uses the slowest rank's clock, so every rank holds the same
weights at every step. Rank 0 validates and writes the one checkpoint.
"""

from __future__ import annotations

import copy
import json
import math
import os
import signal
import threading
import time
from collections.abc import Callable
from contextlib import nullcontext
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import numpy as np
import torch
import torch.distributed as dist
from tqdm.auto import tqdm

from ._checks import PoseLifterError
from .camera import backproject_generic, camera_turn, project_generic, turn_pixels
from .checkpoint import save_checkpoint
from .codec import PoseCodec
from .config import TrainConfig
from .data import H36M, PoseSamples
from .detections import match_scale
from .loss import poselifter_loss
from .model import PoseLifterNet, forward_folded
from .noise import ErrorModel
from .normalization import pose_scale
from .resume import ResumeState, data_fingerprint
from .skeleton import mirror

if TYPE_CHECKING:
    from .api import Lifter

Batch = dict[str, torch.Tensor]
"""A training batch: ``kp`` (B,17,2) px, ``pp`` (B,2) px, ``focal`` (B,2) px, ``rel`` (B,17,3) mm root-relative,
``depth`` (B,) root Z mm, ``clean`` (B,) bool (the 2D is exact)."""


@dataclass(frozen=True)
class TrainResult:
    net: PoseLifterNet
    codec: PoseCodec
    config: TrainConfig
    curve: list[dict[str, float]]
    steps: int
    samples_seen: int
    minutes: float
    error_model: ErrorModel | None = None
    """The fit the synthetic 2D noise was drawn from, whole (``data.noise`` "gaussian" draws from its single-Gaussian
    baseline); the noise model the caller passed to :func:`train`, as given; None: no sample had synthetic noise."""
    interrupted: bool = False
    """The run was stopped with Ctrl-C (one process) before its schedule ended: the weights are those so far."""
    resume: ResumeState | None = None
    """An interrupted run's whole state at the step it stopped after, for :func:`train`'s ``resume`` (None: not
    interrupted, or stopped inside a step by a second Ctrl-C, where the weights may be half updated)."""


# ------------------------------------------------------------------------------------------------
# Distributed context
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Dist:
    """Where this process stands: ``rank`` of ``world`` processes on ``device``."""

    rank: int = 0
    world: int = 1
    device: torch.device = torch.device("cpu")

    @property
    def main(self) -> bool:
        return self.rank == 0

    @property
    def active(self) -> bool:
        return self.world > 1


def init_distributed() -> Dist:
    """Join the process group when started by ``torchrun`` (``WORLD_SIZE > 1``): NCCL with one GPU per
    process when CUDA is available, gloo on CPU otherwise. A single process returns the trivial context."""
    world = int(os.environ.get("WORLD_SIZE", "1"))
    if world <= 1:
        return Dist(device=torch.device("cuda" if torch.cuda.is_available() else "cpu"))
    use_cuda = torch.cuda.is_available()
    if not dist.is_initialized():
        dist.init_process_group(backend="nccl" if use_cuda else "gloo")
    rank = dist.get_rank()
    if use_cuda:
        local = int(os.environ.get("LOCAL_RANK", "0"))
        torch.cuda.set_device(local)
        device = torch.device("cuda", local)
    else:
        device = torch.device("cpu")
    return Dist(rank=rank, world=dist.get_world_size(), device=device)


# ------------------------------------------------------------------------------------------------
# Batches
# ------------------------------------------------------------------------------------------------


def samples_to_tensors(samples: PoseSamples, real_keypoints_2d: np.ndarray | None = None) -> Batch:
    """The tensors batches are drawn from (float32, CPU): GT 2D, intrinsics, relative pose, root depth and,
    when given, the real detections ``(N, 17, 2)`` px aligned with the samples (NaN rows: none)."""
    T = {
        "kp": torch.from_numpy(np.ascontiguousarray(samples.keypoints_2d, np.float32)),
        "pp": torch.from_numpy(np.ascontiguousarray(samples.principal_point, np.float32)),
        "focal": torch.from_numpy(np.ascontiguousarray(samples.focal, np.float32)),
        "rel": torch.from_numpy(np.ascontiguousarray(samples.relative, np.float32)),
        "depth": torch.from_numpy(np.ascontiguousarray(samples.pose_3d[:, 0, 2], np.float32)),
    }
    if real_keypoints_2d is not None:
        real = np.asarray(real_keypoints_2d, np.float32)
        if real.shape != samples.keypoints_2d.shape:
            raise PoseLifterError(f"real detections have shape {real.shape}; expected {samples.keypoints_2d.shape} "
                                  "(one row per training sample)")
        ok = np.asarray(np.isfinite(real).all(axis=(1, 2)))
        T["real"] = torch.from_numpy(np.where(ok[:, None, None], real, 0.0).astype(np.float32))
        T["has_real"] = torch.from_numpy(ok)
    return T


def flip_batch(kp: torch.Tensor, pp: torch.Tensor, rel: torch.Tensor, mask: torch.Tensor
               ) -> tuple[torch.Tensor, torch.Tensor]:
    """Mirror the samples where ``mask`` ``(B,)`` is true: the 2D about its principal point (the same network
    input as the image flip ``x -> W - x``, ``cx -> W - cx``) and the root-relative 3D; depth is unchanged."""
    m = mask[:, None, None]
    return torch.where(m, PoseCodec.mirror_input(kp, pp), kp), torch.where(m, mirror(rel), rel)


def rotate_batch(kp: torch.Tensor, pp: torch.Tensor, f: torch.Tensor, rel: torch.Tensor, depth: torch.Tensor,
                 root_2d: torch.Tensor, *, max_deg: float, gen: torch.Generator, max_roll_deg: float = 0.0,
                 prob: float = 1.0) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The samples as a camera turned about its centre by a random pan and tilt (each uniform in ``+-max_deg``),
    and with ``max_roll_deg`` a roll about its optical axis (uniform in ``+-max_roll_deg``; drawn after the pan and
    tilt, so runs without it draw as before), would see them: 2D ``kp`` ``(B, 17, 2)`` px (any 2D, detections
    included) moved by the homography ``K R K^-1`` (pinhole), the root-relative 3D ``rel`` ``(B, 17, 3)`` mm turned
    by ``R``, and the root depth ``depth`` ``(B,)`` mm that of the turned root, whose 3D is the true root's 2D
    ``root_2d`` ``(B, 2)`` px back-projected to ``depth``. ``pp``, ``f``: ``(B, 2)`` px. With ``prob`` below 1 only
    that share of the samples is turned (drawn after the angles, so runs with every sample turned draw as before);
    the rest stay as they are."""
    bs, dev = len(kp), kp.device

    def uniform(deg: float) -> torch.Tensor:  # (B,) radians, uniform in +-deg
        return torch.deg2rad(torch.tensor(deg, device=dev)) * (2 * torch.rand(bs, generator=gen, device=dev) - 1)

    pan, tilt = uniform(max_deg), uniform(max_deg)
    roll = uniform(max_roll_deg) if max_roll_deg > 0 else None
    if prob < 1.0:
        turned = (torch.rand(bs, generator=gen, device=dev) < prob).to(pan.dtype)
        pan, tilt = pan * turned, tilt * turned
        roll = None if roll is None else roll * turned
    r = camera_turn(pan, tilt, roll).to(kp.dtype)
    root = backproject_generic(root_2d, depth, f, pp)
    return turn_pixels(kp, r, f, pp), rel @ r.transpose(1, 2), (root[:, None] @ r.transpose(1, 2))[:, 0, 2]


MAX_OFF_AXIS_DEG = 80.0
"""A move (:func:`move_batch`) that would put a joint more than this many degrees off the optical axis, less the
largest camera turn to come, is not made: the turn could then put that joint at or behind the camera."""


def move_batch(kp: torch.Tensor, gt: torch.Tensor, pp: torch.Tensor, f: torch.Tensor, rel: torch.Tensor,
               depth: torch.Tensor, factor: torch.Tensor, *, max_off_axis_deg: float = MAX_OFF_AXIS_DEG
               ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """The samples moved along their root's viewing ray to ``factor`` ``(B,)`` times their root depth, as the same
    pinhole camera sees them: the 3D root (the true 2D root ``gt[:, 0]`` back-projected to ``depth`` ``(B,)`` mm)
    times ``factor``, the root-relative 3D ``rel`` ``(B, 17, 3)`` mm kept, the true 2D ``gt`` ``(B, 17, 2)`` px
    re-projected (its root's 2D does not move), and the 2D ``kp`` ``(B, 17, 2)`` px the network is shown (a detection,
    or ``gt`` itself) re-projected with its error from the truth scaled by the truth's change of 2D size (a detector's
    error follows the person's size in the image, as the error model's scale rule says). ``pp``, ``f``: ``(B, 2)`` px.
    A sample whose moved joints would lie more than ``max_off_axis_deg`` off the optical axis (a person moved very
    near) stays where it is (factor 1). Returns the moved ``kp``, ``gt`` and root depth ``(B,)`` mm."""
    root = backproject_generic(gt[:, 0], depth, f, pp)

    def place(s: torch.Tensor) -> torch.Tensor:  # (B, 17, 3) mm: the joints with the root moved to s times its depth
        return root[:, None] * s[:, None, None] + rel

    points = place(factor)
    cos_off_axis = (points[..., 2] / points.norm(dim=-1)).amin(dim=-1)
    factor = torch.where(cos_off_axis > math.cos(math.radians(max_off_axis_deg)), factor, torch.ones_like(factor))
    points = place(factor)
    moved = project_generic(points, f, pp)
    ratio = pose_scale(moved) / pose_scale(gt)
    return moved + (kp - gt) * ratio[:, None, None], moved, depth * factor


def make_batch(T: Batch, idx: torch.Tensor, cfg: TrainConfig, gen: torch.Generator, *,
               noise: ErrorModel | None = None) -> Batch:
    """One training batch (:data:`Batch`) of the samples ``idx`` (module docstring for the order).

    Sources: clean with ``cfg.data.clean_prob``; else the real detection with ``real_prob`` where there is
    one; else GT 2D with ``noise`` at a level uniform in ``[noise_level_min, noise_level_max]`` (GT 2D
    without noise when ``noise`` is None). The move along the viewing ray (``augment.distance_prob``) follows the
    flip, the camera turn and roll (``augment.rotate_deg``, ``roll_deg``) follow the move; noise is drawn after flip,
    move, turn and zoom, so it follows the shown size."""
    d = cfg.data
    kp, pp, f = T["kp"][idx], T["pp"][idx], T["focal"][idx]
    rel, depth = T["rel"][idx], T["depth"][idx]
    gt = kp  # the true 2D, before a real detection replaces it
    bs, dev = len(idx), kp.device
    u = torch.rand(bs, generator=gen, device=dev)
    clean = u < d.clean_prob
    real = (u >= d.clean_prob) & (u < d.clean_prob + d.real_prob)
    if "has_real" in T:
        real &= T["has_real"][idx]
        kp = torch.where(real[:, None, None], T["real"][idx], kp)
    else:
        real = torch.zeros_like(real)
    if cfg.augment.flip_prob > 0:
        flipped = torch.rand(bs, generator=gen, device=dev) < cfg.augment.flip_prob
        kp, rel = flip_batch(kp, pp, rel, flipped)
        if cfg.augment.turns_camera or cfg.augment.moves_people:  # (the true 2D, mirrored with the rest)
            gt = torch.where(flipped[:, None, None], PoseCodec.mirror_input(gt, pp), gt)
    if cfg.augment.moves_people:  # (pinhole: the config refuses distance_prob with distorted 2D)
        a = cfg.augment
        lo, hi = math.log(a.distance_min), math.log(a.distance_max)
        factor = torch.exp(lo + (hi - lo) * torch.rand(bs, generator=gen, device=dev))
        moved = torch.rand(bs, generator=gen, device=dev) < a.distance_prob
        turn = math.hypot(a.rotate_deg, a.rotate_deg)  # the most a pan and a tilt turn a ray (a roll keeps it)
        kp, gt, depth = move_batch(kp, gt, pp, f, rel, depth, torch.where(moved, factor, torch.ones_like(factor)),
                                   max_off_axis_deg=MAX_OFF_AXIS_DEG - turn)
    if cfg.augment.turns_camera:
        root_2d = gt[:, 0]  # (pinhole: the config refuses rotate_deg and roll_deg with distorted 2D)
        kp, rel, depth = rotate_batch(kp, pp, f, rel, depth, root_2d, max_deg=cfg.augment.rotate_deg, gen=gen,
                                      max_roll_deg=cfg.augment.roll_deg, prob=cfg.augment.turn_prob)
    if cfg.augment.zoom:
        a = cfg.augment
        s = torch.exp2((a.zoom_sigma * torch.randn(bs, generator=gen, device=dev)).clamp(-a.zoom_clip, a.zoom_clip))
        kp, pp, f = kp * s[:, None, None], pp * s[:, None], f * s[:, None]
    synth = ~clean & ~real
    if noise is not None:  # drawn for every batch: asking whether any sample needs it would wait for the device
        level = d.noise_level_min + (d.noise_level_max - d.noise_level_min) * torch.rand(bs, generator=gen, device=dev)
        noisy = noise.sample_torch(kp, level=level, generator=gen, outliers=d.noise_outliers)
        kp = torch.where(synth[:, None, None], noisy, kp)
    return {"kp": kp, "pp": pp, "focal": f, "rel": rel, "depth": depth, "clean": clean}


def target_statistics(codec: PoseCodec, T: Batch) -> tuple[np.ndarray, np.ndarray]:
    """Mean and std ``(49,)`` of the raw targets (mm) of the clean training samples and their mirror images."""
    kp, pp, f = T["kp"].double(), T["pp"].double(), T["focal"].double()
    y = codec.encode_targets(T["rel"].double(), T["depth"].double(),
                             codec.encode(kp, principal_point=pp, focal=f, source="clean"))
    y_m = codec.encode_targets(mirror(T["rel"].double()), T["depth"].double(),  # (the mirror image's own view)
                               codec.encode(PoseCodec.mirror_input(kp, pp), principal_point=pp, focal=f,
                                            source="clean"))
    y = torch.cat([y, y_m])
    return y.mean(0).numpy(), y.std(0).numpy()


def load_fit(cfg: TrainConfig) -> ErrorModel | None:
    """The error-model fit ``cfg.data.error_model`` names when some samples get synthetic noise, else None: what a
    checkpoint stores (``meta["error_model"]``), whichever of its parts ``data.noise`` draws from."""
    return ErrorModel.resolve(cfg.data.error_model) if cfg.data.noise_prob > 0 else None


def load_noise(cfg: TrainConfig, fit: ErrorModel | None = None) -> ErrorModel | None:
    """The error model noise is drawn from for ``cfg.data`` (the fit, or its single-Gaussian baseline for
    ``noise="gaussian"``) when some samples get synthetic noise, else None. ``fit``: :func:`load_fit`'s, if read."""
    fit = fit if fit is not None else load_fit(cfg)
    if fit is None:
        return None
    return fit.baseline() if cfg.data.noise == "gaussian" else fit


# ------------------------------------------------------------------------------------------------
# Pieces of the loop
# ------------------------------------------------------------------------------------------------


class WeightAverage:
    """Exponential moving average of a network's state: ``avg <- d * avg + (1 - d) * current`` for every
    floating-point parameter and buffer (BatchNorm statistics included); integer buffers are copied. ``module`` is
    the averaged copy (starts equal to the network).

    The decay warms up: at the n-th update (from 0) ``d = min(decay, (1 + n) / (10 + n))`` (TensorFlow's
    ``ExponentialMovingAverage`` with ``num_updates``), so the starting weights do not linger in a run shorter than
    about ``1 / (1 - decay)`` steps (a researcher trial: 684 steps at decay 0.999 without it kept half the random
    initial weights, 242.5 mm MPJPE against 62.4 for the live network); ``d`` reaches 0.999 after about 9,000
    updates. ``warmup=False`` (``--no-ema-warmup``; a config stored before the option) averages as before it."""

    def __init__(self, net: torch.nn.Module, *, decay: float, warmup: bool = True) -> None:
        if not 0.0 <= decay < 1.0:
            raise ValueError(f"EMA decay must be in [0, 1); got {decay}")
        self.decay = float(decay)
        self.warmup = bool(warmup)
        self.module = copy.deepcopy(net)
        self.updates = 0

    def current_decay(self) -> float:
        """The decay the next :meth:`update` uses (the warm-up's, until it reaches :attr:`decay`; without
        ``warmup``, as the runs from before it: :attr:`decay` from the first update)."""
        if not self.warmup:
            return self.decay
        return min(self.decay, (1.0 + self.updates) / (10.0 + self.updates))

    @torch.no_grad()
    def update(self, net: torch.nn.Module) -> None:
        d = self.current_decay()
        for avg, cur in zip(self.module.state_dict().values(), net.state_dict().values()):
            if avg.is_floating_point():
                avg.lerp_(cur, 1.0 - d)
            else:
                avg.copy_(cur)
        self.updates += 1


class _StopAsked:
    """Ctrl-C during a one-process run's loop: the first one is noted (:attr:`flag`) and the loop stops at the next
    step's start, so the weights kept are those of whole steps (a review: stopped inside the optimizer's update, some
    tensors had moved and others not); a second one stops at once. Only in the main thread (where Python delivers
    signals) and not under torchrun (``enabled``); :meth:`restore` puts the previous handler back."""

    def __init__(self, *, enabled: bool) -> None:
        self.flag = False
        self._previous: Any = None
        if enabled and threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._on_sigint)

    def _on_sigint(self, signum: int, frame: Any) -> None:
        if self.flag:
            raise KeyboardInterrupt
        self.flag = True

    def restore(self) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
            self._previous = None


def lr_factor(progress: float, cfg: TrainConfig) -> float:
    """Learning-rate multiplier at ``progress`` in [0, 1]: linear warm-up, then cosine to ``final_lr_fraction``."""
    s = cfg.schedule
    if progress < s.warmup_fraction:
        return max(progress / s.warmup_fraction, 1e-3)
    t = (progress - s.warmup_fraction) / max(1e-9, 1.0 - s.warmup_fraction)
    t = min(max(t, 0.0), 1.0)
    lo = s.final_lr_fraction
    return lo + (1 - lo) * 0.5 * (1 + math.cos(math.pi * t))


def teacher_networks(teacher: Lifter, *, clean_samples: bool = True) -> list[Lifter]:
    """The networks of ``teacher`` that :func:`teacher_targets` runs: its detected networks, and its clean-2D network
    when it has one and some samples are clean (``clean_samples``)."""
    extra = [teacher.clean] if teacher.clean is not None and clean_samples else []
    return [teacher, *teacher.ensemble, *extra]


def check_teacher(teacher: Lifter, codec: PoseCodec, *, lens: str) -> None:
    """Refuse a teacher whose networks read other features, predict another depth parameter than ``codec``, or
    learned other 2D than the ``lens`` trained on (``data.lens``): their raw outputs would not be targets of the
    student's (:func:`teacher_targets`)."""
    fields = ("input_space", "view", "mode", "scale_definition", "conditioning", "depth_target")
    flags = {"input_space": "--input-space", "view": "--view", "mode": "--mode",
             "scale_definition": "--scale-definition", "conditioning": "--conditioning",
             "depth_target": "--depth-target"}
    for m in teacher_networks(teacher):
        differ = [f"{k} {getattr(m.config, k)!r} (trained: {getattr(codec.config, k)!r}; {flags[k]})" for k in fields
                  if getattr(m.config, k) != getattr(codec.config, k)]
        if m.lens != lens:
            differ.append(f"lens {m.lens!r} (trained: {lens!r}; --lens)")
        if m.codec.reference_focal != codec.reference_focal:
            differ.append(f"reference focal {m.codec.reference_focal:g} px (trained: {codec.reference_focal:g})")
        if differ:
            raise PoseLifterError(
                f"teacher network {m.name!r} reads other 2D or features, or predicts in another frame or another "
                "root-depth parameter, than "
                f"the network trained: {', '.join(differ)}; its outputs are not targets of this network: give a "
                "teacher of the same kind, or train with the options named set as the teacher's")


@torch.no_grad()
def teacher_targets(teacher: Lifter, batch: Batch, *, clean_samples: bool = True) -> torch.Tensor:
    """Raw outputs ``(B, 49)`` (mm; the depth parameter of the codec they share, :func:`check_teacher`) of a trained
    model for the batch's 2D, as :meth:`lifter.api.Lifter.lift` makes them: for detected samples the average of its
    detected networks (each with its flip-test default: the mirror image's output mapped back and averaged), for
    clean samples its clean-2D network when it has one. Averaging raw outputs is averaging the decoded relative pose
    and root depth, since every network of the teacher encodes the same features (the depth parameter is linear in
    Z with one factor per input). ``clean_samples=False`` (no sample of the run is clean: ``data.clean_prob`` 0)
    skips the clean network. Computed on the batch's device, with nothing read back to the host."""

    def average(lifter: Lifter, source: Any) -> torch.Tensor:
        # every network encodes the same features (check_teacher): each input once, the mirror image only if a
        # network has the flip test; a network with it runs both rows in one pass, as Lifter.lift does
        c, n = lifter.codec, len(batch["kp"])
        plain = c.encode(batch["kp"], principal_point=batch["pp"], focal=batch["focal"], source=source).features
        both: torch.Tensor | None = None
        total: torch.Tensor | None = None
        members = (lifter, *lifter.ensemble)
        for m in members:
            if m.network_rows() == 2 and both is None:
                mirrored = c.mirror_input(batch["kp"], batch["pp"])
                both = torch.cat([plain, c.encode(mirrored, principal_point=batch["pp"], focal=batch["focal"],
                                                  source=source).features])
            feats = both if both is not None and m.network_rows() == 2 else plain
            folded = forward_folded(m.net, feats)
            raw = m.codec.destandardize(folded if folded is not None else m.net(feats))
            if len(raw) > n:
                raw = m.codec.flip_average(raw, n)
            total = raw if total is None else total + raw
        assert total is not None
        return total / len(members)

    if teacher.clean is None:  # one set of networks for both sources (told which, if conditioned on it)
        return average(teacher, batch["clean"])
    detected = average(teacher, "detected")
    if not clean_samples:
        return detected
    return torch.where(batch["clean"][:, None], average(teacher.clean, "clean"), detected)


def teacher_roles(teacher: Lifter, *, clean_prob: float) -> str:
    """Which of the teacher's networks answer which samples of a run with ``data.clean_prob``, for the log."""
    n = len(teacher.ensemble) + 1
    nets = "its detected network" if n == 1 else f"the average of its {n} detected networks"
    if teacher.clean is None:
        return f"{nets}, for every sample"
    if clean_prob <= 0:
        return f"{nets}, for every sample (none is clean)"
    if clean_prob >= 1:
        return "its clean-2D network, for every sample (all are clean: --clean-prob 1)"
    return f"{nets} for detected samples, its clean-2D network for clean ones"


def batch_loss(net: torch.nn.Module, codec: PoseCodec, batch: Batch, cfg: TrainConfig, *,
               teacher: Lifter | None = None) -> torch.Tensor:
    """The training loss (mm) of one batch; with a ``teacher``, ``optim.distill_weight`` of it is taken against
    :func:`teacher_targets` instead of the ground truth."""
    enc = codec.encode(batch["kp"], principal_point=batch["pp"], focal=batch["focal"], source=batch["clean"])
    target = codec.encode_targets(batch["rel"], batch["depth"], enc)
    autocast = torch.autocast(batch["kp"].device.type, dtype=torch.bfloat16) if cfg.optim.precision == "bf16" \
        else nullcontext()
    with autocast:
        out = net(enc.features)
    pred = codec.destandardize(out.float())
    scale = codec.depth_loss_scale(enc)
    loss = poselifter_loss(pred, target, depth_weight=cfg.optim.depth_weight, depth_scale=scale,
                           pose_loss=cfg.optim.pose_loss)
    if teacher is None:
        return loss
    w = cfg.optim.distill_weight
    taught = poselifter_loss(pred, teacher_targets(teacher, batch, clean_samples=cfg.data.clean_prob > 0),
                             depth_weight=cfg.optim.depth_weight, depth_scale=scale, pose_loss=cfg.optim.pose_loss)
    return (1.0 - w) * loss + w * taught


@torch.inference_mode()
def validate(net: PoseLifterNet, codec: PoseCodec, val: dict[str, Batch]) -> dict[str, float]:
    """MPJPE and MRPE (mm) of ``net`` on each validation set (``{"clean": batch, "detected": batch}``): learning
    curve points, never used to pick a checkpoint."""
    was = net.training
    net.eval()
    out: dict[str, float] = {}
    for name, b in val.items():
        source = "clean" if name == "clean" else "detected"
        enc = codec.encode(b["kp"], principal_point=b["pp"], focal=b["focal"], source=source)
        raw = codec.destandardize(net(enc.features))
        dec = codec.decode(raw, enc, root_2d=b["kp"][:, 0], principal_point=b["pp"], focal=b["focal"])
        out[f"val_mpjpe_{name}"] = (dec.relative - b["rel"]).norm(dim=-1).mean().item()
        out[f"val_mrpe_{name}"] = (dec.root - b["root"]).norm(dim=-1).mean().item()
    net.train(was)
    return out


def validation_sets(samples: PoseSamples, detections: np.ndarray | None) -> dict[str, Batch]:
    """Validation batches: GT 2D ("clean") and, when given, the real detections ("detected")."""
    sets: dict[str, Batch] = {}
    T = samples_to_tensors(samples)
    T["root"] = torch.from_numpy(samples.root.astype(np.float32))
    sets["clean"] = T
    if detections is not None:
        ok = np.isfinite(detections).all(axis=(1, 2))
        if ok.any():
            D = {k: v[torch.from_numpy(ok)] for k, v in T.items()}
            D["kp"] = torch.from_numpy(detections[ok].astype(np.float32))
            sets["detected"] = D
    return sets


def _sync_buffers(net: torch.nn.Module) -> None:
    """Copy rank 0's buffers (BatchNorm running statistics) to every rank."""
    for b in net.buffers():
        dist.broadcast(b, src=0)


# ------------------------------------------------------------------------------------------------
# The loop
# ------------------------------------------------------------------------------------------------


FINITE_CHECK_EVERY = 50
"""Steps between checks that the training loss is finite (each check waits for the device)."""


def _check_finite(running: torch.Tensor, step: int, ctx: Dist) -> None:
    """Raise on every rank when the running loss of any rank is not finite (one rank alone raising would leave the
    others waiting in their next collective)."""
    ok = torch.isfinite(running).to(torch.int32).reshape(1)
    if ctx.active:
        dist.all_reduce(ok, op=dist.ReduceOp.MIN)
    if not bool(ok):
        where = f" on another process (this one's: {float(running):.4g})" if bool(torch.isfinite(running)) \
            else f" ({float(running)})"
        raise FloatingPointError(f"the training loss became non-finite by step {step}{where}; "
                                 "lower --lr, or check the data")


BF16_EMULATED_NOTE: Final[str] = (
    "training in float32, not bf16 (--precision bf16): this CPU has no native bf16 arithmetic (AVX512-BF16 or AMX), "
    "so bf16 matmuls would be emulated, 12-20x slower (measured on a 2-core AVX2 machine, one thread per run: 95 "
    "against 1,930 samples/s at width 1024); the checkpoint's config says fp32")
"""What :func:`train` logs where it trains in float32 although the config says bf16 (:func:`cpu_has_native_bf16`)."""


def cpu_has_native_bf16() -> bool:
    """Whether this CPU computes bf16 matmuls natively (AVX512-BF16 or AMX tiles, as torch detects them). Without
    them torch emulates bf16 autocast on the CPU, far slower than float32, so :func:`train` trains in float32 there
    (on a 2-core AVX2 VM, one thread per run, two runs at once: bf16 95 and 237 samples/s, float32 1,930 and 2,790,
    for a width-1024 network and the width-512 mirror network)."""
    import torch.cpu as tcpu

    for probe in ("_is_avx512_bf16_supported", "_is_amx_tile_supported"):
        fn = getattr(tcpu, probe, None)
        try:
            if fn is not None and bool(fn()):
                return True
        except Exception:  # (a private probe that changed: counted as absent)  # noqa: BLE001
            continue
    return False


def train(
    cfg: TrainConfig,
    *,
    data: H36M | None = None,
    train_samples: PoseSamples | None = None,
    real_keypoints_2d: np.ndarray | None = None,
    val_sets: dict[str, Batch] | None = None,
    init: tuple[PoseLifterNet, PoseCodec] | None = None,
    noise: ErrorModel | None = None,
    teacher: Lifter | None = None,
    progress: bool = True,
    log: Callable[[str], None] = print,
    ctx: Dist | None = None,
    resume: ResumeState | None = None,
) -> TrainResult:
    """Train a network (module docstring). Data: ``train_samples`` (default: the protocol's training subjects
    from ``data``), ``real_keypoints_2d`` aligned with them (needed when ``cfg.data.real_prob > 0``),
    ``val_sets`` for the learning curve (default: the test subjects at ``val_stride``, GT 2D only).
    ``init``: fine-tune a copy of this network and codec (``cfg.model`` is replaced by its config).
    ``noise``: the error model (default: :func:`load_noise`). ``teacher``: the model to distil (default: ``cfg.teacher``
    loaded, if set; :func:`teacher_targets`). ``ctx``: the distributed context (default: :func:`init_distributed`).
    ``resume``: go on with a run stopped with Ctrl-C (:attr:`TrainResult.resume`, :class:`lifter.resume.ResumeState`)
    where it stopped; ``cfg`` must be its config, the data its data, and ``init`` and ``noise`` are not given (its
    weights, codec and error-model fit are in the state). One process only."""
    ctx = ctx or init_distributed()
    if resume is not None:
        check_resume(resume, cfg, init=init, noise=noise, ctx=ctx)
    torch.manual_seed(cfg.schedule.seed)
    # this rank's augmentation draws, made where the batches are made: on the training device
    gen = torch.Generator(device=ctx.device).manual_seed(cfg.schedule.seed + 1000 * ctx.rank)
    perm_gen = torch.Generator().manual_seed(cfg.schedule.seed)  # the shared permutation
    if train_samples is None:
        data = data or H36M()
        train_samples = data.load_protocol(cfg.data.protocol, "train", stride=cfg.data.train_stride,
                                           max_frames_per_sequence=cfg.data.max_frames_per_sequence,
                                           lens=cfg.data.lens)
    if val_sets is None:
        data = data or H36M()
        val = data.load_protocol(cfg.data.protocol, "test", stride=cfg.data.val_stride,
                                 max_frames_per_sequence=cfg.data.max_frames_per_sequence, lens=cfg.data.lens)
        val_sets = validation_sets(val, None)
    if train_samples.lens != cfg.data.lens:
        raise PoseLifterError(f"the training samples' 2D is lens={train_samples.lens!r} but the config says data.lens="
                              f"{cfg.data.lens!r}: load them with H36M.load(..., lens={cfg.data.lens!r})")
    if cfg.data.real_prob > 0 and real_keypoints_2d is None:
        raise PoseLifterError("data.real_prob > 0 needs the real detections of the training samples")
    if init is not None:
        cfg = replace(cfg, model=init[0].config)
    if cfg.optim.precision == "bf16" and ctx.device.type == "cpu" and not cpu_has_native_bf16():
        cfg = replace(cfg, optim=replace(cfg.optim, precision="fp32"))
        if ctx.main:
            log(f"note: {BF16_EMULATED_NOTE}")
    if cfg.augment.zoom and cfg.model.input_space == "camera":
        raise PoseLifterError("--zoom scales the 2D, principal point and focal together, which the reference-camera "
                              "input (input_space 'camera') undoes exactly: the network would see the same input "
                              "(only each sample's depth-loss weight would change): drop --zoom, or train a "
                              "pixel-space model (--input-space pixel)"
                              + (" (this model's config comes from --init)" if init is not None else ""))
    if cfg.data.real_rescale and real_keypoints_2d is not None:  # (the config refuses it with real_prob 0)
        real_keypoints_2d, ratio = match_scale(real_keypoints_2d, train_samples.keypoints_2d)
        if ctx.main:
            log(f"real detections rescaled by 1/{ratio:.4f} about their 2D mean (their median 2D scale was "
                f"{100 * ratio:.2f} % of the GT 2D's)")
    T = samples_to_tensors(train_samples, real_keypoints_2d if cfg.data.real_prob > 0 else None)
    if resume is not None and (resume.samples != len(train_samples) or resume.data_sha256 != data_fingerprint(T)):
        raise PoseLifterError(f"the training data is not the stopped run's ({len(train_samples)} samples, the run had "
                              f"{resume.samples}, or their values differ): resume it with the same Human3.6M data "
                              "(--h36m) and detections")
    if resume is not None:  # (the model it drew from, whatever the config's path now holds)
        fit = None if resume.error_model is None else ErrorModel.from_dict(resume.error_model)
        noise = None if resume.noise is None else ErrorModel.from_dict(resume.noise)
    else:
        fit = None if noise is not None else load_fit(cfg)  # (a caller's own noise model is stored as given)
    noise = noise if noise is not None else load_noise(cfg, fit)
    if cfg.data.noise_prob > 0 and noise is None:
        raise PoseLifterError("some samples need synthetic noise (clean_prob + real_prob < 1) but no error model")

    if resume is not None:
        codec = PoseCodec.from_state_dict(cfg.model, {k: v.numpy() for k, v in resume.codec.items()})
        net = PoseLifterNet(cfg.model)
        net.set_target_statistics(codec.target_mean, codec.target_std)
        net.load_state_dict(resume.network)
    elif init is not None:
        net, codec = copy.deepcopy(init[0]), init[1]
        net.set_target_statistics(codec.target_mean, codec.target_std)
    else:
        codec = PoseCodec(cfg.model)
        mean, std = target_statistics(codec, T)
        codec = PoseCodec(cfg.model, target_mean=mean, target_std=std)
        net = PoseLifterNet(cfg.model)
        net.set_target_statistics(mean, std)
    net.to(ctx.device).train()
    if teacher is None and cfg.teacher is not None:
        from .api import Lifter  # (the api imports the training config's modules, not this one)

        teacher = Lifter.load(cfg.teacher)
    if teacher is not None:
        check_teacher(teacher, codec, lens=cfg.data.lens)
        teacher = copy.deepcopy(teacher)  # its networks move to the training device; the caller's stay put
        for m in teacher_networks(teacher):
            m.net.to(ctx.device).eval()
    T = {k: v.to(ctx.device) for k, v in T.items()}  # batches are drawn on the device, not copied to it
    model: torch.nn.Module = net
    if ctx.active:
        model = torch.nn.parallel.DistributedDataParallel(
            net, device_ids=[ctx.device.index] if ctx.device.type == "cuda" else None)
    opt = torch.optim.AdamW(net.parameters(), lr=cfg.optim.lr, weight_decay=cfg.optim.weight_decay)
    ema = (WeightAverage(net, decay=cfg.optim.ema_decay, warmup=cfg.optim.ema_warmup)
           if cfg.optim.ema_decay is not None else None)
    if resume is not None:
        opt.load_state_dict(copy.deepcopy(resume.optimizer))  # (it would take the state's own tensors and step them)
        if ema is not None and resume.average is not None:
            ema.module.load_state_dict(resume.average)
            ema.updates = resume.average_updates
    eval_net: PoseLifterNet = ema.module if ema is not None else net  # type: ignore[assignment]
    val_dev = {k: {n: t.to(ctx.device) for n, t in v.items()} for k, v in val_sets.items()}

    n = len(train_samples)
    gbs = min(cfg.optim.batch_size, n)
    if gbs < ctx.world:
        raise PoseLifterError(f"batch size {gbs} is smaller than the {ctx.world} processes")
    lbs = gbs // ctx.world
    asked = "" if lbs * ctx.world == gbs else f"; {gbs} asked, rounded down to a multiple of {ctx.world}"
    gbs = lbs * ctx.world  # the samples a step really trains on (and counts)
    steps = max(1, int(round(cfg.schedule.epochs * n / gbs)))
    limit = f"max {cfg.schedule.max_minutes:g} min" if cfg.schedule.max_minutes else "no time limit"
    if ctx.main:
        log(f"training on {n} samples, global batch {gbs} ({ctx.world} process(es) x {lbs}{asked}), {steps} steps "
            f"({cfg.schedule.epochs:g} epochs), {limit}, {cfg.model}"
            + ("" if teacher is None else f", distilling {teacher.name!r} at weight {cfg.optim.distill_weight:g} ("
               + teacher_roles(teacher, clean_prob=cfg.data.clean_prob) + ")"))
    curve: list[dict[str, float]] = []
    perm = torch.randperm(n, generator=perm_gen).to(ctx.device)
    pos = 0
    t0 = time.perf_counter()
    running: torch.Tensor | None = None  # on the device: read back only every FINITE_CHECK_EVERY steps
    step = 0
    if resume is not None:  # (last: everything above that draws from the generators has drawn)
        step, pos, curve = resume.step, resume.position, list(resume.curve)
        perm = resume.permutation.to(ctx.device)
        t0 -= 60.0 * resume.minutes
        running = None if resume.running_loss is None else torch.tensor(resume.running_loss, device=ctx.device)
        perm_gen.set_state(resume.rng["permutation"])
        gen.set_state(resume.rng["batches"])
        torch.set_rng_state(resume.rng["torch"])
        if ctx.device.type == "cuda" and "cuda" in resume.rng:
            torch.cuda.set_rng_state(resume.rng["cuda"], ctx.device)
        if ctx.main:
            log(f"resuming at step {step} of {steps} ({minutes_text(resume.minutes)} trained)")
    bar = tqdm(total=steps, initial=step, disable=None if progress and ctx.main else True, unit="step",
               dynamic_ncols=True, mininterval=2.0)
    clock = torch.zeros(1, device=ctx.device)

    def record() -> None:
        rec = {"step": step, "samples": step * gbs, "minutes": (time.perf_counter() - t0) / 60.0,
               "lr": opt.param_groups[0]["lr"], "train_loss": 0.0 if running is None else float(running)}
        rec.update(validate(eval_net, codec, val_dev))
        curve.append(rec)
        bar.set_postfix({k.replace("val_", ""): f"{v:.1f}" for k, v in rec.items() if k.startswith("val_")})
        if bar.disable:  # (--no-progress, or stderr not a terminal: the curve goes to the log instead)
            log(f"step {step}: " + ", ".join(f"{k} {v:.4g}" for k, v in rec.items() if k != "step"))

    interrupted = False
    whole = True  # every step begun has ended: the state is a step boundary's (a resume can start from it)
    asked = _StopAsked(enabled=not ctx.active)
    try:
        while True:
            if asked.flag:  # (Ctrl-C came during the step before: it ended whole)
                interrupted = True
                break
            elapsed = (time.perf_counter() - t0) / 60.0
            if ctx.active:  # every rank follows the slowest clock, so all stop at the same step
                clock.fill_(elapsed)
                dist.all_reduce(clock, op=dist.ReduceOp.MAX)
                elapsed = float(clock.item())
            prog = step / steps
            if cfg.schedule.max_minutes is not None:
                prog = max(prog, elapsed / cfg.schedule.max_minutes)
            if prog >= 1.0:
                break
            for g in opt.param_groups:
                g["lr"] = cfg.optim.lr * lr_factor(prog, cfg)
            whole = False
            if pos + gbs > n:
                perm = torch.randperm(n, generator=perm_gen).to(ctx.device)
                pos = 0
            idx = perm[pos + ctx.rank * lbs: pos + (ctx.rank + 1) * lbs]
            pos += gbs
            batch = make_batch(T, idx, cfg, gen, noise=noise)
            loss = batch_loss(model, codec, batch, cfg, teacher=teacher)
            opt.zero_grad(set_to_none=True)
            loss.backward()
            opt.step()
            if ctx.active:
                _sync_buffers(net)
            if ema is not None:
                ema.update(net)
            step += 1
            running = loss.detach() if running is None else 0.98 * running + 0.02 * loss.detach()
            whole = True
            if step % FINITE_CHECK_EVERY == 0:
                _check_finite(running, step, ctx)
            if ctx.main and (step % cfg.schedule.eval_every == 0 or step == steps):
                record()
            bar.update(1)
    except KeyboardInterrupt:  # (one process: the weights so far are kept, written beside --out by the CLI)
        if ctx.active:
            raise  # (the other ranks stop at their own points: no collective can be trusted to finish)
        interrupted = True
    finally:
        asked.restore()
    if running is not None:
        _check_finite(running, step, ctx)
    state = None
    if interrupted and whole and step > 0:  # (the live weights, before the curve's last point is taken)
        try:
            state = _resume_state(cfg, step=step, minutes=(time.perf_counter() - t0) / 60.0, T=T, pos=pos,
                                  perm=perm, gens={"permutation": perm_gen, "batches": gen}, net=net, opt=opt,
                                  ema=ema, codec=codec, running=running, curve=curve,
                                  fit=(fit or noise) if cfg.data.noise_prob > 0 else None,
                                  noise=noise if cfg.data.noise_prob > 0 else None, device=ctx.device)
        except KeyboardInterrupt:  # (a second Ctrl-C while it was taken, ~0.1 s: the weights so far are still kept;
            log("a second Ctrl-C while the run's state was taken: no resume state, the weights so far are kept")
    if ctx.main and (not curve or curve[-1]["step"] != step):
        record()  # (an interrupted run too: the curve's last point is the weights it keeps)
    bar.close()
    minutes = (time.perf_counter() - t0) / 60.0
    eval_net.eval()
    eval_net.cpu()
    if ctx.main:
        log(f"done: {step} steps, {step * gbs} samples in {minutes_text(minutes)} "
            f"({step * gbs / max(minutes * 60, 1e-9):.0f} samples/s)")
    if interrupted:
        log(f"interrupted at step {step} of {steps} ({minutes_text(minutes)})")
    return TrainResult(net=eval_net, codec=codec, config=cfg, curve=curve, steps=step, samples_seen=step * gbs,
                       minutes=minutes, error_model=(fit or noise) if cfg.data.noise_prob > 0 else None,
                       interrupted=interrupted, resume=state)


def minutes_text(minutes: float) -> str:
    """A duration for logs: ``"12.3 min"``, or seconds below a minute (``"0.0 min"`` said nothing)."""
    return f"{minutes:.1f} min" if minutes >= 1 else f"{60 * minutes:.1f} s"


def check_resume(state: ResumeState, cfg: TrainConfig, *, ctx: Dist, init: Any = None, noise: Any = None) -> None:
    """Refuse a resume that could not go on as the stopped run would have, naming why."""
    if ctx.active:
        raise PoseLifterError("a run is resumed on one process (its state is one process's): start it without "
                              "torchrun")
    if init is not None or noise is not None:
        raise PoseLifterError("a resumed run takes its weights and error model from its state: give neither init "
                              "nor noise")
    if state.device != ctx.device.type:
        raise PoseLifterError(f"the run was stopped training on the {state.device.upper()}, and this process trains "
                              f"on the {ctx.device.type.upper()}: resume it where it ran (its random generators' "
                              "states are that device's), or start a new run from its weights (--init "
                              "NAME.interrupted.pt)")
    stored = _flat(TrainConfig.from_dict(state.train_config).to_dict())  # (a field added since: its default)
    given = _flat(cfg.to_dict())
    if given != stored:
        diff = sorted(k for k in set(stored) | set(given) if stored.get(k) != given.get(k))
        raise PoseLifterError(f"a resumed run goes on with its own config; this one differs in {', '.join(diff[:6])}: "
                              "resume with the state's config (TrainConfig.from_dict(state.train_config)), or start "
                              "a new run (--init NAME.interrupted.pt)")


def _to_cpu(obj: Any) -> Any:
    """``obj`` (nested dicts, lists and tuples) with every tensor copied to the CPU."""
    if isinstance(obj, torch.Tensor):
        return obj.detach().cpu().clone()
    if isinstance(obj, dict):
        return {k: _to_cpu(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return type(obj)(_to_cpu(v) for v in obj)
    return obj


def _flat(d: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _resume_state(cfg: TrainConfig, *, step: int, minutes: float, T: Batch, pos: int, perm: torch.Tensor,
                  gens: dict[str, torch.Generator], net: PoseLifterNet, opt: torch.optim.Optimizer,
                  ema: WeightAverage | None, codec: PoseCodec, running: torch.Tensor | None,
                  curve: list[dict[str, float]], fit: ErrorModel | None, noise: ErrorModel | None,
                  device: torch.device) -> ResumeState:
    """The whole state of a run at a step boundary (:class:`lifter.resume.ResumeState`), on the CPU (the weights are
    float32 as trained: bf16 autocast keeps float32 parameters)."""
    rng = {name: g.get_state() for name, g in gens.items()}
    rng["torch"] = torch.get_rng_state()
    if device.type == "cuda":
        rng["cuda"] = torch.cuda.get_rng_state(device)
    return ResumeState(
        train_config=cfg.to_dict(), step=step, minutes=minutes, samples=int(T["kp"].shape[0]),
        data_sha256=data_fingerprint(T), position=pos, permutation=perm.cpu().clone(), rng=rng,
        network=_to_cpu(net.state_dict()), optimizer=_to_cpu(opt.state_dict()), device=device.type,
        average=None if ema is None else _to_cpu(ema.module.state_dict()),
        average_updates=0 if ema is None else ema.updates,
        codec={k: v.clone() for k, v in codec.state_dict().items()},
        running_loss=None if running is None else float(running), curve=[dict(c) for c in curve],
        error_model=None if fit is None else fit.to_dict(), noise=None if noise is None else noise.to_dict(),
        meta={})


def save_training_outputs(result: TrainResult, out: str | Path, *, half: bool = True,
                          extra_meta: dict[str, Any] | None = None) -> Path:
    """Write ``out`` (checkpoint, with the config), ``out`` with ``.curve.json`` and a learning-curve PNG beside it.
    The checkpoint's meta keeps the error-model fit the noise was drawn from, and its sha256 (``error_model``,
    ``error_model_sha256``): the config names it only by a name or path, whose file can change (a researcher trial
    repeated a run with ``--config`` from another folder, whose ``em/fit.json`` was another fit, without a word)."""
    out = Path(out)
    meta: dict[str, Any] = {"steps": result.steps, "samples_seen": result.samples_seen, "minutes": result.minutes,
                            "final_val": result.curve[-1] if result.curve else {}}
    if result.error_model is not None:
        meta["error_model"] = result.error_model.to_dict()
        meta["error_model_sha256"] = result.error_model.sha256()
    meta.update(extra_meta or {})
    save_checkpoint(out, result.net, result.codec, train_config=result.config.to_dict(), meta=meta, half=half)
    from .io import write_atomic  # (not through a link at its name; its own temporary file: a security trial)

    write_atomic(out.with_suffix(".curve.json"),
                 json.dumps({"train_config": result.config.to_dict(), "curve": result.curve}, indent=1))
    # matplotlib only when a curve is drawn: `import lifter.train` (every `poselifter` command) stays ~0.5 s faster
    from .plots import plot_learning_curve

    plot_learning_curve(result.curve, out.with_suffix(".curve.png"), title=out.stem)
    return out
