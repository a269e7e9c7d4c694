"""Typed groups of 3D scene handles and the functions that draw into them (viser world: metres, z up).

* ``/floor``: the floor grid (z = 0; hidden for uploads, whose camera height is a guess);
* ``/cam``: the sample's camera, posed by its extrinsics (``X_world = R^T (X_cam - t)``). Everything below it is
  in the **OpenCV camera frame** (+x right, +y down, +z forward), metres: the frustum and the image plane at 1 m,
  or nearer where it would be more than 1 m across (:func:`image_plane_depth`: short focals bring it nearer as they
  bring the lifted person nearer, so it never grows in front of them), the draggable 2D joints on that plane,
  the lifted skeleton at its absolute position, the per-joint uncertainty clouds, the ground truth, the
  analytic-root skeleton, the root's viewing ray and the lifted root's trajectory during playback.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import viser
import viser.transforms as vtf

from lifter.camera import image_centre
from lifter.skeleton import EDGES, JOINT_NAMES, NUM_JOINTS

from . import framing
from .core import Frame, SessionState
from .drawing import COLORS, JOINT_RGB, canvas

IMAGE_PLANE_MAX_DEPTH_M: float = 1.0
"""The image plane's depth (m) in the 3D view where it is at most :data:`IMAGE_PLANE_SIDE_M` across there
(:func:`image_plane_depth`)."""
IMAGE_PLANE_SIDE_M: float = 1.0
"""The image plane's longest side (m) in the 3D view: nearer than :data:`IMAGE_PLANE_MAX_DEPTH_M` at focal
lengths that would make it larger (:func:`image_plane_depth`)."""
JOINT_RADIUS_M: float = 0.012
"""Radius (m) of the draggable 2D joint spheres on the image plane in the overview."""
HEAD_ON_JOINT_RADIUS: float = 0.02
"""Head-on image view: sphere radius as a fraction of the 2D joints' extent on the image plane."""
GT_RGB = COLORS["gt"]
ANALYTIC_RGB = (255, 140, 0)
RAY_RGB = (250, 210, 0)
FRUSTUM_RGB = (30, 30, 30)
OTHER_RGB = (0, 150, 150)
DRAG_OFFSET_RGB = (120, 120, 120)
MAX_PEOPLE_LABELS: int = 8
"""Labels drawn for at most this many other people (their skeletons are all drawn)."""
MAX_TRAIL_GAP: int = 12
"""Trajectory: recorded frames further apart than this are not joined."""


def edges_points(P: np.ndarray) -> np.ndarray:
    """``(16, 2, 3)`` bone segments of a ``(17, 3)`` pose."""
    P = np.asarray(P)
    return np.stack([P[[a for a, _ in EDGES]], P[[b for _, b in EDGES]]], axis=1)


def _bone_colors() -> np.ndarray:
    c = JOINT_RGB[[b for _, b in EDGES]]
    return np.repeat(c[:, None, :], 2, axis=1)


ANALYTIC_DASH_M: float = 0.05
"""Length (m) of a dash of the analytic-root skeleton, and of the gap after it (each bone holds a whole number of
dash-gap pairs, at least one): a browser trial saw the earlier 4 dashes per bone, 4.5 cm thick, merge into a solid
skeleton."""
ANALYTIC_THICKNESS_M: float = 0.012


def _dashed(P: np.ndarray, dash: float = ANALYTIC_DASH_M) -> np.ndarray:
    """Bones of ``P`` (m) cut into dashes ``(n, 2, 3)``: each bone into ``k = max(1, round(length / (2 dash)))``
    equal dash-gap pairs, the dashes kept."""
    out = []
    for a, b in edges_points(P):
        k = max(1, round(float(np.linalg.norm(b - a)) / (2.0 * dash)))
        t = np.linspace(0.0, 1.0, 2 * k + 1)
        pts = a[None] + (b - a)[None] * t[:, None]
        out.append(np.stack([pts[0:-1:2], pts[1::2]], axis=1))
    return np.concatenate(out)


