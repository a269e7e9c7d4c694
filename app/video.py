"""Uploaded videos and keypoint sequences as playable sequences (headless; no viser here).

An uploaded video goes through :func:`lifter.video.lift_video` exactly as ``poselifter lift clip.mp4`` does:
everyone detected in every frame, lifted, tracked (stable ``track_id``) and smoothed over time (causal
One-Euro filter); a keypoint JSON with ``frames`` through :func:`lifter.video.lift_keypoint_sequence`. The result
is a :class:`VideoSequence`, a :class:`app.playback.SequenceSource` the app plays like a Human3.6M sequence: each
frame is a :class:`app.samples.Sample` with the frame's people (ordered by track id, so "person k" stays the same
person while the same people are in view), drawn on the frame itself (kept as small JPEGs) or on a plain canvas.

Per frame the app lifts the frame's 2D itself (so the focal slider, the model and joint drags act on it); the
root trajectories it draws are the tracked, smoothed ones of :meth:`VideoSequence.trajectories`, recomputed for
the model and focal length in use. Units: px, mm, seconds; camera frame OpenCV.
"""

from __future__ import annotations

import json
import tempfile
import threading
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Final

import cv2
import numpy as np

from lifter import PoseLifterError
from lifter._text import sentence
from lifter.camera import focal_alpha, undistort_pixels_opencv
from lifter.detect import ASSUMED_FOCAL_NOTE, MIN_PERSON_SCORE, people_scores
from lifter.io import ASSUMED_FPS, is_sequence_doc, json_text, model_info
from lifter.keypoints import H36M17
from lifter.skeleton import JOINT_NAMES
from lifter.video import (
    MEDIA_HEAD_BYTES,
    OUTPUT_NOTE_LINE,
    ROOT_STEP_NOTE,
    VIDEO_SUFFIXES,
    SequenceRecord,
    input_kind,
    lift_keypoint_sequence,
    lift_video,
    output_note_lines,
    track_lifted,
    track_root_step_notes,
    tracked_output_notes,
)

from .core import lens_free_2d, undoes_lens
from .keys import frame_of, sequence_of, with_frame
from .samples import Sample, id_tag
from .upload import (
    MAX_CANVAS_SIDE,
    MAX_PEOPLE,
    OPENCV_LENS_UNDONE_NOTE,
    DetectorMissing,
    MissingDependencyError,
    UploadError,
    UploadInfo,
    check_upload,
    display_canvas,
    focal_note,
    missing_detector_message,
    note_if_busy,
    safe_name,
    upload_camera,
)

FOCAL_SAME_PX: Final[float] = 0.5
"""A focal length within this of the upload's (alpha, px) is the upload's (the focal box shows 0.1 px)."""
VIDEO_MAX_SECONDS: Final[float] = 20.0
"""Uploaded videos and keypoint sequences are lifted up to this duration (the rest is dropped, with a note)."""
VIDEO_MAX_FRAMES: Final[int] = 1200
"""And uploaded videos up to this many frames (20 s at 60 frames/s; a security review's 1000-frames/s clip of 20,000
frames held the app's detector, which every tab shares, for twenty minutes)."""
VIDEO_DISPLAY_MAX_SIDE: Final[int] = 640
"""Frames are kept for display downscaled to this longer side, as JPEG."""


def is_video_upload(name: str, content: bytes = b"") -> bool:
    """A video: by ``content``'s first bytes when they say (:func:`lifter.video.input_kind`: a JPEG renamed ``.mp4`` is
    a photo, a video named ``.jpg`` a video, keypoint JSON named ``.mp4`` keypoints), else by a video suffix in the
    name (:data:`lifter.video.VIDEO_SUFFIXES`)."""
    return input_kind(safe_name(name), bytes(content[:MEDIA_HEAD_BYTES]))[0] == "video"


