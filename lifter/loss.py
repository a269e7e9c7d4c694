"""The PoseLifter training loss (spec §4, the authors' code form).

``L = sum_{j=1..16, c in xyz} |P_jc - P*_jc|  +  w_depth * |Z - Z*| * F0 / alpha``, averaged over the batch.

With ``pose_loss="joint"`` the pose term is instead the sum of the 16 joints' Euclidean errors in mm,
``sum_j ||P_j - P*_j||`` over joints 1..16 (16 times their mean error, which is 17 times the sample's MPJPE over
17 joints with the root exact: the metric itself) rather than the sum of their 48
coordinates' absolute errors (which is between 1 and sqrt(3) times it).

Units: the pose term is the plain sum of 48 absolute errors in **mm** (root-relative pose, camera
orientation); the depth term is the absolute error of the **canonical depth** ``Z F0 / alpha`` in mm at the
reference focal F0 = 1000 px (about 0.87x the true depth error on H36M), whatever the network's depth
parametrization (:class:`lifter.model.ModelConfig`): the codec's ``depth_loss_scale`` converts an error of
the depth output into it. For the paper's pixel-space canonical model the scale is 1 and this is exactly the
authors' loss.

Weighting: ``w_depth = 1`` (default). The paper's Eq. 7 writes ``lambda = 1e3`` but under its literal
units the code corresponds to ``1e-3`` (spec §4); we keep the code's form because its numbers are
the published ones.
"""

from __future__ import annotations

from typing import Any, Literal

import torch

from .model import NUM_OUTPUTS

JOINT_LOSS_EPS_MM2 = 1e-6
"""Added under the square root of the joint loss (mm^2), so that its gradient stays finite at a zero error."""


def poselifter_loss(pred: torch.Tensor, target: torch.Tensor, *, depth_weight: float = 1.0,
                    depth_scale: Any = 1.0, pose_loss: Literal["l1", "joint"] = "l1") -> torch.Tensor:
    """Loss for ``(B, 49)`` raw predictions and targets in mm (48 relative coordinates, joint-major x, y, z, then the
    depth output). ``depth_scale``: scalar or ``(B,)``, converts the depth output's error into canonical-depth mm.
    ``pose_loss``: ``"l1"`` (the paper's) or ``"joint"`` (the joints' Euclidean errors; module docstring)."""
    if pred.shape != target.shape or pred.ndim != 2 or pred.shape[1] != NUM_OUTPUTS:
        raise ValueError(f"pred and target must both be (B, {NUM_OUTPUTS}); got {tuple(pred.shape)} and "
                         f"{tuple(target.shape)}")
    diff = pred - target
    depth = diff[:, -1].abs() * depth_scale
    if pose_loss == "l1":
        pose = diff[:, :-1].abs().sum(dim=1)
    elif pose_loss == "joint":
        pose = (diff[:, :-1].reshape(len(diff), -1, 3).square().sum(dim=-1) + JOINT_LOSS_EPS_MM2).sqrt().sum(dim=1)
    else:
        raise ValueError(f"pose_loss must be 'l1' or 'joint', got {pose_loss!r}")
    return (pose + depth_weight * depth).mean()
