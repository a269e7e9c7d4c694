"""Keypoint files and poselifter's own records: the reading rules a review of ``lifter.io`` / ``lifter.video``
found broken, each pinned (read back, re-lifted, refused by name)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import lifter
from lifter import Lifter, PoseLifterError
from lifter.camera import project
from lifter.cli.lift import output_names
from lifter.detect import Detection, image_from_array, people_h36m
from lifter.io import parse_keypoint_json, parse_keypoint_sequence
from lifter.pipeline import lift_keypoint_file
from lifter.video import FrameResult, PersonState, SequenceRecord, lift_keypoint_sequence

KP = np.asarray(lifter.demo_sample("walking").keypoints_2d, np.float64)  # (17, 2) px, H36M order
POSE = np.asarray(lifter.demo_sample("walking").pose_3d, np.float64)  # (17, 3) mm, camera frame


@pytest.fixture(scope="module")
def default() -> Lifter:
    return Lifter.from_pretrained()


def write(path: Path, obj: object) -> Path:
    path.write_text(json.dumps(obj))
    return path


def coco_from_h36m(kp: np.ndarray) -> np.ndarray:
    """A COCO-17 pose whose limbs are ``kp``'s (H36M) and whose face sits around its nose."""
    idx = {n: i for i, n in enumerate(lifter.JOINT_NAMES)}
    nose = kp[idx["neck_nose"]]
    face = [nose, nose + [-4, -6], nose + [4, -6], nose + [-10, -2], nose + [10, -2]]
    limbs = [kp[idx[n]] for n in ("l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "l_hip",
                                  "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle")]
    return np.array([*face, *limbs])


def test_own_record_relifted_with_another_default_format_keeps_its_h36m_2d(tmp_path, default):
    """A result's ``keypoints_2d`` are H36M's whatever ``--format`` the batch's other files have."""
    src = write(tmp_path / "in.json", {"keypoints": coco_from_h36m(KP).tolist(), "image_size": [800, 600],
                                       "focal": 800})
    first = lift_keypoint_file(src, lifter=default, default_format="coco17")
    record = write(tmp_path / "record.json", first.to_dict())
    again = lift_keypoint_file(record, lifter=default, default_format="coco17")
    plain = lift_keypoint_file(record, lifter=default)
    np.testing.assert_allclose(again.keypoints_2d, first.keypoints_2d, atol=1e-3)
    np.testing.assert_allclose(again.root, plain.root, atol=1e-6)
    np.testing.assert_allclose(again.root, first.root, atol=0.01)  # (read back with its own camera and 2D)


def test_own_sequence_record_relifted_with_another_default_format(tmp_path, default):
    frames = [{"keypoints": (KP + [5 * i, 0]).tolist()} for i in range(4)]
    src = write(tmp_path / "seq.json", {"fps": 10, "image_size": [800, 600], "focal": 800, "format": "h36m17",
                                        "frames": frames})
    rec = lift_keypoint_sequence(src, lifter=default)
    out = write(tmp_path / "seq_record.json", rec.to_dict())
    again = lift_keypoint_sequence(out, lifter=default, default_format="coco17")
    assert len(again.frames) == len(rec.frames) == 4
    assert [len(f.people) for f in again.frames] == [1] * 4
    for a, b in zip(rec.frames, again.frames):
        np.testing.assert_allclose(b.people[0].keypoints_2d, a.people[0].keypoints_2d, atol=1e-3)


