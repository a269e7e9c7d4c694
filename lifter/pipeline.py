"""The cascade of the paper, image -> 2D estimator -> lifter, for one input: a photo (:func:`lift_image`) or a
keypoint JSON file (:func:`lift_keypoint_file`), and the camera each is lifted with (:func:`resolve_camera`).
Everyone found is lifted, in one batch, into the same camera space (largest first); videos and keypoint
sequences are in :mod:`lifter.video`.

Camera, in this order: a focal length / principal point the caller gives; a keypoint file's own; for photos the
EXIF focal length (:func:`lifter.detect.focal_from_exif`); else the default diagonal field of view of the image
(:data:`lifter.camera.DEFAULT_DIAGONAL_FOV_DEG`). The principal point defaults to the image centre.
Units: px and mm; camera frame OpenCV.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ._checks import (
    PoseLifterError,
    as_pair,
    body_lean_deg,
    input_warnings,
    lean_notes,
    lean_text,
    leaning_people,
    outside_image_notes,
    principal_point_notes,
    sideways_notes,
    sideways_people,
    upside_down_notes,
    upside_down_people,
    view_angle_notes,
)
from ._text import largest_lifted, sentence
from .camera import (
    DEFAULT_DIAGONAL_FOV_DEG,
    MIN_FOCAL_PX,
    DistortionModel,
    check_distortion_model,
    check_lens,
    image_centre,
    lens_notes,
)
from .detect import (
    DEFAULT_MAX_SIDE_PX,
    DOUBTFUL_SCORE,
    MIN_PERSON_SCORE,
    LoadedImage,
    PoseEstimator2D,
    check_min_score,
    detect_people,
    guess_focal,
    h36m_joint_scores,
    left_out_text,
    load_image,
    mean_person_scores,
    people_scores,
)
from .io import (
    REASSUMED_NOTE,
    LiftRecord,
    PersonResult,
    _image_size_field,
    distortion_tuple,
    model_info,
    parse_keypoint_json,
)
from .keypoints import H36M17, convert, placeholder_notes


def _px(v: Any) -> str:
    return " x ".join(f"{float(x):g}" for x in np.ravel(v)) + " px"


def _point(v: Any) -> str:
    """A point in the image, ``(x, y) px`` (a developer trial read "(0 x 0 px)" as a size)."""
    x, y = np.broadcast_to(np.asarray(v, np.float64).ravel(), (2,))
    return f"({x:g}, {y:g}) px"


def resolve_camera(*, user_focal: np.ndarray | None, user_pp: np.ndarray | None, file_focal: np.ndarray | None,
            file_pp: np.ndarray | None, image_size: tuple[int, int] | None, exif: Any, sensor_width_mm: float | None,
            fov_deg: float, where: str, file_distortion: np.ndarray | None = None, unread: Sequence[str] = (),
            assumed_focal: str | None = None, cli_options: bool = True
            ) -> tuple[np.ndarray, str, np.ndarray, list[str]]:
    """The focal length, its source, the principal point and notes for one input, from what the user gave, the
    file's camera fields and the image size. A missing field raises a :class:`PoseLifterError` naming the ways
    to give it, followed by ``unread`` (a keypoint file's notes on fields it has but that are not read, e.g. a
    ``"focal_length"``: :attr:`lifter.io.KeypointFile.unread`), which likely explain it. ``assumed_focal``: the
    focal a result file says was assumed when it was written (:attr:`lifter.io.KeypointFile.assumed_focal`, not
    passed as ``file_focal``); without a focal from the user, the first note says it is assumed again.
    ``cli_options``: the messages name the ways to give what is missing as the Python arguments with
    ``poselifter lift``'s options (``focal= (--focal)``, ``fov_deg= (--fov)``); False (the app, which has neither at
    upload): they name the file's fields only."""
    try:
        f, src, pp, notes = _resolve_camera(
            user_focal=user_focal, user_pp=user_pp, file_focal=file_focal, file_pp=file_pp, image_size=image_size,
            exif=exif, sensor_width_mm=sensor_width_mm, fov_deg=fov_deg, where=where, file_distortion=file_distortion,
            cli_options=cli_options)
    except PoseLifterError as exc:
        if not unread:
            raise
        raise PoseLifterError(f"{exc}. Also in the file: " + " ".join(sentence(n) for n in unread)) from None
    if assumed_focal is not None and user_focal is None:
        notes.insert(0, REASSUMED_NOTE.format(focal=assumed_focal)
                     + (" (give focal= (--focal) if you know it)" if cli_options else " (set it if you know it)"))
    return f, src, pp, notes


