"""Training: the loss, batches (sources, flip, zoom, noise), target statistics, EMA, tiny runs that learn,
fine-tuning, the CLI and its config round trip, and DistributedDataParallel under torchrun."""

from __future__ import annotations

import math
import os
import socket
import subprocess
import sys
import textwrap
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from conftest import random_pose_cam, requires_h36m

from lifter._checks import PoseLifterError, PoseLifterWarning
from lifter.api import Lifter
from lifter.codec import PoseCodec
from lifter.config import AugmentConfig, DataConfig, OptimConfig, ScheduleConfig, TrainConfig
from lifter.data import PoseSamples
from lifter.evaluate import evaluate_lifter
from lifter.loss import poselifter_loss
from lifter.model import ModelConfig, PoseLifterNet, output_mirror
from lifter.skeleton import LEFT_JOINTS, LEFT_RIGHT_PAIRS, RIGHT_JOINTS, mirror
from lifter.train import (
    Dist,
    WeightAverage,
    batch_loss,
    flip_batch,
    make_batch,
    samples_to_tensors,
    target_statistics,
    teacher_targets,
    train,
    validation_sets,
)

ROOT = Path(__file__).resolve().parents[1]


def synthetic_samples(n: int, *, seed: int = 0) -> PoseSamples:
    """Random plausible poses seen by an H36M-like camera (no dataset needed)."""
    from lifter.camera import project

    pose = random_pose_cam(np.random.default_rng(seed), n)
    f, c = np.array([1145.0, 1144.0]), np.array([512.0, 515.0])
    kp = project(pose, focal=f, principal_point=c)
    z = np.zeros(n, np.int32)
    return PoseSamples(keypoints_2d=kp.astype(np.float32), pose_3d=pose.astype(np.float32),
                       focal=np.tile(f, (n, 1)).astype(np.float32),
                       principal_point=np.tile(c, (n, 1)).astype(np.float32),
                       image_size=np.tile([1000, 1000], (n, 1)).astype(np.int32), subject=z + 1, action=z, camera=z,
                       frame=np.arange(n, dtype=np.int32), sequence=z, sequence_names=("S1/Walking 1",),
                       distortion=np.zeros((n, 5), np.float32))


def tiny_config(**model: object) -> TrainConfig:
    return TrainConfig(model=ModelConfig(width=64, **model),  # type: ignore[arg-type]
                       optim=OptimConfig(batch_size=64, lr=2e-3),
                       schedule=ScheduleConfig(epochs=1, eval_every=1000))


def test_loss_units_and_weighting():
    pred = torch.zeros(2, 49)
    target = torch.zeros(2, 49)
    target[:, :48] = 1.0  # 1 mm on each of 48 coordinates
    target[:, 48] = 10.0  # 10 mm of canonical depth
    assert poselifter_loss(pred, target).item() == pytest.approx(58.0)
    assert poselifter_loss(pred, target, depth_weight=0.0).item() == pytest.approx(48.0)
    assert poselifter_loss(pred, target, depth_scale=torch.tensor([0.5, 0.5])).item() == pytest.approx(53.0)
    with pytest.raises(ValueError, match="49"):
        poselifter_loss(torch.zeros(2, 48), torch.zeros(2, 48))


def test_joint_loss_sums_the_joints_euclidean_errors():
    """pose_loss="joint": each joint's error counts by its length (16 x the mean over joints 1..16), not by the sum of
    its three coordinates' absolute errors; the depth term is the same as the L1 loss's."""
    pred = torch.zeros(2, 49)
    target = torch.zeros(2, 49)
    target[:, :48] = torch.tensor([3.0, 4.0, 0.0]).repeat(16)  # a 5 mm error on each joint: 7 mm in L1
    target[:, 48] = 10.0
    assert poselifter_loss(pred, target, pose_loss="joint").item() == pytest.approx(16 * 5.0 + 10.0, abs=1e-4)
    assert poselifter_loss(pred, target).item() == pytest.approx(16 * 7.0 + 10.0)
    target[1, :3] = torch.tensor([0.0, 0.0, 12.0])  # one joint of the second sample 12 mm off along z
    assert poselifter_loss(pred, target, pose_loss="joint", depth_weight=0.0).item() == pytest.approx(
        (80.0 + 75.0 + 12.0) / 2, abs=1e-4)
    with pytest.raises(ValueError, match="pose_loss must be 'l1' or 'joint'"):
        poselifter_loss(pred, target, pose_loss="l2")  # type: ignore[arg-type]


def test_joint_loss_is_the_mpjpe_and_its_gradient_stays_finite():
    g = torch.Generator().manual_seed(0)
    pred = torch.randn(5, 49, generator=g, dtype=torch.float64) * 30
    target = torch.randn(5, 49, generator=g, dtype=torch.float64) * 30
    from lifter.metrics import mpjpe

    # the codec's own reading of the outputs (the layout the targets are encoded in), not the loss's reshape
    codec = PoseCodec(ModelConfig(input_space="camera", depth_target="size", conditioning="none"))
    s = synthetic_samples(5)
    kp, pp, f = (torch.tensor(a, dtype=torch.float64) for a in (s.keypoints_2d, s.principal_point, s.focal))
    enc = codec.encode(kp, principal_point=pp, focal=f)
    rel = lambda v: codec.split(v, enc)[0]  # noqa: E731
    per_pose = torch.as_tensor(mpjpe(rel(pred).numpy(), rel(target).numpy()))  # over 17 joints, root exact
    assert poselifter_loss(pred, target, pose_loss="joint", depth_weight=0.0).item() == pytest.approx(
        float((per_pose * 17).mean()), rel=1e-9)
    # bounded by the L1 form: ||e|| <= |ex| + |ey| + |ez| <= sqrt(3) ||e||
    j = poselifter_loss(pred, target, pose_loss="joint", depth_weight=0.0).item()
    l1 = poselifter_loss(pred, target, depth_weight=0.0).item()
    assert j <= l1 <= 3 ** 0.5 * j
    exact = target.clone().requires_grad_(True)  # zero error: the square root's gradient must not be NaN
    poselifter_loss(exact, target, pose_loss="joint").backward()
    assert exact.grad is not None and torch.isfinite(exact.grad).all()
    p = pred.clone().requires_grad_(True)
    assert torch.autograd.gradcheck(lambda x: poselifter_loss(x, target, pose_loss="joint"), (p,))
    with pytest.raises(PoseLifterError, match="pose_loss must be 'l1' or 'joint'"):
        OptimConfig(pose_loss="l2")  # type: ignore[arg-type]


@pytest.mark.parametrize("space,target", [("pixel", "canonical"), ("pixel", "absolute"), ("camera", "canonical"),
                                          ("camera", "size")])
def test_loss_depth_term_is_the_canonical_depth_error(space, target):
    """Whatever the depth parametrization, the depth term is |dZ| * F0 / alpha in mm (the paper's form)."""
    codec = PoseCodec(ModelConfig(input_space=space, depth_target=target, conditioning="none"))
    s = synthetic_samples(8)
    kp, pp, f = (torch.tensor(a, dtype=torch.float64) for a in (s.keypoints_2d, s.principal_point, s.focal))
    enc = codec.encode(kp, principal_point=pp, focal=f)
    z = torch.tensor(s.pose_3d[:, 0, 2], dtype=torch.float64)
    rel = torch.tensor(s.relative, dtype=torch.float64)
    t = codec.encode_targets(rel, z, enc)
    p = codec.encode_targets(rel, z + 100.0, enc)  # 100 mm too deep
    loss = poselifter_loss(p, t, depth_scale=codec.depth_loss_scale(enc))
    alpha = torch.sqrt(f[:, 0] * f[:, 1])
    assert loss.item() == pytest.approx(float((100.0 * 1000.0 / alpha).mean()), rel=1e-9)


def test_flip_batch_is_the_image_flip():
    from lifter.camera import flip_keypoints_2d, flip_pose_3d

    g = torch.Generator().manual_seed(0)
    kp = torch.rand(6, 17, 2, generator=g, dtype=torch.float64) * 1000
    pp = torch.rand(6, 2, generator=g, dtype=torch.float64) * 1000
    rel = torch.randn(6, 17, 3, generator=g, dtype=torch.float64) * 300
    mask = torch.tensor([True, False, True, False, True, True])
    kp_f, rel_f = flip_batch(kp, pp, rel, mask)
    # about the principal point: the same coordinates relative to it as the image flip x -> W - x, cx -> W - cx
    kp_img, pp_img = flip_keypoints_2d(kp.numpy(), image_width=1000, principal_point=pp.numpy())
    m = mask.numpy()
    np.testing.assert_allclose((kp_f - pp[:, None]).numpy()[m], (kp_img - pp_img[:, None])[m], rtol=1e-12)
    np.testing.assert_allclose(rel_f.numpy()[m], flip_pose_3d(rel.numpy())[m], rtol=1e-12)
    np.testing.assert_array_equal(kp_f.numpy()[~m], kp.numpy()[~m])


def _tensors(n: int = 2000) -> dict[str, torch.Tensor]:
    T = samples_to_tensors(synthetic_samples(n))
    T["real"] = T["kp"] + 7.0  # a "detection" 7 px off in x and y
    T["has_real"] = torch.arange(n) % 2 == 0  # every other sample has one
    return T


class Plus1000:
    """A noise model whose effect is unmistakable; records the levels it was asked for."""

    def __init__(self) -> None:
        self.levels: list[torch.Tensor] = []

    def sample_torch(self, kp, *, level, generator, outliers):  # noqa: ANN001
        self.levels.append(level)
        return kp + 1000.0


def test_make_batch_sources():
    """Each row is its clean GT, its real detection (never noised) or noisy GT, at the configured rates."""
    T = _tensors()
    n = len(T["kp"])
    idx = torch.arange(n)
    cfg = TrainConfig(data=DataConfig(clean_prob=0.3, real_prob=0.4, noise_level_min=0.5, noise_level_max=1.5),
                      augment=AugmentConfig(flip_prob=0.0))
    noise = Plus1000()
    b = make_batch(T, idx, cfg, torch.Generator().manual_seed(0), noise=noise)  # type: ignore[arg-type]
    off = (b["kp"] - T["kp"])[:, 0, 0]
    clean, real, noisy = (torch.isclose(off, torch.tensor(v)) for v in (0.0, 7.0, 1000.0))
    assert bool((clean | real | noisy).all())
    assert torch.equal(clean, b["clean"])  # the source flag says which rows are exact
    assert not bool(real[~T["has_real"]].any())  # never a detection where there is none
    assert 0.25 < clean.float().mean() < 0.35
    assert 0.35 < real[T["has_real"]].float().mean() < 0.45
    lv = noise.levels[0]
    assert float(lv.min()) >= 0.5 and float(lv.max()) <= 1.5 and float(lv.std()) > 0.2  # one level per pose
    torch.testing.assert_close(b["rel"], T["rel"])
    torch.testing.assert_close(b["depth"], T["depth"])
    torch.testing.assert_close(b["focal"], T["focal"])


def test_make_batch_flip_and_zoom_apply_to_detections_too():
    T = _tensors()
    n = len(T["kp"])
    h = T["has_real"]
    cfg = TrainConfig(data=DataConfig(clean_prob=0.0, real_prob=1.0), augment=AugmentConfig(flip_prob=1.0))
    b = make_batch(T, torch.arange(n), cfg, torch.Generator().manual_seed(0), noise=Plus1000())  # type: ignore[arg-type]
    c = T["pp"][:, None]
    torch.testing.assert_close(b["kp"][h], (c + mirror(T["real"] - c))[h])
    torch.testing.assert_close(b["rel"], mirror(T["rel"]))
    cfg = TrainConfig(data=DataConfig(clean_prob=1.0), augment=AugmentConfig(flip_prob=0.0, zoom=True, zoom_sigma=0.5,
                                                                              zoom_clip=1.0))
    b = make_batch(T, torch.arange(n), cfg, torch.Generator().manual_seed(0))
    s = b["pp"][:, 0] / T["pp"][:, 0]
    assert float(s.min()) < 0.8 and float(s.max()) > 1.2
    torch.testing.assert_close(b["kp"], T["kp"] * s[:, None, None])
    torch.testing.assert_close(b["focal"], T["focal"] * s[:, None])  # intrinsics scale together
    torch.testing.assert_close(b["depth"], T["depth"])  # the 3D does not change


