"""The PoseLifter normalization layer (paper Eq. 1-4).

Given 2D joints ``p_i`` in **image pixels** and the principal point ``c`` (px):

1. ``p'_i = p_i - c``                                   (subtract the principal point)
2. ``u = mean_i p'_i``                                   (2D location of the person, px)
3. ``sigma``: a single scalar scale (px), either
   * ``"paper"`` (default): the RMS radius ``sqrt(mean_i |p'_i - u|^2)`` (Eq. 4), or
   * ``"repo"``: the unbiased std (divisor J-1) of the radial distances ``|p'_i - u|``,
     as in the authors' code;
4. ``p_hat_i = (p'_i - u) / sigma``                      (zero mean, unit scale)
5. features = ``[p_hat (2J, joint-major x0,y0,x1,y1,...), u * 1e-3, sigma * 1e-3]``
   (location and scale in kilo-pixels, as in the authors' code).

Ablation modes select which of ``u`` and ``sigma`` are appended: ``"baseline"`` (2J = 34 features),
``"location"`` (36), ``"scale"`` (35), ``"both"`` (37, the PoseLifter default).

The functions work on torch tensors ``(B, J, 2)`` so that the layer is part of the network; use
:func:`normalize_keypoints_np` for numpy.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import torch

NormMode = Literal["baseline", "location", "scale", "both"]
ScaleDefinition = Literal["paper", "repo"]

NORM_MODES: tuple[str, ...] = ("baseline", "location", "scale", "both")
FEATURE_UNIT: float = 1e-3
"""Location and scale features are multiplied by this (px -> kilo-px)."""


def num_features(mode: NormMode, num_joints: int = 17) -> int:
    """Number of input features of the network for a mode: 2J (+2 location) (+1 scale)."""
    if mode not in NORM_MODES:
        raise ValueError(f"unknown normalization mode {mode!r}; expected one of {NORM_MODES}")
    return 2 * num_joints + (2 if mode in ("location", "both") else 0) + (1 if mode in ("scale", "both") else 0)


def location_and_scale(
    centred: torch.Tensor, *, scale_definition: ScaleDefinition = "paper"
) -> tuple[torch.Tensor, torch.Tensor]:
    """Location ``u`` ``(B, 2)`` and scale ``sigma`` ``(B,)`` of principal-point-centred keypoints ``(B, J, 2)``."""
    u = centred.mean(dim=-2)
    d = centred - u[..., None, :]
    if scale_definition == "paper":
        sigma = torch.sqrt((d**2).sum(-1).mean(-1))
    elif scale_definition == "repo":
        sigma = torch.linalg.vector_norm(d, dim=-1).std(dim=-1, unbiased=True)
    else:
        raise ValueError(f"unknown scale definition {scale_definition!r}; expected 'paper' or 'repo'")
    return u, sigma


def normalize_keypoints(
    keypoints: torch.Tensor,
    principal_point: torch.Tensor,
    *,
    mode: NormMode = "both",
    scale_definition: ScaleDefinition = "paper",
    eps: float = 1e-6,
) -> torch.Tensor:
    """Features ``(B, num_features(mode))`` from keypoints ``(B, J, 2)`` px and principal point ``(B, 2)`` px.

    ``sigma`` is clamped at ``eps`` px to keep the graph finite; the public API rejects degenerate
    (zero-scale) poses before they get here.
    """
    if keypoints.ndim != 3 or keypoints.shape[-1] != 2:
        raise ValueError(f"keypoints: expected shape (B, J, 2), got {tuple(keypoints.shape)}")
    if principal_point.shape != (keypoints.shape[0], 2):
        raise ValueError(f"principal_point: expected shape ({keypoints.shape[0]}, 2), got {tuple(principal_point.shape)}")
    centred = keypoints - principal_point[:, None, :]
    u, sigma = location_and_scale(centred, scale_definition=scale_definition)
    sigma = sigma.clamp_min(eps)
    pose = ((centred - u[:, None, :]) / sigma[:, None, None]).flatten(1)
    parts = [pose]
    if mode in ("location", "both"):
        parts.append(u * FEATURE_UNIT)
    if mode in ("scale", "both"):
        parts.append(sigma[:, None] * FEATURE_UNIT)
    if mode not in NORM_MODES:
        raise ValueError(f"unknown normalization mode {mode!r}; expected one of {NORM_MODES}")
    return torch.cat(parts, dim=1)


def normalize_keypoints_np(
    keypoints: np.ndarray,
    principal_point: np.ndarray,
    *,
    mode: NormMode = "both",
    scale_definition: ScaleDefinition = "paper",
) -> np.ndarray:
    """Numpy version of :func:`normalize_keypoints`, batched over leading dims: ``(..., J, 2)`` -> ``(..., F)``."""
    kp = np.asarray(keypoints, np.float64)
    lead = kp.shape[:-2]
    pp = np.broadcast_to(np.asarray(principal_point, np.float64), lead + (2,))
    out = normalize_keypoints(
        torch.from_numpy(kp.reshape(-1, *kp.shape[-2:])),
        torch.from_numpy(pp.reshape(-1, 2).copy()),
        mode=mode,
        scale_definition=scale_definition,
    )
    return out.numpy().reshape(*lead, -1)


def pose_scale_np(keypoints: np.ndarray, *, scale_definition: ScaleDefinition = "paper") -> np.ndarray:
    """The 2D scale ``sigma`` (px) of keypoints ``(..., J, 2)``; shape ``(...)``."""
    kp = np.asarray(keypoints, np.float64)
    d = kp - kp.mean(axis=-2, keepdims=True)
    if scale_definition == "paper":
        return np.sqrt((d**2).sum(-1).mean(-1))
    return np.linalg.norm(d, axis=-1).std(axis=-1, ddof=1)
