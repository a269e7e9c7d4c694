"""In-process tests of the app's upload / download (photo or keypoint JSON in, `poselifter lift` JSON or GLB
out) and of its use of the library's keypoint converter and error model. Uploads go through a fake
browser tab speaking viser's upload protocol; the photo test with the real MediaPipe detector runs only
where the ``detect`` extra is installed, the others use a fake 2D estimator so they run everywhere."""

from __future__ import annotations

import dataclasses
import io
import json
import time
from pathlib import Path

import numpy as np
import pytest

viser = pytest.importorskip("viser")


from conftest import fail_once, hold  # noqa: E402
from poselifter_app import upload as up  # noqa: E402
from poselifter_app.demo_assets import DEMO_DIR  # noqa: E402
from poselifter_app.scene import image_plane  # noqa: E402
from poselifter_app.testing import FakeTab, local_server, wait_for  # noqa: E402
from poselifter_app.viewer import PoseLifterApp, SessionView  # noqa: E402
from poselifter_app.viser_hooks import drag_callback  # noqa: E402

from lifter import demo_sample  # noqa: E402
from lifter.detect import Detection, MissingDependencyError, bbox_of, mediapipe_available  # noqa: E402
from lifter.io import LiftRecord  # noqa: E402

LIFT_FIELDS = {"keypoints_2d", "absolute", "root", "canonical_depth", "focal", "principal_point"}


def _standing_app(server, *, default_model: str = "gt") -> PoseLifterApp:
    """An app with the "gt" (and "mixture") models whose detector finds the demo sample "standing" in any photo."""
    models = ["gt", "mixture"] if default_model == "mixture" else ["gt"]
    a = PoseLifterApp(server, h36m_root=None, models=models, default_model=default_model,
                      estimator_factory=lambda: FakeEstimator([a.demo.get("standing").keypoints_2d], full_width=800))
    return a


class FakeEstimator:
    """A 2D estimator returning given H36M-order people (full-resolution px), scaled to the image it sees."""

    name = "fake"
    keypoint_format = "h36m17"

    def __init__(self, people: list[np.ndarray], full_width: int) -> None:
        self.people = [np.asarray(p, np.float64) for p in people]
        self.full_width = full_width
        self.seen: list[tuple[int, int]] = []

    def detect(self, image: np.ndarray) -> list[Detection]:
        self.seen.append(image.shape[:2])
        s = image.shape[1] / self.full_width
        return [Detection(keypoints=p * s, scores=np.full(17, 0.9), bbox_xywh=bbox_of(p * s), keypoint_format="h36m17")
                for p in self.people]



def _jpeg(rgb: np.ndarray, **save: object) -> bytes:
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(rgb).save(buf, format="JPEG", quality=90, **save)
    return buf.getvalue()


def _open_tab(app: PoseLifterApp) -> tuple[FakeTab, SessionView]:
    """A new fake browser tab and its session view (other tests' tabs may still be disconnecting)."""
    before = set(app.views)
    tab = FakeTab(app.server)
    assert wait_for(lambda: bool(set(app.views) - before)), "the fake tab never got a session"
    return tab, app.views[max(set(app.views) - before)]


def _snapshot(view: SessionView) -> tuple:
    st = view.state
    return st.sample.key, st.keypoints.copy(), st.focal_px, view.frame


def _assert_unchanged(view: SessionView, snap: tuple) -> None:
    key, kp, f, frame = snap
    assert view.state.sample.key == key and view.state.focal_px == f
    np.testing.assert_array_equal(view.state.keypoints, kp)
    np.testing.assert_allclose(view.frame.lifted, frame.lifted, atol=1e-9)


# ----------------------------------------------------------------------------------------------
# Integration with the library
# ----------------------------------------------------------------------------------------------


def test_noise_slider_uses_the_shipped_error_model(app: PoseLifterApp) -> None:
    from lifter.noise import ErrorModel
    from lifter.resources import asset

    assert isinstance(app.error_model, ErrorModel)
    if asset("error_model/sh_mixture.json").is_file():
        assert "stand-in" not in app.error_model.source
        assert np.any(app.error_model.gamma < 1.0)  # a fitted mixture: some outlier weight


def test_h36m_detections_use_the_library_converter() -> None:
    import poselifter_app.samples as samples
    from poselifter_app.samples import default_h36m_root, open_h36m

    from lifter.keypoints import convert

    assert not hasattr(samples, "sh16_to_h36m17") and not hasattr(samples, "SH16_TO_H36M17")
    root = default_h36m_root()
    if root is None:
        pytest.skip("Human3.6M not present")
    cat = open_h36m(str(root))
    s = cat.get(9, "Walking 1", cat.camera_ids[0], 0)
    rows = cat._detections["S9/Walking 1/" + cat.camera_ids[0]]
    np.testing.assert_allclose(s.detected_2d, convert(rows[0], src="sh16"))


# ----------------------------------------------------------------------------------------------
# Keypoint JSON upload (through a fake tab, viser's upload protocol)
# ----------------------------------------------------------------------------------------------


def test_keypoint_json_upload_through_a_tab(app: PoseLifterApp) -> None:
    tab, v = _open_tab(app)
    try:
        s = app.demo.get(app.demo.names[1])
        # COCO-style list of two people: the largest is used, and the app says so
        coco = np.zeros((17, 3))
        from lifter.keypoints import convert

        coco[:, :2] = _coco_from_h36m(s.keypoints_2d)
        coco[:, 2] = 1.0
        small = coco.copy()
        small[:, :2] = 0.2 * coco[:, :2] + 10
        content = json.dumps([{"keypoints": small.ravel().tolist()}, {"keypoints": coco.ravel().tolist()}]).encode()
        assert "upload" not in v.gui.sample.source.options  # (a user trial picked it with nothing uploaded)
        tab.upload(v.gui.files.upload, "two_people.json", content)
        # a COCO file carries no image size: refused with the reason, the tab keeps its sample
        assert wait_for(lambda: "image_size" in (v.messages[-1] if v.messages else ""))
        assert v.state.sample.key.startswith("demo/")
        content = json.dumps({"keypoints": coco.tolist(), "format": "coco17", "image_size": [800, 600]}).encode()
        tab.upload(v.gui.files.upload, "pose.json", content)
        assert wait_for(lambda: v.state.sample.key.startswith("upload/") and "coco17 keypoints" in v.messages[-1])
        st = v.state
        assert st.sample.pose_3d is None and not st.sample.has_gt_2d and st.input_kind == "detected"
        np.testing.assert_allclose(st.keypoints, convert(coco[:, :2], src="coco17"))
        assert st.sample.camera.width == 800 and st.sample.camera.principal_point == (400.0, 300.0)
        from lifter.camera import focal_from_fov as default_focal

        assert st.focal_px == pytest.approx(default_focal((800, 600)))  # the stated default field of view
        assert "coco17" in v.messages[-1] and "field of view" in v.messages[-1]
        assert v.gui.sample.source.value == "upload" and "upload" in v.gui.sample.source.options
        assert "pose.json" in v.gui.readout.readout.content and np.all(v.frame.lifted[:, 2] > 0)
        # the 2D joints are draggable and the focal slider still works
        assert v.move_joint(13, st.keypoints[13] + 30.0) is True and 13 in v.state.dragged
        z = v.frame.root[2]
        v.gui.lift.focal.value = 2 * v.state.focal_px
        assert 1.5 * z < v.frame.root[2] < 2.5 * z  # a longer lens: further away
        # back to a demo sample and to the upload again
        v.gui.sample.source.value = "demo sample"
        assert v.state.sample.key.startswith("demo/")
        v.gui.sample.source.value = "upload"
        assert v.state.sample.key.startswith("upload/")
    finally:
        tab.close()


def _coco_from_h36m(kp: np.ndarray) -> np.ndarray:
    """COCO-17 keypoints for an H36M pose: limbs copied, the face placed around neck/nose and head."""
    n = {name: i for i, name in enumerate(("pelvis", "r_hip", "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle",
                                           "spine", "thorax", "neck_nose", "head_top", "l_shoulder", "l_elbow",
                                           "l_wrist", "r_shoulder", "r_elbow", "r_wrist"))}
    head = 0.5 * (kp[n["neck_nose"]] + kp[n["head_top"]])
    face = [kp[n["neck_nose"]], head + (6, 0), head - (6, 0), head + (14, 3), head - (14, -3)]
    limbs = ["l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "l_hip", "r_hip", "l_knee",
             "r_knee", "l_ankle", "r_ankle"]
    return np.array(face + [kp[n[j]] for j in limbs], np.float64)


