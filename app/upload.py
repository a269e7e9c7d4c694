"""Uploads and downloads of the app, headless (no viser here).

Upload: a **photo** (any format Pillow reads) goes through :mod:`lifter.detect` and
:func:`lifter.pipeline.lift_image` exactly as ``poselifter lift`` does: EXIF orientation, downscaling of
huge images for detection (keypoints stay in full-resolution px), the largest person when there are
several, and the focal length from EXIF (:func:`lifter.detect.focal_from_exif`) or the default diagonal
field of view (:data:`lifter.detect.DEFAULT_DIAGONAL_FOV_DEG`); the principal point is the image centre.
A **keypoint JSON** (every layout ``poselifter lift`` accepts, :func:`lifter.io.parse_keypoint_json`,
converted with :func:`lifter.keypoints.convert`) is drawn on a plain canvas of its ``image_size``, or on
the photo uploaded just before when the sizes agree (so a photo + keypoints work without MediaPipe).
Both become a :class:`app.samples.Sample` without 3D ground truth whose 2D is the detected / given one.

Download: :func:`result_record` lifts the tab's current (possibly dragged) clean 2D at the current focal
length and returns a :class:`lifter.io.LiftRecord`; its ``to_dict()`` has the same fields as the
files ``poselifter lift`` writes (``keypoints_2d``, ``absolute``, ``root``, ``canonical_depth``, ``focal``,
``principal_point``, ...). :func:`glb_bytes` is the skeleton as a binary glTF (:mod:`lifter.export`).

Every problem raises :class:`lifter.PoseLifterError` (subclasses: :class:`UploadError`,
:class:`lifter.detect.ImageError`, :class:`lifter.detect.NoPersonError`,
:class:`lifter.detect.MissingDependencyError`) with a message meant for the user.
"""

from __future__ import annotations

import dataclasses
import json
import math
import re
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import cv2
import numpy as np

from lifter import Camera, PoseLifterError
from lifter._checks import OutputNote
from lifter._text import sentence
from lifter.camera import DEFAULT_DIAGONAL_FOV_DEG, focal_alpha, lens_notes, undistort_pixels_opencv
from lifter.detect import (
    DEFAULT_MAX_SIDE_PX,
    IMAGE_SUFFIXES,
    INSTALL_DETECT,
    MIN_PERSON_SCORE,
    ExifCamera,
    LoadedImage,
    MissingDependencyError,
    PoseEstimator2D,
    guess_focal,
    load_image,
)
from lifter.io import MAX_KEYPOINT_FILE_BYTES, LiftRecord, json_text, model_info, parse_keypoint_json
from lifter.keypoints import H36M17, convert, placeholder_notes
from lifter.pipeline import (
    keep_scored_people,
    keypoint_file_scores,
    keypoints_image,
    lift_image,
    lift_people,
    plausibility_notes,
    resolve_camera,
    unsure_people,
)
from lifter.skeleton import JOINT_NAMES, NUM_JOINTS
from lifter.video import MEDIA_HEAD_BYTES, input_kind

from .core import lens_free_2d, undoes_lens
from .drawing import canvas
from .samples import Sample, id_tag

MAX_UPLOAD_BYTES: Final[int] = 20 * 1024 * 1024
"""Uploads larger than this (20 MiB) are refused (viser itself buffers uploads of any size)."""
DISPLAY_MAX_SIDE: Final[int] = 1280
"""Uploaded photos are shown (GUI panel, frustum image) downscaled to this longer side."""
MAX_CANVAS_SIDE: Final[int] = 100_000
"""A keypoint file's ``image_size`` must be at most this many px per side."""
CAMERA_HEIGHT_MM: Final[float] = 1600.0
"""Uploaded photos have no extrinsics: the camera is placed 1.6 m above the floor, looking horizontally
along the world's +y axis (world z up), so the 3D view has the usual floor grid."""
MAX_PEOPLE: Final[int] = 6
"""People looked for in an uploaded photo / kept from a keypoint file (the largest first)."""
DEFAULT_DETECTOR: Final[str] = "blazepose"
OPENCV_LENS_UNDONE_NOTE: Final[str] = (
    "the file's OpenCV lens (\"distortion_model\": \"opencv\") is undone as the file is read: the 2D {what} is the "
    "undistorted (pinhole) 2D at the file's focal length, and no 'distortion' is recorded")
"""The note of a keypoint file or sequence whose OpenCV lens the app undid as it read it (its cameras hold Human3.6M's
lens form; ``what``: which 2D the user sees so)."""


class UploadError(PoseLifterError):
    """An upload that cannot be used (empty, too large, not a keypoint file, ...)."""


