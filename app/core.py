"""Headless per-tab state and the computation behind one redraw (no viser here).

Units and frames: 2D in **pixels** of the sample's image; 3D in **millimetres** in the OpenCV camera
frame (+x right, +y down, +z forward) of the sample's camera. The viewer converts to metres.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field

import numpy as np

from lifter import Lifter, PoseLifterError, analytic_root, available_models
from lifter.metrics import mpjpe, pa_mpjpe
from lifter.skeleton import NUM_JOINTS

from .noise import ErrorModelLike
from .samples import Sample

FOCAL_MIN_PX: float = 100.0
FOCAL_MAX_PX: float = 6000.0
"""Range of the focal-length slider (px, the geometric mean ``alpha = sqrt(fx fy)``)."""
NOISE_MAX: float = 3.0
"""Noise level: 0 = clean, 1 = as fitted, up to 3 (exaggerated)."""
CLOUD_SAMPLES: int = 64
"""Default number of noisy 2D draws lifted for the uncertainty cloud."""
DEFAULT_SEED: int = 0
DRAG_MARGIN: float = 1.0
"""A dragged joint is clamped to the image grown by this fraction of its size on every side."""


class LifterPool:
    """Lazily loaded, shared (read-only) :class:`Lifter` objects by model name."""

    def __init__(self, names: list[str] | None = None) -> None:
        self._lock = threading.Lock()
        self._cache: dict[str, Lifter] = {}
        self.error: str | None = None
        try:
            self.names: list[str] = list(names) if names is not None else available_models()
        except PoseLifterError as exc:
            self.names = []
            self.error = str(exc)

    def get(self, name: str) -> Lifter:
        """The model ``name`` (loaded on first use); raises :class:`PoseLifterError` if unknown."""
        with self._lock:
            if name not in self._cache:
                if name not in self.names:
                    raise PoseLifterError(f"unknown model {name!r}; available: {self.names}")
                self._cache[name] = Lifter.from_pretrained(name)
            return self._cache[name]

    def add(self, name: str, lifter: Lifter) -> None:
        """Register an already-built lifter (tests, notebooks)."""
        with self._lock:
            self._cache[name] = lifter
            if name not in self.names:
                self.names.append(name)


@dataclass
class SessionState:
    """Everything one browser tab controls. Focal ``focal_px`` is ``alpha`` in px; the x/y ratio of the
    sample's camera is kept. ``keypoints`` is the current (possibly dragged) clean 2D, ``(17, 2)`` px."""

    sample: Sample
    model: str
    keypoints: np.ndarray = field(default=None)  # type: ignore[assignment]
    input_kind: str = "gt"
    focal_px: float = 0.0
    noise_level: float = 0.0
    seed: int = DEFAULT_SEED
    cloud_samples: int = CLOUD_SAMPLES
    analytic: bool = False
    dragged: set[int] = field(default_factory=set)

    def __post_init__(self) -> None:
        if self.keypoints is None:
            self.keypoints = self.base_keypoints().copy()
        if not self.focal_px:
            self.focal_px = self.sample.camera.alpha

    def base_keypoints(self) -> np.ndarray:
        """The un-dragged 2D input: ground truth, or the detection when ``input_kind == "detected"``. Raises
        :class:`PoseLifterError` when the sample has no such 2D (no detection; no ground truth for an upload)."""
        if self.input_kind == "detected":
            if self.sample.detected_2d is None:
                raise PoseLifterError(f"no 2D detection for {self.sample.label}")
            return np.asarray(self.sample.detected_2d, np.float64)
        if self.input_kind != "gt":
            raise PoseLifterError(f"unknown 2D input {self.input_kind!r}; expected 'gt' or 'detected'")
        if not self.sample.has_gt_2d:
            raise PoseLifterError(f"no ground-truth 2D for {self.sample.label}: its 2D input is the detected / "
                                  "uploaded one")
        return np.asarray(self.sample.keypoints_2d, np.float64)

    @property
    def focal(self) -> tuple[float, float]:
        """``(fx, fy)`` px used for lifting: the camera's, scaled to ``alpha = focal_px``."""
        s = self.focal_px / self.sample.camera.alpha
        return (self.sample.camera.focal[0] * s, self.sample.camera.focal[1] * s)

    @property
    def image_size(self) -> tuple[int, int]:
        return (self.sample.camera.width, self.sample.camera.height)


def focal_max(sample: Sample) -> float:
    """Upper end of the focal slider for ``sample``: :data:`FOCAL_MAX_PX`, or 2.5 x the camera's focal
    rounded up to 100 px when that is larger (big uploaded photos have focal lengths of several 1000 px)."""
    return max(FOCAL_MAX_PX, 100.0 * math.ceil(2.5 * sample.camera.alpha / 100.0))


