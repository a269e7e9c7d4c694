"""Write a smaller copy of the Human3.6M folder for a device machine that takes at most 64 MiB of upload.

Training reads every 5th frame and evaluation every 5th (or a multiple of it), so the 3D poses of the other
frames are zeroed and the test subjects' detections of the other frames set to NaN; both then compress to
almost nothing (62 MB -> 27 MB). Frame numbering, shapes and keys are unchanged, so ``H36M(out)`` loads it
like the original for any stride that is a multiple of 5; its ``compact.json`` makes ``H36M`` refuse the rest.

The copy is Human3.6M data: keep it in a git-ignored folder (the default, ``.gpu/h36m``, is ignored) and
never commit it.

    python scripts/compact_h36m.py [--h36m ../shared/data/h36m] [--out .gpu/h36m]
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import numpy as np

from lifter.data import COMPACT_FILE, default_h36m_dir
from lifter.detections import SH_DETECTIONS_FILE

KEEP_EVERY = 5
TEST_SUBJECTS = ("S9", "S11")


def main() -> int:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--h36m", type=Path, default=None, help="Human3.6M folder (default ../shared/data/h36m)")
    p.add_argument("--out", type=Path, default=Path(".gpu/h36m"),
                   help="where to write the copy (default .gpu/h36m, git-ignored)")
    args = p.parse_args()
    src = args.h36m or default_h36m_dir()
    missing = [f for f in ("cameras.json", "poses3d_world_17j_mm.npz", SH_DETECTIONS_FILE) if not (src / f).is_file()]
    if missing:
        p.error(f"no Human3.6M data at {src} ({', '.join(missing)} missing): pass --h36m FOLDER")
    if args.out.resolve() == src.resolve():
        p.error(f"--out {args.out} is the Human3.6M folder itself: write the copy elsewhere")
    args.out.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(src / "cameras.json", args.out / "cameras.json")  # not the source's read-only mode
    poses = np.load(src / "poses3d_world_17j_mm.npz")
    out = {}
    for k in poses.files:
        a = poses[k].copy()
        a[np.arange(len(a)) % KEEP_EVERY != 0] = 0
        out[k] = a
    np.savez_compressed(args.out / "poses3d_world_17j_mm.npz", **out)
    det = np.load(src / SH_DETECTIONS_FILE)
    out = {}
    for k in det.files:
        a = det[k].copy()
        if k.split("/")[0] in TEST_SUBJECTS:  # row i is frame i; training subjects are stored every 5th frame
            a[np.arange(len(a)) % KEEP_EVERY != 0] = np.nan
        out[k] = a
    np.savez_compressed(args.out / SH_DETECTIONS_FILE, **out)
    # H36M(out) reads this and refuses frames that were dropped (they hold zeros, not poses)
    (args.out / COMPACT_FILE).write_text(json.dumps({"keep_every": KEEP_EVERY}) + "\n")
    total = sum(f.stat().st_size for f in args.out.iterdir())
    print(f"wrote {args.out} ({total / 1e6:.1f} MB; only frames at a multiple of {KEEP_EVERY} kept)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
