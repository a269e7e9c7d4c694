"""Several people over time: video files and keypoint sequences in, tracked and smoothed absolute 3D out.

* :class:`SequenceTracker` is the temporal core: per frame it takes the lifted people (2D keypoints, root,
  root-relative pose), gives each a stable ``track_id`` (:class:`lifter.tracking.Tracker`) and smooths each
  track's root and pose causally (:class:`lifter.smoothing.PoseSmoother`). Lifting is not part of it, so a
  keypoint sequence can be lifted in one batch and then tracked.
* :func:`lift_video` reads a video with OpenCV frame by frame, detects everyone in each frame (a
  :class:`lifter.detect.PoseEstimator2D`), lifts them and tracks them. Bad input gets a clear message and
  the rest is still lifted: a file OpenCV cannot open or decode (:class:`VideoError`), a zero-length video
  (:class:`VideoError`), a frame that cannot be decoded or whose size differs from the first frame (reported
  in ``bad_frames`` and skipped), a frame with nobody in it (an empty ``people`` list, counted in the
  warnings), more people than ``max_people`` (those continuing a tracked person are kept, then the largest:
  :func:`keep_tracked`) and a video longer than ``max_seconds`` (only its first ``max_seconds`` are lifted, with a
  warning).
* :func:`lift_keypoint_sequence` does the same for a keypoint JSON with ``frames`` (see :mod:`lifter.io`).

The camera is resolved once per video (from the first frame's size, :func:`lifter.pipeline.resolve_camera`).
Units: px and mm, seconds; camera frame OpenCV (+x right, +y down, +z forward).
"""

from __future__ import annotations

import bisect
import math
import os
import re
import time
from collections import Counter
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Final, Literal, NamedTuple

import numpy as np

from ._checks import (
    PoseLifterError,
    _real_array,
    _untorch,
    as_pair,
    collect_output_notes,
    lean_notes,
    warn_user,
)
from .camera import DEFAULT_DIAGONAL_FOV_DEG, DistortionModel, canonical_depth_from_depth
from .detect import (
    DEFAULT_MAX_SIDE_PX,
    IMAGE_SUFFIXES,
    MIN_PERSON_SCORE,
    EstimatorError,
    PoseEstimator2D,
    _StderrSilenced,
    bbox_of,
    box_iou,
    check_max_side,
    check_min_score,
    h36m_joint_scores,
    image_from_array,
    left_out_text,
    mean_person_scores,
    people_h36m,
    people_scores,
    scored_people,
)
from .io import (
    ASSUMED_FPS,
    CAMERA_DECIMALS,
    KEYPOINT_DECIMALS,
    JsonReady,
    check_frame_rate,
    depth_is_metric,
    distortion_tuple,
    is_frame_rate,
    json_head,
    model_info,
    own_fps_note,
    parse_keypoint_sequence,
)
from .keypoints import convert, placeholder_notes
from .skeleton import JOINT_NAMES
from .smoothing import PoseSmoother
from .tracking import Tracker

# FFmpeg's own log lines ("[mov,mp4 @ 0x..] moov atom not found", ...) went to stderr ahead of this module's message
# about the same problem. OpenCV reads the level once, when FFmpeg is first used: set here, at import, unless the
# user chose one.
os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")

VIDEO_SUFFIXES: Final[frozenset[str]] = frozenset(
    {".mp4", ".m4v", ".mov", ".avi", ".mkv", ".webm", ".mpg", ".mpeg", ".wmv", ".flv", ".3gp", ".ts", ".m2ts", ".mts"})
"""File suffixes treated as videos (a folder's videos are lifted too)."""

MEDIA_HEAD_BYTES: Final[int] = 512
"""How many of a file's first bytes :func:`media_kind` reads."""

_HEIF_IMAGE_BRANDS: Final[frozenset[bytes]] = frozenset(
    {b"heic", b"heix", b"heim", b"heis", b"hevc", b"hevx", b"hevm", b"hevs", b"mif1", b"msf1", b"avif", b"avis",
     b"crx "})
"""ISO-BMFF brands of images (HEIC / HEIF and AVIF, stills and image sequences, Canon CR3): an ``ftyp`` box whose
major or compatible brands include one is an image; any other is a video (MP4, MOV, 3GP, ...)."""


def media_kind(head: bytes) -> Literal["image", "video"] | None:
    """What a file's first bytes (:data:`MEDIA_HEAD_BYTES` of them) say it holds: ``"image"`` (JPEG, PNG, GIF, BMP,
    WebP, TIFF, PNM, HEIC / AVIF), ``"video"`` (MP4 / MOV / 3GP, Matroska / WebM, AVI, MPEG program or transport
    stream, M2TS, ASF / WMV, FLV) or None (neither signature: go by the file's name)."""
    h = bytes(head[:MEDIA_HEAD_BYTES])
    size = int.from_bytes(h[0:4], "big") if len(h) >= 4 else 0
    if h[4:8] == b"ftyp" and size >= 16:
        brands = [h[8:12]] + [h[i:i + 4] for i in range(16, min(size, len(h)) - 3, 4)]  # (major, then compatible)
        return "image" if any(b in _HEIF_IMAGE_BRANDS for b in brands) else "video"
    if h.startswith((b"\xff\xd8\xff", b"\x89PNG\r\n\x1a\n", b"GIF87a", b"GIF89a", b"II*\x00", b"MM\x00*")):
        return "image"
    if h.startswith(b"RIFF") and h[8:12] in (b"WEBP", b"AVI "):
        return "image" if h[8:12] == b"WEBP" else "video"
    if h.startswith(b"BM") and len(h) >= 26 and h[6:10] == b"\x00\x00\x00\x00":  # (BMP: its reserved bytes are 0)
        return "image"
    if re.match(rb"P[1-6](\s+\d|\s*#)", h):  # (PNM: "P6", then a width or a comment; "P1 is ..." is text)
        return "image"
    if h.startswith((b"\x1a\x45\xdf\xa3", b"\x00\x00\x01\xba", b"\x00\x00\x01\xb3", b"FLV\x01",
                     b"\x30\x26\xb2\x75\x8e\x66\xcf\x11")):
        return "video"
    if h[4:8] in (b"moov", b"mdat", b"wide", b"free", b"skip", b"pnot") and 8 <= size < 1 << 24:
        return "video"  # (QuickTime without an ftyp box: a small first box; "Get free ..." is text)
    if len(h) > 376 and h[0] == h[188] == h[376] == 0x47:  # (MPEG transport stream: a sync byte every 188)
        return "video"
    if len(h) > 388 and h[4] == h[196] == h[388] == 0x47:  # (BDAV / AVCHD .m2ts: 192-byte packets, 4-byte stamps)
        return "video"
    return None


def looks_like_json(head: bytes) -> bool:
    """Whether a file's first bytes start like JSON text: ``{`` or ``[`` after an optional byte-order mark (UTF-8's,
    or UTF-16's / UTF-32's: :func:`lifter.io.json_head`) and white space (a keypoint file, whatever its name)."""
    return json_head(bytes(head[:MEDIA_HEAD_BYTES])).lstrip(b"\xef\xbb\xbf").lstrip(b" \t\r\n")[:1] in (b"{", b"[")


InputKind = Literal["keypoints", "image", "video"]
"""What ``poselifter lift`` and the app's upload take a file for (:func:`input_kind`)."""


def input_kind(name: str | os.PathLike[str], head: bytes) -> tuple[InputKind, str | None]:
    """``(kind, note)`` for a file called ``name`` whose first bytes are ``head``, by its content first: JSON text
    (:func:`looks_like_json`: keypoints), else a photo's or video's signature (:func:`media_kind`), else its name
    (``.json``: keypoints; :data:`VIDEO_SUFFIXES`: a video; anything else is tried as an image). ``note`` says so
    when the content and the name disagree (a keypoint file named ``.mp4`` was tried as a video; a JPEG named
    ``.json`` was refused as "cannot read"; a JPEG renamed ``.mp4`` was lifted as a one-frame video at 25 fps; a video
    named ``.jpg`` was refused as "not an image"); a name whose suffix says nothing (``.txt``, none) is not noted.
    ``poselifter lift`` and the app's upload both go by it."""
    sfx = Path(name).suffix.lower()
    by_name: InputKind = "keypoints" if sfx == ".json" else "video" if sfx in VIDEO_SUFFIXES else "image"
    # (JSON text first: no photo's or video's signature starts with "{" or "[", but a transport stream's sync bytes
    # are a weak test that JSON text with "G" in the right places passes)
    by_content: InputKind | None = "keypoints" if looks_like_json(head) else media_kind(head)
    if by_content is None or by_content == by_name:
        return by_name, None
    if by_name == "image" and sfx not in IMAGE_SUFFIXES:
        return by_content, None
    said = {"keypoints": "keypoint JSON", "image": "an image", "video": "a video"}
    lifted = {"keypoints": "a keypoint file", "image": "a photo", "video": "a video"}
    return by_content, (f"{Path(name).name} holds {said[by_content]}, not {said[by_name]} as its name says: lifted "
                        f"as {lifted[by_content]}")


DEFAULT_MAX_SECONDS: Final[float] = 600.0
"""Videos and keypoint sequences longer than this are lifted up to this duration only."""

DEFAULT_MAX_PEOPLE: Final[int] = 3
"""People looked for per image / frame by default (the largest are kept)."""

MAX_FRAME_PIXELS: Final[int] = 40_000_000
"""A video whose frames are larger than this (px; 8K DCI is 35 MP) is refused before its frames are decoded: a
security review's 3-MiB video of 16000 x 16000 px frames took 4.1 GB."""

DEFAULT_SEARCH_EVERY_S: Final[float] = 0.5
"""Videos: the whole frame is searched for (new) people at least this often, in seconds."""

RETURN_SEARCH_S: Final[float] = 0.1
"""Videos: while fewer people were seen in the last :data:`DEFAULT_SEARCH_EVERY_S` than before someone was lost (for
up to :data:`REJOIN_MAX_S` after), the whole frame is searched this often instead (s; at least every frame): a
browser trial's second person, hidden for 1 s, was lifted again 0.3 s after they were back in view, at the next full
search (``python scripts/returning_person.py --hidden 10:22``)."""

MIN_TRACK_FRAMES: Final[int] = 2
"""Videos of at least :data:`MIN_FRAMES_FOR_TRACK_FILTER` frames: a track the detector saw in fewer frames than this
is left out (a person flashing up in one frame is almost always a false detection), with a warning naming the
frames."""

MIN_FRAMES_FOR_TRACK_FILTER: Final[int] = 10

SPARSE_TRACK_FRAMES: Final[int] = 4
SPARSE_TRACK_SHARE: Final[float] = 0.25
"""Videos of at least :data:`MIN_FRAMES_FOR_TRACK_FILTER` frames: a track seen in fewer than
:data:`SPARSE_TRACK_FRAMES` frames that fill less than this share of the video's frames from its first sighting to
its last is left out too, with a warning naming the frames (a user trial: a "person" on an empty wall, seen in frames 2
and 19 of a 25-fps clip and nowhere between, was kept as a track and lifted; a developer trial's, lifted 1.1 m from
the camera in frames 46, 65 and 86 of an empty scene, was kept with its BVH). Sightings in a row, or a person seen
in two or three frames of a 1-frame/s clip, are kept."""

CLOCK_MISMATCH: Final[float] = 10.0
""":meth:`SequenceTracker.step` warns once when the time between steps is more than this many times, or less than its
inverse times, what their frame numbers and ``fps`` say, three steps in a row (times in ms rather than s, or the wrong
fps; one late frame, a camera warming up, is not)."""


class VideoError(PoseLifterError):
    """A video file cannot be opened or decoded, or has no frames."""


@dataclass
class PersonState(JsonReady):
    """One person in one frame. keypoints_2d ``(17, 2)`` px; root ``(3,)``, relative / absolute ``(17, 3)`` mm
    (smoothed when the tracker smooths); root_raw / absolute_raw: the per-frame lift before smoothing;
    canonical_depth: mm at a 1000-px focal (of the smoothed root); scores ``(17,)`` or None."""

    track_id: int
    keypoints_2d: np.ndarray
    root: np.ndarray
    relative: np.ndarray
    root_raw: np.ndarray
    relative_raw: np.ndarray
    canonical_depth: float
    scores: np.ndarray | None = None
    person_id: str | int | None = None
    """Keypoint sequences: the person's own ``person_id`` (or ``id``, ``track_id``) field in that frame, when it
    has one (``track_id`` is the tracker's)."""

    @property
    def absolute(self) -> np.ndarray:
        return self.root[None, :] + self.relative

    @property
    def absolute_raw(self) -> np.ndarray:
        return self.root_raw[None, :] + self.relative_raw

    def to_dict(self) -> dict[str, Any]:
        r = lambda a, d=1: np.round(np.asarray(a, np.float64), d).tolist()  # noqa: E731
        return {"track_id": self.track_id, "keypoints_2d": r(self.keypoints_2d, KEYPOINT_DECIMALS),
                "absolute": r(self.absolute),
                "relative": r(self.relative), "root": r(self.root),
                "canonical_depth": round(float(self.canonical_depth), 1),
                "root_unsmoothed": r(self.root_raw),
                "scores": None if self.scores is None else r(self.scores, 3)} | (
                {} if self.person_id is None else {"person_id": self.person_id})


TRACK_TIMEOUT_S: Final[float] = 1.0
"""A track unseen this long (s) ends; a person coming back gets a new id (:class:`SequenceTracker`), unless they
are found again where their 3D root leads (:data:`REJOIN_MAX_S`)."""

REJOIN_MAX_S: Final[float] = 4.0
"""An unnamed person whose track ended (unseen for :data:`TRACK_TIMEOUT_S`) and who is found again within this long
(s) of their last sighting keeps their track id when the new sighting's 3D root lies where theirs leads
(:func:`rejoin_radius_mm`), and no one else fits there or them (a person hidden behind another, or behind a pillar,
for more than 1 s got a new id)."""

