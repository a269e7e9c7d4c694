"""The Lifter API: shapes, conventions and bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import torch

from lifter import Lifter, LiftResult, ModelConfig, PoseLifterError, PoseLifterNet
from lifter.camera import project
from lifter.checkpoint import load_checkpoint, save_checkpoint
from lifter._checks import CheckpointError

from conftest import random_pose_cam, tiny_net


@pytest.fixture(scope="module")
def small_lifter() -> Lifter:
    return Lifter(tiny_net(64), name="small")


@pytest.fixture()
def keypoints() -> np.ndarray:
    pose = random_pose_cam(np.random.default_rng(0), 6)
    return project(pose, focal=1145.0, principal_point=(512.0, 515.0))


def test_shapes_batched(small_lifter, keypoints):
    kp = keypoints.reshape(2, 3, 17, 2)
    res = small_lifter.lift(kp, focal=(1145.0, 1144.0), principal_point=(512.0, 515.0))
    assert isinstance(res, LiftResult)
    assert res.canonical_depth.shape == (2, 3)
    assert res.root.shape == (2, 3, 3)
    assert res.relative.shape == res.absolute.shape == (2, 3, 17, 3)
    np.testing.assert_allclose(res.relative[..., 0, :], 0)
    np.testing.assert_allclose(res.absolute, res.root[..., None, :] + res.relative)
    assert res.metric_depth
    single = small_lifter.lift(kp[1, 2], focal=1145.0, principal_point=(512.0, 515.0))
    assert single.root.shape == (3,)


def test_root_lies_on_the_ray_of_the_2d_root(small_lifter, keypoints):
    res = small_lifter.lift(keypoints, focal=1145.0, principal_point=(512.0, 515.0))
    reproj = project(res.root[:, None, :], focal=1145.0, principal_point=(512.0, 515.0))[:, 0]
    np.testing.assert_allclose(reproj, keypoints[:, 0], atol=1e-6)


def test_focal_changes_only_depth_along_ray(small_lifter, keypoints):
    """The pose and canonical depth do not depend on the focal length; Z scales with it."""
    a = small_lifter.lift(keypoints, focal=1000.0, principal_point=(512.0, 515.0))
    b = small_lifter.lift(keypoints, focal=2000.0, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(a.relative, b.relative)
    np.testing.assert_allclose(a.canonical_depth, b.canonical_depth)
    np.testing.assert_allclose(b.root[:, 2], 2 * a.root[:, 2])
    np.testing.assert_allclose(b.root[:, :2], a.root[:, :2], rtol=1e-9)


def test_unknown_focal_is_flagged(small_lifter, keypoints):
    res = small_lifter.lift(keypoints, principal_point=(512.0, 515.0))
    assert not res.metric_depth and res.focal is None
    assert "up to" in res.note
    np.testing.assert_allclose(res.root[:, 2], res.canonical_depth)
    known = small_lifter.lift(keypoints, focal=1000.0, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(known.root, res.root)


def test_principal_point_from_image_size(small_lifter, keypoints):
    a = small_lifter.lift(keypoints, focal=1145.0, image_size=(1000, 1000))
    b = small_lifter.lift(keypoints, focal=1145.0, principal_point=(500.0, 500.0))
    np.testing.assert_allclose(a.absolute, b.absolute)


def test_flip_test_is_equivariant(small_lifter, keypoints):
    """With flip test, lifting the mirrored input gives the mirrored output."""
    from lifter.camera import flip_keypoints_2d

    c = np.array([512.0, 515.0])
    res = small_lifter.lift(keypoints, focal=1145.0, principal_point=c, flip_test=True)
    kp_f, c_f = flip_keypoints_2d(keypoints, image_width=1000, principal_point=c)
    res_f = small_lifter.lift(kp_f, focal=1145.0, principal_point=c_f, flip_test=True)
    from lifter.camera import flip_pose_3d

    np.testing.assert_allclose(flip_pose_3d(res_f.relative), res.relative, atol=1e-3)
    np.testing.assert_allclose(res_f.canonical_depth, res.canonical_depth, rtol=1e-5)


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.zeros((16, 2)), r"expected shape \(\.\.\., 17, 2\)"),
        (np.zeros((17, 3)), r"expected shape"),
        ("abc", "could not convert"),
    ],
)
def test_bad_keypoint_shapes(small_lifter, bad, match):
    with pytest.raises(PoseLifterError, match=match):
        small_lifter.lift(bad, focal=1000.0, principal_point=(0, 0))


@pytest.mark.parametrize("value", [np.nan, np.inf])
def test_non_finite_keypoints(small_lifter, keypoints, value):
    kp = keypoints.copy()
    kp[2, 5, 1] = value
    with pytest.raises(PoseLifterError, match="NaN/inf"):
        small_lifter.lift(kp, focal=1000.0, principal_point=(0, 0))


def test_degenerate_pose(small_lifter):
    with pytest.raises(PoseLifterError, match="degenerate pose"):
        small_lifter.lift(np.full((17, 2), 300.0), focal=1000.0, principal_point=(500, 500))


@pytest.mark.parametrize("focal", [0.0, -1000.0, (1000.0, 0.0), np.nan])
def test_bad_focal(small_lifter, keypoints, focal):
    with pytest.raises(PoseLifterError, match="focal"):
        small_lifter.lift(keypoints, focal=focal, principal_point=(500, 500))


def test_keypoints_not_in_pixels(small_lifter, keypoints):
    with pytest.raises(PoseLifterError, match="must be in image pixels"):
        small_lifter.lift(keypoints / 1000.0, focal=1.145, principal_point=(0.512, 0.515))


def test_batched_focal_and_broadcast_errors(small_lifter, keypoints):
    per_pose = np.stack([np.full(6, 1000.0), np.linspace(900, 1500, 6)], -1)  # (6, 2)
    res = small_lifter.lift(keypoints, focal=per_pose, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(res.focal, per_pose)
    one = small_lifter.lift(keypoints[3], focal=per_pose[3], principal_point=(512.0, 515.0))
    np.testing.assert_allclose(one.absolute, res.absolute[3], atol=1e-6)
    with pytest.raises(PoseLifterError, match="focal: shape"):
        small_lifter.lift(keypoints, focal=np.full((4, 2), 1000.0), principal_point=(512.0, 515.0))
    with pytest.raises(PoseLifterError, match="principal_point: shape"):
        small_lifter.lift(keypoints, focal=1000.0, principal_point=np.zeros((5, 2)))


def test_absolute_depth_model_path():
    """A direct-depth model (Table 6 "w/o canonical"): its root Z is the network's depth; it needs the focal."""
    torch.manual_seed(1)
    net = PoseLifterNet(ModelConfig(width=32, depth_target="absolute"))
    mean = torch.zeros(49)
    mean[-1] = 5000.0
    net.set_target_statistics(mean, torch.full((49,), 50.0))
    lifter = Lifter(net.eval(), name="abs")
    kp = project(random_pose_cam(np.random.default_rng(2), 3), focal=1100.0, principal_point=(500.0, 500.0))
    with pytest.raises(PoseLifterError, match="needs the focal length"):
        lifter.lift(kp, principal_point=(500.0, 500.0))
    res = lifter.lift(kp, focal=1100.0, principal_point=(500.0, 500.0))
    with torch.inference_mode():
        z = net(torch.tensor(kp, dtype=torch.float32), torch.tensor([[500.0, 500.0]] * 3)).depth.numpy()
    np.testing.assert_allclose(res.root[:, 2], z, rtol=1e-5)
    np.testing.assert_allclose(res.canonical_depth, z * 1000.0 / 1100.0, rtol=1e-5)
    # a different focal does not move the depth of a direct-depth model: that is its failure mode
    res2 = lifter.lift(kp, focal=2200.0, principal_point=(500.0, 500.0))
    np.testing.assert_allclose(res2.root[:, 2], res.root[:, 2], rtol=1e-6)