@dataclass(frozen=True)
class UploadInfo:
    """Where an uploaded sample came from (for the readout and the download).

    name: the uploaded file's name. kind: ``"image"`` or ``"keypoints"``. focal_source: as in
    ``poselifter lift`` (``exif-35mm``, ``default-fov``, ``keypoint-file``, ...). focal_detail: the
    human-readable reason. scores: ``(17,)`` detector confidences or None. source_format: the keypoint
    format before conversion. num_people: people found (photos). detector: the 2D estimator's name.
    warnings: notes for the user (several people, downscaling, EXIF rotation, focal guess).
    """

    name: str
    kind: str
    focal_source: str
    focal_detail: str
    scores: np.ndarray | None = None
    source_format: str = H36M17
    num_people: int | None = None
    source: str = "detected"
    """What the 2D is, for the lifter: photos are detector output; keypoint files say so (``"source"``)."""
    detector: str | None = None
    warnings: tuple[str, ...] = ()
    people_index: tuple[int, ...] = ()
    """A keypoint file with several people: each shown person's position in the file (largest first), and"""
    people_ids: tuple[str | int | None, ...] = ()
    """their own ids (``person_id``, ``track_id`` or ``id``; None where none): the download keeps both, as
    ``poselifter lift`` writes them."""
    people_scores: tuple[np.ndarray | None, ...] = ()
    """Each shown person's ``(17,)`` confidences of the H36M joints (largest first; None where they have none), or
    ``()``: only :attr:`scores`, the largest person's. The download keeps them, as ``poselifter lift`` writes them
    (a review's download of a keypoint file with scores had none)."""


@dataclass(frozen=True)
class Photo:
    """A decoded uploaded photo: display copy (RGB, longer side <= :data:`DISPLAY_MAX_SIDE`), the
    upright full-resolution size ``(W, H)`` and the EXIF focal-length fields."""

    name: str
    display: np.ndarray
    size: tuple[int, int]
    exif: ExifCamera
    notes: tuple[str, ...] = ()


# ------------------------------------------------------------------------------------------------
# Checks and helpers
# ------------------------------------------------------------------------------------------------


MAX_NAME_CHARS: Final[int] = 60
"""Uploaded file names are shortened to this many characters in messages and download names (the readout
does not wrap a long unbroken name)."""


def safe_name(name: str) -> str:
    """The file name part of an uploaded name, for messages and download names: at most
    :data:`MAX_NAME_CHARS` characters (a longer name keeps its start and its end, suffix included)."""
    base = re.split(r"[\\/]", str(name or "upload"))[-1].strip() or "upload"
    if len(base) > MAX_NAME_CHARS:
        base = base[: MAX_NAME_CHARS - 21] + "…" + base[-20:]
    return base


def check_upload(name: str, content: bytes, *, max_bytes: int = MAX_UPLOAD_BYTES) -> None:
    """Refuse empty and oversize uploads (:class:`UploadError`)."""
    n = len(content)
    if n == 0:
        raise UploadError(f"{safe_name(name)}: empty file")
    if n > max_bytes:
        raise UploadError(f"{safe_name(name)}: file is {n / 2**20:.1f} MiB, more than the {max_bytes / 2**20:.0f} MiB "
                          f"the app accepts; {_smaller_advice(name, bytes(content[:MEDIA_HEAD_BYTES]))}")


def oversize_message(name: str, size_bytes: int, *, max_bytes: int = MAX_UPLOAD_BYTES) -> str:
    return (f"{safe_name(name)}: file is {size_bytes / 2**20:.1f} MiB, more than the {max_bytes / 2**20:.0f} MiB the "
            f"app accepts; the upload was stopped. {_smaller_advice(name, capital=True)}")


def _smaller_advice(name: str, head: bytes = b"", *, capital: bool = False) -> str:
    """What to do with a file too large to upload, by the kind its name says (an app trial: a keypoint file was told
    to re-encode "the photo")."""
    kind = input_kind(safe_name(name), head)[0]
    if kind == "keypoints":
        advice = (f"lift a keypoint file this large with `poselifter lift FILE` (up to "
                  f"{MAX_KEYPOINT_FILE_BYTES // 2**20} MiB), or split it")
    elif kind == "video":
        advice = ("cut the video shorter or re-encode it at a lower resolution first, or lift it with `poselifter lift "
                  "FILE`")
    else:
        advice = "downscale or re-encode the photo (e.g. JPEG) first"
    return advice[:1].upper() + advice[1:] if capital else advice


def is_json_upload(name: str, content: bytes) -> bool:
    """A keypoint file: content that starts like JSON (``{`` or ``[``), or a ``.json`` name on content that is not a
    photo's or video's (:func:`lifter.video.input_kind`: a JPEG named ``.json`` is a photo)."""
    return input_kind(safe_name(name), bytes(content[:MEDIA_HEAD_BYTES]))[0] == "keypoints"


