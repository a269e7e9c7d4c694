"""``python -m lifter ...`` is ``poselifter ...``.

E.g. under ``torchrun``: ``torchrun --nproc_per_node 2 -m lifter train ...``.
"""

import sys

from .cli import main

sys.exit(main())
