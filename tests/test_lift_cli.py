"""``poselifter lift`` on keypoint JSON files and bad inputs, and the EXIF / image-loading logic.
None of these need mediapipe (images that would reach the detector are bad files, or the detector is
a stub)."""

from __future__ import annotations

import dataclasses
import io
import json
import math
import os
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import random_pose_cam, tiny_lifter

from lifter import Lifter, PoseLifterError, PoseLifterWarning
from lifter.camera import DEFAULT_DIAGONAL_FOV_DEG, project
from lifter.camera import focal_from_fov as default_focal
from lifter.checkpoint import save_checkpoint
from lifter.cli import main
from lifter.cli.lift import output_names
from lifter.detect import (
    Detection,
    ExifCamera,
    ImageError,
    bbox_of,
    detect_pose,
    focal_from_exif,
    image_from_array,
    load_image,
    register_estimator,
)
from lifter.io import parse_keypoint_json
from lifter.keypoints import COCO17_JOINT_NAMES, OPENPOSE25_JOINT_NAMES
from lifter.skeleton import JOINT_NAMES

Image = pytest.importorskip("PIL.Image")


@pytest.fixture(scope="module")
def weights(tmp_path_factory) -> Path:
    return _save_tiny(tmp_path_factory.mktemp("w") / "tiny.pt", 32)


@pytest.fixture()
def kp17() -> np.ndarray:
    return project(random_pose_cam(np.random.default_rng(0), 1)[0], focal=1000.0, principal_point=(640.0, 360.0))


def run(argv: list[str], capsys) -> tuple[int, str]:
    code = main(["lift", "--no-progress", *argv])
    return code, capsys.readouterr().err


def coco_from_h36m(kp: np.ndarray) -> np.ndarray:
    """A COCO-17 pose whose limb joints are the H36M ones; face joints near the head."""
    H = {n: i for i, n in enumerate(JOINT_NAMES)}
    face = {"nose": kp[H["neck_nose"]], "l_eye": kp[H["neck_nose"]] + [3, -4], "r_eye": kp[H["neck_nose"]] + [-3, -4],
            "l_ear": kp[H["head_top"]] + [8, 10], "r_ear": kp[H["head_top"]] + [-8, 10]}
    return np.stack([face[n] if n in face else kp[H[n]] for n in COCO17_JOINT_NAMES])


def test_h36m_order_given_as_coco17_is_said(tmp_path, weights, capsys):
    """A developer trial: H36M-order keypoints in a file that says "format": "coco17" were converted as COCO-17 and
    lifted scrambled (root at 55 % of its depth), the only note blaming the detector. The record now says what is
    likely wrong, naming the fix (a note, not a refusal: the file said coco17, and a large face beside a body seen in
    part can spread as far); a sequence too, and lifter.convert warns. COCO-17 keypoints of the same pose are not."""
    from lifter import convert, demo_sample
    from lifter.io import parse_keypoint_sequence

    s = demo_sample("walking")
    h36m, coco = s.keypoints_2d, coco_from_h36m(s.keypoints_2d)
    cam = {"image_size": list(s.image_size), "focal": float(np.ravel(s.focal)[0])}
    (tmp_path / "h.json").write_text(json.dumps({"keypoints": h36m.tolist(), "format": "coco17", **cam}))
    (tmp_path / "c.json").write_text(json.dumps({"keypoints": coco.tolist(), "format": "coco17", **cam}))
    code, err = run([str(tmp_path / "h.json"), str(tmp_path / "c.json"), "--out", str(tmp_path / "o"),
                     "--weights", str(weights)], capsys)
    said = ("format 'coco17', but the first five joints of the pose spread over 51 % or more of its 2D size, as "
            "H36M's pelvis, hips, right knee and right foot do")
    assert code == 0 and f"h.json: note: {said}" in err and "give \"format\": \"h36m17\" in the file" in err, err
    assert any(w.startswith(said) for w in json.loads((tmp_path / "o" / "h.json").read_text())["warnings"])
    assert not any("first five" in w for w in json.loads((tmp_path / "o" / "c.json").read_text())["warnings"])
    (tmp_path / "s.json").write_text(json.dumps({"frames": [h36m.tolist()] * 3, "fps": 25, "format": "coco17"}))
    seq = parse_keypoint_sequence(tmp_path / "s.json")
    assert any("first five joints of each of 3 poses spread over 51 % or more of their" in w for w in seq.warnings)
    with pytest.warns(PoseLifterWarning, match="format 'coco17', but the first five joints.*lift takes H36M-17 order"):
        convert(h36m, src="coco17")
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)
        convert(coco, src="coco17")


def test_image_size_option_for_keypoint_files_that_give_none(tmp_path, weights, kp17, capsys):
    """A developer trial: a list of people (MMPose's or COCO's results) cannot hold 'image_size', and the message
    named only that, or the full calibration. --image-size gives it (the principal point its centre, the focal
    length the --fov field of view of it), and replaces a file's own with a note; photos are refused it."""
    from lifter.camera import image_centre

    coco = coco_from_h36m(kp17)
    (tmp_path / "l.json").write_text(json.dumps([{"keypoints": coco.tolist(), "keypoint_scores": [0.9] * 17}]))
    code, err = run([str(tmp_path / "l.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 1 and "or the image's size, image_size= (--image-size W H)" in err, err
    code, err = run([str(tmp_path / "l.json"), "--out", str(tmp_path / "o"), "--weights", str(weights),
                     "--image-size", "1280", "720"], capsys)
    rec = json.loads((tmp_path / "o" / "l.json").read_text())
    want = default_focal((1280, 720))
    assert code == 0 and rec["image_size"] == [1280, 720] and rec["principal_point"] == list(image_centre((1280, 720)))
    assert rec["focal"] == pytest.approx([want, want], abs=0.01) and rec["focal_source"] == "default-fov", rec
    (tmp_path / "s.json").write_text(json.dumps({"keypoints": coco.tolist(), "format": "coco17",
                                                 "image_size": [640, 360]}))
    code, err = run([str(tmp_path / "s.json"), "--out", str(tmp_path / "o"), "--weights", str(weights),
                     "--image-size", "1280", "720"], capsys)
    rec = json.loads((tmp_path / "o" / "s.json").read_text())
    assert code == 0 and rec["image_size"] == [1280, 720]
    assert "the image size given (1280 x 720 px) replaces the file's own (640 x 360 px)" in rec["warnings"]
    (tmp_path / "p.png").write_bytes(b"not read")
    code, err = run([str(tmp_path / "p.png"), "--out", str(tmp_path / "o"), "--weights", str(weights),
                     "--image-size", "1280", "720"], capsys)
    # (a user trial: a photo in a batch with keypoint files failed for it; its own size is read, with a note)
    assert code == 1 and "p.png: note: --image-size is for keypoint files; a photo's own size is read from it" in err
    assert "error: " in err and "--image-size" not in err.split("error: ")[1], err  # (it fails for being no image)
    assert main(["lift", str(tmp_path / "l.json"), "--out", str(tmp_path / "o"), "--image-size", "0", "720"]) == 2
    assert "--image-size: image_size must be [width, height] in px" in capsys.readouterr().err


def test_a_rerun_into_the_same_folder_leaves_no_stale_outputs(tmp_path, weights, kp17, capsys):
    """A developer trial: a photo lifted again with --max-people 1 into the same --out rewrote pair.json for one
    person but left pair_person2.bvh and the two-person pair.glb of the run before, without a word (a video's
    <name>_track<ID>.bvh the same). The earlier files of a kind written again are removed; those of a kind not asked
    for are left, and said; another input's own result is never touched."""
    two = {"people": [{"keypoints": kp17.tolist()}, {"keypoints": (kp17 * 0.8 + [300, 40]).tolist()}],
           "format": "h36m17", "image_size": [1280, 720], "focal": 1000.0}
    (tmp_path / "pair.json").write_text(json.dumps(two))
    out = tmp_path / "o"
    code, err = run([str(tmp_path / "pair.json"), "--out", str(out), "--weights", str(weights), "--bvh", "--glb"],
                    capsys)
    assert code == 0 and {f.name for f in out.iterdir()} == {"pair.json", "pair.glb", "pair.bvh", "pair_person2.bvh"}
    (out / "pair_track7.bvh").write_text("an earlier video's track")
    (out / "pair_person3.json").write_text("{}")  # another input's result, with its own BVH
    (out / "pair_person3.bvh").write_text("another input's")
    code, err = run([str(tmp_path / "pair.json"), "--out", str(out), "--weights", str(weights), "--bvh",
                     "--max-people", "1"], capsys)
    assert code == 0 and len(json.loads((out / "pair.json").read_text())["people"]) == 1
    assert {f.name for f in out.iterdir()} == {"pair.json", "pair.glb", "pair.bvh", "pair_person3.json",
                                               "pair_person3.bvh", "pair_track7.bvh"}  # (not a photo's kind)
    assert f"pair.json: note: removed pair_person2.bvh from {out}: an earlier run's, which this result " \
           "replaces" in err, err
    assert f"pair.json: note: pair.glb in {out} is an earlier run's, left as it was: it may not match this " \
           "result (pair.json)" in err
    code, err = run([str(tmp_path / "pair.json"), "--out", str(out), "--weights", str(weights), "--glb"], capsys)
    assert code == 0 and "removed" not in err and (out / "pair.glb").exists() and (out / "pair.bvh").exists()
    # (a review) another input's earlier result of the same name, and the files beside it, are never touched
    (out / "pair.json").write_text(json.dumps({"input": str(tmp_path / "elsewhere" / "pair.png")}))
    (out / "pair_person2.bvh").write_text("the other input's second person")
    code, err = run([str(tmp_path / "pair.json"), "--out", str(out), "--weights", str(weights), "--bvh",
                     "--max-people", "1"], capsys)
    assert code == 0 and (out / "pair_person2.bvh").read_text() == "the other input's second person"
    assert "removed" not in err and "the result of another input" in err, err
    # a video's: only its own kind (a review: the user's walk.bvh beside walk.mp4 was removed)
    from lifter.cli.lift import tidy_earlier_outputs

    v = tmp_path / "v"
    v.mkdir()
    for f in ("walk.json", "walk.bvh", "walk_track1.bvh", "walk_track2.bvh", "walk_person2.bvh", "walking.glb"):
        (v / f).write_text("x")
    notes = tidy_earlier_outputs(v, "walk", {v / "walk.json", v / "walk_track1.bvh"}, glb=True, bvh=True,
                                 sequence=True)
    assert sorted(f.name for f in v.iterdir()) == ["walk.bvh", "walk.json", "walk_person2.bvh", "walk_track1.bvh",
                                                   "walking.glb"]
    assert notes == [f"removed walk_track2.bvh from {v}: an earlier run's, which this result replaces"]


def test_keypoint_json_inputs(tmp_path, weights, kp17, capsys):
    d = tmp_path / "in"
    d.mkdir()
    (d / "a.json").write_text(json.dumps({"keypoints": kp17.tolist(), "image_size": [1280, 720], "focal": 1000}))
    (d / "b.json").write_text(json.dumps({"keypoints": coco_from_h36m(kp17).tolist(), "format": "coco17",
                                          "image_size": [1280, 720]}))
    # OpenPose output with two people: the larger one is used
    op = np.zeros((25, 3))
    for i, n in enumerate(OPENPOSE25_JOINT_NAMES):
        op[i, :2] = kp17[JOINT_NAMES.index(n)] if n in JOINT_NAMES else kp17[0] + [i, -i]
        op[i, 2] = 0.9
    small = op.copy()
    small[:, :2] = 0.3 * (small[:, :2] - small[0, :2]) + [100, 100]
    (d / "notes.txt").write_text("ignored")
    out = tmp_path / "out"
    code, err = run([str(d), "--out", str(out), "--principal-point", "640", "360", "--glb", "--bvh",
                     "--weights", str(weights)], capsys)
    assert code == 0, err
    assert "lifted 2 of 2" in err
    assert sorted(p.name for p in out.iterdir()) == ["a.bvh", "a.glb", "a.json", "b.bvh", "b.glb", "b.json"]
    # OpenPose's output has no image size: it needs --focal (and --principal-point)
    (tmp_path / "c.json").write_text(json.dumps({"people": [{"pose_keypoints_2d": small.ravel().tolist(),
                                                             "person_id": "kid"},
                                                            {"pose_keypoints_2d": op.ravel().tolist(), "id": 7}]}))
    code, err = run([str(tmp_path / "c.json"), "--out", str(out), "--principal-point", "640", "360",
                     "--weights", str(weights)], capsys)
    assert code == 1 and "no focal length and no image size" in err
    code, err = run([str(tmp_path / "c.json"), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 1 and ("no focal length and no principal point and no image size: pass focal= (--focal) and "
                          "principal_point= (--principal-point), or the image's size, image_size= (--image-size W "
                          "H), or put 'image_size' (or 'focal' and "
                          "'principal_point') in the file") in err
    code, err = run([str(tmp_path / "c.json"), "--out", str(out), "--principal-point", "640", "360", "--focal", "1000",
                     "--weights", str(weights)], capsys)
    assert code == 0 and "2 people in the file; each is lifted (largest first; 'input_index'" in err
    c = json.loads((out / "c.json").read_text())
    assert c["num_people"] == 2 and len(c["people"]) == 2
    assert c["people"][0]["absolute"] == c["absolute"] and c["people"][0]["keypoints_2d"] == c["keypoints_2d"]
    spans = [np.ptp(np.array(q["keypoints_2d"]), axis=0).prod() for q in c["people"]]
    assert spans[0] > spans[1]  # largest first
    # who is who: each person's position in the file and their own id field are kept
    assert [(q["input_index"], q["person_id"]) for q in c["people"]] == [(1, 7), (0, "kid")]
    # both lifted in one camera space: each root projects back onto its own 2D pelvis
    for q in c["people"]:
        np.testing.assert_allclose(project(np.array(q["root"])[None], focal=1000.0, principal_point=(640, 360))[0],
                                   q["keypoints_2d"][0], atol=0.05)
    a = json.loads((out / "a.json").read_text())
    assert np.array(a["keypoints_2d"]).shape == (17, 2) and np.array(a["absolute"]).shape == (17, 3)
    assert np.array(a["root"]).shape == (3,) and a["focal"] == [1000.0, 1000.0] and a["focal_source"] == "keypoint-file"
    assert a["principal_point"] == [640.0, 360.0] and a["joint_names"] == list(JOINT_NAMES)
    np.testing.assert_allclose(a["keypoints_2d"], kp17, atol=0.01)
    np.testing.assert_allclose(np.array(a["absolute"])[0], a["root"], atol=0.02)
    # the root projects back onto the 2D pelvis (Eq. 6)
    np.testing.assert_allclose(project(np.array(a["root"])[None], focal=1000.0, principal_point=(640, 360))[0],
                               kp17[0], atol=0.05)
    b = json.loads((out / "b.json").read_text())
    assert b["source_format"] == "coco17" and b["focal_source"] == "default-fov"
    assert b["focal"][0] == pytest.approx(default_focal((1280, 720)), abs=0.01)
    c = json.loads((out / "c.json").read_text())
    assert c["source_format"] == "openpose25"
    assert np.ptp(np.array(c["keypoints_2d"])[:, 1]) > 0.9 * np.ptp(kp17[:, 1])  # the large person
    from lifter.export import read_bvh, read_glb_joints

    np.testing.assert_allclose(read_bvh(out / "a.bvh"), a["absolute"], atol=0.05)
    np.testing.assert_allclose(read_glb_joints(out / "a.glb"), a["absolute"], atol=0.1)


def test_cli_matches_api(tmp_path, weights, kp17, capsys):
    (tmp_path / "k.json").write_text(json.dumps(kp17.tolist()))
    code, err = run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o"), "--focal", "900", "950",
                     "--principal-point", "600", "300", "--weights", str(weights)], capsys)
    assert code == 0, err
    assert "assumed H36M order" in err
    got = json.loads((tmp_path / "o" / "k.json").read_text())
    ref = Lifter.from_checkpoint(weights).lift(kp17, focal=(900, 950), principal_point=(600, 300))
    np.testing.assert_allclose(got["absolute"], ref.absolute, atol=0.01)
    assert got["canonical_depth"] == pytest.approx(float(ref.canonical_depth), abs=0.01)
    assert got["focal"] == [900.0, 950.0] and got["focal_source"] == "user"
    # -o is --out (a user trial typed -o and was told --out was missing)
    code, err = run([str(tmp_path / "k.json"), "-o", str(tmp_path / "o2"), "--focal", "900", "950",
                     "--principal-point", "600", "300", "--weights", str(weights)], capsys)
    assert code == 0, err
    assert json.loads((tmp_path / "o2" / "k.json").read_text())["absolute"] == got["absolute"]


def test_threads_sets_the_lifts_torch_threads_and_bad_counts_are_refused(tmp_path, weights, kp17, capsys,
                                                                         monkeypatch):
    import torch

    monkeypatch.setattr(torch, "set_num_threads", lambda n: seen.append(n))
    seen: list[int] = []
    (tmp_path / "k.json").write_text(json.dumps(kp17.tolist()))
    code, err = run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o"), "--threads", "1", "--focal", "900",
                     "--principal-point", "600", "300", "--weights", str(weights)], capsys)
    assert code == 0 and seen == [1], err
    with pytest.raises(SystemExit):
        main(["lift", str(tmp_path / "k.json"), "--out", str(tmp_path / "o2"), "--threads", "0"])
    assert "--threads" in capsys.readouterr().err and not (tmp_path / "o2").exists()


def test_format_taken_from_the_joint_count_is_said(tmp_path, weights, kp17, capsys):
    """A keypoint file without 'format' is read by its joint count, and the output's warnings say so."""
    (tmp_path / "k16.json").write_text(json.dumps(kp17[:16].tolist()))
    code, err = run([str(tmp_path / "k16.json"), "--out", str(tmp_path / "o"), "--focal", "900",
                     "--principal-point", "600", "300", "--weights", str(weights)], capsys)
    assert code == 0, err
    got = json.loads((tmp_path / "o" / "k16.json").read_text())
    assert got["source_format"] == "sh16"
    assert any("16 joints without 'format': assumed 'sh16'" in w for w in got["warnings"]), got["warnings"]


def test_coco_keypoints_without_format_are_refused_not_lifted_as_h36m(tmp_path, weights, capsys):
    """User trial: a COCO-17 file without 'format' was lifted in H36M order with exit 0 (root 2.0 m where the same
    file told coco17 gives 4.9 m; only the note every unnamed 17-joint file gets). Its first five points (nose, eyes,
    ears) lie together, where H36M's (pelvis, hips, right knee and foot) span the legs: refused, naming the fix;
    --format h36m17 or coco17 decides; a real H36M pose without 'format' is still read as H36M."""
    rng = np.random.default_rng(3)
    h36m = [project(p, focal=1000.0, principal_point=(640.0, 360.0)) for p in random_pose_cam(rng, 40)]
    coco = [coco_from_h36m(k) for k in h36m]
    for c in coco:  # the ears beside the eyes, as a face's are (coco_from_h36m puts them at the head's top)
        c[3:5] = c[0] + np.array([[10.0, -2.0], [-10.0, -2.0]])
    (tmp_path / "coco.json").write_text(json.dumps({"people": [{"keypoints": coco[0].tolist()},
                                                               {"keypoints": coco[1].tolist()}], "focal": 1000}))
    common = ["--out", str(tmp_path / "o"), "--principal-point", "640", "360", "--weights", str(weights)]
    code, err = run([str(tmp_path / "coco.json"), *common], capsys)
    assert code == 1 and "17 joints without 'format', and each person's first five lie within 12 %" in err, err
    assert "give \"format\": \"coco17\" in the file, or --format coco17" in err and "Traceback" not in err
    assert "--format coco17 with poselifter lift (--format h36m17" in err  # (a browser trial: "on the command line")
    code, err = run([str(tmp_path / "coco.json"), *common, "--format", "coco17"], capsys)
    assert code == 0, err
    assert json.loads((tmp_path / "o" / "coco.json").read_text())["source_format"] == "coco17"
    code, err = run([str(tmp_path / "coco.json"), *common, "--format", "h36m17"], capsys)
    assert code == 0, err  # (the user's word wins)
    for k, kp in enumerate(h36m):  # H36M poses of every kind are not taken for faces
        (tmp_path / f"h{k}.json").write_text(json.dumps({"keypoints": kp.tolist(), "focal": 1000}))
    code, err = run([str(tmp_path / f"h{k}.json") for k in range(len(h36m))] + common, capsys)
    assert code == 0, err


def test_a_focal_given_over_the_file_s_own_is_said(tmp_path, weights, kp17, capsys):
    """--focal / --principal-point win over the file's camera fields, and the output's warnings say so."""
    doc = {"keypoints": kp17.tolist(), "format": "h36m17", "focal": 800, "principal_point": [640, 360]}
    (tmp_path / "k.json").write_text(json.dumps(doc))
    code, err = run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o"), "--focal", "1600",
                     "--principal-point", "600", "300", "--weights", str(weights)], capsys)
    assert code == 0, err
    got = json.loads((tmp_path / "o" / "k.json").read_text())
    assert got["focal"] == [1600.0, 1600.0] and got["focal_source"] == "user"
    assert any("(1600 x 1600 px) replaces the file's own (800 x 800 px)" in w for w in got["warnings"]), got
    assert any("the principal point given, (600, 300) px, replaces the file's own, (640, 360) px" in w
               for w in got["warnings"]), got  # (a point, not "(600 x 300 px)": a developer trial read it as a size)
    # the same values as the file's: nothing to say
    run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o2"), "--focal", "800", "--weights", str(weights)], capsys)
    assert not any("replaces" in w for w in json.loads((tmp_path / "o2" / "k.json").read_text())["warnings"])


