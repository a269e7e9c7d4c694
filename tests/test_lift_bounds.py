"""Lifter.lift refuses out-of-range input and never returns non-finite output."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from conftest import random_pose_cam, tiny_lifter

from lifter import Lifter, PoseLifterError
from lifter.camera import project


@pytest.fixture()
def lifter() -> Lifter:
    return tiny_lifter(64)


@pytest.fixture()
def kp() -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(0), 4), focal=1145.0, principal_point=(512.0, 515.0))


@pytest.mark.parametrize("what", ["keypoints_huge", "keypoints_offset", "focal", "principal_point"])
def test_out_of_range_pixels_are_refused(lifter, kp, what):
    args = {"keypoints": kp, "focal": 1145.0, "principal_point": (512.0, 515.0)}
    if what == "keypoints_huge":
        args["keypoints"] = kp * 1e39  # overflows float32
    elif what == "keypoints_offset":
        args["keypoints"] = kp + 1e20  # float32 cannot resolve the pose: looked degenerate before
    elif what == "focal":
        args["focal"] = 1e300
    else:
        args["principal_point"] = (5e7, 515.0)
    name = what.split("_")[0] if what.startswith("keypoints") else what
    with pytest.raises(PoseLifterError, match=rf"{name}: values up to .* must be below"):
        lifter.lift(args.pop("keypoints"), **args)


def test_degenerate_pose_in_a_batch_is_located(lifter, kp):
    kp = kp.reshape(2, 2, 17, 2).copy()
    kp[1, 0] = 400.0
    with pytest.raises(PoseLifterError, match=r"degenerate pose \(pose at index \(1, 0\), 1 such pose"):
        lifter.lift(kp, focal=1145.0, principal_point=(512.0, 515.0))
    with pytest.raises(PoseLifterError, match=r"^degenerate pose: all 17 joints"):  # a single pose: no index
        lifter.lift(kp[1, 0], focal=1145.0, principal_point=(512.0, 515.0))


@pytest.mark.parametrize("n", [1, 4])
def test_non_finite_outputs_are_an_error(lifter, kp, n):
    with torch.no_grad():
        lifter.net.head.bias[5] = float("inf")
    with pytest.raises(PoseLifterError, match="non-finite outputs"):
        lifter.lift(kp[:n], focal=1145.0, principal_point=(512.0, 515.0))


def test_written_files_follow_the_umask(tmp_path):
    """Atomic writes go through a private temporary file but end with the usual permissions (0666 & ~umask)."""
    import os

    from lifter.io import write_atomic

    mask = os.umask(0o022)
    os.umask(mask)
    p = write_atomic(tmp_path / "x.json", "{}")
    assert (p.stat().st_mode & 0o777) == (0o666 & ~mask)
    # checkpoints too (user trial: a trained .pt was 0600 beside 0644 curve files, unreadable on shared storage)
    from lifter.checkpoint import save_checkpoint
    from lifter.codec import PoseCodec
    from lifter.model import ModelConfig, PoseLifterNet

    cfg = ModelConfig(width=16)
    ck = save_checkpoint(tmp_path / "sub" / "m.pt", PoseLifterNet(cfg), PoseCodec(cfg))
    assert (ck.stat().st_mode & 0o777) == (0o666 & ~mask)
    assert [f.name for f in ck.parent.iterdir()] == ["m.pt"]  # no temporary file left


def test_a_replaced_file_keeps_its_permissions(tmp_path):
    """A review: a 0600 file (a result kept private) came back 0644, readable by all, once written again."""
    from lifter.io import write_atomic

    p = write_atomic(tmp_path / "x.json", "{}")
    p.chmod(0o600)
    write_atomic(p, '{"a": 1}')
    assert (p.stat().st_mode & 0o777) == 0o600 and p.read_text() == '{"a": 1}'
    p.chmod(0o640)
    write_atomic(p, b"{}")
    assert (p.stat().st_mode & 0o777) == 0o640
    p.chmod(0o4755)  # (a review: setuid kept on the new file)
    write_atomic(p, b"{}")
    assert (p.stat().st_mode & 0o7777) == 0o755


def test_atomic_write_into_a_missing_folder_names_the_problem(tmp_path):
    from lifter.io import write_json_atomic

    with pytest.raises(PoseLifterError, match="folder does not exist"):
        write_json_atomic(tmp_path / "no_such_dir" / "x.json", {})
    assert not (tmp_path / "no_such_dir").exists()