def _with_temp_file(name: str, content: bytes, suffix: str, func: Callable[[Path], Any]) -> Any:
    """Run ``func(path)`` on ``content`` written to a temporary file; the temporary path in any
    :class:`PoseLifterError` message is replaced by the uploaded name."""
    with tempfile.TemporaryDirectory(prefix="poselifter-upload-") as d:
        path = Path(d) / f"upload{suffix}"
        path.write_bytes(content)
        try:
            return func(path)
        except PoseLifterError as exc:
            msg = str(exc).replace(str(path), safe_name(name))
            try:
                new = type(exc)(msg)
            except TypeError:
                new = PoseLifterError(msg)
            raise new from None


def upload_camera(focal: tuple[float, float], principal_point: tuple[float, float], size: tuple[int, int],
                  name: str, distortion: Sequence[float] | np.ndarray | None = None) -> Camera:
    """The camera of an uploaded photo / keypoint file (intrinsics as given, lens distortion ``(k1, k2, k3, p1,
    p2)`` as a keypoint file gives it, else none; extrinsics: :data:`CAMERA_HEIGHT_MM`)."""
    d = (0.0,) * 5 if distortion is None else tuple(float(v) for v in distortion)
    R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # world z up -> camera y down, z = world y
    C = np.array([0.0, 0.0, CAMERA_HEIGHT_MM])
    return Camera(focal=(float(focal[0]), float(focal[1])),
                  principal_point=(float(principal_point[0]), float(principal_point[1])),
                  width=int(size[0]), height=int(size[1]), k=d[:3], p=d[3:], R=R, t=-R @ C,  # type: ignore[arg-type]
                  name=f"upload/{name}")


def _display(rgb: np.ndarray, max_side: int = DISPLAY_MAX_SIDE) -> np.ndarray:
    h, w = rgb.shape[:2]
    s = min(1.0, max_side / float(max(h, w)))
    if s >= 1.0:
        return np.ascontiguousarray(rgb)
    return cv2.resize(rgb, (max(1, round(w * s)), max(1, round(h * s))), interpolation=cv2.INTER_AREA)


def display_canvas(size: tuple[int, int], max_side: int = DISPLAY_MAX_SIDE) -> np.ndarray:
    """A plain canvas for an image of ``size = (W, H)`` px, downscaled to ``max_side`` (uploads without a photo)."""
    W, H = size
    s = min(1.0, max_side / float(max(W, H)))
    return canvas(max(1, round(W * s)), max(1, round(H * s)))


def _check_2d(kp: np.ndarray, where: str, size: tuple[int, int] | None = None) -> np.ndarray:
    """Finite ``(17, 2)`` px and, given the image size, within the image grown by its size on every side."""
    kp = np.asarray(kp, np.float64)
    if kp.shape != (NUM_JOINTS, 2) or not np.all(np.isfinite(kp)):
        raise UploadError(f"{where}: the 2D pose must be 17 finite (x, y) px, got shape {kp.shape}")
    if size is not None:
        W, H = size
        out = (kp[:, 0] < -W) | (kp[:, 0] > 2 * W) | (kp[:, 1] < -H) | (kp[:, 1] > 2 * H)
        if out.any():
            names = [JOINT_NAMES[j] for j in np.flatnonzero(out)][:5]
            raise UploadError(f"{where}: joint(s) {names} lie far outside the {W} x {H} px image (more than its size "
                              "beyond an edge); are the keypoints in pixels of this image?")
    return kp


# ------------------------------------------------------------------------------------------------
# Photos
# ------------------------------------------------------------------------------------------------


def decode_photo(name: str, content: bytes, *, max_side: int = DEFAULT_MAX_SIDE_PX) -> tuple[Photo, LoadedImage]:
    """Decode an uploaded photo with :func:`lifter.detect.load_image` (EXIF orientation, downscaling of
    huge images, :class:`lifter.detect.ImageError` for not-an-image / truncated / too many pixels)."""
    check_upload(name, content)
    suffix = Path(safe_name(name)).suffix.lower()
    suffix = suffix if suffix in IMAGE_SUFFIXES else ".img"
    img: LoadedImage = _with_temp_file(name, content, suffix, lambda p: load_image(p, max_side=max_side))
    _, misnamed = input_kind(safe_name(name), content[:MEDIA_HEAD_BYTES])  # (a JPEG renamed .mp4)
    notes = img.notes if misnamed is None else (misnamed, *img.notes)
    img = dataclasses.replace(img, path=Path(safe_name(name)), notes=notes)
    return Photo(name=safe_name(name), display=_display(img.rgb), size=img.size, exif=img.exif, notes=notes), img


