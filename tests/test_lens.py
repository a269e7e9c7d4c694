"""Lens distortion: undistortion inverts H36M's lens model, and a lifter that learned pinhole 2D is given
undistorted 2D (``Lifter.lift(distortion=...)``), while one that learned H36M's own 2D is given it as it is."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import random_pose_cam, requires_h36m, tiny_lifter
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from lifter import Lifter, PoseLifterError, PoseLifterWarning
from lifter import camera as cam
from lifter.config import DataConfig

# one H36M camera's coefficients (S9, 54138969), and a stronger made-up lens (barrel, a few % at the border)
H36M_LENS = ((-0.2083, 0.2554, -0.0026), (-0.0011, -0.0026))
STRONG_LENS = ((-0.3, 0.1, 0.0), (0.002, -0.001))


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 10_000), strong=st.booleans())
def test_undistort_inverts_distort(seed, strong):
    k, p = STRONG_LENS if strong else H36M_LENS
    xy = np.random.default_rng(seed).uniform(-0.45, 0.45, (50, 2))  # a 1000-px image at f = 1145 px, and beyond
    back = cam.undistort(cam.distort(xy, k, p), k, p)
    np.testing.assert_allclose(back, xy, atol=1e-10)


def test_undistort_pixels_gives_the_pinhole_projection(rng):
    X = random_pose_cam(rng, 20)
    k, p = H36M_LENS
    f, c = (1145.0, 1144.0), (512.0, 515.0)
    distorted = cam.project(X, focal=f, principal_point=c, k=k, p=p)
    pinhole = cam.project(X, focal=f, principal_point=c)
    assert np.abs(distorted - pinhole).max() > 1.0  # (the lens moves the joints by whole pixels)
    np.testing.assert_allclose(cam.undistort_pixels(distorted, focal=f, principal_point=c, k=k, p=p), pinhole,
                               atol=1e-7)


def test_undistort_pixels_per_pose_lenses_and_missing_joints(rng):
    X = random_pose_cam(rng, 3)
    lenses = np.array([[*H36M_LENS[0], *H36M_LENS[1]], [0, 0, 0, 0, 0], [*STRONG_LENS[0], *STRONG_LENS[1]]])
    f, c = np.array([[1145.0, 1145.0], [900.0, 900.0], [1500.0, 1500.0]]), np.array([[512, 515], [400, 300], [0, 0.0]])
    d = np.stack([cam.project(X[i], focal=f[i], principal_point=c[i], k=lenses[i, :3], p=lenses[i, 3:])
                  for i in range(3)])
    d[1, 4] = np.nan  # a missing joint stays missing and does not spoil the others
    u = cam.undistort_pixels(d, focal=f, principal_point=c, k=lenses[:, :3], p=lenses[:, 3:])
    pin = cam.project(X, focal=f, principal_point=c)
    assert np.isnan(u[1, 4]).all()
    ok = np.isfinite(d).all(-1)
    np.testing.assert_allclose(u[ok], pin[ok], atol=1e-7)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 10_000))
def test_distort_jacobian_is_the_derivative_of_distort(seed):
    """``distort_jacobian`` (what the undistortion's Newton steps use) against central differences of
    ``distort``, rows x_d, y_d and columns x, y; and its ``gain`` is the factor ``distort`` scales by."""
    rng = np.random.default_rng(seed)
    k, p = rng.uniform(-0.5, 0.5, 3), rng.uniform(-0.05, 0.05, 2)
    xy = rng.uniform(-1.2, 1.2, (20, 2))
    J, gain = cam.distort_jacobian(xy, k, p)
    h = 1e-6
    for col in range(2):
        e = np.zeros(2)
        e[col] = h
        np.testing.assert_allclose(J[:, :, col], (cam.distort(xy + e, k, p) - cam.distort(xy - e, k, p)) / (2 * h),
                                   atol=1e-7)
    r2 = (xy**2).sum(-1)
    np.testing.assert_allclose(cam.distort(xy, k, p), xy * gain[:, None] + p[::-1] * r2[:, None], atol=1e-12)


def test_undistort_refuses_a_lens_it_cannot_invert():
    """k1 = -0.6 folds at r = 0.75 (r (1 - 0.6 r^2) peaks at 0.50): no point on the lens's own side reaches
    r_d = 2.1. A point past the fold does (x = -1.331 (1, 1) gives x_d = (1.5, 1.5)), and must not be returned."""
    k, p = (-0.6, 0.0, 0.0), (0.0, 0.0)
    np.testing.assert_allclose(cam.distort(np.array([-1.3313, -1.3313]), k, p), [1.5, 1.5], atol=1e-3)
    with pytest.raises(PoseLifterError, match="1 point.*no inverse through this lens.*too strong.*undistort the 2D "
                                              "yourself"):
        cam.undistort(np.array([[0.1, 0.1], [1.5, 1.5]]), k, p)


@settings(max_examples=60, deadline=None)
@given(k1=st.floats(-0.5, 0.5), k2=st.floats(-0.3, 0.3), k3=st.floats(-0.1, 0.1), p1=st.floats(-0.01, 0.01),
       p2=st.floats(-0.01, 0.01), seed=st.integers(0, 10_000), reach=st.floats(0.05, 0.8))
@example(k1=0.0703125, k2=-0.259765625, k3=0.0703125, p1=0.0, p2=0.0078125, seed=0, reach=0.5)
@example(k1=0.0703125, k2=-0.259765625, k3=0.0703125, p1=0.0, p2=0.0078125, seed=188, reach=0.5)
def test_undistort_inverts_any_lens_up_to_its_fold(k1, k2, k3, p1, p2, seed, reach):
    """Points anywhere inside the radius where the radial map r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops rising (to
    `reach` of it, at most r = 3: 72 deg off the axis) come back exactly. The fixed-point iteration used before
    stopped short beyond r ~ 1.2 with Human3.6M's own lens, and where the pincushion pushes x_d past the fold."""
    k, p = (k1, k2, k3), (p1, p2)
    r = np.linspace(0.0, 3.0, 3001)
    # the fold: where the radial map's slope 1 + 3 k1 r^2 + 5 k2 r^4 + 7 k3 r^6 falls below 0.1 (CI found a lens whose
    # radial slope only dips to 0.04 near r = 1.35: its tangential terms (p2 = 0.0078) fold it there, and a point at
    # r = 1.29 has two preimages, so "comes back exactly" has no single answer)
    rising = 1 + 3 * k1 * r**2 + 5 * k2 * r**4 + 7 * k3 * r**6 > 0.1
    r_fold = r[np.argmin(rising)] if not rising.all() else 3.0
    rng = np.random.default_rng(seed)
    radius, angle = rng.uniform(0.0, reach * r_fold, 64), rng.uniform(0.0, 2 * np.pi, 64)
    xy = np.stack([radius * np.cos(angle), radius * np.sin(angle)], axis=-1)
    np.testing.assert_allclose(cam.undistort(cam.distort(xy, k, p), k, p), xy, atol=1e-9)


@settings(max_examples=200, deadline=None)
@given(k1=st.floats(-0.6, 0.6), k2=st.floats(-0.4, 0.4), k3=st.floats(-0.15, 0.15), r_d=st.floats(0.0, 3.0))
@example(k1=-0.6, k2=0.1, k3=0.0, r_d=1.0)  # folds at r = 0.83 (g_max 0.53) and rises again past r = 2.2
def test_undistort_of_a_radial_lens_finds_the_own_side_point_or_refuses(k1, k2, k3, r_d):
    """For a radial lens the answer is known: the distorted radius r_d has an inverse on the lens's own side iff it
    is below the radial map's first maximum g_max (where r (1 + k1 r^2 + k2 r^4 + k3 r^6) stops rising at r_fold),
    and that inverse has r <= r_fold. Anything else (a point further out that the lens also sends to r_d, in the
    second rising region of a curve that falls and rises again) must be refused, not returned."""
    k = (k1, k2, k3)
    r = np.linspace(0.0, 4.0, 40_001)
    g = r * (1 + k1 * r**2 + k2 * r**4 + k3 * r**6)
    falls = np.diff(g) <= 0
    fold = int(np.argmax(falls)) if falls.any() else len(r) - 1
    g_max, r_fold = g[: fold + 1].max(), r[fold]
    assume(abs(r_d - g_max) > 1e-3)  # (the grid's resolution)
    xd = np.array([[r_d * 0.8, r_d * 0.6]])
    if r_d < g_max:
        x = cam.undistort(xd, k, (0.0, 0.0))
        assert np.hypot(*x[0]) <= r_fold + 1e-3
        np.testing.assert_allclose(cam.distort(x, k, (0.0, 0.0)), xd, atol=1e-9)
    else:
        with pytest.raises(PoseLifterError, match="no inverse through this lens"):
            cam.undistort(xd, k, (0.0, 0.0))


def test_undistort_broadcasts_points_against_per_pose_lenses():
    """One point against 4 lenses gives 4 answers, as ``distort`` broadcasts; shapes that do not broadcast are
    refused by name."""
    k = np.array([[-0.2, 0.2, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0], [-0.3, 0.1, 0.0]])
    p = np.zeros((4, 2))
    xy = np.array([0.3, 0.2])
    out = cam.undistort(xy, k, p)
    assert out.shape == (4, 2)
    np.testing.assert_allclose(cam.distort(out, k, p), np.broadcast_to(xy, (4, 2)), atol=1e-12)
    with pytest.raises(PoseLifterError, match=r"points \(3, 2\), k \(4, 3\) .* do not broadcast"):
        cam.undistort(np.zeros((3, 2)), k, p)


def test_undistort_beyond_the_old_iterations_reach():
    """Cases the fixed-point iteration refused: Human3.6M's lens 1.2-2 focal lengths off the centre (a short focal
    length typed for a wide photo), and a pincushion lens whose distorted point lies past its fold."""
    k, p = H36M_LENS
    xy = np.array([[1.2, 0.0], [0.96, 0.72], [1.28, 0.96], [-1.6, 1.2]])
    np.testing.assert_allclose(cam.undistort(cam.distort(xy, k, p), k, p), xy, atol=1e-10)
    k, p = (0.16, 0.05, -0.034), (0.001, 0.002)  # r (1 + 0.16 r^2 + ...) stops rising at r = 1.586
    xy = np.array([[1.26, 0.61]])  # r = 1.40
    assert np.hypot(*cam.distort(xy, k, p)[0]) > 1.6  # x_d itself lies past the fold
    np.testing.assert_allclose(cam.undistort(cam.distort(xy, k, p), k, p), xy, atol=1e-10)


def test_undistort_converges_for_a_wide_angle_lens_near_the_border():
    """A user trial's case: a strong barrel lens (k1 = -0.3) and points near the image border, where a fixed
    number of steps had stopped short (residual 1.3e-9) and the lift was refused."""
    k, p = (-0.3, 0.1, 0.0), (0.0, 0.0)
    xy = np.array([[0.70, 0.38], [0.55, 0.05], [-0.6, -0.4]])  # 1280 x 720 at f = 600 px reaches |x| ~ 1.07
    back = cam.undistort(cam.distort(xy, k, p), k, p)
    np.testing.assert_allclose(back, xy, atol=1e-11)


def test_undistort_leaves_a_half_missing_joint_missing_and_the_rest_exact():
    k, p = H36M_LENS
    xy = np.array([[0.1, 0.2], [np.nan, 0.3], [0.2, -0.1]])
    d = cam.distort(np.nan_to_num(xy), k, p)
    d[1, 0] = np.nan
    out = cam.undistort(d, k, p)
    assert np.isnan(out[1]).all()
    np.testing.assert_allclose(out[[0, 2]], xy[[0, 2]], atol=1e-12)


@pytest.mark.parametrize(("k", "p", "message"), [
    ((0.1, 0.0, 0.0, 0.0, 0.0), (0.0, 0.0), r"k must be \(k1, k2, k3\) and p \(p1, p2\)"),
    ((0.1, 0.0), (0.0, 0.0), r"k must be \(k1, k2, k3\)"),
    (None, (0.0, 0.0), r"k must be"),
    ((np.nan, 0.0, 0.0), (0.0, 0.0), "coefficients must be finite"),
    (np.zeros((17, 3)), (0.0, 0.0), r"does not match the keypoints' poses"),
])
def test_undistort_pixels_checks_its_lens(k, p, message):
    kp = np.arange(34, dtype=float).reshape(17, 2) * 10
    with pytest.raises(PoseLifterError, match=message):
        cam.undistort_pixels(kp, focal=1000.0, principal_point=(500, 500), k=k, p=p)


def pinhole_lifter(**kw) -> Lifter:
    lf = tiny_lifter(**kw)
    lf.train_config = {"data": {"lens": "pinhole"}}
    return lf


def test_lens_property_reads_the_training_config():
    assert tiny_lifter().lens == "h36m"  # a checkpoint that does not say learned H36M's own 2D
    assert pinhole_lifter().lens == "pinhole"
    bad = tiny_lifter()
    bad.train_config = {"data": {"lens": "fisheye"}}
    with pytest.raises(PoseLifterError, match="data.lens is 'fisheye'"):
        _ = bad.lens


def test_lift_undistorts_for_a_pinhole_lifter_only(rng):
    X = random_pose_cam(rng, 8)
    k, p = H36M_LENS
    f, c = 1145.0, (512.0, 515.0)
    distorted = cam.project(X, focal=f, principal_point=c, k=k, p=p)
    pinhole = cam.project(X, focal=f, principal_point=c)
    lens = (*k, *p)
    lf = pinhole_lifter()
    given_lens = lf.lift(distorted, focal=f, principal_point=c, distortion=lens)
    np.testing.assert_allclose(given_lens.root, lf.lift(pinhole, focal=f, principal_point=c).root, rtol=1e-5)
    np.testing.assert_allclose(given_lens.keypoints_2d, pinhole, atol=1e-6)  # (what was lifted)
    assert not np.allclose(lf.lift(distorted, focal=f, principal_point=c).root, given_lens.root, rtol=1e-4)
    old = tiny_lifter()  # learned H36M's distorted 2D: given it as it is, and said (a developer trial: nothing was)
    with pytest.warns(PoseLifterWarning, match=r"model 'small' learned Human3.6M's 2D with that camera's own lens "
                                               r"distortion .* the distortion given is not undone"):
        kept = old.lift(distorted, focal=f, principal_point=c, distortion=lens)
    np.testing.assert_array_equal(kept.root, old.lift(distorted, focal=f, principal_point=c).root)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)  # (a lens of zeros changes nothing: nothing to say)
        old.lift(distorted, focal=f, principal_point=c, distortion=np.zeros(5))
    per_pose = np.tile(np.asarray(lens), (8, 1))
    np.testing.assert_allclose(lf.lift(distorted, focal=f, principal_point=c, distortion=per_pose).root,
                               given_lens.root, rtol=1e-12)


