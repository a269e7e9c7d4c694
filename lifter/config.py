"""Training configuration: nested, validated dataclasses, the one source of truth for a run.

:class:`TrainConfig` holds :class:`~lifter.model.ModelConfig` (the network and codec), :class:`DataConfig`
(which samples and which 2D inputs), :class:`AugmentConfig`, :class:`OptimConfig` and
:class:`ScheduleConfig`. Every field is validated on construction, round-trips through JSON
(:meth:`TrainConfig.to_dict` / :meth:`TrainConfig.from_dict`), is stored in every checkpoint, and is a
``poselifter train`` option (:func:`add_config_arguments` generates them from the fields' types, defaults and
help texts), so ``poselifter train --config run.json`` (or a checkpoint) repeats a run.
"""

from __future__ import annotations

import argparse
import json
import math
import types
import typing
from dataclasses import MISSING, asdict, dataclass, field, fields, is_dataclass, replace
from pathlib import Path
from typing import Any, Literal, get_args, get_origin

from ._checks import PoseLifterError
from .checkpoint import load_checkpoint
from .data import LENSES, Lens
from .model import ModelConfig


def _help(text: str, **kw: Any) -> Any:
    return field(metadata={"help": text}, **kw)


def _check(cond: bool, message: str) -> None:
    if not cond:
        raise PoseLifterError(f"train config: {message}")


def _prob(name: str, v: float) -> None:
    _check(isinstance(v, (int, float)) and not isinstance(v, bool) and 0.0 <= v <= 1.0,
           f"{name} must be a probability in [0, 1], got {v!r}")


def _positive(name: str, v: float, *, integer: bool = False, allow_zero: bool = False) -> None:
    ok = isinstance(v, int) if integer else isinstance(v, (int, float)) and math.isfinite(v)
    ok = ok and not isinstance(v, bool) and (v >= 0 if allow_zero else v > 0)
    _check(ok, f"{name} must be {'an integer' if integer else 'a number'} {'>= 0' if allow_zero else '> 0'}, got {v!r}")


def _booleans(section: Any) -> None:
    """Every ``bool`` field of a config section holds a bool (a Python caller's ``"false"`` would read as true)."""
    for f in fields(section):
        if f.type in (bool, "bool"):
            v = getattr(section, f.name)
            _check(isinstance(v, bool), f"{f.name} must be true or false, got {v!r}")


