#!/usr/bin/env bash
# Trainings on one GPU through the torchrun path (`torchrun -m lifter train`, NCCL would join more GPUs),
# then evaluation of each on the machine's CPUs (`poselifter evaluate`, S9+S11, flip test):
#   paper4096     the paper's width (67.5M parameters) with the default's detected-2D recipe
#   detected1024  the same recipe at the default's width 1024 (same minutes, same GPU: the width comparison)
#   clean1024     the default's clean-2D recipe at width 1024
# All three run at once on the one GPU (JOBS=all) or only paper4096 (JOBS=paper). Settings (environment):
#   M minutes per training (6), WA / WB widths (4096 / 1024), DROP dropout of paper4096 (0.25; the paper's is
#   0.5), TH CPU threads per process (5), H36M data folder (.gpu/h36m, from scripts/compact_h36m.py), OUT
#   folder for the results (results.tgz, the width-1024 checkpoints, logs.txt).
# Run from the repository root, on a machine where python3 has torch with CUDA; wheels of missing pure-Python
# dependencies (array-api-compat) can be put in .gpu/whl. What the lent H200 gave: docs/results/gpu_h200/.
#   M=5.5 OUT=/tmp/out bash scripts/gpu_train.sh
#   M=3.5 JOBS=paper DROP=0.5 TH=12 OUT=/tmp/out bash scripts/gpu_train.sh
set -u
OUT=${OUT:?set OUT to the folder for the results}
if compgen -G ".gpu/whl/*.whl" > /dev/null; then
  python3 -m pip install -q --no-index --no-deps --no-compile --no-cache-dir --target /tmp/site .gpu/whl/*.whl && export PYTHONPATH=/tmp/site
fi
export PYTHONUNBUFFERED=1 PYTHONPATH=$PWD:${PYTHONPATH:-}
M=${M:-6}; WA=${WA:-4096}; WB=${WB:-1024}; EV=${EV:-1}; TH=${TH:-5}
D=${H36M:-.gpu/h36m}; R=runs/gpu
rm -rf "$R"; mkdir -p "$R" "$OUT"  # a second run on the same machine must not report the first one's files
(nvidia-smi --query-gpu=name,memory.total,driver_version --format=csv; nproc; python3 -c "import torch, numpy, tqdm; print('torch', torch.__version__, 'cuda', torch.cuda.is_available(), 'numpy', numpy.__version__)") > $R/env.txt 2>&1
cat $R/env.txt
DMON=
if command -v nvidia-smi >/dev/null; then nvidia-smi dmon -s um -d 10 > "$R/dmon.txt" 2>&1 & DMON=$!; fi
waitall() { for p in $(jobs -p); do [ "$p" != "$DMON" ] && wait $p; done; }
DET="--input-space camera --depth-target size --conditioning none --ema-decay 0.999 --precision bf16 --epochs 100000 --no-progress --clean-prob 0 --real-prob 0.5 --noise-level-min 0 --noise-level-max 1.5"
CLEAN="--depth-target size --conditioning none --ema-decay 0.999 --precision bf16 --epochs 100000 --no-progress --clean-prob 1.0"
tr() { # name port args...
  local name=$1 port=$2; shift 2
  OMP_NUM_THREADS=$TH torchrun --nnodes 1 --nproc_per_node 1 --master_port $port -m lifter train --h36m "$D" --threads $TH --max-minutes $M --out "$R/$name.pt" "$@" > "$R/$name.log" 2>&1
  echo "$name exit $?" >> "$R/$name.log"
}
JOBS=${JOBS:-all}; DROP=${DROP:-0.25}
tr paper4096 29511 $DET --width $WA --dropout $DROP --eval-every 2000 &
if [ "$JOBS" = all ]; then
tr detected1024 29512 $DET --width $WB --eval-every 1000 &
tr clean1024 29513 $CLEAN --width $WB --eval-every 1000 &
fi
waitall
tail -n 3 $R/*.log
if [ "$EV" = 1 ]; then
  ev() { # label path inputs stride source
    local f="$R/$1_$3_s$4"
    python3 -m lifter evaluate "$1=$2" --h36m "$D" --inputs $3 --stride $4 --source $5 --flip-test --threads $TH --json "$f.json" > "$f.txt" 2>&1; echo "exit $?" >> "$f.txt"; }
  TH=8 ev paper4096 $R/paper4096.pt gt 5 clean & ev paper4096 $R/paper4096.pt sh 50 detected &
  if [ "$JOBS" = all ]; then
  ev detected1024 $R/detected1024.pt gt 5 clean & ev detected1024 $R/detected1024.pt sh 50 detected &
  ev clean1024 $R/clean1024.pt gt 5 clean &
  fi
  waitall
  cat $R/*_s*.txt
fi
[ -n "$DMON" ] && kill "$DMON" 2>/dev/null
ls -la $R
tar czf "$OUT/results.tgz" --exclude='*.pt' -C runs gpu
cp "$R/clean1024.pt" "$R/detected1024.pt" "$OUT/" 2>/dev/null
cat "$R"/*.log > "$OUT/logs.txt"