def test_missing_principal_point(small_lifter, keypoints):
    with pytest.raises(PoseLifterError, match="principal_point is required"):
        small_lifter.lift(keypoints, focal=1000.0)


def test_checkpoint_round_trip_and_errors(tmp_path, small_lifter, keypoints):
    path = save_checkpoint(tmp_path / "m.pt", small_lifter.net, meta={"note": "test"})
    loaded = Lifter.from_checkpoint(path)
    a = small_lifter.lift(keypoints, focal=1145.0, principal_point=(512.0, 515.0))
    b = loaded.lift(keypoints, focal=1145.0, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(a.absolute, b.absolute, atol=1e-3)
    assert loaded.meta["note"] == "test"
    half = save_checkpoint(tmp_path / "h.pt", small_lifter.net, half=True)
    assert half.stat().st_size < path.stat().st_size

    with pytest.raises(CheckpointError, match="not found"):
        Lifter.from_checkpoint(tmp_path / "missing.pt")
    corrupt = tmp_path / "corrupt.pt"
    corrupt.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(CheckpointError, match="corrupt"):
        Lifter.from_checkpoint(corrupt)
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"not a checkpoint at all")
    with pytest.raises(CheckpointError, match="corrupt"):
        load_checkpoint(garbage)
    foreign = tmp_path / "foreign.pt"
    torch.save({"weights": torch.zeros(3)}, foreign)
    with pytest.raises(CheckpointError, match="not a poselifter checkpoint"):
        load_checkpoint(foreign)


