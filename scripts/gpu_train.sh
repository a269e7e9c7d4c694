#!/usr/bin/env bash
# Trainings on one GPU through the torchrun path (`torchrun -m lifter train`, NCCL would join more GPUs),
# then evaluation of each on the machine's CPUs (`poselifter evaluate`, S9+S11, flip test):
#   paper<WA>     the paper's width (4096: 67.5M parameters) with the default's detected-2D recipe
#   detected<WB>  the same recipe at the default's width 1024 (same minutes, same GPU: the width comparison)
#   clean<WB>     the default's clean-2D recipe at width 1024
# All three run at once on the one GPU (JOBS=all) or only paper<WA> (JOBS=paper). Settings (environment):
#   M minutes per training (6), WA / WB widths (4096 / 1024), DROP dropout of paper<WA> (0.25; the paper's is
#   0.5), TH CPU threads per process (5), EV=0 to skip the evaluations, H36M data folder (.gpu/h36m, from
#   scripts/compact_h36m.py), OUT folder for the results: results.tgz (this run's folder without checkpoints:
#   logs, .curve.json/.png, evaluation tables), the width-WB checkpoints, logs.txt.
# Each run gets its own folder runs/gpu/<UTC time>. The script exits 1 when a training or an evaluation failed,
# after printing its error lines. Run from the repository root, on a machine where python3 has torch with
# CUDA; wheels of missing pure-Python dependencies (array-api-compat) can be put in .gpu/whl. What the lent
# H200 gave: docs/results/gpu_h200/.
#   M=5.5 OUT=/tmp/out bash scripts/gpu_train.sh
#   M=3.5 JOBS=paper DROP=0.5 TH=12 OUT=/tmp/out bash scripts/gpu_train.sh
set -u
OUT=${OUT:?set OUT to the folder for the results}
M=${M:-6}; WA=${WA:-4096}; WB=${WB:-1024}; EV=${EV:-1}; TH=${TH:-5}; JOBS=${JOBS:-all}; DROP=${DROP:-0.25}
D=${H36M:-.gpu/h36m}
if [ ! -f "$D/poses3d_world_17j_mm.npz" ]; then
  echo "gpu_train.sh: no Human3.6M data at $D: run python scripts/compact_h36m.py, or set H36M=<folder>" >&2
  exit 2
fi
# shellcheck source=scripts/gpu_setup.sh
. scripts/gpu_setup.sh  # wheels, PYTHONPATH, R and OUT, R/env.txt, nvidia-smi dmon (DMON)
waitall() { for p in $(jobs -p); do [ "$p" != "$DMON" ] && wait "$p"; done; }
FAILED=()
failed() { # file: the file's own error lines, not torchrun's wrapper
  FAILED+=("$1"); echo "FAILED: $1" >&2; grep -m 3 -E "error: |Error: " "$1" >&2; }
DET="--input-space camera --depth-target size --conditioning none --ema-decay 0.999 --precision bf16 --epochs 100000 --no-progress --clean-prob 0 --real-prob 0.5 --noise-level-min 0 --noise-level-max 1.5"
CLEAN="--depth-target size --conditioning none --ema-decay 0.999 --precision bf16 --epochs 100000 --no-progress --clean-prob 1.0"
train_run() { # name port args...
  local name=$1 port=$2; shift 2
  OMP_NUM_THREADS=$TH torchrun --nnodes 1 --nproc_per_node 1 --master_port "$port" -m lifter train --h36m "$D" \
    --threads "$TH" --max-minutes "$M" --out "$R/$name.pt" "$@" > "$R/$name.log" 2>&1
  echo "$name exit $?" >> "$R/$name.log"
}
NAMES=("paper$WA")
# shellcheck disable=SC2086  # the recipes are word lists
train_run "paper$WA" 29511 $DET --width "$WA" --dropout "$DROP" --eval-every 2000 &
if [ "$JOBS" = all ]; then
  NAMES+=("detected$WB" "clean$WB")
  # shellcheck disable=SC2086
  train_run "detected$WB" 29512 $DET --width "$WB" --eval-every 1000 &
  # shellcheck disable=SC2086
  train_run "clean$WB" 29513 $CLEAN --width "$WB" --eval-every 1000 &
fi
waitall
for n in "${NAMES[@]}"; do
  tail -n 3 "$R/$n.log"
  [ "$(tail -n 1 "$R/$n.log")" = "$n exit 0" ] || failed "$R/$n.log"
done
if [ "$EV" = 1 ]; then
  ev() { # label inputs stride source
    local f="$R/$1_$2_s$3"
    python3 -m lifter evaluate "$1=$R/$1.pt" --h36m "$D" --inputs "$2" --stride "$3" --source "$4" --flip-test \
      --threads "$TH" --json "$f.json" > "$f.txt" 2>&1
    echo "exit $?" >> "$f.txt"
  }
  for n in "${NAMES[@]}"; do
    [ -f "$R/$n.pt" ] || continue
    if [ "$n" = "paper$WA" ]; then TH=8 ev "$n" gt 5 clean & else ev "$n" gt 5 clean & fi
    [[ $n == clean* ]] || ev "$n" sh 50 detected &
  done
  waitall
  for f in "$R"/*_s*.txt; do
    [ -f "$f" ] || continue
    grep -v "^lifting (" "$f"
    [ "$(tail -n 1 "$f")" = "exit 0" ] || failed "$f"
  done
fi
[ -n "$DMON" ] && kill "$DMON" 2> /dev/null
ls -la "$R"
tar czf "$OUT/results.tgz" --exclude='*.pt' -C runs/gpu "$STAMP"
for n in "detected$WB" "clean$WB"; do [ -f "$R/$n.pt" ] && cp "$R/$n.pt" "$OUT/"; done
cat "$R"/*.log > "$OUT/logs.txt"
if [ ${#FAILED[@]} -gt 0 ]; then
  echo "gpu_train.sh: ${#FAILED[@]} step(s) failed: ${FAILED[*]}" >&2
  exit 1
fi
echo "gpu_train.sh: results in $R and $OUT"