def clamp_focal(value: float, *, hi: float = FOCAL_MAX_PX) -> tuple[float, str | None]:
    """Clamp a focal length (px) to the slider range ``[FOCAL_MIN_PX, hi]``; returns the value and a
    message if it was changed."""
    v = float(value)
    if not math.isfinite(v):
        return FOCAL_MIN_PX, f"focal length {value!r} is not a finite number; using {FOCAL_MIN_PX:g} px"
    if v < FOCAL_MIN_PX or v > hi:
        c = min(max(v, FOCAL_MIN_PX), hi)
        return c, f"focal length {v:g} px is outside [{FOCAL_MIN_PX:g}, {hi:g}]; clamped to {c:g} px"
    return v, None


def clamp_noise(value: float) -> tuple[float, str | None]:
    """Clamp a noise level to ``[0, NOISE_MAX]``."""
    v = float(value)
    if not math.isfinite(v):
        return 0.0, f"noise level {value!r} is not a finite number; using 0"
    if v < 0 or v > NOISE_MAX:
        c = min(max(v, 0.0), NOISE_MAX)
        return c, f"noise level {v:g} is outside [0, {NOISE_MAX:g}]; clamped to {c:g}"
    return v, None


def clamp_joint(uv: np.ndarray, *, size: tuple[int, int]) -> tuple[np.ndarray, str | None]:
    """Clamp a dragged 2D joint (px) to the image grown by :data:`DRAG_MARGIN` on every side."""
    uv = np.asarray(uv, np.float64).reshape(2)
    W, H = size
    if not np.all(np.isfinite(uv)):
        return np.array([W / 2.0, H / 2.0]), "dragged joint position is not finite; moved to the image centre"
    lo = np.array([-DRAG_MARGIN * W, -DRAG_MARGIN * H])
    hi = np.array([(1 + DRAG_MARGIN) * W, (1 + DRAG_MARGIN) * H])
    c = np.clip(uv, lo, hi)
    if np.any(c != uv):
        return c, (f"joint dragged far outside the image ({uv[0]:.0f}, {uv[1]:.0f}) px; "
                   f"clamped to ({c[0]:.0f}, {c[1]:.0f}) px")
    return c, None


@dataclass(frozen=True)
class Frame:
    """The result of one redraw. 3D in mm, camera frame; 2D in px.

    lifted: ``(17, 3)`` the lift of ``noisy_2d`` (= the current 2D when the noise level is 0).
    cloud: ``(N, 17, 3)`` lifted noisy draws, or None at noise level 0.
    analytic: ``(17, 3)`` the lifted relative pose at the analytic weak-perspective root, or None.
    metrics: MPJPE, PA-MPJPE, root error (mm) against the ground truth, when known.
    """

    current_2d: np.ndarray
    noisy_2d: np.ndarray
    lifted: np.ndarray
    root: np.ndarray
    canonical_depth: float
    focal: tuple[float, float]
    principal_point: tuple[float, float]
    cloud: np.ndarray | None
    analytic: np.ndarray | None
    gt_3d: np.ndarray | None
    metrics: dict[str, float]


def compute_frame(state: SessionState, lifter: Lifter, error_model: ErrorModelLike) -> Frame:
    """Noise, lift (the shown pose and the cloud in one batch), analytic root and metrics for ``state``.

    Raises :class:`PoseLifterError` for invalid input (e.g. a degenerate 2D pose).
    """
    kp = np.asarray(state.keypoints, np.float64)
    if kp.shape != (NUM_JOINTS, 2) or not np.all(np.isfinite(kp)):
        raise PoseLifterError(f"current 2D pose must be finite with shape (17, 2), got {kp.shape}")
    cam = state.sample.camera
    pp = cam.principal_point
    f = state.focal
    if state.noise_level > 0:
        rng = np.random.default_rng(state.seed)
        noisy = error_model.sample(kp, level=state.noise_level, rng=rng)
        n = int(state.cloud_samples)
        cloud_in = error_model.sample(np.broadcast_to(kp, (n, NUM_JOINTS, 2)), level=state.noise_level,
                                      rng=np.random.default_rng([state.seed, 1])) if n > 0 else np.zeros((0, NUM_JOINTS, 2))
        batch = np.concatenate([noisy[None], cloud_in], axis=0)
    else:
        noisy = kp.copy()
        batch = kp[None]
    res = lifter.lift(batch, focal=f, principal_point=pp, source=lift_source(state))
    if not (np.all(np.isfinite(res.absolute)) and np.all(np.isfinite(res.root))):
        raise PoseLifterError("the lift is not finite (extreme 2D coordinates or focal length); input ignored")
    lifted = res.absolute[0]
    cloud = res.absolute[1:] if batch.shape[0] > 1 else None
    analytic = None
    if state.analytic:
        root_a = analytic_root(noisy, res.relative[0], focal=f, principal_point=pp)
        analytic = root_a[None, :] + res.relative[0]
    metrics: dict[str, float] = {}
    gt = state.sample.pose_3d
    if gt is not None:
        metrics["MPJPE"] = float(mpjpe(lifted, gt))
        metrics["PA-MPJPE"] = float(pa_mpjpe(lifted, gt))
        metrics["root error"] = float(np.linalg.norm(lifted[0] - gt[0]))
        if analytic is not None:
            metrics["analytic root error"] = float(np.linalg.norm(analytic[0] - gt[0]))
    return Frame(current_2d=kp, noisy_2d=noisy, lifted=lifted, root=res.root[0], canonical_depth=float(res.canonical_depth[0]),
                 focal=f, principal_point=pp, cloud=cloud, analytic=analytic, gt_3d=gt, metrics=metrics)


