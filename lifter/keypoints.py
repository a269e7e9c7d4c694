"""Keypoint formats: the one place where other detectors' joint sets meet the lifter's 17 H36M joints.

A format (:class:`KeypointFormat`) is a name, its joint names, and for each of the 17 H36M joints a
**rule**: an affine combination ``sum_k w_k * src[k]`` of the format's joints (weights sum to 1, so the
rule commutes with translation and scaling of the image). A joint the format has is a one-term rule
(a *direct* mapping); a joint it lacks is interpolated. Formats whose joints all exist in H36M can
also be produced from H36M (``dst=that format``): :func:`convert` goes ``src -> h36m17 -> dst``.
Register a new format with :func:`register_format` (the cascade issue adds e.g. ``"coco17"``).

Built-in formats
----------------
``"h36m17"``: the identity (:data:`lifter.skeleton.JOINT_NAMES`).

``"sh16"``: the Stacked-Hourglass / MPII 16-joint order of the H36M detections (data README): RFoot,
RKnee, RHip, LHip, LKnee, LFoot, Hip, Spine, Thorax, Head(top), RWrist, RElbow, RShoulder, LShoulder,
LElbow, LWrist. Measured on the training subjects' detections (S1, S5, S6, S7, S8, every 5th frame, 4
cameras, 293,116 samples) against the projected ground truth, the MPII-pretrained detector's joints
do **not** all mean what their names say:

* "Thorax" (index 8) is the H36M thorax (median distance 6.5 px): mapped directly.
* "Spine" (index 7) is MPII's *thorax*: it sits 87 % of the way from pelvis to thorax, 41 px (median)
  from the H36M spine, which lies halfway (48 %). Rule: ``spine = Hip + 0.585 (Spine - Hip)``.
* "Head" (index 9) is the top of the skull, above H36M's head joint (median 23 px away). Rule:
  ``head_top = Thorax + 0.483 (Head - Thorax)`` (median error 9.0 px instead of 23.1 px).
* H36M's Neck/Nose (9) has no counterpart. Rule: ``neck_nose = Thorax + 0.222 (Head - Thorax)``.

The three weights are least-squares fits of the 2D ground-truth joint onto the line through the two
detected joints, over all training samples (:func:`fit_line_weight`; ``poselifter fit-noise``
re-measures and prints them). Measured 2D errors on the training subjects (px, mean / median):

=================  ===========================  ================
joint              rule                         error (mean/med)
=================  ===========================  ================
spine              Hip + 0.585 (Spine - Hip)     7.5 / 6.1
spine (direct)     Spine                        41.8 / 41.2
neck_nose          Thorax + 0.222 (Head-Thorax) 10.4 / 8.7
head_top           Thorax + 0.483 (Head-Thorax) 13.3 / 9.0
head_top (direct)  Head                         26.4 / 23.1
=================  ===========================  ================

The pure interpolation error of the Neck/Nose rule on ground truth alone (neck = thorax + w (head -
thorax) with GT joints, w = 0.444 fitted on GT) is 10.0 px mean / 9.2 px median: the neck/nose is not
on the thorax-head line (it is the nose, in front of the neck), so no interpolation does much better.
The remaining 13 joints are direct. The same affine rules are applied to 3D input ``(..., J, 3)``;
they were fitted in 2D.


Detector formats: ``"blazepose33"``, ``"coco17"``, ``"openpose25"``
-------------------------------------------------------------------
MediaPipe BlazePose's 33 landmarks, MS-COCO's 17 keypoints and OpenPose's BODY_25 share the limb
joints (shoulders, elbows, wrists, knees, ankles: mapped directly) and a face (nose, eyes, ears).
With MH = mid-hips (OpenPose: its MidHip), MS = mid-shoulders (OpenPose: its Neck), ME = mid-ears,
N = nose, T = MS - MH (the trunk), the other seven H36M joints are (:func:`body_rules`):

==========  ==================================================  =====================================
joint       rule                                                why
==========  ==================================================  =====================================
pelvis      MH + 0.160 T                                        H36M's hip line is higher than COCO's
r/l_hip     MH + 1.223 (hip - MH) + 0.160 T                     ... and wider (mocap hip joint centres)
spine       MH + 0.628 T
thorax      MS + 0.087 T                                        slightly above the shoulder line
neck_nose   MS + 0.270 (N - MS) + 0.500 (ME - MS)
head_top    ME + 0.644 (ME - N) + 0.218 (ME - MS)               up from the ears, away from the face
==========  ==================================================  =====================================

The weights are least-squares fits to the ground truth 2D of the 84 H36M demo frames
(``../shared/data/h36m/demo``) of MediaPipe BlazePose's landmarks on those images, over the 78 of 82
detected frames whose median limb-joint error is below 15 px (``scripts/eval_cascade.py`` re-fits
and prints them). Measured error (px, mean / median over the 78 inlier frames; over all 82 detected frames
(2 of 84 have no detection) they are within 0.4 px of these):

==========  ============================  ==================  ============================
joint       naive mapping                 naive error         rule error (cross-camera*)
==========  ============================  ==================  ============================
pelvis      mid-hips                      18.8 / 18.5         4.6 / 4.2 (5.3 / 5.2)
r_hip       BlazePose r_hip               22.9 / 22.3         6.8 / 6.7 (7.5 / 8.1)
l_hip       BlazePose l_hip               16.1 / 15.8         6.4 / 5.3 (7.2 / 6.4)
spine       midpoint of MH and MS         15.3 / 15.5         3.7 / 2.7 (4.1 / 2.9)
thorax      mid-shoulders                 10.8 / 10.4         4.3 / 4.1 (4.4 / 4.9)
neck_nose   nose                          10.8 / 10.0         2.8 / 2.5 (3.4 / 3.0)
head_top    mid-ears                      13.1 / 12.6         3.5 / 3.1 (4.0 / 3.6)
==========  ============================  ==================  ============================

* worst of the two folds "fit on one camera's frames, test on the other camera's". The same
weights serve ``coco17`` (its joints are BlazePose's subset with the same meaning) and
``openpose25`` (MidHip and Neck in place of the midpoints). They were measured with BlazePose's
landmarks only (no COCO or OpenPose network runs offline here); another detector places hips and neck
a little differently, so treat its errors as indicative. The 84 frames are 5 subjects, mostly S9
"Posing" from two cameras.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import ArrayLike

from ._checks import (
    PoseLifterError,
    _joint_labels,
    _real_array,
    not_face_first_message,
    warn_user,
    where_in_batch,
    zero_placeholders,
)
from .skeleton import JOINT_NAMES, NUM_JOINTS

H36M17: Final[str] = "h36m17"

Rule = tuple[tuple[int, float], ...]
"""An affine combination ``((src_index, weight), ...)`` with weights summing to 1."""

SH16_SPINE_WEIGHT: Final[float] = 0.585
SH16_NECK_WEIGHT: Final[float] = 0.222
SH16_HEAD_WEIGHT: Final[float] = 0.483
"""Interpolation weights of the ``sh16`` rules (module docstring), fitted on the training subjects."""


@dataclass(frozen=True, eq=False)
class KeypointFormat:
    """A 2D keypoint format.

    name: registry key. joint_names: the format's joints, in order (J of them).
    to_h36m: 17 rules, one per H36M joint (:data:`lifter.skeleton.JOINT_NAMES` order), indices into
        this format's joints. from_h36m: optional, for each of this format's joints the H36M index it
        equals, or a rule over H36M joints (the inverse of an interpolated ``to_h36m`` rule), so that the
        format can be a conversion target.
    description: one line, shown in error messages and docs.
    """

    name: str
    joint_names: tuple[str, ...]
    to_h36m: tuple[Rule, ...]
    from_h36m: tuple[int | Rule, ...] | None = None
    description: str = ""

    def __post_init__(self) -> None:
        J = len(self.joint_names)
        if len(self.to_h36m) != NUM_JOINTS:
            raise ValueError(f"format {self.name!r}: needs {NUM_JOINTS} rules, got {len(self.to_h36m)}")
        for j, rule in enumerate(self.to_h36m):
            if not rule or any(not 0 <= k < J for k, _ in rule):
                raise ValueError(f"format {self.name!r}: rule for {JOINT_NAMES[j]} has bad indices {rule}")
            if abs(sum(w for _, w in rule) - 1.0) > 1e-9:
                raise ValueError(f"format {self.name!r}: weights of the rule for {JOINT_NAMES[j]} must sum to 1")
        if self.from_h36m is not None:
            rules = [((e, 1.0),) if isinstance(e, int) else e for e in self.from_h36m]
            if len(rules) != J or any(not r or any(not 0 <= k < NUM_JOINTS for k, _ in r)
                                      or abs(sum(w for _, w in r) - 1.0) > 1e-9 for r in rules):
                raise ValueError(f"format {self.name!r}: from_h36m must give one H36M index or rule (weights "
                                 "summing to 1) per joint")

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    @property
    def rule_joints(self) -> tuple[int, ...]:
        """This format's joints that the rules to H36M read (sorted indices): the ones a person must give."""
        return tuple(sorted({k for rule in self.to_h36m for k, _ in rule}))

    @property
    def matrix(self) -> np.ndarray:
        """``(17, J)`` weights: ``h36m = matrix @ src`` (per coordinate)."""
        M = np.zeros((NUM_JOINTS, self.num_joints))
        for j, rule in enumerate(self.to_h36m):
            for k, w in rule:
                M[j, k] += w
        return M

    @property
    def from_matrix(self) -> np.ndarray | None:
        """``(J, 17)`` weights: ``fmt = from_matrix @ h36m`` (per coordinate); None without ``from_h36m``."""
        if self.from_h36m is None:
            return None
        M = np.zeros((self.num_joints, NUM_JOINTS))
        for j, e in enumerate(self.from_h36m):
            for k, w in (((e, 1.0),) if isinstance(e, int) else e):
                M[j, k] += w
        return M

    @property
    def direct_joints(self) -> dict[int, int]:
        """``{h36m_index: src_index}`` for the H36M joints taken over unchanged (one-term rules)."""
        return {j: rule[0][0] for j, rule in enumerate(self.to_h36m) if len(rule) == 1}


