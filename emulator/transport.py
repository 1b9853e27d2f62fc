"""Transports for the emulated robot: a real TCP server, and an in-process link on a virtual clock.

Both drive the same pure :class:`~emulator.core.EmulatorCore`; only this module touches sockets
or the wall clock.

TCP server
==========

``TcpServer(host, port, settings, faults, log_path).start()`` runs a ``selectors`` loop in one
background thread.  ``.port`` is the bound port (pass ``port=0`` for a free one), ``.stop()`` closes
every socket and joins the thread.  While the project is stopped the listening socket is closed, so
clients get "connection refused" as from a real robot (spec §1.2).  Each outgoing frame is written
with its own ``send`` call and ``TCP_NODELAY`` (spec §2: one frame per write).

In-process link (deterministic lockstep)
========================================

No threads, no sockets, no wall clock.  Time is an integer number of nanoseconds that only moves
when the owner calls :meth:`InProcessLink.advance_to` (or :meth:`InProcessLink.step`).  Bytes take
``latency_ns`` in each direction; a connection attempt takes one latency to reach the robot and one
to come back.  Events at the same instant are processed in the order they were created, so a
scenario gives bit-identical results on every run::

    from emulator.transport import InProcessLink

    link = InProcessLink(latency_ns=1_000_000)        # 1 ms each way
    client = link.endpoint()                          # one client socket
    client.connect()                                  # status -> "connecting"
    link.step(2_000_000)                              # status -> "connected"
    client.send(b"$TMSTA,2,00,*41\\r\\n")
    link.step(2_000_000)
    client.recv(4096)                                 # b"$TMSTA,15,00,true,Listen1,*79\\r\\n"
    client.close()

:class:`ClientEndpoint` (what a PLC socket function block polls once per scan):

* ``connect(host=None, port=None)``: start connecting (address ignored); never blocks.
* ``status``: ``"closed"`` (new or after ``close()``), ``"connecting"``, ``"connected"``,
  ``"refused"`` (the robot's listener is closed or a ``refuse`` fault), ``"peer_closed"`` (the
  robot closed the connection: project stop, ``drop`` fault; unread bytes can still be read).
* ``send(data) -> int``: bytes accepted (all of them while connected, else 0).  They reach the
  robot ``latency_ns`` later, as one segment.
* ``recv(max_bytes) -> bytes``: up to ``max_bytes`` already arrived; ``b""`` if none.
* ``available``: number of bytes ready to read.
* ``close()``: close our side (the robot learns it one latency later).

The link also exposes ``now_ns``, ``robot`` (the :class:`~emulator.robot.Robot`) and ``core``.
"""

from __future__ import annotations

import errno
import heapq
import json
import selectors
import socket
import sys
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from typing import IO, Any, Callable

from .core import Delivery, EmulatorCore
from .faults import NO_FAULTS, FaultPlan
from .settings import DEFAULT_SETTINGS, EmulatorSettings

# Pending connections the kernel queues before accept(): like a real server's (nginx 511,
# asyncio 100), not 16, which made a client's connect/close loop stall for the 1 s SYN retry.
ACCEPT_BACKLOG = 128

# accept() failing for lack of descriptors or memory leaves the pending connection queued, so the
# listener stays readable: selecting on it again at once spins a core (3.9 s CPU per 5 s measured).
# The listener is taken out of the selector for a back-off that doubles up to the maximum, as
# nginx and asyncio do, and put back afterwards; a connection that closes frees a descriptor.
ACCEPT_BACKOFF_MIN_S = 0.05
ACCEPT_BACKOFF_MAX_S = 1.0
_RESOURCE_ERRNOS = frozenset({errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM})

# Clients served at once; one more is accepted and reset at once (as a refused connection), so a
# flood of idle connections cannot take every descriptor of the process. A TM robot's Listen node
# serves a handful of clients; `tm-emulator --max-connections N` changes it.
MAX_CONNECTIONS = 64
_FOREVER = 1 << 63   # `InProcessLink._quiet_until` when nothing is pending at all

# ============================================================================ frame log


