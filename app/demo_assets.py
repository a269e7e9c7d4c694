# pyright: reportAttributeAccessIssue=false, reportOptionalMemberAccess=false, reportIndexIssue=false, reportReturnType=false, reportArgumentType=false
# (trimesh / numpy stubs)
"""The embedded demo samples: authored 3D poses, a trimesh mannequin, rendered with OpenCV.

Nothing here comes from Human3.6M. Each sample is made from scratch:

1. a 3D pose is authored joint by joint (17 H36M joints, world frame: **millimetres, z up**,
   floor at z = 0) with forward kinematics on plausible adult bone lengths;
2. a mannequin mesh is built around it with :mod:`trimesh` (capsules for limbs and torso, a
   sphere for the head, boxes for the feet and, for "sitting", a stool);
3. the mesh is rendered through a known pinhole camera (no lens distortion; OpenCV camera frame
   +x right, +y down, +z forward) with OpenCV, painter's algorithm and Lambert shading, over a
   floor and a wall, at 2x and down-sampled (anti-aliasing).

The 2D joints are the exact pinhole projections of the 3D joints and the 3D ground truth is exact,
so the demo samples have ground truth for every metric. ``scripts/make_demo_assets.py`` writes them
to ``assets/demo/`` (``samples.npz`` + one JPEG per sample); :func:`load_demo_samples` reads them.
"""

from __future__ import annotations

import io
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np
import trimesh

from lifter.camera import image_centre, project, project_generic, world_to_camera
from lifter.io import write_atomic
from lifter.skeleton import EDGES, JOINT_NAMES, NUM_JOINTS

DEMO_DIR = Path(__file__).resolve().parent.parent / "assets" / "demo"
"""Default location of the generated demo assets."""

J = {name: i for i, name in enumerate(JOINT_NAMES)}

# Bone lengths, mm (roughly an adult of 1.75 m).
HIP_HALF_WIDTH = 125.0
THIGH = 440.0
SHIN = 430.0
PELVIS_TO_SPINE = 230.0
SPINE_TO_THORAX = 250.0
THORAX_TO_NECK = 110.0
NECK_TO_HEAD_TOP = 120.0
SHOULDER_HALF_WIDTH = 160.0
UPPER_ARM = 280.0
FOREARM = 250.0
ANKLE_HEIGHT = 80.0


def _unit(v: tuple[float, float, float]) -> np.ndarray:
    a = np.asarray(v, np.float64)
    return a / np.linalg.norm(a)


@dataclass(frozen=True)
class PoseSpec:
    """Limb directions in the body frame ``(right, forward, up)`` (unit-free; normalized)."""

    r_thigh: tuple[float, float, float] = (0.05, 0.0, -1.0)
    r_shin: tuple[float, float, float] = (0.0, 0.0, -1.0)
    l_thigh: tuple[float, float, float] = (-0.05, 0.0, -1.0)
    l_shin: tuple[float, float, float] = (0.0, 0.0, -1.0)
    spine: tuple[float, float, float] = (0.0, 0.0, 1.0)
    neck: tuple[float, float, float] = (0.0, 0.25, 1.0)
    r_upper: tuple[float, float, float] = (0.15, 0.0, -1.0)
    r_fore: tuple[float, float, float] = (0.05, 0.2, -1.0)
    l_upper: tuple[float, float, float] = (-0.15, 0.0, -1.0)
    l_fore: tuple[float, float, float] = (-0.05, 0.2, -1.0)
    stool: bool = False