def _openpose_from_h36m(kp: np.ndarray) -> np.ndarray:
    """OpenPose BODY_25 keypoints for an H36M pose (built from :func:`_coco_from_h36m`; feet at the ankles)."""
    c = dict(zip(("nose", "l_eye", "r_eye", "l_ear", "r_ear", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow",
                  "l_wrist", "r_wrist", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle"),
                 _coco_from_h36m(kp)))
    c["neck"] = 0.5 * (c["l_shoulder"] + c["r_shoulder"])
    c["mid_hip"] = 0.5 * (c["l_hip"] + c["r_hip"])
    for side in "lr":
        a = c[f"{side}_ankle"]
        c[f"{side}_big_toe"], c[f"{side}_small_toe"], c[f"{side}_heel"] = a + (0, 12), a + (4, 12), a + (-3, 4)
    from lifter.keypoints import get_format

    return np.array([c[j] for j in get_format("openpose25").joint_names], np.float64)


def test_a_utf16_keypoint_file_and_sequence_are_read(view: SessionView, app: PoseLifterApp) -> None:
    """A user trial: keypoint JSON written by Windows PowerShell (UTF-16 with its byte-order mark) was refused by
    ``poselifter lift``; the app read it as "not a UTF-8 keypoint JSON file". Both read it, a sequence too."""
    s = app.demo.get(app.demo.names[0])
    one = {"keypoints": s.keypoints_2d.tolist(), "format": "h36m17", "image_size": [800, 600]}
    assert view.load_upload("ps.json", json.dumps(one).encode("utf-16")) is True, view.messages[-1]
    np.testing.assert_allclose(view.state.keypoints, s.keypoints_2d, atol=1e-9)
    seq = {"frames": [{"keypoints": (s.keypoints_2d + [2.0 * i, 0]).tolist()} for i in range(3)], "fps": 10,
           "format": "h36m17", "image_size": [800, 600]}
    assert view.load_upload("seq.json", json.dumps(seq).encode("utf-16")) is True, view.messages[-1]
    assert view.sequence() is not None and len(view.sequence().record.frames) == 3


@pytest.mark.parametrize("layout", ["object_h36m", "openpose", "flat_rows_sh16"])
def test_keypoint_json_layouts(view: SessionView, app: PoseLifterApp, layout: str) -> None:
    from lifter.keypoints import convert

    s = app.demo.get(app.demo.names[0])
    kp = s.keypoints_2d
    if layout == "object_h36m":
        doc: object = {"keypoints": kp.tolist(), "format": "h36m17", "image_size": [800, 600], "focal": [1000, 1000]}
        expect = kp
    elif layout == "openpose":
        op = _openpose_from_h36m(kp)
        doc = {"people": [{"pose_keypoints_2d": np.c_[op, np.ones(25)].ravel().tolist()}]}
        expect = convert(op, src="openpose25")
    else:
        sh = convert(kp, src="h36m17", dst="sh16") if "sh16" in _dst_formats() else None
        if sh is None:
            pytest.skip("sh16 cannot be produced from h36m17")
        doc = {"keypoints": sh.ravel().tolist(), "image_size": [800, 600]}
        expect = convert(sh, src="sh16")
    if layout == "openpose":  # OpenPose output has no image size: drawn on the photo uploaded before
        photo = (DEMO_DIR / f"{app.demo.names[0]}.jpg").read_bytes()
        view.load_upload("photo.jpg", photo)  # decodes; detection may or may not be available
    ok = view.load_upload(f"{layout}.json", json.dumps(doc).encode())
    assert ok is True, view.messages[-1]
    np.testing.assert_allclose(view.state.keypoints, expect, atol=1e-9)
    if layout == "object_h36m":
        assert view.state.focal_px == pytest.approx(1000.0)
        np.testing.assert_allclose(view.frame.lifted, app.pool.get(view.state.model).lift(
            kp, focal=1000.0, principal_point=(400, 300)).absolute, atol=1e-6)
    if layout == "openpose":
        assert "that of the photo photo.jpg uploaded before (800 x 600 px) is used" in view.messages[-1]
        assert view.state.sample.image.shape[:2] == (600, 800)


def _dst_formats() -> set[str]:
    from lifter.keypoints import convert, keypoint_formats

    ok = set()
    for f in keypoint_formats():
        try:
            convert(np.zeros((17, 2)) + np.arange(17)[:, None], src="h36m17", dst=f)
            ok.add(f)
        except Exception:  # noqa: BLE001
            pass
    return ok


# ----------------------------------------------------------------------------------------------
# Bad uploads: a message, the tab's state untouched, the server alive
# ----------------------------------------------------------------------------------------------


def test_corrupt_and_not_an_image_uploads(view: SessionView, app: PoseLifterApp) -> None:
    view.move_joint(5, view.state.keypoints[5] + 20)  # some state worth keeping
    snap = _snapshot(view)
    photo = (DEMO_DIR / "standing.jpg").read_bytes()
    cases = {
        "notes.txt": (b"just some text, not a photo", "not an image"),
        "photo.jpg": (b"\xff\xd8\xff\xe0" + b"\x00" * 50, "image"),
        "truncated.jpg": (photo[: len(photo) // 2], "truncated"),
        "empty.png": (b"", "empty file"),
        "broken.json": (b'{"keypoints": [[1, 2], ', "not valid JSON"),
        "wrong.json": (json.dumps({"keypoints": [[1, 2]] * 5}).encode(), "5 joints"),
        "nan.json": (json.dumps({"keypoints": [[400, 300]] * 17, "image_size": [800, 600]}).encode(), "degenerate"),
        "binary.json": (b"\x89PNG\r\n\x1a\n" + b"\x00" * 30, "not"),
        "far.json": (json.dumps({"keypoints": (np.arange(34).reshape(17, 2) * 1e6).tolist(),
                                 "image_size": [800, 600]}).encode(), "far outside"),
        "focal.json": (json.dumps({"keypoints": (np.arange(34).reshape(17, 2) * 10.0).tolist(),
                                   "image_size": [800, 600], "focal": 0}).encode(), "focal"),
        "deep.json": (b"[" * 100000 + b"]" * 100000, "nested too deeply"),
    }
    from poselifter_app.viewer import UPLOAD_REFUSED_TITLE

    for name, (content, expect) in cases.items():
        assert view.load_upload(name, content) is False, name
        assert expect in view.messages[-1], (name, view.messages[-1])
        # (a user trial read the browser's own "File uploaded successfully" beside a notification that went: this
        # one says the file arrived but is refused, and stays)
        assert view.notices[-1] == (UPLOAD_REFUSED_TITLE, view.messages[-1], True), view.notices[-1]
        assert view.messages[-1].startswith(name), view.messages[-1]
        assert "internal error" not in view.messages[-1]
        _assert_unchanged(view, snap)
    # a long name is shortened in the message (the readout does not wrap it), its start and suffix kept
    assert view.load_upload("A" * 250 + ".jpg", b"not a photo") is False
    shown = view.messages[-1].split(":")[0]
    assert len(shown) <= 60 and shown.startswith("AAAA") and shown.endswith("A.jpg"), shown
    _assert_unchanged(view, snap)
    import urllib.request

    with urllib.request.urlopen(f"http://127.0.0.1:{app.server.get_port()}/", timeout=10) as r:
        assert r.status == 200


def test_oversize_upload_is_refused(app: PoseLifterApp) -> None:
    from poselifter_app.viewer import UPLOAD_TOO_LARGE_TITLE

    big = b"\xff\xd8" + b"\x00" * (up.MAX_UPLOAD_BYTES + 10)
    tab, v = _open_tab(app)
    try:
        snap = _snapshot(v)
        # checked on the bytes themselves
        assert v.load_upload("huge.jpg", big) is False and "more than the 20 MiB" in v.messages[-1]
        assert "downscale or re-encode the photo" in v.messages[-1]
        _assert_unchanged(v, snap)
        # the advice follows the file's kind (an app trial: a keypoint file was told to re-encode "the photo")
        assert v.load_upload("people.json", b"[" + b" " * (up.MAX_UPLOAD_BYTES + 10)) is False
        assert "lift a keypoint file this large with `poselifter lift FILE` (up to 64 MiB)" in v.messages[-1]
        assert "photo" not in v.messages[-1]
        assert "stopped. Cut the video shorter" in up.oversize_message("clip.mp4", 30 * 2**20)
        assert "the upload was stopped. Lift a keypoint file" in up.oversize_message("k.json", 30 * 2**20)
        # and refused as soon as the browser announces the size: viser does not buffer the rest
        states = v.target.gui._current_file_upload_states
        tab.upload(v.gui.files.upload, "huge2.jpg", big[: 3 * 512 * 1024], declared_size=len(big), max_parts=3)
        assert wait_for(lambda: "huge2.jpg" in (v.messages[-1] if v.messages else ""))
        time.sleep(0.5)  # (the parts sent after the start message arrive and are ignored)
        assert "more than the 20 MiB" in v.messages[-1] and not states
        # (its own title: "the file arrived" contradicted "the upload was stopped", a user trial)
        assert v.notices[-1][0] == UPLOAD_TOO_LARGE_TITLE and v.notices[-1][2]
        assert "the upload was stopped" in v.messages[-1]
        _assert_unchanged(v, snap)
        # a client that announces 1 KiB and then sends more is stopped by the bytes received: viser never holds
        # more than the limit and one part of it
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "liar.jpg", big, declared_size=1024, max_parts=45)
        assert wait_for(lambda: len(v.messages) > n_msgs and "liar.jpg" in v.messages[-1])
        assert "more than the 20 MiB" in v.messages[-1] and not states
        _assert_unchanged(v, snap)
    finally:
        tab.close()


def test_uploads_in_flight_from_one_tab_are_capped(app: PoseLifterApp) -> None:
    """A third upload that starts while two from the same tab are still arriving is refused at once (viser buffers
    every transfer: a security trial held 1 GB with 60 open 19-MiB transfers); another tab's are its own, and once
    a tab's transfers are done it uploads again."""
    from poselifter_app.viewer import UPLOAD_BUSY_TITLE

    part = b"\xff\xd8" + b"\x00" * (512 * 1024)
    tab, v = _open_tab(app)
    tab2, v2 = _open_tab(app)
    try:
        snap = _snapshot(v)
        states = v.target.gui._current_file_upload_states
        for k in range(2):  # (announced 5 MiB, one part sent: still arriving)
            tab.upload(v.gui.files.upload, f"slow{k}.jpg", part, declared_size=5 * 1024**2, max_parts=1)
        assert wait_for(lambda: len(states) >= 2)
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "third.jpg", part, declared_size=5 * 1024**2, max_parts=1)
        assert wait_for(lambda: len(v.messages) > n_msgs and "third.jpg" in v.messages[-1])
        assert "2 uploads from this tab are still arriving" in v.messages[-1], v.messages[-1]
        assert v.notices[-1][0] == UPLOAD_BUSY_TITLE
        time.sleep(0.3)
        assert sorted(s["filename"] for s in states.values()) == ["slow0.jpg", "slow1.jpg"]
        _assert_unchanged(v, snap)
        # the other tab uploads meanwhile: a keypoint file, whole
        kp = json.dumps({"keypoints": demo_sample("walking").keypoints_2d.tolist(), "focal": 1145.0,
                         "image_size": [1000, 1000]}).encode()
        n2 = len(v2.messages)
        for k in range(3):  # (each done before the next: never refused)
            tab2.upload(v2.gui.files.upload, f"pose{k}.json", kp)
            assert wait_for(lambda k=k: any(f"pose{k}.json" in m for m in v2.messages[n2:])), v2.messages[n2:]
        assert not any("still arriving" in m for m in v2.messages[n2:]), v2.messages[n2:]
    finally:
        tab.close()
        tab2.close()


def test_what_viser_buffers_is_bounded_whatever_the_messages_name(app: PoseLifterApp) -> None:
    """A security review: viser buffers a transfer's parts whatever control they name and whatever size was
    announced, so parts tagged with another control's id went past the 20-MiB check to 1 GB; a transfer started on
    the focal slider was buffered (100 MiB) and, once complete, made the slider's value a file, breaking the tab; and
    many raw connections each holding two unfinished uploads added up without bound. Each is stopped before viser
    buffers it, and the tab keeps working."""
    from poselifter_app.viewer import UPLOAD_BUSY_TITLE, UPLOADS_HELD_FACTOR

    big = b"\xff\xd8" + b"\x00" * (up.MAX_UPLOAD_BYTES + 10)
    tab, v = _open_tab(app)
    tabs = [tab]
    try:
        snap = _snapshot(v)
        states = v.target.gui._current_file_upload_states
        held = []  # (bytes viser holds for this tab, sampled as the parts arrive)
        # parts naming the slider, for a transfer started through the button: counted all the same
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "spoof.jpg", big, declared_size=1024, max_parts=45,
                   part_tag=v.gui.lift.focal._impl.uuid)
        assert wait_for(lambda: (held.append(sum(st["transferred_bytes"] for st in states.values())) or True)
                        and len(v.messages) > n_msgs and "spoof.jpg" in v.messages[-1])
        assert "more than the 20 MiB" in v.messages[-1] and not states
        assert max(held) <= up.MAX_UPLOAD_BYTES, max(held)
        # a transfer started on the focal slider: nothing buffered, and the slider keeps a number
        focal = float(v.gui.lift.focal.value)
        tab.upload(v.gui.lift.focal, "x.jpg", b"\xff\xd8" + b"\x00" * 2_000_000)
        tab.upload(v.gui.lift.focal, "empty.jpg", b"")  # (zero parts: viser would finish it at once)
        time.sleep(1.0)
        assert not states and float(v.gui.lift.focal.value) == focal
        _assert_unchanged(v, snap)
        # every tab's unfinished uploads together: within UPLOADS_HELD_FACTOR x the limit
        part = b"\xff\xd8" + b"\x00" * (4 * 1024**2)
        views = [v]
        for _ in range(3):
            t, w = _open_tab(app)
            tabs.append(t)
            views.append(w)
        for t, w in zip(tabs, views):
            for k in range(2):  # (four 4-MiB parts announced, three sent: still arriving, 12 MiB each)
                t.upload(w.gui.files.upload, f"slow{k}.jpg", part * 4, chunk_size=len(part), max_parts=3)
        every = [w.target.gui._current_file_upload_states for w in views]
        assert wait_for(lambda: any(w.notices and w.notices[-1][0] == UPLOAD_BUSY_TITLE for w in views))
        time.sleep(1.0)
        total = sum(st["transferred_bytes"] for sts in every for st in sts.values())
        assert total <= UPLOADS_HELD_FACTOR * up.MAX_UPLOAD_BYTES, total
        refused = [m for w in views for m in w.messages if "the app is receiving other uploads" in m]
        assert refused and "upload it again in a moment" in refused[0], refused
        # and the first tab still takes a keypoint file once its own transfers are gone
        for sts in every:
            sts.clear()
        kp = json.dumps({"keypoints": demo_sample("walking").keypoints_2d.tolist(), "focal": 1145.0,
                         "image_size": [1000, 1000]}).encode()
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "pose.json", kp)
        assert wait_for(lambda: any("pose.json" in m for m in v.messages[n_msgs:])), v.messages[n_msgs:]
        assert v.state.sample.upload is not None
    finally:
        for t in tabs:
            t.close()