def test_target_statistics_are_flip_symmetric():
    codec = PoseCodec(ModelConfig())
    mean, std = target_statistics(codec, samples_to_tensors(synthetic_samples(500)))
    m = np.asarray(mean[:48]).reshape(16, 3)  # joints 1-16, root-relative (the root row is not a target)
    # mirrored copies: each left joint's mean is its right partner's with x negated, a middle joint's x is 0 (a
    # review: the mean x over all joints, checked before, is 0 for any left/right pairing)
    for left, right in LEFT_RIGHT_PAIRS:
        np.testing.assert_allclose(m[left - 1], m[right - 1] * [-1, 1, 1], atol=1e-3)
    middle = [j - 1 for j in range(1, 17) if j not in {*LEFT_JOINTS, *RIGHT_JOINTS}]
    np.testing.assert_allclose(m[middle, 0], 0.0, atol=1e-3)
    assert 2000 < mean[48] < 8000 and np.all(std > 0)


def test_weight_average_is_an_exponential_moving_average():
    """avg <- d avg + (1 - d) current, d warming up as (1 + n) / (10 + n) to the decay asked for."""
    net = torch.nn.Sequential(torch.nn.Linear(3, 2), torch.nn.BatchNorm1d(2))
    w0 = {k: v.clone() for k, v in net.state_dict().items()}
    avg = WeightAverage(net, decay=0.9)
    assert avg.current_decay() == pytest.approx(0.1)
    with torch.no_grad():
        net[0].weight.add_(1.0)
        net[1].running_mean.fill_(5.0)
        net[1].num_batches_tracked.fill_(3)
    avg.update(net)
    sd = avg.module.state_dict()
    torch.testing.assert_close(sd["0.weight"], 0.1 * w0["0.weight"] + 0.9 * (w0["0.weight"] + 1.0))
    torch.testing.assert_close(sd["1.running_mean"], torch.full((2,), 4.5))
    assert int(sd["1.num_batches_tracked"]) == 3
    assert avg.module is not net
    for _ in range(79):  # (1 + 80) / (10 + 80) = 0.9: the warm-up is over
        avg.update(net)
    assert avg.current_decay() == pytest.approx(0.9)
    avg.update(net)
    with torch.no_grad():
        net[0].weight.add_(1.0)
    before = avg.module.state_dict()["0.weight"].clone()
    avg.update(net)
    torch.testing.assert_close(avg.module.state_dict()["0.weight"], 0.9 * before + 0.1 * net[0].weight)
    with pytest.raises(ValueError, match="decay"):
        WeightAverage(net, decay=1.0)


def test_weight_average_without_warmup_averages_as_runs_from_before_it_and_stored_configs_keep_that(tmp_path):
    """--no-ema-warmup (and a config stored before the option, which had no warm-up) averages with the decay from the
    first update; a stored config without an EMA keeps today's default (the option does nothing there)."""
    net = torch.nn.Linear(2, 2, bias=False)
    avg = WeightAverage(net, decay=0.9, warmup=False)
    assert avg.current_decay() == 0.9
    from lifter.checkpoint import save_checkpoint
    from lifter.config import TrainConfig

    lf = Lifter.load("universal_far")
    old = TrainConfig().to_dict()
    old["optim"] = {k: v for k, v in old["optim"].items() if k != "ema_warmup"}
    for decay, warm in ((0.999, False), (None, True)):
        old["optim"]["ema_decay"] = decay
        ck = save_checkpoint(tmp_path / f"old{decay}.pt", lf.net, lf.codec, train_config=old)
        assert TrainConfig.load(ck).optim.ema_warmup is warm


def test_weight_average_forgets_the_starting_weights_in_a_short_run():
    """A researcher trial: 684 steps at decay 0.999 kept half the random starting weights in the average (0.999^684),
    and the checkpoint was 242.5 mm off where the live network was 62.4. With the warm-up the start's share after
    684 updates is the product of the decays used, about 1e-20 (float64: zero to its precision)."""
    net = torch.nn.Linear(4, 4, bias=False, dtype=torch.float64)
    with torch.no_grad():
        net.weight.zero_()
    avg = WeightAverage(net, decay=0.999)
    with torch.no_grad():
        net.weight.fill_(1.0)  # (the live network jumps away from the start at once and stays there)
    for _ in range(684):
        avg.update(net)
    share_of_start = 1.0 - float(avg.module.weight.detach().mean())
    assert abs(share_of_start) < 1e-12
    assert 0.98 < avg.current_decay() < 0.999


@pytest.mark.parametrize("precision,symmetry,pose_loss", [("fp32", "none", "l1"), ("bf16", "none", "l1"),
                                                           ("bf16", "mirror", "l1"), ("fp32", "none", "joint"),
                                                           ("bf16", "mirror", "joint")])
def test_tiny_training_learns(precision, symmetry, pose_loss, monkeypatch):
    """A small network on synthetic poses beats the mean pose, in float32 and with bf16 blocks, and so does the
    mirror-equivariant network, which stays exactly equivariant after training (its output mirror follows the
    trained codec's statistics)."""
    import lifter.train as lt

    monkeypatch.setattr(lt, "cpu_has_native_bf16", lambda: True)  # (bf16 autocast runs, emulated or not)
    train_s, val_s = synthetic_samples(3000, seed=1), synthetic_samples(300, seed=2)
    cfg = TrainConfig(model=ModelConfig(width=128, dropout=0.0, symmetry=symmetry),
                      optim=OptimConfig(batch_size=128, lr=2e-3, precision=precision, pose_loss=pose_loss),
                      schedule=ScheduleConfig(epochs=8, eval_every=40))
    res = train(cfg, train_samples=train_s, val_sets=validation_sets(val_s, None), progress=False, log=lambda s: None,
                ctx=Dist())
    assert res.config.optim.precision == precision
    losses = [c["train_loss"] for c in res.curve]
    # the joint loss's pose term is smaller than L1's, so the depth term, slower to fall here, is more of it
    assert losses[-1] < (0.8 if pose_loss == "joint" else 0.7) * losses[0], losses
    if symmetry == "mirror":  # the trained net's output mirror is its codec's, before any Lifter sets it
        perm, scale, offset = output_mirror(res.codec.target_mean, res.codec.target_std)
        torch.testing.assert_close(res.net.out_offset, torch.from_numpy(offset))
        torch.testing.assert_close(res.net.out_scale, torch.from_numpy(scale))
    lifter = Lifter(res.net, res.codec, name="tiny")
    row = evaluate_lifter(lifter, val_s, progress=False, source="clean")[0]
    assert abs(row.depth_bias) <= row.mrpe_z + 1e-9  # (a signed mean is within the mean absolute error)
    from lifter.evaluate import score

    nearer = score("t", "learned", val_s.relative, val_s.root - [0.0, 0.0, 100.0], val_s)
    assert nearer.depth_bias == pytest.approx(-100.0) and nearer.mrpe_z == pytest.approx(100.0)
    mean_rel = np.concatenate([np.zeros((1, 3)), res.codec.target_mean[:48].reshape(16, 3)])
    from lifter.metrics import mpjpe

    baseline = float(mpjpe(np.broadcast_to(mean_rel, val_s.pose_3d.shape), val_s.relative).mean())
    assert row.mpjpe < 0.8 * baseline, (row.mpjpe, baseline)
    assert res.curve[-1]["val_mpjpe_clean"] == pytest.approx(row.mpjpe, rel=1e-3)
    if symmetry == "mirror":
        kp, pp, f = val_s.keypoints_2d[:5], val_s.principal_point[:5], val_s.focal[:5]
        a = lifter.lift(kp, focal=f, principal_point=pp, source="clean")
        b = lifter.lift(res.codec.mirror_input(kp, pp), focal=f, principal_point=pp, source="clean")
        np.testing.assert_allclose(b.relative, mirror(a.relative), atol=5e-3)


def test_bf16_on_a_cpu_without_native_bf16_trains_in_float32_and_says_so(monkeypatch):
    """bf16 autocast on a CPU without AVX512-BF16 or AMX is emulated, 12-20x slower than float32 (a session's
    70-minute fine-tune saw 0.4M samples): training there runs in float32, logs why, and the result's config says
    fp32; where the CPU has it, bf16 is kept without a word."""
    import lifter.train as lt

    train_s, val_s = synthetic_samples(256, seed=1), synthetic_samples(64, seed=2)
    cfg = replace(tiny_config(), optim=OptimConfig(batch_size=64, lr=2e-3, precision="bf16"))
    for native, want in ((False, "fp32"), (True, "bf16")):
        monkeypatch.setattr(lt, "cpu_has_native_bf16", lambda native=native: native)
        said: list[str] = []
        res = train(cfg, train_samples=train_s, val_sets=validation_sets(val_s, None), progress=False,
                    log=said.append, ctx=Dist())
        assert res.config.optim.precision == want
        assert (lt.BF16_EMULATED_NOTE in " ".join(said)) is (not native), said
    assert isinstance(lt.cpu_has_native_bf16(), bool)


def test_a_run_stores_its_error_model_fit_and_a_repeat_with_another_fit_says_so(tmp_path):
    """A researcher trial: the checkpoint named its fit only by the path "em/fit.json", so ``--config`` from another
    folder, whose em/fit.json was another fit, trained on it without a word. The fit and its sha256 are in the meta;
    ``--error-model RUN.pt`` takes it back; another fit is said by the repeat notes."""
    from lifter.checkpoint import load_checkpoint
    from lifter.cli.train import repeat_notes
    from lifter.noise import ErrorModel
    from lifter.train import save_training_outputs

    train_s = synthetic_samples(200, seed=3)
    noisy = replace(tiny_config(), data=DataConfig(clean_prob=0.0))  # (every sample with mixture noise)
    res = train(noisy, train_samples=train_s, val_sets=validation_sets(synthetic_samples(20, seed=4), None),
                progress=False, log=lambda s: None, ctx=Dist())
    shipped = ErrorModel.shipped("sh_mixture")
    assert res.error_model is not None and res.error_model.sha256() == shipped.sha256()
    out = save_training_outputs(res, tmp_path / "run.pt")
    meta = load_checkpoint(out).meta
    assert meta["error_model_sha256"] == shipped.sha256() and meta["error_model"]["format"] == "poselifter-error-model"
    back = ErrorModel.resolve(str(out))
    assert back.sha256() == shipped.sha256()
    # (a researcher trial: reading the fit from the run drew its network's initialisation from the global generator
    # after the seed, so a repeat with --error-model RUN.pt trained other weights than the run)
    again = train(replace(noisy, data=replace(noisy.data, error_model=str(out))), train_samples=train_s,
                  val_sets=validation_sets(synthetic_samples(20, seed=4), None), progress=False, log=lambda s: None,
                  ctx=Dist())
    for k, v in res.net.state_dict().items():
        assert torch.equal(v, again.net.state_dict()[k]), k
    np.testing.assert_allclose(back.sigma, shipped.sigma, atol=1e-6)
    other = replace(shipped, sigma=3 * shipped.sigma)
    assert repeat_notes(out, error_model=("em/fit.json", other.sha256())) == [
        f"the error model em/fit.json (sha256 {other.sha256()[:12]}) is not the fit {out} drew its noise from "
        f"({shipped.sha256()[:12]}): this does not repeat that run (--error-model {out} takes the fit it stored)"]
    assert repeat_notes(out, error_model=("sh_mixture", shipped.sha256())) == []
    plain = train(tiny_config(), train_samples=train_s, val_sets=validation_sets(synthetic_samples(20, seed=4), None),
                  progress=False, log=lambda s: None, ctx=Dist())  # (the default: exact 2D only)
    assert plain.error_model is None
    bare = save_training_outputs(plain, tmp_path / "clean.pt")
    assert "error_model" not in load_checkpoint(bare).meta
    with pytest.raises(PoseLifterError, match="this checkpoint stores no error-model fit"):
        ErrorModel.resolve(str(bare))
    # a single-Gaussian run stores the fit whole (a review: it stored the baseline, and --error-model RUN.pt then
    # drew from the baseline of the baseline, whose digest differed: "not the fit" for the very fit stored)
    gauss = train(replace(noisy, data=replace(noisy.data, noise="gaussian")), train_samples=train_s,
                  val_sets=validation_sets(synthetic_samples(20, seed=4), None), progress=False, log=lambda s: None,
                  ctx=Dist())
    assert gauss.error_model is not None and gauss.error_model.sha256() == shipped.sha256()
    # the digest is of the parameters noise is drawn with, not of the description or meta
    assert replace(shipped, source="edited", meta={"note": 1}).sha256() == shipped.sha256()
    assert shipped.baseline().sha256() != shipped.sha256()
    # a checkout's path to a shipped fit, not found from here, is that fit, and said
    with pytest.warns(PoseLifterWarning, match="taken as the shipped fit 'sh_mixture'"):
        far = ErrorModel.resolve(str(tmp_path / "elsewhere" / "assets" / "error_model" / "sh_mixture.json"))
    assert far.sha256() == shipped.sha256()
    with pytest.raises(PoseLifterError, match="cannot read"):
        ErrorModel.resolve(str(tmp_path / "assets" / "error_model" / "no_such_fit.json"))