@dataclass(frozen=True)
class DataConfig:
    """Which H36M samples, and which 2D each training sample is given.

    Per sample: with probability ``clean_prob`` its exact GT 2D (source "clean"); with ``real_prob`` its real
    Stacked-Hourglass detection where the frame has one (source "detected"); otherwise its GT 2D plus noise
    drawn from the error model at a level uniform in ``[noise_level_min, noise_level_max]`` (source "detected").
    """

    protocol: Literal[1, 2] = _help("H36M protocol: 1 (train S1,5,6,7,8) or 2 (also S9)", default=1)
    train_stride: int = _help("training frames: every n-th 50-fps frame (real detections need a multiple of 5)",
                              default=5)
    val_stride: int = _help("learning-curve frames of the test subjects: every n-th", default=100)
    max_frames_per_sequence: int | None = _help("keep only the first this many frames of each sequence, counted "
                                                "after the stride (tiny runs)", default=None)
    clean_prob: float = _help("share of samples given their exact GT 2D", default=1.0)
    real_prob: float = _help("share given their real SH detection (where the frame has one)", default=0.0)
    real_rescale: bool = _help("rescale the real detections about their 2D mean so that their median 2D scale "
                               "matches the GT 2D's (SH's 2D poses are ~2.3 %% smaller): the network then does not "
                               "learn SH's size bias", default=False)
    noise: Literal["mixture", "gaussian"] = _help("synthetic noise: the fitted mixture or its single-Gaussian "
                                                  "baseline", default="mixture")
    error_model: str = _help("error-model fit: a shipped name (sh_mixture), a JSON path, or a training checkpoint "
                             "(.pt) whose noise fit it stored", default="sh_mixture")
    noise_level_min: float = _help("lowest noise level (0 clean, 1 as fitted)", default=1.0)
    noise_level_max: float = _help("highest noise level", default=1.0)
    noise_outliers: bool = _help("sample the mixture's uniform outliers (False: the authors' code)", default=False)
    lens: Lens = _help("the 2D the network learns: 'h36m' H36M's own, with its cameras' lens distortion (the "
                       "paper's models), or 'pinhole' the ideal pinhole projection, with the real detections "
                       "undistorted (what undistorted photos give; the default lifter)", default="h36m")

    def __post_init__(self) -> None:
        _check(self.protocol in (1, 2), f"protocol must be 1 or 2, got {self.protocol!r}")
        for name in ("train_stride", "val_stride"):
            _positive(name, getattr(self, name), integer=True)
        if self.max_frames_per_sequence is not None:
            _positive("max_frames_per_sequence", self.max_frames_per_sequence, integer=True)
        _prob("clean_prob", self.clean_prob)
        _prob("real_prob", self.real_prob)
        _check(self.clean_prob + self.real_prob <= 1.0 + 1e-9,
               f"clean_prob + real_prob must be <= 1 (the rest get synthetic noise), got {self.clean_prob} + "
               f"{self.real_prob}: lower --clean-prob or --real-prob")
        _check(self.real_prob == 0 or self.train_stride % 5 == 0,
               f"real detections exist every 5th frame: train_stride must be a multiple of 5, got {self.train_stride}")
        _check(self.lens in LENSES, f"lens must be one of {list(LENSES)}, got {self.lens!r}")
        _booleans(self)
        _check(not self.real_rescale or self.real_prob > 0,
               "real_rescale rescales the real detections, but real_prob is 0 (none are used): give --real-prob P "
               "(with --clean-prob at most 1 - P) or --no-real-rescale")
        _check(self.noise in ("mixture", "gaussian"), f"noise must be 'mixture' or 'gaussian', got {self.noise!r}")
        for name in ("noise_level_min", "noise_level_max"):
            _positive(name, getattr(self, name), allow_zero=True)
        _check(self.noise_level_min <= self.noise_level_max,
               f"noise_level_min {self.noise_level_min} > noise_level_max {self.noise_level_max}")
        _check(bool(self.error_model), "error_model must name a shipped fit or a JSON file")

    @property
    def noise_prob(self) -> float:
        return max(0.0, 1.0 - self.clean_prob - self.real_prob)


@dataclass(frozen=True)
class AugmentConfig:
    """Geometric augmentation (2D and 3D together, so every sample stays physically consistent)."""

    flip_prob: float = _help("horizontal flip probability (x and cx mirrored, L/R swapped, X negated)", default=0.5)
    zoom: bool = _help("zoom: scale 2D, principal point and focal together (pixel input space only; training "
                       "refuses it in the reference camera, where it is an exact symmetry)", default=False)
    zoom_sigma: float = _help("zoom: std of log2(scale)", default=0.25)
    zoom_clip: float = _help("zoom: |log2(scale)| limit (0.5: x0.71..x1.41)", default=0.5)
    rotate_deg: float = _help("turn the camera about its centre by a pan and a tilt each uniform in +-this many "
                              "degrees (0: off, at most 45): the 3D turns with it and every 2D point, detections "
                              "included, moves as that camera would see it (the homography K R K^-1), so where a "
                              "person stands in the image no longer tells their depth by the training cameras' pose "
                              "(needs --lens pinhole)", default=0.0)
    roll_deg: float = _help("roll the camera about its optical axis by an angle uniform in +-this many degrees (0: "
                            "off, at most 45), after the pan and tilt of --rotate-deg if any: the picture turns in "
                            "its plane, as a hand-held photo's often does (needs --lens pinhole)", default=0.0)
    turn_prob: float = _help("share of the samples whose camera --rotate-deg and --roll-deg turn (1: every sample; "
                             "below 1 the rest keep the training cameras' own pose, so a network sees turned cameras "
                             "and still the training cameras' pose as the most likely one)", default=1.0)

    distance_prob: float = _help("move this share of the samples along their root's viewing ray, their root depth "
                                 "times a factor log-uniform in [--distance-min, --distance-max] (0: off): the 3D "
                                 "keeps its shape, the 2D is re-projected and a detection keeps its error relative to "
                                 "the person's 2D size, so people nearer and farther than the training subjects' "
                                 "3.3-6.9 m are seen (needs --lens pinhole)", default=0.0)
    distance_min: float = _help("smallest root-depth factor of --distance-prob (0.4 to 1; a move that would bring a "
                                "joint within 10 deg of the image plane, plus the camera turn, is not made)",
                                default=0.5)
    distance_max: float = _help("largest root-depth factor of --distance-prob (1 to 10)", default=5.0)

    def __post_init__(self) -> None:
        _booleans(self)
        _prob("flip_prob", self.flip_prob)
        _prob("distance_prob", self.distance_prob)
        _prob("turn_prob", self.turn_prob)
        _check(isinstance(self.distance_min, (int, float)) and 0.4 <= self.distance_min <= 1.0,
               f"distance_min must be in [0.4, 1] (a factor of the root depth), got {self.distance_min!r}")
        _check(isinstance(self.distance_max, (int, float)) and 1.0 <= self.distance_max <= 10.0,
               f"distance_max must be in [1, 10] (a factor of the root depth), got {self.distance_max!r}")
        for name in ("rotate_deg", "roll_deg"):
            value = getattr(self, name)
            _check(isinstance(value, (int, float)) and 0.0 <= value <= 45.0,
                   f"{name} must be in [0, 45] degrees, got {value!r}")
        _positive("zoom_sigma", self.zoom_sigma, allow_zero=True)
        _positive("zoom_clip", self.zoom_clip, allow_zero=True)

    @property
    def turns_camera(self) -> bool:
        """Whether the samples' cameras are turned (``rotate_deg`` or ``roll_deg`` above 0)."""
        return self.rotate_deg > 0 or self.roll_deg > 0

    @property
    def moves_people(self) -> bool:
        """Whether some samples are moved along their root's viewing ray (``distance_prob`` above 0)."""
        return self.distance_prob > 0