def test_a_result_file_can_be_lifted_again(tmp_path, weights, kp17, capsys):
    """poselifter lift's own output is a keypoint file: everyone's 2D (H36M order), its camera and source."""
    doc = {"people": [{"keypoints": kp17.tolist()}, {"keypoints": (kp17 * 0.5 + 100).tolist()}], "format": "h36m17",
           "focal": [900, 950], "principal_point": [600, 300], "source": "clean"}
    (tmp_path / "k.json").write_text(json.dumps(doc))
    assert run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)[0] == 0
    first = json.loads((tmp_path / "o" / "k.json").read_text())
    code, err = run([str(tmp_path / "o" / "k.json"), "--out", str(tmp_path / "o2"), "--weights", str(weights)],
                    capsys)
    assert code == 0, err
    again = json.loads((tmp_path / "o2" / "k.json").read_text())
    assert again["num_people"] == 2 and again["source"] == "clean" and again["focal"] == [900.0, 950.0]
    # the same lift (the written 2D is rounded to 0.01 px)
    np.testing.assert_allclose(again["absolute"], first["absolute"], atol=0.2)
    np.testing.assert_allclose(again["people"][1]["absolute"], first["people"][1]["absolute"], atol=0.2)
    assert first["metric_depth"] is True and again["focal_source"] == "keypoint-file"
    assert first["frame"].endswith("2D in px of the image the keypoints belong to")  # (no image was read)
    assert any(w.startswith("2 people in the file; each is lifted") for w in first["warnings"])
    # (a user trial) with --max-people 1, only the cut is said, not also that each is lifted
    assert run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o3"), "--max-people", "1", "--weights",
                str(weights)], capsys)[0] == 0
    cut = json.loads((tmp_path / "o3" / "k.json").read_text())
    assert len(cut["people"]) == 1 and "2 people in the file; the largest is lifted (max_people)" in cut["warnings"]
    assert not any("each is lifted" in w for w in cut["warnings"]), cut["warnings"]


def test_a_result_file_lifted_again_keeps_its_scores(tmp_path, weights, kp17, capsys):
    """A user trial: a result's detector scores (and so its notes on unsure joints) were lost when the result was
    lifted again. They are read back with the 2D; a score written as 0 (rounded) is a low score, not a missing
    joint (every joint of a result was lifted)."""
    conf = np.full(17, 0.9)
    conf[[13, 16]] = [0.12, 0.0004]  # l_wrist unsure; r_wrist written as 0.0
    doc = {"people": [{"keypoints": np.column_stack([kp17, conf]).tolist()}], "format": "h36m17", "focal": 900,
           "principal_point": [600, 300]}
    (tmp_path / "k.json").write_text(json.dumps(doc))
    assert run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)[0] == 0
    first = json.loads((tmp_path / "o" / "k.json").read_text())
    assert first["scores"][13] == 0.12 and first["scores"][16] == 0.0
    assert run([str(tmp_path / "o" / "k.json"), "--out", str(tmp_path / "o2"), "--weights", str(weights)],
               capsys)[0] == 0
    again = json.loads((tmp_path / "o2" / "k.json").read_text())
    assert again["scores"] == first["scores"] and again["people"][0]["scores"] == first["scores"]
    unsure = [w for w in again["warnings"] if "unsure of some joints" in w]
    assert unsure and "l_wrist (0.12)" in unsure[0] and "r_wrist (0.00)" in unsure[0], again["warnings"]
    np.testing.assert_allclose(again["absolute"], first["absolute"], atol=0.2)  # (no joint read as missing)


