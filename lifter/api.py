"""The inference API: :class:`Lifter` and its :class:`LiftResult`.

Example::

    from lifter import Lifter
    lifter = Lifter.from_pretrained()                  # the shipped default, for every input
    res = lifter.lift(keypoints, focal=(fx, fy), principal_point=(cx, cy))            # detector 2D
    res = lifter.lift(keypoints, focal=(fx, fy), principal_point=(cx, cy), source="clean")  # exact 2D
    res.absolute   # (..., 17, 3) mm, camera frame (OpenCV: +x right, +y down, +z forward)
"""

from __future__ import annotations

import copy
import dataclasses
import os
import re
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np
import torch
from numpy.typing import ArrayLike

from . import resources as assets
from ._checks import (
    CheckpointError,
    OutputNote,
    PoseLifterError,
    as_pair,
    as_points,
    collect_output_notes,  # noqa: F401 -- (re-exported: it lived here, lifter.api.collect_output_notes)
    face_first_notes,
    input_warnings,
    lean_notes,
    outside_image_notes,
    principal_point_notes,
    sideways_notes,
    upside_down_notes,
    view_angle_notes,
    warn_user,
    where_in_batch,
)
from .camera import (
    CANONICAL_FOCAL,
    DEFAULT_DIAGONAL_FOV_DEG,
    MIN_FOCAL_PX,
    DistortionModel,
    _misfit,
    check_distortion_model,
    check_lens,
    focal_alpha,
    focal_from_fov,
    image_centre,
    lens_notes,
    undistort_pixels,
    undistort_pixels_opencv,
)
from .checkpoint import Checkpoint, load_checkpoint, save_checkpoint
from .codec import SOURCES, Encoded, PoseCodec, Source
from .data import LENSES, Lens
from .io import depth_is_metric
from .model import (
    MirrorCoupledLinear,
    ModelConfig,
    PoseLifterNet,
    QuantizedCoupledLinear,
    drop_packed,
    forward_folded,
    forward_numpy,
    forward_packed,
)
from .normalization import pose_scale
from .skeleton import NUM_JOINTS

NUMPY_MAX_BATCH: Final[int] = 2
"""Batches up to this many network rows run in numpy (:func:`~lifter.model.forward_numpy`, matrix-vector
products, each block of a weight matrix used for every row while it is in cache), larger ones through torch
(:func:`~lifter.model.forward_folded`, in cache-sized slices; the module itself when a layer is not the plain
float32 one). Two rows are one pose with flip-test averaging; a matrix-vector product in numpy's BLAS has less
overhead than torch's kernels, and from a few rows on torch's matrix products win (``benchmarks/bench_lift.py``
times both). Before both, networks whose weight matrices are float16 numbers (every shipped one) run up to
:data:`lifter.model.PACKED_MAX_ROWS` rows through float16-packed matrices (:func:`~lifter.model.forward_packed`)."""
CHUNK_SIZE: Final[int] = 32768
"""Poses per network pass in :meth:`Lifter.lift`: larger batches are lifted in chunks of this size, so
memory stays bounded (the result is the same as one pass)."""
DEGENERATE_SCALE_PX: Final[float] = 1e-3
MIN_POSE_SCALE_PX: Final[float] = 2.0
"""Poses whose 2D scale (RMS radius) is below this many pixels are rejected: they are degenerate or not in pixels."""
MAX_ABS_PX: Final[float] = 1e6
"""Keypoints, principal point and focal length beyond this magnitude (px) are refused: float32 overflow
territory, and never image pixels."""

H36M_POSE_PX: Final[tuple[float, float, float]] = (34.7, 208.1, 421.6)
"""Human3.6M's training 2D poses (Protocol 1, ground truth, every frame): the smallest and largest scale (RMS radius,
:func:`lifter.normalization.pose_scale`) and the largest distance of their centre from the principal point, px. A
network that reads pixels knows poses of these sizes (times its zoom augmentation),
:attr:`Lifter.trained_pixel_range`."""

FocalSource = Literal["given", "default-fov", "reference"]


def available_models() -> list[str]:
    """Names accepted by :meth:`Lifter.from_pretrained` (besides ``"default"`` and checkpoint paths)."""
    return assets.model_names()


FAR_ROOT_DEPTH_MM: Final[float] = 8000.0
"""Roots lifted farther than this (mm) from detected 2D by a reference-camera network trained where the training
subjects stood get a note: their roots reach 7.6 m (:data:`TRAINING_ROOT_MAX_MM`; 1-99 %: 3.3-6.9 m), and such
detected-2D networks place farther people too near (``universal_turn``: -11 % at 9 m, -38 % at 25 m on exact 2D;
``scripts/far_people.py``, ``docs/results/far_people.txt``). The reference camera makes the networks read the 2D as
seen from the true distance, whatever the focal length and image size, so the distance itself is what is outside
their training. A network trained with people moved along their viewing rays (``--distance-prob``, up to
``--distance-max`` times their depth) saw them that much farther: :attr:`Lifter.far_root_depth_mm`."""

TRAINING_ROOT_MAX_MM: Final[float] = 7600.0
"""The farthest root depth (mm, rounded up) of Human3.6M's training subjects (Protocol 1; 7556 mm)."""


def _far_limit_mm(distance_factor: float) -> float:
    """:attr:`Lifter.far_root_depth_mm` for networks whose training moved people ``distance_factor`` times farther."""
    return FAR_ROOT_DEPTH_MM if distance_factor <= 1.0 else TRAINING_ROOT_MAX_MM * distance_factor


