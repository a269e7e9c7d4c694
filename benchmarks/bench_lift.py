"""Inference speed of ``Lifter.lift``: single-pose latency and batched throughput against the FLOP limit.

The FLOP limit is the machine's float32 matmul rate (GFLOP/s, the fastest ``(B, W) @ (W, W)`` product at the model's
width over B = 256, 1024, 4096 rows) divided by the FLOPs of one pose through the network (2 x multiply-adds of
every Linear layer), times two when the model averages each pose with its mirror image by default
(``Lifter.flip_test``: two network rows per pose), summed over an ensemble's networks. For each batch size the limit
and the model are timed alternately in ``--rounds`` rounds, each the best of a few repeats, and the fraction of the
limit is taken per round; the median over rounds is reported with its quartiles (the poses/s and limit columns are
their own medians, so their quotient can differ a little from it). Reported ratios are within one run, so they hold
on a shared, noisy machine; absolute times are indicative only.

    python benchmarks/bench_lift.py [--model default] [--threads 2] [--json out.json]
"""

from __future__ import annotations

import argparse
import json
import os
import time


def _thread_args() -> argparse.Namespace:
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--threads", type=int, default=2)
    return pre.parse_known_args()[0]


# numpy's BLAS (used by Lifter.lift for a single pose) reads its thread count at import: match --threads.
os.environ.setdefault("OPENBLAS_NUM_THREADS", str(_thread_args().threads))

import numpy as np  # noqa: E402
import torch  # noqa: E402

import lifter.api as api  # noqa: E402
import lifter.model as lifter_model  # noqa: E402
from lifter import Lifter  # noqa: E402
from lifter.camera import project  # noqa: E402
from lifter.cli._help import positive_int  # noqa: E402
from lifter.model import MirrorCoupledLinear  # noqa: E402


def flops_per_pose(net: torch.nn.Module) -> int:
    """FLOPs of one pose through the network (2 x multiply-adds). A mirror-equivariant net (``symmetry="mirror"``)
    runs its stem and head on two streams and each coupled layer as two W x W products (U on the streams' sum,
    V on their difference)."""
    streams = 2 if getattr(getattr(net, "config", None), "symmetry", "none") == "mirror" else 1
    total = 0
    for m in net.modules():
        if isinstance(m, torch.nn.Linear):
            total += streams * 2 * m.in_features * m.out_features
        elif isinstance(m, MirrorCoupledLinear):
            total += 2 * 2 * m.weight_sum.numel()
    return int(total)


LIMIT_ROWS: tuple[int, ...] = (256, 1024, 4096)
"""Row counts of the matmul whose fastest rate is the limit (smaller products can run faster: cache)."""


def peak_gflops(width: int, repeats: int = 5) -> float:
    """The machine's float32 matmul rate at ``width``: the fastest of ``(B, W) @ (W, W)`` over B in LIMIT_ROWS."""
    return max(matmul_gflops(width, batch=b, repeats=repeats) for b in LIMIT_ROWS)


def matmul_gflops(width: int, batch: int = 4096, repeats: int = 20) -> float:
    a = torch.randn(batch, width)
    b = torch.randn(width, width)
    for _ in range(3):
        a @ b
    best = float("inf")
    for _ in range(repeats):
        t = time.perf_counter()
        a @ b
        best = min(best, time.perf_counter() - t)
    return 2 * batch * width * width / best / 1e9


def time_calls_cold(fn) -> float:
    """One call's wall time (s), no warm-up of its own."""
    t = time.perf_counter()
    fn()
    return time.perf_counter() - t


def time_calls(fn, n: int) -> np.ndarray:
    for _ in range(min(20, n)):
        fn()
    out = np.empty(n)
    for i in range(n):
        t = time.perf_counter()
        fn()
        out[i] = time.perf_counter() - t
    return out


