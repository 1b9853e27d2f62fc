"""Omron TCP socket instructions on a pluggable transport (sysmac.md 4 and 5).

Three layers:

* `Link`: one byte-stream connection, polled, never blocking. `TcpLink` is a non-blocking Python
  socket; an in-process robot emulator provides its own (lockstep runs).
* `SocketTable`: what the controller's socket service keeps per handle, the same whatever the link:
  handle numbers 1, 2, 3, … (never reused, so a stale handle is always "closed"), at most 16 open
  sockets, a 9,000-byte receive buffer whose overflow is discarded, the TCP state. It implements the
  `Transport` interface the FBs use; `RealTcpTransport` is a `SocketTable` of `TcpLink`s.
* the six FBs (`SktTCPConnect`, `SktTCPSend`, `SktTCPRcv`, `SktClearBuf`, `SktGetTCPStatus`,
  `SktClose`) with the Execute/Done/Busy/Error protocol of section 4, one poll per call: a scan never
  blocks. Every failure becomes Error + ErrorID (`skt_error_codes`), never a Python exception.

`RealTcpTransport.serve_between_scans(vm)` moves the network I/O out of the FB calls into the VM's
scan hooks: one `poll(0)` of all sockets before each scan, the queued sends after it; an FB's
`poll` then reads the state the service left. Every `stvm run` asks for it (`ctx.socket_service_vm`).

The FBs use `ctx.transport`, creating `make_default_transport()` there when it is None; the VM calls
`ctx.transport.close_all()` at the end of a run. The 75 s connect limit and receive timeouts run on
the VM clock (`ctx.now_ns`).
"""

from __future__ import annotations

import errno
import ipaddress
import select
import socket
import time
from dataclasses import dataclass, field
from typing import Callable, Protocol

from stvm.lower.bind import st_names
from stvm.runtime.values import FunctionError
from stvm.stdlib.omron import as_array_ref
from stvm.stdlib.registry import native_fb
from stvm.settings import (
    SktConnectSrcport0, SktErrorIdReset, SktProgressWithoutCall, SktRcvPeerClosed, SktRcvTimeout0,
    SktSendCopy, SktSendSize0, SktSocketAfterClose, SktStatusClosedHandle,
)

# The setting values the FBs compare with, as module constants: reading an Enum member through
# its class costs ~170 ns on Python 3.11 (a descriptor), a global ~15 ns, and some of these
# comparisons run at every call of an FB, every scan.
_CANCEL = SktProgressWithoutCall.CANCEL
_START_AND_CLEAR = SktErrorIdReset.START_AND_CLEAR
_ZEROED = SktSocketAfterClose.ZEROED
_SRCPORT0_ERROR = SktConnectSrcport0.ERROR
_STATUS_CLOSED_ERROR = SktStatusClosedHandle.ERROR
_SIZE0_ERROR = SktSendSize0.ERROR
_COPY_AT_START = SktSendCopy.AT_START
_PEER_CLOSED_ERROR = SktRcvPeerClosed.ERROR
_TIMEOUT0_ERROR_IF_EMPTY = SktRcvTimeout0.ERROR_IF_EMPTY

MAX_SOCKETS = 16                       # sysmac.md 5, CONFIRMED
RECEIVE_BUFFER_BYTES = 9_000           # per socket, overflow discarded (CONFIRMED)
RECEIVE_MAX_BYTES = 2_000              # per SktTCPRcv (CONFIRMED)
CONNECT_TIMEOUT_NS = 75 * 1_000_000_000  # SYN resent up to 4 times, error 75 s after start

# Link states (what the connection is doing; mapped to `_eCONNECTION_STATE` names below)
CONNECTING = "connecting"
ESTABLISHED = "established"
PEER_CLOSED = "peer_closed"   # FIN received: _CLOSE_WAIT until SktClose
RESET = "reset"               # RST received (or the connection broke): _CLOSED
FAILED = "failed"             # the connect did not succeed (`Link.failure` says why)

STATE_NAMES = {CONNECTING: "_SYN_SENT", ESTABLISHED: "_ESTABLISHED", PEER_CLOSED: "_CLOSE_WAIT",
               RESET: "_CLOSED", FAILED: "_CLOSED"}


class SocketError(Exception):
    """A socket request failed; `kind` is a key of `SysmacSettings.skt_error_codes`."""

    def __init__(self, kind: str, detail: str = "") -> None:
        super().__init__(f"{kind}: {detail}" if detail else kind)
        self.kind = kind


# --- links ------------------------------------------------------------------------------------