class JsonFrameLog:
    """``--log FILE``: one JSON object per frame, flushed per frame:
    ``{"t": seconds since start, "dir": "rx"|"tx", "data": "<frame text>", "conn": id}``."""

    def __init__(self, path: str | None, start_ns: int = 0, keep_last: int = 12) -> None:
        self._file: IO[str] | None = open(path, "a", encoding="utf-8") if path else None
        self.start_ns = start_ns
        self.keep_last = keep_last
        # The last frames as they came (t_ns, dir, bytes, conn); ``recent`` formats them when read,
        # so that without a log file a frame costs one append, not a decode.
        self._recent: deque[tuple[int, str, bytes, int]] = deque(maxlen=keep_last)
        self.count = {"rx": 0, "tx": 0}
        self._lock = threading.Lock()

    def __call__(self, t_ns: int, direction: str, data: bytes, conn: int) -> None:
        # Called by one thread at a time (the server thread, under the server lock, or the owner of
        # an InProcessLink); readers copy ``count`` and ``recent`` atomically (GIL).
        self.count[direction] += 1
        self._recent.append((t_ns, direction, data, conn))
        if self._file is not None:
            t_s = (t_ns - self.start_ns) / 1e9
            text = data.decode("utf-8", errors="backslashreplace")
            with self._lock:
                if self._file is not None:
                    self._file.write(json.dumps({"t": round(t_s, 9), "dir": direction, "data": text,
                                                 "conn": conn}) + "\n")
                    self._file.flush()

    @property
    def recent(self) -> deque[tuple[float, str, str, int]]:
        """The last ``keep_last`` frames as ``(seconds since start, "rx"|"tx", text, conn)``."""
        start = self.start_ns
        return deque((((t_ns - start) / 1e9, direction, data.decode("utf-8", errors="backslashreplace"), conn)
                      for t_ns, direction, data, conn in list(self._recent)), maxlen=self.keep_last)

    def close(self) -> None:
        with self._lock:
            if self._file is not None:
                self._file.close()
                self._file = None


# ============================================================================ TCP server


@dataclass
class _Conn:
    sock: socket.socket
    conn_id: int
    out: deque[bytes] = field(default_factory=deque)
    closing: bool = False
    writing: bool = False  # registered for EVENT_WRITE (a frame is partly sent)