def test_a_run_whose_fit_path_is_not_found_names_the_fit_it_stores(tmp_path, monkeypatch, capsys):
    """A researcher trial: a run's config keeps --error-model em/fit.json as typed, and ``--config RUN.pt`` from
    another folder failed with "cannot read" only; the run stores the fit, and the message now says to take it."""
    from lifter.cli import main
    from lifter.noise import ErrorModel
    from lifter.train import save_training_outputs

    (tmp_path / "em").mkdir()
    (tmp_path / "em" / "fit.json").write_text(ErrorModel.shipped("sh_mixture").to_json())
    monkeypatch.chdir(tmp_path)
    cfg = replace(tiny_config(), data=DataConfig(clean_prob=0.0, error_model="em/fit.json"))
    res = train(cfg, train_samples=synthetic_samples(100, seed=3), progress=False, log=lambda s: None, ctx=Dist(),
                val_sets=validation_sets(synthetic_samples(20, seed=4), None))
    run = save_training_outputs(res, tmp_path / "run.pt")
    (tmp_path / "elsewhere").mkdir()
    monkeypatch.chdir(tmp_path / "elsewhere")
    assert main(["train", "--config", str(run), "--out", "again.pt"]) == 2
    err = capsys.readouterr().err
    assert "error model em/fit.json: cannot read" in err
    assert f"{run} stores the fit it trained with: add --error-model {run}" in err


def _interrupt_at(monkeypatch, call: int) -> None:
    """Make the training loop's ``call``-th batch raise KeyboardInterrupt (Ctrl-C in the middle of a run)."""
    import lifter.train as lt

    real, calls = lt.make_batch, []

    def stopping(*a, **kw):
        calls.append(1)
        if len(calls) == call:
            raise KeyboardInterrupt
        return real(*a, **kw)

    monkeypatch.setattr(lt, "make_batch", stopping)


def test_a_run_stopped_with_ctrl_c_keeps_its_weights_so_far(monkeypatch):
    """A researcher trial: Ctrl-C in a long CPU run wrote nothing. One process returns the weights so far, said
    interrupted, with a validation point for them; under DDP it re-raises (not tested here: one process)."""
    _interrupt_at(monkeypatch, 4)
    res = train(replace(tiny_config(), schedule=ScheduleConfig(epochs=3, eval_every=1000)),
                train_samples=synthetic_samples(400, seed=3), progress=False, log=lambda s: None, ctx=Dist(),
                val_sets=validation_sets(synthetic_samples(20, seed=4), None))
    assert res.interrupted and res.steps == 3 and res.curve[-1]["step"] == 3
    assert all(torch.isfinite(p).all() for p in res.net.parameters())
    # a real Ctrl-C (SIGINT) during the 4th step lets that step end whole, then stops (a review: stopped inside the
    # optimizer's update, some tensors had moved and others not); the previous handler is back afterwards
    import signal

    import lifter.train as lt

    monkeypatch.undo()
    real, calls = lt.make_batch, []

    def signalling(*a, **kw):
        calls.append(1)
        if len(calls) == 4:
            os.kill(os.getpid(), signal.SIGINT)
        return real(*a, **kw)

    monkeypatch.setattr(lt, "make_batch", signalling)
    before = signal.getsignal(signal.SIGINT)
    res = train(replace(tiny_config(), schedule=ScheduleConfig(epochs=3, eval_every=1000)),
                train_samples=synthetic_samples(400, seed=3), progress=False, log=lambda s: None, ctx=Dist(),
                val_sets=validation_sets(synthetic_samples(20, seed=4), None))
    assert res.interrupted and res.steps == 4 and len(calls) == 4
    assert signal.getsignal(signal.SIGINT) is before


def _sigint_at(monkeypatch, call: int) -> None:
    """A real Ctrl-C (SIGINT) during the training loop's ``call``-th batch: that step ends whole, then the run stops."""
    import signal

    import lifter.train as lt

    real, calls = lt.make_batch, []

    def signalling(*a, **kw):
        calls.append(1)
        if len(calls) == call:
            os.kill(os.getpid(), signal.SIGINT)
        return real(*a, **kw)

    monkeypatch.setattr(lt, "make_batch", signalling)


def _resumable_config() -> TrainConfig:
    """Every part of the state a resume must carry is used: dropout, weight average, synthetic noise, real
    detections, flips, a schedule that wraps the sample order twice."""
    c = tiny_config()
    return replace(c, data=replace(c.data, clean_prob=0.3, real_prob=0.3),
                   optim=replace(c.optim, ema_decay=0.99, batch_size=48),
                   schedule=ScheduleConfig(epochs=2.5, eval_every=4))


def test_a_run_stopped_with_ctrl_c_resumes_to_the_weights_of_the_run_never_stopped(monkeypatch, tmp_path):
    """A researcher trial: a run stopped with Ctrl-C could only restart its schedule (--init). Its resume state,
    written and read back, goes on to the same weights, average and curve as the run never stopped, bit for bit."""
    from lifter.resume import ResumeState

    samples, vs = synthetic_samples(300, seed=3), validation_sets(synthetic_samples(20, seed=4), None)
    real = samples.keypoints_2d + np.random.default_rng(5).normal(0, 4, samples.keypoints_2d.shape)
    cfg = _resumable_config()
    quiet = dict(train_samples=samples, real_keypoints_2d=real, val_sets=vs, progress=False, log=lambda s: None,
                 ctx=Dist())
    whole = train(cfg, **quiet)
    assert not whole.interrupted and whole.resume is None and whole.steps == 16
    _sigint_at(monkeypatch, 7)
    stopped = train(cfg, **quiet)
    monkeypatch.undo()
    assert stopped.interrupted and stopped.steps == 7 and stopped.resume is not None
    path = stopped.resume.save(tmp_path / "run.resume.pt")
    state = ResumeState.load(path)
    assert state.step == 7 and state.position == 7 * 48 - 288  # (the sample order wrapped after 6 steps)
    logs: list[str] = []
    resumed = train(TrainConfig.from_dict(state.train_config), **{**quiet, "log": logs.append}, resume=state)
    assert any(line.startswith("resuming at step 7 of 16") for line in logs), logs
    assert resumed.steps == 16 and not resumed.interrupted
    for (k, a), b in zip(whole.net.state_dict().items(), resumed.net.state_dict().values()):
        assert torch.equal(a, b), k
    strip = [{k: v for k, v in c.items() if k != "minutes"} for c in whole.curve]
    assert [{k: v for k, v in c.items() if k != "minutes"} for c in resumed.curve] == strip
    assert resumed.error_model is not None and resumed.error_model.to_dict() == whole.error_model.to_dict()
    # stopped again after resuming, and resumed again: still the run never stopped
    _sigint_at(monkeypatch, 3)
    again = train(TrainConfig.from_dict(state.train_config), **quiet, resume=state)
    monkeypatch.undo()
    assert again.steps == 10 and again.resume is not None and again.resume.device == "cpu"
    last = train(TrainConfig.from_dict(state.train_config), **quiet, resume=again.resume)
    for (k, a), b in zip(whole.net.state_dict().items(), last.net.state_dict().values()):
        assert torch.equal(a, b), k


def test_a_resume_is_refused_where_it_could_not_go_on_as_the_run_would(monkeypatch, tmp_path):
    from lifter.resume import ResumeState

    samples, vs = synthetic_samples(300, seed=3), validation_sets(synthetic_samples(20, seed=4), None)
    real = samples.keypoints_2d + 3.0
    cfg = _resumable_config()
    quiet = dict(real_keypoints_2d=real, val_sets=vs, progress=False, log=lambda s: None, ctx=Dist())
    _sigint_at(monkeypatch, 3)
    state = train(cfg, train_samples=samples, **quiet).resume
    monkeypatch.undo()
    assert state is not None
    with pytest.raises(PoseLifterError, match=r"differs in optim\.lr: resume with the state's config"):
        train(replace(cfg, optim=replace(cfg.optim, lr=1e-3)), train_samples=samples, **quiet, resume=state)
    other = synthetic_samples(300, seed=9)
    with pytest.raises(PoseLifterError, match="the training data is not the stopped run's"):
        train(cfg, train_samples=other, **{**quiet, "real_keypoints_2d": other.keypoints_2d + 3.0}, resume=state)
    with pytest.raises(PoseLifterError, match="resumed on one process"):
        train(cfg, train_samples=samples, **{**quiet, "ctx": Dist(rank=0, world=2)}, resume=state)
    # (a review: a state from the GPU failed on the CPU with a raw generator-state error, after the data was read)
    with pytest.raises(PoseLifterError, match="stopped training on the CUDA, and this process trains on the CPU"):
        train(cfg, train_samples=samples, **quiet, resume=replace(state, device="cuda"))
    # a second Ctrl-C inside a step leaves no resume state (the weights may be half updated)
    _interrupt_at(monkeypatch, 3)
    assert train(cfg, train_samples=samples, **quiet).resume is None
    monkeypatch.undo()
    # and one while the state is taken (~0.1 s after the first) keeps the weights (a review: they were lost)
    import lifter.train as lt

    def stop(*a, **k):
        raise KeyboardInterrupt

    _sigint_at(monkeypatch, 3)
    monkeypatch.setattr(lt, "_resume_state", stop)
    logs: list[str] = []
    res = train(cfg, train_samples=samples, **{**quiet, "log": logs.append})
    monkeypatch.undo()
    assert res.interrupted and res.steps == 3 and res.resume is None
    assert any("a second Ctrl-C while the run's state was taken" in line for line in logs)
    # files: damaged, a checkpoint given for one, another file
    path = state.save(tmp_path / "run.resume.pt")
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    (tmp_path / "bad.resume.pt").write_bytes(bytes(data))
    with pytest.raises(PoseLifterError, match="damaged|not a poselifter resume file"):
        ResumeState.load(tmp_path / "bad.resume.pt")
    ck = _tiny_lifter(seed=1).save(tmp_path / "weights.pt")
    with pytest.raises(PoseLifterError, match="a checkpoint: --init starts a new run from its weights"):
        ResumeState.load(ck)
    (tmp_path / "notes.txt").write_text("hello")
    with pytest.raises(PoseLifterError, match="not a poselifter resume file"):
        ResumeState.load(tmp_path / "notes.txt")
    with pytest.raises(PoseLifterError, match="no such file"):
        ResumeState.load(tmp_path / "missing.resume.pt")
    # and the other way round (a review: --init or --config RUN.resume.pt said only 'missing format tag')
    with pytest.raises(PoseLifterError, match="is a stopped training run's resume state, not a checkpoint: poselifter "
                                              "train --resume"):
        Lifter.load(str(path))