def photo_sample(photo: Photo, img: LoadedImage, *, key: str, lifter: Any, estimator: PoseEstimator2D,
                 fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG, max_people: int = MAX_PEOPLE,
                 min_score: float = MIN_PERSON_SCORE) -> Sample:
    """Detect everyone on an uploaded photo (at most ``max_people``, largest first, of those whose mean joint score
    is at least ``min_score``) and make it a sample: the largest person's 2D, the others in ``others_2d``
    (:func:`lifter.pipeline.lift_image`: raises :class:`lifter.detect.NoPersonError` when nobody is found)."""
    rec = lift_image(img, lifter=lifter, estimator=estimator, fov_deg=fov_deg, max_people=max_people,
                     min_score=min_score)
    kp = _check_2d(rec.keypoints_2d, photo.name)  # (detections may be extrapolated outside the image)
    others = tuple(_check_2d(p.keypoints_2d, f"{photo.name}, person {i + 2}") for i, p in enumerate(rec.people[1:]))
    detail = focal_note(rec.warnings, rec.focal_source)
    info = UploadInfo(name=photo.name, kind="image", focal_source=rec.focal_source, focal_detail=detail,
                      scores=None if rec.scores is None else np.asarray(rec.scores, np.float64),
                      source_format=rec.source_format, num_people=rec.num_people, detector=rec.detector,
                      warnings=tuple(rec.warnings),
                      people_scores=tuple(None if q.scores is None else np.asarray(q.scores, np.float64)
                                          for q in rec.people[:1 + len(others)]))
    cam = upload_camera(rec.focal, rec.principal_point, photo.size, photo.name)
    return Sample(key=key, label=f"upload: {photo.name}", keypoints_2d=kp, pose_3d=None, detected_2d=kp.copy(),
                  camera=cam, image=photo.display, has_gt_2d=False, upload=info, others_2d=others)


# ------------------------------------------------------------------------------------------------
# Keypoint files
# ------------------------------------------------------------------------------------------------


def focal_note(notes: Sequence[str], fallback: str) -> str:
    """The note of ``notes`` that says how a focal length not given was found (from EXIF, or the default field of
    view: :func:`lifter.detect.guess_focal`'s detail, in px), else ``fallback``: the upload's "Focal: ..." line."""
    return next((w for w in notes if "px" in w and ("EXIF" in w or "field of view" in w)), fallback)