class TcpServer:
    """The emulator on a real TCP port, served from one background thread."""

    def __init__(self, host: str = "127.0.0.1", port: int = 5890,
                 settings: EmulatorSettings = DEFAULT_SETTINGS, faults: FaultPlan = NO_FAULTS,
                 log_path: str | None = None, max_connections: int = MAX_CONNECTIONS) -> None:
        self.host = host
        self.max_connections = max_connections
        self.refused_over_limit = 0
        self.requested_port = port
        self.port = port
        self._t0 = time.monotonic_ns()
        self.frame_log = JsonFrameLog(log_path)
        self.core = EmulatorCore(settings, faults, self.frame_log, now_ns=0)
        self.lock = threading.RLock()
        self._sel = selectors.DefaultSelector()
        self._listener: socket.socket | None = None
        self._conns: dict[int, _Conn] = {}
        self._by_sock: dict[socket.socket, _Conn] = {}
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.error: BaseException | None = None
        # accept() back-off (see ACCEPT_BACKOFF_MIN_S): the monotonic instant the listener goes
        # back into the selector, None when it is in
        self._accept_resume_s: float | None = None
        self._accept_backoff_s = ACCEPT_BACKOFF_MIN_S
        self.accept_failures = 0   # accept() calls that failed for lack of resources
        self.handler_errors = 0    # frames whose handling raised (the connection was dropped)
        self.log_line: Callable[[str], None] = _log_stderr

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> "TcpServer":
        self._open_listener()
        # a robot that refuses from the start (`refuse`, `stop:0`) closes the port before anyone
        # can connect: clients see a TCP refusal, not an accepted-then-reset connection
        with self.lock:
            self._flush(self.now_ns())
        self._sel.register(self._wake_r, selectors.EVENT_READ, "wake")
        self._thread = threading.Thread(target=self._serve, name=f"tm-emulator:{self.port}", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout_s: float = 5.0) -> None:
        """Close every socket and end the server thread."""
        self._stop.set()
        try:
            self._wake_w.send(b"x")
        except OSError:
            pass
        if self._thread is not None:
            self._thread.join(timeout_s)
        self._cleanup()

    def __enter__(self) -> "TcpServer":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def now_ns(self) -> int:
        return time.monotonic_ns() - self._t0

    @property
    def listening(self) -> bool:
        """Whether the port is open (False while the project is stopped: connection refused)."""
        return self._listener is not None

    def snapshot(self) -> dict[str, Any]:
        with self.lock:
            snap = self.core.robot.snapshot()
            snap["log"] = list(self.core.robot.log)[-8:]
        snap["recent_frames"] = list(self.frame_log.recent)
        snap["frames"] = dict(self.frame_log.count)
        snap["address"] = f"{self.host}:{self.port}"
        return snap

    def call(self, fn: Callable[[EmulatorCore, int], Any]) -> Any:
        """Run ``fn(core, now_ns)`` in the server's lock (e.g. ``robot.stop_project``) and wake
        the loop so that its output goes out."""
        with self.lock:
            result = fn(self.core, self.now_ns())
        self._wake_w.send(b"x")
        return result

    # ------------------------------------------------------------------ internals

    def _open_listener(self) -> None:
        sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((self.host, self.port))
        sock.listen(ACCEPT_BACKLOG)
        sock.setblocking(False)
        self.port = sock.getsockname()[1]
        self._listener = sock
        self._sel.register(sock, selectors.EVENT_READ, "listen")

    def _close_listener(self) -> None:
        if self._listener is not None:
            try:
                self._sel.unregister(self._listener)
            except (KeyError, ValueError):   # out of the selector during an accept() back-off
                pass
            self._accept_resume_s = None
            self._listener.close()
            self._listener = None

    def _serve(self) -> None:
        # One lock section per wake-up: handle the events, send what is due, compute the next
        # deadline; then sleep in select() until a socket is ready or the deadline comes.
        select = self._sel.select
        stop = self._stop
        lock = self.lock
        core = self.core
        try:
            with lock:
                now = self.now_ns()
                deadline = core.next_deadline_ns()
            while not stop.is_set():
                timeout = 1.0 if deadline is None else min(1.0, max(0.0, (deadline - now) / 1e9))
                if self._accept_resume_s is not None:
                    timeout = min(timeout, max(0.0, self._accept_resume_s - time.monotonic()))
                events = select(timeout)
                with lock:
                    if self._accept_resume_s is not None and time.monotonic() >= self._accept_resume_s:
                        self._resume_accept()
                    # One instant per wake-up: the events, then what is due at that instant.
                    now = self.now_ns()
                    for key, mask in events:
                        self._on_event(key, mask, now)
                    self._flush(now)
                    deadline = core.next_deadline_ns()
        except BaseException as exc:  # surfaced through .error; the thread must not die silently
            self.error = exc
            raise

    def _on_event(self, key: selectors.SelectorKey, mask: int, now: int) -> None:
        conn = key.data
        if conn.__class__ is _Conn:  # the hot path: a client socket
            if mask & selectors.EVENT_WRITE:
                self._write(conn)
            if mask & selectors.EVENT_READ:
                try:
                    data = conn.sock.recv(65536)
                except (BlockingIOError, InterruptedError):
                    return
                except OSError:
                    data = b""
                if data:
                    try:
                        self.core.receive(conn.conn_id, data, now)
                    except Exception as exc:  # noqa: BLE001 - defence in depth, see _handler_failed
                        self._handler_failed(conn, exc, now)
                else:
                    self.core.close(conn.conn_id, now)
                    self._drop(conn)
            return
        if key.data == "wake":
            try:
                self._wake_r.recv(4096)
            except OSError:
                pass
            return
        if key.data == "listen":
            assert self._listener is not None
            try:
                sock, _ = self._listener.accept()
            except OSError as exc:
                if exc.errno in _RESOURCE_ERRNOS:
                    self._pause_accept(exc)
                return
            self._accept_backoff_s = ACCEPT_BACKOFF_MIN_S
            if len(self._conns) >= self.max_connections:
                self.refused_over_limit += 1
                _reset(sock)
                return
            conn_id = self.core.open(now)
            if conn_id is None:
                # Refuse: reset the connection at once (SO_LINGER 0 sends RST).
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
                sock.close()
                return
            sock.setblocking(False)
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn = _Conn(sock, conn_id)
            self._conns[conn_id] = conn
            self._by_sock[sock] = conn
            self._sel.register(sock, selectors.EVENT_READ, conn)

    def _handler_failed(self, conn: _Conn, exc: Exception, now: int) -> None:
        """A frame raised while being handled: a bug in the emulator, which no client may turn
        into a dead server. That connection is closed (its state may be half-updated), one line
        is logged, and the thread goes on serving every other client."""
        self.handler_errors += 1
        self.log_line(f"tm-emulator: internal error on connection {conn.conn_id}, closed: "
                      f"{type(exc).__name__}: {str(exc)[:200]}")
        try:
            self.core.close(conn.conn_id, now)
        except Exception:  # noqa: BLE001 - the connection goes in any case
            self.core.framers.pop(conn.conn_id, None)
            self.core.rx_buffers.pop(conn.conn_id, None)
        self._drop(conn)

    def _pause_accept(self, exc: OSError) -> None:
        if self._listener is None:
            return
        if self.accept_failures == 0 or self._accept_backoff_s == ACCEPT_BACKOFF_MIN_S:
            self.log_line(f"tm-emulator: cannot accept a connection ({exc.strerror or exc}); "
                          f"retrying in {self._accept_backoff_s:.2f} s")
        self.accept_failures += 1
        try:
            self._sel.unregister(self._listener)
        except (KeyError, ValueError):
            pass
        self._accept_resume_s = time.monotonic() + self._accept_backoff_s
        self._accept_backoff_s = min(ACCEPT_BACKOFF_MAX_S, self._accept_backoff_s * 2)

    def _resume_accept(self) -> None:
        self._accept_resume_s = None
        if self._listener is not None:
            try:
                self._sel.register(self._listener, selectors.EVENT_READ, "listen")
            except (KeyError, ValueError):
                pass

    def _flush(self, now: int) -> None:
        for delivery in self.core.pop_ready(now):
            self._deliver(delivery)  # each frame with its own send (spec §2)
        # Project stopped -> listener closed (connection refused); started again -> reopened.
        if self.core.accepting and self._listener is None and not self._stop.is_set():
            try:
                self._open_listener()
            except OSError:
                pass
        elif not self.core.accepting and self._listener is not None:
            self._close_listener()

    def _deliver(self, delivery: Delivery) -> None:
        conn = self._conns.get(delivery.conn)
        if conn is None:
            return
        if delivery.data is None:
            conn.closing = True
            if not conn.out:
                self._drop(conn)
            return
        conn.out.append(delivery.data)
        self._write(conn)

    def _write(self, conn: _Conn) -> None:
        while conn.out:
            chunk = conn.out[0]
            try:
                sent = conn.sock.send(chunk)  # one frame per send (spec §2)
            except (BlockingIOError, InterruptedError):
                sent = 0
            except OSError:
                self.core.close(conn.conn_id, self.now_ns())
                self._drop(conn)
                return
            if sent < len(chunk):
                conn.out[0] = chunk[sent:]
                if not conn.writing:
                    self._sel.modify(conn.sock, selectors.EVENT_READ | selectors.EVENT_WRITE, conn)
                    conn.writing = True
                return
            conn.out.popleft()
        if conn.closing:
            self._drop(conn)
            return
        if conn.writing:  # everything sent: stop watching for writability
            conn.writing = False
            try:
                self._sel.modify(conn.sock, selectors.EVENT_READ, conn)
            except (KeyError, ValueError):
                pass

    def _drop(self, conn: _Conn) -> None:
        if self._conns.pop(conn.conn_id, None) is None:
            return
        self._by_sock.pop(conn.sock, None)
        try:
            self._sel.unregister(conn.sock)
        except (KeyError, ValueError):
            pass
        conn.sock.close()

    def _cleanup(self) -> None:
        for conn in list(self._conns.values()):
            self._drop(conn)
        if self._listener is not None:
            self._close_listener()
        for sock in (self._wake_r, self._wake_w):
            try:
                self._sel.unregister(sock)
            except (KeyError, ValueError):
                pass
            sock.close()
        self._sel.close()
        self.frame_log.close()