@requires_h36m
def test_cli_train_stopped_with_ctrl_c_writes_beside_out_not_over_it(tmp_path, monkeypatch, capsys):
    from lifter.checkpoint import load_checkpoint
    from lifter.cli import main

    out = tmp_path / "run.pt"
    out.write_bytes(b"an earlier run")  # (Ctrl-C also stops a run started with a wrong option: never over --out)
    _interrupt_at(monkeypatch, 3)
    quick = ["--width", "32", "--max-frames-per-sequence", "4", "--val-stride", "400", "--threads", "1",
             "--no-progress"]
    assert main(["train", "--out", str(out), *quick]) == 130
    err = capsys.readouterr().err
    partial = tmp_path / "run.interrupted.pt"
    assert ("poselifter train: interrupted at step 2 (" in err and f"the weights so far are in {partial} (meta "
            f"'interrupted'; not {out}); --init {partial} starts a new run from them" in err), err
    assert out.read_bytes() == b"an earlier run"
    ck = load_checkpoint(partial)
    assert ck.meta["interrupted"] is True and ck.meta["steps"] == 2 and partial.with_suffix(".curve.json").is_file()
    _interrupt_at(monkeypatch, 1)
    assert main(["train", "--out", str(tmp_path / "none.pt"), *quick]) == 130
    assert "interrupted before the first step: nothing written" in capsys.readouterr().err
    assert not list(tmp_path.glob("none*"))
    # Ctrl-C while the outputs are written says which are written whole (a security trial was told "no checkpoint
    # was written" with the new checkpoint on disk)
    monkeypatch.undo()
    import lifter.plots

    def stop(*a, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(lifter.plots, "plot_learning_curve", stop)
    done = tmp_path / "done.pt"
    with pytest.raises(SystemExit) as exc:
        main(["train", "--out", str(done), "--max-minutes", "0.01", *quick])
    err = capsys.readouterr().err
    assert exc.value.code == 130 and (f"interrupted while writing the run's outputs; written whole: {done}, "
                                      f"{done.with_suffix('.curve.json')} (the others were not written)") in err, err


@requires_h36m
def test_cli_train_resumes_a_run_stopped_with_ctrl_c_to_the_run_never_stopped(tmp_path, monkeypatch, capsys):
    from lifter.checkpoint import load_checkpoint
    from lifter.cli import main

    quick = ["--width", "32", "--max-frames-per-sequence", "4", "--val-stride", "400", "--epochs", "1",
             "--ema-decay", "0.9", "--clean-prob", "0.5", "--threads", "1", "--no-progress", "--fp32-weights"]
    whole = tmp_path / "whole.pt"
    assert main(["train", "--out", str(whole), *quick]) == 0
    capsys.readouterr()
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    monkeypatch.chdir(tmp_path / "a")  # (a review: a relative --out was stored as typed, so resuming in another folder
    out = tmp_path / "a" / "runs" / "run.pt"  # wrote the run there)
    _sigint_at(monkeypatch, 2)
    monkeypatch.setattr(sys, "argv", ["poselifter", "train", "--out", "runs/run.pt", *quick])
    assert main(["train", "--out", "runs/run.pt", *quick]) == 130
    monkeypatch.undo()
    err = capsys.readouterr().err
    state = out.with_name("run.resume.pt")
    assert ("interrupted at step 2 (" in err and "poselifter train --resume runs/run.resume.pt goes on where it "
            "stopped" in err and not out.exists()), err
    # options that would change the run are refused, by name; a checkpoint is not a resume file
    assert main(["train", "--resume", str(state), "--lr", "0.1", "--config", str(whole)]) == 2
    assert "--resume goes on with the stopped run's own config: drop --config, --lr (" in capsys.readouterr().err
    assert main(["train", "--resume", str(out.with_name("run.interrupted.pt"))]) == 2
    assert "(a checkpoint: --init starts a new run from its weights)" in capsys.readouterr().err
    monkeypatch.chdir(tmp_path / "b")
    assert main(["train", "--resume", str(state), "--no-progress"]) == 0  # (--out and --threads: the run's own)
    err = capsys.readouterr().err
    assert f"resuming {state} at step 2" in err and "note: 1 torch thread(s), as the run had" in err, err
    assert f"note: {state} is the state the run went on from; not needed now" in err
    assert not list((tmp_path / "b").iterdir())
    a, b = load_checkpoint(whole), load_checkpoint(out)
    assert b.meta["resumed"]["step"] == 2 and b.meta["steps"] == a.meta["steps"] > 2
    assert b.train_config == a.train_config
    for (k, x), y in zip(a.net.state_dict().items(), b.net.state_dict().values()):
        assert torch.equal(x, y), k
    assert b.meta["resumed"]["run"]["command"] == "poselifter train --out runs/run.pt " + " ".join(quick)
    # a later run of the same --out stopped inside a step (no state of its own) is told the state beside it is the
    # earlier stop's; a Ctrl-C while the state is written says the weights are kept
    _interrupt_at(monkeypatch, 2)
    assert main(["train", "--out", str(out), *quick]) == 130
    assert f"{state} beside it is an earlier stop's state" in capsys.readouterr().err
    monkeypatch.undo()
    from lifter.resume import ResumeState

    def stop(*a, **k):
        raise KeyboardInterrupt

    _sigint_at(monkeypatch, 2)
    monkeypatch.setattr(ResumeState, "save", stop)
    with pytest.raises(SystemExit):
        main(["train", "--out", str(tmp_path / "c.pt"), *quick])
    err = capsys.readouterr().err
    assert (f"while its resume state was written: the weights so far are in {tmp_path / 'c.interrupted.pt'}" in err
            and (tmp_path / "c.interrupted.pt").is_file()), err


def test_fine_tuning_keeps_config_and_initial_network_and_ema_averages():
    train_s, val_s = synthetic_samples(400, seed=3), synthetic_samples(50, seed=4)
    vs = validation_sets(val_s, None)
    quiet = dict(val_sets=vs, progress=False, log=lambda s: None, ctx=Dist())
    base = train(tiny_config(), train_samples=train_s, **quiet)
    before = {k: v.clone() for k, v in base.net.state_dict().items()}
    cfg = replace(tiny_config(), model=ModelConfig(width=32), optim=OptimConfig(batch_size=64, ema_decay=0.5))
    res = train(cfg, train_samples=train_s, init=(base.net, base.codec), **quiet)
    assert res.net.config == base.net.config and res.config.model == base.net.config and res.net is not base.net
    for k, v in base.net.state_dict().items():
        torch.testing.assert_close(v, before[k])  # the initial network is not modified
    np.testing.assert_array_equal(res.codec.target_mean, base.codec.target_mean)  # nor its codec
    # one step with EMA decay 0.5 from `base` is 0.1 of the initial and 0.9 of the trained weights (the decay's
    # warm-up: (1 + 0) / (10 + 0) at the first update)
    one = replace(tiny_config(), augment=AugmentConfig(flip_prob=0.0),
                  optim=OptimConfig(batch_size=len(train_s), ema_decay=0.5))
    plain = train(replace(one, optim=replace(one.optim, ema_decay=None)), train_samples=train_s,
                  init=(base.net, base.codec), **quiet).net
    avg = train(one, train_samples=train_s, init=(base.net, base.codec), **quiet).net
    torch.testing.assert_close(avg.stem.weight, 0.1 * base.net.stem.weight + 0.9 * plain.stem.weight)


def test_fine_tuning_a_mirror_net_sets_its_output_mirror_from_the_codec():
    train_s, val_s = synthetic_samples(200, seed=5), synthetic_samples(20, seed=6)
    cfg = replace(tiny_config(symmetry="mirror"), optim=OptimConfig(batch_size=200, lr=1e-9),
                  augment=AugmentConfig(flip_prob=0.0))
    codec = PoseCodec(cfg.model, target_mean=np.linspace(-50, 50, 49), target_std=np.linspace(20, 90, 49))
    net = PoseLifterNet(cfg.model)  # its output mirror is that of mean 0 / std 1, not the codec's
    res = train(cfg, train_samples=train_s, init=(net, codec), val_sets=validation_sets(val_s, None), progress=False,
                log=lambda s: None, ctx=Dist())
    _, scale, offset = output_mirror(codec.target_mean, codec.target_std)
    torch.testing.assert_close(res.net.out_offset, torch.from_numpy(offset))
    torch.testing.assert_close(res.net.out_scale, torch.from_numpy(scale))


@pytest.mark.parametrize("steps", [3, 120])
def test_a_loss_that_stops_being_finite_ends_training_with_its_step(steps):
    """The loss is read back from the device only every FINITE_CHECK_EVERY steps and at the end: a short run and
    a long one both stop with a FloatingPointError naming the step, not with a NaN checkpoint."""
    from lifter.train import FINITE_CHECK_EVERY

    train_s, val_s = synthetic_samples(64 * steps, seed=7), synthetic_samples(20, seed=8)
    cfg = replace(tiny_config(), optim=OptimConfig(batch_size=64, lr=1e30))  # diverges in a few steps
    with pytest.raises(FloatingPointError, match=r"the training loss became non-finite by step \d+ \((nan|inf)\)"):
        train(cfg, train_samples=train_s, val_sets=validation_sets(val_s, None), progress=False, log=lambda s: None,
              ctx=Dist())
    assert FINITE_CHECK_EVERY < 120


def test_real_detections_are_required_and_aligned():
    train_s = synthetic_samples(100)
    cfg = replace(tiny_config(), data=DataConfig(clean_prob=0.5, real_prob=0.5))
    with pytest.raises(ValueError, match="real detections"):
        train(cfg, train_samples=train_s, val_sets=validation_sets(train_s, None), progress=False, ctx=Dist())
    with pytest.raises(ValueError, match="one row per training sample"):
        train(cfg, train_samples=train_s, real_keypoints_2d=np.zeros((3, 17, 2)),
              val_sets=validation_sets(train_s, None),
              progress=False, ctx=Dist())


def test_match_scale_removes_a_detectors_size_bias_and_nothing_else():
    from lifter.detections import match_scale
    from lifter.normalization import location_and_scale

    rng = np.random.default_rng(3)
    gt = synthetic_samples(200).keypoints_2d.astype(np.float64)
    shape_noise = rng.normal(0, 3.0, gt.shape)
    u = gt.mean(axis=1, keepdims=True)
    det = u + 0.97 * (gt - u) + shape_noise  # a detector 3 % small, with shape errors
    det[5] = np.nan  # a frame without a detection
    out, r = match_scale(det, gt)
    assert r == pytest.approx(0.97, abs=0.005)
    ok = np.isfinite(det).all(axis=(1, 2))
    assert np.isnan(out[5]).all() and np.isfinite(out[ok]).all()
    (u0, s0), (u1, s1) = location_and_scale(det[ok]), location_and_scale(out[ok])
    np.testing.assert_allclose(u1, u0, atol=1e-9)  # the 2D location is kept
    np.testing.assert_allclose(s1, s0 / r, rtol=1e-12)  # every pose scaled by the one factor
    assert np.median(s1 / location_and_scale(gt[ok])[1]) == pytest.approx(1.0, abs=1e-9)
    with pytest.raises(ValueError, match="must both be"):
        match_scale(det[:3], gt)
    with pytest.raises(ValueError, match="no sample has both"):
        match_scale(np.full_like(gt, np.nan), gt)
    with pytest.raises(ValueError, match="zero size"):
        match_scale(det, np.zeros_like(gt))
    with pytest.raises(ValueError, match="real_prob is 0"):
        DataConfig(real_rescale=True)
    with pytest.raises(ValueError, match="must be true or false"):
        DataConfig(clean_prob=0.5, real_prob=0.5, real_rescale="false")  # type: ignore[arg-type]
    for section, key in (("augment", "zoom"), ("data", "real_rescale"), ("data", "noise_outliers")):
        with pytest.raises(ValueError, match=f"{section}.{key} must be a JSON boolean .*'false' \\(a string\\)"):
            TrainConfig.from_dict({section: {key: "false"}})
    assert TrainConfig.from_dict({"augment": {"zoom": True}}).augment.zoom is True
    with pytest.raises(ValueError, match=r"unknown keys \['real_rescale', 'width'\].*inside their section's object: "
                                         r'"data", "model"'):
        TrainConfig.from_dict({"real_rescale": True, "width": 64})


def test_training_with_real_rescale_trains_on_the_rescaled_detections(monkeypatch):
    import lifter.train as T

    train_s = synthetic_samples(128)
    gt = train_s.keypoints_2d.astype(np.float64)
    u = gt.mean(axis=1, keepdims=True)
    real = u + 0.95 * (gt - u)
    seen: list[np.ndarray] = []
    real_samples_to_tensors = T.samples_to_tensors

    def spy(samples, real_keypoints_2d=None):
        seen.append(real_keypoints_2d)
        return real_samples_to_tensors(samples, real_keypoints_2d)

    monkeypatch.setattr(T, "samples_to_tensors", spy)
    logs: list[str] = []
    for rescale in (False, True):
        cfg = replace(tiny_config(), data=DataConfig(clean_prob=0.5, real_prob=0.5, real_rescale=rescale),
                      schedule=ScheduleConfig(epochs=1, eval_every=1000, max_minutes=None))
        train(cfg, train_samples=train_s, real_keypoints_2d=real, val_sets=validation_sets(train_s, None),
              progress=False, ctx=Dist(), log=logs.append)
    given = [r for r in seen if r is not None]  # (validation_sets converts its samples without detections)
    assert len(given) == 2
    np.testing.assert_allclose(given[0], real)
    np.testing.assert_allclose(given[1], gt, atol=1e-6)  # a pure 5 % shrink is undone exactly
    assert any("rescaled by 1/0.9500" in line and "95.00 % of" in line for line in logs)



def _tiny_lifter(*, seed: int, symmetry: str = "none", flip_test: bool = False, conditioning: str = "none",
                 **kw: object) -> Lifter:
    """An untrained network with a codec of nontrivial target statistics (so destandardizing matters)."""
    torch.manual_seed(seed)
    cfg = ModelConfig(width=32, dropout=0.0, symmetry=symmetry, conditioning=conditioning)  # type: ignore[arg-type]
    rng = np.random.default_rng(seed)
    codec = PoseCodec(cfg, target_mean=rng.uniform(-80, 80, 49) + np.r_[np.zeros(48), 4000.0],
                      target_std=rng.uniform(30, 90, 49))
    return Lifter(PoseLifterNet(cfg), codec, name=f"tiny{seed}", flip_test=flip_test, **kw)  # type: ignore[arg-type]


def test_teacher_targets_are_what_the_teacher_lifts():
    """The distillation targets are the teacher's own lift, decoded through the student's codec: the average of its
    detected networks (flip test where a network has it on) for detected samples, its clean network for clean
    ones; relative pose in mm and the root depth (same 2D root ray)."""
    teacher = _tiny_lifter(seed=1, flip_test=True, clean=_tiny_lifter(seed=2, flip_test=True),
                           ensemble=[_tiny_lifter(seed=3, symmetry="mirror")])
    s = synthetic_samples(40, seed=7)
    T = samples_to_tensors(s)
    clean = torch.arange(40) % 3 == 0
    batch = {"kp": T["kp"], "pp": T["pp"], "focal": T["focal"], "rel": T["rel"], "depth": T["depth"], "clean": clean}
    raw = teacher_targets(teacher, batch)
    codec = _tiny_lifter(seed=9).codec  # any codec with the same features and depth parameter decodes them
    enc = codec.encode(batch["kp"].double(), principal_point=batch["pp"].double(), focal=batch["focal"].double())
    rel, depth = codec.split(raw.double(), enc)
    for source, rows in (("detected", ~clean), ("clean", clean)):
        ref = teacher.lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point, source=source)
        np.testing.assert_allclose(rel.numpy()[rows.numpy()], ref.relative[rows.numpy()], atol=2e-3)
        np.testing.assert_allclose(depth.numpy()[rows.numpy()], ref.root[rows.numpy(), 2], rtol=2e-6)
    # without a separate clean network its networks answer every sample (a network conditioned on the source is
    # told each sample's)
    plain = _tiny_lifter(seed=1, flip_test=True, ensemble=[_tiny_lifter(seed=3, symmetry="mirror")])
    np.testing.assert_allclose(teacher_targets(plain, batch).numpy()[~clean.numpy()], raw.numpy()[~clean.numpy()],
                               rtol=1e-6, atol=1e-4)
    torch.testing.assert_close(teacher_targets(plain, batch), teacher_targets(plain, {**batch, "clean": ~clean}))
    told = _tiny_lifter(seed=6, conditioning="source")
    raw = teacher_targets(told, batch).double()
    assert not torch.allclose(raw, teacher_targets(told, {**batch, "clean": ~clean}).double())
    for source, rows in (("detected", ~clean), ("clean", clean)):
        ref = told.lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point, source=source)
        np.testing.assert_allclose(codec.split(raw, enc)[1].numpy()[rows.numpy()], ref.root[rows.numpy(), 2], rtol=2e-6)