def test_track_id_comes_before_an_annotation_id(tmp_path, default):
    """PoseTrack / COCO annotations: ``id`` is new in every frame, ``track_id`` names the person. Two people
    trade places at frame 3; their ``track_id`` says who is who, not their boxes."""
    frames, ann = [], 100
    for i in range(6):
        a, b = KP + [-150, 0], KP * 0.9 + [180, 30]
        if i >= 3:
            a, b = KP + [180, 0], KP * 0.9 + [-150, 30]
        frames.append({"people": [{"keypoints": a.tolist(), "id": ann, "track_id": 0},
                                  {"keypoints": b.tolist(), "id": ann + 1, "track_id": 1}]})
        ann += 2
    p = write(tmp_path / "posetrack.json", {"fps": 10, "image_size": [800, 600], "focal": 800, "format": "h36m17",
                                            "frames": frames})
    assert parse_keypoint_sequence(p).people_ids[0] == [0, 1]
    rec = lift_keypoint_sequence(p, lifter=default)
    for fr in rec.frames:
        by_id = {q.person_id: q for q in fr.people}
        assert set(by_id) == {0, 1}
        # person 0 is the larger one (KP's height), person 1 is 0.9 of it, before and after the swap
        assert np.ptp(by_id[0].keypoints_2d[:, 1]) > np.ptp(by_id[1].keypoints_2d[:, 1])
    tracks = {t["person_id"]: t["track_id"] for t in rec.to_dict()["tracks"]}
    assert set(tracks) == {0, 1} and len(set(tracks.values())) == 2
    for fr in rec.frames:
        assert {q.person_id: q.track_id for q in fr.people} == tracks


def _gappy_record() -> SequenceRecord:
    frames = []
    for idx in [0, 1, 2, 5, 6]:  # frames 3 and 4 undecodable (bad_frames)
        st = PersonState(track_id=1, keypoints_2d=KP + [idx * 20, 0], root=np.array([0, 0, 4000.0]),
                         relative=np.zeros((17, 3)), root_raw=np.array([0, 0, 4000.0]), relative_raw=np.zeros((17, 3)),
                         canonical_depth=5000.0)
        frames.append(FrameResult(index=idx, time_s=idx / 10, people=[st]))
    return SequenceRecord(input="clip.mp4", kind="video", model="default", fps=10.0, image_size=(800, 600),
                          focal=(800.0, 800.0), focal_source="user", principal_point=(400.0, 300.0), smoothing=1.0,
                          frames=frames, bad_frames=[{"index": 3, "error": "x"}, {"index": 4, "error": "x"}])


def test_video_record_read_back_keeps_its_frame_indices_and_times(tmp_path, default):
    p = write(tmp_path / "video.json", _gappy_record().to_dict())
    assert parse_keypoint_sequence(p).frame_indices == [0, 1, 2, 5, 6]
    again = lift_keypoint_sequence(p, lifter=default)
    assert [f.index for f in again.frames] == [0, 1, 2, 5, 6]
    assert [f.time_s for f in again.frames] == pytest.approx([0.0, 0.1, 0.2, 0.5, 0.6])
    # the duration bound counts time, not frames: 0.35 s keeps frames 0-2
    short = lift_keypoint_sequence(p, lifter=default, max_seconds=0.35)
    assert [f.index for f in short.frames] == [0, 1, 2]
    assert any("only the first 0.35 s (3 frames)" in w for w in short.warnings)


def test_unreadable_frame_indices_are_said(tmp_path):
    d = _gappy_record().to_dict()
    d["frames"][2]["index"] = 9  # (not increasing)
    ks = parse_keypoint_sequence(write(tmp_path / "bad.json", d))
    assert ks.frame_indices is None
    assert any("'index' and 'time_s' are not read" in w for w in ks.warnings)
    consecutive = [{"index": i, "time_s": i / 5, "people": [{"keypoints": KP.tolist()}]} for i in range(3)]
    plain = parse_keypoint_sequence(write(tmp_path / "ok.json", {"fps": 5, "format": "h36m17",
                                                                 "frames": consecutive}))
    assert plain.frame_indices is None and not any("index" in w for w in plain.warnings)


def test_another_tools_frame_numbers_are_not_read_as_times(tmp_path, default):
    """A review: a clip cut out of a long video keeps its source frame numbers (18000 on) as each frame's 'index';
    read as poselifter's own indices, every frame fell past --max-seconds ("no person in any frame")."""
    frames = [{"index": 18000 + i, "people": [{"keypoints": (KP + [i, 0]).tolist()}]} for i in range(30)]
    p = write(tmp_path / "clip.json", {"fps": 30, "format": "h36m17", "image_size": [800, 600], "focal": 800,
                                       "frames": frames})
    assert parse_keypoint_sequence(p).frame_indices is None
    rec = lift_keypoint_sequence(p, lifter=default)
    assert [f.index for f in rec.frames] == list(range(30)) and not any("index" in w for w in rec.warnings)


