"""2D overlays drawn with OpenCV: the input image (or a plain canvas) with 2D joints and bones.

Colours (RGB) distinguish the kind of 2D pose; bones are solid on the subject's left side and
dashed-looking (thinner, lighter) on the right side, and joints carry a side-coloured ring.
"""

from __future__ import annotations

import cv2
import numpy as np

from lifter.skeleton import EDGES, NUM_JOINTS, edge_side, joint_side

COLORS: dict[str, tuple[int, int, int]] = {
    "gt": (40, 200, 60),  # green: ground-truth 2D
    "detected": (240, 150, 0),  # orange: 2D detector
    "noisy": (160, 60, 220),  # purple: input + noise (what is lifted)
    "current": (230, 30, 30),  # red: the current / dragged 2D
}
SIDE_COLORS: dict[str, tuple[int, int, int]] = {"left": (30, 110, 255), "right": (255, 60, 160), "center": (250, 250, 250)}
"""Left joints blue ring, right joints pink ring (subject's own sides)."""


def canvas(width: int, height: int) -> np.ndarray:
    """A plain light canvas ``(H, W, 3)`` uint8 RGB of the camera's size, with a faint grid."""
    img = np.full((height, width, 3), 236, np.uint8)
    for x in range(0, width, 100):
        img[:, x] = 220
    for y in range(0, height, 100):
        img[y, :] = 220
    return img


def draw_pose(img: np.ndarray, kp: np.ndarray, color: tuple[int, int, int], *, scale: float = 1.0,
              thickness: int = 2, radius: int = 4, selected: int | None = None) -> None:
    """Draw a 17-joint 2D pose ``kp (17, 2)`` px (in the original image's pixels) in place."""
    pts = np.asarray(kp, np.float64) * scale
    if not np.all(np.isfinite(pts)):
        return
    ip = np.round(pts * 16).astype(np.int64)
    lim = 1 << 24
    ip = np.clip(ip, -lim, lim)
    for a, b in EDGES:
        right = edge_side((a, b)) == "right"
        col = tuple(int(0.55 * c + 0.45 * 255) for c in color) if right else color
        cv2.line(img, tuple(ip[a]), tuple(ip[b]), col, max(1, thickness - (1 if right else 0)), cv2.LINE_AA, shift=4)
    for j in range(NUM_JOINTS):
        c = tuple(ip[j])
        cv2.circle(img, c, (radius + 2) * 16, SIDE_COLORS[joint_side(j)], -1, cv2.LINE_AA, shift=4)
        cv2.circle(img, c, radius * 16, color, -1, cv2.LINE_AA, shift=4)
        if selected == j:
            cv2.circle(img, c, (radius + 6) * 16, (255, 255, 0), 2, cv2.LINE_AA, shift=4)


def scaled_base(base: np.ndarray | None, *, size: tuple[int, int], max_width: int = 480) -> tuple[np.ndarray, float]:
    """The image (or a canvas of ``size = (W, H)``) downscaled to at most ``max_width`` px wide, and the scale."""
    W, H = size
    s = min(1.0, max_width / float(W))
    w, h = max(1, int(round(W * s))), max(1, int(round(H * s)))
    src = canvas(W, H) if base is None else base
    if (w, h) != (src.shape[1], src.shape[0]):
        return cv2.resize(src, (w, h), interpolation=cv2.INTER_AREA), s
    return src.copy(), s


def overlay(base: np.ndarray | None, *, size: tuple[int, int], poses: dict[str, np.ndarray | None],
            max_width: int = 480, selected: int | None = None,
            prescaled: tuple[np.ndarray, float] | None = None) -> np.ndarray:
    """The image (or a canvas of ``size = (W, H)``) downscaled to at most ``max_width`` px wide, with the
    given poses (keys of :data:`COLORS`, ``(17, 2)`` px in full-resolution pixels) drawn on it. RGB uint8.
    ``prescaled``: the result of :func:`scaled_base` for this image, to skip the resize."""
    small, s = prescaled if prescaled is not None else scaled_base(base, size=size, max_width=max_width)
    img = small.copy()
    for key in ("gt", "detected", "noisy", "current"):
        kp = poses.get(key)
        if kp is not None:
            draw_pose(img, kp, COLORS[key], scale=s, thickness=2 if key == "current" else 1,
                      radius=3 if key == "current" else 2, selected=selected if key == "current" else None)
    return img