def test_teacher_targets_stay_on_the_batchs_device_and_read_nothing_back():
    """On the meta device (no data, and any read back to the host raises), the targets come out on the batch's
    device: what a GPU run needs (the folded inference path writes on the features' device)."""
    import copy

    from lifter.train import teacher_networks

    teacher = copy.deepcopy(_tiny_lifter(seed=1, flip_test=True, clean=_tiny_lifter(seed=2, flip_test=True),
                                         ensemble=[_tiny_lifter(seed=3, symmetry="mirror")]))
    for m in teacher_networks(teacher):
        m.net.to("meta")
    T = samples_to_tensors(synthetic_samples(8))
    batch = {k: v.to("meta") for k, v in T.items()} | {"clean": (torch.arange(8) % 2 == 0).to("meta")}
    for clean_samples in (True, False):
        out = teacher_targets(teacher, batch, clean_samples=clean_samples)
        assert out.device.type == "meta" and out.shape == (8, 49)


def test_distillation_weight_splits_the_loss_and_training_follows_the_teacher():
    s = synthetic_samples(512, seed=8)
    T = samples_to_tensors(s)
    batch = {"kp": T["kp"], "pp": T["pp"], "focal": T["focal"], "rel": T["rel"], "depth": T["depth"],
             "clean": torch.zeros(512, dtype=torch.bool)}
    student = _tiny_lifter(seed=4)
    teacher = _tiny_lifter(seed=5)
    cfg = tiny_config()
    gt_loss = batch_loss(student.net, student.codec, batch, cfg)
    w = {x: batch_loss(student.net, student.codec, batch, replace(cfg, optim=replace(cfg.optim, distill_weight=x)),
                       teacher=teacher) for x in (0.0, 0.3, 1.0)}
    torch.testing.assert_close(w[0.0], gt_loss)
    assert abs((w[1.0] - gt_loss).item()) > 1.0  # the teacher's outputs are not the ground truth
    torch.testing.assert_close(w[0.3], 0.7 * w[0.0] + 0.3 * w[1.0])
    # trained at weight 1 towards a teacher that places every root 600 mm farther than the truth, the student
    # learns the teacher's depth, not the truth; at weight 0 it learns the truth
    base = train(replace(tiny_config(), optim=OptimConfig(batch_size=128, lr=3e-3),
                         schedule=ScheduleConfig(epochs=20, eval_every=10_000)),
                 train_samples=s, val_sets=validation_sets(s, None), progress=False, log=lambda _: None, ctx=Dist())
    far = Lifter(base.net, PoseCodec(base.codec.config, target_mean=base.codec.target_mean,
                                     target_std=base.codec.target_std), name="far")
    enc = base.codec.encode(T["kp"], principal_point=T["pp"], focal=T["focal"])
    far.codec.target_mean = far.codec.target_mean.copy()
    far.codec.target_mean[-1] += float(base.codec.depth_parameter(torch.tensor(600.0), enc).mean())
    depth = {}
    for weight in (0.0, 1.0):
        cfg = replace(tiny_config(), teacher="far (given)",
                      optim=OptimConfig(batch_size=128, lr=3e-3, distill_weight=weight),
                      schedule=ScheduleConfig(epochs=10, eval_every=10_000))
        res = train(cfg, train_samples=s, init=(base.net, base.codec), teacher=far, val_sets=validation_sets(s, None),
                    progress=False, log=lambda _: None, ctx=Dist())
        lifted = Lifter(res.net, res.codec).lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point)
        depth[weight] = float(np.mean(lifted.root[:, 2] - s.root[:, 2]))
    assert abs(depth[0.0]) < 150 and depth[1.0] > 400, depth


def test_a_teacher_reading_other_features_is_refused():
    s = synthetic_samples(64, seed=9)
    pixel = Lifter(PoseLifterNet(ModelConfig(width=16, input_space="pixel", depth_target="canonical")),
                   PoseCodec(ModelConfig(width=16, input_space="pixel", depth_target="canonical")), name="pixel")
    with pytest.raises(PoseLifterError,
                       match="teacher network 'pixel'.*input_space 'pixel' .trained: 'camera'; --input"):
        train(tiny_config(), train_samples=s, teacher=pixel, val_sets=validation_sets(s, None), progress=False,
              log=lambda _: None, ctx=Dist())
    # a teacher that learned undistorted 2D is not given Human3.6M's distorted 2D (the run's data.lens)
    pinhole = _tiny_lifter(seed=1, conditioning="source", train_config={"data": {"lens": "pinhole"}})
    with pytest.raises(PoseLifterError, match=r"lens 'pinhole' \(trained: 'h36m'; --lens\)"):
        train(tiny_config(), train_samples=s, teacher=pinhole, val_sets=validation_sets(s, None), progress=False,
              log=lambda _: None, ctx=Dist())
    with pytest.raises(PoseLifterError, match="distill_weight must be a probability"):
        OptimConfig(distill_weight=1.5)


