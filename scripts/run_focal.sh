#!/usr/bin/env bash
# The focal-length claim (paper Table 6 analogue): canonical vs direct (absolute) depth, with and without
# zoom augmentation, all with mixture noise, 4 epochs each. Evaluated on virtual cameras (focal x0.5..x2)
# by scripts/make_results.sh. The canonical run without zoom is runs/t3_mixture.pt (run_table3.sh).
# Each run is claimed atomically, so two copies of this script can share the work on two cores.
set -euo pipefail
PAPER=(--input-space pixel --conditioning none --depth-target canonical)  # the paper's pixel-space layer (v1 runs)
EPOCHS=${EPOCHS:-4}
run() {
  local name=$1; shift
  mkdir "runs/.claim_${name}" 2>/dev/null || return 0
  poselifter train --out "runs/${name}.pt" "$@" --epochs "$EPOCHS" --threads 1 --eval-every 250
}
run f_canonical_zoom "${PAPER[@]}" --clean-prob 0 --noise mixture --noise-outliers --zoom
run f_absolute "${PAPER[@]}" --clean-prob 0 --noise mixture --noise-outliers --depth-target absolute
run f_absolute_zoom "${PAPER[@]}" --clean-prob 0 --noise mixture --noise-outliers --depth-target absolute --zoom
