"""The 2D error model used by the noise slider.

Uses :class:`lifter.noise.ErrorModel` (the fitted Gaussian + uniform mixture of issue "Realistic 2D
inputs") when it is importable, else :class:`GaussianStandIn`, a plain isotropic Gaussian with the
same call signature: ``model.sample(keypoints (..., 17, 2) px, *, level, rng) -> (..., 17, 2) px``.
``level`` 0 is clean, 1 is "as fitted", up to 3.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class ErrorModelLike(Protocol):
    def sample(self, keypoints: np.ndarray, *, level: float, rng: np.random.Generator) -> np.ndarray: ...


class GaussianStandIn:
    """Isotropic Gaussian 2D noise, ``sigma = level * sigma_px`` per coordinate (px)."""

    name = "Gaussian stand-in"

    def __init__(self, *, sigma_px: float = 8.0) -> None:
        self.sigma_px = float(sigma_px)

    def sample(self, keypoints: np.ndarray, *, level: float, rng: np.random.Generator) -> np.ndarray:
        """Noisy copy of ``keypoints (..., 17, 2)`` px."""
        kp = np.asarray(keypoints, np.float64)
        if level <= 0:
            return kp.copy()
        return kp + rng.normal(0.0, self.sigma_px * float(level), kp.shape)


def default_error_model() -> ErrorModelLike:
    """``lifter.noise.ErrorModel.default()`` when available, else :class:`GaussianStandIn`."""
    try:
        from lifter.noise import ErrorModel  # type: ignore[import-not-found]

        return ErrorModel.default()
    except Exception:  # noqa: BLE001 - module not written yet, or no fitted parameters
        return GaussianStandIn()


def model_name(model: object) -> str:
    """A short human-readable description of an error model."""
    text = str(getattr(model, "source", "") or getattr(model, "name", "") or type(model).__name__)
    return text.split(":")[0]
