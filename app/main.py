"""``poselifter-app``: start the viser exploration app.

Binds 127.0.0.1 by default (use ``--host 0.0.0.0`` to expose it on purpose) and prints the URL. Without
Human3.6M it opens on the embedded demo samples; with it (``--h36m DIR``, default ``../shared/data/h36m`` when
it exists; ``--no-h36m`` to leave it out) it opens on a Human3.6M frame, and the subject / sequence / camera /
frame browser appears beside the demo samples.
"""

from __future__ import annotations

import argparse
import gc
import logging
import socket
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import NoReturn

from lifter._text import plain_text

from .samples import default_h36m_root

START_TIMEOUT_S: float = 15.0
"""The server must be listening within this many seconds, else the app exits with an error."""


def _port(text: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a port number") from None
    if not 0 <= v <= 65535:
        raise argparse.ArgumentTypeError(f"port {v} is outside 0-65535 (0 = any free port)")
    return v


def check_bind(host: str, port: int) -> str | None:
    """None when ``host`` resolves and a socket can listen on it (``port``, or the next one viser would try when
    it is busy); otherwise the reason, for the user."""
    try:
        infos = socket.getaddrinfo(host, None, type=socket.SOCK_STREAM)
    except (socket.gaierror, UnicodeError, OSError) as exc:
        return f"cannot use --host {host!r}: {exc}"
    errors = []
    for family, _, _, _, addr in infos:
        for p in ([port] if port == 0 else [port, port + 1]):
            if p > 65535:
                continue
            with socket.socket(family, socket.SOCK_STREAM) as s:
                s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
                try:
                    s.bind((addr[0], p) + tuple(addr[2:]))
                    return None
                except OSError as exc:
                    errors.append(f"{addr[0]}:{p}: {exc.strerror or exc}")
    return f"cannot listen on --host {host!r} --port {port}: " + "; ".join(errors[:3])


def start_lines(*, url: str, requested_port: int, actual_port: int, h36m: Path | None, no_h36m: bool,
                models: Sequence[str], host: str = "127.0.0.1") -> list[str]:
    """What ``poselifter-app`` prints once it is up: its URL, where Human3.6M was read from or looked for, the models;
    before it, a note when ``--port`` was busy and the server took the next free one (a README trial's second app
    went to 8081 without a word, while the browser still showed the first one on 8080); and a warning when ``host``
    is not this machine's loopback (the app has no login: whoever reaches the port can use it)."""
    from lifter.data import default_h36m_dir

    from .viser_hooks import is_loopback

    lines = []
    if not is_loopback(host):
        lines.append(f"warning: --host {host} lets anyone who can reach this machine on port {actual_port} use the app "
                     "and upload files to it (it has no login); leave --host out to serve this machine only")
    if requested_port != 0 and actual_port != requested_port:
        lines.append(f"note: port {requested_port} is busy (another poselifter-app?), so this one serves on "
                     f"{actual_port}: open the URL below (--port to choose another)")
    where = (str(h36m.resolve()) if h36m is not None else "off (--no-h36m)" if no_h36m else
             f"not found at {default_h36m_dir().resolve()}, demo samples only (--h36m DIR or $POSELIFTER_H36M)")
    lines.append(f"poselifter app: {url}  (Human3.6M: {where}; models: {list(models)})")
    return lines


class _OneLineErrors(argparse.ArgumentParser):
    """argparse, but a bad option is one ``error: ...`` line (exit code 2), as the app's other start-up errors are,
    not the usage block first (a README trial's ``--port 99999``)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"error: {message} (poselifter-app --help)\n")


def build_parser() -> argparse.ArgumentParser:
    from lifter import __version__

    p = _OneLineErrors(prog="poselifter-app", description=plain_text(__doc__),
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--version", action="version", version=f"poselifter-app {__version__}")
    p.add_argument("--host", default="127.0.0.1", help="interface to bind (default 127.0.0.1, local only)")
    p.add_argument("--port", type=_port, default=8080,
                   help="port 0-65535 (default 8080; 0 = any free port; a busy port: the next free one, and a "
                        "note says so)")
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
    problem = check_bind(args.host, args.port)
    if problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    started: list[viser.ViserServer] = []
    failed: list[BaseException] = []
    from .viser_hooks import guard_requests

    guard_requests()  # (before the server starts: a page of another site may not drive the app)

    def start() -> None:
        try:
            started.append(viser.ViserServer(host=args.host, port=args.port, label="poselifter", verbose=False))
        except BaseException as exc:  # noqa: BLE001 - reported below
            failed.append(exc)

    t = threading.Thread(target=start, daemon=True)  # viser waits forever when it cannot bind
    t.start()
    t.join(START_TIMEOUT_S)
    if not started:
        why = f"{type(failed[0]).__name__}: {failed[0]}" if failed else f"not listening after {START_TIMEOUT_S:g} s"
        print(f"error: could not start the server on {args.host}:{args.port} ({why})", file=sys.stderr, flush=True)
        import os

        os._exit(2)  # (a server thread may still be trying: do not wait for it)
    server = started[0]
    try:
        app = PoseLifterApp(server, h36m_root=h36m, default_model=args.model)
    except Exception as exc:  # noqa: BLE001
        server.stop()
        print(f"error: {exc}", file=sys.stderr)
        return 2
    # Startup objects (models, modules, demo data) never become garbage: keep them out of the collector's full
    # passes, which otherwise stall playback for ~0.15 s every few seconds.
    gc.freeze()
    for line in start_lines(url=app.url, requested_port=args.port, actual_port=server.get_port(), h36m=h36m,
                            no_h36m=args.no_h36m, models=app.pool.names, host=args.host):
        print(line, flush=True)
    try:
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        server.stop()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