def test_upload_bookkeeping_holds_for_tiny_parts_spoofed_tags_empty_files_and_idle_transfers(app: PoseLifterApp
                                                                                              ) -> None:
    """A review of the upload bounds: one-byte parts, counted by their bytes, held 114 bytes each in viser; a transfer
    whose parts name another control was only stopped, never shown to be given to the button; uploads let start on
    what the others had received were stopped half-way; idle transfers were dropped without a word; and a closed
    tab's flag was set only by hand in a test."""
    from poselifter_app.viser_hooks import PART_COST_BYTES

    tab, v = _open_tab(app)
    try:
        states = v.target.gui._current_file_upload_states
        # tiny parts: stopped once their count passes the limit by 1/64, whatever their bytes
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "tiny.jpg", b"\xff" * 6000, chunk_size=1)
        assert wait_for(lambda: len(v.messages) > n_msgs and "tiny.jpg" in v.messages[-1]), v.messages[-2:]
        assert not states and up.MAX_UPLOAD_BYTES // 64 // PART_COST_BYTES < 6000
        # a keypoint file whose parts name the focal slider: given to the upload button all the same, the slider kept
        focal = float(v.gui.lift.focal.value)
        kp = json.dumps({"keypoints": demo_sample("walking").keypoints_2d.tolist(), "focal": 1145.0,
                         "image_size": [1000, 1000]}).encode()
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "tagged.json", kp, part_tag=v.gui.lift.focal._impl.uuid)
        assert wait_for(lambda: any("tagged.json" in m for m in v.messages[n_msgs:])), v.messages[n_msgs:]
        assert v.state.sample.upload is not None and "tagged" in v.state.sample.key
        assert isinstance(v.gui.lift.focal.value, float), v.gui.lift.focal.value  # (not the file)
        assert v.gui.lift.focal.value == pytest.approx(1145.0) != focal  # (the upload's own focal)
        # an empty file through the button: said to be empty
        n_msgs = len(v.messages)
        tab.upload(v.gui.files.upload, "empty.jpg", b"")
        assert wait_for(lambda: any("empty.jpg" in m for m in v.messages[n_msgs:])), v.messages[n_msgs:]
        assert "empty" in [m for m in v.messages[n_msgs:] if "empty.jpg" in m][-1]
        # admitted on what they announce: four uploads of 18 MiB still arriving on two other tabs, one part sent
        # each; a fifth of 10 MiB would take the announced sizes past the 80-MiB budget: refused as it starts, not
        # stopped half-way
        part = b"\x00" * (512 * 1024)
        budget = app.upload_budget
        tab2, v2 = _open_tab(app)
        tab3, v3 = _open_tab(app)
        try:
            for t, w in ((tab2, v2), (tab3, v3)):
                for k in range(2):
                    t.upload(w.gui.files.upload, f"big{k}.jpg", part * 36, max_parts=1)  # (18 MiB announced each)
            assert wait_for(lambda: budget.held() >= 4 * 18 * 2**20)
            n_msgs = len(v.messages)
            tab.upload(v.gui.files.upload, "late.jpg", part * 20, max_parts=1)  # (10 MiB: past 80 MiB in all)
            assert wait_for(lambda: any("late.jpg" in m for m in v.messages[n_msgs:])), v.messages[n_msgs:]
            assert "the app is receiving other uploads" in v.messages[-1] and not states
            # idle: dropped when the next upload starts, each tab told
            budget.idle_s = 0.0
            time.sleep(0.05)
            n2 = len(v2.messages)
            tab.upload(v.gui.files.upload, "pose.json", kp)
            assert wait_for(lambda: any("upload dropped: nothing of it arrived" in m for m in v2.messages[n2:]))
            assert wait_for(lambda: not v2.target.gui._current_file_upload_states)
        finally:
            budget.idle_s = 60.0
            tab2.close()
            tab3.close()
        # a tab that goes is marked gone (its video, if one were being lifted, stops at its next frame)
        tab.close()
        assert wait_for(lambda: v.gone)
    finally:
        tab.close()


def test_a_tab_that_goes_while_its_view_is_built_leaves_no_view(app: PoseLifterApp, monkeypatch) -> None:
    """A review: a tab that disconnected while its view was being built had nothing to drop yet, and the view, added
    once built, was kept for good (its state, its playback)."""
    import types
    from typing import Any

    import poselifter_app.viewer as viewer_module

    built: list[Any] = []

    class Built:
        def __init__(self, app_: Any, client: Any) -> None:
            self.gone, self.stopped = False, False
            app_._on_disconnect(client)  # (the tab goes meanwhile)
            built.append(self)

        def stop_playback(self, wait: bool = True) -> None:
            self.stopped = True

    monkeypatch.setattr(viewer_module, "SessionView", Built)
    client = types.SimpleNamespace(client_id=987654)
    app._on_connect(client)  # type: ignore[arg-type]
    assert 987654 not in app.views and built[0].gone and built[0].stopped
    assert 987654 not in app._gone_early  # (nothing kept of it)


def test_without_the_upload_bounds_the_upload_button_is_off(monkeypatch) -> None:
    """A review: when the bounds could not be installed (viser's internals changed), uploads went on unbounded. The
    button is off instead, and its hint says why."""
    import poselifter_app.viewer as viewer_module
    from poselifter_app.viewer import UPLOADS_OFF

    monkeypatch.setattr(viewer_module, "limit_uploads", lambda *a, **k: False)
    server = local_server()
    try:
        v = PoseLifterApp(server, h36m_root=None).headless_view()
        assert v.gui.files.upload.disabled and v.gui.files.upload.hint == UPLOADS_OFF
        assert not v.gui.files.upload._impl.update_cb  # (no callback takes a file)
    finally:
        server.stop()


def test_missing_mediapipe_message_and_json_on_that_photo(app: PoseLifterApp) -> None:
    def no_mediapipe():
        raise MissingDependencyError("the BlazePose 2D detector needs the optional 'detect' extra")

    server = local_server()
    try:
        a = PoseLifterApp(server, h36m_root=None, estimator_factory=no_mediapipe)
        v = a.headless_view()
        snap = _snapshot(v)
        photo = (DEMO_DIR / "walking.jpg").read_bytes()
        assert v.load_upload("walking.jpg", photo) is False
        msg = v.messages[-1]
        assert 'pip install -e ".[detect]"' in msg and "keypoint JSON" in msg and "still works" in msg
        assert v.notices[-1][0] == "Input problem"  # (the install's problem, not "the file ... cannot be used")
        _assert_unchanged(v, snap)
        # the keypoint JSON path still works, drawn on that photo (same size, no image_size in the file)
        s = a.demo.get("walking")
        assert v.load_upload("walking_kp.json", json.dumps({"keypoints": s.keypoints_2d.tolist(),
                                                            "format": "h36m17"}).encode()) is True
        assert v.state.sample.image.shape[:2] == (600, 800)
        assert "that of the photo walking.jpg uploaded before (800 x 600 px) is used" in v.messages[-1]
        assert float(v.state.sample.image.std()) > 20  # the photo, not a blank canvas
        assert "top-left quarter" not in v.messages[-1]
        # keypoints of a half-size copy: drawn in its top-left corner, and said (a user trial's 26 m, unsaid)
        half = (s.keypoints_2d / 2).tolist()
        assert v.load_upload("half.json", json.dumps({"keypoints": half, "format": "h36m17"}).encode()) is True
        assert ("the pose lies in the top-left quarter of the photo walking.jpg uploaded before (800 x 600 px)"
                in v.messages[-1]), v.messages[-1]
        assert any("top-left quarter" in w for w in v.state.sample.upload.warnings)  # (and in the download)
        # keypoints that do not fit the borrowed size: the refusal says where the size came from (user trial)
        far = (s.keypoints_2d * 3).tolist()
        assert v.load_upload("far.json", json.dumps({"keypoints": far, "format": "h36m17"}).encode()) is False
        assert ("its poses lie mostly outside the photo walking.jpg uploaded before (800 x 600 px), whose size would "
                "be used: add the file's own \"image_size\"") in v.messages[-1], v.messages[-1]
        # every person of the file counts for that rule, not only the six shown (a review: six inside and eight
        # outside were drawn on the photo, where the library refuses them)
        crowd = [{"keypoints": (s.keypoints_2d + [3.0 * i, 0.0]).tolist()} for i in range(6)] + \
                [{"keypoints": (s.keypoints_2d * 0.2 + [2000.0 + 50 * i, 2000.0]).tolist()} for i in range(8)]
        assert v.load_upload("crowd.json", json.dumps({"people": crowd, "format": "h36m17"}).encode()) is False
        assert "its poses lie mostly outside the photo walking.jpg uploaded before" in v.messages[-1], v.messages[-1]
        # a file with its own camera (a K matrix: a principal point) but no image size is another image's pixels, as
        # for a keypoint sequence (lifter.pipeline.keypoints_image's rule): a canvas twice its principal point, not
        # the photo (which had put the principal point at the photo's corner)
        K = [[1000.0, 0.0, 800.0], [0.0, 1000.0, 600.0], [0.0, 0.0, 1.0]]
        assert v.load_upload("k.json", json.dumps({"keypoints": (s.keypoints_2d * 2).tolist(), "format": "h36m17",
                                                   "K": K}).encode()) is True, v.messages[-1]
        cam = v.state.sample.camera
        assert (cam.width, cam.height) == (1600, 1200) and cam.principal_point == (800.0, 600.0)
        assert float(v.state.sample.image.std()) < 10  # (a plain canvas, not the photo: std > 20)
        assert not any("walking.jpg" in w for w in v.state.sample.upload.warnings), v.state.sample.upload.warnings
        # the photo's own size in the file: drawn on it, and said so
        assert v.load_upload("same.json", json.dumps({"keypoints": s.keypoints_2d.tolist(), "format": "h36m17",
                                                      "image_size": [800, 600]}).encode()) is True
        assert "keypoints drawn on the photo walking.jpg uploaded before (the same image size)" in v.messages[-1]
        assert float(v.state.sample.image.std()) > 20
        # a focal length in mm by mistake: lifted as given (not clamped to the slider) and said, as by the CLI
        n = v._message_count
        assert v.load_upload("mm.json", json.dumps({"keypoints": s.keypoints_2d.tolist(), "format": "h36m17",
                                                    "image_size": [800, 600], "focal": 35}).encode()) is True
        assert v.state.focal_px == 35.0 and v.frame.alpha == pytest.approx(35.0)
        assert v.gui.lift.focal.min == 17.0  # the slider reaches down to half this camera's focal (not below 10 px)
        new = v._message_count - n
        assert new > 0 and any("deg of view" in m and "is the focal length in pixels?" in m
                               for m in v.messages[len(v.messages) - new:])
    finally:
        server.stop()
    if not mediapipe_available():  # this environment: the real default detector says the same
        v = app.headless_view()
        assert v.load_upload("walking.jpg", photo) is False and 'pip install -e ".[detect]"' in v.messages[-1]


# ----------------------------------------------------------------------------------------------
# Photo upload with a fake detector: several people, nobody, a huge image, EXIF focal
# ----------------------------------------------------------------------------------------------


