"""The single-pose fast path: ``Lifter.lift`` runs one pose through numpy on the live weights.

``lifter.model.forward_flat_numpy`` must give the torch module's outputs, see every change to the
weights (no cache to go stale) and step aside for layers it cannot run (quantized, training mode).
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from lifter import Lifter, ModelConfig, PoseLifterError, PoseLifterNet
from lifter.camera import project
from lifter.model import forward_flat_numpy, split_output
from lifter.normalization import normalize_keypoints

from conftest import random_pose_cam

PP = (512.0, 515.0)


def _net(seed: int = 0, **config) -> PoseLifterNet:
    """A small net whose BatchNorm layers have non-trivial affine parameters and running statistics."""
    torch.manual_seed(seed)
    net = PoseLifterNet(ModelConfig(width=64, **config))
    with torch.no_grad():
        for m in net.modules():
            if isinstance(m, torch.nn.BatchNorm1d):
                m.weight.uniform_(0.5, 1.5)
                m.bias.normal_(0.0, 0.3)
                m.running_mean.normal_(0.0, 0.5)
                m.running_var.uniform_(0.3, 2.0)
        net.head.weight.normal_(0.0, 0.05)
    mean = torch.linspace(-300.0, 300.0, 49)
    mean[-1] = 4400.0
    net.set_target_statistics(mean, torch.linspace(50.0, 400.0, 49))
    return net.eval()


@pytest.fixture()
def kp() -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(1), 32), focal=1145.0, principal_point=PP)


def _module(net: PoseLifterNet, kp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The reference: the torch module's eval-mode forward."""
    kp = kp.reshape(-1, 17, 2)
    with torch.inference_mode():
        out = split_output(net.forward_flat(torch.from_numpy(kp.astype(np.float32)),
                                            torch.tensor([PP]).expand(len(kp), 2)))
    return out.relative.numpy(), out.depth.numpy()


def _assert_lift_matches_module(lifter: Lifter, kp: np.ndarray) -> None:
    rel, depth = _module(lifter.net, kp)
    res = lifter.lift(kp, focal=1145.0, principal_point=PP)
    np.testing.assert_allclose(res.relative.reshape(rel.shape), rel, rtol=1e-5, atol=2e-3)
    np.testing.assert_allclose(res.canonical_depth.reshape(depth.shape), depth, rtol=1e-5, atol=2e-2)


@pytest.mark.parametrize("mode", ["both", "baseline"])
def test_numpy_forward_matches_module(kp, mode):
    net = _net(mode=mode)
    k = torch.from_numpy(kp.astype(np.float32))
    pp = torch.tensor([PP]).expand(len(kp), 2)
    with torch.inference_mode():
        ref = net.forward_flat(k, pp).numpy()
        x = normalize_keypoints(k, pp, mode=mode).numpy()
    got = forward_flat_numpy(net, x)
    assert np.abs(ref).max() > 100.0  # the de-standardization is exercised (outputs in mm, not O(1))
    np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-3)


def test_single_pose_and_batch_agree_with_module(kp):
    lifter = Lifter(_net(), name="small")
    _assert_lift_matches_module(lifter, kp)  # batch: torch module
    for i in (0, 7):  # one pose: numpy
        _assert_lift_matches_module(lifter, kp[i])
    one = lifter.lift(kp[3], focal=1145.0, principal_point=PP, flip_test=True)
    batch = lifter.lift(kp[3:5], focal=1145.0, principal_point=PP, flip_test=True)
    np.testing.assert_allclose(one.absolute, batch.absolute[0], rtol=1e-5, atol=1e-2)


@pytest.mark.parametrize("change", ["in_place", "data", "data_assign", "vector_to_parameters", "state_dict",
                                    "state_dict_assign", "nested_module", "buffer", "eps"])
