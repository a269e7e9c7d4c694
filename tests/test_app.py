"""In-process tests of the viser app: every control driven through GUI handles and drag callbacks,
on a server bound to 127.0.0.1 and a free port; no browser."""

from __future__ import annotations

import urllib.request
from pathlib import Path

import numpy as np
import pytest

from lifter import project

viser = pytest.importorskip("viser")

from conftest import require_shipped_models  # noqa: E402

from app.demo_assets import DEMO_DIR  # noqa: E402
from app.samples import DemoCatalog, default_h36m_root  # noqa: E402
from app.testing import FakeTab, local_server, wait_for  # noqa: E402
from app.viewer import IMAGE_PLANE_DEPTH_M, PoseLifterApp, SessionView  # noqa: E402




def _drag_event(view: SessionView, joint: int, uv: np.ndarray, *, client=None):
    """A SceneNodeDragEvent whose pointer lies on the image plane at pixel ``uv``."""
    cam = view.state.sample.camera
    R = np.asarray(cam.R)
    C = -R.T @ np.asarray(cam.t) / 1000.0
    p_cam = view._image_plane(np.asarray(uv, float))
    p_world = R.T @ p_cam + C
    return viser.SceneNodeDragEvent(client=client, client_id=0, target=view.joint_nodes[joint], phase="update",
                                    instance_index=None, start_position=tuple(p_world), start_screen_pos=(0.5, 0.5),
                                    end_position=tuple(p_world), end_screen_pos=(0.5, 0.5), button="left", modifier=None)


# ----------------------------------------------------------------------------------------------
# Demo assets
# ----------------------------------------------------------------------------------------------


def test_demo_assets_are_exact_and_look_rendered() -> None:
    cat = DemoCatalog()
    assert len(cat.names) >= 5
    for name in cat.names:
        s = cat.get(name)
        kp = project(s.pose_3d, focal=s.camera.focal, principal_point=s.camera.principal_point)
        np.testing.assert_allclose(kp, s.keypoints_2d, atol=1e-6)
        assert s.image is not None and s.image.shape == (s.camera.height, s.camera.width, 3)
        assert float(s.image.std()) > 20.0  # a render, not a blank canvas
        # the mannequin is in front of the joints: pixels at the joints are not the floor/wall grey
        u, v = np.round(s.keypoints_2d[8]).astype(int)
        assert np.ptp(s.image[v, u].astype(int)) > 20  # thorax pixel is coloured (shirt)
        R = s.camera.R
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-9) and np.all(s.pose_3d[:, 2] > 0)
    assert (DEMO_DIR / "samples.npz").is_file()


# ----------------------------------------------------------------------------------------------
# Server
# ----------------------------------------------------------------------------------------------


def test_server_binds_localhost_on_a_free_port(app: PoseLifterApp) -> None:
    port = app.server.get_port()
    assert port > 0 and app.server.get_host() == "127.0.0.1"
    with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=10) as r:
        assert r.status == 200


def test_main_parser_defaults() -> None:
    from app.main import build_parser

    a = build_parser().parse_args([])
    assert a.host == "127.0.0.1" and a.port == 8080 and a.h36m is None
    a = build_parser().parse_args(["--host", "0.0.0.0", "--port", "0", "--h36m", "/x"])
    assert a.host == "0.0.0.0" and a.port == 0 and a.h36m == Path("/x")


# ----------------------------------------------------------------------------------------------
# Controls
# ----------------------------------------------------------------------------------------------


def test_initial_view_shows_everything(view: SessionView) -> None:
    fr = view.frame
    assert fr.lifted.shape == (17, 3) and np.all(fr.lifted[:, 2] > 0)
    assert {"MPJPE", "PA-MPJPE", "root error"} <= set(fr.metrics)
    assert "Canonical depth" in view.readout_md.content and "MPJPE" in view.readout_md.content
    assert view.gt_lines.visible and not view.cloud_node.visible and not view.analytic_lines.visible
    assert view.image_gui.image.shape[2] == 3
    np.testing.assert_allclose(np.asarray(view.lifted_joints.points), fr.lifted / 1000, atol=2e-3)


def test_focal_slider_moves_root_along_its_ray(view: SessionView) -> None:
    f0 = view.state.sample.camera.alpha
    before = view.frame
    width_before = np.ptp(np.asarray(view.frustum.points)[:, :, 0])
    view.focal_slider.value = 2.0 * f0
    after = view.frame
    assert view.state.focal_px == pytest.approx(2 * f0)
    assert after.canonical_depth == pytest.approx(before.canonical_depth, rel=1e-6)
    assert after.root[2] == pytest.approx(2 * before.root[2], rel=1e-6)
    np.testing.assert_allclose(after.root[:2], before.root[:2], atol=1e-6)  # X = (u - c) Z / f: unchanged
    # the root stays on the viewing ray of its pixel (for the current focal length), drawn as /cam/ray
    uv, c, f = after.current_2d[0], np.asarray(after.principal_point), np.asarray(after.focal)
    np.testing.assert_allclose(after.root[:2] / after.root[2], (uv - c) / f, atol=1e-9)
    np.testing.assert_allclose(np.asarray(view.ray.points)[0, 1], 1.25 * after.root / 1000, rtol=1e-3)
    np.testing.assert_allclose(after.lifted - after.root, before.lifted - before.root, atol=1e-6)  # same shape
    assert np.ptp(np.asarray(view.frustum.points)[:, :, 0]) == pytest.approx(width_before / 2, rel=1e-6)  # FOV follows
    assert "Z/f" in view.readout_md.content
    view.focal_reset.value = True  # button click
    assert view.state.focal_px == pytest.approx(f0)


