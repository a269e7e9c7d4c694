#!/usr/bin/env bash
# The default's fourth training stage: its three networks fine-tuned 25 minutes each on undistorted (pinhole) 2D
# (--lens pinhole: the GT 2D is the pinhole projection, the real SH detections are undistorted with each camera's
# lens model), every other part of each recipe as shipped (--config repeats it from the checkpoint). Before this
# stage every network had learned Human3.6M's lens distortion, which makes 2D poses ~0.8 % smaller than a pinhole
# shows them, and placed users' undistorted 2D ~1 % too near (scripts/pinhole_bias.py). On a 2-core CPU, one torch
# thread per run: the clean network and the width-1024 detected member side by side, then the mirror member.
# --init is each network as shipped at git 8982963 (before this stage). Then, to ship:
#   python scripts/ship_model.py runs/pinhole/detected_w1024.pt --clean runs/pinhole/clean.pt \
#     --ensemble runs/pinhole/detected_mirror.pt --flip-test --name universal --default
set -euo pipefail
cd "$(dirname "$0")/.."  # the repository root: the paths below are relative to it
MINUTES=${MINUTES-25}
[[ "$MINUTES" =~ ^[0-9]*\.?[0-9]+$ ]] && awk -v m="$MINUTES" 'BEGIN { exit !(m > 0) }' \
  || { echo "MINUTES must be a number > 0 (the wall-clock budget of each run), got '$MINUTES'" >&2; exit 2; }
mkdir -p runs/pinhole
init() {  # init NAME SHA256: the shipped network NAME as of 8982963, checked, in runs/pinhole/init_NAME.pt
  local out="runs/pinhole/init_$1.pt"
  if ! echo "$2  $out" | sha256sum --check --status 2>/dev/null; then
    git show "8982963:assets/weights/$1.pt" > "$out.tmp" \
      || { rm -f "$out.tmp"; echo "needs the git history to commit 8982963 (not a shallow clone)" >&2; exit 1; }
    echo "$2  $out.tmp" | sha256sum --check --status || { rm -f "$out.tmp"; echo "$out: wrong sha256" >&2; exit 1; }
    mv "$out.tmp" "$out"
  fi
  echo "$out"
}
CLEAN=$(init universal_clean 1b9a5c1f078ef66792bddf5a27ecfd3200d2b43cf05c30712285465908877dee)
W1024=$(init universal bd2c4cf3798cb46402795f3e20a957852821f456b9f8db693fc94016d6146d5e)
MIRROR=$(init universal_member2 62fdea36ade82849ebc0cb74997df76e44f7d7ff414701c1aecdcd5fcfd193d9)
COMMON=(--lens pinhole --lr 3e-4 --max-minutes "$MINUTES" --threads 1 --no-progress)
echo "fine-tuning the clean and width-1024 detected networks ($MINUTES min each, side by side), then the mirror member;"
echo "logs: runs/pinhole/{clean,w1024,mirror}.log"
poselifter train --out runs/pinhole/clean.pt --config "$CLEAN" --init "$CLEAN" "${COMMON[@]}" \
  > runs/pinhole/clean.log 2>&1 &
a=$!
poselifter train --out runs/pinhole/detected_w1024.pt --config "$W1024" --init "$W1024" "${COMMON[@]}" \
  > runs/pinhole/w1024.log 2>&1 &
b=$!
wait $a && wait $b
poselifter train --out runs/pinhole/detected_mirror.pt --config "$MIRROR" --init "$MIRROR" "${COMMON[@]}" \
  > runs/pinhole/mirror.log 2>&1
echo "done: runs/pinhole/{clean,detected_w1024,detected_mirror}.pt"
