"""The cascade of the paper, image -> 2D estimator -> lifter, for one input: a photo (:func:`lift_image`) or a
keypoint JSON file (:func:`lift_keypoint_file`), and the camera each is lifted with (:func:`resolve_camera`).

Camera, in this order: a focal length / principal point the caller gives; a keypoint file's own; for photos the
EXIF focal length (:func:`lifter.detect.focal_from_exif`); else the default diagonal field of view of the image
(:data:`lifter.camera.DEFAULT_DIAGONAL_FOV_DEG`). The principal point defaults to the image centre.
Units: px and mm; camera frame OpenCV.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ._checks import PoseLifterError, as_pair
from .camera import DEFAULT_DIAGONAL_FOV_DEG
from .detect import DEFAULT_MAX_SIDE_PX, LoadedImage, PoseEstimator2D, detect_pose, guess_focal, load_image
from .io import LiftRecord, parse_keypoint_json
from .keypoints import convert


def resolve_camera(*, user_focal: np.ndarray | None, user_pp: np.ndarray | None, file_focal: np.ndarray | None,
            file_pp: np.ndarray | None, image_size: tuple[int, int] | None, exif: Any, sensor_width_mm: float | None,
            fov_deg: float, where: str) -> tuple[np.ndarray, str, np.ndarray, list[str]]:
    notes: list[str] = []
    if user_focal is not None:
        focal, src = user_focal, "user"
    elif file_focal is not None:
        focal, src = file_focal, "keypoint-file"
    elif image_size is not None:
        g = guess_focal(image_size, exif=exif, sensor_width_mm=sensor_width_mm, fov_deg=fov_deg)
        focal, src = np.array([g.focal, g.focal]), g.source
        notes.append(g.detail)
    else:
        raise PoseLifterError(f"{where}: no focal length and no image size: pass --focal, or put 'focal' or "
                              "'image_size' in the file")
    if user_pp is not None:
        pp = user_pp
    elif file_pp is not None:
        pp = file_pp
    elif image_size is not None:
        pp = np.asarray(image_size, np.float64) / 2.0
    else:
        raise PoseLifterError(f"{where}: no principal point and no image size: pass --principal-point, or put "
                              "'principal_point' or 'image_size' in the file")
    return np.asarray(focal, np.float64), src, np.asarray(pp, np.float64), notes


def _lift(lifter: Any, kp17: np.ndarray, focal: np.ndarray, pp: np.ndarray, *, flip_test: bool | None, source: str) -> Any:
    return lifter.lift(kp17, focal=focal, principal_point=pp, flip_test=flip_test, source=source)


def lift_keypoint_file(path: str | Path, *, lifter: Any, focal: Any | None = None, principal_point: Any | None = None,
                       default_format: str | None = None, fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG,
                       flip_test: bool | None = None) -> LiftRecord:
    """Lift one keypoint JSON file (module docstring)."""
    kf = parse_keypoint_json(path, default_format=default_format)
    kp17 = convert(kf.keypoints, src=kf.format)
    f, src, pp, notes = resolve_camera(user_focal=None if focal is None else as_pair(focal, name="focal", positive=True),
                                user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
                                file_focal=kf.focal, file_pp=kf.principal_point, image_size=kf.image_size, exif=None,
                                sensor_width_mm=None, fov_deg=fov_deg, where=str(path))
    res = _lift(lifter, kp17, f, pp, flip_test=flip_test, source=kf.source)
    return LiftRecord(input=str(path), kind="keypoints", keypoints_2d=kp17, absolute=res.absolute,
                      relative=res.relative, root=res.root, canonical_depth=float(res.canonical_depth),
                      focal=(float(f[0]), float(f[1])), focal_source=src, principal_point=(float(pp[0]), float(pp[1])),
                      image_size=kf.image_size, model=lifter.name, source_format=kf.format,
                      warnings=kf.warnings + tuple(notes), source=kf.source)


def lift_image(image: str | Path | LoadedImage, *, lifter: Any, estimator: PoseEstimator2D, focal: Any | None = None,
               principal_point: Any | None = None, sensor_width_mm: float | None = None,
               fov_deg: float = DEFAULT_DIAGONAL_FOV_DEG, max_side: int = DEFAULT_MAX_SIDE_PX,
               flip_test: bool | None = None) -> LiftRecord:
    """Detect the (largest) person in a photo (a path or a :class:`lifter.detect.LoadedImage`) and lift
    them (module docstring)."""
    img = image if isinstance(image, LoadedImage) else load_image(image, max_side=max_side)
    path = img.path if img.path is not None else "<image>"
    det = detect_pose(img, estimator=estimator)
    f, src, pp, notes = resolve_camera(user_focal=None if focal is None else as_pair(focal, name="focal", positive=True),
                                user_pp=None if principal_point is None else as_pair(principal_point, name="principal_point"),
                                file_focal=None, file_pp=None, image_size=img.size, exif=img.exif,
                                sensor_width_mm=sensor_width_mm, fov_deg=fov_deg, where=str(path))
    res = _lift(lifter, det.keypoints_2d, f, pp, flip_test=flip_test, source="detected")
    return LiftRecord(input=str(path), kind="image", keypoints_2d=det.keypoints_2d, absolute=res.absolute,
                      relative=res.relative, root=res.root, canonical_depth=float(res.canonical_depth),
                      focal=(float(f[0]), float(f[1])), focal_source=src, principal_point=(float(pp[0]), float(pp[1])),
                      image_size=img.size, model=lifter.name, scores=det.scores, source_format=det.raw.keypoint_format,
                      num_people=det.num_people, detector=estimator.name, warnings=det.warnings + tuple(notes))