def test_photo_upload_with_fake_detector(app: PoseLifterApp) -> None:
    s = app.demo.get("standing")
    rgb = s.image
    server = local_server()
    try:
        other = 0.5 * (s.keypoints_2d - s.keypoints_2d.mean(0)) + np.array([120.0, 420.0])
        est = FakeEstimator([other, s.keypoints_2d], full_width=800)
        a = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
        v = a.headless_view()
        assert v.load_upload("two.jpg", _jpeg(rgb)) is True
        np.testing.assert_allclose(v.state.keypoints, s.keypoints_2d, atol=1e-6)  # the largest person
        assert "found 2 people" in v.messages[-1]
        assert "**People** 2 in one camera space" in v.gui.readout.readout.content
        assert "unsmoothed" not in v.gui.readout.readout.content  # (a photo: nothing is smoothed)
        assert "person 2: root" in v.gui.readout.readout.content
        assert "is drawn for" not in v.gui.readout.readout.content
        # with noise on, the line says whose 2D it is drawn for (an app trial read the distance as noisy for both)
        v.gui.noise.level.value = 1.0
        assert wait_for(lambda: "the noise (level 1) is drawn for person 1 only: the others are lifted from their 2D "
                        "as it is" in v.gui.readout.readout.content), v.gui.readout.readout.content
        v.gui.noise.level.value = 0.0
        assert wait_for(lambda: "is drawn for" not in v.gui.readout.readout.content)
        # nobody
        est.people = []
        snap = _snapshot(v)
        assert v.load_upload("empty_room.jpg", _jpeg(rgb)) is False and "no person found" in v.messages[-1]
        # (a trial: that the refused photo stays the one a keypoint file is drawn on was not said)
        assert "The photo (800 x 600 px) stays the one a keypoint JSON uploaded next is drawn on" in v.messages[-1]
        # (an app trial: the screen still showed the photo before, and "the photo" read as that one)
        assert v.messages[-1].rstrip(".").endswith(", not the one still shown"), v.messages[-1]
        _assert_unchanged(v, snap)
        # a huge image: downscaled for detection, keypoints in full-resolution px, focal slider range follows
        est.people, est.full_width = [s.keypoints_2d * 4], 3200
        big = np.repeat(np.repeat(rgb, 4, axis=0), 4, axis=1)  # 3200 x 2400
        assert v.load_upload("big.jpg", _jpeg(big)) is True
        assert max(est.seen[-1]) <= 2048 and "downscaled 3200 x 2400" in v.messages[-1]
        np.testing.assert_allclose(v.state.keypoints, s.keypoints_2d * 4, atol=3.0)
        assert v.state.sample.camera.width == 3200 and max(v.state.sample.image.shape[:2]) <= up.DISPLAY_MAX_SIDE
        assert v.gui.lift.focal.max >= v.state.focal_px
        # EXIF 35-mm-equivalent focal length, as `poselifter lift` reads it
        from PIL import Image

        est.people, est.full_width = [s.keypoints_2d], 800
        exif = Image.new("RGB", (1, 1)).getexif()
        exif.get_ifd(0x8769)[41989] = 26
        assert v.load_upload("phone.jpg", _jpeg(rgb, exif=exif.tobytes())) is True
        f35 = 26 * np.hypot(800, 600) / np.hypot(36, 24)
        assert v.state.focal_px == pytest.approx(f35, rel=1e-6)
        assert v.state.sample.upload.focal_source == "exif-35mm" and "EXIF" in v.gui.readout.readout.content
        z = v.frame.root[2]
        v.gui.lift.focal.value = 1.5 * f35
        assert 1.2 * z < v.frame.root[2] < 1.8 * z  # a longer lens: further away
    finally:
        server.stop()


def test_the_file_tabs_min_person_score_sets_the_floor_of_the_next_upload(app: PoseLifterApp) -> None:
    """A person scored below the floor is left out of a photo or keypoint file (as poselifter lift does); the refusal
    named the library's min_score and the CLI's --min-score, which the app has neither of. The File tab's "min person
    score" sets the floor for the next upload, and the app's messages name it."""
    import json

    from poselifter_app.core import APP_KEEP_EVERY_ONE

    from lifter.detect import KEEP_EVERY_ONE, MIN_PERSON_SCORE

    s = app.demo.get("standing")
    server = local_server()
    try:
        est = FakeEstimator([s.keypoints_2d], full_width=800)
        a = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
        v = a.headless_view()
        assert v.gui.files.min_score.value == pytest.approx(MIN_PERSON_SCORE)
        # (viser's buttons show no hints: the limits and the GLB's frame are said under them; a trial saw neither)
        assert f"at most {up.MAX_UPLOAD_BYTES // 2**20} MiB" in v.gui.files.about.content
        assert "GLB: metres, y-up, (x, -y, -z)" in v.gui.files.about.content
        est.detect = lambda image: [Detection(keypoints=s.keypoints_2d * image.shape[1] / 800, scores=np.full(17, 0.14),
                                              bbox_xywh=bbox_of(s.keypoints_2d), keypoint_format="h36m17")]
        snap = _snapshot(v)
        assert v.load_upload("dim.jpg", _jpeg(s.image)) is False
        said = v.messages[-1]
        assert "no person found" in said and "below 0.3 (0.14)" in said and APP_KEEP_EVERY_ONE in said, said
        assert KEEP_EVERY_ONE not in said and "--min-score" not in said and "min_score=" not in said
        _assert_unchanged(v, snap)
        v.gui.files.min_score.value = 0.0
        assert v.load_upload("dim.jpg", _jpeg(s.image)) is True
        # (a trial: the notification, cut at 240 characters, lost that there may be no person at all)
        assert v.messages[-1].startswith("dim.jpg: fake found 1 person (the detector is unsure of it: maybe no person "
                                         "at all, see the note); drag the 2D joints"), v.messages[-1]
        # a keypoint file's person scored 0.1: lifted at floor 0, refused at 0.3, naming the control
        rows = np.column_stack([s.keypoints_2d, np.full(17, 0.1)]).tolist()
        doc = json.dumps({"format": "h36m17", "image_size": [800, 600], "focal": 1000,
                          "people": [{"keypoints": rows}]}).encode()
        assert v.load_upload("low.json", doc) is True
        v.gui.files.min_score.value = 0.3
        assert v.load_upload("low.json", doc) is False
        assert "nobody to lift" in v.messages[-1] and APP_KEEP_EVERY_ONE in v.messages[-1], v.messages[-1]
        # a keypoint sequence the same way (the video path)
        seq = json.dumps({"format": "h36m17", "image_size": [800, 600], "focal": 1000, "fps": 10,
                          "frames": [{"people": [{"keypoints": rows}]}] * 4}).encode()
        assert v.load_upload("low_seq.json", seq) is False
        assert "no person in any frame" in v.messages[-1] and APP_KEEP_EVERY_ONE in v.messages[-1], v.messages[-1]
        v.gui.files.min_score.value = 0.0
        assert v.load_upload("low_seq.json", seq) is True and v.sequence() is not None
    finally:
        server.stop()


def test_a_detected_person_cut_off_by_the_edge_is_cautioned_on_the_frame_shown(app: PoseLifterApp) -> None:
    """The photo and video notes say when a detected person is cut off by the image's edge; a video's named the
    frames only in the upload's message, not on the frames. The readout's caution follows the 2D shown: the person's
    joints outside the image (not those dragged there)."""
    s = app.demo.get("standing")
    server = local_server()
    try:
        low = s.keypoints_2d + [0.0, 600.0 - float(s.keypoints_2d[:, 1].max()) + 30.0]  # (feet 30 px below the image)
        est = FakeEstimator([low], full_width=800)
        a = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
        v = a.headless_view()
        assert v.load_upload("cut.jpg", _jpeg(s.image)) is True
        cut = [c for c in v.frame.caution if "cut off by the image's edge here" in c]
        assert len(cut) == 1 and "r_ankle" in cut[0] and "the detector guesses the joints" in cut[0], v.frame.caution
        assert "cut off by the image's edge here" in v.gui.readout.readout.content
        out = np.flatnonzero(v.state.keypoints[:, 1] > 600)
        for j in out:  # dragged into the image: no caution
            v.move_joint(int(j), (float(v.state.keypoints[j, 0]), 590.0))
        assert not [c for c in v.frame.caution if "cut off" in c], v.frame.caution
        # another person cut off is named too, the selected one first (a known gap: only the selected one was)
        small = 0.5 * (s.keypoints_2d - s.keypoints_2d.mean(0)) + [790.0, 300.0]  # (half beyond the right edge)
        est.people = [low, small]
        assert v.load_upload("two.jpg", _jpeg(s.image)) is True
        cut = [c for c in v.frame.caution if "cut off by the image's edge here" in c]
        assert len(cut) == 1 and cut[0].startswith("person 1 (") and "; person 2 (" in cut[0], v.frame.caution
        v.gui.joints.person.value = v.gui.joints.person.options[1]
        cut = [c for c in v.frame.caution if "cut off by the image's edge here" in c]
        assert len(cut) == 1 and cut[0].startswith("person 2 (") and "; person 1 (" in cut[0], v.frame.caution
        v.gui.sample.source.value = "demo sample"  # (a demo, not a detection: never)
        assert not [c for c in v.frame.caution if "cut off" in c]
    finally:
        server.stop()


def test_photo_uploads_are_lifted_as_detections_with_the_tabs_model(monkeypatch) -> None:
    """One model for every input: a photo keeps the tab's model and is lifted with source "detected"; a keypoint
    file saying "source": "clean" is lifted as exact 2D."""
    from poselifter_app.core import lift_source

    server = local_server()
    try:
        a = _standing_app(server, default_model="mixture")
        s = a.demo.get("standing")
        v = a.headless_view()
        assert lift_source(v.state) == "clean"  # a demo sample: exact 2D
        assert v.load_upload("one.jpg", _jpeg(s.image)) is True
        assert v.state.model == "mixture" and lift_source(v.state) == "detected"
        assert v.set_model("gt") is True and v.load_upload("two.jpg", _jpeg(s.image)) is True
        assert v.state.model == "gt"
        payload = {"keypoints": s.keypoints_2d.tolist(), "image_size": [800, 600], "source": "clean"}
        assert v.load_upload("pose.json", json.dumps(payload).encode()) is True
        assert lift_source(v.state) == "clean"
    finally:
        server.stop()


def test_a_new_sample_that_fails_to_draw_leaves_the_tab_as_it_was(monkeypatch) -> None:
    """A browser trial: an upload that failed while being drawn (the inset's crop, since mended) left the tab half
    updated (the new photo's frustum, the old readout, the focal typed before reset) and a focal typed next was not
    applied. A sample that fails to draw is now taken back: the state, frame and drawing are the previous ones, and
    the tab goes on from them."""
    import poselifter_app.viewer as viewer_module

    server = local_server()
    try:
        a = _standing_app(server)
        v = a.headless_view()
        v.gui.lift.focal.value = 2000.0
        assert v.state.focal_px == 2000.0
        key, root = v.state.sample.key, v.frame.root.copy()
        calls = fail_once(monkeypatch, viewer_module, "overlay")
        assert v.load_upload("one.jpg", _jpeg(a.demo.get("standing").image)) is False
        assert "internal error: RuntimeError: drawing failed" in v.messages[-1]
        assert v.state.sample.key == key and v.state.focal_px == 2000.0
        np.testing.assert_array_equal(v.frame.root, root)
        assert calls[0] >= 2  # (the previous sample drawn again)
        v.gui.lift.focal.value = 3000.0
        assert v.state.focal_px == 3000.0 and "Focal 3000" in v.gui.readout.readout.content
        assert v.load_upload("one.jpg", _jpeg(a.demo.get("standing").image)) is True  # (and the tab goes on)
        assert v.state.sample.key.startswith("upload/")
    finally:
        server.stop()


