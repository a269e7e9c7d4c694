"""Sample keys: the one place that writes and reads the strings naming what the viewer shows.

A key is ``SOURCE/...``:

- ``demo/NAME``: an embedded demo sample;
- ``motion/I``: frame ``I`` of the demo motion;
- ``h36m/S9/Walking 1/54138969/F``: frame ``F`` (0-based row) of a Human3.6M sequence seen by one camera;
- ``upload/N/NAME``: the ``N``-th upload, a photo or keypoint file (``NAME`` made safe by
  :func:`poselifter_app.upload.safe_name`);
- ``video/N/NAME/F``: frame ``F`` of the ``N``-th upload, a video or keypoint sequence.

The last part of a key of a sequence source (:data:`SEQUENCE_SOURCES`) is its frame index, and the key less that
part names the sequence (:func:`sequence_of`). Human3.6M's sequence names and cameras hold no ``/``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

SEQUENCE_SOURCES: Final[tuple[str, ...]] = ("h36m", "motion", "video")
"""Sources whose keys end in a frame index."""

UPLOADED_SOURCES: Final[tuple[str, ...]] = ("upload", "video")
"""Sources the user gave (a photo, keypoint file, video or keypoint sequence)."""


def source_of(key: str) -> str:
    """The source a key names (``"demo"``, ``"motion"``, ``"h36m"``, ``"upload"`` or ``"video"``)."""
    return key.partition("/")[0]


def sequence_of(key: str) -> str:
    """The sequence a frame's key belongs to (``h36m/S9/Posing 1/54138969``, ``video/3/clip.mp4``, ``motion``), else
    the key itself (a still sample is its own sequence: a demo sample, an uploaded photo)."""
    return key.rpartition("/")[0] if source_of(key) in SEQUENCE_SOURCES else key


def frame_of(key: str) -> int | None:
    """The frame index a key of a sequence source ends in, else None (a still sample, or no index)."""
    if source_of(key) not in SEQUENCE_SOURCES:
        return None
    tail = key.rpartition("/")[2]
    return int(tail) if tail.isdigit() else None


def with_frame(sequence: str, frame: int) -> str:
    """The key of frame ``frame`` of ``sequence`` (:func:`sequence_of`)."""
    return f"{sequence}/{int(frame)}"


def demo_key(name: str) -> str:
    """The key of the embedded demo sample ``name``."""
    return f"demo/{name}"


def demo_name(key: str) -> str | None:
    """The demo sample a ``demo/NAME`` key names, else None."""
    src, _, rest = key.partition("/")
    return rest if src == "demo" else None


def motion_key(frame: int) -> str:
    """The key of the demo motion's frame ``frame``."""
    return f"motion/{int(frame)}"


def upload_key(number: int, name: str) -> str:
    """The key of the ``number``-th upload, a photo or keypoint file named ``name`` (made safe already)."""
    return f"upload/{int(number)}/{name}"


def video_key(number: int, name: str) -> str:
    """The sequence key of the ``number``-th upload, a video or keypoint sequence named ``name`` (made safe already);
    its frames are :func:`with_frame` of it."""
    return f"video/{int(number)}/{name}"


@dataclass(frozen=True)
class H36MKey:
    """A Human3.6M frame: subject number (9 for S9), sequence (``"Walking 1"``), camera id (``"54138969"``) and
    0-based frame row."""

    subject: int
    sequence: str
    camera: str
    frame: int

    @property
    def subject_name(self) -> str:
        """``"S9"``."""
        return f"S{self.subject}"

    @property
    def sequence_key(self) -> str:
        """The key of this frame's sequence seen by its camera (:func:`sequence_of`)."""
        return f"h36m/S{self.subject}/{self.sequence}/{self.camera}"

    @property
    def photo_entry(self) -> str:
        """How the "frame with photo" picker names this frame: ``"S9 Posing 1 54138969 0"``
        (:func:`parse_photo_entry` reads it back)."""
        return f"{self.subject_name} {self.sequence} {self.camera} {self.frame}"

    def __str__(self) -> str:
        return with_frame(self.sequence_key, self.frame)


def h36m_key(subject: int, sequence: str, camera: str, frame: int) -> str:
    """The key of frame ``frame`` of subject ``subject``'s ``sequence`` seen by ``camera``."""
    return str(H36MKey(int(subject), sequence, str(camera), int(frame)))


def parse_h36m(key: str) -> H36MKey | None:
    """The Human3.6M frame an ``h36m/S9/SEQUENCE/CAMERA/F`` key names, else None (another source, or malformed)."""
    src, _, rest = key.partition("/")
    parts = rest.split("/")
    if src != "h36m" or len(parts) != 4:
        return None
    subj, sequence, camera, frame = parts
    if subj[:1] != "S" or not subj[1:].isdigit() or not frame.removeprefix("-").isdigit():
        return None  # (a negative frame parses, for the catalogue's out-of-range message)
    return H36MKey(int(subj[1:]), sequence, camera, int(frame))


NO_PHOTO: Final[str] = "(none)"
"""The "frame with photo" picker's entry for a frame without a photo."""


def parse_photo_entry(entry: str) -> H36MKey | None:
    """The Human3.6M frame a "frame with photo" entry (:attr:`H36MKey.photo_entry`) names, else None."""
    subj, _, rest = entry.partition(" ")
    parts = rest.rsplit(" ", 2)
    if subj[:1] != "S" or not subj[1:].isdigit() or len(parts) != 3 or not parts[2].removeprefix("-").isdigit():
        return None
    return H36MKey(int(subj[1:]), parts[0], parts[1], int(parts[2]))