def test_lift_distortion_errors_name_the_fix():
    kp = cam.project(random_pose_cam(np.random.default_rng(1), 2), focal=1000.0, principal_point=(500, 500))
    lf = pinhole_lifter()
    with pytest.raises(PoseLifterError, match="distortion needs the focal length.*pass focal="):
        lf.lift(kp, image_size=(1000, 1000), distortion=(0.1, 0, 0, 0, 0))
    with pytest.raises(PoseLifterError, match=r"distortion must be \(k1, k2, k3, p1, p2\).*OpenCV.*\(2 value"):
        lf.lift(kp, focal=1000.0, principal_point=(500, 500), distortion=(0.1, 0.0))
    for bad in ("abc", ["a", 0, 0, 0, 0], {"k1": 0.1}, [[0.1, 0], [0, 0, 0]]):
        with pytest.raises(PoseLifterError, match="distortion must be"):
            lf.lift(kp, focal=1000.0, principal_point=(500, 500), distortion=bad)
    with pytest.raises(PoseLifterError, match=r"pose at index \(1,\).*must be finite and below 10.*nan"):
        lf.lift(kp, focal=1000.0, principal_point=(500, 500), distortion=[[0.1, 0, 0, 0, 0], [np.nan, 0, 0, 0, 0]])
    with pytest.raises(PoseLifterError, match="below 10 in magnitude"):
        lf.lift(kp, focal=1000.0, principal_point=(500, 500), distortion=[1e6, 0, 0, 0, 0])
    with pytest.raises(PoseLifterError, match=r"distortion: shape \(3, 5\) does not match the keypoints' poses"):
        lf.lift(kp, focal=1000.0, principal_point=(500, 500), distortion=np.zeros((3, 5)))


