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
from collections.abc import Callable
from pathlib import Path
from typing import Any, Final, Literal

import numpy as np

from ._checks import PoseLifterError, as_points, warn_user
from .io import write_atomic
from .metrics import best_rotation
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


def _poses(pose: Any) -> np.ndarray:
    """One ``(17, 3)`` pose or several ``(n, 17, 3)`` as ``(n, 17, 3)`` float64 mm."""
    p = as_points(pose, name="pose", dim=3, num_joints=NUM_JOINTS)
    if p.ndim == 2:
        return p[None]
    if p.ndim != 3 or len(p) == 0:
        raise PoseLifterError(f"pose: expected (17, 3) or (n, 17, 3) mm, got {tuple(p.shape)}")
    return p


def person_prefix(k: int) -> str:
    """Node-name prefix of person ``k`` (0-based) in a scene: '' for the first, ``person<k+1>_`` after."""
    return "" if k == 0 else f"person{k + 1}_"


def skeleton_scene(pose: Any, *, joint_radius_mm: float = 25.0, bone_radius_mm: float = 12.0) -> Any:
    """A ``trimesh.Scene`` of the skeleton of ``pose`` ``(17, 3)`` mm (camera frame), in metres, y-up; several
    people ``(n, 17, 3)`` go into one scene, person ``k``'s nodes prefixed by :func:`person_prefix`."""
    import trimesh

    scene = trimesh.Scene()
    for k, one in enumerate(_poses(pose)):
        p = to_y_up(one) / 1000.0
        pre = person_prefix(k)
        for j, name in enumerate(JOINT_NAMES):
            s = trimesh.creation.icosphere(subdivisions=2, radius=joint_radius_mm / 1000.0)
            s.apply_translation(p[j])
            s.visual.face_colors = SIDE_COLORS[joint_side(j)]  # type: ignore[union-attr]
            scene.add_geometry(s, node_name=f"{pre}joint_{name}", geom_name=f"{pre}joint_{name}")
        for a, b in EDGES:
            length = float(np.linalg.norm(p[b] - p[a]))
            if length < 1e-6:
                continue
            c = trimesh.creation.cylinder(radius=bone_radius_mm / 1000.0, segment=np.stack([p[a], p[b]]), sections=12)
            c.visual.face_colors = SIDE_COLORS[joint_side(b)]  # type: ignore[union-attr]
            nm = f"{pre}bone_{JOINT_NAMES[a]}_{JOINT_NAMES[b]}"
            scene.add_geometry(c, node_name=nm, geom_name=nm)
    return scene


