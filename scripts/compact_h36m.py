"""Write a smaller copy of the Human3.6M folder for a device machine that takes at most 64 MiB of upload.

Training reads every 5th frame and evaluation every 5th (or a multiple of it), so the 3D poses of the other
frames are zeroed and the test subjects' detections of the other frames set to NaN; both then compress to
almost nothing (62 MB -> 27 MB). Frame numbering, shapes and keys are unchanged, so ``H36M(out)`` loads it
like the original for any stride that is a multiple of 5; its ``compact.json`` makes ``H36M`` refuse the rest.

``--train-every 1`` keeps every frame of the training subjects (S1, S5, S6, S7, S8: for ``--train-stride 1``) and
``--test-every 100`` only the test subjects' learning-curve frames (``--val-stride 100``), to fit the upload beside
the repository; ``compact.json`` then names each subject's rate.

The copy is Human3.6M data: keep it in a git-ignored folder (the default, ``.gpu/h36m``, is ignored) and
never commit it.

    python scripts/compact_h36m.py [--h36m ../shared/data/h36m] [--out .gpu/h36m] [--train-every 5] [--test-every 5]
"""

from __future__ import annotations

import argparse
import io
import json
from pathlib import Path

import numpy as np

from lifter.data import COMPACT_FILE, default_h36m_dir
from lifter.detections import SH_DETECTIONS_FILE
from lifter.io import write_atomic

KEEP_EVERY = 5
TEST_SUBJECTS = ("S9", "S11")


def main() -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--h36m", type=Path, default=None, help="Human3.6M folder (default ../shared/data/h36m)")
    p.add_argument("--out", type=Path, default=Path(".gpu/h36m"),
                   help="where to write the copy (default .gpu/h36m, git-ignored)")
    p.add_argument("--train-every", type=int, default=KEEP_EVERY, metavar="N",
                   help=f"keep every N-th frame of the training subjects (default {KEEP_EVERY}; their real detections "
                        "exist every 5th frame whatever N is)")
    p.add_argument("--test-every", type=int, default=KEEP_EVERY, metavar="N",
                   help=f"keep every N-th frame of the test subjects S9 and S11 (default {KEEP_EVERY})")
    args = p.parse_args()
    for name in ("train_every", "test_every"):
        if getattr(args, name) < 1:
            p.error(f"--{name.replace('_', '-')} must be an integer >= 1, got {getattr(args, name)}")
    every = lambda key: args.test_every if key.split("/")[0] in TEST_SUBJECTS else args.train_every  # noqa: E731
    src = args.h36m or default_h36m_dir()
    missing = [f for f in ("cameras.json", "poses3d_world_17j_mm.npz", SH_DETECTIONS_FILE) if not (src / f).is_file()]
    if missing:
        p.error(f"no Human3.6M data at {src} ({', '.join(missing)} missing): pass --h36m FOLDER")
    if args.out.resolve() == src.resolve():
        p.error(f"--out {args.out} is the Human3.6M folder itself: write the copy elsewhere")
    args.out.mkdir(parents=True, exist_ok=True)
    write_atomic(args.out / "cameras.json", (src / "cameras.json").read_bytes())  # not the source's read-only mode
    poses = np.load(src / "poses3d_world_17j_mm.npz")
    out = {}
    for k in poses.files:
        a = poses[k].copy()
        a[np.arange(len(a)) % every(k) != 0] = 0
        out[k] = a
    buf = io.BytesIO()
    np.savez_compressed(buf, **out)
    write_atomic(args.out / "poses3d_world_17j_mm.npz", buf.getvalue())
    det = np.load(src / SH_DETECTIONS_FILE)
    out = {}
    for k in det.files:
        a = det[k].copy()
        if k.split("/")[0] in TEST_SUBJECTS:  # row i is frame i; training subjects are stored every 5th frame
            a[np.arange(len(a)) % args.test_every != 0] = np.nan
        out[k] = a
    buf = io.BytesIO()
    np.savez_compressed(buf, **out)
    write_atomic(args.out / SH_DETECTIONS_FILE, buf.getvalue())
    # H36M(out) reads this and refuses frames that were dropped (they hold zeros, not poses)
    subjects = sorted({k.split("/")[0] for k in poses.files}, key=lambda s: int(s[1:]))
    keep: int | dict[str, int] = (args.train_every if args.train_every == args.test_every
                                  else {s: every(s) for s in subjects})
    write_atomic(args.out / COMPACT_FILE, json.dumps({"keep_every": keep}) + "\n")
    total = sum(f.stat().st_size for f in args.out.iterdir())
    print(f"wrote {args.out} ({total / 1e6:.1f} MB; frames kept: every {args.train_every} of the training subjects, "
          f"every {args.test_every} of S9 and S11)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
