"""The mirror-equivariant network (``ModelConfig(symmetry="mirror")``).

Pinned here: the feature and output mirror maps agree with the codec's one mirror convention; the network is
exactly mirror-equivariant in eval mode for any weights (one pass, no flip-test); with its cross-stream
coupling switched off it *is* the flip-test average of a plain network; the numpy single-pose path and the
half-precision checkpoint give the module's outputs; the coupled layer's gradients are right.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from conftest import random_pose_cam
from hypothesis import given, settings
from hypothesis import strategies as st

from lifter import Lifter, ModelConfig, PoseCodec, PoseLifterNet
from lifter.api import NUMPY_MAX_BATCH
from lifter.camera import project
from lifter.checkpoint import CheckpointError, load_checkpoint, save_checkpoint, tensor_checksum
from lifter.model import MirrorCoupledLinear, forward_numpy, output_mirror
from lifter.normalization import feature_mirror, pose_features
from lifter.skeleton import mirror

PP = (500.0, 490.0)
F = 1100.0


def _randomize(net: PoseLifterNet, seed: int = 0) -> PoseLifterNet:
    """Non-trivial BatchNorm statistics and a head that is not near zero, so every part of the net matters."""
    g = torch.Generator().manual_seed(seed)
    with torch.no_grad():
        for m in net.modules():
            if isinstance(m, torch.nn.BatchNorm1d):
                m.weight.uniform_(0.5, 1.5, generator=g)
                m.bias.normal_(0.0, 0.3, generator=g)
                m.running_mean.normal_(0.0, 0.5, generator=g)
                m.running_var.uniform_(0.3, 2.0, generator=g)
        net.head.weight.normal_(0.0, 0.05, generator=g)
        net.head.bias.normal_(0.0, 0.05, generator=g)
    return net.eval()


def _codec(config: ModelConfig) -> PoseCodec:
    """Target statistics that are *not* mirror-symmetric: the output mirror must still be exact."""
    rng = np.random.default_rng(3)
    mean = rng.normal(0.0, 200.0, 49)
    mean[-1] = 400.0
    return PoseCodec(config, target_mean=mean, target_std=rng.uniform(30.0, 300.0, 49))


def _mirror_lifter(seed: int = 0, **config) -> Lifter:
    torch.manual_seed(seed)
    cfg = ModelConfig(width=48, symmetry="mirror", **config)
    return Lifter(_randomize(PoseLifterNet(cfg), seed), _codec(cfg), name="mirror")


def _poses(n: int, seed: int = 1) -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(seed), n), focal=F, principal_point=PP)


@pytest.mark.parametrize("mode", ["both", "baseline", "location", "scale"])
@pytest.mark.parametrize("scale_definition", ["paper", "repo"])
def test_feature_mirror_is_the_codec_mirror(mode, scale_definition):
    kp = _poses(8).astype(np.float64)
    centred = kp - np.asarray(PP)
    perm, sign = feature_mirror(mode)
    np.testing.assert_allclose(pose_features(mirror(centred), mode=mode, scale_definition=scale_definition),
                               pose_features(centred, mode=mode, scale_definition=scale_definition)[..., perm] * sign,
                               atol=1e-12)
    cfg = ModelConfig(mode=mode, scale_definition=scale_definition, conditioning="source")
    codec = PoseCodec(cfg)
    perm, sign = feature_mirror(mode, num_extra=1)
    for source in ("clean", "detected"):
        f, c = np.full((8, 2), F), np.broadcast_to(np.asarray(PP), (8, 2))
        a = codec.encode(codec.mirror_input(kp, c), principal_point=c, focal=f, source=source).features
        b = codec.encode(kp, principal_point=c, focal=f, source=source).features
        np.testing.assert_allclose(a, b[..., perm] * sign, atol=1e-12)


def test_output_mirror_is_the_codec_mirror_and_an_involution():
    codec = _codec(ModelConfig())
    z = np.random.default_rng(0).normal(size=(5, 49))
    perm, scale, offset = output_mirror(codec.target_mean, codec.target_std)
    via_map = codec.destandardize(z[:, perm] * scale.astype(np.float64) + offset)
    np.testing.assert_allclose(via_map, codec.mirror_output(codec.destandardize(z)), rtol=1e-5, atol=1e-3)
    twice = (z[:, perm] * scale + offset)[:, perm] * scale + offset
    np.testing.assert_allclose(twice, z, atol=1e-4)


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 10_000), n=st.sampled_from([1, 3, NUMPY_MAX_BATCH + 5]),
       source=st.sampled_from(["clean", "detected"]), view=st.sampled_from(["camera", "look_at"]))
def test_mirror_net_is_equivariant_in_one_pass(seed, n, source, view):
    """Any weights: lifting the mirror image gives the mirrored result (numpy path for small batches, the torch
    module for large ones); looking at the root too (the turn commutes with the mirror)."""
    lifter = _mirror_lifter(seed % 7, conditioning="source", view=view)
    kp = _poses(n, seed)
    res = lifter.lift(kp, focal=F, principal_point=PP, source=source)
    mir = lifter.lift(lifter.codec.mirror_input(kp, PP), focal=F, principal_point=PP, source=source)
    np.testing.assert_allclose(mir.relative, mirror(res.relative), atol=2e-3)
    np.testing.assert_allclose(mir.root[..., 1:], res.root[..., 1:], rtol=1e-5, atol=1e-2)
    # the root's x mirrors about the principal point's ray: same depth, x' - ... = -(x ...) in camera space
    np.testing.assert_allclose(mir.root[..., 0], -res.root[..., 0], rtol=1e-5, atol=1e-2)
    assert np.abs(res.relative).max() > 1.0  # the output depends on the net


def test_uncoupled_mirror_net_is_the_flip_test_average():
    """With U = V (no coupling between the streams) the network is two copies of a plain MLP whose hidden weights
    are U + V, one on the pose and one on its mirror image, averaged: exactly flip-test averaging."""
    torch.manual_seed(0)
    plain_cfg = ModelConfig(width=40, conditioning="none")
    plain = _randomize(PoseLifterNet(plain_cfg), 1)
    sym = PoseLifterNet(ModelConfig(width=40, conditioning="none", symmetry="mirror"))
    state = sym.state_dict()
    for k, v in plain.state_dict().items():
        if k.endswith((".3.weight", ".7.weight")):
            state[k.replace(".weight", ".weight_sum")] = v / 2
            state[k.replace(".weight", ".weight_diff")] = v / 2
        else:
            state[k] = v
    sym.load_state_dict(state)
    codec = _codec(plain_cfg)
    kp = _poses(6)
    a = Lifter(plain, codec).lift(kp, focal=F, principal_point=PP, flip_test=True)
    b = Lifter(sym.eval(), PoseCodec(sym.config, target_mean=codec.target_mean, target_std=codec.target_std)).lift(
        kp, focal=F, principal_point=PP)
    np.testing.assert_allclose(b.relative, a.relative, atol=2e-3)
    np.testing.assert_allclose(b.root, a.root, rtol=1e-5, atol=1e-2)


@pytest.mark.parametrize("rows", [1, 2, 4])
def test_mirror_numpy_path_matches_module(rows):
    """A few rows run as one chain (each weight read once for all rows), equal to the module."""
    lifter = _mirror_lifter(2)
    x = lifter.codec.encode(_poses(rows).astype(np.float32), principal_point=np.full((rows, 2), PP, np.float32),
                            focal=np.full((rows, 2), F, np.float32)).features
    with torch.inference_mode():
        ref = lifter.net(torch.from_numpy(x)).numpy()
    got = forward_numpy(lifter.net, x)
    assert got is not None and np.abs(ref).std() > 0.05
    np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-5)
    with torch.no_grad():  # the numpy path reads the live weights
        lifter.net.blocks[0].body[3].weight_diff.mul_(2.0)
        ref2 = lifter.net(torch.from_numpy(x)).numpy()
    np.testing.assert_allclose(forward_numpy(lifter.net, x), ref2, rtol=1e-5, atol=1e-5)
    assert np.abs(ref2 - ref).max() > 1e-3


def test_coupled_layer_gradcheck_and_stream_swap():
    layer = MirrorCoupledLinear(5).double()
    x = torch.randn(6, 5, dtype=torch.float64, requires_grad=True)
    assert torch.autograd.gradcheck(layer, (x,))
    y = layer(x)
    swapped = layer(torch.cat([x[3:], x[:3]]))
    torch.testing.assert_close(swapped, torch.cat([y[3:], y[:3]]))
    with pytest.raises(ValueError, match="two streams"):
        layer(torch.randn(3, 5, dtype=torch.float64))


def _equivariance_gap(net: PoseLifterNet, codec: PoseCodec) -> float:
    """Largest mm difference between the module's output on mirrored features, mapped back by the codec, and its
    output on the features (no Lifter involved)."""
    kp = _poses(6).astype(np.float32)
    c, f = np.full((6, 2), PP, np.float32), np.full((6, 2), F, np.float32)
    x = codec.encode(kp, principal_point=c, focal=f).features
    xm = codec.encode(codec.mirror_input(kp, c), principal_point=c, focal=f).features
    with torch.inference_mode():
        a = codec.destandardize(net(torch.from_numpy(x)).double().numpy())
        b = codec.destandardize(net(torch.from_numpy(xm)).double().numpy())
    return float(np.abs(codec.mirror_output(b) - a).max())


def test_mirror_checkpoint_round_trip_half(tmp_path):
    lifter = _mirror_lifter(4)
    path = save_checkpoint(tmp_path / "m.pt", lifter.net, lifter.codec, half=True)
    ck = load_checkpoint(path)
    # the output mirror is rebuilt from the float64 codec statistics (not the float16 copies in the file), so the
    # loaded network is exactly equivariant on its own, before any Lifter touches it
    assert _equivariance_gap(ck.net, ck.codec) < 1e-2
    with torch.no_grad():
        ck.net.out_offset.add_(0.1)  # (the check above can fail)
    assert _equivariance_gap(ck.net, ck.codec) > 1.0
    back = Lifter.load(path)
    assert back.config.symmetry == "mirror"
    kp = _poses(5)
    a = lifter.lift(kp, focal=F, principal_point=PP)
    b = back.lift(kp, focal=F, principal_point=PP)
    np.testing.assert_allclose(b.relative, a.relative, rtol=0.02, atol=1.0)  # float16 weights


def test_mirror_lift_is_one_pass(monkeypatch):
    """flip_test=True changes nothing for a mirror network: one network row per pose."""
    lifter = _mirror_lifter(6)
    rows: list[int] = []
    real = Lifter._network
    monkeypatch.setattr(Lifter, "_network", lambda self, x: rows.append(len(x)) or real(self, x))
    kp = _poses(3)
    a = lifter.lift(kp, focal=F, principal_point=PP, flip_test=True)
    b = lifter.lift(kp[0], focal=F, principal_point=PP)
    assert rows == [3, 1]
    np.testing.assert_allclose(b.relative, a.relative[0], atol=2e-3)


def test_mirror_quantized_is_int8_and_equivariant():
    lifter = _mirror_lifter(7)
    q = lifter.quantized()
    kinds = {type(m).__name__ for m in q.net.modules()}
    assert "QuantizedCoupledLinear" in kinds and "MirrorCoupledLinear" not in kinds
    # each coupled layer's two products int8 once; the stem and head stay float32
    int8 = [m for m in q.net.modules() if isinstance(m, torch.ao.nn.quantized.dynamic.Linear)]
    assert len(int8) == 2 * 2 * len(q.net.blocks)
    assert sum(isinstance(m, torch.nn.Linear) for m in q.net.modules()) == 2
    x = lifter.codec.encode(_poses(1).astype(np.float32), principal_point=np.full((1, 2), PP, np.float32),
                            focal=np.full((1, 2), F, np.float32)).features
    assert forward_numpy(q.net, x) is None  # int8 layers run as the torch module
    kp = _poses(4)
    a, b = lifter.lift(kp, focal=F, principal_point=PP), q.lift(kp, focal=F, principal_point=PP)
    assert 0 < np.abs(b.relative - a.relative).max() < 0.05 * np.abs(a.relative).max()
    mir = q.lift(q.codec.mirror_input(kp, PP), focal=F, principal_point=PP)
    np.testing.assert_allclose(mir.relative, mirror(b.relative), atol=2e-2)


def test_mirror_numpy_path_empty_batch():
    lifter = _mirror_lifter(8)
    assert forward_numpy(lifter.net, np.zeros((0, lifter.config.num_features), np.float32)).shape == (0, 49)


def test_mirror_checkpoint_with_a_foreign_feature_map_is_refused(tmp_path):
    lifter = _mirror_lifter(5)
    path = save_checkpoint(tmp_path / "m.pt", lifter.net, lifter.codec)
    payload = torch.load(path, weights_only=True)
    payload["state_dict"]["in_perm"] = torch.flip(payload["state_dict"]["in_perm"], [0])
    payload["tensors_sha256"] = tensor_checksum(payload["state_dict"], payload["codec"])  # (written so, not damaged)
    torch.save(payload, path)
    with pytest.raises(CheckpointError, match="in_perm"):
        load_checkpoint(path)
