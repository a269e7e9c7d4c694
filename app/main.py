"""``poselifter-app``: start the viser exploration app.

Binds 127.0.0.1 by default (use ``--host 0.0.0.0`` to expose it on purpose) and prints the URL. Opens
on the embedded demo samples; with Human3.6M (``--h36m DIR``, default ``../shared/data/h36m`` when it
exists) the subject / sequence / camera / frame browser appears as well.
"""

from __future__ import annotations

import argparse
import logging
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from .samples import default_h36m_root


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="poselifter-app", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--host", default="127.0.0.1", help="interface to bind (default 127.0.0.1, local only)")
    p.add_argument("--port", type=int, default=8080, help="port (0 = any free port)")
    p.add_argument("--h36m", type=Path, default=None,
                   help="Human3.6M folder (default: ../shared/data/h36m or $POSELIFTER_H36M when present)")
    p.add_argument("--no-h36m", action="store_true", help="demo samples only, even if Human3.6M is present")
    p.add_argument("--model", default=None, help="initial model name (assets/models.json; default: its default)")
    p.add_argument("--threads", type=int, default=2, help="torch CPU threads")
    return p


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    import torch
    import viser

    from .viewer import PoseLifterApp

    torch.set_num_threads(max(1, args.threads))
    h36m = None
    if not args.no_h36m:
        h36m = args.h36m if args.h36m is not None else default_h36m_root()
        if args.h36m is not None and not (args.h36m / "poses3d_world_17j_mm.npz").is_file():
            print(f"error: no Human3.6M data at {args.h36m} (expected poses3d_world_17j_mm.npz)", file=sys.stderr)
            return 2
    server = viser.ViserServer(host=args.host, port=args.port, label="poselifter", verbose=False)
    try:
        app = PoseLifterApp(server, h36m_root=h36m, default_model=args.model)
    except Exception as exc:  # noqa: BLE001
        server.stop()
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"poselifter app: {app.url}  (Human3.6M: {h36m or 'not used'}; models: {app.pool.names})", flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        server.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
