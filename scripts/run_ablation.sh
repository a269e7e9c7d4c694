#!/usr/bin/env bash
# Paper Table 2 ablation: four lifters of equal budget (4 epochs of stride-5 P1 training frames, GT 2D),
# differing only in the normalization layer's features. Writes runs/ablation_<mode>.pt (+ curves).
set -euo pipefail
PAPER=(--input-space pixel --conditioning none --depth-target canonical)  # the paper's pixel-space layer (v1 runs)
EPOCHS=${EPOCHS:-4}
for mode in baseline location scale both; do
  poselifter train --out "runs/ablation_${mode}.pt" --mode "$mode" "${PAPER[@]}" --epochs "$EPOCHS" --threads 1 --eval-every 250
done
