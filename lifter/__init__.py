"""poselifter: absolute 3D human pose from a single 2D pose (PoseLifter, Chang, Moon & Lee).

Data flows one way: 2D keypoints (px) -> :mod:`lifter.codec` (reference camera, normalization layer) ->
:mod:`lifter.model` (network) -> codec decode (relative pose, canonical depth, root) -> absolute pose (mm)
-> :mod:`lifter.metrics` / the app. Units: pixels for 2D, millimetres for 3D. Camera frame: OpenCV
(+x right, +y down, +z forward). Joint order: the 17 Human3.6M joints of :mod:`lifter.skeleton`.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from ._checks import CheckpointError, PoseLifterError, PoseLifterWarning
from .analytic import analytic_root
from .camera import (
    CANONICAL_FOCAL,
    DEFAULT_DIAGONAL_FOV_DEG,
    Camera,
    backproject,
    canonical_depth_from_depth,
    depth_from_canonical_depth,
    flip_keypoints_2d,
    flip_pose_3d,
    focal_alpha,
    focal_from_fov,
    project,
    root_from_canonical_depth,
    to_reference_camera,
)
from .keypoints import KEYPOINT_FORMATS, convert
from .metrics import auc, mpjpe, pa_mpjpe, pck, root_errors
from .normalization import location_and_scale, normalize_keypoints, pose_features, pose_scale
from .resources import DemoSample, demo_sample, demo_sample_names
from .skeleton import EDGES, FLIP_PERMUTATION, JOINT_NAMES, NUM_JOINTS, PARENTS, mirror

# The names that need torch are imported on first use (PEP 562), so that the numpy-only parts -- geometry,
# metrics, keypoint formats, the shipped demo samples -- import without it (`import lifter.metrics`).
_LAZY: dict[str, str] = {
    "Lifter": "api", "LiftResult": "api", "available_models": "api",
    "SOURCES": "codec", "Decoded": "codec", "Encoded": "codec", "PoseCodec": "codec",
    "ModelConfig": "model", "PoseLifterNet": "model",
    "ErrorModel": "noise",
}

if TYPE_CHECKING:
    from .api import Lifter, LiftResult, available_models
    from .codec import SOURCES, Decoded, Encoded, PoseCodec
    from .model import ModelConfig, PoseLifterNet
    from .noise import ErrorModel


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        try:  # submodules as attributes (`lifter.checkpoint.save_checkpoint` after `import lifter`)
            return importlib.import_module(f".{name}", __name__)
        except ModuleNotFoundError as exc:
            if exc.name != f"{__name__}.{name}":
                raise
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY))


__all__ = [
    "CANONICAL_FOCAL", "DEFAULT_DIAGONAL_FOV_DEG", "EDGES", "FLIP_PERMUTATION", "JOINT_NAMES", "KEYPOINT_FORMATS",
    "NUM_JOINTS", "PARENTS", "SOURCES", "Camera", "CheckpointError", "Decoded", "Encoded", "ErrorModel", "LiftResult",
    "DemoSample", "Lifter", "ModelConfig", "PoseCodec", "PoseLifterError", "PoseLifterNet", "PoseLifterWarning",
    "analytic_root", "auc",
    "available_models", "backproject", "canonical_depth_from_depth", "convert", "demo_sample", "demo_sample_names",
    "depth_from_canonical_depth",
    "flip_keypoints_2d", "flip_pose_3d", "focal_alpha", "focal_from_fov", "location_and_scale", "mirror", "mpjpe",
    "normalize_keypoints", "pa_mpjpe", "pck", "pose_features", "pose_scale", "project", "root_errors",
    "root_from_canonical_depth", "to_reference_camera",
]
__version__ = "0.3.0"
