"""Where the default's root-depth bias on the demo photos comes from (README, "Photos in"): subject size, and the
2D detector's scale against the detector the network was trained on.

1. Mean signed root-depth error (% of the true depth, + = too far) of the default on Protocol 1's test frames
   (every ``--stride``-th, S9 and S11 apart, per camera): ground-truth 2D told ``source="clean"`` (the clean
   network), the same exact 2D told ``"detected"`` (the detected networks), that 2D with Gaussian noise of
   :data:`NOISE_PX` px per joint and axis (told detected), and the real SH detections.
2. How much smaller than the ground-truth 2D pose a detector's 2D pose is (median ratio of
   :func:`lifter.normalization.pose_scale`): SH on the training and test frames per camera, BlazePose on the 84 demo
   photos (detections cached by ``scripts/eval_cascade.py``; the first run needs the ``detect`` extra).
3. A diagnostic, not a shipped correction: the photos' BlazePose 2D rescaled about its centre so that its scale
   against the ground truth matches SH's on the training frames (the BlazePose ratio measured on the error-fit
   camera's 42 photos only), then lifted; all 84 photos and the 42 of the held-out camera. Beside it, the photos'
   ground-truth 2D told "clean" and "detected": how much of the photos' bias is there without the detector.
4. Subject size: per subject (training and test), the mean signed root-depth error of each network given the
   subject's exact 2D (every ``--stride``-th frame, all four cameras), beside the error a lifter that took everyone
   for the training subjects' mean size would make (``scripts/subject_size.py``). On the test subjects this shows
   how much of a larger-than-average person's size each network reads from the 2D (the rest it places too near).

    python scripts/root_bias.py [--h36m PATH] [--stride 50]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

from subject_size import TEST_SUBJECTS, TRAIN_SUBJECTS, subject_size  # noqa: E402

from lifter import Lifter  # noqa: E402
from lifter.cli._help import add_h36m_arguments  # noqa: E402
from lifter.codec import Source  # noqa: E402
from lifter.data import CAMERA_IDS, H36M, default_h36m_dir  # noqa: E402
from lifter.detections import load_sh_detections  # noqa: E402
from lifter.keypoints import convert  # noqa: E402
from lifter.metrics import mpjpe, root_errors  # noqa: E402
from lifter.normalization import pose_scale  # noqa: E402

FIT_CAMERA = "54138969"
"""The camera whose demo photos the BlazePose error model was fitted on (``eval_cascade.py --holdout-camera``)."""


NOISE_PX: tuple[float, ...] = (4.0, 8.0)
"""Gaussian 2D noise (px, per joint and axis) added to the exact 2D in the depth-bias table."""


def depth_bias_table(lifter: Lifter, data: H36M, stride: int) -> list[str]:
    s = data.load_protocol(1, "test", stride=stride)
    det, ok = load_sh_detections(s, data=data)
    gt = s.pose_3d.astype(np.float64)
    cams = np.unique(s.camera)
    lines = ["| 2D, told | " + " | ".join(f"{CAMERA_IDS[c]} S9 / S11" for c in cams) + " |",
             "|---|" + "---|" * len(cams)]
    rng = np.random.default_rng(0)
    every = np.ones(len(s), bool)
    noisy = [(f"GT 2D + {sigma:g} px white noise per joint, detected",
              s.keypoints_2d + rng.normal(0.0, sigma, s.keypoints_2d.shape), "detected", every)
             for sigma in NOISE_PX]  # (a developer trial: roots pulled nearer as 2D noise grows)
    for name, kp, src, m in (("GT 2D, clean", s.keypoints_2d, "clean", every),
                             ("GT 2D, detected", s.keypoints_2d, "detected", every), *noisy,
                             ("SH detections, detected", det, "detected", ok)):
        r = lifter.lift(np.asarray(kp[m], np.float64), focal=s.focal[m], principal_point=s.principal_point[m],
                        source=src, distortion=s.distortion[m])
        z = 100 * (r.root[:, 2] - gt[m][:, 0, 2]) / gt[m][:, 0, 2]
        cam, sub = s.camera[m], s.subject[m]
        lines.append(f"| {name} | " + " | ".join(
            f"{z[(cam == c) & (sub == 9)].mean():+.1f} % / {z[(cam == c) & (sub == 11)].mean():+.1f} %"
            for c in cams) + " |")
    return lines


def sh_scale_lines(data: H36M, stride: int) -> tuple[list[str], float]:
    lines, train_ratio = [], float("nan")
    for split in ("train", "test"):
        s = data.load_protocol(1, split, stride=stride)
        det, ok = load_sh_detections(s, data=data)
        r = pose_scale(det[ok]) / pose_scale(s.keypoints_2d[ok].astype(np.float64))
        cam = s.camera[ok]
        per_camera = ", ".join(f"{CAMERA_IDS[c]} {100 * (np.median(r[cam == c]) - 1):+.2f} %" for c in np.unique(cam))
        lines.append(f"SH / GT 2D scale, {split} frames: median {100 * (np.median(r) - 1):+.2f} %; per camera "
                     + per_camera)
        if split == "train":
            train_ratio = float(np.median(r))
    return lines, train_ratio


def size_lines(lifter: Lifter, data: H36M, stride: int) -> list[str]:
    """Section 4: per subject, its size against the training subjects' mean and the mean signed root-depth error
    (% of the true depth) of each network given its exact 2D: the clean network, the detected networks averaged
    (the default for ``source="detected"``) and each of them alone (its own flip-test default)."""
    nets: list[tuple[str, Lifter, Source]] = [("clean network", lifter, "clean"),
                                           ("detected, averaged", lifter, "detected")]
    if lifter.ensemble:  # each detected network alone (Lifter.networks: with its own flip test and training config)
        for i, m in enumerate(lifter.networks()[f"detected {k + 1}"] for k in range(1 + len(lifter.ensemble))):
            nets.append((f"detected member {i + 1} ({m.net.config.symmetry}, width {m.net.config.width})", m,
                         "detected"))
    sizes = {s: subject_size(data, s, stride=200)[0] for s in TRAIN_SUBJECTS + TEST_SUBJECTS}
    ref = float(np.mean([sizes[s] for s in TRAIN_SUBJECTS]))
    cols = TRAIN_SUBJECTS + TEST_SUBJECTS
    lines = ["| exact 2D through | " + " | ".join(f"S{s} ({'train' if s in TRAIN_SUBJECTS else 'test'})" for s in cols)
             + " |", "|---|" + "---|" * len(cols),
             "| size vs the training mean | " + " | ".join(f"{100 * (sizes[s] / ref - 1):+.1f} %" for s in cols) + " |",
             "| a lifter that took everyone for the mean size | "
             + " | ".join(f"{100 * (ref / sizes[s] - 1):+.1f} %" for s in cols) + " |"]
    samples = {s: data.load([s], stride=stride) for s in cols}
    for name, net, src in nets:
        row = []
        for s in cols:
            p = samples[s]
            r = net.lift(np.asarray(p.keypoints_2d, np.float64), focal=p.focal, principal_point=p.principal_point,
                         source=src, distortion=p.distortion)
            z = p.pose_3d[:, 0, 2].astype(np.float64)
            row.append(f"{100 * float(((r.root[:, 2] - z) / z).mean()):+.1f} %")
        lines.append(f"| {name} | " + " | ".join(row) + " |")
    return lines


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    add_h36m_arguments(ap, stride=50)
    ap.add_argument("--model", default="default", help="a shipped model name or checkpoint (default: the default)")
    args = ap.parse_args()
    import torch

    torch.set_num_threads(2)
    h36m = args.h36m or default_h36m_dir()
    data = H36M(h36m)
    lifter = Lifter.from_pretrained() if args.model == "default" else Lifter.load(args.model)
    print(f"1. mean signed root-depth error of {lifter.name!r}, % of the true depth (+ = too far), Protocol 1 test, "
          f"every {args.stride}th frame")
    print("\n".join(depth_bias_table(lifter, data, args.stride)))
    lines, sh_ratio = sh_scale_lines(data, args.stride)
    print("\n2. detector 2D pose scale against the ground truth's")
    print("\n".join(lines))

    from eval_cascade import detect_demo  # the cached BlazePose detections of the demo photos

    ann = np.load(h36m / "demo" / "annotations.npz")
    cams = [data.camera(int(str(s).lstrip("S")), str(c)) for s, c in zip(ann["subject"], ann["camera"])]
    focal = np.array([c.focal for c in cams])
    pp = np.array([c.principal_point for c in cams])
    lens = np.array([[*c.k, *c.p] for c in cams])  # (the photos' 2D is seen through H36M's lenses)
    gt2d, gt3d = ann["p2d_gt"].astype(np.float64), ann["p3d_cam"].astype(np.float64)
    det = detect_demo(h36m / "demo", ann["image"])
    ok = det["people"] > 0
    kp = convert(det["kp33"][ok], src="blazepose33")
    gt2d, gt3d, focal, pp, camera, lens = gt2d[ok], gt3d[ok], focal[ok], pp[ok], ann["camera"][ok], lens[ok]
    ratio = pose_scale(kp) / pose_scale(gt2d)
    fit = camera == FIT_CAMERA
    bp_fit = float(np.median(ratio[fit]))
    print(f"BlazePose / GT 2D scale, {ok.sum()} demo photos: median {100 * (np.median(ratio) - 1):+.2f} % "
          f"(camera {FIT_CAMERA}'s {fit.sum()}: {100 * (bp_fit - 1):+.2f} %)")
    print(f"\n3. diagnostic: BlazePose 2D rescaled by {sh_ratio / bp_fit:.4f} about its centre (SH's training ratio / "
          f"BlazePose's on camera {FIT_CAMERA}), true focal; MPJPE / MRPE mm (mean signed root-depth error)")
    for k_s in (1.0, sh_ratio / bp_fit):
        c = kp.mean(1, keepdims=True)
        r = lifter.lift(c + (kp - c) * k_s, focal=focal, principal_point=pp, distortion=lens)
        e, _ = root_errors(r.absolute[:, 0], gt3d[:, 0])
        parts = []
        for name, m in (("all", np.ones(len(kp), bool)), ("held-out camera", ~fit)):
            bias = float((r.root[m, 2] - gt3d[m, 0, 2]).mean())
            parts.append(f"{name} ({m.sum()}): {mpjpe(r.absolute[m], gt3d[m]).mean():.1f} / {e[m].mean():.1f} "
                         f"({bias:+.0f})")
        print(f"  x{k_s:.4f}: " + "; ".join(parts))
    exact: list[str] = []
    sources: tuple[Source, ...] = ("clean", "detected")
    for src in sources:
        dz = lifter.lift(gt2d, focal=focal, principal_point=pp, source=src, distortion=lens).root[:, 2] - gt3d[:, 0, 2]
        exact.append(f"told {src}: {float(dz.mean()):+.0f} mm ({100 * float((dz / gt3d[:, 0, 2]).mean()):+.1f} %)")
    print(f"  the same photos' exact 2D, mean signed root-depth error (all {len(gt2d)}): " + "; ".join(exact))
    print(f"\n4. mean signed root-depth error given each subject's exact 2D, % of the true depth (+ = too far), "
          f"every {args.stride}th frame, all cameras; subject size: RMS joint distance from the pelvis "
          "(scripts/subject_size.py)")
    print("\n".join(size_lines(lifter, data, args.stride)))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
