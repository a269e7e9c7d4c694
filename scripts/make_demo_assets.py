#!/usr/bin/env python
"""Regenerate the embedded demo samples in ``assets/demo/`` (authored poses, trimesh mannequin,
OpenCV render through a known camera; no Human3.6M data involved).

Usage: ``python scripts/make_demo_assets.py [--out assets/demo]``
"""

from __future__ import annotations

import argparse
from pathlib import Path

from poselifter_app.demo_assets import DEMO_DIR, write_demo_assets


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", type=Path, default=DEMO_DIR, help="output folder")
    args = p.parse_args()
    write_demo_assets(args.out)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
