# Shared by scripts/gpu_long.sh and scripts/gpu_turn.sh (sourced from the repository root, after M, BS, LR, EP, TH,
# D and OUT are set): the default's detected-2D recipe in one stage from scratch (reference-camera input, pinhole 2D,
# real SH detections rescaled to the truth's size for half the samples, BlazePose-fit mixture noise at levels
# 0.25-1.5 for the rest, EMA, bf16) as RECIPE, train_run NAME PORT ARGS... (one torchrun training into $R, its log
# ending "NAME exit CODE"), and gpu_setup.sh's set-up. Exits 2 without the data.
if [ ! -f "$D/poses3d_world_17j_mm.npz" ]; then
  echo "$(basename "$0"): no Human3.6M data at $D: run python scripts/compact_h36m.py --out $D, or set H36M=<folder>" >&2
  exit 2
fi
# shellcheck source=scripts/gpu_setup.sh
. scripts/gpu_setup.sh  # wheels, PYTHONPATH, R and OUT, R/env.txt, nvidia-smi dmon (DMON)
RECIPE=(--input-space camera --depth-target size --conditioning none --ema-decay 0.999 --precision bf16
        --clean-prob 0 --real-prob 0.5 --real-rescale --error-model assets/error_model/blazepose_demo_train.json
        --noise-level-min 0.25 --noise-level-max 1.5 --lens pinhole --epochs "$EP" --batch-size "$BS" --lr "$LR"
        --no-progress)
train_run() { # name port args...
  local name=$1 port=$2; shift 2
  OMP_NUM_THREADS=$TH torchrun --nnodes 1 --nproc_per_node 1 --master_port "$port" -m lifter train --h36m "$D" \
    --threads "$TH" --max-minutes "$M" --out "$R/$name.pt" "${RECIPE[@]}" "$@" > "$R/$name.log" 2>&1
  echo "$name exit $?" >> "$R/$name.log"
}
FAILED=()
finish() { # pack $R's logs and curves into OUT/results.tgz and OUT/logs.txt; exit 1 when a step is in FAILED
  tar czf "$OUT/results.tgz" --exclude='*.pt' -C runs/gpu "$STAMP"
  cat "$R"/*.log > "$OUT/logs.txt"
  if [ ${#FAILED[@]} -gt 0 ]; then
    echo "$(basename "$0"): ${#FAILED[@]} step(s) failed: ${FAILED[*]}" >&2
    exit 1
  fi
  echo "$(basename "$0"): results in $R and $OUT"
}
