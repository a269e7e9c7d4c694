"""The weight-read floor of one pose: how fast this machine streams float32 weights through one-row products.

That rate bounds one pose through the default model (the issue's ``Lifter.lift`` one-pose line).

A single pose is a chain of ``(1, W) @ (W, W)`` products: every weight is read once and used for one multiply-add,
so the time is the weight bytes over the rate at which the core can read them. That rate depends on whether the
weights stay in the cache between calls: this script times chains of ``W x W`` float32 matrices (1 BLAS thread)
whose total size spans the model's, each the median of many warm calls, and reports GB/s per total size. It then
prints the model's weight bytes per pose (every network a ``source="detected"`` lift runs; flip-test averaging reads
a network's weights once for both rows, ``lifter.model.forward_numpy``) and the network time those bytes need at
the measured rate for a working set of that size: a floor that no kernel reading float32 weights once reaches
below on this machine. Absolute rates vary between runs of a shared VM; compare sizes within one run.

    python benchmarks/bench_weight_traffic.py [--model default] [--sizes-mb 4,8,12,17,21,26,34] [--json out.json]
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")  # before numpy loads its BLAS

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from lifter import Lifter  # noqa: E402
from lifter._checks import PoseLifterError  # noqa: E402
from lifter.io import check_writable, write_atomic  # noqa: E402


def chain_rate(total_mb: float, *, width: int = 1024, calls: int = 300) -> tuple[float, float]:
    """``(MB actually used, GB/s)``: the median time of one pass of a vector through ``round(total / W^2 / 4)``
    float32 ``W x W`` matrices, after warm-up passes (so the weights are as cached as they can stay)."""
    n = max(1, round(total_mb * 1e6 / (width * width * 4)))
    rng = np.random.default_rng(0)
    mats = [rng.standard_normal((width, width), dtype=np.float32) for _ in range(n)]
    x = rng.standard_normal(width, dtype=np.float32)

    def one() -> None:
        for m in mats:
            m @ x

    for _ in range(20):
        one()
    times = []
    for _ in range(calls):
        t0 = time.perf_counter()
        one()
        times.append(time.perf_counter() - t0)
    mb = n * width * width * 4 / 1e6
    return mb, mb / 1e3 / float(np.median(times))


def weight_bytes(lifter: Lifter) -> int:
    """Float32 bytes of every parameter of the networks a ``source="detected"`` lift runs."""
    nets = [lifter.net, *(m.net for m in lifter.ensemble)]
    return sum(4 * p.numel() for net in nets for p in net.parameters())


def main() -> int:
    ap = argparse.ArgumentParser(description=(__doc__ or "").split("\n")[0])
    ap.add_argument("--model", default="default", help="shipped model name or checkpoint .pt")
    ap.add_argument("--sizes-mb", default="4,8,12,17,21,26,34", help="total weight sizes to time, MB")
    ap.add_argument("--json", default=None, help="write the numbers here")
    args = ap.parse_args()
    try:
        sizes = [float(v) for v in args.sizes_mb.split(",")]
    except ValueError:
        ap.error(f"--sizes-mb: expected comma-separated numbers, got {args.sizes_mb!r}")
    if not sizes or not all(math.isfinite(v) and 0 < v <= 4096 for v in sizes):
        ap.error(f"--sizes-mb: give sizes in MB between 0 and 4096, got {args.sizes_mb!r}")
    if args.json:
        try:
            check_writable(args.json, option="--json")
        except PoseLifterError as exc:
            ap.error(str(exc))
    try:
        lifter = Lifter.from_pretrained(args.model)
    except (PoseLifterError, OSError) as exc:
        ap.error(f"--model {args.model}: {exc}")
    model_mb = weight_bytes(lifter) / 1e6
    rows = []
    print("one-row float32 matrix-vector chains, W = 1024, 1 BLAS thread (median of 300 warm passes)")
    print(f"{'weights MB':>11} {'GB/s':>7} {'ms per pass':>12}")
    per_matrix = 1024 * 1024 * 4 / 1e6
    model_n = max(1, round(model_mb / per_matrix))
    for n in sorted({max(1, round(s / per_matrix)) for s in sizes} | {model_n}):  # whole matrices, each size once
        mb, rate = chain_rate(n * per_matrix)
        rows.append({"mb": round(mb, 2), "gb_per_s": round(rate, 1), "ms": round(mb / rate, 3)})
        print(f"{mb:11.1f} {rate:7.1f} {mb / rate:12.3f}" + ("   <- nearest the model's size" if n == model_n else ""))
    at_model = min(rows, key=lambda r: abs(r["mb"] - model_mb))
    best = max(rows, key=lambda r: r["gb_per_s"])
    floor = model_mb / at_model["gb_per_s"]
    print(f"\nmodel {lifter.name}: {model_mb:.1f} MB of float32 weights per detected-2D pose "
          f"({1 + len(lifter.ensemble)} network(s))")
    print(f"floor for its networks at the rate measured for that working set: {floor:.3f} ms per pose "
          f"(at this run's best rate, {best['gb_per_s']:.0f} GB/s for {best['mb']:.0f} MB: "
          f"{model_mb / best['gb_per_s']:.3f} ms)")
    if args.json:
        out = {"model": lifter.name, "model_mb": round(model_mb, 2), "rows": rows, "floor_ms": round(floor, 3)}
        write_atomic(args.json, (json.dumps(out, indent=1) + "\n").encode())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
