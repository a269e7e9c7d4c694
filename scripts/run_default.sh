#!/usr/bin/env bash
# The shipped default: a pair of reference-camera lifters (2D mapped to a 1000-px camera, root depth as
# Z * sigma / f), one for exact 2D and one for detector 2D, trained side by side on a 2-core CPU (one torch
# thread each, bf16 autocast, weight EMA); wall-clock budgets drive the lr schedule. Then:
#   python scripts/ship_model.py runs/pair/detected.pt --clean runs/pair/clean.pt --flip-test --name universal --default
set -euo pipefail
MINUTES=${MINUTES:-80}
mkdir -p runs/pair
COMMON=(--input-space camera --depth-target size --conditioning none --ema-decay 0.999 --precision bf16
        --max-minutes "$MINUTES" --epochs 200 --threads 1 --no-progress --eval-every 1000)
# exact 2D (ground truth, hand-placed or dragged joints): source="clean"
poselifter train --out runs/pair/clean.pt "${COMMON[@]}" --clean-prob 1.0 > runs/pair/clean.log 2>&1 &
# detector 2D: half the real SH detections of the training subjects, half GT 2D with mixture noise at a random
# level in [0, 1.5] x the fitted error model
poselifter train --out runs/pair/detected.pt "${COMMON[@]}" --clean-prob 0 --real-prob 0.5 \
  --noise-level-min 0 --noise-level-max 1.5 > runs/pair/detected.log 2>&1 &
wait