class Link(Protocol):
    """One TCP connection as the socket service sees it.

    `state` is one of the link states above; `failure` the error kind once FAILED;
    `local_address`/`remote_address` are (ip, port) once established.
    """

    state: str
    failure: str | None
    local_address: tuple[str, int]
    remote_address: tuple[str, int]

    def poll(self, now_ns: int) -> bytes:
        """Advance the connection (connect progress, flush queued sends) and return the bytes
        received since the last poll. Never blocks."""

    def send(self, data: bytes) -> None:
        """Queue `data` for sending; raise SocketError('wrong_state') if the connection broke."""

    def close(self) -> None:
        """Discard what is buffered and close gracefully (FIN)."""


LinkFactory = Callable[[int, str, int, int], Link]
"""`open_link(src_port, host, port, now_ns)`: start connecting; raise SocketError for
`port_in_use`, `unresolvable` or `wrong_state` when that is known at once."""


def resolve_ipv4(host: str) -> str:
    """A dotted IPv4 address for DstAdr; host names go through the resolver.

    Choice: a name lookup may block briefly (DNS); dotted addresses never do.
    """
    try:
        return str(ipaddress.IPv4Address(host))
    except ValueError:
        pass
    if not host:
        raise SocketError("unresolvable", "empty destination address")
    try:
        return socket.getaddrinfo(host, None, socket.AF_INET, socket.SOCK_STREAM)[0][4][0]
    except (OSError, UnicodeError) as error:
        raise SocketError("unresolvable", f"{host!r}: {error}") from None


_IN_PROGRESS = {0, errno.EINPROGRESS, errno.EWOULDBLOCK, errno.EALREADY, errno.EAGAIN}
_READ_LIMIT_PER_POLL = 1 << 20  # bytes read from the OS per poll; beyond 9,000 they are discarded
# one receive buffer for every TcpLink (recv_into, then a bytes copy of what came: no 64 KiB
# allocation per recv). Polls run in one thread at a time (the VM's), so sharing it is safe.
_RECV_CHUNK = memoryview(bytearray(65_536))


def _failure_kind(code: int) -> str:
    return "timeout" if code == errno.ETIMEDOUT else "wrong_state"


