"""Measure the cascade image -> BlazePose -> PoseLifter on the 84 H36M demo frames.

Quick evaluation of any lifter (BlazePose detections cached after the first run)::

    python scripts/eval_cascade.py --model default            # or a shipped name, or runs/my.pt
    python scripts/eval_cascade.py --model runs/a.pt --compare runs/b.pt gt

prints MPJPE / PA-MPJPE / MRPE (mm) with each frame's true focal length and principal point, on BlazePose 2D
(told ``source="detected"``), on the SH detections and on the ground-truth 2D (told ``source="clean"``) of
the same frames. The detections of the 84 photos are cached in ``runs/cache/`` (git-ignored; H36M-derived,
never committed), keyed by the model bundle's sha256, so only the first run needs mediapipe and takes
~10 s; ``--redetect`` refreshes the cache.

The full report (``--full [--out docs/cascade/eval_cascade.json]``) also measures, with each frame's
true camera intrinsics (focal, principal point, and lens distortion, which a pinhole lifter undistorts):

* MPJPE, PA-MPJPE, MRPE (mm), per joint, for BlazePose 2D, and for reference the ground-truth 2D
  and the Stacked-Hourglass detections of the same frames; also BlazePose with the focal length
  unknown (the CLI's default 65 deg diagonal field of view instead of the true focal);
* time per image (decode, detection, conversion + lifting) on this machine;
* the keypoint-format rules (:mod:`lifter.keypoints`): pixel error of every interpolated joint
  against the ground-truth 2D (``p2d_gt``, with lens distortion), the naive mapping for comparison, a
  re-fit of the weights on the inlier frames and a cross-camera check (fit on one camera's frames,
  test on the other's). coco17 and openpose25 are measured with BlazePose's landmarks in their joint
  sets (OpenPose's Neck / MidHip = BlazePose's mid-shoulders / mid-hips): the rules' error given
  BlazePose-quality joints, not a COCO or OpenPose network's;
* the Gaussian + uniform mixture error model (:func:`lifter.noise.fit_error_model`) fitted to
  BlazePose's converted errors over the detected demo frames (and without the held-out camera's frames),
  compared with the shipped SH fit (``assets/error_model/sh_mixture.json``) and with a fit of SH's errors on
  the same frames. The fits are written only when asked (``--error-model-out``, ``--error-model-train-out``):
  the shipped ``assets/error_model/blazepose_demo*.json`` are what the default was trained with, and a re-run
  (e.g. with a changed detector) must not replace them unnoticed.

Writes the JSON and prints markdown tables for the README. Nothing from H36M (images, poses,
detections) is written: only measured numbers and fitted parameters.
"""

from __future__ import annotations

import argparse
import hashlib
import inspect
import json
import os
import sys
import time
from pathlib import Path
from typing import Any, Literal

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import lifter.detect as detect_module  # noqa: E402
import lifter.keypoints as keypoints_module  # noqa: E402
from lifter.api import Lifter  # noqa: E402
from lifter.camera import DEFAULT_DIAGONAL_FOV_DEG, focal_from_fov  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detect import ensure_pose_task, get_estimator, load_image  # noqa: E402
from lifter.keypoints import BLAZEPOSE33_JOINT_NAMES, COCO17_JOINT_NAMES, OPENPOSE25_JOINT_NAMES, convert  # noqa: E402
from lifter.metrics import joint_errors, mpjpe, pa_mpjpe, root_errors  # noqa: E402
from lifter.noise import ErrorModel, fit_error_model, mixture_loglik, normalized_errors  # noqa: E402
from lifter.skeleton import JOINT_NAMES  # noqa: E402

ASSETS_DIR = ROOT / "assets"
CACHE_DIR = ROOT / "runs" / "cache"

INLIER_MEDIAN_PX = 15.0
"""A frame is an inlier for the rule fits when the median error of its 12 limb joints is below this."""

RULE_JOINTS = ("pelvis", "r_hip", "l_hip", "spine", "thorax", "neck_nose", "head_top")
BP = {n: i for i, n in enumerate(BLAZEPOSE33_JOINT_NAMES)}
H = {n: i for i, n in enumerate(JOINT_NAMES)}
LIMBS = (
    "r_knee",
    "r_ankle",
    "l_knee",
    "l_ankle",
    "l_shoulder",
    "l_elbow",
    "l_wrist",
    "r_shoulder",
    "r_elbow",
    "r_wrist",
)