def keypoint_sample(name: str, content: bytes, *, key: str, photo: Photo | None = None,
                    fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG, min_score: float = MIN_PERSON_SCORE) -> Sample:
    """A sample from an uploaded keypoint JSON (any layout ``poselifter lift`` accepts).

    Image size: the file's ``image_size``; else, when the file gives neither it nor a principal point, that of
    ``photo`` (the photo uploaded just before; refused when the keypoints lie mostly outside it), by
    :func:`lifter.pipeline.keypoints_image`'s rule, as for a keypoint sequence. The photo is drawn under the
    keypoints when the size lifted with is its own. Focal: the file's
    ``focal``; else the photo's EXIF focal (when drawn on it); else the default field of view ``fov_deg`` of the
    image size. Principal point: the file's, else the image centre. Focal and principal point are resolved, checked
    and noted by :func:`lifter.pipeline.resolve_camera`, as for ``poselifter lift`` (a file with neither a focal nor
    an image size is refused). A file with a focal and a principal point but no image size is drawn on a canvas
    twice its principal point.
    """
    check_upload(name, content)
    nm = safe_name(name)
    try:
        json_text(content)
    except UnicodeDecodeError:
        raise UploadError(f"{nm}: not a photo Pillow can read, and not a keypoint JSON file (JSON text in UTF-8, "
                          "UTF-16 or UTF-32)") from None
    # the keypoint-file reader parses it once and names what is wrong (not valid JSON, nested too deeply, ...)
    kf = _with_temp_file(name, content, ".json", parse_keypoint_json)
    kf, low = keep_scored_people(kf, min_score, where=nm)  # (people scored below the floor: as the CLI)
    kp = _check_2d(convert(kf.keypoints, src=kf.format, warn=False), nm)
    misnamed = input_kind(nm, content[:MEDIA_HEAD_BYTES])[1]  # (keypoint JSON named .mp4)
    notes = [*([misnamed] if misnamed else []), *kf.warnings, *low]
    people = list(kf.people[1:])
    if len(people) + 1 > MAX_PEOPLE:
        notes.append(f"{len(people) + 1} people in the file; the {MAX_PEOPLE} largest are shown")
        people = people[:MAX_PEOPLE - 1]
    others = tuple(_check_2d(convert(p, src=kf.format, warn=False), f"{nm}, person {i + 2}")
                   for i, p in enumerate(people))
    notes += placeholder_notes(np.stack([kf.keypoints, *people]), src=kf.format)
    file_scores, doubt = keypoint_file_scores(kf, 1 + len(others))
    notes += doubt  # (the unsure joints, named as poselifter lift names them)
    tags = tuple("" if i is None else id_tag(i) for i in kf.people_ids[:1 + len(others)])
    # the photo's size (and EXIF focal) by the library's rule for the image the keypoints were found in (as for a
    # keypoint sequence): where the file gives no image size nor principal point, or the same size
    try:
        found = keypoints_image(kf.image_size, kf.principal_point, poses=list(kf.people) or [kf.keypoints], where=nm,
                                fallback_image=None if photo is None else (f"the photo {photo.name} uploaded before",
                                                                           photo.size, photo.exif))
    except PoseLifterError as exc:
        raise UploadError(str(exc)) from None
    size, use_photo = found.size, found.on_fallback
    if size is None and kf.principal_point is None:  # (nothing to draw the keypoints on)
        raise UploadError(f"{nm}: the keypoint file has no \"image_size\": [W, H] (nor a \"principal_point\"); "
                          "add it, or upload the photo first"
                          + (". Also in the file: " + " ".join(sentence(n) for n in kf.unread) if kf.unread else ""))
    # the camera by poselifter lift's rules and notes (a review: the app's own rules had left out its notes), from
    # the image's own size, not the canvas's guess below (no focal is assumed from twice the principal point);
    # first, so that a file lift refuses for its camera is refused for that here too
    exif = found.exif
    try:
        f, src, c, cam_notes = resolve_camera(
            user_focal=None, user_pp=None, file_focal=kf.focal, file_pp=kf.principal_point, image_size=size,
            exif=exif, sensor_width_mm=None, fov_deg=fov_deg, where=nm, file_distortion=kf.distortion,
            unread=kf.unread, assumed_focal=kf.assumed_focal, cli_options=False)
    except PoseLifterError as exc:
        raise UploadError(str(exc)) from None
    if size is None and kf.principal_point is not None:
        size = (max(1, round(2 * float(kf.principal_point[0]))), max(1, round(2 * float(kf.principal_point[1]))))
        notes.append(f"no image_size in the file: assumed {size[0]} x {size[1]} px (twice the principal point)")
    assert size is not None  # (a principal point, else refused above)
    if min(size) <= 0 or max(size) > MAX_CANVAS_SIDE:
        raise UploadError(f"{nm}: image_size {list(size)} px is not plausible")
    try:
        for i, q in enumerate((kp, *others)):
            _check_2d(q, nm if i == 0 else f"{nm}, person {i + 1}", size)
    except UploadError as exc:
        if use_photo and kf.image_size is None:  # (say where the size came from: an earlier upload)
            raise UploadError(f"{exc} (the file gives no \"image_size\", so the size of the photo {photo.name} "  # type: ignore[union-attr]
                              "uploaded before was used; add the file's own \"image_size\": [W, H])") from None
        raise
    notes += found.notes  # (the size taken from the photo)
    if use_photo and not found.notes:  # (the file's own size is the photo's)
        notes.append(f"keypoints drawn on the photo {photo.name} uploaded before (the same image size)")  # type: ignore[union-attr]
    notes += cam_notes
    focal, pp = (float(f[0]), float(f[1])), (float(c[0]), float(c[1]))
    detail = ("focal from the keypoint file" if src == "keypoint-file" else
              guess_focal(size, exif=exif, fov_deg=fov_deg).detail)  # (the guess resolve_camera made, named)
    # what poselifter lift notes too: a focal in mm (a pose spanning > 120 deg), (0, 0) placeholders
    notes += plausibility_notes(np.stack([kp, *others]), np.array(focal), None, focal_source=src,
                                source_format=kf.format)
    lens = kf.distortion
    if lens is not None and kf.distortion_model == "opencv":  # (the app's cameras have Human3.6M's lens model)
        try:
            kp, *rest = undistort_pixels_opencv(np.stack([kp, *others]), focal=focal, principal_point=pp,
                                                dist_coeffs=lens)
        except PoseLifterError as exc:
            raise UploadError(f"{nm}: {exc}") from None
        others, lens = tuple(rest), None
        notes.append(OPENCV_LENS_UNDONE_NOTE.format(what="shown, dragged and downloaded"))
    else:
        notes += lens_notes(lens, kf.distortion_model)
    info = UploadInfo(name=nm, kind="keypoints", focal_source=src, focal_detail=detail, source_format=kf.format,
                      source=kf.source, num_people=1 + len(others), warnings=tuple(notes),
                      people_index=tuple(kf.people_index[:1 + len(others)]),
                      people_ids=tuple(kf.people_ids[:1 + len(others)]),
                      scores=None if file_scores is None else file_scores[0],
                      people_scores=() if file_scores is None else tuple(file_scores))
    image = photo.display if use_photo else display_canvas(size)  # type: ignore[union-attr]
    cam = upload_camera(focal, pp, size, nm, lens)  # (the lift undistorts with it: core.compute_frame)
    return Sample(key=key, label=f"upload: {nm}", keypoints_2d=kp, pose_3d=None, detected_2d=kp.copy(), camera=cam,
                  image=image, has_gt_2d=False, upload=info, others_2d=others,
                  person_tags=tags if any(tags) else ())


