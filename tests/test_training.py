"""A tiny training run on a slice of H36M reduces the loss and beats the mean pose; CLI wiring."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import torch

from lifter.api import Lifter
from lifter.evaluate import evaluate_lifter
from lifter.loss import poselifter_loss
from lifter.model import ModelConfig, pack_targets, split_output
from lifter.train import TrainConfig, flip_batch, target_statistics, train

from conftest import requires_h36m


def test_loss_units_and_weighting():
    pred = torch.zeros(2, 49)
    target = torch.zeros(2, 49)
    target[:, :48] = 1.0  # 1 mm on each of 48 coordinates
    target[:, 48] = 10.0  # 10 mm of canonical depth
    assert poselifter_loss(pred, target).item() == pytest.approx(58.0)
    assert poselifter_loss(pred, target, depth_weight=0.0).item() == pytest.approx(48.0)
    with pytest.raises(ValueError, match="49"):
        poselifter_loss(torch.zeros(2, 48), torch.zeros(2, 48))


def test_pack_split_round_trip():
    rel = torch.randn(4, 17, 3)
    rel[:, 0] = 0
    depth = torch.rand(4) * 5000
    out = split_output(pack_targets(rel, depth))
    torch.testing.assert_close(out.relative, rel)
    torch.testing.assert_close(out.depth, depth)


def test_flip_batch_matches_numpy_flip():
    from lifter.camera import flip_keypoints_2d, flip_pose_3d

    g = torch.Generator().manual_seed(0)
    kp = torch.rand(6, 17, 2, generator=g) * 1000
    pp = torch.rand(6, 2, generator=g) * 1000
    w = torch.full((6,), 1000.0)
    rel = torch.randn(6, 17, 3, generator=g) * 300
    mask = torch.tensor([True, False, True, False, True, True])
    kp_f, pp_f, rel_f = flip_batch(kp, pp, w, rel, mask)
    kp_np, pp_np = flip_keypoints_2d(kp.numpy(), image_width=1000, principal_point=pp.numpy())
    m = mask.numpy()
    np.testing.assert_allclose(kp_f.numpy()[m], kp_np[m], rtol=1e-6)
    np.testing.assert_allclose(pp_f.numpy()[m], pp_np[m], rtol=1e-6)
    np.testing.assert_allclose(rel_f.numpy()[m], flip_pose_3d(rel.numpy())[m], rtol=1e-6)
    np.testing.assert_array_equal(kp_f.numpy()[~m], kp.numpy()[~m])


def test_zoom_batch_keeps_the_3d_root():
    """Zooming 2D, principal point and focal by s with the canonical target / s describes the same 3D root."""
    from lifter.camera import project, root_from_canonical_depth
    from lifter.train import zoom_batch

    from conftest import random_pose_cam

    pose = random_pose_cam(np.random.default_rng(0), 8)
    f, c = np.array([1145.0, 1143.0]), np.array([512.0, 515.0])
    kp = torch.tensor(project(pose, focal=f, principal_point=c))
    pp = torch.tensor(np.tile(c, (8, 1)))
    cd = torch.tensor(pose[:, 0, 2] * 1000 / np.sqrt(f.prod()))
    s = torch.linspace(0.7, 1.4, 8, dtype=torch.float64)
    kp_z, pp_z, cd_z = zoom_batch(kp, pp, cd, s, canonical=True)
    root = root_from_canonical_depth(kp_z[:, 0].numpy(), cd_z.numpy(), focal=f * s.numpy()[:, None], principal_point=pp_z.numpy())
    np.testing.assert_allclose(root, pose[:, 0], rtol=1e-9)
    # the zoomed 2D is exactly the projection through the zoomed camera
    np.testing.assert_allclose(kp_z.numpy(), project(pose, focal=f * s.numpy()[:, None], principal_point=pp_z.numpy()), rtol=1e-9)
    _, _, z_abs = zoom_batch(kp, pp, torch.tensor(pose[:, 0, 2]), s, canonical=False)
    np.testing.assert_allclose(z_abs.numpy(), pose[:, 0, 2])


def test_target_statistics_are_flip_symmetric():
    rel = torch.randn(100, 17, 3) * 200 + torch.tensor([50.0, 0.0, 0.0])
    rel[:, 0] = 0
    mean, std = target_statistics(rel, torch.rand(100) * 1000 + 4000)
    x_means = mean[:48].reshape(16, 3)[:, 0]
    # mirrored copies cancel the X offset on average over each left/right pair
    assert abs(float(x_means.mean())) < 1e-3
    assert mean[48] > 4000 and std[48] > 0


@requires_h36m
def test_tiny_training_reduces_loss_and_beats_mean_pose(h36m):
    train_s = h36m.load([1, 5], stride=20, max_frames_per_sequence=40)
    test_s = h36m.load([9], stride=100, max_frames_per_sequence=10)
    cfg = TrainConfig(model=ModelConfig(width=256, dropout=0.1), batch_size=128, epochs=6, lr=2e-3,
                      eval_every=40, seed=0)
    res = train(cfg, train_samples=train_s, val_samples=test_s, progress=False, log=lambda s: None)
    losses = [c["train_loss"] for c in res.curve]
    assert losses[-1] < 0.6 * losses[0], losses
    lifter = Lifter(res.net, name="tiny")
    row = evaluate_lifter(lifter, test_s, progress=False)[0]
    # the mean pose (the network's output at initialization) as the baseline
    mean_rel = np.concatenate([np.zeros((1, 3)), res.net.target_mean[:48].numpy().reshape(16, 3)])
    from lifter.metrics import mpjpe

    baseline = float(mpjpe(np.broadcast_to(mean_rel, test_s.pose_3d.shape), test_s.relative).mean())
    assert row.mpjpe < 0.75 * baseline, (row.mpjpe, baseline)
    assert row.mrpe < 1000


@requires_h36m
def test_cli_train_and_evaluate(tmp_path, capsys):
    from lifter.cli import main

    out = tmp_path / "tiny.pt"
    rc = main(["train", "--out", str(out), "--width", "64", "--epochs", "1", "--batch-size", "64",
               "--max-frames-per-sequence", "4", "--train-stride", "50", "--eval-every", "20", "--threads", "1"])
    assert rc == 0 and out.is_file() and out.with_suffix(".curve.json").is_file()
    rc = main(["evaluate", f"tiny={out}", "--stride", "200", "--max-frames-per-sequence", "3", "--analytic-root"])
    text = capsys.readouterr().out
    assert rc == 0 and "MPJPE" in text and "analytic" in text and "Discussion 1" in text


@requires_h36m
def test_cli_mixed_inputs_fine_tune_with_another_error_model(tmp_path, capsys):
    from lifter.checkpoint import load_checkpoint
    from lifter.cli import main
    from lifter.noise import ErrorModel

    base = tmp_path / "base.pt"
    common = ["--epochs", "1", "--batch-size", "64", "--max-frames-per-sequence", "10", "--train-stride", "5",
              "--eval-every", "50", "--threads", "1"]
    assert main(["train", "--out", str(base), "--width", "64", "--inputs", "mix", "--real-prob", "0.7",
                 "--noise", "mixture", *common]) == 0
    assert "mixing real detections" in capsys.readouterr().out
    em = tmp_path / "em.json"
    ErrorModel.standin().save(em)
    ft = tmp_path / "ft.pt"
    assert main(["train", "--out", str(ft), "--init", str(base), "--width", "128", "--noise", "mixture",
                 "--error-model", str(em), "--ema", "0.9", *common]) == 0
    net, meta = load_checkpoint(ft)
    assert net.config.width == 64  # the initial checkpoint's architecture, not --width
    assert meta["init"].startswith(str(base)) and meta["error_model"] == str(em) and meta["train_config"]["ema_decay"] == 0.9
    capsys.readouterr()
    assert main(["train", "--out", str(ft), "--inputs", "mix", "--train-stride", "7", "--epochs", "1"]) == 2
    assert "multiple of 5" in capsys.readouterr().err  # detections exist every 5th frame only


def test_cli_reports_bad_checkpoint(tmp_path, capsys):
    from lifter.cli import main

    bad = tmp_path / "bad.pt"
    bad.write_bytes(b"junk")
    rc = main(["evaluate", str(bad), "--stride", "500", "--max-frames-per-sequence", "1"])
    err = capsys.readouterr().err
    assert rc == 2
    assert "corrupt" in err  # weights are loaded before the data, so this does not need Human3.6M


def _batch_tensors(n: int = 2000) -> dict[str, torch.Tensor]:
    g = torch.Generator().manual_seed(1)
    return {"kp": 400 + 100 * torch.rand(n, 17, 2, generator=g), "pp": torch.full((n, 2), 500.0),
            "w": torch.full((n,), 1000.0), "rel": torch.randn(n, 17, 3, generator=g) * 100,
            "depth": 4000 + torch.rand(n, generator=g) * 1000}


def test_make_batch_mixes_real_detections_without_noising_them():
    from lifter.train import make_batch

    T = _batch_tensors()
    n = len(T["kp"])
    T["real"] = T["kp"] + 7.0  # a "detection" 7 px off in x and y
    T["has_real"] = torch.arange(n) % 2 == 0  # every other sample has one
    plus_1000 = lambda kp, pp, gen: kp + 1000.0  # noqa: E731 - a noise hook whose effect is unmistakable
    cfg = TrainConfig(flip_prob=0.0, real_2d_prob=0.5)
    idx = torch.arange(n)
    kp, pp, rel, depth = make_batch(T, idx, cfg, torch.Generator().manual_seed(0), augment_2d=plus_1000)
    off = (kp - T["kp"])[:, 0, 0]
    real_rows = torch.isclose(off, torch.tensor(7.0))
    noisy_rows = torch.isclose(off, torch.tensor(1000.0))
    assert bool((real_rows | noisy_rows).all())  # each row is either its detection (un-noised) or noisy GT
    assert not bool(real_rows[~T["has_real"]].any())  # never a detection where there is none
    frac = real_rows[T["has_real"]].float().mean().item()
    assert 0.45 < frac < 0.55, frac
    torch.testing.assert_close(rel, T["rel"])
    torch.testing.assert_close(depth, T["depth"])
    # p = 1 with zoom: detections are zoomed like GT (kp and pp scale together), never noised
    cfg = TrainConfig(flip_prob=0.0, real_2d_prob=1.0, zoom_aug=True, zoom_sigma=0.5, zoom_clip=1.0)
    kp, pp, rel, depth = make_batch(T, idx, cfg, torch.Generator().manual_seed(0), augment_2d=plus_1000)
    s = pp[:, 0] / T["pp"][:, 0]
    h = T["has_real"]
    torch.testing.assert_close(kp[h], T["real"][h] * s[h, None, None])
    torch.testing.assert_close(kp[~h], (T["kp"][~h] + 0.0) * s[~h, None, None] + 1000.0)
    torch.testing.assert_close(depth, T["depth"] / s)  # canonical depth follows the zoom
    # p = 1 with flip: it is the detection that gets mirrored (x -> W - x, left/right swapped)
    from lifter.skeleton import FLIP_PERMUTATION

    cfg = TrainConfig(flip_prob=1.0, real_2d_prob=1.0)
    kp, pp, rel, depth = make_batch(T, idx, cfg, torch.Generator().manual_seed(0))
    expect = T["real"][h][:, list(FLIP_PERMUTATION)].clone()
    expect[..., 0] = 1000.0 - expect[..., 0]
    torch.testing.assert_close(kp[h], expect)
    torch.testing.assert_close(pp[:, 0], 1000.0 - T["pp"][:, 0])


def test_weight_average_is_an_exponential_moving_average():
    from lifter.train import WeightAverage

    net = torch.nn.Sequential(torch.nn.Linear(3, 2), torch.nn.BatchNorm1d(2))
    w0 = {k: v.clone() for k, v in net.state_dict().items()}
    avg = WeightAverage(net, decay=0.9)
    with torch.no_grad():
        net[0].weight.add_(1.0)
        net[1].running_mean.fill_(5.0)
        net[1].num_batches_tracked.fill_(3)
    avg.update(net)
    sd = avg.module.state_dict()
    torch.testing.assert_close(sd["0.weight"], 0.9 * w0["0.weight"] + 0.1 * (w0["0.weight"] + 1.0))
    torch.testing.assert_close(sd["1.running_mean"], torch.full((2,), 0.5))
    assert int(sd["1.num_batches_tracked"]) == 3
    assert avg.module is not net
    with pytest.raises(ValueError, match="decay"):
        WeightAverage(net, decay=1.0)


@requires_h36m
def test_fine_tuning_keeps_architecture_and_does_not_touch_the_initial_network(h36m, monkeypatch):
    train_s = h36m.load([1], stride=50, max_frames_per_sequence=20)
    test_s = h36m.load([9], stride=200, max_frames_per_sequence=5)
    base = train(TrainConfig(model=ModelConfig(width=64), batch_size=64, epochs=1, eval_every=1000),
                 train_samples=train_s, val_samples=test_s, progress=False, log=lambda s: None).net
    before = {k: v.clone() for k, v in base.state_dict().items()}
    # cfg.model asks for another width: ignored, the initial network's architecture and output statistics are kept
    cfg = TrainConfig(model=ModelConfig(width=32), batch_size=64, epochs=1, eval_every=1000, ema_decay=0.5)
    res = train(cfg, train_samples=train_s, val_samples=test_s, init=base, progress=False, log=lambda s: None)
    assert res.net.config == base.config and res.net is not base
    for k, v in base.state_dict().items():
        torch.testing.assert_close(v, before[k])  # the initial network is not modified
    torch.testing.assert_close(res.net.target_mean, base.target_mean)
    assert not torch.allclose(res.net.stem.weight, base.stem.weight)  # but the copy was trained
    # with EMA, the returned network is the average, not the last weights: decay 0.5 over 1 step from `base`
    # gives the midpoint of the initial and the trained weights
    one = TrainConfig(batch_size=len(train_s), epochs=1, eval_every=1000, ema_decay=0.5, flip_prob=0.0)
    plain = train(replace(one, ema_decay=None), train_samples=train_s, val_samples=test_s, init=base,
                  progress=False, log=lambda s: None).net
    avg = train(one, train_samples=train_s, val_samples=test_s, init=base, progress=False, log=lambda s: None).net
    torch.testing.assert_close(avg.stem.weight, 0.5 * (base.stem.weight + plain.stem.weight))
    # the depth target is the initial network's, whatever cfg.model says
    absolute = train(TrainConfig(model=ModelConfig(width=64, depth_target="absolute"), batch_size=64, epochs=1,
                                 eval_every=1000), train_samples=train_s, val_samples=test_s,
                     progress=False, log=lambda s: None).net
    import lifter.train as train_module

    targets: list[str] = []
    as_tensors = train_module._as_tensors
    monkeypatch.setattr(train_module, "_as_tensors", lambda s, t: targets.append(t) or as_tensors(s, t))
    ft = train(cfg, train_samples=train_s, val_samples=test_s, init=absolute, progress=False, log=lambda s: None).net
    assert ft.config.depth_target == "absolute" and targets == ["absolute", "absolute"]  # train and val targets
    # real keypoints must align with the training samples
    with pytest.raises(ValueError, match="real_keypoints_2d"):
        train(cfg, train_samples=train_s, val_samples=test_s, real_keypoints_2d=np.zeros((3, 17, 2)),
              progress=False, log=lambda s: None)