def test_corrected_upload_joints_survive_a_return_that_fails_to_draw(monkeypatch) -> None:
    """A review: going back to an upload whose joints the user corrected forgot the corrections before the upload was
    drawn, so a drawing that failed (and was taken back) lost them for good. They now wait until the upload is
    shown, and come back on the next try."""
    import poselifter_app.viewer as viewer_module

    server = local_server()
    try:
        a = _standing_app(server)
        v = a.headless_view()
        assert v.load_upload("one.jpg", _jpeg(a.demo.get("standing").image)) is True
        upload_key = v.state.sample.key
        assert v.move_joint(16, v.state.keypoints[16] + [12.0, -7.0]) is True
        moved = v.state.keypoints.copy()
        assert v.set_source("demo") is True and v.state.sample.key != upload_key
        demo_key = v.state.sample.key
        calls = fail_once(monkeypatch, viewer_module, "overlay")
        v.set_source("upload")  # (the picker still says "upload": the pass tries again, and it is shown then)
        assert calls[0] >= 3 and any("internal error: RuntimeError: drawing failed" in m for m in v.messages)
        assert v.state.sample.key == upload_key
        np.testing.assert_allclose(v.state.keypoints, moved)
        assert v.state.dragged == {16} and "corrected are back" in v.messages[-1]
        assert v.set_source("demo") is True and v.state.sample.key == demo_key
    finally:
        server.stop()


def test_a_joint_position_being_typed_survives_a_sample_that_fails_to_draw(monkeypatch) -> None:
    """A (u, v) being typed when another sample fails to draw (and is taken back) is still applied, to the joint of
    the sample still shown, once the typing settles, also when its timer fired while the other was drawn (a review:
    the value came back without a timer, and was never applied)."""
    import time

    import poselifter_app.viewer as viewer_module
    from poselifter_app.viewer import TYPING_SETTLE_S

    server = local_server()
    try:
        a = _standing_app(server)
        v = a.headless_view()
        key, j = v.state.sample.key, v.selected
        target = v.state.keypoints[j] + [9.0, -6.0]
        v.gui.joints.uv._impl.value = tuple(target)  # (viser's private field: the value as a tab's key puts it)
        later = v._later
        v._later = lambda *args: None  # (its timer: the call in failing() below stands for it)
        v._note_typed_uv()  # (as a tab's keystroke: applied once the typing settles)
        v._later = later
        seq = v._typed_uv[0]
        real = viewer_module.overlay

        def failing(*args, **kwargs):  # (the typing's timer fires while the other sample is being drawn)
            monkeypatch.setattr(viewer_module, "overlay", real)
            v._settle_typed_uv(seq)
            raise RuntimeError("drawing failed")

        monkeypatch.setattr(viewer_module, "overlay", failing)
        with pytest.raises(RuntimeError, match="drawing failed"):
            with v.lock:
                v._show_sample(a.demo.get(a.demo.names[1]), reframe=False)
        assert v.state.sample.key == key
        time.sleep(TYPING_SETTLE_S + 0.5)
        assert wait_for(lambda: np.allclose(v.state.keypoints[j], np.round(target, 1), atol=0.06)), \
            (v.state.keypoints[j], target)
        assert v.state.dragged == {j}
    finally:
        server.stop()


def test_a_photo_read_after_a_later_upload_is_neither_shown_nor_drawn_on(monkeypatch) -> None:
    """A review: a slow photo that finished after a later photo was shown was not shown, but still became the photo
    a keypoint file uploaded next is drawn on. Only a photo shown is."""
    import threading

    server = local_server()
    try:
        a = _standing_app(server)
        v = a.headless_view()
        reading, go = hold(monkeypatch, up, "upload_sample", when=lambda name, *args, **kwargs: name == "a.jpg")
        img = a.demo.get("standing").image
        done: list[bool] = []
        t = threading.Thread(target=lambda: done.append(v.load_upload("a.jpg", _jpeg(img))))
        t.start()
        try:
            assert reading.wait(30)
            assert v.load_upload("b.jpg", _jpeg(img[:, ::-1].copy())) is True
        finally:
            go.set()
            t.join(60)
        assert done == [True] and "b.jpg" in v.state.sample.key
        assert any("a.jpg: read, but not shown: another file was uploaded" in m for m in v.messages[-3:])
        kp = {"keypoints": a.demo.get("standing").keypoints_2d.tolist(), "format": "h36m17"}
        assert v.load_upload("k.json", json.dumps(kp).encode()) is True
        assert any("b.jpg" in w for w in v.state.sample.upload.warnings), v.state.sample.upload.warnings
        assert not any("a.jpg" in w for w in v.state.sample.upload.warnings)
    finally:
        server.stop()


def test_a_photo_refused_after_a_later_upload_does_not_say_it_is_kept(monkeypatch) -> None:
    """(a review) A photo whose detection failed after a later upload had begun said it stays the photo a keypoint
    JSON is drawn on, which it does not (the later upload's wins)."""
    import threading

    server = local_server()
    try:
        a = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: FakeEstimator([], full_width=800))
        s = a.demo.get("standing")
        v = a.headless_view()
        reading, go = hold(monkeypatch, up, "upload_sample", when=lambda name, *args, **kwargs: name == "a.jpg")
        done: list[bool] = []
        t = threading.Thread(target=lambda: done.append(v.load_upload("a.jpg", _jpeg(s.image))))
        t.start()
        try:
            assert reading.wait(30)
            kp = {"keypoints": s.keypoints_2d.tolist(), "format": "h36m17", "image_size": [800, 600]}
            assert v.load_upload("k.json", json.dumps(kp).encode()) is True
        finally:
            go.set()
            t.join(60)
        assert done == [False]
        refused = [m for m in v.messages if m.startswith("a.jpg") and "no person found" in m]
        assert refused and "stays the one a keypoint JSON" not in refused[-1], refused
        assert v.load_upload("a.jpg", _jpeg(s.image)) is False  # (alone: it is kept, and says so)
        assert "The photo (800 x 600 px) stays the one a keypoint JSON uploaded next is drawn on" in v.messages[-1]
    finally:
        server.stop()


# ----------------------------------------------------------------------------------------------
# Download
# ----------------------------------------------------------------------------------------------


def test_download_payload(app: PoseLifterApp, tmp_path: Path) -> None:
    from lifter.export import read_glb_joints

    tab, v = _open_tab(app)
    try:
        sent: list[tuple] = []
        v.target.send_file_download = lambda name, data, *a, **k: sent.append((name, data, k))  # type: ignore[method-assign]
        s = app.demo.get("sitting")
        v.load_upload("sitting kp.json", json.dumps({"keypoints": s.keypoints_2d.tolist(), "format": "h36m17",
                                                     "image_size": [800, 600], "focal": 1000}).encode())
        v.move_joint(16, v.state.keypoints[16] + np.array([25.0, -10.0]))
        v.set_noise(1.0)  # the download is the clean lift of the current 2D, not a noisy draw
        v.gui.lift.focal.value = 1200.0
        v.gui.files.download_json.value = True  # click
        assert sent and sent[-1][0] == "sitting_kp_lifted.json" and sent[-1][2].get("save_immediately") is True
        d = json.loads(sent[-1][1])
        assert LIFT_FIELDS <= set(d) and set(d) == set(_record_keys())
        kp = np.asarray(d["keypoints_2d"])
        np.testing.assert_allclose(kp, v.state.keypoints, atol=0.01)
        lifter = app.pool.get(v.state.model)
        ref = lifter.lift(v.state.keypoints, focal=(1200.0, 1200.0), principal_point=(400.0, 300.0))
        np.testing.assert_allclose(d["absolute"], ref.absolute, atol=0.01)
        np.testing.assert_allclose(d["root"], ref.root, atol=0.01)
        assert d["focal"] == [1200.0, 1200.0] and d["principal_point"] == [400.0, 300.0]
        assert d["canonical_depth"] == pytest.approx(float(ref.canonical_depth), abs=0.01)
        assert d["focal_source"] == "app-slider" and any("r_wrist" in w for w in d["warnings"])
        assert d["kind"] == "keypoints" and d["image_size"] == [800, 600] and d["model"] == v.state.model
        assert d["source"] == "detected"  # (the file says nothing: detector 2D, as poselifter lift reads it)
        assert d["model_info"] == lifter.provenance(source="detected")  # (the networks, their sha256, flip test)
        v.gui.files.download_glb.value = True
        assert sent[-1][0] == "sitting_kp_lifted.glb"
        path = tmp_path / "skeleton.glb"
        path.write_bytes(sent[-1][1])
        np.testing.assert_allclose(read_glb_joints(path), ref.absolute, atol=1.0)
        # a demo sample downloads too (its calibrated camera)
        v.gui.sample.source.value = "demo sample"
        name, data = v.download_payload("json")
        d = json.loads(data)
        assert name.startswith("demo_") and d["kind"] == "sample" and d["focal_source"] == "calibrated-camera"
        assert d["source"] == "clean"  # exact 2D, and the record says so (user trial: it said "detected")
        ref = app.pool.get(v.state.model).lift(v.state.keypoints, focal=v.state.focal,
                                               principal_point=v.state.sample.camera.principal_point, source="clean")
        np.testing.assert_allclose(d["root"], ref.root, atol=0.01)
        clean_doc = {"keypoints": s.keypoints_2d.tolist(), "format": "h36m17", "image_size": [800, 600],
                     "focal": 1000, "source": "clean"}
        assert v.load_upload("clean.json", json.dumps(clean_doc).encode()) is True
        assert json.loads(v.download_payload("json")[1])["source"] == "clean"
        assert v.download("xml") is False and "unknown download format" in v.messages[-1]
    finally:
        tab.close()


def _record_keys() -> list[str]:
    rec = LiftRecord(input="x", kind="image", keypoints_2d=np.zeros((17, 2)), absolute=np.zeros((17, 3)),
                     relative=np.zeros((17, 3)), root=np.zeros(3), canonical_depth=1.0, focal=(1.0, 1.0),
                     focal_source="user", principal_point=(0.0, 0.0), image_size=(1, 1), model="m")
    return list(rec.to_dict())


# ----------------------------------------------------------------------------------------------
# The real detector (only with the `detect` extra)
# ----------------------------------------------------------------------------------------------


def test_photo_upload_with_blazepose(app: PoseLifterApp) -> None:
    pytest.importorskip("mediapipe")
    tab, v = _open_tab(app)
    try:
        s = app.demo.get("standing")
        tab.upload(v.gui.files.upload, "standing.jpg", (DEMO_DIR / "standing.jpg").read_bytes())
        assert wait_for(lambda: v.state.sample.key.startswith("upload/") and bool(v.messages)
                        and "found" in v.messages[-1], timeout=60), v.messages[-1:]
        st = v.state
        err = np.linalg.norm(st.keypoints - s.keypoints_2d, axis=1)
        assert np.median(err) < 25.0, err  # BlazePose finds the mannequin's joints
        info = st.sample.upload
        assert info.kind == "image" and info.detector == "blazepose" and info.num_people == 1
        assert list(v.gui.sample.input.options) == ["detected 2D"] and v.gui.sample.input.value == "detected 2D"
        assert info.focal_source == "default-fov" and "blazepose found 1 person" in v.messages[-1]
        assert st.sample.detected_2d is not None and np.all(v.frame.lifted[:, 2] > 0)
        # drag to correct a joint, then download
        assert v.move_joint(16, s.keypoints_2d[16]) is True
        name, data = v.download_payload("json")
        d = json.loads(data)
        assert name == "standing_lifted.json" and d["detector"] == "blazepose" and d["num_people"] == 1
        np.testing.assert_allclose(d["keypoints_2d"][16], s.keypoints_2d[16], atol=0.01)
    finally:
        tab.close()