def missing_detector_message(name: str, exc: Exception, *, video: bool = False) -> str:
    """What the app says when a photo (or a ``video``) cannot be lifted because the detector extra is missing: the
    install command, and the keypoint JSON that still works."""
    if video:
        other = ("Uploading a keypoint sequence JSON still works (e.g. {\"frames\": [{\"keypoints\": [[x, y], ...]}, "
                 "...], \"fps\": 25, \"format\": \"coco17\", \"image_size\": [W, H]}). ")
    else:
        other = ("Uploading a keypoint JSON file still works (e.g. {\"keypoints\": [[x, y], ...], \"format\": "
                 "\"coco17\", \"image_size\": [W, H]}); one uploaded now is drawn on this photo when its image_size "
                 "matches. ")
    return (f"{safe_name(name)}: cannot find 2D joints in a {'video' if video else 'photo'}: the MediaPipe detector "
            f"is not installed (install it with: {INSTALL_DETECT}). {other}[{type(exc).__name__}]")


# ------------------------------------------------------------------------------------------------
# Download
# ------------------------------------------------------------------------------------------------


def result_record(sample: Sample, keypoints: np.ndarray, *, lifter: Any, focal: tuple[float, float],
                  dragged: set[int] | frozenset[int] = frozenset(), focal_changed: bool = False,
                  people: list[np.ndarray] | None = None, people_dragged: dict[int, frozenset[int]] | None = None,
                  source: str | None = None) -> Any:
    """The tab's result as a :class:`lifter.io.LiftRecord`: the current clean 2D (``(17, 2)`` px,
    dragged joints included, no noise) lifted at ``focal`` and the sample's principal point, told ``source``
    (None: the upload's own, ``"clean"`` for a sample without one); the record's ``source`` says which.

    With several people, ``people`` is everyone's current 2D in the sample's order (largest first) and
    ``people_dragged`` their dragged joints (person index -> joints); they are lifted in one batch into
    ``people`` of the record, and the top-level fields are the largest person's, as ``poselifter lift`` writes
    them (``keypoints`` and ``dragged`` are then not used)."""
    cam = sample.camera
    pp = (float(cam.principal_point[0]), float(cam.principal_point[1]))
    info: UploadInfo | None = sample.upload
    if source is None:  # (the tab says: a sample's detections are "detected", its ground truth "clean")
        source = "clean" if info is None or info.source == "clean" else "detected"
    if people is None:
        people, people_dragged = [keypoints], {0: frozenset(dragged)}
    kp_all = np.stack([_check_2d(q, sample.label if i == 0 else f"{sample.label}, person {i + 1}")
                       for i, q in enumerate(people)])
    output_notes: list[str] = []  # (what looks wrong in the output, as poselifter lift's records carry it)
    # (as the tab lifted it: undistorted with the camera's own focal, then lifted at the tab's)
    lifted = lift_people(lifter, lens_free_2d(kp_all, camera=cam, lifter=lifter, source=source),
                         np.asarray(focal, np.float64), np.asarray(pp, np.float64), flip_test=None, source=source,
                         notes=output_notes)
    # the record's 2D: as given, with its lens, at the camera's own focal (the lens belongs to it); at another
    # focal, undistorted and without the lens, so that lifting the record again gives this result
    keep_lens = cam.distortion is not None and not (focal_changed and undoes_lens(camera=cam, lifter=lifter,
                                                                                   source=source))
    if cam.distortion is not None and not keep_lens:
        output_notes.append(f"2D undistorted with the camera's lens at its own focal length ({cam.alpha:.1f} px), then "
                            "lifted at the app's focal length: keypoints_2d is that undistorted 2D, and no "
                            "'distortion' is recorded")
    else:
        lifted = tuple(dataclasses.replace(q, keypoints_2d=kp_all[i]) for i, q in enumerate(lifted))
    scores = None if info is None else info.scores
    if info is not None and len(info.people_scores) == len(lifted):  # (everyone's, as poselifter lift writes them)
        lifted = tuple(dataclasses.replace(q, scores=sc) for q, sc in zip(lifted, info.people_scores))
    elif scores is not None:  # (the detector's confidences are the largest person's)
        lifted = (dataclasses.replace(lifted[0], scores=scores), *lifted[1:])
    if info is not None and info.people_index and len(info.people_index) == len(lifted):  # who is who in the file
        lifted = tuple(dataclasses.replace(q, input_index=k, person_id=i)
                       for q, k, i in zip(lifted, info.people_index, info.people_ids))
    # (the upload's own notes, less those on its lift's output, which output_notes says of this lift: a trial's
    # download listed the upload's misfit note twice, and a drag since can have made it untrue)
    warnings = [w for w in (info.warnings if info is not None else ()) if not isinstance(w, OutputNote)] + output_notes
    for k, joints in sorted((people_dragged or {}).items()):
        if joints:
            who = f" (person {k + 1})" if len(people) > 1 else ""
            warnings.append(f"2D joints corrected in the app{who}: "
                            + ", ".join(JOINT_NAMES[j] for j in sorted(joints)))
    if focal_changed:
        src = "app-slider"
        warnings.append(f"focal length set in the app (slider or box) to {float(focal_alpha(focal)):.1f} px")
    else:
        src = info.focal_source if info is not None else "calibrated-camera"
    top = lifted[0]
    return LiftRecord(input=info.name if info is not None else sample.label,
                      kind=info.kind if info is not None else "sample",
                      keypoints_2d=top.keypoints_2d, absolute=top.absolute, relative=top.relative,
                      root=top.root, canonical_depth=top.canonical_depth, people=lifted,
                      focal=(float(focal[0]), float(focal[1])), focal_source=src, principal_point=pp,
                      image_size=(int(cam.width), int(cam.height)), model=str(getattr(lifter, "name", "custom")),
                      model_info=model_info(lifter, source=source),
                      scores=top.scores,
                      source_format=H36M17 if info is None else info.source_format,
                      num_people=len(lifted) if info is None else info.num_people,  # (a trial read null)
                      detector=None if info is None else info.detector, warnings=tuple(warnings), source=source,
                      distortion=cam.distortion if keep_lens else None)