@dataclass
class CameraNodes:
    """The sample's camera: its pose, frustum, image plane, the root ray and the trajectory."""

    floor: viser.GridHandle
    frame: viser.FrameHandle
    frustum: viser.LineSegmentsHandle
    image: viser.ImageHandle
    ray: viser.LineSegmentsHandle
    root: viser.IcosphereHandle
    root_label: viser.LabelHandle
    trail: viser.LineSegmentsHandle


@dataclass
class PoseNodes:
    """The 2D joints on the image plane and the 3D poses."""

    bones2d: viser.LineSegmentsHandle
    joints2d: list[viser.IcosphereHandle]
    drag_offsets: viser.LineSegmentsHandle
    """On the image plane, a grey tether from each dragged joint's own 2D to where it was dragged (a trial could not
    tell the dragged spheres from the others)."""
    lifted_bones: viser.LineSegmentsHandle
    lifted_joints: viser.PointCloudHandle
    cloud: viser.PointCloudHandle
    gt: viser.LineSegmentsHandle
    analytic: viser.LineSegmentsHandle
    analytic_root: viser.IcosphereHandle
    noisy2d: viser.LineSegmentsHandle
    """At a noise level above 0, the noisy draw that is lifted, on the image plane in the inset's purple (a teacher
    trial found it only in the small inset at the bottom of the Sample tab)."""
    others_bones2d: viser.LineSegmentsHandle
    others_bones: viser.LineSegmentsHandle
    others_joints: viser.PointCloudHandle
    others_labels: list[viser.LabelHandle]
    """The other people of the image: their 2D on the image plane, lifted skeletons and a label each."""


@dataclass
class Scene:
    camera: CameraNodes
    pose: PoseNodes


def build_scene(scene: viser.SceneApi, *, on_drag: Callable[[int, Any], None]) -> Scene:
    """The scene nodes of a tab; ``on_drag(joint, event)`` is called for drags of the 2D joint spheres."""
    z = np.zeros((1, 2, 3))
    cam = CameraNodes(
        floor=scene.add_grid("/floor", width=12.0, height=12.0, plane="xy", cell_size=0.5, section_size=1.0),
        frame=scene.add_frame("/cam", show_axes=True, axes_length=0.15, axes_radius=0.006),
        # (in screen pixels: lines of a world width met the view's own camera near the frustum's apex and filled the
        # view with black wedges, zoomed out of the head-on view: a user trial)
        frustum=scene.add_line_segments("/cam/frustum", np.zeros((8, 2, 3)), FRUSTUM_RGB, thickness=1.5,
                                        thickness_units="screen"),
        image=scene.add_image("/cam/image", np.zeros((4, 4, 3), np.uint8), 1.0, 1.0, format="jpeg",
                              cast_shadow=False, receive_shadow=False),
        ray=scene.add_line_segments("/cam/ray", np.concatenate([z, z]), RAY_RGB, thickness=2.0,
                                    thickness_units="screen"),
        root=scene.add_icosphere("/cam/root", radius=0.05, color=RAY_RGB),
        root_label=scene.add_label("/cam/root/label", "root"),
        trail=scene.add_line_segments("/cam/trail", np.zeros((1, 2, 3)), RAY_RGB, thickness=0.02, visible=False),
    )
    joints2d = []
    for j in range(NUM_JOINTS):
        # (markers on the image plane, not bodies: their shadows were a grey blob on the floor, a browser trial)
        h = scene.add_icosphere(f"/cam/joints2d/{JOINT_NAMES[j]}", radius=JOINT_RADIUS_M, subdivisions=2,
                                color=(int(JOINT_RGB[j, 0]), int(JOINT_RGB[j, 1]), int(JOINT_RGB[j, 2])),
                                cast_shadow=False, receive_shadow=False)
        h.on_drag(lambda event, j=j: on_drag(j, event))
        joints2d.append(h)
    pose = PoseNodes(
        bones2d=scene.add_line_segments("/cam/bones2d", np.zeros((16, 2, 3)), _bone_colors(), thickness=0.004),
        joints2d=joints2d,
        drag_offsets=scene.add_line_segments("/cam/drag_offsets", np.zeros((1, 2, 3)), DRAG_OFFSET_RGB,
                                             thickness=0.004, visible=False),
        lifted_bones=scene.add_line_segments("/cam/lifted/bones", np.zeros((16, 2, 3)), _bone_colors(),
                                             thickness=0.03),
        lifted_joints=scene.add_point_cloud("/cam/lifted/joints", np.zeros((NUM_JOINTS, 3)), JOINT_RGB,
                                            point_size=0.05, point_shape="circle"),
        cloud=scene.add_point_cloud("/cam/cloud", np.zeros((1, 3)), (0, 0, 0), point_size=0.018,
                                    point_shape="circle", visible=False),
        gt=scene.add_line_segments("/cam/gt", np.zeros((16, 2, 3)), GT_RGB, thickness=0.012),
        analytic=scene.add_line_segments("/cam/analytic", np.zeros((16, 2, 3)), ANALYTIC_RGB,
                                         thickness=ANALYTIC_THICKNESS_M, visible=False),
        analytic_root=scene.add_icosphere("/cam/analytic_root", radius=0.06, color=ANALYTIC_RGB, visible=False),
        noisy2d=scene.add_line_segments("/cam/noisy2d", np.zeros((16, 2, 3)), COLORS["noisy"], thickness=0.004,
                                        visible=False),
        others_bones2d=scene.add_line_segments("/cam/others/bones2d", np.zeros((16, 2, 3)), OTHER_RGB,
                                               thickness=0.003, visible=False),
        others_bones=scene.add_line_segments("/cam/others/bones", np.zeros((16, 2, 3)), OTHER_RGB, thickness=0.02,
                                             visible=False),
        others_joints=scene.add_point_cloud("/cam/others/joints", np.zeros((NUM_JOINTS, 3)), OTHER_RGB,
                                            point_size=0.04, point_shape="circle", visible=False),
        others_labels=[scene.add_label(f"/cam/others/label{k}", "", visible=False) for k in range(MAX_PEOPLE_LABELS)],
    )
    return Scene(camera=cam, pose=pose)


