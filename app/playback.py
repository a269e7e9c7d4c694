"""Sequences the app plays, and the playback clock (pure; the view runs it on a thread).

A :class:`SequenceSource` gives, per frame index, a :class:`SequenceFrame`: the :class:`Sample` of every person
in that frame (same camera). The app shows and lifts ``people[0]`` today; a video source (decoded frames,
several people per frame from :mod:`lifter.detect`) plugs in by implementing the same protocol.

Sources here: a Human3.6M sequence seen by one camera (50 fps) and :class:`DemoMotion`, a 10-s walk made from the
demo samples' authored 3D poses (the walking pose, standing and the mirrored walking pose blended in turn while
the body walks a loop in front of the ``walking`` sample's camera; exact 2D, 3D ground truth), so playback works
without Human3.6M.
"""

from __future__ import annotations

import collections
import logging
import math
import threading
import time
import traceback
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from lifter import Camera
from lifter.skeleton import FLIP_PERMUTATION

from .keys import h36m_key, motion_key, sequence_of
from .samples import DemoCatalog, H36MCatalog, Sample

log = logging.getLogger("poselifter.app")

DISPLAY_FPS: float = 25.0
"""Playback redraws per second."""


@dataclass(frozen=True)
class SequenceFrame:
    people: tuple[Sample, ...]


class SequenceSource(Protocol):
    key: str
    label: str
    fps: float
    num_frames: int

    def frame(self, index: int) -> SequenceFrame: ...


@dataclass
class H36MSequence:
    catalog: H36MCatalog
    subject: int
    sequence: str
    camera: str
    fps: float = 50.0
    key: str = field(init=False)
    label: str = field(init=False)
    num_frames: int = field(init=False)

    def __post_init__(self) -> None:
        self.key = sequence_of(h36m_key(self.subject, self.sequence, self.camera, 0))
        self.label = f"S{self.subject} {self.sequence} cam {self.camera}"
        self.num_frames = self.catalog.num_frames(self.subject, self.sequence)

    def frame(self, index: int) -> SequenceFrame:
        return SequenceFrame((self.catalog.get(self.subject, self.sequence, self.camera, index),))


def _smoothstep(t: float) -> float:
    return t * t * (3.0 - 2.0 * t)


class DemoMotion:
    """A walk made from the demo samples (no Human3.6M needed): the ``walking`` pose, ``standing``, the mirrored
    ``walking`` pose (the other leg forward), ``standing`` again, blended in turn (``frames_per_pose`` frames
    each) for ``cycles`` gait cycles, while the body walks an ellipse of ``radius`` m by half that (depth) around
    the ``walking`` sample's root, facing where it goes, seen by the ``walking`` camera. Exact 2D and 3D ground
    truth; 25 fps."""

    fps: float = 25.0

    def __init__(self, demo: DemoCatalog, *, frames_per_pose: int = 8, cycles: int = 8, radius: float = 0.9) -> None:
        self.key = "motion"
        self.label = "demo motion"
        names = [n for n in ("walking", "standing") if n in demo.names] or [demo.names[0]]
        base = demo.get(names[0])
        self.camera: Camera = base.camera

        def aligned(name: str) -> tuple[np.ndarray, float]:
            """Root-relative world pose facing +x (left along +y), and the root's height (mm)."""
            s = demo.get(name)
            assert s.pose_3d is not None
            w = s.camera.camera_to_world(s.pose_3d)  # world mm, z up
            r = w - w[0]
            hip = r[4] - r[1]  # right hip -> left hip
            a = math.atan2(hip[1], hip[0]) - math.pi / 2
            c, s_ = math.cos(-a), math.sin(-a)
            return r @ np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]]).T, float(w[0, 2])

        walk, z_walk = aligned(names[0])
        stand, z_stand = aligned(names[-1])
        mirrored = walk[list(FLIP_PERMUTATION)] * np.array([1.0, -1.0, 1.0])  # left <-> right, y = 0 plane
        self._poses = [(walk, z_walk), (stand, z_stand), (mirrored, z_walk), (stand, z_stand)]
        assert base.pose_3d is not None
        self._centre = self.camera.camera_to_world(base.pose_3d[:1])[0]
        self.frames_per_pose = int(frames_per_pose)
        self.num_frames = self.frames_per_pose * len(self._poses) * int(cycles)
        self.radius = float(radius)

    def world_pose(self, index: int) -> np.ndarray:
        """``(17, 3)`` world mm of frame ``index``."""
        i = int(index) % self.num_frames
        k, t = divmod(i, self.frames_per_pose)
        t = _smoothstep(t / self.frames_per_pose)
        n = len(self._poses)
        (a, za), (b, zb) = self._poses[k % n], self._poses[(k + 1) % n]
        rel = (1 - t) * a + t * b
        phase = 2 * math.pi * i / self.num_frames
        x, y = 1000 * self.radius * math.cos(phase), 500 * self.radius * math.sin(phase)
        heading = math.atan2(500 * self.radius * math.cos(phase), -1000 * self.radius * math.sin(phase))
        c, s = math.cos(heading), math.sin(heading)
        Rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        root = np.array([self._centre[0] + x, self._centre[1] + y, (1 - t) * za + t * zb])
        return rel @ Rz.T + root

    def frame(self, index: int) -> SequenceFrame:
        i = int(index) % self.num_frames
        p3 = self.camera.world_to_camera(self.world_pose(i))
        kp = self.camera.project(p3)
        s = Sample(key=motion_key(i), label=f"demo motion frame {i}", keypoints_2d=kp, pose_3d=p3, detected_2d=None,
                   camera=self.camera, image=None)
        return SequenceFrame((s,))


