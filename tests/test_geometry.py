"""Conventions: projection <-> back-projection, canonical depth invariance, flips, normalization invariances."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_pose_cam
from hypothesis import given, settings
from hypothesis import strategies as st

from lifter import camera as cam
from lifter.normalization import normalize_keypoints, pose_scale
from lifter.skeleton import EDGES, FLIP_PERMUTATION, JOINT_NAMES, LEFT_RIGHT_PAIRS, PARENTS

finite = dict(allow_nan=False, allow_infinity=False)


def test_skeleton_tables_consistent():
    assert len(JOINT_NAMES) == len(PARENTS) == len(FLIP_PERMUTATION) == 17
    assert len(EDGES) == 16
    perm = np.asarray(FLIP_PERMUTATION)
    assert np.array_equal(perm[perm], np.arange(17)), "flip permutation must be an involution"
    for left, right in LEFT_RIGHT_PAIRS:
        assert JOINT_NAMES[left].startswith("l_") and JOINT_NAMES[right].startswith("r_")
        assert JOINT_NAMES[left][2:] == JOINT_NAMES[right][2:]
        assert FLIP_PERMUTATION[left] == right


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), f=st.floats(200, 5000, **finite), cx=st.floats(0, 2000, **finite),
       cy=st.floats(0, 2000, **finite), aspect=st.floats(0.9, 1.1, **finite))
def test_project_backproject_round_trip(seed, f, cx, cy, aspect):
    pose = random_pose_cam(np.random.default_rng(seed), 3)
    uv = cam.project(pose, focal=(f, f * aspect), principal_point=(cx, cy))
    back = cam.backproject(uv, pose[..., 2], focal=(f, f * aspect), principal_point=(cx, cy))
    np.testing.assert_allclose(back, pose, rtol=1e-9, atol=1e-6)


def test_projection_convention_opencv():
    # +x right, +y down, +z forward: a point right of and below the axis lands right of and below c.
    uv = cam.project(np.array([[[100.0, 50.0, 1000.0]]]), focal=1000.0, principal_point=(500.0, 400.0))
    np.testing.assert_allclose(uv[0, 0], [600.0, 450.0])
    with pytest.raises(ValueError, match="in front of the camera"):
        cam.project(np.array([[[0.0, 0.0, -1.0]]]), focal=1000.0, principal_point=(0, 0))


def test_one_pinhole_projection_for_numpy_and_torch():
    """project_generic is project without lens distortion, for numpy and torch (float32 and float64), per pose set
    or per joint, and differentiable; turn_pixels by the identity leaves pixels where they are."""
    import torch

    pose = random_pose_cam(np.random.default_rng(3), 4)
    f = np.array([[1145.0, 1144.0], [900.0, 950.0], [2000.0, 2000.0], [600.0, 610.0]])
    c = np.array([[512.0, 515.0], [320.0, 240.0], [0.0, 0.0], [1000.0, -20.0]])
    want = pose[..., :2] / pose[..., 2:] * f[:, None] + c[:, None]  # (written out: project calls project_generic)
    np.testing.assert_array_equal(cam.project(pose, focal=f, principal_point=c), want)
    np.testing.assert_array_equal(cam.project_generic(pose, f, c), want)
    np.testing.assert_array_equal(cam.project_generic(pose, f[:, None], c[:, None], per_joint=True), want)
    for dtype, tol in ((torch.float64, 1e-9), (torch.float32, 1e-3)):
        got = cam.project_generic(torch.as_tensor(pose, dtype=dtype), torch.as_tensor(f, dtype=dtype),
                                  torch.as_tensor(c, dtype=dtype))
        assert got.dtype == dtype and got.shape == (4, 17, 2)
        np.testing.assert_allclose(got.numpy(), want, atol=tol)
    X = torch.as_tensor(pose[:1, :3], dtype=torch.float64).requires_grad_()
    F = torch.tensor([1145.0, 1144.0], dtype=torch.float64, requires_grad=True)
    torch.autograd.gradcheck(lambda X, F: cam.project_generic(X, F, torch.tensor([512.0, 515.0],
                                                                                 dtype=torch.float64)), (X, F))
    uv = torch.as_tensor(want, dtype=torch.float64)
    turned = cam.turn_pixels(uv, torch.eye(3, dtype=torch.float64), torch.as_tensor(f), torch.as_tensor(c))
    np.testing.assert_allclose(turned.numpy(), want, atol=1e-9)
    np.testing.assert_allclose(cam.alpha_generic(torch.as_tensor(f)).numpy(), cam.focal_alpha(f))
    # parameters of another type take the points' (a review: a numpy float64 focal with torch points was a
    # TypeError, and a numpy (2,) focal made float32 torch points float64)
    pts = torch.as_tensor(pose, dtype=torch.float32)
    for focal in (np.float64(1000.0), np.array([1000.0, 990.0]), 1000.0, [1000.0, 990.0]):
        got = cam.project_generic(pts, focal, np.array([512.0, 515.0]))
        assert isinstance(got, torch.Tensor) and got.dtype == torch.float32
    assert isinstance(cam.project_generic(pose, torch.tensor([1000.0, 990.0]), 0.0), np.ndarray)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), f1=st.floats(300, 4000, **finite), f2=st.floats(300, 4000, **finite),
       aspect=st.floats(0.8, 1.25, **finite))
def test_canonical_depth_gives_same_root_for_any_focal(seed, f1, f2, aspect):
    """The same person imaged with focal f1 or f2 (fx != fy) and the canonical depth of each gives the same 3D
    root; and canonical depth x 2D scale is the same for both cameras -- the cue the network learns."""
    pose = random_pose_cam(np.random.default_rng(seed), 2)
    root = pose[:, 0]
    c = (512.0, 500.0)
    roots, products = [], []
    for f in (f1, f2):
        focal = (f, f * aspect)
        uv = cam.project(pose, focal=focal, principal_point=c)
        cd = cam.canonical_depth_from_depth(root[:, 2], focal=focal)
        roots.append(cam.root_from_canonical_depth(uv[:, 0], cd, focal=focal, principal_point=c))
        products.append(cd * pose_scale(uv))
    np.testing.assert_allclose(roots[0], root, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(roots[1], root, rtol=1e-9, atol=1e-6)
    # canonical depth scales as 1/f while the 2D scale scales as f: their product is focal-invariant
    np.testing.assert_allclose(products[0], products[1], rtol=1e-9)


def test_canonical_depth_is_depth_at_1000px():
    np.testing.assert_allclose(cam.canonical_depth_from_depth(5000.0, focal=(1000.0, 1000.0)), 5000.0)
    np.testing.assert_allclose(cam.canonical_depth_from_depth(5000.0, focal=(2000.0, 2000.0)), 2500.0)
    np.testing.assert_allclose(cam.depth_from_canonical_depth(2500.0, focal=(2000.0, 2000.0)), 5000.0)


def test_a_flip_swaps_left_and_right_joints_by_name():
    """Written out joint by joint, not from one flip helper against another (a review: with ``mirror`` negating x
    but no longer swapping joints, every flip test passed, each comparing two helpers built on it)."""
    from lifter.skeleton import mirror

    rng = np.random.default_rng(5)
    p = rng.normal(0, 300, (17, 3))
    kp = rng.uniform(0, 1000, (17, 2))
    W, c = 1000.0, (480.0, 510.0)
    flipped, c_out = cam.flip_keypoints_2d(kp, image_width=W, principal_point=c)
    np.testing.assert_allclose(c_out, [W - 480.0, 510.0])
    swap = {"l_hip": "r_hip", "l_knee": "r_knee", "l_ankle": "r_ankle", "l_shoulder": "r_shoulder",
            "l_elbow": "r_elbow", "l_wrist": "r_wrist"}
    swap.update({b: a for a, b in swap.items()})
    for j, name in enumerate(JOINT_NAMES):
        src = JOINT_NAMES.index(swap.get(name, name))
        np.testing.assert_allclose(mirror(p)[j], [-p[src, 0], p[src, 1], p[src, 2]], err_msg=name)
        np.testing.assert_allclose(cam.flip_pose_3d(p)[j], [-p[src, 0], p[src, 1], p[src, 2]], err_msg=name)
        np.testing.assert_allclose(flipped[j], [W - kp[src, 0], kp[src, 1]], err_msg=name)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), W=st.integers(200, 3000))
def test_flip_twice_is_identity(seed, W):
    rng = np.random.default_rng(seed)
    kp = rng.uniform(0, W, (4, 17, 2))
    c = rng.uniform(0, W, (4, 2))
    kp1, c1 = cam.flip_keypoints_2d(kp, image_width=W, principal_point=c)
    kp2, c2 = cam.flip_keypoints_2d(kp1, image_width=W, principal_point=c1)
    np.testing.assert_allclose(kp2, kp)
    np.testing.assert_allclose(c2, c)
    p = random_pose_cam(rng, 4)
    np.testing.assert_allclose(cam.flip_pose_3d(cam.flip_pose_3d(p)), p)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1))
def test_flip_commutes_with_projection(seed):
    rng = np.random.default_rng(seed)
    pose = random_pose_cam(rng, 3)
    W, f, c = 1000, 1145.0, (512.5, 515.4)
    kp = cam.project(pose, focal=f, principal_point=c)
    kp_flipped, c_flipped = cam.flip_keypoints_2d(kp, image_width=W, principal_point=c)
    kp_of_flipped = cam.project(cam.flip_pose_3d(pose), focal=f, principal_point=c_flipped)
    np.testing.assert_allclose(kp_flipped, kp_of_flipped, atol=1e-9)


def test_flip_commutes_with_distorted_projection():
    """With lens distortion the mirror camera also negates p2 (Camera.flipped)."""
    rng = np.random.default_rng(1)
    c = cam.Camera(focal=(1145.0, 1143.8), principal_point=(512.5, 515.5), width=1000, height=1002,
                   k=(-0.207, 0.248, -0.003), p=(-0.0014, -0.00098))
    pose = random_pose_cam(rng, 5)
    kp_flipped, _ = cam.flip_keypoints_2d(c.project(pose), image_width=c.width, principal_point=c.principal_point)
    np.testing.assert_allclose(c.flipped().project(cam.flip_pose_3d(pose)), kp_flipped, atol=1e-9)
    # and the flip is not the trivial identity
    assert np.abs(kp_flipped - c.project(pose)).max() > 1.0


def test_distortion_matches_readme_formula():
    x, y = 0.3, -0.2
    k1, k2, k3, p1, p2 = -0.2, 0.25, -0.003, -0.0014, -0.001
    r2 = x * x + y * y
    radial = 1 + k1 * r2 + k2 * r2**2 + k3 * r2**3
    tan = p1 * y + p2 * x
    expected = [x * (radial + tan) + p2 * r2, y * (radial + tan) + p1 * r2]
    np.testing.assert_allclose(cam.distort(np.array([x, y]), (k1, k2, k3), (p1, p2)), expected)


def test_world_camera_round_trip():
    rng = np.random.default_rng(2)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    t = rng.normal(size=3) * 1000
    p = rng.normal(size=(5, 17, 3)) * 1000
    np.testing.assert_allclose(cam.camera_to_world(cam.world_to_camera(p, q, t), q, t), p, atol=1e-9)


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**31 - 1),
       shift=st.tuples(st.floats(-2000, 2000, **finite), st.floats(-2000, 2000, **finite)),
       s=st.floats(0.1, 10, **finite), definition=st.sampled_from(["paper", "repo"]))
def test_normalization_invariance(seed, shift, s, definition):
    """Translating/scaling the 2D pose leaves the normalized pose unchanged; location and scale features move."""
    rng = np.random.default_rng(seed)
    kp = rng.uniform(100, 900, (17, 2))
    c = np.array([500.0, 500.0])
    f0 = normalize_keypoints(kp, c, mode="both", scale_definition=definition)
    moved = (kp - c) * s + c + np.asarray(shift)
    f1 = normalize_keypoints(moved, c, mode="both", scale_definition=definition)
    np.testing.assert_allclose(f1[:34], f0[:34], atol=1e-4)
    u0, u1 = f0[34:36] / 1e-3, f1[34:36] / 1e-3
    np.testing.assert_allclose(u1, u0 * s + np.asarray(shift), rtol=1e-4, atol=1e-2)
    np.testing.assert_allclose(f1[36], f0[36] * s, rtol=1e-4)


def test_normalization_features_by_mode():
    kp = np.random.default_rng(0).uniform(0, 1000, (3, 17, 2))
    sizes = {m: normalize_keypoints(kp, (500, 500), mode=m).shape[-1]
             for m in ("baseline", "location", "scale", "both")}
    assert sizes == {"baseline": 34, "location": 36, "scale": 35, "both": 37}
    f = normalize_keypoints(kp, (500, 500), mode="both")
    # normalized pose has zero mean and (paper definition) unit RMS radius
    pose = f[..., :34].reshape(3, 17, 2)
    np.testing.assert_allclose(pose.mean(-2), 0, atol=1e-5)
    np.testing.assert_allclose(np.sqrt((pose**2).sum(-1).mean(-1)), 1, atol=1e-5)
    np.testing.assert_allclose(f[..., 36] / 1e-3, pose_scale(kp), rtol=1e-5)
    with pytest.raises(ValueError, match="unknown normalization mode"):
        normalize_keypoints(kp, (500, 500), mode="nope")  # type: ignore[arg-type]


def test_principal_point_subtraction():
    kp = np.random.default_rng(0).uniform(0, 1000, (17, 2))
    a = normalize_keypoints(kp, (500, 500))
    b = normalize_keypoints(kp + 100, (600, 600))
    np.testing.assert_allclose(a, b, atol=1e-5)


def test_camera_centre_is_where_camera_frame_origin_lies_in_the_world():
    """Camera.centre is -R^T t: the world point that maps to the camera-frame origin; camera_to_world inverts
    world_to_camera."""
    rng = np.random.default_rng(3)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    R = q * np.sign(np.linalg.det(q))
    c = cam.Camera(focal=(1000.0, 1000.0), principal_point=(500.0, 500.0), width=1000, height=1000, R=R,
                   t=rng.normal(0, 2000, 3))
    np.testing.assert_allclose(c.world_to_camera(c.centre), np.zeros(3), atol=1e-9)
    np.testing.assert_allclose(c.centre, -R.T @ c.t, atol=1e-9)
    pts = rng.normal(0, 1000, (4, 17, 3))
    np.testing.assert_allclose(c.camera_to_world(c.world_to_camera(pts)), pts, atol=1e-9)


def test_camera_turn_convention_and_homography():
    """camera_turn: + pan turns the camera right (what is ahead moves left in the image), + tilt turns it up (what
    is ahead moves down), + roll turns it clockwise seen from behind (what is to the right moves up: the picture
    turns counter-clockwise), a rotation; turn_pixels equals projecting the turned 3D, numpy and torch alike."""
    import torch

    from lifter.camera import camera_turn, project, turn_pixels

    ahead = np.array([0.0, 0.0, 1000.0])
    right = camera_turn(np.array(np.deg2rad(10.0)), np.array(0.0))
    up = camera_turn(np.array(0.0), np.array(np.deg2rad(10.0)))
    assert (right @ ahead)[0] < 0 and abs((right @ ahead)[1]) < 1e-12
    assert (up @ ahead)[1] > 0 and abs((up @ ahead)[0]) < 1e-12
    clockwise = camera_turn(np.array(0.0), np.array(0.0), np.array(np.deg2rad(10.0)))
    to_the_right = clockwise @ np.array([500.0, 0.0, 1000.0])
    assert to_the_right[1] < 0 and to_the_right[0] > 0 and to_the_right[2] == 1000.0
    np.testing.assert_allclose(camera_turn(np.array(0.3), np.array(-0.2), np.array(0.0)),
                               camera_turn(np.array(0.3), np.array(-0.2)), atol=0)
    rng = np.random.default_rng(3)
    r = camera_turn(*rng.uniform(-0.4, 0.4, (3, 5)))
    np.testing.assert_allclose(r @ np.swapaxes(r, -1, -2), np.broadcast_to(np.eye(3), (5, 3, 3)), atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(r), 1.0)
    pts = rng.uniform([-800, -800, 3000], [800, 800, 6000], (5, 17, 3))
    f, c = np.array([1145.0, 1143.5]), np.array([512.0, 515.0])
    uv = project(pts, focal=f, principal_point=c)
    expected = project(pts @ np.swapaxes(r, -1, -2), focal=f, principal_point=c)
    np.testing.assert_allclose(turn_pixels(uv, r, f, c), expected, atol=1e-9)
    got = turn_pixels(torch.from_numpy(uv), torch.from_numpy(r), torch.from_numpy(f), torch.from_numpy(c))
    np.testing.assert_allclose(got.numpy(), expected, atol=1e-9)
    # turning back by R^T undoes a turn (README, "Camera roll": a known roll undone before lifting)
    np.testing.assert_allclose(turn_pixels(turn_pixels(uv, r, f, c), np.swapaxes(r, -1, -2), f, c), uv, atol=1e-9)


def test_bone_lengths_follow_edges_and_check_shapes():
    """``lifter.skeleton.bone_lengths``: one length per EDGES bone, batched, in the points' unit; invariant to a
    shift and to the mirror; a wrong shape is refused."""
    from lifter.skeleton import bone_lengths, mirror

    pose = random_pose_cam(np.random.default_rng(3), 4)  # (4, 17, 3) mm
    lengths = bone_lengths(pose)
    assert lengths.shape == (4, 16)
    np.testing.assert_allclose(lengths[2], [np.linalg.norm(pose[2, c] - pose[2, p]) for p, c in EDGES])
    np.testing.assert_allclose(bone_lengths(pose + 123.0), lengths)
    np.testing.assert_allclose(np.sort(bone_lengths(mirror(pose)), -1), np.sort(lengths, -1))
    assert bone_lengths(pose[..., :2]).shape == (4, 16)
    with pytest.raises(ValueError, match=r"bone_lengths: expected shape \(\.\.\., 17, 2 or 3\)"):
        bone_lengths(pose[:, :16])


def test_an_angle_of_view_beyond_the_plausible_one_never_reads_as_within_it():
    """A teacher's caution read "spans 120° of view (a whole person rarely spans more than 120°)": the angle is
    written with the decimals it takes to read beyond the limit."""
    from lifter.camera import MAX_PLAUSIBLE_VIEW_DEG, pose_view_deg, view_deg_text

    assert MAX_PLAUSIBLE_VIEW_DEG == 120.0
    assert [view_deg_text(v) for v in (126.2, 120.6, 120.3, 120.04, 120.0004)] == ["126", "121", "120.3", "120.04",
                                                                                   "120.001"]
    kp = np.array([[0.0, 0.0], [400.0, 300.0]] + [[200.0, 150.0]] * 15)  # (a 500 px diagonal)
    assert float(pose_view_deg(kp, 250.0 / np.tan(np.radians(120.3) / 2))) == pytest.approx(120.3)


def test_project_refuses_parameters_whose_leading_axes_are_not_the_points():
    """A developer trial: ``project(P (N, J, 3), focal=F[:, None], principal_point=C[:, None])`` broadcast every point
    set through every camera, (N, N, J, 2), without a word; each parameter's leading axes must be the points' own
    (or broadcast to them), else an error names the shape that works."""
    from lifter import PoseLifterError
    from lifter.camera import project

    P = np.random.default_rng(0).normal(0, 300, (4, 17, 3)) + [0, 0, 4000]
    F, C = np.linspace(900, 1200, 4), np.full((4, 2), 500.0)
    assert project(P, focal=F[:, None], principal_point=C).shape == (4, 17, 2)  # (a scalar focal per set)
    assert project(P, focal=1000.0, principal_point=(500, 500), k=np.zeros(3), p=np.zeros(2)).shape == (4, 17, 2)
    with pytest.raises(PoseLifterError, match=r"principal_point: leading shape \(4, 1\) does not match the points' "
                       r"\(4,\) \(points_cam \(4, 17, 3\)\): give one per point set, shape \(4, 2\), or one for all"):
        project(P, focal=F[:, None], principal_point=C[:, None])
    with pytest.raises(PoseLifterError, match=r"k: leading shape \(3,\) does not match the points' \(4,\)"):
        project(P, focal=1000.0, principal_point=(500, 500), k=np.zeros((3, 3)))
    # (a review: one point set through several cameras is a broadcast that stays; a ragged focal is named)
    assert project(P[0], focal=np.full((3, 2), 1000.0), principal_point=(500, 500)).shape == (3, 17, 2)
    with pytest.raises(PoseLifterError, match="focal"):
        project(P, focal=[1000.0, [1, 2]], principal_point=(500, 500))
