"""The codec: 2D keypoints -> network features, 3D -> network targets, network outputs -> 3D.

One object (:class:`PoseCodec`) owns every convention between the data and the network, as mmpose's
``ImagePoseLifting`` codec does, and training and inference share it:

* **encode** (:meth:`PoseCodec.encode`): 2D keypoints ``(..., 17, 2)`` px, principal point and focal length
  (px) and the input's source -> features ``(..., F)``:

  1. the 2D is expressed relative to the principal point, in the *input space* of the model:
     ``"pixel"``: image pixels, ``p - c`` (the paper); ``"camera"``: the reference camera of focal
     F0 = 1000 px, ``(p - c) F0 / f`` (:func:`lifter.camera.to_reference_camera`), where image
     resolution and focal length are exact symmetries;
  1b. with ``view="look_at"`` (:meth:`PoseCodec.look_at`), the reference camera turned about its centre to look at
     the 2D root: an exact change of view (every viewing ray kept) after which the root is at the principal point;
  2. the normalization layer (:func:`lifter.normalization.pose_features`): normalized pose, location
     ``u`` and scale ``sigma`` (kilo-px);
  3. with ``conditioning="source"``, one more feature: 1 for exact 2D (``"clean"``), 0 for detector
     output (``"detected"``).

* **targets** (:meth:`PoseCodec.encode_targets`): the root-relative pose (48 numbers, joints 1..16, mm; looking
  at the root, in that turned camera's frame)
  and the depth parameter of :class:`lifter.model.ModelConfig`'s ``depth_target``, in mm;
  **standardization** (:meth:`PoseCodec.standardize` / :meth:`PoseCodec.destandardize`) with the
  training targets' mean and std, which the codec stores (and the checkpoint with it).

* **decode** (:meth:`PoseCodec.decode`): network outputs in mm -> :class:`Decoded` relative pose,
  root depth Z, canonical depth ``Z F0 / alpha`` and the absolute root (the pose turned back to the camera
  frame when the network looked at the root), which back-projects the
  input's 2D root at depth Z (PoseLifter Eq. 5-6).

Units: px and mm. Camera frame: OpenCV (+x right, +y down, +z forward). ``alpha = sqrt(fx fy)`` px.
Every method works on numpy arrays and torch tensors (differentiable), batched over leading dimensions.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final, Generic, Literal, TypeVar

import numpy as np
import torch

from ._array import namespace as array_namespace
from ._checks import PoseLifterError
from .camera import (
    CANONICAL_FOCAL,
    alpha_generic,
    backproject_generic,
    look_at_rotation,
    to_reference_camera,
    turn_pixels,
)
from .model import NUM_OUTPUTS, ModelConfig
from .normalization import location_and_scale, pose_features
from .skeleton import NUM_JOINTS, mirror

Source = Literal["detected", "clean"]
SOURCES: Final[tuple[str, ...]] = ("detected", "clean")
"""What the 2D is: ``"detected"`` (a 2D detector's output, the default) or ``"clean"`` (exact: ground truth,
hand-placed or dragged joints)."""

A = TypeVar("A", np.ndarray, torch.Tensor)


@dataclass(frozen=True)
class Encoded(Generic[A]):
    """The codec's view of a batch of 2D inputs.

    features: ``(..., F)`` network inputs. sigma_in: ``(...)`` the 2D scale in the input space (px of
    the input camera). alpha_in: ``(...)`` the input camera's focal length (px): ``alpha`` for the
    pixel space, F0 for the reference camera. alpha: ``(...)`` the real camera's ``sqrt(fx fy)`` px.
    rotation, ray_norm: with ``view="look_at"`` (:class:`~lifter.model.ModelConfig`), the turn ``(..., 3, 3)`` from
    the camera frame to the virtual camera that looks at the 2D root (:func:`lifter.camera.look_at_rotation`), and
    the length ``(...)`` of the 2D root's viewing ray ``(x/f, y/f, 1)``: the root's depth in that camera is ``Z *
    ray_norm``. None otherwise.
    """

    features: A
    sigma_in: A
    alpha_in: A
    alpha: A
    rotation: A | None = None
    ray_norm: A | None = None


@dataclass(frozen=True)
class Decoded(Generic[A]):
    """Decoded network outputs, all mm, camera frame.

    relative: ``(..., 17, 3)`` root-relative pose, root row zero. depth: ``(...)`` root Z.
    canonical_depth: ``(...)`` ``Z * F0 / alpha``. root: ``(..., 3)`` absolute root (2D root back-projected at Z).
    """

    relative: A
    depth: A
    canonical_depth: A
    root: A


def _like(x: Any, ref: A) -> A:
    """``x`` (a number or numpy array) as an array of ``ref``'s type, dtype and device."""
    if isinstance(ref, torch.Tensor):
        if isinstance(x, torch.Tensor):
            return x.to(dtype=ref.dtype, device=ref.device)  # type: ignore[return-value]
        return torch.as_tensor(np.asarray(x), dtype=ref.dtype, device=ref.device)  # type: ignore[return-value]
    return np.asarray(x, dtype=ref.dtype)  # type: ignore[attr-defined, return-value]


