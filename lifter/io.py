"""Files in and out of the pipeline: keypoint JSON files (:func:`parse_keypoint_json`) and the per-input
result record (:class:`LiftRecord`) that ``poselifter lift`` and the app's download write as JSON.

Keypoint JSON files: an object ``{"keypoints": [[x, y], ...], "format": "coco17", "image_size": [W, H],
"focal": F or [FX, FY], "principal_point": [CX, CY], "distortion": [K1, K2, K3, P1, P2], "distortion_model":
"h36m" | "opencv", "source": "detected" | "clean"}`` (only ``keypoints`` is
required; rows may have a third value, a confidence, where 0 marks a missing joint, as does ``null`` for a
coordinate, a confidence or a whole row; third values that look like coordinates are refused,
:data:`Z_LIKE_THIRD_VALUE`; a flat ``[x0, y0, c0, x1, ...]`` list works too), a bare list of
``[x, y]`` rows, OpenPose's output ``{"people": [{"pose_keypoints_2d": [...]}, ...]}`` (format openpose25), a
COCO-style list of people ``[{"keypoints": [...]}, ...]`` of one image (several ``image_id`` are refused: a file is
one image, one camera) or a result this module wrote (:class:`LiftRecord`: ``people[].keypoints_2d``, H36M order,
with its camera, or one such person on its own; lift it again with another focal length or model).
Without ``format`` it is inferred from the joint count (17: h36m17; 16: sh16; 25: openpose25; 33:
blazepose33). ``source`` says what the 2D is: ``"detected"`` (a detector's output, the default) or ``"clean"``
(exact: ground truth or hand-placed). Camera fields must be JSON numbers: ``image_size`` whole px in [1, 100000]
(:data:`MAX_IMAGE_SIDE_PX`), ``focal`` in (0, 1e6) px, ``principal_point`` finite and below 1e6 px in
magnitude; ``distortion`` five finite numbers below 10 in magnitude, the lens that saw the 2D in Human3.6M's
Brown-Conrady form (:func:`lifter.camera.distort`; needs the camera's focal length, in the file or given with it;
without it the 2D is taken as undistorted), or with ``"distortion_model": "opencv"`` (ROS's ``"plumb_bob"`` and
``"rational_polynomial"`` say the same) OpenCV's ``distCoeffs`` as calibrated, 4, 5 or 8 numbers
``[k1, k2, p1, p2, k3, ...]`` (:func:`lifter.camera.undistort_pixels_opencv`); anything
else fails with a message naming the field. MMPose's / RTMPose's ``keypoint_scores`` beside ``[x, y]`` rows are
read as the rows' confidences. A missing face or mid-body joint of a detector format is stood in for, with a note
(:data:`lifter.keypoints.STAND_INS`: a hidden ear, the nose, OpenPose's Neck and MidHip). A person still missing a
joint that the format's rules to H36M need is left out with a note naming them (a frame of a sequence then has one
person fewer); a file where nobody is left fails.

Units: px for 2D, mm for 3D; camera frame OpenCV (+x right, +y down, +z forward).
"""

from __future__ import annotations

import codecs
import difflib
import json
import math
import os
import re
import stat
import tempfile
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np

from ._checks import (
    COCO_FACE_SPREAD,
    MEDIAPIPE_XY_NOTE,
    PoseLifterError,
    face_first_people,
    not_face_first_message,
    other_layout_hint,
)
from .camera import (
    MAX_DISTORTION_COEFFICIENT,
    OPENCV_DISTORTION_COUNTS,
    DistortionModel,
    check_distortion,
    check_distortion_model,
    check_opencv_distortion,
)
from .keypoints import H36M17, fill_missing, get_format, keypoint_formats, missing_joints
from .skeleton import JOINT_NAMES

FORMAT_BY_COUNT: Final[dict[int, str]] = {17: H36M17, 16: "sh16", 25: "openpose25", 33: "blazepose33"}
LAYOUT_FORMATS: Final[dict[str, str]] = {"openpose25": "OpenPose's 'pose_keypoints_2d' layout",
                                          "coco17": "a list of COCO results"}
"""The formats a file's layout implies when it has no ``format``, with the layout."""
"""Keypoint format assumed from the joint count when a JSON file names none."""


class JsonReady:
    """``to_dict()`` gives the plain data (lists, numbers, strings) ready for ``json.dump``, as
    :meth:`lifter.LiftResult.to_dict` does; ``to_json()`` is its old name (it returned the dict, where
    ``ErrorModel.to_json`` and ``TrainConfig.to_json`` return the text: a developer trial called ``to_dict`` on a
    record and met an AttributeError)."""

    def to_dict(self) -> dict[str, Any]:
        raise NotImplementedError

    def to_json(self) -> dict[str, Any]:
        """Deprecated: :meth:`to_dict` (the same dict)."""
        warnings.warn(f"{type(self).__name__}.to_json() is now to_dict() (the same dict, ready for json.dump)",
                      DeprecationWarning, stacklevel=2)
        return self.to_dict()


@dataclass(frozen=True)
class PersonResult(JsonReady):
    """One lifted person of an image or keypoint file: keypoints_2d ``(17, 2)`` px, absolute / relative
    ``(17, 3)`` mm, root ``(3,)`` mm, canonical_depth mm, scores ``(17,)`` or None."""

    keypoints_2d: np.ndarray
    absolute: np.ndarray
    relative: np.ndarray
    root: np.ndarray
    canonical_depth: float
    scores: np.ndarray | None = None
    input_index: int | None = None
    """Keypoint files: the person's position in the file's list of people (0-based; the output is largest first)."""
    person_id: str | int | None = None
    """Keypoint files: the person's own ``person_id`` (or ``id``, ``track_id``) field, when it has one."""

    def to_dict(self) -> dict[str, Any]:
        r = lambda a, d=2: np.round(np.asarray(a, np.float64), d).tolist()  # noqa: E731
        out = {"keypoints_2d": r(self.keypoints_2d, KEYPOINT_DECIMALS), "absolute": r(self.absolute),
               "relative": r(self.relative), "root": r(self.root),
               "canonical_depth": round(float(self.canonical_depth), 2),
               "scores": None if self.scores is None else r(self.scores, 3)}
        if self.input_index is not None:
            out["input_index"] = self.input_index
        if self.person_id is not None:
            out["person_id"] = self.person_id
        return out


KEYPOINT_DECIMALS: Final[int] = 4
"""Decimals of the 2D (px) in written records: a record read back lifts to its own result within 0.01 mm (at 2
decimals, rounding by up to 0.005 px moved a clean 2D's root by 0.16 mm)."""

CAMERA_DECIMALS: Final[int] = 9
"""Decimals of the focal length and principal point (px) in written records: enough that a record read back
lifts with its own camera (at 2 decimals a review's focal 801.234567 px moved the root 0.17 mm)."""


@dataclass(frozen=True)
class LiftRecord(JsonReady):
    """The result for one input; :meth:`to_dict` is what ``DIR/<name>.json`` holds.

    keypoints_2d: ``(17, 2)`` px (H36M order); absolute, relative: ``(17, 3)`` mm camera frame;
    root: ``(3,)`` mm; canonical_depth: mm (at a 1000-px focal); focal: ``(fx, fy)`` px;
    principal_point: ``(cx, cy)`` px; image_size: ``(W, H)`` px or None; scores: ``(17,)`` or None.
    The top-level pose fields describe the largest person; ``people`` holds everyone lifted, largest first
    (``people[0]`` is the top-level person). ``num_people``: how many the detector found in an image (or the
    keypoint file holds); at most ``max_people`` of them are lifted, so it can exceed ``len(people)``.
    """

    input: str
    kind: str
    keypoints_2d: np.ndarray
    absolute: np.ndarray
    relative: np.ndarray
    root: np.ndarray
    canonical_depth: float
    focal: tuple[float, float]
    focal_source: str
    principal_point: tuple[float, float]
    image_size: tuple[int, int] | None
    model: str
    scores: np.ndarray | None = None
    source_format: str = H36M17
    num_people: int | None = None
    detector: str | None = None
    warnings: tuple[str, ...] = field(default=())
    source: str = "detected"
    people: tuple[PersonResult, ...] = ()
    distortion: tuple[float, ...] | None = None
    """The lens distortion the 2D was given with ``(k1, k2, k3, p1, p2)`` (a keypoint file's ``distortion``), or
    None; ``keypoints_2d`` stays as given (distorted)."""
    distortion_model: DistortionModel = "h36m"
    """The form of :attr:`distortion`: ``"h36m"`` or ``"opencv"`` (:data:`lifter.camera.DistortionModel`)."""
    model_info: dict[str, Any] | None = None
    """What lifted it (:func:`model_info`: the version, each network's checkpoint sha256, flip test, int8), or
    None for a lifter-like object that does not say."""

    @property
    def metric_depth(self) -> bool:
        """Whether the absolute depths (mm) rest on the camera's own focal length (:func:`depth_is_metric` of
        :attr:`focal_source`), as the written record's ``metric_depth`` says."""
        return depth_is_metric(self.focal_source)

    def to_dict(self) -> dict[str, Any]:
        r = lambda a, d=2: np.round(np.asarray(a, np.float64), d).tolist()  # noqa: E731
        return {
            "input": self.input, "kind": self.kind, "model": self.model, "model_info": self.model_info,
            "joint_names": list(JOINT_NAMES),
            "units": {"keypoints_2d": "px", "absolute": "mm", "relative": "mm", "root": "mm", "canonical_depth": "mm",
                      "focal": "px", "principal_point": "px"},
            "frame": "camera, OpenCV: +x right, +y down, +z forward; 2D in px of the "
                     + ("upright full-resolution image" if self.kind == "image" else "image the keypoints belong to"),
            "keypoints_2d": r(self.keypoints_2d, KEYPOINT_DECIMALS), "absolute": r(self.absolute),
            "relative": r(self.relative), "root": r(self.root),
            "canonical_depth": round(float(self.canonical_depth), 2),
            # (the camera unrounded, as the lens is: reading the record back lifts with the same camera)
            "focal": r(self.focal, CAMERA_DECIMALS), "focal_source": self.focal_source,
            "metric_depth": self.metric_depth, "principal_point": r(self.principal_point, CAMERA_DECIMALS),
            "image_size": None if self.image_size is None else [int(v) for v in self.image_size],
            **({} if self.distortion is None else {"distortion": [float(v) for v in self.distortion],
                                                   "distortion_model": self.distortion_model}),
            "source": self.source, "source_format": self.source_format, "detector": self.detector,
            "num_people": self.num_people,
            "scores": None if self.scores is None else r(self.scores, 3), "warnings": list(self.warnings),
            "people": [q.to_dict() for q in self.people],
        }




@dataclass(frozen=True)
class KeypointFile:
    """A parsed keypoint JSON: ``keypoints (J, 2)`` px in ``format``; optional camera fields."""

    keypoints: np.ndarray
    format: str
    image_size: tuple[int, int] | None = None
    focal: np.ndarray | None = None
    principal_point: np.ndarray | None = None
    warnings: tuple[str, ...] = ()
    source: str = "detected"
    distortion: np.ndarray | None = None
    """``(5,)`` ``(k1, k2, k3, p1, p2)``: the lens that saw the 2D (module docstring), or None (undistorted); with
    :attr:`distortion_model` ``"opencv"``, OpenCV's ``distCoeffs`` ``(n,)``."""
    distortion_model: DistortionModel = "h36m"
    """The form of :attr:`distortion` (the file's ``distortion_model``): ``"h36m"`` or ``"opencv"``."""
    people: tuple[np.ndarray, ...] = ()
    """Everyone in the file, ``(J, 2)`` px each, largest (box area) first; ``keypoints`` is ``people[0]``."""
    people_index: tuple[int, ...] = ()
    """For each of ``people``: its position in the file's list of people (0-based)."""
    people_ids: tuple[str | int | None, ...] = ()
    """For each of ``people``: its ``person_id`` (or ``id``, ``track_id``) field, None where it has none."""
    unread: tuple[str, ...] = ()
    """The notes (also in ``warnings``) on fields that were not read: camera fields inside a person, fields named
    otherwise than the ones read (:func:`unread_field_notes`). An error about a missing field repeats them."""
    assumed_focal: str | None = None
    """The focal length (px, as text) the file says was assumed when this package wrote it (``focal_source``
    ``"default-fov"``): not read as known (``focal`` is None); :data:`REASSUMED_NOTE` says so."""
    people_scores: tuple[np.ndarray | None, ...] = ()
    """For each of ``people``: its ``(J,)`` confidences (the rows' third values or ``keypoint_scores``; a stood-in
    joint has the lowest of its stand-ins'), None where the file gave none."""


