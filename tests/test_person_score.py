"""Detections and a keypoint file's people whose mean joint score is below ``min_score`` are left out as no person
(:data:`lifter.detect.MIN_PERSON_SCORE`), and people lying sideways in a photo or video are named (a developer
trial: a close-up of a wall was lifted as a person half a metre away, scored 0.14, with exit code 0 under --strict; a
COCO results file's detection scored 0.04 was kept by --max-people 1 over the real person; a photo turned a quarter
without its EXIF orientation was lifted 1.6 m off without a word)."""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
import pytest
from conftest import ScriptedEstimator, random_pose_cam, tiny_lifter

from lifter import PoseLifterError
from lifter.camera import project
from lifter.checkpoint import save_checkpoint
from lifter.cli import main
from lifter.detect import (
    MIN_PERSON_SCORE,
    Detection,
    EstimatorError,
    NoPersonError,
    bbox_of,
    detect_people,
    load_image,
)
from lifter.pipeline import detected_sideways_notes, lift_image, lift_keypoint_file
from lifter.video import lift_keypoint_sequence, lift_video

Image = pytest.importorskip("PIL.Image")


class _Scored:
    """Fixed detections ``(17, 2)`` px, each with its own score for every joint."""

    name = "scored"
    keypoint_format = "h36m17"

    def __init__(self, people: list[tuple[np.ndarray, float]]) -> None:
        self.people = people

    def detect(self, image: np.ndarray) -> list[Detection]:
        return [Detection(keypoints=k, scores=np.full(17, s), bbox_xywh=bbox_of(k), keypoint_format="h36m17")
                for k, s in self.people]


@pytest.fixture(scope="module")
def lifter():
    return tiny_lifter(32)


@pytest.fixture(scope="module")
def weights(tmp_path_factory, lifter) -> Path:
    return save_checkpoint(tmp_path_factory.mktemp("w") / "tiny.pt", lifter.net, lifter.codec)


@pytest.fixture()
def kp17() -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(0), 1)[0], focal=1000.0, principal_point=(640.0, 360.0))


@pytest.fixture()
def photo(tmp_path) -> Path:
    p = tmp_path / "p.png"
    Image.new("RGB", (1280, 720), (50, 60, 70)).save(p)
    return p


def test_a_photos_only_detection_below_the_floor_is_no_person(photo, lifter, kp17):
    junk = _Scored([(kp17, 0.14)])
    with pytest.raises(NoPersonError, match=r"p\.png: no person found by the scored 2D detector; 1 detection with a "
                                            r"mean joint score below 0\.3 \(0\.14\) left out as no person \(the "
                                            r"library's min_score=0 or poselifter lift --min-score 0 keeps every "
                                            r"one\)"):
        lift_image(load_image(photo), lifter=lifter, estimator=junk, focal=1000.0)
    rec = lift_image(load_image(photo), lifter=lifter, estimator=junk, focal=1000.0, min_score=0)
    assert rec.num_people == 1 and any("detector is unsure" in w for w in rec.warnings), rec.warnings
    # exactly at the floor: kept
    rec = lift_image(load_image(photo), lifter=lifter, estimator=_Scored([(kp17, MIN_PERSON_SCORE)]), focal=1000.0)
    assert rec.num_people == 1 and not any("left out" in w for w in rec.warnings)
    for bad in (1.5, -0.1, float("nan"), "high", "0.5", True, None):  # (a review: True and "0.5" were taken)
        with pytest.raises(PoseLifterError, match=r"min_score must be"):
            detect_people(load_image(photo), estimator=junk, min_score=bad)
    assert len(detect_people(load_image(photo), estimator=junk, min_score=np.float32(0.1))) == 1
    assert len(detect_people(load_image(photo), estimator=junk, min_score=np.array(0.1))) == 1  # (a 0-d array)
    # a score just under the floor is not shown as the floor (a review: 0.2996 read "below 0.3 (0.30)")
    with pytest.raises(NoPersonError, match=r"below 0\.3 \(0\.29\)"):
        detect_people(load_image(photo), estimator=_Scored([(kp17, 0.2996)]))
    with pytest.raises(NoPersonError, match=r"below 0\.3 \(0\.29\)"):  # (a review: 0.29 read 0.28)
        detect_people(load_image(photo), estimator=_Scored([(kp17, 0.29)]))


