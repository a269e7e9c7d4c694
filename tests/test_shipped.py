"""The shipped weights: the registry, their integrity, and that they reproduce the numbers recorded in
assets/models.json (and quoted in the README) on the every-50th-frame slice."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import requires_h36m
from hypothesis import given, settings
from hypothesis import strategies as st

from lifter import CheckpointError, Lifter, PoseLifterError, PoseLifterWarning, available_models, demo_sample
from lifter.camera import CANONICAL_FOCAL, project
from lifter.detections import with_sh_detections
from lifter.evaluate import evaluate_lifter
from lifter.resources import asset, registry

ROOT = Path(__file__).resolve().parents[1]
# Tolerance: the slice is re-evaluated with the same weights; differences come only from float
# summation order (threads, BLAS), far below these bounds.
TOL_MM = 0.3
MAX_WEIGHTS_BYTES = 40e6
_F, _C = 1145.0, np.array([512.0, 515.0])
_DEMO = demo_sample("walking")
_LIFTERS: dict[str, Lifter] = {}


def _default() -> Lifter:
    if "default" not in _LIFTERS:
        _LIFTERS["default"] = Lifter.from_pretrained()
    return _LIFTERS["default"]


def _slices() -> list[tuple[str, str]]:
    try:
        reg = registry()
    except Exception:  # noqa: BLE001 - no assets: the registry test reports it
        return []
    return [(name, key) for name, e in sorted(reg["models"].items()) for key, m in e.get("metrics", {}).items()
            if m["stride"] == 50]


def test_registry_and_every_model_loads_with_its_checksum():
    reg = registry()
    assert reg["default"] in reg["models"]
    for name, entry in reg["models"].items():
        size = asset(entry["file"]).stat().st_size if hasattr(asset(entry["file"]), "stat") else 0
        assert size <= MAX_WEIGHTS_BYTES, f"{name}: {size / 1e6:.1f} MB > 40 MB"
        assert len(entry["sha256"]) == 64
    assert Lifter.from_pretrained().name == reg["default"]
    for name in available_models():
        Lifter.from_pretrained(name)


def test_a_damaged_shipped_file_is_refused(tmp_path, monkeypatch):
    """4 KB flipped in the middle of the default's weights: the checksum refuses it before torch reads it."""
    import shutil

    src = Path(str(asset("models.json"))).parent
    dst = tmp_path / "assets"
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("*.png", "demo"))
    entry = registry()["models"][registry()["default"]]
    f = dst / entry["file"]
    data = bytearray(f.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 4096] = bytes(b ^ 0x5A for b in data[mid:mid + 4096])
    f.write_bytes(bytes(data))
    monkeypatch.setenv("POSELIFTER_ASSETS", str(dst))
    with pytest.raises(CheckpointError, match="damaged or was replaced") as exc:
        Lifter.from_pretrained()
    assert "reinstall poselifter" in str(exc.value)


def test_a_missing_shipped_weights_file_is_a_checkpoint_error(tmp_path, monkeypatch):
    """The README: "a missing, corrupt or foreign weights file raises lifter.CheckpointError"; a shipped one missing
    from a broken install raised its parent class, which ``except CheckpointError`` missed (a README audit). A
    missing shipped file of another kind stays a PoseLifterError."""
    import shutil

    from lifter import PoseLifterError
    from lifter.resources import read_bytes

    src = Path(str(asset("models.json"))).parent
    dst = tmp_path / "assets"
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("*.png", "demo", "*.pt"))
    monkeypatch.setenv("POSELIFTER_ASSETS", str(dst))
    with pytest.raises(CheckpointError, match=r"shipped file '.*\.pt' not found in .*reinstall poselifter"):
        Lifter.from_pretrained()
    with pytest.raises(PoseLifterError, match="shipped file 'demo/samples.npz' not found") as exc:
        read_bytes("demo/samples.npz")
    assert not isinstance(exc.value, CheckpointError)


