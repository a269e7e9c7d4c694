"""Input validation shared by the public functions. Errors name the argument and the problem."""

from __future__ import annotations

import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

import numpy as np


class PoseLifterError(ValueError):
    """Raised for invalid user input (shape, non-finite values, degenerate poses, bad cameras)."""


class CheckpointError(PoseLifterError):
    """Raised when a weights file is missing, corrupt or of an unknown format."""


class PoseLifterWarning(UserWarning):
    """Input the lifter takes but that looks wrong (a focal length in mm, a missing joint placed at (0, 0)); the
    message names the problem. Turn into errors with ``warnings.simplefilter("error", PoseLifterWarning)``."""


_PACKAGE_DIR = os.path.dirname(__file__) + os.sep  # (as the package's code objects name their files)


def warn_user(message: str) -> None:
    """Warn :class:`PoseLifterWarning` ``message`` at the first frame outside the ``lifter`` package: the caller's
    own line, however deep inside the package the warning arises (a review: a checkpoint's warning named a line of
    ``lifter/api.py``; Python 3.12's ``skip_file_prefixes`` does this, 3.11 does not have it)."""
    import warnings

    level, frame = 2, sys._getframe(1)  # (stacklevel 1 is this function, 2 its caller)
    while frame is not None and frame.f_code.co_filename.startswith(_PACKAGE_DIR):
        level, frame = level + 1, frame.f_back
    warnings.warn(PoseLifterWarning(message), stacklevel=level)


def where_in_batch(mask: Any, *, whose: str | None = None, names: Sequence[str] | None = None) -> str:
    """`` (pose at index (i, j), n such pose(s))`` for the first True entry of a mask over a batch's leading shape;
    empty for a single pose (a 0-d mask, or a batch of one like a file's single pose). ``whose``: the batch is a
    list of people (one image's, file's or frame's, as its record lists them): `` (person i+1 of <whose>, and n-1
    more)``, 1-based, as the joint-score notes count. ``names``: the people's own labels, one per entry of a 1-D
    mask (a video frame's ``"track 3"``): `` (<name>, and n-1 more)``, for a batch of one too."""
    mask = np.asarray(mask)
    if names is not None and mask.ndim == 1 and len(names) == mask.size and mask.any():
        first_name = names[int(np.argmax(mask))]
        more = int(mask.sum()) - 1
        return f" ({first_name}" + (f", and {more} more)" if more else ")")
    if mask.size <= 1:
        return ""
    first = tuple(int(i) for i in np.argwhere(mask)[0])
    if whose is not None and mask.ndim == 1:
        more = int(mask.sum()) - 1
        return f" (person {first[0] + 1} of {whose}" + (f", and {more} more)" if more else ")")
    return f" (pose at index {first}, {int(mask.sum())} such pose(s))"


def _untorch(x: Any) -> Any:
    """A torch tensor (any device, with or without ``requires_grad``, any float dtype) as a CPU tensor numpy
    can read; anything else unchanged. torch is only consulted when the caller already imported it."""
    torch = sys.modules.get("torch")
    if torch is not None and isinstance(x, torch.Tensor):
        x = x.detach().cpu()
        if x.is_floating_point():
            x = x.double()  # float16 / bfloat16 -> float64 (numpy has no bfloat16)
    return x


def _real_array(x: Any, *, name: str, what: str) -> np.ndarray:
    """``x`` as float64, refusing complex numbers, booleans and anything non-numeric with a clear message. A numpy
    masked array's masked values become NaN, which the callers refuse by name (a user trial: its mask was ignored and
    the values under it lifted)."""
    x = _untorch(x)
    if isinstance(x, (list, tuple)) and any(isinstance(v, np.ma.MaskedArray) for v in x):
        try:  # (a list of masked arrays: np.asarray would drop their masks)
            x = np.ma.stack([np.ma.asarray(v) for v in x])
        except (TypeError, ValueError):
            pass  # (ragged: refused below as any ragged list is)
    if isinstance(x, np.ma.MaskedArray) and np.ma.getmaskarray(x).any() and x.dtype.kind != "b":
        try:
            x = np.ma.filled(x.astype(np.float64), np.nan)
        except (TypeError, ValueError):
            pass  # (not numbers: refused below, naming what they are)
    try:
        raw = np.asarray(x)
    except (TypeError, ValueError, RuntimeError) as exc:
        raise PoseLifterError(f"{name}: could not convert to {what} ({exc})") from None
    if np.iscomplexobj(raw):
        raise PoseLifterError(f"{name}: complex numbers are not pixel coordinates; pass real values")
    if raw.dtype == bool:
        raise PoseLifterError(f"{name}: booleans are not pixel coordinates; pass numbers")
    if raw.dtype.kind in "USO" and any(isinstance(v, (str, bytes)) for v in np.ravel(raw)[:1000]):
        raise PoseLifterError(f"{name}: strings are not numbers; pass numbers (e.g. float(value))")
    try:
        return np.asarray(raw, dtype=np.float64)
    except (TypeError, ValueError, RuntimeError) as exc:
        raise PoseLifterError(f"{name}: could not convert to {what} ({exc})") from None


_OTHER_FORMATS: dict[int, tuple[str, ...]] = {16: ("sh16",), 25: ("openpose25",), 33: ("blazepose33",)}
"""Joint counts of the other keypoint formats (:mod:`lifter.keypoints`), for the shape error's hint (17 joints
is also COCO's: the count cannot tell, so it gets none)."""


OTHER_LAYOUTS: dict[int, tuple[str, str, str, str]] = {
    26: ("Halpe-26 (AlphaPose)", "coco17", "the first 17 joints", "[..., :17, :]"),
    32: ("Human3.6M's 32-joint mocap skeleton", "h36m17", "the 17 joints at lifter.skeleton.H36M32_INDICES",
         "[..., lifter.skeleton.H36M32_INDICES, :]"),
    133: ("COCO-WholeBody", "coco17", "the first 17 joints (the body)", "[..., :17, :]"),
}
"""Joint counts of layouts that hold one of the formats read (:mod:`lifter.keypoints`) among their joints: ``(layout,
format, which joints, the index that takes them)``, for the messages about a joint count no format has (a user
trial got a bare shape error for each)."""