def is_sequence_json(content: bytes) -> bool:
    """A keypoint sequence (:func:`lifter.io.is_sequence_doc`: an object with ``frames``, or MMPose's predictions of
    several frames)."""
    try:
        doc = json.loads(json_text(content))
    except (UnicodeDecodeError, ValueError, RecursionError):  # (ValueError: not JSON, or an integer too long)
        return False  # the keypoint-file reader says what is wrong with it
    return is_sequence_doc(doc)


def track_tag(track_id: int, person_id: object = None) -> str:
    """How a video frame's sample names a tracked person (:attr:`Sample.person_tags`): ``"track 3"``, with the
    input's own id of the track's person when it has one (:meth:`lifter.video.SequenceRecord.track_person_ids`):
    ``"track 3, id kid"`` (:func:`app.samples.id_tag`)."""
    return f"track {int(track_id)}" + ("" if person_id is None else f", {id_tag(person_id)}")


@dataclass
class VideoSequence:
    """A lifted video or keypoint sequence the app can play (:class:`app.playback.SequenceSource`).

    key: ``video/<id>/<name>``; frame ``i`` (0 .. num_frames - 1: the lifted frames with someone in them, in order;
    bad frames of the file and frames with nobody are left out) is the sample ``<key>/<i>``. record: the
    :class:`lifter.video.SequenceRecord` of the upload. jpegs: those frames for display (None: a keypoint
    sequence, drawn on a canvas).
    """

    key: str
    label: str
    record: SequenceRecord
    info: UploadInfo
    jpegs: list[bytes] | None
    fps: float = field(init=False)
    num_frames: int = field(init=False)
    uploaded_with: Any = None
    """The lifter object the upload was lifted with (None: known by the record's model name only)."""
    _relifted: tuple[tuple, Any, SequenceRecord] | None = field(default=None, init=False, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, init=False, repr=False)

    def __post_init__(self) -> None:
        self.fps = float(self.record.fps)
        self.frames = [fr for fr in self.record.frames if fr.people]
        self.num_frames = len(self.frames)
        size = self.record.image_size or (1000, 1000)
        self.camera = upload_camera(self.record.focal, self.record.principal_point, size, self.info.name,
                                    self.record.distortion)
        self._canvas = None if self.jpegs is not None else display_canvas(size, VIDEO_DISPLAY_MAX_SIDE)
        ids = self.record.track_person_ids()
        self._tags = {tid: track_tag(tid, pid) for tid, pid in ids.items()}

    def frame(self, index: int) -> Any:
        from .playback import SequenceFrame

        return SequenceFrame((self.sample(index),))

    def sample(self, index: int) -> Sample:
        """Frame ``index`` as a sample: the frame's people ordered by track id (the first is the draggable one when
        the frame is shown), their detected 2D as the sample's 2D. A frame with nobody in it raises."""
        i = int(index)
        if not 0 <= i < self.num_frames:
            raise PoseLifterError(f"{self.label}: no frame {i} (0 .. {self.num_frames - 1})")
        fr = self.frames[i]
        people = sorted(fr.people, key=lambda p: p.track_id)
        kp = np.asarray(people[0].keypoints_2d, np.float64)
        if self.jpegs is not None:
            img = cv2.imdecode(np.frombuffer(self.jpegs[i], np.uint8), cv2.IMREAD_COLOR)
            image = self._canvas_for_bad() if img is None else cv2.cvtColor(img, cv2.COLOR_BGR2RGB)
        else:
            image = self._canvas
        return Sample(key=with_frame(self.key, i), label=f"{self.info.name} frame {fr.index} ({fr.time_s:.2f} s)",
                      keypoints_2d=kp, pose_3d=None, detected_2d=kp.copy(), camera=self.camera, image=image,
                      has_gt_2d=False,
                      upload=self.info, others_2d=tuple(np.asarray(p.keypoints_2d, np.float64) for p in people[1:]),
                      person_tags=tuple(self._tags[p.track_id] for p in people))

    def _canvas_for_bad(self) -> np.ndarray:
        return display_canvas(self.record.image_size or (1000, 1000), VIDEO_DISPLAY_MAX_SIDE)

    def seen_after(self, tag: str, index: int) -> bool:
        """Whether the person ``tag`` (``"track 3"``, :attr:`Sample.person_tags`) is in any frame after frame
        ``index`` (0 .. :attr:`num_frames` - 1): False once their track has ended."""
        return any(self._tags[p.track_id] == tag for fr in self.frames[int(index) + 1:] for p in fr.people)

    def index_of(self, key: str) -> int | None:
        """The frame index of a sample key of this sequence, else None."""
        at = frame_of(key)
        return at if at is not None and sequence_of(key) == self.key and at < self.num_frames else None

    def is_upload_pair(self, lifter: Any, focal: tuple[float, float]) -> bool:
        """Whether ``lifter`` at ``focal`` is what the upload was lifted with: the same lifter object (its name when
        the sequence does not know it) and the same focal length within :data:`FOCAL_SAME_PX` (the box shows
        0.1 px)."""
        rec = self.record
        same = (lifter is self.uploaded_with if self.uploaded_with is not None
                else getattr(lifter, "name", None) == rec.model)
        return same and self._upload_focal(focal)

    def _upload_focal(self, focal: tuple[float, float]) -> bool:
        """Whether ``focal`` is the upload's focal length, within :data:`FOCAL_SAME_PX` (alpha, px)."""
        f = self.record.focal
        return abs(float(focal_alpha(focal)) - float(focal_alpha(f))) <= FOCAL_SAME_PX

    def corrections(self, index: int, people_2d: list[np.ndarray],
                    dragged: dict[int, frozenset[int]]) -> dict[int, dict[int, tuple[np.ndarray, frozenset[int]]]]:
        """The joints dragged on frame ``index`` (as :meth:`sample` orders its people: ``people_2d``, each ``(17, 2)``
        px, and ``dragged``, person -> joints) for :meth:`record_at`: ``{record frame index: {track id: (2D,
        joints)}}``, empty when none were dragged."""
        fr = self.frames[int(index)]
        people = sorted(fr.people, key=lambda p: p.track_id)
        out = {people[k].track_id: (np.asarray(people_2d[k], np.float64), frozenset(j)) for k, j in dragged.items()
               if j and 0 <= k < len(people)}
        return {fr.index: out} if out else {}

    def record_at(self, lifter: Any, focal: tuple[float, float], *,
                  corrected: dict[int, dict[int, tuple[np.ndarray, frozenset[int]]]] | None = None) -> SequenceRecord:
        """The whole sequence as ``poselifter lift`` writes it, for ``lifter`` at ``focal``: the upload's record
        when both are the upload's (:meth:`is_upload_pair`), else every frame's people lifted again in one batch and
        tracked and smoothed as the upload was (cached for the last pair), each person keeping their
        ``person_id``, with the new lift's notes on its output in place of the upload's and a note saying so. A
        lens is undone at the upload's own focal (:func:`app.core.lens_free_2d`); the record then holds that
        undistorted 2D and no lens, so that lifting it again gives the same result. ``corrected``
        (:meth:`corrections`): joints dragged in the app, lifted in place of those people's 2D on that frame and named
        in a note (a browser trial's download of a sequence left them out, where the app had said to download to keep
        them)."""
        rec = self.record
        corrected = corrected or {}
        if self.is_upload_pair(lifter, focal) and not corrected:
            return rec
        f = (float(focal[0]), float(focal[1]))
        same_focal = self._upload_focal(f)
        if same_focal:  # (another model at the upload's focal length)
            f = (float(rec.focal[0]), float(rec.focal[1]))
        name = str(getattr(lifter, "name", "custom"))
        key = (id(lifter), f)
        with self._lock:
            if (self._relifted is not None and self._relifted[0] == key and self._relifted[1] is lifter
                    and not corrected):
                return self._relifted[2]
        src = "clean" if rec.source == "clean" else "detected"
        net = lifter.network_for(src) if hasattr(lifter, "network_for") else lifter
        seen = [fr for fr in rec.frames if fr.people]
        undistorted = undoes_lens(camera=self.camera, lifter=lifter, source=src)
        lifted_by_index: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}
        noted: set[int] = set()
        if seen:
            pp = np.asarray(rec.principal_point, np.float64)
            # every frame's people in one array: undistorted (if at all) and lifted in one call each
            given = [[corrected.get(fr.index, {}).get(p.track_id, (p.keypoints_2d,))[0] for p in fr.people]
                     for fr in seen]
            kp = lens_free_2d(np.stack([k for fr in given for k in fr]), camera=self.camera, lifter=lifter, source=src)
            res = lifter.lift(kp, focal=f, principal_point=pp, source=src, warn=False)
            root, rel = np.asarray(res.root).reshape(-1, 3), np.asarray(res.relative).reshape(-1, 17, 3)
            k = 0
            for fr, fr_given in zip(seen, given):
                c = len(fr.people)
                q = kp[k:k + c] if undistorted else np.stack(fr_given)
                lifted_by_index[fr.index] = (q, root[k:k + c], rel[k:k + c])
                if getattr(res, "warnings", ()) and hasattr(net, "output_notes"):
                    noted.add(fr.index)  # (said once tracked, by track id: tracked_output_notes)
                k += c
        lifted = []
        for fr in rec.frames:  # (a frame with nobody keeps its place)
            q, r, rl = lifted_by_index.get(fr.index, (np.zeros((0, 17, 2)), np.zeros((0, 3)), np.zeros((0, 17, 3))))
            scores = people_scores([p.scores for p in fr.people])
            lifted.append((fr.index, fr.time_s, q, r, rl, scores))
        ids = [[p.person_id for p in fr.people] for fr in rec.frames]
        frames = track_lifted(lifted, fps=rec.fps, focal=np.asarray(f), smoothing=rec.smoothing, person_ids=ids,
                              names=rec.tracking_names if rec.tracking_names is not None
                              and len(rec.tracking_names) == len(lifted)
                              else None)  # (the whole file's, as the upload's)
        for new, old in zip(frames, rec.frames):  # (the tracker keeps each frame's order)
            for st, was in zip(new.people, old.people):
                # (the tracker reads the 2D and the file's ids as the upload did, so it groups as the upload did;
                # but its numbers differ once the upload's one-frame detections were left out: keep the upload's,
                # which its notes and picker name)
                st.track_id = was.track_id
        # (why, first: a browser trial's note after a drag alone read "model 'x' at 1144.4 px (the upload's: 'x' at
        # 1144.4 px)", as if nothing had changed)
        why = [*([f"model {name!r} in place of the upload's {rec.model!r}"] if name != rec.model else []),
               *([f"focal length {float(focal_alpha(f)):.1f} px in place of the upload's "
                  f"{float(focal_alpha(rec.focal)):.1f} px"] if not same_focal else []),
               *(["2D joints corrected in the app, named below"] if corrected else [])]
        note = (f"lifted again in the app ({'; '.join(why) or 'as uploaded'}): model {name!r} at focal length "
                f"{float(focal_alpha(f)):.1f} px")
        if undistorted:
            note += ("; the 2D was undistorted with the lens at the upload's own focal length: keypoints_2d is that "
                     "undistorted 2D, and no 'distortion' is recorded")
        output_notes = tracked_output_notes(net, frames, np.asarray(rec.principal_point, np.float64), source=src,
                                            only=noted, focal=np.asarray(f, np.float64)) if noted else {}
        # (the upload's lift's notes on its output are replaced; and at another focal, the upload's assumed one is
        # no longer what was used: a user trial's download said both "assumed ... 555.0 px" and "at 572.2 px")
        kept = [w for w in rec.warnings if not OUTPUT_NOTE_LINE.match(w) and not ROOT_STEP_NOTE.match(w)
                and (same_focal or not w.startswith(ASSUMED_FOCAL_NOTE))]
        kept += track_root_step_notes(frames, fps=rec.fps)  # (of this lift's roots)
        fixed = [f"2D joints corrected in the app: frame {i} (track {tid}): "
                 + ", ".join(JOINT_NAMES[j] for j in sorted(joints))
                 for i, people in sorted(corrected.items()) for tid, (_, joints) in sorted(people.items())]
        out = replace(rec, model=name, model_info=model_info(lifter, source=src), focal=f,
                      focal_source=rec.focal_source if same_focal else "app-slider",
                      frames=frames,
                      warnings=[*kept, *output_note_lines(output_notes), note, *fixed],
                      distortion=None if undistorted else rec.distortion)
        if not corrected:
            with self._lock:
                self._relifted = (key, lifter, out)
        return out

    def trajectories(self, lifter: Any, focal: tuple[float, float]) -> list[dict[int, np.ndarray]]:
        """Every track's smoothed root trajectory, ``[{frame index: root (3,) mm}, ...]`` (one dict per track id,
        frames counted as :meth:`sample` counts them: those with someone in them), for ``lifter`` at ``focal``
        (:meth:`record_at`)."""
        frames = [fr for fr in self.record_at(lifter, focal).frames if fr.people]
        tracks: dict[int, dict[int, np.ndarray]] = {}
        for i, fr in enumerate(frames):
            for p in fr.people:
                tracks.setdefault(p.track_id, {})[i] = np.asarray(p.root, np.float64)
        return [tracks[t] for t in sorted(tracks)]


