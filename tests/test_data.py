"""H36M loading: camera frame, distorted projection matches the dataset's own 2D, splits, flips."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import H36M_DIR, requires_h36m

from lifter.camera import flip_keypoints_2d, flip_pose_3d, project
from lifter.data import ACTIONS, CAMERA_IDS, PROTOCOLS, action_of


def test_action_names():
    assert action_of("S9/Walking 1") == "Walking"
    assert action_of("WalkDog") == "WalkDog"
    assert action_of("S1/SittingDown 2") == "SittingDown"
    assert len(ACTIONS) == 15
    with pytest.raises(ValueError, match="unknown H36M action"):
        action_of("S1/Dancing 1")



def test_default_folder_for_a_checkout_and_for_a_wheel(tmp_path):
    """User trial: from an installed wheel the default resolved to site-packages' ../shared/data/h36m. A checkout
    (pyproject.toml beside lifter/) looks beside the project; an install looks from the working folder."""
    from lifter.data import _default_h36m_dir

    (tmp_path / "repo").mkdir()
    (tmp_path / "repo" / "pyproject.toml").write_text("")
    assert _default_h36m_dir(tmp_path / "repo") == tmp_path / "shared" / "data" / "h36m"
    assert _default_h36m_dir(tmp_path / "site-packages") == Path("..") / "shared" / "data" / "h36m"

def test_missing_folder_error(tmp_path):
    from lifter.data import H36M

    with pytest.raises(FileNotFoundError, match="Human3.6M data not found"):
        H36M(tmp_path)


def test_a_compacted_copy_refuses_the_frames_it_dropped(tmp_path):
    """scripts/compact_h36m.py keeps every 5th frame and zeroes the rest; its compact.json makes H36M refuse a
    stride or frame that would read a zeroed pose, naming the fix, and serve the kept frames as before."""
    import json

    from lifter._checks import PoseLifterError
    from lifter.data import COMPACT_FILE, H36M

    poses = np.zeros((12, 17, 3), np.int16)
    poses[::5] = np.arange(17 * 3, dtype=np.int16).reshape(17, 3) + 100
    np.savez_compressed(tmp_path / "poses3d_world_17j_mm.npz", **{"S9/Walking 1": poses})
    (tmp_path / "cameras.json").write_text(json.dumps({"cameras": {}}))
    assert H36M(tmp_path).keep_every == 1  # a plain folder: every frame
    np.testing.assert_array_equal(H36M(tmp_path).poses_world("S9/Walking 1", 1), poses[1])
    (tmp_path / COMPACT_FILE).write_text(json.dumps({"keep_every": 5}))
    data = H36M(tmp_path)
    np.testing.assert_array_equal(data.poses_world("S9/Walking 1", np.arange(0, 12, 5)), poses[::5])
    np.testing.assert_array_equal(data.poses_world("S9/Walking 1", 10), poses[10])
    for frames in (np.arange(0, 12, 2), 3, None, slice(0, 12, 4)):
        with pytest.raises(PoseLifterError, match="keeps only every 5th frame .* a stride that is a multiple of 5 "
                                                  ".*--val-stride.*evaluate: --stride"):
            data.poses_world("S9/Walking 1", frames)


def test_a_compacted_copy_can_keep_each_subject_at_its_own_rate(tmp_path):
    """compact_h36m.py --train-every 1 --test-every 100 writes per-subject rates: every frame of a training
    subject is served, a test subject's dropped frames are refused naming that subject, and an unnamed subject
    keeps every frame."""
    import json

    from lifter._checks import PoseLifterError
    from lifter.data import COMPACT_FILE, H36M

    poses = (np.arange(12 * 17 * 3, dtype=np.int16) % 1000).reshape(12, 17, 3)
    np.savez_compressed(tmp_path / "poses3d_world_17j_mm.npz",
                        **{"S1/Walking 1": poses, "S9/Walking 1": poses, "S5/Walking 1": poses})
    (tmp_path / "cameras.json").write_text(json.dumps({"cameras": {}}))
    (tmp_path / COMPACT_FILE).write_text(json.dumps({"keep_every": {"S1": 1, "S9": 10}}))
    data = H36M(tmp_path)
    assert data.keep_every == {"S1": 1, "S9": 10}
    np.testing.assert_array_equal(data.poses_world("S1/Walking 1"), poses)
    np.testing.assert_array_equal(data.poses_world("S5/Walking 1", 3), poses[3])
    np.testing.assert_array_equal(data.poses_world("S9/Walking 1", np.arange(0, 12, 10)), poses[::10])
    with pytest.raises(PoseLifterError, match="keeps only every 10th frame of S9 .* multiple of 10"):
        data.poses_world("S9/Walking 1", np.arange(0, 12, 5))


@requires_h36m
def test_missing_detections_are_named_by_sequence_and_camera(h36m):
    """A developer trial read "19 samples without a detection dropped" as frames missing here and there: the file
    has none for one whole sequence and camera, which the note now names."""
    from lifter.detections import load_sh_detections, missing_detection_note, with_sh_detections

    s = h36m.load_protocol(1, "test", stride=200)
    note = missing_detection_note(s, load_sh_detections(s, data=h36m)[1])
    _, dropped = with_sh_detections(s, data=h36m)
    assert dropped > 0 and note == (f"{dropped} samples without a detection dropped: the file has none for "
                                    f"S11/Directions camera 54138969 ({dropped})")
    one = s.subset(np.flatnonzero(s.camera == 1))
    assert missing_detection_note(one, load_sh_detections(one, data=h36m)[1]) == ""


@requires_h36m
def test_projection_with_distortion_matches_dataset_2d(h36m):
    """Our camera-frame 3D + distorted projection reproduces the 2D annotations shipped with the demo frames."""
    ann = np.load(H36M_DIR / "demo" / "annotations.npz")
    for i in range(0, len(ann["image"]), 7):
        subject = int(str(ann["subject"][i]).lstrip("S"))
        c = h36m.camera(subject, str(ann["camera"][i]))
        p3 = c.world_to_camera(ann["p3d_world"][i])
        np.testing.assert_allclose(p3, ann["p3d_cam"][i], atol=1.0)  # int16 world coordinates
        np.testing.assert_allclose(c.project(p3), ann["p2d_gt"][i], atol=0.5)
        # and distortion is not negligible everywhere: pinhole differs
        assert np.abs(c.project(p3, distortion=False) - ann["p2d_gt"][i]).max() > 0.05


@requires_h36m
def test_load_slice_shapes_and_units(h36m):
    s = h36m.load([9], stride=50, max_frames_per_sequence=3)
    n = len(s)
    assert n == 3 * 4 * len(h36m.sequences_of([9]))
    assert s.keypoints_2d.shape == (n, 17, 2) and s.pose_3d.shape == (n, 17, 3)
    assert np.all(s.pose_3d[..., 2] > 1000) and np.all(s.pose_3d[..., 2] < 10000)  # mm in front of the camera
    assert set(s.camera.tolist()) == set(range(len(CAMERA_IDS)))
    np.testing.assert_allclose(s.relative[:, 0], 0)
    assert np.all(s.keypoints_2d > -200) and np.all(s.keypoints_2d < 1300)
    cd = s.canonical_depth
    np.testing.assert_allclose(cd, s.pose_3d[:, 0, 2] * 1000 / np.sqrt(s.focal.prod(-1)), rtol=1e-5)


@requires_h36m
def test_protocol_splits(h36m):
    assert PROTOCOLS[1] == ((1, 5, 6, 7, 8), (9, 11))
    s = h36m.load_protocol(2, "test", stride=200)
    assert set(s.subject.tolist()) == {11}
    assert "S9/Discussion 1" not in h36m.sequences  # documented gap in the data
    with pytest.raises(ValueError, match="split"):
        h36m.load_protocol(1, "val", stride=5)


@requires_h36m
def test_flip_of_real_sample_is_a_valid_view(h36m):
    """The flipped 2D is the (pinhole) projection of the flipped 3D through the mirrored principal point."""
    s = h36m.load([11], stride=100, max_frames_per_sequence=2)
    kp = project(s.pose_3d, focal=s.focal, principal_point=s.principal_point)
    kp_f, c_f = flip_keypoints_2d(kp, image_width=s.image_size[:, 0], principal_point=s.principal_point)
    np.testing.assert_allclose(project(flip_pose_3d(s.pose_3d), focal=s.focal, principal_point=c_f), kp_f, atol=1e-6)


@requires_h36m
def test_virtual_camera_samples(h36m):
    from lifter.evaluate import virtual_camera_samples

    s = h36m.load([9], stride=200, max_frames_per_sequence=2)
    v = virtual_camera_samples(s, focal_scale=1.4, principal_shift=(100.0, -80.0))
    np.testing.assert_allclose(v.focal, s.focal * 1.4, rtol=1e-6)
    np.testing.assert_allclose(v.principal_point, s.principal_point + np.array([100.0, -80.0]), rtol=1e-6)
    np.testing.assert_array_equal(v.pose_3d, s.pose_3d)
    np.testing.assert_allclose(v.keypoints_2d, project(s.pose_3d, focal=v.focal, principal_point=v.principal_point),
                               atol=1e-3)


@requires_h36m
def test_turned_camera_samples_with_a_roll_project_the_turned_3d(h36m):
    """turned_camera_samples: H36M's distorted 2D is undistorted, then moved as the turned camera (pan, tilt and
    roll, one per sample) sees it: the pinhole projection of the turned 3D; a roll keeps each joint's depth and its
    ray's angle from the optical axis (its distance from the principal point in focal units: fx and fy differ)."""
    from lifter.evaluate import turned_camera_samples

    s = h36m.load([9], stride=200, max_frames_per_sequence=2)
    n = len(s)
    rng = np.random.default_rng(0)
    v = turned_camera_samples(s, pan_deg=rng.uniform(-20, 20, n), tilt_deg=rng.uniform(-20, 20, n),
                              roll_deg=rng.uniform(-30, 30, n))
    assert v.lens == "pinhole"
    np.testing.assert_allclose(v.keypoints_2d, project(v.pose_3d, focal=v.focal, principal_point=v.principal_point),
                               atol=1e-2)
    rolled = turned_camera_samples(s, pan_deg=0.0, tilt_deg=0.0, roll_deg=25.0)
    np.testing.assert_allclose(rolled.pose_3d[..., 2], s.pose_3d[..., 2], atol=1e-2)
    flat = turned_camera_samples(s, pan_deg=0.0, tilt_deg=0.0)  # the undistorted 2D, unturned
    def radius(x):
        return np.linalg.norm((x.keypoints_2d - x.principal_point[:, None]) / x.focal[:, None], axis=-1)

    np.testing.assert_allclose(radius(rolled), radius(flat), atol=1e-5)
    assert np.abs(rolled.keypoints_2d - flat.keypoints_2d).max() > 50  # px: it did turn