def test_single_pose_sees_every_weight_change(kp, change):
    lifter = Lifter(_net(seed=0), name="small")
    net = lifter.net
    before = lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative
    with torch.no_grad():
        if change == "in_place":
            net.head.bias.add_(0.5)
        elif change == "data":
            net.head.bias.data.add_(0.5)
        elif change == "data_assign":  # new storage behind the same Parameter object
            net.head.bias.data = net.head.bias.data + 0.5
        elif change == "vector_to_parameters":
            torch.nn.utils.vector_to_parameters(0.5 * torch.nn.utils.parameters_to_vector(net.parameters()),
                                                net.parameters())
        elif change == "state_dict":
            net.load_state_dict(_net(seed=3).state_dict())
        elif change == "state_dict_assign":
            net.load_state_dict(_net(seed=3).state_dict(), assign=True)
        elif change == "nested_module":
            net.blocks[0].body[4] = torch.nn.BatchNorm1d(64).eval()
        elif change == "buffer":
            net.target_mean.data.mul_(0.5)
        elif change == "eps":
            net.blocks[1].body[0].eps = 0.5
    after = lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative
    assert np.abs(after - before).max() > 1.0
    _assert_lift_matches_module(lifter, kp[0])


def test_net_built_under_inference_mode(kp):
    with torch.inference_mode():
        net = PoseLifterNet(ModelConfig(width=64))
        net.load_state_dict(_net().state_dict())
    lifter = Lifter(net, name="inference")
    _assert_lift_matches_module(lifter, kp[0])
    _assert_lift_matches_module(lifter, kp[:4])


def test_quantized_blocks_use_the_module(kp):
    lifter = Lifter(_net(), name="small")
    torch.ao.quantization.quantize_dynamic(lifter.net.blocks, {torch.nn.Linear}, dtype=torch.qint8, inplace=True)
    with torch.inference_mode():
        x = normalize_keypoints(torch.from_numpy(kp[:1].astype(np.float32)), torch.tensor([PP])).numpy()
    assert forward_flat_numpy(lifter.net, x) is None
    _assert_lift_matches_module(lifter, kp[0])
    _assert_lift_matches_module(lifter.quantized(), kp[0])


def test_replaced_activation_uses_the_module(kp):
    """A layer the numpy path does not model (here a GELU in place of a ReLU) sends the pose to the module."""
    lifter = Lifter(_net(), name="small")
    before = lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative
    lifter.net.blocks[0].body[2] = torch.nn.GELU()
    with torch.inference_mode():
        x = normalize_keypoints(torch.from_numpy(kp[:1].astype(np.float32)), torch.tensor([PP])).numpy()
    assert forward_flat_numpy(lifter.net, x) is None
    assert np.abs(lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative - before).max() > 1e-3
    _assert_lift_matches_module(lifter, kp[0])


def test_subclass_with_its_own_forward_uses_the_module(kp):
    class Clamped(PoseLifterNet):
        def forward_flat(self, keypoints, principal_point):
            return super().forward_flat(keypoints, principal_point).clamp(max=100.0)

    net = Clamped(ModelConfig(width=64))
    net.load_state_dict(_net().state_dict())
    lifter = Lifter(net.eval(), name="clamped")
    assert lifter.lift(kp[0], focal=1145.0, principal_point=PP).canonical_depth <= 100.0
    _assert_lift_matches_module(lifter, kp[0])


@pytest.mark.parametrize("part", ["net", "blocks"])
def test_training_mode_is_refused(kp, part):
    lifter = Lifter(_net(), name="small")
    (lifter.net if part == "net" else lifter.net.blocks).train()
    for k in (kp[0], kp[:4]):
        with pytest.raises(PoseLifterError, match="training mode"):
            lifter.lift(k, focal=1145.0, principal_point=PP)
    lifter.net.eval()
    _assert_lift_matches_module(lifter, kp[0])


def test_shipped_default_single_pose_matches_module(kp):
    lifter = Lifter.from_pretrained("default")
    _assert_lift_matches_module(lifter, kp[:16])
    _assert_lift_matches_module(lifter, kp[3])