def test_an_estimators_scores_off_the_0_1_scale_are_refused_by_name(photo, lifter, kp17):
    """Detection.scores are confidences in [0, 1], which the floor and the notes read; an estimator that returns
    another scale (heatmap maxima up to 4.5, logits below 0) or a score per keypoint of another count is refused,
    naming the estimator and the fix. Before, scores of 4.5 kept any detection and logits dropped real people."""
    for score, shown in ((4.5, "4.5 to 4.5"), (-2.0, "-2 to -2")):
        with pytest.raises(PoseLifterError, match=rf"the scored 2D estimator returned scores from {shown}: "
                                                  r"Detection\.scores must be confidences in \[0, 1\].*sigmoid"):
            detect_people(load_image(photo), estimator=_Scored([(kp17, 0.9), (kp17 + 5.0, score)]))
        with pytest.raises(PoseLifterError, match=r"in \[0, 1\]"):
            lift_image(load_image(photo), lifter=lifter, estimator=_Scored([(kp17, score)]), focal=1000.0, min_score=0)

    class _Short(_Scored):
        def detect(self, image: np.ndarray) -> list[Detection]:
            return [Detection(keypoints=kp17, scores=np.full(16, 0.9), bbox_xywh=bbox_of(kp17),
                              keypoint_format="h36m17")]

    with pytest.raises(EstimatorError, match=r"returned \(16,\) scores for a person in h36m17 \(17 keypoints\): "
                                             r"Detection\.scores must be \(17,\), one per keypoint"):
        detect_people(load_image(photo), estimator=_Short([]))
    for edge in (0.0, 1.0, 1.0000001, -1e-7):  # (the scale's ends are on it; rounding past them is clipped: a review)
        found = detect_people(load_image(photo), estimator=_Scored([(kp17, edge)]), min_score=0)
        assert len(found) == 1 and 0.0 <= found[0].scores.min() <= found[0].scores.max() <= 1.0
    with pytest.raises(EstimatorError, match=r"returned scores from 1\.00001 to 1\.00001"):  # (not "1 to 1")
        detect_people(load_image(photo), estimator=_Scored([(kp17, 1.00001)]))
    with pytest.raises(EstimatorError, match=r"returned scores that are not numbers \(ndarray of <U4\)"):
        detect_people(load_image(photo), estimator=_Scored([(kp17, "high")]))  # type: ignore[list-item]


def test_an_estimator_that_returns_an_iterator_still_finds_its_people(photo, kp17):
    """(a review) Checking the scores read an iterator the estimator returned, and sorting found nobody after it."""

    class _Iter(_Scored):
        def detect(self, image: np.ndarray):  # type: ignore[override]
            return iter(super().detect(image))

    assert len(detect_people(load_image(photo), estimator=_Iter([(kp17, 0.9), (kp17 + 5.0, 0.8)]))) == 2


def test_a_video_whose_estimator_gives_scores_off_the_scale_stops_by_name(tmp_path, lifter, kp17):
    """(a review) The check's error was caught as a bad frame: a clip came back with no frames and "12 bad frame(s)
    skipped", exit code 0. The estimator's fault is every frame's: the video stops, naming it."""
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]

    class _Heat(ScriptedEstimator):
        def detect(self, image: np.ndarray) -> list:
            return [replace(d, scores=np.full(17, 4.5)) for d in super().detect(image)]

    from dataclasses import replace

    with pytest.raises(EstimatorError, match=r"the scripted 2D estimator returned scores from 4\.5 to 4\.5"):
        lift_video(_clip(tmp_path / "c.avi", 6), lifter=lifter, estimator=_Heat([[real]] * 6), focal=1000.0)