def image_plane_depth(state: SessionState) -> float:
    """Depth (m, camera frame) of the image plane (and of the draggable 2D joints on it) at the state's focal
    length: :data:`IMAGE_PLANE_MAX_DEPTH_M`, or nearer where the image would be more than
    :data:`IMAGE_PLANE_SIDE_M` across there: ``d = min(1, 1 / max(W / fx, H / fy))`` m. A browser trial: at 1 m
    for every focal the plane was 2 m wide at 500 px for a 1000-px image and 10 m at 100 px, and hid the person
    lifted behind it; at the depth where it is 1 m across for every focal, it stood 6 m away at 6000 px and hid
    a person lifted 25 m away from views near the camera's axis. Short focals bring it nearer as they bring the
    person nearer (Z / f is nearly constant), so a whole body in the frame stays at least about 1.7 plane depths
    away (its height spans at most the image's longer side); long focals leave it small, near the camera."""
    W, H = state.image_size
    f = np.asarray(state.focal, np.float64)
    return min(IMAGE_PLANE_MAX_DEPTH_M, IMAGE_PLANE_SIDE_M / max(W / f[0], H / f[1]))


def image_plane(state: SessionState, uv: np.ndarray) -> np.ndarray:
    """Pixels ``(..., 2)`` -> points on the image plane ``(..., 3)`` m, camera frame, at the state's focal
    (:func:`image_plane_depth`)."""
    f = np.asarray(state.focal)
    c = np.asarray(state.sample.camera.principal_point)
    d = image_plane_depth(state)
    xy = (np.asarray(uv, np.float64) - c) / f * d
    return np.concatenate([xy, np.full(xy.shape[:-1] + (1,), d)], axis=-1)


def frustum_corners(state: SessionState) -> np.ndarray:
    """The image's corners on the image plane ``(4, 3)`` m, camera frame."""
    W, H = state.image_size
    return image_plane(state, np.array([[0, 0], [W, 0], [W, H], [0, H]], np.float64))


