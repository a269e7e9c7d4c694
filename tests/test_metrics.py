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


def test_only_the_repo_variant_aligns_a_mirror_image():
    """The authors' variant has no reflection fix, so it aligns a mirrored copy exactly; the standard one keeps a
    rotation and cannot (a review: with the standard branch run for "repo", every metric test passed)."""
    rng = np.random.default_rng(4)
    gt = random_pose_cam(rng, 4)
    mirrored = gt * np.array([-1.0, 1.0, 1.0])
    np.testing.assert_allclose(pa_mpjpe(mirrored, gt, variant="repo"), 0, atol=1e-6)
    assert np.all(pa_mpjpe(mirrored, gt, variant="standard") > 10)
    # and its scale is the RMS ratio, not the least-squares one: they differ once the shapes differ
    noisy = 0.8 * gt + rng.normal(0, 40, gt.shape)
    assert np.all(np.abs(pa_mpjpe(noisy, gt, variant="repo") - pa_mpjpe(noisy, gt, variant="standard")) > 0.1)


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
    # each threshold's share of the 14 PCK joints, written out (a review: a curve over all 17 joints passed)
    scored = all_err[list(PCK_JOINTS)]
    expected = [np.mean(scored < t) for t in range(0, 151, 5)]
    np.testing.assert_allclose(c, expected)
    assert abs(np.mean([np.mean(all_err < t) for t in range(0, 151, 5)]) - np.mean(expected)) > 0.01  # (differs)
    assert auc(pred, gt) == pytest.approx(np.mean(expected))
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


@pytest.mark.parametrize("correct", [True, False])
def test_analytic_root_methods_by_their_definitions(correct):
    """On a body with depth and 2D noise, where the two methods disagree: "rms" matches the 2D pose's RMS size to
    the 3D pose's seen at depth z, "lstsq" fits the 2D pose as (f / z) times the 3D pose's x, y by least squares
    (solved here by np.linalg.lstsq); ``mean_depth_correction`` moves the root by the mean relative depth (a review:
    both methods were tested only where they agree, and the correction's off switch never)."""
    rng = np.random.default_rng(8)
    pose = random_pose_cam(rng, 3)
    rel = pose - pose[:, :1]
    f, c = 1150.0, np.array([500.0, 500.0])
    kp = project(pose, focal=f, principal_point=c) + rng.normal(0, 3, (3, 17, 2))
    roots = {}
    for method in ("rms", "lstsq"):
        roots[method] = analytic_root(kp, rel, focal=f, principal_point=c, method=method,
                                      mean_depth_correction=correct)
    for i in range(3):
        dk = kp[i] - kp[i].mean(0)
        dP = rel[i, :, :2] - rel[i, :, :2].mean(0)
        shift = rel[i, :, 2].mean() if correct else 0.0
        z_rms = f * np.sqrt((dP**2).sum() / (dk**2).sum()) - shift
        m = np.linalg.lstsq(dP.reshape(-1, 1), dk.reshape(-1), rcond=None)[0][0]  # dk ~ (f / z) dP
        z_lstsq = f / m - shift
        for method, z in (("rms", z_rms), ("lstsq", z_lstsq)):
            np.testing.assert_allclose(roots[method][i, 2], z, rtol=1e-9)
            np.testing.assert_allclose(roots[method][i, :2], (kp[i, 0] - c) * z / f, rtol=1e-9)
    assert np.abs(roots["rms"][:, 2] - roots["lstsq"][:, 2]).max() > 5  # (the two differ here)


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