def other_layout_hint(num_joints: int, *, name: str | None = None) -> str:
    """``"; 32 joints is ...: take ..."`` for a joint count of :data:`OTHER_LAYOUTS` (``name``: the array's, for
    the API's message; None: a keypoint file's), else empty."""
    if num_joints not in OTHER_LAYOUTS:
        return ""
    layout, fmt, which, index = OTHER_LAYOUTS[num_joints]
    take = (f"lifter.convert({name}{index}, src=\"{fmt}\")" if name is not None else
            f"write those 17 with \"format\": \"{fmt}\"")
    return f"; {num_joints} joints is {layout}? {which[0].upper() + which[1:]} are {fmt}'s: {take}"


MEDIAPIPE_XY_NOTE: str = "MediaPipe's x, y are fractions of the image: multiply by its width and height"
"""Said with each hint that rows of 4 values may be MediaPipe's (x, y, z, visibility) (here and in
:mod:`lifter.io`)."""


def _has_mask(x: Any) -> bool:
    """Whether ``x`` is a numpy masked array, or a list of them, with a value masked."""
    parts = x if isinstance(x, (list, tuple)) else [x]
    return any(isinstance(v, np.ma.MaskedArray) and bool(np.ma.getmaskarray(v).any()) for v in parts)


def as_points(x: Any, *, name: str, dim: int, num_joints: int | None = 17) -> np.ndarray:
    """Return ``x`` as a float64 array of shape ``(..., num_joints, dim)`` or raise a clear error.
    Torch tensors are accepted (detached and copied to the CPU)."""
    arr = _real_array(x, name=name, what="a numeric array")
    expected = f"(..., {num_joints if num_joints is not None else 'J'}, {dim})"
    if arr.ndim < 2 or arr.shape[-1] != dim or (num_joints is not None and arr.shape[-2] != num_joints):
        hint = ""
        if dim == 2 and arr.ndim >= 2 and arr.shape[-1] == 3:
            hint = f"; if the third column is a detector confidence, pass {name}[..., :2]"
        elif num_joints is not None and arr.ndim >= 2 and arr.shape[-2:] == (dim, num_joints):
            hint = f"; transposed? pass {name}.swapaxes(-1, -2) (one row of {dim} coordinates per joint)"
        elif dim == 2 and arr.ndim >= 2 and arr.shape[-1] == 4:
            hint = (f"; 4 columns (MediaPipe's x, y, z, visibility?): pass the pixel coordinates {name}[..., :2] "
                    f"({MEDIAPIPE_XY_NOTE})")
        elif num_joints == 17 and arr.ndim >= 2 and arr.shape[-1] == dim and arr.shape[-2] in _OTHER_FORMATS:
            fmts = " or ".join(f'src="{f}"' for f in _OTHER_FORMATS[arr.shape[-2]])
            hint = (f"; {arr.shape[-2]} joints is another detector's layout: convert it to Human3.6M's 17 with "
                    f"lifter.convert({name}, {fmts}) first")
        elif num_joints == 17 and arr.ndim >= 2 and arr.shape[-1] == dim:
            hint = other_layout_hint(arr.shape[-2], name=name)
        raise PoseLifterError(f"{name}: expected shape {expected}, got {tuple(arr.shape)}{hint}")
    if not np.all(np.isfinite(arr)):
        bad_joint = np.asarray(~np.isfinite(arr).all(-1))
        which = _joint_labels(bad_joint)
        where = where_in_batch(bad_joint.any(-1))
        fix = (" A joint the detector missed has to be filled in (from a neighbouring frame, or its left/right "
               "partner) or the pose left out" if dim == 2 else "")
        masked = " or are masked" if _has_mask(x) else ""
        raise PoseLifterError(
            f"{name}: joint(s) {which} contain NaN/inf{masked}{where}; every joint needs a finite position.{fix}")
    return arr