@requires_h36m
def test_evaluation_notes_are_said_once_per_kind_with_the_batches_that_had_them(h36m, capsys):
    """predict() lifts in batches; a pixel-space model's notes (2D outside its trained sizes, roots behind the
    camera) come once per kind, from the first batch that had them, with how many batches did, not once per batch."""
    import warnings

    from lifter import Lifter, PoseLifterWarning
    from lifter.evaluate import predict, virtual_camera_samples

    s = virtual_camera_samples(h36m.load([9], stride=100, max_frames_per_sequence=4), focal_scale=6.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        predict(Lifter.from_pretrained("gt"), s, batch_size=16, progress=False)
    said = [str(w.message) for w in caught if issubclass(w.category, PoseLifterWarning)]
    batches = -(-len(s) // 16)
    assert batches > 2 and len(said) == 2, said
    assert said[0].startswith("samples 0-15: model 'gt' reads pixels") and said[0].endswith(
        f"; so in {batches} of {batches} batches of up to 16 samples"), said[0]
    assert "behind the camera" in said[1] and "of up to 16 samples" in said[1], said[1]
    # poselifter evaluate prints them as the other commands print notes, not in Python's warning form (user trial)
    from lifter.cli import main

    with warnings.catch_warnings():
        warnings.simplefilter("default", PoseLifterWarning)  # (shown, also in a run that makes them errors)
        assert main(["evaluate", "gt", "--focal-scales", "6", "--stride", "100", "--max-frames-per-sequence", "4",
                     "--h36m", str(h36m.root)]) == 0
    err = capsys.readouterr().err
    assert "note: focal x6: model 'gt' reads pixels" in err, err  # (which factor the note is about: a trial)
    assert "PoseLifterWarning" not in err and "evaluate.py" not in err, err
