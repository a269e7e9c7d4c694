"""The 17-joint Human3.6M skeleton used throughout poselifter.

Joint order (index: name, index in the 32-joint H36M mocap skeleton):

====  ===========  ======
 idx  name         32-idx
====  ===========  ======
   0  pelvis        0   (the root)
   1  r_hip         1
   2  r_knee        2
   3  r_ankle       3
   4  l_hip         6
   5  l_knee        7
   6  l_ankle       8
   7  spine        12
   8  thorax       13
   9  neck_nose    14
  10  head_top     15
  11  l_shoulder   17
  12  l_elbow      18
  13  l_wrist      19
  14  r_shoulder   25
  15  r_elbow      26
  16  r_wrist      27
====  ===========  ======

"Left" and "right" are the subject's own sides.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from ._array import ArrayT
from ._array import namespace as array_namespace

NUM_JOINTS: Final[int] = 17
ROOT: Final[int] = 0

JOINT_NAMES: Final[tuple[str, ...]] = (
    "pelvis",
    "r_hip",
    "r_knee",
    "r_ankle",
    "l_hip",
    "l_knee",
    "l_ankle",
    "spine",
    "thorax",
    "neck_nose",
    "head_top",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
)

H36M32_INDICES: Final[tuple[int, ...]] = (0, 1, 2, 3, 6, 7, 8, 12, 13, 14, 15, 17, 18, 19, 25, 26, 27)
"""Index of each of the 17 joints in the 32-joint H36M mocap skeleton."""

PARENTS: Final[tuple[int, ...]] = (-1, 0, 1, 2, 0, 4, 5, 0, 7, 8, 9, 8, 11, 12, 8, 14, 15)
"""Parent of each joint in the kinematic tree; -1 for the root."""

EDGES: Final[tuple[tuple[int, int], ...]] = tuple((p, c) for c, p in enumerate(PARENTS) if p >= 0)
"""Bones as ``(parent, child)`` pairs, 16 of them."""

LEFT_RIGHT_PAIRS: Final[tuple[tuple[int, int], ...]] = ((4, 1), (5, 2), (6, 3), (11, 14), (12, 15), (13, 16))
"""``(left, right)`` joint index pairs swapped by a horizontal flip."""

FLIP_PERMUTATION: Final[tuple[int, ...]] = (0, 4, 5, 6, 1, 2, 3, 7, 8, 9, 10, 14, 15, 16, 11, 12, 13)
"""``flipped[..., j, :] = original[..., FLIP_PERMUTATION[j], :]`` swaps left and right joints."""

LEFT_JOINTS: Final[tuple[int, ...]] = tuple(left for left, _ in LEFT_RIGHT_PAIRS)
RIGHT_JOINTS: Final[tuple[int, ...]] = tuple(right for _, right in LEFT_RIGHT_PAIRS)




def mirror(points: ArrayT) -> ArrayT:
    """Mirror points ``(..., 17, D)`` (D = 2 or 3) in the plane ``x = 0``: left and right joints swap and x is
    negated. numpy arrays or torch tensors (differentiable); returns a new array of the same type.

    This is the one implementation of the horizontal flip. For camera-frame 3D (mm) it mirrors the scene
    in the camera's vertical plane; for 2D it applies to coordinates *relative to the principal point*,
    where it equals the image flip ``x -> W - x`` together with ``cx -> W - cx``
    (:func:`lifter.camera.flip_keypoints_2d`). Mirroring twice is the identity.
    """
    xp = array_namespace(points)
    if points.ndim < 2 or points.shape[-2] != NUM_JOINTS or points.shape[-1] not in (2, 3):  # type: ignore[attr-defined]
        raise ValueError(f"mirror: expected shape (..., {NUM_JOINTS}, 2 or 3), got {tuple(points.shape)}")  # type: ignore[attr-defined]
    swapped = points[..., list(FLIP_PERMUTATION), :]  # type: ignore[index]
    x = -swapped[..., :1]
    return xp.concat([x, swapped[..., 1:]], axis=-1)


def bone_lengths(points: np.ndarray) -> np.ndarray:
    """The lengths of the 16 bones (:data:`EDGES` order) of poses ``(..., 17, D)`` (D = 2 px or 3 mm), in the
    points' unit: ``(..., 16)``."""
    p = np.asarray(points, np.float64)
    if p.ndim < 2 or p.shape[-2] != NUM_JOINTS or p.shape[-1] not in (2, 3):
        raise ValueError(f"bone_lengths: expected shape (..., {NUM_JOINTS}, 2 or 3), got {tuple(p.shape)}")
    parent, child = zip(*EDGES)
    return np.linalg.norm(p[..., list(child), :] - p[..., list(parent), :], axis=-1)


def joint_side(index: int) -> str:
    """Return ``"left"``, ``"right"`` or ``"center"`` for a joint index."""
    if index in LEFT_JOINTS:
        return "left"
    if index in RIGHT_JOINTS:
        return "right"
    if 0 <= index < NUM_JOINTS:
        return "center"
    raise IndexError(f"joint index {index} out of range [0, {NUM_JOINTS})")


def edge_side(edge: tuple[int, int]) -> str:
    """Side of a bone: the side of its child joint."""
    return joint_side(edge[1])