@requires_h36m
@pytest.mark.parametrize("name,key", _slices())
def test_shipped_weights_reproduce_recorded_metrics(h36m, name, key):
    rec = registry()["models"][name]["metrics"][key]
    samples = h36m.load_protocol(1, "test", stride=rec["stride"])
    if rec["inputs"] == "sh":
        samples, _ = with_sh_detections(samples, data=h36m)
    assert len(samples) == rec["learned"]["num_samples"]
    learned, analytic = evaluate_lifter(Lifter.from_pretrained(name), samples, analytic_root=True, progress=False,
                                        source=rec["source"], flip_test=rec.get("flip_test", False))
    for k in ("mpjpe", "pa_mpjpe", "mrpe"):
        assert getattr(learned, k) == pytest.approx(rec["learned"][k], abs=TOL_MM), k
        assert getattr(analytic, k) == pytest.approx(rec["analytic_root"][k], abs=TOL_MM), k


@settings(max_examples=20, deadline=None)
@given(k=st.floats(0.1, 10.0), shift=st.tuples(st.floats(-300, 300), st.floats(-300, 300)),
       source=st.sampled_from(["clean", "detected"]))
def test_default_is_invariant_to_image_scale_and_principal_point(k, shift, source):
    """The shipped default, on the issue's property: the same physical camera imaged at k x the resolution
    (keypoints, focal and principal point scaled together), or with the principal point and the 2D moved
    together, gives the same root and pose (the issue asks within 0.5 %; camera-space input makes it exact up to
    float32 rounding, and it is tested at that: a review found a principal point rounded to whole pixels, 1.8 mm
    of pose, passed the 0.5 % tolerance)."""
    lifter = _default()
    if lifter.config.input_space != "camera":
        pytest.skip("the default reads pixels; only reference-camera models are invariant by construction")
    pose = _DEMO.pose_3d
    kp = project(pose, focal=_F, principal_point=_C)
    a = lifter.lift(kp, focal=_F, principal_point=_C, source=source)
    b = lifter.lift(kp * k, focal=_F * k, principal_point=_C * k, source=source)
    d = np.asarray(shift)
    c = lifter.lift(kp + d, focal=_F, principal_point=_C + d, source=source)
    for other in (b, c):
        np.testing.assert_allclose(other.root, a.root, rtol=1e-5)
        np.testing.assert_allclose(other.relative, a.relative, rtol=0, atol=0.01)


def test_default_knows_the_root_only_up_to_z_over_f_without_a_focal():
    """Unknown focal (paper Eq. 5-6): the lift assumes the reference camera and says so; what it states is Z/f
    (the canonical depth / F0), and the root lies on the ray of the 2D root through that camera."""
    lifter = _default()
    kp = project(_DEMO.pose_3d, focal=_F, principal_point=_C)
    res = lifter.lift(kp, principal_point=_C)
    assert not res.metric_depth and res.focal_source == "reference"
    assert res.input_space == "camera" == lifter.input_space and "rest on that assumption" in res.note
    assert lifter.clean is not None
    assert lifter.lift(kp, principal_point=_C, source="clean").input_space == lifter.clean.input_space == "camera"
    f = res.focal[..., 0]
    assert res.root[2] / f == pytest.approx(res.canonical_depth / CANONICAL_FOCAL, rel=1e-6)
    np.testing.assert_allclose(project(res.root[None], focal=f, principal_point=_C)[0], kp[0], atol=1e-3)