def test_late_drag_events_after_a_sample_change_are_ignored(view: SessionView, app: PoseLifterApp) -> None:
    """A drag that began on one sample must not move a joint of the next (events arrive late)."""
    def _drag_event(v: SessionView, joint: int, uv: np.ndarray, phase: str = "update"):
        cam = v.state.sample.camera
        R = np.asarray(cam.R)
        C = -R.T @ np.asarray(cam.t) / 1000.0
        p = tuple(R.T @ image_plane(v.state, np.asarray(uv, float)) + C)
        return viser.SceneNodeDragEvent(client=None, client_id=0, target=v.scene.pose.joints2d[joint], phase=phase,
                                        instance_index=None, start_position=p, start_screen_pos=(0.5, 0.5),
                                        end_position=p, end_screen_pos=(0.5, 0.5), button="left", modifier=None)

    j = 16
    cb = drag_callback(view.scene.pose.joints2d[j])
    ev_start = _drag_event(view, j, view.state.keypoints[j] + 30.0, "start")
    cb(ev_start)
    assert j in view.state.dragged
    view.select_demo(app.demo.names[2])
    before = view.state.keypoints.copy()
    cb(_drag_event(view, j, view.state.keypoints[j] + 80.0))  # a late "update" of the old drag
    np.testing.assert_array_equal(view.state.keypoints, before)
    assert not view.state.dragged
    cb(_drag_event(view, j, view.state.keypoints[j] + 20.0, "start"))  # a new drag works
    assert j in view.state.dragged


def test_photo_with_several_people_every_person_lifted_and_draggable(app: PoseLifterApp, tmp_path: Path) -> None:
    """Issue 14, app: every person of an uploaded photo is lifted into one camera space, shown (2D, 3D, label,
    readout) and draggable through the person picker; each person's drags are kept, and the download has them all."""
    s = app.demo.get("standing")
    server = local_server()
    try:
        other = 0.7 * (s.keypoints_2d - s.keypoints_2d.mean(0)) + np.array([150.0, 380.0])
        third = 0.5 * (s.keypoints_2d - s.keypoints_2d.mean(0)) + np.array([650.0, 330.0])
        est = FakeEstimator([other, s.keypoints_2d, third], full_width=800)
        a = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est)
        v = a.headless_view()
        assert v.load_upload("three.jpg", _jpeg(s.image)) is True
        st, fr = v.state, v.frame
        assert st.sample.num_people == 3 and st.person == 0 and sorted(st.others) == [1, 2]
        np.testing.assert_allclose(st.keypoints, s.keypoints_2d, atol=1e-6)  # largest first
        np.testing.assert_allclose(st.others[1], other, atol=1e-6)
        np.testing.assert_allclose(st.others[2], third, atol=1e-6)
        # everyone lifted at the tab's focal length, as the library lifts them one by one
        lf = a.pool.get(st.model)
        for o in fr.others:
            ref = lf.lift(st.others[o.person], focal=st.focal, principal_point=st.sample.camera.principal_point)
            np.testing.assert_allclose(o.lifted, ref.absolute, atol=0.05)
        # smaller people are further away (same body size, smaller in the image)
        assert fr.root[2] < fr.others[0].root[2] < fr.others[1].root[2]
        ro = v.gui.readout.readout.content
        assert "**People** 3" in ro and "person 2: root" in ro and "person 3: root" in ro
        dist = np.linalg.norm(fr.others[0].root - fr.root)
        assert f"{dist:.0f} mm from person 1" in ro
        nodes = v.scene.pose
        assert nodes.others_bones.visible and nodes.others_bones.points.shape == (32, 2, 3)
        assert [h.text.split(" ·")[0] for h in nodes.others_labels if h.visible] == ["person 2", "person 3"]
        assert nodes.others_bones2d.visible
        pick = v.gui.joints.person
        assert list(pick.options) == ["person 1", "person 2", "person 3"] and not pick.disabled
        # select person 2 (from the head-on view, which follows: a trial's stayed on person 1) and drag a joint
        from poselifter_app.scene import camera_world, image_plane

        assert v.head_on_view() is True
        pick.value = "person 2"
        assert wait_for(lambda: v.state.person == 1)
        R, C = camera_world(v.state)
        look = R @ (np.asarray(v.camera.get()[0].look_at) - C)
        kp2 = v.state.keypoints
        np.testing.assert_allclose(look, image_plane(v.state, (kp2.min(0) + kp2.max(0)) / 2), atol=1e-6)
        assert v.overview() is True
        np.testing.assert_allclose(v.state.keypoints, other, atol=1e-6)
        np.testing.assert_allclose(v.state.others[0], s.keypoints_2d, atol=1e-6)
        moved = other[13] + np.array([25.0, -10.0])
        assert v.move_joint("l_wrist", moved) is True
        assert wait_for(lambda: np.allclose(v.state.keypoints[13], moved))
        assert v.state.dragged == {13}
        z_main = v.frame.others[0].root[2]  # person 1, now one of the others
        np.testing.assert_allclose(z_main, fr.root[2], atol=1e-6)
        # back to person 1: its 2D as it was, person 2's drag kept
        pick.value = "person 1"
        assert wait_for(lambda: v.state.person == 0)
        np.testing.assert_allclose(v.state.keypoints, s.keypoints_2d, atol=1e-6)
        np.testing.assert_allclose(v.state.others[1][13], moved)
        assert v.state.others_dragged[1] == frozenset({13}) and not v.state.dragged
        assert "also dragged: 1 joint of person 2" in v.gui.readout.readout.content  # (a trial: it went unmentioned)
        # a longer lens moves everyone away along their rays, all in the same camera space
        roots = np.stack([v.frame.root] + [o.root for o in v.frame.others])
        v.gui.lift.focal.value = round(1.5 * v.state.focal_px)
        assert wait_for(lambda: v.frame.root[2] > roots[0, 2] * 1.2)
        new = np.stack([v.frame.root] + [o.root for o in v.frame.others])
        assert np.all(new[:, 2] > 1.05 * roots[:, 2])  # (off-centre people less: the default reads the rays)
        # the download has everyone, the largest at the top level, person 2's corrected joint named
        name, data = v.download_payload("json")
        rec = json.loads(data)
        assert len(rec["people"]) == 3 and rec["num_people"] == 3
        np.testing.assert_allclose(rec["keypoints_2d"], s.keypoints_2d, atol=0.01)
        np.testing.assert_allclose(rec["people"][1]["keypoints_2d"][13], moved, atol=0.01)
        assert any("(person 2): l_wrist" in w for w in rec["warnings"])
        from lifter.export import read_glb_joints

        gname, glb = v.download_payload("glb")
        path = tmp_path / gname
        path.write_bytes(glb)
        for k in range(3):  # everyone in one scene
            np.testing.assert_allclose(read_glb_joints(path, person=k), rec["people"][k]["absolute"], atol=1.0)
        # a one-person photo: the picker goes back to one entry, disabled; nothing of the others is left
        est.people = [s.keypoints_2d]
        assert v.load_upload("one.jpg", _jpeg(s.image)) is True
        assert v.state.sample.num_people == 1 and not v.state.others and v.frame.others == ()
        assert list(pick.options) == ["person 1"] and pick.disabled
        assert not v.scene.pose.others_bones.visible and not any(h.visible for h in v.scene.pose.others_labels)
        assert "**People**" not in v.gui.readout.readout.content
    finally:
        server.stop()


def test_an_uploaded_files_unsure_joints_are_named_as_poselifter_lift_names_them(app: PoseLifterApp) -> None:
    """A user trial: a two-person COCO file whose first person's l_wrist scored 0.2 got "the detector is unsure of
    some joints ... person 1: l_wrist (0.20)" from poselifter lift, and nothing in the app. The upload's notes (and
    so the readout) now name them, from the same function; scores all above 0.3, or above 1 (another scale), do not."""
    s = app.demo.get(app.demo.names[1])
    coco = _coco_from_h36m(s.keypoints_2d)
    small = 0.5 * coco + 40.0
    low = np.full(17, 0.9)
    low[9] = 0.2  # COCO-17's l_wrist
    doc = {"people": [{"keypoints": small.tolist(), "keypoint_scores": np.full(17, 0.9).tolist()},
                      {"keypoints": coco.tolist(), "keypoint_scores": low.tolist()}], "format": "coco17",
           "image_size": [800, 600], "focal": 1145}
    sample = up.keypoint_sample("unsure.json", json.dumps(doc).encode(), key="upload/t/unsure.json")
    said = [w for w in sample.upload.warnings if "the detector is unsure of some joints" in w]
    assert len(said) == 1 and "person 1: l_wrist (0.20)" in said[0], sample.upload.warnings
    v = app.headless_view()
    assert v.load_upload("unsure.json", json.dumps(doc).encode()) is True
    assert "l_wrist (0.20)" in v.gui.readout.readout.content + " ".join(v.messages)
    for scores in (np.full(17, 0.9), np.full(17, 20.0)):
        doc["people"][1]["keypoint_scores"] = scores.tolist()
        quiet = up.keypoint_sample("sure.json", json.dumps(doc).encode(), key="upload/t/sure.json")
        assert not any("unsure of some joints" in w for w in quiet.upload.warnings)


def test_keypoint_file_with_several_people(app: PoseLifterApp) -> None:
    """A keypoint file with several people: all of them in the sample (largest first), at most MAX_PEOPLE."""
    from lifter.keypoints import convert

    s = app.demo.get(app.demo.names[1])
    coco = _coco_from_h36m(s.keypoints_2d)
    small = 0.5 * coco + 40.0
    doc = {"people": [{"keypoints": small.tolist()}, {"keypoints": coco.tolist()}], "format": "coco17",
           "image_size": [800, 600]}
    sample = up.keypoint_sample("two.json", json.dumps(doc).encode(), key="upload/t/two.json")
    assert sample.num_people == 2 and sample.upload.num_people == 2
    np.testing.assert_allclose(sample.keypoints_2d, convert(coco, src="coco17"))
    np.testing.assert_allclose(sample.others_2d[0], convert(small, src="coco17"))
    assert sample.person_tags == ()  # no ids in the file: the picker says "person 1", "person 2"
    # the file's own ids go with each person (largest first) into the person picker's labels
    doc["people"] = [{"keypoints": small.tolist(), "person_id": "kid"}, {"keypoints": coco.tolist(), "id": 7}]
    tagged = up.keypoint_sample("ids.json", json.dumps(doc).encode(), key="upload/t/ids.json")
    assert tagged.person_tags == ("id 7", "id kid")
    v = app.headless_view()
    assert v.load_upload("ids.json", json.dumps(doc).encode()) is True
    assert list(v.gui.joints.person.options) == ["person 1 (id 7)", "person 2 (id kid)"]
    v.gui.joints.person.value = "person 2 (id kid)"
    assert v.state.person == 1 and v.gui.joints.person.value == "person 2 (id kid)"
    # the readout and the 3D label name them as the picker does (a user trial: "person 2" where the file said "kid")
    readout = v.gui.readout.readout.content
    assert "**person 2 (id kid)** selected" in readout and "person 1 (id 7): root X" in readout
    assert "mm from person 2 (id kid)" in readout
    assert v.frame.others[0].name == "person 1 (id 7)"
    assert v.scene.pose.others_labels[0].text.startswith("person 1 (id 7) · Z ")
    # joints corrected on an upload come back with it (a user trial lost them going to a demo sample and back)
    kp_before = v.state.keypoints.copy()
    assert v.move_joint(16, kp_before[16] + [12.0, -7.0]) is True
    moved = v.state.keypoints.copy()
    assert v.set_source("demo") is True and not v.state.sample.key.startswith("upload/")
    assert v.set_source("upload") is True and v.state.sample.key.startswith("upload/")
    np.testing.assert_allclose(v.state.keypoints, moved)
    assert v.state.person == 1 and v.state.dragged == {16} and "corrected are back" in v.messages[-1]
    assert v.set_source("demo") is True and v.set_source("upload") is True  # (once: back to the file's own 2D)
    np.testing.assert_allclose(v.state.keypoints, moved)  # (left again with the correction: kept again)
    assert v.reset_joints() is True
    # the download keeps who is who, as poselifter lift writes it (user trial: the app's dropped both fields)
    name, payload = v.download_payload("json")
    people = json.loads(payload)["people"]
    assert [(q["input_index"], q["person_id"]) for q in people] == [(1, 7), (0, "kid")], name
    doc["people"] = [{"keypoints": (coco * (1 - 0.05 * k) + 10 * k).tolist()} for k in range(up.MAX_PEOPLE + 2)]
    crowd = up.keypoint_sample("crowd.json", json.dumps(doc).encode(), key="upload/t/crowd.json")
    assert crowd.num_people == up.MAX_PEOPLE
    assert any(f"the {up.MAX_PEOPLE} largest are shown" in w for w in crowd.upload.warnings)
    # a person far outside the image is named in the refusal
    doc["people"] = [{"keypoints": coco.tolist()}, {"keypoints": (coco + 5000.0).tolist()}]
    with pytest.raises(up.UploadError, match="person 2"):
        up.keypoint_sample("far.json", json.dumps(doc).encode(), key="upload/t/far.json")