def _resolve_camera(*, user_focal: np.ndarray | None, user_pp: np.ndarray | None, file_focal: np.ndarray | None,
                    file_pp: np.ndarray | None, image_size: tuple[int, int] | None, exif: Any,
                    sensor_width_mm: float | None, fov_deg: float, where: str, file_distortion: np.ndarray | None,
                    cli_options: bool) -> tuple[np.ndarray, str, np.ndarray, list[str]]:
    notes: list[str] = []
    or_pass = ", pass focal= (--focal)," if cli_options else ""
    if image_size is None:  # everything missing in one message, not one run per missing field
        have = {"focal": user_focal is not None or file_focal is not None,
                "principal_point": user_pp is not None or file_pp is not None}
        need = [(opt, f) for opt, f in (("focal= (--focal)", "focal"),
                                        ("principal_point= (--principal-point)", "principal_point")) if not have[f]]
        if need:
            what = " and no ".join("focal length" if f == "focal" else "principal point" for _, f in need)
            put = f"put 'image_size' (or {' and '.join(repr(f) for _, f in need)}) in the file"
            raise PoseLifterError(f"{where}: no {what} and no image size: " + (
                f"pass {' and '.join(o for o, _ in need)}, or the image's size, image_size= (--image-size W H), "
                f"or {put}" if cli_options else put))
    if user_focal is not None:
        focal, src = user_focal, "user"
        if file_focal is not None and not np.allclose(np.broadcast_to(file_focal, (2,)), user_focal):
            notes.append(f"the focal length given ({_px(user_focal)}) replaces the file's own ({_px(file_focal)})"
                         + ("; the file's 'distortion' is applied with it (lens coefficients act on (x - c) / f, so "
                            "at another focal they bend the 2D differently: leave focal= (--focal) out if the lens was "
                            "calibrated with the file's focal)" if file_distortion is not None else ""))
    elif file_focal is not None:
        focal, src = file_focal, "keypoint-file"
        if float(np.min(file_focal)) < MIN_FOCAL_PX:  # (else the lifter's message would name focal=, not the file)
            raise PoseLifterError(
                f"{where}: the file's 'focal' {_px(file_focal)} is below {MIN_FOCAL_PX:g} px: it must be in pixels, "
                f"not mm (f_px = f_mm * image width px / sensor width mm); correct it{or_pass or ','} or remove it to "
                "assume a field of view from 'image_size'")
    else:
        assert image_size is not None  # (checked above, with every missing field named)
        if file_distortion is not None:  # (lens coefficients act on px / focal: an assumed focal makes them wrong)
            raise PoseLifterError(f"{where}: 'distortion' needs the camera's own focal length: put 'focal' (px) in "
                                  f"the file{' or pass focal= (--focal)' if cli_options else ''}, or leave "
                                  "'distortion' out")
        g = guess_focal(image_size, exif=exif, sensor_width_mm=sensor_width_mm, fov_deg=fov_deg)
        focal, src = np.array([g.focal, g.focal]), g.source
        if g.focal < MIN_FOCAL_PX:  # (else the lifter's message would blame a focal length the user never gave)
            raise PoseLifterError(
                f"{where}: the focal length assumed for this {image_size[0]} x {image_size[1]} px image ({g.detail}) "
                f"is {g.focal:.3g} px, below {MIN_FOCAL_PX:g} px: give the focal length "
                + ("with focal= (--focal)" + (", or a narrower field of view with fov_deg= (--fov)"
                                           if g.source == "default-fov" else "")
                   if cli_options else "('focal', px, in the file)"))
        notes.append(g.detail)
    if user_pp is not None:
        pp = user_pp
        if file_pp is not None and not np.allclose(np.broadcast_to(file_pp, (2,)), user_pp):
            notes.append(f"the principal point given, {_point(user_pp)}, replaces the file's own, {_point(file_pp)}")
    elif file_pp is not None:
        pp = file_pp
    else:
        assert image_size is not None  # (checked above)
        pp = image_centre(image_size)
    notes += principal_point_notes(pp, image_size)
    if src in FOCAL_GIVEN_SOURCES or src.startswith("exif"):  # (not the field of view assumed)
        notes += view_angle_notes(focal, image_size, from_exif=src.startswith("exif"))
    return np.asarray(focal, np.float64), src, np.asarray(pp, np.float64), notes


FOCAL_GIVEN_SOURCES: tuple[str, ...] = ("user", "keypoint-file")
"""The ``focal_source`` values of a focal length that was given (the others are assumed: EXIF, field of view)."""


def plausibility_notes(kp17: np.ndarray, focal: np.ndarray, image_size: tuple[int, int] | None, *,
                       focal_source: str = "user", detected: bool = False, source_format: str = H36M17) -> list[str]:
    """Notes on 2D that the lifter takes but that look wrong, for the records (files, photos, videos): poses
    ``(n, 17, 2)`` px spanning more than :data:`lifter.camera.MAX_PLAUSIBLE_VIEW_DEG` at ``focal`` ``(2,)`` px or
    with a joint at (0, 0) (:func:`lifter._checks.input_warnings`, what :meth:`lifter.Lifter.lift` warns of),
    upright but upside down (keypoints only: :func:`upside_down_notes`), or lying mostly outside the ``image_size``
    (None: not checked). detected: the 2D is this package's detector's
    (photos, videos), not the user's keypoints, which changes the advice. source_format: the format the keypoints
    came in; another than h36m17 has its (0, 0) joints said by :func:`lifter.keypoints.placeholder_notes` (once,
    not again here: a user trial read two notes for one joint)."""
    notes: list[str] = []
    k = np.asarray(kp17, np.float64).reshape(-1, kp17.shape[-2], 2)
    if not len(k):
        return notes
    notes += input_warnings(k, focal, focal_given=focal_source in FOCAL_GIVEN_SOURCES,
                            placeholders=source_format == H36M17, focal_from_exif=focal_source.startswith("exif"))
    if not detected:  # (the package's own detector gives upright image coordinates, in (x, y) order)
        notes += upside_down_notes(k)
        notes += sideways_notes(k)
        notes += lean_notes(k)
    notes += outside_image_notes(k, image_size, detected=detected)
    return notes