def draw_camera(nodes: CameraNodes, state: SessionState, *, new_sample: bool, new_image: bool = True) -> None:
    """Pose and floor (``new_sample``), image (``new_image``; frames of a sequence without photos share their
    canvas), and frustum / image plane for the current focal length."""
    cam = state.sample.camera
    if new_sample:
        R = np.asarray(cam.R)
        nodes.frame.wxyz = vtf.SO3.from_matrix(R.T).wxyz
        nodes.frame.position = tuple(cam.centre / 1000.0)
        nodes.floor.visible = state.sample.upload is None  # an upload's camera height is a guess
    if new_sample and new_image:
        img = state.sample.image
        nodes.image.image = img if img is not None else canvas(cam.width, cam.height)
    corners = frustum_corners(state)
    segs = [np.stack([np.zeros(3), c]) for c in corners]
    segs += [np.stack([corners[i], corners[(i + 1) % 4]]) for i in range(4)]
    nodes.frustum.points = np.stack(segs).astype(np.float32)
    W, H = state.image_size
    f = state.focal
    nodes.image.position = tuple(image_plane(state, image_centre((W, H))) + np.array([0, 0, 0.002]))
    d = image_plane_depth(state)
    nodes.image.render_width = W / f[0] * d
    nodes.image.render_height = H / f[1] * d


def draw_2d(nodes: PoseNodes, state: SessionState, kp: np.ndarray, last: np.ndarray | None) -> np.ndarray:
    """The 2D joints and bones on the image plane, and the dragged joints' tethers to their own 2D; only spheres
    that moved are updated. Returns the plane points."""
    plane = image_plane(state, kp)
    nodes.bones2d.points = edges_points(plane)
    moved = sorted(j for j in state.dragged if 0 <= j < len(kp))
    if moved:
        own = image_plane(state, state.base_keypoints()[moved])
        nodes.drag_offsets.points = np.stack([own, plane[moved]], axis=1).astype(np.float32)
    nodes.drag_offsets.visible = bool(moved)
    for j, h in enumerate(nodes.joints2d):
        if last is None or not np.array_equal(last[j], plane[j]):
            h.position = tuple(plane[j])
    return plane


def draw_pose(nodes: PoseNodes, cam: CameraNodes, fr: Frame, *, show_gt: bool, name: str = "",
              labels: bool = True) -> None:
    """The lifted skeleton, its per-joint clouds (each joint's draws in its own colour), ground truth, analytic
    root (dashed, with its root marker) and the root ray. ``name``: the person's (:meth:`Sample.person_name`), put
    on the root's label when the image has others, whose labels carry theirs (a trial could not tell whose the bare
    "root Z" was). ``labels``: the other people's labels too (not in the head-on view, :func:`draw_others`)."""
    m = 1e-3
    nodes.lifted_bones.points = edges_points(fr.lifted * m)
    nodes.lifted_joints.points = (fr.lifted * m).astype(np.float32)
    if fr.gt_3d is not None:
        nodes.gt.points = edges_points(fr.gt_3d * m)
    nodes.gt.visible = show_gt and fr.gt_3d is not None
    if fr.analytic is not None:
        nodes.analytic.points = _dashed(fr.analytic * m)
        nodes.analytic_root.position = tuple(fr.analytic[0] * m)
    nodes.analytic.visible = nodes.analytic_root.visible = fr.analytic is not None
    if fr.cloud is not None and len(fr.cloud):
        n = fr.cloud.shape[0]
        nodes.cloud.points = (fr.cloud.reshape(-1, 3) * m).astype(np.float32)
        nodes.cloud.colors = np.tile(JOINT_RGB, (n, 1))
        nodes.cloud.visible = True
    else:
        nodes.cloud.visible = False
    draw_others(nodes, fr, labels=labels)
    root = fr.root * m
    cam.ray.points = np.stack([np.stack([np.zeros(3), root * 1.25])]).astype(np.float32)
    cam.root.position = tuple(root)
    who = f"{name} · " if name and fr.others else ""
    cam.root_label.text = f"{who}root Z {fr.root[2] / 1000:.2f} m"


