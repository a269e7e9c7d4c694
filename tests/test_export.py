"""GLB and BVH export: files load back to the same joint positions."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from conftest import random_pose_cam

from lifter import PoseLifterError, PoseLifterWarning
from lifter.export import (
    bvh_animation_text,
    bvh_text,
    from_y_up,
    read_bvh,
    read_bvh_frames,
    read_glb_joints,
    to_y_up,
    write_bvh,
    write_bvh_animation,
    write_glb,
)
from lifter.skeleton import EDGES, JOINT_NAMES, PARENTS


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
    scene: Any = trimesh.load(str(path), force="scene")
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
    with pytest.raises(PoseLifterError, match=r"\(n, 17, 3\)"):
        write_glb(np.zeros((2, 2, 17, 3)), "/nonexistent/x.glb")
    with pytest.raises(PoseLifterError, match="fps"):
        bvh_animation_text(np.zeros((3, 17, 3)), fps=0)
    with pytest.raises(PoseLifterError, match="units"):
        bvh_text(np.zeros((17, 3)), units="inch")


def test_glb_several_people_in_one_scene(tmp_path):
    poses = random_pose_cam(np.random.default_rng(5), 3)
    p = write_glb(poses, tmp_path / "three.glb")
    for k in range(3):
        np.testing.assert_allclose(read_glb_joints(p, person=k), poses[k], atol=1e-3)
    with pytest.raises(PoseLifterError, match=r"person 3 is not in this GLB: it holds 3 people \(person = 0 .. 2\)"):
        read_glb_joints(p, person=3)


def test_bvh_animation_round_trip(tmp_path):
    """Every frame comes back exactly, bone lengths changing from frame to frame included."""
    rng = np.random.default_rng(7)
    poses = random_pose_cam(rng, 1)[0][None] + np.cumsum(rng.normal(0, 8, (40, 17, 3)), axis=0)
    p = write_bvh_animation(poses, tmp_path / "walk.bvh", fps=25.0)
    text = p.read_text()
    assert "Frames: 40" in text and "Frame Time: 0.040000" in text
    np.testing.assert_allclose(read_bvh_frames(p), poses, atol=1e-3)
    np.testing.assert_allclose(read_bvh(p), poses[0], atol=1e-3)
    one = write_bvh(poses[3], tmp_path / "one.bvh")  # the single-pose writer still reads back
    np.testing.assert_allclose(read_bvh_frames(one)[0], poses[3], atol=1e-3)


def _bvh_parse(text: str):
    """An independent BVH reader for the tests: joints (name, parent, OFFSET, channels) and the MOTION rows."""
    head, motion = text.split("MOTION")
    joints, stack, pending, end_site = [], [], -1, False
    tok = head.split()
    i = 0
    while i < len(tok):
        t = tok[i]
        if t in ("ROOT", "JOINT"):
            joints.append([tok[i + 1], stack[-1] if stack else -1, None, []])
            pending, i = len(joints) - 1, i + 2
        elif t == "End":
            end_site, i = True, i + 2
        elif t == "{":
            stack.append(-2 if end_site else pending)
            i += 1
        elif t == "}":
            end_site = False if stack.pop() == -2 else end_site
            i += 1
        elif t == "OFFSET":
            if stack[-1] != -2:
                joints[stack[-1]][2] = np.array([float(v) for v in tok[i + 1:i + 4]])
            i += 4
        elif t == "CHANNELS":
            joints[stack[-1]][3] = tok[i + 2:i + 2 + int(tok[i + 1])]
            i += 2 + int(tok[i + 1])
        else:
            i += 1
    rows = np.array([[float(v) for v in ln.split()] for ln in motion.splitlines()[3:] if ln.strip()])
    return joints, rows


def _fk_blender(joints, row):
    """Blender's reading of one MOTION row: a joint's transform is its translation (its position channels in place
    of its OFFSET) then its rotation (Euler channels in the listed order, intrinsic); positions and global
    rotations of every joint, in the file's order."""
    def rot(axis, deg):
        c, s_ = np.cos(np.radians(deg)), np.sin(np.radians(deg))
        return {"X": np.array([[1, 0, 0], [0, c, -s_], [0, s_, c]]),
                "Y": np.array([[c, 0, s_], [0, 1, 0], [-s_, 0, c]]),
                "Z": np.array([[c, -s_, 0], [s_, c, 0], [0, 0, 1]])}[axis]

    pos, glob, k = [], [], 0
    for _, parent, off, ch in joints:
        t, R = off.copy(), np.eye(3)
        for c in ch:
            if c.endswith("position"):
                t["XYZ".index(c[0])] = row[k]
            else:
                R = R @ rot(c[0], row[k])
            k += 1
        if parent < 0:
            pos.append(t)
            glob.append(R)
        else:
            pos.append(pos[parent] + glob[parent] @ t)
            glob.append(glob[parent] @ R)
    return np.array(pos), np.array(glob)