def test_a_detection_whose_scores_are_not_numbers_is_kept(photo, lifter, kp17):
    """(a review) A detector's NaN scores made the mean NaN, which no floor compares above: the person was left out
    even at min_score=0. Such a person is kept (there is no score to read)."""
    for floor in (0.0, MIN_PERSON_SCORE):
        assert len(detect_people(load_image(photo), estimator=_Scored([(kp17, float("nan"))]), min_score=floor)) == 1


def test_a_larger_detection_below_the_floor_does_not_take_max_people(photo, lifter, kp17):
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    big = 1.2 * (kp17 - kp17[0]) + [900.0, 360.0]
    est = _Scored([(big, 0.05), (real, 0.9)])
    rec = lift_image(load_image(photo), lifter=lifter, estimator=est, focal=1000.0, max_people=1)
    assert rec.num_people == 1 and len(rec.people) == 1
    np.testing.assert_allclose(rec.keypoints_2d, real)
    assert any(w.startswith("1 detection with a mean joint score below 0.3 (0.05) left out as no person")
               for w in rec.warnings), rec.warnings
    assert not any("more than 1 person" in w for w in rec.warnings)  # (the one left out is no person)


def test_the_cli_fails_a_photo_with_only_a_low_scored_detection(tmp_path, photo, weights, kp17, capsys, monkeypatch):
    import lifter.detect as detect

    monkeypatch.setitem(detect._ESTIMATORS, "_junk", lambda **kw: _Scored([(kp17, 0.14)]))
    base = ["lift", "--no-progress", str(photo), "--detector", "_junk", "--weights", str(weights), "--focal", "1000"]
    code = main([*base, "--out", str(tmp_path / "o"), "--strict"])
    err = capsys.readouterr().err
    assert code == 1 and "left out as no person" in err and not (tmp_path / "o" / "p.json").exists(), err
    code = main([*base, "--out", str(tmp_path / "o2"), "--min-score", "0"])
    assert code == 0 and json.loads((tmp_path / "o2" / "p.json").read_text())["num_people"] == 1
    capsys.readouterr()
    code = main([*base, "--out", str(tmp_path / "o3"), "--min-score", "1.5"])
    assert code == 2 and "--min-score must be in [0, 1]" in capsys.readouterr().err


def _coco_rows(kp17: np.ndarray, score: float) -> list[float]:
    """A COCO-17 pose (x, y, score rows, flattened) with the H36M limbs of ``kp17`` and a face at its head."""
    h = {n: i for i, n in enumerate(("pelvis", "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle", "spine",
                                     "thorax", "neck_nose", "head_top", "l_shoulder", "l_elbow", "l_wrist",
                                     "r_shoulder", "r_elbow", "r_wrist"))}
    nose = kp17[h["neck_nose"]]
    xy = [nose, nose + [3, -4], nose + [-3, -4], nose + [6, -2], nose + [-6, -2]] + [
        kp17[h[n]] for n in ("l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "l_hip", "r_hip",
                             "l_knee", "r_knee", "l_ankle", "r_ankle")]
    return [float(v) for p in xy for v in (*p, score)]


