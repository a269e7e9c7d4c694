#!/usr/bin/env bash
# The paper's width (4096) on a long schedule, on one GPU through the torchrun path, beside the default's two
# detected-network shapes on the same schedule (issue 11, item 4). All three run at once on the one GPU with the
# default's detected-2D recipe in one stage from scratch (reference-camera input, pinhole 2D, real SH detections
# rescaled to the truth's size for half the samples, BlazePose-fit mixture noise at levels 0.25-1.5 for the rest,
# EMA, bf16), with a large batch so that one process's Python per step does not limit the GPU:
#   paper<WA>   width WA (4096, 67.5M parameters), the paper's dropout 0.5
#   detected<WB> width WB (1024), the default's first detected network's shape
#   mirror<WC>  width WC (512), mirror-equivariant: the default's second detected network's shape
# The schedule asks for EP epochs (300, the paper's: ~88M samples of the 293k); the lr follows
# max(step / steps, elapsed / M minutes), so a run that the time limit stops still ends its cosine decay.
# Then paper<WA> is evaluated on the machine's CPUs (its checkpoint, 135 MB in float16, cannot come back):
# GT 2D stride 5 told "clean", SH detections stride 5 told "detected", their default (flip test on). The width-WB and WC
# checkpoints come back in OUT and are evaluated where the full Human3.6M folder is.
#
# Data: python scripts/compact_h36m.py --out .gpu/h36m5 (every 5th frame of every subject; never committed).
# Settings (environment): M minutes per training (6), BS batch (2048), LR (1e-3), EP epochs (300), WA / WB / WC
# widths, RUNS which of the three to train ("paper detected mirror"), EXTRA more training arguments for each (e.g. the
# shipped default's "--rotate-deg 20 --distance-prob 0.25"), PAIR a checkpoint averaged with paper<WA> in one more
# evaluation (SH detections; e.g. assets/weights/universal_far_member2.pt), TH CPU threads per process (5), EV=0 to skip the evaluations, EVS evaluation stride (5), EVT seconds
# allowed each evaluation (170), H36M data
# folder (.gpu/h36m5), OUT folder for what comes back: results.tgz (logs, curves, env, dmon, evaluation
# tables), detected<WB>.pt, mirror<WC>.pt, logs.txt. Exits 1 when a training or an evaluation failed.
#   M=6 OUT=/tmp/out bash scripts/gpu_long.sh
set -u
OUT=${OUT:?set OUT to the folder for the results}
M=${M:-6}; BS=${BS:-2048}; LR=${LR:-1e-3}; EP=${EP:-300}; WA=${WA:-4096}; WB=${WB:-1024}; WC=${WC:-512}
RUNS=${RUNS:-paper detected mirror}; read -r -a XA <<< "${EXTRA:-}"; PAIR=${PAIR:-}; ETH=$([ -n "$PAIR" ] && echo 5 || echo 8)
# (EXTRA is split on blanks, without quoting; checked before any device minute is spent:)
for r in $RUNS; do
  case $r in paper|detected|mirror) ;; *) echo "$(basename "$0"): RUNS has '$r'; use words of: paper detected mirror" >&2
    exit 2 ;; esac
done
[ -n "${RUNS// /}" ] || { echo "$(basename "$0"): RUNS is empty; use words of: paper detected mirror" >&2; exit 2; }
if [ -n "$PAIR" ] && { [ ! -f "$PAIR" ] || [[ " $RUNS " != *" paper "* ]]; }; then
  echo "$(basename "$0"): PAIR=$PAIR needs that file and 'paper' in RUNS" >&2; exit 2
fi
TH=${TH:-5}; EV=${EV:-1}; EVS=${EVS:-5}; EVT=${EVT:-170}; D=${H36M:-.gpu/h36m5}
# shellcheck source=scripts/gpu_detected.sh
. scripts/gpu_detected.sh  # the data check, gpu_setup.sh, RECIPE, train_run
NAMES=()
case " $RUNS " in *" paper "*) NAMES+=("paper$WA"); train_run "paper$WA" 29511 --width "$WA" --dropout 0.5 \
  --eval-every 500 ${XA[@]+"${XA[@]}"} & ;; esac
case " $RUNS " in *" detected "*) NAMES+=("detected$WB"); train_run "detected$WB" 29512 --width "$WB" \
  --eval-every 1000 ${XA[@]+"${XA[@]}"} & ;; esac
case " $RUNS " in *" mirror "*) NAMES+=("mirror$WC"); train_run "mirror$WC" 29513 --width "$WC" --symmetry mirror \
  --eval-every 1000 ${XA[@]+"${XA[@]}"} & ;; esac
for p in $(jobs -p); do [ "$p" != "$DMON" ] && wait "$p"; done
[ -n "$DMON" ] && kill "$DMON" 2> /dev/null
failed() { FAILED+=("$1"); echo "FAILED: $1" >&2; grep -m 3 -E "error: |Error: " "$1" >&2; }
for n in "${NAMES[@]}"; do
  tail -n 2 "$R/$n.log"
  if [ "$(tail -n 1 "$R/$n.log")" = "$n exit 0" ]; then
    [ "$n" = "paper$WA" ] || cp "$R/$n.pt" "$OUT/"
  else failed "$R/$n.log"; fi
done
if [ "$EV" = 1 ] && [ -f "$R/paper$WA.pt" ]; then
  ev() { # inputs source [name spec]
    local f="$R/${3:-paper$WA}_$1_s$EVS"
    timeout "$EVT" python3 -m lifter evaluate "${3:-paper$WA}=${4:-$R/paper$WA.pt}" --h36m "$D" --inputs "$1" \
      --stride "$EVS" --source "$2" --flip-test --threads "$ETH" --json "$f.json" > "$f.txt" 2>&1
    echo "exit $?" >> "$f.txt"
  }
  ev gt clean &
  ev sh detected &
  [ -n "$PAIR" ] && ev sh detected "paper${WA}_pair" "$R/paper$WA.pt+$PAIR" &
  for p in $(jobs -p); do wait "$p"; done
  for f in "$R"/*_s"$EVS".txt; do
    grep -v "^lifting (" "$f"
    [ "$(tail -n 1 "$f")" = "exit 0" ] || failed "$f"
  done
fi
finish
