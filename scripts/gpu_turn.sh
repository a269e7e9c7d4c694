#!/usr/bin/env bash
# The camera-turn augmentation (--rotate-deg) on one GPU through the torchrun path, beside the same recipe without
# it. A user trial found the default's detected networks rough in where the person stands: a 10 px move of the
# principal point (a 0.5 deg turn of the camera, the same scene) moves their root depth by 2.5 % at the 95th
# percentile on the test poses, against 0.5 % for the clean network (scripts/root_smoothness.py). Turning the camera
# in training (2D moved by K R K^-1, the 3D turned with it) takes away what the training cameras' fixed pose lets a
# network read from the person's image position. Four runs at once, all with gpu_long.sh's detected-2D recipe in one
# stage from scratch (reference-camera input, pinhole 2D, real SH detections rescaled to the truth's size for half
# the samples, BlazePose-fit mixture noise at levels 0.25-1.5 for the rest, EMA, bf16, batch 2048):
#   detected<WB>        width WB (1024), no turn (the baseline, as gpu_long.sh's)
#   detected<WB>_rot<A> width WB, pan and tilt each uniform in +-A degrees (10)
#   detected<WB>_rot<B> width WB, +-B degrees (20)
#   mirror<WC>_rot<A>   width WC (512), mirror-equivariant, +-A degrees
# SET=b trains the rest of a turned default instead, two runs:
#   clean<WB>_rot<B>    width WB, exact 2D only (--clean-prob 1, no detections or noise), +-B degrees
#   mirror<WC>_rot<B>   width WC, mirror-equivariant, the detected recipe, +-B degrees
# Every checkpoint comes back in OUT and is evaluated where the full Human3.6M folder is.
#
# Data: python scripts/compact_h36m.py --out .gpu/h36m5 (never committed). Settings (environment): M minutes per
# training (6), BS batch (2048), LR (1e-3), EP epochs (300), WB / WC widths, A / B degrees, TH CPU threads per
# process (3), H36M data folder (.gpu/h36m5), OUT folder for what comes back: the four .pt, results.tgz (logs,
# curves, env, dmon), logs.txt. Exits 1 when a training failed.
#   M=6 OUT=/tmp/out bash scripts/gpu_turn.sh
set -u
OUT=${OUT:?set OUT to the folder for the results}
M=${M:-6}; BS=${BS:-2048}; LR=${LR:-1e-3}; EP=${EP:-300}; WB=${WB:-1024}; WC=${WC:-512}; A=${A:-10}; B=${B:-20}
TH=${TH:-3}; D=${H36M:-.gpu/h36m5}
# shellcheck source=scripts/gpu_detected.sh
. scripts/gpu_detected.sh  # the data check, gpu_setup.sh, RECIPE, train_run
RECIPE+=(--eval-every 1000)
if [ "${SET:-a}" = b ]; then  # the rest of a default turned by +-B degrees: its clean network and mirror member
  NAMES=("clean${WB}_rot$B" "mirror${WC}_rot$B")
  train_run "${NAMES[0]}" 29525 --width "$WB" --rotate-deg "$B" --clean-prob 1.0 --real-prob 0 --no-real-rescale &
  train_run "${NAMES[1]}" 29526 --width "$WC" --symmetry mirror --rotate-deg "$B" &
else
  NAMES=("detected$WB" "detected${WB}_rot$A" "detected${WB}_rot$B" "mirror${WC}_rot$A")
  train_run "${NAMES[0]}" 29521 --width "$WB" &
  train_run "${NAMES[1]}" 29522 --width "$WB" --rotate-deg "$A" &
  train_run "${NAMES[2]}" 29523 --width "$WB" --rotate-deg "$B" &
  train_run "${NAMES[3]}" 29524 --width "$WC" --symmetry mirror --rotate-deg "$A" &
fi
for p in $(jobs -p); do [ "$p" != "$DMON" ] && wait "$p"; done
[ -n "$DMON" ] && kill "$DMON" 2> /dev/null
for n in "${NAMES[@]}"; do
  tail -n 2 "$R/$n.log"
  if [ "$(tail -n 1 "$R/$n.log")" = "$n exit 0" ]; then cp "$R/$n.pt" "$OUT/"
  else FAILED+=("$n"); echo "FAILED: $n" >&2; grep -m 3 -E "error: |Error: " "$R/$n.log" >&2; fi
done
finish