ASSUMED_FOCAL_SOURCE: Final[str] = "default-fov"
"""The ``focal_source`` of a focal length assumed from the image size (the default field of view): a depth lifted
with it is not metric (:func:`depth_is_metric`); every other source (given, EXIF, a keypoint file) is taken as
the camera's own."""


def model_info(lifter: Any, *, source: str, flip_test: bool | None = None) -> dict[str, Any] | None:
    """A written record's ``model_info``: :meth:`lifter.Lifter.provenance` of the lifter that lifted 2D told
    ``source`` with this ``flip_test`` argument (None: the model's default); None for a lifter-like object without
    one."""
    provenance = getattr(lifter, "provenance", None)
    return None if provenance is None else provenance(source=source, flip_test=flip_test)


def depth_is_metric(focal_source: str) -> bool:
    """Whether a result's absolute depths (mm) rest on a focal length of the camera itself, as every written
    record's and :class:`lifter.LiftResult`'s ``metric_depth`` says: any ``focal_source`` but an assumed one
    (:data:`ASSUMED_FOCAL_SOURCE`, or ``"reference"``, :meth:`lifter.Lifter.lift`'s virtual 1000-px camera)."""
    return focal_source not in (ASSUMED_FOCAL_SOURCE, "reference")


REASSUMED_NOTE: Final[str] = (
    "the file's focal length ({focal} px) was assumed when it was written (focal_source 'default-fov'), not known: it "
    "is assumed again from the image size")
"""The note when a result written with an assumed focal is read back without a focal given (``{focal}``: px)."""

STAND_IN_NOTE: Final[str] = ("missing joint(s) stood in for: {what}; the head's and trunk's H36M joints made from "
                              "them are approximate")
"""The note when a missing face or mid-body joint was stood in for (``{what}``: which, from what; the rules are
:data:`lifter.keypoints.STAND_INS`). It names no module: the app shows it to people in a browser (a trial)."""

MAX_KEYPOINT_FILE_BYTES: Final[int] = 64 * 1024 * 1024
"""Keypoint JSON files larger than this are refused before they are parsed."""


def _is_row(v: Any) -> bool:
    return isinstance(v, list) and len(v) in (2, 3) and all(_is_number(x) or x is None for x in v)


def _rows(raw: Any, where: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``(J, 2)`` px and optional ``(J,)`` confidences from ``[[x, y(, c)], ...]`` or a flat list of numbers.
    ``null`` coordinates, a ``null`` row and a ``null`` confidence mean a missing joint (NaN)."""
    form = "a list of [x, y] or [x, y, confidence] rows, or a flat list of numbers"
    if not isinstance(raw, list):
        raise PoseLifterError(f"{where}: 'keypoints' must be {form}, got {type(raw).__name__} {_short(raw)}")
    if raw and all(_is_number(v) or v is None for v in raw):
        flat = np.array([np.nan if v is None else v for v in raw], np.float64)
        n = flat.size
        if n % 3 == 0 and (n // 3) in FORMAT_BY_COUNT:
            a = flat.reshape(-1, 3)
        elif n % 2 == 0 and (n // 2) in FORMAT_BY_COUNT:
            a = flat.reshape(-1, 2)
        else:
            raise PoseLifterError(f"{where}: a flat keypoint list of {n} numbers is not J x 2 or J x 3 for "
                                  f"J in {sorted(FORMAT_BY_COUNT)}" + (COCO18_HINT if n in (36, 54) else ""))
    elif raw and all(_is_row(r) or r is None for r in raw) and any(r is not None for r in raw):
        widths = {len(r) for r in raw if r is not None}
        if len(widths) != 1:
            raise PoseLifterError(f"{where}: keypoint rows must all have 2 or all have 3 values")
        width = widths.pop()  # a row that is null as a whole: a missing joint
        a = np.array([[np.nan if v is None else v for v in (r if r is not None else [None] * width)] for r in raw],
                     np.float64)
    else:
        bad = next((r for r in raw if not (_is_row(r) or _is_number(r))), None) if raw else None
        four = isinstance(bad, list) and len(bad) == 4 and all(_is_number(v) for v in bad)
        hint = ("; rows of 4 values are MediaPipe's (x, y, z, visibility)? give [x, y, visibility] rows in px (drop z; "
                f"{MEDIAPIPE_XY_NOTE})") if four else ""
        raise PoseLifterError(f"{where}: 'keypoints' must be {form}; found {_short(bad if bad is not None else raw)}"
                              f"{hint}")
    if np.isinf(a[:, :2]).any():  # (1e400, or an integer too long for a float: not a missing joint, null is)
        j, k = (int(v) for v in np.argwhere(np.isinf(a[:, :2]))[0])
        raise PoseLifterError(f"{where}: keypoint {j}'s {'xy'[k]} is {a[j, k]:g} (a number too large for a float): "
                              "coordinates are finite pixels (null marks a missing joint)")
    conf = a[:, 2] if a.shape[1] == 3 else None
    if conf is not None:
        if np.isinf(conf).any():
            j = int(np.flatnonzero(np.isinf(conf))[0])
            raise PoseLifterError(f"{where}: keypoint {j}'s confidence is {conf[j]:g}: a confidence is a finite number "
                                  "(0 or null marks a missing joint)")
        c = conf[np.isfinite(conf)]
        if c.size and (float(np.median(np.abs(c))) > Z_LIKE_THIRD_VALUE or float(c.min()) < -Z_LIKE_THIRD_VALUE):
            raise PoseLifterError(
                f"{where}: the third value of each keypoint row is read as a confidence, but these run from "
                f"{float(c.min()):.4g} to {float(c.max()):.4g} (median size {float(np.median(np.abs(c))):.4g}), like a "
                "coordinate: is this a 3D pose (x, y, z)? The lifter takes 2D image coordinates in px: give [x, y] or "
                "[x, y, confidence] rows")
    return a[:, :2], conf


COCO18_HINT: Final[str] = (
    ". 18 joints: OpenPose's older COCO-18 model? It is not read: run OpenPose with its BODY_25 model (the default), "
    "or drop the Neck (the second joint) and put the rest in COCO-17 order with \"format\": \"coco17\"")
"""Added to the messages about 18 joints per person."""

Z_LIKE_THIRD_VALUE: Final[float] = 50.0
"""Keypoint rows whose third values have a median size above this, or go below minus this, are refused: those are
coordinates (a 3D pose in mm or px given as 2D), not confidences. Detector scores may exceed 1 (Detectron2's and
torchvision's keypoint scores are unbounded, RTMPose's SimCC scores pass 1): they are read, with a note when above 2
(:data:`SCORE_NOTE_ABOVE`), and only a value <= 0 marks a missing joint; COCO's visibility flags (all 0, 1 or 2) are
read as flags (:data:`COCO_VISIBILITY_FLAGS`)."""

FLAGS_NOTE: Final[str] = ("third values all 0, 1 or 2: read as COCO visibility flags (0: not labelled, a missing "
                          "joint; 1 or 2: placed), not as a detector's confidences, so the output has no scores")
"""The note when a file's third values are read as visibility flags (:func:`_visibility_flags`)."""

COCO_VISIBILITY_FLAGS: Final[tuple[float, ...]] = (0.0, 1.0, 2.0)
"""COCO's keypoint visibility flags (0 not labelled, 1 labelled but hidden, 2 visible). Third values that are all
flags, with at least one 2, are read as flags (0: a missing joint), not as confidences: a ground-truth annotation or
a results file in COCO's own form has no scores to keep."""


def _visibility_flags(scores: Sequence[np.ndarray | None]) -> bool:
    """Whether a file's third values (every person's, every frame's) are COCO visibility flags
    (:data:`COCO_VISIBILITY_FLAGS`): all 0, 1 or 2, with a 2 among them. Decided once per file, not per frame."""
    given = [np.asarray(c)[np.isfinite(c)] for c in scores if c is not None]
    return bool(given) and all(np.isin(c, COCO_VISIBILITY_FLAGS).all() for c in given) and any(
        (c == 2).any() for c in given)


SCORE_NOTE_ABOVE: Final[float] = 2.0
"""Third values above this get a note saying they are read as unnormalised scores."""


def _short(v: Any, n: int = 60) -> str:
    text = json.dumps(v) if isinstance(v, (list, dict, str, int, float, bool)) or v is None else repr(v)
    return text if len(text) <= n else text[: n - 3] + "..."


MAX_IMAGE_SIDE_PX: Final[int] = 100_000
"""Largest image side (px) accepted for ``image_size``."""
MAX_FOCAL_PX: Final[float] = 1e6
"""Focal lengths (px) must be below this (a 1e6-px focal is a ~0.1 deg field of view on a 2000-px image)."""
MAX_PRINCIPAL_POINT_PX: Final[float] = 1e6
"""Principal-point coordinates (px) must be below this in magnitude."""


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float, np.integer, np.floating)) and not isinstance(v, (bool, np.bool_))


def _image_size_field(raw: Any, *, where: str) -> tuple[int, int] | None:
    """``image_size`` of a keypoint file: ``[width, height]``, whole px in ``[1, MAX_IMAGE_SIDE_PX]``."""
    if raw is None:
        return None
    form = f"[width, height] in px (whole numbers in [1, {MAX_IMAGE_SIDE_PX}])"
    if not isinstance(raw, (list, tuple)):
        raise PoseLifterError(f"{where}: image_size must be a list {form}, got {raw!r}")
    if len(raw) != 2:
        raise PoseLifterError(f"{where}: image_size needs two values {form}, got {len(raw)}: {list(raw)!r}")
    if not all(_is_number(v) for v in raw):
        raise PoseLifterError(f"{where}: image_size must be numbers {form}, got {list(raw)!r}")
    if not all(math.isfinite(v) and float(v).is_integer() and 1 <= v <= MAX_IMAGE_SIDE_PX for v in raw):
        raise PoseLifterError(f"{where}: image_size must be {form}, got {list(raw)!r}")
    return int(raw[0]), int(raw[1])


def _camera_field(raw: Any, *, name: str, where: str | None) -> np.ndarray:
    """``focal`` (a number or ``[fx, fy]``, finite, in ``(0, MAX_FOCAL_PX)``) or ``principal_point``
    (``[cx, cy]``, finite, magnitude below ``MAX_PRINCIPAL_POINT_PX``) of a keypoint file (``where``: its
    path) or an option (``name``: the option, ``where=None``)."""
    is_focal = name.lstrip("-") == "focal"
    what = name if where is None else f"{where}: {name}"
    form = (f"a number or [fx, fy] in px, each in (0, {MAX_FOCAL_PX:.0e})" if is_focal else
            f"[cx, cy] in px, each finite with magnitude below {MAX_PRINCIPAL_POINT_PX:.0e}")
    items = list(raw) if isinstance(raw, (list, tuple, np.ndarray)) else [raw]
    if not all(_is_number(v) for v in items) or not (len(items) == 2 or (is_focal and len(items) == 1)):
        raise PoseLifterError(f"{what} must be {form}, got {raw!r}")
    arr = np.asarray(items * 2 if len(items) == 1 else items, np.float64)
    ok = np.all(np.isfinite(arr)) and (bool(np.all((arr > 0) & (arr < MAX_FOCAL_PX))) if is_focal else
                                       bool(np.all(np.abs(arr) < MAX_PRINCIPAL_POINT_PX)))
    if not ok:
        raise PoseLifterError(f"{what} must be {form}, got {arr.tolist()}")
    return arr


CAMERA_MATRIX_FIELDS: Final[tuple[str, ...]] = ("K", "camera_matrix", "intrinsic_matrix", "intrinsics", "intrinsic")
"""Names of an OpenCV camera matrix that a keypoint file's top level may give instead of ``focal`` and
``principal_point``: ``[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]``, its nine numbers in a row, or ROS's
``{"rows": 3, "cols": 3, "data": [...]}``."""


MAX_SKEW: Final[float] = 1e-3
"""A camera matrix's skew ``K[0][1]`` up to this share of ``fx`` is left out (a calibration's 0.5 px at fx 1600 moves
a point by under 0.2 px); more is refused, as the lift's camera has none."""


def _nine_numbers(raw: Any) -> np.ndarray | None:
    """The ``(3, 3)`` of nine numbers in ``raw`` (:data:`CAMERA_MATRIX_FIELDS`' layouts: nested, flat, or ROS's
    ``{"data": [...]}``), else None."""
    if isinstance(raw, dict):
        raw = raw.get("data")
    if not isinstance(raw, list):
        return None
    flat = [v for row in raw for v in row] if all(isinstance(r, list) for r in raw) else raw
    if len(flat) != 9 or not all(_is_number(v) for v in flat):
        return None
    return np.asarray(flat, np.float64).reshape(3, 3)


