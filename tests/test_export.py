"""GLB and BVH export: files load back to the same joint positions."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_pose_cam

from lifter import PoseLifterError
from lifter.export import bvh_text, from_y_up, read_bvh, read_glb_joints, to_y_up, write_bvh, write_glb
from lifter.skeleton import EDGES, JOINT_NAMES


@pytest.fixture()
def pose() -> np.ndarray:
    return random_pose_cam(np.random.default_rng(3), 1)[0]


def test_y_up_is_a_rotation(pose):
    q = to_y_up(pose)
    np.testing.assert_allclose(from_y_up(q), pose)
    # a proper rotation keeps handedness: cross products map to cross products
    a, b = pose[1] - pose[0], pose[4] - pose[0]
    np.testing.assert_allclose(np.cross(to_y_up(a), to_y_up(b)), to_y_up(np.cross(a, b)), atol=1e-6)
    assert q[0, 2] < 0  # in front of the camera = -z in the y-up frame


def test_glb_round_trip(tmp_path, pose):
    import trimesh

    path = write_glb(pose, tmp_path / "p.glb")
    assert path.read_bytes()[:4] == b"glTF"
    np.testing.assert_allclose(read_glb_joints(path), pose, atol=0.05)  # mm; float32 vertices
    scene = trimesh.load(str(path), force="scene")
    assert len(scene.geometry) == len(JOINT_NAMES) + len(EDGES)
    # metres, y-up: the scene's extent is a human's, not a thousand times more
    assert 0.3 < float(np.max(scene.extents)) < 5.0


@pytest.mark.parametrize("units", ["mm", "cm", "m"])
def test_bvh_round_trip(tmp_path, pose, units):
    path = write_bvh(pose, tmp_path / "p.bvh", units=units)
    text = path.read_text()
    assert text.startswith("HIERARCHY\nROOT pelvis") and "MOTION\nFrames: 1" in text
    assert text.count("JOINT ") == 16 and text.count("End Site") == 5  # ankles x2, head_top, wrists x2
    np.testing.assert_allclose(read_bvh(path, units=units), pose, atol=0.01)  # 6 decimals in m = 1 um


def test_bvh_reader_applies_rotations(tmp_path, pose):
    """Rotating the root by 90 deg about the y-up axis rotates every joint about the root."""
    text = bvh_text(pose, units="mm").rstrip("\n").split("\n")
    vals = text[-1].split()
    vals[5] = "90.0"  # root channels: X Y Z position, Zrotation Xrotation Yrotation
    (tmp_path / "r.bvh").write_text("\n".join(text[:-1] + [" ".join(vals)]) + "\n")
    got = to_y_up(read_bvh(tmp_path / "r.bvh", units="mm"))
    q = to_y_up(pose)
    rel = q - q[0]
    rot = np.stack([rel[:, 2], rel[:, 1], -rel[:, 0]], -1)  # R_y(90 deg) applied to (x, y, z)
    np.testing.assert_allclose(got - got[0], rot, atol=1e-3)


def test_bad_pose():
    with pytest.raises(PoseLifterError, match="expected shape"):
        bvh_text(np.zeros((16, 3)))
    with pytest.raises(PoseLifterError, match="one pose"):
        write_glb(np.zeros((2, 17, 3)), "/nonexistent/x.glb")
    with pytest.raises(PoseLifterError, match="units"):
        bvh_text(np.zeros((17, 3)), units="inch")
