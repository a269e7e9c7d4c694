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
import math
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from .._checks import PoseLifterError, as_pair
from ..camera import DEFAULT_DIAGONAL_FOV_DEG
from ..detect import DEFAULT_MAX_SIDE_PX, IMAGE_SUFFIXES, MissingDependencyError, load_image
from ..io import _camera_field, write_json_atomic
from ..keypoints import get_format, keypoint_formats
from ..pipeline import lift_image, lift_keypoint_file

# ------------------------------------------------------------------------------------------------
# Batch
# ------------------------------------------------------------------------------------------------


def expand_inputs(inputs: list[str | Path]) -> tuple[list[Path], list[str], list[str]]:
    """Files to process (folders expanded to their images, videos and .json files, sorted, not recursive) and a
    message for every input that is skipped: missing files, dangling symbolic links, folders without inputs,
    and entries of a folder that are neither files nor of a known kind (named, so nothing is skipped silently).
    Returns ``(files, problems, notes)``: problems count as failed inputs, notes (other files in a folder) do not."""
    files: list[Path] = []
    problems: list[str] = []
    notes: list[str] = []
    for raw in inputs:
        p = Path(raw)
        if p.is_symlink() and not p.exists():
            problems.append(f"{p}: dangling symbolic link (its target {os.readlink(p)!r} does not exist); skipped")
        elif p.is_dir():
            found, skipped = [], []
            for q in sorted(p.iterdir()):
                known = q.suffix.lower() in IMAGE_SUFFIXES or q.suffix.lower() == ".json"
                if q.is_symlink() and not q.exists():
                    if known:
                        problems.append(f"{q}: dangling symbolic link (its target {os.readlink(q)!r} does not exist); "
                                        "skipped")
                elif q.is_file() and known:
                    found.append(q)
                elif q.is_file() and not q.name.startswith("."):
                    skipped.append(q.name)
            if skipped:
                notes.append(f"{p}: skipped {len(skipped)} file(s) that are not images or .json: "
                                + ", ".join(skipped[:5]) + (" ..." if len(skipped) > 5 else ""))
            if not found:
                problems.append(f"{p}: folder has no images or .json files")
            files.extend(found)
        elif p.is_file():
            files.append(p)
        else:
            problems.append(f"{p}: no such file or folder")
    return files, problems, notes


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
    p.add_argument("--weights", default="default",
                   help="lifter: 'default' (one model for every input: images are lifted as detector output, keypoint "
                        "files as their 'source' field says), another shipped name or a checkpoint .pt")
    p.add_argument("--detector", default="blazepose", help="2D estimator for images")
    p.add_argument("--max-people", type=int, default=3, help="people the detector looks for (the largest is lifted)")
    p.add_argument("--max-side", type=int, default=DEFAULT_MAX_SIDE_PX, help="downscale larger images for detection")
    p.add_argument("--format", default=None, help="keypoint format of JSON files that name none "
                                                  f"(one of {', '.join(keypoint_formats())})")
    p.add_argument("--flip-test", action=argparse.BooleanOptionalAction, default=None,
                   help="average each pose with its mirror image's lift (default: the model's own setting; on for the "
                        "shipped default)")
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

    from ..api import Lifter

    check_lift_options(args)
    if args.format is not None:
        get_format(args.format)
    focal = None if args.focal is None else as_pair(args.focal, name="--focal", positive=True)
    pp = None if args.principal_point is None else np.asarray(args.principal_point, np.float64)
    files, problems, notes = expand_inputs(args.inputs)
    for msg in problems:
        print(f"error: {msg}", file=sys.stderr)
    for msg in notes:
        print(f"note: {msg}", file=sys.stderr)
    if not files:
        print("poselifter lift: no inputs to process", file=sys.stderr)
        return 1
    lifter = Lifter.load(args.weights)  # bad weights fail before any input
    lifter_for = {"keypoints": lifter, "image": lifter}
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
                        from ..detect import get_estimator

                        kw = {"max_people": args.max_people} if args.detector == "blazepose" else {}
                        estimator = get_estimator(args.detector, **kw)
                    except (MissingDependencyError, PoseLifterError) as exc:
                        estimator_error = str(exc)
                if estimator_error is not None or estimator is None:
                    raise PoseLifterError(f"{path}: cannot detect 2D keypoints: {estimator_error}")
                rec = lift_image(img, lifter=lifter_for["image"], estimator=estimator, focal=focal, principal_point=pp,
                                 sensor_width_mm=args.sensor_width, fov_deg=args.fov, max_side=args.max_side,
                                 flip_test=args.flip_test)
            write_json_atomic(args.out / f"{name}.json", rec.to_json())
            if args.glb:
                from ..export import write_glb

                write_glb(rec.absolute, args.out / f"{name}.glb")
            if args.bvh:
                from ..export import write_bvh

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
