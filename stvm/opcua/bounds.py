"""Limits of the OPC UA server (the manifest's `[opcua.limits]`), and the transport that enforces
the ones asyncua checks too late.

asyncua buffers a whole chunk before it looks at the chunk's size: a header that claims 2 GiB
makes it keep every byte the client sends until the connection closes. `BoundedProtocol`
reads the 8-byte header first and answers a chunk larger than `max_chunk_size` with the
protocol's own error (an ERR message, Bad_TcpMessageTooLarge, OPC UA Part 6 §7.1.5) and closes
the connection without buffering its body. Before a session is activated, a message must fit
one chunk (Hello, OpenSecureChannel, CreateSession and ActivateSession are a few KB): an
unauthenticated client holds a few small chunks of memory per connection at most
(`LOGIN_CHUNK_SIZE`, `LOGIN_QUEUE`).

The other limits are asyncua's own settings (connections, queued requests, time to log in,
session timeout) or checked by the server's service hooks (`stvm.opcua.server`): sessions,
subscriptions and monitored items per session, the publishing and sampling intervals.
"""

from __future__ import annotations

import asyncio
import logging
import struct
import time

from asyncua import ua
from asyncua.server.binary_server_asyncio import BinaryServer, OPCUAProtocol
from asyncua.ua.ua_binary import uatcp_to_binary

from stvm.opcua.config import ServerLimits

_log = logging.getLogger("stvm.opcua")
# before a session is activated (Hello, OpenSecureChannel with a certificate, CreateSession,
# ActivateSession: a few KB each), a chunk is at most this big and this many wait to be processed
LOGIN_CHUNK_SIZE = 32768
LOGIN_QUEUE = 4
_TYPES = {b"HEL", b"ACK", b"ERR", b"RHE", b"OPN", b"CLO", b"MSG"}


def apply(server, limits: ServerLimits) -> None:
    """Put the limits into asyncua's settings of `server` (before it starts)."""
    transport = server.limits
    transport.max_recv_buffer = transport.max_send_buffer = limits.max_chunk_size
    transport.max_message_size = limits.max_message_size
    transport.max_chunk_count = limits.max_chunk_count
    iserver = server.iserver
    iserver.max_connections = limits.max_connections
    iserver.max_pending_messages_per_connection = limits.max_pending_requests
    iserver.max_pending_activation_seconds = limits.login_timeout
    iserver.max_session_timeout_ms = limits.max_session_timeout * 1000.0
    iserver.min_session_timeout_ms = min(iserver.min_session_timeout_ms, iserver.max_session_timeout_ms)
    iserver.max_subscriptions = limits.max_sessions * limits.max_subscriptions_per_session
    iserver.max_monitored_item_queue_size = limits.max_queue_size


class _Inbox(asyncio.Queue):
    """A connection's queue of received chunks that says when one was taken (room again)."""

    def __init__(self, maxsize: int, on_room) -> None:
        super().__init__(maxsize)
        self._on_room = on_room

    async def get(self):
        item = await super().get()
        self._on_room()
        return item


