"""Analytic weak-perspective root (Mehta et al. 3DV'17; spec §9): the baseline for the learned root.

Given the 2D pose ``k_i = p_i - c`` (px), a root-relative 3D pose ``P_i`` (mm) and the focal
length, weak perspective says ``k_i - mean(k) ~ (alpha / Z) (P_i^xy - mean(P^xy))`` with ``Z`` the
body's mean depth. Matching the spreads gives ``Z``:

* ``method="rms"`` (default): ``s = sqrt(sum |P^xy - mean|^2 / sum |k - mean|^2)`` mm/px, ``Z = alpha s``;
* ``method="lstsq"``: least-squares ``m`` in ``k - mean(k) = m (P^xy - mean)``, ``Z = alpha / m``.

``Z`` is the depth of the joints' mean; the root depth is ``Z - mean(P_z)`` (``mean_depth_correction``,
default on; PoseLifter's Table 4 used Z directly). X and Y back-project the 2D root, as PoseLifter did.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np

from ._checks import as_pair, as_points
from .camera import backproject, focal_alpha


def analytic_root(
    keypoints_2d: np.ndarray,
    relative_3d: np.ndarray,
    *,
    focal: Any,
    principal_point: Any,
    method: Literal["rms", "lstsq"] = "rms",
    mean_depth_correction: bool = True,
) -> np.ndarray:
    """Root ``(..., 3)`` mm in the camera frame from 2D ``(..., 17, 2)`` px and relative 3D ``(..., 17, 3)`` mm."""
    kp = as_points(keypoints_2d, name="keypoints_2d", dim=2)
    rel = as_points(relative_3d, name="relative_3d", dim=3)
    c = as_pair(principal_point, name="principal_point")
    k = kp - c[..., None, :]
    dk = k - k.mean(-2, keepdims=True)
    dP = rel[..., :2] - rel[..., :2].mean(-2, keepdims=True)
    alpha = focal_alpha(focal)
    if method == "rms":
        s = np.sqrt((dP**2).sum((-1, -2)) / np.maximum((dk**2).sum((-1, -2)), 1e-12))
        z = alpha * s
    elif method == "lstsq":
        m = (dk * dP).sum((-1, -2)) / np.maximum((dP**2).sum((-1, -2)), 1e-12)
        z = alpha / np.maximum(m, 1e-12)
    else:
        raise ValueError(f"unknown method {method!r}; expected 'rms' or 'lstsq'")
    if mean_depth_correction:
        z = z - rel[..., 2].mean(-1)
    return backproject(kp[..., 0, :], z, focal=focal, principal_point=principal_point)
