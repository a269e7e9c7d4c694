"""The fast paths: ``Lifter.lift`` runs a few rows through float16-packed copies of float16-exact weight matrices,
one pose otherwise through numpy and batches through torch in cache-sized slices, the last two on the live weights.

``lifter.model.forward_numpy`` and ``lifter.model.forward_folded`` must give the torch module's outputs,
see every change to the weights (no cache to go stale) and step aside for layers they cannot run
(quantized, training mode). ``lifter.model.forward_packed`` must give the module's outputs, follow every change made
through torch (version counters), read biases and BatchNorm statistics live, and step aside where it cannot run.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from conftest import random_pose_cam

import lifter.model as lifter_model
from lifter import Lifter, ModelConfig, PoseCodec, PoseLifterError, PoseLifterNet, PoseLifterWarning
from lifter.camera import project
from lifter.model import forward_folded, forward_numpy

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
    return net.eval()


def _lifter(net: PoseLifterNet, name: str = "small") -> Lifter:
    mean = np.linspace(-300.0, 300.0, 49)
    mean[-1] = 4400.0
    return Lifter(net, PoseCodec(net.config, target_mean=mean, target_std=np.linspace(50.0, 400.0, 49)), name=name)


@pytest.fixture()
def kp() -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(1), 32), focal=1145.0, principal_point=PP)


def _features(net: PoseLifterNet, kp: np.ndarray) -> np.ndarray:
    k = kp.reshape(-1, 17, 2).astype(np.float32)
    return PoseCodec(net.config).encode(k, principal_point=np.float32(PP), focal=np.float32([1145.0, 1145.0])).features


def _module(lifter: Lifter, kp: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The reference: the torch module's eval-mode forward, decoded by the codec."""
    kp = kp.reshape(-1, 17, 2)
    c = lifter.codec
    enc = c.encode(kp.astype(np.float32), principal_point=np.float32(PP), focal=np.float32([1145.0, 1145.0]))
    with torch.inference_mode():
        out = lifter.net(torch.from_numpy(enc.features)).numpy()
    dec = c.decode(c.destandardize(out.astype(np.float64)), enc, root_2d=kp[:, 0], principal_point=PP, focal=1145.0)
    return dec.relative, dec.canonical_depth


def _assert_lift_matches_module(lifter: Lifter, kp: np.ndarray) -> None:
    rel, depth = _module(lifter, kp)
    res = lifter.lift(kp, focal=1145.0, principal_point=PP, flip_test=False)
    np.testing.assert_allclose(res.relative.reshape(rel.shape), rel, rtol=1e-5, atol=2e-3)
    np.testing.assert_allclose(res.canonical_depth.reshape(depth.shape), depth, rtol=1e-5, atol=2e-2)


@pytest.mark.parametrize("mode", ["both", "baseline"])
def test_numpy_forward_matches_module(kp, mode):
    net = _net(mode=mode)
    x = _features(net, kp)
    with torch.inference_mode():
        ref = net(torch.from_numpy(x)).numpy()
    got = forward_numpy(net, x)
    assert np.abs(ref).std() > 0.1  # the outputs depend on the input
    np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-5)


def test_single_pose_and_batch_agree_with_module(kp):
    lifter = _lifter(_net())
    _assert_lift_matches_module(lifter, kp)  # batch: torch module
    for i in (0, 7):  # one pose: numpy
        _assert_lift_matches_module(lifter, kp[i])
    one = lifter.lift(kp[3], focal=1145.0, principal_point=PP, flip_test=True)
    batch = lifter.lift(kp[3:5], focal=1145.0, principal_point=PP, flip_test=True)
    np.testing.assert_allclose(one.absolute, batch.absolute[0], rtol=1e-5, atol=1e-2)


@pytest.mark.parametrize("change", ["in_place", "data", "data_assign", "vector_to_parameters", "state_dict",
                                    "state_dict_assign", "nested_module", "buffer", "eps"])
def test_single_pose_sees_every_weight_change(kp, change):
    lifter = _lifter(_net(seed=0))
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
            net.blocks[0].body[0].running_mean.data.add_(0.5)
        elif change == "eps":
            net.blocks[1].body[0].eps = 0.5
    after = lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative
    assert np.abs(after - before).max() > 1.0
    _assert_lift_matches_module(lifter, kp[0])
    _assert_lift_matches_module(lifter, kp[:5])  # a batch: forward_folded


