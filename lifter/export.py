"""Export a lifted 3D pose: a GLB mesh of the skeleton (trimesh) and a BVH file.

Input poses are ``(17, 3)`` mm in the OpenCV camera frame (+x right, +y down, +z forward), H36M joint
order (:mod:`lifter.skeleton`), e.g. ``LiftResult.absolute``.

Both files are written in a **y-up** frame, the convention of glTF and of BVH tools: ``(x, -y, -z)``,
i.e. the camera frame turned 180 deg about its x axis (a rotation, so handedness is kept; the camera
sits at the origin looking down -z, as in glTF). :func:`to_y_up` / :func:`from_y_up` convert.

* GLB: metres (glTF's unit). One sphere per joint (node ``joint_<name>``) and one cylinder per bone
  (node ``bone_<parent>_<child>``), coloured by side (left blue, right red, centre grey, as in the
  app). :func:`read_glb_joints` reads the joint positions back (sphere centres), in mm, camera frame.
* BVH: ``units`` (default cm). The HIERARCHY's OFFSETs are the lifted pose's own bone vectors and
  the single MOTION frame holds the root position and zero rotations, so any BVH viewer shows exactly
  the lifted pose (it is not a retargeting rig with a neutral rest pose). Rotation channels are
  ``Zrotation Xrotation Yrotation`` (degrees). Leaf joints end with a zero-length ``End Site``.
  :func:`read_bvh` does forward kinematics for the first frame and returns ``(17, 3)`` mm, camera frame.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Final

import numpy as np

from ._checks import PoseLifterError, as_points
from .io import write_atomic
from .skeleton import EDGES, JOINT_NAMES, NUM_JOINTS, PARENTS, joint_side

_Y_UP: Final[np.ndarray] = np.diag([1.0, -1.0, -1.0])
UNITS_MM: Final[dict[str, float]] = {"mm": 1.0, "cm": 10.0, "m": 1000.0}
SIDE_COLORS: Final[dict[str, tuple[int, int, int, int]]] = {
    "left": (40, 110, 230, 255), "right": (220, 50, 40, 255), "center": (150, 150, 150, 255)}


def to_y_up(points_cam: np.ndarray) -> np.ndarray:
    """OpenCV camera frame ``(..., 3)`` -> y-up frame ``(x, -y, -z)`` (same units)."""
    return np.asarray(points_cam, np.float64) @ _Y_UP


def from_y_up(points: np.ndarray) -> np.ndarray:
    """Inverse of :func:`to_y_up` (the map is its own inverse)."""
    return np.asarray(points, np.float64) @ _Y_UP


def _pose(pose: Any) -> np.ndarray:
    p = as_points(pose, name="pose", dim=3, num_joints=NUM_JOINTS)
    if p.ndim != 2:
        raise PoseLifterError(f"pose: expected one pose of shape (17, 3) mm, got {tuple(p.shape)}")
    return p


# ------------------------------------------------------------------------------------------------
# GLB
# ------------------------------------------------------------------------------------------------


def skeleton_scene(pose: Any, *, joint_radius_mm: float = 25.0, bone_radius_mm: float = 12.0) -> Any:
    """A ``trimesh.Scene`` of the skeleton of ``pose`` ``(17, 3)`` mm (camera frame), in metres, y-up."""
    import trimesh

    p = to_y_up(_pose(pose)) / 1000.0
    scene = trimesh.Scene()
    for j, name in enumerate(JOINT_NAMES):
        s = trimesh.creation.icosphere(subdivisions=2, radius=joint_radius_mm / 1000.0)
        s.apply_translation(p[j])
        s.visual.face_colors = SIDE_COLORS[joint_side(j)]  # type: ignore[union-attr]
        scene.add_geometry(s, node_name=f"joint_{name}", geom_name=f"joint_{name}")
    for a, b in EDGES:
        length = float(np.linalg.norm(p[b] - p[a]))
        if length < 1e-6:
            continue
        c = trimesh.creation.cylinder(radius=bone_radius_mm / 1000.0, segment=np.stack([p[a], p[b]]), sections=12)
        c.visual.face_colors = SIDE_COLORS[joint_side(b)]  # type: ignore[union-attr]
        nm = f"bone_{JOINT_NAMES[a]}_{JOINT_NAMES[b]}"
        scene.add_geometry(c, node_name=nm, geom_name=nm)
    return scene


def write_glb(pose: Any, path: str | os.PathLike[str], **kwargs: Any) -> Path:
    """Write the skeleton of ``pose`` ``(17, 3)`` mm (camera frame) as a binary glTF; see :func:`skeleton_scene`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = skeleton_scene(pose, **kwargs).export(file_type="glb")
    return write_atomic(path, data)


def read_glb_joints(path: str | os.PathLike[str]) -> np.ndarray:
    """Joint positions ``(17, 3)`` mm, camera frame, from a GLB written by :func:`write_glb`
    (the centres of the ``joint_<name>`` spheres)."""
    import trimesh

    scene: Any = trimesh.load(str(path), file_type="glb", force="scene")
    out = np.full((NUM_JOINTS, 3), np.nan)
    for node in scene.graph.nodes_geometry:
        transform, geom = scene.graph[node]
        name = str(node).removeprefix("joint_")
        if not str(node).startswith("joint_") or name not in JOINT_NAMES:
            continue
        v = np.asarray(scene.geometry[geom].vertices, np.float64)
        v = v @ transform[:3, :3].T + transform[:3, 3]
        out[JOINT_NAMES.index(name)] = 0.5 * (v.min(0) + v.max(0))
    if np.isnan(out).any():
        raise PoseLifterError(f"{path}: not a poselifter skeleton GLB (joint spheres missing)")
    return from_y_up(out * 1000.0)