REJOIN_MIN_SIGHTINGS: Final[int] = 3
"""A track seen fewer times than this is never taken up again (a false detection's)."""

REJOIN_WINDOW_S: Final[float] = 1.0
"""Where a track ends and how fast it moves there, and where a track starts, are read over its last (first) this many
seconds, at least three sightings (per-frame lifts, not smoothed; :func:`_end_of_track`): a person being hidden by a
pillar is lifted deeper and deeper in their last frames (a developer trial: 7.4 to 10.5 m in four frames, which over
the last three and 0.5 s put them at 17 m after 2.4 s)."""

REJOIN_MAX_SPEED_MM_S: Final[float] = 3000.0
"""The velocity a track leaves with is capped at this speed (mm/s: a run; a lift's jitter over few frames is not
motion)."""


def timeout_frames(seconds: float, fps: float) -> int:
    """A track timeout of ``seconds`` in frames at ``fps`` (at least 1): a track unseen for more frames ends
    (:class:`SequenceTracker`, :func:`rejoin_tracks`)."""
    return max(1, round(seconds * fps))


def rejoin_radius_mm(gap_s: float, depth_mm: float) -> float:
    """How far (mm) from where a track's root leads (its end root moved on at its velocity for ``gap_s`` s) a new
    sighting may lie to be that person: 0.5 m, plus 10 % of the last root depth ``depth_mm`` (a lift's root error
    grows with the depth), plus 1.5 m per second of the gap (a person changes speed and direction)."""
    return 500.0 + 0.1 * max(float(depth_mm), 0.0) + 1500.0 * max(float(gap_s), 0.0)


def _end_of_track(hist: list[tuple[float, np.ndarray]]) -> tuple[float, np.ndarray, np.ndarray]:
    """``(t, root, velocity)`` of a track's end or start window (:data:`REJOIN_WINDOW_S`), from its sightings
    ``[(t s, root (3,) mm), ...]``: the median time and root, so that wrong lifts as the person disappears (or
    appears) do not lead astray while they are under half of the window, and the Theil-Sen velocity (per axis, the
    median of the slopes between every two sightings), at most :data:`REJOIN_MAX_SPEED_MM_S`."""
    t = np.array([tt for tt, _ in hist])
    r = np.stack([rr for _, rr in hist])
    t_end, root = float(np.median(t)), np.median(r, axis=0)
    i, j = np.triu_indices(len(t), 1)
    ok = t[j] != t[i]
    v = np.zeros(3)
    if ok.any():
        v = np.median((r[j[ok]] - r[i[ok]]) / (t[j[ok]] - t[i[ok]])[:, None], axis=0)
        speed = float(np.linalg.norm(v))
        v = v * min(1.0, REJOIN_MAX_SPEED_MM_S / speed) if speed > 0 else v
    return t_end, root, v


class Rejoin(NamedTuple):
    """A track taken up again by :func:`rejoin_tracks`: ``track_id`` (kept), ``gone`` (the id the later part had,
    now ``track_id``), the frame it was found again in, and how long (s) it was unseen."""

    track_id: int
    gone: int
    frame: int
    gap_s: float


def check_rejoin_s(rejoin_s: float) -> None:
    if not (math.isfinite(rejoin_s) and (rejoin_s == 0 or rejoin_s > TRACK_TIMEOUT_S)):
        raise PoseLifterError(f"rejoin_s must be 0 (never) or more than the {TRACK_TIMEOUT_S:g}-s track timeout, "
                              f"got {rejoin_s}")


def rejoin_tracks(frames: list[FrameResult], *, fps: float, rejoin_s: float = REJOIN_MAX_S) -> list[Rejoin]:
    """Take up ended tracks again (:data:`REJOIN_MAX_S`), in place: a track that starts more than the tracker's
    timeout (:data:`TRACK_TIMEOUT_S`, in frames at ``fps``) and at most ``rejoin_s`` s after another ended, whose
    start (the median of its first :data:`REJOIN_WINDOW_S` of per-frame roots) lies within :func:`rejoin_radius_mm`
    of where that one's end leads (the median of its last, moved on at its velocity: :func:`_end_of_track`), gets
    that track's id, when neither fits any other such track. Both must be seen :data:`REJOIN_MIN_SIGHTINGS` times or
    more and be unnamed (the input's own ``person_id`` takes named people up again:
    :class:`lifter.tracking.Tracker`). Run it after false detections are left out. Returns what it joined, by
    frame."""
    check_rejoin_s(rejoin_s)
    if rejoin_s == 0:
        return []
    shared = _shared_person_ids(frames)
    time_of = {fr.index: fr.time_s for fr in frames}
    timeout = timeout_frames(TRACK_TIMEOUT_S, fps)
    ends, starts = {}, {}
    for tid, at in _tracks(frames).items():
        if len(at) < REJOIN_MIN_SIGHTINGS or _track_person_id(at, shared) is not None:
            continue
        hist = [(time_of[i], np.asarray(q.root_raw, np.float64)) for i, q in at]
        tail = [h for h in hist if hist[-1][0] - h[0] <= REJOIN_WINDOW_S]
        ends[tid] = (at[0][0], at[-1][0], *_end_of_track(tail if len(tail) >= 3 else hist[-3:]))
        head = [h for h in hist if h[0] - hist[0][0] <= REJOIN_WINDOW_S]
        starts[tid] = _end_of_track(head if len(head) >= 3 else hist[:3])[:2]
    fits: dict[tuple[int, int], float] = {}  # (ended track, later track) -> seconds unseen between them
    for a, (_, last_a, t_a, root_a, v_a) in ends.items():
        for b, (t_b, root_b) in starts.items():
            first_b = ends[b][0]
            gap_s = time_of[first_b] - time_of[last_a]
            if a == b or first_b - last_a <= timeout or gap_s > rejoin_s:
                continue
            # (the prediction runs between the windows' middles; the uncertainty grows with the time unseen)
            if np.linalg.norm(root_b - (root_a + v_a * (t_b - t_a))) <= rejoin_radius_mm(gap_s, float(root_a[2])):
                fits[a, b] = gap_s
    per_ended, per_later = Counter(a for a, _ in fits), Counter(b for _, b in fits)
    joined: list[Rejoin] = []
    new_id: dict[int, int] = {}
    for (a, b), gap_s in sorted(fits.items(), key=lambda f: ends[f[0][1]][0]):
        if per_ended[a] == 1 and per_later[b] == 1:
            new_id[b] = new_id.get(a, a)
            joined.append(Rejoin(new_id[b], b, ends[b][0], gap_s))
    for fr in frames:
        for q in fr.people:
            q.track_id = new_id.get(q.track_id, q.track_id)
    return joined


def renumber_tracks(frames: list[FrameResult], joined: list[Rejoin] | None = None) -> list[Rejoin]:
    """Number the tracks of ``frames`` 1, 2, 3, ... in the order they first appear (by frame, then the frame's order of
    people), in place, and return ``joined`` (:func:`rejoin_tracks`) with their kept ids numbered alike (``gone``
    stays the tracker's). The tracker never gives an id twice, so false detections left out and tracks taken up again
    leave gaps (a developer trial's two people were tracks 1 and 4); the output's ids have none."""
    new: dict[int, int] = {}
    for fr in frames:
        for q in fr.people:
            new.setdefault(q.track_id, len(new) + 1)
    for fr in frames:
        for q in fr.people:
            q.track_id = new[q.track_id]
    return [r._replace(track_id=new.get(r.track_id, r.track_id)) for r in (joined or [])]


def rejoin_notes(joined: list[Rejoin]) -> list[str]:
    """One note per track :func:`rejoin_tracks` took up again."""
    return [f"track {r.track_id}: found again at frame {r.frame} after {r.gap_s:.2f} s unseen (longer than the "
            f"tracker's {TRACK_TIMEOUT_S:g}-s timeout), where its 3D root led and no one else fitted: taken as the "
            f"same person (someone else who came in just there would share this id; between the two, the BVH "
            f"animation is interpolated and the GLB hides them)" for r in joined]


class SequenceTracker:
    """Track ids and causal smoothing for the lifted people of consecutive frames (module docstring).

    smoothing: :class:`lifter.smoothing.PoseSmoother` strength (0 = off). fps: frame rate, for the track
    timeout ``max_missed_s`` (a track unseen that long ends; a person coming back gets a new id).
    """

    def __init__(self, *, fps: float, smoothing: float = 1.0, max_missed_s: float = TRACK_TIMEOUT_S) -> None:
        if not (math.isfinite(fps) and fps > 0):
            raise PoseLifterError(f"fps must be > 0, got {fps}")
        PoseSmoother(smoothing)  # validates the strength
        self.fps, self.smoothing = float(fps), float(smoothing)
        self.tracker = Tracker(max_missed=timeout_frames(max_missed_s, fps))
        self._smoothers: dict[int, PoseSmoother] = {}
        self._focal_geo: float | None = None
        self._last: tuple[int, float] | None = None  # (frame, t) of the last step
        self._clock_off = 0  # steps in a row whose time is CLOCK_MISMATCH off their frames' (-1: warned)

    def step(self, frame: int, t: float, keypoints_2d: np.ndarray, root: np.ndarray, relative: np.ndarray,
             focal: np.ndarray, scores: np.ndarray | None = None,
             person_ids: list[str | int | None] | None = None) -> list[PersonState]:
        """The people of frame number ``frame`` at ``t`` s: ``keypoints_2d (n, 17, 2)`` px, ``root (n, 3)`` and
        ``relative (n, 17, 3)`` mm (camera frame, OpenCV), the frame's ``focal`` px (scalar or ``(2,)``; a
        LiftResult's per-pose ``(n, 2)`` of one frame too); ``scores (n, 17)`` or None. ``n = 0`` (empty arrays
        or lists) is a frame with nobody. A single person's arrays without the leading ``n`` axis are refused with
        the shapes expected. ``person_ids``: the input's own name for each person (a keypoint sequence's
        ``person_id``, None: unnamed), which the tracker follows over the boxes (:class:`lifter.tracking.Tracker`)."""
        # (torch tensors and lists as lift takes them: a developer trial's tensors met a raw torch TypeError)
        kp = _real_array(keypoints_2d, name="keypoints_2d", what="an array of 2D keypoints")
        root = _real_array(root, name="root", what="an array of roots")
        relative = _real_array(relative, name="relative", what="an array of relative poses")
        scores = None if scores is None else np.asarray(_untorch(scores), np.float64)
        nobody = kp.size == 0 and np.size(root) == 0 and np.size(relative) == 0
        if not nobody:
            n = kp.shape[0] if kp.ndim == 3 else -1
            shapes = {"keypoints_2d": (kp.shape, (n, 17, 2)), "root": (np.shape(root), (n, 3)),
                      "relative": (np.shape(relative), (n, 17, 3))}
            if scores is not None:
                shapes["scores"] = (np.shape(scores), (n, 17))
            wrong = [f"{k} {got}" for k, (got, want) in shapes.items() if got != want]
            if n < 0 or wrong:
                raise PoseLifterError(
                    "SequenceTracker.step: expected keypoints_2d (n, 17, 2), root (n, 3), relative (n, 17, 3)"
                    f"{', scores (n, 17)' if scores is not None else ''} for the n people of the frame (one person: "
                    f"n = 1, e.g. root[None]); got {', '.join(wrong) if wrong else f'keypoints_2d {kp.shape}'}")
            f = as_pair(focal, name="focal", positive=True, scalar=True).reshape(-1, 2)
            if not np.all(f == f[0]):  # (a LiftResult's per-pose focal (n, 2) of one frame is fine)
                raise PoseLifterError(f"SequenceTracker.step: focal: one focal length for the frame (scalar or (2,) "
                                      f"px), got {len(f)} different ones")
            focal = f[0]
            bad = [i for i in range(n) if not (np.all(np.isfinite(root[i])) and np.all(np.isfinite(relative[i])))]
            if bad:  # (one NaN root would leave its track's smoother NaN for good: a user trial's)
                raise PoseLifterError(f"SequenceTracker.step: frame {frame}: person {bad[0]}'s root or relative pose "
                                      "is not finite (NaN or inf); step only lifted poses (Lifter.lift refuses such "
                                      "2D), and leave a person out of a frame rather than give NaN")
        if self._last is not None and not (frame > self._last[0] and t > self._last[1]):
            raise PoseLifterError(f"SequenceTracker.step: frame {frame} at {t:g} s comes after frame {self._last[0]} "
                                  f"at {self._last[1]:g} s: frames and times must increase (nothing was updated)")
        clock = self._clock_off
        if self._last is not None and clock >= 0:
            said, by_frames = t - self._last[1], (frame - self._last[0]) / self.fps
            ratio = said / by_frames
            clock = clock + 1 if not 1 / CLOCK_MISMATCH <= ratio <= CLOCK_MISMATCH else 0
            if clock == 3:  # (once: a whole clip in ms would say it every frame)
                clock = -1
                unit = ("t looks like milliseconds: pass seconds (ms / 1000)" if ratio > 100 else
                        "pass t in seconds" if ratio > 1 else "pass t in seconds on the frames' own clock")
                times = f"{ratio:.0f}" if ratio >= 10 else f"{ratio:.2g}"
                warn_user(
                    f"SequenceTracker.step: frame {frame} comes {said:g} s after frame {self._last[0]}, where fps="
                    f"{self.fps:g} puts it {by_frames:g} s after ({times} times), three steps in a row: {unit}, or "
                    "give the frames' true fps; the smoothing follows t")
        ids = self.tracker.update(frame, [] if nobody else list(kp), None if nobody else person_ids)
        self._last = (int(frame), float(t))  # (once the tracker took it: a refused frame may be given again)
        self._clock_off = clock
        for tid in list(self._smoothers):
            if tid not in self.tracker.tracks or tid in self.tracker.resumed:
                del self._smoothers[tid]  # ended tracks, and those a name took up again after the timeout
        out = []
        for i, tid in enumerate(ids):
            sm = self._smoothers.setdefault(tid, PoseSmoother(self.smoothing))
            r, rel = sm(root[i], relative[i], t)
            out.append(PersonState(track_id=tid, keypoints_2d=kp[i].copy(), root=r,
                                   relative=rel, root_raw=np.asarray(root[i], np.float64),
                                   relative_raw=np.asarray(relative[i], np.float64),
                                   canonical_depth=float(canonical_depth_from_depth(r[2], focal=focal)),
                                   scores=None if scores is None else np.asarray(scores[i], np.float64),
                                   person_id=None if person_ids is None else person_ids[i]))
        return out