@dataclass(frozen=True)
class OptimConfig:
    """Optimizer and loss."""

    batch_size: int = _help("global batch size (split across DDP processes)", default=512)
    lr: float = _help("AdamW learning rate", default=1e-3)
    weight_decay: float = _help("AdamW weight decay", default=1e-4)
    depth_weight: float = _help("weight of the canonical-depth L1 term against the pose terms", default=1.0)
    pose_loss: Literal["l1", "joint"] = _help("pose term of the loss: 'l1' sums the 48 coordinates' absolute errors "
                                              "(the paper's); 'joint' sums the 16 joints' Euclidean errors (what "
                                              "MPJPE measures)", default="l1")
    ema_decay: float | None = _help("keep an exponential moving average of the weights (e.g. 0.999); validation "
                                    "and the saved network use it. Its decay warms up as (1 + n) / (10 + n) over "
                                    "the first updates, so a short run does not keep the starting weights "
                                    "(--no-ema-warmup: not)", default=None)
    ema_warmup: bool = _help("warm the EMA's decay up over its first updates (runs stored before this option "
                             "averaged without it, and --config of them keeps that)", default=True)
    precision: Literal["fp32", "bf16"] = _help("matmul precision of the residual blocks in training (bf16 "
                                               "autocast; stem, head and loss stay float32; on a CPU without "
                                               "native bf16, float32, with a note)", default="fp32")
    distill_weight: float = _help("with --teacher: share of the loss taken against the teacher's outputs for the "
                                  "same 2D (the rest against the ground truth)", default=0.5)

    def __post_init__(self) -> None:
        _positive("batch_size", self.batch_size, integer=True)
        _positive("lr", self.lr)
        _positive("weight_decay", self.weight_decay, allow_zero=True)
        _positive("depth_weight", self.depth_weight, allow_zero=True)
        _check(self.ema_decay is None or (isinstance(self.ema_decay, float) and 0.0 <= self.ema_decay < 1.0),
               f"ema_decay must be in [0, 1), got {self.ema_decay!r}")
        _check(self.precision in ("fp32", "bf16"), f"precision must be 'fp32' or 'bf16', got {self.precision!r}")
        _check(self.pose_loss in ("l1", "joint"), f"pose_loss must be 'l1' or 'joint', got {self.pose_loss!r}")
        _prob("distill_weight", self.distill_weight)
        _booleans(self)