class PoseCodec:
    """Encode/decode for one :class:`~lifter.model.ModelConfig` (module docstring).

    target_mean, target_std: ``(49,)`` statistics of the training targets (mm): outputs are
    ``mean + std * network(features)``. Defaults: 0 and 1 (an untrained codec).
    """

    def __init__(self, config: ModelConfig, *, target_mean: Any = None, target_std: Any = None,
                 reference_focal: float = CANONICAL_FOCAL) -> None:
        self.config = config
        self.reference_focal = float(reference_focal)
        mean = np.zeros(NUM_OUTPUTS) if target_mean is None else np.asarray(target_mean, np.float64)
        std = np.ones(NUM_OUTPUTS) if target_std is None else np.asarray(target_std, np.float64)
        if mean.shape != (NUM_OUTPUTS,) or std.shape != (NUM_OUTPUTS,):
            raise ValueError(f"target statistics must have shape ({NUM_OUTPUTS},), got {mean.shape} and {std.shape}")
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(std)) and np.all(std > 0)):
            raise ValueError("target statistics must be finite, with std > 0")
        self.target_mean = mean
        self.target_std = std

    # -- state ---------------------------------------------------------------------------------------
    def state_dict(self) -> dict[str, torch.Tensor]:
        return {"target_mean": torch.tensor(self.target_mean, dtype=torch.float64),
                "target_std": torch.tensor(self.target_std, dtype=torch.float64)}

    @classmethod
    def from_state_dict(cls, config: ModelConfig, state: dict[str, Any]) -> PoseCodec:
        return cls(config, target_mean=np.asarray(state["target_mean"]), target_std=np.asarray(state["target_std"]))

    # -- inputs ---------------------------------------------------------------------------------------
    @property
    def feature_key(self) -> tuple[Any, ...]:
        """Everything :meth:`encode` depends on besides its arguments: two codecs with equal keys give equal
        encodings of the same input (an ensemble encodes once for its networks that share one)."""
        c = self.config
        return (c.input_space, c.view, c.mode, c.scale_definition, c.conditioning, self.reference_focal)

    def input_space(self, keypoints: A, principal_point: Any, focal: Any) -> tuple[A, A, A]:
        """Keypoints ``(..., 17, 2)`` in the input space, relative to its principal point; the input camera's
        focal ``alpha_in`` ``(...)`` and the real ``alpha`` ``(...)`` px."""
        xp = array_namespace(keypoints)
        f, c = _like(focal, keypoints), _like(principal_point, keypoints)
        alpha = alpha_generic(f)
        if self.config.input_space == "camera":
            k = to_reference_camera(keypoints, focal=f, principal_point=c, reference_focal=self.reference_focal)
            alpha_in = xp.full_like(alpha, self.reference_focal)
        else:
            k = keypoints - c[..., None, :]  # type: ignore[index, operator]
            alpha_in = alpha
        return k, alpha_in, alpha

    def encode(self, keypoints: A, *, principal_point: Any, focal: Any, source: Any = "detected") -> Encoded[A]:
        """Features for 2D keypoints ``(..., 17, 2)`` px with principal point and focal ``(..., 2)`` px.

        source: ``"detected"`` / ``"clean"`` for all inputs, or a boolean array ``(...)``, True = clean.
        Ignored unless the model is conditioned on it.
        """
        xp = array_namespace(keypoints)
        k, alpha_in, alpha = self.input_space(keypoints, principal_point, focal)
        rotation = ray_norm = None
        if self.config.view == "look_at":
            k, rotation, ray_norm = self.look_at(k)
        u, sigma = location_and_scale(k, scale_definition=self.config.scale_definition)
        feats = pose_features(k, mode=self.config.mode, scale_definition=self.config.scale_definition,
                              location_scale=(u, sigma))
        if self.config.conditioning == "source":
            flag = self.source_flag(source, like=sigma)
            feats = xp.concat([feats, flag[..., None]], axis=-1)
        return Encoded(features=feats, sigma_in=sigma, alpha_in=alpha_in, alpha=alpha, rotation=rotation,  # type: ignore[return-value]
                       ray_norm=ray_norm)

    def look_at(self, k: A) -> tuple[A, A, A]:
        """``view="look_at"``: keypoints ``(..., 17, 2)`` of the reference camera (px at F0, relative to its principal
        point) as the camera turned to look at their root (joint 0) sees them, the root then at 0; the turn
        ``(..., 3, 3)`` and the root ray's length ``(...)`` (:class:`Encoded`). The turn is exact for any 2D (the
        viewing rays are kept), so the network reads the pose free of where it stands in the image."""
        xp = array_namespace(k)
        f0 = self.reference_focal
        root_ray = xp.concat([k[..., 0, :] / f0, xp.ones_like(k[..., 0, :1])], axis=-1)  # type: ignore[index]
        rotation = look_at_rotation(root_ray)
        return (turn_pixels(k, rotation, f0, xp.zeros_like(k[..., 0, :])),  # type: ignore[index]
                rotation, xp.sqrt(xp.sum(root_ray * root_ray, axis=-1)))

    @staticmethod
    def source_flag(source: Any, *, like: A) -> A:
        """``(...)`` 1.0 where the 2D is clean, 0.0 where it is detected, as ``like``'s type and shape."""
        xp = array_namespace(like)
        if isinstance(source, str):
            if source not in SOURCES:
                raise ValueError(f"source must be one of {SOURCES}, got {source!r}")
            return xp.full_like(like, 1.0 if source == "clean" else 0.0)
        return xp.broadcast_to(_like(source, like), like.shape)  # type: ignore[attr-defined]

    # -- targets --------------------------------------------------------------------------------------
    def _mm_per_parameter(self, enc: Encoded[A]) -> A | float:
        """``dZ / dparameter``: mm of root depth per unit of the network's depth output (the map is linear)."""
        t = self.config.depth_target
        if t == "canonical":
            unit = enc.alpha_in / self.reference_focal  # type: ignore[operator]
        elif t == "absolute":
            return 1.0
        else:
            unit = enc.alpha_in / enc.sigma_in  # type: ignore[operator]
        # looking at the root, the network's camera has the root on its axis at depth Z * ray_norm
        return unit if enc.ray_norm is None else unit / enc.ray_norm  # type: ignore[operator]

    def depth_parameter(self, depth: A, enc: Encoded[A]) -> A:
        """The network's depth output for root depth Z ``(...)`` mm (:class:`~lifter.model.ModelConfig`)."""
        return depth / self._mm_per_parameter(enc)  # type: ignore[operator, return-value]

    def depth_from_parameter(self, param: A, enc: Encoded[A]) -> A:
        """Inverse of :meth:`depth_parameter`: root depth Z ``(...)`` mm."""
        return param * self._mm_per_parameter(enc)  # type: ignore[operator, return-value]

    def depth_loss_scale(self, enc: Encoded[A]) -> A:
        """``(...)`` factor turning an error in the depth parameter into the canonical-depth error
        ``|dZ| * F0 / alpha`` (mm at the reference focal), the loss's depth term for every depth target."""
        unit = self.depth_from_parameter(enc.alpha_in * 0 + 1, enc)  # dZ / dparameter (the map is linear)
        return unit * (self.reference_focal / enc.alpha)  # type: ignore[operator]

    def encode_targets(self, relative: A, depth: A, enc: Encoded[A]) -> A:
        """Raw targets ``(..., 49)`` mm: joints 1..16 of the root-relative pose ``(..., 17, 3)`` (camera frame, xyz
        per joint; with ``view="look_at"`` turned into the frame of the camera looking at the root), then
        :meth:`depth_parameter` of the root depth ``(...)`` mm."""
        xp = array_namespace(relative)
        if enc.rotation is not None:
            relative = relative @ xp.matrix_transpose(enc.rotation)  # type: ignore[operator]
        rel = relative[..., 1:, :]  # type: ignore[index]
        flat = xp.reshape(rel, (*rel.shape[:-2], 3 * (NUM_JOINTS - 1)))
        return xp.concat([flat, self.depth_parameter(depth, enc)[..., None]], axis=-1)  # type: ignore[index]

    def standardize(self, raw: A) -> A:
        return (raw - _like(self.target_mean, raw)) / _like(self.target_std, raw)  # type: ignore[operator]

    def destandardize(self, out: A) -> A:
        """Network outputs ``(..., 49)`` -> raw outputs in mm."""
        return _like(self.target_mean, out) + _like(self.target_std, out) * out  # type: ignore[operator]

    # -- decode ---------------------------------------------------------------------------------------
    def split(self, raw: A, enc: Encoded[A]) -> tuple[A, A]:
        """Raw outputs ``(..., 49)`` mm -> relative pose ``(..., 17, 3)`` (camera frame, root row zero) and root depth
        Z ``(...)``."""
        xp = array_namespace(raw)
        rel = xp.reshape(raw[..., : NUM_OUTPUTS - 1], (*raw.shape[:-1], NUM_JOINTS - 1, 3))  # type: ignore[index, attr-defined]
        rel = xp.concat([xp.zeros_like(rel[..., :1, :]), rel], axis=-2)
        if enc.rotation is not None:  # back from the frame of the camera looking at the root
            rel = rel @ enc.rotation  # type: ignore[operator]
        return rel, self.depth_from_parameter(raw[..., -1], enc)  # type: ignore[index]

    def decode(self, raw: A, enc: Encoded[A], *, root_2d: A, principal_point: Any, focal: Any) -> Decoded[A]:
        """Raw outputs ``(..., 49)`` mm -> :class:`Decoded`. ``root_2d`` ``(..., 2)`` px is the input's 2D root
        (pelvis); ``principal_point`` and ``focal`` ``(..., 2)`` px are those the input was encoded with."""
        rel, depth = self.split(raw, enc)
        root = backproject_generic(root_2d, depth, _like(focal, root_2d), _like(principal_point, root_2d))
        return Decoded(relative=rel, depth=depth, canonical_depth=depth * (self.reference_focal / enc.alpha),  # type: ignore[operator]
                       root=root)

    @staticmethod
    def mirror_output(raw: A) -> A:
        """Raw outputs of a mirrored input mapped back: the pose is mirrored (:func:`lifter.skeleton.mirror`),
        the depth parameter is unchanged (mirroring keeps Z and the 2D scale)."""
        xp = array_namespace(raw)
        rel = xp.reshape(raw[..., : NUM_OUTPUTS - 1], (*raw.shape[:-1], NUM_JOINTS - 1, 3))  # type: ignore[index, attr-defined]
        full = xp.concat([xp.zeros_like(rel[..., :1, :]), rel], axis=-2)
        back = mirror(full)[..., 1:, :]
        return xp.concat([xp.reshape(back, (*raw.shape[:-1], NUM_OUTPUTS - 1)), raw[..., -1:]], axis=-1)  # type: ignore[index, attr-defined]

    @classmethod
    def flip_average(cls, raw: A, n: int) -> A:
        """The flip test's answer for ``n`` inputs from raw outputs ``(2n, 49)``: the inputs' rows, then their
        mirror images' rows (:meth:`mirror_input`), whose outputs are mapped back (:meth:`mirror_output`) and
        averaged with the first ``n``. The one implementation that :meth:`lifter.Lifter.lift` (numpy) and
        distillation's teacher (:func:`lifter.train.teacher_targets`, torch) share."""
        if raw.shape[0] != 2 * n:
            raise PoseLifterError(f"flip_average: {raw.shape[0]} rows of raw outputs, expected 2 x {n} (inputs, then "
                                  "mirror images)")
        return 0.5 * (raw[:n] + cls.mirror_output(raw[n:]))  # type: ignore[index, operator]

    @staticmethod
    def mirror_input(keypoints: A, principal_point: Any) -> A:
        """The mirrored image's keypoints, relative to the same principal point: ``c + mirror(p - c)``. Its
        features equal those of the image flipped about its centre (``x -> W - x``, ``cx -> W - cx``)."""
        c = _like(principal_point, keypoints)[..., None, :]  # type: ignore[index]
        return c + mirror(keypoints - c)  # type: ignore[operator]

    def __repr__(self) -> str:
        return f"PoseCodec({self.config!r})"
