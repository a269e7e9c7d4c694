#!/usr/bin/env bash
# The default's clean-2D network trained on one GPU through the torchrun path, every 5th training frame against
# every frame, then Lifter.lift's speed on that machine's CPU. Three trainings run at once on the one GPU (one
# process's Python per step does not fill it): clean_s5 (the shipped clean member's recipe from scratch: pinhole
# 2D, --train-stride 5), clean_s1 and clean_s1b (every frame, --train-stride 1; seeds 0 and 1, to see the seed
# spread). The 293k stride-5 training samples are seen ~70 times in a few GPU minutes, and the shipped clean
# member's validation error rises after ~5M samples: more distinct frames is the lever tested here.
# Then `benchmarks/bench_lift.py --threads 1` and `benchmarks/bench_weight_traffic.py` on the machine's CPU.
# The checkpoints come back in OUT and are evaluated where the full Human3.6M folder is (`poselifter evaluate`).
#
# Data: a copy that keeps every frame of the training subjects and every 100th of S9/S11 (the learning curve):
#   python scripts/compact_h36m.py --out .gpu/h36m_s1 --train-every 1 --test-every 100
# Settings (environment): M minutes per training (5.5), TH CPU threads per process (4), BENCH=0 to skip the
# benchmarks, H36M (.gpu/h36m_s1),
# OUT folder for what comes back: clean_s5.pt, clean_s1.pt, clean_s1b.pt, logs.tgz (logs, curves, env, dmon),
# bench_lift.json, bench_lift.txt. Exits 1 when a training failed, after printing its error lines.
#   M=5.5 OUT=/tmp/out bash scripts/gpu_clean_stride.sh
set -u
OUT=${OUT:?set OUT to the folder for the results}
M=${M:-5.5}; TH=${TH:-4}; BENCH=${BENCH:-1}; D=${H36M:-.gpu/h36m_s1}
if [ ! -f "$D/poses3d_world_17j_mm.npz" ]; then
  echo "gpu_clean_stride.sh: no Human3.6M data at $D: run python scripts/compact_h36m.py --out $D --train-every 1" \
    "--test-every 100, or set H36M=<folder>" >&2
  exit 2
fi
# shellcheck source=scripts/gpu_setup.sh
. scripts/gpu_setup.sh  # wheels, PYTHONPATH, R and OUT, R/env.txt, nvidia-smi dmon (DMON)
RECIPE=(--input-space camera --depth-target size --conditioning none --ema-decay 0.999 --precision bf16 --epochs 200
        --clean-prob 1.0 --lens pinhole --width 1024 --eval-every 2000 --no-progress)
train_run() { # name port args...
  local name=$1 port=$2; shift 2
  OMP_NUM_THREADS=$TH torchrun --nnodes 1 --nproc_per_node 1 --master_port "$port" -m lifter train --h36m "$D" \
    --threads "$TH" --max-minutes "$M" --out "$R/$name.pt" "${RECIPE[@]}" "$@" > "$R/$name.log" 2>&1
  echo "$name exit $?" >> "$R/$name.log"
}
NAMES=(clean_s5 clean_s1 clean_s1b)
train_run clean_s5 29511 --train-stride 5 --seed 0 &
train_run clean_s1 29512 --train-stride 1 --seed 0 &
train_run clean_s1b 29513 --train-stride 1 --seed 1 &
for p in $(jobs -p); do [ "$p" != "$DMON" ] && wait "$p"; done
[ -n "$DMON" ] && kill "$DMON" 2> /dev/null
FAILED=()
for n in "${NAMES[@]}"; do
  tail -n 3 "$R/$n.log"
  if [ "$(tail -n 1 "$R/$n.log")" = "$n exit 0" ]; then cp "$R/$n.pt" "$OUT/"; else
    FAILED+=("$n"); echo "FAILED: $n" >&2; grep -m 3 -E "error: |Error: " "$R/$n.log" >&2
  fi
done
# the default's speed on this machine's CPU (one thread), then its memory bandwidth for a 25 MB working set
if [ "$BENCH" = 1 ]; then
  python3 benchmarks/bench_lift.py --threads 1 --single-calls 2000 --rounds 5 --json "$OUT/bench_lift.json" \
    > "$OUT/bench_lift.txt" 2>&1 || echo "bench_lift failed" >&2
  python3 benchmarks/bench_weight_traffic.py >> "$OUT/bench_lift.txt" 2>&1 || echo "bench_weight_traffic failed" >&2
  cat "$OUT/bench_lift.txt"
fi
tar czf "$OUT/logs.tgz" --exclude='*.pt' -C runs/gpu "$STAMP"
if [ ${#FAILED[@]} -gt 0 ]; then
  echo "gpu_clean_stride.sh: ${#FAILED[@]} training(s) failed: ${FAILED[*]}" >&2
  exit 1
fi
echo "gpu_clean_stride.sh: results in $R and $OUT"