def test_ensemble_members_must_share_the_lens():
    a, b = tiny_lifter(seed=1), pinhole_lifter(seed=2)
    with pytest.raises(PoseLifterError, match="ensemble members must have learned the same 2D"):
        Lifter(a.net, a.codec, ensemble=[b])


def test_data_config_lens_is_validated():
    assert DataConfig().lens == "h36m"
    with pytest.raises(PoseLifterError, match="lens must be one of"):
        DataConfig(lens="fisheye")  # type: ignore[arg-type]


@requires_h36m
def test_h36m_pinhole_samples_and_undistorted_2d(h36m):
    s = h36m.load([9], stride=1000, cameras=["54138969", "60457274"])
    q = h36m.load([9], stride=1000, cameras=["54138969", "60457274"], lens="pinhole")
    assert (s.lens, q.lens) == ("h36m", "pinhole")
    assert np.abs(s.keypoints_2d - q.keypoints_2d).max() > 5.0  # H36M's lenses move border joints by ~10 px
    np.testing.assert_allclose(s.undistort(s.keypoints_2d), q.keypoints_2d, atol=1e-3)
    assert s.input_distortion is s.distortion and q.input_distortion is None
    cam9 = h36m.camera(9, "60457274")
    np.testing.assert_array_equal(s.distortion[s.camera == 3][0], np.float32([*cam9.k, *cam9.p]))


@requires_h36m
def test_training_refuses_samples_of_the_other_lens(h36m):
    from lifter.config import TrainConfig
    from lifter.train import train

    s = h36m.load([1], stride=500, max_frames_per_sequence=2)
    with pytest.raises(PoseLifterError, match="lens='h36m' but the config says data.lens='pinhole'"):
        train(TrainConfig(data=DataConfig(lens="pinhole")), data=h36m, train_samples=s, val_sets={}, progress=False)


def _write(path, obj):
    import json

    path.write_text(json.dumps(obj))
    return path