def test_max_seconds_shorter_than_a_frame_is_named(tmp_path, default):
    p = write(tmp_path / "short.json", {"fps": 30, "image_size": [800, 600], "format": "h36m17",
                                        "frames": [{"keypoints": KP.tolist()}] * 5})
    with pytest.raises(PoseLifterError, match="shorter than one frame"):
        lift_keypoint_sequence(p, lifter=default, max_seconds=0.02)


def test_a_person_under_another_tools_keypoint_name_is_refused(tmp_path):
    p = write(tmp_path / "mixed.json", {"people": [{"keypoints": KP.tolist()}, {"kpts": (KP * 1.3).tolist()}],
                                        "format": "h36m17", "image_size": [800, 600]})
    with pytest.raises(PoseLifterError, match="person 2 has 'kpts' and no 'keypoints'"):
        parse_keypoint_json(p)
    nobody = write(tmp_path / "null.json", {"people": [{"keypoints": KP.tolist()}, {"keypoints": None, "id": 5}],
                                            "format": "h36m17", "image_size": [800, 600]})
    assert len(parse_keypoint_json(nobody).people) == 1  # (null keypoints: nobody there, as before)


@pytest.mark.parametrize("fmt", [17, ["coco17"]])
def test_a_non_string_format_is_refused_in_every_layout(tmp_path, fmt):
    for body in ({"people": [{"keypoints": KP.tolist()}]}, {"keypoints": KP.tolist()}):
        p = write(tmp_path / "f.json", {**body, "format": fmt, "image_size": [800, 600]})
        with pytest.raises(PoseLifterError, match="'format' must be a string"):
            parse_keypoint_json(p)


@pytest.mark.parametrize("field", ["focal", "image_size", "confidence", "fps"])
def test_integers_too_large_for_a_float_are_refused_by_name(tmp_path, field):
    big, kp = str(10**400), json.dumps(KP.tolist())
    rows = json.dumps(np.c_[KP, np.ones(17)].tolist()).replace("1.0]", big + "]", 1)
    text = {"focal": f'{{"keypoints": {kp}, "focal": {big}}}',
            "image_size": f'{{"keypoints": {kp}, "image_size": [{big}, 1]}}',
            "confidence": f'{{"keypoints": {rows}}}',
            "fps": f'{{"fps": {big}, "frames": [{kp}]}}'}[field]
    (tmp_path / "x.json").write_text(text)
    match = {"focal": "focal must be", "image_size": "image_size must be", "confidence": "confidence is inf",
             "fps": "'fps' must be the frame rate"}[field]
    with pytest.raises(PoseLifterError, match=match):
        (parse_keypoint_sequence if field == "fps" else parse_keypoint_json)(tmp_path / "x.json")


def test_an_infinite_confidence_is_refused(tmp_path):
    rows = json.dumps(np.c_[KP, np.ones(17)].tolist()).replace("1.0]", "Infinity]", 1)
    (tmp_path / "inf.json").write_text(f'{{"keypoints": {rows}, "format": "h36m17"}}')
    with pytest.raises(PoseLifterError, match="keypoint 0's confidence is inf"):
        parse_keypoint_json(tmp_path / "inf.json")


def test_sequence_notes_come_from_every_frame(tmp_path):
    fr = {"keypoints": KP.tolist()}
    ks = parse_keypoint_sequence(write(tmp_path / "a.json", {"fps": 10, "image_size": [800, 600],
                                                             "frames": [[], fr, fr]}))
    assert any("17 joints without 'format'" in w for w in ks.warnings)  # (after a leading empty frame)
    low, high = ({"keypoints": np.c_[KP, np.full(17, c)].tolist()} for c in (0.9, 5.0))
    ks = parse_keypoint_sequence(write(tmp_path / "b.json", {"fps": 10, "image_size": [800, 600],
                                                             "format": "h36m17", "frames": [low, high]}))
    assert [w for w in ks.warnings if w.startswith("third values up to 5:")]  # (the second frame's)


