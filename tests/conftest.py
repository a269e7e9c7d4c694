from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
import torch

torch.set_num_threads(int(os.environ.get("POSELIFTER_TEST_THREADS", "2")))

H36M_DIR = Path(os.environ.get("POSELIFTER_H36M", Path(__file__).resolve().parents[2] / "shared" / "data" / "h36m"))
requires_h36m = pytest.mark.skipif(not (H36M_DIR / "poses3d_world_17j_mm.npz").is_file(),
                                   reason=f"Human3.6M data not found at {H36M_DIR}")


@pytest.fixture(scope="session")
def h36m():
    from lifter.data import H36M

    if not (H36M_DIR / "poses3d_world_17j_mm.npz").is_file():
        pytest.skip(f"Human3.6M data not found at {H36M_DIR}")
    return H36M(H36M_DIR)


@pytest.fixture()
def rng() -> np.random.Generator:
    return np.random.default_rng(0)


def random_pose_cam(rng: np.random.Generator, n: int = 1, *, upright: bool = True) -> np.ndarray:
    """Plausible-ish camera-frame poses (n, 17, 3) mm: a random body ~1 m tall in front of the camera. ``upright``
    False: bodies lying sideways in the image are left so (the tracking tests' people, whose 2D sizes they set)."""
    from lifter.skeleton import PARENTS

    bones = rng.normal(0, 1, (n, 17, 3))
    bones /= np.linalg.norm(bones, axis=-1, keepdims=True)
    bones *= rng.uniform(100, 450, (n, 17, 1))
    pose = np.zeros((n, 17, 3))
    for j, p in enumerate(PARENTS):
        if p >= 0:
            pose[:, j] = pose[:, p] + bones[:, j]
    root = np.stack([rng.uniform(-1000, 1000, n), rng.uniform(-600, 600, n), rng.uniform(3000, 7000, n)], -1)
    rel = pose - pose[:, :1]
    # head up (camera y down): a body lying sideways (head and ankles apart more along x than y, 11 % of them) is
    # turned a quarter about the optical axis, and one with its head below both ankles (4 %) upright, so that lift
    # does not warn of (y, x) or y-up keypoints (lifter._checks.sideways_notes, upside_down_notes) on a random pose
    axis = rel[:, 10, :2] - 0.5 * (rel[:, 3, :2] + rel[:, 6, :2])
    side = (np.abs(axis[:, 0]) > np.abs(axis[:, 1])) & upright
    rel[side] = np.stack([rel[side, :, 1], -rel[side, :, 0], rel[side, :, 2]], -1)
    down = rel[:, 10, 1] > np.maximum(rel[:, 3, 1], rel[:, 6, 1])
    rel[down, :, 1] *= -1.0
    # a body leaning as a rolled camera leans people (legs and torso the same way by more than 15 deg, within 45 of
    # each other, a margin on lifter._checks.leaning_people's 35 and 20: 14 %) is turned upright about the
    # optical axis by its lean, so that lift does not warn of a rolled camera on a random pose (lean_notes)
    legs = 0.5 * (rel[:, 3, :2] + rel[:, 6, :2]) - 0.5 * (rel[:, 1, :2] + rel[:, 4, :2])
    torso = rel[:, 0, :2] - rel[:, 8, :2]
    a, b = np.arctan2(legs[:, 0], legs[:, 1]), np.arctan2(torso[:, 0], torso[:, 1])
    lean = np.sign(a) * np.minimum(np.abs(a), np.abs(b))
    turn = (np.sign(a) == np.sign(b)) & (np.abs(lean) > np.radians(15)) & (np.abs(a - b) < np.radians(45)) & upright
    c, s = np.cos(lean[turn]), np.sin(lean[turn])
    x, y = rel[turn, :, 0].copy(), rel[turn, :, 1].copy()
    rel[turn, :, 0], rel[turn, :, 1] = c[:, None] * x - s[:, None] * y, s[:, None] * x + c[:, None] * y
    return rel + root[:, None]


def tiny_net(width: int, *, seed: int = 0, **config):
    """An untrained eval-mode ``PoseLifterNet`` of the given width (seeded, so reproducible)."""
    from lifter import ModelConfig, PoseLifterNet

    torch.manual_seed(seed)
    return PoseLifterNet(ModelConfig(width=width, **config)).eval()