def test_bvh_euler_channels_give_back_the_rotation_gimbal_lock_included():
    """The animation's rotation channels (Zrotation Xrotation Yrotation, read in that order, intrinsic) turned back
    into matrices as the BVH reader composes them are the rotations written, at x = +-90 deg too."""
    from lifter.export import _euler_zxy_deg, _rot

    rng = np.random.default_rng(0)
    q, r = np.linalg.qr(rng.normal(size=(500, 3, 3)))
    R = q * np.sign(np.diagonal(r, axis1=-2, axis2=-1))[:, None, :]
    R[np.linalg.det(R) < 0] *= -1  # (rotations, not reflections)
    R = np.concatenate([R, np.stack([_rot("Z", 30) @ _rot("X", s * 90) @ _rot("Y", 40) for s in (1, -1)])])
    back = np.stack([_rot("Z", z) @ _rot("X", x) @ _rot("Y", y) for z, x, y in _euler_zxy_deg(R)])
    np.testing.assert_allclose(back, R, atol=1e-9)


def test_bvh_animation_is_a_rig_whose_bones_point_at_their_joints(tmp_path):
    """A review: the animation's position channels held each bone's change from its OFFSET, added to it, where
    Blender's importer takes them as the joint's whole translation (every bone a few mm long); then a trial: with no
    rotations, and rest bones the mean bone vectors (short where the person turned), Blender drew each bone from its
    joint along its rest direction, 15-20 cm off the child joint on average. Read as Blender reads it (independently
    here), every joint is where the lift put it, and every bone of a joint with one child, turned by the rotations,
    points at that child; the rest bones have the bones' mean lengths."""
    rng = np.random.default_rng(3)
    base = random_pose_cam(rng, 1)[0]
    turn = [np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]) for a in np.linspace(0, 3, 30)]
    poses = np.stack([(base - base[0]) @ R.T + base[0] + [5.0 * t, 0, 0] for t, R in enumerate(turn)])
    poses += rng.normal(0, 6, poses.shape)  # (a person turning half round and walking; bone lengths jitter)
    text = bvh_animation_text(poses, fps=25.0)
    joints, rows = _bvh_parse(text)
    assert rows.shape == (30, 17 * 6) and np.abs(rows.reshape(30, 17, 6)[:, :, 3:]).max() > 20  # (turned)
    names = [j[0] for j in joints]
    y_up = to_y_up(poses) / 10.0  # cm
    for t in range(30):
        pos, glob = _fk_blender(joints, rows[t])
        np.testing.assert_allclose(pos[[names.index(n) for n in JOINT_NAMES]], y_up[t], atol=1e-3)
        for k in range(len(joints)):
            kids = [c for c, q in enumerate(joints) if q[1] == k]
            if len(kids) == 1:  # (its bone drawn along its turned rest bone: at the child)
                drawn = glob[k] @ joints[kids[0]][2]
                real = pos[kids[0]] - pos[k]
                cos = drawn @ real / np.linalg.norm(drawn) / np.linalg.norm(real)
                assert cos > 1 - 1e-6, (t, names[k], cos)
    # (a review) a body turning twice round, rigid: only the root turns, each joint only by its own bend (none here:
    # before, every joint's channels undid the body's turn), and the channels run on without jumps of whole turns
    spin = np.stack([(base - base[0]) @ np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]]).T
                     + base[0] for a in np.linspace(0, 4 * np.pi, 121)])
    sj, srows = _bvh_parse(bvh_animation_text(spin, fps=25.0))
    ch = srows.reshape(121, 17, 6)[:, :, 3:]
    assert np.abs(ch[:, 1:]).max() < 1e-3  # (the joints after the root: no turn of their own)
    assert np.abs(np.diff(ch[:, 0], axis=0)).max() < 10.0  # (6 deg a frame: continuous, no 360-deg wraps)
    assert np.ptp(ch[:, 0]).max() > 700  # (the root's channels run on through the two turns)
    for t in (0, 60, 120):
        pos, _ = _fk_blender(sj, srows[t])
        np.testing.assert_allclose(pos[[[j[0] for j in sj].index(n) for n in JOINT_NAMES]], to_y_up(spin[t]) / 10.0,
                                   atol=1e-3)
    lengths = np.linalg.norm(y_up - y_up[:, [max(q, 0) for q in PARENTS]], axis=-1).mean(0)
    for name, _, off, _ in joints[1:]:
        assert np.linalg.norm(off) == pytest.approx(lengths[JOINT_NAMES.index(name)], abs=1e-4)
    np.testing.assert_allclose(read_bvh_frames(write_bvh_animation(poses, tmp_path / "turn.bvh", fps=25.0)), poses,
                               atol=1e-3)
    # a Blender-style root: OFFSET at rest, channels absolute
    blender = text.replace("ROOT pelvis\n{\n  OFFSET 0.00000 0.00000 0.00000",
                           "ROOT pelvis\n{\n  OFFSET 0.00000 90.00000 0.00000")
    assert blender != text
    (tmp_path / "blender.bvh").write_text(blender)
    np.testing.assert_allclose(read_bvh_frames(tmp_path / "blender.bvh"), poses, atol=1e-3)
    # the earlier convention (OFFSETs the mean bone vectors, channels = bone - OFFSET, no rotations), read with
    # position_channels="add", and named when read without it
    from lifter.export import _bvh_hierarchy

    bones = y_up - y_up[:, [max(q, 0) for q in PARENTS]]
    bones[:, 0] = y_up[:, 0]
    mean = bones.mean(0)
    mean[0] = 0.0
    hier, order = _bvh_hierarchy(mean, lambda v: " ".join(f"{x:.5f}" for x in v), lambda j: "CHANNELS 6 Xposition "
                                 "Yposition Zposition Zrotation Xrotation Yrotation")
    old_rows = np.concatenate([bones - mean, np.zeros_like(bones)], axis=-1)[:, order].reshape(30, -1)
    old_text = "\n".join(hier) + "\nMOTION\nFrames: 30\nFrame Time: 0.040000\n" + "\n".join(
        " ".join(f"{v:.5f}" for v in r) for r in old_rows) + "\n"
    (tmp_path / "old.bvh").write_text(old_text)
    np.testing.assert_allclose(read_bvh_frames(tmp_path / "old.bvh", position_channels="add"), poses, atol=1e-3)
    with pytest.warns(PoseLifterWarning, match=r"old.bvh: its joints' position channels read as each bone's change "
                                               r"from its OFFSET .* read it with position_channels=\"add\""):
        assert np.abs(read_bvh_frames(tmp_path / "old.bvh") - poses).max() > 50  # (not the same files, and said)
    with pytest.raises(PoseLifterError, match="position_channels must be 'replace' or 'add'"):
        read_bvh_frames(tmp_path / "old.bvh", position_channels="sum")  # type: ignore[arg-type]