def blazepose_as(fmt: str, kp33: np.ndarray) -> np.ndarray:
    """BlazePose landmarks ``(N, 33, 2)`` in another format's joint set (coco17, openpose25)."""
    mid = lambda a, b: 0.5 * (kp33[:, BP[a]] + kp33[:, BP[b]])  # noqa: E731
    if fmt == "blazepose33":
        return kp33
    if fmt == "coco17":
        return np.stack([kp33[:, BP[n]] for n in COCO17_JOINT_NAMES], 1)
    extra = {
        "neck": mid("l_shoulder", "r_shoulder"),
        "mid_hip": mid("l_hip", "r_hip"),
        "l_big_toe": kp33[:, BP["l_foot_index"]],
        "r_big_toe": kp33[:, BP["r_foot_index"]],
        "l_small_toe": kp33[:, BP["l_foot_index"]],
        "r_small_toe": kp33[:, BP["r_foot_index"]],
    }
    return np.stack([extra[n] if n in extra else kp33[:, BP[n]] for n in OPENPOSE25_JOINT_NAMES], 1)


def naive(kp33: np.ndarray) -> dict[str, np.ndarray]:
    """The obvious mappings the rules replace: mid-hips, the detector's hips, mid-shoulders, nose,
    and for the head top the mid-ears."""
    mid = lambda a, b: 0.5 * (kp33[:, BP[a]] + kp33[:, BP[b]])  # noqa: E731
    return {
        "pelvis": mid("l_hip", "r_hip"),
        "r_hip": kp33[:, BP["r_hip"]],
        "l_hip": kp33[:, BP["l_hip"]],
        "spine": 0.5 * (mid("l_hip", "r_hip") + mid("l_shoulder", "r_shoulder")),
        "thorax": mid("l_shoulder", "r_shoulder"),
        "neck_nose": kp33[:, BP["nose"]],
        "head_top": mid("l_ear", "r_ear"),
    }


def stats(e: np.ndarray) -> dict[str, float]:
    return {"mean_px": round(float(np.mean(e)), 2), "median_px": round(float(np.median(e)), 2)}


def lsq_affine(target: np.ndarray, anchors: list[np.ndarray]) -> np.ndarray:
    """Weights ``w`` (sum 1) minimizing ``|sum_k w_k anchors_k - target|^2`` over ``(N, 2)`` points."""
    p0 = anchors[0]
    A = np.stack([(p - p0).reshape(-1) for p in anchors[1:]], 1)
    w = np.linalg.lstsq(A, (target - p0).reshape(-1), rcond=None)[0]
    return np.r_[1.0 - w.sum(), w]


def refit_weights(kp33: np.ndarray, gt: np.ndarray) -> dict[str, Any]:
    """Re-fit the shared rule weights (lifter.keypoints constants) by least squares."""
    mid = lambda a, b: 0.5 * (kp33[:, BP[a]] + kp33[:, BP[b]])  # noqa: E731
    MH, MS, ME, N = mid("l_hip", "r_hip"), mid("l_shoulder", "r_shoulder"), mid("l_ear", "r_ear"), kp33[:, BP["nose"]]
    T = MS - MH
    out: dict[str, Any] = {}
    out["PELVIS_UP"] = float(((gt[:, H["pelvis"]] - MH) * T).sum() / (T * T).sum())
    # hips, both sides together: h36m_hip = MH + a (hip - MH) + b (MS - MH)
    A = np.concatenate([np.stack([(kp33[:, BP[s]] - MH).reshape(-1), T.reshape(-1)], 1) for s in ("r_hip", "l_hip")])
    y = np.concatenate([(gt[:, H[s]] - MH).reshape(-1) for s in ("r_hip", "l_hip")])
    a, b = np.linalg.lstsq(A, y, rcond=None)[0]
    out["HIP_WIDEN"], out["hip_up (shipped: PELVIS_UP)"] = float(a), float(b)
    out["SPINE_UP"] = float(((gt[:, H["spine"]] - MH) * T).sum() / (T * T).sum())
    out["THORAX_DOWN"] = float(((gt[:, H["thorax"]] - MS) * -T).sum() / (T * T).sum())
    w = lsq_affine(gt[:, H["neck_nose"]], [MS, N, ME])
    out["NECK_NOSE_W"] = [float(w[1]), float(w[2])]
    w = lsq_affine(gt[:, H["head_top"]], [ME, N, MS])
    out["HEAD_TOP_W"] = [float(-w[1]), float(-w[2])]
    return out