def download_stem(sample: Sample) -> str:
    """A file-name stem for the result of ``sample``: an uploaded video's keeps its file type (``two_mp4``), so that
    it is not named as a photo of the same name is (a trial's ``two.jpg`` and ``two.mp4`` both gave
    ``two_lifted.json``). A video is told by what the upload held, not by its name (a JPEG renamed ``.mp4`` is a
    photo: :func:`lifter.video.input_kind`)."""
    up = sample.upload
    name = Path(up.name) if up is not None else None
    raw = sample.key if up is None or name is None else (
        f"{name.stem}_{name.suffix[1:].lower() or 'video'}" if up.kind == "video" else name.stem)
    stem = re.sub(r"[^A-Za-z0-9._-]+", "_", raw).strip("._") or "pose"
    return stem[:80] + "_lifted"


def json_bytes(record: Any) -> bytes:
    return json.dumps(record.to_dict(), indent=1).encode("utf-8")


def glb_bytes(record: Any) -> bytes:
    """The lifted skeleton(s) as a binary glTF (metres, y-up; :mod:`lifter.export`): everyone in ``record.people``
    in one scene, else ``record.absolute``."""
    from lifter.export import skeleton_scene

    people = getattr(record, "people", ())
    pose = np.stack([p.absolute for p in people]) if len(people) > 1 else record.absolute
    return bytes(skeleton_scene(pose).export(file_type="glb"))


__all__ = ["CAMERA_HEIGHT_MM", "DetectorMissing", "DISPLAY_MAX_SIDE", "MAX_UPLOAD_BYTES", "MissingDependencyError",
           "Photo", "UploadError", "UploadInfo", "UploadRefused", "check_upload", "decode_photo", "download_stem",
           "focal_note", "glb_bytes", "is_json_upload", "json_bytes", "keypoint_sample", "missing_detector_message",
           "note_if_busy", "oversize_message", "photo_sample", "result_record", "safe_name", "upload_camera"]


def note_if_busy(lock: Any, on_wait: Callable[[], None] | None) -> None:
    """Call ``on_wait()`` when ``lock`` (the app's detector lock) is held now: the upload about to need it waits for
    another upload's detection (a security review: a photo waited minutes behind another tab's video, unsaid)."""
    if lock.acquire(blocking=False):
        lock.release()
    elif on_wait is not None:
        on_wait()


