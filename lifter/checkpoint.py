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

FORMAT = "poselifter-checkpoint"
VERSION = 1


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
    try:
        config = ModelConfig.from_dict(dict(payload["model_config"]))
        net = PoseLifterNet(config)
        state = {k: v.float() if v.is_floating_point() else v for k, v in payload["state_dict"].items()}
        net.load_state_dict(state, strict=True)
    except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as exc:
        raise CheckpointError(f"{path}: checkpoint content does not match the model: {exc}") from None
    for name, t in net.state_dict().items():
        if t.is_floating_point() and not torch.isfinite(t).all():
            raise CheckpointError(f"{path}: tensor {name!r} contains NaN/inf")
    net.eval()
    return net, dict(payload.get("meta", {}))