def test_a_saved_network_loads_back_to_the_same_lift(tmp_path):
    """Lifter.save keeps the network's flip-test default (user trial: save_checkpoint(net, codec) reloaded with the
    flip test off, root z 3268 instead of 3291 mm); an int8 lifter is refused with what to do instead."""
    lifter = _default()
    kp = project(_DEMO.pose_3d, focal=_F, principal_point=_C)
    nets = lifter.networks()
    assert list(nets) == ["detected 1", "detected 2", "clean"]
    first = nets["detected 1"]
    assert first.flip_test and first.network_rows() == 2  # its width-1024 detected network: flip test on
    mine = Lifter.from_checkpoint(first.save(tmp_path / "my.pt"))
    assert mine.flip_test and not mine.ensemble and mine.clean is None
    alone = Lifter(lifter.net, lifter.codec, flip_test=True)
    got = mine.lift(kp, focal=_F, principal_point=_C).absolute
    np.testing.assert_array_equal(got, alone.lift(kp, focal=_F, principal_point=_C).absolute)
    assert np.abs(got - mine.lift(kp, focal=_F, principal_point=_C, flip_test=False).absolute).max() > 1.0
    for key, src in (("detected 2", "detected"), ("clean", "clean")):  # every network reloads to its own lifts
        back = Lifter.from_checkpoint(nets[key].save(tmp_path / f"{key}.pt"))
        np.testing.assert_array_equal(back.lift(kp, focal=_F, principal_point=_C, source=src).absolute,
                                      nets[key].lift(kp, focal=_F, principal_point=_C, source=src).absolute)
    # the whole default would reload as one network, lifting differently: refused, with what to do instead
    with pytest.raises(PoseLifterError, match=r"has 3 networks \(detected 1, detected 2, clean\).*networks\(\)"):
        lifter.save(tmp_path / "all.pt")
    assert not (tmp_path / "all.pt").exists()
    with pytest.raises(PoseLifterError, match="int8 weights.*quantize=True"):
        first.quantized().save(tmp_path / "q.pt")


def test_pixel_models_warn_outside_the_2d_sizes_they_were_trained_on(tmp_path):
    """User trial: the paper's pixel-space models put a person behind the camera on an ordinary 4000-px view of an
    H36M frame (intrinsics scaled with it: the same physical camera), silently, exit code 0. They now say so, in
    Python warnings and in the result; a focal length alone (the teacher's slider) changes nothing they read and
    is not warned of; the default (reference-camera input) stays exact and quiet."""
    from lifter.api import H36M_POSE_PX

    kp = project(_DEMO.pose_3d, focal=_F, principal_point=_C)
    gt = Lifter.from_pretrained("gt")
    assert gt.trained_pixel_range == pytest.approx(H36M_POSE_PX)  # no zoom augmentation: H36M's poses only
    lo, hi, off = H36M_POSE_PX
    k = 2 ** 0.5  # their zoom: log2 scale with sigma 0.5 (clipped at 1): the typical range, not the clip
    assert Lifter.from_pretrained("sh_mix").trained_pixel_range == pytest.approx((lo / k, hi * k, off * k), rel=1e-4)
    assert _default().trained_pixel_range is None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert gt.lift(kp, focal=_F, principal_point=_C).warnings == ()  # at home: nothing to say
        assert gt.lift(kp, focal=4 * _F, principal_point=_C).warnings == ()  # Z x4, the network reads the same
        for k in (0.1, 4.0, 10.0):
            assert _default().lift(kp * k, focal=_F * k, principal_point=_C * k).warnings == ()
    with pytest.warns(PoseLifterWarning) as record:
        res = gt.lift(np.stack([kp, kp * 4]), focal=np.array([[_F, _F], [4 * _F, 4 * _F]]),
                      principal_point=np.stack([_C, 4 * _C]))
    assert res.root[1, 2] <= 0 < res.root[0, 2]  # the extrapolation this warns of (else the test proves nothing)
    said = [str(w.message) for w in record]
    assert len(said) == 2 == len(res.warnings) and said == list(res.warnings)
    assert "trained on 2D poses 35-208 px in scale" in said[0] and "(pose at index (1,), 1 such" in said[0]
    assert "use the default model" in said[0]
    assert "1 of 2 root(s) behind the camera (Z <= 0) (pose at index (1,)" in said[1]
    assert res.to_dict()["warnings"] == said
    # (the video records count them by kind)
    assert [getattr(n, "kind", None) for n in res.warnings] == ["pixel-range", "behind-camera"]
    # what the records (CLI, files) carry: a keypoint file of the 4x view
    from lifter.pipeline import lift_keypoint_file

    p = tmp_path / "big.json"
    p.write_text(json.dumps({"format": "h36m17", "keypoints": (kp * 4).tolist(), "focal": 4 * _F,
                             "principal_point": (_C * 4).tolist(), "image_size": [4096, 4096]}))
    assert any("trained on 2D poses" in w for w in lift_keypoint_file(p, lifter=gt).warnings)
    assert not any("trained on 2D poses" in w for w in lift_keypoint_file(p, lifter=_default()).warnings)
    # a keypoint sequence: once per kind, from the first frame that has it, with how many frames do
    from lifter.video import lift_keypoint_sequence

    frames = [{"keypoints": (kp + 3 * _C if i < 2 else kp * 4).tolist()} for i in range(5)]  # (x1 about the same pp)
    q = tmp_path / "seq.json"
    q.write_text(json.dumps({"format": "h36m17", "fps": 10, "focal": 4 * _F, "principal_point": (_C * 4).tolist(),
                             "image_size": [4096, 4096], "frames": frames}))
    said = [w for w in lift_keypoint_sequence(q, lifter=gt).warnings if "reads pixels" in w or "behind" in w]
    assert len(said) == 2 and said[0].startswith("frame 2: model 'gt' reads pixels") and "(3 frames like it)" in said[0]
    assert said[1].startswith("frame 2: the model placed 1 of 1 root(s) behind the camera"), said


