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


def split_output(flat: torch.Tensor) -> NetworkOutput:
    """Split ``(B, 49)`` into the relative pose ``(B, 17, 3)`` (root row zero) and the depth ``(B,)``."""
    rel = flat[:, : NUM_OUTPUTS - 1].reshape(-1, NUM_JOINTS - 1, 3)
    rel = torch.cat([torch.zeros_like(rel[:, :1]), rel], dim=1)
    return NetworkOutput(relative=rel, depth=flat[:, -1])


def pack_targets(relative: torch.Tensor, depth: torch.Tensor) -> torch.Tensor:
    """Inverse of :func:`split_output`: ``(B, 17, 3)`` root-relative mm + ``(B,)`` depth -> ``(B, 49)``."""
    return torch.cat([relative[:, 1:].flatten(1), depth[:, None]], dim=1)
