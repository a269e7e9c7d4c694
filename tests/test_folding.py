"""The inference fast path: BatchNorm and output de-standardization folded into the Linear layers.

``Lifter.lift`` runs the folded weights (numpy for one pose, torch for batches); these tests pin that it
gives the plain ``nn.Module`` forward's outputs and follows in-place weight changes.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch

from lifter import Lifter, ModelConfig, PoseLifterNet
from lifter.camera import project
from lifter.model import fold_for_inference, folded_forward_flat, folded_mlp, folded_mlp_np, split_output
from lifter.normalization import normalize_keypoints

from conftest import random_pose_cam


def _net_with_statistics(seed: int = 0, **config) -> PoseLifterNet:
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
def inputs() -> tuple[torch.Tensor, torch.Tensor]:
    pose = random_pose_cam(np.random.default_rng(1), 32)
    kp = project(pose, focal=1145.0, principal_point=(512.0, 515.0))
    return torch.from_numpy(kp.astype(np.float32)), torch.tensor([[512.0, 515.0]]).expand(32, 2).contiguous()


@pytest.mark.parametrize("mode", ["both", "baseline"])
def test_folded_forward_matches_module(inputs, mode):
    net = _net_with_statistics(mode=mode)
    kp, pp = inputs
    with torch.inference_mode():
        ref = net.forward_flat(kp, pp)
        got = folded_forward_flat(fold_for_inference(net), kp, pp)
    assert ref.abs().max() > 100.0  # the de-standardization is exercised (outputs in mm, not O(1))
    torch.testing.assert_close(got, ref, rtol=1e-5, atol=1e-3)


def test_numpy_mlp_matches_torch(inputs):
    net = _net_with_statistics()
    kp, pp = inputs
    weights = fold_for_inference(net)
    with torch.inference_mode():
        x = normalize_keypoints(kp, pp)
        ref = folded_mlp(weights, x).numpy()
    got = folded_mlp_np(weights.numpy(), x.numpy())
    assert got.dtype == np.float32 and got.shape == (32, 49)
    np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-3)


def test_fold_refuses_quantized_blocks():
    lifter = Lifter(_net_with_statistics(), name="small").quantized()
    with pytest.raises(TypeError, match="fold_for_inference"):
        fold_for_inference(lifter.net)
    assert lifter._folded() is None  # lift falls back to the module forward


def _module_lift(lifter: Lifter, kp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    with torch.inference_mode():
        out = split_output(lifter.net.forward_flat(torch.from_numpy(kp.astype(np.float32)),
                                                   torch.tensor([[512.0, 515.0]]).expand(len(kp), 2)))
    return out.relative.numpy(), out.depth.numpy()


def test_lift_single_and_batched_agree_with_module(inputs):
    lifter = Lifter(_net_with_statistics(), name="small")
    kp = inputs[0].numpy().astype(np.float64)
    rel_ref, depth_ref = _module_lift(lifter, kp)
    batched = lifter.lift(kp, focal=1145.0, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(batched.relative, rel_ref, rtol=1e-5, atol=1e-3)
    np.testing.assert_allclose(batched.canonical_depth, depth_ref, rtol=1e-5, atol=1e-2)
    for i in (0, 7):  # one pose at a time: the numpy path
        one = lifter.lift(kp[i], focal=1145.0, principal_point=(512.0, 515.0))
        np.testing.assert_allclose(one.relative, rel_ref[i], rtol=1e-5, atol=1e-3)
        np.testing.assert_allclose(one.absolute, batched.absolute[i], rtol=1e-5, atol=1e-2)


def test_lift_follows_in_place_weight_changes(inputs):
    lifter = Lifter(_net_with_statistics(seed=0), name="small")
    kp = inputs[0].numpy().astype(np.float64)
    before = lifter.lift(kp[0], focal=1145.0, principal_point=(512.0, 515.0)).relative
    with torch.no_grad():
        lifter.net.head.bias.add_(0.5)  # an optimizer step or a manual edit: in place
    after = lifter.lift(kp[0], focal=1145.0, principal_point=(512.0, 515.0)).relative
    assert np.abs(after - before).max() > 10.0
    np.testing.assert_allclose(after, _module_lift(lifter, kp[:1])[0][0], rtol=1e-5, atol=1e-3)
    # load_state_dict copies into the existing tensors
    lifter.net.load_state_dict(_net_with_statistics(seed=3).state_dict())
    np.testing.assert_allclose(lifter.lift(kp[:4], focal=1145.0, principal_point=(512.0, 515.0)).relative,
                               _module_lift(lifter, kp[:4])[0], rtol=1e-5, atol=1e-3)
    # replacing a whole submodule
    lifter.net.head = torch.nn.Linear(64, 49)
    np.testing.assert_allclose(lifter.lift(kp[0], focal=1145.0, principal_point=(512.0, 515.0)).relative,
                               _module_lift(lifter, kp[:1])[0][0], rtol=1e-5, atol=1e-3)


def test_training_mode_uses_the_module():
    lifter = Lifter(_net_with_statistics(), name="small")
    lifter.net.train()
    try:
        assert lifter._folded() is None
    finally:
        lifter.net.eval()
    assert lifter._folded() is not None


def test_shipped_default_folds_exactly():
    lifter = Lifter.from_pretrained("default")
    pose = random_pose_cam(np.random.default_rng(2), 16)
    kp = project(pose, focal=1145.0, principal_point=(512.0, 515.0))
    rel_ref, depth_ref = _module_lift(lifter, kp)
    res = lifter.lift(kp, focal=1145.0, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(res.relative, rel_ref, atol=0.01)  # mm
    np.testing.assert_allclose(res.canonical_depth, depth_ref, atol=0.05)  # mm
    one = lifter.lift(kp[3], focal=1145.0, principal_point=(512.0, 515.0))
    np.testing.assert_allclose(one.relative, rel_ref[3], atol=0.01)