def test_a_keypoint_files_low_scored_people_are_left_out(tmp_path, weights, kp17, capsys):
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    big = 1.2 * (kp17 - kp17[0]) + [900.0, 360.0]

    def results(*people: tuple[np.ndarray, float], name: str) -> Path:
        p = tmp_path / name
        p.write_text(json.dumps([{"image_id": 1, "category_id": 1, "keypoints": _coco_rows(k, s), "score": s}
                                 for k, s in people]))
        return p

    path = results((real, 0.9), (big, 0.04), name="res.json")
    base = ["lift", "--no-progress", "--weights", str(weights), "--image-size", "1280", "720"]
    code = main([*base, str(path), "--out", str(tmp_path / "o"), "--max-people", "1"])
    d = json.loads((tmp_path / "o" / "res.json").read_text())
    assert code == 0 and d["num_people"] == 1 and [q["input_index"] for q in d["people"]] == [0], d
    assert any(w.startswith("of the file's 2 people, 1 person with a mean joint score below 0.3 (0.04) left out")
               for w in d["warnings"]), d["warnings"]
    assert not any("each is lifted" in w or "are lifted" in w for w in d["warnings"]), d["warnings"]
    capsys.readouterr()
    code = main([*base, str(results((big, 0.04), (real, 0.1), name="junk.json")), "--out", str(tmp_path / "o2")])
    err = capsys.readouterr().err
    assert code == 1 and "junk.json: nobody to lift: 2 people with a mean joint score below 0.3 (0.10, 0.04)" in err
    assert "--min-score 0" in err
    code = main([*base, str(tmp_path / "junk.json"), "--out", str(tmp_path / "o3"), "--min-score", "0"])
    assert code == 0 and json.loads((tmp_path / "o3" / "junk.json").read_text())["num_people"] == 2
    # scores of another scale (a heatmap's, 0-5) are not read: that person is kept; the other is read (a review: one
    # score above 1 anywhere turned the floor off for the whole file)
    rec = lift_keypoint_file(results((real, 4.5), (big, 0.2), name="heat.json"), lifter=tiny_lifter(32),
                             image_size=(1280, 720))
    assert rec.num_people == 1 and [q.input_index for q in rec.people] == [0]
    # three people, one left out: the reader's "each is lifted" note now counts those lifted
    rec = lift_keypoint_file(results((real, 0.9), (big, 0.04), (real + [300.0, 0.0], 0.8), name="three.json"),
                             lifter=tiny_lifter(32), image_size=(1280, 720))
    assert sorted(q.input_index for q in rec.people) == [0, 2]
    assert any(w.startswith("2 of the 3 people in the file are lifted (largest first; 'input_index'")
               for w in rec.warnings), rec.warnings
    assert not any("3 people in the file; each is lifted" in w for w in rec.warnings)
    rec = lift_keypoint_file(tmp_path / "three.json", lifter=tiny_lifter(32), image_size=(1280, 720), max_people=1)
    assert any(w.startswith("2 people in the file scored at least 0.3; the largest is lifted") for w in rec.warnings)
    assert not any("are lifted" in w for w in rec.warnings), rec.warnings


def test_a_keypoint_sequences_low_scored_people_are_left_out_frame_by_frame(tmp_path, lifter, kp17):
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    junk = 1.2 * (kp17 - kp17[0]) + [900.0, 360.0]
    rows = lambda k, s: np.column_stack([k, np.full(17, s)]).tolist()  # noqa: E731
    frames = [{"people": [{"keypoints": rows(real + i, 0.9)}]
               + ([{"keypoints": rows(junk, 0.05)}] if i in (2, 3) else [])} for i in range(8)]
    path = tmp_path / "seq.json"
    path.write_text(json.dumps({"format": "h36m17", "fps": 10, "focal": 1000, "image_size": [1280, 720],
                                "frames": frames}))
    rec = lift_keypoint_sequence(path, lifter=lifter, smoothing=0.0)
    assert [len(f.people) for f in rec.frames] == [1] * 8 and len(rec.to_dict()["tracks"]) == 1
    assert any(w.startswith("in 2 frame(s) (2, 3), 2 people with a mean joint score below 0.3 (0.05, 0.05) left out")
               for w in rec.warnings), rec.warnings
    everyone = lift_keypoint_sequence(path, lifter=lifter, smoothing=0.0, min_score=0)
    assert [len(f.people) for f in everyone.frames] == [1, 1, 2, 2, 1, 1, 1, 1]
    # (a review) max_people counts the people kept, not those left out; a score above 1 in another frame leaves the
    # floor on for the rest
    frames[-1]["people"][0]["keypoints"][0][2] = 1.01
    path.write_text(json.dumps({"format": "h36m17", "fps": 10, "focal": 1000, "image_size": [1280, 720],
                                "frames": frames}))
    one = lift_keypoint_sequence(path, lifter=lifter, smoothing=0.0, max_people=1)
    assert [len(f.people) for f in one.frames] == [1] * 8 and not any("more than 1" in w for w in one.warnings)
    assert float(one.frames[2].people[0].keypoints_2d[:, 0].mean()) < 640.0  # (the real person, not the junk)
    path.write_text(json.dumps({"format": "h36m17", "fps": 10, "focal": 1000, "image_size": [1280, 720],
                                "frames": [{"people": [{"keypoints": rows(junk, 0.05)}]}] * 3}))
    with pytest.raises(PoseLifterError, match=r"seq\.json: no person in any frame; 3 people with a mean joint score "
                                              r"below 0\.3"):
        lift_keypoint_sequence(path, lifter=lifter, smoothing=0.0)


