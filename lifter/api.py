"""The inference API: :class:`Lifter` and its :class:`LiftResult`.

Example::

    from lifter import Lifter
    lifter = Lifter.from_pretrained()                    # shipped default weights
    res = lifter.lift(keypoints, focal=(fx, fy), principal_point=(cx, cy))
    res.absolute   # (..., 17, 3) mm, camera frame (OpenCV: +x right, +y down, +z forward)
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from ._checks import PoseLifterError, as_pair, as_points
from .camera import CANONICAL_FOCAL, canonical_depth_from_depth, root_from_canonical_depth
from .checkpoint import load_checkpoint
from .model import PoseLifterNet, forward_flat_numpy, split_output
from .normalization import normalize_keypoints, pose_scale_np
from .skeleton import FLIP_PERMUTATION, NUM_JOINTS

NUMPY_MAX_BATCH: int = 1
"""Batches up to this many poses run the network in numpy (:func:`~lifter.model.forward_flat_numpy`),
larger ones through the torch module. A single pose is a chain of matrix-vector products, where numpy's
OpenBLAS beats torch's CPU kernels on the development machine (``benchmarks/bench_lift.py`` times both on
one pose); from two poses on torch is as fast or faster."""
ASSETS_DIR = Path(os.environ.get("POSELIFTER_ASSETS", Path(__file__).resolve().parent.parent / "assets"))
DEGENERATE_SCALE_PX = 1e-3
MIN_POSE_SCALE_PX = 2.0
"""Poses whose 2D scale (RMS radius) is below this many pixels are rejected: they are degenerate or not in pixels."""
MAX_ABS_PX = 1e6
"""Keypoints, principal point and focal length beyond this magnitude (px) are refused: float32 overflow
territory, and never image pixels."""


def model_registry(assets_dir: Path | None = None) -> dict[str, Any]:
    """``assets/models.json``: ``{"default": name, "models": {name: {"file": ..., "description": ...}}}``."""
    path = (assets_dir or ASSETS_DIR) / "models.json"
    if not path.is_file():
        raise PoseLifterError(f"no shipped models: {path} not found")
    return json.loads(path.read_text())


def available_models() -> list[str]:
    """Names accepted by :meth:`Lifter.from_pretrained`."""
    return sorted(model_registry()["models"])


def model_for_detector(detector: str) -> str:
    """The shipped model trained for ``detector``'s 2D errors (the registry entry whose ``"detector"`` is
    that name, e.g. ``"blazepose"``); the default model when there is none."""
    reg = model_registry()
    names = [name for name, entry in reg["models"].items() if entry.get("detector") == detector]
    if len(names) > 1:
        raise PoseLifterError(f"assets/models.json names several models for detector {detector!r}: {names}")
    return names[0] if names else reg["default"]


@dataclass(frozen=True)
class LiftResult:
    """Lifted poses for inputs of leading shape ``(...)``.

    canonical_depth: ``(...)`` mm at the reference focal length F0 = 1000 px (``Z * 1000 / alpha``).
    root: ``(..., 3)`` mm, camera frame. If ``metric_depth`` is False (no focal length was given),
        the root is placed for a virtual camera of focal 1000 px: X and Y are correct (they only depend
        on Z/f), Z equals ``canonical_depth`` and the true Z is ``canonical_depth * alpha / 1000``.
    relative: ``(..., 17, 3)`` mm, root-relative pose in camera orientation, root row zero.
    absolute: ``(..., 17, 3)`` mm, camera frame, ``root + relative``.
    keypoints_2d: ``(..., 17, 2)`` px, the input. principal_point: ``(..., 2)`` px.
    focal: ``(..., 2)`` px or None when unknown.
    """

    canonical_depth: np.ndarray
    root: np.ndarray
    relative: np.ndarray
    absolute: np.ndarray
    keypoints_2d: np.ndarray
    principal_point: np.ndarray
    focal: np.ndarray | None
    metric_depth: bool

    @property
    def note(self) -> str:
        if self.metric_depth:
            return "absolute pose in mm, camera frame"
        return ("no focal length given: root placed for a 1000-px focal; X, Y are metric but Z is known only "
                "up to the unknown focal length (Z = canonical_depth * alpha / 1000)")


def _where(bad: np.ndarray) -> str:
    """`` (pose at index (i, j))`` for the first True entry of a batched mask; empty for a single pose."""
    if bad.ndim == 0:
        return ""
    return f" (pose at index {tuple(int(i) for i in np.argwhere(bad)[0])}, {int(bad.sum())} such pose(s))"


def _broadcast(x: np.ndarray, lead: tuple[int, ...], *, name: str) -> np.ndarray:
    try:
        return np.broadcast_to(x, lead + (2,))
    except ValueError:
        raise PoseLifterError(f"{name}: shape {tuple(x.shape)} does not broadcast against the keypoints' leading "
                              f"shape {lead} (expected (2,) or {lead + (2,)})") from None


class Lifter:
    """A trained PoseLifter network with numpy-in / numpy-out inference."""

    def __init__(self, net: PoseLifterNet, *, name: str = "custom", meta: dict[str, Any] | None = None) -> None:
        self.net = net.eval()
        self.name = name
        self.meta = meta or {}

    @property
    def config(self):
        return self.net.config

    @classmethod
    def from_checkpoint(cls, path: str | os.PathLike[str], *, name: str | None = None,
                        quantize: bool = False) -> "Lifter":
        """Load a checkpoint file (``weights_only=True``); see :mod:`lifter.checkpoint`."""
        net, meta = load_checkpoint(path)
        lifter = cls(net, name=name or Path(path).stem, meta=meta)
        return lifter.quantized() if quantize else lifter

    @classmethod
    def from_pretrained(cls, name: str = "default", *, quantize: bool = False) -> "Lifter":
        """Shipped weights by name (see :func:`available_models`); ``"default"`` is the recommended one.
        ``quantize=True``: see :meth:`quantized`."""
        reg = model_registry()
        if name == "default":
            name = reg["default"]
        if name not in reg["models"]:
            raise PoseLifterError(f"unknown model {name!r}; available: {sorted(reg['models'])} or 'default'")
        return cls.from_checkpoint(ASSETS_DIR / reg["models"][name]["file"], name=name, quantize=quantize)

    @classmethod
    def load(cls, ref: str | os.PathLike[str], *, quantize: bool = False) -> "Lifter":
        """A shipped model name (``"default"``, ``"gt"``, ...) or a checkpoint path (``*.pt``)."""
        ref = str(ref)
        if ref == "default" or ref in model_registry()["models"] or not (ref.endswith(".pt") or Path(ref).is_file()):
            return cls.from_pretrained(ref, quantize=quantize)  # shipped names win over same-named local files
        return cls.from_checkpoint(ref, quantize=quantize)

    def quantized(self) -> "Lifter":
        """A copy whose residual-block Linear layers use int8 weights (dynamic quantization).

        A quarter of the weight memory (4 MB instead of 16 MB of block weights), with MPJPE unchanged at
        0.1 mm and MRPE within 1 mm on H36M (``poselifter evaluate --quantize``). It always runs the torch
        module (not the numpy single-pose path of :meth:`lift`); for a single pose it is still ~1.3x
        faster than float32, with less weight memory to stream (``benchmarks/bench_lift.py``). The
        normalization layer, stem and head stay float32 (pixel precision).
        """
        import copy
        import warnings

        net = copy.deepcopy(self.net)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            net.blocks = torch.ao.quantization.quantize_dynamic(net.blocks, {torch.nn.Linear}, dtype=torch.qint8)
        return Lifter(net, name=f"{self.name} (int8)", meta=self.meta)

    # ------------------------------------------------------------------------------------------
    def lift(
        self,
        keypoints: Any,
        *,
        focal: Any | None = None,
        principal_point: Any | None = None,
        image_size: Any | None = None,
        flip_test: bool = False,
    ) -> LiftResult:
        """Lift 2D keypoints ``(..., 17, 2)`` px (H36M joint order) to absolute 3D poses.

        focal: ``fx = fy`` scalar, ``(fx, fy)`` or batched ``(..., 2)`` (per pose: give the last axis
            explicitly, ``(..., 2)`` or ``(..., 1)``; a bare ``(2,)`` always means ``(fx, fy)``), px;
            None -> canonical depth only.
        principal_point: ``(cx, cy)`` or ``(..., 2)`` px; defaults to the image centre when
            ``image_size = (width, height)`` is given.
        flip_test: also lift the mirrored input and average (slower, slightly more accurate).
        """
        kp = as_points(keypoints, name="keypoints", dim=2, num_joints=NUM_JOINTS)
        lead = kp.shape[:-2]
        if principal_point is None:
            if image_size is None:
                raise PoseLifterError("principal_point is required (or pass image_size=(width, height) to use the image centre)")
            wh = as_pair(image_size, name="image_size", positive=True)
            principal_point = wh / 2.0
        pp = _broadcast(as_pair(principal_point, name="principal_point"), lead, name="principal_point")
        f = None
        if focal is not None:
            f = _broadcast(as_pair(focal, name="focal", positive=True), lead, name="focal")
        for name, arr in (("keypoints", kp), ("principal_point", pp), ("focal", f)):
            if arr is not None and arr.size and float(np.abs(arr).max()) > MAX_ABS_PX:
                raise PoseLifterError(f"{name}: values up to {float(np.abs(arr).max()):.3g} px; image pixel values "
                                      f"must be below {MAX_ABS_PX:.0e} in magnitude")
        scale = pose_scale_np(kp)
        if np.any(scale < DEGENERATE_SCALE_PX):
            raise PoseLifterError(
                f"degenerate pose{_where(scale < DEGENERATE_SCALE_PX)}: all 17 joints at (nearly) one point (2D scale "
                f"{float(scale.min()):.2g} px); the normalization needs a pose with non-zero extent")
        if np.any(scale < MIN_POSE_SCALE_PX):
            raise PoseLifterError(
                f"2D pose scale {float(scale.min()):.3g} px{_where(scale < MIN_POSE_SCALE_PX)} is too small "
                f"(< {MIN_POSE_SCALE_PX} px): keypoints must be in image pixels (normalized [0, 1] coordinates? "
                "multiply by the image size)")
        if self.config.depth_target == "absolute" and f is None:
            raise PoseLifterError(f"model {self.name!r} predicts absolute depth and needs the focal length")

        flat_kp = kp.reshape(-1, NUM_JOINTS, 2)
        flat_pp = np.ascontiguousarray(pp.reshape(-1, 2))
        rel, depth = self._run(flat_kp, flat_pp)
        if flip_test:
            perm = np.asarray(FLIP_PERMUTATION)
            kp_m = flat_kp[:, perm].copy()
            kp_m[..., 0] = 2.0 * flat_pp[:, None, 0] - kp_m[..., 0]
            rel_m, depth_m = self._run(kp_m, flat_pp)
            rel_m = rel_m[:, perm]
            rel_m[..., 0] *= -1.0
            rel = 0.5 * (rel + rel_m)
            depth = 0.5 * (depth + depth_m)
        if not (np.all(np.isfinite(rel)) and np.all(np.isfinite(depth))):
            raise PoseLifterError(f"model {self.name!r} produced non-finite outputs (corrupt weights?)")
        rel = rel.reshape(lead + (NUM_JOINTS, 3))
        depth = depth.reshape(lead)
        if self.config.depth_target == "canonical":
            canonical = depth
        else:
            canonical = canonical_depth_from_depth(depth, focal=f)
        root = root_from_canonical_depth(kp[..., 0, :], canonical, focal=f if f is not None else CANONICAL_FOCAL,
                                         principal_point=pp)
        return LiftResult(canonical_depth=canonical, root=root, relative=rel, absolute=root[..., None, :] + rel,
                          keypoints_2d=kp, principal_point=np.array(pp), focal=None if f is None else np.array(f),
                          metric_depth=f is not None)

    def _run(self, kp: np.ndarray, pp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Network on ``(N, 17, 2)`` px and ``(N, 2)`` px -> relative ``(N, 17, 3)`` mm, depth ``(N,)``."""
        net = self.net
        kp_t = torch.from_numpy(kp.astype(np.float32))
        pp_t = torch.from_numpy(pp.astype(np.float32))
        with torch.inference_mode():
            flat = None
            if len(kp) <= NUMPY_MAX_BATCH:
                x = normalize_keypoints(kp_t, pp_t, mode=net.config.mode, scale_definition=net.config.scale_definition)
                flat = forward_flat_numpy(net, x.numpy())
            if flat is not None:
                out = split_output(torch.from_numpy(flat))
            else:
                if any(m.training for m in net.modules() if isinstance(m, (torch.nn.Dropout, torch.nn.BatchNorm1d))):
                    raise PoseLifterError(
                        f"model {self.name!r} is in training mode (dropout, batch statistics): call lifter.net.eval()")
                out = net(kp_t, pp_t)
        return out.relative.numpy().astype(np.float64), out.depth.numpy().astype(np.float64)

    def __repr__(self) -> str:
        c = self.config
        return f"Lifter(name={self.name!r}, width={c.width}, mode={c.mode!r}, depth_target={c.depth_target!r})"

