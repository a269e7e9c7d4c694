"""People tracked across video frames with a stable ``track_id``.

Each frame's people (2D keypoints, px) are matched to the live tracks by an optimal assignment
(:func:`scipy.optimize.linear_sum_assignment`) on a cost that is the distance between the 2D keypoint-box
centres divided by the track's box diagonal (so the gate scales with the person's size in the image), plus
the box-size mismatch ``|log(diag / track diag)|``. A pair costing more than ``gate`` is not matched: the
person starts a new track. A track that is not seen for more than ``max_missed`` frames ends; its id is never
reused.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np

from ._checks import PoseLifterError

DEFAULT_GATE: Final[float] = 0.75
"""Largest matching cost: a centre shift of 0.75 box diagonals between two sightings (less with a size change)."""


@dataclass
class Track:
    """A tracked person: ``track_id``, the last box centre ``(2,)`` and diagonal (px), the frame it was
    last seen in, and how many frames it was seen in."""

    track_id: int
    centre: np.ndarray
    diag: float
    last_frame: int
    first_frame: int
    hits: int = 1
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(2))


def box_centre_diag(keypoints: np.ndarray) -> tuple[np.ndarray, float]:
    """Centre ``(2,)`` and diagonal (px, at least 1) of the box around ``(J, 2)`` keypoints."""
    k = np.asarray(keypoints, np.float64)
    lo, hi = np.nanmin(k, 0), np.nanmax(k, 0)
    return 0.5 * (lo + hi), max(float(np.hypot(*(hi - lo))), 1.0)


class Tracker:
    """Assigns stable track ids to the people of consecutive frames (module docstring)."""

    def __init__(self, *, gate: float = DEFAULT_GATE, max_missed: int = 25) -> None:
        if not (math.isfinite(gate) and gate > 0):
            raise PoseLifterError(f"tracker gate must be > 0, got {gate}")
        if max_missed < 0:
            raise PoseLifterError(f"max_missed must be >= 0 frames, got {max_missed}")
        self.gate, self.max_missed = float(gate), int(max_missed)
        self.tracks: dict[int, Track] = {}
        self.ended: list[Track] = []
        self._next = 1

    def update(self, frame: int, keypoints: list[np.ndarray] | np.ndarray) -> list[int]:
        """Track ids for the people ``keypoints`` (each ``(J, 2)`` px) of frame number ``frame`` (increasing),
        in the same order. First ends the tracks unseen for more than ``max_missed`` frames before this one, so a
        person who comes back after a longer gap gets a new id even if no frame in between was passed here."""
        for tid in [t for t, tr in self.tracks.items() if frame - tr.last_frame > self.max_missed]:
            self.ended.append(self.tracks.pop(tid))
        boxes = [box_centre_diag(k) for k in keypoints]
        live = list(self.tracks.values())
        ids: list[int] = [0] * len(boxes)
        if boxes and live:
            from scipy.optimize import linear_sum_assignment

            cost = np.empty((len(boxes), len(live)))
            for i, (c, d) in enumerate(boxes):
                for j, tr in enumerate(live):
                    gap = frame - tr.last_frame
                    pred = tr.centre + tr.velocity * gap
                    cost[i, j] = float(np.linalg.norm(c - pred)) / tr.diag + abs(math.log(d / tr.diag))
            rows, cols = linear_sum_assignment(cost)
            for i, j in zip(rows, cols):
                if cost[i, j] <= self.gate:
                    tr = live[j]
                    c, d = boxes[i]
                    gap = max(frame - tr.last_frame, 1)
                    tr.velocity = 0.5 * tr.velocity + 0.5 * (c - tr.centre) / gap
                    tr.centre, tr.diag, tr.last_frame, tr.hits = c, d, frame, tr.hits + 1
                    ids[i] = tr.track_id
        for i, (c, d) in enumerate(boxes):
            if ids[i] == 0:
                tr = Track(self._next, c, d, frame, frame)
                self._next += 1
                self.tracks[tr.track_id] = tr
                ids[i] = tr.track_id
        return ids

    def all_tracks(self) -> list[Track]:
        """Every track so far (ended and live), by id."""
        return sorted([*self.ended, *self.tracks.values()], key=lambda t: t.track_id)


__all__ = ["DEFAULT_GATE", "Track", "Tracker", "box_centre_diag"]