def test_keypoint_file_and_sequence_distortion_is_lifted_undistorted(tmp_path, rng):
    """A keypoint file's "distortion" reaches the lift: a pinhole lifter gives the same roots as for the
    undistorted file, the record keeps the 2D as given and says which lens; a sequence likewise."""
    from lifter.pipeline import lift_keypoint_file
    from lifter.video import lift_keypoint_sequence

    k, p = H36M_LENS
    f, c = 1145.0, (512.0, 515.0)
    X = random_pose_cam(rng, 2)
    d = cam.project(X, focal=f, principal_point=c, k=k, p=p)
    u = cam.project(X, focal=f, principal_point=c)
    lf = pinhole_lifter()
    meta = {"focal": f, "principal_point": list(c), "image_size": [1000, 1000], "source": "clean"}
    with_lens = lift_keypoint_file(_write(tmp_path / "d.json", {"keypoints": d[0].tolist(), **meta,
                                                                 "distortion": [*k, *p]}), lifter=lf)
    plain = lift_keypoint_file(_write(tmp_path / "u.json", {"keypoints": u[0].tolist(), **meta}), lifter=lf)
    np.testing.assert_allclose(with_lens.root, plain.root, rtol=1e-6)
    np.testing.assert_allclose(with_lens.keypoints_2d, d[0], atol=1e-9)  # (the record keeps the 2D as given)
    assert with_lens.to_dict()["distortion"] == pytest.approx([*k, *p]) and "distortion" not in plain.to_dict()
    seq = {"frames": [{"keypoints": q.tolist()} for q in d], "fps": 25, **meta, "distortion": [*k, *p]}
    rec = lift_keypoint_sequence(_write(tmp_path / "s.json", seq), lifter=lf, smoothing=0.0)
    ref = lf.lift(u, focal=f, principal_point=c, source="clean")
    np.testing.assert_allclose([fr.people[0].root for fr in rec.frames], ref.root, rtol=1e-6)
    assert rec.to_dict()["distortion"] == pytest.approx([*k, *p])


@pytest.mark.parametrize(("distortion", "focal", "message"), [
    ([0.1, 0.0, 0.0, 0.0], 1000.0, r"distortion must be \[k1, k2, k3, p1, p2\]: five numbers"),
    ([0.1, 0.0, 0.0, 0.0, 25.0], 1000.0, r"distortion must be .* got \[0.1, 0.0, 0.0, 0.0, 25.0\]"),
    ("barrel", 1000.0, "distortion must be"),
])
def test_keypoint_file_distortion_errors_name_the_field(tmp_path, distortion, focal, message):
    from lifter.io import parse_keypoint_json

    obj = {"keypoints": (np.arange(34).reshape(17, 2) * 10.0).tolist(), "distortion": distortion}
    if focal is not None:
        obj["focal"] = focal
    with pytest.raises(PoseLifterError, match=message):
        parse_keypoint_json(_write(tmp_path / "k.json", obj))


def test_camera_distortion_property():
    from lifter.camera import Camera

    assert Camera(focal=(1000.0, 1000.0), principal_point=(500.0, 500.0), width=1000, height=1000).distortion is None
    c = Camera(focal=(1000.0, 1000.0), principal_point=(500.0, 500.0), width=1000, height=1000, k=H36M_LENS[0],
               p=H36M_LENS[1])
    assert c.distortion == (*H36M_LENS[0], *H36M_LENS[1])


def test_keypoint_file_distortion_needs_a_focal_given_not_assumed(tmp_path, rng):
    """Lens coefficients act on px / focal: with the focal assumed from the image size the lift is refused, naming
    both ways to give it; with --focal (the CLI's focal=) the file's lens is used."""
    from lifter.pipeline import lift_keypoint_file

    k, p = H36M_LENS
    X = random_pose_cam(rng, 1)[0]
    d = cam.project(X, focal=1145.0, principal_point=(512.0, 515.0), k=k, p=p)
    path = _write(tmp_path / "k.json", {"keypoints": d.tolist(), "image_size": [1000, 1000],
                                        "principal_point": [512, 515], "distortion": [*k, *p]})
    lf = pinhole_lifter()
    with pytest.raises(PoseLifterError, match="'distortion' needs the camera's own focal length: put 'focal'.*--focal"):
        lift_keypoint_file(path, lifter=lf)
    rec = lift_keypoint_file(path, lifter=lf, focal=1145.0)
    want = lf.lift(cam.project(X, focal=1145.0, principal_point=(512.0, 515.0)), focal=1145.0,
                   principal_point=(512.0, 515.0))
    np.testing.assert_allclose(rec.root, want.root, rtol=1e-6)
    assert not any("replaces" in w for w in rec.warnings)
    # a --focal replacing the file's own focal applies the file's lens with it, and the note says so
    with_focal = _write(tmp_path / "f.json", {"keypoints": d.tolist(), "focal": 1145.0, "principal_point": [512, 515],
                                              "distortion": [*k, *p]})
    rec = lift_keypoint_file(with_focal, lifter=lf, focal=1300.0)
    assert any("replaces the file's own (1145 x 1145 px); the file's 'distortion' is applied with it" in w
               and "leave focal= (--focal) out" in w for w in rec.warnings), rec.warnings
    plain = _write(tmp_path / "g.json", {"keypoints": d.tolist(), "focal": 1145.0, "principal_point": [512, 515]})
    assert not any("'distortion'" in w for w in lift_keypoint_file(plain, lifter=lf, focal=1300.0).warnings)


def test_pose_samples_without_a_lens_model_are_pinhole(rng):
    """Samples built without ``distortion`` (ideal pinhole cameras) need no lens: nothing to pass to lift, and
    undistorting leaves the 2D as it is."""
    from lifter.data import PoseSamples

    X = random_pose_cam(rng, 3)
    kp = cam.project(X, focal=1000.0, principal_point=(500.0, 500.0))
    z = np.zeros(3, np.int32)
    s = PoseSamples(keypoints_2d=kp.astype(np.float32), pose_3d=X.astype(np.float32),
                    focal=np.full((3, 2), 1000, np.float32), principal_point=np.full((3, 2), 500, np.float32),
                    image_size=np.full((3, 2), 1000, np.int32), subject=z + 1, action=z, camera=z, frame=z,
                    sequence=z, sequence_names=("S1/Walking 1",))
    assert s.distortion is None and s.input_distortion is None
    np.testing.assert_array_equal(s.undistort(s.keypoints_2d), s.keypoints_2d)
    assert s.subset(np.array([0, 2])).distortion is None