@dataclass(frozen=True)
class ScheduleConfig:
    """Length, learning-rate schedule (linear warm-up, cosine decay) and bookkeeping."""

    epochs: float = _help("passes over the training samples", default=30.0)
    max_minutes: float | None = _help("wall-clock budget; the lr schedule follows max(step/steps, elapsed/budget), "
                                      "so a run that hits it still ends fully decayed", default=None)
    warmup_fraction: float = _help("share of the schedule spent warming up", default=0.02)
    final_lr_fraction: float = _help("lr at the end, as a fraction of lr", default=0.01)
    eval_every: int = _help("steps between learning-curve points", default=500)
    seed: int = _help("random seed", default=0)

    def __post_init__(self) -> None:
        _positive("epochs", self.epochs)
        if self.max_minutes is not None:
            _positive("max_minutes", self.max_minutes)
        _prob("warmup_fraction", self.warmup_fraction)
        _prob("final_lr_fraction", self.final_lr_fraction)
        _positive("eval_every", self.eval_every, integer=True)
        _check(isinstance(self.seed, int) and not isinstance(self.seed, bool),
               f"seed must be an integer, got {self.seed!r}")


@dataclass(frozen=True)
class TrainConfig:
    """A training run. ``init``: fine-tune from a shipped model name or checkpoint (its model config wins).
    ``teacher``: distil a trained model (:func:`lifter.train.teacher_targets`), weighted by ``optim.distill_weight``."""

    model: ModelConfig = field(default_factory=ModelConfig)
    data: DataConfig = field(default_factory=DataConfig)
    augment: AugmentConfig = field(default_factory=AugmentConfig)
    optim: OptimConfig = field(default_factory=OptimConfig)
    schedule: ScheduleConfig = field(default_factory=ScheduleConfig)
    init: str | None = _help("fine-tune: start from this shipped model name or checkpoint (keeps its model config)",
                             default=None)
    teacher: str | None = _help("distil: also train against the outputs of this shipped model name or checkpoint for "
                                "the same 2D (for detected 2D, the average of its detected networks, each with its "
                                "flip-test default), weighted by --distill-weight", default=None)

    def __post_init__(self) -> None:
        turns = [(name, f"--{name.replace('_', '-')}") for name in ("rotate_deg", "roll_deg")
                 if getattr(self.augment, name) != 0]
        if self.augment.moves_people:
            turns.append(("distance_prob (moving people along their viewing ray)", "--distance-prob"))
        if self.model.view != "camera":
            turns.append((f"view={self.model.view!r} (to look at the root)", "--view"))
        for what, flag in turns:  # each moves the 2D as a pinhole camera sees it, which holds for pinhole 2D only
            _check(self.data.lens == "pinhole",
                   f"{what} moves the 2D as a pinhole camera would see it; this run's 2D is "
                   f"lens={self.data.lens!r} (with lens distortion): add --lens pinhole, or drop {flag}")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def to_json(self) -> str:
        return json.dumps(self.to_dict(), indent=1)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> TrainConfig:
        """Build from nested dicts (missing keys take their defaults; unknown keys are refused)."""
        return _build(cls, d, "train config")

    @classmethod
    def load(cls, path: str | Path) -> TrainConfig:
        """A run's config from a JSON file or from a checkpoint (``.pt``) that stored one."""
        p = Path(path)
        if not p.is_file():
            raise PoseLifterError(f"--config {p}: no such file")
        if p.suffix == ".pt":
            ck = load_checkpoint(p)
            if ck.train_config is not None:
                return cls.from_dict(_as_stored(ck.train_config))
            legacy = ck.meta.get("train_config")
            if not isinstance(legacy, dict):
                raise PoseLifterError(f"--config {p}: this checkpoint stores no training config (an older file)")
            return cls.from_dict(legacy_train_config(legacy, ck.meta, ck.net.config.to_dict()))
        try:
            d = json.loads(p.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise PoseLifterError(f"--config {p}: not a readable JSON file ({exc})") from None
        if isinstance(d, dict) and "train_config" in d and isinstance(d["train_config"], dict):
            d = d["train_config"]  # a .curve.json written by training
        return cls.from_dict(_as_stored(d))


def _as_stored(d: Any) -> Any:
    """A stored config ``d`` as the run that wrote it trained: options added since take the value that repeats it,
    not today's default (``optim.ema_warmup``: False where the run kept an EMA, which had no warm-up then)."""
    if isinstance(d, dict) and isinstance(d.get("optim"), dict) and "ema_warmup" not in d["optim"] \
            and d["optim"].get("ema_decay") is not None:
        d = {**d, "optim": {**d["optim"], "ema_warmup": False}}
    return d


def legacy_train_config(old: dict[str, Any], meta: dict[str, Any], model: dict[str, Any]) -> dict[str, Any]:
    """The config of a run from before the nested :class:`TrainConfig` (the paper-table checkpoints ``gt``,
    ``mixture``, ``sh_mix``, ``blazepose``: a flat ``meta["train_config"]``, the 2D inputs and noise in ``meta``), as
    today's options say it, so that ``--config`` repeats it (a researcher trial: their stored command,
    ``poselifter train --epochs 25 ...``, now trains a reference-camera network conditioned on ``source``, and
    ``--config gt.pt`` was refused). ``model``: the network's model config (pixel space, no conditioning). Those
    runs drew noise for every sample they did not give a real detection (``inputs`` ``"gt"`` or ``"mix"`` with
    ``real_2d_prob``), or none (no ``noise`` in ``meta``: exact 2D), on Human3.6M's distorted 2D."""
    noise = meta.get("noise")
    real = float(old.get("real_2d_prob", 0.0)) if meta.get("inputs") == "mix" else 0.0
    em = meta.get("error_model")
    data: dict[str, Any] = {k: old[k] for k in ("protocol", "train_stride", "val_stride", "max_frames_per_sequence")
                            if k in old}
    data.update(lens="h36m", real_prob=real, clean_prob=1.0 if noise is None else 0.0)
    if noise is not None:
        level = float(meta.get("noise_level", 1.0))
        data.update(noise=noise, noise_level_min=level, noise_level_max=level,
                    noise_outliers=bool(meta.get("noise_outliers", False)),
                    error_model="sh_mixture" if em in (None, "default") else str(em))
    augment = {"flip_prob": old.get("flip_prob", 0.5), "zoom": bool(old.get("zoom_aug", False))}
    augment.update({k: old[k] for k in ("zoom_sigma", "zoom_clip") if k in old})
    optim = {k: old[k] for k in ("batch_size", "lr", "weight_decay", "depth_weight", "ema_decay") if k in old}
    if optim.get("ema_decay") is not None:
        optim["ema_warmup"] = False  # (those runs' EMA had none)
    schedule = {k: old[k] for k in ("epochs", "max_minutes", "warmup_fraction", "final_lr_fraction", "eval_every",
                                    "seed") if k in old}
    return {"model": dict(model), "data": data, "augment": augment, "optim": optim, "schedule": schedule,
            "init": meta.get("init")}


SECTIONS: tuple[tuple[str, type], ...] = (("model", ModelConfig), ("data", DataConfig), ("augment", AugmentConfig),
                                          ("optim", OptimConfig), ("schedule", ScheduleConfig))


def _build(cls: type, d: Any, where: str) -> Any:
    if not isinstance(d, dict):
        raise PoseLifterError(f"{where}: expected an object, got {type(d).__name__}")
    known = {f.name: f for f in fields(cls)}
    unknown = sorted(set(d) - set(known))
    if unknown:
        hint = ""
        if cls is TrainConfig:  # a flat config: leaf keys written without their section
            home = {f.name: sec for sec, c in SECTIONS for f in fields(c)}
            placed = sorted({f'"{home[k]}"' for k in unknown if k in home})
            if placed:
                hint = f" (section keys go inside their section's object: {', '.join(placed)})"
        raise PoseLifterError(f"{where}: unknown keys {unknown}; known: {sorted(known)}{hint}")
    kw = {}
    hints = typing.get_type_hints(cls)
    for name, value in d.items():
        t = hints[name]
        if is_dataclass(t) and isinstance(t, type):
            kw[name] = _build(t, value, f"{where}.{name}")
        else:
            if bool in _scalar_types(t) and not isinstance(value, bool) and not (value is None and t is not bool):
                kind = "a string" if isinstance(value, str) else type(value).__name__
                raise PoseLifterError(f"{where}.{name} must be a JSON boolean (true or false, unquoted), got "
                                      f"{value!r} ({kind})")
            if isinstance(value, int) and not isinstance(value, bool) and float in _scalar_types(t):
                value = float(value)  # JSON writes 30.0 as 30
            kw[name] = value
    try:
        return cls(**kw)
    except TypeError as exc:
        raise PoseLifterError(f"{where}: {exc}") from None


def _scalar_types(t: Any) -> tuple[Any, ...]:
    """The non-None member types of ``t`` (``float | None`` -> ``(float,)``)."""
    if get_origin(t) in (typing.Union, types.UnionType):
        return tuple(a for a in get_args(t) if a is not type(None))
    return (t,)


# ------------------------------------------------------------------------------------------------
# Command-line options generated from the fields
# ------------------------------------------------------------------------------------------------


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _option_fields() -> list[tuple[str | None, Any, Any]]:
    """``(section or None, field, type)`` for every leaf option; flag names are unique across sections."""
    out: list[tuple[str | None, Any, Any]] = []
    for section, cls in SECTIONS:
        hints = typing.get_type_hints(cls)
        out += [(section, f, hints[f.name]) for f in fields(cls)]
    hints = typing.get_type_hints(TrainConfig)
    out += [(None, f, hints[f.name]) for f in fields(TrainConfig) if f.name not in dict(SECTIONS)]
    names = [f.name for _, f, _ in out]
    dup = {n for n in names if names.count(n) > 1}
    if dup:  # pragma: no cover - a programming error caught by the tests
        raise RuntimeError(f"config fields share option names: {sorted(dup)}")
    return out


def _parser_type(t: Any, flag: str) -> dict[str, Any]:
    (base,) = _scalar_types(t) if len(_scalar_types(t)) == 1 else (t,)
    if get_origin(base) is Literal:
        choices = get_args(base)
        kind = type(choices[0])
        return {"type": kind, "choices": choices}
    if base is bool:
        return {"action": argparse.BooleanOptionalAction}
    if base in (int, float, str):
        def convert(text: str, _b: Any = base) -> Any:
            try:
                v = _b(text)
            except ValueError:
                raise argparse.ArgumentTypeError(f"expected {_b.__name__}, got {text!r}") from None
            if _b is float and not math.isfinite(v):
                raise argparse.ArgumentTypeError(f"expected a finite number, got {text!r}")
            return v
        convert.__name__ = base.__name__
        return {"type": convert}
    raise TypeError(f"{flag}: unsupported config field type {t!r}")  # pragma: no cover


def add_config_arguments(parser: argparse.ArgumentParser) -> None:
    """One option per :class:`TrainConfig` leaf field (``--width``, ``--clean-prob``, ...), grouped by section.
    Defaults are not set here: options the user does not give keep the base config's values."""
    groups: dict[str | None, Any] = {}
    for section, f, t in _option_fields():
        if section not in groups:
            title = f"{section} ({dict(SECTIONS)[section].__name__})" if section else "run"
            groups[section] = parser.add_argument_group(title)
        default = f.default if f.default is not MISSING else f.default_factory()  # type: ignore[misc]
        help_text = f.metadata.get("help") or _model_help(f.name)
        kw = _parser_type(t, _flag(f.name))
        if "type" in kw and "choices" not in kw:
            kw["metavar"] = f.name.upper()  # not the internal dest (cfg__section__name)
        groups[section].add_argument(_flag(f.name), dest=f"cfg__{section or ''}__{f.name}", default=None,
                                     help=f"{help_text} (default: {default})", **kw)


def _model_help(name: str) -> str:
    return {"width": "hidden width of the residual MLP", "num_blocks": "residual blocks",
            "dropout": "dropout probability", "mode": "normalization-layer features (paper Table 2 ablation)",
            "scale_definition": "2D scale: the paper's RMS radius or the authors' code variant",
            "input_space": "'camera': 2D mapped to the reference camera (resolution/focal invariant); 'pixel': the "
                           "paper's image pixels",
            "depth_target": "root depth output: canonical Z*F0/f, absolute Z (pixel only) or size Z*sigma/f",
            "conditioning": "'source': one input feature says whether the 2D is exact or detected",
            "view": "'look_at': the 2D turned (exactly) to a camera looking at the root, the pose predicted in its "
                    "frame; 'camera': as seen"}.get(name, name)


def config_from_args(args: argparse.Namespace, base: TrainConfig | None = None) -> TrainConfig:
    """``base`` (default: all defaults) with every option the user gave applied, validated."""
    cfg = base or TrainConfig()
    sections: dict[str, dict[str, Any]] = {}
    top: dict[str, Any] = {}
    for key, value in vars(args).items():
        if not key.startswith("cfg__") or value is None:
            continue
        _, section, name = key.split("__", 2)
        (sections.setdefault(section, {}) if section else top)[name] = value
    new = {s: replace(getattr(cfg, s), **kw) for s, kw in sections.items()}
    return replace(cfg, **new, **top)
