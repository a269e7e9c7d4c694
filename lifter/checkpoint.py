"""Checkpoint files: a plain dict of tensors and primitives, always loaded with ``torch.load(weights_only=True)``.

Format ``"poselifter-checkpoint"``, version 2::

    {"format": str, "version": 2,
     "model_config": dict (lifter.model.ModelConfig),
     "codec": {"target_mean": Tensor (49,), "target_std": Tensor (49,)},
     "state_dict": {name: Tensor},            # the network (lifter.model.PoseLifterNet)
     "train_config": dict or None,            # lifter.config.TrainConfig.to_dict(): reruns with --config
     "meta": dict,                            # provenance and metrics; primitives only
     "tensors_sha256": str}                   # the tensors' checksum (tensor_checksum); files written before
                                              # 2026-11-27, the shipped ones among them, have none: they load
                                              # with a PoseLifterWarning unless their file sha256 is a shipped one

Version 1 files (network and target statistics in one state dict, the paper's pixel-space model) are
migrated on load. Weights may be stored in float16 to halve the file size; they are cast to float32 on
load. Loading checks, in this order and before the network is allocated: the file's sha256 when one is
expected (shipped weights), that the file starts like a torch file (before the rest is read), the format
and version, the tensors' own checksum when the file has one (a byte changed after it was written: torch's
zip reader does not check its CRCs), the model config's values and bounds (:class:`~lifter.model.ModelConfig`),
and every tensor's name and shape against the config; then that all values are finite. Each failure raises
:class:`~lifter._checks.CheckpointError` naming the problem.
"""

from __future__ import annotations

import hashlib
import io
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import torch

from . import resources as assets
from ._checks import CheckpointError, PoseLifterError, warn_user
from .codec import PoseCodec
from .io import write_atomic
from .model import ModelConfig, PoseLifterNet
from .resume import RESUME_FORMAT

FORMAT = "poselifter-checkpoint"
VERSION = 2
MAX_CHECKPOINT_BYTES = 2 * 1024**3
"""Files larger than this are refused before they are read."""


@dataclass(frozen=True)
class Checkpoint:
    """A loaded checkpoint: network (eval mode, float32), codec, training config (dict or None), metadata."""

    net: PoseLifterNet
    codec: PoseCodec
    train_config: dict[str, Any] | None
    meta: dict[str, Any]
    sha256: str | None = None
    """Hex sha256 of the file's bytes as read (what ``sha256sum FILE`` prints): the weights a result was lifted
    with, in the records' ``model_info``. :func:`load_checkpoint` always sets it; None only for one built by hand."""