@dataclass
class FrameResult(JsonReady):
    """One frame: its number, time (s) and the people in it, largest first."""

    index: int
    time_s: float
    people: list[PersonState]

    def to_dict(self) -> dict[str, Any]:
        return {"index": self.index, "time_s": round(self.time_s, 4), "people": [p.to_dict() for p in self.people]}


OUTPUT_NOTE_LINE: Final[re.Pattern[str]] = re.compile(r"frame \d+: ")
"""How a record's line of :func:`output_note_lines` begins (and no other of its notes does)."""


def track_animation(seen: list[tuple[int, PersonState]]) -> np.ndarray:
    """One track's poses on the video's own frame clock, for formats with one pose per frame at a fixed rate
    (BVH): ``(last frame + 1, 17, 3)`` mm (camera frame), frame ``i`` at ``i / fps``. ``seen``: the track's
    ``(frame index, person)`` in frame order (:meth:`SequenceRecord.tracks`). Frames where the track is not seen
    are filled: before its first frame its first pose is held, and a gap is interpolated linearly, joint by joint,
    between the poses on either side (a user trial: the frames were dropped, so everything after a gap, or a
    track that started late, played early)."""
    if not seen:
        raise PoseLifterError("track_animation: the track has no frames")
    idx = np.array([i for i, _ in seen], np.float64)
    poses = np.stack([np.asarray(p.absolute, np.float64) for _, p in seen])
    t = np.arange(int(idx[-1]) + 1, dtype=np.float64)
    flat = poses.reshape(len(poses), -1)
    out = np.stack([np.interp(t, idx, flat[:, k]) for k in range(flat.shape[1])], axis=-1)  # (held before the first)
    return out.reshape(len(t), *poses.shape[1:])


def tracked_output_notes(net: Any, frames: list[FrameResult], principal_point: Any, *, source: str,
                         only: set[int] | None = None, focal: Any = None,
                         lifted_2d: dict[int, np.ndarray] | None = None) -> dict[str, tuple[int, int, str]]:
    """What looks wrong in tracked frames' lifts (``net.output_notes``, :meth:`lifter.Lifter.output_notes`, on each
    person's unsmoothed root), collected per kind (:func:`collect_output_notes`), each note naming the person by
    the track id the record gives them (``"track 3"``: a frame position would not find them in the record).
    ``only``: the frame indices to look at (those whose lift had notes); None: every frame. ``lifted_2d``: per frame
    index, the ``(n, 17, 2)`` px 2D that was lifted, in the frame's order of people, where it is not the record's own
    (undistorted through a lens: a review saw the lens's distorted 2D judged against the lift, a false note)."""
    acc: dict[str, tuple[int, int, str]] = {}
    for fr in frames:
        if not fr.people or (only is not None and fr.index not in only):
            continue
        kp = (lifted_2d[fr.index] if lifted_2d is not None and fr.index in lifted_2d
              else np.stack([q.keypoints_2d for q in fr.people]))
        root = np.stack([q.root_raw for q in fr.people])
        collect_output_notes(acc, fr.index, net.output_notes(kp, principal_point, root, source=source,
                                                             names=[f"track {q.track_id}" for q in fr.people],
                                                             relative=np.stack([q.relative_raw for q in fr.people]),
                                                             focal=focal))
    return acc


def output_note_lines(acc: dict[str, tuple[int, int, str]]) -> list[str]:
    """The record's lines for :func:`collect_output_notes`: the first frame's note, and how many frames had it."""
    return [f"frame {first}: {message}" + (f" ({n} frames like it)" if n > 1 else "")
            for first, n, message in acc.values()]


@dataclass
class SequenceRecord(JsonReady):
    """A lifted video or keypoint sequence; :meth:`to_dict` is what ``DIR/<name>.json`` holds."""

    input: str
    kind: str
    model: str
    fps: float
    image_size: tuple[int, int] | None
    focal: tuple[float, float]
    focal_source: str
    principal_point: tuple[float, float]
    smoothing: float
    frames: list[FrameResult]
    num_frames_in_file: int | None = None
    bad_frames: list[dict[str, Any]] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    detector: str | None = None
    seconds_per_frame: float | None = None
    """Wall-clock seconds this run took per frame (detection, lift, tracking): a timing, not the frame period
    (``1 / fps``), so it differs from run to run; None for keypoint sequences."""
    source: str = "detected"
    distortion: tuple[float, ...] | None = None
    """The lens distortion the 2D was given with (a keypoint sequence's ``distortion``), or None."""
    distortion_model: DistortionModel = "h36m"
    """The form of :attr:`distortion`: ``"h36m"`` or ``"opencv"`` (:data:`lifter.camera.DistortionModel`)."""
    source_format: str | None = None
    """The keypoint format the 2D came in before conversion to H36M (a sequence's ``format``, the detector's), or
    None when no frame had anyone."""
    model_info: dict[str, Any] | None = None
    """What lifted it (:func:`lifter.io.model_info`), or None for a lifter-like object that does not say."""
    tracking_names: list[list[Any]] | None = None
    """Per frame, for each person in it, the name the tracker followed (:func:`tracking_names` of the whole
    input, before a ``max_people`` cut), or None: to track the frames again as they were (not written)."""

    def tracks(self) -> dict[int, list[tuple[int, PersonState]]]:
        """``track_id -> [(frame index, person), ...]`` in frame order."""
        return _tracks(self.frames)

    def track_person_ids(self) -> dict[int, str | int | None]:
        """``track_id -> `` the input's own id of the track's person (a keypoint sequence's ``person_id``), when
        every sighting that has one gives the same; None for a video, an unnamed person, or ids new in every frame
        (an annotation's own). As the written record's ``tracks`` give it."""
        return self._person_ids(self.tracks())

    def _person_ids(self, tracks: dict[int, list[tuple[int, PersonState]]]) -> dict[int, str | int | None]:
        """:meth:`track_person_ids` of :meth:`tracks` already gathered."""
        shared = _shared_person_ids(self.frames)
        return {tid: _track_person_id(seen, shared) for tid, seen in sorted(tracks.items())}

    def write_glb(self, path: str | Path) -> Path:
        """Every track as one animated binary glTF (:func:`lifter.export.write_glb_animation`; metres, y-up) on the
        input's frame clock, from frame 0 to its last frame (one it could not read too), everyone hidden in the frames
        they are not seen in (a user trial's clip started at the first person's first frame, which glTF viewers
        then showed from frame 0), and interpolated in frames the record does not hold. Raises
        :class:`PoseLifterError` when nobody is in any frame."""
        from .export import write_glb_animation

        tracks = self.tracks()
        if not tracks:
            raise PoseLifterError(f"{self.input}: nobody in any frame; nothing to animate")
        return write_glb_animation({tid: ([i for i, _ in seen], np.stack([p.absolute for _, p in seen]))
                                    for tid, seen in tracks.items()}, path, fps=self.fps,
                                   span=(0, max([fr.index for fr in self.frames]
                                                + [int(b["index"]) for b in self.bad_frames if "index" in b])),
                                   recorded=[fr.index for fr in self.frames])

    @property
    def metric_depth(self) -> bool:
        """Whether the absolute depths (mm) rest on the camera's own focal length
        (:func:`lifter.io.depth_is_metric` of :attr:`focal_source`), as the written record's ``metric_depth`` says."""
        return depth_is_metric(self.focal_source)

    def to_dict(self) -> dict[str, Any]:
        by_track = self.tracks()
        named = self._person_ids(by_track)
        tracks = [{"track_id": tid, "first_frame": seen[0][0], "last_frame": seen[-1][0], "num_frames": len(seen),
                   "person_id": named[tid]} for tid, seen in sorted(by_track.items())]
        return {
            "input": self.input, "kind": self.kind, "model": self.model, "model_info": self.model_info,
            "joint_names": list(JOINT_NAMES),
            "units": {"keypoints_2d": "px", "absolute": "mm", "relative": "mm", "root": "mm", "canonical_depth": "mm",
                      "focal": "px", "principal_point": "px", "time_s": "s", "fps": "frames/s"},
            "frame": "camera, OpenCV: +x right, +y down, +z forward; 2D in px of the full-resolution frame",
            "fps": round(self.fps, 4), "num_frames": len(self.frames), "num_frames_in_file": self.num_frames_in_file,
            "image_size": None if self.image_size is None else [int(v) for v in self.image_size],
            "focal": [round(v, CAMERA_DECIMALS) for v in self.focal], "focal_source": self.focal_source,
            "metric_depth": self.metric_depth,
            "principal_point": [round(v, CAMERA_DECIMALS) for v in self.principal_point], "source": self.source,
            **({} if self.distortion is None else {"distortion": [float(v) for v in self.distortion],
                                                   "distortion_model": self.distortion_model}),
            "source_format": self.source_format, "detector": self.detector,
            "smoothing": {"filter": "one-euro, causal", "strength": self.smoothing},
            "seconds_per_frame": None if self.seconds_per_frame is None else round(self.seconds_per_frame, 4),
            "tracks": tracks, "bad_frames": self.bad_frames, "warnings": self.warnings,
            "frames": [f.to_dict() for f in self.frames],
        }


TRACKED_IOU: Final[float] = 0.3
"""A person found in a frame continues a tracked person when their boxes overlap by at least this (IoU)."""


def keep_tracked(boxes: list[np.ndarray], tracked: list[np.ndarray], *, max_people: int,
                 ids: list[Any] | None = None, tracked_ids: list[Any] | None = None,
                 others: list[bool] | None = None) -> list[int]:
    """Which of a frame's people (their ``boxes``, ``(x, y, w, h)`` px, largest first) to lift when it has more than
    ``max_people``: their indices, first those continuing a person tracked in recent frames (the same ``ids`` entry
    as one of ``tracked_ids``, when the file names its people; else a box overlapping one of ``tracked`` by at least
    :data:`TRACKED_IOU`, the best overlap first, not counting a tracked person the file names otherwise;
    ``tracked_ids`` are the names of ``tracked``, in the same order, None where unnamed), then the largest of the
    rest, those that :func:`changed_shape` from a tracked box (a person whose arms moved: a user trial's followed
    person was dropped for a stranger so) before the others, and last those ``others`` marks True (someone else, seen
    beside the tracked people until now). So ``--max-people 1`` follows one person through a
    video or a keypoint sequence instead of switching to whoever looks largest in a frame."""
    known = {i for i, pid in enumerate(ids or []) if pid is not None and pid in (tracked_ids or [])}
    names = list(ids) if ids is not None else [None] * len(boxes)
    tracked_names = list(tracked_ids) if tracked_ids is not None and len(tracked_ids) == len(tracked) else (
        [None] * len(tracked))

    def rank(i: int) -> tuple[int, float, int]:
        if i in known:
            return (0, 0.0, i)
        if others is not None and others[i]:
            return (4, 0.0, i)
        box = np.asarray(boxes[i], float)
        allowed = [np.asarray(b, float) for b, n in zip(tracked, tracked_names) if _names_agree(n, names[i])]
        o = max((box_iou(box, b) for b in allowed), default=0.0)
        if o >= TRACKED_IOU:
            return (1, -o, i)
        return (2, -o, i) if any(changed_shape(b, box) for b in allowed) else (3, 0.0, i)

    return sorted(range(len(boxes)), key=rank)[:max_people]


def _names_agree(a: Any, b: Any) -> bool:
    """Whether two people's names (None: unnamed) allow them to be one person: either is unnamed, or they are equal
    (a tracked person the file names otherwise is not continued by another name)."""
    return a is None or b is None or a == b


def changed_shape(tracked: np.ndarray, box: np.ndarray) -> bool:
    """Whether ``box`` ``(x, y, w, h)`` px, overlapping the ``tracked`` box by less than :data:`TRACKED_IOU`, is
    still most likely the same person with their box's shape changed (arms out, a crouch): its centre within a
    quarter of the tracked box's width and height of the tracked centre, and its area within a factor 2. A
    neighbour beside them is not (a review: a neighbour touching the followed box took the followed person's place
    while they were hidden, for good)."""
    t, b = np.asarray(tracked, np.float64), np.asarray(box, np.float64)
    if min(t[2], t[3], b[2], b[3]) <= 0:
        return False
    d = np.abs((b[:2] + b[2:] / 2) - (t[:2] + t[2:] / 2))
    ratio = (b[2] * b[3]) / (t[2] * t[3])
    return bool(d[0] <= 0.25 * t[2] and d[1] <= 0.25 * t[3] and 0.5 <= ratio <= 2.0)