def test_a_track_missing_where_its_person_scored_below_the_floor_is_said_so(tmp_path, lifter, kp17):
    """A user's sequence whose one person scores 0.1 in frames 3 and 4: the track's gap note said "the person was not
    found there", where the person was found and left out below the score floor."""
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    rows = lambda k, s: np.column_stack([k, np.full(17, s)]).tolist()  # noqa: E731
    frames = [{"people": [{"keypoints": rows(real + i, 0.1 if i in (3, 4) else 0.9)}]} for i in range(8)]
    path = tmp_path / "dip.json"
    path.write_text(json.dumps({"format": "h36m17", "fps": 10, "focal": 1000, "image_size": [1280, 720],
                                "frames": frames}))
    rec = lift_keypoint_sequence(path, lifter=lifter, smoothing=0.0)
    gap = [w for w in rec.warnings if w.startswith("track 1: missing from 2 of the 8 frames")]
    assert len(gap) == 1 and "scored below the score floor was left out" in gap[0], rec.warnings
    assert "not found" not in gap[0], gap


class _JunkInFrames(ScriptedEstimator):
    """The scripted people, with a large detection scored 0.1 added in frames 3-5."""

    def __init__(self, script: list[list[np.ndarray]], junk: np.ndarray) -> None:
        super().__init__(script)
        self.junk = junk

    def detect(self, image: np.ndarray) -> list:
        i = self.n
        out = super().detect(image)
        if 3 <= i <= 5:
            out.append(Detection(keypoints=self.junk, scores=np.full(17, 0.1), bbox_xywh=bbox_of(self.junk),
                                 keypoint_format="h36m17"))
        return out


def _clip(path: Path, n: int, size: tuple[int, int] = (1280, 720)) -> Path:
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, size)
    assert vw.isOpened()
    for i in range(n):
        vw.write(np.full((size[1], size[0], 3), 40 + 5 * i, np.uint8))
    vw.release()
    return path


def test_a_videos_low_scored_detections_are_left_out(tmp_path, lifter, kp17):
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    junk = 1.2 * (kp17 - kp17[0]) + [900.0, 360.0]
    script = [[real + [i, 0.0]] for i in range(8)]
    clip = _clip(tmp_path / "c.avi", 8)
    rec = lift_video(clip, lifter=lifter, estimator=_JunkInFrames(script, junk), focal=1000.0, search_every_s=0)
    assert [len(f.people) for f in rec.frames] == [1] * 8 and len(rec.to_dict()["tracks"]) == 1
    assert any(w.startswith("in 3 frame(s) (3, 4, 5), 3 detections with a mean joint score below 0.3") for w in
               rec.warnings), rec.warnings
    rec = lift_video(clip, lifter=lifter, estimator=_JunkInFrames(script, junk), focal=1000.0, search_every_s=0,
                     min_score=0)
    assert max(len(f.people) for f in rec.frames) == 2


