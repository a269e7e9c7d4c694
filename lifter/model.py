"""The PoseLifter network: normalization layer -> residual MLP -> relative pose + canonical depth.

Architecture (spec §5): ``Linear(F -> W)`` stem (no activation), ``num_blocks`` pre-activation
residual blocks ``x + Linear(ReLU(Dropout(BN(Linear(ReLU(Dropout(BN(x))))))))``, and a
``Linear(W -> 49)`` head: 48 root-relative coordinates (joints 1..16, xyz, mm) and one depth.

Outputs are *standardized*: the head predicts ``(y - mean) / std`` per output, with ``mean`` and
``std`` stored as buffers computed from the training targets (including flipped copies). This
reparametrization does not change the loss (which stays in mm, see :mod:`lifter.loss`) but spares
the network from growing its outputs to ~1e3-1e4 over thousands of steps.
"""

from __future__ import annotations

import weakref
from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
import torch
from torch import nn

from .normalization import NormMode, ScaleDefinition, normalize_keypoints, num_features
from .skeleton import NUM_JOINTS

DepthTarget = Literal["canonical", "absolute"]
NUM_OUTPUTS: int = 3 * (NUM_JOINTS - 1) + 1


@dataclass(frozen=True)
class ModelConfig:
    """Hyper-parameters that define the network's shape and its input/output conventions."""

    width: int = 1024
    num_blocks: int = 2
    dropout: float = 0.25
    mode: NormMode = "both"
    scale_definition: ScaleDefinition = "paper"
    depth_target: DepthTarget = "canonical"
    """``"canonical"``: depth in mm at a 1000-px focal (PoseLifter); ``"absolute"``: root Z in mm."""

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "ModelConfig":
        known = {f for f in cls.__dataclass_fields__}
        unknown = set(d) - known
        if unknown:
            raise ValueError(f"unknown model config keys: {sorted(unknown)}")
        return cls(**d)


@dataclass(frozen=True)
class NetworkOutput:
    """Raw network output for a batch of B poses.

    relative: ``(B, 17, 3)`` mm, camera-frame orientation, root row zero.
    depth: ``(B,)`` mm; canonical (at F0 = 1000 px) or absolute depending on ``ModelConfig.depth_target``.
    """

    relative: torch.Tensor
    depth: torch.Tensor


class ResidualBlock(nn.Module):
    def __init__(self, width: int, dropout: float) -> None:
        super().__init__()
        self.body = nn.Sequential(
            nn.BatchNorm1d(width),
            nn.Dropout(dropout),
            nn.ReLU(inplace=True),
            nn.Linear(width, width),
            nn.BatchNorm1d(width),
            nn.Dropout(dropout),
            nn.ReLU(inplace=True),
            nn.Linear(width, width),
        )

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return x + self.body(x)


class PoseLifterNet(nn.Module):
    """2D keypoints (px) + principal point (px) -> root-relative 3D pose (mm) + root depth.

    Hidden linear layers use PyTorch's default (Kaiming-uniform) initialization; the head is
    initialized N(0, 1e-3) with zero bias, so that at step 0 the output is the training-target mean.
    """

    def __init__(self, config: ModelConfig = ModelConfig()) -> None:
        super().__init__()
        self.config = config
        self.stem = nn.Linear(num_features(config.mode), config.width)
        self.blocks = nn.Sequential(*[ResidualBlock(config.width, config.dropout) for _ in range(config.num_blocks)])
        self.head = nn.Linear(config.width, NUM_OUTPUTS)
        nn.init.normal_(self.head.weight, std=1e-3)
        nn.init.zeros_(self.head.bias)
        self.register_buffer("target_mean", torch.zeros(NUM_OUTPUTS))
        self.register_buffer("target_std", torch.ones(NUM_OUTPUTS))

    def set_target_statistics(self, mean: torch.Tensor, std: torch.Tensor) -> None:
        """Set the output de-standardization: ``y = mean + std * head(x)``; 49 values each."""
        self.target_mean.copy_(mean.to(self.target_mean))
        self.target_std.copy_(std.clamp_min(1e-3).to(self.target_std))

    def forward_flat(self, keypoints: torch.Tensor, principal_point: torch.Tensor) -> torch.Tensor:
        """``(B, 49)`` outputs in mm: 48 relative coordinates (joints 1..16) then the depth."""
        x = normalize_keypoints(
            keypoints, principal_point, mode=self.config.mode, scale_definition=self.config.scale_definition
        )
        x = self.head(self.blocks(self.stem(x)))
        return self.target_mean + self.target_std * x

    def forward(self, keypoints: torch.Tensor, principal_point: torch.Tensor) -> NetworkOutput:
        return split_output(self.forward_flat(keypoints, principal_point))