def test_noise_slider_cloud_seed_and_resample(view: SessionView) -> None:
    clean = view.frame.lifted.copy()
    view.noise_slider.value = 1.0
    fr = view.frame
    assert fr.cloud is not None and fr.cloud.shape == (64, 17, 3) and view.cloud_node.visible
    assert not np.allclose(fr.noisy_2d, fr.current_2d)
    assert not np.allclose(fr.lifted, clean)
    assert view.state.seed == 0
    view.set_noise(1.0 + 1e-9)
    np.testing.assert_allclose(view.frame.noisy_2d, fr.noisy_2d, rtol=0, atol=1e-6)  # fixed seed: reproducible
    view.resample_btn.value = True
    assert view.state.seed == 1 and not np.allclose(view.frame.noisy_2d, fr.noisy_2d)
    view.cloud_num.value = 8
    assert view.frame.cloud.shape == (8, 17, 3)
    view.seed_num.value = 5
    assert view.state.seed == 5
    view.noise_slider.value = 0.0
    assert view.frame.cloud is None and not view.cloud_node.visible
    np.testing.assert_allclose(view.frame.lifted, clean, atol=1e-9)


def test_joint_drag_callback_relifts(view: SessionView) -> None:
    j = 13  # l_wrist
    before = view.frame.lifted.copy()
    target = view.state.keypoints[j] + np.array([60.0, -80.0])
    cb = view.joint_nodes[j]._impl.drag_cb[0].callback
    cb(_drag_event(view, j, target))
    np.testing.assert_allclose(view.state.keypoints[j], target, atol=1e-6)
    assert j in view.state.dragged
    assert not np.allclose(view.frame.lifted, before)
    plane = np.asarray(view.joint_nodes[j].position)
    assert plane[2] == pytest.approx(IMAGE_PLANE_DEPTH_M)  # the sphere stays on the image plane

    class _Cam:  # a viewer looking along the camera's optical axis from behind it
        position = None

    class _Client:
        camera = _Cam()

    cam = view.state.sample.camera
    _Client.camera.position = tuple(-np.asarray(cam.R).T @ np.asarray(cam.t) / 1000.0)  # at the camera centre
    target2 = target + np.array([-30.0, 10.0])
    cb(_drag_event(view, j, target2, client=_Client()))
    np.testing.assert_allclose(view.state.keypoints[j], target2, atol=1e-6)

    view.reset_btn.value = True
    np.testing.assert_allclose(view.state.keypoints, view.state.sample.keypoints_2d)
    np.testing.assert_allclose(view.frame.lifted, before, atol=1e-9)


def test_joint_nudge_via_gui(view: SessionView) -> None:
    view.joint_dd.value = "r_wrist"
    uv = view.joint_uv.value
    view.joint_uv.value = (uv[0] + 25.0, uv[1])
    assert view.state.keypoints[16][0] == pytest.approx(uv[0] + 25.0)


def test_analytic_toggle_and_gt_checkbox(view: SessionView) -> None:
    view.analytic_cb.value = True
    assert view.frame.analytic is not None and view.analytic_lines.visible
    assert "analytic root error" in view.frame.metrics
    np.testing.assert_allclose(view.frame.analytic - view.frame.analytic[0], view.frame.lifted - view.frame.lifted[0],
                               atol=1e-6)
    view.analytic_cb.value = False
    assert not view.analytic_lines.visible
    view.gt_cb.value = False
    assert not view.gt_lines.visible
    view.gt_cb.value = True


def test_sample_and_model_dropdowns(view: SessionView, app: PoseLifterApp) -> None:
    names = app.demo.names
    view.demo_dd.value = names[2]
    assert view.state.sample.key == f"demo/{names[2]}"
    assert view.state.focal_px == pytest.approx(view.state.sample.camera.alpha)
    models = app.pool.names
    view.model_dd.value = models[-1]
    assert view.state.model == models[-1]
    view.input_dd.value = "detected"  # demo samples have no detection
    assert view.state.input_kind == "gt" and "no 2D detection" in view.messages[-1]


# ----------------------------------------------------------------------------------------------
# Bad input: a message, never a crash
# ----------------------------------------------------------------------------------------------


