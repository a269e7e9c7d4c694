"""``poselifter lift``: photos or 2D keypoint files in, absolute 3D poses out.

Registered in :mod:`lifter.cli` by :func:`add_parser`. Usage::

    poselifter lift INPUT... [--focal FX [FY]] [--principal-point CX CY] --out DIR [--glb] [--bvh]

INPUT: image files, folders (their images and ``.json`` files, not recursive) or keypoint JSON files.
For every input it writes ``DIR/<name>.json`` (``<name>`` = the file name without its suffix; a
clash gets ``_<suffix>`` or a number appended) with ``keypoints_2d`` (17 x 2 px, H36M order),
``absolute`` (17 x 3 mm, camera frame: OpenCV, +x right, +y down, +z forward), ``relative``,
``root`` (3, mm), ``canonical_depth`` (mm at a 1000-px focal), ``focal`` (fx, fy px), ``focal_source``,
``principal_point`` (px), ``image_size``, ``warnings`` and, for images, the detector's per-joint
``scores`` and the number of people found; with ``--glb`` / ``--bvh`` also ``DIR/<name>.glb`` /
``.bvh`` (:mod:`lifter.export`).

Camera. ``--focal`` / ``--principal-point`` apply to every input. Otherwise, per input: a keypoint
file's own ``focal`` / ``principal_point``; for photos the EXIF focal length (focal in mm with the
sensor size from the focal-plane resolution or ``--sensor-width``, else the 35-mm equivalent); else
a diagonal field of view of ``--fov`` degrees (default 65, :data:`lifter.detect.DEFAULT_DIAGONAL_FOV_DEG`).
The principal point defaults to the image centre. See :func:`lifter.detect.focal_from_exif`.

Keypoint JSON files: an object ``{"keypoints": [[x, y], ...], "format": "coco17", "image_size": [W, H],
"focal": F or [FX, FY], "principal_point": [CX, CY]}`` (only ``keypoints`` is required; rows may have
a third value, a confidence, which is ignored; a flat ``[x0, y0, c0, x1, ...]`` list works too), a bare
list of ``[x, y]`` rows, OpenPose's output ``{"people": [{"pose_keypoints_2d": [...]}, ...]}`` (format
openpose25) or a COCO-style list of people ``[{"keypoints": [...]}, ...]``. Without ``format`` it is
inferred from the joint count (17: h36m17 unless ``--format`` says otherwise; 16: sh16; 25:
openpose25; 33: blazepose33). Several people: the largest (box area) is used, with a warning. A
keypoint file needs an image size, a principal point or ``--principal-point``. Camera fields must be
JSON numbers: ``image_size`` whole px in [1, 100000] (:data:`MAX_IMAGE_SIDE_PX`), ``focal`` in (0, 1e6) px,
``principal_point`` finite and below 1e6 px in magnitude; anything else fails that input with a message.

Bad input never stops the batch: each failure is reported as ``<input>: error: ...`` and the next
input is processed; a photo with several people uses the largest and says so; images larger than
``--max-side`` px are downscaled for detection. **Exit code**: 0 when at least one input was lifted,
1 when every input failed (or none was found), 2 for a usage error (bad arguments, no lifter weights).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final

import numpy as np

from ._checks import PoseLifterError, as_pair
from .detect import (DEFAULT_DIAGONAL_FOV_DEG, DEFAULT_MAX_SIDE_PX, IMAGE_SUFFIXES, LoadedImage,
                     MissingDependencyError, PoseEstimator2D, default_focal, detect_pose, focal_from_exif, load_image)
from .keypoints import H36M17, convert, get_format, keypoint_formats
from .skeleton import JOINT_NAMES

FORMAT_BY_COUNT: Final[dict[int, str]] = {17: H36M17, 16: "sh16", 25: "openpose25", 33: "blazepose33"}
"""Keypoint format assumed from the joint count when a JSON file names none."""


@dataclass(frozen=True)
class LiftRecord:
    """The result for one input; :meth:`to_json` is what ``DIR/<name>.json`` holds.

    keypoints_2d: ``(17, 2)`` px (H36M order); absolute, relative: ``(17, 3)`` mm camera frame;
    root: ``(3,)`` mm; canonical_depth: mm (at a 1000-px focal); focal: ``(fx, fy)`` px;
    principal_point: ``(cx, cy)`` px; image_size: ``(W, H)`` px or None; scores: ``(17,)`` or None.
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

    def to_json(self) -> dict[str, Any]:
        r = lambda a, d=2: np.round(np.asarray(a, np.float64), d).tolist()  # noqa: E731
        return {
            "input": self.input, "kind": self.kind, "model": self.model,
            "joint_names": list(JOINT_NAMES),
            "units": {"keypoints_2d": "px", "absolute": "mm", "relative": "mm", "root": "mm", "canonical_depth": "mm",
                      "focal": "px", "principal_point": "px"},
            "frame": "camera, OpenCV: +x right, +y down, +z forward; 2D in px of the upright full-resolution image",
            "keypoints_2d": r(self.keypoints_2d), "absolute": r(self.absolute), "relative": r(self.relative),
            "root": r(self.root), "canonical_depth": round(float(self.canonical_depth), 2),
            "focal": r(self.focal), "focal_source": self.focal_source, "principal_point": r(self.principal_point),
            "image_size": None if self.image_size is None else [int(v) for v in self.image_size],
            "source_format": self.source_format, "detector": self.detector, "num_people": self.num_people,
            "scores": None if self.scores is None else r(self.scores, 3), "warnings": list(self.warnings),
        }