class TcpLink:
    """A non-blocking client socket, advanced by `poll`.

    `flush_later` True (set by the socket service between scans): `send` only queues, `flush`
    sends; False: `send` sends at once."""

    def __init__(self, src_port: int, host: str, port: int, now_ns: int,
                 flush_later: bool = False) -> None:
        address = resolve_ipv4(host)
        self.flush_later = flush_later
        self.state = CONNECTING
        self.failure: str | None = None
        self.local_address = ("", 0)
        self.remote_address = (address, port)
        self._unsent = bytearray()
        self._sock: socket.socket | None = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        try:
            self._sock.setblocking(False)
            if src_port:
                try:
                    self._sock.bind(("", src_port))
                except OSError as error:
                    kind = "port_in_use" if error.errno == errno.EADDRINUSE else "wrong_state"
                    raise SocketError(kind, f"bind to port {src_port}: {error}") from None
            code = self._sock.connect_ex((address, port))
        except BaseException:
            self._release()
            raise
        if code not in _IN_PROGRESS:
            self._fail(_failure_kind(code))
        elif code == 0:
            self._established()

    # connection progress

    def _established(self) -> None:
        self.state = ESTABLISHED
        try:
            self.local_address = self._sock.getsockname()[:2]
        except OSError:
            pass

    def _fail(self, kind: str) -> None:
        self.state, self.failure = FAILED, kind
        self._release()

    def _reset(self) -> None:
        # RFC 793: on RST "all segment queues should be flushed"
        self.state = RESET
        self._unsent.clear()
        self._release()

    def _release(self) -> None:
        if self._sock is not None:
            try:
                self._sock.close()
            except OSError:
                pass
            self._sock = None

    def poll(self, now_ns: int) -> bytes:
        if self.state == CONNECTING:
            _, writable, broken = select.select([], [self._sock], [self._sock], 0)
            if not (writable or broken):
                return b""
            code = self._sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if code:
                self._fail(_failure_kind(code))
                return b""
            self._established()
        if self.state not in (ESTABLISHED, PEER_CLOSED):
            return b""
        self._flush()
        if self.state != ESTABLISHED:
            return b""  # after FIN nothing more arrives; after RST nothing is kept
        received = b""
        chunk = _RECV_CHUNK
        while len(received) < _READ_LIMIT_PER_POLL:
            try:
                count = self._sock.recv_into(chunk)
            except (BlockingIOError, InterruptedError):
                break
            except OSError:
                self._reset()
                return b""
            if not count:
                self.state = PEER_CLOSED
                break
            received = received + chunk[:count] if received else bytes(chunk[:count])
            if count < len(chunk):
                # the kernel had no more at this instant: what comes later is read at the next
                # poll (saves the recv that would only raise BlockingIOError)
                break
        return received

    def _flush(self) -> None:
        while self._unsent and self._sock is not None:
            try:
                sent = self._sock.send(self._unsent)
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                self._reset()
                return
            del self._unsent[:sent]

    def send(self, data: bytes) -> None:
        if self.state not in (ESTABLISHED, PEER_CLOSED):
            raise SocketError("wrong_state", f"send while {self.state}")
        # Choice: the send buffer is unbounded; Omron's fills up and keeps SktTCPSend Busy
        self._unsent += data
        if self.flush_later:
            # the socket service sends it at the end of the scan (`flush`). Choice: a reset found
            # then shows from the next scan on (status _CLOSED, later requests fail); this send is
            # Done already, as on the controller, where Done means "in the send buffer"
            return
        self._flush()
        if self.state == RESET:
            raise SocketError("wrong_state", "connection reset by peer")

    @property
    def unsent(self) -> int:
        return len(self._unsent)

    def flush(self) -> None:
        """Send what is queued, as far as the OS takes it now (never blocks)."""
        if self.state in (ESTABLISHED, PEER_CLOSED):
            self._flush()

    def fileno(self) -> int:
        """The OS socket's descriptor; -1 once released."""
        return self._sock.fileno() if self._sock is not None else -1

    def close(self) -> None:
        if self._sock is None:
            return
        self._unsent.clear()  # sysmac.md 5: SktClose discards buffered send/receive data
        try:
            # read what is left, so that the OS closes with FIN rather than RST (bounded: a peer
            # that keeps sending cannot hold the scan)
            for _ in range(_READ_LIMIT_PER_POLL // 65_536):
                if not self._sock.recv(65_536):
                    break
        except OSError:
            pass
        try:
            self._sock.shutdown(socket.SHUT_WR)
        except OSError:
            pass
        self._release()


# --- the socket service -----------------------------------------------------------------------

class Transport(Protocol):
    """The socket service the FBs talk to (one per VM run, `ctx.transport`).

    Handles are ints ≥ 1. `open_connection` starts a connect; `poll` advances one handle and
    returns its link state; data arrives in the handle's receive buffer. Unknown handles, handles
    released after a failed connect and handles closed by `close` raise SocketError('bad_handle')
    (`was_closed` tells the last apart).
    """

    def open_connection(self, src_port: int, host: str, port: int, now_ns: int) -> int: ...
    def poll(self, handle: int, now_ns: int) -> str: ...
    def failure(self, handle: int) -> str | None: ...
    def addresses(self, handle: int) -> tuple[tuple[str, int], tuple[str, int]]: ...
    def pending(self, handle: int) -> int: ...
    def receive(self, handle: int, max_bytes: int) -> bytes: ...
    def clear(self, handle: int) -> None: ...
    def send(self, handle: int, data: bytes) -> None: ...
    def close(self, handle: int) -> None: ...
    def release(self, handle: int) -> None: ...
    def was_closed(self, handle: int) -> bool: ...
    def poll_all(self, now_ns: int) -> None: ...
    def close_all(self) -> None: ...


@dataclass
class _OpenSocket:
    link: Link
    received: bytearray = field(default_factory=bytearray)
    discarded_bytes: int = 0


class SocketTable:
    """Handles, limits and receive buffers over any `LinkFactory` (implements `Transport`)."""

    def __init__(self, open_link: LinkFactory, max_sockets: int = MAX_SOCKETS,
                 receive_buffer_bytes: int = RECEIVE_BUFFER_BYTES) -> None:
        self._open_link = open_link
        self.max_sockets = max_sockets
        self.receive_buffer_bytes = receive_buffer_bytes
        self._sockets: dict[int, _OpenSocket] = {}
        self._closed: set[int] = set()
        self._next_handle = 1
        # True once a socket service runs between the scans (`RealTcpTransport.serve_between_scans`):
        # `poll` then reports the state that service left and does no I/O itself
        self.between_scans = False

    def _get(self, handle: int) -> _OpenSocket:
        entry = self._sockets.get(handle)
        if entry is None:
            detail = "closed by SktClose" if handle in self._closed else "not a socket handle"
            raise SocketError("bad_handle", f"handle {handle}: {detail}")
        return entry

    @property
    def open_count(self) -> int:
        return len(self._sockets)

    def open_connection(self, src_port: int, host: str, port: int, now_ns: int) -> int:
        if len(self._sockets) >= self.max_sockets:
            raise SocketError("too_many_sockets", f"{self.max_sockets} sockets are open")
        link = self._open_link(src_port, host, port, now_ns)
        handle = self._next_handle
        self._next_handle += 1
        self._sockets[handle] = _OpenSocket(link)
        return handle

    def poll(self, handle: int, now_ns: int) -> str:
        entry = self._get(handle)
        if self.between_scans:
            return entry.link.state   # the service polled every socket before this scan
        self._pull(entry, now_ns)
        return entry.link.state

    def _pull(self, entry: _OpenSocket, now_ns: int) -> None:
        """Advance one link and move what it received into the handle's buffer."""
        data = entry.link.poll(now_ns)
        if entry.link.state == RESET:
            entry.received.clear()  # RFC 793: a reset flushes the queues
        elif data:
            room = self.receive_buffer_bytes - len(entry.received)
            entry.received += data[:max(room, 0)]
            entry.discarded_bytes += max(len(data) - max(room, 0), 0)  # sysmac.md 5: discarded

    def failure(self, handle: int) -> str | None:
        return self._get(handle).link.failure

    def addresses(self, handle: int) -> tuple[tuple[str, int], tuple[str, int]]:
        link = self._get(handle).link
        return link.local_address, link.remote_address

    def pending(self, handle: int) -> int:
        return len(self._get(handle).received)

    def quiet_receive(self, handle: int) -> bool:
        """Whether a receive on `handle` would find nothing, with nothing changing: `poll` would
        return ESTABLISHED without I/O (a service runs between the scans) and nothing is
        buffered. A busy SktTCPRcv asks this before its full call (`SktTCPRcv.call`)."""
        entry = self._sockets.get(handle)
        return (self.between_scans and entry is not None and not entry.received
                and entry.link.state == ESTABLISHED)

    def discarded(self, handle: int) -> int:
        return self._get(handle).discarded_bytes

    def receive(self, handle: int, max_bytes: int) -> bytes:
        entry = self._get(handle)
        data = bytes(entry.received[:max_bytes])
        del entry.received[:max_bytes]
        return data

    def clear(self, handle: int) -> None:
        self._get(handle).received.clear()

    def send(self, handle: int, data: bytes) -> None:
        self._get(handle).link.send(data)

    def close(self, handle: int) -> None:
        entry = self._get(handle)
        del self._sockets[handle]
        self._closed.add(handle)
        entry.link.close()

    def release(self, handle: int) -> None:
        """Forget a handle whose connect failed or was abandoned (it was never valid to ST)."""
        entry = self._sockets.pop(handle, None)
        if entry is not None:
            entry.link.close()

    def was_closed(self, handle: int) -> bool:
        return handle in self._closed

    def poll_all(self, now_ns: int) -> None:
        """Advance every socket (the FBs poll on their own unless a service runs between scans)."""
        for entry in list(self._sockets.values()):
            self._pull(entry, now_ns)

    def close_all(self) -> None:
        for handle in list(self._sockets):
            self.close(handle)


class RealTcpTransport(SocketTable):
    """The socket service on the host's TCP stack.

    Alone, every FB call polls its socket (a recv, a select while connecting). Wired to a VM by
    `serve_between_scans(vm)`, it works as the controller's system service does (sysmac.md 1:
    "socket requests run in system services and progress between calls"): before each scan one
    `poll(0)` over all sockets, and a read or a connect check only for those it reports ready;
    after each scan, the sends the FBs queued. The programs then make no system call for a
    socket that is just waiting (most scans), and the scan never blocks either way.
    """

    def __init__(self, max_sockets: int = MAX_SOCKETS,
                 receive_buffer_bytes: int = RECEIVE_BUFFER_BYTES) -> None:
        super().__init__(self._open_tcp_link, max_sockets, receive_buffer_bytes)
        self._poller = select.poll()
        self._watched: dict[int, int] = {}      # fd -> handle, as registered in `_poller`
        self._watch_stale = True                # a socket opened, closed or changed state
        self._to_flush: set[int] = set()        # handles with queued sends
        self.service_ns = None                  # TimingStats of the service's time per scan
        self._before_ns = 0                     # this scan's receive part of it

    def _open_tcp_link(self, src_port: int, host: str, port: int, now_ns: int) -> TcpLink:
        link = TcpLink(src_port, host, port, now_ns, flush_later=self.between_scans)
        self._watch_stale = True
        return link

    # --- the service between scans

    def serve_between_scans(self, vm) -> None:
        """Run the socket service in `vm`'s scan hooks: receive before each scan (its last
        `on_scan_start` hook, after the run control's), send right after the programs (the first
        `on_scan_end` hook). Its time per scan goes to `service_ns`, apart from the ST time."""
        from stvm.runtime.stats import TimingStats   # lazy: start-up
        self.between_scans = True
        for entry in self._sockets.values():
            entry.link.flush_later = True
        self.service_ns = TimingStats()
        vm.on_scan_start.append(self._before_scan)
        vm.on_scan_end.insert(0, self._after_scan)

    def _before_scan(self, vm) -> None:
        started = time.perf_counter_ns()
        if self._sockets:
            if self._watch_stale:
                self._rewatch()
            sockets, watched = self._sockets, self._watched
            for fd, _events in self._poller.poll(0):
                entry = sockets.get(watched.get(fd, 0))
                if entry is None:
                    continue
                state = entry.link.state
                self._pull(entry, vm.now_ns)
                if entry.link.state != state:
                    self._watch_stale = True
        self._before_ns = time.perf_counter_ns() - started

    def _after_scan(self, vm) -> None:
        started = time.perf_counter_ns()
        if self._to_flush:
            for handle in list(self._to_flush):
                entry = self._sockets.get(handle)
                if entry is None:
                    self._to_flush.discard(handle)
                    continue
                link = entry.link
                link.flush()
                if link.state == RESET:
                    entry.received.clear()   # RFC 793: a reset flushes the queues
                    self._watch_stale = True
                if not link.unsent or link.state not in (ESTABLISHED, PEER_CLOSED):
                    self._to_flush.discard(handle)   # else: the rest after the next scan
        self.service_ns.add(self._before_ns + time.perf_counter_ns() - started)
        self._before_ns = 0

    def _rewatch(self) -> None:
        """Register exactly the sockets that can become ready: connecting ones for writability
        (connected or failed), established ones for reading. A new poll object each time, so a
        descriptor number reused by a new socket never keeps an old registration."""
        poller = select.poll()
        watched: dict[int, int] = {}
        for handle, entry in self._sockets.items():
            link = entry.link
            if link.state == CONNECTING:
                mask = select.POLLOUT
            elif link.state == ESTABLISHED:
                mask = select.POLLIN
            else:
                continue   # after FIN nothing more is read; failed and reset links are released
            fd = link.fileno()
            if fd >= 0:
                poller.register(fd, mask)
                watched[fd] = handle
        self._poller, self._watched = poller, watched
        self._watch_stale = False

    # --- requests that change what is watched or queued

    def send(self, handle: int, data: bytes) -> None:
        super().send(handle, data)
        if self.between_scans:
            self._to_flush.add(handle)

    def close(self, handle: int) -> None:
        entry = self._sockets.get(handle)
        if entry is not None and self.between_scans:
            # what an FB of this scan queued goes out before the FIN, as it would have had it
            # been sent at once (per-call mode)
            entry.link.flush()
        super().close(handle)
        self._watch_stale = True

    def release(self, handle: int) -> None:
        super().release(handle)
        self._watch_stale = True


def make_default_transport() -> Transport:
    return RealTcpTransport()


def socket_service_us(vm):
    """(mean, p50, p99, max) µs of `vm`'s socket service per scan, or None (none runs between scans)."""
    from stvm.runtime.vm import timing_us   # lazy: start-up
    stats = getattr(vm.ctx.transport, "service_ns", None)
    return timing_us(stats) if stats is not None else None


def transport_of(ctx) -> Transport:
    """The run's socket service, made at the first socket FB call that needs it; in a run that
    names a VM to serve (`ctx.socket_service_vm`, what `stvm run` does) it runs between that VM's
    scans, as on the controller, so a program without socket FBs pays nothing a scan."""
    if ctx.transport is None:
        transport = ctx.transport = make_default_transport()
        if ctx.socket_service_vm is not None:
            transport.serve_between_scans(ctx.socket_service_vm)
    return ctx.transport


# --- the Execute protocol (sysmac.md 4) --------------------------------------------------------

IDLE, BUSY, HELD, SHOWN_ONCE = "idle", "busy", "held", "shown_once"
DONE = "done"


@st_names("Execute", "Done", "Busy", "Error", "ErrorID")
class SocketRequestFB:
    """Execute/Done/Busy/Error across calls, exactly as sysmac.md 4 says.

    Per call: an edge (Execute TRUE now, FALSE at this instance's previous call) while idle latches
    the inputs and starts the request (Busy TRUE, Done/Error FALSE, ErrorID 0). While busy, edges
    are ignored; completion is possible at a call at least `skt_min_latency_calls` after the
    starting call. Completed with Execute TRUE: Done/Error held until a call with Execute FALSE
    clears them; with Execute already FALSE: TRUE for that one call only.

    Subclasses implement `_start` (latch inputs, start the work; raise SocketError for errors found
    at once, reported at completion) and `_progress` (None while waiting, DONE, or an error kind).

    `quiet` (the `{native quiet:Execute}` of sockets.st): the value of Execute for which the next
    call would change nothing, None when any call may. Idle, a call changes only the memory of
    Execute, so that value is the remembered one; with Done or Error held, it is TRUE. The
    generated call site skips the call while `inst.Execute is impl.quiet` (most calls of the
    thesis's FBs: they call their socket FBs every scan). A skipped call would have kept `quiet`
    as it is.
    """

    def __init__(self) -> None:
        self._previous_execute = False
        self._phase = IDLE
        self._calls_since_start = 0
        self._start_error: str | None = None
        self._last_scan: int | None = None
        self.quiet: bool | None = False

    def call(self, inst, ctx) -> None:
        execute = True if inst.Execute else False   # bool() without a call: ~30 calls a scan
        if self._phase is IDLE and (not execute or self._previous_execute):
            # idle and no rising edge: nothing changes but the memory of this call. `_last_scan`
            # is read only while BUSY, and the call that makes a request BUSY sets it: not
            # stored here
            self._previous_execute = self.quiet = execute
            return
        settings = ctx.settings
        edge = execute and not self._previous_execute
        self._previous_execute = execute
        if (self._phase == HELD and not execute) or self._phase == SHOWN_ONCE:
            self._clear_outputs(inst, settings)
        if (self._phase == BUSY and settings.skt_progress_without_call is _CANCEL
                and self._last_scan is not None and ctx.scan > self._last_scan + 1):
            # `skt_progress_without_call = cancel`: a request not called in some scan is dropped
            self._guarded(self._cancel, inst, ctx)
            inst.Busy = False
            self._phase = IDLE
        if self._phase == IDLE and edge:
            inst.Busy = True
            inst.Done = inst.Error = False
            inst.ErrorID = 0
            self._phase = BUSY
            self._last_scan = ctx.scan
            self._calls_since_start = 0
            self._start_error = self._guarded(self._start, inst, ctx)
        elif self._phase == BUSY:
            self._last_scan = ctx.scan   # read by the next call only while BUSY
            self._calls_since_start += 1
        if self._phase == BUSY and self._calls_since_start >= settings.skt_min_latency_calls:
            outcome = self._start_error or self._guarded(self._progress, inst, ctx)
            if outcome is not None:
                self._complete(inst, ctx, outcome, execute)
        # HELD (Done or Error shown, Execute TRUE): a call with Execute TRUE changes nothing
        self.quiet = execute if self._phase is IDLE or self._phase is HELD else None

    def _guarded(self, step, inst, ctx) -> str | None:
        """Run a step; a failure becomes an error kind, never an exception out of the FB."""
        transport = ctx.transport   # `transport_of` without its call once made (a busy FB: every scan)
        try:
            return step(inst, ctx, transport if transport is not None else transport_of(ctx))
        except SocketError as error:
            return error.kind
        except FunctionError:
            return "too_few_elements"  # the array passed is shorter than the data
        except OSError:
            return "wrong_state"

    def _complete(self, inst, ctx, outcome: str, execute: bool) -> None:
        inst.Busy = False
        if outcome == DONE:
            inst.Done = True
        else:
            inst.Error = True
            # Choice: a kind missing from a user-supplied table reports 16#2003 (wrong state)
            inst.ErrorID = ctx.settings.skt_error_codes.get(outcome, 0x2003)
        self._phase = HELD if execute else SHOWN_ONCE

    def _clear_outputs(self, inst, settings) -> None:
        inst.Done = False
        if inst.Error and settings.skt_errorid_reset is _START_AND_CLEAR:
            inst.ErrorID = 0
        inst.Error = False
        self._phase = IDLE

    # subclass hooks

    def _start(self, inst, ctx, transport: Transport) -> None:
        raise NotImplementedError

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        raise NotImplementedError

    def _cancel(self, inst, ctx, transport: Transport) -> None:
        return None


@st_names("Socket", "Handle")
def _handle_of(inst) -> int:
    return inst.Socket.Handle


def _require_open(transport: Transport, handle: int, now_ns: int) -> str:
    """The handle's link state; bad_handle for 0, unknown or closed handles."""
    if handle == 0:
        raise SocketError("bad_handle", "handle 0")
    return transport.poll(handle, now_ns)


def _require_connected(transport: Transport, handle: int, now_ns: int) -> None:
    state = _require_open(transport, handle, now_ns)
    if state not in (ESTABLISHED, PEER_CLOSED):
        raise SocketError("wrong_state", f"socket is {state}")


@native_fb("SktTCPConnect")
@st_names("Socket", "Handle", "SrcTcpPort", "DstAdr", "DstTcpPort")
class SktTCPConnect(SocketRequestFB):
    """Active open; Done when established, with the Socket output filled (sysmac.md 5)."""

    def __init__(self) -> None:
        super().__init__()
        self._handle = 0
        self._start_ns = 0
        # the handle this FB wrote to Socket, kept only under `skt_socket_after_close = zeroed`
        # (0 otherwise: then a connected FB's call, every scan, checks nothing more)
        self._published_handle = 0

    def call(self, inst, ctx) -> None:
        SocketRequestFB.call(self, inst, ctx)   # not super(): this runs every scan
        if self._published_handle:
            if inst.Socket.Handle == self._published_handle \
                    and self._transport_closed(ctx, self._published_handle):
                _write_socket(inst.Socket, 0, ("", 0), ("", 0))
                self._published_handle = 0
            else:
                self.quiet = None   # every call checks whether the transport closed the socket

    @staticmethod
    def _transport_closed(ctx, handle: int) -> bool:
        return ctx.transport is not None and ctx.transport.was_closed(handle)

    def _start(self, inst, ctx, transport: Transport) -> None:
        self._handle = 0
        self._start_ns = ctx.now_ns
        if inst.DstTcpPort == 0:
            raise SocketError("out_of_range", "DstTcpPort 0")
        if inst.SrcTcpPort == 0 and ctx.settings.skt_connect_srcport0 is _SRCPORT0_ERROR:
            raise SocketError("out_of_range", "SrcTcpPort 0")
        host = inst.DstAdr.decode("latin-1").strip()
        self._handle = transport.open_connection(inst.SrcTcpPort, host, inst.DstTcpPort,
                                                 ctx.now_ns)

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        state = transport.poll(self._handle, ctx.now_ns)
        if state in (ESTABLISHED, PEER_CLOSED):
            local, remote = transport.addresses(self._handle)
            _write_socket(inst.Socket, self._handle, local, remote)
            if ctx.settings.skt_socket_after_close is _ZEROED:
                self._published_handle = self._handle
            return DONE
        if state == CONNECTING and ctx.now_ns - self._start_ns < CONNECT_TIMEOUT_NS:
            return None
        kind = transport.failure(self._handle) if state == FAILED else None
        if state == CONNECTING:
            kind = "timeout"  # 75 s after start (CONFIRMED), on the VM clock
        transport.release(self._handle)
        return kind or "wrong_state"

    def _guarded(self, step, inst, ctx) -> str | None:
        outcome = super()._guarded(step, inst, ctx)
        if outcome not in (None, DONE) and self._handle:
            # every failed connect gives its socket back (issue 4: "the socket is released")
            transport_of(ctx).release(self._handle)
            self._handle = 0
        return outcome

    def _cancel(self, inst, ctx, transport: Transport) -> None:
        if self._handle:
            transport.release(self._handle)
            self._handle = 0


@st_names("Handle", "SrcAdr", "DstAdr", "IpAdr", "PortNo")
def _write_socket(socket_value, handle: int, local: tuple[str, int], remote: tuple[str, int]) -> None:
    socket_value.Handle = handle
    socket_value.SrcAdr.IpAdr = local[0].encode()
    socket_value.SrcAdr.PortNo = local[1]
    socket_value.DstAdr.IpAdr = remote[0].encode()
    socket_value.DstAdr.PortNo = remote[1]


@native_fb("SktClearBuf")
class SktClearBuf(SocketRequestFB):
    """Discard the received, unread bytes; later bytes are kept (sysmac.md 5).

    Choice: the service clears when the request starts (as the controller's system service does,
    between calls); the result shows at completion.
    """

    def _start(self, inst, ctx, transport: Transport) -> None:
        handle = _handle_of(inst)
        _require_open(transport, handle, ctx.now_ns)  # pulls in what has arrived so far
        transport.clear(handle)

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        return DONE


@native_fb("SktGetTCPStatus")
@st_names("TcpStatus", "DatRcvFlag")
class SktGetTCPStatus(SocketRequestFB):
    """TCP state and DatRcvFlag, as a snapshot at completion (sysmac.md 5)."""

    def _start(self, inst, ctx, transport: Transport) -> None:
        self._handle = _handle_of(inst)

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        names = ctx.settings.connection_state_values
        if transport.was_closed(self._handle):
            # a handle once valid, now closed (`skt_status_closed_handle`)
            if ctx.settings.skt_status_closed_handle is _STATUS_CLOSED_ERROR:
                return "bad_handle"
            inst.TcpStatus = names.get("_CLOSED", 0)
            inst.DatRcvFlag = False
            return DONE
        state = _require_open(transport, self._handle, ctx.now_ns)
        # a state missing from a user-supplied table shows as _CLOSED
        inst.TcpStatus = names.get(STATE_NAMES[state], names.get("_CLOSED", 0))
        inst.DatRcvFlag = transport.pending(self._handle) > 0
        return DONE


@native_fb("SktTCPSend")
@st_names("Size", "SendDat")
class SktTCPSend(SocketRequestFB):
    """Send Size bytes from SendDat; Done once they are in the send buffer (sysmac.md 5)."""

    def _start(self, inst, ctx, transport: Transport) -> None:
        settings = ctx.settings
        self._handle = _handle_of(inst)
        self._size = inst.Size
        self._data: bytes | None = None
        if self._size > settings.skt_send_max:
            raise SocketError("out_of_range", f"Size {self._size} > {settings.skt_send_max}")
        if self._size == 0 and settings.skt_send_size0 is _SIZE0_ERROR:
            raise SocketError("out_of_range", "Size 0")
        source = as_array_ref(inst.SendDat)
        if self._size > len(source):
            raise SocketError("too_few_elements", f"Size {self._size} > {len(source)} elements")
        _require_connected(transport, self._handle, ctx.now_ns)
        if settings.skt_send_copy is _COPY_AT_START:
            self._data = bytes(source.read(self._size))
            self._send(transport)

    def _send(self, transport: Transport) -> None:
        if self._data:  # Size 0: Done, nothing sent (`skt_send_size0 = done`)
            transport.send(self._handle, self._data)

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        if self._data is None:  # `skt_send_copy = at_service`: the bytes as they are now
            source = as_array_ref(inst.SendDat)
            if self._size > len(source):
                return "too_few_elements"
            self._data = bytes(source.read(self._size))
            _require_connected(transport, self._handle, ctx.now_ns)
            self._send(transport)
        return DONE


@native_fb("SktTCPRcv")
@st_names("TimeOut", "Size", "RcvDat", "RcvSize")
class SktTCPRcv(SocketRequestFB):
    """Take min(available, Size, 2000) bytes once at least one is buffered (sysmac.md 5)."""

    # set by `_start` once the request is under way without an error on a `SocketTable`
    # (whose `quiet_receive` `call` asks), with what `call` compares with
    _probe = False

    def call(self, inst, ctx) -> None:
        # A request waiting for bytes that have not come (every scan of a robot's motion): when
        # the transport says nothing arrived and nothing changed (`quiet_receive`), the full call
        # would only note the call (Execute, scan, count) and return with the request BUSY: the
        # latency is served, it is not cancelled (called in the next scan, or no cancelling), the
        # timeout has not run out and the link is established with nothing buffered.
        if self._probe and self._phase is BUSY and self._calls_since_start >= self._calls_before_progress:
            scan = ctx.scan
            if (scan <= self._last_scan + 1 or not self._cancel_unpolled) and ctx.now_ns < self._waits_until_ns \
                    and ctx.transport.quiet_receive(self._handle):
                self._previous_execute = True if inst.Execute else False
                self._last_scan = scan
                self._calls_since_start += 1
                return
        SocketRequestFB.call(self, inst, ctx)

    def _start(self, inst, ctx, transport: Transport) -> None:
        self._probe = False
        settings = ctx.settings
        self._handle = _handle_of(inst)
        self._size = inst.Size
        self._timeout_ns = inst.TimeOut * settings.skt_rcv_timeout_unit_ns
        self._start_ns = ctx.now_ns
        if not 0 < self._size <= RECEIVE_MAX_BYTES:
            raise SocketError("out_of_range", f"Size {self._size} not in 1..{RECEIVE_MAX_BYTES}")
        if self._size > len(as_array_ref(inst.RcvDat)):
            raise SocketError("too_few_elements", f"Size {self._size} > elements passed")
        _require_open(transport, self._handle, ctx.now_ns)
        if isinstance(transport, SocketTable):
            # what `call` compares with: `_progress` runs from the call where the count reaches
            # skt_min_latency_calls; it times out at start + timeout (at once with TimeOut 0
            # under error_if_empty, never under wait)
            self._calls_before_progress = settings.skt_min_latency_calls - 1
            self._cancel_unpolled = settings.skt_progress_without_call is _CANCEL
            if self._timeout_ns:
                self._waits_until_ns = self._start_ns + self._timeout_ns
            else:
                self._waits_until_ns = -1 if settings.skt_rcv_timeout0 is _TIMEOUT0_ERROR_IF_EMPTY else 1 << 127
            self._probe = transport is ctx.transport

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        settings = ctx.settings
        state = _require_open(transport, self._handle, ctx.now_ns)
        available = transport.pending(self._handle)
        if available:
            count = min(available, self._size, RECEIVE_MAX_BYTES)
            target = as_array_ref(inst.RcvDat)
            if count > len(target):
                return "too_few_elements"
            target.write(transport.receive(self._handle, count))  # later elements untouched
            inst.RcvSize = count
            return DONE
        if state == PEER_CLOSED:
            if settings.skt_rcv_peer_closed is _PEER_CLOSED_ERROR:
                return "wrong_state"
            inst.RcvSize = 0  # `skt_rcv_peer_closed = done_zero`
            return DONE
        if state in (RESET, FAILED):
            return "wrong_state"
        if self._timeout_ns == 0:
            return "timeout" if settings.skt_rcv_timeout0 is _TIMEOUT0_ERROR_IF_EMPTY else None
        if ctx.now_ns - self._start_ns >= self._timeout_ns:
            return "timeout"
        return None


@native_fb("SktClose")
class SktClose(SocketRequestFB):
    """Discard buffered data, send FIN; the handle is invalid afterwards (sysmac.md 5).

    Choice: Done at the first completion call (the FIN's ACK is not observable without blocking).
    """

    def _start(self, inst, ctx, transport: Transport) -> None:
        handle = _handle_of(inst)
        if handle == 0:
            raise SocketError("bad_handle", "handle 0")
        transport.close(handle)

    def _progress(self, inst, ctx, transport: Transport) -> str | None:
        return DONE