def _gltf(path):
    import json
    import struct

    raw = path.read_bytes()
    n = struct.unpack_from("<I", raw, 12)[0]
    gltf = json.loads(raw[20:20 + n])
    blob = raw[20 + n + 8:]

    def read(i):
        acc = gltf["accessors"][i]
        view = gltf["bufferViews"][acc["bufferView"]]
        w = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[acc["type"]]
        return np.frombuffer(blob, np.float32, acc["count"] * w, view.get("byteOffset", 0)).reshape(-1, w)

    return gltf, read


def test_glb_animation_keys_each_track_over_its_own_span(tmp_path):
    """A review: every track was keyed at every frame of the clip, however briefly seen (five people seen 1 s each
    in a 10-minute clip: 95 MB). A track is keyed from the frame before its first to the frame after its last; a
    glTF player, which holds the first and last keys outside them, hides it there (checked here by evaluating the
    samplers as glTF says, not by the module's reader)."""
    from lifter.export import read_glb_animation, write_glb_animation

    rng = np.random.default_rng(2)
    b = random_pose_cam(rng, 1)[0][None] + rng.normal(0, 5, (5, 17, 3))
    p = write_glb_animation({4: (np.array([300, 301, 302, 306, 307]), b)}, tmp_path / "late.glb", fps=25.0,
                            span=(0, 2999))
    assert p.stat().st_size < 150_000  # (3,000 frames keyed for the one track: 3.2 MB)
    gltf, read = _gltf(p)
    assert gltf["animations"][0]["extras"] == {"fps": 25.0, "first_frame": 0, "last_frame": 2999}
    names = {n["name"]: i for i, n in enumerate(gltf["nodes"])}
    anim = gltf["animations"][0]

    def sampler(node_name, what):
        (ch,) = [c for c in anim["channels"] if c["target"] == {"node": names[node_name], "path": what}]
        smp = anim["samplers"][ch["sampler"]]
        return read(smp["input"])[:, 0].astype(np.float64), read(smp["output"]), smp["interpolation"]

    t, xyz, how = sampler("track4_joint_pelvis", "translation")
    assert how == "LINEAR"
    # its span, and the clip's first and last frames: every track's keys end where the clip does (a review: a player
    # takes the clip's length from its latest key, and the animation was 2 s of a 10-s video)
    np.testing.assert_allclose(t, np.r_[0, np.arange(299, 309), 2999] / 25.0, rtol=1e-6)
    ends = [gltf["accessors"][smp_["input"]]["max"][0] for smp_ in anim["samplers"]]
    np.testing.assert_allclose(ends, 2999 / 25.0, rtol=1e-6)
    # the joints are children of the track's node, which is shown or hidden: the scene's only roots
    assert gltf["scenes"][0]["nodes"] == [names["track4"]]
    assert sorted(gltf["nodes"][names["track4"]]["children"]) == sorted(
        i for n, i in names.items() if n.startswith("track4_"))
    tv, vis, how = sampler("track4", "scale")
    assert how == "STEP"

    def shown(sec):  # (glTF STEP: the last key at or before the time; before the first key, the first)
        return float(vis[max(int(np.searchsorted(tv, sec, side="right")) - 1, 0), 0])

    def where(sec):  # (glTF LINEAR, held before the first key and after the last), metres y-up
        return np.array([np.interp(sec, t, xyz[:, c]) for c in range(3)])

    seen, unseen = [300, 301, 302, 306, 307], [0, 298, 299, 303, 304, 305, 308, 309, 2999]
    # at each frame's time, and a hair either side of it (a player's clock need not land on the float32 key times;
    # a trial's player grew a person in between two frames with LINEAR scales, and STEP keys on the frames' times
    # showed a person a frame late)
    for eps in (0.0, -1e-5, 1e-5):
        assert [shown(f / 25.0 + eps) for f in seen] == [1.0] * 5
        assert [shown(f / 25.0 + eps) for f in unseen] == [0.0] * 9
    # shown from half a frame before their first frame, already where they are in it (not sliding in from elsewhere);
    # likewise until half a frame after the frame they leave in, and into the gap (303-305) at no more than the
    # straight line's pace from where they left to where they come back
    assert shown(299.6 / 25.0) == 1.0 and shown(302.4 / 25.0) == 1.0 and shown(302.6 / 25.0) == 0.0
    pelvis = to_y_up(b[:, 0]) / 1000.0
    np.testing.assert_allclose(where(299.6 / 25.0), pelvis[0], atol=1e-6)
    np.testing.assert_allclose(where(307.4 / 25.0), pelvis[4], atol=1e-6)
    np.testing.assert_allclose(where(302.4 / 25.0), pelvis[2] + 0.4 * (pelvis[3] - pelvis[2]) / 4, atol=1e-6)
    times, joints = read_glb_animation(p)
    np.testing.assert_allclose(times, np.arange(3000) / 25.0)
    np.testing.assert_allclose(joints[4][[300, 301, 302, 306, 307]], b, atol=0.05)
    assert np.isnan(np.delete(joints[4], [300, 301, 302, 306, 307], axis=0)).all()
    with pytest.raises(PoseLifterError, match=r"frame indices must be whole numbers >= 0"):
        write_glb_animation({1: (np.array([0.5, 1.5]), b[:2])}, tmp_path / "x.glb", fps=25.0)
    with pytest.raises(PoseLifterError, match=r"frame indices must be whole numbers >= 0"):
        write_glb_animation({1: (np.array([-1, 0]), b[:2])}, tmp_path / "x.glb", fps=25.0)


