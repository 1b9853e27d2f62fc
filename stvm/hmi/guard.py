"""Bounds of the HMI's HTTP server (issue 34 item 4): connections, time to a complete request
head, idle keep-alive, header size, and quiet logs when a client misbehaves.

uvicorn alone keeps an idle connection that never sends a byte open for ever and, when the
process runs out of descriptors, logs a traceback for every failed accept. `GuardedH11Protocol`
(uvicorn's h11 protocol, given to `uvicorn.Config(http=…)`) adds:

* a **connection cap**: at `max_connections` open connections, a new one first closes the oldest
  connection that is idle (no request in progress: what a flood of idle sockets holds), so an
  operator's request still gets in; only if every connection is busy with a request does the new
  one get `503` with `Connection: close`. Either way descriptors never run out;
* a **header timeout**: a connection whose request head is not complete `header_timeout_s` after
  it opened (or after the first byte of a later request) is closed (slowloris, idle sockets);
* the rest are uvicorn's own settings: `timeout_keep_alive`, `h11_max_incomplete_event_size`
  (a request head larger than `max_header_bytes` gets 400) and `limit_concurrency`.

`quiet_exception_handler` replaces the event loop's handler: a failed accept or a connection reset
logs one line (at most every 10 s), never a traceback.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, fields

from uvicorn.protocols.http.h11_impl import H11Protocol

from stvm.hmi.wire import MAX_BODY_BYTES, MAX_WEBSOCKETS, WS_MAX_MESSAGE_BYTES

log = logging.getLogger("stvm.hmi")


@dataclass(frozen=True)
class ServerLimits:
    """Every bound of the HMI server; `stvm.toml` `[hmi.server]` sets them (docs/hmi.md)."""

    max_connections: int = 256         # open HTTP connections (WebSockets count separately)
    max_websockets: int = MAX_WEBSOCKETS        # open live pages
    header_timeout_s: float = 10.0     # from connect (or a request's first byte) to a complete head
    keep_alive_s: float = 5.0          # an idle connection between two requests
    max_header_bytes: int = 16 * 1024  # request line and headers
    max_body_bytes: int = MAX_BODY_BYTES   # a write's JSON body
    max_json_depth: int = 32           # nesting of a write's JSON body
    ws_max_message_bytes: int = WS_MAX_MESSAGE_BYTES

    @classmethod
    def from_table(cls, table: object) -> "ServerLimits":
        """`[hmi.server]` of stvm.toml → limits; raises ValueError naming a bad key."""
        if table is None:
            return cls()
        if not isinstance(table, dict):
            raise ValueError("[hmi.server] must be a table of limits (docs/hmi.md)")
        known = {f.name: f for f in fields(cls)}
        values = {}
        for key, value in table.items():
            spec = known.get(key)
            if spec is None:
                raise ValueError(f"[hmi.server]: unknown limit {key!r} (known: {', '.join(known)})")
            floats = spec.type in ("float", float)
            if isinstance(value, bool) or not isinstance(value, (int, float) if floats else int) \
                    or not 0 < value <= 10_000_000:
                raise ValueError(f"[hmi.server] {key} must be a positive "
                                 f"{'number' if floats else 'integer'} up to 10000000, got {value!r}")
            values[key] = float(value) if floats else value
        return cls(**values)


class GuardedH11Protocol(H11Protocol):
    """uvicorn's h11 protocol with a connection cap and a header timeout (`ServerLimits`)."""

    limits = ServerLimits()   # replaced by a subclass per server (`guarded_protocol`)
    open: dict = {}           # this server's HTTP connections, oldest first (per subclass)

    def connection_made(self, transport) -> None:
        self._header_timer = None
        self._upgraded = False
        if len(self.open) >= self.limits.max_connections:
            oldest_idle = next((c for c in self.open if not c._busy()), None)
            if oldest_idle is not None:
                self.open.pop(oldest_idle, None)
                oldest_idle._disarm()
                oldest_idle.transport.close()
        if len(self.open) >= self.limits.max_connections:
            # answered without reading: the client learns it is refused, the descriptor is freed
            try:
                transport.write(b"HTTP/1.1 503 Service Unavailable\r\nConnection: close\r\n"
                                b"Content-Type: text/plain\r\nContent-Length: 28\r\n\r\n"
                                b"too many HMI connections\r\n\r\n")
            finally:
                transport.close()
            self.transport = transport
            self.cycle = None
            self.flow = None
            return
        super().connection_made(transport)
        self.open[self] = None
        self._arm()

    def _arm(self) -> None:
        if self._header_timer is None and not self._upgraded:
            self._header_timer = self.loop.call_later(self.limits.header_timeout_s, self._header_timeout)

    def _disarm(self) -> None:
        if self._header_timer is not None:
            self._header_timer.cancel()
            self._header_timer = None

    def _busy(self) -> bool:
        return self.cycle is not None and not self.cycle.response_complete

    def _header_timeout(self) -> None:
        self._header_timer = None
        if not self._busy() and not self.transport.is_closing():
            self.transport.close()

    def data_received(self, data: bytes) -> None:
        super().data_received(data)
        if self._busy():
            self._disarm()
        else:
            self._arm()   # bytes of a request head that is not complete yet: the clock runs

    def handle_websocket_upgrade(self, event) -> None:
        self._upgraded = True   # the WebSocket protocol takes the transport over, with its own pings
        self._disarm()
        self.open.pop(self, None)
        super().handle_websocket_upgrade(event)

    def connection_lost(self, exc) -> None:
        self._disarm()
        self.open.pop(self, None)
        if self.flow is None:   # refused in connection_made
            return
        super().connection_lost(exc)


def guarded_protocol(limits: ServerLimits) -> type[GuardedH11Protocol]:
    return type("GuardedH11Protocol", (GuardedH11Protocol,), {"limits": limits, "open": {}})


_last_logged = [0.0]


def quiet_exception_handler(loop, context) -> None:
    """One line instead of a traceback for what a hostile or vanished client causes."""
    exc = context.get("exception")
    message = context.get("message", "")
    if isinstance(exc, (OSError, ConnectionError)) or "accept" in message:
        now = time.monotonic()
        if now - _last_logged[0] >= 10.0:
            _last_logged[0] = now
            log.warning("HMI server: %s%s", message, f" ({exc.__class__.__name__}: {exc})" if exc else "")
        return
    loop.default_exception_handler(context)