def sha256_file(path: str | os.PathLike[str]) -> str:
    """Hex sha256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def tensor_checksum(state_dict: dict[str, Any], codec: dict[str, Any]) -> str:
    """Hex sha256 of a checkpoint's tensors as stored (network ``state_dict`` and ``codec`` statistics): each one's
    name, dtype, shape and bytes, in name order. Written with every checkpoint and checked on load."""
    h = hashlib.sha256()
    for part, tensors in (("state_dict", state_dict), ("codec", codec)):
        for k in sorted(tensors):
            hash_tensor(h, f"{part}/{k}", torch.as_tensor(tensors[k]))
    return h.hexdigest()


def hash_tensor(h: Any, label: str, t: torch.Tensor) -> None:
    """Feed ``label``, ``t``'s dtype, shape and bytes into the hash ``h`` (the form of every checksum of tensors:
    :func:`tensor_checksum`, :mod:`lifter.resume`); the bytes are read in place, not copied."""
    t = t.detach().cpu().contiguous()
    h.update(f"{label}:{t.dtype}:{tuple(t.shape)}:".encode())
    h.update(t.reshape(-1).view(torch.uint8).numpy())


def save_checkpoint(path: str | os.PathLike[str], net: PoseLifterNet, codec: PoseCodec, *,
                    train_config: dict[str, Any] | None = None, meta: dict[str, Any] | None = None,
                    half: bool = False) -> Path:
    """Write ``net`` and ``codec`` to ``path`` atomically (a temporary file in the same folder, then a rename;
    parents created). ``half=True`` stores the network's floating tensors as float16."""
    state = {k: (v.detach().to(torch.float16) if half and v.is_floating_point() else v.detach()).cpu().clone()
             for k, v in net.state_dict().items()}
    codec_state = codec.state_dict()
    payload = {"format": FORMAT, "version": VERSION, "model_config": net.config.to_dict(),
               "codec": codec_state, "state_dict": state, "train_config": train_config, "meta": meta or {},
               "tensors_sha256": tensor_checksum(state, codec_state)}
    path = Path(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PoseLifterError(f"{path}: cannot create its folder ({exc.strerror or exc}); choose another "
                              "path") from None
    buf = io.BytesIO()
    torch.save(payload, buf)
    # the umask's mode (not mkstemp's 0600), fsync, rename; getbuffer(): no third copy of the weights in memory
    return write_atomic(path, buf.getbuffer())


def _migrate_v1(payload: dict[str, Any], where: str) -> dict[str, Any]:
    """A version-1 payload as version 2: the paper's pixel-space model without conditioning, with the target
    statistics moved from the network's state dict into the codec."""
    cfg = payload.get("model_config")
    if not isinstance(cfg, dict):
        raise CheckpointError(f"{where}: model_config must be a dict, got {type(cfg).__name__}")
    state = payload.get("state_dict")
    if not isinstance(state, dict) or "target_mean" not in state or "target_std" not in state:
        raise CheckpointError(f"{where}: version-1 checkpoint without target statistics in its state dict")
    state = dict(state)
    codec = {"target_mean": state.pop("target_mean"), "target_std": state.pop("target_std")}
    return {**payload, "version": VERSION, "model_config": {"input_space": "pixel", "conditioning": "none", **cfg},
            "codec": codec, "state_dict": state, "train_config": None}


def _shipped_sha256s() -> frozenset[str]:
    """:func:`lifter.resources.shipped_sha256s`, or none where the registry cannot be read (a user's own checkpoint
    loads without it: a review's empty ``$POSELIFTER_ASSETS`` refused it)."""
    try:
        return assets.shipped_sha256s()
    except (PoseLifterError, OSError, ValueError):
        return frozenset()


def _not_torch_file(head: bytes) -> str:
    """Why bytes starting with ``head`` cannot be a torch file, or "" when they may be one (a zip archive, what
    ``torch.save`` writes, or a legacy pickle)."""
    if head.lstrip()[:1] in (b"{", b"[") or (head and head.isspace()):  # (JSON indented past the bytes read)
        return "it is a text file, JSON?"
    if head and not head.startswith((b"PK", b"\x80")):
        return "it is not a torch file (torch.save writes a zip archive, which starts 'PK')"
    return ""


def _load_failure(exc: Exception) -> str:
    """A short reason why ``torch.load(weights_only=True)`` refused some bytes, without torch's advice to load them
    with ``weights_only=False`` (which can run code from the file: never for a file of unknown origin)."""
    text = str(exc)
    m = re.search(r"WeightsUnpickler error:\s*(.*?)(?:\.\s|\n|$)", text)
    if m:
        return f"it holds objects that are not plain tensors or values, refused: {m.group(1).strip()}"
    first = text.strip().split("\n")[0].split(". ")[0].strip()
    return f"{type(exc).__name__}: {first}" if first else f"{type(exc).__name__} (empty or truncated file?)"


def load_checkpoint(source: str | os.PathLike[str] | bytes, *, expected_sha256: str | None = None,
                    name: str | None = None) -> Checkpoint:
    """Load a checkpoint from a path or its bytes (module docstring for the checks).

    expected_sha256: refuse the file unless its bytes hash to this (shipped weights carry one).
    name: how to refer to the file in errors (default: the path).
    """
    if isinstance(source, (bytes, bytearray)):
        data, where = bytes(source), name or "checkpoint"
    else:
        path = Path(source)
        where = name or str(path)
        if path.is_dir():
            raise CheckpointError(f"weights file {where} is a directory, not a checkpoint file")
        if not path.is_file():
            hint = ("; runs/ holds checkpoints that poselifter train writes, none of them shipped: the README's "
                    "paper-table commands name runs that scripts/run_ablation.sh, run_table3.sh and run_focal.sh "
                    "train (about 10 minutes each on 1 CPU thread)") if "runs" in path.parts else ""
            raise CheckpointError(f"weights file not found: {where}{hint}")
        if path.stat().st_size > MAX_CHECKPOINT_BYTES:
            raise CheckpointError(f"weights file {where} is {path.stat().st_size / 1e9:.1f} GB; checkpoints larger "
                                  f"than {MAX_CHECKPOINT_BYTES / 1e9:.1f} GB are refused")
        with open(path, "rb") as f:  # (a file that is not a torch file is refused before the rest is read)
            head = f.read(64)
            if expected_sha256 is None and _not_torch_file(head):
                data = head
            else:
                data = head + f.read()
    file_sha256 = hashlib.sha256(data).hexdigest()
    if expected_sha256 is not None:
        got = file_sha256
        if got != expected_sha256:
            raise CheckpointError(f"weights file {where} is damaged or was replaced: its sha256 is {got[:16]}..., "
                                  f"the registry expects {expected_sha256[:16]}...; reinstall poselifter (or restore "
                                  "the file)")
    why, payload = _not_torch_file(data), None
    if not why:
        try:
            payload = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
        except Exception as exc:  # noqa: BLE001 - torch raises many types (struct.error, UnpicklingError, ...)
            why = _load_failure(exc)
    if why:
        raise CheckpointError(f"weights file {where} is corrupt or not a poselifter checkpoint ({why}); "
                              "give a .pt file written by poselifter train or a shipped model name")
    if isinstance(payload, dict) and payload.get("format") == RESUME_FORMAT:
        raise CheckpointError(f"{where} is a stopped training run's resume state, not a checkpoint: poselifter train "
                              f"--resume {where} goes on with that run; its weights so far are in the "
                              "NAME.interrupted.pt beside it")
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"{where} is not a poselifter checkpoint (missing format tag {FORMAT!r})")
    version = payload.get("version")
    if isinstance(version, int) and not isinstance(version, bool) and version > VERSION:
        raise CheckpointError(f"{where}: checkpoint version {version} is newer than this poselifter reads (1 and "
                              f"{VERSION}); upgrade poselifter")
    if version not in (1, VERSION) or isinstance(version, bool):
        raise CheckpointError(f"{where}: checkpoint version {str(version)[:20]!r} is not one poselifter writes (1 or "
                              f"{VERSION}): the file is damaged or was not written by poselifter; write it again "
                              "with poselifter train or Lifter.save")
    stored = payload.get("tensors_sha256")
    state, codec_state = payload.get("state_dict"), payload.get("codec")
    if stored is not None and not isinstance(stored, str):
        raise CheckpointError(f"{where}: tensors_sha256 must be a hex string, got {type(stored).__name__}; the file is "
                              "damaged")
    if stored is not None and isinstance(state, dict) and isinstance(codec_state, dict):  # (else named below)
        try:
            got = tensor_checksum(state, codec_state)
        except (TypeError, ValueError, RuntimeError) as exc:
            raise CheckpointError(f"{where}: its tensors cannot be read ({exc}); the file is damaged") from None
        if got != stored:
            raise CheckpointError(f"weights file {where} is damaged: its tensors no longer match the checksum "
                                  f"written with them (sha256 {got[:12]}..., written {stored[:12]}...), so it was "
                                  "changed after poselifter wrote it; restore it from a copy or train it again")
    if stored is None and expected_sha256 is None and file_sha256 not in _shipped_sha256s():
        warn_user(f"{where} has no checksum of its tensors (written before 2026-11-27), so a byte changed in it since "
                  "would go unnoticed; Lifter.from_checkpoint(path).save(path) writes it again with one")
    if version == 1:
        payload = _migrate_v1(payload, where)
    try:
        config = ModelConfig.from_dict(payload.get("model_config"))  # type: ignore[arg-type]
    except (PoseLifterError, TypeError) as exc:
        raise CheckpointError(f"{where}: bad model_config: {exc}") from None
    meta = payload.get("meta") or {}
    if not isinstance(meta, dict):
        raise CheckpointError(f"{where}: meta must be a dict, got {type(meta).__name__}")
    train_config = payload.get("train_config")
    if train_config is not None and not isinstance(train_config, dict):
        raise CheckpointError(f"{where}: train_config must be a dict, got {type(train_config).__name__}")
    state = payload.get("state_dict")
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise CheckpointError(f"{where}: state_dict must map names to tensors")
    with torch.device("meta"):  # the expected shapes, without allocating anything
        expected = {k: tuple(v.shape) for k, v in PoseLifterNet(config).state_dict().items()}
    missing, unexpected = sorted(set(expected) - set(state)), sorted(set(state) - set(expected))
    if missing or unexpected:
        raise CheckpointError(f"{where}: checkpoint tensors do not match its model config (missing {missing[:4]}, "
                              f"unexpected {unexpected[:4]})")
    wrong = [(k, tuple(state[k].shape), s) for k, s in expected.items() if tuple(state[k].shape) != s]
    if wrong:
        k, got, want = wrong[0]
        raise CheckpointError(f"{where}: tensor {k!r} has shape {got}, its model config needs {want}")
    try:
        codec_state = payload.get("codec")
        if not isinstance(codec_state, dict):
            raise ValueError("missing codec statistics")
        stats = {k: torch.as_tensor(v).double().numpy() for k, v in codec_state.items()}
        codec = PoseCodec.from_state_dict(config, stats)
    except (KeyError, TypeError, ValueError) as exc:
        raise CheckpointError(f"{where}: bad codec statistics: {exc}") from None
    # its random initialisation is overwritten below: loading never moves the caller's global generator (a seeded
    # run drew other batches and dropout after loading its --error-model or teacher, a seeded script other numbers)
    with torch.random.fork_rng(devices=[]):  # (float32 whatever torch's default dtype: a developer trial set float64
        net = PoseLifterNet(config).float()  # first, and the lift met "mat1 and mat2 must have the same dtype")
    derived = {k: v.clone() for k, v in net.state_dict().items() if k in ("in_perm", "in_sign")}
    net.load_state_dict({k: v.float() if v.is_floating_point() else v for k, v in state.items()}, strict=True)
    for k, v in derived.items():  # the mirror maps follow from the config and the codec, never from the file
        if not torch.equal(net.state_dict()[k], v):
            raise CheckpointError(f"{where}: tensor {k!r} is not the feature mirror of its model config")
    net.set_target_statistics(codec.target_mean, codec.target_std)
    for k, t in net.state_dict().items():
        if t.is_floating_point() and not torch.isfinite(t).all():
            raise CheckpointError(f"{where}: tensor {k!r} contains NaN/inf")
    net.eval()
    return Checkpoint(net=net, codec=codec, train_config=train_config, meta=dict(meta), sha256=file_sha256)