def _reset(sock: socket.socket) -> None:
    """Close `sock` with a reset (SO_LINGER 0 sends RST), as a refused connection."""
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")
    except OSError:
        pass
    sock.close()


def _log_stderr(line: str) -> None:
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def start_server(host: str = "127.0.0.1", port: int = 5890, log_path: str | None = None,
                 faults: FaultPlan | None = None, settings: EmulatorSettings | None = None,
                 max_connections: int = MAX_CONNECTIONS) -> TcpServer:
    """Start the emulator on ``host:port`` in a background thread and return the running server
    (``.port`` is the bound port; ``port=0`` picks a free one; ``.stop()`` shuts it down)."""
    return TcpServer(host, port, settings or DEFAULT_SETTINGS, faults or NO_FAULTS, log_path,
                     max_connections).start()


# ============================================================================ in-process link


class ClientEndpoint:
    """Client side of one in-process connection (see the module docstring)."""

    def __init__(self, link: "InProcessLink") -> None:
        self._link = link
        self.status = "closed"
        self.conn_id: int | None = None
        self._rx = bytearray()
        self._generation = 0  # ignores events of an earlier connection after close/reconnect

    def connect(self, host: str | None = None, port: int | None = None) -> None:
        if self.status in ("connecting", "connected"):
            return
        self._generation += 1
        self._rx.clear()
        self.status = "connecting"
        self._link._schedule(self._link.latency_ns, "syn", self, None)

    def send(self, data: bytes) -> int:
        if self.status != "connected" or not data:
            return 0
        self._link._schedule(self._link.latency_ns, "c2s", self, bytes(data))
        return len(data)

    def recv(self, max_bytes: int = 65536) -> bytes:
        chunk = bytes(self._rx[:max_bytes])
        del self._rx[:max_bytes]
        return chunk

    @property
    def available(self) -> int:
        return len(self._rx)

    def close(self) -> None:
        if self.status in ("connected", "connecting") and self.conn_id is not None:
            self._link._schedule(self._link.latency_ns, "cfin", self, self.conn_id)
        self._generation += 1
        self.status = "closed"
        self.conn_id = None