@pytest.mark.parametrize("change", ["data", "buffer", "eps"])
def test_batch_sees_every_weight_change(kp, change):
    """Changes that bypass the tensors' version counters (``.data``, a plain attribute) reach batches too."""
    lifter = _lifter(_net(seed=0))
    net = lifter.net
    before = lifter.lift(kp[:5], focal=1145.0, principal_point=PP).relative
    with torch.no_grad():
        if change == "data":
            net.blocks[0].body[3].weight.data.mul_(1.5)
        elif change == "buffer":
            net.blocks[0].body[4].running_var.data.mul_(3.0)
        elif change == "eps":
            net.blocks[1].body[4].eps = 0.5
    after = lifter.lift(kp[:5], focal=1145.0, principal_point=PP).relative
    assert np.abs(after - before).max() > 1.0
    _assert_lift_matches_module(lifter, kp[:5])


@pytest.mark.parametrize("config", [{"mode": "both"}, {"mode": "baseline"}, {"symmetry": "mirror"},
                                    {"symmetry": "mirror", "num_blocks": 1}])
@pytest.mark.parametrize("rows", [1, 7, 8, 9, 20])
def test_folded_forward_matches_module(kp, monkeypatch, config, rows):
    """Across slice boundaries (slices of 8 rows here; 4 poses for a mirror network's two streams)."""
    monkeypatch.setattr(lifter_model, "FOLDED_ROWS", 8)
    net = _net(**config)
    if config.get("symmetry") == "mirror":
        lifter = _lifter(net)  # sets the output mirror from the codec's statistics
        net = lifter.net
    x = _features(net, np.concatenate([kp, kp])[:rows])
    with torch.inference_mode():
        ref = net(torch.from_numpy(x)).numpy()
        got = forward_folded(net, torch.from_numpy(x))
    assert got is not None and got.shape == ref.shape == (rows, 49)
    assert np.abs(ref).std() > 0.1
    np.testing.assert_allclose(got.numpy(), ref, rtol=1e-5, atol=1e-5)


def test_folded_forward_steps_aside(kp):
    net = _net()
    x = torch.from_numpy(_features(net, kp[:4]))
    assert forward_folded(net, x.double()) is None  # not float32
    net.blocks[1].train()
    assert forward_folded(net, x) is None  # batch statistics
    net.eval()
    torch.ao.quantization.quantize_dynamic(net.blocks, {torch.nn.Linear}, dtype=torch.qint8, inplace=True)
    assert forward_folded(net, x) is None