def _numpy_tensors(net: PoseLifterNet) -> tuple[list[torch.Tensor], list[float]] | None:
    """The tensors :func:`forward_flat_numpy` reads, in a fixed order: stem weight and bias; per block the
    first BatchNorm's weight, bias, running mean and variance, the first Linear's weight and bias, the same
    for the second pair; head weight and bias; target mean and std. Looked up through the modules' own
    dictionaries on every call (so replaced layers or tensors are always the current ones); and the
    BatchNorm epsilons, in the same order. None if a
    layer is not a plain float ``nn.Linear`` / ``nn.BatchNorm1d`` / ``nn.ReLU`` (or a block not a plain
    :class:`ResidualBlock`) or a BatchNorm or Dropout is in training mode."""
    mods = net._modules
    stem, blocks, head = mods.get("stem"), mods.get("blocks"), mods.get("head")
    if (type(stem) is not nn.Linear or type(head) is not nn.Linear or type(blocks) is not nn.Sequential
            or type(net).forward_flat is not PoseLifterNet.forward_flat or type(net).forward is not PoseLifterNet.forward):
        return None  # (a subclass that changes the forward pass runs as the module it is)
    out = [stem._parameters["weight"], stem._parameters["bias"]]
    eps = []
    for block in blocks._modules.values():
        body = block._modules.get("body")
        layers = list(body._modules.values()) if body is not None else []
        if len(layers) != 8:
            return None
        bn1, drop1, act1, lin1, bn2, drop2, act2, lin2 = layers
        if (type(block) is not ResidualBlock or type(bn1) is not nn.BatchNorm1d or type(bn2) is not nn.BatchNorm1d
                or type(lin1) is not nn.Linear or type(lin2) is not nn.Linear or type(act1) is not nn.ReLU
                or type(act2) is not nn.ReLU or bn1.training or bn2.training or drop1.training or drop2.training):
            return None
        for bn, lin in ((bn1, lin1), (bn2, lin2)):
            p, b = bn._parameters, bn._buffers
            out += [p["weight"], p["bias"], b["running_mean"], b["running_var"], lin._parameters["weight"],
                    lin._parameters["bias"]]
            eps.append(float(bn.eps))
    out += [head._parameters["weight"], head._parameters["bias"], net._buffers["target_mean"], net._buffers["target_std"]]
    return out, eps


_NUMPY_VIEWS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
"""net -> (key, numpy views of :func:`_numpy_tensors`); the views share memory with the tensors, so
in-place changes are seen without a rebuild, and the key (tensor identities and storage addresses)
catches replaced tensors or storage."""


def forward_flat_numpy(net: PoseLifterNet, features: np.ndarray) -> np.ndarray | None:
    """Eval-mode stem -> blocks -> head -> de-standardization in numpy, on normalized features ``(B, F)``
    float32 -> ``(B, 49)`` outputs in mm, as :meth:`PoseLifterNet.forward_flat` after the normalization.

    For one pose the network is a chain of matrix-vector products, which numpy's BLAS (OpenBLAS) runs
    faster than torch's CPU kernels on the development machine (``benchmarks/bench_lift.py`` times both).
    It reads the live weights through numpy views that share memory with the parameters (no copies), so
    any change to the net, in place or by replacing tensors or layers, is seen on the next call;
    BatchNorm is applied as the per-channel affine map of its running statistics. Returns None when a
    layer is not a plain float ``nn.Linear`` / ``nn.BatchNorm1d`` (e.g. quantized) or a BatchNorm or
    Dropout is in training mode: use the module then.
    """
    found = _numpy_tensors(net)
    if found is None:
        return None
    tensors, eps = found
    key = tuple((id(t), t.data_ptr()) for t in tensors)
    cached = _NUMPY_VIEWS.get(net)
    if cached is None or cached[0] != key:
        cached = (key, [t.detach().numpy() for t in tensors])
        _NUMPY_VIEWS[net] = cached  # one assignment: concurrent readers see the old or the new pair
    v = cached[1]
    h = features @ v[0].T + v[1]
    i, k = 2, 0
    while i < len(v) - 4:
        g1, be1, m1, var1, w1, b1, g2, be2, m2, var2, w2, b2 = v[i:i + 12]
        s1 = g1 / np.sqrt(var1 + eps[k])
        s2 = g2 / np.sqrt(var2 + eps[k + 1])
        y = np.maximum((h - m1) * s1 + be1, 0.0)
        y = np.maximum((y @ w1.T + b1 - m2) * s2 + be2, 0.0)
        h = h + (y @ w2.T + b2)
        i, k = i + 12, k + 2
    head_w, head_b, mean, std = v[-4:]
    return mean + std * (h @ head_w.T + head_b)


def split_output(flat: torch.Tensor) -> NetworkOutput:
    """Split ``(B, 49)`` into the relative pose ``(B, 17, 3)`` (root row zero) and the depth ``(B,)``."""
    rel = flat[:, : NUM_OUTPUTS - 1].reshape(-1, NUM_JOINTS - 1, 3)
    rel = torch.cat([torch.zeros_like(rel[:, :1]), rel], dim=1)
    return NetworkOutput(relative=rel, depth=flat[:, -1])


def pack_targets(relative: torch.Tensor, depth: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`split_output`: ``(B, 17, 3)`` root-relative mm + ``(B,)`` depth -> ``(B, 49)``."""
    return torch.cat([relative[:, 1:].flatten(1), depth[:, None]], dim=1)
