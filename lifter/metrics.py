"""Evaluation metrics (spec §8), numpy, batched over leading dimensions. All distances in mm.

* MPJPE: mean over all 17 joints of the Euclidean error of root-relative poses (the root counts
  as a joint with zero error, as in the authors' and Martinez's code).
* PA-MPJPE: MPJPE after a similarity Procrustes alignment (rotation, uniform scale, translation).
  Default: the least-squares optimal alignment with the reflection fix; ``variant="repo"`` uses the
  authors' RMS-ratio scale and no reflection fix.
* MRPE: mean Euclidean error of the absolute root; MRPE-X/Y/Z are mean absolute per-axis errors.
* 3DPCK@150mm: fraction of joints with error < 150 mm (strict), on root-relative poses, over the 14
  joints of the standard 3DPCK protocol (pelvis, spine and neck/nose excluded, spec §8);
  AUC: mean PCK over thresholds 0, 5, ..., 150 mm (x 100 to report as %).
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from ._checks import PoseLifterError


def _check_pair(pred: np.ndarray, gt: np.ndarray, name: str) -> tuple[np.ndarray, np.ndarray]:
    pred = np.asarray(pred, np.float64)
    gt = np.asarray(gt, np.float64)
    if pred.shape != gt.shape:
        raise PoseLifterError(f"{name}: pred and gt must have the same shape (..., J, 3); got {pred.shape} and "
                              f"{gt.shape}")
    if pred.ndim < 2 or pred.shape[-1] != 3:
        raise PoseLifterError(f"{name}: expected 3D poses (..., J, 3) in mm, got shape {pred.shape}" + (
            " (2D keypoints? the metrics compare 3D poses)" if pred.shape[-1:] == (2,) else ""))
    for arr, which in ((pred, "pred"), (gt, "gt")):
        if not np.all(np.isfinite(arr)):
            raise PoseLifterError(f"{name}: {which} contains {int(arr.size - np.isfinite(arr).sum())} NaN/inf "
                                  "value(s); the metrics need finite poses")
    return pred, gt


def joint_errors(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Per-joint Euclidean errors ``(..., J)`` of root-relative poses (both re-centred at joint 0)."""
    pred, gt = _check_pair(pred, gt, "joint_errors")
    return _joint_errors(pred, gt)


def _joint_errors(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    return np.linalg.norm((pred - pred[..., :1, :]) - (gt - gt[..., :1, :]), axis=-1)


def mpjpe(pred: np.ndarray, gt: np.ndarray) -> np.ndarray:
    """Per-pose MPJPE ``(...)`` mm after aligning the roots (joint 0)."""
    pred, gt = _check_pair(pred, gt, "mpjpe")
    return _joint_errors(pred, gt).mean(axis=-1)


def procrustes_align(
    pred: np.ndarray, gt: np.ndarray, *, variant: Literal["standard", "repo"] = "standard"
) -> np.ndarray:
    """``pred`` ``(..., J, 3)`` aligned to ``gt`` by the best similarity transform."""
    pred, gt = _check_pair(pred, gt, "procrustes_align")
    return _procrustes_align(pred, gt, variant=variant)


def best_rotation(X: np.ndarray, Y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The rotations ``R (..., 3, 3)`` (no reflection) minimizing ``sum_j |R X_j - Y_j|^2`` for the vectors
    ``X, Y (..., J, 3)`` (Kabsch: SVD of the cross-covariance ``sum_j Y_j X_j^T``), and ``trace(R M) (...)``, the
    numerator of the best scale (:func:`procrustes_align`)."""
    M = np.einsum("...ji,...jk->...ik", Y, X)
    U, S, Vt = np.linalg.svd(M)
    D = np.ones(S.shape)
    D[..., -1] = np.sign(np.linalg.det(U @ Vt))
    return U @ (D[..., :, None] * Vt), (S * D).sum(-1)


def _procrustes_align(pred: np.ndarray, gt: np.ndarray, *, variant: str) -> np.ndarray:
    mu_p = pred.mean(axis=-2, keepdims=True)
    mu_g = gt.mean(axis=-2, keepdims=True)
    X = pred - mu_p
    Y = gt - mu_g
    if variant == "standard":
        R, trace = best_rotation(X, Y)
        scale = trace / np.maximum((X**2).sum((-1, -2)), 1e-12)
    elif variant == "repo":
        U, _, Vt = np.linalg.svd(np.einsum("...ji,...jk->...ik", Y, X))
        R = U @ Vt
        scale = np.sqrt((Y**2).sum((-1, -2)) / np.maximum((X**2).sum((-1, -2)), 1e-12))
    else:
        raise PoseLifterError(f"unknown Procrustes variant {variant!r}; use 'standard' or 'repo'")
    return scale[..., None, None] * np.einsum("...ik,...jk->...ji", R, X) + mu_g


def pa_mpjpe(pred: np.ndarray, gt: np.ndarray, *, variant: Literal["standard", "repo"] = "standard") -> np.ndarray:
    """Per-pose PA-MPJPE ``(...)`` mm."""
    pred, gt = _check_pair(pred, gt, "pa_mpjpe")
    aligned = _procrustes_align(pred, gt, variant=variant)
    return np.linalg.norm(aligned - gt, axis=-1).mean(axis=-1)


def root_errors(pred_root: np.ndarray, gt_root: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(norm (...), abs per-axis (..., 3))`` root errors in mm."""
    pred_root = np.asarray(pred_root, np.float64)
    gt_root = np.asarray(gt_root, np.float64)
    if pred_root.shape != gt_root.shape or pred_root.shape[-1] != 3:
        raise PoseLifterError(f"root_errors: expected matching (..., 3) shapes, got {pred_root.shape}, {gt_root.shape}")
    d = pred_root - gt_root
    return np.linalg.norm(d, axis=-1), np.abs(d)


PCK_THRESHOLD_MM: float = 150.0
PCK_JOINTS: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 8, 10, 11, 12, 13, 14, 15, 16)
"""The 14 joints scored by 3DPCK / AUC: all but pelvis (0), spine (7) and neck/nose (9)."""
AUC_THRESHOLDS_MM: np.ndarray = np.arange(0.0, 151.0, 5.0)


def pck(pred: np.ndarray, gt: np.ndarray, *, threshold: float = PCK_THRESHOLD_MM,
        joints: tuple[int, ...] | None = PCK_JOINTS) -> np.ndarray:
    """Per-pose fraction ``(...)`` of ``joints`` (None: all) whose root-relative error is < ``threshold`` mm."""
    e = joint_errors(pred, gt)
    if joints is not None:
        e = e[..., list(joints)]
    return (e < threshold).mean(axis=-1)


def pck_curve(pred: np.ndarray, gt: np.ndarray, thresholds: np.ndarray = AUC_THRESHOLDS_MM, *,
              joints: tuple[int, ...] | None = PCK_JOINTS) -> np.ndarray:
    """PCK over all poses and ``joints`` at each threshold ``(T,)``."""
    e = joint_errors(pred, gt)
    if joints is not None:
        e = e[..., list(joints)]
    e = e.reshape(-1)
    return (e[None, :] < np.asarray(thresholds)[:, None]).mean(axis=1)


def auc(pred: np.ndarray, gt: np.ndarray) -> float:
    """Area under the PCK curve over 0:5:150 mm, as a fraction (x 100 for %): the mean of :func:`pck` at the 31
    thresholds, 0 included, as in the MPI-INF-3DHP evaluation. PCK counts errors strictly below a threshold, so the
    0 mm threshold counts nothing and a perfect prediction scores 30 / 31 = 0.968."""
    return float(pck_curve(pred, gt).mean())
