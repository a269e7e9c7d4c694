"""Everything of the app that touches viser 1.1.1 internals (private attributes and its message protocol), in one
place. Each hook is best effort: when viser's internals change it does nothing (and logs why) rather than fail.

* :func:`limit_uploads`: uploads go through the upload button only; one is stopped as soon as the size the browser
  announces, or the bytes actually received so far, exceed the app's limit (viser itself buffers uploads of any
  size, to any control), when it starts while two others from the same tab are still arriving, or when all tabs'
  unfinished uploads would pass :class:`UploadBudget`;
* :func:`report_rejected_values`: a GUI value that viser cannot cast to the control's type (e.g. text for a
  slider) is reported to the user and the control shows the value in use again (viser alone only logs an
  asyncio traceback);
* :func:`note_typed_values`: the time a browser tab sends a value for a control is recorded before viser puts that
  value in the control (viser runs the control's callbacks later, on a thread pool: a sync pass running meanwhile
  would read the new value with the previous key's time);
* :func:`set_value_here` / :func:`send_value` / :func:`clear_box`: a control's value set on the server (its
  callbacks run) without telling the tab, and told later; meanwhile its box is empty. A value that arrives in a
  number box while it is being typed in mixes with the keys (playback's frames landed between a typed frame's keys:
  "200" became 146, then 0146);
* :func:`drag_callback`: the registered drag callback of a scene node (tests and benchmarks call it directly);
* :func:`guard_requests`: the server answers only requests addressed to it by a loopback name when it is bound to
  a loopback address (DNS rebinding), and opens websockets only for pages of its own origin (viser accepts any
  Origin: a web page open in the same browser could drive the app and upload to it).
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from collections.abc import Callable
from typing import Any

import viser

log = logging.getLogger("poselifter.app")


class UploadBudget:
    """The bytes that every tab of a server may hold in uploads still arriving, together (viser buffers each
    transfer until it is complete: a security review's eight raw connections, each with two unfinished 18-MiB
    uploads, held 288 MB), and how long a transfer may go without a new part before it is dropped. Shared by the
    :func:`limit_uploads` hooks of a server's tabs; thread-safe (tabs are built on viser's thread pool, messages
    handled on its event loop)."""

    def __init__(self, *, max_bytes: int, idle_s: float = 60.0) -> None:
        import weakref

        self.max_bytes = int(max_bytes)
        self.idle_s = float(idle_s)
        self._lock = threading.Lock()
        self._guis: weakref.WeakSet[Any] = weakref.WeakSet()
        self._last_part: dict[str, tuple[float, Callable[[], None]]] = {}  # transfer -> (time of its start or latest
        # new part, what tells its tab it is dropped)

    def add(self, gui: Any) -> None:
        with self._lock:
            self._guis.add(gui)

    def _states(self) -> list[dict[str, Any]]:
        with self._lock:
            return [gui._current_file_upload_states for gui in list(self._guis)]

    def held(self) -> int:
        """Bytes every tab's unfinished uploads hold or have announced, whichever is more (an upload is let start on
        what it announces: a review's third upload, let start on what the others had received so far, was stopped
        half-way)."""
        return sum(held_by(st) for states in self._states() for st in list(states.values()))

    def touch(self, transfer: str, dropped: Callable[[], None]) -> None:
        """``transfer`` started or got a new part now; ``dropped()`` tells its tab if it is dropped for idling."""
        with self._lock:
            self._last_part[transfer] = (time.monotonic(), dropped)

    def drop_idle(self) -> None:
        """Drop the transfers of every tab that have had no new part for :attr:`idle_s` (a client that starts an upload
        and never finishes it held its bytes until it disconnected), each with its ``dropped()``."""
        now = time.monotonic()
        told: list[Callable[[], None]] = []
        for states in self._states():
            for t in list(states):
                with self._lock:
                    when, dropped = self._last_part.setdefault(t, (now, lambda: None))
                if now - when > self.idle_s:
                    states.pop(t, None)
                    told.append(dropped)
                    log.warning("upload %s dropped: no part for %.0f s", t, self.idle_s)
        live = {t for states in self._states() for t in list(states)}
        with self._lock:
            for t in [t for t in self._last_part if t not in live]:
                self._last_part.pop(t, None)
        for dropped in told:
            try:
                dropped()
            except Exception:  # noqa: BLE001
                log.exception("could not tell a tab its upload was dropped")


PART_COST_BYTES: int = 128
"""What each part of an upload counts for beside its bytes: viser keeps about 114 bytes for every part, however
small, so a review's 100,000 one-byte parts, counted as 100 KB, held 11 MiB (the browser sends 512-KiB parts). A
transfer may cost :data:`PART_COST_BYTES` a part on top of the upload limit's bytes up to 1/64 of that limit."""


