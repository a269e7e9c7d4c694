"""Helpers for tests and benchmarks: a viser server on a free local port and fake browser tabs.

A :class:`FakeTab` is a bare websocket client that speaks enough of viser's protocol (it sends one
``ViewerCameraMessage``, as the browser does on load) for the server to create a real
:class:`viser.ClientHandle`, so :class:`app.viewer.PoseLifterApp` builds a per-tab session for it.
"""

from __future__ import annotations

import contextlib
import threading
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from typing import Any
from uuid import uuid4

import msgspec
import viser
from viser import _messages
from websockets.sync.client import ClientConnection, connect


def local_server() -> viser.ViserServer:
    """A quiet viser server on 127.0.0.1 and an OS-assigned free port, guarded as the app's
    (:func:`~poselifter_app.viser_hooks.guard_requests`)."""
    from .viser_hooks import guard_requests

    guard_requests()
    return viser.ViserServer(host="127.0.0.1", port=0, verbose=False)


@dataclass
class FakeTab:
    """A websocket "tab" connected to ``server``; close it to disconnect."""

    server: viser.ViserServer
    conn: ClientConnection = field(init=False)
    received: int = 0

    def __post_init__(self) -> None:
        url = f"ws://127.0.0.1:{self.server.get_port()}"
        self.conn = connect(url, subprotocols=[f"viser-v{viser.__version__}"], max_size=None)  # type: ignore[list-item]
        msg = _messages.ViewerCameraMessage(
            wxyz=(1.0, 0.0, 0.0, 0.0), position=(3.0, 3.0, 3.0), fov=1.2, near=0.01, far=1000.0,
            image_height=600, image_width=800, look_at=(0.0, 0.0, 0.0), up_direction=(0.0, 0.0, 1.0))
        self.conn.send(msgspec.msgpack.encode(msg.as_serializable_dict()))
        threading.Thread(target=self._drain, daemon=True).start()

    def _drain(self) -> None:
        try:
            while True:
                self.conn.recv()
                self.received += 1
        except Exception:  # noqa: BLE001 - closed
            pass

    def send(self, msg: Any) -> None:
        """Send one client -> server message (a :mod:`viser._messages` message)."""
        self.conn.send(msgspec.msgpack.encode(msg.as_serializable_dict()))

    def upload(self, handle: Any, name: str, content: bytes, *, chunk_size: int = 512 * 1024,
               declared_size: int | None = None, max_parts: int | None = None, part_tag: str | None = None) -> str:
        """Upload ``content`` through the upload button ``handle`` the way the browser does (a
        ``FileTransferStartUpload`` then 512-KiB ``FileTransferPart`` s); returns the transfer's id.
        ``declared_size`` / ``max_parts`` let a test announce a size it does not send, ``part_tag`` name another
        control in the parts (a hostile client's)."""
        uuid = handle._impl.uuid
        transfer = uuid4().hex
        parts = [content[i:i + chunk_size] for i in range(0, len(content), chunk_size)]
        self.send(_messages.FileTransferStartUpload(
            source_component_uuid=uuid, transfer_uuid=transfer, filename=name, mime_type="", part_count=len(parts),
            size_bytes=len(content) if declared_size is None else int(declared_size)))
        for i, part in enumerate(parts[:max_parts]):
            self.send(_messages.FileTransferPart(source_component_uuid=uuid if part_tag is None else part_tag,
                                                 transfer_uuid=transfer, part_index=i, content=part))
        return transfer

    def close(self) -> None:
        self.conn.close()


def wait_for(predicate: Any, *, timeout: float = 20.0, interval: float = 0.05) -> bool:
    """Poll ``predicate()`` until true or ``timeout`` s; returns its last truth value."""
    end = time.time() + timeout
    while time.time() < end:
        if predicate():
            return True
        time.sleep(interval)
    return bool(predicate())


@contextlib.contextmanager
def open_tab(app: Any, *, timeout: float = 20.0) -> Iterator[tuple[FakeTab, Any]]:
    """A new :class:`FakeTab` on ``app`` (a :class:`poselifter_app.viewer.PoseLifterApp`) and the session view the
    app built for it. On leaving, the tab disconnects and its view must be gone within ``timeout`` s (the next test
    counts the views)."""
    before = set(app.views)
    tab = FakeTab(app.server)
    try:
        assert wait_for(lambda: len(set(app.views) - before) == 1, timeout=timeout), "the fake tab got no session"
        yield tab, app.views[next(iter(set(app.views) - before))]
    finally:
        tab.close()
    assert wait_for(lambda: set(app.views) == before, timeout=timeout), "the fake tab's session did not end"
