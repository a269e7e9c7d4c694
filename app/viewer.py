"""The viser app: one :class:`SessionView` (GUI + 3D scene + state) per browser tab.

Scene layout (viser world: **metres**, z up; Human3.6M's world is z up with the floor at z = 0, and the
demo samples are authored the same way):

* ``/floor``: the floor grid (z = 0);
* ``/cam``: the sample's camera, posed by its extrinsics (``X_world = R^T (X_cam - t)``). Everything
  below it is in the **OpenCV camera frame** (+x right, +y down, +z forward), metres:
  the frustum and the image plane at depth :data:`IMAGE_PLANE_DEPTH_M` (its field of view follows the
  focal slider), the draggable 2D joints on that plane, the lifted skeleton at its absolute position,
  the ground truth, the analytic-root skeleton, the uncertainty cloud and the root's viewing ray.

The "Your photo" folder uploads a photo (2D joints by :mod:`lifter.detect`, largest person, EXIF or
default-FOV focal) or a keypoint JSON (:mod:`app.upload`) into the tab as a sample without 3D ground
truth, and downloads the current result as the JSON ``poselifter lift`` writes, or as a GLB.

Every callback goes through :meth:`SessionView._guard`: invalid input shows a message in the status
panel (and a notification in a real browser) and never propagates into viser's threads.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import threading
import time
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NoReturn

import numpy as np
import viser
import viser.transforms as vtf

from lifter import PoseLifterError
from lifter.skeleton import EDGES, JOINT_NAMES, NUM_JOINTS, edge_side, joint_side

from . import upload as up
from .core import (
    CLOUD_SAMPLES,
    DEFAULT_SEED,
    FOCAL_MAX_PX,
    FOCAL_MIN_PX,
    NOISE_MAX,
    Frame,
    LifterPool,
    SessionState,
    clamp_focal,
    clamp_joint,
    clamp_noise,
    compute_frame,
    focal_max,
    readout_markdown,
)
from .drawing import COLORS, overlay, scaled_base
from .noise import ErrorModelLike, default_error_model, model_name
from .samples import DemoCatalog, H36MCatalog, Sample, open_h36m

log = logging.getLogger("poselifter.app")

IMAGE_PLANE_DEPTH_M: float = 1.0
"""Depth (m, camera frame) at which the image plane and the draggable 2D joints are drawn."""
VIEW_ZOOM: float = 0.85
"""Initial viewpoint: how close to the person the viewer starts (1 = the frustum and the person small)."""
JOINT_RADIUS_M: float = 0.022
"""Radius (m) of the draggable 2D joint spheres on the image plane in the overview (easy to grab from afar)."""
ZOOM_JOINT_RADIUS: float = 0.02
""""zoom to 2D joints": sphere radius as a fraction of the 2D joints' extent on the image plane (small
enough not to hide neighbouring joints up close); the overview restores :data:`JOINT_RADIUS_M`."""
ZOOM_FILL: float = 0.8
""""zoom to 2D joints": the fraction of the view the 2D joints' bounding box fills."""
ZOOM_DEFAULT_FOV_DEG: float = 50.0
"""Vertical field of view assumed when the viewer's is unknown (the server target)."""
SIDE_RGB: dict[str, tuple[int, int, int]] = {"left": (40, 110, 255), "right": (255, 60, 60), "center": (70, 70, 70)}
"""Lifted skeleton: subject's left blue, right red, centre dark grey."""
GT_RGB = COLORS["gt"]
ANALYTIC_RGB = (255, 170, 0)
CLOUD_RGB = (170, 80, 230)
RAY_RGB = (250, 210, 0)
FRUSTUM_RGB = (30, 30, 30)
SOURCES = ("demo", "h36m", "upload")


def _edges_points(P: np.ndarray) -> np.ndarray:
    """``(16, 2, 3)`` bone segments of a ``(17, 3)`` pose."""
    return np.stack([np.stack([P[a], P[b]]) for a, b in EDGES])


def _side_colors() -> np.ndarray:
    c = np.array([SIDE_RGB[edge_side(e)] for e in EDGES], np.uint8)
    return np.repeat(c[:, None, :], 2, axis=1)


def _set_disabled(handle: Any, disabled: bool) -> None:
    if handle is not None and handle.disabled != disabled:
        handle.disabled = disabled


def control(func: Callable[..., Any]) -> Callable[..., bool]:
    """Decorator for :class:`SessionView` controls: returns True on success; on invalid input shows the
    message in the status panel and returns False (never raises into viser's threads). Calls made while
    the view sets a GUI value itself (:meth:`SessionView._set_gui`) are ignored."""

    @functools.wraps(func)
    def wrapper(self: SessionView, *args: Any, **kwargs: Any) -> bool:
        if self._suspend:  # a GUI echo of our own _set_gui, not a user action
            return True
        n = self._message_count
        try:
            func(self, *args, **kwargs)
        except PoseLifterError as exc:
            self.show_message(str(exc), error=True)
            return False
        except Exception as exc:  # noqa: BLE001 - never let a control kill the session
            log.error("control %s failed:\n%s", func.__name__, traceback.format_exc())
            self.show_message(f"internal error: {type(exc).__name__}: {exc}", error=True)
            return False
        if self._message_count == n and getattr(self, "status_md", None) is not None and self.status_md.content:
            self.status_md.content = ""
        return True

    return wrapper


@dataclass
class Timing:
    """Server-side timing of the last update (ms)."""

    compute_ms: float = 0.0
    scene_ms: float = 0.0
    total_ms: float = 0.0