def held_by(state: dict[str, Any]) -> int:
    """What a transfer in viser's buffer holds, or announced (whichever is more): its bytes and
    :data:`PART_COST_BYTES` a part."""
    got = int(state.get("transferred_bytes", 0)) + PART_COST_BYTES * len(state.get("parts", ()))
    return max(got, int(state.get("total_bytes", 0)))


_NOT_HERE = "poselifter: refused"
"""What an upload's control uuid is changed to, before viser reads the message, so that viser ignores it (no
control has this uuid)."""


def limit_uploads(gui: viser.GuiApi, button: viser.GuiUploadButtonHandle, *, max_bytes: int,
                  refuse: Callable[[str, int], None], refuse_busy: Callable[[str, int], None],
                  refuse_full: Callable[[str, int], None] | None = None,
                  refuse_idle: Callable[[str, int], None] | None = None, budget: UploadBudget | None = None,
                  client_id: int | None = None, max_in_flight: int = 2) -> bool:
    """Bound what viser buffers for the uploads of ``gui`` (a tab's): uploads go through ``button`` only, each at
    most ``max_bytes``, at most ``max_in_flight`` at a time, and all tabs' together within ``budget``.

    * A transfer announced for another control (a slider: viser would set its value to the file) is ignored; so is
      every part of a transfer this hook did not let start, whatever control the part names (viser buffers parts by
      their transfer only: a security review's part tagged with another control's id was buffered to 1 GB).
    * An upload announcing more than ``max_bytes``, or whose bytes received pass it, is stopped (checked before
      viser buffers each part, on viser's own count of the transfer's bytes): ``refuse(file name, bytes)``, once.
    * An upload that starts while ``max_in_flight`` others through the button are still arriving is refused with
      ``refuse_busy(file name, max_in_flight)``.
    * An upload that would take every tab's unfinished uploads past ``budget.max_bytes`` is stopped with
      ``refuse_full(file name, bytes held)`` (admitted on the sizes announced, counted on the bytes received where
      more); a transfer without a new part for ``budget.idle_s`` is dropped, with ``refuse_idle(file name, seconds)``.
    * Each part counts :data:`PART_COST_BYTES` on top of its bytes (viser keeps about 114 bytes a part, however
      small): a transfer of many tiny parts is stopped once that passes the limit by 1/64.

    ``client_id``: only that client's messages (None: any). Install it before the button's callbacks can be used.
    Returns False when the hook could not be installed."""
    try:
        from viser import _messages

        iface = gui._websock_interface
        states: dict[str, Any] = gui._current_file_upload_states
        handlers: dict[Any, list[Any]] = iface._incoming_handlers
        controls: dict[str, Any] = gui._gui_input_handle_from_uuid
        uuid = button._impl.uuid
    except AttributeError as exc:
        log.warning("upload size limit not installed (viser internals changed: %s)", exc)
        return False
    mine: dict[str, str] = {}  # transfers let start through the button -> file name
    # every transfer let start on this GUI by a hook like this one (a GUI may hold several upload buttons, each
    # hooked): transfer -> button
    let: dict[str, str] = gui.__dict__.setdefault("_poselifter_uploads", {})
    if budget is not None:
        budget.add(gui)

    def ack(transfer: str, total: int) -> None:  # ends the browser's progress bar
        iface.queue_message(_messages.FileTransferPartAck(
            source_component_uuid=uuid, transfer_uuid=transfer, transferred_bytes=total, total_bytes=total))

    def stop(transfer: str, name: str, size: int, total: int, say: Callable[[str, int], None] | None) -> None:
        states.pop(transfer, None)  # later parts are ignored by viser
        mine.pop(transfer, None)
        let.pop(transfer, None)
        ack(transfer, total)
        if say is not None:
            say(name, size)

    def idle_drop(transfer: str, name: str, total: int) -> Callable[[], None]:
        return lambda: stop(transfer, name, int(budget.idle_s) if budget is not None else 0, total, refuse_idle)

    def on_start(cid: int, msg: Any) -> None:  # (before viser's handler, which makes the transfer's buffer)
        try:
            if client_id is not None and cid != client_id:
                return
            if msg.source_component_uuid != uuid:
                other = controls.get(msg.source_component_uuid)
                if other is not None and not isinstance(other, viser.GuiUploadButtonHandle):
                    log.warning("an upload to control %s, not an upload button, ignored", msg.source_component_uuid)
                    msg.source_component_uuid = _NOT_HERE
                return  # (another upload button's: its own hook checks it; an unknown control's: viser ignores it)
            refusal: tuple[Callable[[str, int], None] | None, int] | None = None
            if budget is not None:
                budget.drop_idle()
            for done in [t for t in mine if t not in states]:  # (finished or dropped since)
                mine.pop(done)
                let.pop(done, None)
            if msg.size_bytes > max_bytes:
                refusal = (refuse, msg.size_bytes)
            elif len(mine) >= max_in_flight:
                refusal = (refuse_busy, max_in_flight)
            elif budget is not None and budget.held() + msg.size_bytes > budget.max_bytes:
                refusal = (refuse_full, budget.held())
            if refusal is not None:
                msg.source_component_uuid = _NOT_HERE  # viser makes no buffer for it
                say, n = refusal
                ack(msg.transfer_uuid, msg.size_bytes)
                if say is not None:
                    say(msg.filename, n)
                return
            mine[msg.transfer_uuid] = msg.filename
            let[msg.transfer_uuid] = uuid
            if budget is not None:
                budget.touch(msg.transfer_uuid, idle_drop(msg.transfer_uuid, msg.filename, msg.size_bytes))
        except Exception:  # noqa: BLE001 - never break viser's message loop
            log.exception("upload check failed")
            msg.source_component_uuid = _NOT_HERE

    def on_part(cid: int, msg: Any) -> None:  # (before viser's handler, which buffers the part)
        try:
            if client_id is not None and cid != client_id:
                return
            t = msg.transfer_uuid
            state = states.get(t)
            if state is None:
                return  # (viser ignores it too)
            if t not in let:  # (a transfer no hook let start: to another control, or begun before the hooks)
                states.pop(t, None)
                ack(t, int(state.get("total_bytes", 0)))
                return
            if t not in mine:
                return  # (another upload button's: its hook checks it)
            msg.source_component_uuid = uuid  # (viser gives the finished file to the control a part names)
            n = int(state.get("transferred_bytes", 0)) + len(msg.content)
            total = int(state.get("total_bytes", 0))
            before = held_by(state)
            after = max(n + PART_COST_BYTES * (len(state.get("parts", ())) + 1), total)  # (with this part)
            if n > max_bytes or after > max_bytes + max_bytes // 64:
                stop(t, mine[t], max(n, after), total or n, refuse)
            elif budget is not None and budget.held() - before + after > budget.max_bytes:
                stop(t, mine[t], budget.held(), total or n, refuse_full)
            elif budget is not None and msg.content and msg.part_index not in state.get("parts", {}):
                budget.touch(t, idle_drop(t, mine[t], int(state.get("total_bytes", n))))  # (a new part: not idle)
        except Exception:  # noqa: BLE001
            log.exception("upload check failed")
            states.pop(msg.transfer_uuid, None)

    handlers.setdefault(_messages.FileTransferStartUpload, []).insert(0, on_start)
    handlers.setdefault(_messages.FileTransferPart, []).insert(0, on_part)
    return True