def test_misplaced_camera_fields_get_a_note_not_silence(tmp_path):
    """A user trial put "distortion" inside a person and inside a sequence's frame: it was not read, and nothing
    said so. Now a note names the field and where it belongs; at the top level there is no note."""
    from lifter.io import parse_keypoint_json, parse_keypoint_sequence

    kp = (np.arange(34).reshape(17, 2) * 10.0 + 100).tolist()
    lens = [*H36M_LENS[0], *H36M_LENS[1]]
    person = parse_keypoint_json(_write(tmp_path / "p.json", {"people": [{"keypoints": kp, "distortion": lens}],
                                                               "focal": 1000}))
    assert person.distortion is None
    assert any("'distortion' inside a person is not read" in n and "top level" in n for n in person.warnings)
    top = parse_keypoint_json(_write(tmp_path / "t.json", {"people": [{"keypoints": kp}], "focal": 1000,
                                                            "distortion": lens}))
    assert top.distortion is not None and not any("not read" in n for n in top.warnings)
    seq = parse_keypoint_sequence(_write(tmp_path / "s.json", {
        "frames": [{"keypoints": kp}, {"keypoints": kp, "focal": 900, "distortion": lens}], "fps": 25}))
    assert any("'distortion' (first in frame 1), 'focal' (first in frame 1) inside a frame is not read" in n
               for n in seq.warnings), seq.warnings


def test_other_names_for_read_fields_get_a_note_naming_ours(tmp_path):
    """A misspelled "distorsion" or OpenCV's "dist_coeffs" at the top level used to be dropped silently (the 2D
    was then lifted as undistorted). Now a note names the field it was probably meant for (for OpenCV's
    coefficients, also their other order); unrelated fields and the fields of our own results are not noted,
    so a result read back as a keypoint file gets no such note."""
    from lifter.io import LiftRecord, PersonResult, parse_keypoint_json, parse_keypoint_sequence

    kp = (np.arange(34).reshape(17, 2) * 10.0 + 100).tolist()
    lens = [*H36M_LENS[0], *H36M_LENS[1]]
    f = parse_keypoint_json(_write(tmp_path / "a.json", {"keypoints": kp, "focal": 1000, "distorsion": lens,
                                                          "dist_coeffs": lens, "focal_length": 900, "K": [[1]],
                                                          "image": "a.jpg", "version": 2}))
    assert f.distortion is None
    notes = [n for n in f.warnings if "is not read" in n]
    assert len(notes) == 3, f.warnings  # (not 'focal_length': the file has 'focal', which is read)
    assert "'distorsion' is not read: did you mean 'distortion'?" in notes
    assert any(n.startswith("'dist_coeffs' is not read: did you mean 'distortion'? It takes Human3.6M's order")
               and "\"distortion_model\": \"opencv\"" in n for n in notes)
    assert any(n.startswith("'K' is not read: did you mean 'focal' and 'principal_point'?") for n in notes)
    # (a developer trial: a focal length in mm under its own name was dropped without a word)
    g = parse_keypoint_json(_write(tmp_path / "mm.json", {"keypoints": kp, "focal_mm": 35, "image_size": [800, 600]}))
    assert any(n.startswith("'focal_mm' is not read: did you mean 'focal'? It takes the focal length in pixels: "
                            "f_px = f_mm * image width px / sensor width mm") for n in g.warnings), g.warnings
    seq = parse_keypoint_sequence(_write(tmp_path / "s.json", {"frames": [kp, kp], "fps": 25, "Distortion": lens}))
    assert seq.distortion is None and any("'Distortion' is not read: did you mean 'distortion'?" in n
                                          for n in seq.warnings), seq.warnings
    rec = LiftRecord(input="x.json", kind="keypoints", model="universal", keypoints_2d=np.asarray(kp),
                     absolute=np.zeros((17, 3)), relative=np.zeros((17, 3)), root=np.array([0.0, 0.0, 3000.0]),
                     canonical_depth=3.0, focal=(1000.0, 1000.0), focal_source="given",
                     principal_point=(500.0, 500.0), image_size=(1000, 1000), distortion=tuple(lens),
                     people=(PersonResult(keypoints_2d=np.asarray(kp), absolute=np.zeros((17, 3)),
                                          relative=np.zeros((17, 3)), root=np.array([0.0, 0.0, 3000.0]),
                                          canonical_depth=3.0, input_index=0),))
    back = parse_keypoint_json(_write(tmp_path / "r.json", rec.to_dict()))
    assert back.distortion is not None and not any("not read" in n for n in back.warnings), back.warnings


def test_an_error_about_a_missing_field_repeats_the_unread_fields(tmp_path):
    """A user trial's file said "focal_length" and no image size: the lift failed with "no focal length", and
    the note that would have explained it was dropped with the record. The error now ends with the file's notes
    on fields that are not read; a nested "camera" object gets its own hint."""
    from lifter.pipeline import lift_keypoint_file
    from lifter.video import lift_keypoint_sequence

    kp = (np.arange(34).reshape(17, 2) * 10.0 + 100).tolist()
    lf = pinhole_lifter()
    path = _write(tmp_path / "a.json", {"keypoints": kp, "focal_length": 1145, "principal_point": [512, 515]})
    with pytest.raises(PoseLifterError, match=r"no focal length and no image size: .*\. Also in the file: "
                                              r"'focal_length' is not read: did you mean 'focal'\?$"):
        lift_keypoint_file(path, lifter=lf)
    path = _write(tmp_path / "c.json", {"keypoints": kp, "camera": {"focal": 1145}, "principal_point": [512, 515]})
    with pytest.raises(PoseLifterError, match=r"Also in the file: 'camera' is not read: .*Camera fields go at the "
                                              r"file's top level"):
        lift_keypoint_file(path, lifter=lf)
    path = _write(tmp_path / "s.json", {"frames": [kp, kp], "fps": 10, "K": [[1145, 0, 512], [0, 1145, 515]]})
    with pytest.raises(PoseLifterError, match=r"Also in the file: 'K' is not read: did you mean 'focal' and "
                                              r"'principal_point'\?"):
        lift_keypoint_sequence(path, lifter=lf)  # (two rows: not a camera matrix)
    ok = _write(tmp_path / "ok.json", {"keypoints": kp, "image_size": [1000, 1000]})
    assert lift_keypoint_file(ok, lifter=lf).root[2] > 0  # (no unread fields: lifted as before)


