"""The app plays uploaded videos and keypoint sequences (issue 14): every person of every frame lifted, tracked and
smoothed (lifter.video), the frames played like a Human3.6M sequence with each track's root trajectory."""

from __future__ import annotations

import contextlib
import json
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np
import pytest

pytest.importorskip("viser")

from conftest import ScriptedEstimator, fail_once, hold  # noqa: E402
from poselifter_app import video as vid  # noqa: E402
from poselifter_app.testing import wait_for  # noqa: E402
from poselifter_app.viewer import PoseLifterApp  # noqa: E402

from lifter import project  # noqa: E402

W, H, F = 640, 480, 600.0



def _script(n: int, *, nobody: tuple[int, ...] = ()) -> list[list[np.ndarray]]:
    """Two people 4 m and 6 m away walking sideways in opposite directions; nobody in frames ``nobody``."""
    from lifter import demo_sample

    pose = demo_sample("standing").pose_3d
    rel = pose - pose[0]
    out = []
    for i in range(n):
        if i in nobody:
            out.append([])
            continue
        a = rel + [-900.0 + 40 * i, 0.0, 4000.0]
        b = rel + [1200.0 - 40 * i, 0.0, 6000.0]
        out.append([project(p, focal=F, principal_point=(W / 2, H / 2)) for p in (a, b)])
    return out


def _clip(path: Path, n: int, fps: float = 25.0) -> bytes:
    vw = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), fps, (W, H))
    assert vw.isOpened()
    for i in range(n):
        vw.write(np.full((H, W, 3), 40 + 7 * i % 200, np.uint8))
    vw.release()
    return path.read_bytes()


def _sequence_doc(n: int) -> dict:
    """A keypoint sequence upload of :func:`_script`'s two people, ``n`` frames at 10 fps."""
    frames = [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(n)]
    return {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}


@contextlib.contextmanager
def _held_upload(monkeypatch, v, name: str, doc: dict) -> Iterator[list[bool]]:
    """Upload the keypoint sequence ``doc`` as ``name`` on a thread, its lift held until the block ends (what the
    block does happens while it is being lifted); yields the list that gets ``load_upload``'s result."""
    import threading

    lifting, go = hold(monkeypatch, vid, "video_sequence")
    done: list[bool] = []
    t = threading.Thread(target=lambda: done.append(v.load_upload(name, json.dumps(doc).encode())))
    t.start()
    try:
        assert lifting.wait(30)
        yield done
    finally:
        go.set()
        t.join(60)