# ------------------------------------------------------------------------------------------------
# Keypoint JSON files
# ------------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class KeypointFile:
    """A parsed keypoint JSON: ``keypoints (J, 2)`` px in ``format``; optional camera fields."""

    keypoints: np.ndarray
    format: str
    image_size: tuple[int, int] | None = None
    focal: np.ndarray | None = None
    principal_point: np.ndarray | None = None
    warnings: tuple[str, ...] = ()


def _rows(raw: Any, where: str) -> tuple[np.ndarray, np.ndarray | None]:
    """``(J, 2)`` px and optional ``(J,)`` confidences from ``[[x, y(, c)], ...]`` or a flat list."""
    try:
        a = np.asarray(raw, np.float64)
    except (TypeError, ValueError):
        raise PoseLifterError(f"{where}: 'keypoints' must be numbers") from None
    if a.ndim == 1:
        if a.size % 3 == 0 and (a.size // 3) in FORMAT_BY_COUNT:
            a = a.reshape(-1, 3)
        elif a.size % 2 == 0 and (a.size // 2) in FORMAT_BY_COUNT:
            a = a.reshape(-1, 2)
        else:
            raise PoseLifterError(f"{where}: a flat keypoint list of {a.size} numbers is not J x 2 or J x 3 for "
                                  f"J in {sorted(FORMAT_BY_COUNT)}")
    if a.ndim != 2 or a.shape[1] not in (2, 3):
        raise PoseLifterError(f"{where}: keypoints must be rows of [x, y] or [x, y, confidence], got shape {a.shape}")
    conf = a[:, 2] if a.shape[1] == 3 else None
    return a[:, :2], conf


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


def parse_keypoint_json(path: str | Path, *, default_format: str | None = None) -> KeypointFile:
    """Read a keypoint JSON file (module docstring). Raises :class:`PoseLifterError` with the reason."""
    p = Path(path)
    try:
        d = json.loads(p.read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise PoseLifterError(f"{p}: cannot read ({exc})") from None
    except json.JSONDecodeError as exc:
        raise PoseLifterError(f"{p}: not valid JSON ({exc})") from None
    notes: list[str] = []
    fmt = default_format
    people: list[Any]
    meta: dict[str, Any] = {}
    if isinstance(d, dict) and "people" in d:  # OpenPose output
        people = [q.get("pose_keypoints_2d") for q in d["people"] if isinstance(q, dict)]
        fmt = fmt or "openpose25"
    elif isinstance(d, list) and d and all(isinstance(q, dict) for q in d):  # COCO-style results
        people = [q.get("keypoints") for q in d]
        fmt = fmt or "coco17"
    elif isinstance(d, dict) and "keypoints" in d:
        people = [d["keypoints"]]
        meta = d
        fmt = d.get("format") or fmt
    elif isinstance(d, list):
        people = [d]
    else:
        raise PoseLifterError(f"{p}: expected an object with 'keypoints', a list of [x, y] rows, OpenPose "
                              "'people' or a list of people")
    people = [q for q in people if q is not None and len(q) > 0]
    if not people:
        raise PoseLifterError(f"{p}: no person in the keypoint file")
    parsed = []
    for q in people:
        xy, conf = _rows(q, str(p))
        missing = ~np.all(np.isfinite(xy), axis=1)
        if conf is not None:
            missing |= conf <= 0  # OpenPose / COCO mark undetected joints with confidence 0
        parsed.append((xy, missing))
    if len(parsed) > 1:
        def area(item: tuple[np.ndarray, np.ndarray]) -> float:
            xy, miss = item
            ok = xy[~miss]
            return 0.0 if len(ok) < 2 else float(np.prod(ok.max(0) - ok.min(0)))

        parsed.sort(key=area, reverse=True)
        notes.append(f"{len(parsed)} people in the file; using the largest")
    xy, missing = parsed[0]
    J = len(xy)
    if fmt is None:
        if J not in FORMAT_BY_COUNT:
            raise PoseLifterError(f"{p}: {J} joints; give 'format' (one of {list(keypoint_formats())})")
        fmt = FORMAT_BY_COUNT[J]
        if J == 17:
            notes.append("17 joints without 'format': assumed H36M order (use --format coco17 for COCO keypoints)")
    f = get_format(fmt)
    if J != f.num_joints:
        raise PoseLifterError(f"{p}: format {fmt!r} has {f.num_joints} joints, the file has {J}")
    if missing.any():
        # only the joints a rule uses are needed
        used = sorted({k for rule in f.to_h36m for k, _ in rule})
        bad = [f.joint_names[k] for k in used if missing[k]]
        if bad:
            raise PoseLifterError(f"{p}: joint(s) {bad} missing (confidence 0 or not finite); every joint the "
                                  f"{fmt} -> h36m17 rules use must be given")
        xy = np.where(missing[:, None], 0.0, xy)
    image_size = _image_size_field(meta.get("image_size"), where=str(p))
    focal = None if meta.get("focal") is None else _camera_field(meta["focal"], name="focal", where=str(p))
    pp = None if meta.get("principal_point") is None else \
        _camera_field(meta["principal_point"], name="principal_point", where=str(p))
    return KeypointFile(keypoints=xy, format=fmt, image_size=image_size, focal=focal, principal_point=pp,
                        warnings=tuple(notes))


# ------------------------------------------------------------------------------------------------
# One input
# ------------------------------------------------------------------------------------------------


def _camera(*, user_focal: np.ndarray | None, user_pp: np.ndarray | None, file_focal: np.ndarray | None,
            file_pp: np.ndarray | None, image_size: tuple[int, int] | None, exif: Any, sensor_width_mm: float | None,
            fov_deg: float, where: str) -> tuple[np.ndarray, str, np.ndarray, list[str]]:
    notes: list[str] = []
    if user_focal is not None:
        focal, src = user_focal, "user"
    elif file_focal is not None:
        focal, src = file_focal, "keypoint-file"
    elif image_size is not None:
        if exif is not None:
            g = focal_from_exif(exif, image_size, sensor_width_mm=sensor_width_mm, fov_deg=fov_deg)
        else:
            from .detect import FocalGuess

            f0 = default_focal(image_size, fov_deg=fov_deg)
            g = FocalGuess(f0, "default-fov", f"no focal length given: assumed a {fov_deg:g} deg diagonal field of "
                                              f"view -> {f0:.1f} px")
        focal, src = np.array([g.focal, g.focal]), g.source
        notes.append(g.detail)
    else:
        raise PoseLifterError(f"{where}: no focal length and no image size: pass --focal, or put 'focal' or "
                              "'image_size' in the file")
    if user_pp is not None:
        pp = user_pp
    elif file_pp is not None:
        pp = file_pp
    elif image_size is not None:
        pp = np.asarray(image_size, np.float64) / 2.0
    else:
        raise PoseLifterError(f"{where}: no principal point and no image size: pass --principal-point, or put "
                              "'principal_point' or 'image_size' in the file")
    return np.asarray(focal, np.float64), src, np.asarray(pp, np.float64), notes


def _lift(lifter: Any, kp17: np.ndarray, focal: np.ndarray, pp: np.ndarray, *, flip_test: bool) -> Any:
    return lifter.lift(kp17, focal=focal, principal_point=pp, flip_test=flip_test)


def lift_keypoint_file(path: str | Path, *, lifter: Any, focal: Any | None = None, principal_point: Any | None = None,
                       default_format: str | None = None, fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG,
                       flip_test: bool = False) -> LiftRecord:
    """Lift one keypoint JSON file (module docstring)."""
    kf = parse_keypoint_json(path, default_format=default_format)
    kp17 = convert(kf.keypoints, src=kf.format)
    f, src, pp, notes = _camera(user_focal=None if focal is None else as_pair(focal, name="focal", positive=True),
                                user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
                                file_focal=kf.focal, file_pp=kf.principal_point, image_size=kf.image_size, exif=None,
                                sensor_width_mm=None, fov_deg=fov_deg, where=str(path))
    res = _lift(lifter, kp17, f, pp, flip_test=flip_test)
    return LiftRecord(input=str(path), kind="keypoints", keypoints_2d=kp17, absolute=res.absolute,
                      relative=res.relative, root=res.root, canonical_depth=float(res.canonical_depth),
                      focal=(float(f[0]), float(f[1])), focal_source=src, principal_point=(float(pp[0]), float(pp[1])),
                      image_size=kf.image_size, model=lifter.name, source_format=kf.format,
                      warnings=kf.warnings + tuple(notes))


def lift_image(image: str | Path | LoadedImage, *, lifter: Any, estimator: PoseEstimator2D, focal: Any | None = None,
               principal_point: Any | None = None, sensor_width_mm: float | None = None,
               fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG, max_side: int = DEFAULT_MAX_SIDE_PX,
               flip_test: bool = False) -> LiftRecord:
    """Detect the (largest) person in a photo (a path or a :class:`lifter.detect.LoadedImage`) and lift
    them (module docstring)."""
    img = image if isinstance(image, LoadedImage) else load_image(image, max_side=max_side)
    path = img.path if img.path is not None else "<image>"
    det = detect_pose(img, estimator=estimator)
    f, src, pp, notes = _camera(user_focal=None if focal is None else as_pair(focal, name="focal", positive=True),
                                user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
                                file_focal=None, file_pp=None, image_size=img.size, exif=img.exif,
                                sensor_width_mm=sensor_width_mm, fov_deg=fov_deg, where=str(path))
    res = _lift(lifter, det.keypoints_2d, f, pp, flip_test=flip_test)
    return LiftRecord(input=str(path), kind="image", keypoints_2d=det.keypoints_2d, absolute=res.absolute,
                      relative=res.relative, root=res.root, canonical_depth=float(res.canonical_depth),
                      focal=(float(f[0]), float(f[1])), focal_source=src, principal_point=(float(pp[0]), float(pp[1])),
                      image_size=img.size, model=lifter.name, scores=det.scores, source_format=det.raw.keypoint_format,
                      num_people=det.num_people, detector=estimator.name, warnings=det.warnings + tuple(notes))


# ------------------------------------------------------------------------------------------------
# Batch
# ------------------------------------------------------------------------------------------------


def expand_inputs(inputs: list[str | Path]) -> tuple[list[Path], list[str]]:
    """Files to process (folders expanded to their images and .json files, sorted, not recursive) and
    messages for inputs that do not exist."""
    files: list[Path] = []
    problems: list[str] = []
    for raw in inputs:
        p = Path(raw)
        if p.is_dir():
            found = sorted(q for q in p.iterdir() if q.is_file() and (q.suffix.lower() in IMAGE_SUFFIXES or
                                                                      q.suffix.lower() == ".json"))
            if not found:
                problems.append(f"{p}: folder has no images or .json files")
            files.extend(found)
        elif p.is_file():
            files.append(p)
        else:
            problems.append(f"{p}: no such file or folder")
    return files, problems


def output_names(files: list[Path], out_dir: Path) -> list[str]:
    """A unique output stem per input: the file stem; on a clash ``<stem>_<suffix>``, then a number.
    A name whose JSON would overwrite one of the inputs also gets ``_lifted``."""
    used: set[str] = set()
    inputs = {f.resolve() for f in files}
    names = []
    for f in files:
        cands = [f.stem, f"{f.stem}_{f.suffix.lstrip('.').lower()}"] + [f"{f.stem}_{i}" for i in range(2, 10_000)]
        for c in cands:
            if c not in used and (out_dir / f"{c}.json").resolve() not in inputs:
                break
        else:  # pragma: no cover
            raise PoseLifterError(f"cannot name the output of {f}")
        if (out_dir / f"{c}.json").resolve() in inputs:  # pragma: no cover
            c = f"{c}_lifted"
        used.add(c)
        names.append(c)
    return names


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``lift`` sub-command on an ``add_subparsers()`` object."""
    p = sub.add_parser(
        "lift", help="lift photos or 2D keypoint files to absolute 3D poses (JSON, optional GLB / BVH)",
        description="Photos (2D detector: MediaPipe BlazePose, the 'detect' extra) or keypoint JSON files in, "
                    "absolute 3D poses out. Exit code 0 if at least one input was lifted, 1 if all failed.",
        formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="images, folders of images, keypoint .json files")
    p.add_argument("--out", type=Path, required=True, help="output folder")
    p.add_argument("--focal", type=float, nargs="+", metavar="F", default=None,
                   help="focal length FX [FY] in px for every input (default: per input, EXIF or --fov)")
    p.add_argument("--principal-point", type=float, nargs=2, metavar=("CX", "CY"), default=None,
                   help="principal point in px (default: the image centre)")
    p.add_argument("--fov", type=float, default=DEFAULT_DIAGONAL_FOV_DEG,
                   help="diagonal field of view (deg) assumed when no focal length is known")
    p.add_argument("--sensor-width", type=float, default=None, metavar="MM",
                   help="camera sensor width (long side) in mm, for EXIF focal lengths in mm")
    p.add_argument("--glb", action="store_true", help="also write <name>.glb (skeleton mesh, metres, y-up)")
    p.add_argument("--bvh", action="store_true", help="also write <name>.bvh (cm, y-up)")
    p.add_argument("--weights", default="auto",
                   help="shipped lifter name or checkpoint .pt; 'auto': for images the model trained for --detector's "
                        "2D errors where one is shipped (e.g. 'blazepose'), for keypoint files the default model")
    p.add_argument("--detector", default="blazepose", help="2D estimator for images")
    p.add_argument("--max-people", type=int, default=3, help="people the detector looks for (the largest is lifted)")
    p.add_argument("--max-side", type=int, default=DEFAULT_MAX_SIDE_PX, help="downscale larger images for detection")
    p.add_argument("--format", default=None, help="keypoint format of JSON files that name none "
                                                  f"(one of {', '.join(keypoint_formats())})")
    p.add_argument("--flip-test", action="store_true", help="average with the mirrored input's prediction")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run_lift)
    return p


def check_lift_options(args: argparse.Namespace) -> None:
    """Usage errors in the options that apply to every input, before any weights or input are read
    (:class:`PoseLifterError` naming the option, the value and what is expected)."""
    if args.focal is not None:
        if len(args.focal) not in (1, 2):
            raise PoseLifterError(f"--focal takes FX or FX FY, got {len(args.focal)} values")
        _camera_field(list(args.focal), name="--focal", where=None)
    if args.principal_point is not None:
        _camera_field(list(args.principal_point), name="--principal-point", where=None)
    if not (math.isfinite(args.fov) and 0 < args.fov < 180):
        raise PoseLifterError(f"--fov must be a diagonal field of view in (0, 180) degrees, got {args.fov:g}")
    if args.sensor_width is not None and not (math.isfinite(args.sensor_width) and 0 < args.sensor_width < 1000):
        raise PoseLifterError(f"--sensor-width must be the sensor's long side in mm, in (0, 1000), "
                              f"got {args.sensor_width:g}")
    for opt, value in (("--max-side", args.max_side), ("--max-people", args.max_people)):
        if value < 1:
            raise PoseLifterError(f"{opt} must be >= 1, got {value}")
    if args.out.exists() and not args.out.is_dir():
        raise PoseLifterError(f"--out {args.out}: exists and is not a folder; --out names the output folder")


def run_lift(args: argparse.Namespace) -> int:
    from tqdm.auto import tqdm

    from .api import Lifter

    check_lift_options(args)
    if args.format is not None:
        get_format(args.format)
    focal = None if args.focal is None else as_pair(args.focal, name="--focal", positive=True)
    pp = None if args.principal_point is None else np.asarray(args.principal_point, np.float64)
    files, problems = expand_inputs(args.inputs)
    for msg in problems:
        print(f"error: {msg}", file=sys.stderr)
    if not files:
        print("poselifter lift: no inputs to process", file=sys.stderr)
        return 1
    from .api import model_for_detector, model_registry

    refs = {"keypoints": model_registry()["default"], "image": model_for_detector(args.detector)} \
        if args.weights == "auto" else \
        {"keypoints": str(args.weights), "image": str(args.weights)}
    kinds = {"keypoints" if f.suffix.lower() == ".json" else "image" for f in files}
    loaded = {ref: Lifter.load(ref) for ref in {refs[k] for k in kinds}}  # bad weights fail before any input
    lifter_for = {k: loaded[refs[k]] for k in kinds}
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PoseLifterError(f"--out {args.out}: cannot create the output folder ({exc.strerror or exc})") from None
    names = output_names(files, args.out)
    estimator: Any = None
    estimator_error: str | None = None
    ok, failed = 0, len(problems)
    bar = tqdm(list(zip(files, names)), desc="lift", unit="input", disable=args.no_progress, file=sys.stderr)
    for path, name in bar:
        try:
            if path.suffix.lower() == ".json":
                rec = lift_keypoint_file(path, lifter=lifter_for["keypoints"], focal=focal, principal_point=pp,
                                         default_format=args.format, fov_deg=args.fov, flip_test=args.flip_test)
            else:
                img = load_image(path, max_side=args.max_side)  # bad files are reported as such, extra or not
                if estimator is None and estimator_error is None:
                    try:
                        from .detect import get_estimator

                        kw = {"max_people": args.max_people} if args.detector == "blazepose" else {}
                        estimator = get_estimator(args.detector, **kw)
                    except (MissingDependencyError, PoseLifterError) as exc:
                        estimator_error = str(exc)
                if estimator_error is not None:
                    raise PoseLifterError(f"{path}: cannot detect 2D keypoints: {estimator_error}")
                rec = lift_image(img, lifter=lifter_for["image"], estimator=estimator, focal=focal, principal_point=pp,
                                 sensor_width_mm=args.sensor_width, fov_deg=args.fov, max_side=args.max_side,
                                 flip_test=args.flip_test)
            (args.out / f"{name}.json").write_text(json.dumps(rec.to_json(), indent=1))
            if args.glb:
                from .export import write_glb

                write_glb(rec.absolute, args.out / f"{name}.glb")
            if args.bvh:
                from .export import write_bvh

                write_bvh(rec.absolute, args.out / f"{name}.bvh")
            for msg in rec.warnings:
                tqdm.write(f"{path}: note: {msg}", file=sys.stderr)
            ok += 1
        except PoseLifterError as exc:
            msg = str(exc)
            tqdm.write(f"error: {msg if msg.startswith(str(path)) else f'{path}: {msg}'}", file=sys.stderr)
            failed += 1
        except Exception as exc:  # noqa: BLE001 -- one bad input must not stop the batch
            tqdm.write(f"error: {path}: unexpected {type(exc).__name__}: {exc}", file=sys.stderr)
            failed += 1
    bar.close()
    total = ok + failed
    print(f"lifted {ok} of {total} input(s) into {args.out}" + (f"; {failed} failed (see the messages above)" if failed else ""),
          file=sys.stderr)
    return 0 if ok else 1
