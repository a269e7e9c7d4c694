"""``poselifter lift``: photos, videos or 2D keypoint files in, absolute 3D poses out.

Registered in :mod:`lifter.cli` by :func:`add_parser`. Usage::

    poselifter lift INPUT... [--focal FX [FY]] [--principal-point CX CY] --out DIR [--glb] [--bvh]
                    [--max-people 3] [--smoothing 1] [--max-seconds 600]

INPUT: image files, videos (anything OpenCV reads: .mp4, .mov, .avi, ...), folders (their images, videos and
``.json`` files, not recursive; in the output folder itself, earlier results are left out) or keypoint JSON files
(one frame, or a sequence with ``frames``).

Several people: everyone found (at most ``--max-people``, the largest) is lifted into one camera space;
``people`` lists them, largest first (from a keypoint file with each person's ``input_index`` in it and
``person_id`` when given), and the top-level fields describe the largest. ``--glb`` puts
everyone in one scene; ``--bvh`` writes ``<name>.bvh`` for the largest and ``<name>_person<k>.bvh`` for the others.

Videos and keypoint sequences (:mod:`lifter.video`): ``DIR/<name>.json`` has ``fps``, ``tracks`` and
``frames: [{"index", "time_s", "people": [{"track_id", "keypoints_2d", "absolute", "root", ...}]}]``; people
are tracked with a stable ``track_id`` and their root and pose smoothed by a causal One-Euro filter of
strength ``--smoothing`` (0 = off). ``--bvh`` writes one BVH animation per track (``<name>_track<ID>.bvh``),
``--glb`` an animated scene (:func:`lifter.export.write_glb_animation`). A progress bar counts frames; a bad
frame (undecodable, or of another size than the first) is reported and skipped; a video longer than
``--max-seconds`` is lifted up to that duration.
For every input it writes ``DIR/<name>.json`` (``<name>`` = the file name without its suffix; two inputs
named alike get ``<folder>_<name>``, else ``<name>_<suffix>`` or a number, with a note) with ``keypoints_2d``
(17 x 2 px, H36M order), ``absolute`` (17 x 3 mm, camera frame: OpenCV, +x right, +y down, +z forward), ``relative``,
``root`` (3, mm), ``canonical_depth`` (mm at a 1000-px focal), ``focal`` (fx, fy px), ``focal_source``,
``principal_point`` (px), ``image_size``, ``warnings`` and, for images, the detector's per-joint
``scores`` and the number of people found; with ``--glb`` / ``--bvh`` also ``DIR/<name>.glb`` /
``.bvh`` (:mod:`lifter.export`).

Camera. ``--focal`` / ``--principal-point`` apply to every input. Otherwise, per input: a keypoint
file's own ``focal`` / ``principal_point``; for photos the EXIF focal length (focal in mm with the
sensor size from the focal-plane resolution or ``--sensor-width``, else the 35-mm equivalent); else
a diagonal field of view of ``--fov`` degrees (default 65, :data:`lifter.detect.DEFAULT_DIAGONAL_FOV_DEG`).
The principal point defaults to the image centre. See :func:`lifter.detect.focal_from_exif`. A photo's lens:
``--distortion`` with ``--distortion-model`` (``h36m``: K1 K2 K3 P1 P2; ``opencv``: OpenCV's distCoeffs as
calibrated), which needs ``--focal`` of the same calibration; the detected 2D is undistorted before it is lifted.

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
1 when every input failed (or none was found; with ``--strict``, when any failed, or when a result is one its
notes call not valid: :func:`not_valid_reasons`), 2 for a usage error (bad arguments, no lifter weights).
"""

from __future__ import annotations

import argparse
import dataclasses
import glob
import json
import math
import os
import re
import sys
from pathlib import Path
from typing import Any, Final

import numpy as np

from .._checks import PoseLifterError, as_pair
from ..camera import (
    DEFAULT_DIAGONAL_FOV_DEG,
    DISTORTION_MODELS,
    MAX_FOV_DEG,
    MIN_FOCAL_PX,
    MIN_FOV_DEG,
    check_lens,
)
from ..detect import (
    DEFAULT_MAX_SIDE_PX,
    IMAGE_SUFFIXES,
    MIN_MAX_SIDE_PX,
    MIN_PERSON_SCORE,
    MissingDependencyError,
    check_max_side,
    load_image,
)
from ..io import (
    FRAME_PATTERN,
    LiftRecord,
    _camera_field,
    _image_size_field,
    check_frame_rate,
    frame_pattern_files,
    is_frame_pattern,
    is_keypoint_sequence,
    openpose_frame_pattern,
    openpose_partial_videos,
    write_json_atomic,
)
from ..keypoints import get_format, keypoint_formats
from ..pipeline import lift_image, lift_keypoint_file
from ..smoothing import check_strength
from ..video import (
    DEFAULT_MAX_PEOPLE,
    DEFAULT_MAX_SECONDS,
    VIDEO_SUFFIXES,
    SequenceRecord,
    input_kind,
    lift_keypoint_sequence,
    lift_video,
    limit_blas_threads,
    track_animation,
)
from . import COMMANDS
from ._help import HelpFormatter, positive_int

# ------------------------------------------------------------------------------------------------
# Batch
# ------------------------------------------------------------------------------------------------


