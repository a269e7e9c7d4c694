#!/usr/bin/env bash
# Every number the README quotes for the shipped default (issues 11 and 14), re-measured from assets/ with the
# commands named there. Output: docs/results/*.txt and *.json, docs/app_bench.json. Needs ../shared/data/h36m,
# the `detect` extra (BlazePose) and ~40 min on a 2-core CPU. MODEL=name|path.pt measures another lifter into
# docs/results/candidate_* instead (nothing else is overwritten).
set -euo pipefail
cd "$(dirname "$0")/.."
MODEL=${MODEL:-universal}
OUT=docs/results
P=$([ "$MODEL" = universal ] && echo "" || echo "candidate_")
mkdir -p "$OUT"
ev() { local name=$1; shift; poselifter evaluate "$@" --json "$OUT/$P$name.json" 2>/dev/null | tee "$OUT/$P$name.txt"; }
# clean GT 2D (source="clean"), every 5th frame; real SH detections (no source: "detected"), every 5th frame
ev universal_gt2d "$MODEL" --analytic-root --per-action --stride 5
ev universal_sh_s5 "$MODEL" sh_mix --inputs sh --stride 5 --analytic-root
# focal length x0.5 ... x2, re-projected, focal given; image resolution x0.1 ... x10 with the intrinsics
ev focal_sweep_universal "$MODEL" --focal-scales 0.5,0.7,1,1.4,2 --stride 50
python benchmarks/bench_invariance.py --models "$MODEL",sh_mix --json "$OUT/${P}bench_invariance.json" \
  | tee "$OUT/${P}bench_invariance.txt"
python benchmarks/bench_invariance.py --models "$MODEL" --source detected \
  --json "$OUT/${P}bench_invariance_detected.json" | tee "$OUT/${P}bench_invariance_detected.txt"
# the 84 demo photos through BlazePose, true focal
python scripts/eval_cascade.py --model "$MODEL" --compare sh_mix blazepose gt | tee "$OUT/${P}cascade_universal.txt"
# speed: one pose, batched throughput against the FLOP limit (1 and 2 threads)
python benchmarks/bench_lift.py --model "$MODEL" --threads 1 --single-calls 4000 --json "$OUT/${P}bench_lift.json" \
  | tee "$OUT/${P}bench_lift.txt"
python benchmarks/bench_lift.py --model "$MODEL" --threads 2 --single-calls 4000 \
  --json "$OUT/${P}bench_lift_2threads.json" | tee "$OUT/${P}bench_lift_2threads.txt"
# several people and video (issue 14)
python benchmarks/bench_multi_person.py --models "$MODEL" --multi windows | tee "$OUT/${P}bench_multi_person.txt"
python benchmarks/bench_video_sh.py --model "$MODEL" | tee "$OUT/${P}bench_video_sh.txt"
python benchmarks/bench_video.py --model "$MODEL" | tee "$OUT/${P}bench_video.txt"
