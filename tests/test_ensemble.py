"""Ensembles (:attr:`lifter.Lifter.ensemble`): more networks for the same 2D, averaged after decoding.

Pinned: the lift is the mean of the members' lifts (relative pose, root, canonical depth), each member with its
own flip-test default; the symmetries every member has (mirror, resolution with scaled intrinsics) survive the
average; int8 copies keep the ensemble; nesting is refused; shipped members are checksummed.
"""

from __future__ import annotations

import numpy as np
import pytest
import torch
from conftest import random_pose_cam

from lifter import Lifter, ModelConfig, PoseCodec, PoseLifterError, PoseLifterNet
from lifter.camera import project
from lifter.skeleton import mirror

PP = (500.0, 490.0)
F = 1100.0

# The members are untrained (random heads): their roots land anywhere, often past FAR_ROOT_DEPTH_MM; the note that says
# so is not what these tests are about (tests/test_shipped.py pins it on the default)
pytestmark = pytest.mark.filterwarnings("ignore:.*root\\(s\\) lifted beyond:lifter.PoseLifterWarning")


def _member(seed: int, **config) -> Lifter:
    torch.manual_seed(seed)
    cfg = ModelConfig(width=32, conditioning="none", depth_target="size", **config)
    net = PoseLifterNet(cfg)
    with torch.no_grad():
        net.head.weight.normal_(0.0, 0.05)
    rng = np.random.default_rng(seed)
    mean = rng.normal(0.0, 100.0, 49)
    mean[-1] = 400.0
    return Lifter(net.eval(), PoseCodec(cfg, target_mean=mean, target_std=rng.uniform(30.0, 200.0, 49)),
                  name=f"m{seed}", flip_test=config.get("symmetry") != "mirror")


def _poses(n: int, seed: int = 1) -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(seed), n), focal=F, principal_point=PP)


def test_ensemble_is_the_mean_of_its_members():
    a, b = _member(0), _member(1, symmetry="mirror")
    ens = Lifter(a.net, a.codec, name="ens", flip_test=True, ensemble=[b])
    kp = _poses(5)
    for k in (kp, kp[2]):  # a batch (torch module) and one pose (numpy path)
        ra, rb, re = (x.lift(k, focal=F, principal_point=PP) for x in (a, b, ens))
        np.testing.assert_allclose(re.relative, 0.5 * (ra.relative + rb.relative), atol=1e-6)
        np.testing.assert_allclose(re.root, 0.5 * (ra.root + rb.root), atol=1e-6)
        np.testing.assert_allclose(re.canonical_depth, 0.5 * (ra.canonical_depth + rb.canonical_depth), atol=1e-6)
        assert np.abs(ra.relative - rb.relative).max() > 1.0  # the members differ, so the mean is a real test
    # flip_test=False switches the plain member's flip off; the mirror member is equivariant either way
    off = ens.lift(kp, focal=F, principal_point=PP, flip_test=False)
    ra_off = a.lift(kp, focal=F, principal_point=PP, flip_test=False)
    np.testing.assert_allclose(off.relative, 0.5 * (ra_off.relative + b.lift(kp, focal=F, principal_point=PP).relative),
                               atol=1e-6)


def test_members_share_encodings_only_when_their_codecs_encode_alike(monkeypatch):
    """Networks whose codecs have the same :attr:`PoseCodec.feature_key` are fed one encoding (and one of the
    mirror image); a member with other features gets its own, and the lift is still the mean of the members."""
    a, b, c = _member(4), _member(5, symmetry="mirror"), _member(6, scale_definition="repo")
    assert a.codec.feature_key == b.codec.feature_key != c.codec.feature_key
    ens = Lifter(a.net, a.codec, name="ens", flip_test=True, ensemble=[b, c])
    kp = _poses(3)
    calls: list[tuple] = []
    real = PoseCodec.encode

    def counting(self, keypoints, **kw):
        calls.append(self.feature_key)
        return real(self, keypoints, **kw)

    monkeypatch.setattr(PoseCodec, "encode", counting)
    re = ens.lift(kp, focal=F, principal_point=PP)
    # a: plain + mirror image; b reuses a's plain one; c (flip test on) its own two
    assert calls == [a.codec.feature_key] * 2 + [c.codec.feature_key] * 2
    members = [x.lift(kp, focal=F, principal_point=PP) for x in (a, b, c)]
    np.testing.assert_allclose(re.root, sum(r.root for r in members) / 3, atol=1e-6)
    np.testing.assert_allclose(re.relative, sum(r.relative for r in members) / 3, atol=1e-6)