def test_zoom_is_refused_where_the_input_space_undoes_it():
    """Zoom augmentation scales 2D, principal point and focal together: the reference-camera codec maps that back
    exactly, so a camera-space run with zoom would spend its time on nothing; the error names the fix. Pixel-space
    runs take it."""
    train_s = synthetic_samples(64, seed=9)
    zoomed = replace(tiny_config(), augment=AugmentConfig(zoom=True),
                     schedule=ScheduleConfig(epochs=1, eval_every=1000, max_minutes=None))
    assert zoomed.model.input_space == "camera"
    with pytest.raises(PoseLifterError, match="drop --zoom, or train a pixel-space model"):
        train(zoomed, train_samples=train_s, val_sets=validation_sets(train_s, None), progress=False, ctx=Dist(),
              log=lambda _: None)
    pixel = replace(zoomed, model=replace(zoomed.model, input_space="pixel", depth_target="canonical"))
    result = train(pixel, train_samples=train_s, val_sets=validation_sets(train_s, None), progress=False, ctx=Dist(),
                   log=lambda _: None)
    assert result.net.config.input_space == "pixel" and result.config.augment.zoom

# -- CLI -------------------------------------------------------------------------------------------


@requires_h36m
def test_cli_train_evaluate_and_repeat_from_the_stored_config(tmp_path, capsys):
    from lifter.checkpoint import load_checkpoint, sha256_file
    from lifter.cli import main

    out = tmp_path / "tiny.pt"
    args = ["--width", "64", "--epochs", "1", "--batch-size", "64", "--max-frames-per-sequence", "4",
            "--train-stride", "5", "--val-stride", "200", "--eval-every", "20", "--threads", "1", "--clean-prob", "0.5",
            "--real-prob", "0.25", "--noise-level-min", "0", "--noise-level-max", "2", "--no-progress"]
    assert main(["train", "--out", str(out), *args]) == 0
    assert out.is_file() and out.with_suffix(".curve.json").is_file() and out.with_suffix(".curve.png").is_file()
    ck = load_checkpoint(out)
    cfg = TrainConfig.from_dict(ck.train_config)
    assert cfg.model.width == 64 and cfg.data.real_prob == 0.25 and cfg.data.noise_level_max == 2.0
    assert {"val_mpjpe_clean", "val_mpjpe_detected"} <= set(ck.meta["final_val"])
    # the stored config repeats the run; options given on top of it override it
    capsys.readouterr()
    assert main(["train", "--config", str(out), "--print-config", "--epochs", "3"]) == 0
    again = TrainConfig.from_dict(__import__("json").loads(capsys.readouterr().out))
    assert again == replace(cfg, schedule=replace(cfg.schedule, epochs=3.0))
    cfg_flip = Lifter.load(str(out)).network_rows(None) == 2  # (the JSON says what the lift did)
    assert main(["evaluate", f"tiny={out}", "--stride", "200", "--max-frames-per-sequence", "3", "--analytic-root",
                 "--json", str(tmp_path / "ev.json")]) == 0
    captured = capsys.readouterr()
    text = captured.out
    assert "MPJPE" in text and "analytic" in text and "Discussion 1" in text and "source='clean'" in text
    # a cut run says so, and how many sequences and cameras it read (a researcher's trial: it printed a full run's
    # header, and "4 cameras" and the missing S9 sequence were fixed text)
    assert "59 sequences of 60, 4 cameras" in text and "ONLY THE FIRST 3 FRAMES OF EACH SEQUENCE" in text
    rows = __import__("json").loads((tmp_path / "ev.json").read_text())  # each row says how it was measured
    assert [r["root"] for r in rows] == ["learned", "analytic"] and all(
        r["protocol"] == 1 and r["stride"] == 200 and r["inputs"] == "gt" and r["source"] == "clean"
        and r["test_subjects"] == [9, 11] and r["flip_test"] is cfg_flip and r["units"].startswith("mm")
        and r["max_frames_per_sequence"] == 3 and r["sequences"] == 59 and r["missing_sequences"] == ["S9/Discussion 1"]
        and len(r["cameras"]) == 4 and len(r["pck_curve_thresholds_mm"]) == len(r["pck_curve"])
        and r["model_info"]["networks"][0]["sha256"] == sha256_file(out)
        for r in rows), rows
    assert main(["evaluate", f"tiny={out}", "--protocol", "2", "--stride", "400", "--max-frames-per-sequence", "2",
                 "--no-flip-test", "--per-action", "--json", str(tmp_path / "ev2.json")]) == 0
    captured = capsys.readouterr()
    assert "tiny: trained on Protocol 1's subjects (S1, S5, S6, S7, S8), not Protocol 2's" in captured.err
    assert "30 sequences, 4 cameras" in captured.out and "Discussion 1" not in captured.out  # (S9 is not tested)
    heads = next(line for line in captured.out.splitlines() if line.startswith("model") and "Avg" in line).split()
    assert len(heads) == len(set(heads)) == 17 and "SitDn" in heads  # (cut to 6, Sitting and SittingDown read alike)
    assert all(r["flip_test"] is False and not any(n["flip_test"] for n in r["model_info"]["networks"])
               for r in __import__("json").loads((tmp_path / "ev2.json").read_text()))
    assert "lifting (" not in captured.err  # stderr is not a terminal here: no progress bar in logs (user trial)
    # the focal sweep's JSON: rows as above, each with its model and numeric factor (a researcher trial met a dict
    # keyed by model, the factor only in the label "x0.5")
    assert main(["evaluate", f"tiny={out}", "--focal-scales", "0.5,2", "--stride", "400", "--max-frames-per-sequence",
                 "2", "--json", str(tmp_path / "ev3.json")]) == 0
    sweep = __import__("json").loads((tmp_path / "ev3.json").read_text())
    assert [(r["model"], r["focal_scale"], r["label"]) for r in sweep] == [("tiny", 0.5, "x0.5"), ("tiny", 2.0, "x2")]
    assert all(isinstance(r["flip_test"], bool) and r["flip_test_detail"].endswith("(tiny)") for r in sweep)
    assert main(["train", "--out", str(out), "--clean-prob", "0", "--real-prob", "0.5", "--train-stride", "7"]) == 2
    assert "multiple of 5" in capsys.readouterr().err  # detections exist every 5th frame only
    # a fine-tune records the weights it started from; repeating it from its own result, or from other weights, says so
    ft = tmp_path / "ft.pt"
    quick = ["--max-minutes", "0.002", "--max-frames-per-sequence", "4", "--val-stride", "200", "--threads", "1"]
    assert main(["train", "--out", str(ft), "--init", str(out), *quick, "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert f"fine-tuning from --init {out}" in err and "not repeat" not in err
    assert load_checkpoint(ft).meta["init_sha256"] == sha256_file(out)
    taught = tmp_path / "taught.pt"
    assert main(["train", "--out", str(taught), "--init", str(out), "--teacher", str(ft), "--distill-weight", "0.7",
                 *quick, "--no-progress"]) == 0
    assert "distilling 'ft' at weight 0.7 (its detected network, for every sample)" in capsys.readouterr().out
    assert load_checkpoint(taught).meta["teacher_sha256"] == sha256_file(ft)
    assert TrainConfig.from_dict(load_checkpoint(taught).train_config).teacher == str(ft)
    ft_bytes = ft.read_bytes()
    ft.write_bytes(out.read_bytes())  # the teacher file now holds other weights: repeating says so
    assert main(["train", "--config", str(taught), "--out", str(tmp_path / "t2.pt"), *quick]) == 0
    assert f"is not what {taught} distilled" in capsys.readouterr().err
    ft.unlink()  # and a teacher that is gone names the option and the run it came from
    assert main(["train", "--config", str(taught), "--out", str(tmp_path / "t3.pt"), *quick]) == 2
    assert f"--teacher {ft} (from the --config run {taught}" in capsys.readouterr().err
    ft.write_bytes(ft_bytes)
    assert main(["train", "--config", str(ft), "--init", str(ft), "--out", str(tmp_path / "b.pt"), *quick]) == 0
    assert "is the --config checkpoint itself" in capsys.readouterr().err
    assert main(["train", "--config", str(ft), "--out", str(tmp_path / "c.pt"), *quick]) == 0
    assert "not repeat" not in capsys.readouterr().err  # the same init weights: a repeat
    out.write_bytes((tmp_path / "b.pt").read_bytes())  # the init file now holds other weights
    assert main(["train", "--config", str(ft), "--out", str(tmp_path / "d.pt"), *quick]) == 0
    assert "is not what" in capsys.readouterr().err


def test_cli_reports_bad_checkpoint_and_bad_options(tmp_path, capsys):
    from lifter.cli import main

    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"junk")
    assert main(["evaluate", str(bad), "--stride", "500", "--max-frames-per-sequence", "1"]) == 2
    assert "corrupt" in capsys.readouterr().err  # weights are loaded before the data: no Human3.6M needed
    assert main(["train", "--out", str(tmp_path / "x.pt"), "--clean-prob", "0.8", "--real-prob", "0.5"]) == 2
    assert "clean_prob + real_prob" in capsys.readouterr().err
    assert main(["train", "--out", str(tmp_path / "x.pt"), "--width", "100000"]) == 2
    assert "width" in capsys.readouterr().err
    assert main(["train", "--out", str(tmp_path / "x.pt"), "--config", str(tmp_path / "missing.json")]) == 2
    assert "no such file" in capsys.readouterr().err
    # an --out that cannot be written is refused before the data is even read (user trial: a run trained to the
    # end, then failed to save), naming the file that stands where a folder must be
    bad.with_name("t1.pt").write_bytes(b"")
    nodata = ["--h36m", str(tmp_path / "no_h36m")]
    assert main(["train", "--out", str(tmp_path / "t1.pt" / "x.pt"), *nodata]) == 2
    assert f"{tmp_path / 't1.pt'} is a file, not a folder" in capsys.readouterr().err
    assert main(["train", "--out", str(tmp_path / "new" / "x.pt"), *nodata]) == 2  # writable: on to the data
    assert "Human3.6M data not found" in capsys.readouterr().err and (tmp_path / "new").is_dir()
    # a teacher that cannot serve, or is not there, is refused before the data is read, naming what differs
    assert main(["train", "--out", str(tmp_path / "x.pt"), "--teacher", "sh_mix", "--input-space", "camera",
                 *nodata]) == 2
    err = capsys.readouterr().err
    assert "teacher network 'sh_mix'" in err and "input_space 'pixel' (trained: 'camera'; --input-space)" in err
    assert "depth_target" not in err  # only what differs is named
    assert main(["train", "--out", str(tmp_path / "x.pt"), "--teacher", str(tmp_path / "none.pt"), *nodata]) == 2
    assert "none.pt" in capsys.readouterr().err
    assert main(["train", "--out", str(tmp_path / "x.pt"), "--distill-weight", "0.3", *nodata]) == 2
    assert "no --teacher is given" in capsys.readouterr().err


def test_cli_output_paths_are_checked_before_the_work_and_ctrl_c_says_nothing_was_saved(tmp_path, capsys,
                                                                                        monkeypatch):
    """User trial: `evaluate --json <folder>` failed with a traceback after evaluating; Ctrl-C in `train` said
    only "interrupted"."""
    import lifter.cli.train as cli_train
    from lifter.cli import main

    nodata = ["--h36m", str(tmp_path / "no_h36m")]
    assert main(["evaluate", "--json", str(tmp_path), *nodata]) == 2
    assert f"--json {tmp_path} is a folder; give a file path in it" in capsys.readouterr().err
    (tmp_path / "f").write_text("")
    assert main(["evaluate", "--pck-plot", str(tmp_path / "f" / "p.png"), *nodata]) == 2
    assert f"{tmp_path / 'f'} is a file, not a folder" in capsys.readouterr().err

    def interrupt(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli_train, "H36M", interrupt)
    assert main(["train", "--out", str(tmp_path / "r.pt"), *nodata]) == 130
    assert capsys.readouterr().err.strip() == "poselifter train: interrupted (no checkpoint was written)"
    assert not (tmp_path / "r.pt").exists()


def test_learning_curve_range_keeps_every_curves_last_point():
    """User trial: a detected-2D MRPE ending at 470 mm fell off a panel capped at 2.5x the clean curve's 160."""
    from lifter.plots import curve_y_range

    lo, hi = curve_y_range([[900.0, 200.0, 160.0], [1500.0, 600.0, 470.0]])
    assert lo == pytest.approx(144.0) and hi >= 470.0
    lo, hi = curve_y_range([[900.0, 100.0, 110.0], [800.0, 120.0, 130.0]])  # the untrained start is still cut
    assert hi == pytest.approx(250.0 * 1.02)


# -- DistributedDataParallel -------------------------------------------------------------------------

DDP_SCRIPT = textwrap.dedent('''
    import sys, torch
    sys.path.insert(0, sys.argv[2])
    from test_training import synthetic_samples, tiny_config
    from dataclasses import replace
    from lifter.config import OptimConfig, ScheduleConfig
    from lifter.train import init_distributed, train, validation_sets
    torch.set_num_threads(1)
    ctx = init_distributed()
    cfg = replace(tiny_config(), optim=OptimConfig(batch_size=64, ema_decay=0.9),
                  schedule=ScheduleConfig(epochs=3, eval_every=5))
    s = synthetic_samples(320)
    res = train(cfg, train_samples=s, val_sets=validation_sets(synthetic_samples(20, seed=9), None),
                progress=False, log=lambda m: None, ctx=ctx)
    torch.save({"state": res.net.state_dict(), "steps": res.steps, "world": ctx.world, "rank": ctx.rank,
                "curve": len(res.curve)}, f"{sys.argv[1]}/rank{ctx.rank}.pt")
    # (the process group ended before the interpreter: a CI run's rank 1 aborted at exit once, "terminate called
    # without an active exception", with gloo's threads still up; poselifter train ends it the same way)
    torch.distributed.barrier()
    torch.distributed.destroy_process_group()
''')


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_ddp_two_cpu_processes_agree(tmp_path):
    """torchrun, 2 processes, gloo: both ranks end with identical weights (parameters, BatchNorm statistics and
    the EMA), having trained on disjoint shards of each batch for the same number of steps; only rank 0
    validates."""
    script = tmp_path / "ddp_run.py"
    script.write_text(DDP_SCRIPT)
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "torch.distributed.run", "--nproc_per_node", "2", "--master_addr", "127.0.0.1",
           "--master_port", str(_free_port()), str(script), str(tmp_path), str(Path(__file__).parent)]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    r0, r1 = (torch.load(tmp_path / f"rank{r}.pt", weights_only=True) for r in (0, 1))
    assert (r0["world"], r1["world"]) == (2, 2) and r0["steps"] == r1["steps"] == 15
    assert r0["curve"] > 0 and r1["curve"] == 0
    assert r0["state"].keys() == r1["state"].keys()
    for k in r0["state"]:
        torch.testing.assert_close(r0["state"][k], r1["state"][k], rtol=0, atol=0, msg=k)


