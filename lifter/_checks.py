"""Input validation shared by the public functions. Errors name the argument and the problem."""

from __future__ import annotations

import sys
from typing import Any

import numpy as np


class PoseLifterError(ValueError):
    """Raised for invalid user input (shape, non-finite values, degenerate poses, bad cameras)."""


class CheckpointError(PoseLifterError):
    """Raised when a weights file is missing, corrupt or of an unknown format."""


def _untorch(x: Any) -> Any:
    """A torch tensor (any device, with or without ``requires_grad``, any float dtype) as a CPU tensor numpy
    can read; anything else unchanged. torch is only consulted when the caller already imported it."""
    torch = sys.modules.get("torch")
    if torch is not None and isinstance(x, torch.Tensor):
        x = x.detach().cpu()
        if x.is_floating_point():
            x = x.double()  # float16 / bfloat16 -> float64 (numpy has no bfloat16)
    return x


def _real_array(x: Any, *, name: str, what: str) -> np.ndarray:
    """``x`` as float64, refusing complex numbers, booleans and anything non-numeric with a clear message."""
    x = _untorch(x)
    try:
        raw = np.asarray(x)
    except (TypeError, ValueError, RuntimeError) as exc:
        raise PoseLifterError(f"{name}: could not convert to {what} ({exc})") from None
    if np.iscomplexobj(raw):
        raise PoseLifterError(f"{name}: complex numbers are not pixel coordinates; pass real values")
    if raw.dtype == bool:
        raise PoseLifterError(f"{name}: booleans are not pixel coordinates; pass numbers")
    if raw.dtype.kind in "USO" and any(isinstance(v, (str, bytes)) for v in np.ravel(raw)[:1000]):
        raise PoseLifterError(f"{name}: strings are not numbers; pass numbers (e.g. float(value))")
    try:
        return np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError, RuntimeError) as exc:
        raise PoseLifterError(f"{name}: could not convert to {what} ({exc})") from None


def as_points(x: Any, *, name: str, dim: int, num_joints: int | None = 17) -> np.ndarray:
    """Return ``x`` as a float64 array of shape ``(..., num_joints, dim)`` or raise a clear error.
    Torch tensors are accepted (detached and copied to the CPU)."""
    arr = _real_array(x, name=name, what="a numeric array")
    expected = f"(..., {num_joints if num_joints is not None else 'J'}, {dim})"
    if arr.ndim < 2 or arr.shape[-1] != dim or (num_joints is not None and arr.shape[-2] != num_joints):
        hint = ""
        if dim == 2 and arr.ndim >= 2 and arr.shape[-1] == 3:
            hint = f"; if the third column is a detector confidence, pass {name}[..., :2]"
        raise PoseLifterError(f"{name}: expected shape {expected}, got {tuple(arr.shape)}{hint}")
    check_finite(arr, name=name)
    return arr


def check_finite(arr: np.ndarray, *, name: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise PoseLifterError(f"{name}: contains {bad} NaN/inf value(s); all values must be finite")


def as_pair(x: Any, *, name: str, positive: bool = False, scalar: bool = False) -> np.ndarray:
    """Return a 2-vector (optionally batched, shape ``(..., 2)``) as float64 ``(..., 2)``. scalar: a scalar (or a
    last axis of 1) means the same value twice (a focal length ``fx = fy``); otherwise it is refused (a principal
    point or image size needs both coordinates)."""
    arr = _real_array(x, name=name, what="a number or pair" if scalar else "a pair")
    if scalar and arr.ndim == 0:
        arr = np.stack([arr, arr])
    elif scalar and arr.shape[-1] == 1:
        arr = np.concatenate([arr, arr], axis=-1)
    if arr.ndim == 0 or arr.shape[-1] != 2:
        expected = "a scalar or shape (..., 2)" if scalar else "a pair (x, y) or shape (..., 2)"
        raise PoseLifterError(f"{name}: expected {expected}, got {arr.tolist() if arr.size <= 4 else tuple(arr.shape)}")
    check_finite(arr, name=name)
    if positive and np.any(arr <= 0):
        raise PoseLifterError(f"{name}: must be > 0, got {arr.tolist() if arr.size <= 8 else 'non-positive values'}")
    return arr