def human_keypoints(n: int, *, seed: int = 0) -> np.ndarray:
    """``(n, 17, 2)`` px at f = 1145, c = (512, 515): the shipped demo poses (``lifter.demo_sample``), each turned
    about the vertical by a random angle, its joints jittered by 15 mm and its root placed 3.5-5.5 m away, so that the
    default's checks see human bodies (random-walk "poses" draw its note that the lift does not fit them, whose
    text would be timed too)."""
    from lifter import demo_sample, demo_sample_names

    rng = np.random.default_rng(seed)
    base = np.stack([demo_sample(name).pose_3d for name in demo_sample_names()])
    base = base - base[:, :1]
    a = rng.uniform(-np.pi, np.pi, n)
    R = np.zeros((n, 3, 3))
    R[:, 0, 0], R[:, 0, 2], R[:, 1, 1], R[:, 2, 0], R[:, 2, 2] = np.cos(a), np.sin(a), 1.0, -np.sin(a), np.cos(a)
    rel = np.einsum("nij,nkj->nki", R, base[rng.integers(0, len(base), n)]) + rng.normal(0, 15, (n, 17, 3))
    root = np.stack([rng.uniform(-800, 800, n), rng.uniform(-200, 300, n), rng.uniform(3500, 5500, n)], -1)
    return project(rel + root[:, None], focal=1145.0, principal_point=(512.0, 515.0))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", default="default")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--single-calls", type=int, default=2000)
    ap.add_argument("--json", default=None)
    ap.add_argument("--rounds", type=positive_int, default=9,
                    help="alternating rounds (matmul, model) per batch size")
    ap.add_argument("--flip-test", action=argparse.BooleanOptionalAction, default=None,
                    help="override the model's flip-test default (every network of an ensemble)")
    args = ap.parse_args()
    torch.set_num_threads(args.threads)
    lifter = Lifter.load(args.model)
    if args.flip_test is not None:
        for m in (lifter, *lifter.ensemble):
            m.flip_test = args.flip_test
    kp = human_keypoints(8192)

    # Every network of the model (an ensemble averages several), each with its network rows per pose: the
    # mirror-image pass of the flip test (a mirror-equivariant net never needs it). The FLOP limit is the time the
    # machine's matmul rate at each network's width needs for its FLOPs, summed.
    parts = []
    for m in (lifter, *lifter.ensemble):
        rows_m = m.network_rows()
        parts.append((m, rows_m, rows_m * flops_per_pose(m.net), peak_gflops(m.config.width, repeats=20)))
    rows = sum(p[1] for p in parts)
    fpp = sum(p[2] for p in parts)
    seconds_per_pose = sum(p[2] / (p[3] * 1e9) for p in parts)
    limit = 1.0 / seconds_per_pose
    gflops = fpp / seconds_per_pose / 1e9
    for m, rows_m, f_m, g_m in parts:
        print(f"network {m.name}: width {m.config.width}, symmetry {m.config.symmetry}, {rows_m} row(s) per pose "
              f"(flip test {'n/a: equivariant' if m.config.symmetry == 'mirror' else 'on' if m.flip_test else 'off'}), "
              f"{f_m / 1e6:.2f} MFLOP/pose; matmul {g_m:.1f} GFLOP/s")
    print(f"model {lifter.name}: {len(parts)} network(s), {fpp / 1e6:.2f} MFLOP/pose; with {args.threads} threads "
          f"-> FLOP limit {limit:,.0f} poses/s")

    single = time_calls(lambda: lifter.lift(kp[0], focal=1145.0, principal_point=(512.0, 515.0)), args.single_calls)
    p50, p95 = np.percentile(single, [50, 95]) * 1e3
    print(f"single pose Lifter.lift (default path: float32 arithmetic; float16-packed matrices where the weights are "
          f"float16 numbers): median {p50:.3f} ms, p95 {p95:.3f} ms "
          f"({args.single_calls} calls; {os.environ['OPENBLAS_NUM_THREADS']} BLAS threads)")
    default_max, packed_max = api.NUMPY_MAX_BATCH, lifter_model.PACKED_MAX_ROWS
    packed_runs = all(lifter_model.forward_packed(m.net, np.zeros((1, m.net.stem.in_features), np.float32)) is not None
                      for m, *_ in parts)

    def lift_with(max_batch: int, kp_: np.ndarray, *, packed: bool = False, calls: int | None = None) -> float:
        """Median ms of lift(kp_) with up to ``max_batch`` rows through float32 numpy and, with ``packed``, the
        float16-packed matrices first (the default path)."""
        api.NUMPY_MAX_BATCH = max_batch
        lifter_model.PACKED_MAX_ROWS = packed_max if packed else 0  # type: ignore[misc]
        try:
            return float(np.median(time_calls(lambda: lifter.lift(kp_, focal=1145.0, principal_point=(512.0, 515.0)),
                                              calls or args.single_calls))) * 1e3
        finally:
            api.NUMPY_MAX_BATCH = default_max
            lifter_model.PACKED_MAX_ROWS = packed_max  # type: ignore[misc]

    # Everything but the networks' arithmetic (input checks, codec, decode, ensemble averaging): each network call
    # replays its output for this pose instead of computing it
    real_network = api.Lifter._network
    replay: dict[tuple[int, int], np.ndarray] = {}

    def replayed(self: Lifter, x: np.ndarray) -> np.ndarray:
        key = (id(self), len(x))
        if key not in replay:
            replay[key] = real_network(self, x)
        return replay[key].copy()

    api.Lifter._network = replayed  # type: ignore[method-assign]
    try:
        rest50 = float(np.median(time_calls(lambda: lifter.lift(kp[0], focal=1145.0, principal_point=(512.0, 515.0)),
                                            args.single_calls))) * 1e3
    finally:
        api.Lifter._network = real_network  # type: ignore[method-assign]
    print(f"single pose, all but the networks' arithmetic (their outputs replayed): median {rest50:.3f} ms; the "
          f"networks: {p50 - rest50:.3f} ms")
    u50, n50 = lift_with(0, kp[0]), lift_with(1 << 30, kp[0])
    print(f"single pose, float32 network rows all through torch (forward_folded): median {u50:.3f} ms; all through "
          f"numpy: {n50:.3f} ms (without float16 packing the default sends up to NUMPY_MAX_BATCH = {default_max} "
          "row(s) to numpy)")
    used = "used" if packed_runs else "NOT used (not float16-exact, or no fbgemm)"
    # the two paths alternately, round after round (a shared machine drifts within minutes: a review measured the
    # ratio of the two medians above, taken minutes apart, 10 % off the alternating one)
    pairs = [(lift_with(default_max, kp[0], packed=True, calls=max(100, args.single_calls // 5)),
              lift_with(1 << 30, kp[0], calls=max(100, args.single_calls // 5))) for _ in range(5)]
    alt_p, alt_n = (float(np.median([p[k] for p in pairs])) for k in (0, 1))
    alt_ratio = float(np.median([n / p for p, n in pairs]))
    print(f"single pose, float16-packed matrices {used} by the default path; alternately with float32 numpy, 5 "
          f"rounds: {alt_p:.3f} ms against {alt_n:.3f} ms, median ratio {alt_ratio:.2f}x")
    two_torch, two_numpy = lift_with(0, kp[:2]), lift_with(1 << 30, kp[:2])
    two_packed = lift_with(default_max, kp[:2], packed=True)
    print(f"two poses: torch {two_torch:.3f} ms, numpy {two_numpy:.3f} ms, float16-packed (default) "
          f"{two_packed:.3f} ms")
    q = lifter.quantized()
    single_q = time_calls(lambda: q.lift(kp[0], focal=1145.0, principal_point=(512.0, 515.0)), args.single_calls)
    q50, q95 = np.percentile(single_q, [50, 95]) * 1e3
    print(f"single pose Lifter.lift (quantize=True, int8 blocks): median {q50:.3f} ms, p95 {q95:.3f} ms "
          f"({q50 / p50:.2f}x the default path's time)")
    results = {"model": lifter.name, "flip_test": lifter.flip_test, "rows_per_pose": rows,
               "mflop_per_pose": fpp / 1e6, "matmul_gflops": gflops, "flop_limit_poses_per_s": limit,
               "single_calls": args.single_calls, "single_median_ms": p50, "single_p95_ms": p95,
               "single_without_network_arithmetic_median_ms": rest50,
               "single_torch_module_median_ms": u50, "single_numpy_median_ms": n50,
               "two_poses_torch_ms": two_torch, "two_poses_numpy_ms": two_numpy, "two_poses_packed_ms": two_packed,
               "single_uses_packed_fp16": packed_runs, "single_packed_alternating_ms": alt_p,
               "single_numpy_alternating_ms": alt_n, "single_numpy_over_packed_ratio": alt_ratio,
               "blas_threads": int(os.environ["OPENBLAS_NUM_THREADS"]), "single_int8_median_ms": q50,
               "single_int8_p95_ms": q95, "batched": []}
    # Each batch size against the FLOP limit measured in the same rounds: a shared machine's matmul rate drifts by
    # +-10 % within minutes, so the two are timed alternately, round after round (the matmul rate at every width,
    # then the model at this batch size), each as its best of a few repeats, and the ratio is taken per round. The
    # reported fraction is the median over rounds, with its quartiles.
    widths = sorted({m.config.width for m, *_ in parts})

    def limit_with(rates: dict[int, float]) -> float:
        return 1.0 / sum(f_m / (rates[m.config.width] * 1e9) for m, _, f_m, _ in parts)

    print(f"batched: {args.rounds} rounds per batch size, each the matmul rate (fastest of {LIMIT_ROWS} rows, best "
          "of 5 each) then the model (best of a few calls). poses/s, FLOP limit and GFLOP/s: medians over rounds; "
          "of FLOP limit: the median of the per-round ratios [quartiles]")
    print(f"{'batch':>6} {'poses/s':>12} {'FLOP limit':>11} {'of FLOP limit':>14}  [quartiles]  (matmul GFLOP/s)")
    for b in (1, 16, 256, 2048, 8192):
        kb = kp[:b]

        def call(kb=kb) -> None:
            lifter.lift(kb, focal=1145.0, principal_point=(512.0, 515.0))

        calls = max(3, int(400 / b))
        call()
        rounds = []
        for _ in range(args.rounds):
            rates = {w: peak_gflops(w) for w in widths}
            t = min(time_calls_cold(call) for _ in range(calls))
            rounds.append({"poses_per_s": b / t, "flop_limit_poses_per_s": limit_with(rates),
                           "matmul_gflops": rates})
        frac = np.array([r["poses_per_s"] / r["flop_limit_poses_per_s"] for r in rounds])
        q1, med, q3 = np.percentile(frac, [25, 50, 75])
        rate = float(np.median([r["poses_per_s"] for r in rounds]))
        lim = float(np.median([r["flop_limit_poses_per_s"] for r in rounds]))
        results["batched"].append({"batch": b, "poses_per_s": rate, "flop_limit_poses_per_s": lim,
                                   "fraction_of_limit": float(med), "fraction_quartiles": [float(q1), float(q3)],
                                   "rounds": rounds})
        gf = ", ".join(f"W{w}: {np.median([r['matmul_gflops'][w] for r in rounds]):.0f}" for w in widths)
        print(f"{b:>6} {rate:>12,.0f} {lim:>11,.0f} {100 * med:>13.1f}%  [{100 * q1:.1f}, {100 * q3:.1f}]  ({gf})")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(results, f, indent=1)


if __name__ == "__main__":
    main()
