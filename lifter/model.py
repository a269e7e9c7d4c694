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

from dataclasses import asdict, dataclass
from typing import Any, Literal

import numpy as np
import torch
from torch import nn

from .normalization import NormMode, ScaleDefinition, normalize_keypoints, num_features
from .skeleton import NUM_JOINTS

DepthTarget = Literal["canonical", "absolute"]
NUM_OUTPUTS: int = 3 * (NUM_JOINTS - 1) + 1
Array = torch.Tensor | np.ndarray


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


@dataclass(frozen=True)
class FoldedWeights:
    """An eval-mode :class:`PoseLifterNet` with its affine layers folded into the Linear layers.

    In eval mode BatchNorm is a per-channel affine map and Dropout is the identity, so a block
    ``x + L2(ReLU(BN2(L1(ReLU(BN1(x))))))`` becomes ``x + L2(ReLU(L1'(ReLU(s * x + c))))`` with ``BN2``
    folded into ``L1'``, and the output de-standardization ``mean + std * head(x)`` is folded into the
    head. Same outputs (to float32 rounding), fewer kernels: for one pose the network is bound by
    per-op overhead and weight traffic, not FLOPs (``benchmarks/bench_lift.py``).

    Weights are stored transposed, ``(in, out)``, for ``torch.addmm``. Build with :func:`fold_for_inference`.
    """

    config: ModelConfig
    stem: tuple[Array, Array]
    blocks: tuple[tuple[Array, ...], ...]
    """Per block ``(s, c, W1', b1', W2, b2)``."""
    head: tuple[Array, Array]

    def numpy(self) -> FoldedWeights:
        """The same weights as float32 numpy arrays (sharing memory with the tensors), for :func:`folded_mlp_np`."""
        def conv(group):
            return tuple(t.numpy() for t in group)

        return FoldedWeights(config=self.config, stem=conv(self.stem), blocks=tuple(conv(b) for b in self.blocks),
                             head=conv(self.head))


def _bn_affine(bn: nn.BatchNorm1d) -> tuple[torch.Tensor, torch.Tensor]:
    s = bn.weight / torch.sqrt(bn.running_var + bn.eps)
    return s, bn.bias - bn.running_mean * s


@torch.no_grad()
def fold_for_inference(net: PoseLifterNet) -> FoldedWeights:
    """Fold BatchNorm (running statistics) and the output de-standardization into the Linear layers.

    Only valid for the net in eval mode (the result never applies dropout or batch statistics).
    Raises ``TypeError`` for a net whose blocks are not plain float Linear/BatchNorm layers (e.g. quantized).
    """
    blocks = []
    for block in net.blocks:
        bn1, _, _, lin1, bn2, _, _, lin2 = block.body
        if not all(type(m) is nn.Linear for m in (lin1, lin2)) or not all(
                type(m) is nn.BatchNorm1d for m in (bn1, bn2)):
            raise TypeError("fold_for_inference needs float nn.Linear / nn.BatchNorm1d blocks")
        s1, c1 = _bn_affine(bn1)
        s2, c2 = _bn_affine(bn2)
        w1 = (lin1.weight * s2[:, None]).t().contiguous()
        b1 = lin1.bias * s2 + c2
        blocks.append((s1.clone(), c1.clone(), w1, b1, lin2.weight.t().contiguous(), lin2.bias.clone()))
    head_w = (net.head.weight * net.target_std[:, None]).t().contiguous()
    head_b = net.head.bias * net.target_std + net.target_mean
    return FoldedWeights(config=net.config, stem=(net.stem.weight.t().contiguous(), net.stem.bias.clone()),
                         blocks=tuple(blocks), head=(head_w, head_b))


def folded_forward_flat(weights: FoldedWeights, keypoints: torch.Tensor, principal_point: torch.Tensor) -> torch.Tensor:
    """:meth:`PoseLifterNet.forward_flat` (eval mode) on folded weights: ``(B, 17, 2)`` px, ``(B, 2)`` px -> ``(B, 49)``."""
    x = normalize_keypoints(keypoints, principal_point, mode=weights.config.mode,
                            scale_definition=weights.config.scale_definition)
    return folded_mlp(weights, x)


def folded_mlp(weights: FoldedWeights, features: torch.Tensor) -> torch.Tensor:
    """The folded stem, blocks and head on normalized features ``(B, F)`` -> ``(B, 49)`` outputs in mm."""
    h = torch.addmm(weights.stem[1], features, weights.stem[0])
    for s, c, w1, b1, w2, b2 in weights.blocks:
        y = torch.relu_(torch.addcmul(c, h, s))
        y = torch.relu_(torch.addmm(b1, y, w1))
        h = torch.addmm(b2, y, w2).add_(h)
    return torch.addmm(weights.head[1], h, weights.head[0])


def folded_mlp_np(weights: FoldedWeights, features: np.ndarray) -> np.ndarray:
    """:func:`folded_mlp` in numpy float32 (``weights`` from :meth:`FoldedWeights.numpy`).

    For a single pose numpy's BLAS (OpenBLAS) runs these matrix-vector products faster than torch's
    CPU kernels on the development machine (``benchmarks/bench_lift.py`` compares them);
    :class:`~lifter.api.Lifter` uses it for single poses only (``NUMPY_MAX_BATCH``).
    """
    h = features @ weights.stem[0] + weights.stem[1]
    for s, c, w1, b1, w2, b2 in weights.blocks:
        y = np.maximum(h * s + c, 0.0)
        y = np.maximum(y @ w1 + b1, 0.0)
        h = h + (y @ w2 + b2)
    return h @ weights.head[0] + weights.head[1]


def split_output(flat: torch.Tensor) -> NetworkOutput:
    """Split ``(B, 49)`` into the relative pose ``(B, 17, 3)`` (root row zero) and the depth ``(B,)``."""
    rel = flat[:, : NUM_OUTPUTS - 1].reshape(-1, NUM_JOINTS - 1, 3)
    rel = torch.cat([torch.zeros_like(rel[:, :1]), rel], dim=1)
    return NetworkOutput(relative=rel, depth=flat[:, -1])


def pack_targets(relative: torch.Tensor, depth: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`split_output`: ``(B, 17, 3)`` root-relative mm + ``(B,)`` depth -> ``(B, 49)``."""
    return torch.cat([relative[:, 1:].flatten(1), depth[:, None]], dim=1)