def draw_others(nodes: PoseNodes, fr: Frame, *, labels: bool = True) -> None:
    """The other people of the image, lifted into the same camera space (teal), each labelled with its number
    and root depth unless ``labels`` is False (the head-on view: seen from beside the camera, a label at a farther
    person's head floated over the nearer one's image, as the root's label would; a browser trial)."""
    m = 1e-3
    if not fr.others:
        nodes.others_bones.visible = nodes.others_joints.visible = False
        for h in nodes.others_labels:
            h.visible = False
        return
    P = np.stack([o.lifted for o in fr.others]) * m
    nodes.others_bones.points = np.concatenate([edges_points(p) for p in P]).astype(np.float32)
    nodes.others_joints.points = P.reshape(-1, 3).astype(np.float32)
    nodes.others_bones.visible = nodes.others_joints.visible = True
    for k, h in enumerate(nodes.others_labels):
        if labels and k < len(fr.others):
            o = fr.others[k]
            h.position = tuple(o.lifted[10] * m + np.array([0.0, -0.12, 0.0]))
            h.text = f"{o.name} · Z {o.root[2] / 1000:.2f} m"
            h.visible = True
        else:
            h.visible = False


def draw_noisy_2d(nodes: PoseNodes, state: SessionState, noisy: np.ndarray | None) -> None:
    """The noisy draw ``(17, 2)`` px that is lifted at a noise level above 0, on the image plane (None: hidden)."""
    if noisy is None:
        nodes.noisy2d.visible = False
        return
    nodes.noisy2d.points = edges_points(image_plane(state, noisy))
    nodes.noisy2d.visible = True


def draw_others_2d(nodes: PoseNodes, state: SessionState, others: list[np.ndarray]) -> None:
    """The other people's current 2D on the image plane."""
    if not others:
        nodes.others_bones2d.visible = False
        return
    nodes.others_bones2d.points = np.concatenate([edges_points(image_plane(state, kp)) for kp in others]).astype(
        np.float32)
    nodes.others_bones2d.visible = True


def draw_trail(cam: CameraNodes, roots: dict[int, np.ndarray], *, visible: bool) -> None:
    """The lifted root's trajectory (camera frame): consecutive recorded frames joined (gaps over
    :data:`MAX_TRAIL_GAP` frames left open)."""
    draw_tracks(cam, [roots], visible=visible)


def draw_tracks(cam: CameraNodes, tracks: list[dict[int, np.ndarray]], *, visible: bool) -> None:
    """Root trajectories (camera frame, mm), one ``{frame index: root}`` per person or track, each drawn as
    :func:`draw_trail` draws one."""
    segs = []
    for roots in tracks:
        idx = sorted(roots)
        segs += [np.stack([roots[a], roots[b]]) * 1e-3 for a, b in zip(idx, idx[1:]) if b - a <= MAX_TRAIL_GAP]
    if not segs or not visible:
        cam.trail.visible = False
        return
    cam.trail.points = np.stack(segs).astype(np.float32)
    cam.trail.visible = True


def set_joint_radius(nodes: PoseNodes, radius: float) -> None:
    for h in nodes.joints2d:
        if abs(h.radius - radius) > 1e-9:
            h.radius = radius


def camera_world(state: SessionState) -> tuple[np.ndarray, np.ndarray]:
    """``(R, C)``: the sample camera's rotation (world -> camera) and centre (world, m)."""
    cam = state.sample.camera
    R = np.asarray(cam.R, np.float64)
    return R, cam.centre / 1000.0


def framing_points(state: SessionState, frame: Frame | None) -> np.ndarray:
    """World points (m) the overview keeps in view: the camera centre first, its frustum at the image plane, the
    lifted skeleton (everyone's) and the ground truth."""
    R, C = camera_world(state)
    pts = [np.zeros((1, 3)), frustum_corners(state)]
    if frame is not None:
        pts.append(frame.lifted / 1000.0)
        pts += [o.lifted / 1000.0 for o in frame.others]
        if frame.gt_3d is not None:
            pts.append(frame.gt_3d / 1000.0)
    return np.concatenate(pts) @ R + C  # R^T x + C, row-wise