def report_rejected_values(gui: viser.GuiApi, report: Callable[[str], None]) -> bool:
    """Wrap viser's GUI-update handler of ``gui``: a value it cannot cast to the control's type is reported with
    ``report(message)`` and the control is sent its current value again. Returns False if not installed."""
    try:
        from viser import _messages

        handlers: list[Any] = gui._websock_interface._incoming_handlers[_messages.GuiUpdateMessage]
        if any(getattr(h, "_poselifter_checked", False) for h in handlers):
            return True  # (the server's GUI, shared by headless views: the first one reports)
        original = gui._handle_gui_updates
        lookup: dict[str, Any] = gui._gui_input_handle_from_uuid
        i = handlers.index(original)
    except (AttributeError, KeyError, ValueError) as exc:
        log.warning("GUI value checks not installed (viser internals changed: %s)", exc)
        return False

    async def checked(client_id: Any, message: Any) -> None:
        try:
            await original(client_id, message)
        except Exception as exc:  # noqa: BLE001 - viser could not cast / apply the value
            handle = lookup.get(message.uuid)
            label = getattr(handle, "label", "a control") if handle is not None else "a control"
            shown = repr(message.updates.get("value", message.updates))[:60]
            report(f"the value {shown} for '{label}' was refused ({type(exc).__name__}: {str(exc)[:80]}); "
                   "the control shows the value in use")
            if handle is not None:
                try:
                    gui._websock_interface.queue_message(_messages.GuiUpdateMessage(message.uuid,
                                                                                    {"value": handle.value}))
                except Exception:  # noqa: BLE001
                    log.exception("could not restore a refused GUI value")

    checked._poselifter_checked = True  # type: ignore[attr-defined]
    handlers[i] = checked
    return True