def test_checkpoint_refuses_pickled_code(tmp_path):
    """weights_only=True: a checkpoint carrying an arbitrary object is rejected, not executed."""

    class Evil:
        def __reduce__(self):
            return (print, ("executed!",))

    evil = tmp_path / "evil.pt"
    torch.save({"format": "poselifter-checkpoint", "version": 1, "payload": Evil()}, evil)
    with pytest.raises(CheckpointError, match="corrupt or not a torch checkpoint"):
        load_checkpoint(evil)


def test_unknown_pretrained_name():
    with pytest.raises(PoseLifterError, match="unknown model"):
        Lifter.from_pretrained("no-such-model")


def test_quantized_lifter_matches_float32(small_lifter, keypoints):
    q = small_lifter.quantized()
    a = small_lifter.lift(keypoints, focal=1145.0, principal_point=(512.0, 515.0))
    b = q.lift(keypoints, focal=1145.0, principal_point=(512.0, 515.0))
    assert "int8" in q.name
    # int8 weights: close to, but not bit-identical with, the float32 network
    assert np.abs(a.relative - b.relative).max() < 0.05 * np.abs(a.relative).max() + 1.0
    assert np.allclose(a.canonical_depth, b.canonical_depth, rtol=0.05)


def _edited_checkpoint(tmp_path, net, name: str, edit) -> Path:
    """A checkpoint of ``net`` whose payload dict was changed in place by ``edit``."""
    path = save_checkpoint(tmp_path / "base.pt", net)
    payload = torch.load(path, map_location="cpu", weights_only=True)
    edit(payload)
    torch.save(payload, tmp_path / name)
    return tmp_path / name


@pytest.mark.parametrize(
    "field, value, allowed",
    [
        ("depth_target", "bogus", "['canonical', 'absolute']"),
        ("scale_definition", "bogus", "['paper', 'repo']"),
        ("mode", "bogus", "['baseline', 'location', 'scale', 'both']"),
        ("depth_target", None, "['canonical', 'absolute']"),
    ],
)
def test_checkpoint_rejects_unknown_config_values(tmp_path, small_lifter, field, value, allowed):
    """These used to load (depth_target: silently treated as absolute; scale_definition: a raw ValueError on lift)."""
    path = _edited_checkpoint(tmp_path, small_lifter.net, "bad.pt", lambda p: p["model_config"].__setitem__(field, value))
    with pytest.raises(CheckpointError) as exc:
        Lifter.from_checkpoint(path)
    assert str(exc.value) == f"{path}: model_config.{field} is {value!r}; expected one of {allowed}"