def test_lens_sequence_is_judged_on_the_2d_it_lifted(tmp_path, default):
    """A pose seen through a strong lens fits its lift once undistorted; the distorted 2D would not (a misfit
    note for every frame once any frame had one)."""
    f, pp, lens = 300.0, [640.0, 480.0], [-0.2, 0.05, 0.0, 0.0, 0.0]
    kd = project(POSE - POSE[0] + [1200, 300, 1200], focal=f, principal_point=pp, k=lens[:3], p=lens[3:])
    bad = KP.copy()
    bad[[13, 16]] = bad[[16, 13]] + [0, 200]  # frame 0: a detector's mistake, with a note of its own
    cam = {"image_size": [1280, 960], "focal": f, "principal_point": pp, "format": "h36m17", "distortion": lens}
    p = write(tmp_path / "lens.json", {"fps": 10, **cam, "frames": [
        {"people": [{"keypoints": (bad * 0.5 + [100, 100]).tolist()}]}, {"people": [{"keypoints": kd.tolist()}]}]})
    notes = [w for w in lift_keypoint_sequence(p, lifter=default).warnings if "do not fit their 2D" in w]
    assert len(notes) == 1 and notes[0].startswith("frame 0:") and "frames like it" not in notes[0]


class _Corner:
    """An estimator that puts its second joint on the bottom-right corner of the image it is given."""

    name = "corner"

    def detect(self, rgb: np.ndarray) -> list[Detection]:
        h, w = rgb.shape[:2]
        uv = np.array([[0.5, 0.5], [1.0, 1.0]] + [[0.5, 0.5 + 0.01 * i] for i in range(15)])
        return [Detection(keypoints=uv * [w, h], scores=np.ones(17), bbox_xywh=np.array([0, 0, w, h], float),
                          keypoint_format="h36m17")]


@pytest.mark.parametrize("size", [(1001, 3000), (150, 4000), (3000, 1001), (1, 5000)])
def test_downscaled_detections_map_back_per_axis(size):
    W, H = size
    img = image_from_array(np.zeros((H, W, 3), np.uint8), max_side=1000)
    d = people_h36m(img, estimator=_Corner())[0]
    np.testing.assert_allclose(d.keypoints_2d[1], [W, H], atol=1e-9)


def test_bvh_per_person_names_are_kept_for_their_input():
    files = [Path("in/a.json"), Path("in/a_person2.json"), Path("in/b_track3.json"), Path("in/b.json")]
    names, notes = output_names(files, Path("out"), per_person=True)
    assert names[0] == "a" and names[1] != "a_person2" and names[2] == "b_track3" and names[3] != "b"
    assert len(set(names)) == 4 and len(notes) == 2 and all("per-person names" in n for n in notes)
    assert output_names(files, Path("out"))[0] == ["a", "a_person2", "b_track3", "b"]  # (no --bvh: no such files)


def test_record_read_back_lifts_with_its_own_camera_and_2d(tmp_path, default):
    obj = {"keypoints": KP.tolist(), "format": "h36m17", "image_size": [800, 600], "focal": [801.234567, 799.87654],
           "principal_point": [401.2345, 299.8765], "source": "clean"}
    first = lift_keypoint_file(write(tmp_path / "in.json", obj), lifter=default)
    out = write(tmp_path / "out.json", first.to_dict())
    kf = parse_keypoint_json(out)
    np.testing.assert_allclose(kf.focal, [801.234567, 799.87654], rtol=0, atol=1e-9)
    np.testing.assert_allclose(kf.principal_point, [401.2345, 299.8765], rtol=0, atol=1e-9)
    again = lift_keypoint_file(out, lifter=default)
    np.testing.assert_allclose(again.root, first.root, atol=0.01)