def test_a_keypoint_files_camera_matrix_is_read(tmp_path, rng):
    """A user trial's file gave OpenCV's "K" (and "dist_coeffs"): it was lifted at an assumed focal with exit code
    0, the calibrated camera silently an uncalibrated one. A 3 x 3 camera matrix (nested, flat or ROS's
    {"data": [...]}) under "K", "camera_matrix", "intrinsics", ... now gives the focal and principal point."""
    from lifter.pipeline import lift_keypoint_file
    from lifter.video import lift_keypoint_sequence

    X = random_pose_cam(rng, 1)
    f, c = (1145.0, 1144.0), (512.0, 515.0)
    kp = cam.project(X, focal=f, principal_point=c)[0].tolist()
    K = [[f[0], 0, c[0]], [0, f[1], c[1]], [0, 0, 1]]
    lf = pinhole_lifter()
    want = lf.lift(np.asarray(kp), focal=f, principal_point=c)
    for key, value in (("K", K), ("camera_matrix", {"rows": 3, "cols": 3, "data": sum(K, [])}),
                       ("intrinsics", sum(K, []))):
        rec = lift_keypoint_file(_write(tmp_path / f"{key}.json", {"keypoints": kp, key: value}), lifter=lf)
        np.testing.assert_allclose(rec.root, want.root, rtol=1e-9)
        assert rec.focal == f and rec.principal_point == c and rec.focal_source == "keypoint-file"
        assert not any("is not read" in w for w in rec.warnings), rec.warnings
    seq = lift_keypoint_sequence(_write(tmp_path / "seq.json", {"frames": [kp, kp], "fps": 10, "K": K}), lifter=lf,
                                 smoothing=0.0)
    assert seq.focal == f and seq.principal_point == c
    with pytest.raises(PoseLifterError, match=r"'focal' \[1000.0, 1000.0\] and the camera matrix 'K' "
                                              r"\(\[1145.0, 1144.0\]\) disagree"):
        lift_keypoint_file(_write(tmp_path / "both.json", {"keypoints": kp, "K": K, "focal": 1000}), lifter=lf)
    same = lift_keypoint_file(_write(tmp_path / "same.json", {"keypoints": kp, "K": K, "focal": list(f)}), lifter=lf)
    np.testing.assert_allclose(same.root, want.root, rtol=1e-9)
    # (a developer trial: each of these was dropped, the focal assumed, with a note asking for 'focal') a multiple
    # of K is the same camera; a calibration's tiny skew is left out; a transposed K or a real skew is refused by name
    for name, value in (("scaled", (2 * np.asarray(K)).tolist()), ("skew", [[f[0], 0.5, c[0]], K[1], K[2]])):
        rec = lift_keypoint_file(_write(tmp_path / f"{name}.json", {"keypoints": kp, "K": value}), lifter=lf)
        np.testing.assert_allclose(rec.root, want.root, rtol=1e-9)
        assert rec.focal == f and rec.focal_source == "keypoint-file"
    for value, match in ((np.asarray(K).T.tolist(), "it is transposed: its last row holds the principal point"),
                         ([[f[0], 30, c[0]], K[1], K[2]], r"its skew \(30, 0\) is more than the 0.001 x fx left out"),
                         ([K[0], K[1], [0, 0.1, 1]], r"its last row must be \[0, 0, 1\], got \[0.0, 0.1, 1.0\]")):
        with pytest.raises(PoseLifterError, match=r"'K' is read as the camera matrix, but " + match):
            lift_keypoint_file(_write(tmp_path / "bad.json", {"keypoints": kp, "K": value}), lifter=lf)
        # (a review) beside the file's own focal and principal point, such a K is left out, and said
        rec = lift_keypoint_file(_write(tmp_path / "own.json", {"keypoints": kp, "K": value, "focal": list(f),
                                                                "principal_point": list(c)}), lifter=lf)
        np.testing.assert_allclose(rec.root, want.root, rtol=1e-9)
        assert any("'K' is not read as the camera matrix: " in w and "'focal' and 'principal_point' are used" in w
                   for w in rec.warnings), rec.warnings
    # (a review) ROS marks an uncalibrated camera with a K of zeros: not read, said, the file's own camera used
    zeros = [[0, 0, 0], [0, 0, 0], [0, 0, 0]]
    rec = lift_keypoint_file(_write(tmp_path / "ros.json", {"keypoints": kp, "K": zeros, "focal": list(f),
                                                            "principal_point": list(c)}), lifter=lf)
    np.testing.assert_allclose(rec.root, want.root, rtol=1e-9)
    assert any("'K' is all zeros, as ROS marks an uncalibrated camera: not read" in w for w in rec.warnings)


def test_unread_field_notes_name_the_right_field_and_spare_other_formats():
    """A review: Human3.6M's own camera names ("k", "p": the lens) were taken for OpenCV's camera matrix "K" or
    not noted at all; a COCO annotation's "num_keypoints", a "keypoints_3d" or a bounding-box "center" got false
    notes; "fx" beside "focal" was noted although the focal was read. One-letter names are now case-sensitive,
    other formats' fields are left alone, and an alias of a field the file has is not noted."""
    from lifter.io import unread_field_notes

    got = unread_field_notes({"f": 1145, "c": [512, 515], "k": [0.1, 0, 0], "p": [0, 0], "K": [[1]]})
    assert [n.split(" is not read")[0] for n in got] == ["'f'", "'c'", "'k'", "'p'", "'K'"]
    assert "did you mean 'distortion'? Human3.6M's cameras name the lens k" in got[2]
    assert "did you mean 'focal' and 'principal_point'? (fx, fy and cx, cy of the camera matrix" in got[4]
    assert unread_field_notes({"num_keypoints": 17, "image_id": 3, "category_id": 1, "bbox": [0, 0, 1, 1],
                               "keypoints_3d": [], "center": [1, 2], "score": 0.9}) == []
    assert unread_field_notes({"fx": 1, "focal": 1, "width": 2, "height": 3, "image_size": [2, 3]}) == []
    assert unread_field_notes({"fx": 1}) == ["'fx' is not read: did you mean 'focal'?"]