@dataclass(frozen=True, eq=False)
class LiftResult:
    """Lifted poses for inputs of leading shape ``(...)``. All 3D in mm, camera frame (OpenCV).

    absolute: ``(..., 17, 3)`` the absolute pose, ``root + relative``.
    root: ``(..., 3)`` the pelvis: the input's 2D pelvis back-projected at depth ``root[..., 2]``.
    relative: ``(..., 17, 3)`` root-relative pose, root row zero.
    canonical_depth: ``(...)`` ``Z * 1000 / alpha`` (mm as seen by a 1000-px camera; alpha = sqrt(fx fy)). A
        pixel-space model's does not depend on the focal length (known whether or not it is); the default's
        (``input_space`` ``"camera"``) does, a little (see ``input_space``).
    keypoints_2d: ``(..., 17, 2)`` px, the 2D that was lifted: the input, undistorted when a ``distortion`` was given to
    a pinhole lifter. principal_point, focal: ``(..., 2)`` px used.
    focal_source: ``"given"``; ``"default-fov"`` (no focal: the default diagonal field of view of
        ``image_size``); ``"reference"`` (no focal and no image size: a 1000-px camera).
    metric_depth: True when the focal length was given. Otherwise the result is for the assumed focal length
        ``focal`` (see ``focal_source``), and how the true one would change it depends on ``input_space``.
    source: ``"detected"`` or ``"clean"``, as passed.
    input_space: what the network read. ``"pixel"`` (the paper's models): the 2D in pixels, so the relative pose
        and the canonical depth do not depend on the focal length, and with an unknown focal Z is known up to it,
        ``Z_true = Z * f_true / f_used`` (paper Eq. 5-6), exactly. ``"camera"`` (the default model): the 2D
        through the focal length (reference camera), so a different focal length changes the pose and the
        canonical depth as well; ``Z * f_true / f_used`` is then only a rough correction (scripts/wrong_focal.py,
        exact H36M 2D, a focal used x0.5-x2 the true one: the median pose within 2.6 % through the clean network,
        2.5 % through the detected ones, for the default; single poses further).
    warnings: what looks wrong in the output (roots behind the camera; a pixel-space model given 2D poses larger
        or smaller than those it was trained on), as :meth:`Lifter.lift` warned them (``warn=True``) or would have;
        empty when nothing does.
    input_warnings: what looks wrong in the input but was lifted (a pose spanning more than 120 deg of view at
        the focal length given, usually a focal in mm rather than px; a joint at exactly (0, 0) far from its pose),
        as :meth:`Lifter.lift` warned them or would have; kept here so that :meth:`to_dict` carries them.
    """

    absolute: np.ndarray
    root: np.ndarray
    relative: np.ndarray
    canonical_depth: np.ndarray
    keypoints_2d: np.ndarray
    principal_point: np.ndarray
    focal: np.ndarray
    focal_source: FocalSource
    metric_depth: bool
    source: Source
    input_space: Literal["pixel", "camera"] = "pixel"
    warnings: tuple[str, ...] = ()
    input_warnings: tuple[str, ...] = ()

    def to_dict(self) -> dict[str, Any]:
        """The result as plain Python (lists of floats, strings, bools), ready for ``json.dump``; ``note`` included.
        Compare results with ``np.allclose`` on the arrays (``==`` between results is identity)."""
        out: dict[str, Any] = {}
        for f in fields(self):
            v = getattr(self, f.name)
            out[f.name] = v.tolist() if isinstance(v, np.ndarray) else list(v) if isinstance(v, tuple) else v
        out["note"] = self.note
        return out

    @property
    def note(self) -> str:
        if self.metric_depth:
            return "absolute pose in mm, camera frame"
        used = ("the default field of view of the image" if self.focal_source == "default-fov"
                else "a 1000-px reference camera")
        if self.input_space == "pixel":
            return (f"no focal length given: depth placed for {used}; the pose, the canonical depth (Z/f) and the "
                    "root's direction are known, Z itself only up to the unknown focal length "
                    "(Z_true = Z * f_true / f_used)")
        return (f"no focal length given: lifted as seen through {used}; this model reads the 2D through the focal "
                "length, so the pose and the depth both rest on that assumption (Z * f_true / f_used only roughly "
                "corrects Z); give the focal length for a metric result")


_PAIRS: Final[dict[str, str]] = {"focal": "(fx, fy)", "principal_point": "(cx, cy)", "image_size": "(width, height)"}


def _lens_of(train_config: dict[str, Any] | None) -> Lens:
    """The ``data.lens`` of a checkpoint's training config; ``"h36m"`` when it has none (checkpoints from before
    the option, the paper's models)."""
    data = (train_config or {}).get("data")
    lens = data.get("lens", "h36m") if isinstance(data, dict) else "h36m"
    if lens not in LENSES:
        raise PoseLifterError(f"checkpoint training config: data.lens is {lens!r}; expected one of {list(LENSES)}")
    return lens


def _broadcast(x: np.ndarray, lead: tuple[int, ...], *, name: str, given: Any = None) -> np.ndarray:
    """``x`` ``(..., 2)`` broadcast to ``lead + (2,)``, else an error naming the shapes (``given``: what the caller
    passed, when :func:`lifter._checks.as_pair` made its scalars or last axis of 1 into pairs)."""
    try:
        return np.broadcast_to(x, lead + (2,))
    except ValueError:
        shape = tuple(x.shape)
        if given is not None and np.shape(given) != shape:
            shape_text = f"{np.shape(given)} (read as {shape}: one value is fx = fy)"
        else:
            shape_text = str(shape)
        if not lead:
            raise PoseLifterError(f"{name}: shape {shape_text} for a single pose (keypoints (17, 2)); give one "
                                  f"(2,) {name}, e.g. {name}[0]") from None
        per_first = "" if len(lead) < 2 else (f", or {lead[:1] + (1,) * (len(lead) - 1) + (2,)} for one per "
                                                 f"index of the first axis")
        raise PoseLifterError(f"{name}: shape {shape_text} does not broadcast against the keypoints' leading "
                              f"shape {lead}: its last axis is {_PAIRS.get(name, '(x, y)')}, so give (2,) for "
                              f"every pose, {lead + (2,)} for each{per_first}") from None


def ensemble_parts(ref: str) -> list[str]:
    """The checkpoint paths of ``"a.pt+b.pt"`` (split only after ``.pt``, so folders named ``run+1`` stay whole),
    or ``[ref]`` for one path, or for an existing file whose own name holds ``+``."""
    if Path(ref).is_file():
        return [ref]
    return re.split(r"(?<=\.pt)\+", ref)


