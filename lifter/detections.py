"""The real 2D detections shipped with the H36M data: Stacked-Hourglass keypoints (MPII-pretrained, not
fine-tuned on H36M) for every 5th frame of the training subjects and every frame of S9 and S11.

They are the "detected" inputs of training (``DataConfig.real_prob``) and of the Table 3 evaluation
(``poselifter evaluate --inputs sh``), and the data the error model is fitted to (``poselifter fit-noise``).
Pixels; converted from the detector's 16 joints with :func:`lifter.keypoints.convert`.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ._checks import PoseLifterError
from .data import CAMERA_IDS, H36M, LENSES, Lens, PoseSamples
from .keypoints import convert, get_format
from .normalization import pose_scale

SH_DETECTIONS_FILE: str = "detections2d_sh_16j_px.npz"


def detection_stride(rows: int, num_frames: int, *, key: str) -> int:
    """The frame step of a sequence's Stacked-Hourglass detections (``key``: ``"<sequence>/<camera>"``) from their
    row count: 1 when the file holds every frame (S9, S11), 5 when it holds every 5th (the training subjects; frame
    ``f``'s row is ``f // 5``). Raises :class:`PoseLifterError` for any other count."""
    if rows == num_frames:
        return 1
    if rows == -(-num_frames // 5):
        return 5
    raise PoseLifterError(f"{key}: {rows} detection rows for {num_frames} frames; expected {num_frames} or "
                          f"{-(-num_frames // 5)}")


def load_sh_detections(samples: PoseSamples, *, data: H36M | None = None, fmt: str = "sh16",
                       dst: str = "h36m17", lens: Lens = "h36m") -> tuple[np.ndarray, np.ndarray]:
    """The real Stacked-Hourglass detections of every sample of a :class:`lifter.data.PoseSamples`.

    Returns ``(keypoints (N, J_dst, 2) px float64, valid (N,) bool)``: detections converted with
    :func:`lifter.keypoints.convert` (``fmt -> dst``); ``valid`` is False (and the keypoints NaN) where
    the file has no detection for the sample (e.g. S11 "Directions" camera 54138969, or a training frame
    that is not a multiple of 5). The row of a frame is inferred per sequence and camera from the row
    count: ``frame // 5`` when the file holds every 5th frame (training subjects), ``frame`` when it
    holds every frame (S9, S11). ``data`` is the :class:`lifter.data.H36M` the samples came from. ``lens``:
    ``"h36m"`` the pixels as detected on H36M's images (with its lens distortion), ``"pinhole"`` undistorted
    (:meth:`lifter.data.PoseSamples.undistort`).
    """
    if lens not in LENSES:
        raise PoseLifterError(f"lens must be one of {list(LENSES)}, got {lens!r}")
    data = data or H36M()
    path = Path(data.root) / SH_DETECTIONS_FILE
    if not path.is_file():
        raise FileNotFoundError(f"Stacked-Hourglass detections not found: {path}")
    npz = np.load(path)
    J = get_format(dst).num_joints
    out = np.full((len(samples), J, 2), np.nan)
    valid = np.zeros(len(samples), bool)
    seq, cam, frame = samples.sequence, samples.camera, samples.frame
    starts = np.flatnonzero(np.r_[True, (seq[1:] != seq[:-1]) | (cam[1:] != cam[:-1])])
    ends = np.r_[starts[1:], len(samples)]
    for a, b in zip(starts, ends):
        name = samples.sequence_names[seq[a]]
        key = f"{name}/{CAMERA_IDS[cam[a]]}"
        if key not in npz.files:
            continue
        det = npz[key]
        stride = detection_stride(det.shape[0], data.num_frames(name), key=key)
        fr = frame[a:b]
        ok = (fr % stride == 0) & (fr // stride < det.shape[0])
        rows = np.arange(a, b)[ok]
        out[rows] = convert(det[fr[ok] // stride], src=fmt, dst=dst)
        valid[rows] = True
    if lens == "pinhole":
        out = samples.undistort(out)
    return out, valid


def match_scale(detections: np.ndarray, reference: np.ndarray) -> tuple[np.ndarray, float]:
    """Detections ``(N, J, 2)`` px rescaled about each row's 2D mean by ``1 / r``, where ``r`` is the median over
    the rows (both finite) of :func:`lifter.normalization.pose_scale` of the detection over that of
    ``reference`` ``(N, J, 2)`` px (the same samples' ground-truth 2D). Returns ``(rescaled, r)``; rows with
    NaN stay NaN.

    A detector whose 2D poses are systematically smaller than the truth (Stacked Hourglass: ``r`` about 0.976 on
    the training subjects) teaches a lifter to place detected people nearer; rescaled, the detections keep
    their shape errors and lose that one detector's size bias (``DataConfig.real_rescale``)."""
    det = np.asarray(detections, np.float64)
    ref = np.asarray(reference, np.float64)
    if det.shape != ref.shape or det.ndim != 3 or det.shape[-1] != 2:
        raise PoseLifterError(f"match_scale: detections {det.shape} and reference {ref.shape} must both be (N, J, 2)")
    ok = np.isfinite(det).all(axis=(1, 2)) & np.isfinite(ref).all(axis=(1, 2))
    if not ok.any():
        raise PoseLifterError("match_scale: no sample has both a detection and its reference 2D")
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = float(np.median(pose_scale(det[ok]) / pose_scale(ref[ok])))
    if not (np.isfinite(ratio) and ratio > 0):
        raise PoseLifterError(f"match_scale: the median scale ratio is {ratio} (reference poses of zero size?); "
                              "check that the reference is the same samples' 2D in px")
    mean = det.mean(axis=1, keepdims=True)
    return mean + (det - mean) / ratio, ratio


def with_sh_detections(samples: PoseSamples, *, data: H36M | None = None) -> tuple[Any, int]:
    """``samples`` with their 2D replaced by the real SH detections (converted to h36m17); samples without a
    detection are dropped. Returns ``(new samples, number dropped)``."""
    det, ok = load_sh_detections(samples, data=data)
    return detected_subset(samples, det, ok), int((~ok).sum())


def detected_subset(samples: PoseSamples, detections: np.ndarray, valid: np.ndarray) -> Any:
    """``samples`` where ``valid``, with their 2D replaced by ``detections`` (:func:`load_sh_detections`' pair)."""
    return samples.subset(np.flatnonzero(valid)).with_keypoints(detections[valid])


def missing_detection_note(samples: PoseSamples, valid: np.ndarray) -> str:
    """Which of ``samples`` have no SH detection (``valid (N,)``: :func:`load_sh_detections`'), in words: the
    sequences and cameras with none at all named (S11 "Directions", camera 54138969: the file has none), and the count
    of the others ("" when none is missing). A developer trial read "19 samples without a detection dropped" as frames
    missing here and there."""
    from .data import CAMERA_IDS

    ok = np.asarray(valid, bool)
    if ok.all():
        return ""
    whole, rest = [], 0
    key = samples.sequence.astype(np.int64) * len(CAMERA_IDS) + samples.camera
    for k in np.unique(key[~ok]):
        here = key == k
        if not ok[here].any():
            q, c = divmod(int(k), len(CAMERA_IDS))
            whole.append(f"{samples.sequence_names[q]} camera {CAMERA_IDS[c]} ({int(here.sum())})")
        else:
            rest += int((here & ~ok).sum())
    parts = ([f"the file has none for {', '.join(whole)}"] if whole else []) + (
        [f"{rest} more frame(s) have none"] if rest else [])
    return f"{int((~ok).sum())} samples without a detection dropped: " + "; ".join(parts)


def detection_alignment_check(data: H36M | None = None, *, subject: int = 1, offsets: Sequence[int] = range(-3, 4),
                              camera: str | None = None) -> dict[int, float]:
    """Verify that detection row ``i`` is frame ``5 i`` for a training subject: the median 2D error (px) of
    the wrists, elbows, knees and ankles (fast-moving, directly mapped joints) when the detections are
    compared with the ground truth shifted by ``offset`` frames (50 fps). The minimum should be at 0."""
    data = data or H36M()
    npz = np.load(Path(data.root) / SH_DETECTIONS_FILE)
    cam_id = camera or CAMERA_IDS[0]
    s = data.load([subject], stride=1, cameras=[cam_id])
    sh_idx, h_idx = [0, 1, 4, 5, 10, 11, 14, 15], [3, 2, 5, 6, 16, 15, 12, 13]
    errs: dict[int, list[np.ndarray]] = {o: [] for o in offsets}
    for q in np.unique(s.sequence):
        key = f"{s.sequence_names[q]}/{cam_id}"
        if key not in npz.files:
            continue
        gt = s.keypoints_2d[s.sequence == q]
        det = npz[key]
        stride = 1 if det.shape[0] == gt.shape[0] else 5
        for o in offsets:
            idx = np.arange(det.shape[0]) * stride + o
            ok = (idx >= 0) & (idx < gt.shape[0])
            errs[o].append(np.linalg.norm(det[ok][:, sh_idx] - gt[idx[ok]][:, h_idx], axis=-1).ravel())
    return {o: float(np.median(np.concatenate(v))) for o, v in errs.items()}
