"""Metrics against hand-made cases."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_pose_cam

from lifter import PoseLifterError
from lifter.analytic import analytic_root
from lifter.camera import project
from lifter.metrics import auc, mpjpe, pa_mpjpe, pck, pck_curve, procrustes_align, root_errors


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.linalg.det(q))


@pytest.mark.parametrize("variant", ["standard", "repo"])
def test_pa_mpjpe_of_similar_copy_is_zero(variant):
    rng = np.random.default_rng(0)
    gt = random_pose_cam(rng, 4)
    R = _rotation(rng)
    pred = 1.7 * np.einsum("ij,npj->npi", R, gt) + rng.normal(0, 500, (4, 1, 3))
    np.testing.assert_allclose(pa_mpjpe(pred, gt, variant=variant), 0, atol=1e-6)
    assert np.all(mpjpe(pred, gt) > 10)


def test_pa_mpjpe_positive_for_nonrigid_error_and_bounded_by_mpjpe():
    rng = np.random.default_rng(1)
    gt = random_pose_cam(rng, 20)
    pred = gt + rng.normal(0, 30, gt.shape)
    pa, e = pa_mpjpe(pred, gt), mpjpe(pred, gt)
    assert np.all(pa > 1) and np.all(pa <= e + 1e-9)


def test_standard_procrustes_does_not_reflect():
    rng = np.random.default_rng(2)
    gt = random_pose_cam(rng, 1)[0]
    mirrored = gt * np.array([-1, 1, 1])
    aligned = procrustes_align(mirrored, gt)
    M = np.linalg.lstsq(mirrored - mirrored.mean(0), aligned - aligned.mean(0), rcond=None)[0]
    assert np.linalg.det(M) > 0


def test_mpjpe_known_value_and_root_alignment():
    gt = np.zeros((17, 3))
    gt[1:, 0] = np.arange(1, 17)
    pred = gt.copy()
    pred[5] += [0, 0, 17.0]  # one joint off by 17 mm
    pred += 1000.0  # a global offset is removed by root alignment
    assert mpjpe(pred, gt) == pytest.approx(1.0)


def test_mrpe_known_offset():
    gt = np.array([[100.0, 200.0, 5000.0], [0.0, 0.0, 3000.0]])
    pred = gt + np.array([[30.0, -40.0, 0.0], [0.0, 0.0, -120.0]])
    norm, axes = root_errors(pred, gt)
    np.testing.assert_allclose(norm, [50.0, 120.0])
    np.testing.assert_allclose(axes.mean(0), [15.0, 20.0, 60.0])


def test_pck_and_auc():
    from lifter.metrics import PCK_JOINTS

    gt = np.zeros((1, 17, 3))
    pred = np.zeros((1, 17, 3))
    errs = np.linspace(10, 300, 16)
    pred[0, 1:, 0] = errs  # joint errors of joints 1..16
    all_err = np.r_[0.0, errs]
    assert PCK_JOINTS == (1, 2, 3, 4, 5, 6, 8, 10, 11, 12, 13, 14, 15, 16)
    assert pck(pred, gt)[0] == pytest.approx(np.mean(all_err[list(PCK_JOINTS)] < 150))
    assert pck(pred, gt, joints=None)[0] == pytest.approx(np.mean(all_err < 150))
    c = pck_curve(pred, gt)
    assert np.all(np.diff(c) >= 0) and c[0] == pytest.approx(0.0)  # strict <: zero error fails at 0 mm
    assert auc(gt, gt) == pytest.approx(30 / 31)


def test_metric_shape_errors():
    with pytest.raises(ValueError, match="same shape"):
        mpjpe(np.zeros((17, 3)), np.zeros((16, 3)))


@pytest.mark.parametrize("method", ["rms", "lstsq"])
def test_analytic_root_recovers_root_under_weak_perspective(method):
    """A flat-ish body far away: weak perspective is nearly exact, so the analytic root is close."""
    rng = np.random.default_rng(3)
    pose = random_pose_cam(rng, 5)
    pose[..., 2] = pose[:, :1, 2] + 0.02 * (pose[..., 2] - pose[:, :1, 2])  # nearly fronto-parallel
    rel = pose - pose[:, :1]
    kp = project(pose, focal=1150.0, principal_point=(500.0, 500.0))
    root = analytic_root(kp, rel, focal=1150.0, principal_point=(500.0, 500.0), method=method)
    err, _ = root_errors(root, pose[:, 0])
    assert np.all(err < 0.01 * pose[:, 0, 2])


def test_metric_input_errors_name_the_problem():
    a = np.random.default_rng(0).normal(size=(5, 17, 3))
    with pytest.raises(PoseLifterError, match=r"expected 3D poses \(\.\.\., J, 3\) in mm, got shape \(5, 17, 2\) "
                       r"\(2D keypoints\?"):
        mpjpe(a[..., :2], a[..., :2])
    with pytest.raises(PoseLifterError, match="same shape"):
        mpjpe(a, a[:4])
    b = a.copy()
    b[1, 3, 0] = np.nan
    with pytest.raises(PoseLifterError, match=r"pa_mpjpe: pred contains 1 NaN/inf value\(s\)"):
        pa_mpjpe(b, a)


def test_auc_of_a_perfect_prediction_is_30_of_31():
    """The 0 mm threshold is one of the 31 and counts nothing (strict <), as in the 3DHP evaluation."""
    a = np.random.default_rng(1).normal(size=(3, 17, 3)) * 100
    assert auc(a, a) == pytest.approx(30 / 31)


def test_results_tables_keep_their_columns_for_long_model_labels():
    """A researcher trial: a checkpoint path longer than 28 characters as the label pushed its row's numbers out of
    their columns. Every table's model column is as wide as its longest label."""
    from lifter.evaluate import EvalRow, format_focal_table, format_per_action, format_table

    def row(label: str, mrpe: float = 90.0) -> EvalRow:
        return EvalRow(label=label, root="learned", num_samples=1, mpjpe=40.0, pa_mpjpe=30.0, mrpe=mrpe, mrpe_x=1.0,
                       mrpe_y=1.0, mrpe_z=1.0, pck150=0.9, auc=0.5, per_action={"Walking": {"mpjpe": 40.0}})

    long = "/work/main/assets/weights/universal_far_clean.pt"
    for text in (format_table([row("gt"), row(long)]), format_per_action([row("gt"), row(long)])):
        lines = [ln for ln in text.splitlines() if ln.startswith(("gt ", long, "model"))]
        assert len(lines) == 3 and len({len(ln) for ln in lines}) == 1, text  # (every row as wide as the head)
    sweep = format_focal_table({"gt": [row("x1")], long: [row("x1", 95.0)]})
    lines = sweep.splitlines()[1:]
    assert len({len(ln) for ln in lines if not ln.startswith("-")}) == 1, sweep