def _display_jpeg(bgr: np.ndarray, *, max_side: int = VIDEO_DISPLAY_MAX_SIDE) -> bytes:
    """A frame (OpenCV BGR) downscaled to ``max_side`` and JPEG-encoded, for display."""
    h, w = bgr.shape[:2]
    s = min(1.0, max_side / float(max(h, w)))
    if s < 1.0:
        bgr = cv2.resize(bgr, (max(1, round(w * s)), max(1, round(h * s))), interpolation=cv2.INTER_AREA)
    ok, buf = cv2.imencode(".jpg", bgr, [cv2.IMWRITE_JPEG_QUALITY, 80])
    if not ok:
        raise UploadError("a video frame could not be encoded for display")
    return buf.tobytes()


def video_sequence(name: str, content: bytes, *, key: str, lifter: Any, estimator: Callable[[], Any] | None,
                   max_bytes: int, detect_lock: Any, max_seconds: float = VIDEO_MAX_SECONDS,
                   progress: Callable[[int, int | None], None] | None = None, photo: Any | None = None,
                   min_score: float = MIN_PERSON_SCORE, on_wait: Callable[[], None] | None = None) -> VideoSequence:
    """Lift an uploaded video (``estimator()`` gives the 2D detector) or keypoint sequence JSON into a
    :class:`VideoSequence` (module docstring). Raises :class:`lifter.PoseLifterError` with a message for the user:
    too large, not decodable, zero-length, nobody in any frame, the detector extra missing, ... A keypoint sequence
    without a frame rate gets :data:`lifter.io.ASSUMED_FPS` (the app has no --fps), and one without an image size or
    principal point the size of ``photo`` (:class:`app.upload.Photo`, the photo uploaded before) where its poses fit
    it, each with a note (``lift_keypoint_sequence``'s ``assumed_fps`` and ``fallback_image``); the photo's EXIF
    focal length is then used where the sequence gives none, as for a single keypoint file. ``min_score``: the score
    floor (:data:`lifter.detect.MIN_PERSON_SCORE`; the File tab's "min person score"). A video is lifted up to
    :data:`VIDEO_MAX_FRAMES` frames; ``on_wait()`` is called when it must wait for another upload's detection, and an
    exception ``progress`` raises stops the lift (the tab closed)."""
    nm = safe_name(name)
    content = bytes(content or b"")
    check_upload(nm, content, max_bytes=max_bytes)
    kind, misnamed = input_kind(nm, content[:MEDIA_HEAD_BYTES])  # (is_video_upload's rule)
    is_video = kind == "video"
    suffix = (Path(nm).suffix.lower() if Path(nm).suffix.lower() in VIDEO_SUFFIXES else ".mp4") if is_video else ".json"
    with tempfile.TemporaryDirectory(prefix="poselifter-upload-") as d:
        path = Path(d) / f"upload{suffix}"
        path.write_bytes(content)
        try:
            if is_video:
                if estimator is None:
                    raise UploadError(f"{nm}: no 2D detector for videos")
                note_if_busy(detect_lock, on_wait)
                try:
                    est = estimator()
                except MissingDependencyError as exc:  # (the install's problem, as for a photo: not a refusal)
                    raise DetectorMissing(missing_detector_message(nm, exc, video=True), photo=None) from None
                shown: dict[int, bytes] = {}  # display copies, made while the video is decoded for lifting
                with detect_lock:
                    rec = lift_video(path, lifter=lifter, estimator=est, max_people=MAX_PEOPLE,
                                     max_seconds=max_seconds, max_frames=VIDEO_MAX_FRAMES, progress=progress,
                                     cli_options=False, min_score=min_score,
                                     on_frame=lambda i, bgr: shown.__setitem__(i, _display_jpeg(bgr)))
                jpegs = [shown[fr.index] for fr in rec.frames if fr.people]
            else:
                rec = lift_keypoint_sequence(
                    path, lifter=lifter, max_people=MAX_PEOPLE, max_seconds=max_seconds, cli_options=False,
                    assumed_fps=ASSUMED_FPS, min_score=min_score,
                    fallback_image=None if photo is None else (f"the photo {photo.name} uploaded before", photo.size,
                                                               photo.exif))
                jpegs = None
                if rec.distortion is not None and rec.distortion_model == "opencv":
                    rec = _without_opencv_lens(rec)  # (the app's cameras have Human3.6M's lens model)
                if rec.image_size is None:  # (lifted with its principal point; the canvas needs a size)
                    cx, cy = rec.principal_point
                    size = (max(1, round(2 * float(cx))), max(1, round(2 * float(cy))))
                    if max(size) > MAX_CANVAS_SIDE:
                        raise UploadError(f"{nm}: the keypoint sequence has no \"image_size\": [W, H], and twice its "
                                          f"principal point ({size[0]} x {size[1]} px) is too large a canvas; add it")
                    rec = replace(rec, image_size=size, warnings=[
                        *rec.warnings, f"no image_size in the file: assumed {size[0]} x {size[1]} px (twice the "
                        "principal point) for the canvas"])
        except DetectorMissing:
            raise
        except PoseLifterError as exc:
            msg = str(exc).replace(str(path), nm)
            if not is_video and photo is None and "'image_size'" in msg:  # (a browser trial: the app's own way out)
                msg += "; or upload the photo the keypoints were found in first: its size is then used"
            raise UploadError(msg) from None
    # the user's file name, not the server's temporary copy (in the download's "input" and in any note)
    rec = replace(rec, input=nm, warnings=[*([misnamed] if misnamed else []),
                                           *(w.replace(str(path), nm) for w in rec.warnings)])
    tracks = rec.tracks()
    notes = list(rec.warnings)
    empty = sum(1 for fr in rec.frames if not fr.people)
    if empty:
        notes.append(f"{empty} frame(s) with nobody in them are left out of playback: the player counts the frames "
                     "shown, and names a frame's own number in the file where the two differ")
    detail = focal_note(notes, {"keypoint-file": "focal length from the keypoint file"}.get(rec.focal_source,
                                                                                            rec.focal_source))
    info = UploadInfo(name=nm, kind="video" if is_video else "keypoints", focal_source=rec.focal_source,
                      focal_detail=detail, num_people=max((len(fr.people) for fr in rec.frames), default=0),
                      source=rec.source, detector=rec.detector, warnings=tuple(notes),
                      source_format=rec.source_format or H36M17)
    label = f"{nm} ({len(rec.frames)} frames at {rec.fps:g} fps, {len(tracks)} track{'s' if len(tracks) != 1 else ''})"
    return VideoSequence(key=key, label=label, record=rec, info=info, jpegs=jpegs, uploaded_with=lifter)