def _turned(kp: np.ndarray, centre: tuple[float, float]) -> np.ndarray:
    """``kp`` turned a quarter about ``centre`` (a photo turned 90 degrees)."""
    c = np.asarray(centre)
    d = kp - c
    return np.stack([-d[:, 1], d[:, 0]], -1) + c


def _standing() -> np.ndarray:
    """The shipped demo's standing person, ``(17, 2)`` px about a pelvis at (400, 360)."""
    demo = np.load(Path(__file__).resolve().parents[1] / "assets" / "demo" / "samples.npz")
    k = demo["keypoints_2d"][list(demo["names"]).index("standing")]
    return 0.8 * (k - k[0]) + [400.0, 360.0]


def test_a_detected_person_lying_sideways_is_named(photo, lifter):
    upright = _standing()
    side = _turned(upright, (400.0, 360.0))
    rec = lift_image(load_image(photo), lifter=lifter, estimator=_Scored([(side, 0.9)]), focal=1000.0)
    said = [w for w in rec.warnings if "sideways" in w]
    assert said and said[0].startswith("the person found lies sideways (head and ankles apart along the image's x): "
                                       "if the photo is turned a quarter (its EXIF orientation lost), turn it "
                                       "upright first"), rec.warnings
    rec = lift_image(load_image(photo), lifter=lifter, estimator=_Scored([(upright, 0.9)]), focal=1000.0)
    assert not any("sideways" in w for w in rec.warnings), rec.warnings
    both = np.stack([upright, side, side + [0.0, 100.0]])
    assert detected_sideways_notes(both)[0].startswith("people 2 and 3 of the output's people lie sideways")
    assert detected_sideways_notes(both, video=True)[0].startswith("most detected poses lie sideways in the frames "
                                                                   "(2 of 3)")
    assert detected_sideways_notes(both[:2], video=True) == []  # (one of two: not most)


def test_a_sideways_video_is_noted(tmp_path, lifter):
    side = _turned(_standing(), (400.0, 360.0))
    rec = lift_video(_clip(tmp_path / "s.avi", 4), lifter=lifter, estimator=ScriptedEstimator([[side]] * 4),
                     focal=1000.0)
    assert any(w.startswith("most detected poses lie sideways in the frames (4 of 4)") and "video is turned a "
               "quarter (its rotation not applied)" in w for w in rec.warnings), rec.warnings


def test_left_out_people_are_not_counted_in_num_people(photo, lifter, kp17):
    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    other = real + [500.0, 0.0]
    dets = detect_people(load_image(photo), estimator=_Scored([(real, 0.9), (other, 0.8), (real + 50.0, 0.1)]))
    assert [d.num_people for d in dets] == [2, 2]
    assert dets[0].warnings[-1].startswith("1 detection with a mean joint score below 0.3 (0.10)")
    assert not any("left out" in w for w in dets[1].warnings)  # (said once, on the first person)


def test_the_apps_keypoint_upload_leaves_out_low_scored_people(kp17):
    """(a review) The app read a keypoint file itself and showed the people poselifter lift leaves out."""
    pytest.importorskip("viser")
    from poselifter_app import upload as up

    real = 0.5 * (kp17 - kp17[0]) + [400.0, 360.0]
    big = 1.2 * (kp17 - kp17[0]) + [900.0, 360.0]
    doc = [{"image_id": 1, "category_id": 1, "keypoints": _coco_rows(k, v), "score": v} for k, v in ((real, 0.9),
                                                                                                     (big, 0.04))]
    doc_json = json.dumps({"format": "coco17", "image_size": [1280, 720], "people": [
        {"keypoints": np.reshape(d["keypoints"], (17, 3)).tolist()} for d in doc]}).encode()
    sample = up.keypoint_sample("res.json", doc_json, key="upload/t/res.json")
    assert sample.num_people == 1
    assert any("1 person with a mean joint score below 0.3 (0.04) left out" in w for w in sample.upload.warnings), \
        sample.upload.warnings
