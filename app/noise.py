"""The 2D error model used by the noise slider: :meth:`lifter.noise.ErrorModel.default`.

That is the Gaussian + uniform mixture fitted on the Stacked-Hourglass detections and shipped in
``assets/error_model/sh_mixture.json`` (issue "Realistic 2D inputs"); only when that file is missing
does the library fall back to its documented stand-in (:meth:`lifter.noise.ErrorModel.standin`, an
isotropic Gaussian). A present but unreadable file is an error, not a silent fallback. Anything with
the call signature ``model.sample(keypoints (..., 17, 2) px, *, level, rng) -> (..., 17, 2) px`` can be
passed to the app instead (tests). ``level`` 0 is clean, 1 is "as fitted", up to 3.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np


class ErrorModelLike(Protocol):
    def sample(self, keypoints: np.ndarray, *, level: float, rng: np.random.Generator) -> np.ndarray: ...


def default_error_model() -> ErrorModelLike:
    """``lifter.noise.ErrorModel.default()``: the shipped fit, or the library's stand-in when the file is
    missing."""
    from lifter.noise import ErrorModel

    return ErrorModel.default()


def model_name(model: object, *, max_chars: int = 110) -> str:
    """A short human-readable description of an error model."""
    text = str(getattr(model, "source", "") or getattr(model, "name", "") or type(model).__name__)
    text = text.split(":")[0].strip()
    return text if len(text) <= max_chars else text[: max_chars - 1] + "…"