def _camera_matrix(raw: Any) -> tuple[np.ndarray | None, str | None]:
    """The ``(3, 3)`` camera matrix in ``raw`` (:data:`CAMERA_MATRIX_FIELDS`' layouts): nine numbers, skew at most
    :data:`MAX_SKEW` (left out), last row ``[0, 0, 1]`` or a multiple of it (divided out: the same camera); and None,
    or (None, what is wrong) for nine numbers that are no such matrix (a developer trial's K with a skew of 0.5 px, a
    transposed K and one whose last row was ``[0, 0, 2]`` were each dropped with a note asking for ``focal``).
    (None, None) when ``raw`` is not nine numbers, or all zeros."""
    K = _nine_numbers(raw)
    if K is None or not np.any(K):  # (ROS marks an uncalibrated camera by zeros: noted by unread_field_notes)
        return None, None
    if not np.all(np.isfinite(K)):
        return None, "its numbers must be finite"
    if K[0, 2] == 0 and K[1, 2] == 0 and K[2, 2] != 0 and (K[2, 0] != 0 or K[2, 1] != 0) and K[0, 1] == 0:
        return None, ("it is transposed: its last row holds the principal point (MATLAB's intrinsicMatrix layout); "
                      "give [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]")
    if K[2, 0] != 0 or K[2, 1] != 0 or not K[2, 2] > 0:
        return None, f"its last row must be [0, 0, 1], got {K[2].tolist()}: give [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]"
    K = K / K[2, 2]
    if K[1, 0] != 0 or abs(K[0, 1]) > MAX_SKEW * abs(K[0, 0]):
        return None, (f"its skew ({K[0, 1]:g}, {K[1, 0]:g}) is more than the {MAX_SKEW:g} x fx left out: the lift's "
                      "camera has none; undistort and give a camera without skew")
    K[0, 1] = 0.0
    return K, None


def _camera_matrix_field(meta: dict[str, Any], *, where: str) -> tuple[str, np.ndarray, np.ndarray] | None:
    """``(its name, focal (fx, fy), principal point (cx, cy))`` from a keypoint file's camera matrix, or None
    when it has none. Checked as ``focal`` and ``principal_point`` are."""
    own = meta.get("focal") is not None or meta.get("principal_point") is not None
    for key in CAMERA_MATRIX_FIELDS:
        K, problem = _camera_matrix(meta.get(key))
        if problem is not None and own:
            continue  # (the file's own focal and principal point are read; unread_field_notes says why K is not)
        if problem is not None:
            raise PoseLifterError(f"{where}: {key!r} is read as the camera matrix, but {problem} (or give 'focal' "
                                  "and 'principal_point')")
        if K is not None:
            return (key, _camera_field([K[0, 0], K[1, 1]], name=f"{key}'s focal", where=where),
                    _camera_field([K[0, 2], K[1, 2]], name=f"{key}'s principal point", where=where))
    return None


def _parse_int(text: str) -> int | float:
    """A JSON integer; one too large for a float (``1e400`` written out) becomes infinity, which the field checks
    refuse by name (a review's crashed with OverflowError)."""
    return int(text) if len(text) <= 300 else float("-inf" if text.startswith("-") else "inf")


JSON_BOMS: Final[tuple[tuple[bytes, str], ...]] = (
    (codecs.BOM_UTF32_LE, "utf-32"), (codecs.BOM_UTF32_BE, "utf-32"),  # (before UTF-16's: FF FE starts both)
    (codecs.BOM_UTF16_LE, "utf-16"), (codecs.BOM_UTF16_BE, "utf-16"),
)
"""The byte-order marks of JSON text not in UTF-8 (Windows PowerShell's ``>`` writes UTF-16 with one), and the codec
each names."""


def json_encoding(raw: bytes) -> str:
    """The encoding of JSON text from its first bytes, as :func:`json.loads` finds it for bytes (RFC 8259: UTF-8,
    UTF-16 or UTF-32, told by a byte-order mark or, without one, by where the first characters' zero bytes lie)."""
    codec = next((c for bom, c in JSON_BOMS if raw.startswith(bom)), None)
    return codec or json.detect_encoding(raw)


def json_text(raw: bytes) -> str:
    """The text of a JSON file's bytes in its encoding (:func:`json_encoding`: UTF-8 with or without a byte-order
    mark, UTF-16 or UTF-32; a user trial: PowerShell's UTF-16 output was refused with a codec error). Raises
    :class:`UnicodeDecodeError` (its ``encoding`` the one tried) for bytes that are not text in it."""
    return raw.decode(json_encoding(raw))


def json_head(head: bytes) -> bytes:
    """A file's first bytes as UTF-8, for sniffing: decoded from UTF-16 / UTF-32 where :func:`json_encoding` finds
    one (a character cut at the end dropped), else as they are."""
    codec = json_encoding(head)
    return head if codec.startswith("utf-8") else head.decode(codec, errors="ignore").encode("utf-8")


def _load_json(p: Path) -> Any:
    try:
        size = p.stat().st_size
    except OSError as exc:
        raise PoseLifterError(f"{p}: cannot read ({exc.strerror or exc})") from None
    if size > MAX_KEYPOINT_FILE_BYTES:
        raise PoseLifterError(f"{p}: {size / 1e6:.0f} MB is more than the {MAX_KEYPOINT_FILE_BYTES / 1e6:.0f} MB a "
                              "keypoint file may have")
    try:
        text = json_text(p.read_bytes())
    except OSError as exc:
        raise PoseLifterError(f"{p}: cannot read ({exc})") from None
    except UnicodeDecodeError as exc:
        enc = "UTF-8" if exc.encoding.startswith("utf-8") else exc.encoding.upper()
        raise PoseLifterError(f"{p}: not {enc} text, as its first bytes say it is ({exc.reason} at byte {exc.start}): "
                              "save the keypoint file as UTF-8 text") from None
    if not text.strip():
        raise PoseLifterError(f"{p}: the file is empty; a keypoint file is JSON with the 2D joints (formats: README, "
                              "'Photos in, absolute 3D out')")
    try:
        return json.loads(text, parse_int=_parse_int)
    except json.JSONDecodeError as exc:
        raise PoseLifterError(f"{p}: not valid JSON ({exc})") from None
    except RecursionError:
        raise PoseLifterError(f"{p}: JSON nested too deeply to be a keypoint file") from None


PERSON_ID_KEYS: Final[tuple[str, ...]] = ("person_id", "track_id", "id")
"""A person object's own identifier, copied to the output (the first of these keys it has, a string or integer). A
``track_id`` comes before an ``id``: in COCO and PoseTrack annotations ``id`` names the annotation (new in every
frame) and ``track_id`` the person (a review saw two people swap at a cut while their ``track_id`` said otherwise)."""


def _person_id(q: Any) -> str | int | None:
    if isinstance(q, dict):
        for k in PERSON_ID_KEYS:
            v = q.get(k)
            if isinstance(v, str) or (isinstance(v, int) and not isinstance(v, bool)):
                return v
    return None


CAMERA_FIELDS: Final[tuple[str, ...]] = ("focal", "principal_point", "image_size", "distortion", "distortion_model",
                                         "source")
"""The fields that describe a file's camera and 2D; read only at a file's (or sequence's) top level."""


READ_FIELDS: Final[tuple[str, ...]] = (*CAMERA_FIELDS, "keypoints", "format", "people", "frames", "fps")
"""Every top-level field a keypoint file or sequence is read by."""

_FIELD_NAMES_ELSEWHERE: Final[dict[str, str]] = {
    "dist_coeffs": "distortion", "distcoeffs": "distortion", "dist": "distortion", "distortion_coeffs": "distortion",
    "distortion_coefficients": "distortion", "lens": "distortion", "focal_length": "focal", "fx": "focal",
    "fy": "focal", "camera_matrix": "focal and principal_point", "intrinsics": "focal and principal_point",
    "intrinsic": "focal and principal_point", "intrinsic_matrix": "focal and principal_point",
    "camera": "focal and principal_point", "cam": "focal and principal_point",
    "calibration": "focal and principal_point", "pp": "principal_point", "cx": "principal_point",
    "cy": "principal_point", "resolution": "image_size", "width": "image_size", "height": "image_size",
    "image_width": "image_size", "image_height": "image_size", "keypoint_format": "format", "fmt": "format",
    "framerate": "fps", "frame_rate": "fps", "focal_px": "focal", "focal_length_px": "focal", "f_px": "focal",
    "focal_pixels": "focal", "focal_mm": "focal", "focal_length_mm": "focal", "f_mm": "focal",
    "image_shape": "image_size", "img_shape": "image_size", "imsize": "image_size",
    "keypoint": "keypoints", "kpts": "keypoints", "joints": "keypoints", "landmarks": "keypoints",
    "lens_model": "distortion_model", "camera_model": "distortion_model", "distortion_type": "distortion_model"}
"""Other tools' names for the fields this module reads (lower case): a file using them gets a note naming ours."""

_FIELD_LETTERS: Final[dict[str, str]] = {
    "f": "focal", "c": "principal_point", "K": "focal and principal_point", "k": "distortion", "p": "distortion",
    "d": "distortion", "D": "distortion", "w": "image_size", "h": "image_size"}
"""One-letter names, case-sensitive (OpenCV's ``K`` is the camera matrix; Human3.6M's ``k``, ``p`` the lens)."""

_OTHER_FIELDS: Final[frozenset[str]] = frozenset((
    "num_keypoints", "keypoints_3d", "image_id", "category_id", "bbox", "area", "iscrowd", "score", "id",
    "person_id", "track_id", "center", "scale", "version", "image", "file_name", "filename"))
"""Fields of common keypoint formats (COCO annotations and results, ...) that are not ours and not meant for ours:
never noted."""

_WRITTEN_FIELDS: Final[frozenset[str]] = frozenset((
    "input", "kind", "model", "model_info", "joint_names", "units", "frame", "keypoints_2d", "absolute", "relative",
    "root", "canonical_depth", "focal_source", "metric_depth", "source_format", "detector", "num_people", "scores",
    "warnings", "tracks",
    "num_frames", "num_frames_in_file", "first_frame", "last_frame", "bad_frames", "smoothing", "filter",
    "strength", "seconds_per_frame", "time_s", "error", "index", "root_unsmoothed", "track_id", "person_id",
    "input_index"))
"""Fields of the results this package writes (:meth:`LiftRecord.to_dict`, video records), which are read back
as keypoint files: not noted as unread."""


def _one_typo(key: str) -> str | None:
    """The field of :data:`READ_FIELDS` that ``key`` (5 letters or more) misspells by one letter changed, added,
    dropped or swapped with its neighbour (``"sourse"``, ``"fromat"``), else None: a short name scores below
    difflib's cutoff for such a slip."""
    k = key.lower()
    if len(k) < 5:
        return None
    for name in READ_FIELDS:
        if abs(len(name) - len(k)) > 1 or name == k:
            continue
        if len(name) == len(k):
            diff = [i for i in range(len(k)) if k[i] != name[i]]
            if len(diff) == 1 or (len(diff) == 2 and diff[1] == diff[0] + 1 and k[diff[0]] == name[diff[1]]
                                  and k[diff[1]] == name[diff[0]]):
                return name
        else:
            short, long_ = (k, name) if len(k) < len(name) else (name, k)
            if any(long_[:i] + long_[i + 1:] == short for i in range(len(long_))):
                return name
    return None


