#!/usr/bin/env bash
# The default's third training stage for detected 2D (README "Not learning one detector's size"): both detected
# members fine-tuned 25 minutes with the real SH detections rescaled to the ground truth's median 2D scale
# (--real-rescale), side by side on a 2-core CPU (one torch thread each), their recipes otherwise unchanged.
# --init is each member as shipped before this stage: the width-1024 one from git d8e1733 (assets/weights/universal.pt
# there; it is now this stage's output; the shipped run named that file directly), the mirror one as it still ships.
# The two runs write runs/rescale/ (the unshipped mirror result too). Only the width-1024 member was shipped:
#   cp runs/rescale/detected_w1024.pt assets/weights/universal.pt   (then its sha256 and metrics in assets/models.json)
set -euo pipefail
cd "$(dirname "$0")/.."  # the repository root: the paths below are relative to it
MINUTES=${MINUTES-25}
[[ "$MINUTES" =~ ^[0-9]*\.?[0-9]+$ ]] && awk -v m="$MINUTES" 'BEGIN { exit !(m > 0) }' \
  || { echo "MINUTES must be a number > 0 (the wall-clock budget of each run), got '$MINUTES'" >&2; exit 2; }
mkdir -p runs/rescale
INIT_W1024=runs/rescale/init_w1024.pt
INIT_SHA=b607715961bb650b6e947e9e49869e29607475e709aa61a26d7d4fdce1c31186  # the registry's train_init_sha256
if ! echo "$INIT_SHA  $INIT_W1024" | sha256sum --check --status 2>/dev/null; then
  git show d8e1733:assets/weights/universal.pt > "$INIT_W1024.tmp" \
    || { rm -f "$INIT_W1024.tmp"; echo "needs the git history to commit d8e1733 (not a shallow clone)" >&2; exit 1; }
  echo "$INIT_SHA  $INIT_W1024.tmp" | sha256sum --check --status \
    || { rm -f "$INIT_W1024.tmp"; echo "$INIT_W1024: wrong sha256" >&2; exit 1; }
  mv "$INIT_W1024.tmp" "$INIT_W1024"
fi
COMMON=(--input-space camera --depth-target size --conditioning none --error-model assets/error_model/blazepose_demo_train.json
        --clean-prob 0 --real-prob 0.5 --real-rescale --lr 3e-4 --ema-decay 0.999 --precision bf16
        --max-minutes "$MINUTES" --epochs 200 --threads 1 --no-progress --eval-every 1000)
echo "training both detected members for $MINUTES min each, side by side; logs: runs/rescale/{w1024,mirror}.log"
poselifter train --out runs/rescale/detected_w1024.pt --init "$INIT_W1024" "${COMMON[@]}" \
  --noise-level-min 0.5 --noise-level-max 1.5 > runs/rescale/w1024.log 2>&1 &
a=$!
poselifter train --out runs/rescale/detected_mirror.pt --init assets/weights/universal_member2.pt "${COMMON[@]}" \
  --symmetry mirror --width 512 --noise-level-min 0.25 --noise-level-max 1.5 > runs/rescale/mirror.log 2>&1 &
b=$!
trap 'kill "$a" "$b" 2>/dev/null' EXIT  # one run failing (or Ctrl-C) stops the other
wait "$a" || { echo "width-1024 run failed: runs/rescale/w1024.log" >&2; exit 1; }
wait "$b" || { echo "mirror run failed: runs/rescale/mirror.log" >&2; exit 1; }
trap - EXIT
echo "wrote runs/rescale/detected_w1024.pt and runs/rescale/detected_mirror.pt (+ .curve.json, .curve.png)"