def upload_sample(name: str, content: bytes, *, key: str, photo: Photo | None, max_bytes: int,
                  estimator: Callable[[], Any], lifter: Any, detect_lock: Any,
                  min_score: float = MIN_PERSON_SCORE,
                  on_wait: Callable[[], None] | None = None) -> tuple[Sample, Photo | None]:
    """The upload rules: ``(sample, photo)`` for an uploaded file — a keypoint JSON (drawn on ``photo``, the photo
    uploaded before, when the sizes agree) or a photo (the largest person by ``estimator()``'s detector, lifted by
    ``lifter`` for its focal; ``detect_lock`` serialises detection). ``photo`` comes back updated: a decodable photo
    is kept for a keypoint JSON uploaded next, even when detection then fails. Raises :class:`PoseLifterError`
    with a message for the user (too large, not an image, nobody found, the detector extra missing, ...).
    ``min_score``: the score floor (:data:`lifter.detect.MIN_PERSON_SCORE`; the File tab's "min person score").
    ``on_wait()``: called when the photo must wait for another upload's detection (:func:`note_if_busy`)."""
    name = safe_name(name)
    content = bytes(content or b"")
    check_upload(name, content, max_bytes=max_bytes)
    if is_json_upload(name, content):
        return keypoint_sample(name, content, key=key, photo=photo, min_score=min_score), photo
    new_photo, img = decode_photo(name, content)  # not-an-image / truncated / too many pixels raise here
    note_if_busy(detect_lock, on_wait)
    try:
        est = estimator()
    except MissingDependencyError as exc:
        raise DetectorMissing(missing_detector_message(name, exc), photo=new_photo) from None
    except PoseLifterError as exc:
        raise UploadFailed(str(exc), photo=new_photo) from None
    with detect_lock:
        try:
            return photo_sample(new_photo, img, key=key, lifter=lifter, estimator=est, min_score=min_score), new_photo
        except PoseLifterError as exc:
            raise UploadFailed(str(exc), photo=new_photo) from None


class UploadRefused(PoseLifterError):
    """An upload that arrived but cannot be used (the app says so in a notification that stays)."""


class UploadFailed(PoseLifterError):
    """An upload that failed after its photo was decoded: ``photo`` is kept for a keypoint JSON uploaded next
    (None: a video, which leaves the photo uploaded before as it was); its message says so (:func:`kept_photo_note`)."""

    def __init__(self, message: str, *, photo: Photo | None) -> None:
        super().__init__(message)
        self.photo = photo


def kept_photo_note(photo: Photo) -> str:
    """Said of a photo whose detection failed: it stays the photo a keypoint JSON uploaded next is drawn on (a trial:
    a keypoint file of the refused photo's size was drawn on it, unexpected, and would take its EXIF focal)."""
    w, h = photo.size
    return (f"The photo ({w} x {h} px) stays the one a keypoint JSON uploaded next is drawn on where its 2D is in the "
            "photo's pixels (with the photo's EXIF focal length where the file gives none), for 2D of your own, until "
            f"another photo is uploaded; this one, {photo.name}, not the one still shown")


class DetectorMissing(UploadFailed):
    """A photo or video that cannot be lifted because this install has no 2D detector: not the file's fault (not
    an :class:`UploadRefused`)."""


def upload_message(sample: Sample) -> str:
    """What the readout says after an upload: what was found, how to correct it, the focal and any notes."""
    info = sample.upload
    n = sample.num_people
    what = (f"{info.name}: {info.detector} found {n} {'person' if n == 1 else 'people'}"
            if info.kind == "image" else f"{info.name}: {info.source_format} keypoints"
            + (f" of {n} people" if n > 1 else ""))
    # (a trial: the notification, cut at 240 characters, lost the note that there may be no person at all)
    # (the library's rule, on the mean as its floor and note read it: a NaN score gives neither)
    means = [float(np.mean(sc)) if sc is not None and np.size(sc) else math.nan for sc in info.people_scores]
    unsure = [i + 1 for i in unsure_people(means)] if info.kind == "image" else []
    if unsure:
        who = ("it" if n == 1 else f"person {unsure[0]}" if len(unsure) == 1 else
               "people " + ", ".join(str(i) for i in unsure[:-1]) + f" and {unsure[-1]}")
        what += f" (the detector is unsure of {who}: maybe no person at all, see the note)"
    if n > 1:
        what += ", all lifted into one camera space (the Drag tab's person picker selects whose joints to drag)"
    # (the notes on the upload's lift's output are the readout's Cautions, for the lift shown: a review saw the
    # upload's misfit note stale beside them after a drag)
    notes = [n for n in info.warnings if n != info.focal_detail and not isinstance(n, OutputNote)]
    return (f"{what}; drag the 2D joints on the image plane to correct them. Focal: {info.focal_detail}."
            + "".join(f"\n\nNote: {sentence(n)}" for n in notes))  # (each its own paragraph)
