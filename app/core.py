"""Headless per-tab state and the computation behind one redraw (no viser here).

Units and frames: 2D in **pixels** of the sample's image; 3D in **millimetres** in the OpenCV camera
frame (+x right, +y down, +z forward) of the sample's camera. The viewer converts to metres.
"""

from __future__ import annotations

import functools
import math
import threading
from dataclasses import dataclass, field, fields
from typing import Any, Final, Literal

import numpy as np

from lifter import Lifter, PoseLifterError, analytic_root, available_models
from lifter._checks import (
    CUT_OFF_TAIL,
    ROLL_RECIPE,
    body_lean_deg,
    joints_outside,
    joints_outside_text,
    lean_text,
    leaning_people,
    sideways_people,
)
from lifter.camera import MIN_FOCAL_PX, pose_view_deg
from lifter.detect import KEEP_EVERY_ONE
from lifter.metrics import mpjpe, pa_mpjpe
from lifter.skeleton import NUM_JOINTS

from .keys import parse_h36m, source_of
from .noise import ErrorModelLike
from .samples import Sample

FOCAL_MIN_PX: float = 100.0
FOCAL_MAX_PX: float = 6000.0
"""Range of the focal-length slider (px, the geometric mean ``alpha = sqrt(fx fy)``); a sample whose camera lies
outside it widens it (:func:`focal_min`, :func:`focal_max`)."""
NOISE_MAX: float = 3.0
"""Noise level: 0 = clean, 1 = as fitted, up to 3 (exaggerated)."""
CLOUD_SAMPLES: int = 64
"""Default number of noisy 2D draws lifted for the uncertainty cloud."""
MAX_CLOUD_SAMPLES: int = 256
"""The cloud-samples slider's end, and the most its box takes."""
DEFAULT_SEED: int = 0
MAX_SEED: int = 2**32 - 1
"""The largest noise seed: numpy's classic seed range, held exactly by the browser's numbers and carried by viser's
messages (an app trial typed 99999999999999999999: the box showed another number, and "resample noise" then sent
seed + 1 past what a message can carry, which dropped the tab's connection and reset its session)."""
JOINT_MARGIN: float = 0.25
"""A dragged or typed 2D joint must lie in the image grown by this fraction of its size on every side;
farther out it is refused (the previous pose is kept), never clamped and lifted."""


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
    sample's camera is kept. ``keypoints`` is the current (possibly dragged) clean 2D, ``(17, 2)`` px, of the
    selected person ``person`` (0: the sample's own, k: ``sample.others_2d[k - 1]``); ``others`` holds the current
    2D of every other person of the image (person index -> ``(17, 2)`` px; their drags are kept while another person
    is selected) and ``others_dragged`` their dragged joints."""

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
    person: int = 0
    others: dict[int, np.ndarray] = field(default_factory=dict)
    others_dragged: dict[int, frozenset[int]] = field(default_factory=dict)
    input_drags: dict[str, tuple[np.ndarray, frozenset[int]]] = field(default_factory=dict)
    """The selected person's dragged 2D ``(17, 2)`` px and dragged joints under each other 2D input of this sample
    (``"gt"`` / ``"detected"``), given back when that input is chosen again (a browser trial lost a researcher's
    corrected joints on a switch to ground truth and back)."""

    def __post_init__(self) -> None:
        n = self.sample.num_people
        if not 0 <= self.person < n:
            raise PoseLifterError(f"person {self.person} out of range: {self.sample.label} has {n} "
                                  f"{'person' if n == 1 else 'people'}")
        if self.keypoints is None:
            self.keypoints = self.base_keypoints().copy()
        if not self.focal_px:
            self.focal_px = self.sample.camera.alpha
        for k in range(n):
            if k != self.person and k not in self.others:
                self.others[k] = self.base_keypoints(k).copy()

    def base_keypoints(self, person: int | None = None) -> np.ndarray:
        """The un-dragged 2D input of ``person`` (default: the selected one): ground truth, or the detection when
        ``input_kind == "detected"``; another person's detected / uploaded 2D. Raises :class:`PoseLifterError`
        when the sample has no such 2D (no detection; no ground truth for an upload)."""
        k = self.person if person is None else int(person)
        if k > 0:
            return np.asarray(self.sample.others_2d[k - 1], np.float64)
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

    def evolve(self, **changes: Any) -> SessionState:
        """A copy with ``changes`` applied (the keypoints array and the dragged set are copied, never shared)."""
        kw: dict[str, Any] = {f.name: getattr(self, f.name) for f in fields(self)}
        kw["keypoints"] = np.array(self.keypoints, np.float64, copy=True)
        kw["dragged"] = set(self.dragged)
        kw["others"] = dict(self.others)  # (their arrays are never changed in place)
        kw["others_dragged"] = dict(self.others_dragged)
        kw["input_drags"] = dict(self.input_drags)  # (their arrays are never changed in place)
        kw.update(changes)
        return SessionState(**kw)

    @property
    def focal(self) -> tuple[float, float]:
        """``(fx, fy)`` px used for lifting: the camera's, scaled to ``alpha = focal_px``."""
        s = self.focal_px / self.sample.camera.alpha
        return (self.sample.camera.focal[0] * s, self.sample.camera.focal[1] * s)

    @property
    def image_size(self) -> tuple[int, int]:
        return (self.sample.camera.width, self.sample.camera.height)

    def people_2d(self) -> list[np.ndarray]:
        """The current 2D of every person of the image, ``(17, 2)`` px each, in the sample's order (largest
        first), the selected person's included."""
        return [self.keypoints if k == self.person else self.others[k] for k in range(self.sample.num_people)]

    def people_dragged(self) -> dict[int, frozenset[int]]:
        """Every person's dragged joints, person index -> joints, the selected person's included (as
        :meth:`people_2d` counts them)."""
        return {**self.others_dragged, self.person: frozenset(self.dragged)}


def focal_max(sample: Sample) -> float:
    """Upper end of the focal slider for ``sample``: :data:`FOCAL_MAX_PX`, or 2.5 x the camera's focal
    rounded up to 100 px when that is larger (big uploaded photos have focal lengths of several 1000 px)."""
    return max(FOCAL_MAX_PX, 100.0 * math.ceil(2.5 * sample.camera.alpha / 100.0))


def focal_min(sample: Sample) -> float:
    """Lower end of the focal slider for ``sample``: :data:`FOCAL_MIN_PX`, or half the camera's focal rounded down
    to 1 px when that is smaller (a 40-px photo's default field of view gives 44 px; a keypoint file may give a
    focal in mm by mistake, which is then lifted as given and noted), never below the library's 10 px. (Not simply
    10 px for everyone: a focal typed key by key would be lifted at "11" on its way to "1145".)"""
    return max(MIN_FOCAL_PX, min(FOCAL_MIN_PX, float(math.floor(0.5 * sample.camera.alpha))))


def clamp_focal(value: float, *, lo: float = FOCAL_MIN_PX, hi: float = FOCAL_MAX_PX) -> tuple[float, str | None]:
    """Clamp a focal length (px) to the slider range ``[lo, hi]``; returns the value and a message if it was
    changed."""
    v = float(value)
    if not math.isfinite(v):
        return lo, f"focal length {value!r} is not a finite number; using {lo:g} px"
    if v < lo or v > hi:
        c = min(max(v, lo), hi)
        return c, f"focal length {v:g} px is outside [{lo:g}, {hi:g}]; clamped to {c:g} px"
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


def check_joint(uv: Any, *, size: tuple[int, int]) -> np.ndarray:
    """A dragged / typed 2D joint ``(2,)`` px, checked: finite and inside the image grown by
    :data:`JOINT_MARGIN` on every side. Raises :class:`PoseLifterError` (naming the allowed range) otherwise."""
    try:
        p = np.asarray(uv, np.float64).reshape(2)
    except (TypeError, ValueError):
        raise PoseLifterError(f"joint position must be (u, v) px, got {uv!r}") from None
    W, H = size
    if not np.all(np.isfinite(p)):
        raise PoseLifterError(f"joint position {tuple(p)} is not finite; type a pixel position such as ({W / 2:.0f}, "
                              f"{H / 2:.0f})")
    lo = np.array([-JOINT_MARGIN * W, -JOINT_MARGIN * H])
    hi = np.array([(1 + JOINT_MARGIN) * W, (1 + JOINT_MARGIN) * H])
    if np.any(p < lo) or np.any(p > hi):
        raise PoseLifterError(
            f"joint position ({p[0]:.0f}, {p[1]:.0f}) px is far outside the {W} x {H} px image; keep it within "
            f"u in [{lo[0]:.0f}, {hi[0]:.0f}], v in [{lo[1]:.0f}, {hi[1]:.0f}] px. The previous pose is kept")
    return p


@dataclass(frozen=True)
class Spread:
    """Spread of the lifted noisy draws (the uncertainty cloud), mm, camera frame.

    mean: ``(17, 3)`` mean joint positions. cov: ``(17, 3, 3)`` per-joint covariance (absolute positions).
    root_std: ``(3,)`` standard deviation of the root X, Y, Z. joint_depth_std: ``(17,)`` standard deviation of
    each joint's depth *relative to the root* (the pose's own depth uncertainty; 0 for the root).
    draws: number of draws.
    """

    mean: np.ndarray
    cov: np.ndarray
    root_std: np.ndarray
    joint_depth_std: np.ndarray
    draws: int


def cloud_spread(cloud: np.ndarray) -> Spread:
    """:class:`Spread` of lifted draws ``(N, 17, 3)`` mm (N >= 2)."""
    c = np.asarray(cloud, np.float64)
    if c.ndim != 3 or c.shape[1:] != (NUM_JOINTS, 3) or c.shape[0] < 2:
        raise PoseLifterError(f"cloud must be (N >= 2, 17, 3) mm, got {c.shape}")
    mean = c.mean(axis=0)
    d = c - mean
    cov = np.einsum("nja,njb->jab", d, d) / (c.shape[0] - 1)
    rel_z = c[:, :, 2] - c[:, :1, 2]
    return Spread(mean=mean, cov=cov, root_std=c[:, 0, :].std(axis=0, ddof=1),
                  joint_depth_std=rel_z.std(axis=0, ddof=1), draws=int(c.shape[0]))


@dataclass(frozen=True)
class PersonLift:
    """Another person of the image: ``person`` (index in the sample, 0 = largest), current 2D ``(17, 2)`` px,
    lifted pose ``(17, 3)`` mm and root ``(3,)`` mm, camera frame; ``name`` as the person picker names them
    (:meth:`Sample.person_name`: ``"person 2 (id 7)"``)."""

    person: int
    keypoints_2d: np.ndarray
    lifted: np.ndarray
    root: np.ndarray
    name: str


@dataclass(frozen=True)
class Frame:
    """The result of one redraw. 3D in mm, camera frame; 2D in px.

    lifted: ``(17, 3)`` the lift of ``noisy_2d`` (= the current 2D when the noise level is 0).
    cloud: ``(N, 17, 3)`` lifted noisy draws, or None at noise level 0.
    spread: :class:`Spread` of the cloud (at least 2 draws), else None.
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
    spread: Spread | None = None
    others: tuple[PersonLift, ...] = ()
    """The other people of the image, lifted at the same focal length into the same camera space."""
    caution: tuple[str, ...] = ()
    """What looks wrong in the lifted pose (:meth:`lifter.Lifter.output_notes` of the network that lifted it): a
    root behind the camera, a pixel-space model given a 2D pose larger or smaller than those it was trained on."""
    trained_subjects: tuple[int, ...] = ()
    """The Human3.6M subjects the network that lifted it was trained on (its checkpoint's protocol; ``()`` where the
    checkpoint does not say): their frames' errors are on data it learned (:func:`training_subject_note`)."""
    two_networks: bool = False
    """Whether the model lifts exact 2D (``source="clean"``) with another network than detected 2D (the default
    does): the readout then says which one lifted this frame (:func:`lifted_as`)."""
    reads_rays: bool = False
    """Whether the network that lifted it reads the 2D through the intrinsics (``ModelConfig.input_space ==
    "camera"``, the default's): its Z/f then shifts with the focal length (another lens is another view),
    where a pixel-space model's (the paper's) stays exactly constant."""

    @property
    def alpha(self) -> float:
        """The focal length the pose was lifted with, ``sqrt(fx fy)`` px."""
        return math.sqrt(self.focal[0] * self.focal[1])


def lens_free_2d(keypoints: np.ndarray, *, camera: Any, lifter: Any, source: str = "detected") -> np.ndarray:
    """``(..., 17, 2)`` px seen through ``camera`` (a :class:`lifter.Camera`), as ``lifter`` should be given them
    at any focal length the app's slider sets: undistorted with the camera's own lens **and its own calibrated
    focal** for a network that learned pinhole 2D (lens coefficients act on ``(x - c) / f`` of the focal they were
    calibrated with; applying them at a what-if focal would bend the 2D differently, or fail to invert at a short
    one); as they are for a camera without a lens or a network that learned Human3.6M's distorted 2D
    (:attr:`lifter.Lifter.lens` of the network ``source`` routes to). The result is then lifted without a
    ``distortion``."""
    if not undoes_lens(camera=camera, lifter=lifter, source=source):
        return np.asarray(keypoints, np.float64)
    return camera.undistort_pixels(np.asarray(keypoints, np.float64))


def undoes_lens(*, camera: Any, lifter: Any, source: str = "detected") -> bool:
    """Whether :func:`lens_free_2d` undistorts for these: ``camera`` has a lens and the network ``source`` routes to
    learned pinhole 2D."""
    net = lifter.network_for(source) if hasattr(lifter, "network_for") else lifter
    return camera.distortion is not None and getattr(net, "lens", "pinhole") == "pinhole"


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
        cloud_in = (error_model.sample(np.broadcast_to(kp, (n, NUM_JOINTS, 2)), level=state.noise_level,
                                       rng=np.random.default_rng([state.seed, 1]))
                    if n > 0 else np.zeros((0, NUM_JOINTS, 2)))
        batch = np.concatenate([noisy[None], cloud_in], axis=0)
    else:
        noisy = kp.copy()
        batch = kp[None]
    n_main = batch.shape[0]
    ids = [k for k in range(state.sample.num_people) if k != state.person]
    if ids:  # everyone else, in the same batch: same focal length, same camera space
        batch = np.concatenate([batch, np.stack([state.others[k] for k in ids])], axis=0)
    # (no Python warnings: a slider's extreme focal length is the user's choice, shown in the readout)
    source = lift_source(state)
    # (H36M frames: their camera's lens; keypoint files that give one; demo renders and photos: none), undistorted
    # with the camera's own focal, whatever focal the slider sets (lens_free_2d)
    res = lifter.lift(lens_free_2d(batch, camera=cam, lifter=lifter, source=source), focal=f, principal_point=pp,
                      source=source, warn=False)
    used = lifter.network_for(source)  # (what lift routed to)
    others = tuple(PersonLift(person=k, keypoints_2d=np.asarray(state.others[k]), lifted=res.absolute[n_main + i],
                              root=res.root[n_main + i], name=state.sample.person_name(k)) for i, k in enumerate(ids))
    res_abs, res_rel = res.absolute[:n_main], res.relative[:n_main]
    if not (np.all(np.isfinite(res.absolute)) and np.all(np.isfinite(res.root))):
        raise PoseLifterError("the lift is not finite (extreme 2D coordinates or focal length); input ignored")
    lifted = res_abs[0]
    cloud = res_abs[1:] if n_main > 1 else None
    analytic = None
    if state.analytic:
        root_a = analytic_root(res.keypoints_2d[0], res_rel[0], focal=f, principal_point=pp)  # (as lifted)
        analytic = root_a[None, :] + res_rel[0]
    metrics: dict[str, float] = {}
    gt = state.sample.pose_3d
    if gt is not None:
        metrics["MPJPE"] = float(mpjpe(lifted, gt))
        metrics["PA-MPJPE"] = float(pa_mpjpe(lifted, gt))
        metrics["root error"] = float(np.linalg.norm(lifted[0] - gt[0]))
        if analytic is not None:
            metrics["analytic root error"] = float(np.linalg.norm(analytic[0] - gt[0]))
    spread = cloud_spread(cloud) if cloud is not None and cloud.shape[0] >= 2 else None
    return Frame(current_2d=kp, noisy_2d=noisy, lifted=lifted, root=res.root[0],
                 canonical_depth=float(res.canonical_depth[0]), focal=f, principal_point=pp, cloud=cloud,
                 analytic=analytic, gt_3d=gt, metrics=metrics, spread=spread,
                 others=others, reads_rays=used.input_space == "camera", trained_subjects=trained_subjects(used),
                 two_networks=lifter.network_for("clean") is not lifter.network_for("detected"),
                 caution=(*used.output_notes(res.keypoints_2d[0], pp, res.root[0], source=source,
                                             relative=res.relative[0], focal=f, misfit_cause=misfit_cause(state)),
                                         *(focal_said := [
                                             *wide_view_caution(noisy, focal=f, camera_focal=cam.alpha,
                                                                input_space=used.input_space,
                                                                camera_focal_known=camera_focal_known(state)),
                                             *short_focal_caution(focal=f, camera_focal=cam.alpha,
                                                                  input_space=used.input_space,
                                                                  camera_focal_known=camera_focal_known(state))]),
                                         *bone_caution(res_rel[0], why=bone_cause(state),
                                                       focal=f if focal_said else None),
                                         *tilt_caution(res.keypoints_2d[0], kind=None if state.sample.upload is None
                                                       else state.sample.upload.kind),
                                         *edge_caution(state)))


BONE_RATIO_LIMITS: Final[tuple[float, float]] = (0.4, 2.0)
"""A lifted bone shorter or longer than these multiples of the reference body's (:func:`reference_bones_mm`) gets
the readout's caution (:func:`bone_caution`)."""


@functools.lru_cache(maxsize=1)
def reference_bones_mm() -> np.ndarray:
    """``(16,)`` bone lengths (mm, :data:`lifter.skeleton.EDGES` order) of the shipped demo body
    (``lifter.demo_sample("standing")``, an authored adult's proportions)."""
    from lifter import demo_sample
    from lifter.skeleton import bone_lengths

    return bone_lengths(demo_sample("standing").pose_3d)


def bone_caution(relative: np.ndarray, *, why: str = "", focal: Any = None) -> list[str]:
    """The readout's caution when a bone of the lifted pose ``(17, 3)`` mm is out of :data:`BONE_RATIO_LIMITS` of
    the reference body's: no body has it, so the 2D is one the lift cannot explain (a trial dragged a wrist within
    the allowed range and got a 1258-mm forearm, the wrist at the camera, without a word). ``why``: the likely cause
    said after "the 2D" (:func:`bone_cause`). ``focal`` (px): the focal length in use, where the readout cautions of
    it (far shorter than the camera's, or a view no camera has): then that is named as the cause (a researcher's
    ground-truth 2D at 100 px read "the 2D is not one a body makes")."""
    from lifter.skeleton import EDGES, JOINT_NAMES, bone_lengths

    ref = reference_bones_mm()
    lengths = bone_lengths(relative)
    ratio = lengths / ref
    lo, hi = BONE_RATIO_LIMITS
    bad = [i for i in np.argsort(-np.abs(np.log(np.maximum(ratio, 1e-9)))) if not lo <= ratio[i] <= hi]
    if not bad:
        return []
    said = ", ".join(f"{JOINT_NAMES[EDGES[i][0]]}-{JOINT_NAMES[EDGES[i][1]]} {lengths[i]:.0f} mm (a body's: about "
                     f"{ref[i]:.0f})" for i in bad[:2])
    more = f" and {len(bad) - 2} more" if len(bad) > 2 else ""
    if focal is not None:
        from lifter.camera import focal_alpha

        why = (f"{why[:-1] if why.endswith('?') else why}, " if why else "") + (
            f"at {float(focal_alpha(focal)):.0f} px, the focal length cautioned of above")
        return [f"the lifted pose has bones no body has: {said}{more}; the 2D ({why}) is not one a body makes through "
                "that lens, so this lift is not a pose to trust"]
    cause = f" ({why})" if why else ""
    return [f"the lifted pose has bones no body has: {said}{more}; the 2D{cause} is not one a body makes, so this lift "
            "is not a pose to trust"]


APP_KEEP_EVERY_ONE: Final[str] = "the File tab's min person score at 0 keeps every one, for the file uploaded again"
"""What the app's messages say in place of :data:`lifter.detect.KEEP_EVERY_ONE` (the library's and the CLI's option)."""

APP_ROLL_NOTE: Final[str] = "turn the 2D upright about the principal point first (the readout's Caution says how here)"
"""What the app's messages say in place of :data:`lifter._checks.ROLL_RECIPE` (a Python recipe); the Caution says how
for the sample shown (:func:`roll_recipe`)."""


def app_wording(text: str) -> str:
    """A library message as the app says it, naming what the app has: the score floor's off switch is the File tab's
    control, not the library's ``min_score`` or ``poselifter lift --min-score`` (a trial: a refused photo named options
    the app does not have); how to undo a roll is the readout Caution's (:func:`roll_recipe`; a trial: the lean note
    sent an app user to a Python recipe)."""
    return text.replace(KEEP_EVERY_ONE, APP_KEEP_EVERY_ONE).replace(ROLL_RECIPE, APP_ROLL_NOTE)


def roll_recipe(lean_deg: float, kind: str | None) -> str | None:
    """How the readout's lean caution says to undo a roll of the sample shown (``kind``: its upload's kind, None for
    a demo or Human3.6M sample): an uploaded photo or video is rotated about its centre, the way named (a body whose
    feet lie toward +x, ``lean_deg`` > 0, leans counter-clockwise on screen), keeping its size, which sets the
    assumed focal length (a review: a 4000 x 3000 photo turned 45 deg on an enlarged canvas is assumed a 40 % longer
    focal); a keypoint file: the library's recipe (None: :data:`lifter._checks.ROLL_RECIPE`, Python); a demo or
    Human3.6M sample, whose camera is known and upright: nothing to undo."""
    if kind in ("image", "video"):
        turn = "clockwise" if lean_deg > 0 else "counter-clockwise"
        return (f"rotate the {'photo' if kind == 'image' else 'video'} {turn} by about {abs(lean_deg):.0f}° about its "
                "centre, keeping its size (crop: an enlarged canvas changes the focal length assumed), and upload it "
                "again, unless the camera's own roll is known")
    if kind is None:
        return "this sample's camera is known and upright: the lean is the pose's own, or a drag's"
    return None


def misfit_cause(state: SessionState) -> str | None:
    """What the readout's caution on 2D that its lift does not fit (:meth:`lifter.Lifter.output_notes`) names as the
    likely cause: the noise the app drew and a dragged joint, where there is one, beside a detector's mistake for a
    detection (a teacher trial at noise level 3 read "a confident detector mistake" with no detector in the app's
    demo; a review: a joint dragged to mend a detection is not the only suspect); None: a detection alone (the
    library's wording)."""
    detected = lift_source(state.evolve(noise_level=0.0)) == "detected"  # (a file's "clean" 2D: no detector)
    parts = [*(["a dragged joint"] if state.dragged else []),
             *([f"the noise drawn at level {state.noise_level:g} with its far-off outliers"]
               if state.noise_level > 0 else []),
             *(["a detector's mistake"] if detected else [])]
    if parts in ([], ["a detector's mistake"]):
        return None
    return (parts[0] if len(parts) == 1 else ", ".join(parts[:-1]) + ", or " + parts[-1]) + "?"


def bone_cause(state: SessionState) -> str:
    """What most likely bent the selected person's 2D in ``state`` when :func:`bone_caution` fires: a joint dragged,
    the noise drawn on it, or the detection (a teacher's noise level 3 on an undragged demo read "a dragged
    joint?")."""
    noise = f"the noise drawn at level {state.noise_level:g}" if state.noise_level > 0 else ""
    if state.dragged:
        return "a dragged joint?" + (f" or {noise}" if noise else "")
    if noise:
        return f"with {noise}"
    return "a detection error?" if state.input_kind == "detected" else ""


def wide_view_caution(keypoints: np.ndarray, *, focal: Any, camera_focal: float,
                      input_space: Literal["pixel", "camera"] = "camera",
                      camera_focal_known: bool = True) -> list[str]:
    """The readout's caution when the 2D pose ``(17, 2)`` px spans more than
    :data:`lifter.camera.MAX_PLAUSIBLE_VIEW_DEG` of view at the focal length in use ``focal`` (px): no camera sees a
    whole person that wide, so a lifter that reads the 2D through the focal (``input_space="camera"``, the default)
    leaves what its networks learned and bends (a teacher's slider at 100 px: PA-MPJPE over 200 mm); a pixel-space
    model (the paper's) lifts the same pose at every focal, and only its depth follows (a user trial: the caution
    said it bent). The camera's own focal length ``camera_focal`` (px) is named, or, where it was only assumed from the
    image size (``camera_focal_known=False``), named as that assumption (a trial read a 65° guess as the camera's)."""
    from lifter.camera import MAX_PLAUSIBLE_VIEW_DEG, focal_alpha, pose_view_deg, view_deg_text

    view = float(pose_view_deg(np.asarray(keypoints, np.float64), focal))
    if view <= MAX_PLAUSIBLE_VIEW_DEG:
        return []
    what = ("the lift is outside what the networks learned, and bends" if input_space == "camera" else
            "no camera sees a person so; this pixel-space model lifts the same pose at every focal length, and only "
            "the depth follows the slider")
    return [f"at {float(focal_alpha(focal)):.0f} px this 2D pose spans {view_deg_text(view)}° of view (a whole person "
            f"rarely spans more than {MAX_PLAUSIBLE_VIEW_DEG:.0f}°, even through an ultra-wide lens): {what}; the "
            + (f"camera's own focal length is {camera_focal:.0f} px" if camera_focal_known else
               f"focal length assumed for this image (its camera's is not known) is {camera_focal:.0f} px")]


def edge_caution(state: SessionState) -> list[str]:
    """The readout's caution when people of an uploaded photo's or video's detection have joints outside the image
    (not dragged there): the detector guessed them (the photo and video notes' rule,
    :data:`lifter._checks.CUT_OFF_TAIL`). A video's note named the frames once, in the upload's message (a known gap:
    per-frame notes were not flagged on the frames they name); this caution follows the frame shown, for the
    selected person first, then the others (each named)."""
    up = state.sample.upload
    if up is None or up.kind not in ("image", "video"):
        return []
    people, dragged = state.people_2d(), state.people_dragged()
    cut = []
    for k in [state.person, *(k for k in range(len(people)) if k != state.person)]:
        out = joints_outside(np.asarray(people[k], np.float64), state.image_size)
        out[sorted(dragged.get(k, ()))] = False  # (a joint dragged outside: the user's own)
        if out.any():
            cut.append(f"{state.sample.person_name(k)} ({joints_outside_text(out)})")
    if not cut:
        return []
    return [f"{'; '.join(cut)}: cut off by the image's edge here; {CUT_OFF_TAIL}"]


def tilt_caution(keypoints: np.ndarray, *, kind: str | None = None) -> list[str]:
    """The readout's caution when the selected person's 2D ``(17, 2)`` px lies sideways in the image or leans as a
    rolled camera leans people (:func:`lifter._checks.sideways_people`, :func:`lifter._checks.leaning_people`, the
    photo notes' rules): the default is trained on upright cameras and people, and such a lift is metres off. A
    browser trial: the note on a photo turned 45 deg was replaced by a later refused upload's message, leaving the
    lift on screen without a word; a video's went as it played. This caution follows the 2D shown, frame by frame
    and drag by drag; ``kind``: the upload's kind (None: a demo or Human3.6M sample), for how to undo a roll
    (:func:`roll_recipe`)."""
    k = np.asarray(keypoints, np.float64).reshape(1, NUM_JOINTS, 2)
    if not np.all(np.isfinite(k)):
        return []
    if sideways_people(k)[0]:
        if kind is None:  # (a demo or Human3.6M camera, known and upright: a researcher trial read "a photo turned")
            return ["the body lies sideways in the image (head and ankles apart along x): this sample's camera is "
                    "known and upright, so the person is lying or bent over, a pose rare in the training data; the "
                    "lift is likely off"]
        return ["the body lies sideways in the image (head and ankles apart along x): a photo or video turned a "
                "quarter (its orientation lost), or a person lying down, a pose rare in the training data; the lift "
                "is likely off"]
    if leaning_people(k)[0]:
        lean = float(body_lean_deg(k)[0])
        return [f"the body leans {abs(lean):.0f}° from the image's vertical (legs and torso alike): "
                f"{lean_text(lean, recipe=roll_recipe(lean, kind))}"]
    return []


SHORT_FOCAL_FACTOR: Final[float] = 0.5
"""A focal length below this multiple of the camera's own gets :func:`short_focal_caution` (ray-reading models)."""

SHORT_FOCAL_MEASURED: Final[str] = (
    "the default over Human3.6M's test frames: mean PA-MPJPE 41 / 71 / 124 mm at ×0.5 / ×0.25 / ×0.1 of the true "
    "focal, 29 at it, and median Z/f +3 / +9 / +27 %; one frame's own can differ")
"""What a too-short focal does to the default (``python scripts/wrong_focal.py``, docs/results/wrong_focal.txt)."""


def camera_focal_known(state: SessionState) -> bool:
    """Whether the sample camera's focal length is the camera's own (Human3.6M, demo, EXIF, a keypoint file, typed at
    upload), not assumed from the image size: :func:`lifter.io.depth_is_metric` of an upload's focal source."""
    from lifter.io import depth_is_metric

    up = state.sample.upload
    return up is None or depth_is_metric(up.focal_source)


def short_focal_caution(*, focal: Any, camera_focal: float, input_space: Literal["pixel", "camera"] = "camera",
                        camera_focal_known: bool = True) -> list[str]:
    """The readout's caution when the focal length in use ``focal`` (px) is below :data:`SHORT_FOCAL_FACTOR` of the
    camera's own ``camera_focal`` (px) and the model reads the 2D through it (``input_space="camera"``): the lift then
    bends and its Z/f leaves ``Z ∝ f`` well before the pose spans an implausible view (a teacher's box at 150 px,
    ×0.13 of the camera's focal, seen on one frame in a browser trial: Z/f 22 % off, PA-MPJPE 60 -> 84 mm, and the
    readout said "a little"). A pixel-space model lifts the same pose at every focal length, so it gets none; nor
    does a camera whose focal was only assumed from the image size (``camera_focal_known=False``: the measured
    numbers are against the true focal, which a typed one may then be)."""
    from lifter.camera import focal_alpha

    alpha = float(focal_alpha(focal))
    ratio = alpha / float(camera_focal)
    if input_space != "camera" or ratio >= SHORT_FOCAL_FACTOR or not camera_focal_known:
        return []
    return [f"at {alpha:.0f} px, ×{ratio:.3g} of the camera's own focal length "
            f"({float(camera_focal):.0f} px), this model's lift bends and its Z/f drifts from Z ∝ f, more the "
            f"shorter the focal ({SHORT_FOCAL_MEASURED})"]


def lift_source(state: SessionState) -> Literal["clean", "detected"]:
    """What the lifted 2D is, for :meth:`lifter.Lifter.lift`: ``"clean"`` for ground-truth and demo 2D (dragged
    joints included: they are placed by hand) without synthetic noise; ``"detected"`` for detections, photos,
    keypoint uploads that do not say ``"source": "clean"``, and any 2D with mixture noise on it."""
    if state.noise_level > 0:
        return "detected"
    up = state.sample.upload
    if up is not None:  # (an upload's own 2D counts as its "detection": it has no ground truth)
        return "clean" if getattr(up, "source", "detected") == "clean" else "detected"
    return "detected" if state.input_kind == "detected" else "clean"


def focal_text(alpha: float) -> str:
    """A focal length (px) as the readout writes it: whole pixels, with one decimal when it is 0.05 px or more from
    a whole number (a typed 1144.5 reads "1144.5", not "1144")."""
    return f"{alpha:.1f}" if abs(alpha - round(alpha)) >= 0.05 else f"{alpha:.0f}"


def view_angles_text(focal: tuple[float, float], image_size: tuple[int, int]) -> str:
    """The field of view of a ``(W, H)`` px image at focal ``(fx, fy)`` px (a pinhole: its width and height, and its
    diagonal at their mean focal), e.g. ``"view 53° × 41° (diagonal 65°)"``."""
    (fx, fy), (w, h) = focal, image_size
    diagonal = float(pose_view_deg(np.array([[0.0, 0.0], [w, h]]), focal))  # (the image's box, as a pose's)
    return (f"view {math.degrees(2.0 * math.atan(w / 2 / fx)):.0f}° × {math.degrees(2.0 * math.atan(h / 2 / fy)):.0f}° "
            f"(diagonal {diagonal:.0f}°)")


def _focal_origin(state: SessionState) -> str:
    up = state.sample.upload
    if up is None:
        return "camera"
    return {"exif-35mm": "EXIF 35 mm equiv.", "exif-focal-plane": "EXIF", "exif-sensor-width": "EXIF",
            "default-fov": "default field of view",
            "keypoint-file": "keypoint file"}.get(up.focal_source, str(up.focal_source))


def input_name(state: SessionState) -> str:
    """Which 2D is lifted: the ground truth, the Stacked-Hourglass detection (H36M) or an upload's 2D."""
    up = state.sample.upload
    if up is not None:
        where = {"image": f" ({up.detector} on the photo)", "video": f" ({up.detector} on the video frame)"}
        if getattr(up, "source", "detected") == "clean":
            return "uploaded exact 2D (keypoint file, \"source\": \"clean\")"
        return "uploaded detection" + where.get(up.kind, " (keypoint file)")
    return "ground truth" if state.input_kind == "gt" else "Stacked-Hourglass detection"


def input_line(state: SessionState) -> str:
    """The readout's line on the lifted 2D: its source, the dragged joints and, at a noise level > 0, that
    the lifted pose (and so the metrics) is one noisy draw."""
    from lifter.skeleton import JOINT_NAMES

    parts = [f"**2D input** {input_name(state)}"]
    n = len(state.dragged)
    if n:  # (named: a trial's count alone did not say which joints were moved)
        parts.append(f"dragged: {', '.join(JOINT_NAMES[j] for j in sorted(state.dragged))}")
    others = {k: v for k, v in state.others_dragged.items() if v and k != state.person}
    if others:  # (a trial: another person's moved joints went unmentioned)
        parts.append("also dragged: " + "; ".join(f"{len(v)} joint{'s' if len(v) != 1 else ''} of "
                                                  f"{state.sample.person_name(k)}" for k, v in sorted(others.items())))
    if state.noise_level > 0:
        parts.append(f"lifted: one noisy draw at level {state.noise_level:g} (seed {state.seed}); "
                     "the metrics refer to that draw")
    return " · ".join(parts)


def lifted_as(frame: Frame, state: SessionState) -> str:
    """For a model with a network for exact 2D and another for detected 2D (:attr:`Frame.two_networks`): which one
    lifted the frame, and, with noise on 2D that would otherwise go to the exact-2D network, that any noise switches
    networks (a teacher trial: the first notch of noise moved the root by 51 mm and MPJPE by 24 mm with a root σZ of
    12 mm, which read as noise making the lift better); else ``""``."""
    if not frame.two_networks:
        return ""
    if lift_source(state) == "clean":
        return "lifted as **exact 2D** (the model's network for exact 2D)"
    if lift_source(state.evolve(noise_level=0.0)) == "clean":
        return ("lifted as **detected 2D** (the model's networks for detected 2D: noisy 2D is not exact; at noise 0 "
                "the exact-2D network lifts it, so the first notch of noise changes the lift by more than the noise "
                "itself)")
    return "lifted as **detected 2D** (the model's networks for detected 2D)"


def spread_line(spread: Spread) -> str:
    """The readout's line on the uncertainty cloud: the root's spread and the joints' depth spread relative to
    the root (median and largest, with the joint's name)."""
    from lifter.skeleton import JOINT_NAMES

    rx, ry, rz = spread.root_std
    rel = spread.joint_depth_std[1:]
    worst = int(np.argmax(rel)) + 1
    return (f"**Spread** ({spread.draws} draws) root σ X {rx:.0f} · Y {ry:.0f} · **Z {rz:.0f}** mm · joint depth σ "
            f"(relative to the root) median {float(np.median(rel)):.0f}, max {float(rel.max()):.0f} mm "
            f"({JOINT_NAMES[worst]})")


CLOUD_CAVEAT: Final[str] = (
    "The cloud is the fitted mixture's uncertainty, not a detector's: its errors are independent per joint, and the "
    "default model lifts its draws with more root error, and nearer the camera, than real detections of the same 2D "
    "error (measured for the default; README, The app).")
"""Said under the cloud's numbers (measured: ``python scripts/noise_vs_detections.py``)."""


def spread_details(spread: Spread) -> str:
    """Every joint's depth spread (σ of Z relative to the root, mm) and the root's own σ Z, small print, with what
    the cloud is not: a real detector's uncertainty (the mixture's draws are lifted worse, and nearer, than real
    detections of the same 2D error: README, "The app"; ``scripts/noise_vs_detections.py``)."""
    from lifter.skeleton import JOINT_NAMES

    parts = [f"root σZ {spread.root_std[2]:.0f}"]
    parts += [f"{JOINT_NAMES[j]} {spread.joint_depth_std[j]:.0f}" for j in range(1, NUM_JOINTS)]
    return ("<small>**Depth σ per joint** (mm; joints relative to the root): " + " · ".join(parts) + ". "
            f"{CLOUD_CAVEAT}</small>")


def trained_subjects(net: Any) -> tuple[int, ...]:
    """The Human3.6M training subjects of ``net`` (a :class:`lifter.Lifter`), from its checkpoint's training protocol
    (:func:`lifter.data.trained_protocol`: the paper-table models' older checkpoints say it too; a browser trial saw
    no note on S1 with them); ``()`` where the checkpoint does not say."""
    from lifter.data import PROTOCOLS, trained_protocol

    p = trained_protocol(net)
    return () if p is None else PROTOCOLS[p][0]


def training_subject_note(key: str, trained: tuple[int, ...]) -> str:
    """For a Human3.6M sample key (``h36m/S1/...``) of one of the subjects ``trained`` (the lifting network's,
    :func:`trained_subjects`): that its errors are on data the model learned (a researcher trial read 7 mm on S1 with
    nothing saying so); else ``""``."""
    frame = parse_h36m(key)
    if frame is None or frame.subject not in trained:
        return ""
    return f" — {frame.subject_name} is one of this model's training subjects: these are errors on data it learned"


Z_PER_F_DETAIL: Final[str] = (
    "Z/f: a ray-reading model (the default) shifts it with f, within 3 % from ×0.5 to ×6 of the camera's focal "
    "(median over Human3.6M's test frames), and more at shorter ones")
"""The readout's small print on a ray-reading model's ``Z/f`` (``docs/results/wrong_focal.txt``)."""


def readout_markdown(frame: Frame, state: SessionState) -> str:
    """The readout panel (numbers without thousands separators), the numbers first, so that they stay in the panel's
    view whatever the notes under them (a teacher trial: with noise on, the 2D-input and Spread lines pushed MPJPE
    below the panel): ``Focal N px`` (the focal length this frame was lifted with, and the camera's;
    :func:`focal_text`), root X/Y/Z, canonical depth and the ambiguity ``Z / f``, the metrics and the analytic root,
    the spread of the uncertainty cloud (:func:`spread_line`); then the cautions, which 2D was lifted
    (:func:`input_line`), the upload and the people; last, in small print, how ``Z/f`` moves with f."""
    X, Y, Z = frame.root
    alpha = frame.alpha
    lines = [
        f"**Focal {focal_text(alpha)} px** ({_focal_origin(state)}: {focal_text(state.sample.camera.alpha)} px) · "
        + view_angles_text(frame.focal, state.image_size),
        f"**Root** X {X:.0f} · Y {Y:.0f} · **Z {Z:.0f}** mm" + (
            # (a user trial: the readout differed from the download's root by up to 66 mm, unexplained)
            " (this frame's own lift: the download's `root_unsmoothed`; its `root` is smoothed along the track, as "
            "the drawn trajectory)" if source_of(state.sample.key) == "video" else ""),
        f"**Canonical depth** {frame.canonical_depth:.0f} mm (at f = 1000 px) · **Z/f** {Z / alpha:.3f} mm/px "
        + ("(this model reads the rays: Z/f shifts a little with f)" if frame.reads_rays else
           "(this pixel-space model: the same at any f)"),
    ]
    if frame.metrics:
        m = frame.metrics
        above = (" _(above MPJPE: the Procrustes fit minimises the squared distances, not their mean)_"
                 if round(m["PA-MPJPE"], 1) > round(m["MPJPE"], 1) else "")  # (two trials took it for a bug)
        lines.append(f"**MPJPE** (roots aligned) {m['MPJPE']:.1f} mm · **PA-MPJPE** {m['PA-MPJPE']:.1f} mm{above} · "
                     f"**root error** {m['root error']:.0f} mm" + training_subject_note(state.sample.key,
                                                                                       frame.trained_subjects))
    else:
        lines.append("_no 3D ground truth for this sample_")
    if frame.analytic is not None:
        a = frame.analytic[0]
        err = frame.metrics.get("analytic root error")
        lines.append(f"**Analytic root** Z {a[2]:.0f} mm ({a[2] - Z:+.0f} mm from the lifted root)"
                     + (f" · error {err:.0f} mm" if err is not None else ""))
    if frame.spread is not None:
        lines.append(spread_line(frame.spread))
    lines += [f"**Caution** {note}" for note in frame.caution]
    lines.append(" · ".join(p for p in (input_line(state), lifted_as(frame, state)) if p))
    up = state.sample.upload
    if up is not None:
        what = {"image": f"photo, {up.detector}",
                "video": f"video, {up.detector}"}.get(up.kind, f"keypoint file, {up.source_format}")
        lines.append(f"**Input** {up.name} ({what})")
    if frame.others:
        lines.append(people_line(frame, state))
    if frame.reads_rays:
        lines.append(f"<small>{Z_PER_F_DETAIL}</small>")
    return "  \n".join(lines)


def people_line(frame: Frame, state: SessionState) -> str:
    """The readout's line on the people of the image: the selected one (draggable) and, for each other person, the
    root and the distance between roots (mm, camera frame)."""
    n = state.sample.num_people
    me = np.asarray(frame.root, np.float64)
    me_name = state.sample.person_name(state.person)
    video = source_of(state.sample.key) == "video"  # (a trial: only the selected person's root said it is unsmoothed)
    parts = [f"**People** {n} in one camera space · **{me_name}** selected (drag its joints; the person picker "
             "selects another)" + (" · roots: this frame's own lifts, unsmoothed, as the Root line's" if video else "")
             # (an app trial: with noise on, a distance mixed the selected person's noisy root with a clean one)
             + (f" · the noise (level {state.noise_level:g}) is drawn for {me_name} only: the others are lifted from "
                "their 2D as it is" if state.noise_level > 0 else "")]
    for o in frame.others:
        X, Y, Z = o.root
        parts.append(f"{o.name}: root X {X:.0f} · Y {Y:.0f} · Z {Z:.0f} mm, "
                     f"{float(np.linalg.norm(np.asarray(o.root) - me)):.0f} mm from {me_name}")
    return "  \n".join(parts)