def test_an_assumed_focal_stays_assumed_when_a_result_is_read_back(tmp_path, weights, kp17, capsys):
    """User trial: a result written with an assumed focal (focal_source "default-fov"), read back, came out as
    focal_source "keypoint-file" with no note: a guess turned into a known focal. It is now assumed again, with a
    note, and the output says whether its depths are metric."""
    _kp_json(tmp_path / "k.json", kp17)  # image_size, no focal
    assert run([str(tmp_path / "k.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)[0] == 0
    first = json.loads((tmp_path / "o" / "k.json").read_text())
    assert first["focal_source"] == "default-fov" and first["metric_depth"] is False
    code, err = run([str(tmp_path / "o" / "k.json"), "--out", str(tmp_path / "o2"), "--weights", str(weights),
                     "--fov", "50"], capsys)
    assert code == 0, err
    again = json.loads((tmp_path / "o2" / "k.json").read_text())
    assert again["focal_source"] == "default-fov" and again["metric_depth"] is False
    # assumed again, with this --fov
    assert again["focal"][0] == pytest.approx(default_focal((1280, 720), fov_deg=50.0), abs=0.01)
    assert "was assumed when it was written (focal_source 'default-fov'), not known" in err
    code, err = run([str(tmp_path / "o" / "k.json"), "--out", str(tmp_path / "o3"), "--weights", str(weights),
                     "--focal", "1000"], capsys)  # a focal given: used, and no word of assuming one
    assert code == 0 and "assumed when it was written" not in err, err
    assert json.loads((tmp_path / "o3" / "k.json").read_text())["focal_source"] == "user"
    # a sequence result likewise (the review: only single frames were)
    seq = tmp_path / "seq.json"
    seq.write_text(json.dumps({"fps": 25, "image_size": [1280, 720], "frames": [{"people": [
        _openpose_person(kp17 + [2.0 * i, 0.0])]} for i in range(6)]}))
    assert run([str(seq), "--out", str(tmp_path / "s1"), "--weights", str(weights)], capsys)[0] == 0
    written = json.loads((tmp_path / "s1" / "seq.json").read_text())
    assert written["focal_source"] == "default-fov" and written["metric_depth"] is False
    code, err = run([str(tmp_path / "s1" / "seq.json"), "--out", str(tmp_path / "s2"), "--weights", str(weights)],
                    capsys)
    assert code == 0 and "was assumed when it was written" in err, err
    again = json.loads((tmp_path / "s2" / "seq.json").read_text())
    assert again["focal_source"] == "default-fov" and again["metric_depth"] is False


def _jpeg_bytes(size=(64, 48)) -> bytes:
    buf = io.BytesIO()
    Image.new("RGB", size, (120, 130, 140)).save(buf, format="JPEG")
    return buf.getvalue()


def test_bad_inputs_do_not_stop_the_batch(tmp_path, weights, kp17, capsys):
    d = tmp_path / "in"
    d.mkdir()
    (d / "good.json").write_text(json.dumps({"keypoints": kp17.tolist(), "image_size": [1280, 720]}))
    (d / "broken.json").write_text("{not json")
    (d / "wrongcount.json").write_text(json.dumps({"keypoints": [[1, 2]] * 12}))
    (d / "nan.json").write_text(json.dumps({"keypoints": [[1, 2]] * 16 + [[float("nan"), 3]], "image_size": [9, 9]}))
    (d / "nosize.json").write_text(json.dumps({"keypoints": kp17.tolist()}))
    (d / "text.jpg").write_text("this is not an image")
    (d / "empty.png").write_bytes(b"")
    (d / "truncated.jpg").write_bytes(_jpeg_bytes()[:300])
    out = tmp_path / "out"
    code, err = run([str(d), str(tmp_path / "missing.png"), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 0, err
    assert (out / "good.json").is_file() and len(list(out.iterdir())) == 1
    for frag in ("broken.json: not valid JSON", "wrongcount.json: 12 joints", "nan.json: joint(s)",
                 "nosize.json: no focal length and no principal point and no image size", "text.jpg: not an image",
                 "empty.png: empty file",
                 "truncated.jpg: unreadable or truncated", "missing.png: no such file", "lifted 1 of 9"):
        assert frag in err, (frag, err)


def test_exit_code_when_all_fail(tmp_path, weights, capsys):
    (tmp_path / "x.jpg").write_text("nope")
    code, err = run([str(tmp_path / "x.jpg"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 1 and "lifted 0 of 1" in err
    code, err = run([str(tmp_path / "nothing_here"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 1
    code, err = run([str(tmp_path / "x.jpg"), "--out", str(tmp_path / "o"), "--focal", "1", "2", "3",
                     "--weights", str(weights)], capsys)
    assert code == 2 and "--focal takes" in err


def test_a_file_of_the_users_in_out_is_not_replaced(tmp_path, weights, kp17, capsys):
    """A review: keypoints ``photo.json`` kept beside ``photo.jpg`` and lifted with ``--out`` that folder were
    replaced by the result of another input of that name, with exit 0 and no note. A JSON in the output folder that
    is not a poselifter result is the user's: left as it is, the result named otherwise, and said."""
    (tmp_path / "src").mkdir()
    src = _kp_json(tmp_path / "src" / "photo.json", kp17)
    mine = tmp_path / "o" / "photo.json"
    mine.parent.mkdir()
    mine.write_text('{"keypoints": "mine"}')
    code, err = run([str(src), "--out", str(mine.parent), "--weights", str(weights)], capsys)
    assert code == 0 and "lifted 1 of 1" in err
    assert mine.read_text() == '{"keypoints": "mine"}'
    assert f"its results are named photo_json.* (photo.json in {mine.parent} is not a poselifter result" in err
    assert json.loads((mine.parent / "photo_json.json").read_text())["units"]
    # a result of an earlier run is replaced, as before (the same input's: no new name)
    code, err = run([str(src), "--out", str(tmp_path / "p"), "--weights", str(weights)], capsys)
    code, err = run([str(src), "--out", str(tmp_path / "p"), "--weights", str(weights)], capsys)
    assert code == 0 and "its results are named" not in err and (tmp_path / "p" / "photo.json").is_file()


def test_an_output_that_cannot_be_written_leaves_the_json_of_before(tmp_path, weights, kp17, capsys):
    """A review: a run whose BVH could not be written replaced the JSON first, so the folder held a JSON at one focal
    length and a BVH at another, and the error did not say which files were new. The JSON is written last."""
    src = _kp_json(tmp_path / "k.json", kp17)
    out = tmp_path / "o"
    code, err = run([str(src), "--out", str(out), "--glb", "--bvh", "--weights", str(weights)], capsys)
    assert code == 0
    before = (out / "k.json").read_text()
    (out / "k.bvh").unlink()
    (out / "k.bvh").symlink_to(tmp_path / "elsewhere.bvh")  # (write_atomic refuses to write through a link)
    code, err = run([str(src), "--out", str(out), "--glb", "--bvh", "--focal", "700", "--weights", str(weights)],
                    capsys)
    assert code == 1 and "lifted 0 of 1" in err and "symbolic link" in err
    assert (out / "k.json").read_text() == before
    assert (f"{src}: note: k.glb was written before the error; its JSON result, written last, was not (any in the "
            "output folder is from before)") in err


def test_strict_exit_code_when_any_input_fails(tmp_path, weights, kp17, capsys):
    """A developer trial: a batch where 4 of 7 inputs failed exited 0, as documented; a pipeline had no way to ask
    for all or nothing. --strict exits 1 when any input fails, and still writes what could be lifted."""
    (tmp_path / "x.jpg").write_text("nope")
    good = _kp_json(tmp_path / "k.json", kp17, image_size=[1280, 720])
    both = [str(good), str(tmp_path / "x.jpg"), "--weights", str(weights)]
    code, err = run([*both, "--out", str(tmp_path / "a")], capsys)
    assert code == 0 and "lifted 1 of 2" in err and "--strict" not in err
    code, err = run([*both, "--out", str(tmp_path / "b"), "--strict"], capsys)
    assert code == 1 and "lifted 1 of 2 input(s) into" in err and err.rstrip().endswith("exit code 1 (--strict)")
    assert (tmp_path / "b" / "k.json").is_file()
    code, err = run([str(good), str(tmp_path / "missing.json"), "--weights", str(weights), "--out",
                     str(tmp_path / "c"), "--strict"], capsys)
    assert code == 1 and "missing.json: no such file" in err  # (an input not found counts as failed)
    code, err = run([str(good), "--weights", str(weights), "--out", str(tmp_path / "d"), "--strict"], capsys)
    assert code == 0 and "lifted 1 of 1" in err


def test_output_names(tmp_path):
    """Two inputs named alike get names that tell them apart (the folder, else the suffix), each said in a note;
    an input's own JSON is never overwritten."""
    files = [tmp_path / "a.png", tmp_path / "sub" / "a.png", tmp_path / "a.json", tmp_path / "b.json",
             tmp_path / "sub" / "b.json"]
    names, notes = output_names(files, tmp_path / "out")
    assert names == ["a", "sub_a", "a_json", "b", "sub_b"]
    assert notes[0] == f"{tmp_path / 'sub' / 'a.png'}: its results are named sub_a.* ({tmp_path / 'a.png'} is also " \
                       "named a)" and len(notes) == 3
    from lifter.cli.lift import expand_inputs

    (tmp_path / "b.json").write_text("{}")
    got, problems, notes = expand_inputs([tmp_path / "b.json", tmp_path / "." / "b.json", tmp_path])
    assert got == [tmp_path / "b.json"] and not problems
    said = [n for n in notes if "given more than once" in n]  # (each name once: a user trial read "x, x")
    assert said == [f"1 input(s) given more than once (2 repeat(s)), each lifted once: {tmp_path / 'b.json'}"], notes
    # never overwrite an input keypoint file
    assert output_names([tmp_path / "b.json"], tmp_path) == (["b_json"], [
        f"{tmp_path / 'b.json'}: its results are named b_json.* (b.json in {tmp_path} is an input)"])


def test_parse_formats(tmp_path):
    p = tmp_path / "f.json"
    xy = np.arange(34.0).reshape(17, 2) * 10
    xy[1:5] = xy[0] + [[-3, -2], [3, -2], [-7, 0], [7, 0]]  # (a face first, as COCO-17's)
    p.write_text(json.dumps([{"keypoints": np.c_[xy, np.ones(17)].ravel().tolist()}]))
    kf = parse_keypoint_json(p)
    assert kf.format == "coco17" and kf.keypoints.shape == (17, 2)
    p.write_text(json.dumps({"keypoints": [[0, 0]] * 17, "format": "nope"}))
    with pytest.raises(PoseLifterError, match="unknown keypoint format"):
        parse_keypoint_json(p)
    for empty in ("", "  \n"):
        p.write_text(empty)
        with pytest.raises(PoseLifterError, match="the file is empty"):
            parse_keypoint_json(p)
    # absurd coordinates: no numpy overflow warning on the way to the message that names them
    p.write_text(json.dumps({"people": [{"keypoints": [[1e300 * (i % 3 + 1), -1e300] for i in range(17)]},
                                       {"keypoints": [[1e300, 1e300 * (i % 2 + 1)] for i in range(17)]}]}))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        parse_keypoint_json(p)
    # a joint count no format has: the message lists the counts, not only the names
    p.write_text(json.dumps({"keypoints": [[10.0 * i, 5.0 * i] for i in range(15)]}))
    with pytest.raises(PoseLifterError, match=r"15 joints per person, which no known keypoint format has") as exc:
        parse_keypoint_json(p)
    assert "17 (h36m17)" in str(exc.value) and "16 (sh16)" in str(exc.value)


# ------------------------------------------------------------------------------------------------
# EXIF focal length and image loading
# ------------------------------------------------------------------------------------------------


def test_focal_rules():
    size = (4000, 3000)
    # focal mm + focal-plane resolution (px per cm): sensor 4000 px / 800 px/cm = 5 mm wide
    g = focal_from_exif(ExifCamera(focal_mm=4.0, focal_plane_xres=8000.0, focal_plane_unit_mm=10.0, pixel_x=4000,
                                   pixel_y=3000), size)
    assert g.source == "exif-focal-plane" and g.focal == pytest.approx(4.0 * 800.0)
    # the same photo resized to half: the focal in px halves
    g2 = focal_from_exif(ExifCamera(focal_mm=4.0, focal_plane_xres=8000.0, focal_plane_unit_mm=10.0, pixel_x=4000,
                                    pixel_y=3000), (2000, 1500))
    assert g2.focal == pytest.approx(1600.0)
    # user-given sensor width wins; portrait images use the long side
    g3 = focal_from_exif(ExifCamera(focal_mm=4.0), (3000, 4000), sensor_width_mm=5.0)
    assert g3.source == "exif-sensor-width" and g3.focal == pytest.approx(3200.0)
    # 35 mm equivalent on the diagonal
    g4 = focal_from_exif(ExifCamera(focal_mm=4.0, focal_35mm=26.0), size)
    assert g4.source == "exif-35mm" and g4.focal == pytest.approx(26.0 * 5000.0 / math.hypot(36, 24))
    # nothing usable: the stated default field of view
    g5 = focal_from_exif(ExifCamera(), size)
    assert g5.source == "default-fov" and "65 deg" in g5.detail
    assert 2 * math.degrees(math.atan(5000 / 2 / g5.focal)) == pytest.approx(DEFAULT_DIAGONAL_FOV_DEG)
    # implausible focal-plane data (sensor 0.04 mm) is ignored
    g6 = focal_from_exif(ExifCamera(focal_mm=4.0, focal_plane_xres=1e6, focal_plane_unit_mm=10.0), size)
    assert g6.source == "default-fov" and "--sensor-width" in g6.detail
    with pytest.raises(PoseLifterError, match="field of view"):
        default_focal(size, fov_deg=190)


def test_an_exif_focal_gets_the_field_of_view_check_and_is_not_called_assumed():
    """A developer trial: an EXIF focal of 114 px for a 1000-px photo (162 deg of view) got no field-of-view note,
    which --focal 114 gets, and the note on the pose's wide view said the focal was "assumed, not given"."""
    from lifter import demo_sample
    from lifter.pipeline import plausibility_notes, resolve_camera

    exif = ExifCamera(focal_mm=8.0, focal_plane_xres=1000.0 / 7.0, focal_plane_unit_mm=10.0, pixel_x=1000, pixel_y=1000)
    f, src, _, notes = resolve_camera(user_focal=None, user_pp=None, file_focal=None, file_pp=None,
                                      image_size=(1000, 1000), exif=exif, sensor_width_mm=None,
                                      fov_deg=DEFAULT_DIAGONAL_FOV_DEG, where="x.jpg")
    assert src == "exif-focal-plane" and f[0] == pytest.approx(114.2857, rel=1e-4)
    assert any(n.startswith("the EXIF's focal length 114.286 px gives this 1000 x 1000 px image a field of view of "
                            "162 deg") and "the photo's EXIF is probably wrong" in n for n in notes), notes
    kp = np.asarray(demo_sample("walking").keypoints_2d)  # (a pose spanning more than 120 deg at half that focal)
    wide = [n for n in plausibility_notes(kp, f / 2, (1000, 1000), focal_source=src) if "deg of view" in n]
    assert len(wide) == 1 and "the focal length was read from the photo's EXIF, not given" in wide[0], wide
    assert "assumed" not in wide[0]
    # the field of view assumed is not checked (it is the default's own), a focal given is, as before
    _, _, _, given = resolve_camera(user_focal=np.array([114.2857, 114.2857]), user_pp=None, file_focal=None,
                                    file_pp=None, image_size=(1000, 1000), exif=None, sensor_width_mm=None,
                                    fov_deg=DEFAULT_DIAGONAL_FOV_DEG, where="x.jpg")
    assert any(n.startswith("the focal length 114.286 px gives") and "is it in mm, not px" in n for n in given)


def test_strict_exit_code_for_a_result_its_notes_call_not_valid(tmp_path, weights, kp17, capsys):
    """A developer trial: --strict exited 0 for a root behind the camera ("the result is not a valid pose") and for a
    focal length in mm (35 px: the person 0.25 m away). Such a result is still written, says why it is not valid,
    and with --strict the exit code is 1."""
    from lifter.cli.lift import not_valid_reasons
    from lifter.pipeline import lift_keypoint_file

    good = _kp_json(tmp_path / "good.json", kp17, focal=1000.0)
    mm = _kp_json(tmp_path / "mm.json", kp17, focal=26.0)
    square = _kp_json(tmp_path / "fxfy.json", kp17, focal=[1000.0, 10000.0])
    code, err = run([str(good), "--weights", str(weights), "--out", str(tmp_path / "a"), "--strict"], capsys)
    assert code == 0 and "not valid" not in err
    for path, why in ((mm, "a focal length (26 px) that gives the image a field of view no pinhole lens has"),
                      (square, "a focal length whose fx / fy is 0.1, beyond the 1.25 of real cameras")):
        code, err = run([str(path), "--weights", str(weights), "--out", str(tmp_path / "b")], capsys)
        assert code == 0 and f"{path}: note: the result is not valid: {why} (--strict makes it exit code 1)" in err
        assert "1 of the 1 lifted with a result that is not valid" in err
        code, err = run([str(good), str(path), "--weights", str(weights), "--out", str(tmp_path / "c"), "--strict"],
                        capsys)
        assert code == 1 and err.rstrip().endswith("exit code 1 (--strict)"), err
        assert (tmp_path / "c" / f"{path.stem}.json").is_file()  # (still written)
    rec = lift_keypoint_file(good, lifter=Lifter.from_checkpoint(weights), focal=None)
    assert not_valid_reasons(rec, None) == []
    behind = dataclasses.replace(rec, people=(dataclasses.replace(rec.people[0], root=rec.root * [1, 1, -1]),))
    assert not_valid_reasons(behind, None) == ["1 root(s) behind the camera (Z <= 0)"]


def _jpeg_with_exif(path: Path, size, *, orientation: int = 1, focal_mm=None, f35=None) -> Path:
    img = Image.new("RGB", size, (90, 100, 110))
    exif = Image.Exif()
    exif[0x0112] = orientation
    ifd = exif.get_ifd(0x8769)
    if focal_mm is not None:
        ifd[37386] = focal_mm
    if f35 is not None:
        ifd[41989] = f35
    img.save(path, format="JPEG", exif=exif)
    return path


def test_load_image_exif(tmp_path):
    p = _jpeg_with_exif(tmp_path / "e.jpg", (120, 80), focal_mm=4.2, f35=28)
    img = load_image(p)
    assert img.size == (120, 80) and img.rgb.shape == (80, 120, 3) and img.scale == 1.0
    assert img.exif.focal_mm == pytest.approx(4.2) and img.exif.focal_35mm == 28
    g = focal_from_exif(img.exif, img.size)
    assert g.source == "exif-35mm" and g.focal == pytest.approx(28 * math.hypot(120, 80) / math.hypot(36, 24))
    # orientation 6 (rotate 90 deg): the upright image is portrait
    r = load_image(_jpeg_with_exif(tmp_path / "r.jpg", (120, 80), orientation=6))
    assert r.size == (80, 120) and r.rgb.shape == (120, 80, 3) and any("orientation" in n for n in r.notes)


def test_huge_images_are_downscaled_or_refused(tmp_path):
    p = tmp_path / "wide.png"
    Image.new("RGB", (3000, 400), (1, 2, 3)).save(p)
    img = load_image(p, max_side=1000)
    assert img.size == (3000, 400) and max(img.rgb.shape[:2]) == 1000
    assert img.scale == pytest.approx(1000 / 3000) and "downscaled" in img.notes[0]
    j = _jpeg_with_exif(tmp_path / "big.jpg", (2400, 1600))
    jj = load_image(j, max_side=500)
    assert jj.size == (2400, 1600) and jj.rgb.shape[1] == 500
    with pytest.raises(ImageError, match="MP"):
        load_image(p, max_pixels=1_000_000)
    a = image_from_array(np.zeros((100, 5000, 3), np.uint8), max_side=1000)
    assert a.size == (5000, 100) and a.rgb.shape[1] == 1000


def _png_header_only(path: Path, width: int, height: int, *, bit_depth: int, colour_type: int,
                     palette: bool = False) -> Path:
    """A PNG that declares ``width x height`` px and holds one tiny IDAT (a decompression bomb's header, written
    without making its pixels)."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)

    body = chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0))
    if palette:
        body += chunk(b"PLTE", b"\x00\x00\x00\xff\xff\xff") + chunk(b"tRNS", b"\x00")
    body += chunk(b"IDAT", zlib.compress(b"\x00" * 64)) + chunk(b"IEND", b"")
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + body)
    return path


def test_an_image_whose_decoding_would_take_too_much_memory_is_refused_before_it(tmp_path):
    """A security review: small PNGs of 20000 x 19999 px took 2.1-4.8 GB to decode (a 389-KB palette PNG 3.7 GB),
    within the 400-MP limit, and three uploads at once took three times that. Refused by the memory its mode takes in
    Pillow, before anything is decoded (or the EXIF read, which decodes a whole PNG); JPEGs decode at reduced size."""
    from lifter.detect import MAX_DECODE_BYTES, _decode_bytes

    assert _decode_bytes("L", 20000, 20000) == 400_000_000 <= MAX_DECODE_BYTES  # (downscaled in its own mode)
    assert _decode_bytes("RGB", 20000, 20000) == 1_600_000_000 > MAX_DECODE_BYTES  # (Pillow: 4 bytes a pixel)
    assert _decode_bytes("P", 20000, 20000) == 2_000_000_000  # (converted to RGB or RGBA at full size)
    assert _decode_bytes("I;16", 20000, 20000) == 1_200_000_000
    for name, depth, colour, pal, mode in (("p.png", 8, 3, True, "P"), ("la.png", 8, 4, False, "LA"),
                                           ("rgba.png", 8, 6, False, "RGBA"), ("g16.png", 16, 0, False, "I;16")):
        bomb = _png_header_only(tmp_path / name, 20000, 19999, bit_depth=depth, colour_type=colour, palette=pal)
        with pytest.raises(ImageError, match=rf"20000 x 19999 px \(400 MP, Pillow mode {re.escape(mode)}\); "
                                             r"decoding it would take about [\d.]+ GiB of memory, more than the 1 GiB"):
            load_image(bomb)
    # within the memory bound: decoded (this one's data is cut short: named as truncated, not as too large)
    grey = _png_header_only(tmp_path / "grey.png", 12000, 11999, bit_depth=8, colour_type=0)
    with pytest.raises(ImageError, match="unreadable or truncated image"):
        load_image(grey)


def test_exif_orientations_turn_the_downscaled_image_as_pillow_turns_the_whole(tmp_path):
    """Each EXIF orientation is undone after the downscale (a review: turning the full-size image first doubled its
    memory), with the pixels Pillow's own exif_transpose gives."""
    from PIL import ImageOps

    rng = np.random.default_rng(3)
    base = Image.fromarray(rng.integers(0, 255, (60, 90, 3), dtype=np.uint8))
    for orientation in range(1, 9):
        exif = Image.Exif()
        exif[0x0112] = orientation
        p = tmp_path / f"o{orientation}.png"
        base.save(p, exif=exif)
        got = load_image(p)
        want = np.asarray(ImageOps.exif_transpose(Image.open(p)).convert("RGB"))
        np.testing.assert_array_equal(got.rgb, want, err_msg=str(orientation))
        assert got.size == (want.shape[1], want.shape[0]) and got.orientation == orientation


def test_formats_decoded_through_buffers_of_their_own_count_four_times(tmp_path, monkeypatch):
    """A review: a 140-KB lossless WebP of 8000 x 8000 px took 976 MiB against an estimate of 244; AVIF, HEIF and
    TIFF decode through buffers of their own too. The same pixels as PNG pass where as WebP they are refused."""
    import lifter.detect as ld

    img = Image.new("RGB", (100, 100), (10, 20, 30))
    img.save(tmp_path / "a.png")
    img.save(tmp_path / "a.webp", lossless=True)
    monkeypatch.setattr(ld, "MAX_DECODE_BYTES", 2 * 100 * 100 * 4)
    assert load_image(tmp_path / "a.png").rgb.shape == (100, 100, 3)
    with pytest.raises(ImageError, match=r"decoding it would take about [\d.]+ GiB of memory"):
        load_image(tmp_path / "a.webp")


class _StubEstimator:
    """Returns fixed detections (in the px of the image it is given)."""

    name = "stub"
    keypoint_format = "h36m17"

    def __init__(self, people: list[np.ndarray], visibility: float | np.ndarray = 1.0) -> None:
        self.people = people
        self.visibility = visibility
        self.seen: tuple[int, ...] | None = None

    def detect(self, image: np.ndarray) -> list[Detection]:
        self.seen = image.shape
        return [Detection(keypoints=k, scores=np.broadcast_to(self.visibility, (17,)).copy(), bbox_xywh=bbox_of(k),
                          keypoint_format="h36m17") for k in self.people]


def test_detect_pose_picks_largest_and_maps_back(tmp_path, kp17):
    p = tmp_path / "big.png"
    Image.new("RGB", (4000, 2000), (9, 9, 9)).save(p)
    img = load_image(p, max_side=1000)  # scale 0.25
    small = 0.3 * (kp17 - kp17[0]) + 100
    est = _StubEstimator([small * 0.25, kp17 * 0.25])
    det = detect_pose(img, estimator=est)
    assert est.seen == (500, 1000, 3)
    np.testing.assert_allclose(det.keypoints_2d, kp17, atol=1e-9)  # full-resolution px
    assert det.num_people == 2 and any("2 people found; using the largest" in w for w in det.warnings)
    from lifter.detect import NoPersonError

    with pytest.raises(NoPersonError, match="no person") as caught:
        detect_pose(img, estimator=_StubEstimator([]))
    assert "px image" not in str(caught.value)
    tiny = tmp_path / "tiny.png"  # (a 1 x 1 image: the message names its size, user trial)
    Image.new("RGB", (1, 1)).save(tiny)
    with pytest.raises(NoPersonError, match=r"no person found by the stub 2D detector in this 1 x 1 px image: a "
                                            "person needs to be tens of pixels tall"):
        detect_pose(load_image(tiny), estimator=_StubEstimator([]))


def test_lift_image_with_stub_detector(tmp_path, weights, kp17, capsys):
    """The image path of the CLI end to end, with a registered stub estimator instead of mediapipe."""
    register_estimator("_stub_test", lambda **kw: _StubEstimator([kp17 * 0.5]), overwrite=True)
    p = tmp_path / "photo.png"
    Image.new("RGB", (1280, 720), (50, 60, 70)).save(p)
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--detector", "_stub_test", "--max-side", "640",
                     "--weights", str(weights)], capsys)
    assert code == 0, err
    got = json.loads((tmp_path / "o" / "photo.json").read_text())
    np.testing.assert_allclose(got["keypoints_2d"], kp17, atol=0.01)
    assert got["image_size"] == [1280, 720] and got["principal_point"] == [640.0, 360.0]
    assert got["focal_source"] == "default-fov" and got["detector"] == "stub" and got["num_people"] == 1
    assert "downscaled" in err and "65 deg" in err


def test_detector_flip_test_option_reaches_blazepose(tmp_path, weights, kp17, capsys, monkeypatch):
    """--no-detector-flip-test builds BlazePose without its flip test (videos about twice as fast); the default
    leaves BlazePose's own (on); another detector is refused the option, naming the one that has it."""
    import lifter.detect as detect_module

    made: list[dict] = []

    def fake(name: str = "blazepose", **kw):
        made.append({"name": name, **kw})
        return _StubEstimator([kp17 * 0.5])

    monkeypatch.setattr(detect_module, "get_estimator", fake)
    p = tmp_path / "photo.png"
    Image.new("RGB", (1280, 720), (50, 60, 70)).save(p)
    for extra, want in (([], None), (["--no-detector-flip-test"], False), (["--detector-flip-test"], True)):
        code, err = run([str(p), "--out", str(tmp_path / "o"), "--weights", str(weights), *extra], capsys)
        assert code == 0, err
        assert made[-1]["name"] == "blazepose" and made[-1].get("flip_test") == want
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--detector", "_stub_test", "--no-detector-flip-test"],
                    capsys)
    assert code != 0 and "--no-detector-flip-test: the detector '_stub_test' has no flip test" in err, err


def test_a_calibration_given_for_a_turned_photo_is_said_to_be_the_upright_image_s(tmp_path, weights, kp17, capsys):
    """A user trial: --principal-point (or fx != fy, or a lens) given for a photo turned upright by its EXIF
    orientation was taken in the upright image's pixels, and only "rotated upright" was said; a calibration in the
    stored (sensor) orientation then had its axes swapped. It is said which; a focal length alone, or a photo not
    turned, gets no such note."""
    register_estimator("_stub_turn", lambda **kw: _StubEstimator([kp17 * 0.05]), overwrite=True)
    turned = _jpeg_with_exif(tmp_path / "turned.jpg", (120, 80), orientation=6)
    level = _jpeg_with_exif(tmp_path / "level.jpg", (80, 120))
    base = ["--detector", "_stub_turn", "--weights", str(weights)]
    said = "is taken in the pixels of the upright image (80 x 120 px), which EXIF orientation 6 turned by a quarter " \
           "from the stored one: a calibration made with the stored (sensor) orientation must be turned"
    for extra, note in ((["--principal-point", "40", "60"], "the calibration given (principal point) " + said),
                        (["--focal", "100", "110"], "the calibration given (fx / fy) " + said),
                        (["--focal", "100"], None)):
        code, err = run([str(turned), "--out", str(tmp_path / "o"), *base, *extra], capsys)
        rec = json.loads((tmp_path / "o" / "turned.json").read_text())
        found = [w for w in rec["warnings"] if "upright image" in w]
        assert code == 0 and (found == [note + " with it"] if note else not found), rec["warnings"]
    code, err = run([str(level), "--out", str(tmp_path / "o"), *base, "--principal-point", "40", "60"], capsys)
    assert code == 0 and "upright image" not in err, err
    from lifter.pipeline import turned_calibration_notes  # (a half turn keeps the axes: fx / fy not said, a review)

    assert turned_calibration_notes(3, (4000, 3000), principal_point=None, focal=(1000, 1100), distortion=None) == []
    assert "(principal point)" in turned_calibration_notes(3, (4000, 3000), principal_point=(1, 2), focal=(1000, 1100),
                                                           distortion=None)[0]


def test_a_photos_opencv_lens_is_undone_before_the_lift(tmp_path, kp17, capsys):
    """``--distortion`` with ``--distortion-model opencv``: the detected 2D (through an OpenCV lens) is lifted as
    the pinhole 2D would be; the record keeps the 2D as detected and says which lens. It needs --focal, and is
    refused (per input) for keypoint files, which give their own."""
    import cv2

    lf = tiny_lifter(32)
    pin = save_checkpoint(tmp_path / "pin.pt", lf.net, lf.codec, train_config={"data": {"lens": "pinhole"}})
    f, c, d = 250.0, (640.0, 360.0), [0.05, -0.1, 0.001, 0.001, 0.8]  # (a wide lens: the joints move by px)
    rays = np.concatenate([(kp17 - c) / f, np.ones((17, 1))], axis=1)
    K = np.array([[f, 0, c[0]], [0, f, c[1]], [0, 0, 1.0]])
    seen = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, np.asarray(d))[0].reshape(-1, 2)
    assert np.abs(seen - kp17).max() > 5.0
    register_estimator("_stub_lens", lambda **kw: _StubEstimator([seen]), overwrite=True)
    p = tmp_path / "photo.png"
    Image.new("RGB", (1280, 720), (50, 60, 70)).save(p)
    base = [str(p), "--detector", "_stub_lens", "--weights", str(pin), "--focal", str(f), "--principal-point",
            str(c[0]), str(c[1])]
    code, err = run([*base, "--out", str(tmp_path / "a"), "--distortion", *map(str, d), "--distortion-model",
                     "opencv"], capsys)
    assert code == 0, err
    got = json.loads((tmp_path / "a" / "photo.json").read_text())
    want = Lifter.from_checkpoint(pin).lift(kp17, focal=f, principal_point=c)
    np.testing.assert_allclose(got["root"], want.root, atol=0.01)
    np.testing.assert_allclose(got["keypoints_2d"], seen, atol=0.01)  # (as detected)
    assert got["distortion"] == pytest.approx(d) and got["distortion_model"] == "opencv"
    # the same numbers in Human3.6M's order (the default): that lens cannot be undone here, and the error says why
    code, err = run([*base, "--out", str(tmp_path / "b"), "--distortion", *map(str, d)], capsys)
    assert code == 1 and "no inverse through this lens" in err and "p1, p2 = 0.001, 0.8" in err, err
    assert "--distortion-model opencv" in err
    code, err = run([str(p), "--detector", "_stub_lens", "--weights", str(pin), "--out", str(tmp_path / "c"),
                     "--distortion", *map(str, d)], capsys)
    assert code != 0 and "--distortion needs the focal length it was calibrated with: give --focal" in err
    code, err = run([*base, "--out", str(tmp_path / "d"), "--distortion", "0.1", "0.2"], capsys)
    assert code != 0 and "distortion must be (k1, k2, k3, p1, p2)" in err
    kp_file = _kp_json(tmp_path / "k.json", kp17, image_size=[1280, 720])
    code, err = run([str(kp_file), "--out", str(tmp_path / "e"), "--weights", str(pin), "--focal", str(f),
                     "--distortion", *map(str, d), "--distortion-model", "opencv"], capsys)
    assert code == 1 and "--distortion is for photos; a keypoint file gives its lens in the file" in err


def _openpose_person(kp17: np.ndarray, *, missing: tuple[str, ...] = (), **extra: object) -> dict:
    op = np.zeros((25, 3))
    for i, n in enumerate(OPENPOSE25_JOINT_NAMES):
        op[i, :2] = kp17[JOINT_NAMES.index(n)] if n in JOINT_NAMES else kp17[0] + [i, -i]
        op[i, 2] = 0.0 if n in missing else 0.9
    return {"pose_keypoints_2d": op.ravel().tolist(), **extra}


def test_a_person_missing_a_joint_is_left_out_not_the_whole_file(tmp_path, weights, kp17, capsys):
    """OpenPose / COCO mark undetected joints with confidence 0. A person missing a joint the rules need is left out
    with a note naming them (position, id, joints); the rest of the file is lifted. Only a file where nobody is
    left fails, with the fix. Before, one missing wrist failed the whole file (user trial)."""
    cam = {"image_size": [1280, 720], "focal": 1000.0}
    two = tmp_path / "two.json"
    two.write_text(json.dumps({"people": [_openpose_person(kp17, missing=("l_wrist",), id="A"),
                                          _openpose_person(0.5 * kp17 + 100, id="B")], **cam}))
    one = tmp_path / "one.json"
    one.write_text(json.dumps({"people": [_openpose_person(kp17, missing=("l_wrist",))], **cam}))
    h36 = kp17.tolist()
    h36[5] = [None, None]
    h = tmp_path / "h.json"
    h.write_text(json.dumps({"keypoints": h36, "format": "h36m17", **cam}))
    out = tmp_path / "out"
    code, err = run([str(two), str(one), str(h), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 0 and "lifted 1 of 3" in err, err
    assert "1 of 2 people left out: joint(s) missing (confidence 0 or below or null, or null / NaN coordinates) for " \
           "person 1 in the file (input_index 0, id 'A'): ['l_wrist']; the lifter needs every joint that the " \
           "openpose25 -> h36m17 rules use" in err
    got = json.loads((out / "two.json").read_text())
    assert got["num_people"] == 1 and got["people"][0]["person_id"] == "B" and got["people"][0]["input_index"] == 1
    assert f"{one}: joint(s) missing (confidence 0 or below or null, or null / NaN coordinates) for the person: " \
           "['l_wrist']" in err and "Give those joints" in err and not (out / "one.json").exists()
    assert "the lifter needs all 17 joints" in err and "h36m17 -> h36m17" not in err



def test_a_null_confidence_or_a_null_row_marks_a_missing_joint(tmp_path, kp17):
    """The README: a confidence of 0 marks a missing joint, as does null. User trial: [x, y, null] was lifted with
    that joint (the same output as confidence 0.9), and a row that is null as a whole failed the file."""
    from lifter.io import parse_keypoint_json

    cam = {"image_size": [1280, 720], "focal": 1000.0, "format": "h36m17"}
    rows = [[float(x), float(y), 0.9] for x, y in kp17]
    missing_msg = r"joint\(s\) missing \(confidence 0 or below or null, or null / NaN coordinates\) for the person: " \
                  r"\['l_wrist'\]"
    for bad in ([float(kp17[13, 0]), float(kp17[13, 1]), None], [float(kp17[13, 0]), float(kp17[13, 1]), 0], None,
                [None, None, 0.9], [float(kp17[13, 0]), float(kp17[13, 1]), -1]):  # (-1: "0 or below", user trial)
        doc = [list(r) for r in rows]
        doc[13] = bad  # l_wrist
        p = tmp_path / "k.json"
        p.write_text(json.dumps({"keypoints": doc, **cam}))
        with pytest.raises(PoseLifterError, match=missing_msg):
            parse_keypoint_json(p)
    two = [[float(x), float(y)] for x, y in kp17]
    two[13] = None  # a whole null row among [x, y] rows too
    p.write_text(json.dumps({"keypoints": two, **cam}))
    with pytest.raises(PoseLifterError, match=missing_msg):
        parse_keypoint_json(p)
    p.write_text(json.dumps({"keypoints": rows, **cam}))  # every confidence > 0: all 17 joints
    np.testing.assert_allclose(parse_keypoint_json(p).keypoints, kp17)
    # a user trial: a coordinate too large for a float (1e400, a 400-digit integer, Infinity) was read as a missing
    # joint and stood in for; refused, naming it (null marks a missing joint)
    for big in ("1e400", "-" + "9" * 400, "Infinity"):
        p.write_text(json.dumps({"keypoints": rows, **cam}).replace(f"[{rows[3][0]!r},", f"[{big},", 1))
        with pytest.raises(PoseLifterError, match=r"keypoint 3's x is -?inf \(a number too large for a float\)"):
            parse_keypoint_json(p)

def test_a_zero_placeholder_in_a_keypoint_file_is_in_its_record(tmp_path, weights, kp17, capsys):
    """A COCO r_hip at (0, 0) without confidences (the user trial's silent 5.2 -> 2.2 m root): each file's record
    and the CLI name it, as a note per file, not a Python warning said once per process."""
    coco = np.column_stack([np.linspace(500, 700, 17), np.linspace(200, 600, 17)])
    coco[1:5] = coco[0] + [[-6, -4], [6, -4], [-14, 0], [14, 0]]  # (a face first, as COCO-17's)
    coco[COCO17_JOINT_NAMES.index("r_hip")] = 0.0
    for name in ("a", "b"):
        (tmp_path / f"{name}.json").write_text(json.dumps({"keypoints": coco.tolist(), "format": "coco17",
                                                            "image_size": [1280, 720], "focal": 1000.0}))
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)
        code, err = run([str(tmp_path / "a.json"), str(tmp_path / "b.json"), "--out", str(tmp_path / "o"),
                         "--weights", str(weights)], capsys)
    assert code == 0, err
    for name in ("a", "b"):
        rec = json.loads((tmp_path / "o" / f"{name}.json").read_text())
        assert any("joint(s) ['r_hip'] of format 'coco17' at exactly (0, 0) px" in w for w in rec["warnings"])
        assert f"{name}.json: note: joint(s) ['r_hip'] of format 'coco17'" in err
    # (a user trial) a joint the conversion copies as it is (a wrist) is said once, in the file's format, not again
    # as the H36M joint
    coco = np.column_stack([np.linspace(500, 700, 17), np.linspace(200, 600, 17)])
    coco[1:5] = coco[0] + [[-6, -4], [6, -4], [-14, 0], [14, 0]]
    coco[COCO17_JOINT_NAMES.index("r_wrist")] = 0.0
    (tmp_path / "w.json").write_text(json.dumps({"keypoints": coco.tolist(), "format": "coco17",
                                                 "image_size": [1280, 720], "focal": 1000.0}))
    code, err = run([str(tmp_path / "w.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    notes = json.loads((tmp_path / "o" / "w.json").read_text())["warnings"]
    assert code == 0 and [w for w in notes if "at exactly (0, 0) px" in w] == [next(
        w for w in notes if w.startswith("joint(s) ['r_wrist'] of format 'coco17' at exactly (0, 0) px"))], notes


def test_a_keypoint_sequence_keeps_its_frames_and_ids_when_one_misses_a_joint(tmp_path, weights, kp17, capsys):
    """A 20-frame OpenPose sequence with one frame missing a wrist: that frame has nobody (noted), the other 19 are
    lifted; each person keeps their own id (person_id) beside the tracker's track_id."""
    frames = [{"people": [_openpose_person(kp17 + [3.0 * i, 0.0], missing=("l_wrist",) if i == 13 else (), id="A")]}
              for i in range(20)]
    seq = tmp_path / "seq.json"
    seq.write_text(json.dumps({"fps": 25, "image_size": [1280, 720], "focal": 1000.0, "frames": frames}))
    code, err = run([str(seq), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0, err
    assert "1 person(s) left out of 1 frame(s) (13) for missing joints ['l_wrist']" in err
    assert "first person 1 of frame 13 (input_index 0, id 'A'))" in err  # (a user trial: who was it?)
    d = json.loads((tmp_path / "o" / "seq.json").read_text())
    assert d["frames"][13]["people"] == [] and d["source_format"] == "openpose25"
    people = [q for i, f in enumerate(d["frames"]) if i != 13 for q in f["people"]]
    assert len(people) == 19 and {q["person_id"] for q in people} == {"A"}
    for fr in frames:
        fr["people"][0] = _openpose_person(kp17, missing=("r_knee",))
    seq.write_text(json.dumps({"fps": 25, "image_size": [1280, 720], "focal": 1000.0, "frames": frames}))
    code, err = run([str(seq), "--out", str(tmp_path / "o2"), "--weights", str(weights)], capsys)
    assert code == 1 and "20 person(s) left out of 20 frame(s)" in err and "nobody is left to lift" in err


class _InterruptedEstimator(_StubEstimator):
    """Ctrl-C during the second detection."""

    calls = 0

    def detect(self, image: np.ndarray) -> list[Detection]:
        type(self).calls += 1
        if type(self).calls == 2:
            raise KeyboardInterrupt
        return super().detect(image)


def test_ctrl_c_ends_the_batch_with_one_line_and_keeps_what_was_written(tmp_path, weights, kp17, capsys, monkeypatch):
    """Ctrl-C: one line saying how far it got (exit 130), the finished outputs kept, no traceback; and without
    --no-progress, no progress bar is written to a stderr that is not a terminal (a log file)."""
    _InterruptedEstimator.calls = 0
    import lifter.detect as detect

    monkeypatch.setitem(detect._ESTIMATORS, "_interrupted", lambda **kw: _InterruptedEstimator([kp17]))
    for n in ("a", "b", "c"):
        Image.new("RGB", (1280, 720), (50, 60, 70)).save(tmp_path / f"{n}.png")
    code = main(["lift", *(str(tmp_path / f"{n}.png") for n in "abc"), "--out", str(tmp_path / "o"), "--detector",
                 "_interrupted", "--focal", "1000", "--weights", str(weights)])
    err = capsys.readouterr().err
    assert code == 130 and "poselifter lift: interrupted after 1 of 3 input(s) lifted" in err, err
    assert "Traceback" not in err and "\r" not in err and "it/s" not in err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["a.json"]
    json.loads((tmp_path / "o" / "a.json").read_text())


def test_a_detection_the_detector_doubts_or_off_the_image_is_noted(tmp_path, weights, kp17):
    """A tiny or blurred photo makes BlazePose invent a person with low landmark visibility and joints off the
    image (seen on a 40 x 40 px photo: visibility 0.37, joints up to 78 px on a 40-px image); the record says so
    instead of lifting it without a word. A plain detection gets neither note."""
    from lifter.detect import load_image
    from lifter.pipeline import lift_image

    p = tmp_path / "tiny.png"
    Image.new("RGB", (300, 300), (50, 60, 70)).save(p)
    off = 0.2 * (kp17 - kp17[0]) + np.array([330.0, 150.0])  # mostly right of the 300-px image
    lifter = Lifter.from_checkpoint(weights)
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([off], visibility=0.37), focal=400.0)
    assert any("the detector placed most joints of 1 of 1 2D pose(s) outside the 300 x 300 px image" in w
               for w in rec.warnings), rec.warnings
    assert any("detector is unsure of the person found: mean joint score 0.37 over the 17 joints lifted" in w
               for w in rec.warnings), rec.warnings
    inside = 0.2 * (kp17 - kp17[0]) + 150.0
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([inside], visibility=0.8), focal=400.0)
    assert not any("outside" in w or "unsure" in w for w in rec.warnings), rec.warnings
    with pytest.raises(PoseLifterError, match=r"max_side must be a whole number of px >= 256"):
        load_image(p, max_side=10)


def test_a_person_cut_off_by_the_photos_edge_is_named(tmp_path, weights):
    """A person whose feet the detector places below the photo's bottom edge (a half-body photo; in a user trial's
    video such frames were lifted metres too far) is named in a note with the joints outside; one wholly inside is
    not, and one mostly outside keeps the plausibility note alone."""
    from lifter.detect import load_image
    from lifter.pipeline import detected_edge_notes, lift_image

    demo = np.load(Path(__file__).resolve().parents[1] / "assets" / "demo" / "samples.npz")
    standing = demo["keypoints_2d"][list(demo["names"]).index("standing")]
    p = tmp_path / "half.png"
    Image.new("RGB", (1000, 800), (50, 60, 70)).save(p)
    body = standing - standing[0]
    cut = body * 0.8 + [300.0, 800.0 - body[[3, 6], 1].max() * 0.8 + 40.0]  # (ankles 40 px below the bottom)
    whole = body * 0.8 + [700.0, 400.0]
    lifter = Lifter.from_checkpoint(weights)
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([cut, whole], visibility=0.9),
                     focal=1000.0)
    n = 1 + int(np.argmin([np.abs(q.keypoints_2d - cut).max() for q in rec.people]))
    said = [w for w in rec.warnings if "cut off" in w]
    assert len(said) == 1 and said[0].startswith(f"person {n} of the output's people is cut off by the image's edge ("
                                                 ) and "r_ankle" in said[0] and "l_ankle" in said[0], rec.warnings
    assert said[0].endswith("the detector guesses the joints it cannot see, so the 2D there, and the lift, its depth "
                            "most of all, are less sure")
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([whole], visibility=0.9), focal=1000.0)
    assert not any("cut off" in w for w in rec.warnings), rec.warnings
    assert detected_edge_notes(cut[None], (1000, 800))[0].startswith("the person found is cut off by the image's edge")
    assert detected_edge_notes((whole + [900.0, 0.0])[None], (1000, 800)) == []  # (mostly outside: the other note)


def test_an_upside_down_detection_is_named(tmp_path, weights):
    """A user trial: BlazePose found a third, upside-down 'person' on the wall beside one of two people (scored 0.86)
    and it was lifted without a word. Each detected person upside down in the image is now named in a note (the
    detector's output is not dropped: a handstand is a person); upright people get none, and a keypoint file's
    upside-down 2D keeps its own y-axis note instead."""
    from lifter.detect import load_image
    from lifter.pipeline import detected_upside_down_notes, lift_image, upside_down_people

    demo = np.load(Path(__file__).resolve().parents[1] / "assets" / "demo" / "samples.npz")
    standing = demo["keypoints_2d"][list(demo["names"]).index("standing")]
    p = tmp_path / "two.png"
    Image.new("RGB", (1200, 1000), (50, 60, 70)).save(p)
    upright = 0.8 * (standing - standing[0]) + np.array([300.0, 500.0])
    other = upright + [500.0, 0.0]
    flipped = upright * [1.0, -1.0] + [250.0, 1000.0]  # the same body mirrored top to bottom, beside the first
    assert upside_down_people(np.stack([upright, other, flipped])).tolist() == [False, False, True]
    lifter = Lifter.from_checkpoint(weights)
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([upright, other, flipped], visibility=0.9),
                     focal=1000.0)
    order = [int(np.argmin([np.abs(q.keypoints_2d - k).max() for k in (upright, other, flipped)])) for q in rec.people]
    n = order.index(2) + 1
    said = [w for w in rec.warnings if "upside down" in w]
    assert said == [f"person {n} of the output's people is upside down in the image (the head below both ankles): the "
                    "detector finds such 'people' on walls and in clutter; unless someone in the photo is upside down "
                    "(a handstand), it is a false detection (the others' lifts do not depend on it)"], rec.warnings
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([upright, other], visibility=0.9),
                     focal=1000.0)
    assert not any("upside down" in w for w in rec.warnings), rec.warnings
    assert detected_upside_down_notes(flipped[None])[0].startswith("the person found is upside down in the image")
    assert detected_upside_down_notes(np.stack([flipped, flipped, upright]))[0].startswith(
        "people 1 and 2 of the output's people are upside down")


def test_a_files_focal_in_mm_is_refused_naming_the_file(tmp_path, weights, kp17, capsys):
    """(a review) A keypoint file's 'focal' of 4.2 was refused with the library's message, naming focal=None."""
    from lifter.io import depth_is_metric

    (tmp_path / "mm.json").write_text(json.dumps({"keypoints": kp17.tolist(), "format": "h36m17", "focal": 4.2,
                                                  "principal_point": [640, 360], "image_size": [1280, 720]}))
    code, err = run([str(tmp_path / "mm.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 1 and "mm.json: the file's 'focal' 4.2 x 4.2 px is below 10 px: it must be in pixels" in err, err
    assert "focal=None" not in err
    assert [depth_is_metric(s) for s in ("given", "user", "keypoint-file", "exif-35mm", "default-fov", "reference")] \
        == [True, True, True, True, False, False]


def test_the_person_doubt_reads_the_17_joints_lifted_not_the_face(tmp_path, weights, kp17):
    """A browser trial's empty-wall photo got an invented person whose 17 lifted joints scored 0.41 on average, and
    no whole-person note: the rule read BlazePose's 33 landmarks, whose face points it scores higher. Here the face
    (11 landmarks) is scored 0.95 and the body 0.3: the 33 landmarks' mean is 0.52, the 17 joints' 0.3."""
    from lifter.detect import Detection, bbox_of, load_image
    from lifter.keypoints import BLAZEPOSE33_JOINT_NAMES
    from lifter.pipeline import lift_image

    j = {n: kp17[i] for i, n in enumerate(JOINT_NAMES)}
    head = 0.5 * (j["neck_nose"] + j["head_top"])
    place = {"nose": j["neck_nose"], "l_shoulder": j["l_shoulder"], "r_shoulder": j["r_shoulder"],
             "l_elbow": j["l_elbow"], "r_elbow": j["r_elbow"], "l_hip": j["l_hip"], "r_hip": j["r_hip"],
             "l_knee": j["l_knee"], "r_knee": j["r_knee"]}
    lm = []
    for name in BLAZEPOSE33_JOINT_NAMES:
        side = name[:2] if name[:2] in ("l_", "r_") else ""
        if name in place:
            lm.append(place[name])
        elif any(k in name for k in ("wrist", "pinky", "index", "thumb")) and "foot" not in name:
            lm.append(j[f"{side}wrist"])
        elif any(k in name for k in ("ankle", "heel", "foot")):
            lm.append(j[f"{side}ankle"])
        else:  # eyes, ears, mouth
            lm.append(head + (np.array([-8.0, 0.0]) if side == "l_" else np.array([8.0, 0.0])))
    lm = np.array(lm)
    scores = np.where(np.arange(33) <= 10, 0.95, 0.3)
    assert np.mean(scores) >= 0.5

    class Stub33:
        name, keypoint_format = "stub33", "blazepose33"

        def detect(self, image):
            return [Detection(keypoints=lm, scores=scores, bbox_xywh=bbox_of(lm), keypoint_format="blazepose33")]

    p = tmp_path / "wall.png"
    Image.new("RGB", (1000, 1000), (200, 190, 180)).save(p)
    rec = lift_image(load_image(p), lifter=Lifter.from_checkpoint(weights), estimator=Stub33(), focal=1000.0)
    assert any("detector is unsure of the person found: mean joint score 0.30 over the 17 joints lifted" in w
               for w in rec.warnings), rec.warnings


def test_a_small_person_in_a_photo_is_noted(tmp_path, weights, kp17):
    """A browser trial's 300-px photo lifted 73 mm off the same photo at 1000 px, without a word. A person shorter
    than SMALL_PERSON_PX in the image the detector saw is noted (scripts/small_people.py: the demo photos lift at
    114 mm with people 68 px tall, against 64 at 340 px); a photo downscaled for the detector says so."""
    from lifter.detect import SMALL_PERSON_PX, load_image
    from lifter.pipeline import lift_image

    assert SMALL_PERSON_PX == 100.0
    p = tmp_path / "photo.png"
    Image.new("RGB", (1000, 1000), (50, 60, 70)).save(p)
    lifter = Lifter.from_checkpoint(weights)
    tall = float(np.ptp(kp17, axis=0).max())  # (the longer side of the joints' box)
    small = (80.0 / tall) * (kp17 - kp17[0]) + 500.0  # 80 px
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([small]), focal=1000.0)
    assert any(w.startswith("the person found is small in the image: 80 px (the longer side of the joints' box), "
                            "below 100 px") for w in rec.warnings), rec.warnings
    big = (150.0 / tall) * (kp17 - kp17[0]) + 500.0
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([big]), focal=1000.0)
    assert not any("small" in w for w in rec.warnings), rec.warnings
    assert rec.metric_depth is True and rec.to_dict()["metric_depth"] is True  # (the focal was given)
    assert lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([big])).metric_depth is False
    # 150 px tall in a 2000-px photo that the detector sees at 1000 px: 75 px for it
    q = tmp_path / "big.png"
    Image.new("RGB", (2000, 2000), (50, 60, 70)).save(q)
    img = load_image(q, max_side=1000)
    rec = lift_image(img, lifter=lifter, estimator=_StubEstimator([big * 0.5]), focal=2000.0)
    assert any("small in the image as downscaled for the detector (--max-side): 75 px (the longer side" in w
               for w in rec.warnings), rec.warnings
    # the pose turned to lie along x, 140 px long and less than 100 px high: not small
    flat = kp17 - kp17[0]
    lying = (flat if np.ptp(flat[:, 0]) >= np.ptp(flat[:, 1]) else flat[:, ::-1]) * (140.0 / tall) + 500.0
    assert np.ptp(lying[:, 0]) == pytest.approx(140.0) and np.ptp(lying[:, 1]) < 100.0
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([lying]), focal=1000.0)
    assert not any("small in the image" in w for w in rec.warnings), rec.warnings


def test_joints_the_detector_is_unsure_of_are_named(tmp_path, weights, kp17):
    """Joints scored below UNSURE_JOINT_SCORE (on the demo photos 19-29 px off, median, against 5.5 for well-scored
    ones) are named in a note, per person; a person whose joints are all scored well gets none."""
    from lifter.detect import UNSURE_JOINT_SCORE, load_image
    from lifter.pipeline import joint_doubt_notes, lift_image

    assert UNSURE_JOINT_SCORE == 0.3
    p = tmp_path / "photo.png"
    Image.new("RGB", (1000, 1000), (50, 60, 70)).save(p)
    scores = np.full(17, 0.95)
    scores[[12, 16]] = [0.25, 0.12]  # l_elbow, r_wrist
    lifter = Lifter.from_checkpoint(weights)
    rec = lift_image(load_image(p), lifter=lifter, estimator=_StubEstimator([kp17], visibility=scores), focal=1000.0)
    assert ("the detector is unsure of some joints (score below 0.3): l_elbow (0.25), r_wrist (0.12): their 2D, and so "
            "their 3D, may be off (an occluded or blurred limb?)") in rec.warnings, rec.warnings
    assert not any("mean joint score" in w for w in rec.warnings)  # the person as a whole is seen well
    two = np.stack([np.full(17, 0.9), scores])
    assert joint_doubt_notes(two) == ["the detector is unsure of some joints (score below 0.3): person 2: l_elbow "
                                      "(0.25), r_wrist (0.12): their 2D, and so their 3D, may be off (an occluded or "
                                      "blurred limb?)"]
    assert joint_doubt_notes(np.full((2, 17), 0.3)) == []  # (at the threshold: not below it)


def test_unsure_joints_near_the_image_edge_are_named_as_near_it():
    """A developer trial: a photo cut at the waist; BlazePose put the ankles inside the image, 31 and 58 px above the
    bottom of a 480-px image, scored low, and the note said only "an occluded or blurred limb". Unsure joints within
    EDGE_NEAR of an edge say so, and the note names a cut-off limb placed inside the image as a likely cause."""
    from lifter.pipeline import EDGE_NEAR, joint_doubt_notes
    from lifter.skeleton import JOINT_NAMES

    assert EDGE_NEAR == 0.15
    kp = np.tile([[320.0, 200.0]], (17, 1))
    scores = np.full(17, 0.9)
    r_ankle, l_ankle, l_wrist = (JOINT_NAMES.index(n) for n in ("r_ankle", "l_ankle", "l_wrist"))
    kp[r_ankle], kp[l_ankle], kp[l_wrist] = [300, 449], [340, 422], [630, 100]
    scores[[r_ankle, l_ankle, l_wrist]] = [0.1, 0.2, 0.25]
    note = joint_doubt_notes(scores[None], kp[None], (640, 480))
    assert note == ["the detector is unsure of some joints (score below 0.3): r_ankle (0.10, near the bottom edge), "
                    "l_ankle (0.20, near the bottom edge), l_wrist (0.25, near the right edge): their 2D, and so "
                    "their 3D, may be off (an occluded or blurred limb, or, near the edge, one outside the image that "
                    "the detector placed inside it?)"], note
    kp[r_ankle], kp[l_ankle], kp[l_wrist] = [300, 300], [340, 300], [300, 100]  # (none near an edge: plain)
    assert joint_doubt_notes(scores[None], kp[None], (640, 480))[0].endswith("(an occluded or blurred limb?)")


def test_h36m_joint_scores_take_the_lowest_source_joint():
    """A converted joint is as sure as the least sure joint it is made from (BlazePose's pelvis reads its hips and
    shoulders)."""
    from lifter.detect import h36m_joint_scores
    from lifter.keypoints import get_format

    rules = get_format("blazepose33").to_h36m
    s33 = np.linspace(0.1, 0.9, 33)
    out = h36m_joint_scores(np.stack([s33, s33[::-1]]), "blazepose33")
    assert out.shape == (2, 17)
    for j, rule in enumerate(rules):
        assert out[0, j] == min(s33[k] for k, _ in rule) and out[1, j] == min(s33[::-1][k] for k, _ in rule)
    assert len(rules[0]) > 1 and len({out[0, 0], *(s33[k] for k, _ in rules[0])}) > 1  # (a real minimum)


def test_images_are_lifted_as_detections_and_keypoint_files_say_what_they_are(tmp_path, weights, kp17, capsys):
    """One model for everything: images are detector output (source "detected"); a keypoint file is "detected"
    unless it says "source": "clean"; the two sources lift the same 2D differently; a bad value is an error."""
    register_estimator("_stub_src", lambda **kw: _StubEstimator([kp17]), overwrite=True)
    img = tmp_path / "photo.png"
    Image.new("RGB", (1000, 1000), (50, 60, 70)).save(img)
    files = []
    for name, extra in (("det", {}), ("clean", {"source": "clean"}), ("bad", {"source": "gt"})):
        f = tmp_path / f"{name}.json"
        f.write_text(json.dumps({"format": "h36m17", "keypoints": kp17.tolist(), "image_size": [1000, 1000],
                                 "focal": 1000.0, **extra}))
        files.append(str(f))
    code, err = run([str(img), *files, "--out", str(tmp_path / "o"), "--detector", "_stub_src", "--focal", "1000",
                     "--weights", str(weights)], capsys)
    assert code == 0, err
    out = {n: json.loads((tmp_path / "o" / f"{n}.json").read_text()) for n in ("photo", "det", "clean")}
    assert [out[n]["source"] for n in ("photo", "det", "clean")] == ["detected", "detected", "clean"]
    np.testing.assert_allclose(out["photo"]["absolute"], out["det"]["absolute"], atol=0.02)
    assert np.abs(np.array(out["clean"]["absolute"]) - np.array(out["det"]["absolute"])).max() > 0.1
    assert "'source' must be" in err and not (tmp_path / "o" / "bad.json").exists()


def test_missing_extra_message(tmp_path, weights, capsys, monkeypatch):
    import sys

    pytest.importorskip("PIL")
    monkeypatch.setitem(sys.modules, "mediapipe", None)  # as without the extra, installed or not
    p = tmp_path / "photo.png"
    Image.new("RGB", (64, 64)).save(p)
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 1 and "optional 'detect' extra" in err and 'pip install -e ".[detect]"' in err


def _save_tiny(path, width: int):
    lf = tiny_lifter(width)
    return save_checkpoint(path, lf.net, lf.codec)


# -- robustness: each case gets a clear message, the batch goes on, nothing half-written -------------------


def _kp_json(path: Path, kp17: np.ndarray, **extra) -> Path:
    path.write_text(json.dumps({"keypoints": kp17.tolist(), "image_size": [1280, 720], **extra}))
    return path


@pytest.mark.parametrize("content, expected", [
    ({"keypoints": 5}, "'keypoints' must be a list of [x, y] or [x, y, confidence] rows"),
    ({"people": 5}, "'people' must be a list of"),
    ({"keypoints": [[True, False]] * 17}, "found [true, false]"),
    ({"keypoints": [[1.0, 2.0]] * 17, "format": 7}, "'format' must be a string"),
    ({"keypoints": [[1.0, 2.0]] * 17, "source": "gt"}, "'source' must be"),
    # a layout that implies a format with another joint count: the formats with the file's count are named
    ({"people": [{"pose_keypoints_2d": [1.0, 2.0, 1.0] * 17}]}, "format 'openpose25' has 25 joints, the file has 17 "
     "(OpenPose's 'pose_keypoints_2d' layout implies 'openpose25' when the file has no 'format'): give the file's "
     "format, "),  # (the formats with 17 joints: 'coco17' or 'h36m17', and any a test registered)
    ([{"keypoints": [1.0, 2.0, 1.0] * 16}], "(a list of COCO results implies 'coco17' when the file has no 'format'): "
     "give the file's format, 'sh16'"),
    ({"keypoints": [[1.0, 2.0]] * 16, "format": "coco17"}, "format 'coco17' has 17 joints, the file has 16: give"),
    # (a user trial) a count no format has: the counts, and what 18 joints are
    ({"keypoints": [[1.0, 2.0]] * 18, "format": "coco17"}, "format 'coco17' has 17 joints, the file has 18: no "
     "format has 18 joints (the formats and their joint counts: "),  # (then any a test registered, by name)
    ({"keypoints": [[1.0, 2.0]] * 18, "format": "coco17"}, "blazepose33 33, coco17 17, h36m17 17, openpose25 25, "
     "sh16 16); convert the keypoints to one of them"),
    ({"keypoints": [[1.0, 2.0]] * 18, "format": "coco17"}, "(18 joints is OpenPose's COCO-18 / BODY_18 layout, which "
     "is not read: run OpenPose with BODY_25, openpose25, or write the 17 COCO joints in COCO order, coco17)"),
])
def test_malformed_keypoint_files_get_clear_messages(tmp_path, weights, kp17, capsys, content, expected):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(content))
    good = _kp_json(tmp_path / "good.json", kp17)
    code, err = run([str(bad), str(good), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0 and expected in err and "unexpected" not in err
    assert (tmp_path / "o" / "good.json").is_file() and not (tmp_path / "o" / "bad.json").exists()


def test_deeply_nested_json(tmp_path, weights, capsys):
    deep = tmp_path / "deep.json"
    deep.write_text("[" * 200_000 + "]" * 200_000)
    code, err = run([str(deep), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 1 and "nested too deeply" in err and "RecursionError" not in err


def test_symlinks_are_not_followed_out_of_the_output_folder(tmp_path, weights, kp17, capsys):
    outside = tmp_path / "precious.txt"
    outside.write_text("keep me")
    out = tmp_path / "o"
    out.mkdir()
    (out / "pose.json").symlink_to(outside)
    src = _kp_json(tmp_path / "pose.json", kp17)
    code, err = run([str(src), "--out", str(out), "--weights", str(weights)], capsys)
    # (not a result where it leads: the user's, so the result is named otherwise)
    assert code == 0 and "its results are named pose_json.*" in err
    assert outside.read_text() == "keep me" and (out / "pose.json").is_symlink()
    # a link to an earlier result is not written through either
    res = tmp_path / "earlier.json"
    res.write_text((out / "pose_json.json").read_text())
    (out / "pose_json.json").unlink()
    (out / "pose_json.json").symlink_to(res)
    before = res.read_text()
    code, err = run([str(src), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 1 and "symbolic link" in err
    assert res.read_text() == before and (out / "pose_json.json").is_symlink()


def test_dangling_symlinks_and_other_files_are_named(tmp_path, weights, kp17, capsys):
    d = tmp_path / "in"
    d.mkdir()
    _kp_json(d / "a.json", kp17)
    (d / "gone.json").symlink_to(tmp_path / "nowhere.json")
    (d / "notes.txt").write_text("x")
    (d / "more_photos").mkdir()
    (tmp_path / "b.png").symlink_to(tmp_path / "nowhere.png")
    code, err = run([str(d), str(tmp_path / "b.png"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0
    assert "gone.json: dangling symbolic link" in err and "b.png: dangling symbolic link" in err
    assert "note:" in err and "notes.txt" in err and "lifted 1 of 3" in err
    assert "skipped 1 subfolder(s) (folders are not searched recursively; give them as inputs too): more_photos/" in err


def test_a_full_disk_leaves_no_partial_files(tmp_path, weights, kp17, capsys, monkeypatch):
    import errno

    import lifter.io

    def no_space(fd: int) -> None:
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(lifter.io.os, "fsync", no_space)
    code, err = run([str(_kp_json(tmp_path / "pose.json", kp17)), "--out", str(tmp_path / "o"), "--weights",
                     str(weights)], capsys)
    assert code == 1 and "No space left on device" in err
    assert list((tmp_path / "o").iterdir()) == []  # neither a 0-byte pose.json nor a temporary file


def test_16_bit_greyscale_png_decodes_with_its_contrast(tmp_path):
    ramp = np.linspace(0, 65535, 64 * 32).reshape(32, 64).astype(np.uint16)
    Image.fromarray(ramp).save(tmp_path / "g16.png")
    img = load_image(tmp_path / "g16.png")
    assert img.rgb.dtype == np.uint8 and img.rgb.min() == 0 and img.rgb.max() == 255
    assert 100 < img.rgb.mean() < 155  # a ramp, not all white


def test_a_large_16_bit_png_is_converted_a_strip_at_a_time_and_downscaled_before_its_rgb_copy(tmp_path):
    """A security trial: a 778 KB 16-bit PNG declaring 20000 x 19999 px took 10.4 GB in float64 copies of the whole
    image. The conversion now goes a strip of rows at a time and downscales before the RGB copy: numpy's peak for a
    3000 x 3000 16-bit image stays under 30 MB (the whole-image float64 copy alone was 72 MB), with the same
    result as converting it whole; an EXIF orientation that is not one (99) is not said to rotate."""
    import tracemalloc

    rng = np.random.default_rng(0)
    big = np.repeat(np.repeat(rng.integers(0, 65535, (30, 30)), 100, 0), 100, 1).astype(np.uint16)
    Image.fromarray(big).save(tmp_path / "big16.png")
    tracemalloc.start()
    img = load_image(tmp_path / "big16.png", max_side=1000)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert peak < 30e6, peak
    assert img.rgb.shape == (1000, 1000, 3) and img.size == (3000, 3000)
    whole = Image.fromarray((big.astype(np.float64) * (255.0 / 65535.0)).astype(np.uint8), "L")  # (converted whole)
    np.testing.assert_array_equal(img.rgb[..., 0], np.asarray(whole.resize((1000, 1000), Image.Resampling.BOX)))
    odd = Image.fromarray(big[:40, :40])
    exif = Image.Exif()
    exif[0x0112] = 99
    odd.convert("RGB").save(tmp_path / "odd.jpg", exif=exif)
    assert not any("rotated" in n for n in load_image(tmp_path / "odd.jpg").notes)


def test_output_folder_that_is_also_the_input_folder_is_not_lifted_again(tmp_path, weights, kp17, capsys):
    d = tmp_path / "work"
    d.mkdir()
    _kp_json(d / "pose.json", kp17)
    code, err = run([str(d), "--out", str(d), "--weights", str(weights)], capsys)
    assert code == 0 and "lifted 1 of 1" in err, err
    first = sorted(p.name for p in d.iterdir())
    assert len(first) == 2  # the input and its result (named so that it does not overwrite the input)
    # again: the same files, no result of a result
    code, err = run([str(d), "--out", str(d), "--weights", str(weights)], capsys)
    assert code == 0 and "lifted 1 of 1" in err and "1 earlier result file(s) are not lifted again" in err, err
    assert sorted(p.name for p in d.iterdir()) == first
    # named as an input, a result is lifted (poselifter reads its own output)
    result = next(p for p in d.iterdir() if p.name != "pose.json")
    code, err = run([str(result), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0, err


def test_implausible_keypoint_files_get_a_note(tmp_path, weights, kp17, capsys):
    """Lifted as given, but said: a focal length that looks like mm, keypoints mostly outside the stated image."""
    mm = _kp_json(tmp_path / "mm.json", kp17, focal=35.0)
    with warnings.catch_warnings(record=True) as caught:  # said once, as a note, not also as a Python warning
        warnings.simplefilter("always")
        code, err = run([str(mm), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert not [w for w in caught if issubclass(w.category, PoseLifterWarning)]
    assert code == 0 and ("deg of view (a whole person rarely spans more than 120 deg, even through an ultra-wide "
                          "lens): is the focal length in pixels") in err
    far = _kp_json(tmp_path / "far.json", kp17 - 5000.0)
    code, err = run([str(far), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0 and "1 of 1 2D pose(s) lie mostly outside the 1280 x 720 px image" in err, err
    fine = _kp_json(tmp_path / "fine.json", kp17, focal=1000.0)
    code, err = run([str(fine), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0 and "deg of view" not in err and "outside" not in err, err


def test_lift_image_refuses_an_array_with_the_way_to_pass_one(weights):
    from lifter.pipeline import lift_image

    lifter = Lifter.from_checkpoint(weights)
    with pytest.raises(PoseLifterError, match=r"numpy array \(20, 30, 3\).*image_from_array\(rgb\).*COLOR_BGR2RGB"):
        lift_image(np.zeros((20, 30, 3), np.uint8), lifter=lifter, estimator=None)  # type: ignore[arg-type]
    with pytest.raises(PoseLifterError, match="expected a file path or a lifter.detect.LoadedImage, got int"):
        lift_image(3, lifter=lifter, estimator=None)  # type: ignore[arg-type]
    from pathlib import PurePosixPath

    with pytest.raises(PoseLifterError, match="missing.jpg"):  # any path object is a path: to the file check
        lift_image(PurePosixPath("/nonexistent/missing.jpg"), lifter=lifter, estimator=None)  # type: ignore[arg-type]


def test_keypoint_file_slips_are_refused_or_noted(tmp_path, weights, kp17, capsys):
    """A helper's trial: a 3D pose in a keypoint file was lifted with z read as a confidence; a COCO results list of
    several images was lifted as several people of one photo; a principal point equal to the image size, and y
    growing upward, were lifted without a word."""
    cam = {"focal": 1000.0, "principal_point": [640.0, 360.0], "image_size": [1280, 720], "format": "h36m17"}
    three_d = np.concatenate([kp17, np.full((17, 1), 4000.0)], 1)
    (tmp_path / "a.json").write_text(json.dumps({"keypoints": three_d.tolist(), **cam}))
    code, err = run([str(tmp_path / "a.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 1 and "like a coordinate: is this a 3D pose (x, y, z)?" in err
    rel = np.concatenate([kp17, np.linspace(-400, 300, 17)[:, None]], 1)  # root-relative z, mm: negative too
    (tmp_path / "a2.json").write_text(json.dumps({"keypoints": rel.tolist(), **cam}))
    code, err = run([str(tmp_path / "a2.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 1 and "is this a 3D pose" in err
    flags = np.concatenate([kp17, np.full((17, 1), 2.0)], 1)  # COCO visibility flags: read as flags, not scores
    flags[5, 2] = 1.0  # (labelled, hidden: placed all the same)
    (tmp_path / "b.json").write_text(json.dumps({"keypoints": flags.tolist(), **cam}))
    code, err = run([str(tmp_path / "b.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "unnormalised" not in err
    assert "third values all 0, 1 or 2: read as COCO visibility flags" in err  # (a user trial: scores of 2.0 came out)
    got = json.loads((tmp_path / "o" / "b.json").read_text())
    assert got["scores"] is None and got["people"][0]["scores"] is None
    ones = np.concatenate([kp17, np.ones((17, 1))], 1)  # no 2 among them: confidences
    (tmp_path / "b1.json").write_text(json.dumps({"keypoints": ones.tolist(), **cam}))
    code, err = run([str(tmp_path / "b1.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "visibility flags" not in err
    assert json.loads((tmp_path / "o" / "b1.json").read_text())["scores"] == [1.0] * 17
    scores = np.concatenate([kp17, np.linspace(0.5, 2.6, 17)[:, None]], 1)  # Detectron2-like scores above 1: read
    (tmp_path / "b2.json").write_text(json.dumps({"keypoints": scores.tolist(), **cam}))
    code, err = run([str(tmp_path / "b2.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "third values up to 2.6: read as a detector's unnormalised scores" in err
    coco = [v for r in coco_from_h36m(kp17) for v in (*r, 0.9)]
    (tmp_path / "c.json").write_text(json.dumps([{"image_id": i, "category_id": 1, "keypoints": coco} for i in (7, 8)]))
    code, err = run([str(tmp_path / "c.json"), "--weights", str(weights), "--out", str(tmp_path / "o"), "--focal",
                     "1000", "--principal-point", "640", "360"], capsys)
    assert code == 1 and "a list of people from 2 images (image_id 7, 8)" in err and "split the list by image_id" in err
    (tmp_path / "c2.json").write_text(json.dumps([{"image_id": i, "keypoints": coco} for i in (10, 9, 100)]))
    code, err = run([str(tmp_path / "c2.json"), "--weights", str(weights), "--out", str(tmp_path / "o"), "--focal",
                     "1000", "--principal-point", "640", "360"], capsys)
    assert code == 1 and "(image_id 9, 10, 100)" in err  # (in number order)
    (tmp_path / "d.json").write_text(json.dumps([{"image_id": 7, "category_id": 1, "keypoints": coco}] * 2))
    code, err = run([str(tmp_path / "d.json"), "--weights", str(weights), "--out", str(tmp_path / "o"), "--focal",
                     "1000", "--principal-point", "640", "360"], capsys)
    assert code == 0 and "2 people in the file" in err  # one image: its people
    (tmp_path / "e.json").write_text(json.dumps({"keypoints": kp17.tolist(), **cam, "principal_point": [1280, 720]}))
    code, err = run([str(tmp_path / "e.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "the principal point (1280, 720) px lies at the edge of the 1280 x 720 px image (it " \
        "equals the image size" in err
    import lifter

    walk = lifter.demo_sample("walking")  # (upright; the random fixture pose is not always)
    W, H = walk.image_size
    up = walk.keypoints_2d * [1, -1] + [0, H]
    wcam = {"focal": walk.focal.tolist(), "principal_point": walk.principal_point.tolist(), "image_size": [W, H]}
    (tmp_path / "f.json").write_text(json.dumps({"keypoints": up.tolist(), **wcam}))
    code, err = run([str(tmp_path / "f.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "the head is below both ankles in 1 of 1 pose(s)" in err
    (tmp_path / "g.json").write_text(json.dumps({"keypoints": walk.keypoints_2d.tolist(), **wcam}))
    code, err = run([str(tmp_path / "g.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 0 and "principal point" not in err and "head is below" not in err
    (tmp_path / "h.json").write_text(json.dumps({"kpts": kp17.tolist(), **cam}))
    code, err = run([str(tmp_path / "h.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)
    assert code == 1 and "(the file has 'kpts': did you mean 'keypoints'?)" in err
    (tmp_path / "i.json").write_text(json.dumps({"keypoints_2d": kp17.tolist(), **cam}))  # one person of our output
    assert run([str(tmp_path / "i.json"), "--weights", str(weights), "--out", str(tmp_path / "o")], capsys)[0] == 0


def test_mmpose_keypoint_scores_are_read_as_confidences(tmp_path, weights, kp17, capsys):
    """User trial: MMPose / RTMPose write the scores beside the keypoints (``keypoint_scores``); they were ignored, so
    a wrist scored 0 and placed 600 px away was lifted as given, with no note. They are now the joints' confidences:
    0 marks a joint missing, low ones are named, and the record carries them as the H36M joints' scores."""
    coco = coco_from_h36m(kp17)
    scores = [0.9] * 17
    cam = {"image_size": [1280, 720], "focal": 1000.0}
    wrist = COCO17_JOINT_NAMES.index("l_wrist")
    far = coco.copy()
    far[wrist] = [1200.0, 700.0]
    scores[wrist] = 0.0
    p = tmp_path / "mmpose.json"
    p.write_text(json.dumps([{"keypoints": far.tolist(), "keypoint_scores": scores, "bbox": [[0, 0, 10, 10]],
                              "bbox_score": 0.9}]))
    with pytest.raises(PoseLifterError, match=r"joint\(s\) missing .* \['l_wrist'\]"):
        parse_keypoint_json(p)
    scores[wrist] = 0.2  # seen, but unsure: lifted, named, and its score in the record
    p.write_text(json.dumps({"people": [{"keypoints": coco.tolist(), "keypoint_scores": scores}], "format": "coco17",
                             **cam}))
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0, err
    rec = json.loads((tmp_path / "o" / "mmpose.json").read_text())
    assert rec["source_format"] == "coco17" and rec["scores"][JOINT_NAMES.index("l_wrist")] == pytest.approx(0.2)
    assert rec["scores"][JOINT_NAMES.index("r_wrist")] == pytest.approx(0.9)
    assert any("unsure of some joints (score below 0.3): l_wrist (0.20)" in w for w in rec["warnings"]), rec["warnings"]
    # the same scores as third values give the same lift
    (tmp_path / "rows.json").write_text(json.dumps({"keypoints": np.column_stack([coco, scores]).tolist(),
                                                    "format": "coco17", **cam}))
    code, err = run([str(tmp_path / "rows.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    rows = json.loads((tmp_path / "o" / "rows.json").read_text())
    np.testing.assert_allclose(rows["absolute"], rec["absolute"])
    assert rows["scores"] == rec["scores"]
    for bad, msg in (({"keypoints": coco.tolist(), "keypoint_scores": scores[:5]},
                      "17 keypoints but 5 'keypoint_scores'"),
                     ({"keypoints": np.column_stack([coco, scores]).tolist(), "keypoint_scores": scores},
                      "both a third value in each 'keypoints' row and 'keypoint_scores'"),
                     ({"keypoints": coco.tolist(), "keypoint_scores": "high"}, "'keypoint_scores' must be a list"),
                     ({"keypoints": coco.ravel().tolist(), "keypoint_scores": scores[:16]},
                      "34 numbers in a flat 'keypoints' list but 16 'keypoint_scores'"),
                     ({"keypoints": np.column_stack([coco, scores]).ravel().tolist(), "keypoint_scores": scores},
                      r"both a confidence in its flat \[x, y, c, ...\] 'keypoints' and 'keypoint_scores'")):
        p.write_text(json.dumps({**bad, "format": "coco17"}))
        with pytest.raises(PoseLifterError, match=msg):
            parse_keypoint_json(p)


def test_a_hidden_ear_nose_or_openpose_mid_joint_is_stood_in_for(tmp_path, weights, kp17, capsys):
    """User trial: one ear hidden (any side view), a nose, or OpenPose's Neck / MidHip at confidence 0 got the whole
    person refused. They are stood in for (the other ear, the eyes, the midpoints of the shoulders and hips), with
    a note; a limb joint still is not."""
    from lifter.keypoints import EAR_EYE_SPACING, stand_in_missing
    from lifter.keypoints import OPENPOSE25_JOINT_NAMES as OP

    cam = {"image_size": [1280, 720], "focal": 1000.0}
    p = tmp_path / "op.json"
    p.write_text(json.dumps({"people": [_openpose_person(kp17, missing=("r_ear", "neck", "mid_hip"))], **cam}))
    kf = parse_keypoint_json(p)
    assert any("stood in for: r_ear from l_ear moved across by the eyes, neck from the shoulders' midpoint, mid_hip "
               "from the hips' midpoint" in w for w in kf.warnings), kf.warnings
    assert not any("lifter." in w for w in kf.warnings), kf.warnings  # (the app shows it: a browser trial)
    xy = kf.keypoints  # the hidden ear: the other one, moved across by EAR_EYE_SPACING times the eyes' spacing
    np.testing.assert_allclose(xy[OP.index("r_ear")], xy[OP.index("l_ear")]
                               + EAR_EYE_SPACING * (xy[OP.index("r_eye")] - xy[OP.index("l_eye")]))
    np.testing.assert_allclose(xy[OP.index("neck")], 0.5 * (xy[OP.index("l_shoulder")] + xy[OP.index("r_shoulder")]))
    assert kf.people_scores[0][OP.index("r_ear")] == pytest.approx(0.9)
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0 and "stood in for: r_ear from l_ear moved across by the eyes" in err, err
    # COCO without ears: the eyes stand in; without a nose too: the eyes for both
    coco = coco_from_h36m(kp17)
    rows = np.column_stack([coco, np.full(17, 0.9)])
    rows[[COCO17_JOINT_NAMES.index(n) for n in ("l_ear", "r_ear", "nose")], 2] = 0.0
    (tmp_path / "c.json").write_text(json.dumps({"keypoints": rows.tolist(), "format": "coco17", **cam}))
    kf = parse_keypoint_json(tmp_path / "c.json")
    eyes = 0.5 * (coco[COCO17_JOINT_NAMES.index("l_eye")] + coco[COCO17_JOINT_NAMES.index("r_eye")])
    for n in ("l_ear", "r_ear", "nose"):
        np.testing.assert_allclose(kf.keypoints[COCO17_JOINT_NAMES.index(n)], eyes)
    # a stand-in reads only joints that were given, and a limb joint has none
    missing = np.isin(np.array(COCO17_JOINT_NAMES), ("l_ear", "r_ear", "l_eye", "r_eye", "r_wrist"))
    _, still, _, said = stand_in_missing(coco, missing, src="coco17")
    assert [COCO17_JOINT_NAMES[k] for k in np.flatnonzero(still)] == ["l_eye", "r_eye", "l_ear", "r_ear", "r_wrist"]
    assert said == []
    rows[COCO17_JOINT_NAMES.index("r_wrist"), 2] = 0.0
    (tmp_path / "c.json").write_text(json.dumps({"keypoints": rows.tolist(), "format": "coco17", **cam}))
    with pytest.raises(PoseLifterError, match=r"joint\(s\) missing .* \['r_wrist'\]"):
        parse_keypoint_json(tmp_path / "c.json")
    # a sequence says it once, with the frames
    frames = [{"people": [_openpose_person(kp17 + [2.0 * i, 0.0], missing=("l_ear",) if i in (4, 9) else ()),
                          _openpose_person(0.5 * kp17 + [2.0 * i, 0.0], missing=("l_ear",) if i == 4 else ())]}
              for i in range(12)]  # (frame 4: two people stood in for; counted once)
    seq = tmp_path / "seq.json"
    seq.write_text(json.dumps({"fps": 25, **cam, "frames": frames}))
    code, err = run([str(seq), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0, err
    assert "stood in for: l_ear from r_ear moved across by the eyes in 2 frame(s) (first at frame 4)" in err, err
    assert "left out" not in err


def test_inputs_after_the_options_are_read_too(tmp_path, weights, kp17, capsys):
    """User trial: ``poselifter lift a.json --out DIR b.json`` failed with "unrecognized arguments: b.json" and the
    top-level usage. Inputs are read wherever they stand; an unknown option is still an error, from lift's parser."""
    for name in ("a", "b"):
        _kp_json(tmp_path / f"{name}.json", kp17)
    out = tmp_path / "o"
    code, err = run([str(tmp_path / "a.json"), "--out", str(out), "--weights", str(weights), str(tmp_path / "b.json")],
                    capsys)
    assert code == 0 and "lifted 2 of 2" in err, err
    assert (out / "a.json").is_file() and (out / "b.json").is_file()
    with pytest.raises(SystemExit) as exc:
        main(["lift", str(tmp_path / "a.json"), "--out", str(out), "--bogus", str(tmp_path / "b.json")])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and "usage: poselifter lift" in err and "unrecognized arguments: --bogus" in err, err


def test_near_miss_formats_get_messages_that_name_the_fix(tmp_path, kp17):
    """User trial: OpenPose's COCO-18 (54 numbers), an MMPose --save-predictions file and a .npy file got generic
    messages. The first and last now say what to do; MMPose's file of one frame is read (its instances, COCO-17,
    with their keypoint_scores), and one of several frames is refused with the sequence layout to use."""
    from lifter.detect import ImageError, load_image

    p = tmp_path / "k.json"
    p.write_text(json.dumps({"people": [{"pose_keypoints_2d": [1.0, 2.0, 0.9] * 18}]}))
    with pytest.raises(PoseLifterError, match="OpenPose's older COCO-18 model"):
        parse_keypoint_json(p)
    p.write_text(json.dumps({"keypoints": [[1.0, 2.0]] * 18}))
    with pytest.raises(PoseLifterError, match="18 joints per person.*OpenPose's older COCO-18 model"):
        parse_keypoint_json(p)
    coco = coco_from_h36m(kp17)
    inst = {"keypoints": coco.tolist(), "keypoint_scores": [0.9] * 17, "bbox": [[0, 0, 1, 1]], "bbox_score": 0.9}
    p.write_text(json.dumps({"meta_info": {"dataset_name": "coco"}, "instance_info": [{"frame_id": 1,
                                                                                        "instances": [inst]}]}))
    kf = parse_keypoint_json(p)
    assert kf.format == "coco17" and len(kf.people) == 1 and kf.people_scores[0] is not None
    np.testing.assert_allclose(kf.keypoints, coco)
    # its top-level fields beside the instances are read (the review: they were dropped, and the camera asked for)
    p.write_text(json.dumps({"meta_info": {}, "image_size": [1280, 720], "focal": 1000.0, "format": "coco17",
                             "instance_info": [inst]}))
    kf = parse_keypoint_json(p)
    assert kf.image_size == (1280, 720) and kf.focal is not None and float(np.ravel(kf.focal)[0]) == 1000.0
    assert kf.format == "coco17" and len(kf.people) == 1
    p.write_text(json.dumps({"meta_info": {}, "instance_info": [{"frame_id": i, "instances": [inst]} for i in (1, 2)]}))
    with pytest.raises(PoseLifterError, match=r"MMPose predictions file of 2 frames.*is a keypoint sequence.*--fps"):
        parse_keypoint_json(p)
    # MMPoseInferencer's predictions of a video (a list of {frame_id, instances}): one frame is read, several are
    # refused with the sequence layout, which then reads them (a trial: "no person in the keypoint file")
    video = [{"frame_id": i, "instances": [inst]} for i in range(3)]
    p.write_text(json.dumps(video[:1]))
    assert parse_keypoint_json(p).format == "coco17"
    p.write_text(json.dumps(video))
    with pytest.raises(PoseLifterError, match=r"MMPose predictions of 3 frames .*lift_keypoint_sequence\(path, fps="):
        parse_keypoint_json(p)
    from lifter.io import is_keypoint_sequence, parse_keypoint_sequence

    p.write_text(json.dumps({"frames": video, "fps": 25, "format": "coco17", "image_size": [1280, 720]}))
    ks = parse_keypoint_sequence(p)
    assert ks.format == "coco17" and [len(f) for f in ks.frames] == [1, 1, 1]
    # a developer trial: MMPose's predictions of a video were refused even with "fps" at the top level; they are a
    # sequence as they stand, their frame rate from the file or from fps= (--fps)
    p.write_text(json.dumps(video))
    assert is_keypoint_sequence(p)
    with pytest.raises(PoseLifterError, match=r"'fps' is missing.*--fps 30 on the command line"):
        parse_keypoint_sequence(p)
    ks = parse_keypoint_sequence(p, fps=30)
    assert ks.fps == 30 and ks.format == "coco17" and [len(f) for f in ks.frames] == [1, 1, 1]
    p.write_text(json.dumps({"meta_info": {}, "fps": 25, "image_size": [1280, 720],
                             "instance_info": [{"frame_id": i, "instances": [inst]} for i in (1, 2)]}))
    assert is_keypoint_sequence(p)
    ks = parse_keypoint_sequence(p, fps=30)  # (the file's own rate wins, with a note)
    assert ks.fps == 25 and ks.image_size == (1280, 720) and len(ks.frames) == 2
    assert "the file's own fps (25) is used, not --fps 30" in ks.warnings
    np.testing.assert_allclose(ks.frames[1][0], coco)
    assert ks.format == "coco17" and parse_keypoint_sequence(p, default_format="h36m17").format == "h36m17"  # (review)
    with pytest.raises(PoseLifterError, match=r"fps \(--fps\) must be the frame rate"):
        parse_keypoint_sequence(p, fps=0)
    npy = tmp_path / "kp.npy"
    np.save(npy, kp17)
    with pytest.raises(ImageError, match=r"if it holds keypoints, write them as a keypoint JSON file .* or lift the "
                                         r"arrays through the Python API \(lifter.Lifter.lift\)"):
        load_image(npy)


@pytest.mark.parametrize("meta", ["names", "dataset"])
def test_an_mmpose_file_is_read_in_the_joints_its_metadata_names(tmp_path, kp17, meta):
    """User trial: MMPose's predictions of an H36M model (``meta_info``: ``dataset_name`` "h36m" and
    ``keypoint_id2name`` in H36M's order) were read as COCO-17, their joints scrambled and the root 2 m off, exit 0.
    The joints the metadata names are read, in a single frame and in a sequence; COCO's metadata stays COCO-17."""
    from lifter.io import MMPOSE_JOINT_NAMES, parse_keypoint_sequence

    def info(fmt: str, dataset: str) -> dict:
        names = {str(i): n for i, n in enumerate(MMPOSE_JOINT_NAMES[fmt])}
        return {"keypoint_id2name": names} if meta == "names" else {"dataset_name": dataset, "num_keypoints": 17}

    inst = {"keypoints": kp17.tolist(), "keypoint_scores": [0.9] * 17}
    p = tmp_path / "h36m.json"
    p.write_text(json.dumps({"meta_info": info("h36m17", "h36m"), "instance_info": [inst]}))
    kf = parse_keypoint_json(p)
    assert kf.format == "h36m17" and not any("COCO" in w for w in kf.warnings), kf.warnings
    np.testing.assert_allclose(kf.keypoints, kp17)
    p.write_text(json.dumps({"meta_info": info("h36m17", "h36m"), "fps": 25,
                             "instance_info": [{"frame_id": i, "instances": [inst]} for i in (1, 2)]}))
    ks = parse_keypoint_sequence(p)
    assert ks.format == "h36m17" and len(ks.frames) == 2
    coco = coco_from_h36m(kp17)
    p.write_text(json.dumps({"meta_info": info("coco17", "coco"),
                             "instance_info": [{**inst, "keypoints": coco.tolist()}]}))
    assert parse_keypoint_json(p).format == "coco17"
    # the file's own 'format' and the caller's come first
    p.write_text(json.dumps({"meta_info": info("h36m17", "h36m"), "format": "coco17",
                             "instance_info": [{**inst, "keypoints": coco.tolist()}]}))
    assert parse_keypoint_json(p).format == "coco17"
    # the caller's format (--format) comes before the metadata's, in a single frame and in a sequence (a review: a
    # sequence took the metadata's over it)
    one = {"meta_info": info("h36m17", "h36m"), "instance_info": [{**inst, "keypoints": coco.tolist()}]}
    p.write_text(json.dumps(one))
    assert parse_keypoint_json(p, default_format="coco17").format == "coco17"
    p.write_text(json.dumps({"meta_info": info("h36m17", "h36m"), "fps": 25, "instance_info": [
        {"frame_id": i, "instances": [{**inst, "keypoints": coco.tolist()}]} for i in (1, 2)]}))
    ks = parse_keypoint_sequence(p, default_format="coco17")
    assert ks.format == "coco17" and not any("format" in w and "not read" in w for w in ks.warnings), ks.warnings
    np.testing.assert_allclose(ks.frames[0][0], coco_from_h36m(kp17))
    assert parse_keypoint_sequence(p).format == "h36m17"


def test_a_file_of_a_layout_that_holds_a_format_s_17_joints_says_which(tmp_path, kp17):
    """A user trial: Halpe-26, Human3.6M's 32 mocap joints and COCO-WholeBody's 133 got a bare joint-count error. The
    message names the layout and the 17 joints to write; the 17 at H36M32_INDICES are then read as H36M's."""
    from lifter.skeleton import H36M32_INDICES

    full = np.zeros((32, 2))
    full[list(H36M32_INDICES)] = kp17
    p = tmp_path / "k.json"
    for doc, said in (({"keypoints": full.tolist()}, "32 joints is Human3.6M's 32-joint mocap skeleton? The 17 joints "
                       "at lifter.skeleton.H36M32_INDICES are h36m17's: write those 17 with \"format\": \"h36m17\""),
                      ({"keypoints": [[1.0, 2.0]] * 133, "format": "coco17"}, "133 joints is COCO-WholeBody? The "
                       "first 17 joints (the body) are coco17's: write those 17 with \"format\": \"coco17\"")):
        p.write_text(json.dumps({**doc, "image_size": [1280, 720]}))
        with pytest.raises(PoseLifterError) as caught:
            parse_keypoint_json(p)
        assert said in str(caught.value), caught.value
    p.write_text(json.dumps({"keypoints": full[list(H36M32_INDICES)].tolist(), "format": "h36m17"}))
    np.testing.assert_allclose(parse_keypoint_json(p).keypoints, kp17)


def test_mmpose_frame_ids_keep_the_frames_a_tracker_left_out(tmp_path, weights, kp17, capsys):
    """A user trial: MMPose frames with frame_id 10-19 missing (a tracker lost the person) came out numbered 0..29,
    frame_id 20 as index 10 at 10 s of a 1-fps clip, and MMPose's demo (frame_id from 1) one frame early. Each frame's
    index is its frame_id less the first one's, its time_s index / fps; a first frame_id above 1 is noted."""
    from lifter.io import parse_keypoint_sequence

    coco = coco_from_h36m(kp17)
    inst = {"keypoints": coco.tolist(), "keypoint_scores": [0.9] * 17}
    kept = [i for i in range(30) if not 10 <= i < 20]
    p = tmp_path / "gap.json"
    for first in (0, 1):  # MMPoseInferencer from 0, MMPose's demo from 1
        p.write_text(json.dumps({"meta_info": {}, "fps": 1, "image_size": [1280, 720],
                                 "instance_info": [{"frame_id": i + first, "instances": [inst]} for i in kept]}))
        ks = parse_keypoint_sequence(p)
        assert ks.frame_indices == kept and not any("frame_id" in w for w in ks.warnings)
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0, err
    rec = json.loads((tmp_path / "o" / "gap.json").read_text())
    assert [(f["index"], f["time_s"]) for f in rec["frames"]] == [(i, float(i)) for i in kept]
    # in poselifter's own sequence layout too; a later start is said, consecutive ids are consecutive frames
    p.write_text(json.dumps({"fps": 2, "format": "coco17", "frames": [{"frame_id": i + 7, "instances": [inst]}
                                                                      for i in kept]}))
    ks = parse_keypoint_sequence(p)
    assert ks.frame_indices == kept
    assert any("first frame's 'frame_id' is 7: it is the output's frame 0" in w for w in ks.warnings)
    p.write_text(json.dumps({"fps": 2, "format": "coco17", "frames": [{"frame_id": i + 1, "instances": [inst]}
                                                                      for i in range(5)]}))
    assert parse_keypoint_sequence(p).frame_indices is None
    p.write_text(json.dumps({"fps": 2, "format": "coco17", "frames": [{"frame_id": i, "instances": [inst]}
                                                                      for i in (3, 2, 5)]}))
    ks = parse_keypoint_sequence(p)
    assert ks.frame_indices is None and any("'frame_id' do not increase" in w for w in ks.warnings)


def test_mmpose_inferencer_results_saved_as_they_come_are_read(tmp_path, kp17):
    """A user trial: MMPoseInferencer's result saved as it comes (``{"predictions": [[instance, ...]],
    "visualization": []}``) was "expected an object with 'keypoints'". One is a frame (COCO-17, its scores read), a
    list of them a video's frames, a sequence; a result of several images is refused, as one file is one image."""
    from lifter.io import is_keypoint_sequence, parse_keypoint_sequence

    coco = coco_from_h36m(kp17)
    inst = {"keypoints": coco.tolist(), "keypoint_scores": [0.9] * 17, "bbox": [[0, 0, 1, 1]], "bbox_score": 0.9}
    p = tmp_path / "r.json"
    p.write_text(json.dumps({"predictions": [[inst, {**inst, "keypoints": (coco * 0.5).tolist()}]],
                             "visualization": []}))
    kf = parse_keypoint_json(p)
    assert kf.format == "coco17" and len(kf.people) == 2 and kf.people_scores[0] is not None
    np.testing.assert_allclose(kf.keypoints, coco)
    assert not is_keypoint_sequence(p)
    p.write_text(json.dumps([{"predictions": [[inst]], "visualization": []} for _ in range(3)]))
    assert is_keypoint_sequence(p)
    ks = parse_keypoint_sequence(p, fps=30)
    assert ks.format == "coco17" and [len(f) for f in ks.frames] == [1, 1, 1]
    p.write_text(json.dumps({"predictions": [[inst], [inst]], "visualization": []}))
    with pytest.raises(PoseLifterError, match="expected an object with 'keypoints'"):
        parse_keypoint_json(p)
    # a review: COCO results with a 'predictions' field of their own were taken for the inferencer's, their own
    # keypoints left unread
    p.write_text(json.dumps([{"image_id": 1, "category_id": 1, "keypoints": np.c_[coco, np.full(17, 0.9)].ravel()
                              .tolist(), "score": 0.9, "predictions": [[0.1, 0.2]]}]))
    kf = parse_keypoint_json(p)
    assert kf.format == "coco17" and len(kf.people) == 1
    np.testing.assert_allclose(kf.keypoints, coco)


@pytest.mark.parametrize("doc, said", [
    ({"keypoints": None}, ": its 'keypoints' is null"),
    ([{"bogus": 1}], ": none of its 1 object(s) has 'keypoints' (a list of [x, y] or [x, y, confidence] rows); they "
                     "have 'bogus'"),
    ({"people": []}, "no person in the keypoint file"),
    # (a developer trial's bare list of frames: said to be a sequence missing its wrapper)
    ([{"people": [{"keypoints": [[1, 2]] * 17}]}], "they have 'people' (a list of frames, each with its 'people', is "
                                                   "a keypoint sequence: give it as {\"frames\": [...], \"fps\": 30})"),
    ([{"image_id": 1, "keypoints": []}], ": the 'keypoints' of its 1 object(s) are empty or null"),
    # (a frame where the detector found nobody: no more to say; a review read "none has 'keypoints'" for these)
    ([{"frame_id": 0, "instances": []}], "no person in the keypoint file"),
    ({"predictions": [[]], "visualization": []}, "no person in the keypoint file"),
])
def test_a_file_with_nobody_says_why(tmp_path, doc, said):
    """A user trial: ``{"keypoints": null}`` and objects without keypoints read "no person in the keypoint file", as
    a frame where nobody was found does. They say why; an empty 'people' is still nobody."""
    p = tmp_path / "n.json"
    p.write_text(json.dumps(doc))
    with pytest.raises(PoseLifterError) as caught:
        parse_keypoint_json(p)
    msg = str(caught.value)
    assert said in msg and (said != "no person in the keypoint file" or msg.endswith(said)), msg


def test_a_result_of_another_input_replaced_is_said(tmp_path, weights, kp17, capsys, monkeypatch):
    """User trial: clip.mp4 and then clip.avi lifted into one folder: the second run replaced clip.json silently.
    Replacing the result of another input is said; lifting the same input again is not."""
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    a, b = _kp_json(tmp_path / "a" / "k.json", kp17), _kp_json(tmp_path / "b" / "k.json", kp17 + 5)
    out = tmp_path / "o"
    for p in (a, a):
        code, err = run([str(p), "--out", str(out), "--weights", str(weights)], capsys)
        assert code == 0 and "replaces" not in err, err
    code, err = run([str(b), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 0 and f"note: replaces {out / 'k.json'}, the result of another input ({a}) written before" in err
    assert json.loads((out / "k.json").read_text())["input"] == str(b)
    # a relative input written from another folder: the same file name tells nothing (the review's false note)
    monkeypatch.chdir(tmp_path / "a")
    assert run(["k.json", "--out", str(out), "--weights", str(weights)], capsys)[0] == 0
    monkeypatch.chdir(tmp_path)
    code, err = run([str(a), "--out", str(out), "--weights", str(weights)], capsys)
    assert code == 0 and "replaces" not in err, err


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le", "utf-16-be", "utf-32", "utf-8-sig", "utf-16-le-no-bom",
                                   "utf-16-be-no-bom"])
def test_a_keypoint_file_in_utf16_with_its_byte_order_mark_is_read(tmp_path, weights, kp17, capsys, codec):
    """A user trial: a keypoint file written by Windows PowerShell's ``>`` (UTF-16 with a byte-order mark) was refused
    with a raw codec error. UTF-16 and UTF-32 with their mark are read as UTF-8 is, by content whatever the name; text
    in no encoding read is refused, naming UTF-8."""
    import codecs

    from lifter.video import input_kind

    text = json.dumps({"keypoints": kp17.tolist(), "image_size": [1280, 720]})
    bom = {"utf-16-le": codecs.BOM_UTF16_LE, "utf-16-be": codecs.BOM_UTF16_BE}.get(codec, b"")
    raw = bom + text.encode(codec.removesuffix("-no-bom"))  # (without a mark: told by the zero bytes, as json.loads)
    p = tmp_path / "ps.json"
    p.write_bytes(raw)
    np.testing.assert_allclose(parse_keypoint_json(p).keypoints, kp17)
    assert input_kind("ps.txt", raw[:512]) == ("keypoints", None)  # (by content: JSON text)
    code, err = run([str(p), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0, err
    p.write_bytes(text.encode("utf-16")[:-1])  # (truncated: named as the UTF-16 it says it is, a review)
    with pytest.raises(PoseLifterError, match=r"ps.json: not UTF-16-LE text, as its first bytes say it is"):
        parse_keypoint_json(p)
    p.write_bytes(b'{"keypoints": [], "name": "caf\xe9"}')  # (Latin-1)
    with pytest.raises(PoseLifterError, match=r"ps.json: not UTF-8 text, as its first bytes say it is \(.*\): save "
                                              r"the keypoint file as UTF-8"):
        parse_keypoint_json(p)


def test_hidden_files_pipes_and_devices_are_named_as_such(tmp_path, weights, kp17, capsys):
    """A user trial: macOS's ._x.json beside x.json was lifted (and failed, so --strict exited 1), and a pipe or a
    device was called "no such file or folder". Hidden files of a folder are skipped with a note; a path that exists
    but is neither a file nor a folder says so."""
    d = tmp_path / "mac"
    d.mkdir()
    _kp_json(d / "x.json", kp17)
    (d / "._x.json").write_bytes(b"\x00\x05\x16\x07Mac OS X")
    code, err = run([str(d), "--strict", "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0 and "lifted 1 of 1" in err, err
    assert f"{d}: skipped 1 hidden file(s) (names starting with '.', as macOS's ._ files; give one as an input to " \
           "lift it): ._x.json" in err
    (d / "._y.json").symlink_to(tmp_path / "gone.json")  # (a hidden dangling link: skipped too, a review)
    code, err = run([str(d), "--strict", "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 0 and "skipped 2 hidden file(s)" in err, err
    code, err = run([str(d / "._x.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code == 1 and "._x.json" in err and "no such file" not in err, err  # (named: read, and refused as such)
    fifo = tmp_path / "pipe.json"
    os.mkfifo(fifo)
    code, err = run([str(fifo), "--out", str(tmp_path / "o"), "--weights", str(weights)], capsys)
    assert code != 0 and f"{fifo}: not a regular file or folder (a pipe or a device?)" in err, err


def test_openpose_per_frame_files_are_lifted_as_one_sequence(tmp_path, weights, kp17, capsys):
    """A developer trial: a folder of OpenPose's --write_json output of a video (video_000000000000_keypoints.json,
    ...) was lifted as unrelated stills, untracked, each repeating its notes, and the command line had no way to give a
    frame rate. They are one keypoint sequence now, tracked and smoothed, at --fps; a gap in the numbers is kept."""
    d = tmp_path / "opdir"
    d.mkdir()
    other = kp17 * 0.7 + [300.0, 40.0]
    numbers = [0, 1, 2, 4, 5, 6, 7]  # (frame 3's file is missing)
    for n in numbers:
        people = [_openpose_person(kp17 + [2.0 * n, 0.0]), _openpose_person(other - [2.0 * n, 0.0])]
        (d / f"video_{n:012d}_keypoints.json").write_text(json.dumps({"version": 1.3, "people": people}))
    (d / "still_000000000000_keypoints.json").write_text(json.dumps({"people": [_openpose_person(kp17)]}))  # (one)
    base = ["--weights", str(weights), "--image-size", "1280", "720"]
    code, err = run([str(d), "--out", str(tmp_path / "a"), *base], capsys)  # (no frame rate: one by one, as before)
    assert code == 0 and "lifted 8 of 8" in err, err
    assert "7 OpenPose per-frame files (video_000000000000_keypoints.json ... video_000000000007_keypoints.json) " \
           "are lifted one by one; give their frame rate (--fps 30) to lift them as one tracked" in err
    code, err = run([str(d), "--out", str(tmp_path / "b"), "--fps", "30", *base], capsys)
    assert code == 0 and "lifted 2 of 2" in err, err
    assert "7 OpenPose per-frame files (video_000000000000_keypoints.json ... video_000000000007_keypoints.json) " \
           "are lifted as one keypoint sequence" in err
    out = json.loads((tmp_path / "b" / "video.json").read_text())
    assert out["kind"] == "keypoint-sequence" and out["fps"] == 30 and len(out["tracks"]) == 2
    assert [fr["index"] for fr in out["frames"]] == numbers
    assert [fr["time_s"] for fr in out["frames"]] == pytest.approx([n / 30 for n in numbers], abs=1e-4)  # (rounded)
    assert all(len(fr["people"]) == 2 for fr in out["frames"])
    from lifter.keypoints import convert

    last = np.reshape(_openpose_person(kp17 + [14.0, 0.0])["pose_keypoints_2d"], (25, 3))[:, :2]
    np.testing.assert_allclose(out["frames"][-1]["people"][0]["keypoints_2d"], convert(last, src="openpose25"),
                               atol=1e-3)
    assert json.loads((tmp_path / "b" / "still_000000000000_keypoints.json").read_text())["kind"] == "keypoints"
    # the pattern itself is an input, as OpenCV names image sequences
    code, err = run([str(d / "video_%012d_keypoints.json"), "--out", str(tmp_path / "c"), "--fps", "25", *base],
                    capsys)
    assert code == 0 and json.loads((tmp_path / "c" / "video.json").read_text())["fps"] == 25, err
    code, err = run([str(d), "--out", str(tmp_path / "e"), "--fps", "0", *base], capsys)
    assert code != 0 and "--fps must be the frame rate, a number in (0, 1000] frames/s, got 0.0" in err
    code, err = run([str(d), "--out", str(tmp_path / "e"), "--video-fps", "-5", *base], capsys)
    assert code != 0 and "--video-fps must be the frame rate, a number in (0, 1000] frames/s, got -5.0" in err
    # a review: two files given of a video's seven were read as all seven; a subset stays files
    two = [str(d / f"video_{n:012d}_keypoints.json") for n in (0, 1)]
    code, err = run([*two, "--out", str(tmp_path / "f"), "--fps", "30", *base], capsys)
    assert code == 0 and "lifted 2 of 2" in err and "lifted as one keypoint sequence" not in err, err
    # ... and says why, and how to lift a part as one (a user trial: a clip's frames picked out, no word)
    assert ("2 of the 7 OpenPose per-frame files of video are given: they are lifted one by one (a keypoint sequence "
            "is all of a video's files") in err and "copy those files into a folder of their own" in err, err
    sparse = [str(d / f"video_{n:012d}_keypoints.json") for n in (0, 7)]  # (not a clip: no such advice, a review)
    code, err = run([*sparse, "--out", str(tmp_path / "g"), "--fps", "30", *base], capsys)
    assert code == 0 and "2 of the 7 OpenPose" in err and "copy those files" not in err, err
    assert json.loads((tmp_path / "f" / "video_000000000001_keypoints.json").read_text())["kind"] == "keypoints"
    # ... and OpenPose's output for a folder of COCO images (numbers are image ids, sparse) stays stills
    coco = tmp_path / "coco"
    coco.mkdir()
    for n in (139, 285, 632):
        (coco / f"COCO_val2014_{n:012d}_keypoints.json").write_text(json.dumps({"people": [_openpose_person(kp17)]}))
    code, err = run([str(coco), "--out", str(tmp_path / "g"), "--fps", "30", *base], capsys)
    assert code == 0 and "lifted 3 of 3" in err and "OpenPose per-frame" not in err, err
    # a pattern is for keypoint files: images named so are not a video
    code, err = run([str(coco / "frame_%04d.jpg"), "--out", str(tmp_path / "h"), *base], capsys)
    assert code == 1 and "a frame pattern is read for keypoint files only" in err


def test_ctrl_c_while_a_sequence_is_written_names_what_of_it_is_whole(tmp_path, weights, kp17, capsys, monkeypatch):
    """Ctrl-C after a sequence's BVH is written but before its GLB (and its JSON, written last): the line says the
    BVH is whole and the rest not (a security trial's run said "interrupted after 0 of 1 input(s) lifted" with
    clip.json on disk)."""
    from lifter.video import SequenceRecord

    def interrupted(self, path):  # noqa: ARG001
        raise KeyboardInterrupt

    monkeypatch.setattr(SequenceRecord, "write_glb", interrupted)
    seq = tmp_path / "clip.json"
    seq.write_text(json.dumps({"fps": 25, "format": "h36m17", "image_size": [1280, 720], "focal": 1000.0,
                               "frames": [kp17.tolist()] * 3}))
    code = main(["lift", str(seq), "--out", str(tmp_path / "o"), "--glb", "--bvh", "--weights", str(weights)])
    err = capsys.readouterr().err
    assert code == 130, err
    assert (f"interrupted after 0 of 1 input(s) lifted into {tmp_path / 'o'}; {seq}'s outputs were being written: "
            "clip_track1.bvh is whole, the rest of them not written") in err, err
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["clip_track1.bvh"]


def test_ctrl_c_while_an_earlier_run_s_outputs_are_tidied_counts_the_input(tmp_path, weights, kp17, capsys,
                                                                             monkeypatch):
    """Ctrl-C after an input's outputs are whole, while an earlier run's of it are tidied away: that input counts as
    lifted (a review: "interrupted after 0 of 1" with every output whole)."""
    import lifter.cli.lift as lift_cli

    (tmp_path / "a.json").write_text(json.dumps({"keypoints": kp17.tolist(), "focal": 1000.0,
                                                 "image_size": [1280, 720]}))
    argv = ["lift", str(tmp_path / "a.json"), "--out", str(tmp_path / "o"), "--weights", str(weights)]
    assert main(argv) == 0

    def interrupted(*a, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(lift_cli, "tidy_earlier_outputs", interrupted)
    capsys.readouterr()
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert "interrupted after 1 of 1 input(s) lifted" in err and "were being written" not in err, err