def head_on_points(state: SessionState) -> np.ndarray:
    """World points (m) the head-on view keeps in view: the current 2D joints on the image plane."""
    R, C = camera_world(state)
    return image_plane(state, np.asarray(state.keypoints, np.float64)) @ R + C  # R^T x + C, row-wise


def overview(state: SessionState, frame: Frame | None, *, fov_y: float, aspect: float) -> framing.Viewpoint:
    """The default view: camera, frustum and person fitted into the view from behind, above and beside the camera."""
    R, C = camera_world(state)
    pts = framing_points(state, frame)
    person = pts[5:].mean(axis=0) if len(pts) > 5 else C + R.T @ np.array([0.0, 0.0, 4.0])
    return framing.fit(pts, direction=framing.overview_direction(C, person), up=np.array([0.0, 0.0, 1.0]),
                       fov_y=fov_y, aspect=aspect)


def head_on(state: SessionState, *, fov_y: float, aspect: float) -> tuple[framing.Viewpoint, float]:
    """The head-on image view of the current 2D joints and the joint-sphere radius for it (m)."""
    kp = np.asarray(state.keypoints, np.float64)
    lo, hi = kp.min(axis=0), kp.max(axis=0)
    centre = image_plane(state, (lo + hi) / 2.0)
    w, h = np.abs(image_plane(state, hi) - image_plane(state, lo))[:2]
    R, C = camera_world(state)
    half = max(h, w / aspect, 1e-3 * image_plane_depth(state)) / 2.0
    radius = float(np.clip(HEAD_ON_JOINT_RADIUS * max(w, h), 1e-3, JOINT_RADIUS_M))
    return framing.head_on(centre_cam=centre, half_extent=half, R=R, C=C, fov_y=fov_y), radius


class ViewerCamera:
    """A tab's 3D viewer camera, or, for the server target (headless views), the initial camera new tabs get."""

    def __init__(self, target: viser.ClientHandle | viser.ViserServer, server: viser.ViserServer) -> None:
        self.target, self.server = target, server

    def get(self) -> tuple[framing.Viewpoint, float, float]:
        """``(viewpoint, vertical fov rad, aspect)``; before a tab reported its camera (and for the server target)
        the initial camera, :data:`framing.DEFAULT_FOV_Y_RAD` and a square view."""
        fov, aspect = framing.DEFAULT_FOV_Y_RAD, 1.0
        if isinstance(self.target, viser.ClientHandle):
            try:
                c = self.target.camera
                if 0.05 < float(c.fov) < 3.0:
                    fov = float(c.fov)
                if c.image_width > 0 and c.image_height > 0:
                    aspect = c.image_width / c.image_height
                return framing.Viewpoint(np.asarray(c.position, np.float64), np.asarray(c.look_at, np.float64),
                                         np.asarray(c.up_direction, np.float64)), fov, aspect
            except (AssertionError, AttributeError, TypeError, ValueError):
                pass
        ic = self.server.initial_camera
        up_ = np.asarray(ic.up if ic.up is not None else (0.0, 0.0, 1.0), np.float64).reshape(-1)
        vp = framing.Viewpoint(np.asarray(ic.position, np.float64), np.asarray(ic.look_at, np.float64),
                               up_ if up_.shape == (3,) else np.array([0.0, 0.0, 1.0]))
        return vp, fov, aspect

    def set(self, vp: framing.Viewpoint) -> None:
        if isinstance(self.target, viser.ClientHandle):
            c = self.target.camera
            c.up_direction = tuple(vp.up)
            c.position = tuple(vp.eye)
            c.look_at = tuple(vp.look_at)
        else:
            ic = self.target.initial_camera
            ic.position = tuple(vp.eye)
            ic.look_at = tuple(vp.look_at)
            ic.up = tuple(vp.up)
