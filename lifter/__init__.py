"""poselifter: absolute 3D human pose from a single 2D pose (PoseLifter, Chang, Moon & Lee).

Units: pixels for 2D, millimetres for 3D. Camera frame: OpenCV (+x right, +y down, +z forward).
Joint order: the 17 Human3.6M joints of :mod:`lifter.skeleton`.
"""

from ._checks import CheckpointError, PoseLifterError
from .analytic import analytic_root
from .api import LiftResult, Lifter, available_models, model_for_detector
from .camera import (
    CANONICAL_FOCAL,
    Camera,
    backproject,
    canonical_depth_from_depth,
    depth_from_canonical_depth,
    flip_keypoints_2d,
    flip_pose_3d,
    focal_alpha,
    project,
    root_from_canonical_depth,
)
from .keypoints import KEYPOINT_FORMATS, convert
from .metrics import auc, mpjpe, pa_mpjpe, pck, root_errors
from .model import ModelConfig, PoseLifterNet
from .noise import ErrorModel
from .normalization import normalize_keypoints, normalize_keypoints_np
from .skeleton import EDGES, FLIP_PERMUTATION, JOINT_NAMES, NUM_JOINTS, PARENTS

__all__ = [
    "CANONICAL_FOCAL", "Camera", "ErrorModel", "KEYPOINT_FORMATS", "convert", "CheckpointError", "EDGES", "FLIP_PERMUTATION", "JOINT_NAMES", "LiftResult",
    "Lifter", "ModelConfig", "NUM_JOINTS", "PARENTS", "PoseLifterError", "PoseLifterNet", "analytic_root", "auc",
    "available_models", "backproject", "canonical_depth_from_depth", "depth_from_canonical_depth",
    "flip_keypoints_2d", "flip_pose_3d", "focal_alpha", "model_for_detector", "mpjpe", "normalize_keypoints", "normalize_keypoints_np",
    "pa_mpjpe", "pck", "project", "root_errors", "root_from_canonical_depth",
]
__version__ = "0.1.0"