_REGISTRY: dict[str, KeypointFormat] = {}


def register_format(fmt: KeypointFormat, *, overwrite: bool = False) -> KeypointFormat:
    """Add a format to the registry (``overwrite=True`` to replace one)."""
    if fmt.name in _REGISTRY and not overwrite:
        raise ValueError(f"keypoint format {fmt.name!r} is already registered")
    _REGISTRY[fmt.name] = fmt
    return fmt


def get_format(name: str) -> KeypointFormat:
    """The registered format ``name``, or a :class:`PoseLifterError` listing the known ones."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise PoseLifterError(f"unknown keypoint format {name!r}; known formats: {sorted(_REGISTRY)}") from None


def mirror_permutation(name: str) -> np.ndarray:
    """``(J,)`` indices that swap a format's left and right joints: ``mirrored[..., j, :] = kp[..., perm[j], :]``
    after the image flip ``x -> W - x``. Derived from the joint names (``l_`` / ``r_`` prefixes, ``_l`` / ``_r``
    suffixes, the subject's sides); joints without a side map to themselves. For ``"h36m17"`` it equals
    :data:`lifter.skeleton.FLIP_PERMUTATION`."""
    return _mirror_permutation(name, tuple(get_format(name).joint_names))


@functools.lru_cache(maxsize=64)
def _mirror_permutation(name: str, names: tuple[str, ...]) -> np.ndarray:
    """:func:`mirror_permutation` of a format's joint names, computed once per format (read-only)."""
    index = {n: i for i, n in enumerate(names)}

    def other(n: str) -> str:
        for a, b in (("l_", "r_"), ("r_", "l_")):
            if n.startswith(a):
                return b + n[2:]
        for a, b in (("_l", "_r"), ("_r", "_l")):
            if n.endswith(a):
                return n[:-2] + b
        return n

    missing = [n for n in names if other(n) not in index]
    if missing:
        raise PoseLifterError(f"keypoint format {name!r}: no mirror counterpart for {missing}")
    perm = np.array([index[other(n)] for n in names], np.intp)
    perm.setflags(write=False)
    return perm


def keypoint_formats() -> tuple[str, ...]:
    """Names of the registered formats (including any added after import)."""
    return tuple(sorted(_REGISTRY))


def _interp(a: int, b: int, w: float) -> Rule:
    """``a + w (b - a)``."""
    return ((a, 1.0 - w), (b, w))


register_format(KeypointFormat(
    name=H36M17,
    joint_names=tuple(JOINT_NAMES),
    to_h36m=tuple(((j, 1.0),) for j in range(NUM_JOINTS)),
    from_h36m=tuple(range(NUM_JOINTS)),
    description="the 17 Human3.6M joints of lifter.skeleton (identity)",
))

SH16_JOINT_NAMES: Final[tuple[str, ...]] = (
    "r_ankle", "r_knee", "r_hip", "l_hip", "l_knee", "l_ankle", "pelvis", "spine", "thorax", "head_top",
    "r_wrist", "r_elbow", "r_shoulder", "l_shoulder", "l_elbow", "l_wrist",
)
"""sh16 order (README names RFoot, RKnee, RHip, LHip, LKnee, LFoot, Hip, Spine, Thorax, Head, RWrist,
RElbow, RShoulder, LShoulder, LElbow, LWrist), spelled as the H36M joints they are named after."""

_SH = {n: i for i, n in enumerate(SH16_JOINT_NAMES)}


def _sh16_rules() -> tuple[Rule, ...]:
    rules: list[Rule] = []
    for name in JOINT_NAMES:
        if name == "spine":
            rules.append(_interp(_SH["pelvis"], _SH["spine"], SH16_SPINE_WEIGHT))
        elif name == "neck_nose":
            rules.append(_interp(_SH["thorax"], _SH["head_top"], SH16_NECK_WEIGHT))
        elif name == "head_top":
            rules.append(_interp(_SH["thorax"], _SH["head_top"], SH16_HEAD_WEIGHT))
        else:
            rules.append(((_SH[name], 1.0),))
    return tuple(rules)


def _sh16_inverse_rules() -> tuple[int | Rule, ...]:
    """h36m17 -> sh16: the exact inverses of the interpolated rules (sh16's "spine" is MPII's thorax,
    ``pelvis + (spine - pelvis) / 0.585``; its "head_top" the top of the skull, ``thorax + (head_top -
    thorax) / 0.483``), so that ``sh16 -> h36m17 -> sh16`` is the identity."""
    h = {n: i for i, n in enumerate(JOINT_NAMES)}
    out: list[int | Rule] = []
    for name in SH16_JOINT_NAMES:
        if name == "spine":
            out.append(_interp(h["pelvis"], h["spine"], 1.0 / SH16_SPINE_WEIGHT))
        elif name == "head_top":
            out.append(_interp(h["thorax"], h["head_top"], 1.0 / SH16_HEAD_WEIGHT))
        else:
            out.append(h[name])
    return tuple(out)


register_format(KeypointFormat(
    name="sh16",
    joint_names=SH16_JOINT_NAMES,
    to_h36m=_sh16_rules(),
    from_h36m=_sh16_inverse_rules(),
    description="Stacked Hourglass / MPII 16 joints as in the H36M SH detections; neck_nose, spine, head_top "
                "interpolated",
))

# ------------------------------------------------------------------------------------------------
# BlazePose-33, COCO-17, OpenPose BODY-25 (the cascade's 2D detectors)
# ------------------------------------------------------------------------------------------------

BLAZEPOSE33_JOINT_NAMES: Final[tuple[str, ...]] = (
    "nose", "l_eye_inner", "l_eye", "l_eye_outer", "r_eye_inner", "r_eye", "r_eye_outer", "l_ear", "r_ear",
    "mouth_l", "mouth_r", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist", "r_wrist", "l_pinky",
    "r_pinky", "l_index", "r_index", "l_thumb", "r_thumb", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle",
    "r_ankle", "l_heel", "r_heel", "l_foot_index", "r_foot_index",
)
"""MediaPipe BlazePose landmark order (``mp.solutions.pose.PoseLandmark``); l/r = the subject's sides."""

COCO17_JOINT_NAMES: Final[tuple[str, ...]] = (
    "nose", "l_eye", "r_eye", "l_ear", "r_ear", "l_shoulder", "r_shoulder", "l_elbow", "r_elbow", "l_wrist",
    "r_wrist", "l_hip", "r_hip", "l_knee", "r_knee", "l_ankle", "r_ankle",
)
"""MS-COCO person keypoints order."""

OPENPOSE25_JOINT_NAMES: Final[tuple[str, ...]] = (
    "nose", "neck", "r_shoulder", "r_elbow", "r_wrist", "l_shoulder", "l_elbow", "l_wrist", "mid_hip", "r_hip",
    "r_knee", "r_ankle", "l_hip", "l_knee", "l_ankle", "r_eye", "l_eye", "r_ear", "l_ear", "l_big_toe",
    "l_small_toe", "l_heel", "r_big_toe", "r_small_toe", "r_heel",
)
"""OpenPose BODY_25 order."""

PELVIS_UP: Final[float] = 0.160
HIP_WIDEN: Final[float] = 1.223
SPINE_UP: Final[float] = 0.628
THORAX_DOWN: Final[float] = -0.087
NECK_NOSE_W: Final[tuple[float, float]] = (0.270, 0.500)
HEAD_TOP_W: Final[tuple[float, float]] = (0.644, 0.218)
"""Weights of the blazepose33 / coco17 / openpose25 rules (module docstring, "Detector formats");
least-squares fits on BlazePose detections of the 84 H36M demo frames (``scripts/eval_cascade.py``)."""

_Combo = dict[int, float]


def _lin(*terms: tuple[float, _Combo]) -> _Combo:
    out: _Combo = {}
    for w, c in terms:
        for k, v in c.items():
            out[k] = out.get(k, 0.0) + w * v
    return out


def _rule(c: _Combo) -> Rule:
    items = [(k, v) for k, v in sorted(c.items()) if abs(v) > 1e-12]
    total = sum(v for _, v in items)
    # absorb rounding so that the weights sum to 1 exactly (the largest weight takes the residue)
    i = max(range(len(items)), key=lambda n: abs(items[n][1]))
    items[i] = (items[i][0], items[i][1] + 1.0 - total)
    return tuple(items)


def body_rules(idx: dict[str, int], *, mid_hip: _Combo | None = None,
               mid_shoulder: _Combo | None = None) -> tuple[Rule, ...]:
    """The 17 H36M rules for a detector with ``nose``, ``l_ear``/``r_ear``, shoulders, elbows, wrists,
    hips, knees and ankles (``idx``: name -> index). ``mid_hip`` / ``mid_shoulder`` default to the
    midpoints of the hips / shoulders (OpenPose passes its own MidHip / Neck joints)."""
    one = lambda name: {idx[name]: 1.0}  # noqa: E731
    MH = mid_hip or _lin((0.5, one("l_hip")), (0.5, one("r_hip")))
    MS = mid_shoulder or _lin((0.5, one("l_shoulder")), (0.5, one("r_shoulder")))
    ME = _lin((0.5, one("l_ear")), (0.5, one("r_ear")))
    N = one("nose")
    trunk = _lin((1.0, MS), (-1.0, MH))  # MS - MH
    rules: dict[str, _Combo] = {
        "pelvis": _lin((1.0, MH), (PELVIS_UP, trunk)),
        "r_hip": _lin((1.0, MH), (HIP_WIDEN, _lin((1.0, one("r_hip")), (-1.0, MH))), (PELVIS_UP, trunk)),
        "l_hip": _lin((1.0, MH), (HIP_WIDEN, _lin((1.0, one("l_hip")), (-1.0, MH))), (PELVIS_UP, trunk)),
        "spine": _lin((1.0, MH), (SPINE_UP, trunk)),
        "thorax": _lin((1.0, MS), (-THORAX_DOWN, trunk)),
        "neck_nose": _lin((1.0, MS), (NECK_NOSE_W[0], _lin((1.0, N), (-1.0, MS))),
                          (NECK_NOSE_W[1], _lin((1.0, ME), (-1.0, MS)))),
        "head_top": _lin((1.0, ME), (HEAD_TOP_W[0], _lin((1.0, ME), (-1.0, N))),
                         (HEAD_TOP_W[1], _lin((1.0, ME), (-1.0, MS)))),
    }
    return tuple(_rule(rules[name]) if name in rules else ((idx[name], 1.0),) for name in JOINT_NAMES)


def _index(names: Sequence[str]) -> dict[str, int]:
    return {n: i for i, n in enumerate(names)}


register_format(KeypointFormat(
    name="blazepose33",
    joint_names=BLAZEPOSE33_JOINT_NAMES,
    to_h36m=body_rules(_index(BLAZEPOSE33_JOINT_NAMES)),
    description="MediaPipe BlazePose 33 landmarks; pelvis, hips, spine, thorax, neck_nose, head_top by rules",
))

register_format(KeypointFormat(
    name="coco17",
    joint_names=COCO17_JOINT_NAMES,
    to_h36m=body_rules(_index(COCO17_JOINT_NAMES)),
    description="MS-COCO 17 keypoints; pelvis, hips, spine, thorax, neck_nose, head_top by rules",
))

_OP = _index(OPENPOSE25_JOINT_NAMES)
register_format(KeypointFormat(
    name="openpose25",
    joint_names=OPENPOSE25_JOINT_NAMES,
    to_h36m=body_rules(_OP, mid_hip={_OP["mid_hip"]: 1.0}, mid_shoulder={_OP["neck"]: 1.0}),
    description="OpenPose BODY_25 (MidHip and Neck used as mid-hips and mid-shoulders); rules as coco17",
))

EAR_EYE_SPACING: Final[float] = 2.3
"""The spacing of the ears over that of the eyes, both across the face: an adult's bitragion breadth (~145 mm) over
the distance between the pupils (~63 mm). A hidden ear is the other ear moved by this times the eye-to-eye vector
(:data:`STAND_INS`): right in a frontal view, and in a side view, where the eyes nearly coincide, the other ear."""

_StandIn = tuple[str, tuple[tuple[str, float], ...]]


def _stand_ins(fmt: str) -> dict[str, tuple[_StandIn, ...]]:
    k = EAR_EYE_SPACING
    eyes: _StandIn = ("the eyes' midpoint", (("l_eye", 0.5), ("r_eye", 0.5)))
    table: dict[str, tuple[_StandIn, ...]] = {
        "l_ear": (("r_ear moved across by the eyes", (("r_ear", 1.0), ("l_eye", k), ("r_eye", -k))),
                  ("r_ear", (("r_ear", 1.0),)), eyes, ("l_eye", (("l_eye", 1.0),)), ("r_eye", (("r_eye", 1.0),))),
        "r_ear": (("l_ear moved across by the eyes", (("l_ear", 1.0), ("r_eye", k), ("l_eye", -k))),
                  ("l_ear", (("l_ear", 1.0),)), eyes, ("r_eye", (("r_eye", 1.0),)), ("l_eye", (("l_eye", 1.0),))),
        "nose": (eyes, ("l_eye", (("l_eye", 1.0),)), ("r_eye", (("r_eye", 1.0),))),
    }
    if fmt == "openpose25":
        table["neck"] = (("the shoulders' midpoint", (("l_shoulder", 0.5), ("r_shoulder", 0.5))),)
        table["mid_hip"] = (("the hips' midpoint", (("l_hip", 0.5), ("r_hip", 0.5))),)
    return table


STAND_INS: Final[dict[str, dict[str, tuple[_StandIn, ...]]]] = {
    fmt: _stand_ins(fmt) for fmt in ("coco17", "openpose25", "blazepose33")}
"""For the detector formats, the face and mid-body joints that may be stood in for when missing: for each, its
stand-ins in order of preference, ``(what, affine combination of given joints)``; the first whose joints were all
given is used. Side views hide an ear (the other ear, moved across by :data:`EAR_EYE_SPACING` times the eyes'
spacing), a turned head the nose (the eyes' midpoint); OpenPose's Neck and MidHip are the midpoints of the
shoulders and hips. The limb joints (shoulders, elbows, wrists, hips, knees, ankles) have no stand-in: a person
missing one is left out. What they cost on the demo photos: ``scripts/stand_in_error.py``."""


def stand_in_missing(keypoints: np.ndarray, missing: np.ndarray, *, src: str, scores: np.ndarray | None = None
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, list[str]]:
    """Fill the missing face and mid-body joints of one person of format ``src`` from their :data:`STAND_INS`.

    keypoints: ``(J, 2)`` px; missing: ``(J,)`` bool; scores: ``(J,)`` confidences or None. Returns the keypoints
    with the stood-in joints filled, the joints still missing, the scores (a stood-in joint gets the lowest of the
    joints it is made from), and one phrase per stood-in joint (``"nose from the eyes' midpoint"``) for the
    caller's note. Joints given are never changed; a stand-in reads only joints given, never one stood in for.
    Formats without stand-ins (h36m17, sh16) come back unchanged."""
    table = STAND_INS.get(src)
    xy = np.array(keypoints, np.float64, copy=True)
    miss = np.array(missing, bool, copy=True)
    sc = None if scores is None else np.array(scores, np.float64, copy=True)
    said: list[str] = []
    if not table or not miss.any():
        return xy, miss, sc, said
    idx = _index(get_format(src).joint_names)
    given = ~np.asarray(missing, bool)
    for joint, options in table.items():
        j = idx[joint]
        if not miss[j]:
            continue
        for what, combo in options:
            ks = [idx[n] for n, _ in combo]
            if all(given[k] for k in ks):
                xy[j] = sum(w * xy[k] for k, (_, w) in zip(ks, combo))
                miss[j] = False
                if sc is not None:
                    sc[j] = sc[ks].min()
                said.append(f"{joint} from {what}")
                break
    return xy, miss, sc, said


KEYPOINT_FORMATS: Final[tuple[str, ...]] = keypoint_formats()
"""The built-in format names (see :func:`keypoint_formats` for the live registry)."""


def missing_joints(keypoints: np.ndarray, scores: np.ndarray | None) -> np.ndarray:
    """Which joints of one person's keypoints ``(J, 2)`` are missing, ``(J,)`` bool: non-finite coordinates, or a
    score ``(J,)`` of 0 or less, or NaN (OpenPose and COCO mark undetected joints with confidence 0; null: unknown).
    The one rule of the keypoint-file reader and :func:`convert` (``scores=``)."""
    missing = ~np.all(np.isfinite(keypoints), axis=-1)
    return missing if scores is None else missing | ~(np.asarray(scores) > 0)


def fill_missing(keypoints: np.ndarray, missing: np.ndarray, *, src: str, scores: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray | None, list[str], list[str]]:
    """One person's keypoints ``(J, 2)`` px of format ``src`` with their ``missing`` joints ``(J,)`` handled as the
    keypoint-file reader and :func:`convert` (``scores=``) handle them: stood in for where :data:`STAND_INS` allows
    (:func:`stand_in_missing`), and those no rule reads set to 0. Returns ``(keypoints, scores, phrases, lacking)``:
    ``phrases`` one per joint stood in for, ``lacking`` the names of the joints still missing that the conversion to
    H36M needs (the person cannot be lifted when it is not empty)."""
    f = get_format(src)
    xy, miss, sc, said = stand_in_missing(keypoints, missing, src=src, scores=scores)
    lacking = [f.joint_names[k] for k in f.rule_joints if miss[k]]
    return np.where(miss[:, None], 0.0, xy), sc, said, lacking


def placeholder_notes(keypoints: ArrayLike, *, src: str) -> list[str]:
    """A note when 2D keypoints ``(..., J, 2)`` px of format ``src`` have a joint at exactly (0, 0) far from the rest
    of its pose (a detector's placeholder for a missing joint) that the rules to H36M read: mixed into a computed
    joint, it would no longer be visible as such to :meth:`lifter.Lifter.lift`'s own check. h36m17 poses and joints
    no rule reads are not flagged. Empty list: nothing to say."""
    f = get_format(src)
    arr = np.asarray(keypoints, np.float64)
    if src == H36M17 or arr.ndim < 2 or arr.shape[-1] != 2 or arr.shape[-2] != f.num_joints or not arr.size:
        return []
    used = np.zeros(f.num_joints, bool)
    used[list(f.rule_joints)] = True
    placeholder = zero_placeholders(arr) & used
    far = np.asarray(placeholder.any(-1))
    if not np.any(far):
        return []
    names = _joint_labels(placeholder, f.joint_names)
    return [f"joint(s) {names} of format {src!r} at exactly (0, 0) px, far from the rest of the pose"
            f"{where_in_batch(far)}: a detector's placeholder for a missing joint? The conversion to H36M mixes it "
            "into the joints made from it, where the lifter can no longer see it; mark it missing (confidence 0 or "
            "null in a keypoint file), fill it in, or leave the pose out"]


def convert(keypoints: ArrayLike, *, src: str, dst: str = H36M17, warn: bool = True,
            scores: ArrayLike | None = None) -> np.ndarray:
    """Convert keypoints ``(..., J_src, D)`` (D = 2 px or 3 mm) from format ``src`` to ``dst``.

    Returns float64 ``(..., J_dst, D)``. ``src -> h36m17`` applies the format's rules. ``h36m17 -> dst`` exists
    only for a format whose every joint H36M has or interpolates (``sh16``: its ``from_h36m``, so
    ``sh16 -> h36m17 -> sh16`` is the identity); the detector formats (``coco17``, ``openpose25``, ``blazepose33``)
    have face, hand and foot points H36M lacks, so converting into them raises. Other pairs go through h36m17. Raises
    :class:`PoseLifterError` for an unknown format, a wrong joint count or dimension, and NaN/inf input without
    ``scores``. ``warn``: warn (:class:`lifter.PoseLifterWarning`) of a (0, 0) placeholder the rules would hide
    (:func:`placeholder_notes`) and of joints stood in for; False for callers that report it themselves (the
    records' notes, the app).

    scores: a detector's confidences ``(..., J_src)`` for 2D keypoints, as a keypoint file gives them: a joint whose
    score is 0 or less (or NaN), or whose coordinates are NaN, is missing. A missing face or mid-body joint is stood
    in for from the others, as the keypoint-file reader does (:func:`stand_in_missing`, :data:`STAND_INS`: a hidden
    ear from the other ear, OpenPose's neck from the shoulders); a missing joint that H36M's joints are made from
    and that nothing stands in for (a wrist, a knee) raises, naming it and its pose. Detector output in memory:
    ``convert(kp[..., :2], src="coco17", scores=kp[..., 2])``.
    """
    f_src, f_dst = get_format(src), get_format(dst)
    arr = _real_array(keypoints, name="keypoints", what="a numeric array")  # (torch tensors as lift reads them)
    if arr.ndim < 2 or arr.shape[-1] not in (2, 3) or arr.shape[-2] != f_src.num_joints:
        raise PoseLifterError(
            f"keypoints: format {src!r} has {f_src.num_joints} joints, expected shape (..., {f_src.num_joints}, 2) "
            f"or (..., {f_src.num_joints}, 3), got {tuple(arr.shape)}")
    if scores is not None:
        arr = _stood_in(arr, scores, src=src, warn=warn)
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.all(np.isfinite(arr), axis=-1))
        joints = sorted({f_src.joint_names[int(i[-1])] for i in bad[:50]})
        raise PoseLifterError(
            f"keypoints: {len(bad)} joint(s) with NaN/inf coordinates (e.g. {joints}) in format {src!r}: pass the "
            "detector's scores (convert(..., scores=...)) to have a missing face or mid-body joint stood in for, as "
            "the keypoint-file reader does; every other joint must be detected")
    if arr.shape[-1] == 3 and arr.size:
        third, xy = arr[..., 2], arr[..., :2]
        ext = xy.max(-2) - xy.min(-2)  # (..., 2) each pose's box
        span = float(np.hypot(ext[..., 0], ext[..., 1]).max())
        if float(third.min()) >= 0.0 and float(third.max()) <= 2.0 and span > 20.0:
            warn_user(
                f"keypoints: the third column is all within [0, 2] while the first two span up to {span:.0f} units "
                "(box diagonal): detector confidences or COCO visibility flags, not a z in mm? They are converted "
                "as a coordinate; for 2D pass keypoints[..., :2]")
    if src == dst:
        return arr.copy()
    if warn:  # (with scores: the joints given, a missing one is stood in for or not read by the rules)
        for message in placeholder_notes(arr, src=src):
            warn_user(message)
        said = (not_face_first_message(arr.reshape(-1, 17, 2)) if src == "coco17" and arr.size and arr.shape[-1] == 2
                else None)
        if said is not None:
            warn_user(f"keypoints: {said} They are converted as COCO-17 (scrambled if they are "
                      "H36M's); lift takes H36M-17 order as it is")
    h36m = arr if src == H36M17 else np.einsum("jk,...kd->...jd", f_src.matrix, arr)
    if dst == H36M17:
        return h36m
    if f_dst.from_h36m is None:
        raise PoseLifterError(f"keypoint format {dst!r} cannot be produced from h36m17 (it has joints H36M lacks)")
    assert f_dst.from_matrix is not None  # (exists whenever from_h36m does)
    return np.einsum("jk,...kd->...jd", f_dst.from_matrix, h36m)