def apply_weights(kp33: np.ndarray, w: dict[str, Any]) -> dict[str, np.ndarray]:
    """The rule joints ``(N, 2)`` with weights ``w`` (as returned by :func:`refit_weights`)."""
    mid = lambda a, b: 0.5 * (kp33[:, BP[a]] + kp33[:, BP[b]])  # noqa: E731
    MH, MS, ME, N = mid("l_hip", "r_hip"), mid("l_shoulder", "r_shoulder"), mid("l_ear", "r_ear"), kp33[:, BP["nose"]]
    T = MS - MH
    b = w["hip_up (shipped: PELVIS_UP)"]
    return {
        "pelvis": MH + w["PELVIS_UP"] * T,
        "r_hip": MH + w["HIP_WIDEN"] * (kp33[:, BP["r_hip"]] - MH) + b * T,
        "l_hip": MH + w["HIP_WIDEN"] * (kp33[:, BP["l_hip"]] - MH) + b * T,
        "spine": MH + w["SPINE_UP"] * T,
        "thorax": MS - w["THORAX_DOWN"] * T,
        "neck_nose": MS + w["NECK_NOSE_W"][0] * (N - MS) + w["NECK_NOSE_W"][1] * (ME - MS),
        "head_top": ME + w["HEAD_TOP_W"][0] * (ME - N) + w["HEAD_TOP_W"][1] * (ME - MS),
    }


def pose_metrics(pred_abs: np.ndarray, gt_abs: np.ndarray) -> dict[str, Any]:
    mrpe, _ = root_errors(pred_abs[:, 0], gt_abs[:, 0])
    je = joint_errors(pred_abs, gt_abs)
    return {
        "n": int(len(gt_abs)),
        "mpjpe": round(float(mpjpe(pred_abs, gt_abs).mean()), 1),
        "pa_mpjpe": round(float(pa_mpjpe(pred_abs, gt_abs).mean()), 1),
        "mrpe": round(float(mrpe.mean()), 1),
        "mrpe_median": round(float(np.median(mrpe)), 1),
        "mrpe_xyz": np.round(np.abs(pred_abs[:, 0] - gt_abs[:, 0]).mean(0), 1).tolist(),
        # mean signed root-depth error (+: placed too far): a bias the absolute errors above do not show
        "root_z_bias": round(float((pred_abs[:, 0, 2] - gt_abs[:, 0, 2]).mean()), 1),
        "per_joint_mpjpe": {n: round(float(v), 1) for n, v in zip(JOINT_NAMES, je.mean(0))},
    }


def demo_cameras(data: H36M, ann: Any) -> list[Any]:
    """Each demo photo's Human3.6M camera (:meth:`lifter.data.H36M.camera`), from its annotations' subject and
    camera."""
    return [data.camera(int(str(s).lstrip("S")), str(c)) for s, c in zip(ann["subject"], ann["camera"])]


def demo_frames(h36m_dir: Path | None) -> tuple[Path, Any, np.ndarray, np.ndarray, np.ndarray]:
    """The demo photos of the Human3.6M folder ``h36m_dir`` (None: the default): their folder, annotations and
    :func:`demo_intrinsics` (the setup the scripts measuring on these photos share)."""
    h36m = h36m_dir or default_h36m_dir()
    demo = h36m / "demo"
    ann = np.load(demo / "annotations.npz")
    return (demo, ann, *demo_intrinsics(demo_cameras(H36M(h36m), ann)))