def note_typed_values(gui: viser.GuiApi, controls: dict[str, Any], note: Callable[[str], None], *,
                      client_id: int | None = None) -> bool:
    """Call ``note(name)`` for each value a browser tab sends to one of ``controls`` (name -> GUI handle), before
    viser's own handler puts the value in the control. ``client_id``: only that client's messages (None: any).
    Returns False when the hook could not be installed."""
    try:
        from viser import _messages

        handlers: dict[Any, list[Any]] = gui._websock_interface._incoming_handlers
        names = {h._impl.uuid: name for name, h in controls.items()}
    except AttributeError as exc:
        log.warning("typed-value times not hooked (viser internals changed: %s)", exc)
        return False

    def on_update(cid: int, msg: Any) -> None:
        try:
            name = names.get(msg.uuid)
            if name is not None and "value" in msg.updates and (client_id is None or cid == client_id):
                note(name)
        except Exception:  # noqa: BLE001 - never break viser's message loop
            log.exception("typed-value time not noted")

    handlers.setdefault(_messages.GuiUpdateMessage, []).insert(0, on_update)
    return True


def set_value_here(handle: Any, value: Any) -> None:
    """What ``handle.value = value`` does on the server (the value, its time, the control's update callbacks, with
    no client named: not the tab's), without sending the value to the tab. The tab goes on showing what it showed,
    so nothing lands in a box being typed in; :func:`send_value` tells it later. Without the internals: a plain
    assignment (sent)."""
    try:
        impl = handle._impl
        value = type(impl.value)(value)
        loop = impl.gui_api._event_loop
    except AttributeError as exc:
        log.warning("value sent to the tab (viser internals changed: %s)", exc)
        handle.value = value
        return
    if impl.value == value:
        return
    impl.value = value
    impl.update_timestamp = time.time()
    for cb in list(impl.update_cb):
        out = cb(viser.GuiEvent(client_id=None, client=None, target=handle))
        if asyncio.iscoroutine(out):
            asyncio.run_coroutine_threadsafe(out, loop)


def _show_in_tab(handle: Any, shown: Any) -> None:
    """Send the tab ``shown`` for the control, whatever the tab last received; the server's value is unchanged."""
    try:
        from viser import _messages

        handle._impl.gui_api._websock_interface.queue_message(
            _messages.GuiUpdateMessage(handle._impl.uuid, {"value": shown}))
    except AttributeError as exc:
        log.warning("nothing sent to the tab (viser internals changed: %s)", exc)


def send_value(handle: Any) -> None:
    """Send the control's value to the tab as it stands on the server (after :func:`set_value_here`), even when the
    tab last received the same value."""
    _show_in_tab(handle, handle.value)