def test_one_letter_slips_of_short_field_names_get_a_note():
    """A helper's trial: "sourse" (a one-letter slip of a short name) scored below difflib's cutoff and was dropped
    silently, and "focal_px" / "image_shape" got no note. Other formats' and unrelated fields stay unnoted."""
    from lifter.io import unread_field_notes

    assert unread_field_notes({"sourse": "clean"}) == ["'sourse' is not read: did you mean 'source'?"]
    assert unread_field_notes({"fromat": "coco17"}) == ["'fromat' is not read: did you mean 'format'?"]  # swapped
    assert unread_field_notes({"sources": "clean"}) == ["'sources' is not read: did you mean 'source'?"]  # added
    assert unread_field_notes({"focal_px": 800}) == ["'focal_px' is not read: did you mean 'focal'?"]
    assert unread_field_notes({"image_shape": [8, 6]}) == ["'image_shape' is not read: did you mean 'image_size'?"]
    assert unread_field_notes({"scores": [1], "person": 1, "frame": 2, "notes": "x", "people_count": 3}) == []


# -- OpenCV's lens model (distortion_model="opencv"): a user trial passed cv2.calibrateCamera's distCoeffs as they
# -- were, read in Human3.6M's order without a word (2D moved by up to 262 px, MPJPE 44 -> 122 mm)

OPENCV_LENSES = {4: [-0.28, 0.09, 0.0012, -0.0008], 5: [0.05, -0.1, 0.001, 0.001, 0.8],
                 8: [0.3, -0.1, 0.001, 0.002, 0.01, 0.5, 0.02, 0.01]}


def _opencv_project(X: np.ndarray, f: tuple[float, float], c: tuple[float, float], d) -> np.ndarray:
    """cv2.projectPoints of camera-frame poses (n, 17, 3) mm: OpenCV's own lens model, the reference."""
    import cv2

    K = np.array([[f[0], 0, c[0]], [0, f[1], c[1]], [0, 0, 1.0]])
    return np.stack([cv2.projectPoints(x, np.zeros(3), np.zeros(3), K, np.asarray(d, np.float64))[0].reshape(-1, 2)
                     for x in X])


@pytest.mark.parametrize("n", sorted(OPENCV_LENSES))
def test_undistort_pixels_opencv_inverts_opencvs_projection(rng, n):
    X = random_pose_cam(rng, 4)
    f, c = (1500.0, 1490.0), (960.0, 545.0)
    d = OPENCV_LENSES[n]
    distorted = _opencv_project(X, f, c, d)
    pinhole = cam.project(X, focal=f, principal_point=c)
    assert np.abs(distorted - pinhole).max() > 2.0
    got = cam.undistort_pixels_opencv(distorted, focal=f, principal_point=c, dist_coeffs=d)
    np.testing.assert_allclose(got, pinhole, atol=1e-6)
    # cv2.calibrateCamera's (1, n) row; per-pose lenses; a missing joint stays missing, the rest exact
    np.testing.assert_allclose(cam.undistort_pixels_opencv(distorted, focal=f, principal_point=c,
                                                           dist_coeffs=np.asarray(d)[None]), pinhole, atol=1e-6)
    lenses = np.stack([d, np.zeros(n), d, np.asarray(d) * 0.5])
    per = np.stack([_opencv_project(X[i:i + 1], f, c, lenses[i])[0] for i in range(4)])
    per[2, 7] = np.nan
    u = cam.undistort_pixels_opencv(per, focal=f, principal_point=c, dist_coeffs=lenses)
    assert np.isnan(u[2, 7]).all()
    ok = np.isfinite(per).all(-1)
    np.testing.assert_allclose(u[ok], pinhole[ok], atol=1e-6)


def test_undistort_pixels_opencv_names_what_is_wrong():
    kp = np.full((17, 2), 500.0) + np.arange(34).reshape(17, 2)
    for bad, msg in (([0.1, 0.0, 0.0], r"4, 5 or 8 numbers.*got shape \(3,\)"),
                     (np.zeros(12), r"thin-prism and tilted-sensor terms \(12 or 14 values\) are not taken"),
                     ([0.1, 0, 0, np.nan, 0], "must be finite and below 10"), ("barrel", "must be numbers")):
        with pytest.raises(PoseLifterError, match=msg):
            cam.undistort_pixels_opencv(kp, focal=1000.0, principal_point=(500, 500), dist_coeffs=bad)
    with pytest.raises(PoseLifterError, match=r"undistort \(opencv\): some points have no inverse"):
        cam.undistort_pixels_opencv(kp * 40.0, focal=100.0, principal_point=(0, 0), dist_coeffs=[-2.0, 0, 0, 0, 0])


def test_lift_takes_opencv_distcoeffs_and_warns_of_them_in_h36m_order(rng):
    """distortion_model="opencv" lifts as the pinhole 2D; the same five numbers read in Human3.6M's order (the
    default) put OpenCV's k3 in p2, and lift says so, naming distortion_model="opencv"."""
    import warnings

    from lifter import PoseLifterWarning

    X = random_pose_cam(rng, 6)
    f, c = (3000.0, 3000.0), (2016.0, 1512.0)
    d = OPENCV_LENSES[5]
    distorted, pinhole = _opencv_project(X, f, c, d), cam.project(X, focal=f, principal_point=c)
    lf = pinhole_lifter()
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)  # (nothing to warn of: the 2D is right)
        res = lf.lift(distorted, focal=f, principal_point=c, distortion=d, distortion_model="opencv")
    ref = lf.lift(pinhole, focal=f, principal_point=c)
    np.testing.assert_allclose(res.root, ref.root, rtol=1e-6)
    np.testing.assert_allclose(res.keypoints_2d, pinhole, atol=1e-6)
    assert not res.input_warnings
    with pytest.warns(PoseLifterWarning, match=r"tangential terms p1, p2 = 0.001, 0.8 .* distortion_model=\"opencv\""):
        wrong = lf.lift(distorted, focal=f, principal_point=c, distortion=d)
    assert any("OpenCV's distCoeffs" in w for w in wrong.input_warnings)
    assert np.abs(wrong.keypoints_2d - pinhole).max() > 50.0  # (what the note is about)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)  # a real Human3.6M lens is not noted
        lf.lift(cam.project(X, focal=f, principal_point=c, k=H36M_LENS[0], p=H36M_LENS[1]), focal=f,
                principal_point=c, distortion=(*H36M_LENS[0], *H36M_LENS[1]))
    old = tiny_lifter()  # learned H36M's own 2D: given it as it is, the coefficients checked all the same
    with pytest.warns(PoseLifterWarning, match="the distortion given is not undone"):
        kept = old.lift(distorted, focal=f, principal_point=c, distortion=d, distortion_model="opencv")
    np.testing.assert_array_equal(kept.root, old.lift(distorted, focal=f, principal_point=c).root)
    with pytest.raises(PoseLifterError, match=r"distortion_model must be \"h36m\" .* or \"opencv\".*'plumb_bob'"):
        lf.lift(distorted, focal=f, principal_point=c, distortion=d, distortion_model="plumb_bob")  # type: ignore
    with pytest.raises(PoseLifterError, match="4, 5 or 8 numbers"):
        lf.lift(distorted, focal=f, principal_point=c, distortion=d[:3], distortion_model="opencv")