def unread_field_notes(meta: dict[str, Any]) -> list[str]:
    """Notes for top-level fields of a keypoint file or sequence that look meant for a field it is read by
    (:data:`READ_FIELDS`) but are not, e.g. OpenCV's ``dist_coeffs`` or a misspelled ``distorsion``: their values
    would otherwise be dropped silently. Fields that resemble none (an image name, a version) are not noted."""
    notes = []
    for key in meta:
        if not isinstance(key, str) or key in READ_FIELDS or key in _WRITTEN_FIELDS or key in _OTHER_FIELDS:
            continue
        if key in CAMERA_MATRIX_FIELDS:
            K, problem = _camera_matrix(meta[key])
            if problem is not None:  # (refused by _camera_matrix_field, unless the file gives its own camera)
                notes.append(f"{key!r} is not read as the camera matrix: {problem}; the file's 'focal' and "
                             "'principal_point' are used")
                continue
            if K is not None:
                continue  # (read: _camera_meta)
            nine = _nine_numbers(meta[key])
            if nine is not None and not np.any(nine):
                notes.append(f"{key!r} is all zeros, as ROS marks an uncalibrated camera: not read")
                continue
        ours = (_FIELD_LETTERS.get(key) if len(key) == 1 else _FIELD_NAMES_ELSEWHERE.get(key.lower())) or next(
            iter(difflib.get_close_matches(key.lower(), READ_FIELDS, n=1, cutoff=0.88)), None) or _one_typo(key)
        if ours is None or all(n in meta for n in ours.split(" and ")):
            continue  # (not like any of ours, or ours is there too: fx beside focal, width beside image_size)
        names = " and ".join(f"{n!r}" for n in ours.split(" and "))
        hint = ""
        if ours == "distortion" and key in ("k", "p"):
            hint = (" Human3.6M's cameras name the lens k (k1, k2, k3) and p (p1, p2); give them together as "
                    "'distortion': [k1, k2, k3, p1, p2]")
        elif ours == "distortion" and (key.lower() in _FIELD_NAMES_ELSEWHERE or key in _FIELD_LETTERS):
            hint = (" It takes Human3.6M's order (k1, k2, k3, p1, p2); for OpenCV's distCoeffs (k1, k2, p1, p2[, k3"
                    "[, k4, k5, k6]]) as calibrated, add \"distortion_model\": \"opencv\" beside them")
        elif key.lower() in ("camera", "cam", "calibration") and isinstance(meta[key], dict):
            hint = (" Camera fields go at the file's top level: 'focal', 'principal_point', 'image_size', "
                    "'distortion'")
        elif ours == "focal and principal_point":
            hint = " (fx, fy and cx, cy of the camera matrix, px)"
        elif ours == "focal" and "mm" in key.lower():
            hint = (" It takes the focal length in pixels: f_px = f_mm * image width px / sensor width mm (or leave "
                    "it out to assume a field of view)")
        notes.append(f"{key!r} is not read: did you mean {names}?{hint}")
    return notes


def _misplaced_camera_fields(d: Any, *, frame_level: bool) -> list[str]:
    """Camera fields (:data:`CAMERA_FIELDS`) inside a person object of decoded frame ``d`` (or, ``frame_level``,
    in the frame object itself), which are not read: a note names them so a misplaced lens or focal is not lost
    silently."""
    people = d.get("people") if isinstance(d, dict) else d if isinstance(d, list) else None
    objs = [q for q in people if isinstance(q, dict)] if isinstance(people, list) else []
    if frame_level and isinstance(d, dict):
        objs.append(d)
    return sorted({k for q in objs for k in CAMERA_FIELDS if k in q})


def _is_own_person(q: Any) -> bool:
    """Whether a person object is poselifter's own output: ``keypoints_2d`` (H36M's 17 joints) and no
    ``keypoints``."""
    return isinstance(q, dict) and "keypoints_2d" in q and "keypoints" not in q


def _check_person_keypoints_field(q: dict[str, Any], p: Path, n: int) -> None:
    """Refuse a person object that holds its joints under another tool's name (``kpts``, ``joints``, ``landmarks``:
    :data:`_FIELD_NAMES_ELSEWHERE`) and has no ``keypoints``: it would be left out without a word (a review lost the
    larger of two people so). A person whose ``keypoints`` is null or absent otherwise is left out as nobody."""
    if "keypoints" in q:
        return
    other = [k for k in q if isinstance(k, str) and _FIELD_NAMES_ELSEWHERE.get(k.lower()) == "keypoints"]
    if other:
        raise PoseLifterError(f"{p}: person {n + 1} has {other[0]!r} and no 'keypoints': name the field 'keypoints' "
                              "(a list of [x, y] or [x, y, confidence] rows)")


def _scored(q: dict[str, Any], p: Path) -> Any:
    """A person object's ``keypoints``, with MMPose's / RTMPose's separate ``keypoint_scores`` (one per joint) made
    their third values, so that they are read as every other confidence is (a score <= 0 marks a missing joint)."""
    raw, scores = q.get("keypoints"), q.get("keypoint_scores")
    if scores is None or raw is None:
        return raw
    if not (isinstance(scores, list) and all(_is_number(v) or v is None for v in scores)):
        raise PoseLifterError(f"{p}: 'keypoint_scores' must be a list of numbers, one per joint, got {_short(scores)}")
    if isinstance(raw, list) and raw and all(_is_row(r) or r is None for r in raw):
        if any(r is not None and len(r) == 3 for r in raw):
            raise PoseLifterError(f"{p}: a person has both a third value in each 'keypoints' row and "
                                  "'keypoint_scores': give the confidences once (drop one of the two)")
        rows = raw
    elif isinstance(raw, list) and raw and all(_is_number(v) or v is None for v in raw):
        if len(raw) == 3 * len(scores):
            raise PoseLifterError(f"{p}: a person has both a confidence in its flat [x, y, c, ...] 'keypoints' and "
                                  "'keypoint_scores': give the confidences once (drop one of the two)")
        if len(raw) != 2 * len(scores):
            raise PoseLifterError(f"{p}: {len(raw)} numbers in a flat 'keypoints' list but {len(scores)} "
                                  "'keypoint_scores': one [x, y] pair per score")
        rows = [raw[i:i + 2] for i in range(0, len(raw), 2)]
    else:
        return raw  # (not rows of [x, y]: _rows says what is wrong with it)
    if len(rows) != len(scores):
        raise PoseLifterError(f"{p}: {len(rows)} keypoints but {len(scores)} 'keypoint_scores': one score per joint")
    return [None if r is None else [*r, c] for r, c in zip(rows, scores)]


def _own_scored(q: dict[str, Any]) -> Any:
    """A person of this package's own output (:meth:`LiftRecord.to_dict`, a video record's frames): its
    ``keypoints_2d`` with its detector ``scores`` as their third values, so that a lift of the output again keeps
    them (and the notes on unsure joints; a user trial lost both). Every joint of such a person was lifted, so a
    score rounded to 0 is read as the smallest positive one, not as a missing joint."""
    rows, scores = q.get("keypoints_2d"), q.get("scores")
    if not (isinstance(rows, list) and isinstance(scores, list) and len(rows) == len(scores)
            and all(isinstance(r, list) and len(r) == 2 and all(_is_number(x) for x in r) for r in rows)
            and all(_is_number(v) for v in scores)):
        return rows  # (no scores, or not in the form written: read as given, _rows says what is wrong)
    return [[*r, max(float(c), 1e-9)] for r, c in zip(rows, scores)]


MMPOSE_JOINT_NAMES: Final[dict[str, tuple[str, ...]]] = {
    "coco17": ("nose", "left_eye", "right_eye", "left_ear", "right_ear", "left_shoulder", "right_shoulder",
               "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hip", "right_hip", "left_knee",
               "right_knee", "left_ankle", "right_ankle"),
    H36M17: ("root", "right_hip", "right_knee", "right_foot", "left_hip", "left_knee", "left_foot", "spine",
             "thorax", "neck_base", "head", "left_shoulder", "left_elbow", "left_wrist", "right_shoulder",
             "right_elbow", "right_wrist"),
}
"""The keypoint names of MMPose's dataset metadata (``meta_info["keypoint_id2name"]`` of a predictions file) for the
formats read here, in their order."""

MMPOSE_DATASETS: Final[dict[str, str]] = {"coco": "coco17", "h36m": H36M17}
"""MMPose's ``meta_info["dataset_name"]`` of the formats read here."""


def _mmpose_meta_format(meta: Any) -> str | None:
    """The keypoint format an MMPose predictions file's ``meta_info`` names: by its ``keypoint_id2name`` (the joints
    in order, :data:`MMPOSE_JOINT_NAMES`), else its ``dataset_name`` (:data:`MMPOSE_DATASETS`); None when it names
    neither (a user trial: a file of H36M joints, saying so, was read as COCO-17 and lifted 2 m off)."""
    if not isinstance(meta, dict):
        return None
    names = meta.get("keypoint_id2name")
    if isinstance(names, dict):
        ordered = tuple(str(names.get(str(i), "")).lower() for i in range(len(names)))  # (JSON's keys: strings)
        found = next((f for f, want in MMPOSE_JOINT_NAMES.items() if ordered == want), None)
        if found is not None:
            return found
    dataset = meta.get("dataset_name")
    return MMPOSE_DATASETS.get(dataset.lower()) if isinstance(dataset, str) else None


def _inferencer_results(d: Any) -> Any:
    """MMPoseInferencer's results saved as they come (``{"predictions": [[instance, ...]], "visualization": [...]}``
    per image or frame; a list of them for a video) as MMPose's frames (``{"instances": [...]}``, a list of
    ``{"frame_id", "instances"}``), which :func:`_mmpose_frame` and :func:`_mmpose_sequence` read; anything else as
    it is (a user trial's saved result was "expected an object with 'keypoints'"). Each result holds the images of
    one call, and one file is one image: a result of several images is left as it is (refused as a layout)."""
    def frame(r: Any) -> Any:
        theirs = isinstance(r, dict) and not any(k in r for k in ("instances", "keypoints", "people",
                                                                    "pose_keypoints_2d", "frames"))
        preds = r.get("predictions") if theirs else None
        if not (isinstance(preds, list) and len(preds) == 1 and isinstance(preds[0], list)):
            return None
        return {**{k: v for k, v in r.items() if k not in ("predictions", "visualization")}, "instances": preds[0]}

    if isinstance(d, dict):
        return frame(d) or d
    if isinstance(d, list) and d and all(isinstance(r, dict) and "predictions" in r for r in d):
        frames = [frame(r) for r in d]
        if all(f is not None for f in frames):
            return [{"frame_id": i, **f} for i, f in enumerate(frames)]
    return d


def _mmpose_frame(d: Any, p: Path, fmt: str | None) -> tuple[Any, str | None]:
    """MMPose's prediction files as one frame of people: the demo's ``--save-predictions`` file (``{"meta_info":
    ..., "instance_info": [{"frame_id": 1, "instances": [...]}]}``, or its instances directly), MMPoseInferencer's
    predictions (``[{"frame_id": 0, "instances": [...]}, ...]``) and one such frame of a sequence, as
    ``{"people": instances, ...the file's other fields}``, in the joints its ``meta_info`` names
    (:func:`_mmpose_meta_format`), else COCO-17, unless a format is given. Several frames are a
    video's, a keypoint sequence (:func:`_mmpose_sequence`): refused here, naming how to lift them. Anything else comes
    back as it is."""
    d = _inferencer_results(d)
    if isinstance(d, dict) and "instance_info" in d and "people" not in d and "keypoints" not in d:
        info, label, rest = d["instance_info"], "an MMPose predictions file", ("instance_info", "meta_info")
        if isinstance(info, list) and all(isinstance(q, dict) and "instances" not in q for q in info):
            info = [{"instances": info}]  # (an image demo's instances directly)
    elif isinstance(d, list) and d and all(isinstance(q, dict) and "instances" in q for q in d):
        info, label, rest, d = d, "MMPose predictions", ("instances", "frame_id"), d[0]
    elif isinstance(d, dict) and "instances" in d and "people" not in d and "keypoints" not in d:
        info, label, rest = [d], "MMPose predictions", ("instances", "frame_id")
    else:
        return d, fmt
    if not (isinstance(info, list) and info and all(isinstance(q, dict) and "instances" in q for q in info)):
        raise PoseLifterError(f"{p}: 'instance_info' (an MMPose predictions file) must be a list of instances or of "
                              f"frames with 'instances', got {_short(info)}")
    if len(info) > 1:
        where = "'instance_info'" if label.endswith("file") else "'instances' per frame"
        raise PoseLifterError(f"{p}: {label} of {len(info)} frames ({where}) is a keypoint sequence: poselifter lift "
                              "lifts it as one, given its frame rate (\"fps\" at the file's top level, or --fps); "
                              "in Python lifter.video.lift_keypoint_sequence(path, fps=...)")
    people = info[0]["instances"]
    if not isinstance(people, list):
        raise PoseLifterError(f"{p}: 'instances' must be a list of people, got {_short(people)}")
    meta_fmt = _mmpose_meta_format(d.get("meta_info")) if isinstance(d, dict) else None
    d = {**{k: v for k, v in d.items() if k not in rest}, "people": people}
    return d, fmt or (d["format"] if isinstance(d.get("format"), str) else meta_fmt or "coco17")