def test_trained_pixel_range_comes_from_the_training_config():
    """A pixel-space checkpoint with its training config: H36M's 2D poses times its zoom range; none without a
    config (unknown) and none for the reference camera (exact at every image size)."""
    from lifter.api import H36M_POSE_PX
    from lifter.codec import PoseCodec
    from lifter.config import AugmentConfig, TrainConfig
    from lifter.model import ModelConfig, PoseLifterNet

    cfg = ModelConfig(width=16, num_blocks=1, input_space="pixel", depth_target="canonical")
    net, codec = PoseLifterNet(cfg), PoseCodec(cfg)
    zoomed = TrainConfig(model=cfg, augment=AugmentConfig(zoom=True, zoom_sigma=0.5, zoom_clip=1.0)).to_dict()
    k = 2 ** 0.5  # one standard deviation of log2 zoom, within the clip
    lo, hi, off = H36M_POSE_PX
    assert Lifter(net, codec, train_config=zoomed).trained_pixel_range == pytest.approx((lo / k, hi * k, off * k))
    plain = TrainConfig(model=cfg).to_dict()
    assert Lifter(net, codec, train_config=plain).trained_pixel_range == pytest.approx(H36M_POSE_PX)
    assert Lifter(net, codec).trained_pixel_range is None
    cam = ModelConfig(width=16, num_blocks=1)
    assert Lifter(PoseLifterNet(cam), PoseCodec(cam), train_config=plain).trained_pixel_range is None


@requires_h36m
def test_h36m_pose_range_is_that_of_the_training_poses(h36m):
    from lifter.api import H36M_POSE_PX
    from lifter.normalization import location_and_scale

    s = h36m.load_protocol(1, "train", stride=1)
    loc, scale = location_and_scale(s.keypoints_2d.astype(np.float64))
    offset = np.linalg.norm(loc - s.principal_point, axis=-1)
    assert (scale.min(), scale.max(), offset.max()) == pytest.approx(H36M_POSE_PX, abs=0.1)


def test_the_default_learned_pinhole_2d_and_the_paper_models_h36m_2d():
    """Every network of the default was trained on undistorted 2D (so users' undistorted 2D is what it knows, and
    H36M's 2D is lifted with its camera's lens); the paper's models keep H36M's distorted 2D."""
    assert {n.lens for n in _default().networks().values()} == {"pinhole"}
    assert {Lifter.from_pretrained(m).lens for m in ("gt", "mixture", "sh_mix", "blazepose")} == {"h36m"}