class Lifter:
    """A trained network and its codec, numpy in / numpy out (module docstring). The network given is put in
    eval mode, and a mirror network's output mirror (:meth:`~lifter.model.PoseLifterNet.set_target_statistics`)
    is set from ``codec``: share a network between Lifters only with the same codec."""

    def __init__(self, net: PoseLifterNet, codec: PoseCodec, *, name: str = "custom",
                 meta: dict[str, Any] | None = None, train_config: dict[str, Any] | None = None,
                 flip_test: bool = False, clean: Lifter | None = None, ensemble: Sequence[Lifter] = (),
                 weights_sha256: str | None = None) -> None:
        if net.config != codec.config:
            raise PoseLifterError(f"network and codec configs differ: {net.config} vs {codec.config}")
        if clean is not None and (clean.clean is not None or clean.ensemble):
            raise PoseLifterError("the clean-2D lifter of a Lifter cannot have a clean lifter or an ensemble of "
                                  "its own")
        if any(m.clean is not None or m.ensemble for m in ensemble):
            raise PoseLifterError("ensemble members cannot have a clean lifter or an ensemble of their own")
        if any(_lens_of(m.train_config) != _lens_of(train_config) for m in ensemble):
            raise PoseLifterError("ensemble members must have learned the same 2D as the network they join "
                                  "(train config data.lens): " + ", ".join(
                                      sorted({_lens_of(m.train_config) for m in ensemble} | {_lens_of(train_config)})))
        self.ensemble: tuple[Lifter, ...] = tuple(ensemble)
        """More networks for the same (detected) 2D: :meth:`lift` averages the relative pose and the root depth of
        this network and of these, each with its own flip-test default (the root stays on the 2D root's ray). Empty
        for a single network."""
        self.clean = clean
        """The network for ``source="clean"`` when this model has a separate one (:meth:`lift` routes by source);
        None when one network (conditioned on the source, or not) serves both."""
        self.net = net.eval()
        # A mirror network's output mirror follows the codec's statistics: set here, on the network given.
        net.set_target_statistics(codec.target_mean, codec.target_std)
        self.codec = codec
        self.name = name
        self.meta = meta or {}
        self.train_config = train_config
        self.flip_test = bool(flip_test)
        """Default of :meth:`lift`'s ``flip_test``: the shipped default averages every pose with its mirror image,
        so mirror equivariance holds exactly (checkpoints: ``meta["inference"]["flip_test"]``). A network with
        ``symmetry="mirror"`` is mirror-equivariant by construction and never needs it (it is then ignored)."""
        self.weights_sha256 = weights_sha256
        """Hex sha256 of the checkpoint file :attr:`net` was loaded from (what ``sha256sum FILE`` prints; shipped
        files' are checked against the registry's), or None for a network not loaded from a file. It names the file,
        not the live weights: a network changed in memory after loading keeps it. Written into every result's
        ``model_info`` (:meth:`provenance`)."""

    def network_rows(self, flip_test: bool | None = None) -> int:
        """Network rows per pose that :meth:`lift` runs through this network: 2 with the flip test's mirror-image
        pass (``flip_test``, default :attr:`flip_test`), 1 without it or for a network that is mirror-equivariant
        by construction (``symmetry="mirror"``), which never needs it."""
        flip = self.flip_test if flip_test is None else bool(flip_test)
        return 2 if flip and self.config.symmetry != "mirror" else 1

    @property
    def config(self) -> ModelConfig:
        return self.net.config

    @property
    def input_space(self) -> Literal["pixel", "camera"]:
        """What this lifter's networks read (:attr:`LiftResult.input_space`): ``"camera"`` when any of them reads
        the 2D through the focal length (the default), else ``"pixel"`` (the paper's models)."""
        return "camera" if any(m.config.input_space == "camera" for m in (self, *self.ensemble)) else "pixel"

    @property
    def trained_pixel_range(self) -> tuple[float, float, float] | None:
        """For a network that reads pixels (``input_space="pixel"``, the paper's models): the 2D poses it was
        trained on, ``(smallest scale, largest scale, largest centre offset)`` px: Human3.6M's
        (:data:`H36M_POSE_PX`) widened by the typical range of its zoom augmentation, ``2 ** ±zoom_sigma`` (its
        training config; for the shipped ones without one, the registry's ``trained_zoom``). Beyond them its depth
        is an extrapolation: the shipped pixel models place people behind the camera on images 3-4 x H36M's size
        (``benchmarks/bench_invariance.py``), and :meth:`lift` warns. The focal length alone does not matter to
        such a network (it only scales Z). None for a reference-camera network (exact at every image size) and for
        a pixel checkpoint that does not say."""
        if self.config.input_space != "pixel":
            return None
        zoom = self.meta.get("trained_zoom")
        if not (isinstance(zoom, (list, tuple)) and len(zoom) == 2):
            augment = (self.train_config or {}).get("augment")
            if not isinstance(augment, dict):
                return None
            # the zoom's typical range (log2 scale within one standard deviation), not its clip: near the clip a
            # zoomed pose is rare in training, and the models are already far off there (re-trial: sh_mix -71 %
            # on a 4x view, inside its clip range)
            spread = min(float(augment.get("zoom_sigma", 0.0)), float(augment.get("zoom_clip", 0.0)))
            k = 2.0 ** spread if augment.get("zoom") else 1.0
            zoom = (1.0 / k, k)
        lo, hi = float(zoom[0]), float(zoom[1])
        return (H36M_POSE_PX[0] * lo, H36M_POSE_PX[1] * hi, H36M_POSE_PX[2] * hi)

    @property
    def distance_factor(self) -> float:
        """How much farther than the training subjects stood its training moved people along their viewing rays:
        the training config's ``augment.distance_max`` where ``distance_prob`` > 0, else 1, for the least-moved of
        the networks that lift detected 2D (this one and its :attr:`ensemble`; a network without a training config:
        1). The default: 5."""

        def factor(train_config: dict[str, Any] | None) -> float:
            augment = (train_config or {}).get("augment")
            if not isinstance(augment, dict) or float(augment.get("distance_prob", 0.0)) <= 0:
                return 1.0
            return max(1.0, float(augment.get("distance_max", 1.0)))

        return min(factor(m.train_config) for m in (self, *self.ensemble))

    @property
    def misfit_limit(self) -> float | None:
        """2D whose lift misses it by more than this share of its size gets a note (:meth:`output_notes`,
        :func:`lifter.camera.reprojection_misfit`): a limit measured for this network's lifts
        (``meta["misfit_limit"]``; the default's detected networks: :data:`lifter.camera.MAX_DETECTED_MISFIT`, its
        clean network: :data:`lifter.camera.MAX_CLEAN_MISFIT`), None (no such note) for a network nobody measured:
        an untrained or unusual one may not fit even good 2D."""
        v = self.meta.get("misfit_limit")
        return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) and v > 0 else None

    @property
    def far_root_depth_mm(self) -> float:
        """Roots lifted farther than this (mm) from detected 2D get a note (:meth:`output_notes`):
        :data:`FAR_ROOT_DEPTH_MM` for networks trained where the training subjects stood, else the farthest a
        training root was moved to, :data:`TRAINING_ROOT_MAX_MM` times :attr:`distance_factor` (the default: 38 m;
        measured to 50 m, where it is still within 2.3 %: ``scripts/far_people.py``)."""
        return _far_limit_mm(self.distance_factor)

    @property
    def lens(self) -> Lens:
        """The 2D this network learned (training config ``data.lens``; :data:`lifter.data.Lens`): ``"pinhole"``,
        undistorted 2D (the default lifter), or ``"h36m"``, Human3.6M's own 2D with its cameras' lens distortion
        (the paper's models, and any checkpoint that does not say). :meth:`lift` undistorts 2D for which it is
        given a ``distortion`` only for a pinhole network."""
        return _lens_of(self.train_config)

    def network_for(self, source: Source) -> Lifter:
        """The lifter :meth:`lift` runs for 2D told ``source``: :attr:`clean` for ``"clean"`` when this model has a
        separate clean-2D network, else this one (with its :attr:`ensemble`)."""
        return self.clean if source == "clean" and self.clean is not None else self

    def output_notes(self, keypoints: ArrayLike, principal_point: ArrayLike, root: ArrayLike, *,
                     source: Source | None = None, whose: str | None = None,
                     names: Sequence[str] | None = None, relative: ArrayLike | None = None,
                     focal: ArrayLike | None = None, misfit_cause: str | None = None) -> list[OutputNote]:
        """:attr:`LiftResult.warnings` for 2D keypoints ``(..., 17, 2)`` px with their principal point
        ``(..., 2)`` px that this lifter lifted to roots ``(..., 3)`` mm (camera frame): roots behind the camera,
        for a pixel-space network 2D poses outside :attr:`trained_pixel_range`, and (with ``source="detected"``, for
        a reference-camera network) roots farther than :attr:`far_root_depth_mm`. For callers that show one pose of a
        batch (the app), or that name the people of a batch (``whose``, or each one's label ``names`` such as a video's
        ``"track 3"``: :func:`lifter._checks.where_in_batch`). With the relative poses ``(..., 17, 3)`` mm and the
        ``focal`` length px, 2D that its lift does not fit (past :attr:`misfit_limit`; the default's networks:
        :data:`lifter.camera.MAX_DETECTED_MISFIT` for detected 2D, most likely a detector's confident mistake, and
        :data:`lifter.camera.MAX_CLEAN_MISFIT` for clean 2D, most likely joints in another order) is noted too;
        ``misfit_cause``: what that note names as the likely cause instead, where the caller knows better (the app:
        the noise it drew, a dragged joint)."""
        from .normalization import location_and_scale

        root = np.asarray(root, np.float64)
        notes: list[OutputNote] = []
        span = self.trained_pixel_range
        if span is not None and root.size:
            loc, scale = location_and_scale(np.asarray(keypoints, np.float64))
            offset = np.linalg.norm(loc - np.asarray(principal_point, np.float64), axis=-1)
            outside = (scale < span[0] * (1 - 1e-6)) | (scale > span[1] * (1 + 1e-6)) | (offset > span[2] * (1 + 1e-6))
            if np.any(outside):
                first = np.unravel_index(int(np.argmax(outside)), outside.shape) if outside.ndim else ()
                notes.append(OutputNote(
                    f"model {self.name!r} reads pixels and was trained on 2D poses {span[0]:.0f}-{span[1]:.0f} "
                    f"px in scale (RMS radius) centred within {span[2]:.0f} px of the principal point; this "
                    f"one is {float(scale[first]):.0f} px, {float(offset[first]):.0f} px off centre"
                    f"{where_in_batch(outside, whose=whose, names=names)}: its depth is an extrapolation (it can "
                    "place people behind the camera): use the default model, which is exact at any image size, or "
                    "scale the image and its intrinsics down", kind="pixel-range"))
        if source == "detected" and self.input_space == "camera" and root.size:
            k = self.distance_factor
            limit = _far_limit_mm(k)
            far = root[..., 2] > limit
            if np.any(far):
                why = ("farther than the training subjects ever stood (their roots reach 7.6 m), and this model's "
                       "detected-2D networks, trained where they stood, place such people too near (universal_turn "
                       "on exact 2D: -11 % at 9 m, -21 % at 12 m, -38 % at 25 m; scripts/far_people.py): the default "
                       "model (Lifter.from_pretrained()), trained with people moved farther, places them at their "
                       "distance"
                       if k <= 1.0 else
                       f"farther than this model's training moved people (the training subjects' 7.6 m times "
                       f"{k:g}): its depth there is an extrapolation")
                notes.append(OutputNote(f"{int(far.sum())} of {far.size} root(s) lifted beyond {limit / 1000:.1f} m"
                                        f"{where_in_batch(far, whose=whose, names=names)}: {why}", kind="far"))
        limit = self.misfit_limit
        if limit is not None and relative is not None and focal is not None and root.size:
            absolute = np.asarray(relative, np.float64) + root[..., None, :]
            f2 = np.asarray(focal, np.float64)  # (checked by lift; the app passes its own checked pair)
            misfit = _misfit(np.asarray(keypoints, np.float64), absolute, (f2 if f2.ndim else f2[None])[..., None, :])
            off = misfit > limit  # (NaN, a joint behind the camera, has its own note below)
            if np.any(off):
                worst = float(np.nanmax(np.where(off, misfit, np.nan)))
                notes.append(OutputNote(
                    f"{int(off.sum())} of {off.size} lifted pose(s) do not fit their 2D"
                    f"{where_in_batch(off, whose=whose, names=names)}: projected back, the joints lie up to "
                    f"{worst:.1%} of the 2D pose's size from it (median joint), where "
                    + ("exact 2D of real people stays" if source == "clean" else "a detector's usual errors leave")
                    + f" under {limit:.0%}: the 2D is probably wrong in places ("
                    + (misfit_cause or ("joints in another order than Human3.6M's (lifter.JOINT_NAMES), or placed "
                                        "where no body bends" if source == "clean" else
                                        "a confident detector mistake: joints bunched together or on the wrong limb"))
                    + "), and so is the lift; check the 2D",
                    kind="misfit"))
        behind = root[..., 2] <= 0
        if np.any(behind):
            notes.append(OutputNote(
                f"the model placed {int(behind.sum())} of {behind.size} root(s) behind the camera (Z <= 0)"
                f"{where_in_batch(behind, whose=whose, names=names)}: the 2D is outside what it was trained on; "
                "the result is not a valid pose"
                + ("" if self.config.input_space == "camera" else " (a pixel-space model: use the default model)"),
                kind="behind-camera"))
        return notes

    # -- construction --------------------------------------------------------------------------------
    @classmethod
    def _from(cls, ck: Checkpoint, name: str, quantize: bool, flip_test: bool | None = None,
              clean: Checkpoint | None = None, ensemble: Sequence[Checkpoint] = ()) -> Lifter:
        """flip_test: the model's default for every network (the registry's ``flip_test``); None: each network's
        own checkpoint default (``meta["inference"]["flip_test"]``, else off)."""

        def flip(c: Checkpoint) -> bool:
            if flip_test is not None:
                return bool(flip_test)
            inference = c.meta.get("inference")
            return bool(inference.get("flip_test", False)) if isinstance(inference, dict) else False

        clean_lifter = None if clean is None else cls(clean.net, clean.codec, name=f"{name} (clean 2D)",
                                                       meta=clean.meta, train_config=clean.train_config,
                                                       flip_test=flip(clean), weights_sha256=clean.sha256)
        members = [cls(m.net, m.codec, name=f"{name} (member {i + 2})", meta=m.meta, train_config=m.train_config,
                       flip_test=flip(m), weights_sha256=m.sha256) for i, m in enumerate(ensemble)]
        lifter = cls(ck.net, ck.codec, name=name, meta=ck.meta, train_config=ck.train_config, flip_test=flip(ck),
                     clean=clean_lifter, ensemble=members, weights_sha256=ck.sha256)
        return lifter.quantized() if quantize else lifter

    @classmethod
    def from_checkpoint(cls, path: str | os.PathLike[str], *, name: str | None = None, quantize: bool = False,
                        clean: str | os.PathLike[str] | None = None,
                        ensemble: Sequence[str | os.PathLike[str]] = ()) -> Lifter:
        """Load your own checkpoint file (``weights_only=True``; :mod:`lifter.checkpoint`). ``clean``: a second
        checkpoint used for ``source="clean"`` (the first then serves detected 2D). ``ensemble``: more checkpoints
        for detected 2D, averaged with the first (:attr:`ensemble`). Each network keeps its checkpoint's
        flip-test default."""
        return cls._from(load_checkpoint(path), name or Path(path).stem, quantize,
                         clean=None if clean is None else load_checkpoint(clean),
                         ensemble=[load_checkpoint(m) for m in ensemble])

    @classmethod
    def from_pretrained(cls, name: str | os.PathLike[str] | None = "default", *, quantize: bool = False) -> Lifter:
        """Shipped weights by name (``"default"``, or one of :func:`available_models`), checked against their
        sha256; or a checkpoint path (``.pt``) of your own; or several joined by ``+`` (``"a.pt+b.pt"``): an
        ensemble for detected 2D whose lifts are averaged (:attr:`ensemble`; :meth:`from_checkpoint` with
        ``ensemble=``), each network with its checkpoint's flip-test default. ``quantize=True``: see
        :meth:`quantized`. ``None`` is the default (a developer trial's ``None`` read "unknown model 'None'")."""
        ref, shipped = ("default" if name is None else str(name)), assets.model_names()
        if "+" in ref and ref not in shipped and not Path(ref).is_file() and (
                any(part in (*shipped, "default") for part in ref.split("+")) or not ref.endswith(".pt")):
            raise PoseLifterError(f"{ref!r}: shipped models cannot be joined by '+' (the default already averages its "
                                  "networks); '+' joins checkpoint files ending in .pt into an ensemble (A.pt+B.pt)")
        if ref != "default" and ref not in shipped and (ref.endswith(".pt") or Path(ref).is_file()):
            # shipped names win over same-named local files; a file whose name holds "+" is that file
            if len(parts := ensemble_parts(ref)) > 1:
                for part in parts:
                    if not Path(part).is_file():
                        raise CheckpointError(f"weights file not found: {part} (in {ref!r}, read as checkpoints joined "
                                              "by '+' into an ensemble: A.pt+B.pt)")
                return cls.from_checkpoint(parts[0], name="+".join(Path(p).stem for p in parts), quantize=quantize,
                                           ensemble=parts[1:])
            return cls.from_checkpoint(ref, quantize=quantize)
        entry = assets.model_entry(ref)
        ck = load_checkpoint(assets.read_bytes(entry["file"]), expected_sha256=entry.get("sha256"),
                             name=f"shipped model {entry['name']!r} ({entry['file']})")
        clean = None
        if clean_file := entry.get("clean_file"):
            clean = load_checkpoint(assets.read_bytes(clean_file), expected_sha256=entry.get("clean_sha256"),
                                    name=f"shipped model {entry['name']!r} ({clean_file})")
        members = [load_checkpoint(assets.read_bytes(f), expected_sha256=h,
                                   name=f"shipped model {entry['name']!r} ({f})")
                   for f, h in assets.ensemble_members(entry)]
        if "trained_zoom" in entry:  # (shipped pixel models older than training configs in checkpoints)
            ck = dataclasses.replace(ck, meta={**ck.meta, "trained_zoom": entry["trained_zoom"]})
        if "misfit_limit" in entry:  # (measured on the shipped networks after they were written)
            ck = dataclasses.replace(ck, meta={**ck.meta, "misfit_limit": entry["misfit_limit"]})
        if clean is not None and "clean_misfit_limit" in entry:
            clean = dataclasses.replace(clean, meta={**clean.meta, "misfit_limit": entry["clean_misfit_limit"]})
        return cls._from(ck, entry["name"], quantize, flip_test=entry.get("flip_test"), clean=clean, ensemble=members)

    load = from_pretrained
    """Alias of :meth:`from_pretrained`: a shipped name or a checkpoint path."""

    def networks(self) -> dict[str, Lifter]:
        """Each network of this model as a lifter of its own (same weights, codec, training config and flip-test
        default; no clean network, no ensemble): ``"detected"`` (:attr:`net`; ``"detected 1"``, ``"detected 2"``, ...
        with an :attr:`ensemble`) and ``"clean"`` when the model has a separate clean-2D network. For one network,
        ``{"detected": self}``-alike. What :meth:`save` writes, one at a time."""
        return {key: Lifter(m.net, m.codec, name=f"{self.name} ({key})", meta=m.meta, train_config=m.train_config,
                            flip_test=m.flip_test, weights_sha256=m.weights_sha256)
                for key, m in self._keyed_networks()}

    def _keyed_networks(self) -> list[tuple[str, Lifter]]:
        """:meth:`networks`' keys with the lifters this model holds (not copies)."""
        detected = (self, *self.ensemble)
        out = [("detected" if len(detected) == 1 else f"detected {i + 1}", m) for i, m in enumerate(detected)]
        return out + ([] if self.clean is None else [("clean", self.clean)])

    @property
    def int8(self) -> bool:
        """Whether :attr:`net` runs int8 weights (:meth:`quantized`)."""
        return any(isinstance(m, QuantizedCoupledLinear) or type(m).__module__.startswith("torch.ao.nn.quantized")
                   for m in self.net.modules())

    def provenance(self, *, source: Source = "detected", flip_test: bool | None = None) -> dict[str, Any]:
        """What lifted a result, as every written result's ``model_info`` gives it: the model's :attr:`name`, the
        poselifter version, and each network that 2D told ``source`` runs through (:meth:`network_for`, with its
        :attr:`ensemble`), in the order of :meth:`networks`. Per network: ``network``, its key in :meth:`networks`
        of this lifter (one network taken out, ``model.networks()["clean"]``, is a model of one: ``"detected"``);
        ``sha256`` of its checkpoint file (:attr:`weights_sha256`; None when not loaded from a file); ``flip_test``
        as :meth:`lift` applies it with this ``flip_test`` argument (False for a mirror-equivariant network, which
        needs no mirror pass: ``symmetry`` says so); and ``int8``. JSON-ready."""
        from . import __version__

        used = self.network_for(source)
        members = {id(m) for m in (used, *used.ensemble)}
        return {"name": self.name, "poselifter_version": __version__, "networks": [
            {"network": key, "sha256": m.weights_sha256, "flip_test": m.network_rows(flip_test) == 2,
             "symmetry": m.config.symmetry, "int8": m.int8}
            for key, m in self._keyed_networks() if id(m) in members]}

    def save(self, path: str | os.PathLike[str], *, half: bool = False) -> Path:
        """Write this lifter's network (:attr:`net`, with its codec, training config and flip-test default) as a
        checkpoint that :meth:`from_checkpoint` loads back to the same lifts (``half=True``: float16 weights). A
        checkpoint holds one network: a model with a separate clean-2D network or an ensemble (like the shipped
        default) is refused, since its reloaded file would lift differently; save one of :meth:`networks`."""
        if self.clean is not None or self.ensemble:
            names = list(self.networks())
            raise PoseLifterError(
                f"model {self.name!r} has {len(names)} networks ({', '.join(names)}) and a checkpoint holds one, so "
                "the file would not lift like this model: save one of them, e.g. "
                f"model.networks()[{names[0]!r}].save(path) (model: this Lifter), or refer to this model by its name "
                f"(Lifter.from_pretrained({self.name!r}))")
        if self.int8:
            raise PoseLifterError(f"model {self.name!r} has int8 weights, which a checkpoint does not hold: save the "
                                  "float32 lifter, and load it with from_checkpoint(path, quantize=True)")
        inference = self.meta.get("inference")
        meta = {**self.meta, "inference": {**(inference if isinstance(inference, dict) else {}),
                                           "flip_test": self.flip_test}}
        return save_checkpoint(path, self.net, self.codec, train_config=self.train_config, meta=meta, half=half)

    def refresh(self) -> Lifter:
        """Drop the float16-packed copies of every network's weight matrices (:func:`lifter.model.forward_packed`):
        needed only after a sparse change to a matrix through ``.data``, a numpy view or its storage, which neither
        torch's version counters nor the first-and-last-row check see (changes through torch operations,
        ``load_state_dict``, new tensors or writes of whole matrices are seen without it). Returns ``self``."""
        for m in (self, *self.ensemble, *([] if self.clean is None else [self.clean])):
            drop_packed(m.net)
        return self

    def quantized(self) -> Lifter:
        """A copy whose residual-block Linear layers use int8 weights (dynamic quantization): a quarter of the
        block weight memory. It always runs the torch module. The stem and head stay float32. A mirror network's
        coupled layers become :class:`~lifter.model.QuantizedCoupledLinear` (both products int8). Dynamic
        quantization scales the activations by the range of the whole batch: a pose's int8 result changes by a few
        mm with the other poses lifted in the same call (and the flip test's mirror symmetry holds to ~mm only);
        the float32 lifter has neither effect."""
        net = copy.deepcopy(self.net)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # the plain Linear layers first, then each coupled layer once (it quantizes its own two products)
            net.blocks = torch.ao.quantization.quantize_dynamic(net.blocks, {torch.nn.Linear}, dtype=torch.qint8)
            for block in net.blocks:
                body: torch.nn.Sequential = block.body  # type: ignore[assignment]
                for i, layer in enumerate(body):
                    if isinstance(layer, MirrorCoupledLinear):
                        body[i] = QuantizedCoupledLinear(layer)
        return Lifter(net, self.codec, name=f"{self.name} (int8)", meta=self.meta, train_config=self.train_config,
                      flip_test=self.flip_test, clean=None if self.clean is None else self.clean.quantized(),
                      ensemble=[m.quantized() for m in self.ensemble], weights_sha256=self.weights_sha256)

    # -- lifting -------------------------------------------------------------------------------------
    def lift(
        self,
        keypoints: ArrayLike,
        *,
        focal: ArrayLike | None = None,
        principal_point: ArrayLike | None = None,
        image_size: ArrayLike | None = None,
        source: Source = "detected",
        distortion: ArrayLike | None = None,
        distortion_model: DistortionModel = "h36m",
        flip_test: bool | None = None,
        warn: bool = True,
        whose: str | None = None,
    ) -> LiftResult:
        """Lift 2D keypoints ``(..., 17, 2)`` px (H36M joint order, :data:`lifter.JOINT_NAMES`) to absolute 3D.

        focal: ``fx = fy`` scalar, ``(fx, fy)`` or per pose ``(..., 2)`` px (a bare ``(2,)`` always means
            ``(fx, fy)``). None: unknown; then the default diagonal field of view
            (:data:`lifter.camera.DEFAULT_DIAGONAL_FOV_DEG`) of ``image_size`` is assumed, or a 1000-px
            reference camera without an image size, and the result says so (``metric_depth=False``).
        principal_point: ``(cx, cy)`` or ``(..., 2)`` px; defaults to the image centre of ``image_size``.
        image_size: ``(width, height)`` px, or per pose ``(..., 2)``, for the defaults above.
        source: ``"detected"`` (default): 2D from a detector; ``"clean"``: exact 2D (ground truth,
            hand-placed or dragged joints). The lifter uses what it was trained for on each.
        distortion: the lens distortion of the camera that saw the 2D, ``(k1, k2, k3, p1, p2)`` or per pose
            ``(..., 5)``, in Human3.6M's Brown-Conrady form (:func:`lifter.camera.distort`; its radial terms are
            OpenCV's, its tangential terms are not). None (default): the 2D is already undistorted, or the
            distortion is not known. The default lifter's networks learned undistorted (pinhole) 2D, so given a
            distortion it undistorts the keypoints first (:func:`lifter.camera.undistort_pixels`) and lifts those
            (:attr:`LiftResult.keypoints_2d`); the paper's models learned H36M's distorted 2D
            (:attr:`lens` ``"h36m"``) and are given the keypoints as they are. Needs the camera's focal length.
            Tangential terms above :data:`lifter.camera.MAX_PLAUSIBLE_TANGENTIAL` are warned of (OpenCV's
            coefficients in Human3.6M's order put OpenCV's k3 there).
        distortion_model: the form of ``distortion``: ``"h36m"`` (default), Human3.6M's ``(k1, k2, k3, p1, p2)``
            above, or ``"opencv"``, OpenCV's ``distCoeffs`` ``(k1, k2, p1, p2[, k3[, k4, k5, k6]])`` exactly as
            ``cv2.calibrateCamera`` gives them (4, 5 or 8 values, or one row per pose), undone by OpenCV's own
            model (:func:`lifter.camera.undistort_pixels_opencv`); ``focal`` and ``principal_point`` are then
            ``K[0, 0], K[1, 1]`` and ``K[0, 2], K[1, 2]`` of the same calibration.
        flip_test: also lift the mirrored input and average: the result is then exactly mirror-equivariant.
            None: the model's default (:attr:`flip_test`). Ignored by networks that are mirror-equivariant by
            construction (``symmetry="mirror"``, like the default's second detected network): for them it would
            give the same result.
        warn: warn (:class:`lifter.PoseLifterWarning`) of input that is taken but looks wrong
            (:func:`lifter._checks.input_warnings`); False for callers that report it themselves (the records'
            notes, the app's readout). A keyword rather than ``warnings.catch_warnings``, which is not thread-safe.
        whose: the batch is a list of people (``(n, 17, 2)``: one image's, file's or frame's, as a record lists
            them); :attr:`LiftResult.warnings` then name them "person 2 of <whose>" (:meth:`output_notes`).
        """
        target = self.network_for(source)
        return target._lift_checked(keypoints, focal=focal, principal_point=principal_point, image_size=image_size,
                                    source=source, distortion=distortion, distortion_model=distortion_model,
                                    flip_test=flip_test, warn=warn, whose=whose)

    def _lift_checked(self, keypoints: ArrayLike, *, focal: ArrayLike | None, principal_point: ArrayLike | None,
                      image_size: ArrayLike | None, source: Source, distortion: ArrayLike | None,
                      flip_test: bool | None, warn: bool, whose: str | None = None,
                      distortion_model: DistortionModel = "h36m") -> LiftResult:
        """:meth:`lift` on this network (the input checks, then the networks); its warnings name lift's caller."""
        if source not in SOURCES:
            raise PoseLifterError(f"source must be one of {list(SOURCES)}, got {source!r}")
        if flip_test is not None and not isinstance(flip_test, (bool, np.bool_)):
            raise PoseLifterError(f"flip_test must be True, False or None (the model's default), got {flip_test!r}")
        lens_model = check_distortion_model(distortion_model)
        kp = as_points(keypoints, name="keypoints", dim=2, num_joints=NUM_JOINTS)
        lead = kp.shape[:-2]
        wh = None if image_size is None else as_pair(image_size, name="image_size", positive=True)
        if wh is not None and wh.ndim > 1:  # one per pose: checked here, before the defaults it gives
            wh = _broadcast(wh, lead, name="image_size")
        pp_given = principal_point is not None
        if principal_point is None:
            if wh is None:
                raise PoseLifterError("principal_point is required (or pass image_size=(width, height) to use the "
                                      "image centre)")
            principal_point = image_centre(wh)
        pp = _broadcast(as_pair(principal_point, name="principal_point"), lead, name="principal_point")
        focal_source: FocalSource = "given"
        if focal is None:
            if any(m.config.input_space == "pixel" and m.config.depth_target == "absolute"
                   for m in (self, *self.ensemble)):
                raise PoseLifterError(f"model {self.name!r} predicts absolute depth and needs the focal length")
            if wh is not None:
                if wh.ndim == 1:
                    focal = focal_from_fov(wh, fov_deg=DEFAULT_DIAGONAL_FOV_DEG)
                else:  # one image size per pose (mixed cameras): each its own default focal length
                    one = np.asarray(focal_from_fov(wh, fov_deg=DEFAULT_DIAGONAL_FOV_DEG))
                    focal = np.stack([one, one], axis=-1)
                focal_source = "default-fov"
            else:
                focal, focal_source = CANONICAL_FOCAL, "reference"
        f = _broadcast(as_pair(focal, name="focal", positive=True, scalar=True, lead=lead), lead, name="focal",
                       given=focal)
        # (a principal point left out is image_size's centre: image_size is named, a developer trial's 1e9 x 1e9
        # image was refused as a principal point it had not given)
        sizes = (("image_size", wh),) if wh is not None and not pp_given else (("principal_point", pp),)
        for name, arr in (("keypoints", kp), *sizes, ("focal", f)):
            if arr.size and float(np.abs(arr).max()) > MAX_ABS_PX:
                raise PoseLifterError(f"{name}: values up to {float(np.abs(arr).max()):.3g} px; image pixel values "
                                      f"must be below {MAX_ABS_PX:.0e} in magnitude")
        scale = pose_scale(kp)
        if np.any(scale < DEGENERATE_SCALE_PX):
            raise PoseLifterError(
                f"degenerate pose{where_in_batch(scale < DEGENERATE_SCALE_PX)}: all 17 joints at (nearly) one point "
                f"(2D scale {float(scale.min()):.2g} px); the normalization needs a pose with non-zero extent")
        if np.any(scale < MIN_POSE_SCALE_PX):
            raise PoseLifterError(
                f"2D pose scale {float(scale.min()):.3g} px{where_in_batch(scale < MIN_POSE_SCALE_PX)} is too small "
                f"(< {MIN_POSE_SCALE_PX} px): keypoints must be in image pixels (normalized [0, 1] coordinates? "
                "multiply by the image size)")
        if f.size and float(f.min()) < MIN_FOCAL_PX:
            raise PoseLifterError(
                f"focal: {float(f.min()):.3g} px is too small (< {MIN_FOCAL_PX:g} px): the focal length must be in "
                "pixels, not mm (f_px = f_mm * image width px / sensor width mm), or leave it out (focal=None) to "
                "assume a default field of view")
        said: list[str] = []  # (what looks wrong in the lens: lens_notes)
        if distortion is not None:
            if focal_source != "given":
                raise PoseLifterError("distortion needs the focal length of the camera it belongs to: pass focal= "
                                      "(px) too, or leave distortion out")
            d = check_lens(distortion, lens_model, lead=lead)  # (also for a network given the 2D as it is)
            said = lens_notes(d, lens_model)
            if self.lens != "pinhole" and np.any(d):  # (a developer trial's lens made no difference, and nothing said)
                said = [f"model {self.name!r} learned Human3.6M's 2D with that camera's own lens distortion and lifts "
                        "the keypoints as they are: the distortion given is not undone (the default model undoes "
                        "it)", *said]
            if self.lens == "pinhole":
                try:
                    kp = (undistort_pixels_opencv(kp, focal=f, principal_point=pp, dist_coeffs=d)
                          if lens_model == "opencv"
                          else undistort_pixels(kp, focal=f, principal_point=pp, distortion=d))
                except PoseLifterError as exc:
                    if not said:
                        raise
                    raise PoseLifterError(f"{exc}. Also: {said[0]}") from None
        # (the view check at an assumed focal too, as the records check it: keypoints in another image's pixels)
        in_list = input_warnings(kp, None if focal_source == "reference" else f, focal_given=focal_source == "given")
        in_list += said
        in_list += outside_image_notes(kp, wh, name_pose=True)
        if pp_given and wh is not None and wh.ndim == 1:  # (the records' own note, for API calls)
            flat = pp.reshape(-1, 2)
            if len(flat) and np.all(flat == flat[0]):
                in_list += principal_point_notes(flat[0], (int(wh[0]), int(wh[1])))
        if focal_source == "given" and wh is not None and wh.ndim == 1:
            flat_focal = f.reshape(-1, 2)
            if len(flat_focal) and np.all(flat_focal == flat_focal[0]):
                in_list += view_angle_notes(flat_focal[0], (int(wh[0]), int(wh[1])))
        in_list += upside_down_notes(kp)
        in_list += sideways_notes(kp)
        in_list += lean_notes(kp)
        in_list += face_first_notes(kp)
        in_notes = tuple(in_list)
        if warn:
            for message in in_notes:
                warn_user(message)

        flat_kp = kp.reshape(-1, NUM_JOINTS, 2)
        flat_pp = pp.reshape(-1, 2)
        flat_f = f.reshape(-1, 2)
        flat_alpha = focal_alpha(flat_f)  # float64; checked once here, shared by every network and chunk
        n = len(flat_kp)
        rel = np.empty((n, NUM_JOINTS, 3))
        root = np.empty((n, 3))
        canonical = np.empty(n)
        for s in range(0, n, CHUNK_SIZE):
            sl = slice(s, min(n, s + CHUNK_SIZE))
            # every network with its own flip-test default unless the call gives one; networks whose codecs
            # encode alike share the encodings (``encoded``)
            encoded: dict[tuple[Any, ...], Encoded[np.ndarray]] = {}
            outs = [m._lift_flat(flat_kp[sl], flat_pp[sl], flat_f[sl], flat_alpha[sl], source,
                                 m.network_rows(flip_test) == 2, encoded=encoded)
                    for m in (self, *self.ensemble)]
            rel[sl], root[sl], canonical[sl] = (sum(o[i] for o in outs) / len(outs) for i in range(3))
        if not (np.all(np.isfinite(rel)) and np.all(np.isfinite(root))):
            raise PoseLifterError(f"model {self.name!r} produced non-finite outputs (corrupt weights?)")
        rel = rel.reshape(lead + (NUM_JOINTS, 3))
        root = root.reshape(lead + (3,))
        absolute = rel + root[..., None, :]
        notes = self.output_notes(kp, pp, root, source=source, whose=whose, relative=rel, focal=f)
        if warn:
            for message in notes:
                warn_user(message)
        return LiftResult(absolute=absolute, root=root, relative=rel, canonical_depth=canonical.reshape(lead),
                          keypoints_2d=np.array(kp), principal_point=np.array(pp), focal=np.array(f),
                          focal_source=focal_source,
                          metric_depth=depth_is_metric(focal_source), source=source, input_space=self.input_space,
                          warnings=tuple(notes), input_warnings=in_notes)

    def _lift_flat(self, kp: np.ndarray, pp: np.ndarray, f: np.ndarray, alpha: np.ndarray, source: Source,
                   flip_test: bool, *, encoded: dict[tuple[Any, ...], Encoded[np.ndarray]] | None = None
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(N, 17, 2)``, ``(N, 2)``, ``(N, 2)`` px and ``alpha = focal_alpha(f)`` ``(N,)`` px -> relative
        ``(N, 17, 3)``, root ``(N, 3)`` mm, canonical ``(N,)``.
        encoded: encodings of these inputs by :attr:`PoseCodec.feature_key` (and its mirror image), shared by the
        networks of one call; filled here."""
        codec = self.codec
        encoded = {} if encoded is None else encoded
        kp32, pp32, f32 = kp.astype(np.float32), pp.astype(np.float32), f.astype(np.float32)

        def encode(mirrored: bool) -> Encoded[np.ndarray]:
            key = (*codec.feature_key, mirrored)
            if key not in encoded:
                k = codec.mirror_input(kp32, pp32) if mirrored else kp32
                encoded[key] = codec.encode(k, principal_point=pp32, focal=f32, source=source)
            return encoded[key]

        enc = encode(False)
        feats = enc.features
        if flip_test:
            feats = np.concatenate([feats, encode(True).features])
        out = self._network(np.ascontiguousarray(feats, np.float32))
        raw = codec.destandardize(out.astype(np.float64))
        if flip_test:
            raw = codec.flip_average(raw, len(kp))
        # float64 from here on: the features alone were float32
        alpha_in = alpha if codec.config.input_space == "pixel" else np.full_like(alpha, codec.reference_focal)
        rotation = ray_norm = None
        if codec.config.view == "look_at":  # the turn again in float64, as the decoding is
            _, rotation, ray_norm = codec.look_at(codec.input_space(kp, pp, f)[0])
        enc64 = Encoded(features=enc.features, sigma_in=enc.sigma_in.astype(np.float64), alpha_in=alpha_in, alpha=alpha,
                        rotation=rotation, ray_norm=ray_norm)
        dec = codec.decode(raw, enc64, root_2d=kp[:, 0], principal_point=pp, focal=f)
        return dec.relative, dec.root, dec.canonical_depth

    def _network(self, features: np.ndarray) -> np.ndarray:
        """Standardized network outputs ``(N, 49)`` for features ``(N, F)`` float32."""
        net = self.net
        device = next(net.parameters()).device
        if device.type != "cpu":
            raise PoseLifterError(f"model {self.name!r} is on {device}; Lifter.lift runs the network on the CPU "
                                  "(numpy in, numpy out): move it back with lifter.net.cpu()")
        out = forward_packed(net, features)  # (a few rows, float16-exact matrices; else None)
        if out is not None:
            return out
        if len(features) <= NUMPY_MAX_BATCH:
            out = forward_numpy(net, features)
            if out is not None:
                return out
        if any(m.training for m in net.modules() if isinstance(m, (torch.nn.Dropout, torch.nn.BatchNorm1d))):
            raise PoseLifterError(f"model {self.name!r} is in training mode (dropout, batch statistics): call "
                                  "lifter.net.eval()")
        with torch.inference_mode():
            x = torch.from_numpy(features)
            folded = forward_folded(net, x)
            return (folded if folded is not None else net(x)).numpy()

    def __repr__(self) -> str:
        c = self.config
        return (f"Lifter(name={self.name!r}, input_space={c.input_space!r}, "
                + (f"view={c.view!r}, " if c.view != "camera" else "") + f"depth_target={c.depth_target!r}, "
                f"conditioning={c.conditioning!r}, width={c.width}, flip_test={self.flip_test}"
                + (", separate clean-2D network" if self.clean is not None else "")
                + (f", ensemble of {1 + len(self.ensemble)} networks" if self.ensemble else "") + ")")