def _without_opencv_lens(rec: SequenceRecord) -> SequenceRecord:
    """A keypoint sequence lifted through an OpenCV lens (``"distortion_model": "opencv"``) as the app plays it: every
    person's 2D undistorted at the file's focal length and principal point (px; OpenCV's own model,
    :func:`lifter.camera.undistort_pixels_opencv`), no lens recorded, and a note saying so. The lift is unchanged: it
    already undid that lens, so lifting the undistorted 2D again without one gives the same poses. Raises
    :class:`lifter.PoseLifterError` where OpenCV cannot undo the lens (its message names the residual)."""
    seen = [p for fr in rec.frames for p in fr.people]
    if seen and rec.distortion is not None:
        flat = undistort_pixels_opencv(np.stack([p.keypoints_2d for p in seen]), focal=rec.focal,
                                       principal_point=rec.principal_point, dist_coeffs=rec.distortion)
        it = iter(flat)
        frames = [replace(fr, people=[replace(p, keypoints_2d=next(it)) for p in fr.people]) for fr in rec.frames]
    else:
        frames = list(rec.frames)
    note = OPENCV_LENS_UNDONE_NOTE.format(what="shown and downloaded")
    return replace(rec, frames=frames, distortion=None, distortion_model="h36m", warnings=[*rec.warnings, note])