@requires_h36m
def test_the_default_places_pinhole_2d_and_lens_2d_alike(h36m):
    """The same poses as H36M's camera sees them through its lens (given the lens) and as an ideal pinhole sees
    them: the default gives the same roots to float precision, and without the lens the distorted 2D is off."""
    s = h36m.load([9], stride=2000)
    pin = h36m.load([9], stride=2000, lens="pinhole")
    for source in ("clean", "detected"):
        a = _default().lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point, source=source,
                            distortion=s.distortion)
        b = _default().lift(pin.keypoints_2d, focal=s.focal, principal_point=s.principal_point, source=source)
        np.testing.assert_allclose(a.root, b.root, rtol=1e-5, atol=0.01)  # mm: float32 2D, undistorted to ~1e-4 px
        c = _default().lift(s.keypoints_2d, focal=s.focal, principal_point=s.principal_point, source=source)
        assert np.abs(c.root[:, 2] / a.root[:, 2] - 1).mean() > 1e-3  # (the lens moves depth by ~1 %)


@requires_h36m
def test_the_default_holds_on_a_camera_turned_away_from_human36m_s(h36m):
    """Human3.6M's cameras look 11-15 deg down from about 1.5 m. The default was trained with turned cameras, so a
    test camera tilted up by 15 deg (about level) or panned by 20 deg lifts as well as the recorded view, told clean
    or detected; `universal`, the default before, read depth from the image position and fails there (README,
    "Any camera pose")."""
    from lifter.evaluate import turned_camera_samples

    s = h36m.load_protocol(1, "test", stride=500)
    default, before = _default(), Lifter.from_pretrained("universal")
    for source in ("clean", "detected"):
        ref = evaluate_lifter(default, s, progress=False, source=source)[0]
        for pan, tilt in ((0.0, 15.0), (20.0, 0.0), (0.0, -15.0)):
            v = turned_camera_samples(s, pan_deg=pan, tilt_deg=tilt)
            row = evaluate_lifter(default, v, progress=False, source=source)[0]
            assert row.mpjpe < ref.mpjpe + 3.0 and row.mrpe < 1.3 * ref.mrpe, (source, pan, tilt, row, ref)
        old = evaluate_lifter(before, turned_camera_samples(s, pan_deg=0.0, tilt_deg=15.0), progress=False,
                              source=source)[0]
        assert old.mpjpe > 2 * ref.mpjpe and old.mrpe > 4 * ref.mrpe, (source, old)