def _stood_in(arr: np.ndarray, scores: ArrayLike, *, src: str, warn: bool) -> np.ndarray:
    """:func:`convert`'s keypoints ``(..., J, 2)`` with their missing joints (``scores`` ``(..., J)`` 0 or less or NaN,
    or NaN coordinates) stood in for (:func:`stand_in_missing`); joints no rule reads left missing are set to 0."""
    f = get_format(src)
    sc = _real_array(scores, name="scores", what="a numeric array")
    if arr.shape[-1] != 2:
        raise PoseLifterError(f"scores are for 2D keypoints (..., {f.num_joints}, 2); got {tuple(arr.shape)}")
    if sc.shape != arr.shape[:-1]:
        raise PoseLifterError(f"scores: expected shape {tuple(arr.shape[:-1])} (one per joint), got {tuple(sc.shape)}")
    if np.any(np.isinf(sc)):
        raise PoseLifterError("scores: infinite values; a detector's confidence is a finite number (0 or less, or "
                              "NaN: a missing joint)")
    flat = arr.reshape(-1, f.num_joints, 2).copy()
    flat_sc = sc.reshape(-1, f.num_joints)
    lacking: list[str] = []
    said_all: list[str] = []
    for i in range(len(flat)):
        missing = missing_joints(flat[i], flat_sc[i])
        if not missing.any():
            continue
        flat[i], _, said, bad = fill_missing(flat[i], missing, src=src)
        where = "" if len(flat) == 1 else f" (pose {i})"
        if bad:
            lacking.append(f"{bad}{where}")
        said_all += [f"{phrase}{where}" for phrase in said]
    if lacking:
        raise PoseLifterError(
            f"keypoints: joint(s) missing (score 0 or less, or NaN) that format {src!r}'s conversion to H36M needs and "
            f"that nothing stands in for: {'; '.join(lacking[:5])}{'; ...' if len(lacking) > 5 else ''}. Give those "
            "joints (placed by hand, or interpolated from neighbouring frames), or leave the pose out")
    if warn and said_all:
        warn_user(
            f"keypoints: stood in for missing joint(s): {', '.join(said_all[:6])}{', ...' if len(said_all) > 6 else ''}"
            " (lifter.keypoints.STAND_INS)")
    return flat.reshape(arr.shape)


def fit_line_weight(target: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Least-squares ``w`` in ``target ~ a + w (b - a)`` over points ``(N, D)``: the interpolation weight
    of a two-joint rule."""
    d = np.asarray(b, np.float64) - np.asarray(a, np.float64)
    return float(((np.asarray(target, np.float64) - a) * d).sum() / max((d * d).sum(), 1e-12))


__all__: Sequence[str] = ("BLAZEPOSE33_JOINT_NAMES", "COCO17_JOINT_NAMES", "KEYPOINT_FORMATS", "KeypointFormat",
                          "OPENPOSE25_JOINT_NAMES", "SH16_JOINT_NAMES", "body_rules", "convert", "fit_line_weight",
                          "placeholder_notes", "EAR_EYE_SPACING", "STAND_INS", "fill_missing", "missing_joints",
                          "stand_in_missing",
                          "get_format", "keypoint_formats", "register_format")