def clear_box(handle: Any) -> None:
    """Send the tab an empty number box for a slider (its value on the server unchanged). A box left showing a
    number while the server's value moves on cannot take that number typed again (the browser sends nothing for
    an unchanged box; a Chromium trial's "0" typed over "0" during playback did not jump back): an empty one
    takes any. The slider's thumb goes to its start."""
    _show_in_tab(handle, "")


def drag_callback(node: Any) -> Callable[[Any], None]:
    """The first drag callback registered on a scene node (``node.on_drag``)."""
    return node._impl.drag_cb[0].callback


LOOPBACK_NAMES: frozenset[str] = frozenset({"127.0.0.1", "localhost", "::1"})
"""Host names a server bound to a loopback address answers to (:func:`guard_requests`), with every other address
:func:`is_loopback` takes (127.0.0.0/8)."""


def is_loopback(host: str) -> bool:
    """Whether ``host`` (a name or an address, IPv6 with or without brackets) is this machine's loopback: ``localhost``
    or an address in 127.0.0.0/8 or ``::1`` (a security review: a server bound to 127.0.0.2 was taken for a public one,
    and its Host check was off)."""
    import ipaddress

    h = str(host).strip().strip("[]").lower()
    if h in LOOPBACK_NAMES:
        return True
    try:
        return ipaddress.ip_address(h).is_loopback
    except ValueError:
        return False


def _host_name(value: str) -> str:
    """The host of a ``Host`` header value: ``"127.0.0.1:8080"`` -> ``"127.0.0.1"``, ``"[::1]:80"`` -> ``"::1"``."""
    v = value.strip().lower()
    if v.startswith("["):
        return v[1:v.index("]")] if "]" in v else v
    return v.rsplit(":", 1)[0] if v.count(":") == 1 else v


def request_refusal(headers: Any, *, loopback: bool) -> str | None:
    """Why a request with these HTTP ``headers`` is refused (None: it is not): on a server bound to a loopback
    address, a ``Host`` that is not a loopback name (a page of another site whose name resolves here: DNS
    rebinding); for a websocket, an ``Origin`` other than the page's own, ``http(s)://`` + its ``Host`` (a page of
    another site open in the same browser). A request without ``Origin`` (not from a browser page) is let through."""
    from urllib.parse import urlsplit

    host = headers.get("Host", "") or ""
    if loopback and not is_loopback(_host_name(host)):
        return f"Host {host!r} is not this machine's loopback name (open the app at http://127.0.0.1:PORT)"
    if (headers.get("Upgrade", "") or "").lower() == "websocket":
        origin = headers.get("Origin")
        if origin is not None and urlsplit(origin).netloc.lower() != host.lower():
            return f"a page of {origin!r} may not connect to the app at {host!r}"
    return None


def guard_requests() -> bool:
    """Make every server viser starts from now on refuse the requests :func:`request_refusal` names (HTTP 403, with
    the reason), whatever viser itself answers; idempotent. The bind address each server gets decides whether its
    ``Host`` must be a loopback name. Returns False (and logs why) when websockets' server API is not the one this
    wraps."""
    import http

    try:
        import websockets.asyncio.server as wss
    except ImportError as exc:  # (best effort, as every hook here)
        log.warning("request guard not installed: %s", exc)
        return False
    if getattr(wss.serve, "_poselifter_guard", False):
        return True
    if not hasattr(wss.ServerConnection, "respond"):
        log.warning("request guard not installed: websockets' ServerConnection has no respond()")
        return False
    original = wss.serve

    def serve(handler: Any, host: Any = None, port: Any = None, *args: Any, process_request: Any = None,
              **kwargs: Any) -> Any:
        loopback = is_loopback(str(host))

        def check(connection: Any, request: Any) -> Any:
            why = request_refusal(request.headers, loopback=loopback)
            if why is not None:
                return connection.respond(http.HTTPStatus.FORBIDDEN, f"poselifter: refused: {why}\n")
            return process_request(connection, request) if process_request is not None else None

        return original(handler, host, port, *args, process_request=check, **kwargs)

    serve._poselifter_guard = True  # type: ignore[attr-defined]
    wss.serve = serve  # type: ignore[assignment,misc]  # (viser looks it up on the module at each start)
    return True