class SessionView:
    """GUI, scene and state of one browser tab (or of the server itself, for headless tests).

    ``target`` is a :class:`viser.ClientHandle` (per-tab, the normal case) or a :class:`viser.ViserServer`
    (shared; used by tests and benchmarks that run without a browser). Public methods are the controls
    in code form; the GUI callbacks call them.
    """

    def __init__(self, app: PoseLifterApp, target: viser.ClientHandle | viser.ViserServer) -> None:
        self.app = app
        self.target = target
        self.gui = target.gui
        self.scene = target.scene
        self.lock = threading.RLock()
        self.messages: list[str] = []
        self._message_count = 0
        self.frame: Frame | None = None
        self.timing = Timing()
        self.update_count = 0
        self._pending: dict[int, np.ndarray] = {}
        self._pending_lock = threading.Lock()
        self._drag_lock = threading.Lock()
        self._tls = threading.local()
        self._base_key: str | None = None
        self._base: tuple[np.ndarray, float] | None = None
        self._last_upload: Sample | None = None
        self._sample_gen = 0
        self._drag_gen: int | None = None
        self._photo: up.Photo | None = None
        self._input_pref = "gt"
        """The 2D input the user chose (:meth:`set_input_kind`); the effective ``state.input_kind`` follows it
        whenever the sample has that 2D (uploads, without ground-truth 2D, always use their detection)."""
        self._view_key: tuple | None = None
        """Source and camera pose the 3D view was last framed for (:meth:`_sync_sample`)."""
        self.last_download: tuple[str, bytes] | None = None
        """``(file name, content)`` of the last download sent (or prepared, for a headless view)."""
        sample = app.demo.get(app.demo.names[0])
        self.state = SessionState(sample=sample, model=app.default_model)
        self._build_gui()
        self._build_scene()
        with self.lock:
            self._set_sample(sample)  # (frames the 3D view: a new camera)

    @property
    def _suspend(self) -> bool:
        """True while this thread sets GUI values programmatically (their callbacks are then ignored)."""
        return bool(getattr(self._tls, "suspend", False))

    @_suspend.setter
    def _suspend(self, value: bool) -> None:
        self._tls.suspend = value

    # ------------------------------------------------------------------------------------------
    # Error handling
    # ------------------------------------------------------------------------------------------
    def _guard(self, func: Callable[..., Any]) -> Callable[..., Any]:
        """Wrap a callback: errors become a status message; the server keeps running."""

        @functools.wraps(func)
        def wrapper(*args: Any, **kwargs: Any) -> Any:
            try:
                return func(*args, **kwargs)
            except PoseLifterError as exc:
                self.show_message(str(exc), error=True)
            except Exception as exc:  # noqa: BLE001 - never let a callback kill the session
                log.error("callback %s failed:\n%s", getattr(func, "__name__", func), traceback.format_exc())
                self.show_message(f"internal error: {type(exc).__name__}: {exc}", error=True)
            return None

        return wrapper

    def show_message(self, text: str, *, error: bool = False) -> None:
        """Show ``text`` in the status panel (and as a browser notification for a real tab)."""
        self.messages.append(text)
        self.messages = self.messages[-20:]
        self._message_count += 1
        try:
            self.status_md.content = ("⚠️ " if error else "ℹ️ ") + text
            if isinstance(self.target, viser.ClientHandle):
                self.target.add_notification(title="poselifter" if not error else "Input problem", body=text,
                                             auto_close_seconds=6.0, color="red" if error else "blue")
        except Exception:  # noqa: BLE001
            log.exception("could not show message %r", text)

    def clear_message(self) -> None:
        self.status_md.content = ""

    # ------------------------------------------------------------------------------------------
    # GUI
    # ------------------------------------------------------------------------------------------
    def _build_gui(self) -> None:
        gui = self.gui
        app = self.app
        self.image_gui = gui.add_image(np.zeros((60, 80, 3), np.uint8), label="input 2D", format="jpeg", jpeg_quality=85)
        self.legend_md = gui.add_markdown(
            "<small>2D: <b style='color:#28c83c'>ground truth</b> · <b style='color:#f09600'>detected / uploaded</b> · "
            "<b style='color:#a03cdc'>noisy (lifted)</b> · <b style='color:#e61e1e'>current / dragged</b>; "
            "rings <b style='color:#1e6eff'>left</b> / <b style='color:#ff3ca0'>right</b>. "
            "3D: lifted (left blue, right red), <b style='color:#28c83c'>ground truth</b>, "
            "<b style='color:#ffaa00'>analytic root</b>, <b style='color:#aa50e6'>noise cloud</b>, "
            "<b style='color:#c8a800'>root ray</b>.</small>")
        self.readout_md = gui.add_markdown("")
        self.status_md = gui.add_markdown("")

        with gui.add_folder("Sample"):
            sources = ["demo"] + (["h36m"] if app.h36m is not None else [])
            self.source_dd = gui.add_dropdown("source", sources, initial_value="demo",
                                              hint="embedded demo renders, or Human3.6M (--h36m)")
            self.demo_dd = gui.add_dropdown("demo sample", list(app.demo.names), initial_value=app.demo.names[0])
            self.input_dd = gui.add_dropdown("2D input", ["gt", "detected"], initial_value="gt",
                                             hint="ground-truth 2D, or the Stacked-Hourglass detection (H36M only)")
            if app.h36m is not None:
                h = app.h36m
                subj = [f"S{s}" for s in h.subjects]
                self.subject_dd = gui.add_dropdown("subject", subj, initial_value=subj[-2] if len(subj) > 1 else subj[0])
                seqs = h.sequences(int(self.subject_dd.value[1:]))
                self.sequence_dd = gui.add_dropdown("sequence", seqs, initial_value=seqs[0])
                self.camera_dd = gui.add_dropdown("camera", list(h.camera_ids), initial_value=h.camera_ids[0])
                n = h.num_frames(int(self.subject_dd.value[1:]), self.sequence_dd.value)
                self.frame_slider = gui.add_slider("frame", 0, max(n - 1, 1), 1, 0)
                photos = ["(none)"] + [f"S{s} {q} {c} {f}" for s, q, c, f in h.photo_frames()]
                self.photo_dd = gui.add_dropdown("frame with photo", photos, initial_value="(none)")
            else:
                self.subject_dd = self.sequence_dd = self.camera_dd = self.frame_slider = self.photo_dd = None  # type: ignore[assignment]

        with gui.add_folder("Your photo"):
            self.upload_btn = gui.add_upload_button(
                "upload photo or keypoint JSON", icon=viser.Icon.UPLOAD, mime_type="image/*,.json,application/json",
                hint=f"a photo (2D joints by MediaPipe BlazePose, draggable) or a 2D keypoint JSON as `poselifter lift` "
                     f"reads it; at most {up.MAX_UPLOAD_BYTES // 2**20} MiB")
            self.download_btn = gui.add_button("download result (JSON)", icon=viser.Icon.DOWNLOAD,
                                               hint="the current lift with the same fields as `poselifter lift` writes")
            self.download_glb_btn = gui.add_button("download skeleton (GLB)", icon=viser.Icon.DOWNLOAD,
                                                   hint="the lifted skeleton as a mesh (metres, y-up)")
        with gui.add_folder("Lifting"):
            models = app.pool.names or ["(none)"]
            self.model_dd = gui.add_dropdown("model", models, initial_value=app.default_model or models[0],
                                             hint="shipped weights (assets/models.json)")
            self.focal_slider = gui.add_slider("focal length (px)", FOCAL_MIN_PX, FOCAL_MAX_PX, 1.0, 1000.0,
                                               hint="alpha = sqrt(fx fy); the root slides along its ray, Z ∝ f")
            self.focal_reset = gui.add_button("reset focal to camera")
            self.analytic_cb = gui.add_checkbox("analytic root", False,
                                                hint="also show the weak-perspective analytic root (baseline)")
            self.gt_cb = gui.add_checkbox("show ground truth", True)
        with gui.add_folder("Noise"):
            self.noise_slider = gui.add_slider("mixture-noise level", 0.0, NOISE_MAX, 0.05, 0.0,
                                               hint="0 clean · 1 as fitted · 3 exaggerated")
            self.cloud_num = gui.add_slider("cloud samples", 0, 256, 1, CLOUD_SAMPLES)
            self.seed_num = gui.add_number("seed", DEFAULT_SEED, step=1)
            self.resample_btn = gui.add_button("resample noise")
            gui.add_markdown(f"<small>error model: {model_name(app.error_model)}</small>")
        with gui.add_folder("Joints"):
            self.joint_dd = gui.add_dropdown("joint", list(JOINT_NAMES), initial_value=JOINT_NAMES[0],
                                             hint="drag the red spheres on the image plane; or nudge here")
            self.joint_uv = gui.add_vector2("joint (u, v) px", (0.0, 0.0), step=1.0)
            self.reset_btn = gui.add_button("reset dragged joints")
            self.view_btn = gui.add_button("reset 3D view")
            self.zoom_btn = gui.add_button("zoom to 2D joints", icon=viser.Icon.ZOOM_IN,
                                           hint="look head-on at the 2D joints on the image plane, for precise dragging")

        g = self._guard
        self.source_dd.on_update(g(lambda _: self.set_source(self.source_dd.value)))
        self.demo_dd.on_update(g(lambda _: self.select_demo(self.demo_dd.value)))
        self.input_dd.on_update(g(lambda _: self.set_input_kind(self.input_dd.value)))
        if self.subject_dd is not None:
            self.subject_dd.on_update(g(lambda _: self._on_subject()))
            self.sequence_dd.on_update(g(lambda _: self._on_h36m_change(reset_frame=True)))
            self.camera_dd.on_update(g(lambda _: self._on_h36m_change()))
            self.frame_slider.on_update(g(lambda _: self._on_h36m_change()))
            self.photo_dd.on_update(g(lambda _: self._on_photo()))
        self.model_dd.on_update(g(lambda _: self.set_model(self.model_dd.value)))
        self.focal_slider.on_update(g(lambda _: self.set_focal(self.focal_slider.value)))
        self.focal_reset.on_click(g(lambda _: self.set_focal(self.state.sample.camera.alpha)))
        self.analytic_cb.on_update(g(lambda _: self.set_analytic(self.analytic_cb.value)))
        self.gt_cb.on_update(g(lambda _: self._redraw()))
        self.noise_slider.on_update(g(lambda _: self.set_noise(self.noise_slider.value)))
        self.cloud_num.on_update(g(lambda _: self.set_cloud_samples(self.cloud_num.value)))
        self.seed_num.on_update(g(lambda _: self.set_seed(self.seed_num.value)))
        self.resample_btn.on_click(g(lambda _: self.resample()))
        self.joint_dd.on_update(g(lambda _: self._on_joint_selected()))
        self.joint_uv.on_update(g(lambda _: self._on_joint_uv()))
        self.reset_btn.on_click(g(lambda _: self.reset_joints()))
        self.view_btn.on_click(g(lambda _: self.set_initial_view()))
        self.zoom_btn.on_click(g(lambda _: self.zoom_to_2d_joints()))
        self.upload_btn.on_upload(g(lambda _: self.load_upload(self.upload_btn.value.name, self.upload_btn.value.content)))
        self.download_btn.on_click(g(lambda _: self.download("json")))
        self.download_glb_btn.on_click(g(lambda _: self.download("glb")))
        self._install_upload_limit()

    def _commit(self, name: str, value: Any, handle: Any, *, message: str = "", camera: bool = False) -> None:
        """Set ``state.<name>``, mirror it in its GUI ``handle``, show ``message`` (clamping notes) and redraw
        (``camera``: the frustum too). The one path by which value controls change the session state."""
        with self.lock:
            setattr(self.state, name, value)
            self._set_gui(handle, value)
            if message:
                self.show_message(message, error=True)
            if camera:
                self._update_camera_geometry()
            self._redraw()

    def _reject(self, handle: Any, name: str, message: str) -> NoReturn:
        """Refuse a value control's input: its GUI ``handle`` shows ``state.<name>`` (the value in use) again,
        and :class:`PoseLifterError` ``message`` is raised."""
        with self.lock:
            self._set_gui(handle, getattr(self.state, name))
        raise PoseLifterError(message)

    def _set_gui(self, handle: Any, value: Any) -> None:
        """Set a GUI value without triggering our own callbacks."""
        if handle is None:
            return
        with self._quiet():
            handle.value = value

    @contextlib.contextmanager
    def _quiet(self) -> Iterator[None]:
        """Change GUI handles inside this block without triggering our own callbacks (nests)."""
        before = self._suspend
        self._suspend = True
        try:
            yield
        finally:
            self._suspend = before

    # ------------------------------------------------------------------------------------------
    # Scene
    # ------------------------------------------------------------------------------------------
    def _build_scene(self) -> None:
        sc = self.scene
        self.floor = sc.add_grid("/floor", width=12.0, height=12.0, plane="xy", cell_size=0.5, section_size=1.0)
        self.cam_frame = sc.add_frame("/cam", show_axes=True, axes_length=0.15, axes_radius=0.006)
        z = np.zeros((1, 2, 3))
        self.frustum = sc.add_line_segments("/cam/frustum", np.zeros((8, 2, 3)), FRUSTUM_RGB, thickness=0.006)
        self.image_node = sc.add_image("/cam/image", np.zeros((4, 4, 3), np.uint8), 1.0, 1.0, format="jpeg",
                                       cast_shadow=False, receive_shadow=False)
        self.bones2d = sc.add_line_segments("/cam/bones2d", np.zeros((16, 2, 3)), COLORS["current"], thickness=0.004)
        self.joint_nodes = []
        for j in range(NUM_JOINTS):
            h = sc.add_icosphere(f"/cam/joints2d/{JOINT_NAMES[j]}", radius=JOINT_RADIUS_M, subdivisions=2,
                                 color=SIDE_RGB[joint_side(j)] if joint_side(j) != "center" else COLORS["current"])
            h.on_drag(self._guard(functools.partial(self.on_joint_drag, j)))
            self.joint_nodes.append(h)
        self.lifted_lines = sc.add_line_segments("/cam/lifted/bones", np.zeros((16, 2, 3)), _side_colors(), thickness=0.035)
        self.lifted_joints = sc.add_point_cloud(
            "/cam/lifted/joints", np.zeros((NUM_JOINTS, 3)),
            np.array([SIDE_RGB[joint_side(j)] for j in range(NUM_JOINTS)], np.uint8), point_size=0.045, point_shape="circle")
        self.gt_lines = sc.add_line_segments("/cam/gt", np.zeros((16, 2, 3)), GT_RGB, thickness=0.012)
        self.analytic_lines = sc.add_line_segments("/cam/analytic", np.zeros((16, 2, 3)), ANALYTIC_RGB, thickness=0.015,
                                                   visible=False)
        self.cloud_node = sc.add_point_cloud("/cam/cloud", np.zeros((1, 3)), CLOUD_RGB, point_size=0.014,
                                             point_shape="circle", visible=False)
        self.ray = sc.add_line_segments("/cam/ray", np.concatenate([z, z]), RAY_RGB, thickness=0.01)
        self.root_marker = sc.add_icosphere("/cam/root", radius=0.05, color=RAY_RGB)
        self.root_label = sc.add_label("/cam/root/label", "root")

    def _image_plane(self, uv: np.ndarray) -> np.ndarray:
        """Pixels ``(..., 2)`` -> points on the image plane ``(..., 3)`` m, camera frame, current focal."""
        f = np.asarray(self.state.focal)
        c = np.asarray(self.state.sample.camera.principal_point)
        d = IMAGE_PLANE_DEPTH_M
        xy = (np.asarray(uv, np.float64) - c) / f * d
        return np.concatenate([xy, np.full(xy.shape[:-1] + (1,), d)], axis=-1)

    def _update_camera_geometry(self) -> None:
        """Frustum and image plane for the current focal length (the field of view follows the slider)."""
        W, H = self.state.image_size
        corners = self._image_plane(np.array([[0, 0], [W, 0], [W, H], [0, H]], np.float64))
        segs = [np.stack([np.zeros(3), c]) for c in corners]
        segs += [np.stack([corners[i], corners[(i + 1) % 4]]) for i in range(4)]
        self.frustum.points = np.stack(segs)
        center = self._image_plane(np.array([W / 2.0, H / 2.0]))
        f = self.state.focal
        self.image_node.position = tuple(center + np.array([0, 0, 0.002]))
        self.image_node.render_width = W / f[0] * IMAGE_PLANE_DEPTH_M
        self.image_node.render_height = H / f[1] * IMAGE_PLANE_DEPTH_M

    @control
    def set_initial_view(self) -> None:
        """A good initial viewpoint: behind, above and to the side of the camera, looking at the person."""
        self._frame_view()

    def _frame_view(self) -> None:
        """:meth:`set_initial_view` (for use inside other controls)."""
        cam = self.state.sample.camera
        R, t = np.asarray(cam.R), np.asarray(cam.t)
        C = -R.T @ t / 1000.0
        if self.state.sample.pose_3d is not None:
            target_cam = self.state.sample.pose_3d[0] / 1000.0
        elif self.frame is not None and np.all(np.isfinite(self.frame.root)) and self.frame.root[2] > 0:
            target_cam = np.asarray(self.frame.root) / 1000.0
        else:
            target_cam = np.array([0, 0, 4.0])
        target = R.T @ target_cam + C
        fwd = target - C
        side = np.cross(fwd, [0, 0, 1.0])
        side /= max(np.linalg.norm(side), 1e-9)
        d = float(np.linalg.norm(fwd))
        mid = 0.3 * C + 0.7 * target
        eye = C - 0.1 * fwd + 0.6 * d * side + np.array([0, 0, 1.5])
        right = np.cross(mid - eye, [0, 0, 1.0])
        mid = mid + 0.35 * right / max(np.linalg.norm(right), 1e-9)  # the GUI panel covers the right of the canvas
        eye = mid + VIEW_ZOOM * (eye - mid)
        self._set_close_up(None)
        self._set_viewpoint(eye, mid, np.array([0.0, 0.0, 1.0]))

    def _set_close_up(self, radius: float | None) -> None:
        """Close-up look of the 2D joints (``radius`` m) or, with None, the overview's: the joint spheres'
        radius, and the root ray, which passes next to a close-up eye and would cover the joints."""
        r = JOINT_RADIUS_M if radius is None else radius
        for h in getattr(self, "joint_nodes", []):
            if abs(h.radius - r) > 1e-9:
                h.radius = r
        if hasattr(self, "ray"):
            self.ray.visible = radius is None

    def _reframe(self) -> None:
        """:meth:`_frame_view` after a sample change: a failure is logged, never fails the change itself."""
        try:
            self._frame_view()
        except Exception:  # noqa: BLE001 - a viewpoint is cosmetic
            log.exception("could not frame the 3D view")

    def _set_viewpoint(self, eye: np.ndarray, look_at: np.ndarray, up: np.ndarray) -> None:
        """Move this tab's viewer camera (world, m); for the server target, its initial camera (new tabs and
        the viewer's "reset view")."""
        if isinstance(self.target, viser.ClientHandle):
            cam_h = self.target.camera
            cam_h.up_direction = tuple(up)
            cam_h.position = tuple(eye)
            cam_h.look_at = tuple(look_at)
        else:
            ic = self.target.initial_camera
            ic.position = tuple(eye)
            ic.look_at = tuple(look_at)
            ic.up = tuple(up)

    def _viewer_fov(self) -> tuple[float, float]:
        """``(vertical field of view (rad), aspect width / height)`` of this tab's viewer; without a browser
        (or before it reported its camera) :data:`ZOOM_DEFAULT_FOV_DEG` and a square view."""
        fov, aspect = np.radians(ZOOM_DEFAULT_FOV_DEG), 1.0
        if isinstance(self.target, viser.ClientHandle):
            try:
                cam_h = self.target.camera
                if 0.05 < float(cam_h.fov) < 3.0:
                    fov = float(cam_h.fov)
                if cam_h.image_width > 0 and cam_h.image_height > 0:
                    aspect = cam_h.image_width / cam_h.image_height
            except (AssertionError, AttributeError, TypeError, ValueError):  # no camera message yet
                pass
        return fov, aspect

    @control
    def zoom_to_2d_joints(self) -> None:
        """Look head-on at the image plane from the camera's side, centred on the bounding box of the current
        2D joints, close enough that the box fills most of the view (:data:`ZOOM_FILL`), with the image's up
        (the camera's -y axis) up: the 2D joints can then be dragged precisely."""
        with self.lock:
            kp = np.asarray(self.state.keypoints, np.float64)
            cam = self.state.sample.camera
            lo, hi = kp.min(axis=0), kp.max(axis=0)
            centre = self._image_plane((lo + hi) / 2.0)  # camera frame, on the plane (z = IMAGE_PLANE_DEPTH_M)
            w, h = np.abs(self._image_plane(hi) - self._image_plane(lo))[:2]  # box size on the plane (m)
            R = np.asarray(cam.R)
            C = -R.T @ np.asarray(cam.t) / 1000.0
        fov, aspect = self._viewer_fov()
        half = max(h, w / aspect, 1e-3 * IMAGE_PLANE_DEPTH_M) / 2.0
        dist = half / (ZOOM_FILL * np.tan(fov / 2.0))
        eye = centre - np.array([0.0, 0.0, dist])  # in front of the plane, on the camera's side
        self._set_close_up(float(np.clip(ZOOM_JOINT_RADIUS * max(w, h), 1e-3, JOINT_RADIUS_M)))
        self._set_viewpoint(R.T @ eye + C, R.T @ centre + C, R.T @ np.array([0.0, -1.0, 0.0]))

    # ------------------------------------------------------------------------------------------
    # Controls (public: tests drive these, the GUI callbacks call them)
    # ------------------------------------------------------------------------------------------
    @control
    def set_source(self, source: str) -> None:
        """``"demo"`` or ``"h36m"``."""
        if source not in SOURCES or (source == "h36m" and self.app.h36m is None):
            raise PoseLifterError(f"unknown sample source {source!r}" + ("" if self.app.h36m else " (no Human3.6M folder)"))
        if source == "demo":
            self.select_demo(self.demo_dd.value)
        elif source == "upload":
            if self._last_upload is None:
                self._set_gui(self.source_dd, self.state.sample.key.split("/")[0])
                raise PoseLifterError("nothing uploaded yet: use the 'upload photo or keypoint JSON' button")
            with self.lock:
                self._set_sample(self._last_upload)
        else:
            self._on_h36m_change()

    @control
    def select_demo(self, name: str) -> None:
        """Show the embedded demo sample ``name``."""
        sample = self.app.demo.get(name)
        with self.lock:
            self._set_sample(sample)  # (the source and demo pickers follow: _sync_sample)

    @control
    def select_h36m(self, *, subject: int, sequence: str, camera: str, frame: int) -> None:
        """Show a Human3.6M view (``camera`` is the camera id, ``frame`` the 0-based 50-fps row)."""
        if self.app.h36m is None:
            raise PoseLifterError("no Human3.6M folder was given (--h36m)")
        sample = self.app.h36m.get(subject, sequence, camera, frame)
        with self.lock:
            self._set_sample(sample)  # (the pickers follow the shown sample: _sync_sample)

    def _on_subject(self) -> None:
        if self._suspend:
            return
        subject = int(self.subject_dd.value[1:])
        seqs = self.app.h36m.sequences(subject)
        with self._quiet():
            self.sequence_dd.options = seqs
            self.sequence_dd.value = seqs[0]
        self._on_h36m_change(reset_frame=True)

    def _on_h36m_change(self, *, reset_frame: bool = False) -> None:
        if self._suspend:
            return
        frame = 0 if reset_frame else int(self.frame_slider.value)
        self.select_h36m(subject=int(self.subject_dd.value[1:]), sequence=self.sequence_dd.value,
                         camera=self.camera_dd.value, frame=frame)

    def _on_photo(self) -> None:
        if self._suspend:
            return
        if self.photo_dd.value == "(none)":  # nothing to show: the dropdown keeps saying what is shown
            with self.lock:
                self._sync_pickers(self.state.sample)
            return
        s, rest = self.photo_dd.value.split(" ", 1)
        seq, cam, fr = rest.rsplit(" ", 2)
        self.select_h36m(subject=int(s[1:]), sequence=seq, camera=cam, frame=int(fr))

    def _set_sample(self, sample: Sample, *, model: str | None = None) -> None:
        """Show ``sample`` (drags reset; focal to its camera's; noise, seed, toggles and, unless ``model`` is
        given, the model kept). If it cannot be lifted the previous state is restored and the error raised.

        2D input: the user's choice (:attr:`_input_pref`) when the sample has it, else ground truth (with a
        message when the detection is lost); an upload (no ground-truth 2D) always uses its own 2D. The lifter
        is told whether that 2D is exact or detected (:func:`poselifter_app.core.lift_source`)."""
        st = self.state
        if not sample.has_gt_2d:
            kind = "detected"
        elif self._input_pref == "detected" and sample.detected_2d is None:
            kind = "gt"
            if st.input_kind == "detected" and st.sample.has_gt_2d:  # (leaving an upload: silently)
                self.show_message(f"no 2D detection for {sample.label}; using ground-truth 2D "
                                  "(the detection is used again where there is one)")
        else:
            kind = self._input_pref
        self._apply_state(SessionState(sample=sample, model=model or st.model, input_kind=kind, noise_level=st.noise_level,
                                       seed=st.seed, cloud_samples=st.cloud_samples, analytic=st.analytic))

    def _apply_state(self, state: SessionState) -> None:
        """Make ``state`` the tab's state and redraw everything; on :class:`PoseLifterError` (e.g. a
        degenerate uploaded pose) put the previous state back and re-raise."""
        old = self.state
        self.state = state
        try:
            self._sync_sample()
        except PoseLifterError:
            self.state = old
            self._sync_sample()
            raise

    def _sync_sample(self) -> None:
        """Push the sample-dependent GUI values, camera pose, image and frustum of :attr:`state`, and redraw."""
        st = self.state
        sample = st.sample
        self._sample_gen += 1
        src = sample.key.split("/")[0]
        if src in SOURCES and src in self.source_dd.options:
            self._set_gui(self.source_dd, src)
        self._sync_pickers(sample)
        self._set_gui(self.input_dd, st.input_kind)
        self._set_gui(self.model_dd, st.model)
        hi = focal_max(sample)
        if self.focal_slider.max != hi:
            self.focal_slider.max = hi
        self._set_gui(self.focal_slider, float(np.clip(round(st.focal_px), FOCAL_MIN_PX, hi)))
        R = np.asarray(sample.camera.R)
        self.cam_frame.wxyz = vtf.SO3.from_matrix(R.T).wxyz
        self.cam_frame.position = tuple(-R.T @ np.asarray(sample.camera.t) / 1000.0)
        img = sample.image
        from .drawing import canvas

        self.image_node.image = img if img is not None else canvas(sample.camera.width, sample.camera.height)
        self._update_camera_geometry()
        self._redraw()
        view_key = (src, R.tobytes(), np.asarray(sample.camera.t, np.float64).tobytes())
        if view_key != self._view_key:  # a new camera (not a new frame of the same one): frame the view
            self._view_key = view_key
            self._reframe()

    def _sync_pickers(self, sample: Sample) -> None:
        """The Sample panel's pickers for ``sample``: those of the other sources disabled; for a Human3.6M
        sample, subject / sequence / camera / frame and the "frame with photo" entry (or "(none)")."""
        src = sample.key.split("/")[0]
        _set_disabled(self.demo_dd, src != "demo")
        h36m = [self.subject_dd, self.sequence_dd, self.camera_dd, self.frame_slider, self.photo_dd]
        for h in h36m:
            _set_disabled(h, src != "h36m")
        if src == "demo":
            self._set_gui(self.demo_dd, sample.key.split("/", 1)[1])
        if src != "h36m" or self.app.h36m is None:
            return
        _, subj, sequence, camera, frame = sample.key.split("/")
        subject, frame_i = int(subj[1:]), int(frame)
        seqs = self.app.h36m.sequences(subject)
        self._set_gui(self.subject_dd, subj)
        if list(self.sequence_dd.options) != seqs:
            with self._quiet():
                self.sequence_dd.options = seqs
        self._set_gui(self.sequence_dd, sequence)
        self._set_gui(self.camera_dd, camera)
        hi = max(self.app.h36m.num_frames(subject, sequence) - 1, 1)
        if self.frame_slider.max != hi:
            with self._quiet():
                self.frame_slider.max = hi
        self._set_gui(self.frame_slider, frame_i)
        entry = f"{subj} {sequence} {camera} {frame_i}"
        self._set_gui(self.photo_dd, entry if entry in self.photo_dd.options else "(none)")

    @control
    def set_input_kind(self, kind: str) -> None:
        """2D input: ``"gt"`` (ground truth; not for uploads) or ``"detected"`` (Stacked-Hourglass, H36M only;
        an upload's own 2D). Resets drags. The choice is kept for the next samples (:meth:`_set_sample`)."""
        if kind not in ("gt", "detected"):
            self._reject(self.input_dd, "input_kind", f"unknown 2D input {kind!r}")
        with self.lock:
            old = self.state.input_kind
            self.state.input_kind = kind
            try:
                self.state.keypoints = self.state.base_keypoints().copy()
            except PoseLifterError:
                self.state.input_kind = old
                self._set_gui(self.input_dd, old)
                raise
            if self.state.sample.has_gt_2d:  # (an upload has no choice: that is no preference)
                self._input_pref = kind
            self._set_gui(self.input_dd, kind)
            self.state.dragged.clear()
            self._redraw()

    @control
    def set_model(self, name: str) -> None:
        """Switch the lifting model (a name from ``assets/models.json``)."""
        try:
            self.app.pool.get(name)  # raises for unknown names, before touching the state
        except PoseLifterError as exc:
            self._reject(self.model_dd, "model", str(exc))
        self._commit("model", name, self.model_dd)

    @control
    def set_focal(self, value: float) -> None:
        """Focal length ``alpha`` (px) used to lift: the pose keeps its shape and the root moves along its
        viewing ray with ``Z ∝ f`` (canonical depth fixed); the frustum's field of view follows."""
        v, msg = clamp_focal(value, hi=focal_max(self.state.sample))
        self._commit("focal_px", v, self.focal_slider, message=msg, camera=True)

    @control
    def set_noise(self, level: float) -> None:
        """Mixture-noise level (0 clean … 1 as fitted … 3): the lifted pose is that of a noisy draw and the
        cloud shows :attr:`SessionState.cloud_samples` more lifted draws."""
        v, msg = clamp_noise(level)
        self._commit("noise_level", v, self.noise_slider, message=msg)

    @control
    def set_cloud_samples(self, n: int) -> None:
        try:
            n_ = int(n)
        except (TypeError, ValueError, OverflowError):
            self._reject(self.cloud_num, "cloud_samples", f"cloud samples must be an integer, got {n!r}")
        if not 0 <= n_ <= 1024:
            self._reject(self.cloud_num, "cloud_samples", f"cloud samples must be in [0, 1024], got {n}")
        self._commit("cloud_samples", n_, self.cloud_num)

    @control
    def set_seed(self, seed: float) -> None:
        try:
            s = int(seed)
        except (TypeError, ValueError, OverflowError):
            self._reject(self.seed_num, "seed", f"seed must be an integer, got {seed!r}")
        if s < 0:
            self._reject(self.seed_num, "seed", f"seed must be >= 0, got {s}")
        self._commit("seed", s, self.seed_num)

    @control
    def resample(self) -> None:
        """New noise draws (seed + 1)."""
        with self.lock:  # read-increment-write as one step
            self._commit("seed", self.state.seed + 1, self.seed_num)

    @control
    def set_analytic(self, on: bool) -> None:
        """Toggle the analytic weak-perspective root skeleton (orange)."""
        self._commit("analytic", bool(on), self.analytic_cb)

    @control
    def reset_joints(self) -> None:
        """Undo all joint drags."""
        with self.lock:
            self.state.keypoints = self.state.base_keypoints().copy()
            self.state.dragged.clear()
            self._redraw()

    @control
    def move_joint(self, joint: int, uv: Any) -> None:
        """Put 2D joint ``joint`` at pixel ``uv`` (clamped near the image) and re-lift. The joint becomes the
        selected one (highlighted; its position in the "joint (u, v) px" box)."""
        if not 0 <= int(joint) < NUM_JOINTS:
            raise PoseLifterError(f"joint index {joint} out of range [0, {NUM_JOINTS})")
        try:
            p = np.asarray(uv, np.float64).reshape(2)
        except (TypeError, ValueError):
            raise PoseLifterError(f"joint position must be (u, v) px, got {uv!r}") from None
        p, msg = clamp_joint(p, size=self.state.image_size)
        with self.lock:
            self._set_gui(self.joint_dd, JOINT_NAMES[int(joint)])
            old = self.state.keypoints.copy()
            self.state.keypoints = old.copy()
            self.state.keypoints[int(joint)] = p
            self.state.dragged.add(int(joint))
            try:
                self._redraw()
            except PoseLifterError:
                self.state.keypoints = old
                self._redraw_2d_only()
                raise
            if msg:
                self.show_message(msg, error=True)

    @control
    def set_keypoints(self, keypoints: Any) -> None:
        """Replace the whole current 2D pose ``(17, 2)`` px (e.g. a pasted pose). Invalid poses raise
        :class:`PoseLifterError` and leave the previous pose in place."""
        kp = np.asarray(keypoints, np.float64)
        if kp.shape != (NUM_JOINTS, 2) or not np.all(np.isfinite(kp)):
            raise PoseLifterError(f"keypoints must be finite with shape (17, 2) px, got {kp.shape}")
        with self.lock:
            old = self.state.keypoints
            self.state.keypoints = kp.copy()
            try:
                self._redraw()
            except PoseLifterError:
                self.state.keypoints = old
                self._redraw_2d_only()
                raise

    def _on_joint_selected(self) -> None:
        if self._suspend:
            return
        self._redraw_2d_only()  # the highlight and the (u, v) box follow the selection

    def _on_joint_uv(self) -> None:
        if self._suspend:
            return
        self.move_joint(JOINT_NAMES.index(self.joint_dd.value), self.joint_uv.value)

    # -- upload / download -----------------------------------------------------------------------
    @control
    def load_upload(self, name: str, content: bytes) -> None:
        """An uploaded file: a photo (2D joints by the app's detector, the largest person) or a keypoint
        JSON (:mod:`app.upload`). On any problem a message is shown and the tab's state is left as it was."""
        name = up.safe_name(name)
        content = bytes(content or b"")
        up.check_upload(name, content, max_bytes=self.app.max_upload_bytes)
        key = f"upload/{self.app.next_upload_id()}/{name}"
        if up.is_json_upload(name, content):
            sample = up.keypoint_sample(name, content, key=key, photo=self._photo)
        else:
            photo, img = up.decode_photo(name, content)  # not-an-image / truncated / too many pixels raise here
            self._photo = photo  # kept for a keypoint JSON uploaded next, even if detection fails below
            try:
                estimator = self.app.estimator()
            except up.MissingDependencyError as exc:
                raise PoseLifterError(up.missing_detector_message(name, exc)) from None
            with self.app.detect_lock:
                sample = up.photo_sample(photo, img, key=key, lifter=self.app.pool.get(self.state.model),
                                         estimator=estimator)
        with self.lock:
            try:  # restores the previous state if the pose cannot be lifted
                self._set_sample(sample)
            except PoseLifterError as exc:
                raise PoseLifterError(f"{name}: {exc}") from None
            self._last_upload = sample
            if "upload" not in self.source_dd.options:
                with self._quiet():
                    self.source_dd.options = list(self.source_dd.options) + ["upload"]
            self._set_gui(self.source_dd, "upload")
            self._reframe()  # (a new photo: a new person to look at, whatever the camera)
        info = sample.upload
        what = (f"{info.name}: {info.detector} found {info.num_people} {'person' if info.num_people == 1 else 'people'}"
                if info.kind == "image" else f"{info.name}: {info.source_format} keypoints")
        notes = [n for n in info.warnings if n != info.focal_detail]
        self.show_message(f"{what}; drag the 2D joints on the image plane to correct them. Focal: {info.focal_detail}."
                          + ("".join(f" Note: {n}." for n in notes)))

    def download_payload(self, fmt: str = "json") -> tuple[str, bytes]:
        """``(file name, bytes)`` of the current result: ``"json"`` (the fields of ``poselifter lift``: the
        current clean 2D, dragged joints included, lifted at the current focal length) or ``"glb"``."""
        if fmt not in ("json", "glb"):
            raise PoseLifterError(f"unknown download format {fmt!r}; expected 'json' or 'glb'")
        with self.lock:
            st = self.state
            rec = up.result_record(st.sample, st.keypoints, lifter=self.app.pool.get(st.model), focal=st.focal,
                                   dragged=set(st.dragged), focal_changed=abs(st.focal_px - st.sample.camera.alpha) > 0.5)
            stem = up.download_stem(st.sample)
        if fmt == "json":
            return f"{stem}.json", up.json_bytes(rec)
        return f"{stem}.glb", up.glb_bytes(rec)

    @control
    def download(self, fmt: str = "json") -> None:
        """Send the current result to this tab as a file download (:meth:`download_payload`)."""
        name, data = self.download_payload(fmt)
        self.last_download = (name, data)
        if isinstance(self.target, viser.ClientHandle):
            self.target.send_file_download(name, data, save_immediately=True)

    def _install_upload_limit(self) -> None:
        """Stop an upload larger than the app's limit as soon as the browser announces its size, so viser
        does not buffer it (viser 1.1.1 has no limit of its own). Best effort: uses viser internals and
        silently does nothing if they change; :meth:`load_upload` checks the size again in any case."""
        gui = self.gui
        iface = getattr(gui, "_websock_interface", None)
        states = getattr(gui, "_current_file_upload_states", None)
        uuid = getattr(getattr(self.upload_btn, "_impl", None), "uuid", None)
        if iface is None or not isinstance(states, dict) or uuid is None:
            return
        from viser import _messages

        def on_start(client_id: int, msg: Any) -> None:
            try:
                if msg.source_component_uuid != uuid or msg.size_bytes <= self.app.max_upload_bytes:
                    return
                if isinstance(self.target, viser.ClientHandle) and client_id != self.target.client_id:
                    return
                states.pop(msg.transfer_uuid, None)  # later parts are ignored by viser
                iface.queue_message(_messages.FileTransferPartAck(  # ends the browser's progress bar
                    source_component_uuid=uuid, transfer_uuid=msg.transfer_uuid, transferred_bytes=msg.size_bytes,
                    total_bytes=msg.size_bytes))
                self.show_message(up.oversize_message(msg.filename, msg.size_bytes, max_bytes=self.app.max_upload_bytes),
                                  error=True)
            except Exception:  # noqa: BLE001 - never break viser's message loop
                log.exception("upload size check failed")

        iface.register_handler(_messages.FileTransferStartUpload, on_start)

    # -- dragging -------------------------------------------------------------------------------
    def drag_to_pixel(self, event: Any) -> np.ndarray:
        """Pixel under the pointer of a drag event: the viewer's ray through ``event.end_position`` (world, m)
        intersected with the image plane; without the viewer's camera, the central projection of
        ``end_position`` through the sample camera."""
        cam = self.state.sample.camera
        R = np.asarray(cam.R)
        C = -R.T @ np.asarray(cam.t) / 1000.0
        end_c = R @ (np.asarray(event.end_position, np.float64) - C)
        d = IMAGE_PLANE_DEPTH_M
        p = None
        client = getattr(event, "client", None)
        if client is not None:
            o_c = R @ (np.asarray(client.camera.position, np.float64) - C)
            ray = end_c - o_c
            if abs(ray[2]) > 1e-9:
                s = (d - o_c[2]) / ray[2]
                if s > 0:
                    p = o_c + s * ray
        if p is None:
            if end_c[2] <= 1e-6:
                raise PoseLifterError("joint dragged behind the camera; ignored")
            p = end_c * (d / end_c[2])
        f = np.asarray(self.state.focal)
        return p[:2] / d * f + np.asarray(cam.principal_point)

    @control
    def on_joint_drag(self, joint: int, event: Any) -> None:
        """Drag callback of 2D joint ``joint`` (a :class:`viser.SceneNodeDragEvent`). Latest position wins:
        events arriving while a lift is running are merged into the next one. Events of a drag that began
        on another sample (late events after the sample changed mid-drag) are ignored."""
        phase = getattr(event, "phase", "update")
        if phase == "start":
            self._drag_gen = self._sample_gen
        elif self._drag_gen is not None and self._drag_gen != self._sample_gen:
            return
        uv = self.drag_to_pixel(event)
        with self._pending_lock:
            self._pending[joint] = uv
        while True:
            if not self._drag_lock.acquire(blocking=False):
                return  # the running worker picks the pending position up
            try:
                while True:
                    with self._pending_lock:
                        todo, self._pending = self._pending, {}
                    if not todo:
                        break
                    for j, p in todo.items():
                        if j == max(todo):
                            self.move_joint(j, p)
                        else:
                            with self.lock:
                                self.state.keypoints[j] = clamp_joint(p, size=self.state.image_size)[0]
                                self.state.dragged.add(j)
            finally:
                self._drag_lock.release()
            with self._pending_lock:
                if not self._pending:
                    return

    # ------------------------------------------------------------------------------------------
    # Redraw
    # ------------------------------------------------------------------------------------------
    def _redraw(self) -> None:
        """Recompute the lift and push the scene + GUI (under :attr:`lock`)."""
        with self.lock:
            t0 = time.perf_counter()
            lifter = self.app.pool.get(self.state.model)
            frame = compute_frame(self.state, lifter, self.app.error_model)
            t1 = time.perf_counter()
            self.frame = frame
            self._push(frame)
            t2 = time.perf_counter()
            self.timing = Timing(compute_ms=1e3 * (t1 - t0), scene_ms=1e3 * (t2 - t1), total_ms=1e3 * (t2 - t0))
            self.update_count += 1

    def _redraw_2d_only(self) -> None:
        with self.lock:
            self._push_2d(self.state.keypoints, None)

    def _push_2d(self, kp: np.ndarray, noisy: np.ndarray | None) -> None:
        """The 2D view (GUI image, joints and bones on the image plane) and the "joint (u, v) px" box of
        the current 2D ``kp`` (so the box always shows the selected joint where it is)."""
        st = self.state
        s = st.sample
        sel = JOINT_NAMES.index(self.joint_dd.value)
        uv = tuple(float(v) for v in np.round(kp[sel], 1))
        if tuple(float(v) for v in self.joint_uv.value) != uv:
            self._set_gui(self.joint_uv, uv)
        poses = {"gt": s.keypoints_2d if (self.gt_cb.value and s.has_gt_2d) else None, "detected": s.detected_2d,
                 "noisy": noisy if st.noise_level > 0 else None, "current": kp}
        if self._base_key != s.key:
            self._base = scaled_base(s.image, size=st.image_size)
            self._base_key = s.key
        self.image_gui.image = overlay(s.image, size=st.image_size, poses=poses, selected=sel, prescaled=self._base)
        plane = self._image_plane(kp)
        self.bones2d.points = _edges_points(plane)
        last = getattr(self, "_last_plane", None)
        for j, h in enumerate(self.joint_nodes):  # only the joints that moved (a drag moves one)
            if last is None or not np.array_equal(last[j], plane[j]):
                h.position = tuple(plane[j])
        self._last_plane = plane

    def _push(self, fr: Frame) -> None:
        st = self.state
        with self.target.atomic():
            self._push_2d(fr.current_2d, fr.noisy_2d)
            m = 1e-3
            self.lifted_lines.points = _edges_points(fr.lifted * m)
            self.lifted_joints.points = (fr.lifted * m).astype(np.float32)
            show_gt = fr.gt_3d is not None and bool(self.gt_cb.value)
            if fr.gt_3d is not None:
                self.gt_lines.points = _edges_points(fr.gt_3d * m)
            self.gt_lines.visible = show_gt
            if fr.analytic is not None:
                self.analytic_lines.points = _edges_points(fr.analytic * m)
            self.analytic_lines.visible = fr.analytic is not None
            if fr.cloud is not None and len(fr.cloud):
                self.cloud_node.points = (fr.cloud.reshape(-1, 3) * m).astype(np.float32)
                self.cloud_node.visible = True
            else:
                self.cloud_node.visible = False
            root = fr.root * m
            self.ray.points = np.stack([np.stack([np.zeros(3), root * 1.25])])
            self.root_marker.position = tuple(root)
            self.root_label.text = f"root Z {fr.root[2] / 1000:.2f} m"
        self.readout_md.content = readout_markdown(fr, st)