def demo_intrinsics(cams: list[Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(focal (N, 2), principal point (N, 2), distortion (N, 5))`` px of :func:`demo_cameras`: the photos' 2D is
    seen through Human3.6M's lenses, so each camera's distortion ``(k1, k2, k3, p1, p2)`` comes with it."""
    return (np.array([c.focal for c in cams]), np.array([c.principal_point for c in cams]),
            np.array([[*c.k, *c.p] for c in cams]))


def detect_demo(
    demo: Path, images: np.ndarray, *, redetect: bool = False, cache_dir: Path = CACHE_DIR, max_people: int = 3
) -> dict[str, np.ndarray]:
    """BlazePose on the demo photos: ``kp33 (N, 33, 2)`` px of the largest person (NaN where none),
    ``scores (N, 33)``, ``people (N,)`` found, per-image ``t_load`` / ``t_det`` seconds. Cached in
    ``cache_dir`` (git-ignored runs/cache) under the model bundle's sha256 and the image list."""
    task = ensure_pose_task(log=print)
    # the cache key: model bundle, images, search settings and the code that finds and selects people (the whole
    # detector module, with its thresholds and helpers, and the keypoint formats' mirror maps)
    setting = f"|{max_people}|{inspect.getsource(detect_module)}|{inspect.getsource(keypoints_module)}"
    key = hashlib.sha256(task.read_bytes() + "\n".join(map(str, images)).encode() + setting.encode())
    cache = cache_dir / f"blazepose_demo_{key.hexdigest()[:16]}.npz"
    if cache.is_file() and not redetect:
        with np.load(cache) as z:
            print(
                "BlazePose detections from the cache "
                f"{cache.relative_to(ROOT) if cache.is_relative_to(ROOT) else cache}"
            )
            return {k: z[k] for k in z.files}
    n = len(images)
    kp33, scores = np.full((n, 33, 2), np.nan), np.full((n, 33), np.nan)
    people = np.zeros(n, int)
    t_load, t_det = np.zeros(n), np.zeros(n)
    with get_estimator("blazepose", max_people=max_people) as est:  # type: ignore[attr-defined]
        est.detect(np.zeros((64, 64, 3), np.uint8))  # warm-up (graph initialisation)
        for i, rel in enumerate(images):
            t0 = time.perf_counter()
            img = load_image(demo / str(rel))
            t1 = time.perf_counter()
            dets = est.detect(img.rgb)
            t2 = time.perf_counter()
            t_load[i], t_det[i] = t1 - t0, t2 - t1
            people[i] = len(dets)
            if dets:
                d = max(dets, key=lambda d: d.area)
                kp33[i], scores[i] = d.keypoints / img.scale, d.scores
    out = {"kp33": kp33, "scores": scores, "people": people, "t_load": t_load, "t_det": t_det}
    cache_dir.mkdir(parents=True, exist_ok=True)
    np.savez(cache, **out)
    print(f"cached the BlazePose detections in {cache}")
    return out


def quick_table(
    refs: list[str],
    det17: np.ndarray,
    ok: np.ndarray,
    sh17: np.ndarray,
    gt2d: np.ndarray,
    gt3d: np.ndarray,
    focal: np.ndarray,
    pp: np.ndarray,
    dist: np.ndarray,
    *,
    flip_test: bool | None = None,
    source: Literal["detected", "clean"] = "detected",
) -> str:
    """MPJPE / PA-MPJPE / MRPE of each lifter on BlazePose, SH and GT 2D of the detected frames (true camera);
    ``flip_test``: forced on or off for every network, or None for each model's own default; ``source``: what the
    lifters are told BlazePose's and SH's 2D is (the ground truth's is told "clean")."""
    L = [
        f"84 H36M demo photos, {int(ok.sum())} with a BlazePose detection; true focal and principal point; mm"
        + ("" if flip_test is None else f"; flip test {'on' if flip_test else 'off'} in every lifter")
        + ("" if source == "detected" else f"; BlazePose's and SH's 2D told source={source!r}"),
        "",
        "MPJPE / PA-MPJPE / MRPE (mean signed root-depth error, + = too far)",
        "",
        "| lifter | BlazePose 2D: MPJPE / PA / MRPE (Z bias) | SH 2D (same frames) | GT 2D (same frames, clean) |",
        "|---|---|---|---|",
    ]
    for ref in refs:
        lf = Lifter.load(ref)
        cells = []
        inputs: tuple[tuple[np.ndarray, Literal["detected", "clean"]], ...] = (
            (det17, source),
            (sh17[ok], source),
            (gt2d[ok], "clean"),
        )
        for kp, src in inputs:
            m = pose_metrics(lf.lift(kp, focal=focal[ok], principal_point=pp[ok], source=src, distortion=dist[ok],
                                     flip_test=flip_test).absolute, gt3d[ok])
            cells.append(f"{m['mpjpe']:.1f} / {m['pa_mpjpe']:.1f} / {m['mrpe']:.1f} ({m['root_z_bias']:+.0f})")
        L.append(f"| {ref if ref.endswith('.pt') else lf.name} | " + " | ".join(cells) + " |")
    return "\n".join(L)


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument(
        "--model", "--weights", dest="weights", default="default",
        help="shipped model name, checkpoint .pt, or A.pt+B.pt (an ensemble)",
    )
    ap.add_argument(
        "--full",
        action="store_true",
        help="the full report (JSON, timing, keypoint rules, error-model fits); default: quick table",
    )
    ap.add_argument("--redetect", action="store_true", help="run BlazePose again instead of using the cache")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "cascade" / "eval_cascade.json")
    ap.add_argument("--error-model-out", type=Path, default=None,
                    help="write the BlazePose error-model fit here (the shipped one: "
                    "assets/error_model/blazepose_demo.json); default: fitted and reported, not written")
    ap.add_argument(
        "--holdout-camera",
        default="55011271",
        help="a second error model is fitted without this camera's frames (for training a lifter), and "
        "lifters are compared on those held-out frames",
    )
    ap.add_argument(
        "--error-model-train-out", type=Path, default=None,
        help="write the fit without the held-out camera here (the shipped one, which the default's detected "
        "networks were trained with: assets/error_model/blazepose_demo_train.json); default: not written",
    )
    ap.add_argument(
        "--compare",
        nargs="*",
        default=[],
        help="more lifters (names or .pt) to compare on BlazePose 2D, all frames and held-out camera",
    )
    ap.add_argument("--flip-test", action=argparse.BooleanOptionalAction, default=None,
                    help="quick table: average each pose with its mirror image's lift in every lifter (on) or in none "
                    "(off); default: each model's own setting (on for the shipped default, off for a checkpoint "
                    "that does not say)")
    ap.add_argument("--source", choices=("detected", "clean"), default="detected",
                    help="quick table: what the lifters are told BlazePose's and SH's 2D is (default: detected)")
    ap.add_argument("--threads", type=int, default=1)
    args = ap.parse_args()
    if args.full and args.flip_test is not None:
        ap.error("--flip-test / --no-flip-test set the quick table's lifts; the --full report keeps each model's own")
    if args.full and args.source != "detected":
        ap.error("--source sets the quick table's lifts; the --full report tells detections 'detected'")
    import torch

    torch.set_num_threads(args.threads)
    h36m_dir = args.h36m or default_h36m_dir()
    demo = h36m_dir / "demo"
    ann = np.load(demo / "annotations.npz")
    data = H36M(h36m_dir)
    n_all = len(ann["image"])
    cams = demo_cameras(data, ann)
    focal, pp, dist = demo_intrinsics(cams)
    sizes = np.array([(c.width, c.height) for c in cams])
    gt2d = ann["p2d_gt"].astype(np.float64)
    gt3d = ann["p3d_cam"].astype(np.float64)

    det = detect_demo(demo, ann["image"], redetect=args.redetect)
    kp33, people, t_load, t_det = det["kp33"], det["people"], det["t_load"], det["t_det"]
    ok = people > 0
    print(f"detected a person in {ok.sum()} of {n_all} frames; several people reported in {(people > 1).sum()}")
    sh17 = convert(ann["sh_det"].astype(np.float64), src="sh16")
    if not args.full:
        print(
            quick_table(
                list(dict.fromkeys([args.weights, *args.compare])),
                convert(kp33[ok], src="blazepose33"),
                ok,
                sh17,
                gt2d,
                gt3d,
                focal,
                pp,
                dist,
                flip_test=args.flip_test,
                source=args.source,
            )
        )
        return 0

    lifter = Lifter.load(args.weights)
    print(f"lifter: {lifter.name} ({lifter!r})")
    t_lift = np.full(n_all, np.nan)
    for i in np.flatnonzero(ok):
        t3 = time.perf_counter()
        lifter.lift(convert(kp33[i], src="blazepose33"), focal=focal[i], principal_point=pp[i], distortion=dist[i])
        t_lift[i] = time.perf_counter() - t3
    timing = {
        "decode_ms": round(1e3 * float(np.median(t_load)), 1),
        "detect_ms": round(1e3 * float(np.median(t_det)), 1),
        "convert_lift_ms": round(1e3 * float(np.nanmedian(t_lift)), 1),
        "total_ms": round(1e3 * float(np.nanmedian(t_load + t_det + t_lift)), 1),
        "detect_ms_mean": round(1e3 * float(np.mean(t_det)), 1),
        "note": "medians over the 84 frames, one process, torch 1 thread, 1000 x 1000 px JPEGs, 2 shared CPU "
        "cores (training jobs running alongside); detection includes the passes that look "
        "for further people (max_people=3); decode and detect times are those of the run that "
        "filled the detection cache (--redetect to re-time)",
    }

    # ---------------------------------------------------------------- lifting metrics
    det17 = convert(kp33[ok], src="blazepose33")
    rows: dict[str, Any] = {}
    res = lifter.lift(det17, focal=focal[ok], principal_point=pp[ok], distortion=dist[ok])
    rows["BlazePose 2D, true focal"] = pose_metrics(res.absolute, gt3d[ok])
    f_def = np.array([focal_from_fov(tuple(s)) for s in sizes[ok]])[:, None].repeat(2, 1)
    res_nf = lifter.lift(det17, focal=f_def, principal_point=sizes[ok] / 2.0)
    rows[f"BlazePose 2D, default {DEFAULT_DIAGONAL_FOV_DEG:g} deg FOV, image centre"] = pose_metrics(
        res_nf.absolute, gt3d[ok]
    )
    rows["SH detections 2D (same frames), true focal"] = pose_metrics(
        lifter.lift(sh17[ok], focal=focal[ok], principal_point=pp[ok], distortion=dist[ok]).absolute, gt3d[ok]
    )
    rows["ground-truth 2D (same frames), true focal"] = pose_metrics(
        lifter.lift(gt2d[ok], focal=focal[ok], principal_point=pp[ok], source="clean",
                    distortion=dist[ok]).absolute, gt3d[ok]
    )
    rows["ground-truth 2D, all 84 frames"] = pose_metrics(
        lifter.lift(gt2d, focal=focal, principal_point=pp, source="clean", distortion=dist).absolute, gt3d
    )
    rows["SH detections 2D, all 84 frames"] = pose_metrics(
        lifter.lift(sh17, focal=focal, principal_point=pp, distortion=dist).absolute, gt3d
    )
    held = ann["camera"][ok] == args.holdout_camera
    if not held.any() or held.all():
        raise SystemExit(
            f"--holdout-camera {args.holdout_camera}: must name one of the demo cameras "
            f"{sorted(set(ann['camera'].tolist()))}, leaving frames on both sides"
        )
    comparison: dict[str, Any] = {}
    for ref in dict.fromkeys([args.weights, *args.compare]):
        lf = lifter if ref == args.weights else Lifter.load(ref)
        a = lf.lift(det17, focal=focal[ok], principal_point=pp[ok], distortion=dist[ok]).absolute
        comparison[ref if ref.endswith(".pt") else lf.name] = {
            "all detected frames": pose_metrics(a, gt3d[ok]),
            f"held-out camera {args.holdout_camera}": pose_metrics(a[held], gt3d[ok][held]),
        }
    default_fov_focal = {
        "mean_px": round(float(f_def[:, 0].mean()), 1),
        "true_mean_px": round(float(np.sqrt(focal[ok].prod(1)).mean()), 1),
    }

    # ---------------------------------------------------------------- converter rules
    k = kp33[ok]
    g = gt2d[ok]
    limb_err = np.linalg.norm(k[:, [BP[n] for n in LIMBS]] - g[:, [H[n] for n in LIMBS]], axis=-1)
    inl = np.median(limb_err, axis=1) < INLIER_MEDIAN_PX
    conv: dict[str, Any] = {
        "inlier_rule": f"median limb-joint error < {INLIER_MEDIAN_PX:g} px",
        "n_detected": int(ok.sum()),
        "n_inlier": int(inl.sum()),
        "formats": {},
    }
    nv = naive(k)
    for fmt in ("blazepose33", "coco17", "openpose25"):
        out17 = convert(blazepose_as(fmt, k), src=fmt)
        e = np.linalg.norm(out17 - g, axis=-1)
        conv["formats"][fmt] = {
            "per_joint_all": {n: stats(e[:, H[n]]) for n in JOINT_NAMES},
            "per_joint_inliers": {n: stats(e[inl, H[n]]) for n in JOINT_NAMES},
            "mean_all_joints": stats(e),
            "mean_all_joints_inliers": stats(e[inl]),
        }
    conv["naive"] = {
        n: {
            "all": stats(np.linalg.norm(nv[n] - g[:, H[n]], axis=-1)),
            "inliers": stats(np.linalg.norm(nv[n][inl] - g[inl, H[n]], axis=-1)),
        }
        for n in RULE_JOINTS
    }
    w_all = refit_weights(k[inl], g[inl])
    conv["refit_on_inliers"] = {kk: np.round(v, 3).tolist() for kk, v in w_all.items()}
    cam_ids = ann["camera"][ok]
    cross: dict[str, Any] = {}
    for c in sorted(set(cam_ids.tolist())):
        tr, te = inl & (cam_ids != c), inl & (cam_ids == c)
        if tr.sum() < 5 or te.sum() < 5:
            continue
        wc = refit_weights(k[tr], g[tr])
        pred = apply_weights(k[te], wc)
        cross[f"test camera {c} (n={int(te.sum())})"] = {
            n: stats(np.linalg.norm(pred[n] - g[te, H[n]], axis=-1)) for n in RULE_JOINTS
        }
    conv["cross_camera"] = cross

    # ---------------------------------------------------------------- error model
    sh_model = ErrorModel.load(Path(ASSETS_DIR) / "error_model" / "sh_mixture.json")
    meta = {
        "data": f"84 H36M demo frames (../shared/data/h36m/demo), {int(ok.sum())} with a detection",
        "detector": "MediaPipe BlazePose full (Tasks PoseLandmarker, models of the mediapipe 0.10.21 wheel), converted "
        "with lifter.keypoints 'blazepose33'",
        "caveat": "84 frames, 5 subjects, mostly S9 'Posing' from 2 cameras: the fit is indicative only",
    }
    bp_model = fit_error_model(
        det17,
        g,
        source="MediaPipe BlazePose detections vs distorted GT projection, 84 H36M demo frames",
        progress=False,
        meta=meta,
    )
    if args.error_model_out is not None:
        args.error_model_out.parent.mkdir(parents=True, exist_ok=True)
        bp_model.save(args.error_model_out)
    meta_train = dict(
        meta,
        data=f"the 84 H36M demo frames without camera {args.holdout_camera} "
        f"({int((~held).sum())} with a detection); held out for evaluating lifters trained on it",
    )
    bp_train = fit_error_model(
        det17[~held],
        g[~held],
        source="MediaPipe BlazePose detections vs distorted GT "
        f"projection, H36M demo frames without camera {args.holdout_camera}",
        progress=False,
        meta=meta_train,
    )
    if args.error_model_train_out is not None:
        args.error_model_train_out.parent.mkdir(parents=True, exist_ok=True)
        bp_train.save(args.error_model_train_out)
    sh_demo = fit_error_model(sh17[ok], g, progress=False)
    e_bp, _, _ = normalized_errors(det17, g, reference_scale=sh_model.reference_scale)
    e_sh, _, _ = normalized_errors(sh17[ok], g, reference_scale=sh_model.reference_scale)

    def nll(m: ErrorModel, e: np.ndarray) -> float:
        return float(
            np.mean([-mixture_loglik(e[:, j], m.gamma[j], m.mu[j], m.sigma[j], v=m.v).mean() for j in range(17)])
        )

    def summ(m: ErrorModel) -> dict[str, Any]:
        return {
            "reference_scale_px": round(m.reference_scale, 1),
            "gamma_mean": round(float(m.gamma.mean()), 3),
            "sigma_mean_px": np.round(m.sigma.mean(0), 2).tolist(),
            "mu_mean_px": np.round(m.mu.mean(0), 2).tolist(),
            "gaussian_sigma_mean_px": np.round(m.gaussian_sigma.mean(0), 2).tolist()
            if m.gaussian_sigma is not None
            else None,
            "gamma": np.round(m.gamma, 3).tolist(),
            "sigma": np.round(m.sigma, 2).tolist(),
            "n": m.n_samples,
        }

    noise = {
        "blazepose_demo": summ(bp_model),
        f"blazepose_demo_train (without camera {args.holdout_camera})": summ(bp_train),
        "sh_shipped (S1,5,6,7,8 training, 293k)": summ(sh_model),
        "sh_demo (same frames)": summ(sh_demo),
        "nll_blazepose_errors": {
            "under blazepose_demo fit (in-sample)": round(nll(bp_model, e_bp), 3),
            "under shipped SH fit": round(nll(sh_model, e_bp), 3),
        },
        "nll_sh_errors_same_frames": {
            "under shipped SH fit": round(nll(sh_model, e_sh), 3),
            "under blazepose_demo fit": round(nll(bp_model, e_sh), 3),
        },
        "raw_error_px_same_frames": {
            "blazepose": stats(np.linalg.norm(det17 - g, axis=-1)),
            "sh": stats(np.linalg.norm(sh17[ok] - g, axis=-1)),
        },
        "nll_note": "mean over joints of the mean NLL (nats per 2D error), errors rescaled to the SH reference scale",
    }

    report = {
        "lifter": {"name": lifter.name, "repr": repr(lifter)},
        "frames": n_all,
        "frames_with_detection": int(ok.sum()),
        "frames_several_people": int((people > 1).sum()),
        "frames_without_detection": [str(x) for x in ann["image"][~ok]],
        "lifting": rows,
        "comparison": comparison,
        "holdout_camera": args.holdout_camera,
        "default_fov_focal": default_fov_focal,
        "timing": timing,
        "converter": conv,
        "error_model": noise,
        "error_model_file": None if args.error_model_out is None else str(args.error_model_out),
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1))
    written = [str(x) for x in (args.out, args.error_model_out, args.error_model_train_out) if x is not None]
    print("wrote " + ", ".join(written) + ("" if len(written) == 3 else
          " (error-model fits not written: --error-model-out / --error-model-train-out)"))
    print(markdown(report))
    return 0


