"""2D overlays drawn with OpenCV: the input image (or a plain canvas) with 2D joints and bones.

Colours (RGB) distinguish the kind of 2D pose; bones are solid on the subject's left side and
dashed-looking (thinner, lighter) on the right side, and joints carry a side-coloured ring.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from lifter.skeleton import EDGES, NUM_JOINTS, edge_side, joint_side

COLORS: dict[str, tuple[int, int, int]] = {
    "gt": (40, 200, 60),  # green: ground-truth 2D
    "detected": (240, 150, 0),  # orange: 2D detector
    "noisy": (160, 60, 220),  # purple: input + noise (what is lifted)
    "current": (230, 30, 30),  # red: the current / dragged 2D
    "other": (0, 150, 150),  # teal: the other people of the image (select one with the person picker)
}
SIDE_COLORS: dict[str, tuple[int, int, int]] = {"left": (30, 110, 255), "right": (255, 60, 160),
                                                "center": (250, 250, 250)}
"""Left joints blue ring, right joints pink ring (subject's own sides)."""
JOINT_RGB: np.ndarray = np.array([
    (90, 90, 90), (200, 40, 40), (235, 95, 35), (250, 150, 50),  # pelvis, r_hip, r_knee, r_ankle
    (30, 70, 190), (40, 120, 240), (90, 170, 255),  # l_hip, l_knee, l_ankle
    (110, 110, 110), (60, 60, 60), (130, 130, 130), (40, 40, 40),  # spine, thorax, neck_nose, head_top
    (0, 90, 150), (0, 150, 200), (40, 205, 225),  # l_shoulder, l_elbow, l_wrist
    (160, 20, 90), (215, 50, 130), (255, 105, 170),  # r_shoulder, r_elbow, r_wrist
], np.uint8)
"""Each joint's own colour (lifted joints, their uncertainty clouds, the draggable 2D joints): the subject's left
in blues, right in reds / oranges, centre in greys; lighter towards the end of each limb."""


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
    """(The current pose, ``selected`` not None, fills its joints with :data:`JOINT_RGB`.)"""
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
        cv2.circle(img, c, (radius + min(2, max(1, radius // 2))) * 16, SIDE_COLORS[joint_side(j)], -1, cv2.LINE_AA,
                   shift=4)
        fill = tuple(int(x) for x in JOINT_RGB[j]) if selected is not None else color
        cv2.circle(img, c, radius * 16, fill, -1, cv2.LINE_AA, shift=4)
        if selected == j:
            cv2.circle(img, c, (radius + max(3, radius)) * 16, (255, 220, 0), max(1, radius // 2), cv2.LINE_AA, shift=4)


def scaled_base(base: np.ndarray | None, *, size: tuple[int, int], max_width: int = 480) -> tuple[np.ndarray, float]:
    """The image (or a canvas of ``size = (W, H)``) downscaled to at most ``max_width`` px wide, and the scale."""
    W, H = size
    s = min(1.0, max_width / float(W))
    w, h = max(1, int(round(W * s))), max(1, int(round(H * s)))
    src = canvas(W, H) if base is None else base
    if (w, h) != (src.shape[1], src.shape[0]):
        return cv2.resize(src, (w, h), interpolation=cv2.INTER_AREA), s
    return src.copy(), s


MARKS_FULL_HEIGHT_PX: float = 200.0
"""A person at least this tall (px, in the drawn inset) gets full-size joint marks (:func:`mark_scale`)."""


def mark_scale(keypoints: np.ndarray | None, *, scale: float) -> float:
    """How large :func:`overlay` draws joint marks for a person whose 2D is ``keypoints`` ``(17, 2)`` px (full
    resolution), drawn at ``scale``: 1 for a person at least :data:`MARKS_FULL_HEIGHT_PX` tall in the inset,
    in proportion below that, down to 0.4; 1 without keypoints."""
    if keypoints is None:
        return 1.0
    kp = np.asarray(keypoints, np.float64)
    ok = np.all(np.isfinite(kp), axis=-1)
    if ok.sum() < 2:
        return 1.0
    extent = float(np.ptp(kp[ok], axis=0).max()) * scale
    return float(np.clip(extent / MARKS_FULL_HEIGHT_PX, 0.4, 1.0))


INSET_ZOOM_BELOW: float = 0.4
""":func:`overlay` with ``zoom`` shows only the region around the people when the box around all their joints is
narrower and lower than this share of the image's width and height (a researcher trial: a person about 100 px tall
in the inset left the ground truth and the detection too small to compare)."""


def inset_crop(size: tuple[int, int], poses: Sequence[np.ndarray]) -> tuple[int, int, int, int] | None:
    """The region ``(x0, y0, x1, y1)`` px (full resolution, inside the image of ``size = (W, H)``, of the image's
    aspect ratio) that :func:`overlay` zooms onto: 1.5 times the box around every finite joint of ``poses`` (each
    ``(17, 2)`` px), at least an eighth of the image wide; None when that box already fills
    :data:`INSET_ZOOM_BELOW` of the image in width or height, or fewer than two joints are finite."""
    W, H = size
    pts = [np.asarray(p, np.float64).reshape(-1, 2) for p in poses]
    xy = np.concatenate(pts) if pts else np.zeros((0, 2))
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if len(xy) < 2:
        return None
    lo, hi = xy.min(axis=0), xy.max(axis=0)
    ext = hi - lo
    if ext[0] >= INSET_ZOOM_BELOW * W or ext[1] >= INSET_ZOOM_BELOW * H:
        return None
    half_w = min(max(0.75 * ext[0], 0.75 * ext[1] * W / H, W / 16.0), W / 2.0)
    half_h = half_w * H / W
    c = (lo + hi) / 2.0
    x0 = float(np.clip(c[0] - half_w, 0.0, W - 2 * half_w))
    y0 = float(np.clip(c[1] - half_h, 0.0, H - 2 * half_h))
    return int(round(x0)), int(round(y0)), int(round(x0 + 2 * half_w)), int(round(y0 + 2 * half_h))


def overlay(base: np.ndarray | None, *, size: tuple[int, int], poses: dict[str, np.ndarray | None],
            max_width: int = 480, selected: int | None = None,
            prescaled: tuple[np.ndarray, float] | None = None,
            others: Sequence[tuple[int, np.ndarray]] = (), zoom: bool = False) -> np.ndarray:
    """The image (or a canvas of ``size = (W, H)``) downscaled to at most ``max_width`` px wide, with the
    given poses (keys of :data:`COLORS`, ``(17, 2)`` px in full-resolution pixels) drawn on it, and the other
    people ``others`` (``(person index, (17, 2) px)``, numbered from 1 at their head). RGB uint8.
    ``prescaled``: the result of :func:`scaled_base` for this image, to skip the resize. ``zoom``: where the people
    are small in the image, show only the region around them (:func:`inset_crop`), at the same inset size, marked
    with its magnification ("zoom x2.5"). ``base`` may be a smaller copy of the ``size`` image (an upload's display
    copy): the region is cut from it at its own scale."""
    crop = inset_crop(size, [p for p in (*poses.values(), *(kp for _, kp in others)) if p is not None]) \
        if zoom else None
    offset = np.zeros(2)
    magnification = 1.0
    if crop is None:
        small, s = prescaled if prescaled is not None else scaled_base(base, size=size, max_width=max_width)
        img = small.copy()
    else:
        W, H = size
        src = canvas(W, H) if base is None else base
        # the crop in the pixels of ``src`` (a display copy is smaller than ``size``: a browser trial's 4000 px photo
        # had its crop cut from the 1280 px copy at full-resolution coordinates, empty, and the upload failed), whole
        # pixels of it, and the full-resolution region they cover, which the poses are drawn in
        sx, sy = src.shape[1] / float(W), src.shape[0] / float(H)
        bx0 = min(int(np.floor(crop[0] * sx)), src.shape[1] - 1)
        by0 = min(int(np.floor(crop[1] * sy)), src.shape[0] - 1)
        bx1 = max(bx0 + 1, min(int(np.ceil(crop[2] * sx)), src.shape[1]))
        by1 = max(by0 + 1, min(int(np.ceil(crop[3] * sy)), src.shape[0]))
        x0, y0, x1, y1 = bx0 / sx, by0 / sy, bx1 / sx, by1 / sy
        out_w = max(1, int(round(W * min(1.0, max_width / float(W)))))
        out_h = max(1, int(round(out_w * (y1 - y0) / float(x1 - x0))))
        s = out_w / float(x1 - x0)
        img = cv2.resize(src[by0:by1, bx0:bx1], (out_w, out_h),
                         interpolation=cv2.INTER_AREA if out_w < bx1 - bx0 else cv2.INTER_LINEAR)
        offset = np.array([x0, y0], np.float64)
        magnification = W / (x1 - x0)
        poses = {k: None if v is None else np.asarray(v, np.float64) - offset for k, v in poses.items()}
        others = [(k, np.asarray(kp, np.float64) - offset) for k, kp in others]
    # marks grow with the inset (readable on 1000-px frames) and shrink for a small person (a browser trial: discs
    # 16 px wide on a person 110 px tall hid the overlays beneath them)
    k = max(1.0, img.shape[1] / 240.0) * mark_scale(poses.get("current"), scale=s)
    for person, kp in others:
        draw_pose(img, kp, COLORS["other"], scale=s, thickness=round(k * 1.5), radius=max(1, round(k * 2)))
        top = np.asarray(kp, np.float64)[10] * s
        if np.all(np.isfinite(top)):
            cv2.putText(img, str(person + 1), (int(top[0]) + 4, int(top[1]) - 4), cv2.FONT_HERSHEY_SIMPLEX,
                        0.35 * k, COLORS["other"], max(1, round(k)), cv2.LINE_AA)
    for key in ("gt", "detected", "noisy", "current"):
        kp = poses.get(key)
        if kp is not None:
            cur = key == "current"
            draw_pose(img, kp, COLORS[key], scale=s, thickness=round(k * (2 if cur else 1.5)),
                      radius=max(1, round(k * (3 if cur else 2))), selected=selected if cur else None)
    if crop is not None:
        text = f"zoom x{magnification:.1f}"
        org = (6, 16 + round(4 * (k - 1)))
        cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.45 * k, (255, 255, 255), max(3, round(3 * k)),
                    cv2.LINE_AA)
        cv2.putText(img, text, org, cv2.FONT_HERSHEY_SIMPLEX, 0.45 * k, (40, 40, 40), max(1, round(k)), cv2.LINE_AA)
    return img


def response_px(points: np.ndarray, *, root: np.ndarray, view: str, centre: tuple[float, float],
                scale: float) -> np.ndarray:
    """Where :func:`response_image` draws ``points`` ``(..., 3)`` mm (camera frame, OpenCV: +y down) in one of its
    views: ``(..., 2)`` px (x right, y down), the root at ``centre``, ``scale`` px per mm. **side**: depth Z to the
    right, the camera's +Y down the image as in the camera, so a person stands upright; **top**: seen from above,
    depth Z to the right, X down (not mirrored)."""
    p, r = np.asarray(points, np.float64), np.asarray(root, np.float64)
    ax = {"side": 1, "top": 0}[view]
    return np.stack([centre[0] + (p[..., 2] - r[2]) * scale, centre[1] + (p[..., ax] - r[ax]) * scale], -1)


def response_image(lifted: np.ndarray, *, root: np.ndarray, gt: np.ndarray | None = None,
                   cloud: np.ndarray | None = None, size: tuple[int, int] = (360, 150)) -> np.ndarray:
    """Two small views of the lifted pose (mm, camera frame), drawn with OpenCV: **side** (depth Z to the right,
    height -Y up) and **top** (depth Z to the right, X down), each a 2.4 m window centred on the root, with the
    distance to the camera. The 3D response in sight while the 3D view looks head-on at the image plane. Each view
    is drawn on its own (nothing crosses into the other), and a ground truth whose root lies outside a window is
    marked at its edge, in the direction of that root, with its depth offset ("GT +3.1 m"; a browser trial lost it
    at a focal far from the camera's)."""
    W, H = size
    half = W // 2
    img = np.full((H, W, 3), 250, np.uint8)
    win = 2400.0
    sc = (min(half, H) - 16) / win
    P = np.asarray(lifted, np.float64)
    r = np.asarray(root, np.float64)
    for v, (title, ax) in enumerate((("side", 1), ("top", 0))):
        x0 = v * half
        panel = np.full((H, half, 3), 250, np.uint8)
        cv2.rectangle(panel, (1, 1), (half - 2, H - 2), (200, 200, 200), 1)
        cx, cy = half / 2.0, H / 2.0 + 6

        def to_px(p: np.ndarray, ax: int = ax, cx: float = cx, cy: float = cy) -> np.ndarray:
            return response_px(p, root=r, view="side" if ax == 1 else "top", centre=(cx, cy), scale=sc)

        if cloud is not None and len(cloud):
            pts = to_px(np.asarray(cloud, np.float64))
            cols = np.broadcast_to(JOINT_RGB, pts.shape[:-1] + (3,)).reshape(-1, 3)
            uv = pts.reshape(-1, 2)
            ok = np.all(np.isfinite(uv), axis=1)
            ok[ok] = (uv[ok, 0] >= 0) & (uv[ok, 0] < half) & (uv[ok, 1] >= 0) & (uv[ok, 1] < H)
            iu = uv[ok].astype(np.int64)
            panel[iu[:, 1], iu[:, 0]] = cols[ok]
        for pose, col in ((gt, COLORS["gt"]), (P, None)):
            if pose is None:
                continue
            q = np.round(to_px(np.asarray(pose, np.float64)) * 16).astype(np.int64)
            for a, b in EDGES:
                c = col if col is not None else tuple(int(x) for x in JOINT_RGB[b])
                cv2.line(panel, tuple(q[a]), tuple(q[b]), c, 2 if col is None else 1, cv2.LINE_AA, shift=4)
        if gt is not None:
            _mark_off_window(panel, to_px(np.asarray(gt, np.float64)[0]), depth_mm=float(gt[0][2] - r[2]),
                             centre=(cx, cy))
        # (a trial read "side  camera 4.2 m <-" as cryptic: the camera is that far to the left, depth to the right)
        cv2.putText(panel, f"{title} view, camera {r[2] / 1000:.1f} m left", (5, 13), cv2.FONT_HERSHEY_SIMPLEX, 0.36,
                    (60, 60, 60), 1, cv2.LINE_AA)
        img[:, x0:x0 + half] = panel
    return img


def _mark_off_window(panel: np.ndarray, at: np.ndarray, *, depth_mm: float, centre: tuple[float, float]) -> None:
    """Where ``at`` (px) lies outside ``panel``: a ground-truth dot on the panel's edge along the line from
    ``centre`` to it, and its depth offset in m beside it."""
    H, Wp = panel.shape[:2]
    lo, hi = np.array([8.0, 22.0]), np.array([Wp - 8.0, H - 8.0])
    a = np.asarray(at, np.float64)
    if not np.all(np.isfinite(a)) or (np.all(a >= lo) and np.all(a <= hi)):
        return
    c = np.asarray(centre, np.float64)
    d = a - c
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.min(np.where(d > 0, (hi - c) / d, np.where(d < 0, (lo - c) / d, np.inf)))
    e = c + d * min(1.0, float(t))
    col = COLORS["gt"]
    cv2.circle(panel, (round(e[0]), round(e[1])), 4, col, -1, cv2.LINE_AA)
    text = f"GT {depth_mm / 1000:+.1f} m"
    (tw, th), _ = cv2.getTextSize(text, cv2.FONT_HERSHEY_SIMPLEX, 0.34, 1)
    x = int(np.clip(e[0] - tw - 7 if e[0] > Wp / 2 else e[0] + 7, 3, Wp - tw - 3))
    y = int(np.clip(e[1] + th / 2, th + 18, H - 4))
    cv2.putText(panel, text, (x, y), cv2.FONT_HERSHEY_SIMPLEX, 0.34, col, 1, cv2.LINE_AA)