def _people_of(d: Any, p: Path, fmt: str | None
               ) -> tuple[list[tuple[int, Any, str | int | None]], str | None, dict[str, Any], bool]:
    """The people in one decoded frame object as ``(position in the file's list, raw keypoint list, person id)``
    (people without keypoints left out), the format it implies, its camera fields (module docstring layouts), and
    whether that format is only the layout's (:data:`LAYOUT_FORMATS`: no ``format`` given)."""
    given = fmt
    meta: dict[str, Any] = {}
    ids: list[str | int | None] = []
    d, fmt = _mmpose_frame(d, p, fmt)
    if isinstance(d, dict) and "people" in d:  # OpenPose output, or a list of {"keypoints": ...}
        if not isinstance(d["people"], list):
            raise PoseLifterError(f"{p}: 'people' must be a list of {{\"pose_keypoints_2d\": [...]}} or "
                                  f"{{\"keypoints\": [...]}} objects, got {_short(d['people'])}")
        people = []
        ids = [_person_id(q) for q in d["people"]]
        own = False
        for n, q in enumerate(d["people"]):
            if isinstance(q, dict) and "pose_keypoints_2d" in q:
                people.append(q["pose_keypoints_2d"])
                fmt = fmt or "openpose25"
            elif _is_own_person(q):
                people.append(_own_scored(q))
                own = True
            elif isinstance(q, dict):
                _check_person_keypoints_field(q, p, n)
                people.append(_scored(q, p))
            else:
                people.append(q)
        meta = {k: v for k, v in d.items() if k != "people"}
        if meta.get("format") is not None:
            fmt = meta["format"]  # (its type is checked below)
        elif own:
            fmt = H36M17  # (its 'keypoints_2d' are H36M's whatever format the other files have: a review re-lifted
            # a result with --format coco17 and got its 2D read as COCO's, the root 46 % too near)
    elif isinstance(d, list) and d and all(isinstance(q, dict) for q in d):  # COCO-style results
        found = {q["image_id"] for q in d if q.get("image_id") is not None and isinstance(q["image_id"], (int, str))}
        images = sorted(found, key=lambda i: (isinstance(i, str), i))  # (numbers in number order, then names)
        if len(images) > 1:
            shown = ", ".join(map(str, images[:5])) + (", ..." if len(images) > 5 else "")
            raise PoseLifterError(f"{p}: a list of people from {len(images)} images (image_id {shown}); a keypoint "
                                  "file is one image, seen by one camera: split the list by image_id into one file "
                                  "per image (or give a sequence with 'frames')")
        for n, q in enumerate(d):
            _check_person_keypoints_field(q, p, n)
        people = [_scored(q, p) for q in d]
        ids = [_person_id(q) for q in d]
        fmt = fmt or "coco17"
    elif isinstance(d, dict) and "keypoints" in d:
        people = [_scored(d, p)]
        ids = [_person_id(d)]
        meta = d
        fmt = d.get("format") or fmt
    elif isinstance(d, list):
        people = [d]
    elif _is_own_person(d):  # a person of poselifter's own output, on its own
        people = [_own_scored(d)]
        ids = [_person_id(d)]
        meta = d
        fmt = d.get("format") or H36M17  # (H36M's, whatever format the other files have)
    else:
        keys = [k for k in d if isinstance(k, str)] if isinstance(d, dict) else []
        near = [k for k in keys if _FIELD_NAMES_ELSEWHERE.get(k.lower()) == "keypoints"] or \
            difflib.get_close_matches("keypoints", keys, n=1, cutoff=0.75)
        raise PoseLifterError(f"{p}: expected an object with 'keypoints', a list of [x, y] rows, OpenPose "
                              "'people' or a list of people"
                              + (f" (the file has {near[0]!r}: did you mean 'keypoints'?)" if near else ""))
    if fmt is not None and not isinstance(fmt, str):
        raise PoseLifterError(f"{p}: 'format' must be a string (one of {list(keypoint_formats())}), got "
                              f"{_short(fmt)}")
    ids = ids or [None] * len(people)
    kept = [(i, q, pid) for i, (q, pid) in enumerate(zip(people, ids)) if q is not None and q != []]
    return kept, fmt, meta, fmt in LAYOUT_FORMATS and fmt != given and not (isinstance(d, dict) and d.get("format"))


def _nobody_detail(d: Any) -> str:
    """Why a decoded keypoint file gave nobody, for the message (a user trial read "no person" for ``{"keypoints":
    null}`` and for objects without keypoints, as for a frame where nobody was found): empty for a layout that says
    nobody was there (``"people": []``, ``[]``)."""
    d = _inferencer_results(d)
    if isinstance(d, dict) and "keypoints" in d and d["keypoints"] is None:
        return ": its 'keypoints' is null (a list of [x, y] or [x, y, confidence] rows)"
    if isinstance(d, list) and d and all(isinstance(q, dict) for q in d):
        if any(k in q for q in d for k in ("instances", "frame_id", "pose_keypoints_2d")):
            return ""  # (MMPose's or OpenPose's frame where nobody was found)
        if all("keypoints" in q for q in d):
            return f": the 'keypoints' of its {len(d)} object(s) are empty or null"
        if not any("keypoints" in q for q in d):
            keys = sorted({str(k) for q in d for k in q})
            frames = (" (a list of frames, each with its 'people', is a keypoint sequence: give it as {\"frames\": "
                      "[...], \"fps\": 30})") if all("people" in q for q in d) else ""
            return (f": none of its {len(d)} object(s) has 'keypoints' (a list of [x, y] or [x, y, confidence] "
                    f"rows); they have {', '.join(repr(k) for k in keys[:8])}" + (", ..." if len(keys) > 8 else "")
                    + frames)
    return ""


def _one_of(names: Sequence[str]) -> str:
    """``'a'``, ``'a' or 'b'``, ``one of 'a', 'b', 'c'``: format names for messages."""
    quoted = [repr(n) for n in names]
    return " or ".join(quoted) if len(quoted) <= 2 else "one of " + ", ".join(quoted)


def _no_format_with(num_joints: int) -> str:
    """The end of the message for a pose of ``num_joints`` that no format has: the formats' joint counts, and for 18
    OpenPose's COCO-18 layout (a user trial's file), which is not read."""
    counts = ", ".join(f"{n} {get_format(n).num_joints}" for n in keypoint_formats())
    return (f": no format has {num_joints} joints (the formats and their joint counts: {counts}); convert the "
            "keypoints to one of them" + other_layout_hint(num_joints)
            + (" (18 joints is OpenPose's COCO-18 / BODY_18 layout, which is not read: run OpenPose with BODY_25, "
               "openpose25, or write the 17 COCO joints in COCO order, coco17)" if num_joints == 18 else ""))


def _needs(fmt: str) -> str:
    """What a person must give, for the messages on missing joints."""
    return ("the lifter needs all 17 joints" if fmt == H36M17
            else f"the lifter needs every joint that the {fmt} -> h36m17 rules use")


def _who(k: int, pid: str | int | None, n: int, *, frame: int | None = None) -> str:
    """A person of a file with ``n`` people (of a sequence's frame number ``frame``), for messages: their place in
    the file's (frame's) list, counted from 1 and as the output's ``input_index`` (from 0), and their id."""
    of = "in the file" if frame is None else f"of frame {frame}"
    return ("the person" + ("" if frame is None else f" {of}") if n == 1 and pid is None
            else f"person {k + 1} {of} (input_index {k}" + ("" if pid is None else f", id {pid!r}") + ")")


@dataclass
class _People:
    """What :func:`_people_arrays` found in one frame of a keypoint file."""

    arrays: list[np.ndarray]
    """Each person kept, ``(J, 2)`` px in ``format``, largest (box area) first."""
    format: str
    identity: list[tuple[int, str | int | None]]
    """For each kept person: ``(position in the file's list, person id)``."""
    dropped: list[tuple[str, list[str]]]
    """The people left out because a joint the lifter needs is missing: ``(who, [joint names])``."""
    scores: list[np.ndarray | None]
    """For each kept person: their ``(J,)`` confidences as given (stood-in joints: their stand-ins' lowest), or None."""
    stood_in: list[tuple[str, list[str]]]
    """The people with missing joints stood in for (:func:`lifter.keypoints.stand_in_missing`): ``(who, phrases)``."""


def _h36m_as_coco_notes(kp17: np.ndarray) -> list[str]:
    """A note on people ``(n, 17, 2)`` px read as COCO-17 whose first five joints each spread as H36M's do
    (:func:`lifter._checks.not_face_first_message`): converted as COCO-17, H36M order is lifted scrambled (a
    developer trial's root at 55 % of its depth, the only note blaming the detector). A note, not a refusal: the
    file said coco17, and a face can be that large beside a body seen only in part (a review: a webcam's head and
    torso, 23 %; a toddler crouching, 24 %)."""
    said = not_face_first_message(kp17)
    if said is None:
        return []
    return [f"{said} If so, give \"format\": \"h36m17\" in the file (or --format h36m17 with poselifter lift, for "
            "a file without 'format'): they were lifted as COCO-17"]


def _face_first(xy: np.ndarray, missing: np.ndarray) -> bool:
    """Whether the 17-joint pose ``xy`` ``(17, 2)`` px (``missing`` ``(17,)``) starts with five points as close together
    as a face's (:func:`lifter._checks.face_first_people`, :data:`COCO_FACE_SPREAD`)."""
    return bool(face_first_people(xy, missing)[0])


def _score_note(top: float) -> str:
    """The note on confidences above :data:`SCORE_NOTE_ABOVE` (the largest ``top``): another scale than [0, 1]."""
    return (f"third values up to {top:.4g}: read as a detector's unnormalised scores (only a value <= 0 marks a "
            "missing joint)")


def _people_arrays(people: list[tuple[int, Any, str | int | None]], p: Path, fmt: str | None, notes: list[str],
                   *, layout_format: bool = False, frame: int | None = None, score_note: bool = True,
                   frames_before: int = 0) -> _People:
    """Each person of :func:`_people_of` as ``(J, 2)`` px, largest (box area) first, checked against the format,
    with a missing face or mid-body joint stood in for where the format allows (:data:`lifter.keypoints.STAND_INS`);
    the people still missing a joint the lifter needs (confidence 0 or below or null, or null / NaN coordinates) are
    left out. layout_format: ``fmt`` is only what the file's layout implies (:func:`_people_of`), for the messages.
    frame: the sequence's frame these people are of (None: a single-frame file), for the messages (:func:`_who`);
    frames_before: how many of the sequence's frames before it have people, each in ``fmt`` (for the messages)."""
    parsed = []
    top = -math.inf
    for _, q, _ in people:
        xy, conf = _rows(q, str(p))
        missing = missing_joints(xy, conf)
        if conf is not None:
            top = max([top, *conf[np.isfinite(conf)].tolist()])
        parsed.append((xy, missing, conf))
    if top > SCORE_NOTE_ABOVE and score_note:
        notes.append(_score_note(top))
    if not parsed:
        return _People([], fmt or H36M17, [], [], [], [])

    def area(k: int) -> float:
        xy, miss, _ = parsed[k]
        ok = xy[~miss]
        with np.errstate(over="ignore"):  # absurd coordinates are refused later, with a message naming them
            return 0.0 if len(ok) < 2 else float(np.prod(ok.max(0) - ok.min(0)))

    order = sorted(range(len(parsed)), key=area, reverse=True)  # stable: equal areas keep the file's order
    parsed = [parsed[k] for k in order]
    identity = [(people[k][0], people[k][2]) for k in order]
    J = len(parsed[0][0])
    if fmt is None:
        if J not in FORMAT_BY_COUNT:
            counts = ", ".join(f"{get_format(n).num_joints} ({n})" for n in keypoint_formats())
            raise PoseLifterError(f"{p}: {J} joints per person, which no known keypoint format has; the formats and "
                                  f"their joint counts: {counts}. Give the joints of one of these formats (and "
                                  "'format' where the count is shared)" + (COCO18_HINT if J == 18 else "")
                                  + other_layout_hint(J))
        fmt = FORMAT_BY_COUNT[J]
        if J == 17 and all(_face_first(xy, miss) for xy, miss, _ in parsed):
            raise PoseLifterError(
                f"{p}: 17 joints without 'format', and each person's first five lie within "
                f"{COCO_FACE_SPREAD * 100:.0f} % of their 2D size of each other, as COCO-17's nose, eyes and ears "
                "do (H36M's first five, the pelvis, hips, right knee and right foot, span the legs): give "
                "\"format\": \"coco17\" in the file, or --format coco17 with poselifter lift (--format h36m17 if "
                "this is H36M order)")
        if J == 17:
            notes.append("17 joints without 'format': assumed H36M order (for COCO keypoints give \"format\": "
                         "\"coco17\" in the file, or --format coco17 with poselifter lift)")
        else:
            notes.append(f"{J} joints without 'format': assumed {fmt!r} by the joint count (give 'format' in the "
                         "file, or --format with poselifter lift, if they are another layout)")
    f = get_format(fmt)
    out, kept, dropped, scores, stood_in = [], [], [], [], []
    for (xy, missing, conf), (pos, pid) in zip(parsed, identity):
        if len(xy) != f.num_joints:
            raise PoseLifterError(_count_message(p, fmt, [len(q[0]) for q in parsed], len(xy), who=_who(
                pos, pid, len(people), frame=frame), layout_format=layout_format, frames_before=frames_before))
        if missing.any():
            xy, conf, said, bad = fill_missing(xy, missing, src=fmt, scores=conf)  # (bad: needed, still missing)
            if bad:
                dropped.append((_who(pos, pid, len(people), frame=frame), bad))
                continue
            if said:
                stood_in.append((_who(pos, pid, len(people), frame=frame), said))
        out.append(xy)
        kept.append((pos, pid))
        scores.append(conf)
    return _People(out, fmt, kept, dropped, scores, stood_in)


