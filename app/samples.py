"""Samples the app can show: the embedded demo set and (optionally) Human3.6M.

A :class:`Sample` bundles one camera view of one pose: 2D joints (px), optional 3D ground truth
(mm, OpenCV camera frame), optional detected 2D (px), the calibrated :class:`lifter.Camera` (its
``R, t`` map the world, z up, mm, to the camera) and optionally the photo. Human3.6M is read at run
time from its folder and never copied.
"""

from __future__ import annotations

import re
import threading
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

import cv2
import numpy as np

from lifter import Camera, DemoSample, PoseLifterError, demo_sample, demo_sample_names
from lifter.data import ACTIONS, CAMERA_IDS, DEFAULT_H36M_DIR, H36M
from lifter.detections import detection_stride
from lifter.keypoints import convert

from .keys import demo_key, h36m_key


@dataclass(frozen=True)
class Sample:
    """One view of one pose.

    keypoints_2d: ``(17, 2)`` px, ground-truth 2D (exact projection; with lens distortion for H36M).
    pose_3d: ``(17, 3)`` mm camera frame (OpenCV), or None when unknown.
    detected_2d: ``(17, 2)`` px from a 2D detector, or None.
    camera: intrinsics (px), extrinsics (world mm, z up -> camera), image size (px).
    image: ``(H, W, 3)`` uint8 RGB photo / render, or None (then a plain canvas is drawn). It may be a
        downscaled copy (uploads): 2D coordinates always refer to ``camera.width x camera.height``.
    has_gt_2d: False when ``keypoints_2d`` is not ground truth (uploads: the detected / given 2D).
    upload: provenance of an uploaded sample (:class:`app.upload.UploadInfo`), else None.
    others_2d: the other people in the same image, ``(17, 2)`` px each, largest first (a photo or a keypoint
        file with several people; video frames). They are lifted into the same camera space; the app's person
        picker makes any of them the draggable one.
    person_tags: the input's own name for each person, this one first (``"id 7"``, ``"track 3"``; ``""`` when it
        has none), shown in the person picker; empty when there are none.
    sequence_detected: a Human3.6M frame whose sequence and camera have 2D detections (on every frame, or every 5th
        for the training subjects), whether or not this frame has one.
    """

    key: str
    label: str
    keypoints_2d: np.ndarray
    pose_3d: np.ndarray | None
    detected_2d: np.ndarray | None
    camera: Camera
    image: np.ndarray | None
    has_gt_2d: bool = True
    upload: Any = None
    others_2d: tuple[np.ndarray, ...] = ()
    person_tags: tuple[str, ...] = ()
    sequence_detected: bool = False

    @property
    def num_people(self) -> int:
        """People in the image: this one and :attr:`others_2d`."""
        return 1 + len(self.others_2d)

    def person_tag(self, k: int) -> str:
        """:attr:`person_tags` ``[k]``, or ``""``."""
        return self.person_tags[k] if 0 <= k < len(self.person_tags) else ""

    def person_name(self, k: int) -> str:
        """How the picker, the readout and the 3D labels name person ``k``: :func:`person_label` with its tag; a
        tracked person (a video's or keypoint sequence's frame, tag ``"track N"``) is person N in every frame (a
        browser trial's track 2 was "person 2" in one frame and "person 1" in those where track 1 was missing; the
        output's tracks are numbered 1, 2, ... without gaps, :func:`lifter.video.renumber_tracks`)."""
        tag = self.person_tag(k)
        number = track_number(tag)
        return person_label(k if number is None else number - 1, tag)


def id_tag(person_id: object) -> str:
    """How a person's own id in the input (a keypoint file's ``person_id`` / ``id``) is named in
    :attr:`Sample.person_tags` and the picker: ``"id 7"``; parentheses become brackets, so that the picker's label
    (:func:`person_label`) reads back, and it is cut to 40 characters."""
    text = str(person_id).replace("(", "[").replace(")", "]")
    return "id " + (text if len(text) <= 40 else text[:39] + "…")


def track_number(tag: str) -> int | None:
    """N of a tracked person's tag ``"track N"`` (``"track 3, id kid"`` too: :func:`app.video.track_tag`), else None."""
    m = re.match(r"track (\d+)", tag)
    return None if m is None else int(m.group(1))


def person_label(k: int, tag: str = "") -> str:
    """The name of person index ``k`` (0 = largest): ``"person 1"``, ..., with the input's own name for them when
    it has one (``tag``: ``"id 7"`` from a keypoint file, ``"track 3"`` in a video): ``"person 2 (id 7)"``."""
    return f"person {int(k) + 1}" + (f" ({tag})" if tag else "")


def _read_rgb(path: Path) -> np.ndarray | None:
    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    return None if img is None else cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