def test_keypoint_file_and_sequence_with_an_opencv_lens(tmp_path, rng):
    """A keypoint file's "distortion_model": "opencv" (or ROS's "plumb_bob") reads its "distortion" as OpenCV's
    distCoeffs; the record says which; Human3.6M-order numbers that look like OpenCV's get the note."""
    from lifter.io import parse_keypoint_json
    from lifter.pipeline import lift_keypoint_file
    from lifter.video import lift_keypoint_sequence

    X = random_pose_cam(rng, 2)
    f, c = (3000.0, 3000.0), (2016.0, 1512.0)
    d = OPENCV_LENSES[5]
    distorted, pinhole = _opencv_project(X, f, c, d), cam.project(X, focal=f, principal_point=c)
    lf = pinhole_lifter()
    meta = {"focal": list(f), "principal_point": list(c), "image_size": [4032, 3024]}
    plain = lift_keypoint_file(_write(tmp_path / "u.json", {"keypoints": pinhole[0].tolist(), **meta}), lifter=lf)
    for model in ("opencv", "plumb_bob"):
        rec = lift_keypoint_file(_write(tmp_path / f"{model}.json", {"keypoints": distorted[0].tolist(), **meta,
                                                                     "distortion": d, "distortion_model": model}),
                                 lifter=lf)
        np.testing.assert_allclose(rec.root, plain.root, rtol=1e-6)
        out = rec.to_dict()
        assert out["distortion"] == pytest.approx(d) and out["distortion_model"] == "opencv"
        assert not any("tangential" in w for w in rec.warnings)
    # the record read back as a keypoint file keeps its lens
    back = tmp_path / "back.json"
    back.write_text(__import__("json").dumps(rec.to_dict()))
    kf = parse_keypoint_json(back)
    assert kf.distortion_model == "opencv" and kf.distortion is not None and len(kf.distortion) == 5
    wrong = lift_keypoint_file(_write(tmp_path / "w.json", {"keypoints": distorted[0].tolist(), **meta,
                                                            "distortion": d}), lifter=lf)
    assert any("tangential terms p1, p2 = 0.001, 0.8" in w and "\"distortion_model\": \"opencv\"" in w
               for w in wrong.warnings)
    seq = {"frames": [{"keypoints": q.tolist()} for q in distorted], "fps": 25, **meta, "distortion": d,
           "distortion_model": "opencv", "source": "clean"}
    srec = lift_keypoint_sequence(_write(tmp_path / "s.json", seq), lifter=lf, smoothing=0.0)
    ref = lf.lift(pinhole, focal=f, principal_point=c, source="clean")
    np.testing.assert_allclose([fr.people[0].root for fr in srec.frames], ref.root, rtol=1e-6)
    assert srec.to_dict()["distortion_model"] == "opencv"
    for bad, msg in (({"distortion": d, "distortion_model": "fisheye"}, "distortion_model must be"),
                     ({"distortion": [0.1, 0.2, 0.0], "distortion_model": "opencv"}, r"OpenCV's distCoeffs.*4, 5, 8")):
        with pytest.raises(PoseLifterError, match=msg):
            parse_keypoint_json(_write(tmp_path / "bad.json", {"keypoints": distorted[0].tolist(), **meta, **bad}))


def test_opencv_shaped_lenses_given_as_human36m_name_the_opencv_model():
    """A review: 4 or 8 coefficients (counts only OpenCV's distCoeffs have), or cv2.calibrateCamera's (1, 5) row, given
    with the default distortion_model="h36m" were refused without naming distortion_model="opencv"; the (1, 5) row's
    message offered the same shape twice ("give one (5,) for all, or one row per pose (5,)"); and OpenCV's (5, 1)
    column (cv2.FileStorage, several cv2 APIs) was refused in opencv mode, where the (1, 5) row is taken."""
    import cv2
    from conftest import tiny_lifter

    X = random_pose_cam(np.random.default_rng(4), 1)[0]
    f, c = 1000.0, (500.0, 500.0)
    lf = tiny_lifter()
    lf.train_config = {"data": {"lens": "pinhole"}}
    kp = cam.project(X, focal=f, principal_point=c)
    for d in ([-0.28, 0.09, 0.001, -0.0005], [-0.28, 0.09, 0.001, -0.0005, -0.012, 0, 0, 0], np.zeros((1, 5))):
        with pytest.raises(PoseLifterError, match=r"OpenCV's distCoeffs\? pass distortion_model=\"opencv\"") as got:
            lf.lift(kp, focal=f, principal_point=c, distortion=d)
        assert "or one row per pose (5,)" not in str(got.value), got.value
    d5 = np.array([-0.28, 0.09, 0.0012, -0.0008, 0.05])
    K = np.array([[f, 0, c[0]], [0, f, c[1]], [0, 0, 1.0]])
    seen = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, d5)[0].reshape(-1, 2)
    want = lf.lift(seen, focal=f, principal_point=c, distortion=d5, distortion_model="opencv", warn=False)
    for shape in ((5, 1), (1, 5)):
        got_ = lf.lift(seen, focal=f, principal_point=c, distortion=d5.reshape(shape), distortion_model="opencv",
                       warn=False)
        np.testing.assert_allclose(got_.absolute, want.absolute)
        # (a developer trial: the (5, 1) column was refused for a batch of poses, taken for one)
        got_ = lf.lift(np.stack([seen] * 3), focal=f, principal_point=c, distortion=d5.reshape(shape),
                       distortion_model="opencv", warn=False)
        np.testing.assert_allclose(got_.absolute, np.stack([want.absolute] * 3))
    with pytest.raises(PoseLifterError, match=r"distortion: shape \(3, 5\) does not match the keypoints' poses \(2,\): "
                                              r"give one \(5,\) for all, or one row per pose \(2, 5\)"):
        lf.lift(np.stack([kp, kp]), focal=f, principal_point=c, distortion=np.zeros((3, 5)))