def _count_message(p: Path, fmt: str, counts: list[int], count: int, *, who: str, layout_format: bool,
                   frames_before: int) -> str:
    """The message for a person ``who`` of ``count`` joints where the format ``fmt`` has another count (``counts``:
    every person's of the frame). Where the frame's other people or the sequence's earlier frames have the format's
    count, it names what differs (a developer trial: one person cut to 16 rows was told to give format 'sh16', and
    a file switching to OpenPose's layout at frame 10 to give 'openpose25' for the whole file)."""
    n = get_format(fmt).num_joints
    same = [k for k in keypoint_formats() if get_format(k).num_joints == count]
    fitting = sum(c == n for c in counts)
    if fitting:
        return (f"{p}: {who} has {count} joints, where format {fmt!r} has {n}, as {fitting} other "
                f"{'person' if fitting == 1 else 'people'} of the frame {'has' if fitting == 1 else 'have'}: that "
                f"person's rows are cut short or padded; give all {n} joints (null for any not known) or leave "
                "them out")
    if frames_before:
        layout = f" ({count} joints: {_one_of(same)})" if same else ""
        alike = len(set(counts)) == 1
        whose = f"{count} joints per person" if alike else f"{who} has {count} joints"
        rows = "their rows are" if alike and len(counts) > 1 else "that person's rows are"
        return (f"{p}: {whose}, where format {fmt!r} has {n}, as the {frames_before} frame(s) with people before it "
                f"have: {rows} cut short or padded, or the file changes keypoint layout at this frame{layout}; give "
                f"every person all {n} joints (null for any not known), in one format for the whole file "
                "(lifter.keypoints.convert converts between formats), or lift each part as a file of its own")
    return (f"{p}: format {fmt!r} has {n} joints, the file has {count}"
            + (f" ({LAYOUT_FORMATS[fmt]} implies {fmt!r} when the file has no 'format')" if layout_format else "")
            + (f": give the file's format, {_one_of(same)} ('format' in the file, or --format with poselifter lift)"
               if same else _no_format_with(count)))


def _missing_message(fmt: str, dropped: list[tuple[str, list[str]]], *, nobody_left: bool) -> str:
    who = "; ".join(f"{w}: {bad}" for w, bad in dropped[:5]) + ("; ..." if len(dropped) > 5 else "")
    return (f"joint(s) missing (confidence 0 or below or null, or null / NaN coordinates) for {who}; {_needs(fmt)}"
            + (". Give those joints (e.g. placed by hand, or interpolated from neighbouring frames)" if nobody_left
               else ""))


def distortion_tuple(distortion: np.ndarray | None) -> tuple[float, ...] | None:
    """A file's ``distortion`` array ``(5,)`` as the records hold it: ``(k1, k2, k3, p1, p2)`` floats, or None."""
    return None if distortion is None else tuple(float(v) for v in np.asarray(distortion).reshape(-1))


def _distortion_field(raw: Any, *, where: str) -> np.ndarray:
    """A keypoint file's ``distortion``: five finite numbers ``[k1, k2, k3, p1, p2]`` below
    :data:`lifter.camera.MAX_DISTORTION_COEFFICIENT` in magnitude."""
    form = (f"[k1, k2, k3, p1, p2]: five numbers below {MAX_DISTORTION_COEFFICIENT:g} in magnitude (Human3.6M's "
            "Brown-Conrady form, lifter.camera.distort; OpenCV's distCoeffs are another order and other tangential "
            "terms: undistort with cv2.undistortPoints instead)")
    if not (isinstance(raw, (list, tuple)) and len(raw) == 5 and all(_is_number(v) for v in raw)):
        count = f" ({len(raw)} values)" if isinstance(raw, (list, tuple)) else ""
        raise PoseLifterError(f"{where}: distortion must be {form}, got {_short(raw)}{count}")
    try:
        return check_distortion(raw)  # (the library's one rule: finite, below MAX_DISTORTION_COEFFICIENT)
    except PoseLifterError:
        raise PoseLifterError(f"{where}: distortion must be {form}, got {[float(v) for v in raw]}") from None


_ROS_DISTORTION_MODELS: Final[dict[str, str]] = {"plumb_bob": "opencv", "rational_polynomial": "opencv"}
"""ROS ``camera_info``'s names for OpenCV's lens models (5 and 8 coefficients), read as ``"opencv"``."""


def _distortion_model_field(raw: Any, *, where: str) -> DistortionModel:
    """A keypoint file's ``distortion_model``: ``"h36m"`` (the default) or ``"opencv"`` (or ROS's names for it)."""
    try:
        return check_distortion_model(_ROS_DISTORTION_MODELS.get(raw, raw) if isinstance(raw, str) else raw)
    except PoseLifterError as exc:
        raise PoseLifterError(f"{where}: {exc} (ROS's \"plumb_bob\" and \"rational_polynomial\" are read as "
                              "\"opencv\")") from None


def _opencv_distortion_field(raw: Any, *, where: str) -> np.ndarray:
    """A keypoint file's ``distortion`` with ``"distortion_model": "opencv"``: OpenCV's ``distCoeffs``, 4, 5 or 8
    finite numbers below :data:`lifter.camera.MAX_DISTORTION_COEFFICIENT` in magnitude."""
    counts = ", ".join(map(str, OPENCV_DISTORTION_COUNTS))
    form = (f"OpenCV's distCoeffs [k1, k2, p1, p2, k3, ...] ({counts} numbers below {MAX_DISTORTION_COEFFICIENT:g} "
            "in magnitude) with \"distortion_model\": \"opencv\"")
    if not (isinstance(raw, (list, tuple)) and all(_is_number(v) for v in raw)):
        raise PoseLifterError(f"{where}: distortion must be {form}, got {_short(raw)}")
    try:
        return check_opencv_distortion(raw)
    except PoseLifterError as exc:
        raise PoseLifterError(f"{where}: distortion must be {form}: {exc}") from None


def _camera_meta(meta: dict[str, Any], p: Path) -> tuple[tuple[int, int] | None, np.ndarray | None,
                                                          np.ndarray | None, str, np.ndarray | None,
                                                          DistortionModel]:
    image_size = _image_size_field(meta.get("image_size"), where=str(p))
    focal = None if meta.get("focal") is None else _camera_field(meta["focal"], name="focal", where=str(p))
    pp = None if meta.get("principal_point") is None else \
        _camera_field(meta["principal_point"], name="principal_point", where=str(p))
    matrix = _camera_matrix_field(meta, where=str(p))
    if matrix is not None:
        key, f_k, pp_k = matrix
        for name, ours, theirs in (("focal", focal, f_k), ("principal_point", pp, pp_k)):
            if ours is not None and not np.allclose(ours, theirs):
                raise PoseLifterError(f"{p}: {name!r} {ours.tolist()} and the camera matrix {key!r} "
                                      f"({theirs.tolist()}) disagree; give one of them")
        focal, pp = f_k, pp_k
    source = meta.get("source", "detected")
    if source not in ("detected", "clean"):
        raise PoseLifterError(f"{p}: 'source' must be \"detected\" (2D from a detector, the default) or \"clean\" "
                              f"(exact 2D: ground truth or hand-placed), got {source!r}")
    model: DistortionModel = "h36m" if meta.get("distortion_model") is None else \
        _distortion_model_field(meta["distortion_model"], where=str(p))
    read = _opencv_distortion_field if model == "opencv" else _distortion_field
    dist = None if meta.get("distortion") is None else read(meta["distortion"], where=str(p))
    return image_size, focal, pp, source, dist, model


def _written_assumed(focal: np.ndarray | None, meta: dict[str, Any], image_size: tuple[int, int] | None
                     ) -> tuple[np.ndarray | None, str | None]:
    """A result this package wrote with an assumed focal (``focal_source`` ``"default-fov"``) and read back: its
    focal is not taken as known (None: assumed again from ``image_size``), and the written one (as text, px) is
    returned for the note that says so (:func:`lifter.pipeline.resolve_camera`'s callers). Otherwise unchanged."""
    if focal is None or meta.get("focal_source") != ASSUMED_FOCAL_SOURCE or image_size is None:
        return focal, None
    return None, " x ".join(f"{v:.1f}" for v in dict.fromkeys(np.round(np.ravel(focal), 1).tolist()))


def parse_keypoint_json(path: str | Path, *, default_format: str | None = None) -> KeypointFile:
    """Read a keypoint JSON file (module docstring). Raises :class:`PoseLifterError` with the reason."""
    p = Path(path)
    d = _load_json(p)
    notes: list[str] = []
    if isinstance(d, dict) and "frames" in d:
        raise PoseLifterError(f"{p}: a keypoint sequence ('frames'); read it with parse_keypoint_sequence")
    people, fmt, meta, layout_format = _people_of(d, p, default_format)
    if not people:
        raise PoseLifterError(f"{p}: no person in the keypoint file{_nobody_detail(d)}")
    found = _people_arrays(people, p, fmt, notes, layout_format=layout_format)
    if found.format == "coco17" and found.arrays:
        notes += _h36m_as_coco_notes(np.stack(found.arrays))
    people_scores: tuple[np.ndarray | None, ...] = tuple(found.scores)
    if _visibility_flags(people_scores):
        notes.append(FLAGS_NOTE)
        people_scores = tuple(None for _ in people_scores)
    arrays, fmt, identity, dropped = found.arrays, found.format, found.identity, found.dropped
    if dropped and not arrays:
        raise PoseLifterError(f"{p}: {_missing_message(fmt, dropped, nobody_left=True)}")
    if found.stood_in:
        notes.append(STAND_IN_NOTE.format(what="; ".join(
            (f"{who}: " if len(people) > 1 else "") + ", ".join(said) for who, said in found.stood_in)))
    if dropped:
        notes.append(f"{len(dropped)} of {len(people)} people left out: "
                     f"{_missing_message(fmt, dropped, nobody_left=False)}")
    if len(arrays) > 1:
        has_ids = any(i is not None for _, i in identity)
        notes.append(f"{len(arrays)} people in the file; each is lifted (largest first; 'input_index' is a person's "
                     "position in the file" + (", 'person_id' their own id)" if has_ids else ")"))
    unread: list[str] = []
    misplaced = _misplaced_camera_fields(d, frame_level=False)
    if misplaced:
        unread.append(f"{', '.join(repr(k) for k in misplaced)} inside a person is not read: camera fields and "
                      "'source' go at the file's top level, beside the people")
    unread += unread_field_notes(meta)
    notes += unread
    image_size, focal, pp, source, dist, model = _camera_meta(meta, p)
    focal, assumed = _written_assumed(focal, meta, image_size)
    return KeypointFile(keypoints=arrays[0], format=fmt, image_size=image_size, focal=focal, principal_point=pp,
                        warnings=tuple(notes), source=source, distortion=dist, distortion_model=model,
                        people=tuple(arrays),
                        people_index=tuple(k for k, _ in identity), people_ids=tuple(i for _, i in identity),
                        unread=tuple(unread), people_scores=people_scores, assumed_focal=assumed)


MAX_SEQUENCE_FRAMES: Final[int] = 1_000_000
"""Keypoint sequences with more frames are refused."""


def is_frame_rate(value: Any) -> bool:
    """Whether ``value`` is a usable frame rate: a number in (0, 1000] frames/s."""
    return _is_number(value) and math.isfinite(value) and 0 < value <= 1000


def check_frame_rate(value: Any, *, name: str) -> None:
    """:class:`PoseLifterError` naming ``name`` unless ``value`` is None or a frame rate (:func:`is_frame_rate`)."""
    if value is not None and not is_frame_rate(value):
        raise PoseLifterError(f"{name} must be the frame rate, a number in (0, 1000] frames/s, got {_short(value)}")


def own_fps_note(own: float, given: float) -> str:
    """The note when a file's own frame rate is used rather than the one given (``--fps``)."""
    return f"the file's own fps ({float(own):g}) is used, not --fps {float(given):g}"