def tracking_names(ids: list[list[Any]]) -> list[list[Any]]:
    """Per frame, the names the tracker follows among a sequence's person ids ``ids`` (per frame, per person; None:
    unnamed): an id seen in one frame only is left out (None), as are ids repeated within a frame. An annotation's
    own ``id``, new in every frame (COCO, PoseTrack), then leaves the people to their boxes instead of making each
    sighting a new person (a review found that); a ``person_id`` or ``track_id`` that recurs decides. A name is its
    text: ``1`` and ``"1"`` are one person (a user trial's file mixed them, and got two half-empty tracks)."""
    texts = [[None if p is None else str(p) for p in frame] for frame in ids]
    frames_of: dict[str, int] = {}
    for frame in texts:
        for pid in set(p for p in frame if p is not None):
            frames_of[pid] = frames_of.get(pid, 0) + 1
    out: list[list[Any]] = []
    for frame in texts:
        twice = repeated_ids(frame)
        out.append([p if p is not None and frames_of[p] > 1 and p not in twice else None for p in frame])
    return out


def repeated_ids(frame: list[Any]) -> dict[str, None]:
    """The person ids one frame gives to more than one person (``frame``: each person's id, None: unnamed), as text
    (``1`` and ``"1"`` are one), in first-seen order: nobody's name (:func:`tracking_names` does not follow them,
    and they name no track)."""
    texts = [str(p) for p in frame if p is not None]
    return dict.fromkeys(t for t in texts if texts.count(t) > 1)


FOLLOWED_RECENT_S: Final[float] = 0.25
"""With ``max_people`` followed, each seen within this, someone whose box overlaps none of theirs is not lifted
(:class:`_Followed`; in whole frames, none below 2 frames/s): within it a walker moves about 0.35 m, under a box's
width."""


@dataclass
class _Followed:
    """The people a keypoint sequence's ``max_people`` cut follows: each with the frame it was last kept in, its box
    ``(x, y, w, h)`` px and the file's name for it. Those kept again are refreshed; someone else joins only while
    there is room, so a person missing from a frame or two (a joint left out) is not replaced by whoever was alone
    there; a person unseen for ``horizon`` frames (a track's timeout) is let go. A person the cut kept because their
    box :func:`changed_shape` from a followed one refreshes that box (else it went stale, and a stranger took its
    place three frames later in a user trial). ``others``: the boxes of the unnamed people not lifted, with the frame
    each was last seen in: one who continues them (overlapping by :data:`TRACKED_IOU`, more than any followed box)
    is someone else, not lifted while the followed people are held (a developer trial's second person, beside the
    followed one all along, was lifted under the followed one's track while they were hidden for 0.5 s, and kept
    when they came back)."""

    max_people: int
    horizon: int
    recent: int = 0
    seen_every: int = 1  # (frames between sightings of the people not lifted: a video's full searches)
    people: list[tuple[int, np.ndarray, Any]] = field(default_factory=list)
    set_aside: int = 0
    aside_frames: list[int] = field(default_factory=list)
    others: list[tuple[int, np.ndarray]] = field(default_factory=list)

    @classmethod
    def at_fps(cls, *, max_people: int, fps: float, seen_every: int = 1) -> _Followed:
        """Followed people let go after the track timeout (:data:`TRACK_TIMEOUT_S`), recent within
        :data:`FOLLOWED_RECENT_S`, in frames at ``fps``. ``seen_every``: how many frames apart the people not lifted
        are seen (a video searches the whole frame every so many; between, only around those lifted): those seen
        beside the followed people are remembered that long at least (a developer trial's, seen every 5th frame and
        forgotten after 2, took the followed person's place when they were hidden)."""
        return cls(max_people=max_people, horizon=timeout_frames(TRACK_TIMEOUT_S, fps),
                   recent=round(fps * FOLLOWED_RECENT_S), seen_every=max(int(seen_every), 1))

    def aside_note(self) -> list[str]:
        """The note on the frames where someone was set aside (else they read only as frames the followed people
        are missing from: a review)."""
        if not self.aside_frames:
            return []
        return [f"someone else was found while the people followed were missing, and not lifted, in "
                f"{len(self.aside_frames)} frame(s) ({_frames_summary(self.aside_frames)}): someone seen beside them "
                f"before is not taken for them until they have been gone {TRACK_TIMEOUT_S:g} s, nor, within "
                f"{FOLLOWED_RECENT_S:g} s of a followed person's last sighting, one whose box overlaps none of theirs "
                "(--max-people)"]

    def keep(self, frame: int, boxes: list[np.ndarray], names: list[Any]) -> list[int]:
        """Which of the frame's people (largest first) to lift (:func:`keep_tracked` when there are too many). While
        as many people are followed as may be and each was seen within ``recent`` frames, someone whose box overlaps
        none of theirs is someone else, set aside (``set_aside`` counts them; the file's names decide where it names
        them all): a developer trial's followed walker, missed by the detector for a frame, was replaced there by
        a person 2 m deeper, 120 px to the side, who took their track (and the walker came back under another).
        Once they have been unseen longer, someone else is lifted while alone (and followed after ``horizon``),
        except one who continues someone seen beside them (``others``), who waits the whole ``horizon``."""
        self.people = [q for q in self.people if frame - q[0] <= self.horizon]
        self.others = [q for q in self.others if frame - q[0] <= max(self.recent, self.seen_every, 1)]
        held = len(self.people) >= self.max_people
        # (each remembered other continues at most one unnamed box of this frame, the best overlapping first, so that
        # someone standing where the other stood is not taken for them while the other is there too)
        claims: dict[int, int] = {}  # box -> its entry in self.others
        claimed: set[int] = set()  # (those entries)
        pairs = sorted(((box_iou(b, boxes[j]), e, j) for e, (_, b) in enumerate(self.others)
                        for j in range(len(boxes)) if names[j] is None), reverse=True)
        for o, e, j in pairs:
            if o >= TRACKED_IOU and e not in claimed and j not in claims:
                claims[j] = e
                claimed.add(e)

        def other(j: int) -> bool:
            if not held or j not in claims:
                return False
            o = box_iou(self.others[claims[j]][1], boxes[j])
            return o > max((box_iou(b, boxes[j]) for _, b, _ in self.people), default=0.0)

        is_other = [other(j) for j in range(len(boxes))]
        full = held and all(frame - q[0] <= self.recent for q in self.people)
        if len(boxes) > self.max_people:
            keep = keep_tracked(boxes, [b for _, b, _ in self.people], max_people=self.max_people, ids=names,
                                tracked_ids=[n for *_, n in self.people], others=is_other)
        else:
            keep = list(range(len(boxes)))
        self.set_aside = 0
        if held and any(is_other[j] for j in keep):  # (someone seen beside the followed people: not them)
            kept = [j for j in keep if not is_other[j]]
            self.set_aside, keep = len(keep) - len(kept), kept
            self.aside_frames.append(frame)
        if full:  # (a person named otherwise than each followed one is lifted: the tracker keeps names apart)
            def them(j: int) -> bool:
                if names[j] is not None and all(n is not None for *_, n in self.people):
                    return True
                return any(n == names[j] if n is not None and names[j] is not None else box_iou(b, boxes[j]) > 0
                           for _, b, n in self.people)

            kept = [j for j in keep if them(j)]
            aside = len(keep) - len(kept)
            if aside and not self.set_aside:
                self.aside_frames.append(frame)
            self.set_aside, keep = self.set_aside + aside, kept
        taken: set[int] = set()
        unmatched: list[int] = []
        for j in keep:
            same = [k for k, (_, b, n) in enumerate(self.people) if k not in taken and (
                n == names[j] if n is not None and names[j] is not None else box_iou(b, boxes[j]) >= TRACKED_IOU)]
            if same:
                k = max(same, key=lambda k: box_iou(self.people[k][1], boxes[j]))
                self.people[k] = (frame, boxes[j], names[j] if names[j] is not None else self.people[k][2])
                taken.add(k)
            elif len(self.people) < self.max_people:
                self.people.append((frame, boxes[j], names[j]))
                taken.add(len(self.people) - 1)
            elif len(boxes) > self.max_people:  # (kept by the cut as one whose box changed shape: that person)
                near = [(box_iou(b, boxes[j]), k) for k, (_, b, n) in enumerate(self.people)
                        if k not in taken and _names_agree(n, names[j]) and changed_shape(b, boxes[j])]
                if near:
                    k = max(near)[1]
                    self.people[k] = (frame, boxes[j], names[j] if names[j] is not None else self.people[k][2])
                    taken.add(k)
                else:
                    unmatched.append(j)
            else:
                unmatched.append(j)
        # one lifted while someone seen beside the followed people is there in the same frame, whom no followed
        # box continues, is a followed person back where their box no longer reaches (a developer trial's followed
        # person, hidden 0.8 s, came back 60 px away: lifted for 1 s, then their entry, never refreshed, was let go
        # and the other took their place for the rest of the sequence): that person's entry, the longest unseen
        # (near where they were and about their size: a review's stranger far away took the place of a followed
        # person coming back to the very box they left)
        if unmatched and any(is_other):
            stale = sorted((q[0], k) for k, q in enumerate(self.people)
                           if k not in taken and frame - q[0] > self.recent)
            for j in [j for j in unmatched if names[j] is None]:
                near = [k for _, k in stale if k not in taken and _near_box(self.people[k][1], boxes[j])]
                if near:
                    self.people[near[0]] = (frame, boxes[j], self.people[near[0]][2])
                    taken.add(near[0])
        # (the unnamed people not lifted in a frame where a followed person was: someone else, followed from frame to
        # frame by their boxes as long as they are not lifted; not a stranger set aside while the followed were away)
        beside = bool(taken)
        self.others = [q for e, q in enumerate(self.others) if e not in claimed] + [
            (frame, np.asarray(boxes[j], np.float64)) for j in range(len(boxes))
            if j not in keep and names[j] is None and (beside or j in claims)]
        return keep


def _near_box(old: np.ndarray, new: np.ndarray) -> bool:
    """Whether the box ``new`` ``(x, y, w, h)`` px could be the person of ``old`` back after a while: its centre within
    the wider box's width across and half the taller's height up or down, its area within half to twice ``old``'s."""
    (x0, y0, w0, h0), (x1, y1, w1, h1) = (np.asarray(b, np.float64) for b in (old, new))
    area = (w1 * h1) / max(w0 * h0, 1e-9)
    return bool(abs((x1 + w1 / 2) - (x0 + w0 / 2)) <= max(w0, w1) and abs((y1 + h1 / 2) - (y0 + h0 / 2))
                <= 0.5 * max(h0, h1) and 0.5 <= area <= 2.0)


def _left_out_note(left_out: list[tuple[int, float]], text: str) -> str:
    """The note on the detections (or a sequence's people) left out below the score floor, ``(frame index, mean joint
    score)`` each: the frames, then ``text`` (:func:`lifter.detect.left_out_text`)."""
    at_frames = sorted({i for i, _ in left_out})
    return f"in {len(at_frames)} frame(s) ({_frames_summary(at_frames)}), {text}"


def _crowd_note(max_people: int, crowded: list[int], *, searched: tuple[int, int] | None = None) -> str:
    """The note on frames with more people than ``max_people``; ``searched``: a video's count of frames searched in
    full and of all its frames (between full searches only around the people followed, so a crowd can be missed
    there)."""
    people = "person" if max_people == 1 else "people"
    where = (f"{len(crowded)} frames" if searched is None else
             f"{len(crowded)} of the {searched[1]} frames ({searched[0]} of them searched in full; between those only "
             "the people followed are looked for)")
    return (f"more than {max_people} {people} in {where} ({_frames_summary(crowded)}); {max_people} "
            f"{'was' if max_people == 1 else 'were'} lifted (--max-people): those already tracked, else the largest")


def _shared_person_ids(frames: list[FrameResult]) -> set[str]:
    """The input's person ids (as text: ``1`` and ``"1"`` are one) that some frame gives to more than one person: not
    anyone's name (:func:`tracking_names` does not follow them either)."""
    return {t for fr in frames for t in repeated_ids([q.person_id for q in fr.people])}


def _track_person_id(seen: list[tuple[int, PersonState]], shared: frozenset[str] | set[str] = frozenset()
                     ) -> str | int | None:
    """The input's own id of a track's person (a keypoint sequence's ``person_id``) when every sighting that has one
    gives the same; None for a video, an unnamed person, ids new in every frame (an annotation's own), or an id that
    a frame gives to several people (``shared``: a user trial's two tracks both read person_id 1)."""
    ids = {q.person_id for _, q in seen if q.person_id is not None}
    return ids.pop() if len(ids) == 1 and str(next(iter(ids))) not in shared else None


def _tracks(frames: list[FrameResult]) -> dict[int, list[tuple[int, PersonState]]]:
    """``track_id -> [(frame index, person), ...]`` of ``frames``, in frame order."""
    out: dict[int, list[tuple[int, PersonState]]] = {}
    for fr in frames:
        for q in fr.people:
            out.setdefault(q.track_id, []).append((fr.index, q))
    return out


def _sparse_tracks(frames: list[FrameResult], seen: dict[int, list[tuple[int, PersonState]]]) -> list[int]:
    """The tracks of ``seen`` (:func:`_tracks` of ``frames``) with fewer than :data:`SPARSE_TRACK_FRAMES` sightings
    that fill less than :data:`SPARSE_TRACK_SHARE` of the frames from their first to their last (counted in
    ``frames``, so that a video read at a lower rate counts the frames read)."""
    pos = {fr.index: k for k, fr in enumerate(frames)}
    out = []
    for tid, at in seen.items():
        span = pos[at[-1][0]] - pos[at[0][0]] + 1
        if len(at) < SPARSE_TRACK_FRAMES and len(at) < SPARSE_TRACK_SHARE * span:
            out.append(tid)
    return out