FINITE_SCRIPT = textwrap.dedent('''
    import sys, torch, torch.distributed as dist
    from lifter.train import init_distributed, _check_finite
    ctx = init_distributed()
    running = torch.tensor(float("nan") if ctx.rank == 1 else 3.0)
    try:
        _check_finite(running, 50, ctx)
        print(f"rank {ctx.rank}: no error")
    except FloatingPointError as e:
        print(f"rank {ctx.rank}: {e}")
    dist.destroy_process_group()
''')


def test_ddp_a_loss_non_finite_on_one_rank_stops_every_rank(tmp_path):
    """Only rank 1's loss is NaN: both ranks raise (a lone raising rank would leave the other waiting in its next
    all-reduce), and rank 0 says the loss went non-finite on another process."""
    script = tmp_path / "finite.py"
    script.write_text(FINITE_SCRIPT)
    env = {**os.environ, "OMP_NUM_THREADS": "1", "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "torch.distributed.run", "--nproc_per_node", "2", "--master_addr", "127.0.0.1",
           "--master_port", str(_free_port()), str(script)]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert "rank 0: the training loss became non-finite by step 50 on another process (this one's: 3)" in proc.stdout
    assert "rank 1: the training loss became non-finite by step 50 (nan)" in proc.stdout
    assert "no error" not in proc.stdout


@requires_h36m
def test_ddp_cli_writes_one_checkpoint(tmp_path):
    out = tmp_path / "ddp.pt"
    env = {**os.environ, "OMP_NUM_THREADS": "1"}
    cmd = [sys.executable, "-m", "torch.distributed.run", "--nproc_per_node", "2", "--master_addr", "127.0.0.1",
           "--master_port", str(_free_port()), "-m", "lifter", "train", "--out", str(out), "--width", "32",
           "--epochs", "1", "--batch-size", "65", "--max-frames-per-sequence", "3", "--val-stride", "400",
           "--threads", "1", "--no-progress"]
    proc = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert out.is_file() and sorted(p.name for p in tmp_path.iterdir() if p.suffix == ".pt") == ["ddp.pt"]
    lifter = Lifter.from_checkpoint(out)
    assert lifter.meta["world_size"] == 2  # a batch of 65 over 2 processes is 64, and the log says so
    assert "global batch 64 (2 process(es) x 32; 65 asked, rounded down to a multiple of 2)" in proc.stdout


def _scene(n: int, *, seed: int, x: float, y: float, z: tuple[float, float], focal: tuple[float, float],
           pp: tuple[float, float]) -> tuple[torch.Tensor, ...]:
    """``n`` random poses (float64) in front of a pinhole camera: roots uniform in +-x, +-y, z mm, root-relative
    joints ~300 mm; returns root ``(n, 3)``, rel ``(n, 17, 3)``, focal and principal point ``(n, 2)``, 2D ``(n, 17,
    2)`` px (their projection)."""
    from lifter.camera import project

    g = torch.Generator().manual_seed(seed)
    root = torch.stack([torch.empty(n).uniform_(-x, x, generator=g), torch.empty(n).uniform_(-y, y, generator=g),
                        torch.empty(n).uniform_(*z, generator=g)], -1).double()
    rel = torch.randn(n, 17, 3, generator=g, dtype=torch.float64) * 300
    rel[:, 0] = 0
    f = torch.tensor([focal], dtype=torch.float64).expand(n, 2)
    c = torch.tensor([pp], dtype=torch.float64).expand(n, 2)
    kp = torch.from_numpy(project((root[:, None] + rel).numpy(), focal=f.numpy(), principal_point=c.numpy()))
    return root, rel, f, c, kp


def _assert_physically_consistent(b: dict[str, torch.Tensor]) -> None:
    """Every sample of a training batch: its 2D is the projection of its 3D (root from the 2D root and depth)."""
    from lifter.camera import project

    n = len(b["kp"])
    root_b = torch.cat([(b["kp"][:, 0] - b["pp"]) / b["focal"], torch.ones(n, 1)], -1) * b["depth"][:, None]
    again = project((root_b[:, None] + b["rel"]).double().numpy(), focal=b["focal"].double().numpy(),
                    principal_point=b["pp"].double().numpy())
    np.testing.assert_allclose(b["kp"].numpy(), again, atol=2e-3)


def test_a_camera_turn_moves_2d_and_3d_as_that_camera_sees_them():
    """rotate_batch: the turned 2D is the pinhole projection of the turned 3D (clean 2D exactly; any 2D by the same
    homography), the root stays at the same distance from the camera centre, and make_batch with a flip and a turn
    keeps every sample a physically consistent one (2D root = projection of the 3D root)."""
    from lifter.camera import camera_turn, project
    from lifter.config import AugmentConfig, DataConfig, TrainConfig
    from lifter.train import make_batch, rotate_batch

    n = 64
    root, rel, f, pp, kp = _scene(n, seed=0, x=1500, y=800, z=(3000, 7000), focal=(1145.0, 1143.0), pp=(512.0, 515.0))
    kp2, rel2, depth2 = rotate_batch(kp, pp, f, rel, root[:, 2], kp[:, 0], max_deg=20.0,
                                     gen=torch.Generator().manual_seed(1))
    u = 2 * torch.rand(2, n, generator=torch.Generator().manual_seed(1)) - 1
    r = camera_turn(*(torch.deg2rad(torch.tensor(20.0)) * u)).double()
    turned = (root[:, None] + rel) @ r.transpose(1, 2)
    np.testing.assert_allclose(rel2.numpy(), (turned - turned[:, :1]).numpy(), atol=1e-9)
    np.testing.assert_allclose(depth2.numpy(), turned[:, 0, 2].numpy(), rtol=1e-12)
    np.testing.assert_allclose(kp2.numpy(), project(turned.numpy(), focal=f.numpy(), principal_point=pp.numpy()),
                               atol=1e-9)
    assert not torch.allclose(kp2, kp) and torch.allclose(turned[:, 0].norm(dim=-1), root.norm(dim=-1))
    angle = torch.rad2deg(torch.arccos(((r.diagonal(dim1=1, dim2=2).sum(-1) - 1) / 2).clamp(-1, 1)))
    assert float(angle.max()) <= 20 * 2 ** 0.5 + 1e-6 and float(angle.max()) > 10  # pan and tilt, each within +-20 deg
    # through make_batch, flipped and turned: the samples stay consistent (float32)
    T = {"kp": kp.float(), "pp": pp.float(), "focal": f.float(), "rel": rel.float(), "depth": root[:, 2].float()}
    cfg = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0),
                      augment=AugmentConfig(flip_prob=0.5, rotate_deg=15.0))
    b = make_batch(T, torch.arange(n), cfg, torch.Generator().manual_seed(2))
    _assert_physically_consistent(b)
    assert not np.allclose(b["depth"].numpy(), T["depth"].numpy())
    with pytest.raises(PoseLifterError, match="lens='h36m' .* add --lens pinhole, or drop --rotate-deg"):
        TrainConfig(data=DataConfig(lens="h36m"), augment=AugmentConfig(rotate_deg=5.0))