ASSUMED_FPS: Final[float] = 30.0
"""The frame rate (frames/s) assumed, with a note, for a video whose container gives no usable one, and for a keypoint
sequence that gives none where the caller asks for it (``assumed_fps=`` of :func:`parse_keypoint_sequence`: the app,
which has no ``--fps``)."""


@dataclass(frozen=True)
class KeypointSequence:
    """A parsed keypoint sequence: per frame a list of people ``(J, 2)`` px (largest first) in ``format``,
    the frame rate ``fps`` and the camera fields of the whole sequence."""

    frames: list[list[np.ndarray]]
    format: str
    fps: float
    image_size: tuple[int, int] | None = None
    focal: np.ndarray | None = None
    principal_point: np.ndarray | None = None
    warnings: tuple[str, ...] = ()
    source: str = "detected"
    distortion: np.ndarray | None = None
    """``(5,)``: the lens that saw the 2D (module docstring), or None (undistorted); OpenCV's ``(n,)`` with
    :attr:`distortion_model` ``"opencv"``."""
    distortion_model: DistortionModel = "h36m"
    """As :attr:`KeypointFile.distortion_model`."""
    people_ids: list[list[str | int | None]] | None = None
    """Per frame, for each of its people: their ``person_id`` (or ``id``, ``track_id``) field, None where they
    have none; None when no frame has one."""
    unread: tuple[str, ...] = ()
    """The notes (also in ``warnings``) on fields that were not read (:attr:`KeypointFile.unread`)."""
    assumed_focal: str | None = None
    """As :attr:`KeypointFile.assumed_focal`."""
    people_scores: list[list[np.ndarray | None]] | None = None
    """Per frame, for each of its people: their ``(J,)`` confidences as :attr:`KeypointFile.people_scores` reads them,
    None where they have none; None when no frame has any."""
    frame_indices: list[int] | None = None
    """Each frame's index in its video (:func:`frame_indices`: a frame's ``index``, as poselifter's own records
    write it, or MMPose's ``frame_id``, where frames were left out), or None: the frames are consecutive from 0."""


def frame_indices(frames: list[Any], where: Path, fps: float) -> tuple[list[int] | None, list[str]]:
    """The frames' own indices in their video, for poselifter's own records (every frame an object with a
    whole-number ``index`` and its ``time_s`` = index / ``fps``; a video's undecodable frames are left out of them),
    increasing; else from MMPose's ``frame_id`` (:func:`_frame_id_indices`); else None: the frames are consecutive
    from 0 (another tool's ``index`` may count from 1, or from
    where a clip was cut out of a longer video: a review's clip of frames 18000-18029 was lost so). A note when the
    frames look like a record's but their indices cannot be read so. A review saw a record's frames 5 and 6 read
    back as 3 and 4, their times 0.2 s early."""
    pairs = [(fr.get("index"), fr.get("time_s")) if isinstance(fr, dict) else (None, None) for fr in frames]
    if not all(i is not None and t is not None for i, t in pairs):
        return _frame_id_indices(frames, where)
    whole = [int(i) for i, _ in pairs if isinstance(i, int) and not isinstance(i, bool) and i >= 0]
    times = [float(t) for _, t in pairs if isinstance(t, (int, float)) and not isinstance(t, bool)]
    timed = len(whole) == len(times) == len(pairs) and all(
        abs(t - i / fps) <= 1e-3 + 1e-5 * i / fps for i, t in zip(whole, times))
    if timed and all(b > a for a, b in zip(whole, whole[1:])):
        return (None if whole == list(range(len(whole))) else whole), []
    return None, [f"{where}: the frames' 'index' and 'time_s' are not read as a poselifter record's (each frame's "
                  "index a whole number >= 0, increasing, its time_s index / fps): the frames are taken as consecutive "
                  "from 0"]


def _frame_id_indices(frames: list[Any], where: Path) -> tuple[list[int] | None, list[str]]:
    """The frames' indices from MMPose's ``frame_id`` (whole numbers, increasing; MMPose's demo counts from 1), the
    first frame given as frame 0: frames a tracker left out keep their place and time (a user trial's frame_id 20,
    after 10 missing, came out as frame 10 at 10 s of a 1-fps clip). None (consecutive from 0) where any frame
    has none, or they are consecutive; a note when the first is above 1 (an offset the output does not keep)."""
    got = [fr.get("frame_id") if isinstance(fr, dict) else None for fr in frames]
    ids = [i for i in got if isinstance(i, int) and not isinstance(i, bool) and i >= 0]
    if not ids or len(ids) != len(got):
        return None, []
    back = next((k for k in range(1, len(ids)) if ids[k] <= ids[k - 1]), None)
    if back is not None:
        return None, [f"{where}: the frames' 'frame_id' do not increase (frame {back} of the file has {ids[back]} "
                      f"after {ids[back - 1]}): the frames are taken as consecutive from 0"]
    notes = [] if ids[0] <= 1 else [f"{where}: the first frame's 'frame_id' is {ids[0]}: it is the output's frame 0 "
                                    f"(each frame's index is its frame_id - {ids[0]}, its time_s index / fps), so the "
                                    "output runs that many frames ahead of the video if frames before it were left "
                                    "out: give those frames too, with no instances"]
    indices = [i - ids[0] for i in ids]
    return (None if indices == list(range(len(ids))) else indices), notes


OPENPOSE_FRAME_FILE: Final = re.compile(r"(?P<video>.+)_(?P<frame>\d{12})_keypoints\.json")
"""OpenPose's ``--write_json`` file of one frame of a video: ``<video>_<12-digit frame>_keypoints.json``."""

FRAME_PATTERN: Final = re.compile(r"%0(?P<width>[1-9]\d?)d")
"""A printf-style frame number in a file name (``video_%012d_keypoints.json``), as OpenCV names image sequences."""


def frame_pattern_files(pattern: str | Path) -> list[tuple[int, Path]]:
    """The files that a frame pattern ``DIR/name_%0Nd_rest.json`` names (:data:`FRAME_PATTERN`: exactly N digits in
    its place), as ``(frame number, path)`` by frame number; empty when the name has no pattern or nothing matches."""
    p = Path(pattern)
    m = FRAME_PATTERN.search(p.name)
    if m is None or not p.parent.is_dir():
        return []
    rx = re.compile(re.escape(p.name[:m.start()]) + rf"(\d{{{m.group('width')}}})" + re.escape(p.name[m.end():]))
    found = [(int(mm.group(1)), q) for q in p.parent.iterdir() if (mm := rx.fullmatch(q.name)) and q.is_file()]
    return sorted(found)


def is_frame_pattern(path: str | Path) -> bool:
    """Whether ``path`` names keypoint files by a frame pattern (:data:`FRAME_PATTERN`; a ``.json`` name) rather than
    being a file of that name. (Images named so are not read as a video: lift the folder, or make a video.)"""
    p = Path(path)
    return p.suffix.lower() == ".json" and FRAME_PATTERN.search(p.name) is not None and not p.exists()


def openpose_frame_pattern(files: Sequence[Path]) -> list[tuple[Path, list[Path]]]:
    """OpenPose's per-frame files of a video among ``files`` (:data:`OPENPOSE_FRAME_FILE`): ``(pattern, its files)``
    per video, the pattern ``DIR/<video>_%012d_keypoints.json``, where ``files`` hold at least two of its frames, all
    the files the pattern names (:func:`frame_pattern_files`: so the pattern reads these and no others), and their
    numbers are dense (their span at most twice their count: OpenPose run on a folder of COCO images writes
    ``COCO_val2014_000000000139_keypoints.json``, stills whose numbers are image ids)."""
    out = []
    for pattern, members in _openpose_videos(files).items():
        named = frame_pattern_files(pattern)
        numbers = [n for n, _ in named]
        if (len(members) >= 2 and {q.resolve() for q in members} == {q.resolve() for _, q in named}
                and _dense(numbers)):
            out.append((pattern, [q for _, q in named]))
    return out


def _openpose_videos(files: Sequence[Path]) -> dict[Path, list[Path]]:
    """OpenPose's per-frame files among ``files`` (:data:`OPENPOSE_FRAME_FILE`) by their video's frame pattern."""
    by_video: dict[Path, list[Path]] = {}
    for f in files:
        m = OPENPOSE_FRAME_FILE.fullmatch(f.name)
        if m is not None:
            by_video.setdefault(f.parent / f"{m.group('video')}_%012d_keypoints.json", []).append(f)
    return by_video


def _dense(numbers: Sequence[int]) -> bool:
    """Frame numbers (sorted) of a video's frames, not of stills: their span at most twice their count."""
    return bool(numbers) and numbers[-1] - numbers[0] + 1 <= 2 * len(numbers)


def openpose_partial_videos(files: Sequence[Path]) -> list[tuple[Path, int, int, bool]]:
    """OpenPose's per-frame files of a video of which ``files`` hold at least two but not all (the frames of a clip
    picked out: :func:`openpose_frame_pattern` does not make them a sequence, which reads all the pattern names):
    ``(pattern, how many are given, how many the pattern names, whether the numbers given are dense themselves,
    so that in a folder of their own they would be a sequence)`` per such video (dense numbers, as a video's)."""
    out = []
    for pattern, members in _openpose_videos(files).items():
        named = frame_pattern_files(pattern)
        number = {q.resolve(): n for n, q in named}
        given = {q.resolve() for q in members}
        if 2 <= len(given) < len(named) and given <= set(number) and _dense([n for n, _ in named]):
            out.append((pattern, len(given), len(named), _dense(sorted(number[q] for q in given))))
    return out


def _mmpose_sequence(d: Any) -> tuple[dict[str, Any], str | None] | None:
    """MMPose's predictions of several frames (the demo's ``{"meta_info", "instance_info": [{"frame_id",
    "instances"}, ...]}``, MMPoseInferencer's ``[{"frame_id", "instances"}, ...]``) as a sequence document
    ``{"frames": [...], ...the file's other fields}`` (its top-level ``fps`` too), with the joints its ``meta_info``
    names (:func:`_mmpose_meta_format`, or None); else None. Its frames are read as the file's ``format``, else the
    caller's (``--format``), else that metadata's, else COCO-17, as :func:`_mmpose_frame` reads one frame."""
    d = _inferencer_results(d)
    if isinstance(d, dict) and isinstance(d.get("instance_info"), list) and "frames" not in d:
        info, rest = d["instance_info"], {k: v for k, v in d.items() if k not in ("instance_info", "meta_info")}
    elif isinstance(d, list):
        info, rest = d, {}
    else:
        return None
    if len(info) < 2 or not all(isinstance(q, dict) and "instances" in q for q in info):
        return None
    meta_fmt = _mmpose_meta_format(d.get("meta_info")) if isinstance(d, dict) else None
    return {**rest, "frames": info}, meta_fmt  # (each frame: _mmpose_frame, COCO-17 unless the file or caller says)


def _sequence_doc(p: Path, fps: float | None) -> tuple[Any, str | None]:
    """The decoded sequence document of ``p``: its JSON (MMPose's predictions of several frames in the sequence
    layout: :func:`_mmpose_sequence`), or for a frame pattern (:func:`frame_pattern_files`: OpenPose's per-frame files)
    ``{"frames": [each file's JSON], "fps": fps}``, the frames' numbers kept where they are not 0, 1, 2, ....; with
    the format an MMPose file's metadata names (None for any other)."""
    if not is_frame_pattern(p):
        d = _load_json(p)
        return _mmpose_sequence(d) or (d, None)
    found = frame_pattern_files(p)
    if not found:
        raise PoseLifterError(f"{p}: no files match this frame pattern (%0Nd: a frame number of N digits)")
    if len(found) > MAX_SEQUENCE_FRAMES:
        raise PoseLifterError(f"{p}: {len(found)} frames is more than the {MAX_SEQUENCE_FRAMES} a sequence may have")
    frames = [_load_json(f) for _, f in found]
    numbers = [n for n, _ in found]
    if numbers != list(range(len(numbers))) and fps is not None:  # (a frame's index and time, as a record's)
        frames = [{**fr, "index": n, "time_s": n / fps} if isinstance(fr, dict) else fr
                  for fr, n in zip(frames, numbers)]
    return {"frames": frames, **({} if fps is None else {"fps": fps})}, None


def is_sequence_doc(d: Any) -> bool:
    """Whether decoded JSON is a keypoint sequence: an object with ``frames``, or MMPose's predictions of several
    frames (:func:`_mmpose_sequence`)."""
    return (isinstance(d, dict) and "frames" in d) or _mmpose_sequence(d) is not None