def clamp_speed(speed: float, *, low: float, high: float) -> float:
    """``speed`` (× real time) within ``[low, high]``; 1 for a value that is not a finite number."""
    return min(max(float(speed), low), high) if math.isfinite(float(speed)) else 1.0


@dataclass
class PlayClock:
    """Which frame to show at time ``now`` (s) while playing: ``index0`` at ``t0``, advancing at ``fps * speed``
    frames per second, looping over ``num_frames``. Re-anchor (:meth:`restart`) when the speed or the frame
    changes by hand."""

    fps: float
    num_frames: int
    speed: float = 1.0
    index0: int = 0
    t0: float = 0.0

    def restart(self, *, index: int, now: float, speed: float | None = None) -> None:
        self.index0, self.t0 = int(index), float(now)
        if speed is not None:
            self.speed = float(speed)

    def index(self, now: float) -> int:
        steps = math.floor((now - self.t0) * self.fps * self.speed + 1e-9)
        return (self.index0 + steps) % max(self.num_frames, 1)


class Player:
    """Plays on a thread, :data:`DISPLAY_FPS` times a second: ``position()`` says which sequence and frame are shown
    (None stops), ``speed()`` the speed; the frame :class:`PlayClock` gives is passed to ``show(index)``; frames are
    skipped, never slowed down, when a redraw is late. A change of sequence, frame (scrubbing) or speed re-anchors
    the clock. ``on_stop()`` runs when playback ends by itself. Server-side time of each ``show`` (ms) and the
    time it was shown are kept in :attr:`frame_ms` and :attr:`shown_at`."""

    def __init__(self, *, position: Callable[[], tuple[SequenceSource, int] | None], speed: Callable[[], float],
                 show: Callable[[int], None], on_stop: Callable[[], None], fps: float = DISPLAY_FPS) -> None:
        self._position, self._speed, self._show, self._on_stop = position, speed, show, on_stop
        self.period = 1.0 / fps
        self._playing = threading.Event()
        self._thread: threading.Thread | None = None
        self.frame_ms: collections.deque[float] = collections.deque(maxlen=5000)
        self.shown_at: collections.deque[float] = collections.deque(maxlen=5000)
        self.playing_key: str | None = None
        """The key of the sequence the frame passed to ``show`` belongs to (set just before the call): a ``show``
        can tell a frame of a sequence left meanwhile."""

    @property
    def playing(self) -> bool:
        return self._playing.is_set()

    def start(self) -> None:
        if self.playing:
            return
        self._playing.set()
        self._thread = threading.Thread(target=self._loop, name="poselifter-play", daemon=True)
        self._thread.start()

    def stop(self, *, wait: bool = True) -> None:
        self._playing.clear()
        t = self._thread
        if wait and t is not None and t is not threading.current_thread():
            t.join(timeout=5.0)

    def _loop(self) -> None:
        clock: PlayClock | None = None
        key, shown, speed = None, -1, None
        next_t = time.perf_counter()
        try:
            while self._playing.is_set():
                pos = self._position()
                if pos is None:
                    break
                seq, idx = pos
                now = time.perf_counter()
                sp = float(self._speed())
                if clock is None or seq.key != key or idx != shown or sp != speed:
                    clock = PlayClock(fps=seq.fps, num_frames=seq.num_frames, speed=sp)
                    clock.restart(index=idx, now=now)
                    key, shown, speed = seq.key, idx, sp
                target = clock.index(now)
                if target != shown:
                    t0 = time.perf_counter()
                    self.playing_key = key
                    self._show(target)
                    t1 = time.perf_counter()
                    self.frame_ms.append(1e3 * (t1 - t0))
                    self.shown_at.append(t1)
                    shown = target
                next_t += self.period
                delay = next_t - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
                else:
                    next_t = time.perf_counter()
        except Exception:  # noqa: BLE001 - a failed frame ends playback, never the server
            log.error("playback failed:\n%s", traceback.format_exc())
        finally:
            if self._playing.is_set():
                self._playing.clear()
                self._on_stop()