def _head(path: Path) -> bytes:
    """The first 4 KB of a file (empty when it cannot be read): a result's identifying fields come first, and a photo's
    or video's signature, or JSON text (:func:`lifter.video.input_kind`)."""
    try:
        with open(path, "rb") as f:
            return f.read(4096)
    except OSError:
        return b""


def _is_result_file(path: Path) -> bool:
    """Whether a .json file is a ``poselifter lift`` result (its ``model`` and ``units`` fields)."""
    head = _head(path)
    return head.lstrip().startswith(b"{") and b'"model"' in head and b'"units"' in head


def expand_inputs(inputs: list[str | Path], *, out: Path | None = None,
                  group_frames: bool = False) -> tuple[list[Path], list[str], list[str]]:
    """Files to process (folders expanded to their images, videos and .json files, sorted, not recursive) and a
    message for every input that is skipped: missing files, dangling symbolic links, folders without inputs,
    and entries of a folder that are neither files nor of a known kind, subfolders included (named, so nothing is
    skipped silently).
    A folder that is also the output folder ``out`` contributes no earlier results (``poselifter lift`` JSON), so a
    second run does not lift the first run's output; a result file named as an input itself is lifted.
    ``group_frames`` (``--fps`` given): all of a video's OpenPose per-frame files among them become one input, their
    frame pattern (:func:`lifter.io.openpose_frame_pattern`); without it they stay files, with a note naming --fps.
    Returns ``(files, problems, notes)``: problems count as failed inputs, notes (other files in a folder) do not."""
    files: list[Path] = []
    problems: list[str] = []
    notes: list[str] = []
    for raw in inputs:
        p = Path(raw)
        if p.is_symlink() and not p.exists():
            problems.append(f"{p}: dangling symbolic link (its target {os.readlink(p)!r} does not exist); skipped")
        elif p.is_dir():
            found, skipped, subdirs, results, hidden = [], [], [], [], []
            is_out = out is not None and out.exists() and p.resolve() == out.resolve()
            for q in sorted(p.iterdir()):
                sfx = q.suffix.lower()
                known = sfx in IMAGE_SUFFIXES or sfx in VIDEO_SUFFIXES or sfx == ".json"
                if q.name.startswith(".") and known and (q.is_file() or q.is_symlink()):  # (macOS's ._x.jpg: a trial)
                    hidden.append(q.name)
                elif q.is_symlink() and not q.exists():
                    if known:
                        problems.append(f"{q}: dangling symbolic link (its target {os.readlink(q)!r} does not exist); "
                                        "skipped")
                elif q.is_file() and known:
                    if is_out and sfx == ".json" and _is_result_file(q):
                        results.append(q.name)
                    else:
                        found.append(q)
                elif q.is_file() and not q.name.startswith("."):
                    skipped.append(q.name)
                elif q.is_dir() and not q.name.startswith("."):
                    subdirs.append(q.name + "/")
            if hidden:
                notes.append(f"{p}: skipped {len(hidden)} hidden file(s) (names starting with '.', as macOS's ._ "
                             "files; give one as an input to lift it): " + ", ".join(hidden[:5])
                             + (" ..." if len(hidden) > 5 else ""))
            if results:
                notes.append(f"{p}: is also the output folder; its {len(results)} earlier result file(s) are not "
                             "lifted again (name one as an input to lift it)")
            if subdirs:
                notes.append(f"{p}: skipped {len(subdirs)} subfolder(s) (folders are not searched recursively; give "
                             "them as inputs too): " + ", ".join(subdirs[:5]) + (" ..." if len(subdirs) > 5 else ""))
            if skipped:
                notes.append(f"{p}: skipped {len(skipped)} file(s) that are not images, videos or .json: "
                                + ", ".join(skipped[:5]) + (" ..." if len(skipped) > 5 else ""))
            if not found:
                problems.append(f"{p}: folder has no images, videos or .json files")
            files.extend(found)
        elif p.is_file() or (is_frame_pattern(p) and frame_pattern_files(p)):  # (a pattern: one file per frame)
            files.append(p)
        elif FRAME_PATTERN.search(p.name) and p.suffix.lower() != ".json" and p.parent.is_dir():
            problems.append(f"{p}: a frame pattern is read for keypoint files only (name.json); images are not read as "
                            "a video: give their folder (each image is lifted), or make them a video")
        elif p.exists():  # (a pipe, <(...), or a device: a user trial read "no such file" for them)
            problems.append(f"{p}: not a regular file or folder (a pipe or a device?): write the input to a file and "
                            "give that")
        else:
            problems.append(f"{p}: no such file or folder")
    for pattern, members in openpose_frame_pattern(files):  # (OpenPose's --write_json output of a video)
        what = f"{len(members)} OpenPose per-frame files ({members[0].name} ... {members[-1].name})"
        if not group_frames:
            notes.append(f"{what} are lifted one by one; give their frame rate (--fps 30) to lift them as one tracked, "
                         f"smoothed keypoint sequence ({pattern})")
            continue
        at = min(files.index(q) for q in members if q in files)
        kept = set(members)
        files = [f for f in files[:at] if f not in kept] + [pattern] + [f for f in files[at:] if f not in kept]
        notes.append(f"{what} are lifted as one keypoint sequence, {pattern}, tracked and smoothed")
    for pattern, given, total, dense in openpose_partial_videos(files):  # (a clip's frames picked out: a user trial)
        notes.append(f"{given} of the {total} OpenPose per-frame files of {pattern.name.split('_%012d')[0]} are given: "
                     "they are lifted one by one (a keypoint sequence is all of a video's files, its folder or the "
                     f"frame pattern {pattern}" + ("; to lift a part of it as one, copy those files into a folder of "
                                                   "their own and give that folder with --fps)" if dense else ")"))
    unique: dict[Path, Path] = {}
    twice = []
    for f in files:
        if f.resolve() in unique:
            twice.append(str(f))
        else:
            unique[f.resolve()] = f
    if twice:
        names = list(dict.fromkeys(twice))  # (each once: "x.json, x.json" read as a stutter in a user trial)
        notes.append(f"{len(names)} input(s) given more than once ({len(twice)} repeat(s)), each lifted once: "
                     + ", ".join(names[:5]) + (" ..." if len(names) > 5 else ""))
    return list(unique.values()), problems, notes