def write_glb(pose: Any, path: str | os.PathLike[str], **kwargs: Any) -> Path:
    """Write the skeleton of ``pose`` ``(17, 3)`` mm (camera frame), or of several people ``(n, 17, 3)`` in one
    scene, as a binary glTF; see :func:`skeleton_scene`."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    data = skeleton_scene(pose, **kwargs).export(file_type="glb")
    return write_atomic(path, data)


def read_glb_joints(path: str | os.PathLike[str], *, person: int = 0) -> np.ndarray:
    """Joint positions ``(17, 3)`` mm, camera frame, of person ``person`` (0 = the first) from a GLB written by
    :func:`write_glb` (the centres of its ``joint_<name>`` spheres)."""
    import trimesh

    scene: Any = trimesh.load(str(path), file_type="glb", force="scene")
    out = np.full((NUM_JOINTS, 3), np.nan)
    pre = person_prefix(person) + "joint_"
    for node in scene.graph.nodes_geometry:
        transform, geom = scene.graph[node]
        name = str(node).removeprefix(pre)
        if not str(node).startswith(pre) or name not in JOINT_NAMES:
            continue
        v = np.asarray(scene.geometry[geom].vertices, np.float64)
        v = v @ transform[:3, :3].T + transform[:3, 3]
        out[JOINT_NAMES.index(name)] = 0.5 * (v.min(0) + v.max(0))
    if np.isnan(out).any():
        nodes = {str(node) for node in scene.graph.nodes_geometry}
        people = 0
        while person_prefix(people) + f"joint_{JOINT_NAMES[0]}" in nodes:
            people += 1
        if 0 < people <= person or person < 0:  # (a user trial's person=2 of two read "joint spheres missing")
            raise PoseLifterError(f"{path}: person {person} is not in this GLB: it holds {people} "
                                  f"{'person' if people == 1 else 'people'} (person = 0 .. {people - 1})")
        raise PoseLifterError(f"{path}: not a poselifter skeleton GLB (joint spheres missing)")
    return from_y_up(out * 1000.0)


def _quat_z_to(d: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` (x, y, z, w) turning +z onto the unit vectors ``d (..., 3)``."""
    z = np.array([0.0, 0.0, 1.0])
    q = np.concatenate([np.cross(z, d), (1.0 + d @ z)[..., None]], axis=-1)
    flip = q[..., 3] < 1e-9  # d = -z: half a turn about x
    q[flip] = [1.0, 0.0, 0.0, 0.0]
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def write_glb_animation(tracks: dict[int, tuple[Any, Any]], path: str | os.PathLike[str], *, fps: float,
                        span: tuple[int, int] | None = None, joint_radius_mm: float = 25.0,
                        bone_radius_mm: float = 12.0, recorded: Any = None) -> Path:
    """An animated binary glTF of several tracked people: ``tracks[track_id] = (frame_indices (n,), poses
    (n, 17, 3) mm camera frame)``; frame ``i`` is at ``i / fps`` s. Metres, y-up, like :func:`write_glb`.
    ``span``: the first and last frame the clip covers (a video's ``(0, last frame)``, so that it plays in step with
    the video, everyone hidden where nobody is seen), widened to the tracks' frames; None: from the first frame
    anyone is seen in to the last.

    trimesh writes no glTF animations, so the meshes are written by trimesh (per track ``track<ID>_joint_<name>``
    spheres and ``track<ID>_bone_<a>_<b>`` unit cylinders) and the animation is added to its glTF: each node
    gets translation (and a bone rotation and length) channels sampled at every frame of its track's span, from the
    frame before the track's first to the frame after its last, and at the clip's first and last frames (LINEAR,
    every track's keys ending where the clip does), so a file grows with the frames people are seen in, not with the
    clip's length times the number of tracks (a review: five people seen 1 s each in a 10-minute clip made 95 MB).
    The nodes of a track are children of a node ``track<ID>`` scaled to zero (hidden) in a frame without the person:
    STEP keys half a frame before each change, so a player shows a person from exactly the frame they are first seen
    in, whatever its clock's rounding. The clip's first and last frame and ``fps`` are in the
    animation's ``extras``. ``recorded``: the frame indices the input holds
    (None: every frame): a frame it does not hold (a sequence that gives every other frame, a video frame that could
    not be read) is no frame without the person, and a person seen before and after it is interpolated there, as a
    BVH is (a developer trial's sequence of every other frame blinked at half its frame rate).
    :func:`read_glb_animation` reads it back.
    """
    import json
    import struct

    import trimesh

    if not (math.isfinite(fps) and fps > 0):
        raise PoseLifterError(f"fps must be > 0, got {fps}")
    if not tracks:
        raise PoseLifterError("write_glb_animation: no tracks")
    clean: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    for tid, (idx, poses) in tracks.items():
        P = as_points(poses, name=f"track {tid} poses", dim=3, num_joints=NUM_JOINTS)
        given = np.asarray(idx).reshape(-1)
        if given.size and not (np.issubdtype(given.dtype, np.number) and np.all(np.isfinite(given))
                               and np.all(given == np.round(given)) and given.min() >= 0):
            raise PoseLifterError(f"track {tid}: frame indices must be whole numbers >= 0 (frame i is at i / fps s), "
                                  f"got {given[:5].tolist()}{' ...' if given.size > 5 else ''}")
        ii = given.astype(np.int64)
        if P.ndim != 3 or len(P) != len(ii) or len(ii) == 0 or np.any(np.diff(ii) <= 0):
            raise PoseLifterError(f"track {tid}: expected increasing frame indices (n,) and poses (n, 17, 3), got "
                                  f"{ii.shape} and {tuple(P.shape)}")
        clean[int(tid)] = (ii, to_y_up(P) / 1000.0)
    first = min(int(i[0]) for i, _ in clean.values())
    last = max(int(i[-1]) for i, _ in clean.values())
    if span is not None:
        lo, hi = (int(v) for v in span)
        if not 0 <= lo <= hi:
            raise PoseLifterError(f"write_glb_animation: span must be (first, last) frames, 0 <= first <= last, got "
                                  f"{tuple(span)}")
        first, last = min(first, lo), max(last, hi)
    frames = np.arange(first, last + 1)
    T = len(frames)
    scene = trimesh.Scene()
    channels: list[tuple[str, str, np.ndarray, int]] = []  # node name, path, (n, 3|4) values, its track's time
    times: list[np.ndarray] = []  # (n,) frame numbers keyed, per track
    not_held = np.zeros(T, bool) if recorded is None else ~np.isin(frames, np.asarray(recorded))
    shown: dict[str, tuple[np.ndarray, np.ndarray]] = {}  # track node name: STEP keys' frame times, values (0 / 1)
    for tid, (ii, p) in sorted(clean.items()):
        present = np.isin(frames, ii)
        # every frame's pose: a sighting's own; between two, the straight line from one to the next (hidden where the
        # input holds the frame without them, shown where it does not hold the frame: a sequence of every other frame
        # would blink at half its rate); before the first and after the last, held
        flat = p.reshape(len(ii), -1)
        full = np.stack([np.interp(frames, ii, flat[:, c]) for c in range(flat.shape[1])],
                        axis=-1).reshape(T, NUM_JOINTS, 3)
        full[present] = p
        present = present | (not_held & (frames > ii[0]) & (frames < ii[-1]))
        lo = max(int(np.searchsorted(frames, ii[0])) - 1, 0)  # (the frame before its first, hidden: held before)
        hi = min(int(np.searchsorted(frames, ii[-1])) + 2, T)  # (past the frame after its last)
        # and the clip's first and last frames: a player takes the clip's length from its keys (a review: a person
        # seen only early in a 10-s video made a 2-s animation, out of step with the video when looped)
        keep = np.unique(np.r_[0, np.arange(lo, hi), T - 1])
        full = full[keep]
        times.append(frames[keep])
        key = len(times) - 1
        # shown or hidden: STEP keys half a frame before each change, so a player evaluating at a frame's time is half
        # a frame from every key whatever its clock's rounding (LINEAR scales grew a person in between two frames in a
        # trial's player; STEP keys on the frames' own float32 times landed a float64 clock just before them)
        change = np.flatnonzero(np.diff(present.astype(np.int8))) + 1
        at = np.r_[frames[0], frames[change] - 0.5, frames[-1]] if T > 1 else frames[:1].astype(np.float64)
        shown[f"track{tid}"] = (at, present[np.r_[0, change, T - 1][:len(at)]].astype(np.float64))
        pre = f"track{tid}_"
        for j, name in enumerate(JOINT_NAMES):
            sph = trimesh.creation.icosphere(subdivisions=2, radius=joint_radius_mm / 1000.0)
            sph.visual.face_colors = SIDE_COLORS[joint_side(j)]  # type: ignore[union-attr]
            nm = f"{pre}joint_{name}"
            scene.add_geometry(sph, node_name=nm, geom_name=nm)
            channels.append((nm, "translation", full[:, j], key))
        for a_, b_ in EDGES:
            cyl = trimesh.creation.cylinder(radius=bone_radius_mm / 1000.0, height=1.0, sections=12)
            cyl.apply_translation([0.0, 0.0, 0.5])  # from the origin along +z, unit length
            cyl.visual.face_colors = SIDE_COLORS[joint_side(b_)]  # type: ignore[union-attr]
            nm = f"{pre}bone_{JOINT_NAMES[a_]}_{JOINT_NAMES[b_]}"
            scene.add_geometry(cyl, node_name=nm, geom_name=nm)
            v = full[:, b_] - full[:, a_]
            length = np.linalg.norm(v, axis=-1)
            d = v / np.maximum(length, 1e-9)[:, None]
            d[length < 1e-9] = [0.0, 0.0, 1.0]
            scale = np.stack([np.ones_like(length), np.ones_like(length), length], axis=1)
            channels += [(nm, "translation", full[:, a_], key), (nm, "rotation", _quat_z_to(d), key),
                         (nm, "scale", scale, key)]
    glb = scene.export(file_type="glb")
    if not isinstance(glb, bytes):  # pragma: no cover -- trimesh returns bytes for glb
        raise PoseLifterError("GLB export: trimesh returned no bytes")
    # ---- add the animation to trimesh's glTF
    json_len = struct.unpack_from("<I", glb, 12)[0]
    gltf = json.loads(glb[20:20 + json_len].decode())
    off = 20 + json_len
    bin_len = struct.unpack_from("<I", glb, off)[0]
    blob = bytearray(glb[off + 8:off + 8 + bin_len])
    views, accessors = gltf.setdefault("bufferViews", []), gltf.setdefault("accessors", [])

    def add(arr: np.ndarray, kind: str, minmax: bool = False) -> int:
        while len(blob) % 4:
            blob.append(0)
        data = np.ascontiguousarray(arr, np.float32)
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes})
        blob.extend(data.tobytes())
        acc: dict[str, Any] = {"bufferView": len(views) - 1, "componentType": 5126, "count": len(data), "type": kind}
        if minmax:
            acc["min"], acc["max"] = [float(data.min())], [float(data.max())]
        accessors.append(acc)
        return len(accessors) - 1

    node_of = {n.get("name"): i for i, n in enumerate(gltf["nodes"])}
    time_acc = [add((f / fps).astype(np.float32), "SCALAR", minmax=True) for f in times]
    samplers, chans = [], []
    # a node per track, parent of its joints and bones, that shows or hides them (scale 1 or 0, STEP)
    roots = []
    for name, (at, vis) in shown.items():
        kids = [node_of[n] for n in node_of if isinstance(n, str) and n.startswith(name + "_")]
        gltf["nodes"].append({"name": name, "children": kids, "scale": [float(vis[0])] * 3})
        roots.append(len(gltf["nodes"]) - 1)
        samplers.append({"input": add((at / fps).astype(np.float32), "SCALAR", minmax=True),
                         "output": add(np.repeat(vis[:, None], 3, axis=1), "VEC3"), "interpolation": "STEP"})
        chans.append({"sampler": len(samplers) - 1, "target": {"node": roots[-1], "path": "scale"}})
    gltf["scenes"][gltf.get("scene", 0)]["nodes"] = roots
    for nm, what, values, key in channels:
        node = node_of.get(nm)
        if node is None:  # pragma: no cover -- trimesh names nodes as given
            raise PoseLifterError(f"GLB export: node {nm} missing")
        gltf["nodes"][node].pop("matrix", None)
        gltf["nodes"][node][what] = [float(x) for x in values[0]]
        samplers.append({"input": time_acc[key], "output": add(values, "VEC4" if what == "rotation" else "VEC3"),
                         "interpolation": "LINEAR"})
        chans.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": what}})
    gltf["animations"] = [{"name": "poselifter", "samplers": samplers, "channels": chans,
                           "extras": {"fps": float(fps), "first_frame": int(first), "last_frame": int(last)}}]
    while len(blob) % 4:
        blob.append(0)
    gltf["buffers"] = [{"byteLength": len(blob)}]
    js = json.dumps(gltf, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    out = (struct.pack("<III", 0x46546C67, 2, total) + struct.pack("<II", len(js), 0x4E4F534A) + js
           + struct.pack("<II", len(blob), 0x004E4942) + bytes(blob))
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_atomic(path, out)


def read_glb_animation(path: str | os.PathLike[str]) -> tuple[np.ndarray, dict[int, np.ndarray]]:
    """``(times (T,) s, {track_id: joints (T, 17, 3) mm camera frame, NaN where the person is hidden})`` from a
    GLB written by :func:`write_glb_animation` (the joint spheres' animated translations): ``times`` every frame of
    the clip (the animation's ``extras``; else every time any track is keyed at), a track NaN outside its keys."""
    import json
    import re
    import struct

    raw = Path(path).read_bytes()
    if raw[:4] != b"glTF":
        raise PoseLifterError(f"{path}: not a binary glTF")
    json_len = struct.unpack_from("<I", raw, 12)[0]
    gltf = json.loads(raw[20:20 + json_len].decode())
    off = 20 + json_len
    blob = raw[off + 8:off + 8 + struct.unpack_from("<I", raw, off)[0]]

    def read(acc_i: int) -> np.ndarray:
        acc = gltf["accessors"][acc_i]
        view = gltf["bufferViews"][acc["bufferView"]]
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
        start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
        return np.frombuffer(blob, np.float32, acc["count"] * width, start).reshape(acc["count"], width)

    anims = gltf.get("animations") or []
    if not anims:
        raise PoseLifterError(f"{path}: no animation in this GLB")
    keyed: list[tuple[int, int, str, np.ndarray, np.ndarray]] = []  # track, joint, path, times (n,) s, values
    shown: dict[int, tuple[np.ndarray, np.ndarray]] = {}  # track: its node's scale keys' times (n,) s, values (n,)
    for ch in anims[0]["channels"]:
        name = gltf["nodes"][ch["target"]["node"]].get("name", "")
        smp = anims[0]["samplers"][ch["sampler"]]
        whole = re.fullmatch(r"track(\d+)", name)
        if whole and ch["target"]["path"] == "scale":  # the track shown or hidden (STEP)
            shown[int(whole.group(1))] = (read(smp["input"])[:, 0], read(smp["output"])[:, 0])
            continue
        m = re.fullmatch(r"track(\d+)_joint_(\w+)", name)
        if not m or m.group(2) not in JOINT_NAMES or ch["target"]["path"] not in ("translation", "scale"):
            continue
        keyed.append((int(m.group(1)), JOINT_NAMES.index(m.group(2)), ch["target"]["path"],
                      read(smp["input"])[:, 0], read(smp["output"]).astype(np.float64)))
    if not keyed:
        raise PoseLifterError(f"{path}: no animated joints")
    extras = anims[0].get("extras") or {}
    if {"fps", "first_frame", "last_frame"} <= set(extras):
        clock = (np.arange(int(extras["first_frame"]), int(extras["last_frame"]) + 1) / float(extras["fps"]))
        clock32 = clock.astype(np.float32)  # (the keys' times, as written)
    else:  # (a file of before 2026-12: every track keyed at every frame of the clip)
        clock32 = np.unique(np.concatenate([t for *_, t, _ in keyed]))
        clock = clock32.astype(np.float64)
    joints: dict[int, np.ndarray] = {}
    for tid, j, what, t, vals in keyed:
        at = np.searchsorted(clock32, t)
        if np.any(at >= len(clock32)) or np.any(clock32[np.minimum(at, len(clock32) - 1)] != t):
            raise PoseLifterError(f"{path}: track {tid}'s keys are not on the clip's frames")
        arr = joints.setdefault(tid, np.full((len(clock), NUM_JOINTS, 3), np.nan))
        if what == "translation":
            arr[at, j] = np.where(np.isnan(arr[at, j]), vals, arr[at, j])  # (a key marked hidden stays so)
        else:  # (a file of before 2026-12: each joint scaled to zero where hidden, LINEAR keys on the frames)
            hidden = at[vals[:, 0] < 0.5]
            arr[hidden, j] = np.inf  # (marked: NaN below, whichever of the two channels comes first)
    for tid, (t, vals) in shown.items():
        if tid in joints:  # (a player's STEP: the last key at or before the time; before the first, the first)
            on = vals[np.maximum(np.searchsorted(t, clock32, side="right") - 1, 0)] >= 0.5
            joints[tid][~on] = np.inf
    for arr in joints.values():
        arr[~np.isfinite(arr)] = np.nan
    return clock, {tid: from_y_up(v * 1000.0) for tid, v in joints.items()}


# ------------------------------------------------------------------------------------------------
# BVH
# ------------------------------------------------------------------------------------------------


def _children(j: int) -> list[int]:
    return [c for c, p in enumerate(PARENTS) if p == j]


_CHANNELS_6: Final[str] = "CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation"
_CHANNELS_3: Final[str] = "CHANNELS 3 Zrotation Xrotation Yrotation"


def _bvh_hierarchy(offsets: np.ndarray, fmt: Callable[[np.ndarray], str],
                   channels: Callable[[int], str]) -> tuple[list[str], list[int]]:
    """The ``HIERARCHY`` lines of the H36M skeleton, depth first from the root, with each joint's OFFSET
    ``offsets[j]`` (``(17, 3)``, BVH units) and CHANNELS line ``channels(j)``; and the joints in that order (the
    order of the MOTION channels)."""
    lines: list[str] = ["HIERARCHY"]
    order: list[int] = []

    def emit(j: int, depth: int) -> None:
        ind = "  " * depth
        lines.append(f"ROOT {JOINT_NAMES[j]}" if j == 0 else f"{ind}JOINT {JOINT_NAMES[j]}")
        order.append(j)
        lines.extend([f"{ind}{{", f"{ind}  OFFSET {fmt(offsets[j])}", f"{ind}  {channels(j)}"])
        kids = _children(j)
        for c in kids:
            emit(c, depth + 1)
        if not kids:
            lines.extend([f"{ind}  End Site", f"{ind}  {{", f"{ind}    OFFSET 0.000000 0.000000 0.000000",
                          f"{ind}  }}"])
        lines.append(f"{ind}}}")

    emit(0, 0)
    return lines, order


def bvh_text(pose: Any, *, units: str = "cm", frame_time: float = 1.0 / 30.0) -> str:
    """The BVH file for ``pose`` ``(17, 3)`` mm (camera frame); see the module docstring."""
    if units not in UNITS_MM:
        raise PoseLifterError(f"units must be one of {sorted(UNITS_MM)}, got {units!r}")
    if not (math.isfinite(frame_time) and frame_time > 0):
        raise PoseLifterError(f"frame_time must be > 0 s, got {frame_time}")
    p = to_y_up(_pose(pose)) / UNITS_MM[units]

    def fmt(v: np.ndarray) -> str:
        return " ".join(f"{x:.6f}" for x in v)

    offsets = p - p[np.array([max(q, 0) for q in PARENTS])]
    offsets[0] = 0.0
    lines, _ = _bvh_hierarchy(offsets, fmt, lambda j: _CHANNELS_6 if j == 0 else _CHANNELS_3)
    n_channels = 6 + 3 * (NUM_JOINTS - 1)
    motion = np.zeros(n_channels)
    motion[:3] = p[0]
    lines += ["MOTION", "Frames: 1", f"Frame Time: {frame_time:.6f}", fmt(motion)]
    return "\n".join(lines) + "\n"


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """``v (..., 3)`` scaled to unit length; ``fallback`` where it has (nearly) none."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 1e-9, v / np.maximum(n, 1e-12), fallback)


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``(..., 3, 3)``: the smallest rotations turning the unit vectors ``a (3,)`` onto ``b (..., 3)``."""
    v = np.cross(a, b)
    c = b @ a
    vx = np.zeros(v.shape[:-1] + (3, 3))
    vx[..., 0, 1], vx[..., 0, 2], vx[..., 1, 2] = -v[..., 2], v[..., 1], -v[..., 0]
    vx[..., 1, 0], vx[..., 2, 0], vx[..., 2, 1] = v[..., 2], -v[..., 1], v[..., 0]
    R = np.eye(3) + vx + vx @ vx / np.maximum(1.0 + c, 1e-12)[..., None, None]
    back = c < -1.0 + 1e-9  # (opposite: half a turn about an axis across a)
    if np.any(back):
        axis = np.cross(a, [1.0, 0.0, 0.0])
        axis = axis if np.linalg.norm(axis) > 1e-6 else np.cross(a, [0.0, 1.0, 0.0])
        axis = axis / np.linalg.norm(axis)
        R[back] = 2.0 * np.outer(axis, axis) - np.eye(3)
    return R


def _euler_zxy_deg(R: np.ndarray) -> np.ndarray:
    """``(..., 3)`` degrees (z, x, y) with ``R = Rz(z) Rx(x) Ry(y)`` for the rotations ``R (..., 3, 3)``: the
    ``Zrotation Xrotation Yrotation`` channels (read in that order, intrinsic)."""
    sx = np.clip(R[..., 2, 1], -1.0, 1.0)
    x = np.arcsin(sx)
    lock = np.abs(sx) > 1.0 - 1e-9  # (x at +-90 deg: z and y turn about one axis; all of it in z)
    z = np.where(lock, np.arctan2(R[..., 1, 0], R[..., 0, 0]), np.arctan2(-R[..., 0, 1], R[..., 1, 1]))
    y = np.where(lock, 0.0, np.arctan2(-R[..., 2, 0], R[..., 2, 2]))
    return np.degrees(np.stack([z, x, y], axis=-1))


def _continuous_euler(E: np.ndarray) -> np.ndarray:
    """``E (T, ..., 3)`` Euler degrees (z, x, y) of :func:`_euler_zxy_deg`, each frame's the one of its two equivalent
    triples (``(z + 180, 180 - x, y + 180)`` turns the same), plus whole turns, nearest the frame before's: a tool
    interpolating between frames turns a joint the short way (a review counted 62 jumps of more than 180 deg in S9's
    Walking 1)."""
    out = E.copy()
    alt = E + np.array([180.0, 0.0, 180.0])
    alt[..., 1] = 180.0 - E[..., 1]
    for t in range(1, len(E)):
        prev = out[t - 1]
        a = E[t] + 360.0 * np.round((prev - E[t]) / 360.0)
        b = alt[t] + 360.0 * np.round((prev - alt[t]) / 360.0)
        use_b = np.abs(b - prev).sum(-1, keepdims=True) < np.abs(a - prev).sum(-1, keepdims=True)
        out[t] = np.where(use_b, b, a)
    return out


def bvh_animation_text(poses: Any, *, fps: float, units: str = "cm") -> str:
    """A BVH animation of one person over ``T`` frames, ``poses (T, 17, 3)`` mm (camera frame), ``fps`` frames/s.

    A rig as animation tools take it: the rest pose (the OFFSETs) has each bone at its mean length over the frames,
    along its direction in the first frame; each frame turns every joint (``Zrotation Xrotation Yrotation``, degrees,
    in its parent's turned frame, continuous from frame to frame) so that its bones point at their children (the one
    bone of a joint with one child exactly; the two or three of the pelvis and
    the thorax as nearly as one rotation can, least squares), so that a tool drawing bones from the rest pose, as
    Blender does, draws them from joint to joint. A lifted pose's bone lengths change a little from frame to frame, so
    every joint also has ``Xposition Yposition Zposition`` channels: its whole translation from its parent in the
    parent's turned frame, in place of the OFFSET (as Blender's BVH importer and exporter read and write them), so
    the joint positions are exact. (Until 2026-12 the channels held each bone's change from the OFFSET, added to it,
    with no rotations: Blender drew bones a few mm long; a review. ``read_bvh_frames(path,
    position_channels="add")`` reads those files.) :func:`read_bvh_frames` reads it back exactly; an importer that
    ignores position channels on non-root joints shows mean-length bones turned as the person turns, and one that
    adds them to the OFFSET (three.js's ``BVHLoader``) shows each bone about twice as long: the GLB
    (:func:`write_glb_animation`) is the file for those.
    """
    if units not in UNITS_MM:
        raise PoseLifterError(f"units must be one of {sorted(UNITS_MM)}, got {units!r}")
    if not (math.isfinite(fps) and fps > 0):
        raise PoseLifterError(f"fps must be > 0, got {fps}")
    P = as_points(poses, name="poses", dim=3, num_joints=NUM_JOINTS)
    if P.ndim != 3 or len(P) == 0:
        raise PoseLifterError(f"poses: expected (T, 17, 3) mm with T >= 1, got {tuple(P.shape)}")
    p = to_y_up(P) / UNITS_MM[units]
    par = np.array([max(q, 0) for q in PARENTS])
    bones = p - p[:, par]  # (T, 17, 3); row 0 unused
    length = np.linalg.norm(bones, axis=-1).mean(0)
    up = np.array([0.0, 1.0, 0.0])
    # (the first frame's directions: a pose the body had; directions averaged over a clip where the person turns
    # point the hips and shoulders anywhere, a review's up and down)
    rest_dir = _unit(bones[0], _unit(bones.mean(0), up))
    offsets = rest_dir * length[:, None]
    offsets[0] = 0.0
    lines, order = _bvh_hierarchy(offsets, lambda v: " ".join(f"{x:.5f}" for x in v), lambda j: _CHANNELS_6)
    T = len(p)
    G = np.zeros((T, NUM_JOINTS, 3, 3))  # each joint's turn in the y-up frame (of its children's offsets)
    for j in order:  # (parents first; each joint turned in its parent's turned frame, so only by its own bend: a
        kids = _children(j)  # review saw every joint undo the whole body's turn, 90 deg at the median)
        Gp = np.broadcast_to(np.eye(3), (T, 3, 3)) if j == 0 else G[:, PARENTS[j]]
        if not kids:
            G[:, j] = Gp
            continue
        seen = np.einsum("tki,tnk->tni", Gp, bones[:, kids])  # (the children's bones in the parent's frame)
        if len(kids) == 1:
            rest = _unit(offsets[kids[0]], up)
            L = _align(rest, _unit(seen[:, 0], rest))
        else:
            L = best_rotation(np.broadcast_to(offsets[kids], seen.shape), seen)[0]
        G[:, j] = Gp @ L
    parent_G = G[:, par]  # (the root's parent: none; its rows below are its own)
    local_R = np.swapaxes(parent_G, -1, -2) @ G
    local_R[:, 0] = G[:, 0]
    local_t = np.einsum("tjki,tjk->tji", parent_G, bones)  # (G_parent^T @ bone)
    local_t[:, 0] = p[:, 0]
    euler = _continuous_euler(_euler_zxy_deg(local_R))
    rows = np.concatenate([local_t, euler], axis=-1)[:, order].reshape(T, -1)
    lines += ["MOTION", f"Frames: {T}", f"Frame Time: {1.0 / fps:.6f}"]
    lines += [" ".join(f"{x:.5f}" for x in row) for row in rows]
    return "\n".join(lines) + "\n"


def write_bvh_animation(poses: Any, path: str | os.PathLike[str], *, fps: float, units: str = "cm") -> Path:
    """Write ``poses (T, 17, 3)`` mm (camera frame) as a BVH animation (:func:`bvh_animation_text`)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    return write_atomic(path, bvh_animation_text(poses, fps=fps, units=units))


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


def read_bvh_frames(path: str | os.PathLike[str], *, units: str = "cm",
                    position_channels: Literal["replace", "add"] = "replace") -> np.ndarray:
    """Forward kinematics of every frame of a BVH file (any joint names/channels; Euler angles in the listed
    channel order, intrinsic). A joint's position channels are its translation from its parent, in place of its
    OFFSET (``position_channels="replace"``, as Blender reads them), or added to the OFFSET (``"add"``: as three.js's
    ``BVHLoader`` reads them, and as :func:`write_bvh_animation` wrote them until 2026-12); a root with an OFFSET of
    zero, as this module writes, reads the same either way. Returns the positions of the joints named like the H36M
    joints, ``(T, 17, 3)`` mm, camera frame (the inverse of :func:`write_bvh` and :func:`write_bvh_animation`)."""
    if position_channels not in ("replace", "add"):
        raise PoseLifterError(f"position_channels must be 'replace' or 'add', got {position_channels!r}")
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except OSError as exc:
        raise PoseLifterError(f"{path}: cannot read ({exc.strerror or exc})") from None
    try:
        return _bvh_frames(text, path, units=units, position_channels=position_channels)
    except PoseLifterError:
        raise
    except (ValueError, IndexError) as exc:  # (a number that is not one, a brace or a field missing)
        raise PoseLifterError(f"{path}: not a well-formed BVH file ({type(exc).__name__}: {exc})") from None


def _bvh_frames(text: str, path: Any, *, units: str, position_channels: str) -> np.ndarray:
    """:func:`read_bvh_frames` of the file's ``text``; a malformed file raises ValueError or IndexError."""
    tokens = text.split()
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
    names = [n for n, *_ in joints]
    missing = [n for n in JOINT_NAMES if n not in names]
    if missing:
        raise PoseLifterError(f"{path}: BVH lacks the H36M joints {missing}")
    # MOTION: Frames: N  Frame Time: dt  values...
    n_frames = 1
    while i < len(tokens) and tokens[i] != "Time:":
        if tokens[i] == "Frames:":
            n_frames = int(tokens[i + 1])
        i += 1
    values = np.array([float(x) for x in tokens[i + 2:]])
    n_ch = sum(len(ch) for *_, ch in joints)
    if n_ch == 0 or len(values) < n_frames * n_ch:
        raise PoseLifterError(f"{path}: BVH MOTION has {len(values)} values, expected {n_frames} x {n_ch}")
    out = np.empty((n_frames, NUM_JOINTS, 3))
    for f in range(n_frames):
        row = values[f * n_ch:(f + 1) * n_ch]
        pos = np.zeros((len(joints), 3))
        rot = [np.eye(3)] * len(joints)
        k = 0
        for j, (_, par, off, ch) in enumerate(joints):
            R = np.eye(3)
            local = off.copy()  # (replace: the channels given, the OFFSET's value for any not given)
            for c in ch:
                v = row[k]
                k += 1
                if c.endswith("position"):
                    axis = "XYZ".index(c[0])
                    local[axis] = v + (off[axis] if position_channels == "add" else 0.0)
                else:
                    R = R @ _rot(c[0], v)
            if par < 0:
                pos[j] = local
                rot[j] = R
            else:
                pos[j] = pos[par] + rot[par] @ local
                rot[j] = rot[par] @ R
        out[f] = np.stack([pos[names.index(n)] for n in JOINT_NAMES])
    if position_channels == "replace" and n_frames:
        _note_delta_channels(joints, values[:n_frames * n_ch].reshape(n_frames, n_ch), path)
    return from_y_up(out * UNITS_MM[units])


def _note_delta_channels(joints: list[tuple[str, int, np.ndarray, list[str]]], motion: np.ndarray, path: Any) -> None:
    """Warn when a BVH reads as one whose joints' position channels hold each bone's change from its OFFSET, added to
    it, as :func:`write_bvh_animation` wrote them before 2026-12 (a review: such a file read now was 735 mm off,
    silently): no rotation anywhere, and the bones' lengths over the frames far steadier with the channels added to
    the OFFSETs than in place of them (a body's bones keep their lengths); in one frame, channels mostly far shorter
    than the OFFSETs."""
    k, add, replace, short, turned = 0, [], [], [], False
    for _, par, off, ch in joints:
        pos = [k + i for i, c in enumerate(ch) if c.endswith("position")]
        turned = turned or bool(np.any(motion[:, [k + i for i, c in enumerate(ch) if c.endswith("rotation")]]))
        k += len(ch)
        if par >= 0 and len(pos) == 3 and np.linalg.norm(off) > 0:
            for out, vec in ((add, off + motion[:, pos]), (replace, motion[:, pos])):
                n = np.linalg.norm(vec, axis=1)
                out.append(float(n.std() / max(n.mean(), 1e-9)))
            short.append(float(np.median(np.linalg.norm(motion[:, pos], axis=1)) / np.linalg.norm(off)))
    if turned or len(short) < 4:
        return
    if float(np.median(short)) < 0.25 or (len(motion) > 1 and float(np.median(add)) < 0.5 * float(np.median(replace))):
        warn_user(f"{path}: its joints' position channels read as each bone's change from its OFFSET (no rotations, "
                  "and the bones keep their lengths far better with the channels added to the OFFSETs), as in a file "
                  "poselifter wrote before 2026-12: read it with position_channels=\"add\"")


def read_bvh(path: str | os.PathLike[str], *, units: str = "cm") -> np.ndarray:
    """The first frame of :func:`read_bvh_frames`: ``(17, 3)`` mm, camera frame (the inverse of :func:`write_bvh`)."""
    frames = read_bvh_frames(path, units=units)
    if not len(frames):
        raise PoseLifterError(f"{path}: the BVH has no frames (Frames: 0)")
    return frames[0]


__all__ = ["bvh_animation_text", "bvh_text", "from_y_up", "person_prefix", "read_bvh", "read_bvh_frames",
           "read_glb_animation", "read_glb_joints", "skeleton_scene", "to_y_up", "write_bvh", "write_bvh_animation",
           "write_glb", "write_glb_animation"]
