"""The PoseLifter normalization layer (paper Eq. 1-4), numpy or torch.

Given 2D joints ``p_i`` (image px) and the principal point ``c`` (px):

1. ``p'_i = p_i - c``                                   (subtract the principal point; :func:`normalize_keypoints`)
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

Which pixels the layer reads is the codec's choice (:mod:`lifter.codec`): the image's own (the paper)
or the reference camera's (:func:`lifter.camera.to_reference_camera`). Every function here is batched
over leading dimensions and works on numpy arrays and torch tensors alike.
"""

from __future__ import annotations

from typing import Any, Final, Literal

import numpy as np

from ._array import ArrayT
from ._array import namespace as array_namespace
from .skeleton import NUM_JOINTS, mirror

NormMode = Literal["baseline", "location", "scale", "both"]
ScaleDefinition = Literal["paper", "repo"]

NORM_MODES: Final[tuple[str, ...]] = ("baseline", "location", "scale", "both")
SCALE_DEFINITIONS: Final[tuple[str, ...]] = ("paper", "repo")
FEATURE_UNIT: Final[float] = 1e-3
"""Location and scale features are multiplied by this (px -> kilo-px)."""



def num_features(mode: NormMode, num_joints: int = 17) -> int:
    """Number of features of the layer for a mode: 2J (+2 location) (+1 scale)."""
    if mode not in NORM_MODES:
        raise ValueError(f"unknown normalization mode {mode!r}; expected one of {NORM_MODES}")
    return 2 * num_joints + (2 if mode in ("location", "both") else 0) + (1 if mode in ("scale", "both") else 0)


def location_and_scale(centred: ArrayT, *, scale_definition: ScaleDefinition = "paper") -> tuple[ArrayT, ArrayT]:
    """Location ``u`` ``(..., 2)`` and scale ``sigma`` ``(...)`` (px) of keypoints ``(..., J, 2)``.

    The one definition of the 2D scale: the normalization layer, the error model's scale rule and the
    API's degenerate-pose check all use it."""
    xp = array_namespace(centred)
    u = xp.mean(centred, axis=-2)
    d = centred - u[..., None, :]  # type: ignore[index, operator]
    r2 = xp.sum(d * d, axis=-1)
    if scale_definition == "paper":
        sigma = xp.sqrt(xp.mean(r2, axis=-1))
    elif scale_definition == "repo":
        sigma = xp.std(xp.sqrt(r2), axis=-1, correction=1)
    else:
        raise ValueError(f"unknown scale definition {scale_definition!r}; expected one of {SCALE_DEFINITIONS}")
    return u, sigma


def pose_scale(keypoints: ArrayT, *, scale_definition: ScaleDefinition = "paper") -> ArrayT:
    """The 2D scale ``sigma`` (px) of keypoints ``(..., J, 2)``; shape ``(...)``. Translation invariant."""
    return location_and_scale(keypoints, scale_definition=scale_definition)[1]


def pose_features(centred: ArrayT, *, mode: NormMode = "both", scale_definition: ScaleDefinition = "paper",
                  eps: float = 1e-6, location_scale: tuple[ArrayT, ArrayT] | None = None) -> ArrayT:
    """Features ``(..., num_features(mode))`` from keypoints ``(..., J, 2)`` px relative to the principal point.

    ``sigma`` is clamped at ``eps`` px to keep the result finite; the public API rejects degenerate
    (zero-scale) poses before they get here. ``location_scale``: :func:`location_and_scale` of ``centred``
    when the caller has it already (the codec needs sigma too).
    """
    if centred.ndim < 2 or centred.shape[-1] != 2:  # type: ignore[attr-defined]
        raise ValueError(f"keypoints: expected shape (..., J, 2), got {tuple(centred.shape)}")  # type: ignore[attr-defined]
    if mode not in NORM_MODES:
        raise ValueError(f"unknown normalization mode {mode!r}; expected one of {NORM_MODES}")
    xp = array_namespace(centred)
    u, sigma = location_scale or location_and_scale(centred, scale_definition=scale_definition)
    sigma = sigma.clip(min=eps)  # (the array's own method: numpy and torch alike, without a wrapper)
    pose = (centred - u[..., None, :]) / sigma[..., None, None]  # type: ignore[index, operator]
    parts = [xp.reshape(pose, (*pose.shape[:-2], pose.shape[-2] * 2))]
    if mode in ("location", "both"):
        parts.append(u * FEATURE_UNIT)
    if mode in ("scale", "both"):
        parts.append(sigma[..., None] * FEATURE_UNIT)  # type: ignore[index]
    return xp.concat(parts, axis=-1)


def feature_mirror(mode: NormMode = "both", *, num_extra: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The mirror image (:func:`lifter.skeleton.mirror` of the 2D about the principal point) in feature space:
    ``pose_features(mirror(p)) == pose_features(p)[..., perm] * sign``, a signed permutation ``(F,)`` int64 and
    ``(F,)`` float32 (+-1). Mirroring negates the location's x and keeps the scale (both scale definitions are
    radial); ``num_extra`` features appended after the layer's (the source flag) are kept."""
    probe = mirror(np.arange(1, 2 * NUM_JOINTS + 1, dtype=np.float64).reshape(NUM_JOINTS, 2)).reshape(-1)
    perm, sign = [int(abs(v)) - 1 for v in probe], [1.0 if v > 0 else -1.0 for v in probe]
    k = 2 * NUM_JOINTS
    if mode in ("location", "both"):
        perm += [k, k + 1]
        sign += [-1.0, 1.0]
        k += 2
    if mode in ("scale", "both"):
        perm.append(k)
        sign.append(1.0)
        k += 1
    perm += list(range(k, k + num_extra))
    sign += [1.0] * num_extra
    return np.asarray(perm, np.int64), np.asarray(sign, np.float32)


def normalize_keypoints(keypoints: ArrayT, principal_point: Any, *, mode: NormMode = "both",
                        scale_definition: ScaleDefinition = "paper", eps: float = 1e-6) -> ArrayT:
    """The paper's layer on image pixels: :func:`pose_features` of ``keypoints - principal_point``.
    ``keypoints`` ``(..., J, 2)`` px and ``principal_point`` ``(..., 2)`` px of the same array type."""
    if not hasattr(principal_point, "shape"):
        principal_point = array_namespace(keypoints).asarray(principal_point, dtype=keypoints.dtype)  # type: ignore[attr-defined]
    if tuple(principal_point.shape[-1:]) != (2,):
        raise ValueError(f"principal_point: expected shape (..., 2), got {tuple(principal_point.shape)}")
    return pose_features(keypoints - principal_point[..., None, :], mode=mode, scale_definition=scale_definition,
                         eps=eps)