class DemoCatalog:
    """The embedded demo samples (:func:`lifter.demo_sample`, made by ``scripts/make_demo_assets.py``; no H36M
    needed). ``root``: read them from that folder instead of the installed package (same layout)."""

    def __init__(self, root: Path | None = None) -> None:
        self.root = None if root is None else Path(root)
        if self.root is not None and not (self.root / "samples.npz").is_file():
            raise FileNotFoundError(f"demo samples not found at {self.root / 'samples.npz'}; run "
                                    "scripts/make_demo_assets.py")
        if self.root is None:
            self.names: tuple[str, ...] = tuple(demo_sample_names())
        else:
            with np.load(self.root / "samples.npz") as d:
                self.names = tuple(str(n) for n in d["names"])

    def _demo(self, name: str) -> DemoSample:
        if self.root is None:
            return demo_sample(name)
        with np.load(self.root / "samples.npz") as d:
            i = [str(n) for n in d["names"]].index(name)
            w, h = (int(v) for v in d["image_size"][i])
            return DemoSample(name=name, keypoints_2d=d["keypoints_2d"][i].astype(np.float64),
                              pose_3d=d["pose_3d"][i].astype(np.float64), focal=d["focal"][i].astype(np.float64),
                              principal_point=d["principal_point"][i].astype(np.float64), image_size=(w, h),
                              R=d["R"][i].astype(np.float64), t=d["t"][i].astype(np.float64),
                              image=(self.root / f"{name}.jpg").read_bytes())

    def get(self, name: str) -> Sample:
        """The demo sample ``name`` (one of :attr:`names`); raises :class:`PoseLifterError` otherwise."""
        if name not in self.names:
            raise PoseLifterError(f"unknown demo sample {name!r}; available: {list(self.names)}")
        d = self._demo(name)
        w, h = d.image_size
        cam = Camera(focal=(float(d.focal[0]), float(d.focal[1])),
                     principal_point=(float(d.principal_point[0]), float(d.principal_point[1])),
                     width=w, height=h, R=d.R, t=d.t, name=f"demo/{name}")
        img = cv2.imdecode(np.frombuffer(d.image, np.uint8), cv2.IMREAD_COLOR)
        return Sample(key=demo_key(name), label=f"demo: {name}", keypoints_2d=d.keypoints_2d, pose_3d=d.pose_3d,
                      detected_2d=None, camera=cam, image=None if img is None else cv2.cvtColor(img, cv2.COLOR_BGR2RGB))


class H36MCatalog:
    """Human3.6M browsing by subject / sequence / camera / frame, read lazily from ``root``.

    The 84 frames in ``root/demo`` show their photo; other frames show a plain canvas.
    """

    def __init__(self, root: Path) -> None:
        self.root = Path(root)
        self.data = H36M(self.root)
        self._lock = threading.Lock()
        self._detections = None
        det = self.root / "detections2d_sh_16j_px.npz"
        if det.is_file():
            self._detections = np.load(det)
        self._photos: dict[tuple[int, str, str, int], str] = {}
        ann = self.root / "demo" / "annotations.npz"
        if ann.is_file():
            a = np.load(ann)
            for img, s, act, cam, fr in zip(a["image"], a["subject"], a["action"], a["camera"], a["frame"]):
                self._photos[(int(str(s)[1:]), str(act), str(cam), int(fr))] = str(img)
        self.subjects: tuple[int, ...] = tuple(sorted({int(s.split("/")[0][1:]) for s in self.data.sequences}))
        self.camera_ids: tuple[str, ...] = CAMERA_IDS

    def sequences(self, subject: int) -> list[str]:
        """Sequence names (``"Walking 1"``) of a subject."""
        return [s.split("/", 1)[1] for s in self.data.sequences_of([subject])]

    def num_frames(self, subject: int, sequence: str) -> int:
        key = f"S{subject}/{sequence}"
        if key not in self.data.sequences:
            raise PoseLifterError(f"unknown H36M sequence {key!r}")
        with self._lock:
            return self.data.num_frames(key)

    def photo_frames(self) -> list[tuple[int, str, str, int]]:
        """``(subject, sequence, camera, frame)`` of the frames that have a real photo."""
        return sorted(self._photos)

    def get(self, subject: int, sequence: str, camera_id: str, frame: int) -> Sample:
        """One H36M view; raises :class:`PoseLifterError` for an unknown subject/sequence/camera/frame."""
        key = f"S{subject}/{sequence}"
        if key not in self.data.sequences:
            raise PoseLifterError(f"unknown H36M sequence {key!r}")
        if camera_id not in CAMERA_IDS:
            raise PoseLifterError(f"unknown H36M camera {camera_id!r}; expected one of {list(CAMERA_IDS)}")
        n = self.num_frames(subject, sequence)
        if not 0 <= int(frame) < n:
            raise PoseLifterError(f"frame {frame} out of range [0, {n}) for {key}")
        frame = int(frame)
        with self._lock:
            world = self.data.poses_world(key, frame)
            cam = self.data.camera(subject, camera_id)
            det, step = None, 0
            if self._detections is not None:
                dkey = f"{key}/{camera_id}"
                if dkey in self._detections.files:
                    rows = self._detections[dkey]
                    try:  # (every frame, or every 5th: the library's rule; any other count: no detection here)
                        step = detection_stride(rows.shape[0], n, key=dkey)
                    except PoseLifterError:
                        step = 0
                    if step and frame % step == 0 and frame // step < rows.shape[0]:
                        det = convert(rows[frame // step], src="sh16")  # the library's sh16 rules
        p3 = cam.world_to_camera(world)
        kp = cam.project(p3)
        photo = self._photos.get((subject, sequence, camera_id, frame))
        image = _read_rgb(self.root / "demo" / photo) if photo else None
        return Sample(key=h36m_key(subject, sequence, camera_id, frame),
                      label=f"S{subject} {sequence} cam {camera_id} frame {frame}", keypoints_2d=kp, pose_3d=p3,
                      detected_2d=det, camera=cam, image=image, sequence_detected=step > 0)


def default_h36m_root() -> Path | None:
    """``../shared/data/h36m`` (or ``$POSELIFTER_H36M``) when it exists, else None."""
    from lifter.data import default_h36m_dir

    root = default_h36m_dir()
    return root if (root / "poses3d_world_17j_mm.npz").is_file() else None


@lru_cache(maxsize=4)
def open_h36m(root: str) -> H36MCatalog:
    """A cached :class:`H36MCatalog` (shared by all browser tabs; read-only)."""
    return H36MCatalog(Path(root))


__all__ = ["ACTIONS", "DEFAULT_H36M_DIR", "DemoCatalog", "H36MCatalog", "Sample", "default_h36m_root", "open_h36m",
           "track_number"]