def test_readout_cautions_when_a_pixel_model_extrapolates(view: SessionView, app: PoseLifterApp) -> None:
    """A 4x-size view of a demo pose (a 3200 x 2400 px keypoint file, focal scaled with it) lifted by the paper's
    pixel-space model 'gt' gets a caution in the readout; the default lifts it exactly and stays quiet."""
    if "gt" not in app.pool.names:
        pytest.skip("the paper-table model 'gt' is not shipped")
    s = app.demo.get(app.demo.names[0])
    kp = (s.keypoints_2d - np.array([400.0, 300.0])) * 4 + np.array([1600.0, 1200.0])
    doc = {"keypoints": kp.tolist(), "format": "h36m17", "image_size": [3200, 2400], "focal": [4000, 4000],
           "source": "clean"}
    assert view.load_upload("big.json", json.dumps(doc).encode()) is True, view.messages[-1]
    assert "Caution" not in view.gui.readout.readout.content
    view.gui.lift.model.value = "gt"
    assert view.state.model == "gt"
    md = view.gui.readout.readout.content
    assert "**Caution** model 'gt' reads pixels and was trained on 2D poses" in md, md
    _, payload = view.download_payload("json")  # the download carries it too, as poselifter lift's record does
    assert any("reads pixels and was trained on 2D poses" in w for w in json.loads(payload)["warnings"])


def test_the_upload_message_names_the_people_the_detector_is_unsure_of(app: PoseLifterApp) -> None:
    """(a review) "unsure of person 2, 3" read as one person; and the mean is the library's (a NaN score: no flag, as
    no note)."""
    s = app.demo.get("standing")
    server = local_server()
    try:
        big, mid, small = (c * (s.keypoints_2d - s.keypoints_2d.mean(0)) + [400.0, 300.0] for c in (1.0, 0.6, 0.4))
        people = [(big, 0.9), (mid + [-200.0, 0.0], 0.2), (small + [200.0, 0.0], 0.2)]
        est = FakeEstimator([], full_width=800)
        est.detect = lambda image: [Detection(keypoints=k, scores=np.full(17, sc), bbox_xywh=bbox_of(k),
                                              keypoint_format="h36m17") for k, sc in people]
        v = PoseLifterApp(server, h36m_root=None, estimator_factory=lambda: est).headless_view()
        v.gui.files.min_score.value = 0.0
        assert v.load_upload("three.jpg", _jpeg(s.image)) is True
        assert "found 3 people (the detector is unsure of people 2 and 3: maybe no person at all" in v.messages[-1]
        people[1] = (people[1][0], float("nan"))
        assert v.load_upload("three.jpg", _jpeg(s.image)) is True
        assert "unsure of person 3: maybe" in v.messages[-1], v.messages[-1]
    finally:
        server.stop()


def test_the_upload_message_leaves_the_output_notes_to_the_readout() -> None:
    """(a review) The "As uploaded" line kept the upload's misfit note, stale after a drag, beside the readout's own
    Caution on the lift shown."""
    from lifter._checks import OutputNote

    s = demo_sample("walking")
    doc = {"keypoints": s.keypoints_2d.tolist(), "focal": 1000.0, "image_size": [1000, 1000], "format": "h36m17"}
    sample = up.keypoint_sample("k.json", json.dumps(doc).encode(), key="upload/t/k.json")
    sample = dataclasses.replace(sample, upload=dataclasses.replace(sample.upload, warnings=(
        "an input note", OutputNote("1 of 1 lifted pose(s) do not fit their 2D", kind="misfit"))))
    said = up.upload_message(sample)
    assert "an input note" in said and "do not fit" not in said, said


def test_the_download_says_its_own_lifts_output_notes_once() -> None:
    """A trial's photo download listed the misfit note twice: once from the upload's lift (the upload's notes) and
    once from the download's own lift. The download keeps the upload's notes on the input and says the notes on the
    output of the lift it holds (a drag since can have made the upload's untrue)."""
    from conftest import tiny_lifter

    from lifter._checks import OutputNote

    s = demo_sample("walking")
    doc = {"keypoints": s.keypoints_2d.tolist(), "focal": 1000.0, "image_size": [1000, 1000]}
    sample = up.keypoint_sample("k.json", json.dumps(doc).encode(), key="upload/t/k.json")
    stale = OutputNote("1 of 1 lifted pose(s) do not fit their 2D (as uploaded)", kind="misfit")
    sample = dataclasses.replace(sample, upload=dataclasses.replace(sample.upload, warnings=(
        *sample.upload.warnings, "an input note", stale)))
    from lifter import Lifter

    plain = tiny_lifter()
    lf = Lifter(plain.net, plain.codec, meta={"misfit_limit": 1e-9})  # (every lift misfits: the download's own note)
    rec = up.result_record(sample, sample.keypoints_2d, lifter=lf, focal=(1000.0, 1000.0), source="detected")
    assert "an input note" in rec.warnings and stale not in rec.warnings, rec.warnings
    assert sum("do not fit their 2D" in w for w in rec.warnings) == 1, rec.warnings


def test_a_keypoint_upload_with_a_lens_is_lifted_and_downloaded_undistorted() -> None:
    """A keypoint file's "distortion" becomes the upload's camera lens: the tab and its download lift the 2D
    undistorted (for a network that learned pinhole 2D) and the record says which lens."""
    from conftest import random_pose_cam, tiny_lifter

    from lifter import project

    lens = [-0.2083, 0.2554, -0.0026, -0.0011, -0.0026]
    X = random_pose_cam(np.random.default_rng(3), 1)[0]
    kp = project(X, focal=1145.0, principal_point=(512.0, 515.0), k=lens[:3], p=lens[3:])
    doc = {"keypoints": kp.tolist(), "focal": 1145.0, "principal_point": [512, 515], "image_size": [1000, 1000],
           "distortion": lens, "source": "clean"}
    sample = up.keypoint_sample("lens.json", json.dumps(doc).encode(), key="upload/t/lens.json")
    assert sample.camera.distortion == pytest.approx(tuple(lens))
    lf = tiny_lifter()
    lf.train_config = {"data": {"lens": "pinhole"}}
    rec = up.result_record(sample, sample.keypoints_2d, lifter=lf, focal=(1145.0, 1145.0))
    want = lf.lift(project(X, focal=1145.0, principal_point=(512.0, 515.0)), focal=1145.0,
                   principal_point=(512.0, 515.0), source="clean")
    np.testing.assert_allclose(rec.root, want.root, rtol=1e-6)
    assert rec.to_dict()["distortion"] == pytest.approx(lens)
    np.testing.assert_array_equal(rec.keypoints_2d, kp)  # (the 2D as given, with its lens)
    # at another focal (the slider): the lens is undone at the file's own focal, and the record holds that pinhole
    # 2D without a lens, so that lifting the record again gives the same result
    rec2 = up.result_record(sample, sample.keypoints_2d, lifter=lf, focal=(2000.0, 2000.0), focal_changed=True)
    pinhole = project(X, focal=1145.0, principal_point=(512.0, 515.0))
    want2 = lf.lift(pinhole, focal=2000.0, principal_point=(512.0, 515.0), source="clean")
    np.testing.assert_allclose(rec2.root, want2.root, rtol=1e-6)
    np.testing.assert_allclose(rec2.keypoints_2d, pinhole, atol=1e-6)
    assert "distortion" not in rec2.to_dict()
    assert any("undistorted with the camera's lens at its own focal length (1145.0 px)" in w for w in rec2.warnings)

    nofocal = {k: v for k, v in doc.items() if k != "focal"}
    with pytest.raises(up.UploadError, match="'distortion' needs the camera's own focal length: put 'focal' \\(px\\) "
                                             "in the file, or leave 'distortion' out"):
        up.keypoint_sample("nofocal.json", json.dumps(nofocal).encode(), key="upload/t/nofocal.json")


def test_a_keypoint_upload_with_an_opencv_lens_is_undistorted_as_it_is_read() -> None:
    """A keypoint file with OpenCV's distCoeffs ("distortion_model": "opencv"): the app's cameras have Human3.6M's
    lens model, so the 2D is undistorted as the file is read (at the file's focal), with a note; the sample's
    camera has no lens and the lift is the pinhole 2D's."""
    import cv2
    from conftest import random_pose_cam, tiny_lifter

    from lifter import project

    f, c, d = 600.0, (512.0, 384.0), [-0.28, 0.09, 0.0012, -0.0008, 0.05]
    X = random_pose_cam(np.random.default_rng(5), 1)[0]
    K = np.array([[f, 0, c[0]], [0, f, c[1]], [0, 0, 1.0]])
    seen = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, np.asarray(d))[0].reshape(-1, 2)
    pinhole = project(X, focal=f, principal_point=c)
    assert np.abs(seen - pinhole).max() > 2.0
    doc = {"keypoints": seen.tolist(), "focal": f, "principal_point": list(c), "image_size": [1024, 768],
           "distortion": d, "distortion_model": "opencv", "source": "clean"}
    sample = up.keypoint_sample("cv.json", json.dumps(doc).encode(), key="upload/t/cv.json")
    np.testing.assert_allclose(sample.keypoints_2d, pinhole, atol=1e-6)
    assert sample.camera.distortion is None
    assert any("OpenCV lens" in w and "undistorted (pinhole) 2D" in w for w in sample.upload.warnings)
    lf = tiny_lifter()
    lf.train_config = {"data": {"lens": "pinhole"}}
    rec = up.result_record(sample, sample.keypoints_2d, lifter=lf, focal=(f, f))
    want = lf.lift(pinhole, focal=f, principal_point=c, source="clean")
    np.testing.assert_allclose(rec.root, want.root, rtol=1e-6)
    assert "distortion" not in rec.to_dict()
    # Human3.6M-order numbers that look like OpenCV's get the library's note
    doc.pop("distortion_model")
    doc["distortion"], doc["keypoints"] = [0.05, -0.1, 0.001, 0.001, 0.3], pinhole.tolist()
    wrong = up.keypoint_sample("h.json", json.dumps(doc).encode(), key="upload/t/h.json")
    assert any("tangential terms p1, p2 = 0.001, 0.3" in w for w in wrong.upload.warnings)


def test_upload_notes_read_as_sentences_and_name_the_files_field() -> None:
    """A user trial: the app's note on a 17-joint file without "format" named a CLI flag (--format) the app does
    not have, and a note ending in "?" got a second full stop ("did you mean 'distortion'?.")."""
    kp = (np.arange(34).reshape(17, 2) * 10.0 + 100).tolist()
    doc = {"keypoints": kp, "image_size": [1000, 1000], "distorsion": [0, 0, 0, 0, 0]}
    sample = up.keypoint_sample("k.json", json.dumps(doc).encode(), key="upload/t/k.json")
    msg = up.upload_message(sample)
    assert "give \"format\": \"coco17\" in the file" in msg and "did you mean 'distortion'? " in msg + " "
    assert "?." not in msg and ".." not in msg


