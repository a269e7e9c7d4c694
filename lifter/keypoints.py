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
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final, Sequence

import numpy as np

from ._checks import PoseLifterError
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
        equals (formats whose joints are all H36M joints), so that it can be a conversion target.
    description: one line, shown in error messages and docs.
    """

    name: str
    joint_names: tuple[str, ...]
    to_h36m: tuple[Rule, ...]
    from_h36m: tuple[int, ...] | None = None
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
        if self.from_h36m is not None and (len(self.from_h36m) != J or
                                           any(not 0 <= k < NUM_JOINTS for k in self.from_h36m)):
            raise ValueError(f"format {self.name!r}: from_h36m must give one H36M index per joint")

    @property
    def num_joints(self) -> int:
        return len(self.joint_names)

    @property
    def matrix(self) -> np.ndarray:
        """``(17, J)`` weights: ``h36m = matrix @ src`` (per coordinate)."""
        M = np.zeros((NUM_JOINTS, self.num_joints))
        for j, rule in enumerate(self.to_h36m):
            for k, w in rule:
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


register_format(KeypointFormat(
    name="sh16",
    joint_names=SH16_JOINT_NAMES,
    to_h36m=_sh16_rules(),
    from_h36m=tuple(JOINT_NAMES.index(n) for n in SH16_JOINT_NAMES),
    description="Stacked Hourglass / MPII 16 joints as in the H36M SH detections; neck_nose, spine, head_top "
                "interpolated",
))

KEYPOINT_FORMATS: Final[tuple[str, ...]] = keypoint_formats()
"""The built-in format names (see :func:`keypoint_formats` for the live registry)."""


def convert(keypoints: Any, *, src: str, dst: str = H36M17) -> np.ndarray:
    """Convert keypoints ``(..., J_src, D)`` (D = 2 px or 3 mm) from format ``src`` to ``dst``.

    Returns float64 ``(..., J_dst, D)``. ``src -> h36m17`` applies the format's rules; ``h36m17 ->
    dst`` selects the H36M joints the format is made of (needs ``from_h36m``); other pairs go through
    h36m17. Raises :class:`PoseLifterError` for an unknown format, a wrong joint count or dimension,
    and NaN/inf input (mark missing joints before converting; the lifter needs all 17).
    """
    f_src, f_dst = get_format(src), get_format(dst)
    try:
        arr = np.asarray(keypoints, np.float64)
    except (TypeError, ValueError) as exc:
        raise PoseLifterError(f"keypoints: could not convert to a numeric array ({exc})") from None
    if arr.ndim < 2 or arr.shape[-1] not in (2, 3) or arr.shape[-2] != f_src.num_joints:
        raise PoseLifterError(
            f"keypoints: format {src!r} has {f_src.num_joints} joints, expected shape (..., {f_src.num_joints}, 2) "
            f"or (..., {f_src.num_joints}, 3), got {tuple(arr.shape)}")
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.all(np.isfinite(arr), axis=-1))
        joints = sorted({f_src.joint_names[int(i[-1])] for i in bad[:50]})
        raise PoseLifterError(f"keypoints: {len(bad)} joint(s) with NaN/inf coordinates (e.g. {joints}) in format "
                              f"{src!r}; every joint must be detected")
    if src == dst:
        return arr.copy()
    h36m = arr if src == H36M17 else np.einsum("jk,...kd->...jd", f_src.matrix, arr)
    if dst == H36M17:
        return h36m
    if f_dst.from_h36m is None:
        raise PoseLifterError(f"keypoint format {dst!r} cannot be produced from h36m17 (it has joints H36M lacks)")
    return h36m[..., list(f_dst.from_h36m), :].copy()


def fit_line_weight(target: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Least-squares ``w`` in ``target ~ a + w (b - a)`` over points ``(N, D)``: the interpolation weight
    of a two-joint rule."""
    d = np.asarray(b, np.float64) - np.asarray(a, np.float64)
    return float(((np.asarray(target, np.float64) - a) * d).sum() / max((d * d).sum(), 1e-12))


__all__: Sequence[str] = ("KEYPOINT_FORMATS", "KeypointFormat", "convert", "fit_line_weight", "get_format",
                          "keypoint_formats", "register_format", "SH16_JOINT_NAMES")