def track_doubt_notes(frames: list[FrameResult], *, max_joints: int = 4) -> list[str]:
    """One note per track that has joints the detector scored below :data:`lifter.detect.UNSURE_JOINT_SCORE`: the
    (at most ``max_joints``) most often unsure joints, each with its count of frames and its first frame (the video
    form of :func:`lifter.pipeline.joint_doubt_notes`, which would repeat on every frame). Tracks without scores
    are skipped."""
    from .detect import UNSURE_JOINT_SCORE

    if max_joints < 1:
        raise PoseLifterError(f"max_joints must be >= 1, got {max_joints}")
    notes: list[str] = []
    for tid, seen in sorted(_tracks(frames).items()):
        rows = [(i, np.asarray(q.scores, np.float64).reshape(-1)) for i, q in seen if q.scores is not None]
        if not rows:
            continue
        low = np.stack([r for _, r in rows]) < UNSURE_JOINT_SCORE  # (frames, 17)
        counts = low.sum(0)
        joints = sorted(np.flatnonzero(counts), key=lambda j: (-int(counts[j]), int(j)))
        if not joints:
            continue
        first = [rows[int(np.argmax(low[:, j]))][0] for j in joints]
        named = [f"{JOINT_NAMES[j]} in {int(counts[j])} of {len(rows)} frames (first at frame {fi})"
                 for j, fi in zip(joints[:max_joints], first[:max_joints])]
        more = f" and {len(joints) - max_joints} more joint(s)" if len(joints) > max_joints else ""
        notes.append(f"track {tid}: the detector is unsure (score below {UNSURE_JOINT_SCORE:g}) of "
                     f"{', '.join(named)}{more}: their 2D, and so their 3D, may be off in those frames (an occluded "
                     "or blurred limb?)")
    return notes


def track_edge_notes(frames: list[FrameResult], image_size: tuple[int, int]) -> list[str]:
    """One note per track of a video whose detected 2D puts joints outside the ``image_size`` ``(W, H)`` px frame
    in some of its frames (a person cut off by the frame's edge; the detector's guess at the joints it cannot see):
    the frames, and the joints most often outside (a user trial: a person leaving at the edge was lifted 0.9 and
    2.4 m farther in its last two frames than before, with no word of why). Frames with most joints outside have
    the plausibility note too (:func:`lifter._checks.outside_image_notes`); this one names the tracks and frames.
    Photos: :func:`lifter.pipeline.detected_edge_notes`."""
    from ._checks import CUT_OFF_TAIL, joints_outside, joints_outside_text

    notes: list[str] = []
    for tid, seen in sorted(_tracks(frames).items()):
        out = joints_outside(np.stack([q.keypoints_2d for _, q in seen]), image_size)  # (frames, 17)
        rows = np.flatnonzero(out.any(-1))
        if len(rows):
            notes.append(f"track {tid}: cut off by the image's edge in {len(rows)} of its {len(seen)} frames "
                         f"({_frames_summary([seen[r][0] for r in rows])}; {joints_outside_text(out)}): "
                         f"{CUT_OFF_TAIL}")
    return notes


FILE_GAP: Final[str] = ("the file does not give this person there, or they were left out for a missing joint or by "
                         "--max-people")
"""A keypoint sequence's reason for a track's gap (:func:`track_gap_notes`): no detector looked for the person (a
browser trial read "not found there" of a person the file itself left out)."""


def track_gap_notes(frames: list[FrameResult], *, left_out: Iterable[int] = (),
                    absent: str = "the person was not found there") -> list[str]:
    """One note per track that is missing from some of the frames between its first and last sighting: those frames
    have no pose for it (the detector missed the person there, or the file leaves them out), and a viewer that follows
    the person sees someone else or nobody there (a browser trial's two-person clip: track 1 missed in frames 16 and
    26, and the app's selection moved to track 2 without a word). ``left_out``: the frame indices where a detection
    (or a file's person) was left out below the score floor (:data:`lifter.detect.MIN_PERSON_SCORE`): a gap there is
    said to be that, not ``absent`` (a video's "not found"; a keypoint sequence's :data:`FILE_GAP`)."""
    notes: list[str] = []
    order = [fr.index for fr in frames]
    low = set(left_out)
    for tid, seen in sorted(_tracks(frames).items()):
        have = {i for i, _ in seen}
        first, last = seen[0][0], seen[-1][0]
        gaps = [i for i in order if first < i < last and i not in have]
        if gaps:
            floored = [i for i in gaps if i in low]
            rest = len(gaps) - len(floored)
            floor = "a person scored below the score floor was left out, maybe this one"
            if not floored:
                why = absent
            elif not rest:
                why = f"in those {floor}"
            else:
                where = f"frame{'s' if len(floored) > 1 else ''} {_frames_summary(floored)}"
                others = "frame" if rest == 1 else f"{rest} frames"
                why = f"in {where} {floor}; in the other {others}: {absent}"
            held, span = len(have) + len(gaps), last - first + 1
            # (a trial read "30 of the 97 frames between frame 0 and 99" where the file left out 3 frame numbers)
            not_held = (f" that the input holds ({span - held} frame number{'s' if span - held > 1 else ''} between "
                        f"{'are' if span - held > 1 else 'is'} not in it)" if held < span else "")
            notes.append(f"track {tid}: missing from {len(gaps)} of the {held} frames between its "
                         f"first (frame {first}) and last (frame {last}){not_held}: {_frames_summary(gaps)}; those "
                         f"frames have no pose for it ({why})")
    return notes


JUMP_FRACTION: Final[float] = 0.15
"""A frame's 2D jumps away from its track when its median joint lies this far (a fraction of the person's box
diagonal) off the line between the frames either side, and more than twice as far as those two are apart; the same
for each limb's two outer joints (:data:`JUMP_LIMBS`), and for a track's first and last frame against where the two
frames next to it lead. The ground truth's own motion in Human3.6M (S9, S11) never does, within the spans judged
(:data:`JUMP_MAX_SPAN_S`, :data:`JUMP_LIMB_MAX_SPAN_S`, :data:`JUMP_END_MAX_SPAN_S`); the Stacked-Hourglass detections
do (``python scripts/jump_rate.py``, ``docs/results/jump_rate.txt``)."""

JUMP_MAX_SPAN_S: Final[float] = 0.4
"""The longest span (s) of three sightings whose middle one :func:`track_jump_notes` judges as a whole (5 frames/s: at
2 frames/s a person's own motion jumps as far)."""

JUMP_LIMB_MAX_SPAN_S: Final[float] = 0.2
"""The longest span (s) of three sightings whose middle one is judged limb by limb (10 frames/s): an arm's own
motion over 0.4 s (a wave, a greeting) moves as far as a detector's swapped wrists, and Human3.6M's ground truth
would be named."""

JUMP_END_MAX_SPAN_S: Final[float] = 0.15
"""The longest span (s) of a track's first or last four sightings whose end one is judged against where the next two
lead (20 frames/s and faster): a guess forward from two frames drifts faster than the line between two (at 10
frames/s Human3.6M's ground truth would be named). The fourth tells which of the end and its neighbour is wrong: the
neighbour must lie where the two after it lead, within a quarter of the end's jump (a review: a wrong second frame
named the first). A user trial: a wrong arm on a video's last frame went unflagged."""

JUMP_LIMBS: Final[tuple[tuple[str, tuple[str, str]], ...]] = (
    ("left arm", ("l_elbow", "l_wrist")), ("right arm", ("r_elbow", "r_wrist")),
    ("left leg", ("l_knee", "l_ankle")), ("right leg", ("r_knee", "r_ankle")))
"""The limbs judged on their own (their two outer H36M joints): four wrong arm joints do not move the median of 17."""


class TrackJump(NamedTuple):
    """A frame of :func:`track_jumps`: where the 2D (``part``: ``"2D"`` for the whole pose, else a limb of
    :data:`JUMP_LIMBS`) lies ``off_px`` (median joint, px) away from the line between the frames either side, or at
    a track's ``end`` (``"first"`` or ``"last"``; None: an inner frame) from where the two frames next to it lead,
    which are ``apart_px`` apart."""

    frame: int
    off_px: float
    apart_px: float
    part: str = "2D"
    end: Literal["first", "last"] | None = None


_LIMB_JOINTS: Final = tuple((name, [JOINT_NAMES.index(j) for j in js]) for name, js in JUMP_LIMBS)
_PART_JOINTS: Final = {"2D": list(range(len(JOINT_NAMES))), **dict(_LIMB_JOINTS)}


def _ahead(kp: np.ndarray, idx: np.ndarray, n: int, m1: int, m2: int) -> np.ndarray:
    """Where sightings ``m1`` (nearer) and ``m2`` of ``kp`` ``(T, 17, 2)`` px, at frames ``idx``, lead at sighting
    ``n``: on along their line, in proportion to the frames between."""
    return kp[m1] + (kp[m1] - kp[m2]) * ((idx[n] - idx[m1]) / (idx[m1] - idx[m2]))


def _worst_part(dist: np.ndarray, apart: np.ndarray, size: np.ndarray, limbs: np.ndarray,
                ) -> list[tuple[str, float, float] | None]:
    """Per pose (``(N, 17)`` joint px off their expected place, ``(N, 17)`` px between the two sightings judging it,
    ``(N,)`` box diagonals px, ``(N,)`` whether its limbs are judged), its worst jumping part as ``(part, median joint
    px off, px apart)``: the whole pose first (it says more than one limb), else the limb furthest off; None when none
    jumps (:data:`JUMP_FRACTION`)."""
    parts = [("2D", list(range(dist.shape[-1])))] + [(name, js) for name, js in _LIMB_JOINTS]
    off = np.stack([np.nanmedian(dist[:, js], axis=-1) for _, js in parts], axis=-1)  # (N, parts)
    gap = np.stack([np.nanmedian(apart[:, js], axis=-1) for _, js in parts], axis=-1)
    jumps = (off > JUMP_FRACTION * size[:, None]) & (off > 2.0 * gap)
    jumps[:, 1:] &= limbs[:, None]
    out: list[tuple[str, float, float] | None] = []
    for n in range(len(off)):
        hit = np.flatnonzero(jumps[n])
        k = None if not hit.size else 0 if hit[0] == 0 else int(hit[np.argmax(off[n, hit])])
        out.append(None if k is None else (parts[k][0], float(off[n, k]), float(gap[n, k])))
    return out


def track_jumps(frames: list[FrameResult], *, fps: float) -> dict[int, list[TrackJump]]:
    """Per track, the frames whose 2D jumps away from its sightings either side (:data:`JUMP_FRACTION`), as a whole
    or (within :data:`JUMP_LIMB_MAX_SPAN_S`) limb by limb, and its first and last frame against where the two next
    to it lead (within :data:`JUMP_END_MAX_SPAN_S`), in frame order; tracks without any are left out. Sightings
    spanning more than :data:`JUMP_MAX_SPAN_S` are not judged."""
    out: dict[int, list[TrackJump]] = {}
    tol = 1e-9
    for tid, seen in sorted(_tracks(frames).items()):
        if len(seen) < 3:
            continue
        idx = np.array([i for i, _ in seen], np.float64)
        kp = np.stack([np.asarray(q.keypoints_2d, np.float64) for _, q in seen])  # (T, 17, 2)
        size = np.hypot(*(np.nanmax(kp, 1) - np.nanmin(kp, 1)).T)  # (T,) box diagonals (bbox_of's)
        found: dict[int, TrackJump] = {}
        # inner sightings, against the line between their neighbours
        span = (idx[2:] - idx[:-2]) / fps
        a, b, c = kp[:-2], kp[1:-1], kp[2:]
        line = a + (c - a) * ((idx[1:-1] - idx[:-2]) / (idx[2:] - idx[:-2]))[:, None, None]
        judged = np.flatnonzero(span <= JUMP_MAX_SPAN_S + tol)
        worst = _worst_part(np.linalg.norm(b - line, axis=-1)[judged], np.linalg.norm(c - a, axis=-1)[judged],
                            0.5 * (size[:-2] + size[2:])[judged], span[judged] <= JUMP_LIMB_MAX_SPAN_S + tol)
        for n, w in zip(judged, worst):
            if w is not None:
                found[int(n) + 1] = TrackJump(int(idx[n + 1]), w[1], w[2], w[0])
        # the first and last sightings, against where the two next to them lead
        last = len(seen) - 1
        for n, m1, m2, m3 in ((0, 1, 2, 3), (last, last - 1, last - 2, last - 3)):
            if m3 < 0 or m3 > last or abs(idx[n] - idx[m3]) / fps > JUMP_END_MAX_SPAN_S + tol or m1 in found:
                continue  # (too few sightings, too far apart, or its neighbour jumps itself)
            w = _worst_part(np.linalg.norm(kp[n] - _ahead(kp, idx, n, m1, m2), axis=-1)[None],
                            np.linalg.norm(kp[m1] - kp[m2], axis=-1)[None], size[m1:m1 + 1], np.array([True]))[0]
            if w is None:
                continue
            js = _PART_JOINTS[w[0]]
            if float(np.nanmedian(np.linalg.norm(kp[m1, js] - _ahead(kp, idx, m1, m2, m3)[js], axis=-1))) < w[1] / 4:
                found[n] = TrackJump(int(idx[n]), w[1], w[2], w[0], "first" if n == 0 else "last")
        if found:
            out[tid] = [found[n] for n in sorted(found)]
    return out


def track_jump_notes(frames: list[FrameResult], *, fps: float) -> list[str]:
    """One note per track with frames of :func:`track_jumps`: most likely the detector's mistake there (a user
    trial's video frame put the head below the pelvis, 98 px off, with its neighbours 5 px apart, and lifted it
    535 mm off with no word; another's wrong arm on the video's last frame went unflagged)."""
    notes: list[str] = []
    for tid, hits in track_jumps(frames, fps=fps).items():
        h = hits[0]
        what = "its 2D" if h.part == "2D" else f"its {h.part}"
        size = "median joint " if h.part == "2D" else ""
        if h.end is not None:
            said = (f"{what} in frame {h.frame}, the track's {h.end}"
                    f", jumps away from where the two frames next to it lead ({size}{h.off_px:.0f} px off, and they "
                    f"are {h.apart_px:.0f} px apart)")
        else:
            said = (f"{what} in frame {h.frame} jumps away from the frames either side ({size}{h.off_px:.0f} px off "
                    f"the line between them, which are {h.apart_px:.0f} px apart)")
        more = (f", and in {len(hits) - 1} more: {_frames_summary([q.frame for q in hits[1:]])}" if len(hits) > 1
                else "")
        notes.append(f"track {tid}: {said}{more}: most likely the detector's mistake there, and the lift there is off "
                     "too; check the 2D of those frames")
    return notes