def is_keypoint_sequence(path: str | Path) -> bool:
    """Whether a JSON file holds a keypoint sequence (:func:`is_sequence_doc`), or ``path`` is a frame pattern naming
    per-frame files (:func:`frame_pattern_files`); False when unreadable."""
    if is_frame_pattern(path):
        return bool(frame_pattern_files(path))
    try:
        d = _load_json(Path(path))
    except PoseLifterError:
        return False
    return is_sequence_doc(d)


def _own_sequence(frames: list[Any]) -> bool:
    """Whether a sequence's frames are poselifter's own output (people with ``keypoints_2d``, H36M's 17 joints, and
    no ``keypoints``): their format is H36M's whatever ``default_format`` the other files are read with."""
    return any(isinstance(fr, dict) and isinstance(fr.get("people"), list) and any(
        _is_own_person(q) for q in fr["people"]) for fr in frames)


def parse_keypoint_sequence(path: str | Path, *, default_format: str | None = None,
                            fps: float | None = None, cli_options: bool = True,
                            assumed_fps: float | None = None) -> KeypointSequence:
    """Read a keypoint sequence: ``{"frames": [FRAME, ...], "fps": 50, "format": ..., "image_size": ...,
    "focal": ..., "principal_point": ..., "distortion": ..., "source": ...}`` where each FRAME is any single-frame
    layout of the module docstring (``{"people": [...]}``, ``{"keypoints": [...]}``, a list of rows, a list of people)
    or an empty list / ``{"people": []}`` for a frame with nobody; MMPose's predictions of several frames; or a frame
    pattern naming one file per frame (``DIR/video_%012d_keypoints.json``, OpenPose's ``--write_json`` output of a
    video: :func:`frame_pattern_files`). The frame rate is required (frames/s, in (0, 1000]): the file's ``fps``,
    else ``fps`` (``poselifter lift --fps``); where both are given and differ the file's is used, with a note.
    ``assumed_fps``: the rate used, with a note, where neither gives one (e.g. :data:`ASSUMED_FPS`; None: refused).
    ``cli_options``: a message may name ``poselifter lift``'s options (False: the app, which has none)."""
    p = Path(path)
    check_frame_rate(fps, name="fps (--fps)")
    check_frame_rate(assumed_fps, name="assumed_fps")
    pattern = is_frame_pattern(p)
    d, meta_format = _sequence_doc(p, fps if fps is not None or not pattern else assumed_fps)
    if not (isinstance(d, dict) and "frames" in d):
        raise PoseLifterError(f"{p}: a keypoint sequence is an object with 'frames' (a list of frames)")
    raw = d["frames"]
    if not isinstance(raw, list):
        raise PoseLifterError(f"{p}: 'frames' must be a list of frames, got {_short(raw)}")
    if not raw:
        raise PoseLifterError(f"{p}: 'frames' is empty (a zero-length sequence)")
    if len(raw) > MAX_SEQUENCE_FRAMES:
        raise PoseLifterError(f"{p}: {len(raw)} frames is more than the {MAX_SEQUENCE_FRAMES} a sequence may have")
    given_fps = fps
    assumed_note = None
    if "fps" in d and not (pattern and fps is None):
        rate: Any = d["fps"]  # (a file's "fps": null is refused below, not filled in)
    elif given_fps is not None:
        rate = given_fps
    elif assumed_fps is not None:
        rate = assumed_fps
        assumed_note = (f"{'files of one frame each give' if pattern else 'the file gives'} no frame rate: assumed "
                        f"{float(assumed_fps):g} frames/s for playback and smoothing (give "
                        + ("fps=" if pattern else "\"fps\" at the file's top level")
                        + (", or --fps" if cli_options else "") + ")")
    elif pattern:
        raise PoseLifterError(f"{p}: one file per frame carries no frame rate: give it, e.g. --fps 30 on the command "
                              "line (fps= in lifter.video.lift_keypoint_sequence; frames/s, in (0, 1000])")
    else:
        other = [k for k in d if isinstance(k, str) and k != "fps" and ("rate" in k.lower() or "fps" in k.lower())]
        named = (f" (the file's {', '.join(repr(k) for k in other[:3])} {'is' if len(other) == 1 else 'are'} not "
                 "read: poselifter reads 'fps')") if other else ""
        raise PoseLifterError(f"{p}: 'fps' is missing{named}: a keypoint sequence needs its frame rate in frames/s, in "
                              "(0, 1000]: \"fps\": 30 at the file's top level (a list of frames becomes "
                              "{\"frames\": [...], \"fps\": 30})" + (", or --fps 30 on the command line" if cli_options
                                                                        else ""))
    if not is_frame_rate(rate):
        raise PoseLifterError(f"{p}: 'fps' must be the frame rate, a number in (0, 1000] frames/s, got {_short(rate)}")
    fmt = d.get("format") or (H36M17 if _own_sequence(raw) else default_format) or meta_format
    if fmt is not None and not isinstance(fmt, str):
        raise PoseLifterError(f"{p}: 'format' must be a string (one of {list(keypoint_formats())}), got {_short(fmt)}")
    indices, notes = frame_indices(raw, p, float(rate))
    if assumed_note is not None:
        notes.insert(0, assumed_note)
    if given_fps is not None and "fps" in d and not pattern and float(d["fps"]) != float(given_fps):
        notes.append(own_fps_note(d["fps"], given_fps))
    frames: list[list[np.ndarray]] = []
    with_people = 0  # (frames so far with people kept: for the messages)
    ids: list[list[str | int | None]] = []
    scores: list[list[np.ndarray | None]] = []
    dropped: list[tuple[int, tuple[str, list[str]]]] = []  # (frame, (who, joints))
    stood_in: dict[str, list[int]] = {}  # "r_ear from l_ear" -> frames
    misplaced: dict[str, int] = {}  # camera field -> first frame that has it inside a frame or person
    for i, fr in enumerate(raw):
        for k in _misplaced_camera_fields(fr, frame_level=True):
            misplaced.setdefault(k, i)
        where = Path(f"{p} frame {i}")
        if fr == [] or fr is None or (isinstance(fr, dict) and fr.get("people") == []):
            frames.append([])
            ids.append([])
            scores.append([])
            continue
        people, f_fmt, _, layout_format = _people_of(fr, where, fmt)
        # (the format's note from the first frame with people, which settles it; the scores' note over every frame:
        # a review saw both lost after a leading empty frame, or for scores above 2 past the first frame)
        found = _people_arrays(people, where, f_fmt, notes if fmt is None else [], layout_format=layout_format,
                               frame=i, score_note=False, frames_before=with_people)
        arrays, f_fmt, identity, gone = found.arrays, found.format, found.identity, found.dropped
        for _, said in found.stood_in:
            for phrase in said:
                at = stood_in.setdefault(phrase, [])
                if not at or at[-1] != i:  # (frames, not people: two people of one frame count once)
                    at.append(i)
        if fmt is None:
            fmt = f_fmt
        elif f_fmt != fmt:
            raise PoseLifterError(f"{where}: format {f_fmt!r} differs from the sequence's {fmt!r}")
        frames.append(arrays)
        with_people += bool(arrays)
        ids.append([pid for _, pid in identity])
        scores.append(list(found.scores))
        dropped += [(i, g) for g in gone]
    fmt = fmt or H36M17
    if fmt == "coco17" and any(frames):
        notes += _h36m_as_coco_notes(np.stack([a for fr in frames for a in fr]))
    top = max((float(np.max(c[np.isfinite(c)])) for fr in scores for c in fr
               if c is not None and np.isfinite(c).any()), default=0.0)
    if top > SCORE_NOTE_ABOVE:
        notes.append(_score_note(top))
    if _visibility_flags([c for fr in scores for c in fr]):
        notes.append(FLAGS_NOTE)
        scores = [[None for _ in fr] for fr in scores]
    if stood_in:
        notes.append(STAND_IN_NOTE.format(what="; ".join(
            f"{phrase} in {len(at)} frame(s) (first at frame {at[0]})" for phrase, at in stood_in.items())))
    if dropped:
        at = sorted({i for i, _ in dropped})
        joints = sorted({j for _, (_, bad) in dropped for j in bad})
        first_who = dropped[0][1][0]
        msg = (f"{len(dropped)} person(s) left out of {len(at)} frame(s) ({', '.join(map(str, at[:10]))}"
               f"{', ...' if len(at) > 10 else ''}) for missing joints {joints} (confidence 0 or below or null, or "
               f"null / NaN coordinates; first {first_who}); {_needs(fmt)}")
        if not any(frames):
            raise PoseLifterError(f"{p}: {msg}; nobody is left to lift. Give those joints (e.g. interpolated from "
                                  "neighbouring frames)")
        notes.append(msg)
    unread: list[str] = []
    if misplaced:
        unread.append(f"{', '.join(f'{k!r} (first in frame {i})' for k, i in sorted(misplaced.items()))} inside a "
                      "frame is not read: " + (
                          "files of one frame each have no top level for the sequence's camera: give it on the command "
                          "line (--image-size, --focal, --principal-point)" if is_frame_pattern(p) else
                          "a sequence's camera fields and 'source' go at its top level, beside 'frames'"))
    unread += unread_field_notes(d)
    notes += unread
    image_size, focal, pp, source, dist, model = _camera_meta(d, p)
    focal, assumed = _written_assumed(focal, d, image_size)
    return KeypointSequence(frames=frames, format=fmt, fps=float(rate), image_size=image_size, focal=focal,
                            principal_point=pp, warnings=tuple(notes), source=source, distortion=dist,
                            distortion_model=model,
                            people_ids=ids if any(i is not None for fr in ids for i in fr) else None,
                            unread=tuple(unread), assumed_focal=assumed,
                            people_scores=scores if any(c is not None for fr in scores for c in fr) else None,
                            frame_indices=indices)


def _read_umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_UMASK: Final[int] = _read_umask()


def _fsync_folder(folder: Path) -> None:
    """``fsync`` a folder, so that a rename in it is on disk (POSIX; where a folder cannot be opened so, as on Windows,
    nothing)."""
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_atomic(path: str | Path, data: bytes | memoryview | str) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, ``fsync``, then a rename (and an
    ``fsync`` of the folder, so that the rename itself survives a power loss): a full disk or a crash never leaves a
    partial or empty file behind (the temporary file is removed on failure). A file replaced keeps its permission
    bits (a review's 0600 file came back 0644, readable by all); a new one follows the umask. Refuses to write
    through a symbolic link, so an existing link cannot redirect the write out of its folder."""
    path = Path(path)
    if path.is_symlink():
        raise PoseLifterError(f"{path}: exists as a symbolic link; refusing to write through it (remove it, or "
                              "choose another output folder)")
    raw = data.encode("utf-8") if isinstance(data, str) else data
    try:
        mode = stat.S_IMODE(path.stat().st_mode) & 0o777  # (not setuid, setgid or sticky bits)
    except OSError:  # (no such file, or not one we may look at: a new file's mode)
        mode = 0o666 & ~_UMASK
    try:
        # (the name cut to 64 characters: a 250-character output name that fits was refused as too long once
        # mkstemp's own characters were added; a security trial)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name[:64]}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        hint = " (the folder does not exist: create it first)" if not path.parent.is_dir() else ""
        raise PoseLifterError(f"{path}: could not write ({exc.strerror or exc}){hint}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(raw)
            f.flush()
            os.fchmod(f.fileno(), mode)  # (mkstemp makes 0600)
            os.fsync(f.fileno())
        os.replace(tmp, path)
        _fsync_folder(path.parent)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise PoseLifterError(f"{path}: could not write ({exc.strerror or exc})") from None
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def check_writable(path: str | Path, *, option: str) -> None:
    """Raise a :class:`PoseLifterError` naming ``option`` (e.g. ``"--out"``) when a file could not be written at
    ``path`` (nor files beside it): a folder there, a parent that is a file, a folder that cannot be created or
    written, a symbolic link. Creates the missing parent folders. For commands that work for minutes first."""
    path = Path(path)
    if path.is_symlink():
        raise PoseLifterError(f"{option} {path} is a symbolic link; give a plain file path")
    if path.is_dir():
        raise PoseLifterError(f"{option} {path} is a folder; give a file path in it")
    blocker = next((p for p in path.parents if p.exists() and not p.is_dir()), None)
    if blocker is not None:
        raise PoseLifterError(f"{option} {path}: {blocker} is a file, not a folder; choose another path")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path.parent):
            pass
    except OSError as exc:
        raise PoseLifterError(f"{option} {path}: cannot write to {path.parent} ({exc.strerror or exc}); choose "
                              "another path") from None


def write_json_atomic(path: str | Path, data: Any) -> Path:
    """``data`` as indented JSON through :func:`write_atomic`."""
    return write_atomic(path, json.dumps(data, indent=1))
