"""The array namespace of an input: numpy or torch, through ``array_api_compat`` (so one implementation of each
convention serves numpy arrays and torch tensors). A cheap type check instead of ``array_namespace``'s general
inspection, which costs more than the arithmetic on a single pose.

torch is not imported here: a tensor can only exist once torch has been imported, so ``sys.modules`` is asked
for it. That keeps the numpy-only modules (:mod:`lifter.metrics`, :mod:`lifter.camera`, ...) free of torch.
"""

from __future__ import annotations

import sys
from types import ModuleType
from typing import TYPE_CHECKING, Any, TypeVar

import array_api_compat.numpy as _np_ns
import numpy as np

if TYPE_CHECKING:
    import torch

ArrayT = TypeVar("ArrayT", np.ndarray, "torch.Tensor")
"""A numpy array or a torch tensor; functions typed with it return the type they were given."""

_torch_ns: ModuleType | None = None


def namespace(x: Any) -> ModuleType:
    """``array_api_compat``'s torch namespace for a tensor, its numpy namespace otherwise."""
    global _torch_ns
    if isinstance(x, np.ndarray):
        return _np_ns
    torch_mod = sys.modules.get("torch")
    if torch_mod is not None and isinstance(x, torch_mod.Tensor):
        if _torch_ns is None:
            import array_api_compat.torch as ns  # only once a tensor is seen: torch is optional for numpy users

            _torch_ns = ns
        return _torch_ns
    return _np_ns