def test_moving_people_along_their_viewing_ray_keeps_samples_physical():
    """move_batch: the moved 3D is the old root scaled along its ray with the shape kept, the true 2D its pinhole
    projection (the root's 2D unmoved), and a detection keeps its error relative to the 2D size; make_batch with a
    flip, a move and a turn keeps every sample physically consistent and moves about distance_prob of them within
    the factor range; runs without it draw as before; the config refuses it with distorted 2D."""
    from lifter.camera import project
    from lifter.config import AugmentConfig, DataConfig, TrainConfig
    from lifter.normalization import pose_scale
    from lifter.train import make_batch, move_batch

    n = 64
    root, rel, f, pp, kp = _scene(n, seed=3, x=1200, y=700, z=(3000, 7000), focal=(1145.0, 1143.0), pp=(512.0, 515.0))
    factor = torch.linspace(0.5, 5.0, n, dtype=torch.float64)
    err = torch.randn(n, 17, 2, generator=torch.Generator().manual_seed(4), dtype=torch.float64) * 8
    det2, gt2, depth2 = move_batch(kp + err, kp, pp, f, rel, root[:, 2], factor)
    moved = root[:, None] * factor[:, None, None] + rel
    np.testing.assert_allclose(depth2.numpy(), moved[:, 0, 2].numpy(), rtol=1e-12)
    np.testing.assert_allclose(gt2.numpy(), project(moved.numpy(), focal=f.numpy(), principal_point=pp.numpy()),
                               atol=1e-9)
    np.testing.assert_allclose(gt2[:, 0].numpy(), kp[:, 0].numpy(), atol=1e-9)  # the root's 2D stays
    ratio = pose_scale(gt2) / pose_scale(kp)
    assert float(ratio[0]) > 1.5 and float(ratio[-1]) < 0.3  # nearer is larger, farther smaller
    np.testing.assert_allclose((det2 - gt2).numpy(), (err * ratio[:, None, None]).numpy(), atol=1e-9)
    # factor 1 changes nothing
    same = move_batch(kp + err, kp, pp, f, rel, root[:, 2], torch.ones(n, dtype=torch.float64))
    np.testing.assert_allclose(same[0].numpy(), (kp + err).numpy(), atol=1e-9)
    # through make_batch, flipped, moved and turned (float32)
    T = {"kp": kp.float(), "pp": pp.float(), "focal": f.float(), "rel": rel.float(), "depth": root[:, 2].float()}
    cfg = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0),
                      augment=AugmentConfig(flip_prob=0.5, rotate_deg=10.0, distance_prob=0.5, distance_min=0.5,
                                            distance_max=4.0))
    b = make_batch(T, torch.arange(n), cfg, torch.Generator().manual_seed(2))
    _assert_physically_consistent(b)
    cfg_still = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0), augment=AugmentConfig(flip_prob=0.5))
    b_still = make_batch(T, torch.arange(n), cfg_still, torch.Generator().manual_seed(2))
    dist_ratio = (b["depth"] / T["depth"]).numpy()  # a turn keeps the distance from the centre, not the depth
    near_one = np.abs(np.log(dist_ratio)) < np.log(1 / np.cos(np.deg2rad(10 * 2 ** 0.5))) + 1e-3
    assert 16 <= int((~near_one).sum()) <= 48  # about half moved
    assert dist_ratio.min() > 0.5 * np.cos(np.deg2rad(15)) - 1e-3 and dist_ratio.max() < 4.0 / np.cos(np.deg2rad(15))
    # without distance_prob the batch draws exactly as before it existed
    b_off = make_batch(T, torch.arange(n), TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0),
                                                       augment=AugmentConfig(flip_prob=0.5, distance_max=3.0)),
                       torch.Generator().manual_seed(2))
    assert torch.equal(b_off["kp"], b_still["kp"])
    # flipped and moved without a turn, from real detections: still physical where the 2D is the truth's, and a
    # detection's error scaled with the person's 2D size
    err32 = err.float()
    T_real = dict(T, real=(kp + err).float(), has_real=torch.ones(n, dtype=torch.bool))
    cfg_real = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=0.0, real_prob=1.0),
                           augment=AugmentConfig(flip_prob=0.5, distance_prob=1.0, distance_min=0.5, distance_max=4.0))
    b_real = make_batch(T_real, torch.arange(n), cfg_real, torch.Generator().manual_seed(6))
    cfg_true = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0), augment=cfg_real.augment)
    b_true = make_batch(T, torch.arange(n), cfg_true, torch.Generator().manual_seed(6))
    _assert_physically_consistent(b_true)
    assert not torch.allclose(b_true["depth"], T["depth"])
    size = pose_scale(b_true["kp"]) / pose_scale(T["kp"])
    e = (b_real["kp"] - b_true["kp"]).norm(dim=-1).sort(dim=-1).values  # (a flip mirrors the error, swaps joints)
    np.testing.assert_allclose(e.numpy(), (err32.norm(dim=-1) * size[:, None]).sort(dim=-1).values.numpy(), atol=1e-3)
    assert float(size.min()) < 0.5 and float(size.max()) > 1.5
    # a person moved very near and then turned far: such moves are not made, so no joint reaches the camera
    near_root, near_rel, nf, npp, near_kp = _scene(n, seed=8, x=600, y=400, z=(5000, 6000), focal=(1000.0, 1000.0),
                                                   pp=(500.0, 500.0))
    T_near = {"kp": near_kp.float(), "pp": npp.float(), "focal": nf.float(), "rel": near_rel.float(),
              "depth": near_root[:, 2].float()}
    cfg_near = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0),
                           augment=AugmentConfig(flip_prob=0.0, rotate_deg=30.0, distance_prob=1.0, distance_min=0.4,
                                                 distance_max=1.0))
    for seed in range(5):
        bn = make_batch(T_near, torch.arange(n), cfg_near, torch.Generator().manual_seed(seed))
        root_b = torch.cat([(bn["kp"][:, 0] - bn["pp"]) / bn["focal"], torch.ones(n, 1)], -1) * bn["depth"][:, None]
        assert float((root_b[:, None] + bn["rel"])[..., 2].min()) > 0
    from lifter.train import MAX_OFF_AXIS_DEG

    limit = MAX_OFF_AXIS_DEG - math.hypot(30.0, 30.0)
    _, _, d_near = move_batch(near_kp, near_kp, npp, nf, near_rel, near_root[:, 2], torch.full((n,), 0.2,
                                                                                              dtype=torch.float64),
                              max_off_axis_deg=limit)
    made = torch.isclose(d_near, 0.2 * near_root[:, 2])
    assert 0 < int(made.sum()) < n and torch.equal(d_near[~made], near_root[~made, 2])  # some made, the rest kept
    moved_points = near_root[made][:, None] * 0.2 + near_rel[made]
    off_axis = torch.rad2deg(torch.arccos(moved_points[..., 2] / moved_points.norm(dim=-1)))
    assert float(off_axis.max()) <= limit
    with pytest.raises(PoseLifterError, match="lens='h36m' .* add --lens pinhole, or drop --distance-prob"):
        TrainConfig(data=DataConfig(lens="h36m"), augment=AugmentConfig(distance_prob=0.3))
    with pytest.raises(PoseLifterError, match="distance_min must be in"):
        AugmentConfig(distance_min=0.1)


def test_a_camera_roll_turns_the_picture_about_the_principal_point():
    """rotate_batch with max_roll_deg: the roll is drawn after pan and tilt (so runs without it draw as before),
    a roll alone turns every 2D point about the principal point by the same angle (the picture turned in its plane)
    and keeps the root's depth, and make_batch with a flip, a turn and a roll keeps every sample physically
    consistent. The config refuses a roll with distorted 2D."""
    from lifter.camera import camera_turn
    from lifter.config import AugmentConfig, DataConfig, TrainConfig
    from lifter.train import make_batch, rotate_batch

    n = 32
    root, rel, f, pp, kp = _scene(n, seed=4, x=1000, y=600, z=(3000, 6000), focal=(1000.0, 1000.0), pp=(500.0, 400.0))
    kp2, rel2, depth2 = rotate_batch(kp, pp, f, rel, root[:, 2], kp[:, 0], max_deg=0.0, max_roll_deg=30.0,
                                     gen=torch.Generator().manual_seed(5))
    draws = torch.rand(3, n, generator=torch.Generator().manual_seed(5), dtype=torch.float32)
    roll = torch.deg2rad(torch.tensor(30.0)) * (2 * draws[2] - 1)
    g = torch.Generator().manual_seed(5)  # without a roll: two draws (pan, tilt), as before the roll existed
    rotate_batch(kp, pp, f, rel, root[:, 2], kp[:, 0], max_deg=10.0, gen=g)
    assert torch.equal(torch.rand(n, generator=g), draws[2])
    assert float(roll.abs().max()) > 0.2
    # the picture turns counter-clockwise on screen by the roll: image "up" is -y
    d = kp - pp[:, None]
    c, s_ = torch.cos(roll).double()[:, None], torch.sin(roll).double()[:, None]
    expected = pp[:, None] + torch.stack([c * d[..., 0] + s_ * d[..., 1], -s_ * d[..., 0] + c * d[..., 1]], -1)
    np.testing.assert_allclose(kp2.numpy(), expected.numpy(), atol=1e-6)
    r = camera_turn(torch.zeros(n), torch.zeros(n), roll).double()
    turned = (root[:, None] + rel) @ r.transpose(1, 2)
    np.testing.assert_allclose(rel2.numpy(), (turned - turned[:, :1]).numpy(), atol=1e-6)
    np.testing.assert_allclose(depth2.numpy(), root[:, 2].numpy(), rtol=1e-12)  # a roll keeps the depth
    T = {"kp": kp.float(), "pp": pp.float(), "focal": f.float(), "rel": rel.float(), "depth": root[:, 2].float()}
    cfg = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0),
                      augment=AugmentConfig(flip_prob=0.5, rotate_deg=15.0, roll_deg=20.0))
    b = make_batch(T, torch.arange(n), cfg, torch.Generator().manual_seed(2))
    _assert_physically_consistent(b)
    assert not np.allclose(b["kp"].numpy(), T["kp"].numpy(), atol=1.0)
    with pytest.raises(PoseLifterError, match="lens='h36m' .* add --lens pinhole, or drop --roll-deg"):
        TrainConfig(data=DataConfig(lens="h36m"), augment=AugmentConfig(roll_deg=5.0))
    with pytest.raises(PoseLifterError, match="view='look_at' .* lens='h36m' .* add --lens pinhole, or drop --view"):
        TrainConfig(model=ModelConfig(view="look_at"), data=DataConfig(lens="h36m"))
    assert TrainConfig(model=ModelConfig(view="look_at"), data=DataConfig(lens="pinhole")).model.view == "look_at"
    with pytest.raises(PoseLifterError, match=r"roll_deg must be in \[0, 45\] degrees"):
        AugmentConfig(roll_deg=60.0)


def test_turn_prob_turns_only_that_share_of_the_samples():
    """rotate_batch(prob=): about that share of the samples is turned and the rest are returned as they were; the
    share is drawn after the angles, so prob=1 draws exactly as before it existed; make_batch passes
    ``augment.turn_prob`` and keeps the samples physical; the config refuses a share outside [0, 1]."""
    from lifter.config import AugmentConfig, DataConfig, TrainConfig
    from lifter.train import make_batch, rotate_batch

    n = 400
    root, rel, f, pp, kp = _scene(n, seed=9, x=1200, y=700, z=(3000, 7000), focal=(1145.0, 1143.0), pp=(512.0, 515.0))
    args = (kp, pp, f, rel, root[:, 2], kp[:, 0])
    every = rotate_batch(*args, max_deg=20.0, gen=torch.Generator().manual_seed(3))
    again = rotate_batch(*args, max_deg=20.0, gen=torch.Generator().manual_seed(3), prob=1.0)
    assert all(torch.equal(a, b) for a, b in zip(every, again))
    kp2, rel2, depth2 = rotate_batch(*args, max_deg=20.0, max_roll_deg=10.0, gen=torch.Generator().manual_seed(3),
                                     prob=0.3)
    still = (kp2 - kp).abs().amax(dim=(1, 2)) < 1e-9
    assert 0.2 * n < int((~still).sum()) < 0.4 * n  # about 30 % turned
    assert torch.equal(depth2[still], root[still, 2]) and torch.allclose(rel2[still], rel[still], atol=1e-12)
    assert float((kp2[~still] - kp[~still]).norm(dim=-1).mean()) > 10  # the turned ones moved in the image
    none = rotate_batch(*args, max_deg=20.0, gen=torch.Generator().manual_seed(3), prob=0.0)
    assert torch.allclose(none[0], kp, atol=1e-9) and torch.allclose(none[2], root[:, 2], rtol=1e-12)
    T = {"kp": kp.float(), "pp": pp.float(), "focal": f.float(), "rel": rel.float(), "depth": root[:, 2].float()}
    cfg = TrainConfig(data=DataConfig(lens="pinhole", clean_prob=1.0),
                      augment=AugmentConfig(flip_prob=0.5, rotate_deg=15.0, turn_prob=0.5))
    b = make_batch(T, torch.arange(n), cfg, torch.Generator().manual_seed(2))
    _assert_physically_consistent(b)
    kept = torch.isclose(b["depth"], T["depth"], rtol=1e-6)
    assert 0.35 * n < int(kept.sum()) < 0.65 * n
    with pytest.raises(PoseLifterError, match=r"turn_prob must be a probability in \[0, 1\]"):
        AugmentConfig(turn_prob=1.5)