def lift_source(state: SessionState) -> str:
    """What the lifted 2D is, for :meth:`lifter.Lifter.lift`: ``"clean"`` for ground-truth and demo 2D (dragged
    joints included: they are placed by hand) without synthetic noise; ``"detected"`` for detections, photos,
    keypoint uploads that do not say ``"source": "clean"``, and any 2D with mixture noise on it."""
    if state.noise_level > 0:
        return "detected"
    up = state.sample.upload
    if up is not None:  # (an upload's own 2D counts as its "detection": it has no ground truth)
        return "clean" if getattr(up, "source", "detected") == "clean" else "detected"
    return "detected" if state.input_kind == "detected" else "clean"


def _focal_origin(state: SessionState) -> str:
    up = state.sample.upload
    if up is None:
        return "camera"
    return {"exif-35mm": "EXIF 35 mm equiv.", "exif-focal-plane": "EXIF", "exif-sensor-width": "EXIF",
            "default-fov": "default field of view", "keypoint-file": "keypoint file"}.get(up.focal_source, up.focal_source)


def input_name(state: SessionState) -> str:
    """Which 2D is lifted: the ground truth, the Stacked-Hourglass detection (H36M) or an upload's 2D."""
    up = state.sample.upload
    if up is not None:
        return "uploaded detection" + (f" ({up.detector} on the photo)" if up.kind == "image" else " (keypoint file)")
    return "ground truth" if state.input_kind == "gt" else "Stacked-Hourglass detection"


def input_line(state: SessionState) -> str:
    """The readout's line on the lifted 2D: its source, the dragged joints and, at a noise level > 0, that
    the lifted pose (and so the metrics) is one noisy draw."""
    parts = [f"**2D input** {input_name(state)}"]
    n = len(state.dragged)
    if n:
        parts.append(f"{n} joint{'s' if n != 1 else ''} dragged")
    if state.noise_level > 0:
        parts.append(f"lifted: one noisy draw at level {state.noise_level:g} (seed {state.seed}); "
                     "the metrics refer to that draw")
    return " · ".join(parts)


def readout_markdown(frame: Frame, state: SessionState) -> str:
    """The readout panel: canonical depth, root X/Y/Z, the ambiguity ``Z / f``, which 2D was lifted
    (:func:`input_line`), and metrics."""
    X, Y, Z = frame.root
    alpha = math.sqrt(frame.focal[0] * frame.focal[1])
    lines = [
        f"**Canonical depth** {frame.canonical_depth:,.0f} mm (at f = 1000 px)",
        f"**Root** X {X:,.0f} · Y {Y:,.0f} · **Z {Z:,.0f}** mm",
        f"**Focal** {alpha:,.0f} px ({_focal_origin(state)}: {state.sample.camera.alpha:,.0f} px) · "
        f"Z/f = {Z / alpha:.3f} mm/px",
    ]
    lines.append(input_line(state))
    up = state.sample.upload
    if up is not None:
        people = f" · {up.num_people} people found, largest used" if (up.num_people or 0) > 1 else ""
        lines.append(f"**Input** {up.name} ({'photo, ' + str(up.detector) if up.kind == 'image' else 'keypoint file, ' + up.source_format})"
                     f"{people}")
    if frame.metrics:
        m = frame.metrics
        lines.append(f"**MPJPE** {m['MPJPE']:.1f} mm · **PA-MPJPE** {m['PA-MPJPE']:.1f} mm · "
                     f"**root error** {m['root error']:.0f} mm")
        if "analytic root error" in m:
            lines.append(f"**analytic root error** {m['analytic root error']:.0f} mm")
    else:
        lines.append("_no 3D ground truth for this sample_")
    return "  \n".join(lines)