ROOT_STEP_MM: Final[float] = 800.0
"""A track's root steps when the median of its unsmoothed roots over the :data:`ROOT_STEP_WINDOW_S` after a frame lies
this far from the median over the same time before it (consecutive frames, so an error in a frame or two does not
count): two people under one track (an id given to another, tracks swapped where people cross), or 2D that is wrong
for a while. On the real Stacked-Hourglass detections of S9 and S11 (one person each, so every step named is 2D
wrong for a while or the lift's own error, never two people), lifted by the default, a step is named about once every
2 minutes at 50 and at 25 frames/s (``python scripts/root_steps.py``); a user trial's sequence, one id given to a second
person 0.96 m deeper, stepped without a word."""

ROOT_STEP_DEPTH_SHARE: Final[float] = 0.15
"""A step must also exceed this share of the nearer median's depth (from 5.3 m on, :data:`ROOT_STEP_MM` is the
larger below it): a monocular root's error grows with its depth. A developer trial's still people 20 m away were named
over and over; on the real Stacked-Hourglass detections of S9 and S11 moved along their rays to 2 and 4 times their
depth (10 and 21 m; the detector's error shrunk with the person), 800 mm alone names a step every 7 s and every 0.8 s
at 50 frames/s, with this share once every 1.3 min at both (at their own depth, 5 m: every 2.7 min, against 2.4 with
800 mm alone; ``python scripts/root_steps.py --farther 1,2,4``, ``docs/results/root_steps.txt``)."""

ROOT_STEP_MAX_SPAN_S: Final[float] = 0.2
"""Steps are judged only where the frames either side (:func:`_root_step_window`) span at most this (10 frames/s and
faster): at 5 frames/s the two medians are 0.4 s apart, over which a runner moves as far; at 1 frame/s a walker
would be named (a review)."""

ROOT_STEP_NOTE: Final[re.Pattern[str]] = re.compile(r"track \d+: its root moves ")
"""How a note of :func:`track_root_step_notes` starts: it is about the lift (another model or focal steps otherwise)."""

ROOT_STEP_WINDOW_S: Final[float] = 0.1
"""The time either side of a frame over which :data:`ROOT_STEP_MM` takes its medians (at least 2 frames each)."""


def _root_step_window(fps: float) -> int:
    """Frames either side in :func:`track_root_steps`: :data:`ROOT_STEP_WINDOW_S`, rounded up, at least 2."""
    return max(2, math.ceil(ROOT_STEP_WINDOW_S * fps - 1e-9))


def track_root_steps(frames: list[FrameResult], *, fps: float, depth_share: float = ROOT_STEP_DEPTH_SHARE,
                     ) -> dict[int, list[tuple[int, int, float]]]:
    """Per track, where its unsmoothed root steps by more than :data:`ROOT_STEP_MM` and ``depth_share`` (default
    :data:`ROOT_STEP_DEPTH_SHARE`; 0: the millimetres alone) of the nearer median's depth (:data:`ROOT_STEP_WINDOW_S`
    medians either side, over consecutive frames only; camera frame, mm): for each run of such frames ``(frame
    before, frame after, step mm)``, the two frames of the run's largest move from one frame to the next, and its
    largest step between the medians; in frame order; tracks without any are left out. Nothing below 10 frames/s
    (:data:`ROOT_STEP_MAX_SPAN_S`)."""
    w = _root_step_window(fps)
    out: dict[int, list[tuple[int, int, float]]] = {}
    if w / fps > ROOT_STEP_MAX_SPAN_S + 1e-9:
        return out
    for tid, seen in sorted(_tracks(frames).items()):
        idx = np.array([i for i, _ in seen])
        root = np.stack([np.asarray(q.root_raw, np.float64) for _, q in seen]) if seen else np.zeros((0, 3))
        steps = np.zeros(max(len(seen) - 1, 0))  # (between sightings n and n + 1)
        limit = np.full(steps.shape, ROOT_STEP_MM)
        for n in range(w - 1, len(seen) - w):
            if idx[n + w] - idx[n - w + 1] == 2 * w - 1:  # (no gap: one back after a gap may be elsewhere)
                after, before = np.median(root[n + 1:n + 1 + w], 0), np.median(root[n - w + 1:n + 1], 0)
                steps[n] = np.linalg.norm(after - before)
                limit[n] = max(ROOT_STEP_MM, depth_share * min(after[2], before[2]))
        edges = np.diff(np.concatenate([[0], (steps > limit).astype(np.int8), [0]]))
        hits = []
        for lo, end in zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)):
            # (a step shows from the frames either side too: where the root moves most in the run is where it is)
            m = lo + int(np.argmax(np.linalg.norm(root[lo + 1:end + 1] - root[lo:end], axis=-1)))
            hits.append((int(idx[m]), int(idx[m + 1]), float(steps[lo:end].max())))
        if hits:
            out[tid] = hits
    return out


def track_root_step_notes(frames: list[FrameResult], *, fps: float) -> list[str]:
    """One note per track with steps of :func:`track_root_steps`."""
    notes = []
    w = _root_step_window(fps)
    for tid, hits in track_root_steps(frames, fps=fps).items():
        a, b, step = hits[0]
        more = (f", and in {len(hits) - 1} more place(s): {_frames_summary([q[1] for q in hits[1:]])}"
                if len(hits) > 1 else "")
        dt = (b - a) / fps
        notes.append(f"track {tid}: its root moves {step / 1000:.2f} m between frames {a} and {b}, and stays moved "
                     f"(the median of the {w} frames either side){more}: two people under one track (an id given to "
                     "someone else, or two tracks swapped where people cross), or 2D wrong for a while; check those "
                     "frames, and give each person their own id (a keypoint sequence's person_id) where they are two; "
                     f"or, if it is one person, the frames lie further apart in time than {fps:g} frames/s says "
                     f"({step / 1000 / dt:.0f} m/s at that rate: a slideshow or a time-lapse? a video's --video-fps, a "
                     "sequence's fps)")
    return notes


def _frames_summary(idx: list[int], n: int = 8) -> str:
    return ", ".join(map(str, idx[:n])) + (f", ... ({len(idx)} in all)" if len(idx) > n else "")


def _frame_limit(max_seconds: float, fps: float, *, where: Any, what: str,
                 error: type[PoseLifterError] = PoseLifterError) -> int:
    """How many frames (from 0) start within ``max_seconds`` at ``fps``; ``error`` when not one does (a user trial
    read "the video has no frames (zero-length)" for a 40-frame video)."""
    limit = int(math.floor(max_seconds * fps + 1e-9))
    if limit == 0:
        raise error(f"{where}: max_seconds {max_seconds:g} (--max-seconds) is shorter than one frame of this {fps:g} "
                    f"frames/s {what}: give at least {1 / fps:.3g} s")
    return limit


def _iso_media_damage(path: Path) -> str | None:
    """Why an MP4 / QuickTime file (ISO base media: a chain of boxes, ``ftyp`` first) that OpenCV cannot open is
    damaged, read from its top-level boxes: one running past the end of the file (cut short) or no ``moov`` box (the
    index a player needs, which a recording writes last). None: not such a file, or its boxes are whole (an app
    trial's MP4 cut short was said to be "not a video, or a codec OpenCV cannot decode")."""
    import struct

    try:
        size = path.stat().st_size
        with path.open("rb") as fh:
            head = fh.read(MEDIA_HEAD_BYTES)
            if head[4:8] != b"ftyp" or media_kind(head) != "video":  # (not ISO media, or a HEIF / AVIF image)
                return None
            boxes, at = [], 0
            while at + 8 <= size and len(boxes) < 100_000:
                fh.seek(at)
                n, kind = struct.unpack(">I4s", fh.read(8))
                if n == 1:
                    wide = fh.read(8)
                    if len(wide) < 8:
                        return (f"an MP4 / QuickTime file cut short inside the header of its "
                                f"'{kind.decode('latin-1')}' box")
                    n = struct.unpack(">Q", wide)[0]
                elif n == 0:
                    n = size - at
                if n < 8:
                    return "an MP4 / QuickTime file whose structure is damaged"
                boxes.append(kind)
                if at + n > size:
                    return (f"an MP4 / QuickTime file cut short: its '{kind.decode('latin-1')}' box runs "
                            f"{at + n - size} bytes past the end of the file, as an interrupted download or recording "
                            "leaves it")
                at += n
    except (OSError, struct.error):
        return None
    if len(boxes) >= 100_000:
        return None
    if b"moov" not in boxes:
        return ("an MP4 / QuickTime file without its index (no 'moov' box, which a recording writes last): cut short "
                "or not finished")
    return None


def _check_frame_pixels(width: int, height: int, *, where: Any) -> None:
    if width * height > MAX_FRAME_PIXELS:
        raise VideoError(f"{where}: its frames are {width} x {height} px ({width * height / 1e6:.0f} MP), more than "
                         f"the {MAX_FRAME_PIXELS / 1e6:.0f} MP this tool decodes; downscale the video first")


def _check_common(smoothing: float, max_people: int, max_seconds: float) -> None:
    PoseSmoother(smoothing)
    if max_people < 1:
        raise PoseLifterError(f"max_people must be >= 1, got {max_people}")
    if not (math.isfinite(max_seconds) and max_seconds > 0):
        raise PoseLifterError(f"max_seconds must be a finite number of seconds > 0, got {max_seconds}")


def lift_video(path: str | Path, *, lifter: Any, estimator: PoseEstimator2D, focal: Any | None = None,
               principal_point: Any | None = None, fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG,
               smoothing: float = 1.0, max_people: int = DEFAULT_MAX_PEOPLE,
               max_seconds: float = DEFAULT_MAX_SECONDS, max_side: int = DEFAULT_MAX_SIDE_PX,
               flip_test: bool | None = None, search_every_s: float = DEFAULT_SEARCH_EVERY_S,
               blas_threads: int | None = 1,
               progress: Callable[[int, int | None], None] | None = None,
               on_frame: Callable[[int, np.ndarray], None] | None = None, cli_options: bool = True,
               fps: float | None = None, video_fps: float | None = None,
               rejoin_s: float = REJOIN_MAX_S, min_score: float = MIN_PERSON_SCORE,
               max_frames: int | None = None) -> SequenceRecord:
    """Detect, lift, track and smooth everyone in a video file (module docstring). ``max_frames``: lift at most this
    many frames from the start, within ``max_seconds`` (None: no bound but the duration; the app's, whose duration
    bound alone let a 1000-frames/s clip hold its detector for minutes). Frames larger than :data:`MAX_FRAME_PIXELS`
    are refused. ``min_score``: detections whose
    mean joint score is below it are left out, frame by frame, as no person (:data:`lifter.detect.MIN_PERSON_SCORE`,
    :func:`lifter.detect.detect_people`; 0 keeps every one). ``rejoin_s``: how long (s) after
    their last sighting a person found again where their 3D root leads keeps their track (:data:`REJOIN_MAX_S`; 0:
    a track unseen for :data:`TRACK_TIMEOUT_S` ends for good). ``fps`` (``--fps``): the frame
    rate where the file gives no usable one (else :data:`lifter.io.ASSUMED_FPS`); the file's own wins, with a note
    where they differ (as for a keypoint sequence). ``video_fps`` (``--video-fps``): the frame rate used in place of
    the file's own, with a note where they differ (a header that is wrong, a slow-motion clip whose capture rate is
    the one wanted: times, smoothing and ``max_seconds`` run on it). ``progress(done, total)``
    is called after each frame (total: the frame count the file declares, within ``max_seconds``; may be None);
    ``on_frame(index, bgr)`` with each lifted frame's decoded image (full resolution, OpenCV BGR), e.g. to keep
    display copies without decoding the video twice. ``cli_options``: as :func:`lifter.pipeline.resolve_camera`'s.
    Raises :class:`VideoError` for a file that cannot be opened or has no decodable frame.

    Detection: the whole frame is searched (the estimator's ``detect``) every ``search_every_s`` seconds, and
    whenever fewer people are found than in the previous frame or nobody is tracked; in between, an estimator
    with ``detect_near`` (BlazePose) searches only around the people seen since the last full search (their last
    boxes), which is what makes video fast (``search_every_s=0``: a full search in every frame).

    blas_threads: numpy's BLAS runs with this many threads during the video (``threadpoolctl``, installed with
    the ``detect`` extra; None = unchanged). One lift is a few small matrix products, and BLAS threads that
    spin beside MediaPipe's own threads cost more than they give (see the README's timings).
    """
    check_max_side(max_side)  # (up front: not as the same error for every frame)
    if max_frames is not None and (isinstance(max_frames, bool) or not isinstance(max_frames, (int, np.integer))
                                   or max_frames < 1):
        raise PoseLifterError(f"max_frames must be a whole number >= 1 (or None), got {max_frames!r}")
    check_rejoin_s(rejoin_s)
    check_frame_rate(fps, name="fps (--fps)")
    check_frame_rate(video_fps, name="video_fps (--video-fps)")
    min_score = check_min_score(min_score)
    with limit_blas_threads(blas_threads):
        return _lift_video(path, lifter=lifter, estimator=estimator, focal=focal, principal_point=principal_point,
                           fov_deg=fov_deg, smoothing=smoothing, max_people=max_people, max_seconds=max_seconds,
                           max_side=max_side, flip_test=flip_test, search_every_s=search_every_s, progress=progress,
                           on_frame=on_frame, cli_options=cli_options, given_fps=fps, video_fps=video_fps,
                           rejoin_s=rejoin_s, min_score=min_score, max_frames=max_frames)


