"""Evaluation of a :class:`~lifter.api.Lifter` on a set of H36M samples: overall and per action.

Averages are over frames (the paper's "Avg." convention); per-action numbers are frame averages
within each action.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from tqdm.auto import tqdm

from ._checks import PoseLifterWarning, collect_output_notes, warn_user
from .analytic import analytic_root
from .api import Lifter
from .camera import camera_turn, project, turn_pixels
from .codec import Source
from .data import ACTIONS, PoseSamples
from .metrics import AUC_THRESHOLDS_MM, mpjpe, pa_mpjpe, pck, pck_curve, root_errors


@dataclass(frozen=True)
class EvalRow:
    """One row of a results table. Distances in mm; pck150 and auc as fractions."""

    label: str
    root: str  # "learned" or "analytic"
    num_samples: int
    mpjpe: float
    pa_mpjpe: float
    mrpe: float
    mrpe_x: float
    mrpe_y: float
    mrpe_z: float
    pck150: float
    auc: float
    depth_bias: float = 0.0
    """Mean signed root depth error (mm, predicted Z minus true Z): below 0, roots placed nearer than they are."""
    per_action: dict[str, dict[str, float]] = field(default_factory=dict)
    pck_curve: list[float] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Predictions:
    relative: np.ndarray  # (N, 17, 3) mm
    root: np.ndarray  # (N, 3) mm
    analytic_root: np.ndarray | None  # (N, 3) mm


def predict(lifter: Lifter, samples: PoseSamples, *, flip_test: bool | None = None, analytic: bool = False,
            batch_size: int = 8192, progress: bool = True, source: Source = "detected") -> Predictions:
    """Lift every sample (its own camera, with its lens distortion for H36M's own 2D:
    :attr:`~lifter.data.PoseSamples.input_distortion`) told ``source``; optionally also the analytic root.
    What :meth:`lifter.Lifter.lift` would warn of is warned once per kind of note (:class:`lifter.PoseLifterWarning`),
    from the first batch that had it, with how many batches did."""
    rel, root, aroot = [], [], []
    notes: dict[str, tuple[int, int, str]] = {}  # kind -> (first sample of the first batch with it, batches, text)
    n = len(samples)
    bar = tqdm(range(0, n, batch_size), disable=None if progress else True, desc=f"lifting ({lifter.name})",
               unit="batch")  # (None: no bar when stderr is not a terminal)
    for s in bar:
        sl = slice(s, min(n, s + batch_size))
        dist = samples.input_distortion
        res = lifter.lift(samples.keypoints_2d[sl], focal=samples.focal[sl],
                          principal_point=samples.principal_point[sl], flip_test=flip_test, source=source,
                          distortion=None if dist is None else dist[sl], warn=False)
        # (not the notes on single detections that the lift does not fit: an evaluation scores them all)
        collect_output_notes(notes, s, (*res.input_warnings,
                                        *(w for w in res.warnings if getattr(w, "kind", "") != "misfit")))
        rel.append(res.relative)
        root.append(res.root)
        if analytic:  # from the 2D the networks lifted (undistorted for a pinhole lifter)
            aroot.append(analytic_root(res.keypoints_2d, res.relative, focal=samples.focal[sl],
                                       principal_point=samples.principal_point[sl]))
    batches = -(-n // batch_size)
    for first, count, text in notes.values():
        where = (f"samples {first}-{min(n, first + batch_size) - 1}" if batches > 1 else "")
        more = f"; so in {count} of {batches} batches of up to {batch_size} samples" if batches > 1 else ""
        warn_user(f"{where + ': ' if where else ''}{text}{more}")
    return Predictions(np.concatenate(rel), np.concatenate(root), np.concatenate(aroot) if analytic else None)


def score(label: str, root_kind: str, rel: np.ndarray, root: np.ndarray, samples: PoseSamples) -> EvalRow:
    gt_rel = samples.relative.astype(np.float64)
    e = mpjpe(rel, gt_rel)
    pa = pa_mpjpe(rel, gt_rel)
    r, rxyz = root_errors(root, samples.root)
    p = pck(rel, gt_rel)
    curve = pck_curve(rel, gt_rel)
    per_action = {}
    for a, name in enumerate(ACTIONS):
        m = samples.action == a
        if m.any():
            per_action[name] = {"mpjpe": float(e[m].mean()), "pa_mpjpe": float(pa[m].mean()),
                                "mrpe": float(r[m].mean()), "n": int(m.sum())}
    return EvalRow(label=label, root=root_kind, num_samples=len(samples), mpjpe=float(e.mean()),
                   pa_mpjpe=float(pa.mean()), mrpe=float(r.mean()), mrpe_x=float(rxyz[:, 0].mean()),
                   mrpe_y=float(rxyz[:, 1].mean()), mrpe_z=float(rxyz[:, 2].mean()), pck150=float(p.mean()),
                   auc=float(curve.mean()), per_action=per_action, pck_curve=[float(v) for v in curve],
                   depth_bias=float(np.mean(np.asarray(root, np.float64)[:, 2] - samples.root[:, 2])))


def evaluate_lifter(lifter: Lifter, samples: PoseSamples, *, label: str | None = None, flip_test: bool | None = None,
                    analytic_root: bool = False, progress: bool = True, source: Source = "detected") -> list[EvalRow]:
    """Rows for the learned root and, optionally, the analytic weak-perspective root."""
    label = label or lifter.name
    pred = predict(lifter, samples, flip_test=flip_test, analytic=analytic_root, progress=progress, source=source)
    rows = [score(label, "learned", pred.relative, pred.root, samples)]
    if pred.analytic_root is not None:
        rows.append(score(label, "analytic", pred.relative, pred.analytic_root, samples))
    return rows


def _label_width(labels: Sequence[str]) -> int:
    """The model column's width: 28, or the longest label and a space (a researcher trial's checkpoint path, longer
    than 28 characters, pushed every number of its row out of its column)."""
    return max([28, *(len(x) + 1 for x in labels)])


def format_table(rows: Sequence[EvalRow]) -> str:
    """The results table: errors in mm, PCK150 and AUC in % (the JSON gives them as fractions)."""
    w = _label_width([r.label for r in rows])
    head = (f"{'model':<{w}} {'root':<9} {'MPJPE':>7} {'PA-MPJPE':>9} {'MRPE':>7} {'MRPE-X':>7} {'MRPE-Y':>7} "
            f"{'MRPE-Z':>7} {'Z-BIAS':>7} {'PCK150':>7} {'AUC':>6}")
    lines = ["errors in mm; Z-BIAS: the mean signed root depth error (below 0: nearer than true); PCK150 (joints "
             "within 150 mm) and AUC (over 0-150 mm) in %", head, "-" * len(head)]
    for r in rows:
        lines.append(f"{r.label:<{w}} {r.root:<9} {r.mpjpe:7.1f} {r.pa_mpjpe:9.1f} {r.mrpe:7.1f} {r.mrpe_x:7.1f} "
                     f"{r.mrpe_y:7.1f} {r.mrpe_z:7.1f} {r.depth_bias:7.1f} {100 * r.pck150:7.1f} {100 * r.auc:6.1f}")
    return "\n".join(lines)


ACTION_COLUMNS: dict[str, str] = {
    "Directions": "Direct", "Discussion": "Discus", "Eating": "Eating", "Greeting": "Greet", "Phoning": "Phone",
    "Posing": "Posing", "Purchases": "Purch", "Sitting": "Sit", "SittingDown": "SitDn", "Smoking": "Smoke",
    "Photo": "Photo", "Waiting": "Wait", "Walking": "Walk", "WalkDog": "WalkD", "WalkTogether": "WalkT"}
"""Per-action column headings (at most 6 characters, each its own: cut to 6, Sitting and SittingDown read alike)."""


def format_per_action(rows: Sequence[EvalRow], metric: str = "mpjpe") -> str:
    short = [ACTION_COLUMNS[a] for a in ACTIONS]
    names = [r.label + ("" if r.root == "learned" else " (an.)") for r in rows]
    w = _label_width(names)
    lines = [f"per-action {metric} (mm; Avg: the mean over all samples, not over the actions; "
             + ", ".join(f"{ACTION_COLUMNS[a]} = {a}" for a in ACTIONS if ACTION_COLUMNS[a] != a) + ")",
             f"{'model':<{w}} " + " ".join(f"{s:>6}" for s in short) + "    Avg"]
    for name, r in zip(names, rows):
        vals = " ".join(f"{r.per_action[a][metric]:6.1f}" if a in r.per_action else f"{'-':>6}" for a in ACTIONS)
        lines.append(f"{name:<{w}} {vals} {getattr(r, metric):6.1f}")
    return "\n".join(lines)


def virtual_camera_samples(samples: PoseSamples, *, focal_scale: float,
                           principal_shift: tuple[float, float] = (0.0, 0.0)) -> PoseSamples:
    """The test poses seen through virtual pinhole cameras: focal ``x focal_scale``, principal point shifted
    by ``principal_shift`` px. The 3D (camera frame) is unchanged; the 2D is re-projected without distortion."""
    f = samples.focal.astype(np.float64) * focal_scale
    c = samples.principal_point.astype(np.float64) + np.asarray(principal_shift, np.float64)
    kp = project(samples.pose_3d.astype(np.float64), focal=f, principal_point=c)
    return replace(samples, keypoints_2d=kp.astype(np.float32), focal=f.astype(np.float32), lens="pinhole",
                   principal_point=c.astype(np.float32),
                   image_size=np.round(samples.image_size * focal_scale).astype(np.int32))


def turned_camera_samples(samples: PoseSamples, *, pan_deg: ArrayLike, tilt_deg: ArrayLike,
                          roll_deg: ArrayLike = 0.0) -> PoseSamples:
    """The samples as their cameras turned about their centres would see them (:func:`lifter.camera.camera_turn`:
    + pan to the right, + tilt up, + roll clockwise seen from behind the camera, degrees; one turn for all, or one
    per sample ``(N,)``): the 3D (camera frame,
    mm) turned, and the 2D, ground truth or a detector's, undistorted where it is H36M's own
    (:meth:`PoseSamples.undistort`) and moved by the homography ``K R K^-1`` (:func:`lifter.camera.turn_pixels`),
    so pinhole 2D with the same intrinsics. Another camera pose than the training cameras' (their height and
    tilt), with the same people and the same 2D errors."""
    pan, tilt, roll = (np.broadcast_to(np.deg2rad(np.asarray(a, np.float64)), (len(samples),))
                       for a in (pan_deg, tilt_deg, roll_deg))
    r = camera_turn(pan, tilt, roll)  # (N, 3, 3)
    kp = samples.keypoints_2d.astype(np.float64)
    if samples.lens == "h36m" and samples.distortion is not None:
        kp = samples.undistort(kp)
    kp = turn_pixels(kp, r, samples.focal.astype(np.float64), samples.principal_point.astype(np.float64))
    turned = samples.pose_3d.astype(np.float64) @ np.swapaxes(r, -1, -2)
    return replace(samples, keypoints_2d=kp.astype(np.float32), lens="pinhole", pose_3d=turned.astype(np.float32))


def focal_sweep(lifter: Lifter, samples: PoseSamples, *, factors: Sequence[float],
                principal_shift: tuple[float, float] = (0.0, 0.0), flip_test: bool | None = None,
                source: Source = "clean") -> list[EvalRow]:
    """One row per focal factor (label ``"x<factor>"``) for virtual cameras of :func:`virtual_camera_samples`."""
    rows = []
    for k in factors:
        vs = virtual_camera_samples(samples, focal_scale=k, principal_shift=principal_shift)
        with warnings.catch_warnings(record=True) as said:  # (each note then says which factor it is about)
            warnings.simplefilter("always", PoseLifterWarning)
            rows.append(evaluate_lifter(lifter, vs, label=f"x{k:g}", flip_test=flip_test, progress=False,
                                        source=source)[0])
        for w in said:
            if issubclass(w.category, PoseLifterWarning):
                warn_user(f"focal x{k:g}: {w.message}")
            else:
                warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    return rows


def format_focal_table(sweep: dict[str, list[EvalRow]], *, principal_shift: tuple[float, float] = (0.0, 0.0)) -> str:
    """MRPE (mm) per model and focal factor, with the ratio to the x1 factor."""
    first = next(iter(sweep.values()))
    w = _label_width(list(sweep))
    head = f"{'model':<{w}} " + " ".join(f"{r.label:>15}" for r in first)
    lines = ["MRPE (mm) and ratio to x1 on virtual cameras (focal x factor, principal point shifted by "
             f"{principal_shift} px)", head, "-" * len(head)]
    for label, rows in sweep.items():
        ref = next((r.mrpe for r in rows if r.label == "x1"), None)
        cells = [f"{r.mrpe:7.1f} ({r.mrpe / ref:4.2f})" if ref else f"{r.mrpe:15.1f}" for r in rows]
        lines.append(f"{label:<{w}} " + " ".join(f"{c:>15}" for c in cells))
    return "\n".join(lines)


__all__ = ["virtual_camera_samples", "turned_camera_samples",
           "focal_sweep", "format_focal_table", "EvalRow", "Predictions", "predict", "score",
           "evaluate_lifter", "format_table", "format_per_action", "AUC_THRESHOLDS_MM"]