def test_a_refused_step_can_be_given_again():
    """A review: a step refused by the tracker (two names for one person) still counted as taken, so the same frame
    given again correctly was refused as out of order."""
    from lifter.video import SequenceTracker

    seq = SequenceTracker(fps=25)
    root, rel = np.array([[0.0, 0, 3000]]), np.zeros((1, 17, 3))
    with pytest.raises(PoseLifterError, match="2 person ids for 1 people"):
        seq.step(0, 0.0, KP[None], root, rel, 1000.0, person_ids=["a", "b"])
    assert seq.step(0, 0.0, KP[None], root, rel, 1000.0, person_ids=["a"])[0].track_id == 1


def test_a_person_under_another_tools_name_is_refused_in_a_coco_list(tmp_path):
    p = write(tmp_path / "coco.json", [{"keypoints": np.c_[KP, np.ones(17)].ravel().tolist(), "image_id": 1},
                                       {"kpts": (KP * 1.3).tolist(), "image_id": 1}])
    with pytest.raises(PoseLifterError, match="person 2 has 'kpts' and no 'keypoints'"):
        parse_keypoint_json(p, default_format="h36m17")


def test_the_reassumed_focal_note_reads_like_a_focal(tmp_path, default):
    obj = {"keypoints": KP.tolist(), "format": "h36m17", "image_size": [800, 600]}
    first = lift_keypoint_file(write(tmp_path / "in.json", obj), lifter=default)
    assert first.focal_source == "default-fov"
    again = lift_keypoint_file(write(tmp_path / "out.json", first.to_dict()), lifter=default)
    want = f"the file's focal length ({first.focal[0]:.1f} px) was assumed when it was written"
    assert any(w.startswith(want) for w in again.warnings), again.warnings


def test_a_sequence_tracked_again_with_its_names_groups_as_it_did(tmp_path, default):
    """A review: the app's re-lift tracked a cut record again with the record's own ids, so a name alone in one kept
    frame joined the followed person's track (their smoothing blended, 95 mm). The record keeps the names its
    tracker followed (``SequenceRecord.tracking_names``), and tracking again with them groups as the upload did."""
    from lifter.video import track_lifted

    frames = []
    for t in range(10):
        a = {"keypoints": (KP + [3 * t, 0]).tolist(), "person_id": "A"}
        b = {"keypoints": (KP * 0.95 + [3 * t + 15, 0]).tolist(), "person_id": "B"}
        frames.append({"people": [b] if t == 5 else [a, b]})
    p = write(tmp_path / "names.json", {"fps": 25, "format": "h36m17", "focal": 1000, "image_size": [1000, 1000],
                                        "frames": frames})
    rec = lift_keypoint_sequence(p, lifter=default, max_people=1)
    assert rec.tracking_names is not None and len(rec.tracking_names) == len(rec.frames)
    lifted = [(f.index, f.time_s, np.stack([q.keypoints_2d for q in f.people]),
               np.stack([q.root_raw for q in f.people]), np.stack([q.relative_raw for q in f.people]), None)
              for f in rec.frames]
    ids = [[q.person_id for q in f.people] for f in rec.frames]
    again = track_lifted(lifted, fps=rec.fps, focal=np.asarray(rec.focal), smoothing=rec.smoothing, person_ids=ids,
                         names=rec.tracking_names)
    assert [f.people[0].track_id for f in again] == [f.people[0].track_id for f in rec.frames]
    for a, b in zip(again, rec.frames):
        np.testing.assert_allclose(a.people[0].root, b.people[0].root, atol=1e-6)