def tiny_lifter(width: int = 64, *, seed: int = 0, name: str = "small", **config):
    """An untrained :class:`lifter.Lifter` whose outputs vary with the input around a plausible pose: target mean
    0 mm for the relative joints and a depth output of 4400 mm (400 mm for the ``"size"`` parametrization)."""
    from lifter import Lifter, PoseCodec

    net = tiny_net(width, seed=seed, **config)
    with torch.no_grad():  # a head that depends visibly on the input (the trained init is nearly constant)
        net.head.weight.normal_(0.0, 0.05, generator=torch.Generator().manual_seed(seed))
    mean = np.zeros(49)
    mean[-1] = 400.0 if net.config.depth_target == "size" else 4400.0
    std = np.full(49, 100.0)
    if net.config.depth_target == "size":
        std[-1] = 10.0
    return Lifter(net, PoseCodec(net.config, target_mean=mean, target_std=std), name=name)


class ScriptedEstimator:
    """A 2D estimator for video tests: for the n-th frame it sees it returns the n-th entry of ``script`` (a list of
    people, ``(17, 2)`` px each, H36M order). ``full_width``: the script is in px of a frame this wide, and is
    scaled to the (possibly downscaled) image the estimator is given; None: used as is."""

    name = "scripted"
    keypoint_format = "h36m17"

    def __init__(self, script: list[list[np.ndarray]], *, full_width: int | None = None) -> None:
        self.script, self.n, self.full_width = script, 0, full_width

    def detect(self, image: np.ndarray) -> list:
        from lifter.detect import Detection, bbox_of

        people = self.script[self.n] if self.n < len(self.script) else []
        self.n += 1
        s = 1.0 if self.full_width is None else image.shape[1] / self.full_width
        return [Detection(keypoints=k * s, scores=np.ones(17), bbox_xywh=bbox_of(k * s), keypoint_format="h36m17")
                for k in people]


def require_shipped_models() -> list[str]:
    """The shipped model names, or skip the test when assets/models.json is missing."""
    from lifter import PoseLifterError, available_models

    try:
        return available_models()
    except PoseLifterError as exc:
        pytest.skip(f"no shipped models: {exc}")


@pytest.fixture(scope="module")
def app():
    """A :class:`app.viewer.PoseLifterApp` on a viser server bound to 127.0.0.1, any free port (demo samples only)."""
    pytest.importorskip("viser")
    from poselifter_app.testing import local_server
    from poselifter_app.viewer import PoseLifterApp

    require_shipped_models()
    server = local_server()
    a = PoseLifterApp(server, h36m_root=None)
    yield a
    server.stop()


@pytest.fixture()
def server():
    """A viser server bound to 127.0.0.1, any free port, for a test's own :class:`app.viewer.PoseLifterApp`."""
    pytest.importorskip("viser")
    from poselifter_app.testing import local_server

    require_shipped_models()
    s = local_server()
    yield s
    s.stop()


@pytest.fixture()
def view(app):
    """A headless per-tab view of :func:`app` (no browser)."""
    v = app.headless_view()
    assert v.frame is not None
    return v


def hold(monkeypatch, module, name: str, *, when=lambda *args, **kwargs: True):
    """Patch ``module.name`` so that a call for which ``when(*args, **kwargs)`` holds waits until the test lets it go
    (a slow upload, deterministically): returns ``(started, go)``, two :class:`threading.Event` s."""
    import threading

    real, started, go = getattr(module, name), threading.Event(), threading.Event()

    def held(*args, **kwargs):
        if when(*args, **kwargs):
            started.set()
            assert go.wait(30)
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, held)
    return started, go


def fail_once(monkeypatch, module, name: str) -> list[int]:
    """Patch ``module.name`` to raise ``RuntimeError("drawing failed")`` on its first call and to work after; returns
    the one-element list counting the calls."""
    real, calls = getattr(module, name), [0]

    def failing(*args, **kwargs):
        calls[0] += 1
        if calls[0] == 1:
            raise RuntimeError("drawing failed")
        return real(*args, **kwargs)

    monkeypatch.setattr(module, name, failing)
    return calls