POSES: dict[str, PoseSpec] = {
    "standing": PoseSpec(),
    "walking": PoseSpec(
        r_thigh=(0.03, 0.4, -1.0), r_shin=(0.0, 0.1, -1.0), l_thigh=(-0.03, -0.35, -1.0), l_shin=(0.0, -0.7, -1.0),
        r_upper=(0.1, -0.35, -1.0), r_fore=(0.05, 0.1, -1.0), l_upper=(-0.1, 0.4, -1.0), l_fore=(0.0, 0.9, -1.0),
        spine=(0.0, 0.08, 1.0)),
    "sitting": PoseSpec(
        r_thigh=(0.12, 1.0, -0.05), r_shin=(0.0, 0.15, -1.0), l_thigh=(-0.12, 1.0, -0.05), l_shin=(0.0, 0.15, -1.0),
        r_upper=(0.1, 0.35, -1.0), r_fore=(0.0, 1.0, -0.15), l_upper=(-0.1, 0.35, -1.0), l_fore=(0.0, 1.0, -0.15),
        spine=(0.0, -0.1, 1.0), stool=True),
    "reaching": PoseSpec(
        r_upper=(0.15, 0.6, 0.8), r_fore=(0.05, 0.75, 0.65), l_upper=(-1.0, 0.15, -0.35), l_fore=(-1.0, 0.3, 0.1),
        spine=(0.0, 0.2, 1.0), r_thigh=(0.08, 0.1, -1.0), l_thigh=(-0.1, -0.1, -1.0)),
    "crouching": PoseSpec(
        r_thigh=(0.3, 0.85, -0.45), r_shin=(0.05, -0.35, -1.0), l_thigh=(-0.3, 0.85, -0.45),
        l_shin=(-0.05, -0.35, -1.0), spine=(0.0, 0.55, 1.0), neck=(0.0, 0.6, 1.0), r_upper=(0.1, 1.0, -0.5),
        r_fore=(0.0, 1.0, 0.1), l_upper=(-0.1, 1.0, -0.5), l_fore=(0.0, 1.0, 0.1)),
}
"""The authored poses, by sample name."""


def author_pose(spec: PoseSpec) -> np.ndarray:
    """Forward kinematics of a :class:`PoseSpec`: ``(17, 3)`` mm in the body frame ``(right, forward, up)``,
    pelvis above the origin and the lowest ankle at :data:`ANKLE_HEIGHT` above the floor ``up = 0``."""
    P = np.zeros((NUM_JOINTS, 3))
    right, up = np.array([1.0, 0, 0]), np.array([0, 0, 1.0])
    P[J["r_hip"]] = P[0] + HIP_HALF_WIDTH * right
    P[J["l_hip"]] = P[0] - HIP_HALF_WIDTH * right
    P[J["r_knee"]] = P[J["r_hip"]] + THIGH * _unit(spec.r_thigh)
    P[J["r_ankle"]] = P[J["r_knee"]] + SHIN * _unit(spec.r_shin)
    P[J["l_knee"]] = P[J["l_hip"]] + THIGH * _unit(spec.l_thigh)
    P[J["l_ankle"]] = P[J["l_knee"]] + SHIN * _unit(spec.l_shin)
    spine = _unit(spec.spine)
    P[J["spine"]] = P[0] + PELVIS_TO_SPINE * spine
    P[J["thorax"]] = P[J["spine"]] + SPINE_TO_THORAX * spine
    P[J["neck_nose"]] = P[J["thorax"]] + THORAX_TO_NECK * _unit(spec.neck)
    P[J["head_top"]] = P[J["neck_nose"]] + NECK_TO_HEAD_TOP * _unit((0.0, -0.15, 1.0))
    shoulder_base = P[J["thorax"]] - 25.0 * up
    P[J["r_shoulder"]] = shoulder_base + SHOULDER_HALF_WIDTH * right
    P[J["l_shoulder"]] = shoulder_base - SHOULDER_HALF_WIDTH * right
    P[J["r_elbow"]] = P[J["r_shoulder"]] + UPPER_ARM * _unit(spec.r_upper)
    P[J["r_wrist"]] = P[J["r_elbow"]] + FOREARM * _unit(spec.r_fore)
    P[J["l_elbow"]] = P[J["l_shoulder"]] + UPPER_ARM * _unit(spec.l_upper)
    P[J["l_wrist"]] = P[J["l_elbow"]] + FOREARM * _unit(spec.l_fore)
    lowest = min(P[J["r_ankle"], 2], P[J["l_ankle"], 2])
    P[:, 2] += ANKLE_HEIGHT - lowest
    return P


