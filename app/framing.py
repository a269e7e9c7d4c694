"""Viewpoints of the 3D view, pure numpy (world metres, z up): fit a set of points into a viewer's field of
view, test whether they are in it, and the two standard views (overview from behind the camera; head-on at
the image plane)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DEFAULT_FOV_Y_RAD: float = float(np.radians(50.0))
"""Vertical field of view assumed when the viewer's is unknown (the server's initial camera)."""
FILL: float = 0.8
"""A fitted view puts the points within this fraction of the half-field of view."""


@dataclass(frozen=True)
class Viewpoint:
    eye: np.ndarray
    look_at: np.ndarray
    up: np.ndarray


def _basis(eye: np.ndarray, look_at: np.ndarray, up: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    f = np.asarray(look_at, np.float64) - np.asarray(eye, np.float64)
    f /= max(float(np.linalg.norm(f)), 1e-12)
    r = np.cross(f, np.asarray(up, np.float64))
    if np.linalg.norm(r) < 1e-9:  # looking along "up"
        r = np.cross(f, np.array([1.0, 0.0, 0.0]) if abs(f[0]) < 0.9 else np.array([0.0, 1.0, 0.0]))
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    return r, u, f


def screen_coords(points: np.ndarray, view: Viewpoint, *, fov_y: float, aspect: float) -> np.ndarray:
    """``(N, 3)`` normalised screen coordinates of world points: x, y in [-1, 1] inside the view (y up), and the
    depth along the view direction (m; <= 0 behind the eye)."""
    r, u, f = _basis(view.eye, view.look_at, view.up)
    d = np.asarray(points, np.float64).reshape(-1, 3) - view.eye
    z = d @ f
    ty = np.tan(fov_y / 2.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        x = (d @ r) / (z * ty * aspect)
        y = (d @ u) / (z * ty)
    return np.stack([x, y, z], axis=-1)


def in_view(points: np.ndarray, view: Viewpoint, *, fov_y: float, aspect: float, margin: float = 1.0) -> bool:
    """True when every point is in front of the eye and inside ``margin`` x the field of view."""
    s = screen_coords(points, view, fov_y=fov_y, aspect=aspect)
    return bool(np.all(s[:, 2] > 1e-3) and np.all(np.abs(s[:, :2]) <= margin))


def fit(points: np.ndarray, *, direction: np.ndarray, up: np.ndarray, fov_y: float, aspect: float,
        fill: float = FILL) -> Viewpoint:
    """The viewpoint looking along ``direction`` at the centre of the points' bounding box, as close as it can be
    with every point within ``fill`` of the half-field of view (closed form: each point gives a minimum distance)."""
    P = np.asarray(points, np.float64).reshape(-1, 3)
    centre = 0.5 * (P.min(axis=0) + P.max(axis=0))
    r, u, f = _basis(centre - np.asarray(direction, np.float64), centre, up)
    d = P - centre
    ty = np.tan(fov_y / 2.0) * fill
    tx = ty * aspect
    need = np.maximum(np.abs(d @ r) / tx, np.abs(d @ u) / ty) - d @ f
    near = 0.05 - d @ f  # every point at least 5 cm in front of the eye
    dist = float(max(np.max(need), np.max(near), 0.5))
    return Viewpoint(eye=centre - dist * f, look_at=centre, up=np.asarray(up, np.float64))


def overview_direction(camera_centre: np.ndarray, target: np.ndarray) -> np.ndarray:
    """The overview's viewing direction: from behind, above and to the side of the camera towards ``target``
    (world, m; z up)."""
    C = np.asarray(camera_centre, np.float64)
    fwd = np.asarray(target, np.float64) - C
    flat = fwd - np.array([0.0, 0.0, fwd[2]])
    if np.linalg.norm(flat) < 1e-6:
        flat = np.array([1.0, 0.0, 0.0])
    flat /= np.linalg.norm(flat)
    side = np.cross(flat, [0.0, 0.0, 1.0])
    d = flat + 0.5 * side - np.array([0.0, 0.0, 0.4])
    return d / np.linalg.norm(d)


def head_on(*, centre_cam: np.ndarray, half_extent: float, R: np.ndarray, C: np.ndarray, fov_y: float,
            fill: float = FILL) -> Viewpoint:
    """Straight at the image plane from the camera's side (camera frame point ``centre_cam`` in the middle, image
    up = the camera's -y), close enough that ``half_extent`` (m) fills ``fill`` of the half-field of view."""
    dist = half_extent / (fill * np.tan(fov_y / 2.0))
    eye = np.asarray(centre_cam, np.float64) - np.array([0.0, 0.0, dist])
    return Viewpoint(eye=R.T @ eye + C, look_at=R.T @ np.asarray(centre_cam, np.float64) + C,
                     up=R.T @ np.array([0.0, -1.0, 0.0]))
