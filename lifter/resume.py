"""Resume files: the whole state of a one-process training run stopped with Ctrl-C at a step boundary, so that
``poselifter train --resume RUN.resume.pt`` goes on exactly where it stopped (:func:`lifter.train.train`'s
``resume``).

What a run needs to go on as if it had never stopped, all written by :func:`lifter.train.train` at the step it
stopped after: the live network's float32 weights (not the float16, averaged ones of the ``.interrupted.pt``
checkpoint), the AdamW moments, the weight average and its update count, the step, the minutes trained (the
wall-clock schedule counts them), the shared sample permutation and the position in it, the three random
generators' states (the permutation's, the batches' augmentation and noise draws, and torch's global one that
dropout draws from), the running loss, the learning curve so far, the codec's target statistics and the
resolved config. With a step-based schedule (no ``--max-minutes``) the resumed run's weights equal those of the
run never stopped, bit for bit, on the same machine and thread count.

The file is a plain dict of tensors and primitives, read with ``torch.load(weights_only=True)`` and checked
against a checksum of everything in it, written atomically.
"""

from __future__ import annotations

import hashlib
import io
import os
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Final

import torch

from ._checks import PoseLifterError
from .io import write_atomic

RESUME_FORMAT: Final[str] = "poselifter-resume"
RESUME_VERSION: Final[int] = 1


@dataclass(frozen=True)
class ResumeState:
    """A stopped run's state (module docstring). Tensors on the CPU; weights float32."""

    train_config: dict[str, Any]
    """The run's resolved config (:meth:`lifter.config.TrainConfig.to_dict`): the one it trained with, a fine-tune's
    model config and a bf16 run trained in float32 included."""
    step: int
    """Steps done: the run goes on with step ``step + 1``."""
    minutes: float
    """Minutes trained so far (the wall-clock schedule and the curve's minutes go on from there)."""
    samples: int
    """Training samples in the run's data; with :attr:`data_sha256`, the same data is checked on resume."""
    data_sha256: str
    """sha256 of the training tensors (GT 2D, intrinsics, 3D and, if used, the real detections)."""
    position: int
    """Where the next batch starts in :attr:`permutation`."""
    permutation: torch.Tensor
    """The shared sample order of the current epoch ``(samples,)`` int64."""
    rng: dict[str, torch.Tensor]
    """Generator states: ``"permutation"``, ``"batches"``, ``"torch"`` (global CPU) and, on CUDA, ``"cuda"``."""
    network: dict[str, torch.Tensor]
    """The live network's state (float32), not the weight average."""
    optimizer: dict[str, Any]
    """``torch.optim.AdamW.state_dict()``."""
    device: str
    """The device type the run trained on (``"cpu"``, ``"cuda"``): a resume goes on there."""
    average: dict[str, torch.Tensor] | None
    """The weight average's state (float32), or None without ``--ema-decay``."""
    average_updates: int
    codec: dict[str, torch.Tensor]
    """:meth:`lifter.codec.PoseCodec.state_dict` (the target statistics)."""
    running_loss: float | None
    curve: list[dict[str, float]]
    error_model: dict[str, Any] | None
    """The error-model fit the run reports (:attr:`lifter.train.TrainResult.error_model`,
    :meth:`lifter.noise.ErrorModel.to_dict`); None: no synthetic noise."""
    noise: dict[str, Any] | None
    """The error model the run's synthetic noise is drawn from (the fit, or its single-Gaussian baseline), used on
    resume whatever the config's path now holds; None: no synthetic noise."""
    meta: dict[str, Any]
    """The caller's own notes (the CLI: its ``--out``, the command, the --init and --teacher sha256)."""

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the state to ``path`` atomically (a temporary file in the same folder, then a rename)."""
        body = {f.name: getattr(self, f.name) for f in fields(self)}
        payload = {"format": RESUME_FORMAT, "version": RESUME_VERSION, "state": body, "sha256": _checksum(body)}
        buf = io.BytesIO()
        torch.save(payload, buf)
        return write_atomic(Path(path), buf.getbuffer())

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> ResumeState:
        """Read a resume file written by :meth:`save`, refusing anything else by name."""
        from .checkpoint import FORMAT as CHECKPOINT_FORMAT
        from .checkpoint import _load_failure, _not_torch_file

        path = Path(path)
        if not path.is_file():
            raise PoseLifterError(f"--resume {path}: no such file (a run stopped with Ctrl-C writes NAME.resume.pt "
                                  "beside its --out)")
        data = path.read_bytes()
        why, payload = _not_torch_file(data), None
        if not why:
            try:
                payload = torch.load(io.BytesIO(data), map_location="cpu", weights_only=True)
            except Exception as exc:  # noqa: BLE001 - torch raises many types
                why = _load_failure(exc)
        if why or not isinstance(payload, dict) or payload.get("format") != RESUME_FORMAT:
            hint = (" (a checkpoint: --init starts a new run from its weights)"
                    if isinstance(payload, dict) and payload.get("format") == CHECKPOINT_FORMAT else "")
            raise PoseLifterError(f"--resume {path}: not a poselifter resume file{f' ({why})' if why else ''}{hint}; "
                                  "give the NAME.resume.pt a run stopped with Ctrl-C wrote")
        if payload.get("version") != RESUME_VERSION:
            raise PoseLifterError(f"--resume {path}: resume format version {str(payload.get('version'))[:20]!r}, this "
                                  f"poselifter reads {RESUME_VERSION}: resume it with the poselifter that wrote it")
        body = payload.get("state")
        names = {f.name for f in fields(cls)}
        if not isinstance(body, dict) or set(body) != names:
            raise PoseLifterError(f"--resume {path}: the file is damaged (its state's fields are not a resume's)")
        try:
            same = payload.get("sha256") == _checksum(body)
        except (TypeError, ValueError, RuntimeError):
            same = False
        if not same:
            raise PoseLifterError(f"--resume {path}: the file is damaged: its contents no longer match the checksum "
                                  "written with them")
        return cls(**body)


def _checksum(obj: Any) -> str:
    """sha256 of everything in ``obj``: each tensor's place, dtype, shape and bytes, each primitive's place and
    repr, dict keys in sorted order."""
    h = hashlib.sha256()

    def walk(o: Any, where: str) -> None:
        if isinstance(o, torch.Tensor):
            hash_tensor(h, where, o)
        elif isinstance(o, dict):
            for k in sorted(o, key=repr):
                walk(o[k], f"{where}/{k!r}")
        elif isinstance(o, (list, tuple)):
            h.update(f"{where}:{type(o).__name__}{len(o)}".encode())
            for i, v in enumerate(o):
                walk(v, f"{where}[{i}]")
        else:
            h.update(f"{where}={o!r};".encode())

    from .checkpoint import hash_tensor  # (checkpoint imports this module's format tag)

    walk(obj, "")
    return h.hexdigest()


def data_fingerprint(tensors: dict[str, torch.Tensor]) -> str:
    """sha256 of a run's training tensors (:func:`lifter.train.samples_to_tensors`), by name."""
    return _checksum(tensors)
