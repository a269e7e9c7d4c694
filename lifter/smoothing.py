"""Causal smoothing of lifted poses over time: the One-Euro filter (Casiez, Roussel & Vogel, CHI 2012).

The One-Euro filter is an exponential low-pass whose cutoff frequency rises with the signal's speed:
``fc = min_cutoff + beta * |dx/dt|`` (Hz), so a still pose is smoothed hard (jitter removed) and a fast one
lightly (little lag). It is causal: the output at time ``t`` uses only inputs up to ``t``, so it runs online
(video, a live camera). Speeds are per point: for ``(..., 3)`` arrays the norm of each point's velocity sets its
cutoff.

:class:`PoseSmoother` smooths what the lifter returns for one tracked person: the **root** (camera frame, mm;
its depth is what jitters most) and the **root-relative pose**, each with its own filter. ``strength`` scales
the smoothing: 0 = off (output = input), 1 = the default (:data:`ROOT_MIN_CUTOFF_HZ` etc., chosen on the SH
detections of S9 at 50 fps, see the README), 2 = twice as smooth (cutoffs halved), and so on.
"""

from __future__ import annotations

import math
from typing import Any, Final

import numpy as np

from ._checks import PoseLifterError, warn_user

ROOT_MIN_CUTOFF_HZ: Final[float] = 0.3
"""Root filter: cutoff (Hz) of a still root at strength 1."""
ROOT_BETA: Final[float] = 0.004
"""Root filter: extra cutoff (Hz) per mm/s of root speed at strength 1."""
POSE_MIN_CUTOFF_HZ: Final[float] = 1.5
"""Pose filter (root-relative joints): cutoff (Hz) of a still joint at strength 1."""
POSE_BETA: Final[float] = 0.01
"""Pose filter: extra cutoff (Hz) per mm/s of joint speed at strength 1."""
D_CUTOFF_HZ: Final[float] = 1.0
"""Cutoff (Hz) of the speed estimate that drives the adaptive cutoff."""


def _alpha(cutoff: np.ndarray | float, dt: np.ndarray | float) -> np.ndarray | float:
    tau = 1.0 / (2.0 * math.pi * np.asarray(cutoff))
    return 1.0 / (1.0 + tau / dt)


def _unknown_as_nan(x: Any) -> tuple[np.ndarray, np.ndarray]:
    """``x (..., D)`` as float64 with every point that has a non-finite coordinate all NaN (not known), and which
    points are known ``(..., 1)``."""
    x = np.asarray(x, np.float64)
    known = np.isfinite(x).all(-1, keepdims=True)
    return np.where(known, x, np.nan), known


class OneEuroFilter:
    """A One-Euro filter over arrays of points ``(..., D)``; the speed of each point (norm over the last axis)
    sets its cutoff. Call with the sample and its time (s); times must increase. ``reset()`` forgets the past.

    A point with a non-finite coordinate (NaN: not known in this sample) is NaN in the output and leaves that point's
    filter as it was; it goes on from its last known sample, over the time since then, when it is known again (a
    review: one NaN sample made every later output NaN)."""

    def __init__(self, *, min_cutoff: float, beta: float, d_cutoff: float = D_CUTOFF_HZ) -> None:
        for name, v in (("min_cutoff", min_cutoff), ("d_cutoff", d_cutoff)):
            if not (math.isfinite(v) and v > 0):
                raise PoseLifterError(f"{name} must be a positive frequency in Hz, got {v}")
        if not (math.isfinite(beta) and beta >= 0):
            raise PoseLifterError(f"beta must be >= 0, got {beta}")
        self.min_cutoff, self.beta, self.d_cutoff = float(min_cutoff), float(beta), float(d_cutoff)
        self.reset()

    def reset(self) -> None:
        self._x: np.ndarray | None = None  # (..., D) the filtered points; NaN where never known
        self._dx: np.ndarray | None = None  # (..., D) their filtered speeds
        self._tp: np.ndarray | None = None  # (..., 1) the time each point was last known (NaN: never)
        self._t: float | None = None  # the last sample's time

    def __call__(self, x: np.ndarray, t: float) -> np.ndarray:
        t = float(t)
        if not math.isfinite(t):
            raise PoseLifterError(f"smoothing: a sample's time must be a finite number of seconds, got {t}")
        x, known = _unknown_as_nan(x)
        if self._x is None or self._tp is None or self._dx is None or self._t is None or self._x.shape != x.shape:
            self._x, self._dx, self._t = x.copy(), np.zeros_like(x), t
            self._tp = np.where(known, t, np.nan)
            return x.copy()
        if not t > self._t:
            raise PoseLifterError(f"smoothing: sample times must increase, got {t} after {self._t}")
        had = np.isfinite(self._tp)
        go = known & had  # (points known now and before: filtered; known now only: taken as they are)
        dt = np.where(go, t - np.where(had, self._tp, t - 1.0), 1.0)
        with np.errstate(invalid="ignore"):
            dx = np.where(go, (x - self._x) / dt, 0.0)
            self._dx = np.where(go, self._dx + _alpha(self.d_cutoff, dt) * (dx - self._dx),
                                np.where(known, 0.0, self._dx))
            speed = np.linalg.norm(self._dx, axis=-1, keepdims=True)
            a = _alpha(self.min_cutoff + self.beta * speed, dt)
            self._x = np.where(go, self._x + a * (x - self._x), np.where(known, x, self._x))
        self._tp = np.where(known, t, self._tp)
        self._t = t
        return np.where(known, self._x, np.nan)