def body_to_world(pose_body: np.ndarray, *, yaw_deg: float, position_xy: tuple[float, float]) -> np.ndarray:
    """Place a body-frame pose in the world (mm, z up): the body faces ``-y`` rotated by ``yaw_deg``
    about +z, with the pelvis above ``position_xy``."""
    th = np.deg2rad(yaw_deg)
    forward = np.array([np.sin(th), -np.cos(th), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(forward, up)
    B = np.stack([right, forward, up], axis=1)  # columns: body axes in world
    world = pose_body @ B.T
    world[:, 0] += position_xy[0]
    world[:, 1] += position_xy[1]
    return world


def look_at_camera(*, eye: np.ndarray, target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """OpenCV world-to-camera ``(R, t)`` for a camera at ``eye`` (mm) looking at ``target``, world z up."""
    z = _unit(tuple(target - eye))
    x = np.cross(z, np.array([0.0, 0.0, 1.0]))
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    R = np.stack([x, y, z])
    return R, -R @ eye


# --------------------------------------------------------------------------------------------
# Mannequin
# --------------------------------------------------------------------------------------------

SHIRT = (70, 110, 175)
TROUSERS = (60, 62, 78)
SKIN = (226, 188, 150)
SHOES = (45, 35, 32)
STOOL = (150, 110, 70)


def _capsule(a: np.ndarray, b: np.ndarray, radius: float, color: tuple[int, int, int]) -> trimesh.Trimesh:
    d = b - a
    length = float(np.linalg.norm(d))
    m = trimesh.creation.capsule(height=max(length, 1e-3), radius=radius, count=[12, 12])
    T = trimesh.geometry.align_vectors([0, 0, 1], d / max(length, 1e-9))
    T[:3, 3] = (a + b) / 2
    m.apply_transform(T)
    m.visual.face_colors = np.array([*color, 255], np.uint8)
    return m


def build_mannequin(pose_world: np.ndarray, *, stool: bool = False) -> trimesh.Trimesh:
    """A coloured mannequin mesh (mm, world frame) around a ``(17, 3)`` pose."""
    P = pose_world
    parts: list[trimesh.Trimesh] = []
    limb = {(1, 2): 70, (2, 3): 52, (4, 5): 70, (5, 6): 52, (11, 12): 46, (12, 13): 38, (14, 15): 46, (15, 16): 38}
    for (a, b), r in limb.items():
        parts.append(_capsule(P[a], P[b], r, TROUSERS if a in (1, 2, 4, 5) else SHIRT))
    parts.append(_capsule(P[0], P[J["spine"]], 120, TROUSERS))
    chest = P[J["thorax"]] - 40 * _unit(tuple(P[J["thorax"]] - P[J["spine"]]))
    parts.append(_capsule(P[J["spine"]], chest, 125, SHIRT))
    parts.append(_capsule(P[J["l_hip"]], P[J["r_hip"]], 95, TROUSERS))
    parts.append(_capsule(P[J["l_shoulder"]], P[J["r_shoulder"]], 62, SHIRT))
    parts.append(_capsule(P[J["thorax"]], P[J["neck_nose"]], 45, SKIN))
    head_axis = _unit(tuple(P[J["head_top"]] - P[J["neck_nose"]]))
    head = trimesh.creation.icosphere(subdivisions=2, radius=100.0)
    head.apply_scale([0.9, 0.9, 1.1])
    head.apply_translation(P[J["head_top"]] - 95.0 * head_axis)
    head.visual.face_colors = np.array([*SKIN, 255], np.uint8)
    parts.append(head)
    for elbow, wrist in ((12, 13), (15, 16)):
        hand = trimesh.creation.icosphere(subdivisions=1, radius=45.0)
        hand.apply_translation(P[wrist] + 40.0 * _unit(tuple(P[wrist] - P[elbow])))
        hand.visual.face_colors = np.array([*SKIN, 255], np.uint8)
        parts.append(hand)
    for knee, ankle in ((2, 3), (5, 6)):
        shin = P[ankle] - P[knee]
        fwd = np.cross(np.array([0.0, 0, 1]), np.cross(shin, np.array([0.0, 0, 1])))
        hip_axis = P[J["r_hip"]] - P[J["l_hip"]]
        fwd = np.cross(np.array([0.0, 0.0, 1.0]), hip_axis)  # body forward = up x right
        fwd = fwd / np.linalg.norm(fwd)
        toe = P[ankle] + 170.0 * fwd
        toe[2] = max(toe[2] - 40.0, 35.0)
        parts.append(_capsule(P[ankle] - 30.0 * fwd + [0, 0, -25.0], toe, 38, SHOES))
    if stool:
        top = P[0][2] - 110.0
        box = trimesh.creation.box(extents=[420.0, 420.0, top])
        box.apply_translation([P[0][0], P[0][1], top / 2])
        box.visual.face_colors = np.array([*STOOL, 255], np.uint8)
        parts.append(box)
    return trimesh.util.concatenate(parts)


# --------------------------------------------------------------------------------------------
# Rendering
# --------------------------------------------------------------------------------------------


def render_mesh(
    mesh: trimesh.Trimesh,
    *,
    R: np.ndarray,
    t: np.ndarray,
    focal: tuple[float, float],
    principal_point: tuple[float, float],
    size: tuple[int, int],
    supersample: int = 2,
) -> np.ndarray:
    """Render a world-frame (mm) mesh with floor and wall through a pinhole camera: ``(H, W, 3)`` uint8 RGB."""
    W, H = size
    s = supersample
    f = np.asarray(focal, np.float64) * s
    # (pixel i covers [i, i + 1) as in lifter.camera.project, and OpenCV draws pixel k's centre at k: a point u px
    # lands at u * s - 0.5 of the supersampled raster. A review measured the renders 0.5 px off with (pp + 0.5) * s.)
    c = np.asarray(principal_point, np.float64) * s - 0.5
    img = np.empty((H * s, W * s, 3), np.uint8)
    grad = np.linspace(235, 200, H * s)[:, None]
    img[:] = np.stack([grad, grad, grad + 6], axis=-1).clip(0, 255).astype(np.uint8)

    def proj(pw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        pc = world_to_camera(pw, R, t)
        z = pc[..., 2]
        return project_generic(np.concatenate([pc[..., :2], np.maximum(z, 1e-6)[..., None]], axis=-1), f, c,
                               per_joint=True), z

    # Floor tiles (checkerboard, 500 mm), far to near, only tiles fully in front of the camera.
    tiles = []
    for ix in range(-24, 24):
        for iy in range(-16, 30):
            quad = np.array([[ix, iy, 0], [ix + 1, iy, 0], [ix + 1, iy + 1, 0], [ix, iy + 1, 0]], np.float64) * 500.0
            uv, z = proj(quad)
            if np.all(z > 200):
                tiles.append((z.mean(), uv, (ix + iy) % 2))
    for _, uv, parity in sorted(tiles, key=lambda x: -x[0]):
        col = (178, 170, 160) if parity else (150, 143, 135)
        cv2.fillConvexPoly(img, np.round(uv * 16).astype(np.int32), col, lineType=cv2.LINE_AA, shift=4)

    V = np.asarray(mesh.vertices, np.float64)
    F = np.asarray(mesh.faces)
    uv, z = proj(V)
    normals_c = world_to_camera(np.asarray(mesh.face_normals), R, np.zeros(3))
    light = _unit((-0.4, -0.6, -1.0))  # from the upper left, towards the camera
    centers_c = world_to_camera(V[F].mean(1), R, t)
    facing = np.einsum("ij,ij->i", normals_c, centers_c) < 0
    shade = 0.35 + 0.65 * np.clip(normals_c @ light, 0, 1)
    colors = np.asarray(mesh.visual.face_colors)[:, :3].astype(np.float64) * shade[:, None]
    order = np.argsort(-z[F].mean(1))
    # (faces behind the camera are not drawn, but their points are divided by ~0: kept within int32 at 1/16 px)
    pts = np.round(np.clip(uv[F], -1e8, 1e8) * 16).astype(np.int32)
    for i in order:
        if facing[i] and np.all(z[F[i]] > 1):
            cv2.fillConvexPoly(img, pts[i], tuple(float(v) for v in colors[i]), lineType=cv2.LINE_AA, shift=4)
    return cv2.resize(img, (W, H), interpolation=cv2.INTER_AREA)


@dataclass(frozen=True)
class DemoSpec:
    """Where a demo sample's person stands and how the camera sees it."""

    name: str
    yaw_deg: float
    position_xy: tuple[float, float]
    focal: float
    camera_height: float = 1500.0
    azimuth_deg: float = 0.0


DEMO_SPECS: tuple[DemoSpec, ...] = (
    DemoSpec("standing", yaw_deg=15.0, position_xy=(300.0, 0.0), focal=1000.0),
    DemoSpec("walking", yaw_deg=-60.0, position_xy=(-400.0, 500.0), focal=800.0, azimuth_deg=10.0),
    DemoSpec("sitting", yaw_deg=35.0, position_xy=(0.0, 0.0), focal=1200.0, camera_height=1300.0),
    DemoSpec("reaching", yaw_deg=-25.0, position_xy=(500.0, -300.0), focal=900.0, azimuth_deg=-15.0),
    DemoSpec("crouching", yaw_deg=20.0, position_xy=(-200.0, 200.0), focal=1500.0, camera_height=1700.0),
)
IMAGE_SIZE = (800, 600)


def make_sample(spec: DemoSpec, *, size: tuple[int, int] = IMAGE_SIZE) -> dict[str, np.ndarray]:
    """Author, build and render one demo sample. Returns arrays (see :func:`write_demo_assets`) plus ``image``."""
    pose_spec = POSES[spec.name]
    world = body_to_world(author_pose(pose_spec), yaw_deg=spec.yaw_deg, position_xy=spec.position_xy)
    W, H = size
    height_px = 0.72 * H
    extent = float(world[:, 2].max() - 0.0 + 150.0)
    dist = spec.focal * extent / height_px
    target = np.array([world[0, 0], world[0, 1], 0.5 * extent])
    az = np.deg2rad(spec.azimuth_deg)
    eye = target + dist * np.array([np.sin(az), -np.cos(az), 0.0])
    eye[2] = spec.camera_height
    R, t = look_at_camera(eye=eye, target=target)
    cx, cy = image_centre((W, H))
    pp = (float(cx), float(cy))
    fxy = (spec.focal, spec.focal)
    mesh = build_mannequin(world, stool=pose_spec.stool)
    image = render_mesh(mesh, R=R, t=t, focal=fxy, principal_point=pp, size=size)
    cam = world_to_camera(world, R, t)
    kp = project(cam, focal=fxy, principal_point=pp)
    return {"name": np.array(spec.name), "keypoints_2d": kp, "pose_3d": cam, "pose_world": world,
            "focal": np.array(fxy), "principal_point": np.array(pp), "image_size": np.array(size),
            "R": R, "t": t, "image": image}


def write_demo_assets(out_dir: Path = DEMO_DIR, *, specs: tuple[DemoSpec, ...] = DEMO_SPECS,
                      log: Callable[[str], None] = print) -> Path:
    """Render every demo sample to ``out_dir``: ``<name>.jpg`` and ``samples.npz`` with
    ``names (N,)``, ``keypoints_2d (N,17,2)`` px, ``pose_3d (N,17,3)`` mm camera frame,
    ``pose_world (N,17,3)`` mm world (z up), ``focal``/``principal_point (N,2)`` px,
    ``image_size (N,2)`` (W, H) px, ``R (N,3,3)``, ``t (N,3)`` mm (``X_cam = R X_world + t``)."""
    out_dir.mkdir(parents=True, exist_ok=True)
    samples = [make_sample(s) for s in specs]
    for s in samples:
        path = out_dir / f"{s['name']}.jpg"
        ok, jpg = cv2.imencode(".jpg", cv2.cvtColor(s["image"], cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, 88])
        if not ok:
            raise RuntimeError(f"could not encode {path}")
        write_atomic(path, jpg.tobytes())
        log(f"wrote {path}")
    keys = ("keypoints_2d", "pose_3d", "pose_world", "focal", "principal_point", "image_size", "R", "t")
    arrays = {k: np.stack([s[k] for s in samples]) for k in keys}
    arrays["names"] = np.array([str(s["name"]) for s in samples])
    buf = io.BytesIO()
    np.savez_compressed(buf, **arrays)
    write_atomic(out_dir / "samples.npz", buf.getvalue())
    log(f"wrote {out_dir / 'samples.npz'}")
    return out_dir


__all__ = ["DEMO_DIR", "DEMO_SPECS", "POSES", "author_pose", "build_mannequin", "make_sample", "render_mesh",
           "write_demo_assets", "EDGES"]