PER_PERSON_STEM: Final = re.compile(r"(.+)_(?:person|track)\d+")
"""The stems of the outputs written per person or track beside ``<name>.json`` (``<name>_person2.bvh``,
``<name>_track3.bvh``): another input's outputs may not take them."""


def input_stem(f: Path) -> str:
    """An input's name for its outputs: the file's stem; for a frame pattern (:func:`lifter.io.frame_pattern_files`)
    the name without its frame number (OpenPose's ``video_%012d_keypoints.json``: ``video``)."""
    m = FRAME_PATTERN.search(f.name)
    if m is None or not is_frame_pattern(f):
        return f.stem
    if f.name.endswith("_%012d_keypoints.json") and len(f.name) > len("_%012d_keypoints.json"):
        return f.name[:-len("_%012d_keypoints.json")]
    return Path(f.name[:m.start()] + f.name[m.end():]).stem.strip("_-. ") or "frames"


def output_names(files: list[Path], out_dir: Path, *, per_person: bool = False) -> tuple[list[str], list[str]]:
    """A unique output stem per input, and a note for each input whose outputs are not named by its own stem.
    The stem; on a clash with an earlier input, ``<folder>_<stem>`` when the two sit in different folders, else
    ``<stem>_<suffix>``, then a number. A name whose JSON would overwrite one of the inputs is not used. With
    ``per_person`` (``--bvh``: ``<stem>_person<k>`` and ``<stem>_track<ID>`` files too), a stem is not used where
    one input's per-person names would be another's (``a`` and ``a_person2``: a review lost a BVH so). Nor is one
    whose JSON exists in ``out_dir`` and is not a ``poselifter lift`` result: a file of the user's (a review's
    ``photo.json`` keypoints beside ``photo.jpg``, lifted with ``--out`` that folder, were replaced by the result)."""
    claimed: dict[str, Path] = {}
    inputs = {f.resolve() for f in files}
    names, notes = [], []

    def not_ours(c: str) -> bool:
        """Whether ``<c>.json`` in ``out_dir`` is an input or a file that is not a result (the user's own)."""
        j = out_dir / f"{c}.json"
        return j.resolve() in inputs or (j.exists() and not _is_result_file(j) and _result_input(j, j)[0] is None)

    def owner(c: str) -> Path | None:
        """The input that has ``c``, or whose per-person outputs could be named ``c``, or that could have ``c``'s."""
        if c in claimed:
            return claimed[c]
        if per_person:
            m = PER_PERSON_STEM.fullmatch(c)
            if m is not None and m.group(1) in claimed:
                return claimed[m.group(1)]
            for d, f in claimed.items():
                m = PER_PERSON_STEM.fullmatch(d)
                if m is not None and m.group(1) == c:
                    return f
        return None

    for f in files:
        stem = input_stem(f)
        first = owner(stem)
        cands = [stem]
        if first is not None and first.parent.name != f.parent.name and f.parent.name:
            cands.append(f"{f.parent.name}_{stem}")
        cands += [f"{stem}_{f.suffix.lstrip('.').lower()}"] + [f"{stem}_{i}" for i in range(2, 10_000)]
        for c in cands:
            if owner(c) is None and not not_ours(c):
                break
        else:  # pragma: no cover
            raise PoseLifterError(f"cannot name the output of {f}")
        claimed[c] = f
        names.append(c)
        if c != stem:
            if first is None and (out_dir / f"{stem}.json").resolve() in inputs:
                why = f"{stem}.json in {out_dir} is an input"
            elif first is None:
                why = f"{stem}.json in {out_dir} is not a poselifter result, so it is left as it is"
            elif input_stem(first) == stem:
                why = f"{first} is also named {stem}"
            else:
                why = f"it and {first} would share --bvh's per-person names <name>_person<k> / <name>_track<ID>"
            notes.append(f"{f}: its results are named {c}.* ({why})")
    return names, notes