def test_a_sequence_without_a_frame_rate_takes_the_assumed_one_with_a_note(tmp_path):
    """``assumed_fps`` (the app's: it has no --fps) fills in a missing frame rate, with a note first; a file's own rate
    and ``fps=`` (--fps) come before it, and without it the missing rate is refused as before."""
    from lifter.io import ASSUMED_FPS

    frames = [{"keypoints": (KP + [5 * i, 0]).tolist()} for i in range(3)]
    bare = write(tmp_path / "bare.json", {"frames": frames, "image_size": [1000, 1000], "format": "h36m17"})
    with pytest.raises(PoseLifterError, match=r"'fps' is missing"):
        parse_keypoint_sequence(bare)
    ks = parse_keypoint_sequence(bare, assumed_fps=ASSUMED_FPS, cli_options=False)
    assert ks.fps == ASSUMED_FPS == 30.0
    assert ks.warnings[0] == ("the file gives no frame rate: assumed 30 frames/s for playback and smoothing (give "
                              "\"fps\" at the file's top level)")
    assert "or --fps" in parse_keypoint_sequence(bare, assumed_fps=30).warnings[0]  # (the command line's option)
    told = parse_keypoint_sequence(bare, fps=12, assumed_fps=30)
    assert told.fps == 12 and not any("assumed" in w for w in told.warnings)
    own = write(tmp_path / "own.json", {"frames": frames, "fps": 25, "image_size": [1000, 1000], "format": "h36m17"})
    ks = parse_keypoint_sequence(own, assumed_fps=30)
    assert ks.fps == 25 and not any("assumed" in w for w in ks.warnings)
    with pytest.raises(PoseLifterError, match=r"assumed_fps must be the frame rate"):
        parse_keypoint_sequence(bare, assumed_fps=float("nan"))
    # OpenPose's files of one frame each carry no rate: assumed too, their frames' times at that rate
    d = tmp_path / "op"
    d.mkdir()
    for n in (0, 1, 3):
        write(d / f"v_{n:012d}_keypoints.json", {"people": [{"pose_keypoints_2d": [
            c for x, y in KP.tolist() + [[0.0, 0.0]] * 8 for c in (x, y, 0.9)]}]})
    ks = parse_keypoint_sequence(d / "v_%012d_keypoints.json", assumed_fps=10)
    assert ks.fps == 10 and ks.frame_indices == [0, 1, 3]
    assert ks.warnings[0].startswith("files of one frame each give no frame rate: assumed 10 frames/s")


def test_a_sequence_without_an_image_size_takes_the_fallback_image_s_where_its_poses_fit(tmp_path, default):
    """``fallback_image`` (the app: the photo uploaded before) gives the size of a sequence that has neither an image
    size nor a principal point, with a note; poses mostly outside it are refused naming it (another image's pixels put
    the root metres off), and a file's own size, principal point or ``image_size=`` come first."""
    F, W, H = 1000.0, 1000, 1000
    frames = [{"keypoints": (KP + [5 * i, 0]).tolist()} for i in range(3)]
    sized = write(tmp_path / "sized.json", {"frames": frames, "fps": 10, "focal": F, "image_size": [W, H],
                                            "format": "h36m17"})
    bare = write(tmp_path / "bare.json", {"frames": frames, "fps": 10, "focal": F, "format": "h36m17"})
    ref = lift_keypoint_sequence(sized, lifter=default)
    rec = lift_keypoint_sequence(bare, lifter=default, fallback_image=("room.jpg", (W, H)))
    assert rec.image_size == (W, H) and rec.principal_point == ref.principal_point
    assert f"no image_size in the file: that of room.jpg ({W} x {H} px) is used" in rec.warnings
    np.testing.assert_allclose(rec.frames[0].people[0].root, ref.frames[0].people[0].root, atol=1e-6)
    with pytest.raises(PoseLifterError, match=r"bare.json: the keypoint sequence has no \"image_size\".*its poses lie "
                                              r"mostly outside room.jpg \(200 x 150 px\), whose size would be used"):
        lift_keypoint_sequence(bare, lifter=default, fallback_image=("room.jpg", (200, 150)))
    for path, kw in ((sized, {}), (bare, {"image_size": (800, 800)}), (bare, {"principal_point": (500, 500)}),
                     (write(tmp_path / "pp.json", {"frames": frames, "fps": 10, "focal": F, "format": "h36m17",
                                                   "principal_point": [W / 2, H / 2]}), {})):
        rec = lift_keypoint_sequence(path, lifter=default, fallback_image=("room.jpg", (200, 150)), **kw)
        assert rec.image_size != (200, 150) and not any("room.jpg" in w for w in rec.warnings), path
    with pytest.raises(PoseLifterError, match=r"fallback_image \(room.jpg\)"):
        lift_keypoint_sequence(bare, lifter=default, fallback_image=("room.jpg", (0, 150)))


