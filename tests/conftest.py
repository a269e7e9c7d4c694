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


def random_pose_cam(rng: np.random.Generator, n: int = 1) -> np.ndarray:
    """Plausible-ish camera-frame poses (n, 17, 3) mm: a random body ~1 m tall in front of the camera."""
    from lifter.skeleton import PARENTS

    bones = rng.normal(0, 1, (n, 17, 3))
    bones /= np.linalg.norm(bones, axis=-1, keepdims=True)
    bones *= rng.uniform(100, 450, (n, 17, 1))
    pose = np.zeros((n, 17, 3))
    for j, p in enumerate(PARENTS):
        if p >= 0:
            pose[:, j] = pose[:, p] + bones[:, j]
    root = np.stack([rng.uniform(-1000, 1000, n), rng.uniform(-600, 600, n), rng.uniform(3000, 7000, n)], -1)
    return pose - pose[:, :1] + root[:, None]


def tiny_net(width: int, *, seed: int = 0):
    """An untrained eval-mode ``PoseLifterNet`` of the given width whose outputs sit near a plausible pose:
    target mean 0 mm for the relative joints and 4400 mm root depth, std 100 (seeded, so reproducible)."""
    from lifter import ModelConfig, PoseLifterNet

    torch.manual_seed(seed)
    net = PoseLifterNet(ModelConfig(width=width))
    mean = torch.zeros(49)
    mean[-1] = 4400.0
    net.set_target_statistics(mean, torch.full((49,), 100.0))
    return net.eval()


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
    from app.testing import local_server
    from app.viewer import PoseLifterApp

    require_shipped_models()
    server = local_server()
    a = PoseLifterApp(server, h36m_root=None)
    yield a
    server.stop()


@pytest.fixture()
def view(app):
    """A headless per-tab view of :func:`app` (no browser)."""
    v = app.headless_view()
    assert v.frame is not None
    return v
