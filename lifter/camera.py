"""Camera geometry: world <-> camera, projection with H36M lens distortion, back-projection,
canonical depth (PoseLifter Eq. 5-6) and the geometrically correct horizontal flip.

Conventions
-----------
* Camera frame: OpenCV, +x right, +y down, +z forward. 3D in **millimetres**.
* World -> camera: ``X_cam = R @ (X_world - C) = R @ X_world + t``.
* Image coordinates in **pixels**, origin at the top-left pixel corner convention of H36M.
* ``focal`` is ``(fx, fy)`` in pixels; ``alpha = sqrt(fx * fy)`` is the single focal length used
  by the canonical depth.
* Canonical depth: ``Z_canonical = Z * F0 / alpha`` with ``F0 = 1000`` px, i.e. the root depth in
  mm *as it would be for a 1000-px focal length*. It does not depend on the focal length of the camera
  that took the picture (PoseLifter Eq. 5).
* Reference camera: :func:`to_reference_camera` maps pixels through the intrinsics to a camera of focal
  ``F0`` and principal point 0, ``(x - c) * F0 / f``. Coordinates there do not depend on the image
  resolution or the focal length: they are the viewing rays, scaled by ``F0``.

All functions are pure and batched over leading dimensions: points are ``(..., J, 2)`` or
``(..., J, 3)``; per-camera parameters broadcast against the leading dimensions.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Final, Literal, get_args, overload

import numpy as np
from numpy.typing import ArrayLike

from ._array import ArrayT
from ._array import namespace as array_namespace
from ._checks import PoseLifterError, as_pair, where_in_batch
from .skeleton import mirror

MIN_FOCAL_PX: Final[float] = 10.0
"""Smallest focal length :meth:`Lifter.lift` accepts (px). A real camera's is hundreds to thousands of pixels
(``image width / (2 tan(horizontal FOV / 2))``); a few pixels is a focal length in mm (or normalized) by mistake."""

CANONICAL_FOCAL: float = 1000.0
"""F0, the reference focal length (px) of the canonical depth and of the reference camera."""
DEFAULT_DIAGONAL_FOV_DEG: float = 65.0
"""Diagonal field of view assumed when neither the user nor the image's EXIF data give a focal length:
``f = image_diagonal / (2 tan 32.5 deg) = 0.785 * diagonal`` (a 34 mm full-frame equivalent)."""
MIN_FOV_DEG: Final[float] = 1.0
MAX_FOV_DEG: Final[float] = 150.0
"""Diagonal fields of view ``poselifter lift --fov`` takes: a long telephoto (about 2500 mm full-frame equivalent)
to beyond the widest rectilinear phone lens (about 120 deg); a pinhole camera wider than this is a fisheye."""



def _last2(x: ArrayLike, *, name: str, positive: bool = False, scalar: bool = False) -> np.ndarray:
    """A ``(..., 2)`` pair (:func:`as_pair`) expanded to broadcast against ``(..., J, 2)``."""
    return as_pair(x, name=name, positive=positive, scalar=scalar)[..., None, :]


def image_centre(image_size: ArrayLike) -> np.ndarray:
    """The centre ``(W / 2, H / 2)`` px of images of ``image_size`` ``(..., 2)`` (width, height), in this module's
    pixel convention (pixel ``i`` covers ``[i, i + 1)``, its centre at ``i + 0.5``): the principal point of an ideal
    camera, assumed when none is given."""
    return np.asarray(image_size, np.float64) / 2.0


def focal_alpha(focal: ArrayLike) -> np.ndarray:
    """``alpha = sqrt(fx * fy)`` for a scalar or ``(..., 2)`` focal length (px). Returns ``(...)``."""
    return alpha_generic(as_pair(focal, name="focal", positive=True, scalar=True))


def alpha_generic(focal: ArrayT) -> ArrayT:
    """``alpha = sqrt(fx * fy)`` px of focal lengths ``(..., 2)`` px, no validation, numpy or torch: the one
    implementation behind :func:`focal_alpha` and :mod:`lifter.codec`."""
    xp = array_namespace(focal)
    return xp.sqrt(focal[..., 0] * focal[..., 1])


MAX_PLAUSIBLE_VIEW_DEG: float = 120.0
"""A 2D pose whose box diagonal spans more than this angle of view at the focal length used is flagged. A focal
length in mm instead of px is the usual cause, and gives 140-175 deg for a person of a few hundred px; a phone's
main camera sees about 75 deg across its whole diagonal and an ultra-wide one about 120 deg, so even a person
filling an ultra-wide portrait frame (about 105 deg) stays below."""


def pose_view_deg(keypoints: ArrayLike, focal: ArrayLike) -> np.ndarray:
    """The angle of view (deg) that each 2D pose's box diagonal spans: keypoints ``(..., J, 2)`` px, focal a scalar
    or ``(..., 2)`` px. ``2 atan(diagonal / (2 alpha))``, alpha = sqrt(fx fy), as if the box were centred on the
    principal point (an off-axis box subtends a little less); returns ``(...)``."""
    k = np.asarray(keypoints, np.float64)
    diag = np.hypot(*np.moveaxis(k.max(-2) - k.min(-2), -1, 0))
    return np.degrees(2 * np.arctan(diag / (2 * focal_alpha(focal))))


def view_deg_text(view_deg: float) -> str:
    """An angle of view (deg) beyond :data:`MAX_PLAUSIBLE_VIEW_DEG` written with as many decimals (up to 3) as it
    takes to read beyond it: 120.4 is "120.4", not "120" (a teacher's caution read "spans 120° ... rarely spans more
    than 120°")."""
    v = float(view_deg)
    for digits in range(4):
        if round(v, digits) > MAX_PLAUSIBLE_VIEW_DEG:
            return f"{v:.{digits}f}"
    return f"{math.ceil(v * 1000) / 1000:.3f}"  # (within a thousandth of a degree: rounded up, as it is beyond)


def world_to_camera(points_world: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``X_cam = R @ X_world + t`` for points ``(..., J, 3)`` in mm; ``R`` is (3, 3), ``t`` is (3,)."""
    return np.einsum("ij,...j->...i", np.asarray(R, np.float64), np.asarray(points_world, np.float64)) + np.asarray(
        t, np.float64
    )


def camera_to_world(points_cam: np.ndarray, R: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Inverse of :func:`world_to_camera`: ``X_world = R^T @ (X_cam - t)``."""
    return np.einsum("ji,...j->...i", np.asarray(R, np.float64), np.asarray(points_cam, np.float64) - np.asarray(t))


def _lens_terms(xy: np.ndarray, k: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``r2 = |x|^2`` and the factor ``radial + tan`` ``(...)`` of :func:`distort`'s lens model (the one place
    that writes it; :func:`distort_jacobian` differentiates it)."""
    x, y = xy[..., 0], xy[..., 1]
    r2 = x * x + y * y
    return r2, 1.0 + k[..., 0] * r2 + k[..., 1] * r2**2 + k[..., 2] * r2**3 + p[..., 0] * y + p[..., 1] * x


def distort(xy: np.ndarray, k: ArrayLike, p: ArrayLike) -> np.ndarray:
    """Apply the H36M / Brown-Conrady lens distortion to normalized image points ``(..., 2)``.

    ``k = (k1, k2, k3)`` radial and ``p = (p1, p2)`` tangential coefficients, in the H36M form:
    ``r2 = |x|^2``, ``radial = 1 + k1 r2 + k2 r2^2 + k3 r2^3``, ``tan = p1*y + p2*x``,
    ``x_d = x * (radial + tan) + [p2, p1] * r2``.
    """
    k = np.asarray(k, np.float64)
    p = np.asarray(p, np.float64)
    r2, gain = _lens_terms(xy, k, p)
    return xy * gain[..., None] + p[..., ::-1] * r2[..., None]


def distort_jacobian(xy: np.ndarray, k: ArrayLike, p: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The derivative of :func:`distort` at normalized points ``xy`` ``(..., 2)``: ``J`` ``(..., 2, 2)`` (rows
    x_d, y_d; columns x, y), and the factor ``radial + tan`` ``(...)`` that :func:`distort` scales each point by
    (negative past the centre's mirror). ``k`` / ``p`` as in :func:`distort`."""
    k = np.asarray(k, np.float64)
    p = np.asarray(p, np.float64)
    x, y = xy[..., 0], xy[..., 1]
    k1, k2, k3, p1, p2 = k[..., 0], k[..., 1], k[..., 2], p[..., 0], p[..., 1]
    r2, gain = _lens_terms(xy, k, p)
    dr = k1 + 2.0 * k2 * r2 + 3.0 * k3 * r2**2  # d radial / d r2
    sx, sy = 2.0 * x * dr + p2, 2.0 * y * dr + p1  # d gain / dx, d gain / dy
    J = np.stack([np.stack([gain + x * sx + 2.0 * p2 * x, x * sy + 2.0 * p2 * y], axis=-1),
                  np.stack([y * sx + 2.0 * p1 * x, gain + y * sy + 2.0 * p1 * y], axis=-1)], axis=-2)
    return J, gain


MAX_DISTORTION_COEFFICIENT: float = 10.0
"""Lens-distortion coefficients must be below this in magnitude (real lenses' are well below 1)."""

UNDISTORT_MAX_ITERATIONS: int = 100
"""Most Newton steps :func:`undistort` takes; it stops as soon as every point has converged (a few steps)."""


def _radial_fold_test(k: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """For lenses ``k`` ``(..., 3)``: a test of whether the radial map ``r (1 + k1 r^2 + k2 r^4 + k3 r^6)`` rises
    over all of ``[0, sqrt(r2)]``, i.e. its derivative ``h(s) = 1 + 3 k1 s + 5 k2 s^2 + 7 k3 s^3`` (``s = r^2``)
    stays positive on ``[0, r2]``. Exact: the cubic's minimum there is at ``r2`` or at a root of
    ``h'(s) = 3 k1 + 10 k2 s + 21 k3 s^2`` inside it (found once per lens; ``h(0) = 1``)."""
    k1, k2, k3 = k[..., 0], k[..., 1], k[..., 2]

    def h(s: np.ndarray) -> np.ndarray:
        return 1.0 + s * (3.0 * k1 + s * (5.0 * k2 + s * 7.0 * k3))

    a, b, c = 21.0 * k3, 10.0 * k2, 3.0 * k1
    quadratic, linear = np.abs(a) > 1e-12, np.abs(b) > 1e-12
    disc = b * b - 4.0 * a * c
    real = ~quadratic | (disc >= 0)
    root = np.sqrt(np.maximum(disc, 0.0))
    two_a = np.where(quadratic, 2.0 * a, 1.0)
    s1 = np.where(quadratic, (-b + root) / two_a, np.where(linear, -c / np.where(linear, b, 1.0), -1.0))
    s2 = np.where(quadratic, (-b - root) / two_a, -1.0)
    # each critical point in (0, inf) with h <= 0 there bounds the interval; the others never do
    s1 = np.where(real & (s1 > 0) & (h(s1) <= 0), s1, np.inf)
    s2 = np.where(real & (s2 > 0) & (h(s2) <= 0), s2, np.inf)
    reach = np.minimum(s1, s2)

    def rises(r2: np.ndarray) -> np.ndarray:
        return (r2 < reach) & (h(r2) > 0)

    return rises


def undistort(xy_distorted: np.ndarray, k: ArrayLike, p: ArrayLike, *,
              max_iterations: int = UNDISTORT_MAX_ITERATIONS) -> np.ndarray:
    """Inverse of :func:`distort`: the normalized pinhole points ``(..., 2)`` whose distortion is ``xy_distorted``.

    Solved by Newton's method from ``x = x_d``, each step halved while it would raise that point's residual or cross
    the lens's fold, until every point's residual ``|distort(x) - x_d|`` is below 1e-12 (normalized units; 1e-9 px
    at a 1000-px focal): Human3.6M's lens in 2-3 steps within 0.9 focal lengths of the centre, 8 at 1.6; a strong
    wide-angle lens (k1 = -0.3) near a wide image's corner in 7. It finds the point on the lens's own side of its
    fold: the radial map rises from the centre out to it, and the map keeps its orientation there as at the centre
    (past the fold lie other points that the lens sends to the same pixel). ``k`` / ``p`` as in :func:`distort`,
    broadcast with the points over the leading dimensions. A point with a non-finite coordinate (a missing joint)
    comes out NaN. Raises :class:`PoseLifterError` naming the residual if a point has no such inverse to 1e-9 (a lens
    that folds before it: points far outside the image, or a wrong focal length).
    """
    xd = np.asarray(xy_distorted, np.float64)
    if xd.shape[-1:] != (2,):
        raise PoseLifterError(f"xy_distorted: expected shape (..., 2), got {xd.shape}")
    k_, p_ = np.asarray(k, np.float64), np.asarray(p, np.float64)
    try:
        lead = np.broadcast_shapes(xd.shape[:-1], k_.shape[:-1], p_.shape[:-1])
    except ValueError:
        raise PoseLifterError(f"undistort: points {xd.shape}, k {k_.shape} and p {p_.shape} do not broadcast over "
                              "their leading dimensions") from None
    xd = np.broadcast_to(xd, lead + (2,))
    k_, p_ = np.broadcast_to(k_, lead + (3,)), np.broadcast_to(p_, lead + (2,))
    missing = ~np.all(np.isfinite(xd), axis=-1, keepdims=True)
    target = np.where(missing, 0.0, xd)

    def evaluate(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The largest |component| of distort(x) - x_d, the Newton step J^-1 (distort(x) - x_d), and whether x lies
        on the lens's own side of its fold: the radial map r (1 + k1 r^2 + k2 r^4 + k3 r^6) rises all the way from
        the centre to |x| (a lens whose curve falls and rises again has a second region beyond, which the local
        tests alone would accept), the map keeps its orientation there as at the centre (both eigenvalues of the
        Jacobian J with positive real part: det > 0 and trace > 0), and it does not mirror the point through the
        centre (radial + tan > 0)."""
        F = distort(x, k_, p_) - target
        J, gain = distort_jacobian(x, k_, p_)
        (a, b), (c, d) = (J[..., 0, 0], J[..., 0, 1]), (J[..., 1, 0], J[..., 1, 1])
        det = a * d - b * c
        step = np.stack([d * F[..., 0] - b * F[..., 1], a * F[..., 1] - c * F[..., 0]], axis=-1) / det[..., None]
        res = np.max(np.abs(np.nan_to_num(F, nan=np.inf)), axis=-1)
        return res, step, (det > 0) & (a + d > 0) & (gain > 0) & rises(np.sum(x * x, axis=-1))

    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # (a point without an inverse: see below)
        rises = _radial_fold_test(k_)
        x = target.copy()
        res, step, on_side = evaluate(x)
        for _ in range(64):  # start on the lens's own side: x_d, drawn towards the centre where it is past the fold
            if np.all(on_side):
                break
            x = np.where(on_side[..., None], x, 0.5 * x)
            res, step, on_side = evaluate(x)
        for _ in range(max_iterations):
            todo = res > 1e-12
            if not np.any(todo):
                break
            step = np.where(np.isfinite(step) & todo[..., None], step, 0.0)
            t = np.ones(res.shape)
            trial = x - step
            res_t, step_t, side_t = evaluate(trial)
            taken = (res_t <= res) & side_t
            for _ in range(40):  # halve each point's step while it raises the residual or crosses the fold
                if np.all(taken):
                    break
                t = np.where(taken, t, 0.5 * t)
                trial = x - t[..., None] * step
                res_t, step_t, side_t = evaluate(trial)
                taken = (res_t <= res) & side_t
            moved = taken & (res_t < res)
            x = np.where(taken[..., None], trial, x)
            step = np.where(taken[..., None], step_t, step)
            res = np.where(taken, res_t, res)
            on_side = np.where(taken, side_t, on_side)
            if not np.any(moved):  # no point got closer: stuck
                break
    bad = ~((res <= 1e-9) & on_side)
    if np.any(bad):
        worst = float(np.max(np.where(np.isfinite(res), res, np.inf)[bad]))
        raise PoseLifterError(f"undistort: {int(bad.sum())} point(s) have no inverse through this lens (residual "
                              f"{worst:.3g} in normalized units): the lens distortion is too strong, or the points too "
                              "far from the image centre (a wrong focal length?), for the lens model to undo; "
                              "an OpenCV calibration's distCoeffs go with distortion_model=\"opencv\"; or "
                              "undistort the 2D yourself and lift it without distortion")
    return np.where(missing, np.nan, x)


def check_distortion(distortion: ArrayLike, *, lead: tuple[int, ...] = ()) -> np.ndarray:
    """Lens-distortion coefficients ``(k1, k2, k3, p1, p2)`` (:func:`distort`'s form) checked and broadcast to
    ``lead + (5,)``: numbers, finite, below :data:`MAX_DISTORTION_COEFFICIENT` in magnitude. Raises
    :class:`PoseLifterError` naming what is wrong (and the pose, for per-pose coefficients)."""
    form = ("(k1, k2, k3, p1, p2), or one row per pose (..., 5), in Human3.6M's Brown-Conrady form (OpenCV's "
            "5-value distCoeffs are (k1, k2, p1, p2, k3), another order and other tangential terms)")
    try:
        d = np.asarray(distortion, np.float64)
    except (TypeError, ValueError):
        raise PoseLifterError(f"distortion must be numbers {form}, got {str(distortion)[:80]}") from None
    # (4 or 8 values only OpenCV's distCoeffs have; a (1, n) row for one pose is cv2.calibrateCamera's)
    opencv_like = d.ndim >= 1 and (d.shape[-1] in (4, 8) or (d.ndim == 2 and d.shape[0] == 1 and not lead
                                                             and d.shape[-1] in OPENCV_DISTORTION_COUNTS))
    hint = "; OpenCV's distCoeffs? pass distortion_model=\"opencv\"" if opencv_like else ""
    if d.ndim == 0 or d.shape[-1] != 5:
        raise PoseLifterError(f"distortion must be {form}; got shape {d.shape} ({d.size} value(s)){hint}")
    try:
        return _lens_rows(d, lead, label="distortion", one="(5,)")
    except PoseLifterError as exc:
        raise PoseLifterError(f"{exc}{hint}") from None


def _lens_rows(d: np.ndarray, lead: tuple[int, ...], *, label: str, one: str) -> np.ndarray:
    """Lens coefficients ``d`` ``(..., n)`` broadcast to ``lead + (n,)``, each finite and below
    :data:`MAX_DISTORTION_COEFFICIENT` in magnitude; errors name ``label`` and ``one`` (the one-lens shape)."""
    try:
        d = np.broadcast_to(d, lead + d.shape[-1:])
    except ValueError:
        raise PoseLifterError(f"{label}: shape {d.shape} does not match the keypoints' poses {lead}: give one "
                              f"{one} for all" + (f", or one row per pose {lead + d.shape[-1:]}" if lead else
                                                  " (the keypoints are one pose)")) from None
    bad = ~np.all(np.isfinite(d) & (np.abs(d) < MAX_DISTORTION_COEFFICIENT), axis=-1)
    if np.any(bad):
        row = d[tuple(np.argwhere(bad)[0])] if bad.ndim else d
        raise PoseLifterError(f"{label}{where_in_batch(bad)}: coefficients must be finite and below "
                              f"{MAX_DISTORTION_COEFFICIENT:g} in magnitude, got {row.tolist()}")
    return d


def undistort_pixels(keypoints: np.ndarray, *, focal: ArrayLike, principal_point: ArrayLike,
                     k: ArrayLike | None = None, p: ArrayLike | None = None,
                     distortion: ArrayLike | None = None) -> np.ndarray:
    """Pixels ``(..., J, 2)`` of a camera with lens distortion ``k``, ``p`` (:func:`distort`'s form) mapped to the
    pixels an ideal pinhole camera with the same intrinsics would see; ``focal``, ``principal_point`` (px) and
    ``k`` ``(..., 3)``, ``p`` ``(..., 2)`` broadcast over the leading dimensions, as in :func:`project`. The lens may
    instead be given as ``distortion`` ``(k1, k2, k3, p1, p2)`` or ``(..., 5)`` (:func:`check_distortion`, as
    :meth:`lifter.Lifter.lift` takes it). For a projection ``project(X, k=k, p=p)`` this gives ``project(X)``.
    Joints with a non-finite coordinate (missing) come out NaN."""
    uv = np.asarray(keypoints, np.float64)
    if uv.ndim < 2 or uv.shape[-1] != 2:
        raise PoseLifterError(f"keypoints: expected shape (..., J, 2), got {uv.shape}")
    lead = uv.shape[:-2]
    if distortion is not None:
        if k is not None or p is not None:
            raise PoseLifterError("undistort_pixels: give the lens as k and p, or as distortion, not both")
        d = check_distortion(distortion, lead=lead)
    else:
        k_ = np.asarray(k, np.float64) if k is not None else None
        p_ = np.asarray(p, np.float64) if p is not None else None
        if k_ is None or p_ is None or k_.shape[-1:] != (3,) or p_.shape[-1:] != (2,):
            raise PoseLifterError(f"undistort_pixels: k must be (k1, k2, k3) and p (p1, p2), or per pose (..., 3) "
                                  f"and (..., 2); got shapes {None if k_ is None else k_.shape} and "
                                  f"{None if p_ is None else p_.shape}")
        try:
            common = np.broadcast_shapes(k_.shape[:-1], p_.shape[:-1])
        except ValueError:
            raise PoseLifterError(f"undistort_pixels: k {k_.shape} and p {p_.shape} have different leading "
                                  "shapes") from None
        d = check_distortion(np.concatenate([np.broadcast_to(k_, common + (3,)), np.broadcast_to(p_, common + (2,))],
                                            axis=-1), lead=lead)
    f = _last2(focal, name="focal", positive=True, scalar=True)
    c = _last2(principal_point, name="principal_point")
    return undistort((uv - c) / f, d[..., None, :3], d[..., None, 3:]) * f + c


DistortionModel = Literal["h36m", "opencv"]
"""The form of a lens-distortion vector: ``"h36m"``, Human3.6M's Brown-Conrady form ``(k1, k2, k3, p1, p2)``
(:func:`distort`), or ``"opencv"``, OpenCV's ``distCoeffs`` ``(k1, k2, p1, p2[, k3[, k4, k5, k6]])`` (4, 5 or 8
values, as ``cv2.calibrateCamera`` returns them; its tangential terms differ from Human3.6M's)."""

DISTORTION_MODELS: Final[tuple[str, ...]] = get_args(DistortionModel)

OPENCV_DISTORTION_COUNTS: Final[tuple[int, ...]] = (4, 5, 8)
"""How many ``distCoeffs`` an ``"opencv"`` lens may have: (k1, k2, p1, p2), with k3, and the rational model's
k4, k5, k6. (OpenCV's thin-prism and tilted-sensor terms, 12 and 14 values, are not taken.)"""

MAX_PLAUSIBLE_TANGENTIAL: Final[float] = 0.05
"""A Human3.6M-form lens whose tangential terms p1, p2 exceed this in magnitude is noted: real lenses' are about
0.001 (Human3.6M's are below 0.002; a phone's or webcam's calibration rarely above 0.01), while OpenCV's
``distCoeffs`` given in Human3.6M's order put OpenCV's k3, often 0.1-1, in p2."""

_OPENCV_FORM: Final[str] = ("(k1, k2, p1, p2), (k1, k2, p1, p2, k3) or (k1, k2, p1, p2, k3, k4, k5, k6): OpenCV's "
                            "distCoeffs, 4, 5 or 8 numbers, or one row per pose (..., n)")


def check_distortion_model(model: object) -> DistortionModel:
    """``model`` checked to be one of :data:`DISTORTION_MODELS`; raises :class:`PoseLifterError` naming them."""
    if model not in DISTORTION_MODELS:
        raise PoseLifterError(f"distortion_model must be \"h36m\" (Human3.6M's (k1, k2, k3, p1, p2), the default) or "
                              f"\"opencv\" (OpenCV's distCoeffs (k1, k2, p1, p2[, k3[, k4, k5, k6]])), got "
                              f"{str(model)[:40]!r}")
    return model  # type: ignore[return-value]


def check_lens(distortion: ArrayLike, model: DistortionModel, *, lead: tuple[int, ...] = ()) -> np.ndarray:
    """Lens coefficients in the form ``model`` checked and broadcast over ``lead``: :func:`check_distortion` for
    ``"h36m"``, :func:`check_opencv_distortion` for ``"opencv"`` (what Lifter.lift, photos and the CLI check a lens
    with; a keypoint file's reader words its errors for the file, :mod:`lifter.io`)."""
    if check_distortion_model(model) == "opencv":
        return check_opencv_distortion(distortion, lead=lead)
    return check_distortion(distortion, lead=lead)


def check_opencv_distortion(dist_coeffs: ArrayLike, *, lead: tuple[int, ...] = ()) -> np.ndarray:
    """OpenCV ``distCoeffs`` checked and broadcast to ``lead + (n,)``: n in :data:`OPENCV_DISTORTION_COUNTS`, finite,
    below :data:`MAX_DISTORTION_COEFFICIENT` in magnitude. Raises :class:`PoseLifterError` naming what is wrong."""
    try:
        d = np.asarray(dist_coeffs, np.float64)
    except (TypeError, ValueError):
        raise PoseLifterError(f"distortion (opencv) must be numbers {_OPENCV_FORM}, got "
                              f"{str(dist_coeffs)[:80]}") from None
    if d.ndim == 2 and ((d.shape[0] == 1 and not lead) or (d.shape[1] == 1 and d.shape[0] in OPENCV_DISTORTION_COUNTS)):
        # (cv2.calibrateCamera returns distCoeffs as a (1, n) row, cv2.FileStorage as (n, 1): one lens, for one pose
        # or a batch; a developer trial's (5, 1) was refused for a batch of poses alone)
        d = d.reshape(-1)
    if d.ndim == 0 or d.shape[-1] not in OPENCV_DISTORTION_COUNTS:
        raise PoseLifterError(f"distortion (opencv) must be {_OPENCV_FORM}; got shape {d.shape} ({d.size} value(s))"
                              + ("; OpenCV's thin-prism and tilted-sensor terms (12 or 14 values) are not taken: "
                                 "undistort the 2D yourself (cv2.undistortPoints with P=K) and lift it without "
                                 "distortion" if d.ndim and d.shape[-1] in (12, 14) else ""))
    return _lens_rows(d, lead, label="distortion (opencv)", one=f"({d.shape[-1]},)")


def _opencv_undistort(uv: np.ndarray, K: np.ndarray, d: np.ndarray) -> np.ndarray:
    """OpenCV's own iterative undistortion of pixels ``(N, 2)`` to the pinhole pixels of camera matrix ``K``, run to
    convergence (OpenCV 4's ``undistortPointsIter``, or 5's ``undistortPoints`` with its criteria)."""
    import cv2  # (a dependency; imported here so that importing lifter does not load it)

    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    src = np.ascontiguousarray(uv, np.float64).reshape(-1, 1, 2)
    solve = getattr(cv2, "undistortPointsIter", None)  # (OpenCV 4; 5 took the criteria into undistortPoints)
    if solve is not None:
        out = solve(src, K, d, None, K, crit)
    else:
        out = cv2.undistortPoints(src, K, d, R=None, P=K, criteria=crit)
    return np.asarray(out, np.float64).reshape(-1, 2)


def _opencv_distort(uv: np.ndarray, K: np.ndarray, d: np.ndarray) -> np.ndarray:
    """OpenCV's projection (``cv2.projectPoints``) of pinhole pixels ``(N, 2)`` of camera matrix ``K`` through lens
    ``d``: the inverse of :func:`_opencv_undistort`."""
    import cv2

    xy = (np.asarray(uv, np.float64) - K[:2, 2]) / K[[0, 1], [0, 1]]
    rays = np.concatenate([xy, np.ones((len(xy), 1))], axis=1)
    out, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, d)
    return np.asarray(out, np.float64).reshape(-1, 2)


def undistort_pixels_opencv(keypoints: ArrayLike, *, focal: ArrayLike, principal_point: ArrayLike,
                            dist_coeffs: ArrayLike) -> np.ndarray:
    """Pixels ``(..., J, 2)`` of a camera calibrated by OpenCV (camera matrix ``K`` of ``focal`` ``(fx, fy)`` and
    ``principal_point`` ``(cx, cy)``, px, and ``distCoeffs`` ``dist_coeffs``, :func:`check_opencv_distortion`) mapped
    to the pixels a pinhole camera with the same ``K`` would see, by OpenCV's own model and solver
    (``cv2.undistortPoints`` with ``P=K``), run to convergence: for ``cv2.projectPoints(X, 0, 0, K, dist_coeffs)``
    this gives the pinhole projection of ``X``. ``focal``, ``principal_point`` and the coefficients broadcast over
    the leading dimensions (one lens, or one per pose). Joints with a non-finite coordinate (missing) come out NaN.
    Raises :class:`PoseLifterError` naming the residual where OpenCV's solver does not find a point's inverse to
    1e-6 px (a lens too strong that far from the centre, or a wrong focal length)."""
    uv = np.asarray(keypoints, np.float64)
    if uv.ndim < 2 or uv.shape[-1] != 2:
        raise PoseLifterError(f"keypoints: expected shape (..., J, 2), got {uv.shape}")
    lead = uv.shape[:-2]
    d = check_opencv_distortion(dist_coeffs, lead=lead)
    f = np.broadcast_to(as_pair(focal, name="focal", positive=True, scalar=True), lead + (2,))
    c = np.broadcast_to(as_pair(principal_point, name="principal_point"), lead + (2,))
    lens = np.concatenate([f, c, d], axis=-1).reshape(-1, 4 + d.shape[-1])
    flat = uv.reshape(-1, uv.shape[-2], 2)
    out = np.full_like(flat, np.nan)
    ok = np.all(np.isfinite(flat), axis=-1)
    rows, which = np.unique(lens, axis=0, return_inverse=True)
    worst = 0.0
    for i, row in enumerate(rows):  # (one OpenCV call per distinct camera: usually one)
        K = np.array([[row[0], 0.0, row[2]], [0.0, row[1], row[3]], [0.0, 0.0, 1.0]])
        sel = (which.reshape(-1) == i)[:, None] & ok
        if not np.any(sel):
            continue
        pts = flat[sel]
        und = _opencv_undistort(pts, K, row[4:])
        back = _opencv_distort(und, K, row[4:])
        res = np.max(np.abs(np.nan_to_num(back - pts, nan=np.inf)), axis=-1)
        worst = max(worst, float(np.max(res)))
        out[sel] = und
    if worst > 1e-6:
        raise PoseLifterError(f"undistort (opencv): some points have no inverse through this lens (residual "
                              f"{worst:.3g} px): the lens distortion is too strong, or the points too far from the "
                              "image centre (a wrong focal length or principal point?), for OpenCV's solver; check "
                              "the calibration, or undistort the 2D yourself and lift it without distortion")
    return out.reshape(uv.shape)


def lens_notes(distortion: ArrayLike | None, model: DistortionModel) -> list[str]:
    """What looks wrong in a lens given in the form ``model``: a Human3.6M-form lens whose tangential terms look
    like OpenCV's k3 (:func:`tangential_notes`); none for OpenCV's form, or no lens."""
    return [] if distortion is None or model != "h36m" else tangential_notes(distortion)


def tangential_notes(distortion: ArrayLike) -> list[str]:
    """A note when a Human3.6M-form lens ``(..., 5)`` (:func:`check_distortion`) has a tangential term above
    :data:`MAX_PLAUSIBLE_TANGENTIAL` in magnitude: most likely OpenCV's ``distCoeffs`` given in Human3.6M's order.
    Empty otherwise."""
    d = np.asarray(distortion, np.float64).reshape(-1, 5)
    big = np.max(np.abs(d[:, 3:]), axis=-1) > MAX_PLAUSIBLE_TANGENTIAL
    if not np.any(big):
        return []
    row = d[int(np.argmax(big))]
    return [f"the lens's tangential terms p1, p2 = {row[3]:.3g}, {row[4]:.3g} are larger than a real lens's (below "
            f"{MAX_PLAUSIBLE_TANGENTIAL:g}; Human3.6M's about 0.001): 'distortion' is read in Human3.6M's order "
            "(k1, k2, k3, p1, p2). If these are OpenCV's distCoeffs (k1, k2, p1, p2, k3), say so: "
            "distortion_model=\"opencv\" (a keypoint file: \"distortion_model\": \"opencv\"; the CLI: "
            "--distortion-model opencv)"]


MAX_DETECTED_MISFIT: Final[float] = 0.15
"""A detected 2D pose whose lift, projected back, misses it by more than this share of its 2D size (median joint,
:func:`reprojection_misfit`) is noted as probably wrong: BlazePose on the 84 Human3.6M photos stays at or below
0.102 (median 0.034); a BlazePose person collapsed in a padded portrait frame (2D error median 250 px, MPJPE 559 mm)
is at 0.190; of the Stacked-Hourglass detections of S9 and S11, 4.2 % exceed it (their MPJPE median 99 mm, all: 58).
Measured for the default (its registry entry's ``misfit_limit``) with ``python scripts/misfit.py``."""

MAX_CLEAN_MISFIT: Final[float] = 0.13
"""The same limit for clean 2D, through the default's clean network (its registry entry's ``clean_misfit_limit``):
just above the most that the exact 2D of the training subjects reaches (0.125 over their 293,116 samples, every 5th
frame; S9 and S11: 0.088), so exact 2D of real people is not noted, and S9 and S11's with 5-px (10-px) Gaussian
noise, 2D placed by hand, in 0.01 % (0.64 %) of the poses. Joints given in another order often are: S9 and S11 with
knees and elbows swapped in 56 % of the poses, wrists and feet in 78 %, but left and right legs in 0.9 % (a mirror
image fits). Measured with ``python scripts/misfit.py`` (``docs/results/misfit.txt``)."""


def reprojection_misfit(keypoints: ArrayLike, absolute: ArrayLike, *, focal: ArrayLike,
                        principal_point: ArrayLike) -> np.ndarray:
    """How far a lifted pose's projection lies from the 2D it was lifted from, as a share of that 2D pose's size:
    the median over joints of ``|(p - mean p) - (k - mean k)|`` divided by the 2D pose's RMS radius
    (:func:`lifter.normalization.location_and_scale`), where ``p`` is the pinhole projection of ``absolute``
    ``(..., J, 3)`` mm through ``focal`` / ``principal_point`` px and ``k`` the ``keypoints`` ``(..., J, 2)`` px
    (both centred, so a root that is off along its ray does not count). Returns ``(...)``; NaN for a pose with a
    joint at Z <= 0. Undistorted 2D: give the 2D that was lifted (:attr:`lifter.LiftResult.keypoints_2d`)."""
    _last2(principal_point, name="principal_point")  # (checked; it cancels in the centring)
    f = _last2(focal, name="focal", positive=True, scalar=True)
    return _misfit(np.asarray(keypoints, np.float64), np.asarray(absolute, np.float64), f)


def _misfit(k: np.ndarray, X: np.ndarray, f: np.ndarray) -> np.ndarray:
    """:func:`reprojection_misfit` of checked arrays, ``f`` ``(..., 1, 2)`` (or broadcastable) px; the principal
    point cancels in the centring. (Lean: it runs on every lift of the default.)"""
    from .normalization import location_and_scale

    z = X[..., 2:3]
    front = np.all(z > 0, axis=(-2, -1))
    if np.all(front):
        uv = X[..., :2] / z * f
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            uv = X[..., :2] / np.where(z > 0, z, np.nan) * f
    u, scale = location_and_scale(k)
    e = (uv - uv.mean(-2, keepdims=True)) - (k - u[..., None, :])
    d = np.sqrt(np.einsum("...i,...i->...", e, e))
    J = d.shape[-1]
    med = np.partition(d, J // 2, axis=-1)[..., J // 2] if J % 2 else np.median(d, axis=-1)
    return np.where(front, med / scale, np.nan)


def project(
    points_cam: np.ndarray,
    *,
    focal: ArrayLike,
    principal_point: ArrayLike,
    k: ArrayLike | None = None,
    p: ArrayLike | None = None,
) -> np.ndarray:
    """Project camera-frame points ``(..., J, 3)`` (mm, z > 0) to pixels ``(..., J, 2)``.

    ``focal`` (px) is a scalar or a pair ``(fx, fy)``, ``principal_point`` (px) a pair ``(cx, cy)``; either may be
    batched as ``(..., 2)`` over the points' leading dimensions (refused when they would widen them: a set of
    poses projected through a batch of cameras of another shape; one pose ``(J, 3)`` goes through any batch). With
    ``k`` and ``p`` the H36M lens distortion is applied (this is how H36M's own 2D annotations are made); without
    them it is a pinhole.
    """
    X = np.asarray(points_cam, np.float64)
    if X.shape[-1] != 3 or X.ndim < 2:
        raise PoseLifterError(f"points_cam: expected shape (..., J, 3), got {X.shape}")
    lead = X.shape[:-2]
    for label, v in (("focal", focal), ("principal_point", principal_point), ("k", k), ("p", p)):
        # (a developer trial: focal[:, None] for points (N, J, 3) projected every set through every camera,
        # (N, N, J, 2), without a word; a parameter's leading axes must be the points' own, or broadcast to them)
        if v is None:
            continue
        try:
            shape = np.shape(v)
        except ValueError:  # (ragged: refused below, by name)
            continue
        if len(shape) < 1:
            continue
        own, last = shape[:-1], shape[-1:]
        try:
            fits = np.broadcast_shapes(own, lead) == lead or not lead  # (one point set through many cameras: fine)
        except ValueError:
            fits = False
        if not fits:
            raise PoseLifterError(f"{label}: leading shape {own} does not match the points' {lead} (points_cam "
                                  f"{X.shape}): give one per point set, shape {lead + last}, or one for all")
    z = X[..., 2:3]
    if np.any(z <= 0):
        raise PoseLifterError("points_cam: all points must be in front of the camera (z > 0)")
    f = _last2(focal, name="focal", positive=True, scalar=True)
    c = _last2(principal_point, name="principal_point")
    if k is None and p is None:
        return project_generic(X, f, c, per_joint=True)
    k_ = np.zeros(3) if k is None else np.asarray(k, np.float64)[..., None, :]
    p_ = np.zeros(2) if p is None else np.asarray(p, np.float64)[..., None, :]
    return distort(X[..., :2] / z, k_, p_) * f + c


def project_generic(points: ArrayT, focal: Any, principal_point: Any, *, per_joint: bool = False) -> ArrayT:
    """Pinhole projection, no validation, numpy or torch: camera-frame points ``(..., J, 3)`` (mm, z > 0) ->
    pixels ``(..., J, 2)``, ``u = X / Z * fx + cx``, ``v = Y / Z * fy + cy``. ``focal`` and ``principal_point``:
    scalars or ``(2,)``, or one per point set ``(..., 2)`` (``per_joint``: already broadcast against the points,
    ``(..., J, 2)`` or ``(2,)``). The one implementation behind :func:`project` (without lens distortion),
    :func:`turn_pixels`, the training's moves along the viewing rays and the app's drag and renders."""
    f, c = _pair(focal, points), _pair(principal_point, points)
    if not per_joint:
        f, c = f[..., None, :], c[..., None, :]
    return points[..., :2] / points[..., 2:] * f + c


def _pair(x: ArrayT, like: Any) -> ArrayT:
    """A scalar / ``(..., 2)`` focal or principal point as a ``(..., 2)`` array of ``like``'s type."""
    xp = array_namespace(like)
    # (scalars, lists and the other library's arrays take the points' type: a review found a numpy float64 focal
    # with torch points a TypeError, and a numpy (2,) focal turning float32 torch points into float64)
    foreign = not hasattr(x, "shape") or array_namespace(x) is not xp
    a = xp.asarray(x, dtype=like.dtype, device=getattr(like, "device", None)) if foreign else x
    if a.ndim == 0:
        a = xp.stack([a, a])
    return a


def to_reference_camera(keypoints: ArrayT, *, focal: Any, principal_point: Any,
                        reference_focal: float = CANONICAL_FOCAL) -> ArrayT:
    """Map pixels ``(..., J, 2)`` through the intrinsics to the reference camera: ``(x - c) * F0 / f``.

    ``focal`` ``(fx, fy)`` and ``principal_point`` px, as ``(2,)`` or ``(..., 2)`` arrays of the keypoints'
    type (numpy or torch). The result is in "pixels of a camera with focal ``F0`` and principal point 0":
    the viewing ray of each joint times ``F0``. Scaling an image together with its intrinsics, or
    re-projecting a scene with another focal length, leaves it unchanged.
    """
    f = _pair(focal, keypoints)
    c = _pair(principal_point, keypoints)
    return (keypoints - c[..., None, :]) * (reference_focal / f[..., None, :])


def backproject_generic(uv: ArrayT, depth: Any, focal: Any, principal_point: Any) -> ArrayT:
    """Pinhole back-projection, no validation, numpy or torch: pixels ``(..., 2)`` at depth ``(...)`` mm ->
    camera frame ``(..., 3)`` mm, ``X = (u - cx) Z / fx``, ``Y = (v - cy) Z / fy``. The one implementation
    behind :func:`backproject`, :func:`root_from_canonical_depth` and :mod:`lifter.codec`."""
    xp = array_namespace(uv)
    z = depth[..., None]
    xy = (uv - _pair(principal_point, uv)) / _pair(focal, uv) * z
    return xp.concat([xy, z], axis=-1)


def camera_turn(pan: ArrayT, tilt: ArrayT, roll: ArrayT | None = None) -> ArrayT:
    """Rotations ``(..., 3, 3)`` for a camera turned about its centre by ``pan`` (about its y axis, + turns it to
    the right), then ``tilt`` (about its new x axis, + turns it up), then ``roll`` (about its new optical axis,
    + turns it clockwise as seen from behind, so the image content turns counter-clockwise on screen; default 0),
    radians ``(...)`` (broadcast together), numpy or torch, in the OpenCV camera frame (+x right, +y down,
    +z forward): a point ``X`` (mm) of the old camera frame is ``R @ X`` in the turned camera's."""
    xp = array_namespace(pan)
    pan, tilt, *rest = xp.broadcast_arrays(pan, tilt, *([] if roll is None else [roll]))  # (one angle may be shared)
    cp, sp, ct, st = xp.cos(pan), xp.sin(pan), xp.cos(tilt), xp.sin(tilt)
    one, zero = xp.ones_like(pan), xp.zeros_like(pan)
    r_pan = xp.reshape(xp.stack([cp, zero, -sp, zero, one, zero, sp, zero, cp], axis=-1), (*pan.shape, 3, 3))
    r_tilt = xp.reshape(xp.stack([one, zero, zero, zero, ct, st, zero, -st, ct], axis=-1), (*pan.shape, 3, 3))
    if not rest:
        return r_tilt @ r_pan
    cr, sr = xp.cos(rest[0]), xp.sin(rest[0])
    r_roll = xp.reshape(xp.stack([cr, sr, zero, -sr, cr, zero, zero, zero, one], axis=-1), (*pan.shape, 3, 3))
    return r_roll @ r_tilt @ r_pan


def look_at_rotation(direction: ArrayT) -> ArrayT:
    """Rotations ``(..., 3, 3)`` that turn a camera about its centre to look along ``direction`` ``(..., 3)`` (any
    length, in front of the camera: z > 0), numpy or torch, OpenCV frame: a point ``X`` (mm) of the camera frame
    is ``R @ X`` in the turned camera's, and ``R @ direction`` lies on its optical axis. The smallest such turn
    (about the axis ``direction x z``), so it commutes with the mirror ``x -> -x``: the mirrored direction's
    rotation is ``M R M``, ``M = diag(-1, 1, 1)``. With ``d`` the unit direction ``(a, b, c)`` this is
    ``I + [v]x + [v]x^2 / (1 + c)``, ``v = d x z``."""
    xp = array_namespace(direction)
    d = direction / xp.sqrt(xp.sum(direction * direction, axis=-1, keepdims=True))
    a, b, c = d[..., 0], d[..., 1], d[..., 2]
    w = 1.0 / (1.0 + c)
    rows = [1 - a * a * w, -a * b * w, -a, -a * b * w, 1 - b * b * w, -b, a, b, c]
    return xp.reshape(xp.stack(rows, axis=-1), (*c.shape, 3, 3))


def turn_pixels(uv: ArrayT, rotation: Any, focal: Any, principal_point: Any) -> ArrayT:
    """Pixels ``(..., J, 2)`` of a pinhole camera as the same camera turned by ``rotation`` ``(..., 3, 3)``
    (:func:`camera_turn`) sees them: the homography ``K R K^-1``, numpy or torch. ``focal``, ``principal_point``:
    ``(fx, fy)``, ``(cx, cy)`` px or ``(..., 2)``. Exact for any 2D (a detector's too), since a turn about the
    centre keeps every viewing ray; the turn must keep the points in front of the camera."""
    xp = array_namespace(uv)
    f = _pair(focal, uv)[..., None, :]
    c = _pair(principal_point, uv)[..., None, :]
    ray = xp.concat([(uv - c) / f, xp.ones_like(uv[..., :1])], axis=-1) @ xp.matrix_transpose(rotation)
    return project_generic(ray, f, c, per_joint=True)


def backproject(uv: ArrayLike, depth: ArrayLike, *, focal: ArrayLike, principal_point: ArrayLike) -> np.ndarray:
    """Pinhole back-projection of pixels ``(..., 2)`` at depth ``(...)`` mm to camera-frame ``(..., 3)``.

    Inverse of :func:`project` without distortion: ``X = (u - cx) Z / fx``, ``Y = (v - cy) Z / fy``.
    """
    return backproject_generic(np.asarray(uv, np.float64), np.asarray(depth, np.float64),
                               as_pair(focal, name="focal", positive=True, scalar=True),
                               as_pair(principal_point, name="principal_point"))


def canonical_depth_from_depth(depth_mm: ArrayLike, *, focal: ArrayLike) -> np.ndarray:
    """PoseLifter Eq. 5: ``Z_canonical = Z * F0 / alpha`` (mm at a 1000-px focal length)."""
    return np.asarray(depth_mm, np.float64) * CANONICAL_FOCAL / focal_alpha(focal)


def depth_from_canonical_depth(canonical_depth: ArrayLike, *, focal: ArrayLike) -> np.ndarray:
    """Inverse of Eq. 5: ``Z = Z_canonical * alpha / F0`` in mm."""
    return np.asarray(canonical_depth, np.float64) * focal_alpha(focal) / CANONICAL_FOCAL


def root_from_canonical_depth(
    root_2d: ArrayLike, canonical_depth: ArrayLike, *, focal: ArrayLike, principal_point: ArrayLike
) -> np.ndarray:
    """PoseLifter Eq. 6: the absolute root ``(..., 3)`` mm from its 2D position ``(..., 2)`` px.

    ``Z = Z_canonical * alpha / F0``; X and Y back-project the 2D root through the pinhole.
    Note ``X = (u - cx) * Z_canonical / F0 * sqrt(fy/fx)``: X and Y barely depend on the focal
    length; only Z scales with it.
    """
    z = depth_from_canonical_depth(canonical_depth, focal=focal)
    return backproject(root_2d, z, focal=focal, principal_point=principal_point)


@overload
def focal_from_fov(image_size: Sequence[float], *, fov_deg: float = ...) -> float: ...
@overload
def focal_from_fov(image_size: np.ndarray, *, fov_deg: float = ...) -> float | np.ndarray: ...
def focal_from_fov(image_size: Sequence[float] | np.ndarray, *, fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG
                   ) -> float | np.ndarray:
    """The focal length (px) that gives a diagonal field of view ``fov_deg`` to an image of
    ``image_size = (W, H)`` px: ``hypot(W, H) / (2 tan(fov / 2))``. Scales with the image. A float for one
    ``(W, H)``; ``(...)`` for image sizes ``(..., 2)``."""
    if not (math.isfinite(fov_deg) and 0 < fov_deg < 180):
        raise PoseLifterError(f"field of view must be in (0, 180) degrees, got {fov_deg}")
    wh = np.asarray(image_size, np.float64)
    if wh.ndim == 0 or wh.shape[-1] != 2 or not (np.all(np.isfinite(wh)) and np.all(wh > 0)):
        shown = tuple(image_size) if wh.ndim == 1 else f"shape {wh.shape}"
        raise PoseLifterError(f"image_size must be two positive numbers (width, height) px, got {shown}")
    f = np.hypot(wh[..., 0], wh[..., 1]) / (2.0 * math.tan(math.radians(fov_deg) / 2.0))
    return float(f) if wh.ndim == 1 else f


# --------------------------------------------------------------------------------------------
# Horizontal flip
# --------------------------------------------------------------------------------------------


def flip_keypoints_2d(
    keypoints: ArrayLike, *, image_width: ArrayLike, principal_point: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Mirror a 2D pose ``(..., 17, 2)`` px about the image's vertical centre line.

    ``x -> W - x`` **and** ``cx -> W - cx``, with left/right joints swapped: :func:`lifter.skeleton.mirror`
    of the coordinates relative to the principal point, re-attached to the mirrored principal point.
    Returns the flipped keypoints and the flipped principal point ``(..., 2)``. Flipping twice is the
    identity, and it commutes with pinhole projection of the 3D pose flipped by :func:`flip_pose_3d`.
    """
    kp = np.asarray(keypoints, np.float64)
    W = np.asarray(image_width, np.float64)
    c = as_pair(principal_point, name="principal_point")
    c_out = np.stack(np.broadcast_arrays(W - c[..., 0], c[..., 1]), axis=-1)
    return mirror(kp - c[..., None, :]) + c_out[..., None, :], c_out


def flip_pose_3d(points_cam: ArrayLike) -> np.ndarray:
    """Mirror a camera-frame 3D pose ``(..., 17, 3)``: negate X and swap left/right joints
    (:func:`lifter.skeleton.mirror`)."""
    return mirror(np.asarray(points_cam, np.float64))


# --------------------------------------------------------------------------------------------
# Camera record
# --------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Camera:
    """A calibrated camera: intrinsics (px), H36M lens distortion, extrinsics (mm), image size (px)."""

    focal: tuple[float, float]
    principal_point: tuple[float, float]
    width: int
    height: int
    k: tuple[float, float, float] = (0.0, 0.0, 0.0)
    p: tuple[float, float] = (0.0, 0.0)
    R: np.ndarray = field(default_factory=lambda: np.eye(3))
    t: np.ndarray = field(default_factory=lambda: np.zeros(3))
    name: str = ""

    @property
    def alpha(self) -> float:
        """``sqrt(fx * fy)`` in px (:func:`focal_alpha`)."""
        return float(focal_alpha(self.focal))

    @property
    def distortion(self) -> tuple[float, float, float, float, float] | None:
        """The lens distortion as :meth:`lifter.Lifter.lift` takes it, ``(k1, k2, k3, p1, p2)``; None for a lens
        without distortion (an ideal pinhole)."""
        d = (*self.k, *self.p)
        return None if not any(d) else (float(d[0]), float(d[1]), float(d[2]), float(d[3]), float(d[4]))

    @property
    def centre(self) -> np.ndarray:
        """The camera centre (the projection centre) in world coordinates ``(3,)`` mm: ``-R^T t``."""
        return camera_to_world(np.zeros(3), self.R, self.t)

    def world_to_camera(self, points_world: np.ndarray) -> np.ndarray:
        return world_to_camera(points_world, self.R, self.t)

    def camera_to_world(self, points_cam: np.ndarray) -> np.ndarray:
        """Camera-frame points ``(..., 3)`` mm in world coordinates (:func:`camera_to_world`)."""
        return camera_to_world(points_cam, self.R, self.t)

    def project(self, points_cam: np.ndarray, *, distortion: bool = True) -> np.ndarray:
        """Project camera-frame mm to px, with this camera's lens distortion unless disabled."""
        if distortion:
            return project(points_cam, focal=self.focal, principal_point=self.principal_point, k=self.k, p=self.p)
        return project(points_cam, focal=self.focal, principal_point=self.principal_point)

    def undistort_pixels(self, keypoints: np.ndarray) -> np.ndarray:
        """This camera's pixels ``(..., J, 2)`` as an ideal pinhole with the same intrinsics sees them
        (:func:`undistort_pixels`): ``undistort_pixels(project(X)) == project(X, distortion=False)``."""
        return undistort_pixels(keypoints, focal=self.focal, principal_point=self.principal_point, k=self.k,
                                p=self.p)

    def flipped(self) -> Camera:
        """The mirror camera: ``cx -> W - cx`` and ``p2 -> -p2``, so that projecting a
        :func:`flip_pose_3d` pose gives exactly the :func:`flip_keypoints_2d` keypoints, with distortion."""
        return Camera(
            focal=self.focal,
            principal_point=(self.width - self.principal_point[0], self.principal_point[1]),
            width=self.width,
            height=self.height,
            k=self.k,
            p=(self.p[0], -self.p[1]),
            R=np.diag([-1.0, 1.0, 1.0]) @ np.asarray(self.R),
            t=np.diag([-1.0, 1.0, 1.0]) @ np.asarray(self.t),
            name=self.name + " (flipped)",
        )

    def scaled(self, factor: float) -> Camera:
        """The camera with focal length and principal point (and image size) scaled by ``factor`` (zoom)."""
        return Camera(
            focal=(self.focal[0] * factor, self.focal[1] * factor),
            principal_point=(self.principal_point[0] * factor, self.principal_point[1] * factor),
            width=int(round(self.width * factor)),
            height=int(round(self.height * factor)),
            k=self.k,
            p=self.p,
            R=self.R,
            t=self.t,
            name=f"{self.name} (x{factor:g})",
        )