def _default_estimator() -> Any:
    from lifter.detect import get_estimator

    return get_estimator(up.DEFAULT_DETECTOR)


class PoseLifterApp:
    """The exploration app on a viser server: one :class:`SessionView` per connected browser tab.

    Build it on any :class:`viser.ViserServer` (tests: ``ViserServer(host="127.0.0.1", port=0)``);
    :meth:`headless_view` builds a view on the server itself for in-process tests without a browser.
    """

    def __init__(self, server: viser.ViserServer, *, h36m_root: Path | None = None, models: list[str] | None = None,
                 default_model: str | None = None, error_model: ErrorModelLike | None = None,
                 demo_dir: Path | None = None, estimator_factory: Callable[[], Any] | None = None,
                 max_upload_bytes: int = up.MAX_UPLOAD_BYTES) -> None:
        self.server = server
        self.max_upload_bytes = int(max_upload_bytes)
        self._estimator_factory = estimator_factory or _default_estimator
        self._estimator: Any = None
        self._estimator_error: Exception | None = None
        self.detect_lock = threading.Lock()
        """Serialises 2D detection (one shared MediaPipe graph)."""
        self._upload_ids = 0
        self.demo = DemoCatalog(demo_dir) if demo_dir is not None else DemoCatalog()
        self.h36m: H36MCatalog | None = open_h36m(str(h36m_root)) if h36m_root is not None else None
        self.pool = LifterPool(models)
        if self.pool.error:
            log.error("no models: %s", self.pool.error)
        if default_model is None:
            from lifter.resources import default_model_name

            try:
                default_model = default_model_name()
            except PoseLifterError:
                default_model = self.pool.names[0] if self.pool.names else ""
        self.default_model = default_model
        self.error_model = error_model if error_model is not None else default_error_model()
        self.views: dict[int, SessionView] = {}
        self._lock = threading.Lock()
        server.gui.configure_theme(control_width="large", dark_mode=False)
        server.on_client_connect(self._on_connect)
        server.on_client_disconnect(self._on_disconnect)

    def _on_connect(self, client: viser.ClientHandle) -> None:
        try:
            view = SessionView(self, client)
        except Exception:  # noqa: BLE001
            log.error("could not build a session for client %s:\n%s", client.client_id, traceback.format_exc())
            return
        with self._lock:
            self.views[client.client_id] = view

    def _on_disconnect(self, client: viser.ClientHandle) -> None:
        with self._lock:
            self.views.pop(client.client_id, None)

    def estimator(self) -> Any:
        """The shared 2D estimator for photo uploads (built on first use); raises
        :class:`lifter.detect.MissingDependencyError` when its extra is not installed."""
        with self.detect_lock:
            if self._estimator is None and self._estimator_error is None:
                try:
                    self._estimator = self._estimator_factory()
                except PoseLifterError as exc:
                    self._estimator_error = exc
            if self._estimator_error is not None:
                if isinstance(self._estimator_error, up.MissingDependencyError):
                    raise self._estimator_error
                raise PoseLifterError(f"the 2D detector could not be started: {self._estimator_error}")
            return self._estimator

    def next_upload_id(self) -> int:
        with self._lock:
            self._upload_ids += 1
            return self._upload_ids

    def headless_view(self) -> SessionView:
        """A view on the server's shared GUI/scene (no browser needed): for tests and benchmarks."""
        return SessionView(self, self.server)

    @property
    def url(self) -> str:
        return f"http://{self.server.get_host()}:{self.server.get_port()}"
