#!/usr/bin/env bash
# Paper Table 3 (training inputs) at the ablation's equal budget (4 epochs, P1, stride 5):
# rows (a) GT w/o location & scale and (b) GT are runs/ablation_baseline.pt and runs/ablation_both.pt;
# (c) real SH detections, (d) single-Gaussian noise, (e) mixture noise (with sampled outliers),
# (e') mixture noise without outliers (the authors' code). All evaluated on real SH detections of S9/S11.
set -euo pipefail
PAPER=(--input-space pixel --conditioning none --depth-target canonical)  # the paper's pixel-space layer (v1 runs)
EPOCHS=${EPOCHS:-4}
poselifter train --out runs/t3_sh.pt "${PAPER[@]}" --clean-prob 0 --real-prob 1 --epochs "$EPOCHS" --threads 1 --eval-every 250
poselifter train --out runs/t3_gauss.pt "${PAPER[@]}" --clean-prob 0 --noise gaussian --epochs "$EPOCHS" --threads 1 --eval-every 250
poselifter train --out runs/t3_mixture.pt "${PAPER[@]}" --clean-prob 0 --noise mixture --noise-outliers --epochs "$EPOCHS" --threads 1 --eval-every 250
poselifter train --out runs/t3_mixture_no_outliers.pt "${PAPER[@]}" --clean-prob 0 --noise mixture --no-noise-outliers --epochs "$EPOCHS" --threads 1 --eval-every 250