MAX_STRENGTH: Final[float] = 10.0
"""The strongest smoothing taken: the cutoffs are divided by the strength, and at 10 the root's is 0.03 Hz at rest
(a lag of seconds); beyond, the pose barely moves (a user trial: 1e9 froze every frame at the first, and 100
doubled the root error)."""


def check_strength(strength: float, *, name: str = "smoothing strength") -> None:
    """Refuse a smoothing strength outside [0, :data:`MAX_STRENGTH`] (or not a number), naming ``name``."""
    if not (math.isfinite(strength) and 0 <= strength <= MAX_STRENGTH):
        raise PoseLifterError(f"{name} must be from 0 to {MAX_STRENGTH:g} (0 = off, 1 = default, 2 = twice "
                              f"as smooth; the filter's cutoffs are divided by it, so above {MAX_STRENGTH:g} the pose "
                              f"barely moves), got {strength:g}")


class PoseSmoother:
    """Causal smoothing of one person's lifted root ``(3,)`` mm and root-relative pose ``(J, 3)`` mm
    (module docstring). ``strength`` from 0 to :data:`MAX_STRENGTH`: 0 = off; the cutoffs are divided by it."""

    def __init__(self, strength: float = 1.0) -> None:
        check_strength(strength)
        self.strength = float(strength)
        s = max(self.strength, 1e-9)
        self._root = OneEuroFilter(min_cutoff=ROOT_MIN_CUTOFF_HZ / s, beta=ROOT_BETA / s)
        self._pose = OneEuroFilter(min_cutoff=POSE_MIN_CUTOFF_HZ / s, beta=POSE_BETA / s)

    def __call__(self, root: np.ndarray, relative: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The smoothed ``(root, relative)`` at time ``t`` (s)."""
        if self.strength == 0:  # (off: the input, a point not known NaN, as the filter gives it)
            return _unknown_as_nan(root)[0], _unknown_as_nan(relative)[0]
        r = self._root(np.asarray(root, np.float64)[None], t)[0]
        rel = self._pose(relative, t)
        rel[..., 0, :] = 0.0  # the root row of a root-relative pose stays zero
        return r, rel

    def reset(self) -> None:
        self._root.reset()
        self._pose.reset()


def smooth_sequence(root: np.ndarray, relative: np.ndarray, times: np.ndarray, *,
                    strength: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Run a :class:`PoseSmoother` over a whole sequence: ``root (T, 3)``, ``relative (T, J, 3)`` mm at
    ``times (T,)`` s, increasing. Causal: row ``t`` of the output depends on rows ``<= t`` only. A NaN root or joint
    (not known in that frame) is NaN in the output, and the filter goes on from that point's last known frame."""
    root, relative = np.asarray(root, np.float64), np.asarray(relative, np.float64)
    times = np.asarray(times, np.float64)
    if (root.ndim != 2 or root.shape[1] != 3 or relative.ndim != 3 or relative.shape[2] != 3
            or relative.shape[:1] != root.shape[:1] or times.shape != root.shape[:1]):
        raise PoseLifterError(f"smooth_sequence: expected root (T, 3), relative (T, J, 3), times (T,), got "
                              f"{root.shape}, {relative.shape}, {times.shape}")
    if len(times) > 1 and not np.all(np.diff(times) > 0):
        i = int(np.flatnonzero(~(np.diff(times) > 0))[0])
        raise PoseLifterError(f"smooth_sequence: times must increase (seconds), got {times[i + 1]:g} after "
                              f"{times[i]:g} at rows {i}, {i + 1}")
    if len(times) > 2 and float(np.median(np.diff(times))) > 1.0:  # (the tracker says the same of its times)
        step = float(np.median(np.diff(times)))
        warn_user(f"smooth_sequence: the times are {step:g} apart (median), under one frame a second: if they are "
                  "milliseconds or frame numbers, give seconds (ms / 1000, frame / fps): the cutoffs are in Hz")
    sm = PoseSmoother(strength)
    out_r, out_rel = np.empty_like(root), np.empty_like(relative)
    for i in range(len(root)):
        out_r[i], out_rel[i] = sm(root[i], relative[i], float(times[i]))
    return out_r, out_rel


__all__ = ["MAX_STRENGTH", "OneEuroFilter", "PoseSmoother", "check_strength", "smooth_sequence"]