def test_a_malformed_bvh_is_named(tmp_path, pose):
    """A review: a BVH with a word among its numbers raised a bare ValueError, without the file's name."""
    good = bvh_text(pose)
    bad = tmp_path / "bad.bvh"
    bad.write_text(good.rsplit("\n", 2)[0] + "\n" + "x " * 54 + "\n")
    with pytest.raises(PoseLifterError, match=r"bad.bvh: not a well-formed BVH file \(ValueError: could not convert"):
        read_bvh_frames(bad)
    bad.write_text(good.replace("Frames: 1", "Frames: 2"))
    with pytest.raises(PoseLifterError, match=r"bad.bvh: BVH MOTION has 54 values, expected 2 x 54"):
        read_bvh_frames(bad)
    bad.write_text(good.replace("Frames: 1", "Frames: 0"))
    with pytest.raises(PoseLifterError, match=r"bad.bvh: the BVH has no frames"):
        read_bvh(bad)  # (a review: a bare IndexError)
    with pytest.raises(PoseLifterError, match=r"frame_time must be > 0 s, got 0"):
        bvh_text(pose, frame_time=0.0)
    bad.write_text(good.replace("r_hip", "r_hipé"), encoding="utf-8")  # (read as UTF-8 on any system)
    with pytest.raises(PoseLifterError, match=r"BVH lacks the H36M joints \['r_hip'\]"):
        read_bvh_frames(bad)