@pytest.mark.parametrize(
    "edit, match",
    [
        (lambda p: p.__setitem__("meta", ["x"]), "meta must be a dict, got list"),
        (lambda p: p.__setitem__("model_config", ["x"]), "model_config must be a dict, got list"),
        (lambda p: p.pop("model_config"), "checkpoint has no model_config"),
        (lambda p: p["model_config"].__setitem__("width", 0), r"model_config.width must be an integer >= 1, got 0"),
        (lambda p: p["model_config"].__setitem__("dropout", 1.5), r"model_config.dropout must be a number in \[0, 1\)"),
    ],
)
def test_checkpoint_rejects_malformed_payload(tmp_path, small_lifter, edit, match):
    path = _edited_checkpoint(tmp_path, small_lifter.net, "bad.pt", edit)
    with pytest.raises(CheckpointError, match=match) as exc:
        load_checkpoint(path)
    assert str(exc.value).startswith(f"{path}: ")


def test_checkpoint_empty_meta_and_valid_configs_load(tmp_path, small_lifter, keypoints):
    path = _edited_checkpoint(tmp_path, small_lifter.net, "none_meta.pt", lambda p: p.__setitem__("meta", None))
    _, meta = load_checkpoint(path)
    assert meta == {}
    net2 = PoseLifterNet(ModelConfig(width=16, mode="scale", scale_definition="repo", depth_target="absolute"))
    loaded, _ = load_checkpoint(save_checkpoint(tmp_path / "ok.pt", net2))
    assert loaded.config == net2.config


def test_checkpoint_path_is_a_directory(tmp_path):
    d = tmp_path / "x.pt"
    d.mkdir()
    with pytest.raises(CheckpointError) as exc:
        load_checkpoint(d)
    assert str(exc.value) == f"weights file {d} is a directory, not a checkpoint file"
    with pytest.raises(CheckpointError, match="is a directory"):
        Lifter.load(str(d))


def test_lift_accepts_torch_tensors_that_require_grad(small_lifter, keypoints):
    ref = small_lifter.lift(keypoints, focal=1145.0, principal_point=(512.0, 515.0))
    kp = torch.tensor(keypoints, dtype=torch.float32, requires_grad=True)
    res = small_lifter.lift(kp, focal=torch.tensor(1145.0, requires_grad=True),
                            principal_point=torch.tensor([512.0, 515.0], requires_grad=True))
    np.testing.assert_allclose(res.absolute, ref.absolute, rtol=1e-4, atol=1e-2)
    half = small_lifter.lift(torch.tensor(keypoints, dtype=torch.bfloat16), focal=1145.0, principal_point=(512.0, 515.0))
    assert half.absolute.shape == ref.absolute.shape


def test_three_column_keypoints_get_a_confidence_hint(small_lifter, keypoints):
    with_conf = np.concatenate([keypoints, np.ones(keypoints.shape[:-1] + (1,))], axis=-1)
    with pytest.raises(PoseLifterError) as exc:
        small_lifter.lift(with_conf, focal=1000.0, principal_point=(0, 0))
    assert str(exc.value) == ("keypoints: expected shape (..., 17, 2), got (6, 17, 3); if the third column is a "
                              "detector confidence, pass keypoints[..., :2]")
    with pytest.raises(PoseLifterError) as exc:  # no hint where it does not apply
        small_lifter.lift(np.zeros((17, 4)), focal=1000.0, principal_point=(0, 0))
    assert "confidence" not in str(exc.value)
