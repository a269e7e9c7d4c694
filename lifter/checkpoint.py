"""Checkpoint files: a plain dict of tensors and primitives, always loaded with ``weights_only=True``.

Format (``format == "poselifter-checkpoint"``, ``version == 1``)::

    {"format": str, "version": int, "model_config": dict, "state_dict": {name: Tensor},
     "meta": dict (training recipe, data, metrics; primitives only)}

Weights may be stored in float16 to halve the file size; they are cast back to float32 on load.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import torch

from ._checks import CheckpointError
from .model import ModelConfig, PoseLifterNet
from .normalization import NORM_MODES

FORMAT = "poselifter-checkpoint"
VERSION = 1

CONFIG_CHOICES: dict[str, tuple[str, ...]] = {
    "mode": tuple(NORM_MODES),
    "scale_definition": ("paper", "repo"),
    "depth_target": ("canonical", "absolute"),
}
"""Allowed values of the string fields of ``model_config`` (:class:`lifter.model.ModelConfig`)."""


def _check_model_config(raw: Any, *, path: Path) -> dict[str, Any]:
    """``model_config`` as a dict whose string fields hold allowed values and whose sizes are sane."""
    if not isinstance(raw, dict):
        raise CheckpointError(f"{path}: model_config must be a dict, got {type(raw).__name__}")
    for name, allowed in CONFIG_CHOICES.items():
        if name in raw and raw[name] not in allowed:
            raise CheckpointError(f"{path}: model_config.{name} is {raw[name]!r}; expected one of {list(allowed)}")
    for name in ("width", "num_blocks"):
        if name in raw and (isinstance(raw[name], bool) or not isinstance(raw[name], int) or raw[name] < 1):
            raise CheckpointError(f"{path}: model_config.{name} must be an integer >= 1, got {raw[name]!r}")
    if "dropout" in raw:
        d = raw["dropout"]
        if isinstance(d, bool) or not isinstance(d, (int, float)) or not 0.0 <= d < 1.0:
            raise CheckpointError(f"{path}: model_config.dropout must be a number in [0, 1), got {d!r}")
    return dict(raw)


def save_checkpoint(
    path: str | os.PathLike[str], net: PoseLifterNet, *, meta: dict[str, Any] | None = None, half: bool = False
) -> Path:
    """Write ``net`` to ``path`` (parents created). ``half=True`` stores floating tensors as float16."""
    state = {k: (v.detach().to(torch.float16) if half and v.is_floating_point() else v.detach()).cpu().clone()
             for k, v in net.state_dict().items()}
    # Statistics that need full precision stay float32.
    for k in ("target_mean", "target_std"):
        state[k] = net.state_dict()[k].detach().cpu().float().clone()
    payload = {"format": FORMAT, "version": VERSION, "model_config": net.config.to_dict(), "state_dict": state,
               "meta": meta or {}}
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(path.suffix + ".tmp")
    torch.save(payload, tmp)
    os.replace(tmp, path)
    return path


def load_checkpoint(path: str | os.PathLike[str]) -> tuple[PoseLifterNet, dict[str, Any]]:
    """Load a network (eval mode, float32) and its metadata. Raises :class:`CheckpointError` with a
    message naming the problem for a missing, truncated, corrupt or foreign file."""
    path = Path(path)
    if path.is_dir():
        raise CheckpointError(f"weights file {path} is a directory, not a checkpoint file")
    if not path.is_file():
        raise CheckpointError(f"weights file not found: {path}")
    try:
        payload = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as exc:  # noqa: BLE001 - torch raises many types (struct.error, UnpicklingError, ...) for bad bytes
        raise CheckpointError(f"weights file {path} is corrupt or not a torch checkpoint: {exc}") from None
    if not isinstance(payload, dict) or payload.get("format") != FORMAT:
        raise CheckpointError(f"{path} is not a poselifter checkpoint (missing format tag {FORMAT!r})")
    if payload.get("version") != VERSION:
        raise CheckpointError(f"{path}: unsupported checkpoint version {payload.get('version')!r} (expected {VERSION})")
    if "model_config" not in payload:
        raise CheckpointError(f"{path}: checkpoint has no model_config")
    config_dict = _check_model_config(payload["model_config"], path=path)
    meta = payload.get("meta")
    if meta is None:
        meta = {}
    if not isinstance(meta, dict):
        raise CheckpointError(f"{path}: meta must be a dict, got {type(meta).__name__}")
    try:
        config = ModelConfig.from_dict(config_dict)
        net = PoseLifterNet(config)
        state = {k: v.float() if v.is_floating_point() else v for k, v in payload["state_dict"].items()}
        net.load_state_dict(state, strict=True)
    except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as exc:
        raise CheckpointError(f"{path}: checkpoint content does not match the model: {exc}") from None
    for name, t in net.state_dict().items():
        if t.is_floating_point() and not torch.isfinite(t).all():
            raise CheckpointError(f"{path}: tensor {name!r} contains NaN/inf")
    net.eval()
    return net, dict(meta)