def not_valid_reasons(rec: LiftRecord | None, seq: SequenceRecord | None) -> list[str]:
    """Why a lifted input's result is one its own notes call not valid, for ``--strict``: a root behind the camera
    (Z <= 0: "the result is not a valid pose"), or a camera no lens has: a focal length that gives the image a field
    of view wider than :data:`lifter._checks.MAX_PLAUSIBLE_IMAGE_VIEW_DEG` or narrower than
    :data:`lifter._checks.MIN_PLAUSIBLE_VIEW_DEG` (a focal in mm), or fx / fy beyond
    :data:`lifter._checks.MAX_FOCAL_ASPECT` (every depth is proportional to it). Empty for a result to keep (a
    developer trial's --strict run exited 0 with a root at Z = -628 mm, and with --focal 35, a focal in mm, placing
    the person 0.25 m away)."""
    from .._checks import MAX_FOCAL_ASPECT, view_angle_notes

    if seq is not None:
        roots = [q.root_raw for fr in seq.frames for q in fr.people]
        focal, size = seq.focal, seq.image_size
    elif rec is not None:
        roots = [q.root for q in rec.people] if rec.people else [rec.root]
        focal, size = rec.focal, rec.image_size
    else:
        return []
    reasons = []
    behind = sum(float(np.asarray(r, np.float64)[2]) <= 0 for r in roots)
    if behind:
        reasons.append(f"{behind} root(s) behind the camera (Z <= 0)")
    fx, fy = (float(v) for v in focal)
    if view_angle_notes((fx, fy), None if size is None else (int(size[0]), int(size[1]))):
        reasons.append(f"a focal length ({fx:.6g} px) that gives the image a field of view no pinhole lens has")
    if not 1.0 / MAX_FOCAL_ASPECT <= fx / fy <= MAX_FOCAL_ASPECT:
        reasons.append(f"a focal length whose fx / fy is {fx / fy:.3g}, beyond the {MAX_FOCAL_ASPECT:g} of real "
                       "cameras")
    return reasons