@pytest.mark.parametrize("reader", ["file", "sequence"])
def test_one_rule_for_the_image_a_keypoint_file_or_sequence_was_found_in(tmp_path, default, reader):
    """A single keypoint file and a sequence take ``fallback_image``'s size and EXIF focal by one rule
    (:func:`lifter.pipeline.keypoints_image`; the app's photo uploaded before): where neither the caller nor the file
    gives an image size or a principal point, and not where the file's principal point (a K matrix) says the
    keypoints are another image's; refused when they lie mostly outside it."""
    from lifter.detect import ExifCamera, guess_focal

    W, H = 1200, 900
    exif = ExifCamera(focal_35mm=50.0)
    want = guess_focal((W, H), exif=exif)

    def doc(**fields):
        kp = (KP + [100, 50]).tolist()
        body = {"frames": [{"keypoints": kp}] * 2, "fps": 10} if reader == "sequence" else {"keypoints": kp}
        return write(tmp_path / f"{len(list(tmp_path.iterdir()))}.json", {**body, "format": "h36m17", **fields})

    def lift(path, image=("room.jpg", (W, H), exif), **kw):
        if reader == "sequence":
            return lift_keypoint_sequence(path, lifter=default, fallback_image=image, **kw)
        return lift_keypoint_file(path, lifter=default, fallback_image=image, **kw)

    rec = lift(doc())
    assert rec.image_size == (W, H) and rec.principal_point == (W / 2, H / 2)
    assert rec.focal_source == "exif-35mm" and np.allclose(rec.focal, want.focal)
    assert f"no image_size in the file: that of room.jpg ({W} x {H} px) is used" in rec.warnings
    assert not any("top-left quarter" in w for w in rec.warnings), rec.warnings
    # a 5x larger image: the keypoints sit in its top-left corner, as those of a smaller copy would (a user trial's
    # 1000-px frame's keypoints on a 5000-px photo, lifted 26 m away unsaid)
    big = lift(doc(), image=("room.jpg", (5 * W, 5 * H)))
    which = "every pose lies" if reader == "sequence" else "the pose lies"  # (two frames; one person)
    assert any(w.startswith(f"{which} in the top-left quarter of room.jpg ({5 * W} x {5 * H} px)") and
               "add the file's own \"image_size\"" in w for w in big.warnings), big.warnings
    assert lift(doc(image_size=[W, H])).focal_source == "exif-35mm"  # (its own size, the same: the same image)
    assert lift(doc(image_size=[1000, 1000])).focal_source == "default-fov"  # (another image)
    K = [[1000.0, 0.0, W], [0.0, 1000.0, H], [0.0, 0.0, 1.0]]  # (a principal point: not the photo's pixels)
    rec = lift(doc(K=K))
    assert rec.image_size is None and rec.focal_source == "keypoint-file" and rec.principal_point == (W, H)
    assert not any("room.jpg" in w for w in rec.warnings), rec.warnings
    assert lift(doc(), principal_point=(W, H), focal=1000.0).image_size is None
    with pytest.raises(PoseLifterError, match=rf"the keypoint {reader} has no \"image_size\".*its poses lie mostly "
                                              r"outside room.jpg \(200 x 150 px\), whose size would be used"):
        lift(doc(), image=("room.jpg", (200, 150)))
    with pytest.raises(PoseLifterError, match=r"fallback_image must be \(name, \(W, H\)\)"):
        lift(doc(), image=("room.jpg",))
    from lifter.pipeline import keypoints_image  # (called on its own: the message names no file, a review)

    with pytest.raises(PoseLifterError, match=r"^the keypoint file has no \"image_size\""):
        keypoints_image(None, None, fallback_image=("room.jpg", (200, 150)), poses=[KP + [100, 50]])


