"""Peak memory of ``Lifter.lift`` on 10^6 poses, and that its chunked result equals one pass.

The lift runs in a child process, so its peak resident set size (``resource.getrusage``'s ``ru_maxrss``)
is that of the lift alone: Python, torch, the model, the input keypoints and the result. The poses are
the five shipped demo poses (:func:`lifter.demo_sample`), each turned about the vertical axis through its
pelvis by a random angle, placed at a random position 2.5-8 m in front of its own camera, with 3 mm of
joint jitter, and projected: plausible 2D at many sizes and positions, no dataset needed.

Then, in the same child, the first ``--check-poses`` rows (more than two chunks of
:data:`lifter.api.CHUNK_SIZE`) are lifted again in one pass (``CHUNK_SIZE`` raised above the batch) and
compared with the rows of the chunked 10^6 lift.

    python benchmarks/bench_memory.py [--poses 1000000] [--threads 1] [--json docs/results/bench_memory.json]

Exit status 1 if the peak is at or above ``--limit-gb`` or the results differ by more than ``--tol-mm``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import subprocess
import sys
import time

import numpy as np


def _rss_peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: KiB


def _rss_now_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def make_poses(n: int, *, seed: int = 0, block: int = 100_000) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``n`` plausible 2D poses ``(n, 17, 2)`` px with their focal and principal point ``(n, 2)`` px."""
    from lifter import demo_sample, demo_sample_names
    from lifter.camera import project

    samples = [demo_sample(name) for name in demo_sample_names()]
    rng = np.random.default_rng(seed)
    kp = np.empty((n, 17, 2))
    focal = np.empty((n, 2))
    pp = np.empty((n, 2))
    for s in range(0, n, block):
        m = min(block, n - s)
        which = rng.integers(0, len(samples), m)
        rel = np.stack([samples[i].pose_3d - samples[i].pose_3d[0] for i in range(len(samples))])[which]
        yaw = rng.uniform(-np.pi, np.pi, m)
        c, si = np.cos(yaw), np.sin(yaw)
        R = np.zeros((m, 3, 3))  # about the camera's y axis (vertical in the OpenCV frame)
        R[:, 0, 0], R[:, 0, 2], R[:, 1, 1], R[:, 2, 0], R[:, 2, 2] = c, si, 1.0, -si, c
        z = rng.uniform(2500.0, 8000.0, m)
        root = np.stack([rng.uniform(-0.25, 0.25, m) * z, rng.uniform(-0.15, 0.15, m) * z, z], axis=-1)
        pose = np.einsum("nij,nkj->nki", R, rel) + root[:, None, :] + rng.normal(0.0, 3.0, (m, 17, 3))
        f = np.stack([samples[i].focal for i in range(len(samples))])[which]
        c_ = np.stack([samples[i].principal_point for i in range(len(samples))])[which]
        kp[s:s + m] = project(pose, focal=f, principal_point=c_)
        focal[s:s + m], pp[s:s + m] = f, c_
    return kp, focal, pp