def add_parser(sub: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register the ``lift`` sub-command on an ``add_subparsers()`` object."""
    p = sub.add_parser(
        "lift", help=COMMANDS["lift"][1],
        description="Photos and videos (2D detector: MediaPipe BlazePose, the 'detect' extra) or keypoint JSON files "
                    "in, absolute 3D poses of everyone found out. Exit code 0 if at least one input was lifted, 1 if "
                    "all failed (--strict: if any failed).",
        formatter_class=HelpFormatter)
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="images, videos, folders of them, keypoint .json files (one frame, or 'frames'), or a "
                        "frame pattern of keypoint files (DIR/video_%%012d_keypoints.json: one file per frame)")
    p.add_argument("-o", "--out", type=Path, required=True, help="output folder")
    p.add_argument("--strict", action="store_true",
                   help="exit code 1 when any input fails, not only when all do, or when a result is one its notes "
                        "call not valid: a root behind the camera, a focal length no lens has (in mm?) (for "
                        "pipelines; the inputs that could be lifted are still written)")
    p.add_argument("--focal", type=float, nargs="+", metavar="F", default=None,
                   help="focal length FX [FY] in px (one or two values) for every input (default, per input: a "
                   "keypoint file's focal; a photo's EXIF; else the --fov field of view of the image size, which a "
                   "keypoint file then has to give as image_size, or --image-size)")
    p.add_argument("--principal-point", type=float, nargs=2, metavar=("CX", "CY"), default=None,
                   help="principal point in px (default: the image centre); for a photo, in the pixels of the "
                        "upright image (after its EXIF orientation), as --focal FX FY and --distortion are")
    p.add_argument("--image-size", type=float, nargs=2, metavar=("W", "H"), default=None,
                   help="keypoint files: the image's size in px, for those that give no image_size (a list of "
                        "people cannot), or in place of their own: the principal point defaults to its centre and "
                        "the focal length to the --fov field of view of it (photos and videos: their own size, "
                        "with a note)")
    p.add_argument("--fov", type=float, default=DEFAULT_DIAGONAL_FOV_DEG,
                   help="diagonal field of view (deg) assumed when no focal length is known")
    p.add_argument("--distortion", type=float, nargs="+", metavar="D", default=None,
                   help="photos: the camera's lens distortion, in the form --distortion-model says, calibrated with "
                        "--focal and --principal-point (which it needs); the 2D is undistorted before it is lifted. "
                        "Keypoint files give theirs in the file ('distortion', 'distortion_model')")
    p.add_argument("--distortion-model", choices=DISTORTION_MODELS, default="h36m",
                   help="the form of --distortion: 'h36m', Human3.6M's K1 K2 K3 P1 P2, or 'opencv', OpenCV's "
                        "distCoeffs K1 K2 P1 P2 [K3 [K4 K5 K6]] as cv2.calibrateCamera gives them")
    p.add_argument("--sensor-width", type=float, default=None, metavar="MM",
                   help="camera sensor width (long side) in mm, for EXIF focal lengths in mm")
    p.add_argument("--glb", action="store_true", help="also write <name>.glb (skeleton meshes of everyone, metres, "
                                                       "y-up; animated for videos)")
    p.add_argument("--bvh", action="store_true", help="also write <name>.bvh (cm, y-up; for videos an animation per "
                                                       "track, <name>_track<ID>.bvh)")
    p.add_argument("--weights", default="default",
                   help="lifter: 'default' (one model for every input: images are lifted as detector output, keypoint "
                        "files as their 'source' field says), another shipped name, a checkpoint .pt, or A.pt+B.pt "
                        "(their lifts averaged)")
    p.add_argument("--detector", default="blazepose",
                   help="2D estimator for images and videos: 'blazepose' (MediaPipe, the 'detect' extra), or one "
                   "registered with lifter.detect.register_estimator")
    p.add_argument("--detector-flip-test", action=argparse.BooleanOptionalAction, default=None,
                   help="BlazePose also searches the mirror image (each full search and a video's crop searches) and "
                        "combines the two (default on); --no-detector-flip-test halves the detection time (a video's "
                        "tracking path about twice as fast) for more 2D error (8.3 against 7.2 px on the Human3.6M "
                        "demo photos' crops: README, 'Photos in')")
    p.add_argument("--max-people", type=int, default=DEFAULT_MAX_PEOPLE,
                   help="people lifted per image or frame at most (the largest; in a video those already tracked "
                   "first, so 1 follows one person; a crowd bound)")
    p.add_argument("--min-score", type=float, default=MIN_PERSON_SCORE, metavar="S",
                   help="leave out, as no person, each detected person (or a keypoint file's, where it gives 0-1 "
                        "scores) whose mean joint score is below S (0 keeps everyone; BlazePose gives real people "
                        "0.84-1 in photos, and 'people' on empty walls often less than 0.3)")
    p.add_argument("--smoothing", type=float, default=1.0,
                   help="videos and keypoint sequences: strength of the causal One-Euro filter on root and pose "
                        "(0 = off, 2 = twice as smooth, at most 10)")
    p.add_argument("--video-fps", type=float, default=None, metavar="FPS",
                   help="videos: lift at this frame rate (frames/s, in (0, 1000]) in place of the one the file "
                        "gives, with a note: for a header that is wrong, or a slow-motion clip whose capture rate is "
                        "the one wanted (times, smoothing and --max-seconds run on it)")
    p.add_argument("--fps", type=float, default=None,
                   help="videos and keypoint sequences that give no frame rate of their own (MMPose's predictions "
                        "of a video; OpenPose's per-frame files: with --fps all of a video's <video>_<12 digits>"
                        "_keypoints.json are lifted as one sequence, else one by one): frames/s, in (0, 1000]; a "
                        "file's own rate wins, with a note")
    p.add_argument("--max-seconds", type=float, default=DEFAULT_MAX_SECONDS,
                   help="videos and keypoint sequences: lift at most this many seconds (a duration bound)")
    p.add_argument("--max-side", type=int, default=DEFAULT_MAX_SIDE_PX,
                   help=f"downscale larger images for detection (px, at least {MIN_MAX_SIDE_PX})")
    p.add_argument("--format", default=None, help="keypoint format of JSON files that name none "
                                                  f"(one of {', '.join(keypoint_formats())})")
    p.add_argument("--flip-test", action=argparse.BooleanOptionalAction, default=None,
                   help="average each pose with its mirror image's lift (default: the model's own setting; on for the "
                        "shipped default)")
    p.add_argument("--threads", type=positive_int, default=None,
                   help="torch threads for the lift (default: torch's, one per core); the 2D detector's are its own")
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
        if min(args.focal) < MIN_FOCAL_PX:  # (refused for every input alike: said once, before any is read)
            raise PoseLifterError(
                f"--focal {min(args.focal):g} px is too small (< {MIN_FOCAL_PX:g} px): give the focal length in "
                "pixels, not mm (f_px = f_mm * image width px / sensor width mm, or --sensor-width with a photo's "
                "EXIF), or leave --focal out to use the photo's EXIF or the --fov field of view")
    if args.principal_point is not None:
        _camera_field(list(args.principal_point), name="--principal-point", where=None)
    if args.image_size is not None:
        _image_size_field(list(args.image_size), where="--image-size")
    if not (math.isfinite(args.fov) and MIN_FOV_DEG <= args.fov <= MAX_FOV_DEG):
        raise PoseLifterError(f"--fov must be a diagonal field of view in [{MIN_FOV_DEG:g}, {MAX_FOV_DEG:g}] degrees "
                              f"(a long telephoto to beyond the widest phone lens, ~120), got {args.fov:g}")
    if args.sensor_width is not None and not (math.isfinite(args.sensor_width) and 0 < args.sensor_width < 1000):
        raise PoseLifterError(f"--sensor-width must be the sensor's long side in mm, in (0, 1000), "
                              f"got {args.sensor_width:g}")
    if args.max_people < 1:
        raise PoseLifterError(f"--max-people must be >= 1, got {args.max_people}")
    if not 0.0 <= args.min_score <= 1.0:
        raise PoseLifterError(f"--min-score must be in [0, 1] (a mean joint score; 0 keeps everyone), got "
                              f"{args.min_score:g}")
    if args.detector_flip_test is not None and args.detector != "blazepose":
        raise PoseLifterError(f"--{'' if args.detector_flip_test else 'no-'}detector-flip-test: the detector "
                              f"{args.detector!r} has no flip test of poselifter's (only 'blazepose')")
    check_max_side(args.max_side, name="--max-side")
    check_strength(args.smoothing, name="--smoothing")
    if not (math.isfinite(args.max_seconds) and args.max_seconds > 0):
        raise PoseLifterError(f"--max-seconds must be a duration > 0 s, got {args.max_seconds:g}")
    for option, rate in (("--fps", args.fps), ("--video-fps", args.video_fps)):
        check_frame_rate(rate, name=option)
    if args.out.exists() and not args.out.is_dir():
        raise PoseLifterError(f"--out {args.out}: exists and is not a folder; --out names the output folder")
    if args.distortion is not None:
        if args.focal is None:
            raise PoseLifterError("--distortion needs the focal length it was calibrated with: give --focal FX [FY] "
                                  "and --principal-point CX CY of the same calibration")
        check_lens(args.distortion, args.distortion_model)
    from ..detect import available_estimators

    if args.detector not in available_estimators():
        raise PoseLifterError(f"--detector {args.detector!r}: unknown 2D estimator; available: "
                              f"{list(available_estimators())}")


def run_lift(args: argparse.Namespace) -> int:
    from tqdm.auto import tqdm

    from ..api import Lifter

    check_lift_options(args)
    if args.format is not None:
        get_format(args.format)
    focal = None if args.focal is None else as_pair(args.focal, name="--focal", positive=True, scalar=True)
    pp = None if args.principal_point is None else np.asarray(args.principal_point, np.float64)
    files, problems, notes = expand_inputs(args.inputs, out=args.out, group_frames=args.fps is not None)
    for msg in problems:
        print(f"error: {msg}", file=sys.stderr)
    for msg in notes:
        print(f"note: {msg}", file=sys.stderr)
    if not files:
        print("poselifter lift: no inputs to process", file=sys.stderr)
        return 1
    if args.threads is not None:
        import torch

        torch.set_num_threads(args.threads)
    lifter = Lifter.load(args.weights)  # bad weights fail before any input
    if args.glb:
        # (trimesh's first import runs its optional imports inside `except BaseException`, which swallows a Ctrl-C
        # landing there: a security trial's SIGINT was ignored in 2 of 10 batches, mid-way through; imported before
        # the batch starts, nothing of it runs between inputs)
        import trimesh  # noqa: F401
    lifter_for = {"keypoints": lifter, "image": lifter}
    try:
        args.out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PoseLifterError(f"--out {args.out}: cannot create the output folder ({exc.strerror or exc})") from None
    names, name_notes = output_names(files, args.out, per_person=args.bvh)
    for msg in name_notes:
        print(f"note: {msg}", file=sys.stderr)
    estimator: Any = None
    estimator_error: str | None = None
    ok, failed, not_valid = 0, len(problems), 0
    quiet = True if args.no_progress else None  # (tqdm's None: no bar when stderr is not a terminal, e.g. a pipe)
    bar = tqdm(list(zip(files, names)), desc="lift", unit="input", disable=quiet, file=sys.stderr, position=0)

    written: set[Path] = set()  # every file this run wrote (never tidied away as an earlier run's)
    now: list[Path] = []  # the outputs of the input being lifted, each added once it is whole

    def say(msg: str) -> None:  # a message on its own line, never glued onto a progress bar
        tqdm.write(msg, file=sys.stderr)

    def get_estimator_once(path: Path) -> Any:
        nonlocal estimator, estimator_error
        if estimator is None and estimator_error is None:
            try:
                from ..detect import get_estimator

                # one more than lifted, so that a crowd is noticed and reported (so --max-people 1 still runs the
                # window search: README, "Photos in")
                kw: dict[str, Any] = ({"max_people": args.max_people + 1, "log": say}
                                      if args.detector == "blazepose" else {})
                if args.detector_flip_test is not None:
                    kw["flip_test"] = args.detector_flip_test
                estimator = get_estimator(args.detector, **kw)
            except (MissingDependencyError, PoseLifterError) as exc:
                estimator_error = str(exc)
        if estimator_error is not None or estimator is None:
            raise PoseLifterError(f"{path}: cannot detect 2D keypoints: {estimator_error}")
        return estimator

    def say_partial(path: Path, now: list[Path]) -> None:
        """After an input's error: which of its outputs were written before it (its JSON, written last, was not)."""
        if now:
            say(f"{path}: note: {', '.join(q.name for q in now)} {'was' if len(now) == 1 else 'were'} written before "
                "the error; its JSON result, written last, was not (any in the output folder is from before)")

    interrupted = False
    with limit_blas_threads(1):  # see lifter.video.lift_video: faster beside MediaPipe's threads
        seq_kw = {"smoothing": args.smoothing, "max_people": args.max_people, "max_seconds": args.max_seconds,
                  "fov_deg": args.fov, "flip_test": args.flip_test, "focal": focal, "principal_point": pp,
                  "min_score": args.min_score}
        current: Path | None = None
        try:
            for path, name in bar:
                current, now = path, []
                misnamed: str | None = None
                try:
                    kind, misnamed = input_kind(path, _head(path))
                    if args.image_size is not None and kind != "keypoints":  # (a mixed batch: not a failure)
                        media = "video" if kind == "video" else "photo"
                        say(f"{path}: note: --image-size is for keypoint files; a {media}'s own size is read from it")
                    if args.distortion is not None and kind != "image":
                        raise PoseLifterError(
                            f"{path}: --distortion is for photos; " + (
                                "a keypoint file gives its lens in the file: 'distortion' (and 'distortion_model')"
                                if kind == "keypoints" else "a video's frames are not undistorted: lift it without "
                                "--distortion, or undistort the video first (e.g. OpenCV's cv2.undistort per frame)"))
                    seq: SequenceRecord | None = None
                    rec: LiftRecord | None = None
                    if kind == "keypoints" and is_keypoint_sequence(path):
                        seq = lift_keypoint_sequence(path, lifter=lifter_for["keypoints"], default_format=args.format,
                                                     image_size=args.image_size, fps=args.fps, **seq_kw)
                    elif kind == "keypoints":
                        rec = lift_keypoint_file(path, lifter=lifter_for["keypoints"], focal=focal, principal_point=pp,
                                                 default_format=args.format, fov_deg=args.fov, flip_test=args.flip_test,
                                                 max_people=args.max_people, image_size=args.image_size,
                                                 min_score=args.min_score)
                    elif kind == "video":
                        est = get_estimator_once(path)
                        with tqdm(desc=f"  {path.name}", unit="frame", disable=quiet, file=sys.stderr, position=1,
                                  leave=False) as fbar:
                            def progress(done: int, total: int | None, fbar: Any = fbar) -> None:
                                if total is not None and fbar.total != total:
                                    fbar.total = total
                                fbar.update(done - fbar.n)

                            seq = lift_video(path, lifter=lifter_for["image"], estimator=est, max_side=args.max_side,
                                             progress=progress, fps=args.fps, video_fps=args.video_fps,
                                             **seq_kw)
                    else:
                        img = load_image(path, max_side=args.max_side)  # bad files are reported as such, extra or not
                        rec = lift_image(img, lifter=lifter_for["image"], estimator=get_estimator_once(path),
                                         focal=focal, principal_point=pp, sensor_width_mm=args.sensor_width,
                                         fov_deg=args.fov, max_side=args.max_side, flip_test=args.flip_test,
                                         max_people=args.max_people, distortion=args.distortion,
                                         distortion_model=args.distortion_model, min_score=args.min_score)
                    if misnamed is not None and seq is not None:
                        seq.warnings.insert(0, misnamed)
                    elif misnamed is not None and rec is not None:
                        rec = dataclasses.replace(rec, warnings=(misnamed, *rec.warnings))
                    earlier, again = _result_input(args.out / f"{name}.json", path)  # (again: this input's own)
                    if earlier is not None and not again:
                        say(f"{path}: note: replaces {args.out / f'{name}.json'}, the result of another input "
                            f"({earlier}) written before")
                    if seq is not None:
                        write_sequence_outputs(seq, args.out, name, glb=args.glb, bvh=args.bvh, say=say, written=now)
                        for b in seq.bad_frames[:20]:
                            say(f"{path}: frame {b['index']}: {b['error']}")
                        for msg in seq.warnings:
                            say(f"{path}: note: {msg}")
                    elif rec is not None:
                        poses = np.stack([q.absolute for q in rec.people]) if rec.people else rec.absolute[None]
                        if args.glb:
                            from ..export import write_glb

                            write_glb(poses, args.out / f"{name}.glb")
                            now.append(args.out / f"{name}.glb")
                        if args.bvh:
                            from ..export import write_bvh

                            for k, pose in enumerate(poses):
                                bvh = args.out / (f"{name}.bvh" if k == 0 else f"{name}_person{k + 1}.bvh")
                                write_bvh(pose, bvh)
                                now.append(bvh)
                        # (last: a GLB or BVH that cannot be written leaves the JSON of before, not a JSON that
                        # disagrees with the files beside it, as a review's failed --focal run did)
                        write_json_atomic(args.out / f"{name}.json", rec.to_dict())
                        now.append(args.out / f"{name}.json")
                        for msg in rec.warnings:
                            say(f"{path}: note: {msg}")
                    written.update(now)
                    ok += 1  # (its outputs are whole: counted before an earlier run's are tidied away)
                    if why_not := not_valid_reasons(rec, seq):
                        not_valid += 1
                        say(f"{path}: note: the result is not valid: {'; '.join(why_not)}"
                            + (" (--strict: exit code 1)" if args.strict else " (--strict makes it exit code 1)"))
                    now = []
                    if again:  # (only this input's own earlier result: never another's, nor the user's files)
                        for msg in tidy_earlier_outputs(args.out, name, written, glb=args.glb, bvh=args.bvh,
                                                        sequence=seq is not None):
                            say(f"{path}: note: {msg}")
                except PoseLifterError as exc:
                    msg = str(exc)
                    if misnamed is not None:  # (what it was read as, which the error may not say)
                        say(f"{path}: note: {misnamed}")
                    say(f"error: {msg if msg.startswith(str(path)) else f'{path}: {msg}'}")
                    say_partial(path, now)
                    failed += 1
                except Exception as exc:  # noqa: BLE001 -- one bad input must not stop the batch
                    say(f"error: {path}: unexpected {type(exc).__name__}: {exc}")
                    say_partial(path, now)
                    failed += 1
        except KeyboardInterrupt:
            interrupted = True
    if estimator is not None and hasattr(estimator, "close"):
        estimator.close()
    bar.close()
    total = ok + failed
    if interrupted:
        part = (f"; {current}'s outputs were being written: {', '.join(p.name for p in now)} "
                f"{'is' if len(now) == 1 else 'are'} whole, the rest of them not written" if now else "")
        print(f"poselifter lift: interrupted after {ok} of {len(files)} input(s) lifted into {args.out}{part} (the "
              "files written are complete: each is written whole or not at all)", file=sys.stderr)
        return 130
    strict_fails = args.strict and (failed or not_valid)
    print(f"lifted {ok} of {total} input(s) into {args.out}"
          + (f"; {failed} failed (see the messages above)" if failed else "")
          + (f"; {not_valid} of the {ok} lifted with a result that is not valid (see the notes above)"
             if not_valid else "")
          + ("; exit code 1 (--strict)" if strict_fails and ok else ""), file=sys.stderr)
    return 0 if ok and not strict_fails else 1


def _result_input(target: Path, path: Path) -> tuple[str | None, bool]:
    """The ``input`` an existing result file ``target`` was written for, and whether that is ``path`` (None, False:
    no readable result there). Reads only the file's start (``input`` is its first field). A relative ``input`` was
    relative to a working folder that may not be this one: only the file name tells then."""
    m = re.match(r'\s*\{\s*"input":\s*("(?:[^"\\]|\\.)*")', _head(target).decode("utf-8", "replace"))
    if m is None:
        return None, False
    try:
        earlier = Path(json.loads(m.group(1)))
    except ValueError:
        return None, False
    same = earlier.resolve() == path.resolve() if earlier.is_absolute() else earlier.name == path.name
    return str(earlier), same


def tidy_earlier_outputs(out: Path, name: str, written: set[Path], *, glb: bool, bvh: bool,
                         sequence: bool) -> list[str]:
    """Notes on the files of ``<name>``'s outputs in ``out`` that this run did not write (``written``), for an input
    whose own earlier result ``<name>.json`` this run replaced (the caller checks: never another input's, nor files
    of the user's): they no longer match it (a developer trial: a photo lifted again with --max-people 1 left
    ``pair_person2.bvh`` and a two-person ``pair.glb`` beside the one-person result). Those of a kind written now
    (``--bvh``: ``<name>.bvh`` and ``<name>_person<K>.bvh`` of a photo or keypoint file, ``<name>_track<ID>.bvh`` of
    a video or sequence, ``sequence``; ``--glb``: ``<name>.glb``) are removed; those of a kind not asked for are
    left, and said."""
    bvh_family = re.compile(re.escape(name) + (r"_track\d+\.bvh" if sequence else r"(?:_person\d+)?\.bvh"))
    removed: list[str] = []
    left: list[str] = []
    try:
        entries = sorted(out.glob(glob.escape(name) + "*"))
    except OSError:
        return []
    for f in entries:
        is_bvh, is_glb = bvh_family.fullmatch(f.name) is not None, f.name == f"{name}.glb"
        if not (is_bvh or is_glb) or f in written or not f.is_file():
            continue
        if is_bvh and f.stem != name and (out / f"{f.stem}.json").exists():
            continue  # (another input's own result: "pair_person2.jpg" writes pair_person2.json and .bvh)
        if (is_bvh and bvh) or (is_glb and glb):
            try:
                f.unlink()
                removed.append(f.name)
            except OSError as exc:
                left.append(f"{f.name} (could not be removed: {exc.strerror})")
        else:
            left.append(f.name)
    notes = []
    if removed:
        notes.append(f"removed {', '.join(removed)} from {out}: an earlier run's, which this result replaces")
    if left:
        notes.append(f"{', '.join(left)} in {out} {'is' if len(left) == 1 else 'are'} an earlier run's, left as "
                     f"{'it was: it' if len(left) == 1 else 'they were: they'} may not match this result ({name}.json)")
    return notes


def write_sequence_outputs(seq: SequenceRecord, out: Path, name: str, *, glb: bool, bvh: bool,
                           say: Any = print, written: list[Path] | None = None) -> list[Path]:
    """``out/<name>.json`` for a lifted video or keypoint sequence; with ``bvh`` one animation per track
    (``<name>_track<ID>.bvh``, the track's own frames), with ``glb`` the animated scene ``<name>.glb``; the JSON
    last, so that a GLB or BVH that cannot be written leaves the JSON of before. Returns the
    files written: ``written`` (a new list when None), each appended once it is whole, so a caller interrupted
    meanwhile knows which are."""
    written = [] if written is None else written
    tracks = seq.tracks()
    if bvh:
        from ..export import write_bvh_animation

        for tid, seen in sorted(tracks.items()):
            write_bvh_animation(track_animation(seen), out / f"{name}_track{tid}.bvh", fps=seq.fps)
            written.append(out / f"{name}_track{tid}.bvh")
        if not tracks:
            say(f"{seq.input}: note: nobody in any frame; no BVH written")
    if glb:
        if tracks:
            written.append(seq.write_glb(out / f"{name}.glb"))
        else:
            say(f"{seq.input}: note: nobody in any frame; no GLB written")
    write_json_atomic(out / f"{name}.json", seq.to_dict())  # (last: see the photo's outputs in main)
    written.append(out / f"{name}.json")
    return written