class InProcessLink:
    """The emulator and its clients on one virtual clock (integer ns), stepped by the caller."""

    def __init__(self, settings: EmulatorSettings = DEFAULT_SETTINGS, faults: FaultPlan = NO_FAULTS,
                 latency_ns: int = 1_000_000, start_ns: int = 0, log_path: str | None = None) -> None:
        if latency_ns < 0:
            raise ValueError("latency must not be negative")
        self.latency_ns = int(latency_ns)
        self.now_ns = int(start_ns)
        self.frame_log = JsonFrameLog(log_path, start_ns)
        self._core = core = EmulatorCore(settings, faults, self.frame_log, now_ns=self.now_ns)
        self._robot = core.robot
        self._events: list[tuple[int, int, str, ClientEndpoint, Any, int]] = []
        self._seq = 0
        self._by_conn: dict[int, ClientEndpoint] = {}
        # Quiet steps (issue 33): after a full `advance_to`, nothing is due before `_quiet_until`
        # (the earliest of the next event, the core's next deadline and its first pending
        # delivery), and while the robot keeps its deadline (`Robot._deadline_known`: every call
        # that changes its state forgets it) an `advance_to` earlier than that only moves the
        # clocks. Then only this link's clock moves and the core stays `_behind`: the robot
        # would reach the same state by one later `advance` as by one per step (its clocks add
        # up; nothing else changes while nothing is due, see `Robot.advance`). Whatever reads or
        # changes the core catches it up first: the `core` and `robot` properties, the robot's
        # `snapshot` and the executor's pose (their `catch_up` hook), and the full path here.
        self._quiet_until = -1
        self._behind = False
        core.robot.catch_up = core.robot.executor.catch_up = self._catch_up

    @property
    def core(self) -> EmulatorCore:
        """The connection core, caught up with this link's clock."""
        if self._behind:
            self._catch_up()
        return self._core

    @property
    def robot(self):  # -> Robot (not imported for typing to keep the import graph flat)
        if self._behind:
            self._catch_up()
        return self._robot

    def _catch_up(self) -> None:
        """Bring the core's clocks to this link's after quiet steps (nothing is due by then)."""
        if self._behind:
            self._behind = False
            self._core.advance(self.now_ns)

    def endpoint(self) -> ClientEndpoint:
        return ClientEndpoint(self)

    def step(self, dt_ns: int) -> None:
        self.advance_to(self.now_ns + int(dt_ns))

    def advance_to(self, now_ns: int) -> None:
        """Process everything up to and including ``now_ns``, in time order."""
        target = int(now_ns)
        if target < self._quiet_until and self._robot._deadline_known:
            # a quiet step (see __init__): nothing is due by `target`
            if target < self.now_ns:
                raise ValueError("time cannot go backwards")
            self.now_ns = target
            self._behind = True
            return
        if target < self.now_ns:
            raise ValueError("time cannot go backwards")
        self._behind = False   # the core's own calls below move its clocks (a jump is a step)
        core = self._core
        for _ in range(10_000_000):
            t_event = self._events[0][0] if self._events else None
            t_core = core.next_deadline_ns()
            # the earlier of the two that are due by `target` (no list: this runs every VM scan)
            due = t_event if t_event is not None and t_event <= target else None
            if t_core is not None and t_core <= target and (due is None or t_core < due):
                due = t_core
            if due is None:
                break
            t = due if due > self.now_ns else self.now_ns
            self.now_ns = t
            if t_event is not None and t_event <= t:
                _, _, kind, ep, payload, gen = heapq.heappop(self._events)
                self._process(kind, ep, payload, gen, t)
            else:
                before = core.next_deadline_ns()
                core.advance(t)
                self._collect(t)
                if core.next_deadline_ns() == before and before is not None and before <= t:
                    break  # nothing consumed the deadline; do not spin
        self.now_ns = target
        core.advance(target)
        # `core.pop_ready(target)` only when it could return something or tick: after `advance`
        # it has ticked at target, and with nothing due by then it returns [] and changes
        # nothing (its own early outs, without its call on the quiet scans of the lockstep loop)
        pending = core._pending
        if (pending and pending[0][0] <= target) or core._ticked_ns != target \
                or core.robot._settled_ns != target:
            ready = core.pop_ready(target)
            if ready:   # (`_collect` without its call on the scans when nothing is sent)
                self._deliver(ready)
        # nothing is due before the earliest of the next event and the core's next deadline
        # (which counts its first pending delivery); `_schedule` lowers it
        quiet = core.next_deadline_ns()
        events = self._events
        if events and (quiet is None or events[0][0] < quiet):
            quiet = events[0][0]
        self._quiet_until = _FOREVER if quiet is None else quiet

    def close(self) -> None:
        self.frame_log.close()

    # ------------------------------------------------------------------ internals

    def _schedule(self, delay_ns: int, kind: str, ep: ClientEndpoint, payload: Any) -> None:
        self._seq += 1
        at = self.now_ns + delay_ns
        heapq.heappush(self._events, (at, self._seq, kind, ep, payload, ep._generation))
        if at < self._quiet_until:
            self._quiet_until = at

    def _process(self, kind: str, ep: ClientEndpoint, payload: Any, gen: int, t: int) -> None:
        if kind == "syn":
            if gen != ep._generation:
                return
            conn = self._core.open(t)
            if conn is None:
                self._schedule(self.latency_ns, "refused", ep, None)
            else:
                ep.conn_id = conn
                self._by_conn[conn] = ep
                self._schedule(self.latency_ns, "established", ep, conn)
        elif kind == "established":
            if gen == ep._generation and ep.status == "connecting":
                ep.status = "connected"
        elif kind == "refused":
            if gen == ep._generation and ep.status == "connecting":
                ep.status = "refused"
        elif kind == "c2s":
            if gen == ep._generation and ep.conn_id is not None:
                self._core.receive(ep.conn_id, payload, t)
        elif kind == "cfin":
            self._by_conn.pop(payload, None)
            self._core.close(payload, t)
        elif kind == "s2c":
            if gen == ep._generation:
                ep._rx.extend(payload)
        elif kind == "fin":
            if gen == ep._generation and ep.status in ("connected", "connecting"):
                ep.status = "peer_closed"
                ep.conn_id = None
        self._collect(t)

    def _collect(self, t: int) -> None:
        self._deliver(self._core.pop_ready(t))

    def _deliver(self, ready: list[Delivery]) -> None:
        for delivery in ready:
            ep = self._by_conn.get(delivery.conn)
            if ep is None:
                continue
            if delivery.data is None:
                self._by_conn.pop(delivery.conn, None)
                self._schedule(self.latency_ns, "fin", ep, None)
            else:
                self._schedule(self.latency_ns, "s2c", ep, delivery.data)
