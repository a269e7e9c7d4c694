"""``poselifter lift`` on video, measured on clips assembled from real H36M frames, detector included.

    python benchmarks/bench_video.py [--model blazepose] [--json out.json]

The 80 S9 "Posing 1" demo frames (two cameras, every 50th frame) become two clips, one per camera, written at
run time into the git-ignored ``runs/cache/clips/`` (MJPG .avi, H36M-derived, never committed) at their true
spacing: 1 frame/s. Each clip goes through :func:`lifter.video.lift_video` (BlazePose, tracking, One-Euro filter,
the camera's true focal length and principal point; one BLAS thread, as ``poselifter lift``) with smoothing off
(0) and on (1), and the same frames are
lifted one image at a time (:func:`lifter.pipeline.lift_image` on the original JPEGs) for comparison. Reported:
per-frame MPJPE (root-aligned) and MRPE (mm) over the frames where the person was found, the acceleration
error (mm/frame^2) of the root and of the root-relative joints, and the time per frame: the whole of
``lift_video`` (decode, detection, lifting, tracking) divided by the frames. At 1 frame/s every frame gets a full
search (the tracker's crop search runs between full searches every 0.5 s), so the clips are also written
labelled 25 frame/s to time the tracking path against a full search of every frame. These clips test the
pipeline and its speed; the filter on real detector jitter at 50 fps is measured by
``benchmarks/bench_video_sh.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from lifter import Lifter  # noqa: E402
from lifter.data import H36M, default_h36m_dir  # noqa: E402
from lifter.detect import BlazePoseEstimator, load_image  # noqa: E402
from lifter.pipeline import lift_image  # noqa: E402
from lifter.video import lift_video, limit_blas_threads  # noqa: E402

FPS = 1.0  # every 50th frame of a 50-fps sequence


def build_clips(demo: Path, ann: Any, out: Path, fps: float = FPS) -> list[tuple[Path, list[int]]]:
    import cv2

    out.mkdir(parents=True, exist_ok=True)
    clips = []
    for cam in sorted(set(ann["camera"].tolist())):
        idx = sorted((i for i in range(len(ann["image"])) if ann["subject"][i] == "S9" and ann["camera"][i] == cam),
                     key=lambda i: int(ann["frame"][i]))
        if len(idx) < 10:
            continue
        path = out / f"S9_Posing_1_{cam}_{fps:g}fps.avi"
        if not path.is_file():
            frames = [cv2.imread(str(demo / str(ann["image"][i]))) for i in idx]
            if any(f is None for f in frames):
                raise SystemExit(f"cannot read the demo frames of camera {cam}")
            h, w = frames[0].shape[:2]  # type: ignore[union-attr]
            vw = cv2.VideoWriter(str(path), cv2.VideoWriter.fourcc(*"MJPG"), fps, (w, h))
            for f in frames:
                vw.write(f)  # type: ignore[arg-type]
            vw.release()
        clips.append((path, idx))
    return clips


def accel(x: np.ndarray) -> np.ndarray:
    return x[2:] - 2 * x[1:-1] + x[:-2]


def metrics(root: np.ndarray, rel: np.ndarray, gt: np.ndarray) -> dict[str, float]:
    """Per-frame errors over frames with a pose (NaN rows = not found); acceleration over runs of found frames."""
    ok = ~np.isnan(root[:, 0])
    gt_rel = gt - gt[:, :1]
    run = ok[2:] & ok[1:-1] & ok[:-2]
    return {"frames_found": int(ok.sum()), "frames": len(ok),
            "mpjpe": float(np.linalg.norm(rel[ok] - gt_rel[ok], axis=-1).mean()),
            "mrpe": float(np.linalg.norm(root[ok] - gt[ok, 0], axis=-1).mean()),
            "accel_root": float(np.linalg.norm(accel(root) - accel(gt[:, 0]), axis=-1)[run].mean()),
            "accel_joints": float(np.linalg.norm(accel(rel) - accel(gt_rel), axis=-1).mean(-1)[run].mean())}


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--model", default="blazepose")
    ap.add_argument("--json", type=Path, default=None)
    ap.add_argument("--detector-flip-test", action=argparse.BooleanOptionalAction, default=True,
                    help="BlazePose's flip test in full and crop searches (the default; off: one pass each)")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(1)
    h36m = default_h36m_dir()
    demo = h36m / "demo"
    ann = np.load(demo / "annotations.npz")
    data = H36M(h36m)
    lifter = Lifter.load(args.model)
    clips = build_clips(demo, ann, ROOT / "runs" / "cache" / "clips")
    fast = dict(build_clips(demo, ann, ROOT / "runs" / "cache" / "clips", fps=25.0))
    report: dict[str, Any] = {"model": lifter.name, "detector_flip_test": args.detector_flip_test, "fps": FPS,
                              "cpu_count": os.cpu_count(),
                              "load_average": os.getloadavg(), "clips": {}}
    with BlazePoseEstimator(max_people=3, flip_test=args.detector_flip_test) as est:
        est.detect(np.zeros((64, 64, 3), np.uint8))
        for path, idx in clips:
            cam = data.camera(9, str(ann["camera"][idx[0]]))
            f, pp = np.asarray(cam.focal), np.asarray(cam.principal_point)
            gt = ann["p3d_cam"][idx].astype(np.float64)
            gt2 = ann["p2d_gt"][idx]
            rows: dict[str, Any] = {}
            # one image at a time
            root, rel = np.full((len(idx), 3), np.nan), np.full((len(idx), 17, 3), np.nan)
            t0 = time.perf_counter()
            blas = limit_blas_threads(1)  # as poselifter lift does
            blas.__enter__()
            for n, i in enumerate(idx):
                try:
                    rec = lift_image(load_image(demo / str(ann["image"][i])), lifter=lifter, estimator=est, focal=f,
                                     principal_point=pp)
                except Exception:  # noqa: BLE001 -- nobody found
                    continue
                if np.linalg.norm(rec.keypoints_2d[0] - gt2[n, 0]) <= 40:
                    root[n], rel[n] = rec.root, rec.relative
            blas.__exit__(None, None, None)
            rows["per image (lift_image)"] = dict(metrics(root, rel, gt),
                                                  ms_per_frame=1e3 * (time.perf_counter() - t0) / len(idx))
            fast_path = next(p for p, ii in fast.items() if ii == idx)
            runs: tuple[tuple[str, Path, dict[str, Any]], ...] = (
                    ("video, smoothing 0", path, {"smoothing": 0.0}),
                    ("video, smoothing 1", path, {"smoothing": 1.0}),
                    ("same frames labelled 25 frame/s: crop tracking, full search every 0.5 s", fast_path,
                     {"smoothing": 1.0}),
                    ("same frames labelled 25 frame/s: full search every frame", fast_path,
                     {"smoothing": 1.0, "search_every_s": 0.0}))
            for label, clip, kw in runs:
                t0 = time.perf_counter()
                vrec = lift_video(clip, lifter=lifter, estimator=est, focal=f, principal_point=pp, **kw)
                dt = time.perf_counter() - t0
                root, rel = np.full((len(idx), 3), np.nan), np.full((len(idx), 17, 3), np.nan)
                for fr in vrec.frames:
                    near = [p for p in fr.people if np.linalg.norm(p.keypoints_2d[0] - gt2[fr.index, 0]) <= 40]
                    if near:
                        root[fr.index], rel[fr.index] = near[0].root, near[0].relative
                rows[label] = dict(metrics(root, rel, gt), ms_per_frame=1e3 * dt / len(idx),
                                   tracks=len(vrec.tracks()))
            report["clips"][path.name] = rows
            print(f"{path.name}: {len(idx)} frames at {FPS:g} frame/s, lifter {lifter.name}, detector flip test "
                  f"{'on' if args.detector_flip_test else 'off'}")
            print("| run | frames found | MPJPE | MRPE | accel. error root | accel. error joints | ms/frame |")
            print("|---|---|---|---|---|---|---|")
            for k, m in rows.items():
                print(f"| {k} | {m['frames_found']}/{m['frames']} | {m['mpjpe']:.1f} | {m['mrpe']:.1f} | "
                      f"{m['accel_root']:.1f} | {m['accel_joints']:.1f} | {m['ms_per_frame']:.0f} |")
    print(f"load average during the run: {os.getloadavg()}")
    if args.json is not None:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