def check_finite(arr: np.ndarray, *, name: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise PoseLifterError(f"{name}: contains {bad} NaN/inf value(s); all values must be finite")


def as_pair(x: Any, *, name: str, positive: bool = False, scalar: bool = False,
            lead: tuple[int, ...] | None = None) -> np.ndarray:
    """Return a 2-vector (optionally batched, shape ``(..., 2)``) as float64 ``(..., 2)``. scalar: a scalar (or a
    last axis of 1) means the same value twice (a focal length ``fx = fy``); otherwise it is refused (a principal
    point or image size needs both coordinates). lead: the keypoints' leading shape, for the messages."""
    arr = _real_array(x, name=name, what="a number or pair" if scalar else "a pair")
    if scalar and arr.ndim == 0:
        arr = np.stack([arr, arr])
    elif scalar and arr.shape[-1] == 1:
        arr = np.concatenate([arr, arr], axis=-1)
    if arr.shape[-2:] == (3, 3) and np.allclose(arr[..., 2, :], [0.0, 0.0, 1.0]):
        raise PoseLifterError(f"{name}: got a 3 x 3 camera matrix K; pass its entries: focal=(K[0, 0], K[1, 1]) and "
                              "principal_point=(K[0, 2], K[1, 2]), px")
    if arr.ndim == 0 or arr.shape[-1] != 2:
        pair = "(width, height)" if "size" in name else "(x, y)"
        expected = "a scalar or shape (..., 2)" if scalar else f"a pair {pair} or shape (..., 2)"
        hint = (f" (one value per pose: give shape {tuple(arr.shape) + (1,)}, e.g. {name}[..., None]; a bare (2,) "
                "always means (fx, fy))" if scalar and arr.ndim >= 1 and arr.shape[-1] > 2 else "")
        if hint and lead is not None and len(lead) >= 2 and arr.ndim == 1 and arr.shape[0] in (lead[0], lead[-1]):
            # (a developer trial: for poses (B, T, 17, 2) the hint's focal[:, None] was taken per frame, silently
            # so where B == T)
            ways = ([f"one per index of the first axis (each sequence) is shape {lead[:1] + (1,) * len(lead)}, e.g. "
                     f"{name}[:{', None' * len(lead)}]"] if arr.shape[0] == lead[0] else []) + (
                [f"one per index of the last axis is shape ({lead[-1]}, 1), e.g. {name}[:, None]"]
                if arr.shape[0] == lead[-1] else [])
            hint = f" (the keypoints' leading shape is {lead}: {'; '.join(ways)}; a bare (2,) always means (fx, fy))"
        raise PoseLifterError(f"{name}: expected {expected}, got "
                              f"{arr.tolist() if arr.size <= 4 else tuple(arr.shape)}{hint}")
    check_finite(arr, name=name)
    if positive and np.any(arr <= 0):
        raise PoseLifterError(f"{name}: must be > 0, got {arr.tolist() if arr.size <= 8 else 'non-positive values'}")
    return arr


def input_warnings(keypoints: np.ndarray, focal: np.ndarray | None, *, focal_given: bool = True,
                   placeholders: bool = True, focal_from_exif: bool = False) -> list[str]:
    """What looks wrong in 2D keypoints ``(..., 17, 2)`` px that the lifter takes anyway (finite, checked shape):
    a pose spanning more than :data:`lifter.camera.MAX_PLAUSIBLE_VIEW_DEG` of view at ``focal`` (scalar or
    ``(..., 2)`` px; None: not checked), usually a focal length in mm; a joint at exactly (0, 0) far from the rest
    of its pose, usually a detector's placeholder for a missing joint. One message per kind, naming the first
    pose. focal_given: False when ``focal`` was assumed (from the image size or EXIF), which changes the advice;
    focal_from_exif: it was read from a photo's EXIF (a developer trial's note said "assumed" of an EXIF focal).
    placeholders: False when the (0, 0) joints were already said in the keypoints' own format
    (:func:`lifter.keypoints.placeholder_notes`), whose advice fits a file better.
    :meth:`lifter.Lifter.lift` warns with these (:class:`PoseLifterWarning`)."""
    from .camera import MAX_PLAUSIBLE_VIEW_DEG, focal_alpha, pose_view_deg, view_deg_text

    notes: list[str] = []
    k = np.asarray(keypoints, np.float64)
    if k.size == 0:
        return notes
    lead = k.shape[:-2]

    if focal is not None:
        # (the box diagonal against 2 alpha tan(view / 2) first: the angles only when something is wide)
        ext = k.max(-2) - k.min(-2)
        alpha = focal_alpha(focal)
        limit = 2.0 * alpha * math.tan(math.radians(MAX_PLAUSIBLE_VIEW_DEG) / 2.0)
        if np.any(ext[..., 0] ** 2 + ext[..., 1] ** 2 > limit**2):
            view = pose_view_deg(k, focal)
            wide = view > MAX_PLAUSIBLE_VIEW_DEG
            if np.any(wide):  # (quoted: the widest pose and its own focal length)
                widest = np.unravel_index(int(np.argmax(view)), view.shape) if lead else ()
                alpha_w = float(np.broadcast_to(alpha, lead)[widest])
                notes.append(f"at the focal length used ({alpha_w:.4g} px) a 2D pose spans "
                             f"{view_deg_text(np.max(view))} deg of view (a whole person rarely spans more than "
                             f"{MAX_PLAUSIBLE_VIEW_DEG:.0f} deg, even through an ultra-wide lens)"
                             f"{where_in_batch(wide)}: " + (
                                 "is the focal length in pixels? (f_px = f_mm * image width px / sensor width mm; or "
                                 "leave it out to assume a field of view)" if focal_given else
                                 "the focal length was read from the photo's EXIF, not given: is the EXIF right, and "
                                 "are the keypoints in this image's pixels? (or give the true focal length in pixels)"
                                 if focal_from_exif else
                                 "the focal length was assumed, not given: are the keypoints in this image's pixels? "
                                 "(or give the true focal length in pixels)"))
    if focal is not None:
        fxy = np.asarray(focal, np.float64)
        if fxy.ndim and fxy.shape[-1] == 2:
            aspect = fxy[..., 0] / fxy[..., 1]
            odd = (aspect > MAX_FOCAL_ASPECT) | (aspect < 1.0 / MAX_FOCAL_ASPECT)
            if np.any(odd):
                i = np.unravel_index(int(np.argmax(np.abs(np.log(aspect)))), aspect.shape) if aspect.ndim else ()
                fx, fy = (float(v) for v in fxy[i])
                notes.append(f"focal (fx, fy) = ({fx:g}, {fy:g}) px: fx / fy = {fx / fy:.3g}, where a camera's "
                             "pixels are square to within a few % (fx close to fy); a (2,) focal always means "
                             "(fx, fy): for one focal length per pose give shape (n, 1) or (n, 2)")
    placeholder = zero_placeholders(k) if placeholders else np.zeros(k.shape[:-1], bool)
    far = np.asarray(placeholder.any(-1))
    if np.any(far):
        notes.append(f"joint(s) {_joint_labels(placeholder)} at exactly (0, 0) px, far from the rest of the pose"
                     f"{where_in_batch(far)}: a "
                     "detector's placeholder for a missing joint? It is lifted as a real position; fill it in "
                     "(from a neighbouring frame, or its left/right partner) or leave the pose out")
    return notes


MAX_FOCAL_ASPECT: float = 1.25
"""A focal length whose fx / fy lies outside [1 / this, this] is noted (:func:`input_warnings`): real pixels are
square to within a few per cent."""


def _joint_labels(mask: np.ndarray, names: Sequence[str] | None = None) -> list[str] | list[int]:
    """The joints flagged anywhere in a mask ``(..., J)``: by ``names`` (default: H36M's for 17 joints), else
    indices."""
    from .skeleton import JOINT_NAMES

    joints = np.flatnonzero(mask.reshape(-1, mask.shape[-1]).any(0))
    if names is None and mask.shape[-1] == len(JOINT_NAMES):
        names = JOINT_NAMES
    return [names[int(j)] for j in joints] if names is not None else [int(j) for j in joints]


def zero_placeholders(keypoints: np.ndarray) -> np.ndarray:
    """Which joints ``(..., J)`` of 2D keypoints ``(..., J, 2)`` px lie at exactly (0, 0) far from the rest of their
    pose (the pose's other joints' centre is more than 3 times their RMS radius from the origin): a detector's usual
    placeholder for a missing joint."""
    k = np.asarray(keypoints, np.float64)
    zero = (k == 0.0).all(-1)  # (..., J)
    if not np.any(zero):
        return zero
    n_other = np.maximum((~zero).sum(-1, keepdims=True), 1)
    centre = np.where(zero[..., None], 0.0, k).sum(-2) / n_other
    radius = np.sqrt((np.where(zero[..., None], 0.0, (k - centre[..., None, :]) ** 2)).sum((-2, -1))
                     / n_other[..., 0])
    far = (np.hypot(*np.moveaxis(centre, -1, 0)) > 3.0 * radius) & (zero.sum(-1) < k.shape[-2])
    return zero & far[..., None]


MIN_PLAUSIBLE_VIEW_DEG: float = 1.0
"""A focal length that gives the image a diagonal field of view narrower than this gets a note
(:func:`view_angle_notes`): a 2000 mm lens on a full-frame camera still sees 1.2 deg."""
MAX_PLAUSIBLE_IMAGE_VIEW_DEG: float = 150.0
"""A focal length that gives the image a diagonal field of view wider than this gets a note
(:func:`view_angle_notes`): the widest phone ultra-wides see about 120 deg, and a pinhole camera never 180."""


def mostly_outside(keypoints: np.ndarray, image_size: Any) -> np.ndarray:
    """Which 2D poses ``(..., J, 2)`` px lie mostly (more than half their joints) outside their image ``image_size``
    (``(W, H)`` px, one for all or ``(..., 2)`` one per pose; a joint on the border is inside): ``(...)`` bool."""
    return joints_outside(keypoints, image_size).mean(-1) > 0.5


def joints_outside(keypoints: np.ndarray, image_size: Any) -> np.ndarray:
    """Which joints of 2D poses ``(..., J, 2)`` px lie outside their image ``image_size`` (:func:`mostly_outside`):
    ``(..., J)`` bool."""
    k = np.asarray(keypoints, np.float64)
    wh = np.broadcast_to(np.asarray(image_size, np.float64), k.shape[:-2] + (2,))  # (one size per pose)
    return np.any((k < 0) | (k > wh[..., None, :]), axis=-1)


CUT_OFF_TAIL = ("the detector guesses the joints it cannot see, so the 2D there, and the lift, its depth most of all, "
                "are less sure")
"""How the notes on detected people cut off by the image's edge end (photos:
:func:`lifter.pipeline.detected_edge_notes`; videos: :func:`lifter.video.track_edge_notes`)."""


def joints_outside_text(outside: np.ndarray, *, most: int = 3) -> str:
    """The joints most often outside the image in ``outside`` ``(..., 17)`` bool (:func:`joints_outside` of one or
    more 2D poses), at most ``most`` named: ``"r_knee, r_ankle and 2 more placed outside the image"``."""
    from .skeleton import JOINT_NAMES

    counts = np.asarray(outside).reshape(-1, len(JOINT_NAMES)).sum(0)
    joints = sorted(np.flatnonzero(counts), key=lambda j: (-int(counts[j]), int(j)))
    more = f" and {len(joints) - most} more" if len(joints) > most else ""
    return ", ".join(JOINT_NAMES[j] for j in joints[:most]) + more + " placed outside the image"


def outside_image_notes(keypoints: np.ndarray, image_size: Any, *, detected: bool = False,
                        name_pose: bool = False) -> list[str]:
    """A note when 2D poses ``(..., 17, 2)`` px lie mostly (more than half their joints) outside their image
    ``image_size`` (``(W, H)`` px, one for all or ``(..., 2)`` one per pose; None: not checked): keypoints in
    another image's pixels (a full-size photo's with its thumbnail's size), whose root is then wrong. detected:
    the 2D is this package's detector's (a person cut off by the frame), which changes the advice. Used by
    :meth:`lifter.Lifter.lift` (``name_pose``: the first such pose's index, :func:`where_in_batch`) and
    :func:`lifter.pipeline.plausibility_notes`."""
    if image_size is None:
        return []
    k = np.asarray(keypoints, np.float64)
    if k.size == 0:
        return []
    wh = np.broadcast_to(np.asarray(image_size, np.float64), k.shape[:-2] + (2,))
    outside = joints_outside(k, wh)
    mostly = outside.mean(-1) > 0.5
    if not np.any(mostly):
        return []
    first = np.unravel_index(int(np.argmax(mostly)), mostly.shape) if mostly.ndim else ()
    W, H = (int(v) for v in wh[first])
    n = f"{int(mostly.sum())} of {int(mostly.size)} 2D pose(s)"
    at = where_in_batch(mostly) if name_pose else ""
    # (the others with a joint outside too: a user trial read "4 of 40" as marginal where all 40 had)
    partly = int(np.sum(outside.any(-1) & ~mostly))
    more = f", and {partly} more with some joints outside it" if partly else ""
    return [f"the detector placed most joints of {n} outside the {W} x {H} px image (a person cut off by the frame, "
            "or half-invented): their 3D is uncertain" if detected else
            f"{n} lie mostly outside the {W} x {H} px image{at}{more}: are the keypoints in this image's pixels?"]


def view_angle_notes(focal: Any, image_size: tuple[int, int] | None, *, from_exif: bool = False) -> list[str]:
    """A note when the focal length ``focal`` (px, scalar or ``(fx, fy)``) gives the ``image_size`` image a diagonal
    field of view narrower than :data:`MIN_PLAUSIBLE_VIEW_DEG` or wider than :data:`MAX_PLAUSIBLE_IMAGE_VIEW_DEG`
    (None: not checked): a focal length in other pixels or units, or a typo (a user trial's 100000 px on a 1000 px
    image placed a person at 438 m with only a note about the distance; a developer trial's 26 mm phone focal on a
    4000 x 3000 px photo, a small person near its centre, went unnoticed). The depth is proportional to the focal
    length. from_exif: the focal length was read from the photo's EXIF (a developer trial's EXIF gave 114 px for a
    1000-px image, with no such note), whose advice differs."""
    if image_size is None:
        return []
    from .camera import focal_alpha

    alpha = float(focal_alpha(np.asarray(focal, np.float64).reshape(-1)))
    if not (math.isfinite(alpha) and alpha > 0):  # (a focal that small is refused elsewhere, naming MIN_FOCAL_PX)
        return []
    W, H = image_size
    fov = math.degrees(2.0 * math.atan(math.hypot(W, H) / (2.0 * alpha)))
    which = "the EXIF's focal length" if from_exif else "the focal length"
    if fov > MAX_PLAUSIBLE_IMAGE_VIEW_DEG:
        return [f"{which} {alpha:.6g} px gives this {W} x {H} px image a field of view of {fov:.0f} deg "
                "(diagonal), wider than any camera's without a fisheye lens (the widest phone ultra-wides: about "
                "120 deg): " + ("the photo's EXIF is probably wrong (its focal-plane resolution or sensor size): "
                                "give the focal length in px." if from_exif else
                                "is it in mm, not px (f_px = f_mm * image width px / sensor width mm)?")
                + " Every depth is proportional to it"]
    if not fov < MIN_PLAUSIBLE_VIEW_DEG:
        return []
    return [f"{which} {alpha:.6g} px gives this {W} x {H} px image a field of view of {fov:.2g} deg "
            f"(diagonal), narrower than a 2000 mm telephoto lens's on a full-frame camera (1.2 deg): "
            + ("the photo's EXIF is probably wrong (its focal-plane resolution or sensor size): give the focal length "
               "in px." if from_exif else
               "is it in this image's pixels (f_px = f_mm * image width px / sensor width mm)?")
            + " Every depth is proportional to it"]


PRINCIPAL_POINT_EDGE: float = 0.05
"""A principal point within this share of the image's width / height of its edge, or outside it, gets a note."""


def principal_point_notes(pp: Any, image_size: tuple[int, int] | None) -> list[str]:
    """A note when the principal point ``pp`` ``(cx, cy)`` px lies outside the ``image_size`` image or within
    :data:`PRINCIPAL_POINT_EDGE` of its edge (None: not checked): a camera's principal point lies near the image
    centre, and only a crop moves it far; the image size given as the principal point is a common slip. Every
    root then lies off to the side by as much (mm, at its depth)."""
    if image_size is None:
        return []
    W, H = image_size
    c = np.asarray(pp, np.float64).reshape(-1)
    e = PRINCIPAL_POINT_EDGE
    if e * W <= c[0] <= (1 - e) * W and e * H <= c[1] <= (1 - e) * H:
        return []
    slip = " (it equals the image size: was that given as the principal point?)" if np.allclose(c, (W, H)) else ""
    where = "at the edge of" if 0 <= c[0] <= W and 0 <= c[1] <= H else "outside"
    return [f"the principal point ({c[0]:g}, {c[1]:g}) px lies {where} the {W} x {H} px image{slip}; unless the "
            f"image is a crop, a camera's lies near the centre ({W / 2:g}, {H / 2:g}), and a wrong one moves every "
            "root sideways (by its error in px x depth / focal). Give the calibrated one, or leave it out to use the "
            "centre"]


def _most(flags: np.ndarray) -> bool:
    """Whether more than half of a batch's poses are flagged (False for an empty batch): the batch-wide notes
    (:func:`upside_down_notes`, :func:`face_first_notes`) speak of the input as a whole, not of an odd pose."""
    return bool(len(flags)) and float(flags.mean()) > 0.5


def upside_down_notes(kp17: np.ndarray) -> list[str]:
    """A note when most of the poses ``(n, 17, 2)`` px (H36M order) are upright bodies upside down (taller than wide,
    the head below both ankles by more than half the pose's height; a joint at (0, 0) gives no reading) in the image:
    the 2D then likely has its y axis pointing up, where this package expects image y to grow downward (OpenCV);
    a handstand looks the same, hence a note, not an error."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    down = upside_down_people(k)
    if not _most(down):
        return []
    return [f"the head is below both ankles in {int(down.sum())} of {len(k)} pose(s): this package takes image y "
            "growing downward (OpenCV, +y down); if your keypoints' y grows upward, give y' = image height - y "
            "(an upside-down person, e.g. a handstand, is lifted as given)"]


def sideways_notes(kp17: np.ndarray) -> list[str]:
    """A note when most of the poses ``(n, 17, 2)`` px (H36M order) lie sideways in the image
    (:func:`sideways_people`): keypoints given as (row, column) = (y, x), as image arrays index them, look so (a
    developer trial: an upright person's (y, x) was lifted 1.6 m off without a word); so does a person lying down,
    hence a note, not an error."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    side = sideways_people(k)
    if not _most(side):
        return []
    return [f"the body lies sideways in {int(side.sum())} of {len(k)} pose(s) (head and ankles apart along the "
            "image's x, the pose wider than tall): this package takes keypoints as (x, y) = (column, row); if yours "
            "are (row, column), as image arrays index them, give keypoints[..., ::-1] (a person lying down is lifted "
            "as given, a pose rare in the training data)"]


def sideways_people(kp17: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: which of the poses ``(n, 17, 2)`` px (H36M order) lie sideways in the image: wider than tall,
    the head top and the ankles' midpoint apart along x by more than half the pose's width and more than twice as
    far as along y (a joint at (0, 0), a detector's placeholder, gives no reading)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    h, ra, la = _HEAD_TOP, _R_ANKLE, _L_ANKLE
    x = k[..., 0]
    x_ext = x.max(1) - x.min(1)
    dx = np.abs(x[:, h] - 0.5 * (x[:, ra] + x[:, la]))
    side = dx > 0.5 * x_ext  # (first: cheap, and rarely true)
    if side.any():  # (the rest only where it can matter: lift runs this on every batch)
        sub = k[side]
        dy = np.abs(sub[:, h, 1] - 0.5 * (sub[:, ra, 1] + sub[:, la, 1]))
        side[side] = ((x_ext[side] > sub[..., 1].max(1) - sub[..., 1].min(1)) & (dx[side] > 2.0 * dy)
                      & ~zero_placeholders(sub)[:, [h, ra, la]].any(1))
    return side


LEAN_NOTE_DEG: float = 35.0
"""A pose whose legs and torso both lean more than this (deg) the same way from the image's vertical
(:func:`body_lean_deg`) gets a note that the camera may be rolled (:func:`lean_notes`). ``python scripts/roll_lean.py``
(``docs/results/roll_lean.txt``; the default, exact 2D lifted as detected, S9 + S11 every 50th frame): 0.1 % of the
poses of upright cameras are named (people sitting on the floor), 3 % at a roll of 30 deg, 66 % at 45 deg and 58 % at
60 deg (many others there get the sideways note), where the root is 0.49, 0.81 and 0.89 m off (0.17 upright); the
roots of the poses named at 30, 45 and 60 deg, 0.67, 0.93 and 0.99 m off as given, are 0.17, 0.16 and 0.17 m off
turned upright by their own lean as the note says."""


LEAN_STRAIGHT_DEG: float = 20.0
"""The legs and the torso of a pose the lean note names lie within this angle (deg) of each other: a straight body, as
a standing or walking person turned by a rolled camera is (people bending or sitting are not: without this rule 0.4 %
of Human3.6M's poses were named on upright cameras, against 0.1 %)."""


def _lean_vectors(k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The legs (hips' midpoint to ankles' midpoint) and the torso (thorax to pelvis) of poses ``(n, 17, 2)``,
    ``(n, 2)`` each: the two axes the lean reads."""
    return 0.5 * (k[:, _R_ANKLE] + k[:, _L_ANKLE] - k[:, _R_HIP] - k[:, _L_HIP]), k[:, _PELVIS] - k[:, _THORAX]


def _lean_angles(k: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The legs' and the torso's angles (deg) from the image's +y of poses ``(n, 17, 2)``, + toward +x (NaN where a
    joint is), and the signed lean they give: the smaller of the two where they lean the same way, else 0."""
    legs, torso = _lean_vectors(k)
    a, b = np.degrees(np.arctan2(legs[:, 0], legs[:, 1])), np.degrees(np.arctan2(torso[:, 0], torso[:, 1]))
    with np.errstate(invalid="ignore"):
        return a, b, np.where(np.sign(a) == np.sign(b), np.sign(a) * np.minimum(np.abs(a), np.abs(b)), 0.0)


def _lean_readable(k: np.ndarray) -> np.ndarray:
    """``(n,)``: where the lean of poses ``(n, 17, 2)`` can be read: its joints there (finite, not at (0, 0): a
    detector's placeholder), and the legs and torso each at least a tenth of the pose's size (box diagonal; a short
    one's angle says little)."""
    used = [_PELVIS, _R_HIP, _L_HIP, _R_ANKLE, _L_ANKLE, _THORAX]
    if not len(k):
        return np.zeros(0, bool)
    legs, torso = _lean_vectors(k)
    finite = np.isfinite(k).all(-1, keepdims=True)
    with np.errstate(invalid="ignore"):  # (np.nanmax of an all-NaN pose warns: a review)
        size = np.linalg.norm(np.where(finite, k, -np.inf).max(1) - np.where(finite, k, np.inf).min(1), axis=-1)
        return (np.isfinite(k[:, used]).all((1, 2)) & ~zero_placeholders(k)[:, used].any(1)
                & (np.linalg.norm(legs, axis=-1) >= 0.1 * size) & (np.linalg.norm(torso, axis=-1) >= 0.1 * size))


def body_lean_deg(kp17: np.ndarray) -> np.ndarray:
    """``(n,)`` deg: how far each pose ``(n, 17, 2)`` px (H36M order, image y down) leans from the image's vertical,
    signed: the smaller of the legs' (hips' midpoint to ankles' midpoint) and the torso's (thorax to pelvis) angles
    from +y, + where the lower end lies toward +x; 0 where the two lean opposite ways or the lean cannot be read (a
    joint missing: non-finite, or at (0, 0), a detector's placeholder; a leg or torso shorter than a tenth of the
    pose). A camera rolled by ``r`` (:func:`lifter.camera.camera_turn`'s third angle, + clockwise seen from behind the
    camera) leans an upright body by about ``+r``."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    return np.where(_lean_readable(k), _lean_angles(k)[2], 0.0)


def leaning_people(kp17: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: which poses ``(n, 17, 2)`` px lean more than :data:`LEAN_NOTE_DEG` (:func:`body_lean_deg`; less
    than 90 deg: beyond, the body is upside down, that note's) with a straight body (legs and torso within
    :data:`LEAN_STRAIGHT_DEG`) and do not lie sideways (:func:`sideways_people`, which has its own note)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    x, y = _lean_vectors(k)[0].T  # (the legs first, cheap: lift runs this on every batch; NaN: False)
    with np.errstate(invalid="ignore"):
        out = (y > 0.0) & (x * x > math.sin(math.radians(LEAN_NOTE_DEG)) ** 2 * (x * x + y * y))
    if not out.any():
        return out
    sub = k[out]  # (the rest only where it can matter)
    a, b, lean = _lean_angles(sub)
    lean = np.abs(lean)
    with np.errstate(invalid="ignore"):
        out[out] = ((lean > LEAN_NOTE_DEG) & (lean < 90.0) & (np.abs(a - b) < LEAN_STRAIGHT_DEG)
                    & _lean_readable(sub) & ~sideways_people(sub))
    return out


ROLL_RECIPE: Final[str] = "turn the 2D upright about the principal point first (the README's 'Camera roll' recipe)"
"""How :func:`lean_text` says to undo a roll (the app names its readout's Caution, which says how for the sample shown:
rotate an uploaded photo, for one)."""


def lean_text(leans_deg: Any, *, recipe: str | None = None) -> str:
    """The advice of a lean note for the signed leans ``leans_deg`` (deg, :func:`body_lean_deg`) of the poses it
    names: the roll to undo is named where they lean the same way (a review: opposite leans named "about -0 deg").
    A camera tilted steeply down leans people near the image's sides too, and undoing a roll that was never there
    makes their lift worse (a review: 289 -> 546 mm), hence the proviso. ``recipe``: how to undo it, in place of
    :data:`ROLL_RECIPE` and the roll (the app: rotate the photo)."""
    v = np.atleast_1d(np.asarray(leans_deg, np.float64))
    same = bool(np.all(v > 0) or np.all(v < 0))
    roll = f"by a roll of about {float(np.median(v)):+.0f} deg, or by the camera's own" if same else \
        "by the camera's own roll"
    return ("if the camera was rolled (a slanted hand-held photo), the lift is off: the default is trained on upright "
            f"cameras, and a roll of 45 deg puts the root about 0.8 m off; {recipe or f'{ROLL_RECIPE}, {roll}'}; but a "
            "camera tilted steeply down leans people "
            "near the image's sides as well, with no roll to undo, and a person sitting or lying on the floor is "
            "lifted as given")


def lean_notes(kp17: np.ndarray) -> list[str]:
    """A note when most of the poses ``(n, 17, 2)`` px lean as a rolled camera leans them (:func:`leaning_people`):
    a developer trial's photos turned 30-60 deg were lifted a metre off without a word (the sideways note begins
    near 65 deg)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    lean = leaning_people(k)
    if not _most(lean):
        return []
    deg = body_lean_deg(k[lean])
    return [f"the body leans {float(np.median(np.abs(deg))):.0f} deg from the image's vertical in {int(lean.sum())} "
            f"of {len(k)} pose(s) (legs and torso alike): {lean_text(deg)}"]


def upside_down_people(kp17: np.ndarray) -> np.ndarray:
    """``(n,)`` bool: which of the poses ``(n, 17, 2)`` px (H36M order, image y down) are upright bodies upside down
    in the image: taller than wide, the head below both ankles by more than half the pose's height (a person lying
    down, head a little lower than the feet, is not; a joint at (0, 0), a detector's placeholder, gives no reading)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    h, ra, la = _HEAD_TOP, _R_ANKLE, _L_ANKLE
    y = k[..., 1]
    y_ext = y.max(1) - y.min(1)
    down = y[:, h] - np.maximum(y[:, ra], y[:, la]) > 0.5 * y_ext  # (first: cheap, and rarely true)
    if down.any():  # (the rest only where it can matter: lift runs this on every batch)
        x = k[down, :, 0]
        down[down] = (y_ext[down] > x.max(1) - x.min(1)) & ~zero_placeholders(k[down])[:, [h, ra, la]].any(1)
    return down


COCO_FACE_SPREAD: float = 0.12
"""A 17-joint pose whose first five points lie within this share of its 2D size (box diagonal) of each other has
COCO-17's face first (nose, eyes, ears), not H36M's pelvis, hips, right knee and foot (:func:`face_first_people`).
Measured: BlazePose's nose, eyes and ears on the 84 Human3.6M photos span at most 0.077; H36M's first five, on every
10th frame of every Human3.6M subject and camera (200k poses), at least 0.214."""


def face_first_people(kp17: np.ndarray, missing: np.ndarray | None = None) -> np.ndarray:
    """``(n,)`` bool: which of the 17-joint poses ``(n, 17, 2)`` px start with five points as close together as a
    face's (:data:`COCO_FACE_SPREAD`): COCO-17 order given where H36M order was meant. ``missing`` ``(n, 17)``: the
    joints that are not there (None: the non-finite ones and (0, 0) placeholders, :func:`zero_placeholders`);
    False where too few joints are there to tell (fewer than 4 of the first five, or than 10 of all)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    if missing is None:  # (first over every joint, cheap: lift runs this on every batch; then where it can matter)
        x, y = k[..., 0], k[..., 1]  # (a reduction over the joints of (n, 17, 2) as a whole is 15 x slower)
        zero = (x == 0) & (y == 0)
        if zero.any():  # (a hidden ear at (0, 0) leaves four face points: left out here, NaN, which fmax skips)
            x, y = np.where(zero, np.nan, x), np.where(zero, np.nan, y)
        hx, hy = x[:, :5], y[:, :5]
        hi, lo = np.fmax.reduce, np.fmin.reduce
        with np.errstate(invalid="ignore", over="ignore"):
            maybe = (np.square(hi(hx, 1) - lo(hx, 1)) + np.square(hi(hy, 1) - lo(hy, 1))
                     < COCO_FACE_SPREAD**2 * (np.square(hi(x, 1) - lo(x, 1)) + np.square(hi(y, 1) - lo(y, 1))))
        if not maybe.any():
            return maybe
        out = np.zeros(len(k), bool)
        sub = k[maybe]
        out[maybe] = face_first_people(sub, ~np.isfinite(sub).all(-1) | zero_placeholders(sub))
        return out
    with np.errstate(invalid="ignore"):
        return face_spread(k, missing) < COCO_FACE_SPREAD  # (NaN: cannot tell, False)


NOT_A_FACE_SPREAD: float = 0.2
"""A 17-joint pose given as COCO-17 whose first five points spread over at least this share of its 2D size (box
diagonal) does not start with a face (BlazePose's nose, eyes and ears on the 84 Human3.6M photos: at most 0.077) but
likely with H36M's pelvis, hips, right knee and right foot (at least 0.214 on 200k Human3.6M poses;
:data:`COCO_FACE_SPREAD`): H36M order given as COCO-17 (:func:`not_face_first_message`)."""


def face_spread(kp17: np.ndarray, missing: np.ndarray | None = None) -> np.ndarray:
    """``(n,)``: how far the first five points of each 17-joint pose ``(n, 17, 2)`` px spread, as a share of the
    pose's 2D size (box diagonals): under :data:`COCO_FACE_SPREAD` for COCO-17's face, over
    :data:`NOT_A_FACE_SPREAD` for H36M's first five. ``missing`` ``(n, 17)``: the joints that are not there (None:
    the non-finite ones and (0, 0) placeholders); NaN where too few are there to tell (fewer than 4 of the first
    five, or than 10 of all)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    if missing is None:
        missing = ~np.isfinite(k).all(-1) | zero_placeholders(k)
    ok = ~np.asarray(missing, bool).reshape(-1, 17)
    enough = (ok[:, :5].sum(1) >= 4) & (ok.sum(1) >= 10)

    def diagonal(pts: np.ndarray, there: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore", over="ignore"):
            lo = np.where(there[..., None], pts, np.inf).min(1)
            hi = np.where(there[..., None], pts, -np.inf).max(1)
            return np.hypot(*np.moveaxis(hi - lo, -1, 0))

    size, spread = diagonal(k, ok), diagonal(k[:, :5], ok[:, :5])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        return np.where(enough & np.isfinite(size) & (size > 0), spread / size, np.nan)


def not_face_first_message(kp17: np.ndarray) -> str | None:
    """What to say of poses ``(n, 17, 2)`` px given as COCO-17 when each that can be told starts with five points
    spread as H36M's pelvis, hips, right knee and right foot are (:data:`NOT_A_FACE_SPREAD`), not as a face: H36M
    order given as COCO-17, which converting would scramble (a developer trial: lifted without a word but a misfit
    note blaming the detector, the root at 55 % of its depth). None when any pose looks like COCO-17, or none can
    be told."""
    spread = face_spread(kp17)
    told = spread[np.isfinite(spread)]
    if not len(told) or float(told.min()) < NOT_A_FACE_SPREAD:
        return None
    which = "the pose" if len(told) == 1 else f"each of {len(told)} poses"
    return (f"format 'coco17', but the first five joints of {which} spread over {float(told.min()) * 100:.0f} % "
            f"or more of {'its' if len(told) == 1 else 'their'} 2D size, as H36M's pelvis, hips, right knee and "
            f"right foot do (COCO-17's nose, eyes and ears lie within {COCO_FACE_SPREAD * 100:.0f} %): H36M-order "
            "keypoints?")


def face_first_notes(kp17: np.ndarray) -> list[str]:
    """A note when most of the poses ``(n, 17, 2)`` px given as H36M order start with a face
    (:func:`face_first_people`): COCO-17 keypoints passed to :meth:`lifter.Lifter.lift` without converting them
    (lifted as if the nose were the pelvis: a user trial's root came out at 39 % of its depth)."""
    k = np.asarray(kp17, np.float64).reshape(-1, 17, 2)
    face = face_first_people(k)
    if not _most(face):
        return []
    return [f"the first five joints of {int(face.sum())} of {len(k)} pose(s) lie within {COCO_FACE_SPREAD * 100:.0f} % "
            "of their 2D size of each other, as COCO-17's nose, eyes and ears do (H36M's first five, the pelvis, "
            "hips, right knee and right foot, span the legs): lift takes H36M-17 order; convert COCO-17 keypoints "
            "first, lifter.convert(keypoints, src=\"coco17\") (the depth and pose of unconverted ones are wrong)"]


_HEAD_TOP, _R_ANKLE, _L_ANKLE = 10, 3, 6
"""H36M-17 indices of the head's top and the ankles (:data:`lifter.skeleton.JOINT_NAMES`; a test pins them)."""
_PELVIS, _R_HIP, _L_HIP, _THORAX = 0, 1, 4, 8
"""H36M-17 indices of the pelvis, the hips and the thorax (:data:`lifter.skeleton.JOINT_NAMES`; a test pins them)."""


class OutputNote(str):
    """A note on a lift's output (an entry of :attr:`LiftResult.warnings`): the text, and its ``kind``,
    ``"pixel-range"`` (a pixel-space network given 2D outside the sizes it was trained on), ``"far"`` (a detected
    person farther than the networks learned) or ``"behind-camera"`` (a root at Z <= 0), by which the video records
    count the frames that had it."""

    kind: str

    def __new__(cls, text: str, *, kind: str = "") -> OutputNote:
        note = super().__new__(cls, text)
        note.kind = kind
        return note


def collect_output_notes(acc: dict[str, tuple[int, int, str]], frame: int, notes: Any) -> None:
    """Gather :attr:`LiftResult.warnings` of one frame (a video frame; a batch of an evaluation) into ``acc``:
    one entry per kind of note (:attr:`OutputNote.kind`: a pixel model outside its trained sizes, roots behind
    the camera; any other note by its text), with its first frame and how many frames had it."""
    for note in notes:
        kind = getattr(note, "kind", note)
        first, n, message = acc.get(kind, (frame, 0, note))
        acc[kind] = (first, n + 1, message)


PLOT_FORMATS: tuple[str, ...] = ("png", "pdf", "svg")
"""The file formats a plot (:mod:`lifter.plots`) is written in, by its name's suffix."""


def plot_format(path: str | Path, *, option: str = "the plot") -> str:
    """The format of a plot written to ``path``, from its suffix (:data:`PLOT_FORMATS`); :class:`PoseLifterError`
    naming ``option`` for any other (a user trial's ``--pck-plot x.jpg`` got PNG data under a .jpg name)."""
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in PLOT_FORMATS:
        raise PoseLifterError(f"{option}: {Path(path).name} is not a name a plot can be written under: name it "
                              + ", ".join(f".{f}" for f in PLOT_FORMATS[:-1]) + f" or .{PLOT_FORMATS[-1]}")
    return fmt
