"""People tracked across video frames with a stable ``track_id``.

Each frame's people (2D keypoints, px) are matched to the live tracks by an optimal assignment
(:func:`scipy.optimize.linear_sum_assignment`) on a cost that is the distance between the 2D keypoint-box
centres divided by the track's box diagonal (so the gate scales with the person's size in the image), plus
the box-size mismatch ``|log(diag / track diag)|``. A pair costing more than ``gate`` is not matched: the
person starts a new track. A track that is not seen for more than ``max_missed`` frames ends; its id is never
reused by anyone else. Where the input names its people (a keypoint sequence's ``person_id``), the names decide: a
person is matched to the live track of the same name, whatever the cost, and never to a track of another name; a
name that comes back after its track ended takes that track up again (same id), however long the gap.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np

from ._checks import PoseLifterError

DEFAULT_GATE: Final[float] = 0.75
"""Largest matching cost: a centre shift of 0.75 box diagonals between two sightings (less with a size change)."""


_NEVER: Final[float] = 1e9
"""The matching cost of a person and a track the input names differently (never below any gate)."""


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
    person_id: str | int | None = None
    """The input's own name for this person (a keypoint sequence's ``person_id``), None where it has none."""


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
        self.resumed: set[int] = set()
        """The ids of the ended tracks the last :meth:`update` took up again (a name back after the timeout): what
        follows a track over time (a smoother) starts afresh for them."""
        self._next = 1

    def update(self, frame: int, keypoints: list[np.ndarray] | np.ndarray,
               person_ids: list[str | int | None] | None = None) -> list[int]:
        """Track ids for the people ``keypoints`` (each ``(J, 2)`` px) of frame number ``frame`` (increasing),
        in the same order. First ends the tracks unseen for more than ``max_missed`` frames before this one, so a
        person who comes back after a longer gap gets a new id even if no frame in between was passed here.
        ``person_ids``: the input's own name for each person (None: unnamed), which decides over the boxes
        (module docstring)."""
        for tid in [t for t, tr in self.tracks.items() if frame - tr.last_frame > self.max_missed]:
            self.ended.append(self.tracks.pop(tid))
        boxes = [box_centre_diag(k) for k in keypoints]
        names: list[str | int | None] = list(person_ids) if person_ids is not None else [None] * len(boxes)
        if len(names) != len(boxes):
            raise PoseLifterError(f"Tracker.update: {len(names)} person ids for {len(boxes)} people")
        live_names = {tr.person_id for tr in self.tracks.values()}
        self.resumed = set()
        for name in dict.fromkeys(n for n in names if n is not None and n not in live_names):
            gone = [k for k, tr in enumerate(self.ended) if tr.person_id == name]
            if gone:  # a name back after its track ended: that track again (the boxes then match it at any jump)
                tr = self.ended.pop(gone[-1])
                tr.velocity = np.zeros(2)
                self.tracks[tr.track_id] = tr
                self.resumed.add(tr.track_id)
        live = list(self.tracks.values())
        ids: list[int] = [0] * len(boxes)

        def box_cost(i: int, tr: Track) -> float:
            c, d = boxes[i]
            pred = tr.centre + tr.velocity * (frame - tr.last_frame)
            return float(np.linalg.norm(c - pred)) / tr.diag + abs(math.log(d / tr.diag))

        def assign(people: list[int], tracks: list[Track], cost: np.ndarray, gate: float) -> None:
            from scipy.optimize import linear_sum_assignment

            if not people or not tracks:
                return
            # (pairs past the gate are never matched, so they must not steer the assignment of the others either: a
            # person far from every track would otherwise push someone near two tracks onto the farther one)
            within = cost <= gate
            rows, cols = linear_sum_assignment(np.where(within, cost, _NEVER))
            for r, k in zip(rows, cols):
                if within[r, k]:
                    i, tr = people[r], tracks[k]
                    c, d = boxes[i]
                    gap = max(frame - tr.last_frame, 1)
                    tr.velocity = 0.5 * tr.velocity + 0.5 * (c - tr.centre) / gap
                    tr.centre, tr.diag, tr.last_frame, tr.hits = c, d, frame, tr.hits + 1
                    if tr.person_id is None:
                        tr.person_id = names[i]
                    ids[i] = tr.track_id

        # first the names: each named person to a live track of that name (the nearest box among several), whatever
        # the jump; then everyone left by the boxes, within the gate, never to a track of another name
        for name in dict.fromkeys(n for n in names if n is not None):
            people = [i for i, n in enumerate(names) if n == name]
            tracks = [tr for tr in live if tr.person_id == name]
            assign(people, tracks, np.array([[box_cost(i, tr) for tr in tracks] for i in people]), math.inf)
        taken = set(ids)
        people = [i for i in range(len(boxes)) if ids[i] == 0]
        tracks = [tr for tr in live if tr.track_id not in taken]
        cost = np.array([[_NEVER if names[i] is not None and tr.person_id is not None and names[i] != tr.person_id
                          else box_cost(i, tr) for tr in tracks] for i in people]).reshape(len(people), len(tracks))
        assign(people, tracks, cost, self.gate)
        for i, (c, d) in enumerate(boxes):
            if ids[i] == 0:
                tr = Track(self._next, c, d, frame, frame, person_id=names[i])
                self._next += 1
                self.tracks[tr.track_id] = tr
                ids[i] = tr.track_id
        return ids

    def all_tracks(self) -> list[Track]:
        """Every track so far (ended and live), by id."""
        return sorted([*self.ended, *self.tracks.values()], key=lambda t: t.track_id)


__all__ = ["DEFAULT_GATE", "Track", "Tracker", "box_centre_diag"]