def test_bad_inputs_show_messages(view: SessionView, app: PoseLifterApp) -> None:
    good = view.frame
    assert view.select_demo("no-such-sample") is False and "unknown demo sample" in view.messages[-1]
    assert view.set_model("no-such-model") is False and "unknown model" in view.messages[-1]
    view.focal_slider.value = 1e9
    assert "clamped" in view.messages[-1] and view.state.focal_px == 6000.0 and np.isfinite(view.frame.root).all()
    view.focal_slider.value = float("nan")
    assert "not a finite" in view.messages[-1]
    view.focal_slider.value = -5.0
    assert view.state.focal_px == 100.0
    view.noise_slider.value = 99.0
    assert view.state.noise_level == 3.0 and "clamped" in view.messages[-1]
    view.noise_slider.value = 0.0
    cb = view.joint_nodes[3]._impl.drag_cb[0].callback
    cb(_drag_event(view, 3, np.array([1e7, -1e7])))
    assert "far outside" in view.messages[-1]
    assert np.all(np.abs(view.state.keypoints[3]) <= 2 * 800)
    # degenerate pose: all joints at one point -> message, previous pose kept
    prev = view.frame
    assert view.set_keypoints(np.full((17, 2), 400.0)) is False and "degenerate" in view.messages[-1]
    assert view.frame is prev
    # ... also when the user drags every joint onto the same pixel
    for j in range(17):
        view.move_joint(j, (300.0, 300.0))
    assert "degenerate" in view.messages[-1]
    assert view.move_joint(99, (1, 2)) is False
    assert view.set_seed("abc") is False and view.set_cloud_samples(10**6) is False
    assert view.select_h36m(subject=9, sequence="x", camera="y", frame=0) is False  # no H36M here
    # the server still serves and the view still works
    with urllib.request.urlopen(f"http://127.0.0.1:{app.server.get_port()}/", timeout=10) as r:
        assert r.status == 200
    assert view.reset_joints() is True and view.select_demo(app.demo.names[0]) is True
    assert view.status_md.content == "" and good is not None


# ----------------------------------------------------------------------------------------------
# Per-tab state
# ----------------------------------------------------------------------------------------------


def test_each_tab_has_its_own_state(app: PoseLifterApp) -> None:
    n0 = len(app.views)
    tabs = [FakeTab(app.server), FakeTab(app.server)]
    try:
        assert wait_for(lambda: len(app.views) == n0 + 2)
        new = [v for k, v in app.views.items()][-2:]
        a, b = new
        za = a.frame.root[2]
        a.focal_slider.value = 3.0 * a.state.sample.camera.alpha
        assert a.frame.root[2] == pytest.approx(3 * za, rel=1e-6)
        a.noise_slider.value = 1.0
        assert b.state.focal_px == pytest.approx(b.state.sample.camera.alpha) and b.state.noise_level == 0.0
        assert b.frame.root[2] == pytest.approx(za, rel=1e-6)
        cb = b.joint_nodes[5]._impl.drag_cb[0].callback
        cb(_drag_event(b, 5, b.state.keypoints[5] + 40))
        assert 5 in b.state.dragged and 5 not in a.state.dragged
        assert a.focal_slider is not b.focal_slider
    finally:
        for t in tabs:
            t.close()
    assert wait_for(lambda: len(app.views) == n0)


# ----------------------------------------------------------------------------------------------
# Human3.6M browsing (only where the data are present)
# ----------------------------------------------------------------------------------------------


@pytest.mark.skipif(default_h36m_root() is None, reason="Human3.6M not present at ../shared/data/h36m")
def test_h36m_browsing() -> None:
    require_shipped_models()
    server = local_server()
    try:
        app = PoseLifterApp(server, h36m_root=default_h36m_root())
        v = app.headless_view()
        v.source_dd.value = "h36m"
        photos = app.h36m.photo_frames()
        assert len(photos) == 84
        choice = next(p for p in photos if p[0] == 9)
        v.photo_dd.value = f"S{choice[0]} {choice[1]} {choice[2]} {choice[3]}"
        s = v.state.sample
        assert s.image is not None and s.image.shape[:2] == (s.camera.height, s.camera.width)
        assert s.detected_2d is not None
        v.input_dd.value = "detected"
        assert v.state.input_kind == "detected" and "MPJPE" in v.readout_md.content
        v.frame_slider.value = choice[3] + 1  # no photo: plain canvas of the camera's size
        assert v.state.sample.image is None and v.frame is not None
        v.camera_dd.value = app.h36m.camera_ids[2]
        assert v.state.sample.camera.name.endswith(app.h36m.camera_ids[2])
        v.subject_dd.value = "S11"
        assert v.state.sample.key.startswith("h36m/S11/")
        assert v.select_h36m(subject=9, sequence="Posing 1", camera="54138969", frame=10**7) is False
        assert "out of range" in v.messages[-1]
    finally:
        server.stop()