def test_video_upload_plays_with_every_person_and_trajectories(server, tmp_path: Path) -> None:
    n = 14
    est = ScriptedEstimator(_script(n, nobody=(6,)), full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
    v = app.headless_view()
    assert v.load_upload("walk.avi", _clip(tmp_path / "walk.avi", n)) is True, v.messages[-3:]
    seq = v.sequence()
    assert isinstance(seq, vid.VideoSequence) and seq.num_frames == n - 1 and seq.fps == pytest.approx(25.0)
    assert "13 frames" not in seq.label and "14 frames" in seq.label and "2 tracks" in seq.label
    assert any("nobody" in w for w in seq.info.warnings)
    st = v.state
    assert st.sample.key == f"{seq.key}/0" and st.sample.num_people == 2 and st.person == 0
    assert list(v.gui.joints.person.options) == ["person 1 (track 1)", "person 2 (track 2)"]  # the tracks' ids
    assert v.gui.sample.source.value == "upload" and not v.gui.play.frame.disabled and v.gui.play.frame.max == n - 2
    # every person is lifted into the same camera space: the near one ~4 m, the far one ~6 m
    assert 3000 < v.frame.root[2] < 5000 and 5000 < v.frame.others[0].root[2] < 7500
    assert "**People** 2" in v.gui.readout.readout.content and "video, scripted" in v.gui.readout.readout.content
    assert "person 2 (track 2): root X" in v.gui.readout.readout.content  # (named as the person picker names them)
    # (a trial: only the selected person's root line said it is this frame's own lift, unsmoothed)
    assert "roots: this frame's own lifts, unsmoothed" in v.gui.readout.readout.content
    assert "(this frame's own lift: the download's `root_unsmoothed`; its `root` is smoothed along the track" in \
        v.gui.readout.readout.content  # (a user trial: the numbers differed from the download's root, unexplained)
    assert "press play" in v.messages[-1]
    # each track's root trajectory, smoothed: two paths of 12 segments (the empty frame is left out)
    trail = v.scene.camera.trail
    assert trail.visible and np.asarray(trail.points).shape == (2 * (n - 2), 2, 3)
    tracks = seq.trajectories(app.pool.get(st.model), st.focal)
    assert len(tracks) == 2 and all(len(t) == n - 1 for t in tracks)
    x = np.array([tracks[0][i][0] for i in range(n - 1)])
    assert np.all(np.diff(x) > 0)  # track 1 walks to the right the whole time (a stable track id)
    # scrubbing: the frame slider shows that frame, focal length kept
    v.gui.lift.focal.value = 800.0
    assert wait_for(lambda: abs(v.state.focal_px - 800.0) < 1e-6)
    v.gui.play.frame.value = 5
    assert wait_for(lambda: v.state.sample.key == f"{seq.key}/5")
    assert v.state.focal_px == pytest.approx(800.0) and v.state.sample.image.shape[1] <= vid.VIDEO_DISPLAY_MAX_SIDE
    # the trajectories follow the focal length in use (recomputed, not the upload's)
    moved = seq.trajectories(app.pool.get(v.state.model), v.state.focal)
    assert moved is not tracks and moved[0][0][2] > tracks[0][0][2]
    # play: frames advance; pause stops
    assert v.toggle_play() is True
    assert wait_for(lambda: v.state.sample.key != f"{seq.key}/5", timeout=10)
    v.stop_playback()
    assert not v.playing
    # downloads: the whole sequence as `poselifter lift clip.mp4 [--glb]` writes it
    name, data = v.download_payload("json")
    rec = json.loads(data)
    assert name == "walk_avi_lifted.json" and rec["fps"] == pytest.approx(25.0) and len(rec["frames"]) == n
    assert sorted(t["track_id"] for t in rec["tracks"]) == sorted({p["track_id"] for f in rec["frames"] for p in
                                                                   f["people"]}) and len(rec["tracks"]) == 2
    # ... at the focal length the tab shows (800 px, set above), not the upload's: a user trial's download kept
    # the upload's while the readout showed another
    assert np.sqrt(np.prod(rec["focal"])) == pytest.approx(800.0, abs=0.01) and rec["focal_source"] == "app-slider"
    assert any("lifted again in the app" in w and "800.0 px" in w for w in rec["warnings"]), rec["warnings"]
    # (a user trial) the upload's assumed focal is no longer said beside the one used
    assert any(w.startswith("no focal length given: assumed") for w in seq.record.warnings)
    assert not any(w.startswith("no focal length given: assumed") for w in rec["warnings"]), rec["warnings"]
    first = next(p for p in rec["frames"][0]["people"] if p["track_id"] == 1)
    np.testing.assert_allclose(first["root"], moved[0][0], atol=0.06)  # (the file rounds to 0.1 mm)
    name, glb = v.download_payload("glb")
    from lifter.export import read_glb_animation

    path = tmp_path / name
    path.write_bytes(glb)
    times, anim = read_glb_animation(path)
    assert len(anim) == 2 and len(times) == n
    # another source and back: the same frame again
    shown = v.state.sample.key
    v.gui.sample.source.value = "demo sample"
    assert wait_for(lambda: v.state.sample.key.startswith("demo/"))
    v.gui.sample.source.value = "upload"
    assert wait_for(lambda: v.state.sample.key == shown)


def test_a_sequence_lifted_again_says_its_own_root_steps(server) -> None:
    """A review: the app's lift at another focal dropped the upload's root-step note but nothing tested that it says
    its own. One name on the person 4 m away, then on the one 6 m away: both lifts name the step, each its own."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": people[0 if i < 30 else 1].tolist(), "person_id": "ann"}]}
              for i, people in enumerate(_script(60))]
    doc = {"fps": 50, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames, "source": "clean"}
    assert v.load_upload("steps.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert seq is not None
    own = [w for w in seq.record.warnings if w.startswith("track 1: its root moves ")]
    assert len(own) == 1 and "between frames 29 and 30" in own[0], seq.record.warnings
    again = seq.record_at(app.pool.get(v.state.model), (2 * F, 2 * F))
    new = [w for w in again.warnings if w.startswith("track 1: its root moves ")]
    assert len(new) == 1 and "between frames 29 and 30" in new[0] and new != own, (own, new)


def test_bad_videos_keep_the_tab(server, tmp_path: Path) -> None:
    est = ScriptedEstimator(_script(4), full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
    v = app.headless_view()
    key = v.state.sample.key
    assert v.load_upload("broken.mp4", b"\x00\x01 not a video" * 50) is False
    assert "cannot open as a video" in v.messages[-1] and "broken.mp4" in v.messages[-1]
    assert "poselifter-upload" not in v.messages[-1]  # (the temporary path is not shown)
    assert v.load_upload("empty.mp4", b"") is False and "empty file" in v.messages[-1]
    est.script = [[] for _ in range(4)]
    est.n = 0
    assert v.load_upload("room.avi", _clip(tmp_path / "room.avi", 4)) is False
    assert "room.avi: no person found by the scripted 2D detector in any of the 4 frames" in v.messages[-1]
    assert v.state.sample.key == key and v.sequence() is None


def test_a_video_waiting_for_the_detector_says_so_and_a_closed_tab_s_video_stops(server, tmp_path: Path) -> None:
    """A security review: a photo waited minutes behind another tab's video with nothing said, and a closed tab's
    video went on holding the detector every tab shares to its last frame."""
    import threading

    est = ScriptedEstimator(_script(8), full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
    v = app.headless_view()
    clip = _clip(tmp_path / "walk.avi", 8)
    key = v.state.sample.key
    shown: list[str] = []
    app.detect_lock.acquire()  # (another tab's upload is being lifted)
    try:
        done = threading.Thread(target=v.load_upload, args=("walk.avi", clip))
        done.start()
        assert wait_for(lambda: "waiting for the detector" in v.gui.readout.status.content)
        shown.append(v.gui.readout.status.content)
    finally:
        app.detect_lock.release()
    done.join(timeout=60)
    assert "⏳ walk.avi: waiting for the detector: another upload (of this tab or another) is being lifted" == shown[0]
    assert v.sequence() is not None and len(v.sequence().frames) == 8  # (then lifted)
    # the tab goes: its video stops at the next frame, and the tab's state is left as it was
    v2 = app.headless_view()
    key2 = v2.state.sample.key
    v2.gone = True
    est.n = 0
    assert v2.load_upload("walk2.avi", clip) is False
    assert "walk2.avi: the tab was closed; lifting stopped" in v2.messages[-1]
    assert v2.state.sample.key == key2 and est.n <= 1
    assert key != v.state.sample.key


def test_a_misnamed_photo_or_video_upload_is_shown_as_what_it_holds(server, tmp_path: Path) -> None:
    """A browser trial: a JPEG renamed .mp4 played as a one-frame video, and a video named .jpg was refused as "not an
    image". Each is now shown as what its bytes hold, and the upload's message says so."""
    import io

    from PIL import Image

    est = ScriptedEstimator(_script(6), full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
    v = app.headless_view()
    assert v.load_upload("walk.jpg", _clip(tmp_path / "walk.avi", 6)) is True, v.messages[-3:]
    seq = v.sequence()
    assert isinstance(seq, vid.VideoSequence) and seq.num_frames == 6 and not v.gui.play.play.disabled
    assert seq.info.warnings[0] == "walk.jpg holds a video, not an image as its name says: lifted as a video"
    assert any("walk.jpg holds a video" in m for m in v.messages[-3:])
    assert v.download_payload("json")[0].startswith("walk_jpg_lifted")  # (a video's download keeps its file type)
    buf = io.BytesIO()
    Image.new("RGB", (W, H), (40, 40, 40)).save(buf, format="JPEG")
    est.n = 0
    assert v.load_upload("still.mp4", buf.getvalue()) is True, v.messages[-3:]
    assert v.sequence() is None and v.state.sample.upload.kind == "image" and v.gui.play.play.disabled
    assert "Note: still.mp4 holds an image, not a video as its name says: lifted as a photo." in v.messages[-1]
    assert v.download_payload("json")[0].startswith("still_lifted")  # (a photo's does not)
    # a later trial: keypoint JSON named .mp4 was tried as a video, and a JPEG named .json refused as not UTF-8
    est.n = 0
    assert v.load_upload("photo.json", buf.getvalue()) is True, v.messages[-3:]
    assert v.sequence() is None and v.state.sample.upload.kind == "image"
    assert "Note: photo.json holds an image, not keypoint JSON as its name says: lifted as a photo." in v.messages[-1]
    kp = _script(1)[0][0]
    doc = {"keypoints": kp.tolist(), "format": "h36m17", "focal": F, "image_size": [W, H]}
    assert v.load_upload("pose.mp4", json.dumps(doc).encode()) is True, v.messages[-3:]
    assert v.sequence() is None and v.state.sample.upload.kind == "keypoints"
    np.testing.assert_allclose(v.state.sample.keypoints_2d, kp)
    assert "pose.mp4 holds keypoint JSON, not a video as its name says: lifted as a keypoint file" in v.messages[-1]


def test_keypoint_sequence_upload_plays_on_a_canvas(server, monkeypatch) -> None:
    nobody = ScriptedEstimator([[]], full_width=W)  # (photos: decoded and kept, nobody found)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: nobody)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(10)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("walk.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert isinstance(seq, vid.VideoSequence) and seq.num_frames == 10 and seq.jpegs is None
    assert v.state.sample.num_people == 2 and v.state.focal_px == pytest.approx(F)
    assert 3000 < v.frame.root[2] < 5000
    _, payload = v.download_payload("json")  # the user's file name, not the server's temporary copy (user trial)
    assert json.loads(payload)["input"] == "walk.json"
    # MMPose's predictions of a video, with its rate at the top level, play too (a developer trial: refused)
    mm = {"meta_info": {}, "fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17",
          "instance_info": [{"frame_id": i, "instances": [{"keypoints": p.tolist(), "keypoint_scores": [0.9] * 17}
                                                          for p in people]} for i, people in enumerate(_script(10))]}
    assert v.load_upload("mmpose.json", json.dumps(mm).encode()) is True, v.messages[-3:]
    mseq = v.sequence()
    assert isinstance(mseq, vid.VideoSequence) and mseq.num_frames == 10 and v.state.sample.num_people == 2
    # a browser trial: MMPose's own file has neither "fps" nor "image_size", and the app has no control for either.
    # The app assumes 30 frames/s, and takes the size of the photo uploaded before, each with a note
    del mm["fps"], mm["image_size"]
    assert v.load_upload("bare.json", json.dumps(mm).encode()) is False  # (no photo yet: no size, no principal point)
    assert "image_size" in v.messages[-1] and "--" not in v.messages[-1], v.messages[-1]
    assert "or upload the photo the keypoints were found in first" in v.messages[-1]  # (a browser trial)
    import io

    from PIL import Image

    buf = io.BytesIO()
    Image.new("RGB", (W, H), (60, 60, 60)).save(buf, format="JPEG")
    assert v.load_upload("room.jpg", buf.getvalue()) is False  # (nobody found: not shown, but kept, as for a file)
    import lifter.io as lio

    reads: list[object] = []
    monkeypatch.setattr(lio, "_load_json", lambda p, _load=lio._load_json: reads.append(p) or _load(p))
    assert v.load_upload("bare.json", json.dumps(mm).encode()) is True, v.messages[-3:]
    assert len(reads) == 1, reads  # (the reader reads the upload once: the app's defaults are the lift's own)
    monkeypatch.undo()
    bare = v.sequence()
    assert isinstance(bare, vid.VideoSequence) and bare.record.fps == 30 and bare.record.image_size == (W, H)
    assert bare.info.warnings[:2] == (
        "the file gives no frame rate: assumed 30 frames/s for playback and smoothing (give \"fps\" at the file's top "
        "level)", f"no image_size in the file: that of the photo room.jpg uploaded before ({W} x {H} px) is used")
    said = next(m for m in reversed(v.messages) if m.startswith("bare.json"))
    assert said.count("\n\nNote, as uploaded: ") >= 2, said  # (each its own paragraph: a browser trial read a run-on
    # one; each the upload's: a later trial read a root step's metres, stale after a focal change, as current)
    assert v.frame.root == pytest.approx(seq.record.frames[0].people[0].root, abs=1e-3)  # (the same camera: the same)
    assert v.load_upload("mmpose.json", json.dumps({**mm, "fps": 10, "image_size": [W, H]}).encode()) is True
    assert v.frame.root == pytest.approx(seq.record.frames[0].people[0].root, abs=1e-3)  # (the same lift)
    # a review: the photo's size was taken for a file whose camera is a K matrix (its principal point read), and for
    # poses that do not fit the photo (another image's pixels: ~3 m off in depth)
    K = [[F, 0.0, W], [0.0, F, H], [0.0, 0.0, 1.0]]
    assert v.load_upload("k.json", json.dumps({**mm, "K": K}).encode()) is True, v.messages[-3:]
    ksq = v.sequence()
    assert ksq is not None and ksq.record.image_size == (2 * W, 2 * H)  # (twice its principal point, not the photo)
    assert not any("room.jpg" in w for w in ksq.info.warnings), ksq.info.warnings
    big = json.loads(json.dumps(mm))
    for fr in big["instance_info"]:
        for q in fr["instances"]:
            q["keypoints"] = (np.asarray(q["keypoints"]) * 3 + [W, H]).tolist()
    key = v.state.sample.key
    assert v.load_upload("big.json", json.dumps(big).encode()) is False
    assert f"its poses lie mostly outside the photo room.jpg uploaded before ({W} x {H} px)" in v.messages[-1]
    assert v.state.sample.key == key  # (the tab keeps what it showed)
    huge = b'{"fps": 10, "frames": [], "n": ' + b"9" * 5000 + b"}"  # (an integer too long for Python's JSON reader)
    assert v.load_upload("huge.json", huge) is False and "internal error" not in v.messages[-1], v.messages[-1]
    assert v.load_upload("walk.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    no_size = dict(doc)
    del no_size["image_size"]
    assert v.load_upload("nosize.json", json.dumps(no_size).encode()) is True  # (room.jpg above gives its size)
    nosize = v.sequence()
    assert nosize is not None and nosize.record.image_size == (W, H)
    # with a principal point but no image size (which poselifter lift accepts), the canvas is twice the principal
    # point, as for a single keypoint file, and a note says so (a user trial's sequence was refused)
    no_size["principal_point"] = [W / 2 + 10, H / 2 - 20]
    assert v.load_upload("pp.json", json.dumps(no_size).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert seq is not None and seq.record.image_size == (W + 20, H - 40)
    assert any("assumed" in w and "twice the principal point" in w for w in seq.info.warnings), seq.info.warnings
    # an OpenCV lens (the app's cameras have Human3.6M's lens model; it was refused): undone as the file is read,
    # so the app shows and re-lifts the pinhole 2D, and the lift is the pinhole 2D's
    assert v.load_upload("walk.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    plain = v.sequence()
    assert plain is not None
    dist = np.array([-0.3, 0.05, 0.001, -0.002, 0.003])
    K = np.array([[F, 0.0, W / 2], [0.0, F, H / 2], [0.0, 0.0, 1.0]])

    def through_lens(uv: list[float]) -> list[list[float]]:
        rays = np.c_[(np.asarray(uv) - [W / 2, H / 2]) / F, np.ones(len(uv))]
        return cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, dist)[0].reshape(-1, 2).tolist()

    lensed = dict(doc, distortion=dist.tolist(), distortion_model="opencv",
                  frames=[{"people": [{"keypoints": through_lens(q["keypoints"])} for q in fr["people"]]}
                          for fr in frames])
    assert v.load_upload("lens.json", json.dumps(lensed).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert seq is not None and seq.record.distortion is None and seq.camera.distortion is None
    assert any("OpenCV lens" in w and "undone as the file is read" in w for w in seq.info.warnings)
    moved = 0.0
    for fr, ref, given in zip(seq.record.frames, plain.record.frames, lensed["frames"]):
        for q, r, g in zip(fr.people, ref.people, given["people"]):
            np.testing.assert_allclose(q.keypoints_2d, r.keypoints_2d, atol=1e-5)  # the pinhole 2D again
            np.testing.assert_allclose(q.root, r.root, atol=1e-3)
            moved = max(moved, float(np.abs(np.asarray(g["keypoints"]) - r.keypoints_2d).max()))
    assert moved > 3.0  # (the lens moved the 2D by px: undoing it matters)
    again = seq.record_at(app.pool.get(v.state.model), (2 * F, 2 * F))  # re-lifted at another focal: lens-free
    ref = plain.record_at(app.pool.get(v.state.model), (2 * F, 2 * F))
    np.testing.assert_allclose(again.frames[3].people[0].root, ref.frames[3].people[0].root, atol=1e-3)


def test_a_keypoint_sequence_in_the_photo_s_pixels_takes_its_exif_focal(server) -> None:
    """As for a single keypoint file: a sequence with no focal and no image size, uploaded after the photo it was
    found in, takes that photo's size and its EXIF focal length (it took the default field of view: a known gap)."""
    import io

    from PIL import Image

    from lifter.detect import ExifCamera, guess_focal

    nobody = ScriptedEstimator([[]], full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: nobody)
    v = app.headless_view()
    exif = Image.new("RGB", (1, 1)).getexif()
    exif.get_ifd(0x8769)[41989] = 26
    buf = io.BytesIO()
    Image.new("RGB", (W, H), (60, 60, 60)).save(buf, format="JPEG", exif=exif.tobytes())
    assert v.load_upload("phone.jpg", buf.getvalue()) is False  # (nobody found: kept for the file after it)
    frames = [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(10)]
    assert v.load_upload("seq.json", json.dumps({"fps": 10, "format": "h36m17", "frames": frames}).encode()) is True, \
        v.messages[-3:]
    seq = v.sequence()
    want = guess_focal((W, H), exif=ExifCamera(focal_35mm=26.0))
    assert seq is not None and seq.record.image_size == (W, H) and seq.info.focal_source == "exif-35mm"
    assert v.state.focal_px == pytest.approx(want.focal, rel=1e-6)
    assert "EXIF" in seq.info.focal_detail and "EXIF" in v.gui.readout.readout.content


def test_a_sequence_lifted_again_keeps_person_ids_and_replaces_output_notes(server) -> None:
    """A review: the download at another focal lost each person's person_id, and kept the upload's notes on its
    lift's output while dropping the new lift's. Now ids are kept, the output notes are the new lift's, and the
    upload's own focal within 0.5 px (the box shows 0.1 px) is the upload's record."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist(), "person_id": name} for p, name in zip(people, ("ann", "bob"))]}
              for people in _script(6)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("ids.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert seq is not None
    lf = app.pool.get(v.state.model)
    assert seq.record_at(lf, (F + 0.3, F + 0.3)) is seq.record  # (the upload's focal, as the box shows it)
    ids = [[p.person_id for p in fr.people] for fr in seq.record.frames]
    assert ids[0] == ["ann", "bob"]
    again = seq.record_at(lf, (2 * F, 2 * F))
    assert [[p.person_id for p in fr.people] for fr in again.frames] == ids
    assert again.focal_source == "app-slider" and any("lifted again in the app" in w for w in again.warnings)
    # a note on the upload's lift's output ("frame N: ..." lines) does not describe another lift: it is dropped
    from dataclasses import replace

    stale = "frame 0: the model placed 1 of 2 root(s) behind the camera (Z <= 0)"
    seq.record = replace(seq.record, warnings=[*seq.record.warnings, stale])
    step = ("track 1: its root moves 0.95 m between frames 2 and 3 and stays there (the median of the 2 frames either "
            "side): two people under one track")  # (the upload's lift's roots: also a note on its output)
    seq.record = replace(seq.record, warnings=[*seq.record.warnings, step])
    relifted = seq.record_at(lf, (3 * F, 3 * F))
    assert stale not in relifted.warnings and stale in seq.record.warnings
    assert step not in relifted.warnings
    assert all(w in relifted.warnings for w in seq.record.warnings if w not in (stale, step))
    # the new lift's own notes name the people by track id, as poselifter lift's do (not by place in a frame)
    far = seq.record_at(lf, (20 * F, 20 * F))
    notes = [w for w in far.warnings if "lifted beyond" in w]
    assert len(notes) == 1 and notes[0].startswith("frame 0: 2 of 2 root(s) lifted beyond") and \
        "(track 1, and 1 more)" in notes[0], far.warnings


def test_a_sequence_lifted_again_with_another_model_says_which_in_model_info(server) -> None:
    """The download of a sequence lifted again names the networks of the model that lifted it, not the upload's."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17",
           "frames": [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(3)]}
    assert v.load_upload("which.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert seq is not None
    first = app.pool.get(v.state.model)
    assert seq.record.to_dict()["model_info"] == first.provenance()
    other = app.pool.get("universal_turn")
    again = seq.record_at(other, (F, F)).to_dict()
    assert again["model"] == "universal_turn" and again["model_info"] == other.provenance()
    assert again["model_info"]["networks"][0]["sha256"] != first.provenance()["networks"][0]["sha256"]


def test_a_video_note_goes_when_another_sample_is_shown(server, tmp_path: Path) -> None:
    """A browser trial: right after a video's note ("... press play"), switching the source to Human3.6M left the
    note under the Human3.6M frame (a note stays a while, and no later event cleared it). A sync pass that shows
    another sample, or sequence, and says nothing of its own now clears it; frames of the same video keep it."""
    n = 8
    est = ScriptedEstimator(_script(n), full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
    v = app.headless_view()
    assert v.load_upload("walk.avi", _clip(tmp_path / "walk.avi", n)) is True, v.messages[-3:]
    seq = v.sequence()
    assert seq is not None and "press play" in v.gui.readout.status.content
    v.gui.play.frame.value = 3  # another frame of the same video: the note stays (within its time)
    assert wait_for(lambda: v.state.sample.key == f"{seq.key}/3")
    assert "press play" in v.gui.readout.status.content
    v.gui.sample.source.value = "demo sample"  # at once, well within the note's time
    assert wait_for(lambda: v.state.sample.key.startswith("demo/"))
    assert wait_for(lambda: v.gui.readout.status.content == ""), v.gui.readout.status.content


def test_a_video_lifted_again_keeps_the_upload_s_track_ids(server, tmp_path: Path) -> None:
    """A review: lifting a video again in the app (another focal) re-tracked it, and once the upload had left out a
    one-frame detection the tracker numbered the tracks differently, so the download's notes and the person
    picker named tracks the download did not have. The upload's track ids are kept."""
    n = 12
    both = _script(n)
    flash = [p + [150.0, -60.0] for p in both[2][:1]]
    script = [[both[i][0]] + (flash if i == 2 else []) + ([both[i][1]] if i >= 5 else []) for i in range(n)]
    est = ScriptedEstimator(script, full_width=W)
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
    v = app.headless_view()
    assert v.load_upload("walk.avi", _clip(tmp_path / "walk.avi", n)) is True, v.messages[-3:]
    seq = v.sequence()
    assert isinstance(seq, vid.VideoSequence)
    ids = sorted({p.track_id for fr in seq.record.frames for p in fr.people})
    assert ids == [1, 2], ids  # (the flash, left out, took a number of the tracker's: no gap is left for it)
    again = seq.record_at(app.pool.get(v.state.model), (F * 1.5, F * 1.5))
    assert again is not seq.record
    assert [[p.track_id for p in fr.people] for fr in again.frames] == \
        [[p.track_id for p in fr.people] for fr in seq.record.frames]


def test_a_focal_chosen_for_one_upload_is_not_kept_for_the_next(server) -> None:
    """The review of the calibration match (a focal chosen on one Human3.6M camera is kept across its subjects): two
    uploaded sequences of one image size and an assumed focal are not one camera. The focal chosen for the first is
    replaced by the second's, and said."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(6)]
    doc = {"fps": 10, "image_size": [W, H], "format": "h36m17", "frames": frames}
    assert v.load_upload("first.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    assumed = v.state.focal_px
    assert v.set_focal(3000.0) is True and v.state.focal_px == 3000.0
    assert v.load_upload("second.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    assert v.state.focal_px == pytest.approx(assumed)
    assert v.state.sample.upload is not None and v.state.sample.upload.source_format == "h36m17"
    # the sequence's own format is shown (a trial: an OpenPose sequence was labelled h36m17)
    from lifter import convert

    sh = dict(doc, format="sh16", frames=[{"people": [{"keypoints": convert(p, src="h36m17", dst="sh16").tolist()}
                                                      for p in people]} for people in _script(6)])
    assert v.load_upload("third.json", json.dumps(sh).encode()) is True, v.messages[-3:]
    assert v.state.sample.upload is not None and v.state.sample.upload.source_format == "sh16"
    assert any("(it was 3000 px: a new input)" in m for m in v.messages[-3:]), v.messages[-3:]


def test_the_person_picked_in_a_video_is_followed_from_frame_to_frame(server) -> None:
    """A browser trial's two-person clip: the detector missed track 1 in two frames, and the selection went to
    track 2 there without a word; a pick of track 2 went back to track 1 on the next frame. The tab now follows the
    picked track (at first the first frame's first person), says once per video when it is not in a frame, picks it
    again when it is back, and says when its track has ended (following the one shown from then on); the record
    says where each track is missing."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    people = _script(9)
    people[3] = people[3][1:]  # track 1 (the nearer person) not found in frame 3
    people[5] = people[5][:1]  # track 2 not found in frame 5
    people[8] = people[8][:1]  # ... nor in the last frame: its track has ended
    frames = [{"people": [{"keypoints": p.tolist()} for p in pp]} for pp in people]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("two.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    warnings = v.sequence().record.warnings
    assert any(w.startswith("track 1: missing from 1 of the 9 frames") and w.split(": ")[2].startswith("3;")
               for w in warnings), warnings
    assert any(w.startswith("track 2: missing from 1 of the 8 frames") for w in warnings), warnings

    def shown() -> str:
        return v.state.sample.person_tag(v.state.person)

    def go(frame: int) -> None:
        v.gui.play.frame.value = frame
        assert wait_for(lambda: v.state.sample.key.endswith(f"/{frame}")), v.state.sample.key

    assert shown() == "track 1"
    go(2)
    assert shown() == "track 1"
    go(3)  # track 1 missing: the other one, said
    assert shown() == "track 2" and "track 1 is not found in two.json frame 3" in v.messages[-1], v.messages[-1]
    go(4)
    assert shown() == "track 1"
    said = len(v.messages)
    go(3)  # said once per video: not again (a notification per gap during playback would pile up)
    assert shown() == "track 2" and not any("is not found" in m for m in v.messages[said:]), v.messages[said:]
    go(4)
    v.gui.joints.person.value = v.state.sample.person_name(1)  # pick track 2
    assert wait_for(lambda: shown() == "track 2")
    go(1)  # (was: back to track 1)
    assert shown() == "track 2" and v.state.person == 1
    assert 5000 < v.frame.root[2] < 7000  # the far person's lift is the one shown
    go(5)
    assert shown() == "track 1" and "track 2 is not found in two.json frame 5" in v.messages[-1]
    go(6)
    assert shown() == "track 2"
    go(8)  # track 2 has ended: said, and the one shown is followed from now on
    assert shown() == "track 1" and "track 2 is not seen after this point of the video" in v.messages[-1]
    go(7)
    assert shown() == "track 1"


def test_play_is_off_for_a_still_upload_after_a_video(server) -> None:
    """A browser trial uploaded a photo after a video: play stayed on, and pressing it gave an error. A still
    upload turns play off; a video (and a demo still, whose play plays the demo motion) turns it on."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist()} for p in pp]} for pp in _script(6)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("walk.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    assert not v.gui.play.play.disabled and not v.gui.play.frame.disabled
    one = {"people": [{"keypoints": p.tolist()} for p in _script(1)[0]], "image_size": [W, H], "focal": F,
           "format": "h36m17"}
    assert v.load_upload("photo.json", json.dumps(one).encode()) is True, v.messages[-3:]
    assert v.gui.play.play.disabled and v.gui.play.frame.disabled
    v.select_demo("walking")
    assert wait_for(lambda: not v.gui.play.play.disabled)


def test_labels_name_whose_root_it_is_and_leave_the_head_on_view(server) -> None:
    """A browser trial: with two people, the selected one's label read only "root Z 7.67 m", and in the head-on view
    the other's label ("person 2 · Z 8.23 m") floated over the selected person's image. The root's label now names
    its person when there are others; the head-on view hides the others' labels (as it hides the root's), and the
    overview shows them again."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    one = {"people": [{"keypoints": p.tolist()} for p in _script(1)[0]], "image_size": [W, H], "focal": F,
           "format": "h36m17"}
    assert v.load_upload("two.json", json.dumps(one).encode()) is True, v.messages[-3:]
    assert wait_for(lambda: v.scene.camera.root_label.text.startswith("person 1 · root Z"))
    other = v.scene.pose.others_labels[0]
    assert other.visible and other.text.startswith("person 2 · Z")
    v.head_on_view()
    assert not other.visible and not v.scene.camera.root_label.visible
    v.gui.noise.level.value = 0.5  # a redraw in the head-on view keeps them hidden
    assert wait_for(lambda: v.state.noise_level == 0.5)
    assert not other.visible
    v.overview()
    assert other.visible and v.scene.camera.root_label.visible
    v.select_demo("walking")  # one person: the bare label
    assert wait_for(lambda: v.scene.camera.root_label.text.startswith("root Z"))


def test_a_sequence_download_keeps_the_joints_dragged_on_its_frame(server) -> None:
    """A browser trial: on a keypoint sequence's frame, a dragged wrist moved the lift, but the download (which the
    app says to make to keep such drags) held the original joint and no note."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(10)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("walk.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    v.gui.play.frame.value = 6
    assert wait_for(lambda: v.state.sample.key.endswith("/6")), v.state.sample.key
    tid = int(v.state.sample.person_tag(v.state.person).split()[-1])
    before = json.loads(v.download_payload("json")[1])
    moved = np.asarray(v.state.keypoints[16]) + [30.0, -20.0]
    v.move_joint(16, moved)  # r_wrist
    after = json.loads(v.download_payload("json")[1])
    person = next(p for p in after["frames"][6]["people"] if p["track_id"] == tid)
    np.testing.assert_allclose(person["keypoints_2d"][16], moved, atol=1e-3)
    was = next(p for p in before["frames"][6]["people"] if p["track_id"] == tid)
    assert person["root_unsmoothed"] != was["root_unsmoothed"]  # (lifted with the corrected joint)
    assert f"2D joints corrected in the app: frame 6 (track {tid}): r_wrist" in after["warnings"]
    # (why it was lifted again, first: a browser trial's read "model 'x' at 1144.4 px (the upload's: 'x' at 1144.4
    # px)", as if nothing had changed)
    again = [w for w in after["warnings"] if w.startswith("lifted again in the app")]
    assert len(again) == 1 and again[0].startswith("lifted again in the app (2D joints corrected in the app, named "
                                                   "below): model "), again
    for a, b in zip(after["frames"][:6], before["frames"][:6]):  # (the frames before it: as they were)
        assert a["people"] == b["people"]


def test_the_not_found_note_names_the_frame_typed(server) -> None:
    """An app trial typed 35 in the frame box and read "track 3 is not found in ... frame 3": each key loads a frame,
    and the note (said once per video and person) named the first key's. It is said once the typing settles, for
    the frame then shown; not at all when the person is in that frame."""
    from poselifter_app.viewer import TYPING_SETTLE_S

    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    people = _script(40)
    for i in (3, 35):
        people[i] = people[i][1:]  # track 1 (the nearer person) not found in frames 3 and 35
    frames = [{"people": [{"keypoints": p.tolist()} for p in pp]} for pp in people]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("two.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    assert v.state.sample.person_tag(v.state.person) == "track 1"
    for value in (3, 35):  # typed key by key: "3", then "35"
        v._note_key("frame")
        v.gui.play.frame.value = value
        assert wait_for(lambda value=value: v.state.sample.key.endswith(f"/{value}")), v.state.sample.key
    assert not any("is not found" in m for m in v.messages)  # not yet: the box is being typed
    assert wait_for(lambda: any("is not found" in m for m in v.messages), timeout=TYPING_SETTLE_S + 3)
    said = [m for m in v.messages if "is not found" in m]
    assert len(said) == 1 and "track 1 is not found in two.json frame 35" in said[0], said
    # typed to a frame that has them: nothing said
    v2 = app.headless_view()
    assert v2.load_upload("two.json", json.dumps(doc).encode()) is True
    for value in (3, 34):
        v2._note_key("frame")
        v2.gui.play.frame.value = value
        assert wait_for(lambda value=value: v2.state.sample.key.endswith(f"/{value}")), v2.state.sample.key
    import time

    time.sleep(TYPING_SETTLE_S + 0.5)
    assert not any("is not found" in m for m in v2.messages), v2.messages[-3:]


def test_a_keypoint_sequence_s_person_picker_names_the_file_s_person_ids(server) -> None:
    """A browser trial: a keypoint sequence's person picker said "person 1 (track 1)", "person 2 (track 2)", not the
    file's own ``person_id``s, which the keypoint-file upload's picker shows ("person 1 (id 7)"). A track whose
    person has one id in every frame is now named with it; a name with parentheses is still picked by its label."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist(), "person_id": pid}
                          for p, pid in zip(pp, ("alice (left)", 7))]} for pp in _script(4)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("ids.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    labels = list(v.gui.joints.person.options)
    assert labels == ["person 1 (track 1, id alice [left])", "person 2 (track 2, id 7)"], labels
    v.gui.joints.person.value = labels[1]
    assert v.state.person == 1 and v.state.sample.person_tag(1) == "track 2, id 7"
    v.gui.joints.person.value = labels[0]
    assert v.state.person == 0
    assert "person 1 (track 1, id alice [left])" in v.gui.readout.readout.content


def test_a_new_sequence_with_the_same_file_name_is_lifted_at_its_own_focal(server) -> None:
    """A review: uploading a corrected clip.json (another focal) under the last one's name kept the old file's
    focal for every frame, without a word, and the download said "app-slider": the cameras were taken for one by
    their names ("upload/clip.json"). A new upload is a new camera; the frames of one upload keep a chosen focal."""
    from lifter import demo_sample

    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    s = demo_sample("walking")

    def seq(focal: float) -> bytes:
        return json.dumps({"frames": [{"keypoints": (s.keypoints_2d + i).tolist()} for i in range(3)], "fps": 25,
                           "image_size": list(map(int, s.image_size)), "focal": focal, "source": "clean"}).encode()

    assert v.load_upload("clip.json", seq(800.0)) is True, v.messages[-3:]
    v.gui.lift.focal.value = 1200.0
    assert v.state.focal_px == pytest.approx(1200.0)
    v.gui.play.frame.value = 2  # (another frame of the same upload: the chosen focal stays)
    assert wait_for(lambda: v.state.sample.key.endswith("/2")) and v.state.focal_px == pytest.approx(1200.0)
    assert v.load_upload("clip.json", seq(1500.0)) is True, v.messages[-3:]
    assert v.state.focal_px == pytest.approx(1500.0), v.state.focal_px
    assert "(it was 1200 px: a new input)" in " ".join(v.messages[-3:]), v.messages[-3:]
    _, payload = v.download_payload("json")
    doc = json.loads(payload)
    assert doc["focal"] == [1500.0, 1500.0] and doc["focal_source"] == "keypoint-file", doc["focal_source"]


def test_a_video_upload_without_the_detector_is_the_install_s_problem(server, tmp_path: Path) -> None:
    """A review: a video uploaded to an install without MediaPipe was "Upload refused: the file arrived, but it
    cannot be used", with a bare "mediapipe is not installed"; a photo gets "Input problem" with the install command
    and the keypoint-JSON way. A video now gets that too, naming the keypoint sequence layout."""
    from lifter.detect import MissingDependencyError

    def no_mediapipe():
        raise MissingDependencyError("the BlazePose 2D detector needs the optional 'detect' extra")

    app = PoseLifterApp(server, h36m_root=None, estimator_factory=no_mediapipe)
    v = app.headless_view()
    shown = v.state.sample.key
    assert v.load_upload("clip.avi", _clip(tmp_path / "clip.avi", 3)) is False
    msg = v.messages[-1]
    assert "clip.avi: cannot find 2D joints in a video: the MediaPipe detector is not installed" in msg, msg
    assert 'pip install -e ".[detect]"' in msg and '"frames"' in msg and "still works" in msg, msg
    assert v.notices[-1][0] == "Input problem", v.notices[-1]
    assert v.state.sample.key == shown


def test_a_keypoint_sequence_s_camera_errors_name_the_file_s_fields(server) -> None:
    """A review: a keypoint sequence uploaded to the app without a focal or image size was refused naming
    poselifter lift's options ("pass focal= (--focal)"), which the app does not have (single keypoint files name
    the file's fields)."""
    from lifter import demo_sample

    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    kp = demo_sample("walking").keypoints_2d
    doc = {"frames": [{"keypoints": (kp + i).tolist()} for i in range(3)], "fps": 25, "format": "h36m17",
           "principal_point": [400, 300]}
    assert v.load_upload("seq.json", json.dumps(doc).encode()) is False
    msg = v.messages[-1]
    assert "no focal length and no image size: put 'image_size' (or 'focal') in the file" in msg, msg
    assert "--focal" not in msg and "focal=" not in msg, msg


@pytest.mark.parametrize("meanwhile", ["upload", "pick"])
def test_an_upload_lifted_after_a_later_choice_is_not_shown_over_it(server, monkeypatch, meanwhile: str) -> None:
    """A browser trial: a video still being lifted when a keypoint file was uploaded, or a sample picked, replaced
    that choice once it finished (about 0.5 s later), without a word. The last thing the user did wins: the late
    upload is not shown, and a note says so."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    doc = _sequence_doc(6)
    with _held_upload(monkeypatch, v, "walk.json", doc) as done:
        if meanwhile == "upload":
            one = {"keypoints": _script(1)[0][0].tolist(), "image_size": [W, H], "focal": F, "format": "h36m17"}
            assert v.load_upload("one.json", json.dumps(one).encode()) is True
            want = v.state.sample.key
            assert want.startswith("upload/") and "one.json" in want
        else:
            v.gui.sample.demo.value = "crouching"
            v.gui.sample.source.value = "demo"
            assert wait_for(lambda: v.state.sample.key == "demo/crouching")
            want = "demo/crouching"
    assert done == [True] and v.state.sample.key == want and v.sequence() is None
    assert any("walk.json: lifted (6 frames), but not shown: another " in m for m in v.messages[-3:]), v.messages[-3:]


def test_a_refused_upload_does_not_stop_one_being_lifted_and_a_failed_drawing_keeps_the_sequence(
        server, monkeypatch) -> None:
    """A review of the rule above: a later upload that is refused (a text file) does not count as the user's
    choice, so the video being lifted is still shown; and a sequence upload whose drawing fails leaves the tab on the
    previous sequence with that sequence still playable (its frames, not None)."""
    import poselifter_app.viewer as viewer_module

    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    doc = _sequence_doc(6)
    real = vid.video_sequence
    with _held_upload(monkeypatch, v, "a.json", doc) as done:
        assert v.load_upload("oops.txt", b"not a pose") is False
    assert done == [True] and v.state.sample.key.startswith("video/") and "a.json" in v.state.sample.key
    first = v.sequence()
    assert first is not None and first.num_frames == 6
    monkeypatch.setattr(vid, "video_sequence", real)
    fail_once(monkeypatch, viewer_module, "overlay")
    key = v.state.sample.key
    assert v.load_upload("b.json", json.dumps(doc).encode()) is False
    assert v.state.sample.key == key and v.sequence() is first


def test_a_sequence_with_an_empty_frame_names_each_frame_s_own_number(server) -> None:
    """A browser trial: after a frame with nobody (left out of playback), the player's frame 15 showed the file's
    frame 16 with no word, while the notes and the download count the file's frames. The play line names the file's
    own frame number where the two differ."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    people = _script(8)
    frames = [{"people": [] if i == 3 else [{"keypoints": p.tolist()} for p in fr]} for i, fr in enumerate(people)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("gap.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    seq = v.sequence()
    assert isinstance(seq, vid.VideoSequence) and seq.num_frames == 7
    assert any("left out of playback: the player counts the frames shown" in w for w in seq.info.warnings)
    v.gui.play.frame.value = 2
    assert wait_for(lambda: v.state.sample.key == f"{seq.key}/2")
    assert "frame 2 of 0–6 (10 fps)</small>" in v.gui.play.info.content  # (the same number: nothing added)
    v.gui.play.frame.value = 3
    assert wait_for(lambda: v.state.sample.key == f"{seq.key}/3")
    assert wait_for(lambda: "frame 3 of 0–6 (10 fps) · the file's frame 4 (0.40 s)" in v.gui.play.info.content), \
        v.gui.play.info.content
    np.testing.assert_allclose(v.state.keypoints, people[4][0], atol=1e-6)


def test_a_tracked_person_keeps_their_number_in_frames_another_track_is_missing_from() -> None:
    """A browser trial: in a video, track 2 was "person 2 (track 2)" in one frame and "person 1 (track 2)" in the
    frames where track 1 was missing. A tracked person is person N (track N) in every frame; others keep the order."""
    import numpy as np
    from poselifter_app.samples import Sample

    kw = {"key": "k", "label": "l", "keypoints_2d": np.zeros((17, 2)), "pose_3d": None, "detected_2d": None,
          "camera": None, "image": None}
    assert Sample(**kw, person_tags=("track 2",)).person_name(0) == "person 2 (track 2)"
    assert Sample(**kw, person_tags=("track 1", "track 3, id kid")).person_name(1) == "person 3 (track 3, id kid)"
    assert Sample(**kw, others_2d=(np.zeros((17, 2)),), person_tags=("id 7", "")).person_name(1) == "person 2"


def test_a_sequence_s_corrected_joints_are_kept_frame_by_frame(server) -> None:
    """A browser trial: a joint dragged on a video's frame was dropped on scrubbing to the next ("dropped, as another
    sample shows its own 2D"), so one frame at a time could be corrected. Each frame keeps its corrections: back when
    it is shown again, and every corrected frame lifted in the download."""
    app = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: None)
    v = app.headless_view()
    frames = [{"people": [{"keypoints": p.tolist()} for p in people]} for people in _script(10)]
    doc = {"fps": 10, "image_size": [W, H], "focal": F, "format": "h36m17", "frames": frames}
    assert v.load_upload("walk.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    moved = {}
    for i in (6, 8):
        v.gui.play.frame.value = i
        assert wait_for(lambda i=i: v.state.sample.key.endswith(f"/{i}")), v.state.sample.key
        moved[i] = np.asarray(v.state.keypoints[16]) + [30.0, -20.0 + i]
        v.move_joint(16, moved[i])  # r_wrist
    tid = int(v.state.sample.person_tag(v.state.person).split()[-1])
    assert not any("dropped" in m for m in v.messages[-5:]), v.messages[-5:]
    v.gui.play.frame.value = 6
    assert wait_for(lambda: v.state.sample.key.endswith("/6")), v.state.sample.key
    np.testing.assert_allclose(v.state.keypoints[16], moved[6], atol=1e-6)
    assert 16 in v.state.dragged
    after = json.loads(v.download_payload("json")[1])
    for i in (6, 8):
        person = next(p for p in after["frames"][i]["people"] if p["track_id"] == tid)
        np.testing.assert_allclose(person["keypoints_2d"][16], moved[i], atol=1e-3)
        assert f"2D joints corrected in the app: frame {i} (track {tid}): r_wrist" in after["warnings"]
    # another upload: the first one's corrections go with it, and a note says so (a review: without a word)
    v.gui.play.frame.value = 3
    assert wait_for(lambda: v.state.sample.key.endswith("/3")), v.state.sample.key
    assert v.load_upload("walk2.json", json.dumps(doc).encode()) is True, v.messages[-3:]
    assert not any("corrected" in w for w in json.loads(v.download_payload("json")[1])["warnings"])
    assert any(m.startswith("the joints you corrected on 2 frames of the sequence shown before are dropped")
               for m in v.messages[-4:]), v.messages[-4:]
    assert not v._frames_left


def test_a_bare_person_number_picks_that_track_in_a_video_frame() -> None:
    """A review: labels carry the track's number ("person 2 (track 2)" is a frame's first person where track 1 is
    missing), but a bare "person 2" typed picked by position (track 3), and "person 3" was refused."""
    from poselifter_app import session as ss

    from lifter import PoseLifterError

    tags = ("track 2", "track 3")
    assert ss.person_index("person 2", tags=tags) == 0 and ss.person_index("person 3", tags=tags) == 1
    assert ss.person_index("person 3 (track 3)", tags=tags) == 1
    with pytest.raises(PoseLifterError, match=r"person 1 is not in this frame: it has person 2, person 3"):
        ss.person_index("person 1", tags=tags)
    assert ss.person_index("person 2", tags=("id 7", "id 9")) == 1  # (no tracks: by position, as in a photo)