# ------------------------------------------------------------------------------------------------
# BVH
# ------------------------------------------------------------------------------------------------


def _children(j: int) -> list[int]:
    return [c for c, p in enumerate(PARENTS) if p == j]


def bvh_text(pose: Any, *, units: str = "cm", frame_time: float = 1.0 / 30.0) -> str:
    """The BVH file for ``pose`` ``(17, 3)`` mm (camera frame); see the module docstring."""
    if units not in UNITS_MM:
        raise PoseLifterError(f"units must be one of {sorted(UNITS_MM)}, got {units!r}")
    p = to_y_up(_pose(pose)) / UNITS_MM[units]
    lines: list[str] = ["HIERARCHY"]

    def fmt(v: np.ndarray) -> str:
        return " ".join(f"{x:.6f}" for x in v)

    def emit(j: int, depth: int) -> None:
        ind = "  " * depth
        if j == 0:
            lines.append(f"ROOT {JOINT_NAMES[j]}")
            off = np.zeros(3)
            chans = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
        else:
            lines.append(f"{ind}JOINT {JOINT_NAMES[j]}")
            off = p[j] - p[PARENTS[j]]
            chans = "CHANNELS 3 Zrotation Xrotation Yrotation"
        lines.extend([f"{ind}{{", f"{ind}  OFFSET {fmt(off)}", f"{ind}  {chans}"])
        kids = _children(j)
        for c in kids:
            emit(c, depth + 1)
        if not kids:
            lines.extend([f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET 0.000000 0.000000 0.000000", f"{ind}  }}"])
        lines.append(f"{ind}}}")

    emit(0, 0)
    n_channels = 6 + 3 * (NUM_JOINTS - 1)
    motion = np.zeros(n_channels)
    motion[:3] = p[0]
    lines += ["MOTION", "Frames: 1", f"Frame Time: {frame_time:.6f}", fmt(motion)]
    return "\n".join(lines) + "\n"


def write_bvh(pose: Any, path: str | os.PathLike[str], *, units: str = "cm") -> Path:
    """Write ``pose`` ``(17, 3)`` mm (camera frame) as a BVH file (module docstring)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_atomic(path, bvh_text(pose, units=units))


def _rot(axis: str, deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    if axis == "X":
        return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == "Y":
        return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def read_bvh(path: str | os.PathLike[str], *, units: str = "cm") -> np.ndarray:
    """Forward kinematics of the first frame of a BVH file (any joint names/channels; Euler angles in
    the listed channel order, intrinsic). Returns the positions of the joints named like the H36M
    joints, ``(17, 3)`` mm, camera frame (the inverse of :func:`write_bvh`)."""
    tokens = Path(path).read_text().split()
    i = 0
    joints: list[tuple[str, int, np.ndarray, list[str]]] = []  # name, parent, offset, channels
    stack: list[int] = []
    pending_parent = -1
    end_site = False
    while i < len(tokens):
        t = tokens[i]
        if t in ("ROOT", "JOINT"):
            joints.append((tokens[i + 1], stack[-1] if stack else -1, np.zeros(3), []))
            pending_parent = len(joints) - 1
            i += 2
        elif t == "End":
            end_site = True
            i += 2
        elif t == "{":
            stack.append(-2 if end_site else pending_parent)
            i += 1
        elif t == "}":
            top = stack.pop()
            if top == -2:
                end_site = False
            i += 1
        elif t == "OFFSET":
            if not end_site:
                name, par, _, ch = joints[stack[-1]]
                joints[stack[-1]] = (name, par, np.array([float(x) for x in tokens[i + 1:i + 4]]), ch)
            i += 4
        elif t == "CHANNELS":
            n = int(tokens[i + 1])
            name, par, off, _ = joints[stack[-1]]
            joints[stack[-1]] = (name, par, off, tokens[i + 2:i + 2 + n])
            i += 2 + n
        elif t == "MOTION":
            i += 1
            break
        else:
            i += 1
    # MOTION: Frames: N  Frame Time: dt  values...
    while i < len(tokens) and tokens[i] != "Time:":
        i += 1
    values = [float(x) for x in tokens[i + 2:]]
    pos = np.zeros((len(joints), 3))
    rot = [np.eye(3)] * len(joints)
    k = 0
    for j, (_, par, off, ch) in enumerate(joints):
        R = np.eye(3)
        trans = np.zeros(3)
        for c in ch:
            v = values[k]
            k += 1
            if c.endswith("position"):
                trans["XYZ".index(c[0])] = v
            else:
                R = R @ _rot(c[0], v)
        if par < 0:
            pos[j] = off + trans
            rot[j] = R
        else:
            pos[j] = pos[par] + rot[par] @ off
            rot[j] = rot[par] @ R
    names = [n for n, *_ in joints]
    missing = [n for n in JOINT_NAMES if n not in names]
    if missing:
        raise PoseLifterError(f"{path}: BVH lacks the H36M joints {missing}")
    out = np.stack([pos[names.index(n)] for n in JOINT_NAMES])
    return from_y_up(out * UNITS_MM[units])


__all__ = ["bvh_text", "from_y_up", "read_bvh", "read_glb_joints", "skeleton_scene", "to_y_up", "write_bvh",
           "write_glb"]