def test_ensemble_keeps_the_symmetries_of_its_members():
    a, b = _member(2), _member(3, symmetry="mirror")
    ens = Lifter(a.net, a.codec, flip_test=True, ensemble=[b])
    kp = _poses(4)
    res = ens.lift(kp, focal=F, principal_point=PP)
    mir = ens.lift(ens.codec.mirror_input(kp, PP), focal=F, principal_point=PP)
    np.testing.assert_allclose(mir.relative, mirror(res.relative), atol=2e-3)
    k = 3.7  # the same camera at another resolution
    big = ens.lift(kp * k, focal=F * k, principal_point=(PP[0] * k, PP[1] * k))
    np.testing.assert_allclose(big.root, res.root, rtol=1e-4)


def test_ensemble_quantized_and_nesting_refused():
    a, b = _member(4), _member(5, symmetry="mirror")
    ens = Lifter(a.net, a.codec, flip_test=True, ensemble=[b])
    q = ens.quantized()
    assert len(q.ensemble) == 1 and q.ensemble[0].name.endswith("(int8)")
    kp = _poses(3)
    assert np.abs(q.lift(kp, focal=F, principal_point=PP).relative
                  - ens.lift(kp, focal=F, principal_point=PP).relative).max() < 5.0
    with pytest.raises(PoseLifterError, match="ensemble"):
        Lifter(a.net, a.codec, ensemble=[ens])
    with pytest.raises(PoseLifterError, match="ensemble"):
        Lifter(a.net, a.codec, clean=ens)


def test_shipped_ensemble_members_are_checksummed(monkeypatch):
    """The default's second network is loaded with its registry sha256: a wrong one is refused."""
    from lifter import resources
    from lifter.checkpoint import CheckpointError

    entry = resources.model_entry("default")
    assert entry.get("ensemble_files"), "the shipped default averages several networks"
    lifter = Lifter.from_pretrained()
    assert len(lifter.ensemble) == len(entry["ensemble_files"])
    assert lifter.ensemble[0].config.symmetry == "mirror"
    bad = {**entry, "ensemble_sha256": ["0" * 64] * len(entry["ensemble_files"])}
    monkeypatch.setattr(resources, "model_entry", lambda name: bad)
    with pytest.raises(CheckpointError, match="sha256|checksum"):
        Lifter.from_pretrained()
    monkeypatch.setattr(resources, "model_entry", lambda name: {**entry, "ensemble_sha256": []})
    with pytest.raises(PoseLifterError, match="differ in length"):
        Lifter.from_pretrained()


def test_the_far_note_follows_the_least_moved_network_of_an_ensemble():
    """far_root_depth_mm: 8 m for networks trained where the training subjects stood (no training config, or
    distance_prob 0 whatever distance_max says), 7.6 m x distance_max for networks trained with people moved along
    their rays, and for an ensemble the least-moved member's; the note that a lift past it gets says which."""
    from lifter.api import FAR_ROOT_DEPTH_MM, TRAINING_ROOT_MAX_MM

    def with_config(seed: int, augment: dict | None) -> Lifter:
        m = _member(seed)
        return Lifter(m.net, m.codec, name=m.name, train_config=None if augment is None else {"augment": augment})

    none, off = with_config(0, None), with_config(1, {"distance_prob": 0.0, "distance_max": 5.0})
    moved5, moved3 = with_config(2, {"distance_prob": 0.25, "distance_max": 5.0}), with_config(3, {"distance_prob": 0.5,
                                                                                                   "distance_max": 3.0})
    assert none.far_root_depth_mm == off.far_root_depth_mm == FAR_ROOT_DEPTH_MM
    assert moved5.far_root_depth_mm == pytest.approx(5 * TRAINING_ROOT_MAX_MM)
    assert moved3.far_root_depth_mm == pytest.approx(3 * TRAINING_ROOT_MAX_MM)
    both = Lifter(moved5.net, moved5.codec, name="both", train_config=moved5.train_config, ensemble=[moved3])
    assert both.far_root_depth_mm == pytest.approx(3 * TRAINING_ROOT_MAX_MM)
    mixed = Lifter(moved5.net, moved5.codec, name="mixed", train_config=moved5.train_config, ensemble=[none])
    assert mixed.far_root_depth_mm == FAR_ROOT_DEPTH_MM
    kp = np.zeros((1, 17, 2))
    root = np.array([[0.0, 0.0, 30000.0]])  # 30 m: past 8 m and 22.8 m, not past 38 m
    notes = {lf.name: [n for n in lf.output_notes(kp, np.zeros((1, 2)), root, source="detected") if n.kind == "far"]
             for lf in (none, moved5, moved3, mixed)}
    assert not notes["m2"] and len(notes["m3"]) == 1 and "7.6 m times 3" in notes["m3"][0]
    assert "trained where they stood" in notes["m0"][0] and "trained where they stood" in notes["mixed"][0]
    assert not moved3.output_notes(kp, np.zeros((1, 2)), root, source="clean")  # told clean: no far note