def sequence_json_bytes(seq: VideoSequence, *, lifter: Any = None, focal: tuple[float, float] | None = None,
                        corrected: dict[int, dict[int, tuple[np.ndarray, frozenset[int]]]] | None = None) -> bytes:
    """The whole lifted sequence as ``poselifter lift clip.mp4`` writes ``DIR/clip.json`` (fps, frames, people with
    ``track_id``; smoothed), for ``lifter`` at ``focal`` (:meth:`VideoSequence.record_at`, with the joints
    ``corrected`` in the app; None: the upload's)."""
    rec = seq.record if lifter is None or focal is None else seq.record_at(lifter, focal, corrected=corrected)
    return json.dumps(rec.to_dict(), indent=1).encode("utf-8")


def sequence_glb_bytes(seq: VideoSequence, *, lifter: Any = None, focal: tuple[float, float] | None = None,
                       corrected: dict[int, dict[int, tuple[np.ndarray, frozenset[int]]]] | None = None) -> bytes:
    """The whole lifted sequence as the animated binary glTF of ``poselifter lift clip.mp4 --glb`` (every track;
    metres, y-up), for ``lifter`` at ``focal`` (None: the upload's), with the joints ``corrected`` in the app."""
    rec = seq.record if lifter is None or focal is None else seq.record_at(lifter, focal, corrected=corrected)
    if not rec.tracks():
        raise UploadError(f"{seq.info.name}: nobody in any frame; nothing to export")
    with tempfile.TemporaryDirectory(prefix="poselifter-download-") as d:
        return rec.write_glb(Path(d) / "sequence.glb").read_bytes()


def video_message(seq: VideoSequence) -> str:
    """What the readout says after a video / sequence upload."""
    rec = seq.record
    per = f", {1e3 * rec.seconds_per_frame:.0f} ms per frame" if rec.seconds_per_frame else ""
    notes = [n for n in seq.info.warnings if n != seq.info.focal_detail]
    return (f"{seq.label}: everyone lifted, tracked and smoothed{per}; press play (Sample tab) to play it with the "
            f"root trajectories. Focal: {seq.info.focal_detail}."
            # (each its own paragraph: a browser trial; each says it is the upload's, as a focal length or model set
            # since is not lifted until the download: a browser trial read "root moves 1.48 m" as current, where the
            # download at twice the focal said 2.63 m)
            + "".join(f"\n\nNote, as uploaded: {sentence(n)}" for n in notes))


__all__ = ["VIDEO_DISPLAY_MAX_SIDE", "VIDEO_MAX_FRAMES", "VIDEO_MAX_SECONDS", "VideoSequence", "is_sequence_json",
           "is_video_upload", "sequence_glb_bytes", "sequence_json_bytes", "video_message", "video_sequence"]