def detected_upside_down_notes(kp17: np.ndarray) -> list[str]:
    """A note naming each detected person (``(n, 17, 2)`` px, the output's order) who is upside down in the image
    (:func:`upside_down_people`): the detector's false people on walls and in clutter often are (a user trial: a
    two-person photo gave a third, upside-down 'person' on the wall beside one of them, scored 0.86)."""
    down = np.flatnonzero(upside_down_people(kp17))
    if not len(down):
        return []
    n = len(np.asarray(kp17).reshape(-1, 17, 2))
    who = ("the person found is" if n == 1 else
           f"{_people_list([int(i) + 1 for i in down])} of the output's people {'is' if len(down) == 1 else 'are'}")
    return [f"{who} upside down in the image (the head below both ankles): the detector finds such 'people' on walls "
            "and in clutter; unless someone in the photo is upside down (a handstand), it is a false detection "
            "(the others' lifts do not depend on it)"]


def detected_sideways_notes(kp17: np.ndarray, *, video: bool = False) -> list[str]:
    """A note naming each detected person (``(n, 17, 2)`` px, the output's order) who lies sideways in the image
    (:func:`lifter._checks.sideways_people`; ``video``: one note when most of a video's poses do): a photo turned a
    quarter without its EXIF orientation (a developer trial: such a photo was lifted 1.6 m off without a word, where
    the same 2D given as keypoints got a note), a phone video whose rotation was not applied, a person lying down, or
    a false detection along furniture."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    side = sideways_people(k)
    if not ((len(k) > 0 and side.mean() > 0.5) if video else side.any()):
        return []
    if video:
        who = f"most detected poses lie sideways in the frames ({int(side.sum())} of {len(k)})"
    else:
        idx = [int(i) + 1 for i in np.flatnonzero(side)]
        who = ("the person found lies" if len(k) == 1 else
               f"{_people_list(idx)} of the output's people {'lies' if len(idx) == 1 else 'lie'}") + " sideways"
    medium = "video is turned a quarter (its rotation not applied)" if video else \
        "photo is turned a quarter (its EXIF orientation lost)"
    return [f"{who} (head and ankles apart along the image's x): if the {medium}, turn it upright first; a person "
            "lying down is lifted as given, a pose rare in the training data (the detector also finds such 'people' "
            "along furniture)"]


def detected_lean_notes(kp17: np.ndarray) -> list[str]:
    """A note naming each detected person (``(n, 17, 2)`` px, the output's order) who leans as a rolled camera leans
    people (:func:`lifter._checks.leaning_people`): a developer trial's photo turned 35 deg was lifted 0.9 m too near
    without a word."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    lean = leaning_people(k)
    if not lean.any():
        return []
    deg = body_lean_deg(k)
    idx = np.flatnonzero(lean)
    if len(k) == 1:
        who = f"the person found leans {deg[0]:+.0f} deg"
    else:
        people = ", ".join(f"person {int(i) + 1} ({deg[i]:+.0f} deg)" for i in idx)
        who = f"{people} of the output's people {'leans' if len(idx) == 1 else 'lean'}"
    return [f"{who} from the image's vertical (legs and torso alike; + toward +x at the feet): {lean_text(deg[idx])}"]


def detected_edge_notes(kp17: np.ndarray, image_size: tuple[int, int]) -> list[str]:
    """A note naming each detected person (``(n, 17, 2)`` px, the output's order) with some joints outside the
    ``image_size`` ``(W, H)`` px image, but not most (those are :func:`lifter._checks.outside_image_notes`'): a person
    cut off by the photo's edge, whose hidden joints the detector guesses (the video form is
    :func:`lifter.video.track_edge_notes`)."""
    from ._checks import CUT_OFF_TAIL, joints_outside, joints_outside_text

    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    out = joints_outside(k, image_size)  # (n, 17)
    cut = np.flatnonzero(out.any(-1) & (out.mean(-1) <= 0.5))
    if not len(cut):
        return []
    who = ("the person found is" if len(k) == 1 else
           f"{_people_list([int(i) + 1 for i in cut])} of the output's people {'is' if len(cut) == 1 else 'are'}")
    return [f"{who} cut off by the image's edge ({joints_outside_text(out[cut])}): {CUT_OFF_TAIL}"]


def _people_list(numbers: list[int]) -> str:
    """``person 3`` / ``people 2 and 3`` / ``people 1, 2 and 4``."""
    if len(numbers) == 1:
        return f"person {numbers[0]}"
    return f"people {', '.join(map(str, numbers[:-1]))} and {numbers[-1]}"


def unsure_people(mean_scores: Sequence[float]) -> list[int]:
    """The indices of the people (largest first) whose mean score over the 17 joints lifted is below
    :data:`lifter.detect.DOUBTFUL_SCORE` (NaN: no score, not unsure): those :func:`detector_doubt_notes` names, and
    the app flags at the start of an upload's message."""
    return [i for i, v in enumerate(mean_scores) if v < DOUBTFUL_SCORE]


def detector_doubt_notes(visibility: list[float]) -> list[str]:
    """A note naming each detected person (largest first) whose mean score over the 17 joints lifted (the
    detector's own confidence, 0-1, :attr:`lifter.detect.DetectedPose.scores`) is below
    :data:`lifter.detect.DOUBTFUL_SCORE`. BlazePose gives 0.84-1.00 to the people of the 84 Human3.6M demo photos;
    of the 31 "people" it invented in 240 crops of their empty walls, 12 score below 0.5 (quartiles 0.13 / 0.74 /
    0.84), the same 12 as on BlazePose's 33 landmarks, which this read before. A user trial's empty-wall photo got
    0.41 over the 17 joints and no note under that rule: BlazePose scores the face points higher
    (``python scripts/empty_crops.py``, ``docs/results/empty_crops.txt``)."""
    low = [(i, visibility[i]) for i in unsure_people(visibility)]
    if not low:
        return []
    who = _by_person(low, len(visibility), "{:.2f}")
    return [f"the detector is unsure of {'the person found' if len(visibility) == 1 else 'some people'}: mean "
            f"joint score {who} over the 17 joints lifted, below {DOUBTFUL_SCORE:g} (BlazePose gives 0.84-1 to the "
            "people of real photos): the 2D, and so the 3D, may be wrong, or there may be no person at all; is the "
            "person large and sharp enough in the image?"]


def _by_person(found: list[tuple[int, float]], n: int, fmt: str) -> str:
    """``(person index, value)`` pairs of an image with ``n`` people, the values formatted by ``fmt``:
    ``"0.41"`` for a single person, ``"person 1 (0.41), person 3 (0.38)"`` among several."""
    return ", ".join(f"person {i + 1} ({fmt.format(v)})" if n > 1 else fmt.format(v) for i, v in found)


def small_person_notes(heights_px: list[float], *, downscaled: bool = False) -> list[str]:
    """A note naming each detected person (largest first) whose size in the image the detector saw (px, the longer
    side of their 2D joints' box: a standing person's height, and a lying person's length) is below
    :data:`lifter.detect.SMALL_PERSON_PX`: the detector's 2D, and the lift with it, gets coarse there (a browser
    trial's 300-px photo lifted 73 mm off the same photo at 1000 px, without a word). ``downscaled``: the photo was
    downscaled for the detector (``--max-side``), which is then named."""
    from .detect import SMALL_PERSON_PX

    small = [(i, h) for i, h in enumerate(heights_px) if h < SMALL_PERSON_PX]
    if not small:
        return []
    who = _by_person(small, len(heights_px), "{:.0f} px")
    seen = "in the image as downscaled for the detector (--max-side)" if downscaled else "in the image"
    return [f"{'the person found is' if len(heights_px) == 1 else 'some people are'} small {seen}: {who} (the "
            f"longer side of the joints' box), below {SMALL_PERSON_PX:g} px, where the detector's 2D gets coarse and "
            "the 3D with it (the demo photos downscaled: MPJPE 64 mm with people 340 px tall, 70 at 102 px, 114 at 68 "
            "px); a larger photo of them helps"]


EDGE_NEAR: Final[float] = 0.15
"""An unsure joint within this share of the image's height (or width) of its bottom or top (left or right) edge is
named as near that edge (:func:`joint_doubt_notes`): a limb cut off by the edge is placed inside the image by the
detector, and scored low (a developer trial's photo cut at the waist: the ankles were put 31 and 58 px above the
bottom of a 480-px image, 6 and 12 % of its height, and the note said only "an occluded or blurred limb")."""


def joint_doubt_notes(scores: np.ndarray, keypoints: np.ndarray | None = None,
                      image_size: tuple[int, int] | None = None) -> list[str]:
    """A note naming, for each detected person (``scores`` ``(people, 17)``, largest first, H36M order), the joints
    whose score is below :data:`lifter.detect.UNSURE_JOINT_SCORE`: such joints are several times further off than
    the others on the demo photos (an occluded or blurred wrist, most often), and their 3D with them. Given the
    people's ``keypoints`` ``(people, 17, 2)`` px and the ``image_size`` ``(W, H)`` px, an unsure joint within
    :data:`EDGE_NEAR` of an edge is named as near it (a cut-off limb the detector placed inside the image?)."""
    from .detect import UNSURE_JOINT_SCORE
    from .skeleton import JOINT_NAMES

    s = np.asarray(scores, np.float64).reshape(-1, len(JOINT_NAMES))
    k = None if keypoints is None or image_size is None else np.asarray(keypoints, np.float64).reshape(-1, 17, 2)

    def edge(i: int, j: int) -> str:
        if k is None or image_size is None:
            return ""
        (x, y), (w, h) = k[i, j], image_size
        near = [name for name, d, side in (("bottom", h - y, h), ("top", y, h), ("left", x, w), ("right", w - x, w))
                if d <= EDGE_NEAR * side]
        return f", near the {near[0]} edge" if near else ""

    who, at_edge = [], False
    for i, row in enumerate(s):
        unsure = np.flatnonzero(row < UNSURE_JOINT_SCORE)
        edges = [edge(i, int(j)) for j in unsure]
        at_edge = at_edge or any(edges)
        low = [f"{JOINT_NAMES[j]} ({row[j]:.2f}{e})" for j, e in zip(unsure, edges)]
        if low:
            who.append((f"person {i + 1}: " if len(s) > 1 else "") + ", ".join(low))
    if not who:
        return []
    why = ("an occluded or blurred limb, or, near the edge, one outside the image that the detector placed inside it?"
           if at_edge else "an occluded or blurred limb?")
    return [f"the detector is unsure of some joints (score below {UNSURE_JOINT_SCORE:g}): {'; '.join(who)}: their 2D, "
            f"and so their 3D, may be off ({why})"]


def lift_people(lifter: Any, kp17: np.ndarray, f: np.ndarray, pp: np.ndarray, *, flip_test: bool | None, source: str,
                scores: np.ndarray | None = None, notes: list[str] | None = None,
                distortion: ArrayLike | None = None, distortion_model: DistortionModel = "h36m"
                ) -> tuple[PersonResult, ...]:
    """Lift ``(n, 17, 2)`` people (px) in one batch at focal ``f`` / principal point ``pp`` (px); one
    :class:`PersonResult` each (mm, camera frame), in the same order. No Python warnings: the records carry
    them as notes (:func:`plausibility_notes`; what looks wrong in the output, :attr:`LiftResult.warnings`, is
    appended to ``notes``). ``distortion``: the lens that saw the 2D (:meth:`lifter.Lifter.lift`), or None, in the
    form ``distortion_model``."""
    res = lifter.lift(kp17, focal=f, principal_point=pp, flip_test=flip_test, source=source, warn=False,
                      distortion=distortion, distortion_model=distortion_model, whose="the output's people")
    if notes is not None:
        notes.extend(getattr(res, "warnings", ()))
    cd = np.asarray(res.canonical_depth).reshape(-1)
    return tuple(PersonResult(keypoints_2d=kp17[i], absolute=np.asarray(res.absolute)[i],
                              relative=np.asarray(res.relative)[i], root=np.asarray(res.root)[i],
                              canonical_depth=float(cd[i]), scores=None if scores is None else scores[i])
                 for i in range(len(kp17)))


def keypoint_file_scores(kf: Any, count: int) -> tuple[np.ndarray | None, list[str]]:
    """The confidences of the first ``count`` people of a keypoint file (:class:`lifter.io.KeypointFile`, largest
    first) as the H36M joints' ``(count, 17)`` (each the lowest of the joints its rule reads; None unless every one
    of them has scores), and the note naming their unsure joints (:func:`joint_doubt_notes`) when the scores lie
    between 0 and 1 (scores above 1 are another scale, with no threshold to read them by)."""
    conf = people_scores(kf.people_scores[:count])
    if conf is None:
        return None, []
    scores = h36m_joint_scores(conf, kf.format)
    return scores, (joint_doubt_notes(scores) if float(np.nanmax(conf)) <= 1.0 else [])


def keep_scored_people(kf: Any, min_score: float, *, where: str) -> tuple[Any, list[str]]:
    """A keypoint file (:class:`lifter.io.KeypointFile`, largest first) without the people whose mean joint score
    (:func:`lifter.detect.mean_person_scores`: scores in 0-1 only) is below ``min_score``
    (:data:`lifter.detect.MIN_PERSON_SCORE`), and the note on them; the file as it is when nobody is. A
    :class:`PoseLifterError` naming the fix when nobody is left (a developer trial: a COCO results file's detections
    scored 0.04 were lifted as people, and ``--max-people 1`` kept one of them, the largest, over the real person).
    ``poselifter lift`` and the app's keypoint upload read a file so."""
    people = kf.people or (kf.keypoints,)
    mean = mean_person_scores(kf.people_scores, kf.format, len(people))
    low = mean < min_score  # (NaN: no scores to read, kept)
    if not low.any():
        return kf, []
    text = left_out_text(mean[low], min_score, what="person")
    keep = np.flatnonzero(~low)
    if not len(keep):
        raise PoseLifterError(f"{where}: nobody to lift: {text}")
    n = len(kf.people)
    each = f"{n} people in the file; each is lifted"  # (the reader's note, no longer true: said of those kept)
    notes = tuple(w.replace(each, f"{len(keep)} of the {n} people in the file are lifted", 1) for w in kf.warnings
                  if len(keep) > 1 or not w.startswith(each))
    kept = {k: tuple(getattr(kf, k)[i] for i in keep) for k in ("people", "people_index", "people_ids", "people_scores")
            if len(getattr(kf, k)) == n}
    return dataclasses.replace(kf, keypoints=kf.people[keep[0]], warnings=notes, **kept), [
        f"of the file's {n} people, {text}"]


def given_image_size(image_size: Any | None, file_size: tuple[int, int] | None, *,
                     where: str) -> tuple[tuple[int, int] | None, list[str]]:
    """The image size (px) a keypoint file is lifted with: ``image_size`` ``(W, H)`` given by the user
    (``--image-size``; checked as a file's ``image_size``), which replaces the file's own ``file_size`` with a note
    when they differ, else the file's (None: neither gave one)."""
    if image_size is None:
        return file_size, []
    raw = list(image_size) if isinstance(image_size, (list, tuple)) else np.asarray(image_size).reshape(-1).tolist()
    size = _image_size_field(raw, where=where)
    assert size is not None
    if file_size is not None and tuple(file_size) != size:
        return size, [f"the image size given ({size[0]} x {size[1]} px) replaces the file's own ({file_size[0]} x "
                      f"{file_size[1]} px)"]
    return size, []


class KeypointsImage(NamedTuple):
    """The image a keypoint file's (or sequence's) 2D is lifted in (:func:`keypoints_image`)."""

    size: tuple[int, int] | None
    """``(W, H)`` px lifted with (None: nobody gives one; the principal point must then be given)."""
    notes: list[str]
    """Where the size came from, when not from the file itself."""
    exif: Any
    """The fallback image's EXIF focal-length fields (:class:`lifter.detect.ExifCamera`) when the keypoints are in
    its pixels (``on_fallback``) and it has them, else None."""
    on_fallback: bool
    """The keypoints are in the fallback image's pixels: its size is the one lifted with (taken from it, or the
    same)."""


def _in_top_left_quarter(poses: np.ndarray, size: tuple[int, int]) -> bool:
    """Whether every joint given (finite) of ``poses`` ``(n, J, 2)`` px lies within ``[0, W/2] x [0, H/2]``: the
    signature of keypoints in the pixels of a copy at half the size or less (a detector run on a downscaled image),
    which a photo's own people rarely show (a user trial's keypoints of a 1000-px frame sat unsaid in the corner of
    a 5000-px photo, 26 m away)."""
    pts = poses.reshape(-1, 2)
    pts = pts[np.isfinite(pts).all(axis=1)]
    return bool(len(pts)) and bool(np.all(pts[:, 0] <= size[0] / 2) and np.all(pts[:, 1] <= size[1] / 2))


def keypoints_image(file_size: tuple[int, int] | None, file_pp: Any | None, *, image_size: Any | None = None,
                    principal_point: Any | None = None, fallback_image: tuple[Any, ...] | None = None,
                    poses: Sequence[np.ndarray] = (), where: str | Path = "",
                    what: str = "keypoint file") -> KeypointsImage:
    """The image size (px) a keypoint ``what`` (a file, a sequence) read from ``where`` is lifted with, and whether
    its keypoints are in the pixels of ``fallback_image`` (the image they were found in, as far as the caller knows:
    the app's photo uploaded before), one rule for every reader.

    ``image_size``: the caller's ``(W, H)`` (``--image-size``), which replaces the file's ``file_size`` with a note
    (:func:`given_image_size`). ``fallback_image``: ``(name, (W, H) px)`` or ``(name, (W, H) px, exif)``; its size is
    used, with a note, where neither the caller (``image_size``, ``principal_point``) nor the file (``file_size``,
    ``file_pp``) gives an image size or a principal point (a principal point without a size belongs to another
    camera: a K matrix's (W, H) is the centre of a 2W x 2H image). Refused (:class:`PoseLifterError` naming it)
    when most ``poses`` (each ``(J, 2)`` px) lie mostly outside it, as keypoints in another image's pixels would (the
    root then metres off); noted when every pose lies in its top-left quarter, as keypoints in a smaller copy's
    pixels would. Its EXIF focal-length fields ``exif`` are returned where the size lifted with is its
    own (taken from it, or the same), for :func:`resolve_camera`, as for a photo."""
    from ._checks import mostly_outside

    fallback = None
    if fallback_image is not None:
        if not isinstance(fallback_image, tuple | list) or len(fallback_image) not in (2, 3):
            raise PoseLifterError(f"fallback_image must be (name, (W, H)) or (name, (W, H), exif); got "
                                  f"{fallback_image!r}")
        fallback = (str(fallback_image[0]), fallback_image[1], fallback_image[2] if len(fallback_image) == 3 else None)
    notes: list[str] = []
    if (fallback is not None and image_size is None and principal_point is None and file_size is None
            and file_pp is None):
        name, wh, _ = fallback
        image_size = given_image_size(wh, None, where=f"fallback_image ({name})")[0]
        assert image_size is not None
        W, H = image_size
        stacked = np.stack(poses) if len(poses) else None
        if stacked is not None and float(np.mean(mostly_outside(stacked, (W, H)))) > 0.5:
            at = f"{where}: " if str(where) else ""
            raise PoseLifterError(f"{at}the {what} has no \"image_size\": [W, H] (nor a principal point), and its "
                                  f"poses lie mostly outside {name} ({W} x {H} px), whose size would be used: add the "
                                  "file's own \"image_size\"")
        notes.append(f"no image_size in the file: that of {name} ({W} x {H} px) is used")
        if stacked is not None and _in_top_left_quarter(stacked, (W, H)):
            which = "the pose lies" if len(poses) == 1 else "every pose lies"
            notes.append(f"{which} in the top-left quarter of {name} ({W} x {H} px), as keypoints in the pixels of a "
                         "smaller copy of it, or of another image, would (their root is then metres off): if they "
                         "are, add the file's own \"image_size\"; a person who does stand there is lifted right")
    size, size_notes = given_image_size(image_size, file_size, where="image_size= (--image-size)")
    on_fallback = False
    if fallback is not None and size is not None:
        try:
            on_fallback = [int(v) for v in fallback[1]] == [int(v) for v in size]
        except (TypeError, ValueError):  # (a malformed size that was not needed: the file gives its own)
            on_fallback = False
    return KeypointsImage(size=size, notes=notes + size_notes, exif=fallback[2] if on_fallback and fallback else None,
                          on_fallback=on_fallback)


def lift_keypoint_file(path: str | Path, *, lifter: Any, focal: Any | None = None, principal_point: Any | None = None,
                       default_format: str | None = None, fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG,
                       flip_test: bool | None = None, max_people: int | None = None,
                       image_size: Any | None = None, fallback_image: tuple[Any, ...] | None = None,
                       min_score: float = MIN_PERSON_SCORE) -> LiftRecord:
    """Lift everyone in one keypoint JSON file, largest first (at most ``max_people``; module docstring), but those
    whose mean joint score is below ``min_score`` (:func:`keep_scored_people`; 0 keeps every one).
    ``image_size`` ``(W, H)`` px: for a file that gives none (a list layout cannot), or in place of its own
    (:func:`given_image_size`). ``fallback_image``: ``(name, (W, H) px[, exif])`` of the image the keypoints were
    found in, whose size (and EXIF focal) a file that gives no image size takes by :func:`keypoints_image`'s rule,
    as :func:`lifter.video.lift_keypoint_sequence` does."""
    kf = parse_keypoint_json(path, default_format=default_format)
    in_file, min_score = len(kf.people), check_min_score(min_score)
    kf, low = keep_scored_people(kf, min_score, where=str(path))  # (before max_people: the largest of those kept)
    people = kf.people or (kf.keypoints,)
    img = keypoints_image(kf.image_size, kf.principal_point, image_size=image_size, principal_point=principal_point,
                          fallback_image=fallback_image, poses=people, where=str(path), what="keypoint file")
    size = img.size
    notes = list(kf.warnings) + img.notes
    cut = max_people is not None and len(people) > max_people
    if cut:  # (the reader's note, no longer true)
        said = (f"{in_file} people in the file; each is lifted", f"{len(people)} of the {in_file} people in the file "
                "are lifted")
        notes = [n for n in notes if not n.startswith(said)]
    notes += low
    if cut:
        assert max_people is not None
        notes.append(f"{len(people)} people in the file{' scored at least ' + format(min_score, 'g') if low else ''}; "
                     f"{largest_lifted(max_people)}")
        people = people[:max_people]
    raw = np.stack(people)
    kp17 = convert(raw, src=kf.format, warn=False)
    notes += placeholder_notes(raw, src=kf.format)  # (in the record, not a Python warning)
    scores, doubt = keypoint_file_scores(kf, len(people))
    notes += doubt
    f, src, pp, cam_notes = resolve_camera(
        user_focal=None if focal is None else as_pair(focal, name="focal", positive=True, scalar=True),
        user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
        file_focal=kf.focal, file_pp=kf.principal_point, image_size=size, exif=img.exif,
        sensor_width_mm=None, fov_deg=fov_deg, where=str(path), file_distortion=kf.distortion, unread=kf.unread,
        assumed_focal=kf.assumed_focal)
    cam_notes += plausibility_notes(kp17, f, size, focal_source=src, source_format=kf.format)
    cam_notes += lens_notes(kf.distortion, kf.distortion_model)
    lifted = lift_people(lifter, kp17, f, pp, flip_test=flip_test, source=kf.source, scores=scores, notes=cam_notes,
                         distortion=kf.distortion, distortion_model=kf.distortion_model)
    if kf.people_index:  # who is who in the file (the output is largest first)
        lifted = tuple(dataclasses.replace(q, input_index=k, person_id=i)
                       for q, k, i in zip(lifted, kf.people_index, kf.people_ids))
    top = lifted[0]
    return LiftRecord(input=str(path), kind="keypoints", keypoints_2d=top.keypoints_2d, absolute=top.absolute,
                      relative=top.relative, root=top.root, canonical_depth=top.canonical_depth,
                      focal=(float(f[0]), float(f[1])), focal_source=src, principal_point=(float(pp[0]), float(pp[1])),
                      image_size=size, model=lifter.name, source_format=kf.format,
                      model_info=model_info(lifter, source=kf.source, flip_test=flip_test),
                      num_people=len(kf.people) or 1, warnings=tuple(notes + cam_notes), source=kf.source,
                      people=lifted, distortion=distortion_tuple(kf.distortion),
                      distortion_model=kf.distortion_model, scores=top.scores)


def turned_calibration_notes(orientation: int, size: tuple[int, int], *, principal_point: Any | None,
                             focal: Any | None, distortion: Any | None) -> list[str]:
    """A note when a photo turned upright by its EXIF ``orientation`` (2 to 8) is given a calibration that depends on
    the image's axes (a principal point, a lens, or a focal length whose ``fx`` and ``fy`` differ): it is taken in
    the upright image's pixels (``size`` ``(W, H)``), and one made in the sensor's orientation (OpenCV's, as the file
    is stored) would have to be turned with it (a user trial: nothing said which). Else none."""
    if orientation == 1:
        return []
    quarter = orientation in (5, 6, 7, 8)  # (a flip or a half turn keeps the axes: fx and fy stay)
    f = None if focal is None else np.ravel(np.asarray(focal, np.float64))
    axes = [name for name, given in (("principal point", principal_point is not None),
                                     ("fx / fy", f is not None and f.size == 2 and f[0] != f[1] and quarter),
                                     ("lens distortion", distortion is not None)) if given]
    if not axes:
        return []
    turned = "turned by a quarter" if quarter else "flipped or turned by a half"
    return [f"the calibration given ({', '.join(axes)}) is taken in the pixels of the upright image ({size[0]} x "
            f"{size[1]} px), "
            f"which EXIF orientation {orientation} {turned} from the stored one: a calibration made with the "
            "stored (sensor) orientation must be turned with it"]


def lift_image(image: str | Path | LoadedImage, *, lifter: Any, estimator: PoseEstimator2D, focal: Any | None = None,
               principal_point: Any | None = None, sensor_width_mm: float | None = None,
               fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG, max_side: int = DEFAULT_MAX_SIDE_PX,
               flip_test: bool | None = None, max_people: int | None = None, distortion: ArrayLike | None = None,
               distortion_model: DistortionModel = "h36m", min_score: float = MIN_PERSON_SCORE) -> LiftRecord:
    """Detect everyone in a photo (a path or a :class:`lifter.detect.LoadedImage`) and lift them all into one
    camera space, largest first (at most ``max_people``); the top-level fields are the largest person's
    (module docstring). ``min_score``: detections whose mean joint score is below it are left out as no person
    (:data:`lifter.detect.MIN_PERSON_SCORE`, :func:`lifter.detect.detect_people`; 0 keeps every one).
    ``distortion``: the camera's lens in the form ``distortion_model`` (:meth:`lifter.Lifter.lift`), calibrated with
    ``focal`` and ``principal_point``, which it needs; the record keeps the 2D as detected (distorted)."""
    if distortion is not None and focal is None:
        raise PoseLifterError("distortion needs the focal length it was calibrated with (lens coefficients act on "
                              "(x - c) / f): give focal= (--focal) and principal_point= (--principal-point) of the "
                              "same calibration, or leave the distortion out")
    distortion_model = check_distortion_model(distortion_model)
    if isinstance(image, np.ndarray):
        raise PoseLifterError(
            f"lift_image: got a numpy array {image.shape}; pass a file path, or wrap an RGB array with "
            "lifter.detect.image_from_array(rgb) (from OpenCV's BGR: cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB))")
    if not isinstance(image, (str, os.PathLike, LoadedImage)):
        raise PoseLifterError(f"lift_image: expected a file path or a lifter.detect.LoadedImage, got "
                              f"{type(image).__name__}")
    img = image if isinstance(image, LoadedImage) else load_image(image, max_side=max_side)
    path = img.path if img.path is not None else "<image>"
    dets = detect_people(img, estimator=estimator, max_people=max_people, min_score=min_score)
    f, src, pp, notes = resolve_camera(
        user_focal=None if focal is None else as_pair(focal, name="focal", positive=True, scalar=True),
        user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
        file_focal=None, file_pp=None, image_size=img.size, exif=img.exif,
        sensor_width_mm=sensor_width_mm, fov_deg=fov_deg, where=str(path))
    kp_people = np.stack([d.keypoints_2d for d in dets])
    notes += turned_calibration_notes(img.orientation, img.size, principal_point=principal_point, focal=focal,
                                      distortion=distortion)
    notes += plausibility_notes(kp_people, f, img.size, focal_source=src, detected=True)
    notes += detected_upside_down_notes(kp_people)
    notes += detected_sideways_notes(kp_people)
    notes += detected_lean_notes(kp_people)
    notes += detected_edge_notes(kp_people, img.size)
    notes += detector_doubt_notes([float(np.mean(d.scores)) for d in dets])  # (the 17 joints lifted)
    notes += small_person_notes([float(np.ptp(d.keypoints_2d, axis=0).max()) * img.scale for d in dets],
                                downscaled=img.scale < 1.0)  # (the box's longer side: lying people too)
    scores = np.stack([d.scores for d in dets])
    notes += joint_doubt_notes(scores, kp_people, img.size)
    dist = None
    if distortion is not None:
        dist = check_lens(distortion, distortion_model)
        notes += lens_notes(dist, distortion_model)
    lifted = lift_people(lifter, kp_people, f, pp, flip_test=flip_test, source="detected", scores=scores, notes=notes,
                         distortion=dist, distortion_model=distortion_model)
    top, det = lifted[0], dets[0]
    warn = list(det.warnings)
    if len(dets) > 1:
        warn.append(f"{len(dets)} people lifted into one camera space ('people', largest first; the top-level "
                    "fields are the largest)")
    return LiftRecord(input=str(path), kind="image", keypoints_2d=top.keypoints_2d, absolute=top.absolute,
                      relative=top.relative, root=top.root, canonical_depth=top.canonical_depth,
                      focal=(float(f[0]), float(f[1])), focal_source=src, principal_point=(float(pp[0]), float(pp[1])),
                      image_size=img.size, model=lifter.name, scores=det.scores, source_format=det.raw.keypoint_format,
                      model_info=model_info(lifter, source="detected", flip_test=flip_test),
                      num_people=det.num_people, detector=estimator.name, warnings=tuple(warn + notes), people=lifted,
                      distortion=distortion_tuple(dist), distortion_model=distortion_model)
