"""A what-if for the photos line of issue 11 (MRPE <= 160 mm): the root of detector 2D taken partly from the clean
network, by how well the two networks agree. Not shipped: the training subjects' detections, the only data a width
could be chosen on, do not favour it (docs/results/root_agreement.txt).

    python scripts/root_agreement.py [--stride 50] [--model default] [--out docs/results/root_agreement.txt]

The default lifts detector 2D with its detected networks, whose root leans on the training subjects' size (S9, 5 %
larger, is placed too near: "Known limits"); its clean network leans on it less but is not robust to a noisy
detector (``docs/results/source_clean_detections.txt``). Where the two roots agree, the 2D is likely precise. The
root here is ``(1 - w) * detected + w * clean`` with ``w = exp(-(dz / tau)^2)``, ``dz`` the two roots' depth
difference over the detected root's depth, for a few ``tau``; camera frame, mm. Measured on the real SH detections
of S9 and S11 (Protocol 1, every ``stride``-th frame, each camera's intrinsics and lens), on those of the training
subjects (which the detected networks were trained on, partly), and on the 84 demo photos through BlazePose
(``scripts/eval_cascade.py``'s cached detections, true intrinsics): MRPE (mm) and mean signed
root-depth error. The pose (root-relative) is the detected networks' and does not change.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import eval_cascade as cascade  # noqa: E402  (scripts/eval_cascade.py)
from _report import emit  # noqa: E402  (scripts/_report.py)

from lifter import Lifter  # noqa: E402
from lifter.data import H36M, PoseSamples, default_h36m_dir  # noqa: E402
from lifter.detections import with_sh_detections  # noqa: E402
from lifter.keypoints import convert  # noqa: E402

TAUS = (0.02, 0.03, 0.05, 0.08, 0.12)
TRAINING = (1, 5, 6, 7, 8)


def _sh_samples(data: H36M, stride: int, subjects: tuple[int, ...]) -> dict[str, PoseSamples]:
    """Per subject, its samples (every ``stride``-th frame, each camera) with the real SH detections as their 2D
    (:func:`lifter.detections.with_sh_detections`; a stride that is a multiple of 5 for the training subjects)."""
    sh, _ = with_sh_detections(data.load(list(subjects), stride=stride), data=data)
    return {f"S{s}": sh.subset(np.flatnonzero(sh.subject == s)) for s in subjects}


def _roots(lifter: Lifter, kp: np.ndarray, focal: np.ndarray, pp: np.ndarray, lens: np.ndarray | None,
           ) -> tuple[np.ndarray, np.ndarray]:
    return tuple(np.asarray(lifter.lift(kp, focal=focal, principal_point=pp, distortion=lens, source=src,  # type: ignore[return-value]
                                        warn=False).root) for src in ("detected", "clean"))


def _row(name: str, det: np.ndarray, clean: np.ndarray, true: np.ndarray) -> str:
    dz = np.abs(clean[:, 2] - det[:, 2]) / det[:, 2]
    cells = []
    for root in (det, clean, *[(1 - w) * det + w * clean for w in (np.exp(-(dz / t) ** 2)[:, None] for t in TAUS)]):
        cells.append(f"{np.linalg.norm(root - true, axis=-1).mean():.1f} ({(root[:, 2] - true[:, 2]).mean():+.0f})")
    return f"| {name} | {len(det)} | {np.median(dz) * 100:.1f} % | " + " | ".join(cells) + " |"


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--h36m", type=Path, default=None)
    ap.add_argument("--model", default="default")
    ap.add_argument("--stride", type=int, default=50, help="every n-th frame, a multiple of 5 (default 50)")
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    if args.stride < 5 or args.stride % 5:
        ap.error(f"--stride must be a multiple of 5 (the training subjects' detections are of every 5th frame), "
                 f"got {args.stride}")
    h36m = args.h36m or default_h36m_dir()
    data = H36M(h36m)
    lifter = Lifter.load(args.model)
    rows = []
    everyone: list[tuple[np.ndarray, ...]] = []
    for s, sh in sorted(_sh_samples(data, args.stride, (9, 11)).items()):
        det, clean = _roots(lifter, sh.keypoints_2d, sh.focal, sh.principal_point, sh.distortion)
        everyone.append((det, clean, sh.pose_3d[:, 0]))
        rows.append(_row(f"SH detections, {s}", det, clean, sh.pose_3d[:, 0]))
    rows.insert(0, _row("SH detections, S9 + S11", *(np.concatenate(v) for v in zip(*everyone))))
    trained = []
    for s, sh in _sh_samples(data, args.stride, TRAINING).items():
        det, clean = _roots(lifter, sh.keypoints_2d, sh.focal, sh.principal_point, sh.distortion)
        trained.append((det, clean, sh.pose_3d[:, 0]))
        rows.append(_row(f"SH detections, {s} (trained on)", det, clean, sh.pose_3d[:, 0]))
    rows.append(_row("SH detections, S1-S8 (trained on)", *(np.concatenate(v) for v in zip(*trained))))
    demo = h36m / "demo"
    ann = np.load(demo / "annotations.npz")
    focal, pp, lens = cascade.demo_intrinsics(cascade.demo_cameras(data, ann))
    found = cascade.detect_demo(demo, ann["image"])
    ok = found["people"] > 0
    det, clean = _roots(lifter, convert(found["kp33"][ok], src="blazepose33"), focal[ok], pp[ok], lens[ok])
    rows.append(_row("84 photos, BlazePose", det, clean, ann["p3d_cam"].astype(np.float64)[ok][:, 0]))
    head = ["detected (shipped)", "clean", *[f"tau {t:g}" for t in TAUS]]
    emit("\n".join([
        f"Root of detector 2D from the clean and the detected networks by their agreement ({lifter.name}; SH: every "
        f"{args.stride}th frame, Protocol 1): MRPE mm (mean signed root-depth error, + = too far); dz: the roots' "
        "depth difference over the detected root's depth", "",
        "| input | samples | median dz | " + " | ".join(head) + " |", "|---|---|---|" + "---|" * len(head), *rows]),
        args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