def test_glb_animation_round_trip(tmp_path):
    """Two tracks over a clip: every joint of every frame comes back; a person is hidden where absent."""
    import trimesh

    from lifter.export import read_glb_animation, write_glb_animation

    rng = np.random.default_rng(11)
    a = random_pose_cam(rng, 1)[0][None] + np.cumsum(rng.normal(0, 10, (12, 17, 3)), axis=0)
    b = random_pose_cam(rng, 1)[0][None] + np.array([800.0, 0, 500]) + rng.normal(0, 5, (5, 17, 3))
    p = write_glb_animation({1: (np.arange(12), a), 4: (np.array([3, 4, 5, 9, 10]), b)}, tmp_path / "clip.glb",
                            fps=25.0)
    times, joints = read_glb_animation(p)
    np.testing.assert_allclose(times, np.arange(12) / 25.0, atol=1e-6)
    np.testing.assert_allclose(joints[1], a, atol=0.05)
    np.testing.assert_allclose(joints[4][[3, 4, 5, 9, 10]], b, atol=0.05)
    assert np.isnan(joints[4][[0, 1, 2, 6, 7, 8, 11]]).all()
    scene: Any = trimesh.load(str(p), file_type="glb", force="scene")  # a valid glTF for another reader too
    assert len(scene.geometry) == 2 * (17 + 16)
    with pytest.raises(PoseLifterError, match="increasing frame indices"):
        write_glb_animation({1: (np.array([2, 1]), a[:2])}, tmp_path / "x.glb", fps=25.0)
    # a span: the clip's own frames 0-15, everyone hidden where unseen (a user trial's clip began at frame 3's time)
    p = write_glb_animation({4: (np.array([3, 4, 5, 9, 10]), b)}, tmp_path / "span.glb", fps=25.0, span=(0, 15))
    times, joints = read_glb_animation(p)
    np.testing.assert_allclose(times, np.arange(16) / 25.0, atol=1e-6)
    np.testing.assert_allclose(joints[4][[3, 4, 5, 9, 10]], b, atol=0.05)
    assert np.isnan(joints[4][[0, 1, 2, 6, 7, 8, 11, 12, 13, 14, 15]]).all()
    with pytest.raises(PoseLifterError, match=r"span must be \(first, last\) frames"):
        write_glb_animation({4: (np.array([3, 4]), b[:2])}, tmp_path / "x.glb", fps=25.0, span=(5, 2))
    # frames the input does not hold (a sequence of every other frame, a developer trial: everyone blinked at half
    # its rate): a person seen either side is interpolated there and shown; a frame it holds without them hides them
    p = write_glb_animation({4: (np.array([3, 4, 5, 9, 10]), b)}, tmp_path / "rec.glb", fps=25.0, span=(0, 15),
                            recorded=[0, 1, 2, 3, 4, 5, 6, 9, 10, 11, 12, 13, 14, 15])
    times, joints = read_glb_animation(p)
    np.testing.assert_allclose(joints[4][[7, 8]], b[2] + (b[3] - b[2]) * np.array([2 / 4, 3 / 4])[:, None, None],
                               atol=0.05)
    assert np.isnan(joints[4][[0, 1, 2, 6, 11, 12, 13, 14, 15]]).all()