class BoundedProtocol(OPCUAProtocol):
    """asyncua's connection, with the chunk header checked before a byte of its body is kept, and
    backpressure instead of a disconnect when the client sends more requests than
    `max_pending_requests` without waiting for the answers (asyncua's own client does, loading
    the DataType definitions): the rest stays unread in the socket until one is answered."""

    _held = b""

    def connection_made(self, transport) -> None:
        super().connection_made(transport)
        self.messages = _Inbox(self.messages.maxsize, self._room)
        if self.processor is not None:
            # asyncua builds its processor inside connection_made: give it BrowseNext (stvm.opcua.browse)
            from stvm.opcua.browse import BrowsingProcessor   # lazy: a cycle (browse imports the server's pieces)
            self.processor.__class__ = BrowsingProcessor

    def data_received(self, data: bytes) -> None:
        if self.transport is None or self.transport.is_closing():
            return
        buffered = self._buffer + data if self._buffer else data
        pos = 0
        # walk the complete and the started chunk headers; refuse the first one out of bounds
        while len(buffered) - pos >= 8:
            kind, chunk, size = buffered[pos:pos + 3], buffered[pos + 3:pos + 4], \
                struct.unpack_from("<I", buffered, pos + 4)[0]
            problem = self._problem(kind, chunk, size)
            if problem is not None:
                self._refuse(*problem)
                return
            pos += size
        self._buffer = b""
        room = self.messages.maxsize - self.messages.qsize() if self.messages.maxsize > 0 else None
        if room is not None and self._activated():
            pos = chunks = 0
            while chunks < room and len(buffered) - pos >= 8:
                size = struct.unpack_from("<I", buffered, pos + 4)[0]
                if len(buffered) - pos < size:
                    break
                pos += size
                chunks += 1
            if chunks >= room and pos < len(buffered):
                # a full queue: keep the rest and stop reading until a request is taken from it
                self._held = buffered[pos:]
                buffered = buffered[:pos]
                self.transport.pause_reading()
        super().data_received(buffered)

    def _room(self) -> None:
        if self._held and self.transport is not None and not self.transport.is_closing():
            held, self._held = self._held, b""
            asyncio.get_running_loop().call_soon(self._resume, held)

    def _resume(self, held: bytes) -> None:
        if self.transport is None or self.transport.is_closing():
            return
        self.data_received(held)
        if not self._held:
            self.transport.resume_reading()

    def _problem(self, kind: bytes, chunk: bytes, size: int) -> tuple[int, str] | None:
        limit = self.limits.max_recv_buffer
        if kind not in _TYPES or chunk not in (b"F", b"C", b"A"):
            return ua.StatusCodes.BadTcpMessageTypeInvalid, "not an OPC UA message"
        if size < 8:
            return ua.StatusCodes.BadTcpMessageTypeInvalid, "a chunk shorter than its header"
        if size > limit:
            return ua.StatusCodes.BadTcpMessageTooLarge, f"a chunk of {size} bytes (the limit is {limit})"
        if not self._activated():
            if size > LOGIN_CHUNK_SIZE:
                return ua.StatusCodes.BadTcpMessageTooLarge, f"a chunk of {size} bytes before login"
            if chunk == b"C":
                return ua.StatusCodes.BadTcpMessageTooLarge, "a message of several chunks before login"
            if self.messages.qsize() >= LOGIN_QUEUE:
                return ua.StatusCodes.BadTcpNotEnoughResources, "too many requests queued before login"
        return None

    def _activated(self) -> bool:
        session = self.processor.session if self.processor is not None else None
        return session is not None and session.is_activated()

    def _refuse(self, status: int, why: str) -> None:
        self._buffer = b""
        log_limited(f"OPC UA client {self.peer_name} refused: {why}")
        try:
            self.transport.write(uatcp_to_binary(ua.MessageType.Error, ua.ErrorMessage(ua.StatusCode(status), why)))
        finally:
            self.transport.close()


class BoundedBinaryServer(BinaryServer):
    def _make_protocol(self) -> OPCUAProtocol:
        return BoundedProtocol(iserver=self.iserver, policies=self._policies, clients=self.clients,
                               closing_tasks=self.closing_tasks, limits=self.limits)


_LOG_WINDOW_S = 10.0
_LOG_PER_WINDOW = 20
_log_window = [0.0, 0, 0]   # window start, lines logged in it, lines dropped


def log_limited(message: str) -> None:
    """One warning line, at most `_LOG_PER_WINDOW` per `_LOG_WINDOW_S`: a hostile client cannot
    flood the terminal the scan loop reports to."""
    now = time.monotonic()
    if now - _log_window[0] > _LOG_WINDOW_S:
        if _log_window[2]:
            _log.warning("%d more OPC UA refusals not shown", _log_window[2])
        _log_window[:] = [now, 0, 0]
    if _log_window[1] < _LOG_PER_WINDOW:
        _log_window[1] += 1
        _log.warning("%s", message)
    else:
        _log_window[2] += 1


class OneLine(logging.Filter):
    """asyncua's log records as one line without the traceback, rate-limited like `log_limited`:
    malformed requests are answered with a status code, and the terminal shows one line at most."""

    def filter(self, record: logging.LogRecord) -> bool:
        if record.exc_info:
            exc = record.exc_info[1]
            record.msg = f"{record.getMessage()}: {type(exc).__name__}: {exc}" if exc else record.getMessage()
            record.args = None
            record.exc_info = None
            record.exc_text = None
        if record.levelno >= logging.WARNING:
            now = time.monotonic()
            if now - _log_window[0] > _LOG_WINDOW_S:
                _log_window[:] = [now, 0, 0]
            if _log_window[1] >= _LOG_PER_WINDOW:
                _log_window[2] += 1
                return False
            _log_window[1] += 1
        return True