@pytest.mark.parametrize("block_bytes", [256, 1000, 1 << 20])
def test_row_blocked_products_equal_row_by_row(kp, monkeypatch, block_bytes):
    """Two rows (a pose and its mirror image) through row blocks of the weights give each row's own result."""
    monkeypatch.setattr(lifter_model, "_BLOCK_BYTES", block_bytes)
    net = _net()
    x = _features(net, kp[:2])
    both = forward_numpy(net, x)
    rows = np.concatenate([forward_numpy(net, x[i:i + 1]) for i in range(2)])
    assert both is not None and both.shape == (2, 49)
    np.testing.assert_allclose(both, rows, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("symmetry", ["none", "mirror"])
def test_net_built_under_inference_mode(kp, symmetry):
    """A network made and loaded under ``torch.inference_mode()`` (inference tensors) can be wrapped outside it;
    a mirror network's output mirror is then set from the codec's statistics (buffers replaced, not written)."""
    with torch.inference_mode():
        net = PoseLifterNet(ModelConfig(width=64, symmetry=symmetry))
        net.load_state_dict(_net(symmetry=symmetry).state_dict())
    lifter = _lifter(net, name="inference")
    if symmetry == "mirror":
        assert lifter.codec.target_std.std() > 0 and torch.equal(
            net.out_scale, torch.from_numpy(lifter_model.output_mirror(lifter.codec.target_mean,
                                                                       lifter.codec.target_std)[1]).float())
    _assert_lift_matches_module(lifter, kp[0])
    _assert_lift_matches_module(lifter, kp[:4])


def test_quantized_blocks_use_the_module(kp):
    lifter = _lifter(_net())
    torch.ao.quantization.quantize_dynamic(lifter.net.blocks, {torch.nn.Linear}, dtype=torch.qint8, inplace=True)
    assert forward_numpy(lifter.net, _features(lifter.net, kp[:1])) is None
    _assert_lift_matches_module(lifter, kp[0])
    _assert_lift_matches_module(lifter.quantized(), kp[0])


def test_replaced_activation_uses_the_module(kp):
    """A layer the numpy path does not model (here a GELU in place of a ReLU) sends the pose to the module."""
    lifter = _lifter(_net())
    before = lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative
    lifter.net.blocks[0].body[2] = torch.nn.GELU()
    assert forward_numpy(lifter.net, _features(lifter.net, kp[:1])) is None
    assert np.abs(lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative - before).max() > 1e-3
    _assert_lift_matches_module(lifter, kp[0])


def test_subclass_with_its_own_forward_uses_the_module(kp):
    class Clamped(PoseLifterNet):
        def forward(self, features):
            return super().forward(features).clamp(max=-30.0)

    net = Clamped(ModelConfig(width=64))
    net.load_state_dict(_net().state_dict())
    lifter = _lifter(net.eval(), name="clamped")
    with pytest.warns(PoseLifterWarning, match="behind the camera"):  # (and LiftResult.warnings says it too)
        assert lifter.lift(kp[0], focal=1145.0, principal_point=PP).canonical_depth < 0  # 4400 + 400 * (-30) mm
        _assert_lift_matches_module(lifter, kp[0])


@pytest.mark.parametrize("part", ["net", "blocks"])
def test_training_mode_is_refused(kp, part):
    lifter = _lifter(_net())
    (lifter.net if part == "net" else lifter.net.blocks).train()
    for k in (kp[0], kp[:4]):
        with pytest.raises(PoseLifterError, match="training mode"):
            lifter.lift(k, focal=1145.0, principal_point=PP)
    lifter.net.eval()
    _assert_lift_matches_module(lifter, kp[0])


def test_shipped_default_single_pose_matches_module(kp):
    lifter = Lifter.from_pretrained("default")
    for part in (lifter, *lifter.ensemble):  # every network of the default, on its own
        alone = Lifter(part.net, part.codec, name=part.name)
        _assert_lift_matches_module(alone, kp[:16])
        _assert_lift_matches_module(alone, kp[3])
    # the default's flip-test averaging and its ensemble: one pose (numpy rows) equals the same pose in a batch
    # (random bodies: the default notes that its lifts do not fit them, which is not what this test is about)
    one = lifter.lift(kp[3], focal=1145.0, principal_point=PP, flip_test=True, warn=False)
    batch = lifter.lift(kp[3:6], focal=1145.0, principal_point=PP, flip_test=True, warn=False)
    np.testing.assert_allclose(one.absolute, batch.absolute[0], rtol=1e-5, atol=1e-2)


def _half_exact(net: PoseLifterNet) -> PoseLifterNet:
    """``net`` with its weight matrices rounded to float16 numbers, as every shipped network's are (stored float16)."""
    with torch.no_grad():
        for p in net.parameters():
            if p.ndim == 2:
                p.copy_(p.half().float())
    return net


packing = pytest.mark.skipif(not lifter_model.fp16_packing_available(),
                             reason="this torch build has no fbgemm float16 packing (the float32 paths run)")


@pytest.fixture(autouse=True)
def _one_torch_thread():
    """The packed path runs where torch runs on one thread (forward_packed): every test here starts there."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


@packing
@pytest.mark.parametrize("config", [{}, {"symmetry": "mirror"}, {"mode": "baseline"}])
def test_packed_forward_matches_module_for_float16_weights(kp, config):
    """forward_packed (float16-packed matrices, products summed in float32) gives the module's outputs for a network
    whose matrices are float16 numbers, up to PACKED_MAX_ROWS rows; it steps aside otherwise."""
    net = _half_exact(_net(seed=2, **config))
    many = np.concatenate([kp] * 8)  # 256 poses
    for rows in (1, 2, 5, lifter_model.PACKED_MAX_ROWS):
        x = _features(net, many[:rows])
        got = lifter_model.forward_packed(net, x)
        assert got is not None and got.shape == (rows, 49) and got.dtype == np.float32
        with torch.inference_mode():
            want = net(torch.from_numpy(x)).numpy()
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=2e-5)
    assert lifter_model.forward_packed(net, _features(net, many[:lifter_model.PACKED_MAX_ROWS + 1])) is None
    assert lifter_model.forward_packed(_net(seed=2, **config), _features(net, kp[:1])) is None  # float32 weights
    net.train()
    assert lifter_model.forward_packed(net, _features(net, kp[:1])) is None
    net.eval()
    lifter = _lifter(net)
    _assert_lift_matches_module(lifter, kp[0])
    _assert_lift_matches_module(lifter, kp[:20])
    with torch.no_grad():  # (a review: fbgemm clamps an infinite float16 weight to 65504, where the module is inf)
        net.stem.weight[0, 0] = float("inf")
    assert lifter_model.forward_packed(net, _features(net, kp[:1])) is None


@packing
def test_packed_matrices_follow_weight_changes(kp):
    """The packed copies are rebuilt when a matrix is replaced, changed by torch (its version counter) or changed in a
    way that bypasses the version counter but touches its first or last row (a fused optimizer step, .data of the
    whole matrix); biases and BatchNorm statistics are read live; Lifter.refresh() packs again after anything else."""
    net = _half_exact(_net(seed=0))
    lifter = _lifter(net)
    lift = lambda: lifter.lift(kp[0], focal=1145.0, principal_point=PP).relative  # noqa: E731
    first = lift()
    assert lifter_model.forward_packed(net, _features(net, kp[:1])) is not None
    w = net.blocks[0].body[3].weight
    with torch.no_grad():
        w.mul_(2.0)  # (twice a float16 number is one)
    assert np.abs(lift() - first).max() > 1.0
    _assert_lift_matches_module(lifter, kp[0])
    net.load_state_dict(_half_exact(_net(seed=3)).state_dict())
    _assert_lift_matches_module(lifter, kp[0])
    with torch.no_grad():
        net.head.bias.data.add_(0.5)  # (read live)
        net.blocks[0].body[0].running_mean.data.add_(0.5)
    _assert_lift_matches_module(lifter, kp[0])
    before = lift()
    w.data.mul_(0.5)  # bypasses the version counter, but every row changes (a review: not seen before the row check)
    assert np.abs(lift() - before).max() > 1.0
    _assert_lift_matches_module(lifter, kp[0])
    # a new Parameter in place of a matrix, whatever its version counter says
    net.blocks[1].body[7].weight = torch.nn.Parameter(_half_exact(_net(seed=5)).blocks[1].body[7].weight.detach())
    _assert_lift_matches_module(lifter, kp[0])
    # a fused optimizer step writes without moving the version counters (a review: 146 mm off before the row check)
    net.train()
    opt = torch.optim.AdamW(net.parameters(), lr=1e-2, fused=True)
    enc = _features(net, kp[:8])
    net(torch.from_numpy(enc)).square().mean().backward()
    opt.step()
    net.eval()
    _assert_lift_matches_module(lifter, kp[0])
    # a sparse change through .data (a middle row) needs refresh()
    net.load_state_dict(_half_exact(_net(seed=3)).state_dict())
    lift()
    w.data[5].mul_(0.5)
    lifter.refresh()
    _assert_lift_matches_module(lifter, kp[0])


@packing
def test_packed_path_runs_on_one_thread_only_and_steps_aside_without_packing(kp, monkeypatch):
    """The packed path runs where torch runs on one thread, and steps aside otherwise, leaving the thread count alone
    (a review: fbgemm split the small products over torch's threads, 4-128 ms for one pose on a busy 2-core machine;
    setting one thread around them set it for every thread started meanwhile); under a quantized engine that cannot
    pack (qnnpack, onednn) or a build without fbgemm the float32 paths run (a review: lift raised)."""
    import threading

    lifter = _lifter(_half_exact(_net(seed=0)))
    threads = torch.get_num_threads()
    try:
        torch.set_num_threads(2)
        assert lifter_model.forward_packed(lifter.net, _features(lifter.net, kp[:1])) is None
        _assert_lift_matches_module(lifter, kp[0])
        seen: list[int] = []
        started = threading.Thread(target=lambda: seen.append(torch.get_num_threads()))
        started.start()
        started.join()
        assert torch.get_num_threads() == 2 and seen == [2]
        torch.set_num_threads(1)
        assert lifter_model.forward_packed(lifter.net, _features(lifter.net, kp[:1])) is not None
    finally:
        torch.set_num_threads(threads)
    engine = torch.backends.quantized.engine
    for other in [e for e in ("qnnpack", "onednn") if e in torch.backends.quantized.supported_engines]:
        try:
            torch.backends.quantized.engine = other
            fresh = _lifter(_half_exact(_net(seed=1)))
            assert lifter_model.forward_packed(fresh.net, _features(fresh.net, kp[:1])) is None
            _assert_lift_matches_module(fresh, kp[0])
        finally:
            torch.backends.quantized.engine = engine
    monkeypatch.setattr(lifter_model, "_PACKING", {engine: False})
    assert lifter_model.forward_packed(lifter.net, _features(lifter.net, kp[:1])) is None
    _assert_lift_matches_module(lifter, kp[0])


@packing
def test_shipped_networks_run_packed():
    """Every network of the default is float16-exact (its file stores float16), so one pose runs packed."""
    lifter = Lifter.from_pretrained("default")
    for part in (lifter, *lifter.ensemble, lifter.clean):
        x = np.zeros((2, part.net.stem.in_features), np.float32)
        assert lifter_model.forward_packed(part.net, x) is not None, part.name