def child(args: argparse.Namespace) -> dict[str, object]:
    import torch

    torch.set_num_threads(args.threads)
    import lifter.api as api
    from lifter import Lifter

    model = Lifter.from_pretrained(args.model)
    model.lift(np.zeros((17, 2)) + np.arange(17)[:, None] * 10.0, focal=1000.0, principal_point=(500.0, 500.0))
    baseline = _rss_now_mb()
    kp, focal, pp = make_poses(args.poses, seed=args.seed)
    after_inputs = _rss_now_mb()
    input_mb = (kp.nbytes + focal.nbytes + pp.nbytes) / 2**20
    t0 = time.perf_counter()
    res = model.lift(kp, focal=focal, principal_point=pp, source="detected")
    seconds = time.perf_counter() - t0
    peak = _rss_peak_mb()
    result_mb = sum(a.nbytes for a in (res.absolute, res.root, res.relative, res.canonical_depth)) / 2**20
    root_z_median = float(np.median(res.root[:, 2]))

    # Keep the first rows, free the rest, then lift those rows in one pass: the one-pass batch (larger than a
    # chunk) then cannot raise the peak above that of the 10^6 lift.
    m = min(args.check_poses, args.poses)
    keys = ("absolute", "root", "relative", "canonical_depth")
    chunked = {k: getattr(res, k)[:m].copy() for k in keys}
    kp, focal, pp = kp[:m].copy(), focal[:m].copy(), pp[:m].copy()
    del res
    chunk = api.CHUNK_SIZE
    api.CHUNK_SIZE = m + 1  # type: ignore[misc]  # one pass over the slice
    try:
        one = model.lift(kp, focal=focal, principal_point=pp, source="detected")
    finally:
        api.CHUNK_SIZE = chunk  # type: ignore[misc]
    diffs = {k: float(np.abs(chunked[k] - getattr(one, k)).max()) for k in keys}
    return {
        "model": model.name, "flip_test": model.flip_test, "poses": args.poses, "chunk_size": chunk,
        "networks": [{"symmetry": m.config.symmetry, "width": m.config.width,
                      "rows_per_pose": m.network_rows()}
                     for m in (model, *model.ensemble)],
        "threads": args.threads, "seed": args.seed,
        "rss_after_model_load_mb": baseline, "rss_after_inputs_mb": after_inputs,
        "input_mb": input_mb, "result_arrays_mb": result_mb,
        "peak_rss_mb": peak, "lift_seconds": seconds, "poses_per_s": args.poses / seconds,
        "root_z_mm_median": root_z_median,
        "one_pass_check": {"poses": m, "chunks_in_chunked_run": -(-m // chunk), "max_abs_diff_mm": diffs,
                           "bitwise_equal": all(v == 0.0 for v in diffs.values())},
    }


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--poses", type=int, default=1_000_000)
    ap.add_argument("--check-poses", type=int, default=70_000,
                    help="rows lifted again in one pass and compared (default: more than two chunks)")
    ap.add_argument("--model", default="default")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--limit-gb", type=float, default=3.0)
    ap.add_argument("--tol-mm", type=float, default=1e-3)
    ap.add_argument("--json", default=None)
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args)))
        return 0

    cmd = [sys.executable, os.path.abspath(__file__), "--child", "--poses", str(args.poses), "--check-poses",
           str(args.check_poses), "--model", args.model, "--threads", str(args.threads), "--seed", str(args.seed)]
    env = {**os.environ, "OMP_NUM_THREADS": str(args.threads), "OPENBLAS_NUM_THREADS": str(args.threads)}
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        sys.stderr.write(proc.stderr)
        return proc.returncode
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    # The child's whole-life peak as the parent sees it: the same as peak_rss_mb unless the check raised it.
    out["child_peak_rss_mb_from_parent"] = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0
    out["wall_seconds"] = time.perf_counter() - t0
    out["limit_gb"] = args.limit_gb
    worst = max(out["one_pass_check"]["max_abs_diff_mm"].values())
    peak = max(out["peak_rss_mb"], out["child_peak_rss_mb_from_parent"])
    out["pass"] = bool(peak < args.limit_gb * 1024 and worst <= args.tol_mm)
    out["machine"] = {"python": platform.python_version(), "platform": platform.platform(),
                      "cpus": os.cpu_count()}
    try:
        import torch

        out["machine"]["torch"] = torch.__version__
    except ImportError:
        pass
    out["command"] = "python benchmarks/bench_memory.py " + " ".join(sys.argv[1:])
    text = json.dumps(out, indent=1)
    print(text)
    if args.json:
        with open(args.json, "w") as f:
            f.write(text + "\n")
    print(f"peak RSS {out['peak_rss_mb'] / 1024:.2f} GB for {args.poses:,} poses (limit {args.limit_gb} GB); "
          f"chunked vs one pass on {out['one_pass_check']['poses']:,} poses: max |diff| {worst:.3g} mm -> "
          f"{'PASS' if out['pass'] else 'FAIL'}", file=sys.stderr)
    return 0 if out["pass"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
