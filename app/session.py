"""Pure session transitions: what a tab's state becomes after a user action (no viser here).

Every function takes a :class:`~poselifter_app.core.SessionState` (never modified) and returns a new one, or
raises :class:`lifter.PoseLifterError` with a message for the user (the caller keeps the previous state).
:func:`apply_controls` is the one transition for the value controls: given the values the GUI holds *now*
(the last ones received), it returns the state they describe, so a burst of events ends on its last value
whatever order the callbacks run in.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from lifter import PoseLifterError
from lifter.skeleton import JOINT_NAMES, NUM_JOINTS

from .core import NOISE_MAX, SessionState, check_joint, clamp_focal, clamp_noise, focal_max
from .samples import Sample

INPUT_KINDS: tuple[str, ...] = ("gt", "detected")
MAX_CLOUD_SAMPLES: int = 1024


def input_options(sample: Sample) -> list[str]:
    """The 2D inputs ``sample`` offers: ground truth (``"gt"``) when it has exact 2D, ``"detected"`` when it has a
    detection (an upload's own 2D counts as one). Demo samples offer only ``["gt"]``."""
    opts = ["gt"] if sample.has_gt_2d else []
    if sample.detected_2d is not None or not sample.has_gt_2d:
        opts.append("detected")
    return opts


def for_sample(state: SessionState, sample: Sample, *, input_pref: str) -> tuple[SessionState, str | None]:
    """The state showing ``sample``: drags reset, focal to its camera's; model, noise, seed, cloud size and the
    analytic toggle kept. 2D input: ``input_pref`` when the sample has it, else the other one (with a note when
    a detection is missing); an upload (no ground-truth 2D) always uses its own 2D."""
    note = None
    opts = input_options(sample)
    kind = input_pref if input_pref in opts else opts[0]
    if input_pref == "detected" and kind != "detected" and state.sample.has_gt_2d:
        note = (f"no 2D detection for {sample.label}; using ground-truth 2D (the detection is used again where "
                "there is one)")
    new = SessionState(sample=sample, model=state.model, input_kind=kind, noise_level=state.noise_level,
                       seed=state.seed, cloud_samples=state.cloud_samples, analytic=state.analytic)
    return new, note


def with_input(state: SessionState, kind: str) -> SessionState:
    """2D input ``"gt"`` or ``"detected"`` (drags reset). Raises when the sample does not have that 2D."""
    if kind not in INPUT_KINDS:
        raise PoseLifterError(f"unknown 2D input {kind!r}; expected one of {list(INPUT_KINDS)}")
    if kind == state.input_kind:
        return state
    new = state.evolve(input_kind=kind, dragged=set())
    new.keypoints = new.base_keypoints().copy()  # raises: no detection / no ground truth
    return new


def with_model(state: SessionState, name: str, *, known: Callable[[str], object]) -> SessionState:
    """Lift with model ``name``; ``known(name)`` raises :class:`PoseLifterError` for unknown names."""
    if name == state.model:
        return state
    known(name)
    return state.evolve(model=name)


def with_focal(state: SessionState, value: float) -> tuple[SessionState, str | None]:
    """Focal length ``alpha`` (px). Out of the slider's range: clamped, with a note. Not finite: refused."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise PoseLifterError(f"focal length must be a number of px, got {value!r}") from None
    if not np.isfinite(v):
        raise PoseLifterError(f"focal length {value!r} is not a finite number; kept {state.focal_px:.0f} px")
    v, note = clamp_focal(v, hi=focal_max(state.sample))
    if v == state.focal_px or (note is None and v == round(state.focal_px)):  # (the slider shows whole px)
        return state, None
    return state.evolve(focal_px=v), note


def with_noise(state: SessionState, level: float) -> tuple[SessionState, str | None]:
    """Mixture-noise level in ``[0, NOISE_MAX]`` (clamped with a note; not finite: refused)."""
    try:
        v = float(level)
    except (TypeError, ValueError):
        raise PoseLifterError(f"noise level must be a number in [0, {NOISE_MAX:g}], got {level!r}") from None
    if not np.isfinite(v):
        raise PoseLifterError(f"noise level {level!r} is not a finite number; kept {state.noise_level:g}")
    v, note = clamp_noise(v)
    return (state if v == state.noise_level else state.evolve(noise_level=v)), note


def _integer(value: object, what: str) -> int:
    try:
        f = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise PoseLifterError(f"{what} must be an integer, got {value!r}") from None
    if not np.isfinite(f) or f != int(f):
        raise PoseLifterError(f"{what} must be an integer, got {value!r}")
    return int(f)


def with_seed(state: SessionState, seed: object) -> SessionState:
    s = _integer(seed, "seed")
    if s < 0:
        raise PoseLifterError(f"seed must be >= 0, got {s}")
    return state if s == state.seed else state.evolve(seed=s)


def with_cloud_samples(state: SessionState, n: object) -> SessionState:
    k = _integer(n, "cloud samples")
    if not 0 <= k <= MAX_CLOUD_SAMPLES:
        raise PoseLifterError(f"cloud samples must be in [0, {MAX_CLOUD_SAMPLES}], got {k}")
    return state if k == state.cloud_samples else state.evolve(cloud_samples=k)


def with_joint(state: SessionState, joint: int, uv: object) -> SessionState:
    """2D joint ``joint`` moved to pixel ``uv``. Refused (never clamped) far outside the image
    (:func:`poselifter_app.core.check_joint`)."""
    j = joint_index(joint)
    p = check_joint(uv, size=state.image_size)
    new = state.evolve()
    new.keypoints[j] = p
    new.dragged.add(j)
    return new


def with_keypoints(state: SessionState, keypoints: object) -> SessionState:
    """The whole current 2D pose ``(17, 2)`` px replaced (every joint checked like a drag)."""
    kp = np.asarray(keypoints, np.float64)
    if kp.shape != (NUM_JOINTS, 2) or not np.all(np.isfinite(kp)):
        raise PoseLifterError(f"keypoints must be finite with shape (17, 2) px, got {kp.shape}")
    for j in range(NUM_JOINTS):
        check_joint(kp[j], size=state.image_size)
    return state.evolve(keypoints=kp.copy())


def reset_joints(state: SessionState) -> SessionState:
    return state.evolve(keypoints=state.base_keypoints().copy(), dragged=set())


def joint_index(joint: object) -> int:
    """A joint index from an index or a joint name; raises for anything else (e.g. a crafted dropdown value)."""
    if isinstance(joint, str):
        if joint not in JOINT_NAMES:
            raise PoseLifterError(f"unknown joint {joint[:40]!r}; expected one of {list(JOINT_NAMES)}")
        return JOINT_NAMES.index(joint)
    try:
        j = int(joint)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise PoseLifterError(f"unknown joint {joint!r}") from None
    if not 0 <= j < NUM_JOINTS:
        raise PoseLifterError(f"joint index {j} out of range [0, {NUM_JOINTS})")
    return j


@dataclass(frozen=True)
class ControlValues:
    """The values the GUI's value controls hold (the last ones the tab sent)."""

    model: str
    input_kind: str
    focal_px: float
    noise_level: float
    seed: object
    cloud_samples: object
    analytic: bool


@dataclass(frozen=True)
class Rejection:
    """A control value that was refused or changed: the control (:class:`ControlValues` field name), the
    value it must show again, and the message for the user."""

    control: str
    value: object
    message: str
    refused: bool = True


def apply_controls(state: SessionState, values: ControlValues, *,
                   known_model: Callable[[str], object]) -> tuple[SessionState, list[Rejection]]:
    """The state the value controls describe. Each control is applied on its own: a refused value keeps that
    part of the previous state (and is reported, with the value its control must show again); a clamped value is
    applied clamped (reported with ``refused=False``)."""
    out: list[Rejection] = []
    st = state

    def attempt(control: str, fn: Callable[[SessionState], SessionState | tuple[SessionState, str | None]],
                keep: object) -> None:
        nonlocal st
        try:
            res = fn(st)
        except PoseLifterError as exc:
            out.append(Rejection(control, keep, str(exc)))
            return
        if isinstance(res, tuple):
            st, note = res
            if note:
                out.append(Rejection(control, getattr(st, control), note, refused=False))
        else:
            st = res

    attempt("model", lambda s: with_model(s, str(values.model), known=known_model), state.model)
    attempt("input_kind", lambda s: with_input(s, str(values.input_kind)), state.input_kind)
    attempt("focal_px", lambda s: with_focal(s, values.focal_px), state.focal_px)
    attempt("noise_level", lambda s: with_noise(s, values.noise_level), state.noise_level)
    attempt("seed", lambda s: with_seed(s, values.seed), state.seed)
    attempt("cloud_samples", lambda s: with_cloud_samples(s, values.cloud_samples), state.cloud_samples)
    if bool(values.analytic) != st.analytic:
        st = st.evolve(analytic=bool(values.analytic))
    return st, out


def same_lift(a: SessionState, b: SessionState) -> bool:
    """True when ``a`` and ``b`` give the same lift (nothing to recompute)."""
    return (a.sample is b.sample and a.model == b.model and a.input_kind == b.input_kind and a.focal_px == b.focal_px
            and a.noise_level == b.noise_level and a.seed == b.seed and a.cloud_samples == b.cloud_samples
            and a.analytic == b.analytic and np.array_equal(a.keypoints, b.keypoints))