def test_a_sequence_in_the_fallback_image_s_pixels_takes_its_exif_focal(tmp_path, default):
    """``fallback_image``'s EXIF (the app: the photo uploaded before) gives the focal length of a sequence in that
    image's pixels that gives none, as for a photo (:func:`lifter.detect.guess_focal`); a file's or the caller's focal
    comes first, and a file of another image size does not take it."""
    from lifter.detect import ExifCamera, guess_focal

    W, H = 1200, 900
    exif = ExifCamera(focal_35mm=50.0)
    want = guess_focal((W, H), exif=exif)
    frames = [{"keypoints": (KP + [5 * i, 0]).tolist()} for i in range(3)]
    bare = write(tmp_path / "bare.json", {"frames": frames, "fps": 10, "format": "h36m17"})
    rec = lift_keypoint_sequence(bare, lifter=default, fallback_image=("room.jpg", (W, H), exif))
    assert rec.focal_source == want.source == "exif-35mm"
    np.testing.assert_allclose(rec.focal, want.focal, rtol=1e-6)
    assert any(want.detail in w for w in rec.warnings)
    # the same size given by the file: the same image, so its EXIF too
    same = write(tmp_path / "same.json", {"frames": frames, "fps": 10, "image_size": [W, H], "format": "h36m17"})
    assert lift_keypoint_sequence(same, lifter=default, fallback_image=("room.jpg", (W, H), exif)).focal_source == \
        "exif-35mm"
    # without EXIF, or another image, or a focal given: not used
    assert lift_keypoint_sequence(bare, lifter=default, fallback_image=("room.jpg", (W, H))).focal_source == \
        "default-fov"
    other = write(tmp_path / "other.json", {"frames": frames, "fps": 10, "image_size": [1000, 1000],
                                            "format": "h36m17"})
    assert lift_keypoint_sequence(other, lifter=default, fallback_image=("room.jpg", (W, H), exif)).focal_source == \
        "default-fov"
    told = lift_keypoint_sequence(bare, lifter=default, focal=800.0, fallback_image=("room.jpg", (W, H), exif))
    assert told.focal_source != "exif-35mm" and np.allclose(told.focal, 800.0)
    filed = write(tmp_path / "filed.json", {"frames": frames, "fps": 10, "focal": 700.0, "format": "h36m17"})
    rec = lift_keypoint_sequence(filed, lifter=default, fallback_image=("room.jpg", (W, H), exif))
    assert rec.focal_source == "keypoint-file" and np.allclose(rec.focal, 700.0)
    with pytest.raises(PoseLifterError, match=r"fallback_image must be \(name, \(W, H\)\)"):
        lift_keypoint_sequence(bare, lifter=default, fallback_image=("room.jpg",))


def test_every_record_gives_its_data_by_to_dict_and_to_json_is_deprecated(tmp_path, default):
    """A developer trial: ``LiftResult.to_dict()`` but ``LiftRecord.to_json()`` (which returned the dict, where
    ErrorModel's and TrainConfig's ``to_json`` return text) and AttributeError on ``rec.to_dict()``. Every record and
    its parts give the plain data by ``to_dict()``; ``to_json()`` still returns the same dict, with a
    DeprecationWarning naming the new name."""
    import json

    from lifter.io import JsonReady
    from lifter.video import lift_keypoint_sequence

    sample = lifter.demo_sample("walking")
    rec = lift_keypoint_file(write(tmp_path / "kp.json", {"keypoints": sample.keypoints_2d.tolist(),
                                                         "image_size": list(sample.image_size)}), lifter=default)
    seq = lift_keypoint_sequence(write(tmp_path / "seq.json", {"fps": 10, "image_size": list(sample.image_size),
                                                               "frames": [
        {"keypoints": (sample.keypoints_2d + [i, 0]).tolist()} for i in range(3)]}), lifter=default)
    for obj in (rec, rec.people[0], seq, seq.frames[0], seq.frames[0].people[0]):
        assert isinstance(obj, JsonReady)
        d = obj.to_dict()
        json.dumps(d)  # (plain data)
        with pytest.warns(DeprecationWarning, match=r"\.to_json\(\) is now to_dict\(\)"):
            assert obj.to_json() == d