def markdown(r: dict[str, Any]) -> str:
    L = [
        f"Cascade on the {r['frames']} H36M demo frames (BlazePose found a person in {r['frames_with_detection']}; "
        f"lifter `{r['lifter']['name']}`; camera intrinsics of each frame unless stated):",
        "",
        "| 2D input | frames | MPJPE | PA-MPJPE | MRPE | MRPE x / y / z | Z bias (+: too far) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, m in r["lifting"].items():
        L.append(
            f"| {name} | {m['n']} | {m['mpjpe']:.1f} | {m['pa_mpjpe']:.1f} | {m['mrpe']:.1f} | "
            + " / ".join(f"{v:.0f}" for v in m["mrpe_xyz"])
            + f" | {m['root_z_bias']:+.0f} |"
        )
    L += [
        "",
        "Per joint MPJPE (mm):",
        "",
        "| joint | " + " | ".join(r["lifting"].keys()) + " |",
        "|---|" + "---|" * len(r["lifting"]),
    ]
    for j in JOINT_NAMES:
        L.append(f"| {j} | " + " | ".join(f"{m['per_joint_mpjpe'][j]:.1f}" for m in r["lifting"].values()) + " |")
    L += [
        "",
        "Lifters compared on BlazePose 2D (true focal), MPJPE / PA-MPJPE / MRPE (mm):",
        "",
        "| lifter | " + " | ".join(f"{k} (n)" for k in next(iter(r["comparison"].values()))) + " |",
        "|---|" + "---|" * len(next(iter(r["comparison"].values()))),
    ]
    for name, sets in r["comparison"].items():
        L.append(
            f"| {name} | "
            + " | ".join(f"{m['mpjpe']:.1f} / {m['pa_mpjpe']:.1f} / {m['mrpe']:.1f} ({m['n']})" for m in sets.values())
            + " |"
        )
    t = r["timing"]
    L += [
        "",
        f"Time per image (median): decode {t['decode_ms']} ms + BlazePose {t['detect_ms']} ms + convert & lift "
        f"{t['convert_lift_ms']} ms = {t['total_ms']} ms ({t['note']}).",
        "",
    ]
    c = r["converter"]
    L += [
        f"Keypoint rules, pixel error vs ground-truth 2D (mean / median px; all {c['n_detected']} detected frames | "
        f"{c['n_inlier']} inlier frames, {c['inlier_rule']}):",
        "",
        "| joint | naive mapping | blazepose33 | coco17 | openpose25 |",
        "|---|---|---|---|---|",
    ]
    for j in RULE_JOINTS:
        nv = c["naive"][j]
        cells = [
            f"{nv['all']['mean_px']:.1f} / {nv['all']['median_px']:.1f} \\| "
            f"{nv['inliers']['mean_px']:.1f} / {nv['inliers']['median_px']:.1f}"
        ]
        for fmt in ("blazepose33", "coco17", "openpose25"):
            a, b = c["formats"][fmt]["per_joint_all"][j], c["formats"][fmt]["per_joint_inliers"][j]
            cells.append(f"{a['mean_px']:.1f} / {a['median_px']:.1f} \\| {b['mean_px']:.1f} / {b['median_px']:.1f}")
        L.append(f"| {j} | " + " | ".join(cells) + " |")
    L += [
        "",
        "Cross-camera check (rule weights fitted on one camera's inlier frames, error on the other's, "
        "mean / median px):",
        "",
    ]
    for k, v in c["cross_camera"].items():
        L.append(f"- {k}: " + ", ".join(f"{j} {s['mean_px']:.1f} / {s['median_px']:.1f}" for j, s in v.items()))
    e = r["error_model"]
    L += [
        "",
        "Mixture error model (px at the fit's reference 2D scale): BlazePose on the demo frames vs Stacked Hourglass:",
        "",
        "| fit | n per joint | ref. scale px | mean gamma | mean sigma x, y px | mean single-Gaussian sigma x, y px |",
        "|---|---|---|---|---|---|",
    ]
    for name in e:
        if not isinstance(e[name], dict) or "gamma_mean" not in e[name]:
            continue
        m = e[name]
        gs = m["gaussian_sigma_mean_px"]
        L.append(
            f"| {name} | {m['n']} | {m['reference_scale_px']} | {m['gamma_mean']:.3f} | {m['sigma_mean_px'][0]:.2f}, "
            f"{m['sigma_mean_px'][1]:.2f} | {gs[0]:.2f}, {gs[1]:.2f} |"
        )
    L += [
        "",
        f"NLL of BlazePose's errors: {e['nll_blazepose_errors']}; of SH's errors on the same frames: "
        f"{e['nll_sh_errors_same_frames']} ({e['nll_note']}). Raw 2D error, same frames: "
        f"{e['raw_error_px_same_frames']}.",
    ]
    return "\n".join(L)


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    raise SystemExit(main())