def test_an_upload_refused_for_a_missing_field_repeats_the_unread_ones() -> None:
    """A review: the app's own "no image_size" refusal dropped the note on a "focal_length" / "pp" field that
    would have explained it (poselifter lift's error repeats it)."""
    kp = (np.arange(34).reshape(17, 2) * 10.0 + 100).tolist()
    doc = {"keypoints": kp, "focal_length": 1145, "pp": [512, 515]}
    with pytest.raises(up.UploadError, match=r"has no \"image_size\".*upload the photo first\. Also in the file: "
                                             r"'focal_length' is not read: did you mean 'focal'\? 'pp' is not read"):
        up.keypoint_sample("k.json", json.dumps(doc).encode(), key="upload/t/k.json")


def test_a_result_with_an_assumed_focal_uploaded_again_says_it_is_assumed_again(view: SessionView) -> None:
    """As poselifter lift does: a result written with an assumed focal (focal_source "default-fov") is not a known
    focal when uploaded again; it is assumed again from the image size, and the upload's notes say so."""
    from lifter import demo_sample

    kp = np.asarray(demo_sample("walking").keypoints_2d)
    doc = {"people": [{"keypoints_2d": kp.tolist()}], "format": "h36m17", "image_size": [800, 600],
           "focal": [555.0, 555.0], "focal_source": "default-fov"}
    assert view.load_upload("result.json", json.dumps(doc).encode()) is True, view.messages[-1]
    info = view.state.sample.upload
    assert info is not None and info.focal_source == "default-fov" and view.state.focal_px != pytest.approx(555.0)
    assert any(w.startswith("the file's focal length (555.0 px) was assumed when it was written")
               for w in info.warnings), info.warnings


def test_keypoint_file_scores_reach_the_download(tmp_path: Path) -> None:
    """Everyone's confidences of an uploaded keypoint file are in the app's download, as ``poselifter lift`` writes
    them (a review's download had none)."""
    from conftest import tiny_lifter

    from lifter import demo_sample
    from lifter.pipeline import lift_keypoint_file

    kp = np.asarray(demo_sample("walking").keypoints_2d, np.float64)
    sc = np.linspace(0.5, 1.0, 17).round(3)
    doc = {"people": [{"keypoints": np.c_[kp, sc].tolist()}, {"keypoints": np.c_[kp * 0.8 + 30, sc[::-1]].tolist()}],
           "format": "h36m17", "image_size": [800, 600], "focal": 800}
    sample = up.keypoint_sample("scores.json", json.dumps(doc).encode(), key="upload/t/scores.json")
    lf = tiny_lifter()
    got = up.result_record(sample, sample.keypoints_2d, lifter=lf, focal=(800.0, 800.0),
                           people=[sample.keypoints_2d, *sample.others_2d]).to_dict()
    path = tmp_path / "scores.json"
    path.write_text(json.dumps(doc))
    want = lift_keypoint_file(path, lifter=lf).to_dict()
    assert got["scores"] == want["scores"] == pytest.approx(sc.tolist())
    assert [p["scores"] for p in got["people"]] == [p["scores"] for p in want["people"]]
    assert got["people"][1]["scores"] == pytest.approx(sc[::-1].tolist())


@pytest.mark.parametrize(("camera", "said"), [
    ({"focal": 1145, "principal_point": [800, 600]}, "was that given as the principal point?"),
    ({"focal": 100000}, "narrower than a 2000 mm telephoto lens's"),
    ({"focal": 20}, "wider than any camera's without a fisheye lens"),
])
def test_a_keypoint_upload_gets_the_camera_notes_poselifter_lift_gives(camera: dict, said: str,
                                                                      tmp_path: Path) -> None:
    """A review: the app resolved a keypoint file's camera by its own rules, not by
    :func:`lifter.pipeline.resolve_camera`, so the notes ``poselifter lift`` gives on the same file (the image size
    given as the principal point; a focal length no lens has on this image) were missing from the app."""
    from conftest import tiny_lifter

    from lifter import demo_sample
    from lifter.pipeline import lift_keypoint_file

    doc = {"keypoints": np.asarray(demo_sample("walking").keypoints_2d).tolist(), "format": "h36m17",
           "image_size": [800, 600], "source": "clean", **camera}
    path = tmp_path / "k.json"
    path.write_text(json.dumps(doc))
    rec = lift_keypoint_file(path, lifter=tiny_lifter())
    assert any(said in w for w in rec.warnings), rec.warnings
    sample = up.keypoint_sample("k.json", path.read_bytes(), key="upload/t/k.json")
    assert any(said in w for w in sample.upload.warnings), sample.upload.warnings
    assert sample.camera.principal_point == pytest.approx(tuple(doc.get("principal_point", (400, 300))))
    assert sample.camera.alpha == pytest.approx(float(doc["focal"]))


@pytest.mark.parametrize(("camera", "lib", "app_says"), [
    ({"image_size": [800, 600], "focal": 4.2}, "must be in pixels, not mm",
     r"mm\.json: the file's 'focal' 4\.2 x 4\.2 px is below 10 px: it must be in pixels, not mm .*; correct it, or "
     r"remove it to assume"),
    ({"principal_point": [400, 300]}, "no focal length and no image size",
     r"mm\.json: no focal length and no image size: put 'image_size' \(or 'focal'\) in the file$"),
])
def test_a_keypoint_file_lift_refuses_for_its_camera_is_refused_alike(camera: dict, lib: str, app_says: str,
                                                                      tmp_path: Path) -> None:
    """The same rules and messages as ``poselifter lift`` (reviews): a file's focal below 10 px (mm, not px); a file
    with a principal point but no focal and no image size (the app had assumed an image twice the principal point
    and a focal from it). The app's message names the file's fields, not CLI options."""
    from conftest import tiny_lifter

    from lifter import PoseLifterError, demo_sample
    from lifter.pipeline import lift_keypoint_file

    doc = {"keypoints": np.asarray(demo_sample("walking").keypoints_2d).tolist(), "format": "h36m17", **camera}
    path = tmp_path / "mm.json"
    path.write_text(json.dumps(doc))
    with pytest.raises(PoseLifterError, match=lib):
        lift_keypoint_file(path, lifter=tiny_lifter())
    with pytest.raises(up.UploadError, match=app_says):
        up.keypoint_sample("mm.json", path.read_bytes(), key="upload/t/mm.json")


def test_a_keypoint_file_with_a_focal_and_principal_point_but_no_size_is_drawn_on_a_canvas() -> None:
    """With a focal it is taken: the canvas is twice the principal point, and said."""
    from lifter import demo_sample

    doc = {"keypoints": np.asarray(demo_sample("walking").keypoints_2d).tolist(), "format": "h36m17",
           "principal_point": [400, 300], "focal": 800}
    sample = up.keypoint_sample("pp.json", json.dumps(doc).encode(), key="upload/t/pp.json")
    assert (sample.camera.width, sample.camera.height) == (800, 600) and sample.camera.alpha == 800
    assert any("twice the principal point" in w for w in sample.upload.warnings)


def test_a_person_id_with_parentheses_is_picked_by_its_label(app: PoseLifterApp) -> None:
    """The picker's label "person 2 (id alice (left))" did not read back: picking it was refused as an unknown
    person. Parentheses in a file's ids become brackets in the tag (:func:`app.samples.id_tag`)."""
    s = app.demo.get(app.demo.names[1])
    coco = _coco_from_h36m(s.keypoints_2d)
    doc = {"people": [{"keypoints": coco.tolist(), "person_id": 7},
                      {"keypoints": (0.5 * coco + 40.0).tolist(), "person_id": "alice (left)"}], "format": "coco17",
           "image_size": [800, 600]}
    v = app.headless_view()
    assert v.load_upload("ids.json", json.dumps(doc).encode()) is True
    assert list(v.gui.joints.person.options) == ["person 1 (id 7)", "person 2 (id alice [left])"]
    v.gui.joints.person.value = "person 2 (id alice [left])"
    assert v.state.person == 1 and v.gui.joints.person.value == "person 2 (id alice [left])"
    name, payload = v.download_payload("json")  # (the record keeps the file's own id as it was)
    assert [q["person_id"] for q in json.loads(payload)["people"]] == [7, "alice (left)"], name


def test_people_whose_ids_read_alike_are_each_picked(app: PoseLifterApp) -> None:
    """A review: two people of a file whose ids give one tag ("kid" twice; 7 and "7"; "a(b)" and "a[b]") could not
    both be picked: "person 2 (id kid)" selected person 1, the first with that tag. A label's own position decides
    when its tag is the one there."""
    s = app.demo.get(app.demo.names[1])
    coco = _coco_from_h36m(s.keypoints_2d)
    for ids in (["kid", "kid"], [7, "7"], ["a(b)", "a[b]"]):
        doc = {"people": [{"keypoints": coco.tolist(), "person_id": ids[0]},
                          {"keypoints": (0.5 * coco + 40.0).tolist(), "person_id": ids[1]}], "format": "coco17",
               "image_size": [800, 600]}
        v = app.headless_view()
        assert v.load_upload("ids.json", json.dumps(doc).encode()) is True
        labels = list(v.gui.joints.person.options)
        v.gui.joints.person.value = labels[1]
        assert v.state.person == 1, (ids, labels)
        v.gui.joints.person.value = labels[0]
        assert v.state.person == 0, (ids, labels)


def test_the_server_refuses_pages_of_other_sites_and_other_host_names():
    """A security trial: the app's websocket accepted a connection with `Origin: http://evil.example.com` (a page of
    another site open in the same browser could drive the app and upload to it), and HTTP answered any Host (DNS
    rebinding). The guard answers 403 naming why; the app's own page, other tools (no Origin) and the loopback
    names keep working."""
    import urllib.error
    import urllib.request

    from poselifter_app.viser_hooks import request_refusal
    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    server = local_server()
    try:
        port = server.get_port()
        with pytest.raises(InvalidStatus) as exc:
            connect(f"ws://127.0.0.1:{port}", origin="http://evil.example.com", open_timeout=10)  # type: ignore[arg-type]
        assert exc.value.response.status_code == 403
        assert b"a page of 'http://evil.example.com' may not connect" in exc.value.response.body
        for origin in (f"http://127.0.0.1:{port}", None):  # (the app's own page; a tool without an Origin)
            connect(f"ws://127.0.0.1:{port}", origin=origin, open_timeout=10).close()  # type: ignore[arg-type]
        with pytest.raises(urllib.error.HTTPError) as http_exc:
            urllib.request.urlopen(urllib.request.Request(f"http://127.0.0.1:{port}/",
                                                          headers={"Host": f"evil.example.com:{port}"}), timeout=10)
        assert http_exc.value.code == 403
        for name in ("127.0.0.1", "localhost"):
            req = urllib.request.Request(f"http://127.0.0.1:{port}/", headers={"Host": f"{name}:{port}"})
            assert urllib.request.urlopen(req, timeout=10).status == 200
    finally:
        server.stop()
    # bound to every interface (--host 0.0.0.0), any Host name, but still only the page's own origin
    ws = {"Upgrade": "websocket", "Host": "lab-pc:8080"}
    assert request_refusal({"Host": "lab-pc:8080"}, loopback=False) is None
    assert request_refusal({**ws, "Origin": "http://lab-pc:8080"}, loopback=False) is None
    assert request_refusal({**ws, "Origin": "http://evil.example.com"}, loopback=False) is not None
    assert request_refusal({"Host": "[::1]:8080"}, loopback=True) is None
    # any address of 127.0.0.0/8 is this machine's (a security review: --host 127.0.0.2 turned the Host check off)
    from poselifter_app.viser_hooks import is_loopback

    assert all(is_loopback(h) for h in ("127.0.0.2", "127.1.2.3", "localhost", "::1", "[::1]", "LOCALHOST"))
    assert not any(is_loopback(h) for h in ("0.0.0.0", "192.168.1.5", "lab-pc", "127.0.0.1.evil.example", "::"))
    assert request_refusal({"Host": "127.0.0.2:8080"}, loopback=True) is None
    assert request_refusal({"Host": "127.0.0.2.nip.io:8080"}, loopback=True) is not None