class limit_blas_threads:  # noqa: N801 -- a context manager, named like one
    """``with limit_blas_threads(1): ...`` limits numpy's BLAS threads (``threadpoolctl.threadpool_limits(n, "blas")``)
    when threadpoolctl is installed and ``n`` is not None; otherwise does nothing."""

    def __init__(self, n: int | None) -> None:
        self.n: int | None = n
        self._ctx: Any = None

    def __enter__(self) -> None:
        if self.n is None:
            return
        try:
            from threadpoolctl import threadpool_limits  # pyright: ignore[reportMissingImports]
        except ImportError:
            return
        self._ctx = threadpool_limits(limits=self.n, user_api="blas")

    def __exit__(self, *exc: Any) -> None:
        if self._ctx is not None:
            self._ctx.restore_original_limits()


def _lift_video(path: str | Path, *, lifter: Any, estimator: PoseEstimator2D, focal: Any | None,
                principal_point: Any | None, fov_deg: float, smoothing: float, max_people: int,
                max_seconds: float, max_side: int, flip_test: bool | None, search_every_s: float,
                progress: Callable[[int, int | None], None] | None,
                on_frame: Callable[[int, np.ndarray], None] | None = None, cli_options: bool = True,
                given_fps: float | None = None, video_fps: float | None = None,
                rejoin_s: float = REJOIN_MAX_S, min_score: float = MIN_PERSON_SCORE,
                max_frames: int | None = None) -> SequenceRecord:
    import cv2

    from .pipeline import detected_sideways_notes, plausibility_notes, resolve_camera

    _check_common(smoothing, max_people, max_seconds)
    p = Path(path)
    if not p.is_file():
        raise VideoError(f"{p}: no such file")
    if p.stat().st_size == 0:
        raise VideoError(f"{p}: empty file (zero-length video)")
    with _StderrSilenced():  # (OpenCV's own parser prints raw bytes of a damaged file; the error below says it)
        cap = cv2.VideoCapture(str(p))
    try:
        if not cap.isOpened():
            damage = _iso_media_damage(p)
            raise VideoError(f"{p}: cannot open as a video " + (f"({damage})" if damage else
                                                                 "(not a video, or a codec OpenCV cannot decode)"))
        _check_frame_pixels(int(cap.get(cv2.CAP_PROP_FRAME_WIDTH) or 0), int(cap.get(cv2.CAP_PROP_FRAME_HEIGHT) or 0),
                            where=p)
        fps = float(cap.get(cv2.CAP_PROP_FPS) or 0.0)
        warnings: list[str] = []
        noted: set[int] = set()  # frames whose lift had notes (said once tracked: tracked_output_notes)
        source_format: str | None = None  # (the detector's keypoint format, once anyone is found)
        if video_fps is not None:  # (the caller's, in place of the file's: a user trial's header said 25 for 10)
            if float(video_fps) != fps:
                warnings.append(f"{float(video_fps):g} frames/s used (--video-fps), not the file's own "
                                + (f"{fps:g}" if is_frame_rate(fps) else f"(no usable rate: {fps:g})"))
            fps = float(video_fps)
        elif not is_frame_rate(fps):
            warnings.append(f"the file gives no usable frame rate ({fps:g}); " + (
                f"assumed {ASSUMED_FPS:g} frames/s" + (" (give it: --fps)" if cli_options else "")
                if given_fps is None else f"{given_fps:g} frames/s used (--fps)"))
            fps = ASSUMED_FPS if given_fps is None else float(given_fps)
        elif given_fps is not None and float(given_fps) != fps:
            warnings.append(own_fps_note(fps, given_fps) + (" (--video-fps to use it in place of the file's: a wrong "
                                                            "header, slow motion)" if cli_options else ""))
        declared = int(cap.get(cv2.CAP_PROP_FRAME_COUNT) or 0)
        limit = _frame_limit(max_seconds, fps, where=p, what="video", error=VideoError)
        if max_frames is not None and max_frames < limit:
            if declared > max_frames:
                warnings.append(f"the video holds {declared} frames ({fps:g} frames/s); only its first {max_frames} "
                                f"({max_frames / fps:.1f} s) are lifted (at most {max_frames} frames)")
            limit = max_frames
        elif declared > limit:
            warnings.append(f"the video is {declared / fps:.1f} s long; only its first {max_seconds:g} s "
                            f"({limit} frames) are lifted (the duration bound, --max-seconds)")
        total = min(declared, limit) if declared > 0 else None
        frames: list[FrameResult] = []
        bad: list[dict[str, Any]] = []
        nobody: list[int] = []
        crowded: list[int] = []
        left_out: list[tuple[int, float]] = []  # (frame, mean joint score) of detections below min_score
        full_searches = 0  # (frames searched in full: _crowd_note)
        size: tuple[int, int] | None = None
        cam: tuple[np.ndarray, str, np.ndarray] | None = None
        seq: SequenceTracker | None = None
        t_total, n_done = 0.0, 0
        index = -1
        failures_in_a_row = 0
        recent: dict[int, tuple[int, np.ndarray]] = {}  # track id -> (frame last seen, box in full-res px)
        prev_count = 0
        last_search = -(10**9)
        search_every = max(1, round(search_every_s * fps)) if search_every_s > 0 else 1
        return_every = min(search_every, max(1, round(RETURN_SEARCH_S * fps)))
        missing_until, missing_count = -1, 0  # (someone lost: until then, while fewer than that, search more often)
        can_track = callable(getattr(estimator, "detect_near", None))
        followed = _Followed.at_fps(max_people=max_people, fps=fps, seen_every=search_every)  # (--max-people)
        while index + 1 < limit:
            t0 = time.perf_counter()
            ok, bgr = cap.read()
            index += 1
            if not ok or bgr is None:
                if declared > 0 and index < declared and failures_in_a_row < 10:
                    # OpenCV may fail a damaged frame and go on with the next one
                    bad.append({"index": index, "error": "frame could not be decoded; skipped"})
                    failures_in_a_row += 1
                    continue
                index -= 1 + failures_in_a_row
                bad = bad[: len(bad) - failures_in_a_row]
                break
            failures_in_a_row = 0
            H, W = bgr.shape[:2]
            if size is None:
                _check_frame_pixels(W, H, where=p)  # (a header may say less than the frames hold)
                size = (W, H)
                f, src, pp, notes = resolve_camera(
                    user_focal=None if focal is None else as_pair(focal, name="focal", positive=True, scalar=True),
                    user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
                    file_focal=None, file_pp=None, image_size=size, exif=None, sensor_width_mm=None,
                    fov_deg=fov_deg, where=str(p), cli_options=cli_options)
                cam = (f, src, pp)
                warnings.extend(notes)
                seq = SequenceTracker(fps=fps, smoothing=smoothing)
            elif (W, H) != size:
                bad.append({"index": index, "error": f"frame size {W} x {H} px differs from the first frame's "
                                                     f"{size[0]} x {size[1]} px; skipped"})
                continue
            assert cam is not None and seq is not None
            try:
                img = image_from_array(cv2.cvtColor(bgr, cv2.COLOR_BGR2RGB), max_side=max_side)
                people = None
                boxes = [b for seen, b in recent.values() if index - seen <= search_every]
                left: list[float] = []
                # (a near search still covers those seen in the last search_every frames: more often only beyond)
                every = return_every if index <= missing_until and len(boxes) < missing_count else search_every
                if can_track and boxes and index - last_search < every:
                    people, left = scored_people(people_h36m(img, estimator=estimator, near=boxes), min_score)
                    if len(people) < prev_count:
                        people = None  # someone was lost: search the whole frame
                if people is None:
                    people, left = scored_people(people_h36m(img, estimator=estimator), min_score)
                    last_search = index
                    full_searches += 1
                left_out += [(index, v) for v in left]
            except EstimatorError:
                raise  # (the estimator's fault, in every frame: not a bad frame; a review saw 12 frames skipped)
            except PoseLifterError as exc:
                bad.append({"index": index, "error": f"{exc}; skipped"})
                continue
            if len(people) > max_people:
                crowded.append(index)
            # (every frame, so that the people followed are those lifted, held through an absence up to the track
            # timeout: a user trial's followed person, gone for 0.5 s, was replaced for good by the one seen alone)
            people = [people[i] for i in followed.keep(index, [q.raw.bbox_xywh for q in people], [None] * len(people))]
            t_s = index / fps
            if not people:
                nobody.append(index)
                states: list[PersonState] = []
            else:
                kp = np.stack([q.keypoints_2d for q in people])
                source_format = source_format or people[0].raw.keypoint_format
                res = lifter.lift(kp, focal=cam[0], principal_point=cam[2], flip_test=flip_test, source="detected",
                                  warn=False)  # (the record's notes say it, once)
                if getattr(res, "warnings", ()):
                    noted.add(index)
                states = seq.step(index, t_s, kp, np.asarray(res.root).reshape(-1, 3),
                                  np.asarray(res.relative).reshape(-1, 17, 3), cam[0],
                                  scores=np.stack([q.scores for q in people]))
            frames.append(FrameResult(index=index, time_s=t_s, people=states))
            lifted_now = len(states) + followed.set_aside  # (someone set aside: the next frame is searched whole)
            if lifted_now < prev_count:  # (someone lost: searched for more often for a while, RETURN_SEARCH_S)
                missing_count = max(prev_count, missing_count if index <= missing_until else 0)
                missing_until = index + round(REJOIN_MAX_S * fps)
            prev_count = lifted_now
            for st, q in zip(states, people):
                recent[st.track_id] = (index, q.raw.bbox_xywh)
            recent = {tid: v for tid, v in recent.items() if index - v[0] <= search_every}
            t_total += time.perf_counter() - t0
            n_done += 1
            if on_frame is not None:  # (outside the timed pipeline)
                on_frame(index, bgr)
            if progress is not None:
                progress(n_done, total)
    finally:
        cap.release()
    if size is None or cam is None:
        why = "no frame could be decoded" if bad else "the video has no frames (zero-length)"
        raise VideoError(f"{p}: {why}")
    if declared > 0 and index + 1 < min(declared, limit):
        short = min(declared, limit) - index - 1
        upto = " (up to --max-seconds)" if limit < declared else ""
        warnings.append(f"{index + 1} of the {min(declared, limit)} frames the file declares{upto} were decoded: "
                        f"the {short} missing may lie at the end, or have been dropped where the file is damaged "
                        "(OpenCV does not say where); then the frame numbers and times after that point run up to "
                        f"{short} frame(s) early (re-encoding the file, e.g. ffmpeg -i IN -c:v libx264 OUT.mp4, says "
                        "whether it is damaged)")
    dropped: list[str] = []  # (the notes of tracks left out as false detections)
    if len(frames) >= MIN_FRAMES_FOR_TRACK_FILTER:
        seen = _tracks(frames)
        flashes = {tid for tid, at in seen.items() if len(at) < MIN_TRACK_FRAMES}
        sparse = set(_sparse_tracks(frames, seen)) - flashes
        if flashes or sparse:
            for fr in frames:
                fr.people = [q for q in fr.people if q.track_id not in flashes | sparse]
            nobody = [fr.index for fr in frames if not fr.people]
        if flashes:
            where = sorted(i for tid in flashes for i, _ in seen[tid])
            seen_in = ("in one frame only" if MIN_TRACK_FRAMES == 2 else f"in fewer than {MIN_TRACK_FRAMES} frames")
            dropped.append(f"{len(flashes)} detection(s) seen {seen_in}, each left out as a likely false detection "
                           f"(frames {_frames_summary(where)}; a person cut off by the frame's edge can be one)")
        if sparse:
            where = sorted(i for tid in sparse for i, _ in seen[tid])
            dropped.append(f"{len(sparse)} track(s) seen in fewer than {SPARSE_TRACK_FRAMES} frames far apart, missing "
                            f"from most frames between them, left out as likely false detections (frames "
                            f"{_frames_summary(where)})")
        warnings += dropped
    # (after false detections; then the ids without the gaps those and the rejoined tracks leave)
    warnings.extend(rejoin_notes(renumber_tracks(frames, rejoin_tracks(frames, fps=fps, rejoin_s=rejoin_s))))
    low = [_left_out_note(left_out, left_out_text([v for _, v in left_out], min_score, detector=estimator.name))
           ] if left_out else []
    if frames and len(nobody) == len(frames):
        raise PoseLifterError(f"{p}: no person found by the {estimator.name} 2D detector in any of the "
                              f"{len(frames)} frames" + (f" ({len(bad)} more could not be decoded)" if bad else "")
                              + "".join(f"; {w}" for w in dropped + low))
    if nobody:
        warnings.append(f"no person found in {len(nobody)} of {len(frames)} frames: {_frames_summary(nobody)}")
    warnings += low
    if crowded:
        warnings.append(_crowd_note(max_people, crowded,
                                    searched=None if full_searches >= len(frames) else (full_searches, len(frames))))
    warnings.extend(followed.aside_note())
    if bad:
        warnings.append(f"{len(bad)} bad frame(s) skipped: {_frames_summary([b['index'] for b in bad])}")
    f, src, pp = cam
    seen_2d = [q.keypoints_2d for fr in frames for q in fr.people]
    if seen_2d:
        everyone = np.stack(seen_2d)
        warnings.extend(plausibility_notes(everyone, f, size, focal_source=src, detected=True))
        warnings.extend(detected_sideways_notes(everyone, video=True))
        warnings.extend(lean_notes(everyone))
    warnings.extend(track_gap_notes(frames, left_out=(i for i, _ in left_out)))
    warnings.extend(track_edge_notes(frames, size))
    warnings.extend(track_jump_notes(frames, fps=fps))
    warnings.extend(track_root_step_notes(frames, fps=fps))
    warnings.extend(track_doubt_notes(frames))
    if noted:
        warnings.extend(output_note_lines(tracked_output_notes(lifter.network_for("detected"), frames, pp,
                                                               source="detected", only=noted, focal=f)))
    return SequenceRecord(input=str(p), kind="video", model=lifter.name, fps=fps, image_size=size,
                          model_info=model_info(lifter, source="detected", flip_test=flip_test),
                          focal=(float(f[0]), float(f[1])), focal_source=src,
                          principal_point=(float(pp[0]), float(pp[1])),
                          smoothing=float(smoothing), frames=frames, num_frames_in_file=declared or None,
                          bad_frames=bad, warnings=warnings, detector=estimator.name,
                          seconds_per_frame=t_total / max(n_done, 1), source_format=source_format)