def test_far_people_are_placed_at_their_distance_and_beyond_the_training_noted(tmp_path):
    """A user trial: people in the background were placed far too near (exact 2D at 12 m: -21 %) with no word. The
    default's networks were trained with people moved along their rays up to 5 x farther: a person at 14 m is lifted
    within 5 % of it, from detected and clean 2D alike, with no note, and the same at a quarter image size (the distance
    is what the networks read). Beyond its training (38 m) a detected-2D lift says so. universal_turn, trained where
    the subjects stood, still places them too near, and its notes say so from 8 m."""
    from lifter.api import FAR_ROOT_DEPTH_MM, TRAINING_ROOT_MAX_MM

    lifter, before = Lifter.from_pretrained(), Lifter.from_pretrained("universal_turn")
    assert lifter.far_root_depth_mm == pytest.approx(5 * TRAINING_ROOT_MAX_MM)
    assert before.far_root_depth_mm == FAR_ROOT_DEPTH_MM
    s = demo_sample("walking")
    f, c = s.focal, s.principal_point
    pose = np.asarray(s.pose_3d, np.float64)

    def at(z: float) -> np.ndarray:
        return project(pose - pose[:1] + np.array([0.0, 0.0, z]), focal=f, principal_point=c)

    kp = at(14000.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)
        far = lifter.lift(kp, focal=f, principal_point=c)
        clean = lifter.lift(kp, focal=f, principal_point=c, source="clean")
        quarter = lifter.lift(kp * 0.25, focal=np.asarray(f) * 0.25, principal_point=np.asarray(c) * 0.25)
    for r in (far, clean):
        assert not r.warnings and float(r.root[2]) == pytest.approx(14000.0, rel=0.05)
    assert float(quarter.root[2]) == pytest.approx(float(far.root[2]), rel=1e-4)
    with pytest.warns(PoseLifterWarning, match=r"root.s. lifted beyond 38.0 m.*training moved people .*7.6 m times 5"):
        very_far = lifter.lift(at(60000.0), focal=f, principal_point=c)
    assert float(very_far.root[2]) > 5 * TRAINING_ROOT_MAX_MM and any(w.kind == "far" for w in very_far.warnings)
    # in a record of several people (a photo, a keypoint file) the note names the person in the output's list
    from lifter.pipeline import lift_people

    notes: list[str] = []
    f2 = np.broadcast_to(np.asarray(f, np.float64), (2,))
    lift_people(lifter, np.stack([at(4000.0), at(60000.0)]), f2, np.asarray(c, np.float64), flip_test=None,
                source="detected", notes=notes)
    assert [getattr(n, "kind", "") for n in notes] == ["far"] and "(person 2 of the output's people)" in notes[0]
    # and in a keypoint sequence, the person of the frame, as the frame's output lists them
    from lifter.video import lift_keypoint_sequence

    frames = [[{"keypoints": at(4000.0).tolist()}, {"keypoints": at(60000.0 + 100 * i).tolist()}] for i in range(6)]
    seq = tmp_path / "far_seq.json"
    seq.write_text(json.dumps({"format": "h36m17", "fps": 10, "focal": float(np.mean(f)),
                               "principal_point": np.asarray(c, float).tolist(), "frames": frames}))
    rec = lift_keypoint_sequence(seq, lifter=lifter)
    far_notes = [w for w in rec.warnings if "beyond 38.0 m" in w]
    far_id = rec.frames[0].people[1].track_id
    assert far_id == 2 and rec.frames[0].people[1].root_raw[2] > 38000.0
    assert len(far_notes) == 1 and f"frame 0: 1 of 2 root(s) lifted beyond 38.0 m (track {far_id})" in far_notes[0]
    assert "(6 frames like it)" in far_notes[0], rec.warnings
    # and in a video, by its track id, not by its place in the frame's list (the near person, who came into view
    # later, is listed first as the larger one; a position would not find the far one in the record)
    cv2 = pytest.importorskip("cv2")
    from conftest import ScriptedEstimator

    from lifter.video import lift_video

    W, H = s.image_size
    clip = tmp_path / "far.avi"
    vw = cv2.VideoWriter(str(clip), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (W, H))
    for _ in range(10):
        vw.write(np.zeros((H, W, 3), np.uint8))
    vw.release()
    script = [[at(60000.0)] + ([at(4000.0)] if i >= 2 else []) for i in range(10)]
    vid = lift_video(clip, lifter=lifter, estimator=ScriptedEstimator(script), focal=float(np.mean(f)),
                     principal_point=np.asarray(c, float))
    late = vid.frames[5].people
    assert [q.track_id for q in late] == [2, 1] and late[1].root_raw[2] > 38000.0  # far: listed second, track 1
    far_notes = [w for w in vid.warnings if "beyond 38.0 m" in w]
    assert len(far_notes) == 1 and "frame 0: 1 of 1 root(s) lifted beyond 38.0 m (track 1)" in far_notes[0]
    assert "(10 frames like it)" in far_notes[0], vid.warnings
    with pytest.warns(PoseLifterWarning, match="beyond 8.0 m.*trained where they stood, place such people too near"):
        old = before.lift(kp, focal=f, principal_point=c)
    assert float(old.root[2]) < 0.85 * 14000.0 and any(w.kind == "far" for w in old.warnings)


