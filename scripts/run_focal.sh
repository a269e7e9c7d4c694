#!/usr/bin/env bash
# The focal-length claim (paper Table 6 analogue): canonical vs direct (absolute) depth, with and without
# zoom augmentation, all with mixture noise, 4 epochs each. Evaluated on virtual cameras (focal x0.5..x2).
set -euo pipefail
EPOCHS=${EPOCHS:-4}
poselifter train --out runs/f_canonical_zoom.pt --noise mixture --zoom-aug --epochs "$EPOCHS" --threads 1 --eval-every 250
poselifter train --out runs/f_absolute.pt --noise mixture --depth-target absolute --epochs "$EPOCHS" --threads 1 --eval-every 250
poselifter train --out runs/f_absolute_zoom.pt --noise mixture --depth-target absolute --zoom-aug --epochs "$EPOCHS" --threads 1 --eval-every 250