def track_lifted(lifted: list[tuple[int, float, np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]], *,
                 fps: float, focal: np.ndarray, smoothing: float = 1.0,
                 person_ids: list[list[str | int | None]] | None = None,
                 names: list[list[Any]] | None = None) -> list[FrameResult]:
    """Track and smooth already lifted frames ``[(index, time_s, keypoints_2d (n, 17, 2), root (n, 3),
    relative (n, 17, 3), scores (n, 17) or None), ...]`` (an empty ``n = 0`` frame keeps its place).
    ``person_ids``: per frame, the input's own id for each of its people (None: none), kept as each person's
    ``person_id``; those that recur from frame to frame are followed by the tracker (:func:`tracking_names`), or
    ``names``, per frame and person, when given: the names read from the whole input (a ``--max-people`` cut can
    leave a recurring name in one frame only, which would then be no name: a user trial saw another name take the
    followed track so). Tracks are not taken up again here (:func:`rejoin_tracks`)."""
    if person_ids is not None and len(person_ids) != len(lifted):
        raise PoseLifterError(f"track_lifted: person_ids for {len(person_ids)} frames, {len(lifted)} frames lifted")
    if names is not None and len(names) != len(lifted):
        raise PoseLifterError(f"track_lifted: names for {len(names)} frames, {len(lifted)} frames lifted")
    names_by_frame = names if names is not None else (
        None if person_ids is None else tracking_names([list(fr) for fr in person_ids]))
    seq = SequenceTracker(fps=fps, smoothing=smoothing)
    out = []
    for k, (index, t, kp, root, rel, sc) in enumerate(lifted):
        frame_names = None if names_by_frame is None else names_by_frame[k]
        states = seq.step(index, t, kp, root, rel, focal, scores=sc, person_ids=frame_names) if len(kp) else []
        if person_ids is not None:
            for st, pid in zip(states, person_ids[k]):  # (the tracker keeps each frame's order)
                st.person_id = pid
        out.append(FrameResult(index=index, time_s=t, people=states))
    return out


def _frame_scores(people: list[np.ndarray | None], keypoint_format: str) -> np.ndarray | None:
    """One frame's confidences ``(n, 17)`` of the H36M joints (:func:`lifter.detect.h36m_joint_scores`, from each
    person's ``(J,)`` in ``keypoint_format``), or None unless every person of the frame has them."""
    given = people_scores(people)
    return None if given is None else h36m_joint_scores(given, keypoint_format)


def lift_keypoint_sequence(path: str | Path, *, lifter: Any, focal: Any | None = None,
                           principal_point: Any | None = None, default_format: str | None = None,
                           fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG, smoothing: float = 1.0,
                           max_people: int = DEFAULT_MAX_PEOPLE, max_seconds: float = DEFAULT_MAX_SECONDS,
                           flip_test: bool | None = None, cli_options: bool = True,
                           image_size: Any | None = None, fps: float | None = None,
                           assumed_fps: float | None = None,
                           fallback_image: tuple[Any, ...] | None = None,
                           rejoin_s: float = REJOIN_MAX_S, min_score: float = MIN_PERSON_SCORE) -> SequenceRecord:
    """Lift, track and smooth a keypoint sequence (:func:`lifter.io.parse_keypoint_sequence`: a JSON with ``frames``,
    MMPose's predictions of several frames, or a frame pattern naming OpenPose's per-frame files): every person of
    every frame is lifted in one batch, then tracked and smoothed frame by frame. ``cli_options``: as
    :func:`lifter.pipeline.resolve_camera`'s (False: messages name the file's fields, not the CLI's options).
    ``image_size`` ``(W, H)`` px: for a file that gives none, or in place of its own
    (:func:`lifter.pipeline.given_image_size`). ``fps``: the frame rate of a sequence that does not give its own;
    ``assumed_fps``: the rate assumed, with a note, where neither does (:data:`lifter.io.ASSUMED_FPS`; None: refused).
    ``fallback_image``: ``(name, (W, H) px[, exif])`` of the image the keypoints were found in (the app: the photo
    uploaded before): its size where nobody gives an image size or a principal point, and its EXIF focal where
    neither ``focal`` nor the file gives one and the keypoints are in its pixels, by
    :func:`lifter.pipeline.keypoints_image`'s rule (refused when most poses lie mostly outside it). ``rejoin_s``: as
    :func:`lift_video`'s. ``min_score``: a person whose mean joint score (where the file gives 0-1 scores) is below it
    is left out as no person (:func:`lifter.detect.mean_person_scores`; 0 keeps every one)."""
    from .camera import lens_notes
    from .pipeline import keypoints_image, plausibility_notes, resolve_camera

    check_rejoin_s(rejoin_s)  # (before the lift, not after it)
    min_score = check_min_score(min_score)

    _check_common(smoothing, max_people, max_seconds)
    ks = parse_keypoint_sequence(path, default_format=default_format, fps=fps, cli_options=cli_options,
                                 assumed_fps=assumed_fps)
    img = keypoints_image(ks.image_size, ks.principal_point, image_size=image_size, principal_point=principal_point,
                          fallback_image=fallback_image, poses=[k for fr in ks.frames for k in fr], where=path,
                          what="keypoint sequence")
    size, exif = img.size, img.exif  # (exif: the image's, where the keypoints are in its pixels)
    warnings = [*ks.warnings, *img.notes]
    f, src, pp, notes = resolve_camera(
        user_focal=None if focal is None else as_pair(focal, name="focal", positive=True, scalar=True),
        user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
        file_focal=ks.focal, file_pp=ks.principal_point, image_size=size, exif=exif,
        sensor_width_mm=None, fov_deg=fov_deg, where=str(path), file_distortion=ks.distortion, unread=ks.unread,
        assumed_focal=ks.assumed_focal, cli_options=cli_options)
    warnings.extend(notes)
    frames = ks.frames
    at = ks.frame_indices or list(range(len(frames)))  # each frame's index in its video (a record leaves some out)
    limit = _frame_limit(max_seconds, ks.fps, where=path, what="sequence")
    within = bisect.bisect_left(at, limit)  # (the frames that start before max_seconds)
    if len(frames) > within:
        warnings.append(f"the sequence has {len(frames)} frames ({(at[-1] + 1) / ks.fps:.1f} s); only the first "
                        f"{max_seconds:g} s ({within} frames) are lifted (the duration bound, --max-seconds)")
        frames = frames[:within]
    crowded: list[int] = []  # (frames with more people than max_people, those left out below min_score not counted)
    ids = None if ks.people_ids is None else list(ks.people_ids[:len(frames)])
    given_scores = None if ks.people_scores is None else list(ks.people_scores[:len(frames)])
    kept_frames: list[list[np.ndarray]] = []
    kept_ids: list[list[Any]] | None = None if ids is None else []
    kept_scores: list[list[np.ndarray | None]] = []
    kept_names: list[list[Any]] | None = None if ids is None else []
    followed = _Followed.at_fps(max_people=max_people, fps=ks.fps)
    names_by_frame = None if ids is None else tracking_names(ids)
    if ids is not None:  # (ids a frame gives to several people: said, as tracking_names leaves them out)
        twice = [(at[i], t) for i, frame in enumerate(ids) for t in repeated_ids(frame)]
        if twice:
            names = list(dict.fromkeys(t for _, t in twice))
            warnings.append(f"person id(s) {', '.join(names[:5])} given to several people in one frame (first at frame "
                            f"{twice[0][0]}): not used to follow anyone, nor as a track's person_id")
    left_out: list[tuple[int, float]] = []  # (frame, mean joint score) of people below min_score
    for i, fr in enumerate(frames):
        boxes = [bbox_of(k) for k in fr]
        names = [None] * len(fr) if names_by_frame is None else list(names_by_frame[i])
        scored = mean_person_scores(given_scores[i] if given_scores is not None else [], ks.format, len(fr))
        ok = [j for j in range(len(fr)) if not scored[j] < min_score]  # (NaN: no scores to read, kept)
        left_out += [(at[i], float(scored[j])) for j in range(len(fr)) if scored[j] < min_score]
        if len(ok) > max_people:
            crowded.append(at[i])
        keep = [ok[j] for j in followed.keep(at[i], [boxes[j] for j in ok], [names[j] for j in ok])]
        kept_frames.append([fr[j] for j in keep])
        kept_scores.append([None if given_scores is None else given_scores[i][j] for j in keep])
        if kept_ids is not None and ids is not None:
            kept_ids.append([ids[i][j] for j in keep])
        if kept_names is not None:
            kept_names.append([names[j] for j in keep])
    frames, ids = kept_frames, kept_ids
    if crowded:
        warnings.append(_crowd_note(max_people, crowded))
    warnings.extend(followed.aside_note())
    text = left_out_text([v for _, v in left_out], min_score, what="person") if left_out else ""
    if left_out:
        warnings.append(_left_out_note(left_out, text))
    counts = [len(fr) for fr in frames]
    nobody = [at[i] for i, c in enumerate(counts) if c == 0]
    if nobody:
        warnings.append(f"no person in {len(nobody)} of {len(frames)} frames: {_frames_summary(nobody)}")
    if not sum(counts):
        raise PoseLifterError(f"{path}: no person in any frame" + (f"; {text}" if text else ""))
    raw = np.stack([k for fr in frames for k in fr])  # every person of every frame, one batch
    kp17 = convert(raw, src=ks.format, warn=False)
    warnings.extend(placeholder_notes(raw, src=ks.format))
    warnings.extend(plausibility_notes(kp17, f, size, focal_source=src, source_format=ks.format))
    warnings.extend(lens_notes(ks.distortion, ks.distortion_model))
    res = lifter.lift(kp17, focal=f, principal_point=pp, flip_test=flip_test, source=ks.source, warn=False,
                      distortion=ks.distortion, distortion_model=ks.distortion_model)
    root, rel = np.asarray(res.root).reshape(-1, 3), np.asarray(res.relative).reshape(-1, 17, 3)
    seen = np.asarray(res.keypoints_2d).reshape(-1, 17, 2)  # (the 2D lifted: undistorted through a lens)
    lifted, lifted_2d, k = [], {}, 0
    for i, c in enumerate(counts):
        lifted.append((at[i], at[i] / ks.fps, kp17[k:k + c], root[k:k + c], rel[k:k + c],
                       _frame_scores(kept_scores[i], ks.format)))
        lifted_2d[at[i]] = seen[k:k + c]
        k += c
    out = track_lifted(lifted, fps=ks.fps, focal=f, smoothing=smoothing, person_ids=ids, names=kept_names)
    warnings.extend(rejoin_notes(renumber_tracks(out, rejoin_tracks(out, fps=ks.fps, rejoin_s=rejoin_s))))
    if getattr(res, "warnings", ()):  # per frame and track (the batch's own notes count people of all frames at once)
        warnings.extend(output_note_lines(tracked_output_notes(lifter.network_for(ks.source), out, pp,
                                                               source=ks.source, focal=f, lifted_2d=lifted_2d)))
    warnings.extend(track_gap_notes(out, left_out=(i for i, _ in left_out), absent=FILE_GAP))
    warnings.extend(track_jump_notes(out, fps=ks.fps))
    warnings.extend(track_root_step_notes(out, fps=ks.fps))
    given = [sc for *_, sc in lifted if sc is not None]
    if given and float(max(np.nanmax(sc) for sc in given)) <= 1.0:  # (above 1: another scale, no threshold to read)
        warnings.extend(track_doubt_notes(out))
    return SequenceRecord(input=str(path), kind="keypoint-sequence", model=lifter.name, fps=ks.fps,
                          model_info=model_info(lifter, source=ks.source, flip_test=flip_test),
                          image_size=size, focal=(float(f[0]), float(f[1])), focal_source=src,
                          principal_point=(float(pp[0]), float(pp[1])), smoothing=float(smoothing), frames=out,
                          num_frames_in_file=len(ks.frames), warnings=warnings, source=ks.source,
                          distortion=distortion_tuple(ks.distortion), distortion_model=ks.distortion_model,
                          source_format=ks.format, tracking_names=kept_names)


__all__ = ["DEFAULT_MAX_PEOPLE", "DEFAULT_MAX_SECONDS", "OUTPUT_NOTE_LINE", "ROOT_STEP_NOTE", "FrameResult",
           "PersonState",
           "track_animation", "tracking_names",
           "SequenceRecord", "SequenceTracker", "VIDEO_SUFFIXES", "VideoError", "collect_output_notes",
           "input_kind", "lift_keypoint_sequence", "lift_video", "limit_blas_threads", "output_note_lines",
           "TrackJump", "track_doubt_notes", "track_edge_notes", "track_gap_notes", "track_jump_notes", "track_jumps",
           "track_lifted", "tracked_output_notes", "ROOT_STEP_MM", "ROOT_STEP_DEPTH_SHARE", "ROOT_STEP_WINDOW_S",
           "track_root_steps", "track_root_step_notes"]
