#!/usr/bin/env bash
# The mirror-equivariant default (ModelConfig symmetry="mirror", width 512 per stream): a pair of
# reference-camera lifters trained side by side on a 2-core CPU (one torch thread each, bf16 autocast, EMA),
# one for exact 2D and one for detector 2D. The shipped default uses only the detector-2D network, as the second
# member beside the width-1024 one (registry `universal`: ensemble_files); to ship them as a pair of their own
# under a new name (never over the default):
#   python scripts/ship_model.py runs/eq/detected.pt --clean runs/eq/clean.pt --name mirror_pair
set -euo pipefail
MINUTES=${MINUTES:-62}
mkdir -p runs/eq
COMMON=(--input-space camera --depth-target size --conditioning none --symmetry mirror --width 512
        --ema-decay 0.999 --precision bf16 --max-minutes "$MINUTES" --epochs 200 --threads 1 --no-progress
        --eval-every 1000)
# exact 2D (ground truth, hand-placed or dragged joints): source="clean"
poselifter train --out runs/eq/clean.pt "${COMMON[@]}" --clean-prob 1.0 > runs/eq/clean.log 2>&1 &
# detector 2D: half the real SH detections of the training subjects, half GT 2D with noise from the
# Gaussian + uniform mixture fitted to BlazePose's errors, at a random level in [0.25, 1.5]
poselifter train --out runs/eq/detected.pt "${COMMON[@]}" --clean-prob 0 --real-prob 0.5 \
  --error-model assets/error_model/blazepose_demo_train.json --noise-level-min 0.25 --noise-level-max 1.5 \
  > runs/eq/detected.log 2>&1 &
wait
