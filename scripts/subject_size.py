"""How big each Human3.6M subject is, against the training subjects' mean: the scale / depth ambiguity behind
the root-depth bias on the demo photos (README, "Photos").

A lifter sees only the 2D pose; a person 5 % larger than the people it was trained on looks like an average
person 5 % nearer. Size here: the root-mean-square 3D distance of the 17 joints from the pelvis (mm), over
every ``--stride``-th frame of all of a subject's sequences (every subject performs the same actions).

    python scripts/subject_size.py [--h36m PATH] [--stride 200]
"""

from __future__ import annotations

import argparse

import numpy as np

from lifter.cli._help import add_h36m_arguments
from lifter.data import H36M, default_h36m_dir

TRAIN_SUBJECTS = (1, 5, 6, 7, 8)
TEST_SUBJECTS = (9, 11)


def subject_size(data: H36M, subject: int, *, stride: int) -> tuple[float, int]:
    """Mean RMS joint distance from the pelvis (mm) of one subject, and the number of frames used."""
    poses = np.concatenate([data.poses_world(q, slice(None, None, stride)) for q in data.sequences_of([subject])])
    size = np.sqrt(((poses - poses[:, :1]) ** 2).sum(-1).mean(-1))
    return float(size.mean()), len(poses)


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    add_h36m_arguments(ap, stride=200)
    args = ap.parse_args()
    data = H36M(args.h36m or default_h36m_dir())
    sizes = {s: subject_size(data, s, stride=args.stride) for s in TRAIN_SUBJECTS + TEST_SUBJECTS}
    ref = float(np.mean([sizes[s][0] for s in TRAIN_SUBJECTS]))
    ann = data.root / "demo" / "annotations.npz"
    demo = np.load(ann) if ann.is_file() else None
    print(f"training subjects' mean size: {ref:.1f} mm (RMS joint distance from the pelvis, "
          f"every {args.stride}th frame)")
    print("| subject | split | frames | size mm | vs training mean |")
    print("|---|---|---|---|---|")
    for s, (size, n) in sizes.items():
        split = "train" if s in TRAIN_SUBJECTS else "test"
        print(f"| S{s} | {split} | {n} | {size:.1f} | {100 * (size / ref - 1):+.1f} % |")
    if demo is not None:
        subj = np.array([int(str(x).lstrip("S")) for x in demo["subject"]])
        z = demo["p3d_cam"][:, 0, 2].astype(np.float64)
        for s in np.unique(subj):
            if s not in sizes:
                continue
            m = subj == s
            scale = sizes[s][0] / ref
            print(f"demo photos of S{s}: {m.sum()}, mean root depth {z[m].mean():.0f} mm; a lifter that took this "
                  f"subject for an average one would place the root {z[m].mean() * (1 / scale - 1):+.0f} mm off "
                  "(if it judged depth from the 2D size alone)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