def test_the_default_notes_detected_2d_its_lift_does_not_fit():
    """A user trial's portrait photo: BlazePose bunched the person's joints with high scores, and the lift (MPJPE
    552 mm) came with no note. The default notes detected 2D whose lift, projected back, misses it by more than its
    measured limit (registry ``misfit_limit``, scripts/misfit.py); good 2D and clean 2D get no such note."""
    import warnings

    from lifter import PoseLifterWarning
    from lifter.camera import MAX_DETECTED_MISFIT, reprojection_misfit

    lf = _default()
    assert lf.network_for("detected").misfit_limit == MAX_DETECTED_MISFIT
    kp, f, pp = _DEMO.keypoints_2d, _DEMO.focal, _DEMO.principal_point
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)
        good = lf.lift(kp, focal=f, principal_point=pp)  # (a clean render told "detected": fits)
    assert float(reprojection_misfit(good.keypoints_2d, good.absolute, focal=f, principal_point=pp)) < 0.05
    # a detector's confident mistake: the head and nose put on the right ankle and knee (misfit about 0.23; legs
    # merely bunched read as a crouch, which the lift fits)
    bad = kp.copy()
    bad[[10, 9]] = kp[[3, 2]]
    with pytest.warns(PoseLifterWarning, match=r"1 of 1 lifted pose\(s\) do not fit their 2D: projected back, the "
                                               r"joints lie up to \d+\.\d% of the 2D pose's size"):
        res = lf.lift(bad, focal=f, principal_point=pp)
    assert [w.kind for w in res.warnings] == ["misfit"]
    with warnings.catch_warnings():
        warnings.simplefilter("error", PoseLifterWarning)
        # (the clean network fits this one: under its own limit, measured on exact 2D)
        lf.lift(bad, focal=f, principal_point=pp, source="clean")


def test_the_default_notes_clean_2d_in_another_joint_order():
    """A developer trial: exact 2D with the knees and elbows swapped, told source="clean", was lifted 3.3 m too near
    with no note (24 of 40 random joint orders had none); the misfit note was for detected 2D only. The clean network
    has its own limit (MAX_CLEAN_MISFIT, measured on the training subjects' exact 2D): the shipped samples in H36M
    order are not noted, the same joints in another order are, naming that cause."""
    import warnings

    from lifter.camera import MAX_CLEAN_MISFIT, reprojection_misfit

    lf = _default()
    assert lf.network_for("clean").misfit_limit == MAX_CLEAN_MISFIT
    for name in ("walking", "sitting", "standing", "reaching", "crouching"):
        d = demo_sample(name)
        with warnings.catch_warnings():
            warnings.simplefilter("error", PoseLifterWarning)
            lf.lift(d.keypoints_2d, focal=d.focal, principal_point=d.principal_point, source="clean")
    kp, f, pp = _DEMO.keypoints_2d, _DEMO.focal, _DEMO.principal_point
    swapped = kp[[0, 1, 15, 3, 4, 12, 6, 7, 8, 9, 10, 11, 5, 13, 14, 2, 16]]  # knees <-> elbows
    with pytest.warns(PoseLifterWarning, match=r"1 of 1 lifted pose\(s\) do not fit their 2D: projected back, the "
                                               r"joints lie up to \d+\.\d% of the 2D pose's size from it \(median "
                                               r"joint\), where exact 2D of real people stays under 13%: the 2D is "
                                               r"probably wrong in places \(joints in another order than Human3.6M's"):
        res = lf.lift(swapped, focal=f, principal_point=pp, source="clean")
    assert [w.kind for w in res.warnings] == ["misfit"]
    assert float(reprojection_misfit(res.keypoints_2d, res.absolute, focal=f, principal_point=pp)) > MAX_CLEAN_MISFIT
