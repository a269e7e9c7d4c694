#!/usr/bin/env python
"""Where the float16-packed matrices stop paying: ``Lifter.lift`` of B poses with ``lifter.model.PACKED_MAX_ROWS``
above every batch (packed) and at 0 (the float32 paths), alternately, round after round, on one torch thread.

    python benchmarks/bench_packed_rows.py [--model default] [--rounds 3] [--calls 20]

Prints, per batch size, both medians and their ratio; the default's width-1024 network reads two rows per pose
(flip-test averaging), its mirror network one, so B poses are 2B rows for the first.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")

import argparse  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402

import lifter.model as lifter_model  # noqa: E402
from lifter import Lifter  # noqa: E402
from lifter.cli._help import positive_int  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default="default")
    ap.add_argument("--rounds", type=positive_int, default=3)
    ap.add_argument("--calls", type=positive_int, default=20)
    ap.add_argument("--batches", default="1,16,32,64,65,96,128,160,192",
                    help="poses per call, comma-separated")
    args = ap.parse_args()
    torch.set_num_threads(1)
    from bench_lift import human_keypoints  # (the benchmark's own plausible poses)

    lifter = Lifter.load(args.model)
    kp = human_keypoints(max(int(b) for b in args.batches.split(",")))
    default = lifter_model.PACKED_MAX_ROWS

    def timed(k: np.ndarray) -> float:
        for _ in range(3):
            lifter.lift(k, focal=1145.0, principal_point=(512.0, 515.0), warn=False)
        t = time.perf_counter()
        for _ in range(args.calls):
            lifter.lift(k, focal=1145.0, principal_point=(512.0, 515.0), warn=False)
        return (time.perf_counter() - t) / args.calls * 1e3

    print(f"model {lifter.name}, 1 torch thread, {args.rounds} alternating rounds of {args.calls} calls; "
          f"PACKED_MAX_ROWS is {default}")
    print(" poses  rows(1st)  packed ms  float32 ms  float32/packed")
    try:
        for b in (int(x) for x in args.batches.split(",")):
            pairs = []
            for _ in range(args.rounds):
                lifter_model.PACKED_MAX_ROWS = 1 << 30  # type: ignore[misc]
                p = timed(kp[:b])
                lifter_model.PACKED_MAX_ROWS = 0  # type: ignore[misc]
                pairs.append((p, timed(kp[:b])))
            p50, f50 = (float(np.median([q[i] for q in pairs])) for i in (0, 1))
            print(f"{b:6d}  {2 * b:9d}  {p50:9.2f}  {f50:10.2f}  {np.median([f / p for p, f in pairs]):14.2f}")
    finally:
        lifter_model.PACKED_MAX_ROWS = default  # type: ignore[misc]


if __name__ == "__main__":
    main()
