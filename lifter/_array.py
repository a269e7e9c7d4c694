"""The array namespace of an input: numpy or torch, through ``array_api_compat`` (so one implementation of each
convention serves numpy arrays and torch tensors). A cheap type check instead of ``array_namespace``'s general
inspection, which costs more than the arithmetic on a single pose."""

from __future__ import annotations

from types import ModuleType
from typing import Any, TypeVar

import array_api_compat.numpy as _np_ns
import array_api_compat.torch as _torch_ns
import numpy as np
import torch

ArrayT = TypeVar("ArrayT", np.ndarray, torch.Tensor)
"""A numpy array or a torch tensor; functions typed with it return the type they were given."""


def namespace(x: Any) -> ModuleType:
    """``array_api_compat``'s torch namespace for a tensor, its numpy namespace otherwise."""
    return _torch_ns if isinstance(x, torch.Tensor) else _np_ns
