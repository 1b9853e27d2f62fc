"""Connection core shared by both transports: robot + one framer per connection + byte-level
faults + frame log.  Pure: no sockets, no clock; the transport passes ``now_ns`` in.

Outgoing bytes are queued as :class:`Delivery` items with the instant they may go on the wire
(``pop_ready``).  Each item is one whole frame, to be written with a single write (spec §2: some
clients cannot reassemble a frame split over two reads) unless the ``split`` fault is active.
"""

from __future__ import annotations

import heapq
from typing import Callable, NamedTuple

from .faults import NO_FAULTS, FaultPlan, corrupt_checksum
from .framing import ListenNodeFramer
from .motion import NS_PER_MS
from .robot import Action, Close, Robot, Send
from .settings import DEFAULT_SETTINGS, EmulatorSettings

FrameLog = Callable[[int, str, bytes, int], None]  # (t_ns, "rx"/"tx", frame bytes, conn)


_new_tuple = tuple.__new__


class Delivery(NamedTuple):
    """Bytes for a connection (``data``), or its closing (``data is None``).  Immutable."""

    conn: int
    data: bytes | None
    at_ns: int


class EmulatorCore:
    def __init__(self, settings: EmulatorSettings = DEFAULT_SETTINGS, faults: FaultPlan = NO_FAULTS,
                 frame_log: FrameLog | None = None, now_ns: int = 0) -> None:
        self.settings = settings
        self.faults = faults
        self.robot = Robot(settings, faults, now_ns)
        self.frame_log = frame_log
        self.framers: dict[int, ListenNodeFramer] = {}
        self.rx_buffers: dict[int, bytes] = {}
        self._next_conn = 1
        self._refused = 0
        self._tx_count = 0
        self._pending: list[tuple[int, int, Delivery]] = []
        self._seq = 0
        self._was_moving = False
        self._drop_at_ns: int | None = None
        self.now_ns = now_ns
        self._ticked_ns: int | None = None   # the instant of the last `_tick` (see there)

    # ------------------------------------------------------------------ connections

    @property
    def accepting(self) -> bool:
        """Whether connection attempts are accepted: the project runs and no `refuse` (all)
        fault is active. The TCP server closes its listener otherwise, so clients get a real
        TCP refusal (spec §1.2); a count-limited `refuse:N` has to accept and reset."""
        return self.robot.accepting and self.faults.refuse_connections != -1

    def apply_faults(self, plan: FaultPlan, now_ns: int, fault_name: str | None = None) -> None:
        """Switch to fault plan `plan` during a run (scenario events, `inject_fault`).

        Timed faults count from now: `stop:MS` stops the project MS ms later, `unsolicited:MS`
        sends its first frame MS ms later, and a `drop:MS` given while a motion runs drops the
        connections MS ms later (given while idle, MS ms after the next motion starts)."""
        robot = self.robot
        robot.forget_deadline()
        self._ticked_ns = None
        self.faults = plan
        robot.faults = plan
        robot.executor.stalled = plan.stay_busy
        if fault_name == "stop" and plan.stop_project_at_ms is not None:
            robot.stop_at_ns = now_ns + plan.stop_project_at_ms * NS_PER_MS
        if fault_name == "unsolicited":
            robot.next_unsolicited_ns = now_ns + plan.unsolicited_every_ms * NS_PER_MS
        if fault_name == "drop" and robot.executor.moving:
            self._drop_at_ns = now_ns + (plan.drop_after_motion_ms or 0) * NS_PER_MS

    def clear_faults(self) -> None:
        """Back to a robot without faults (timers armed by faults are disarmed)."""
        robot = self.robot
        robot.forget_deadline()
        self._ticked_ns = None
        self.faults = robot.faults = NO_FAULTS
        robot.executor.stalled = False
        robot.next_unsolicited_ns = None
        robot.stop_at_ns = None
        self._drop_at_ns = None

    def open(self, now_ns: int) -> int | None:
        """A client connects; return its connection id, or None if refused."""
        self._tick(now_ns)
        self._ticked_ns = None   # what follows changes the state
        refuse = self.faults.refuse_connections
        if not self.robot.accepting or refuse == -1 or self._refused < refuse:
            self._refused += 1
            return None
        conn = self._next_conn
        self._next_conn += 1
        self.framers[conn] = ListenNodeFramer(self.settings)
        self.rx_buffers[conn] = b""
        self._absorb(self.robot.connect(conn, now_ns))
        return conn

    def close(self, conn: int, now_ns: int) -> None:
        """The client closed (or lost) the connection."""
        self._tick(now_ns)
        self._ticked_ns = None   # what follows changes the state
        self.framers.pop(conn, None)
        self.rx_buffers.pop(conn, None)
        self._absorb(self.robot.disconnect(conn, now_ns))

    def receive(self, conn: int, data: bytes, now_ns: int) -> None:
        """Bytes arrived from ``conn``: decode every complete frame and answer it."""
        self._tick(now_ns)
        self._ticked_ns = None   # what follows changes the state
        framer = self.framers.get(conn)
        if framer is None:
            return
        held = self.rx_buffers[conn]
        buf = held + data if held else bytes(data)
        end = len(buf)
        pos = 0
        frame_log = self.frame_log
        framers = self.framers
        while pos < end and conn in framers:
            used, result = framer.decode(buf, pos)  # walks the buffer without slicing it
            if used == 0:
                break
            pos += used
            if result is None:
                continue  # garbage before "$" skipped (spec §2 [U])
            if frame_log is not None:
                frame_log(now_ns, "rx", result.raw, conn)
            self._absorb(self.robot.handle(conn, result, now_ns))
        if conn in self.rx_buffers:
            self.rx_buffers[conn] = buf[pos:] if pos < end else b""

    # ------------------------------------------------------------------ time

    def next_deadline_ns(self) -> int | None:
        robot = self.robot
        # `robot.next_deadline_ns()` without its call when the robot keeps it (every quiet scan)
        best = robot._deadline_ns if robot._deadline_known else robot.next_deadline_ns()
        drop = self._drop_at_ns
        if drop is not None and (best is None or drop < best):
            best = drop
        if self._pending:
            due = self._pending[0][0]
            if best is None or due < best:
                best = due
        return best

    def pop_ready(self, now_ns: int) -> list[Delivery]:
        """Deliveries due at ``now_ns``, in order."""
        if now_ns != self._ticked_ns or self.robot._settled_ns != now_ns:
            self._tick(now_ns)   # (else it would return at once: in lockstep, right after `advance`)
        pending = self._pending
        if not pending or pending[0][0] > now_ns:
            return []
        ready: list[Delivery] = []
        while pending and pending[0][0] <= now_ns:
            ready.append(heapq.heappop(pending)[2])
        frame_log = self.frame_log
        if frame_log is not None:
            for item in ready:
                if item.data is not None:
                    frame_log(item.at_ns, "tx", item.data, item.conn)
        return ready

    def _tick(self, now_ns: int) -> None:
        if now_ns < self.now_ns:
            now_ns = self.now_ns
        if now_ns == self._ticked_ns and self.robot._settled_ns == now_ns:
            # ticked at this instant already, with no call since that changes the state (those
            # forget `_ticked_ns`; a direct robot call forgets its `_settled_ns`): this tick
            # would change nothing. In lockstep `pop_ready` ticks right after `advance`.
            return
        if self._drop_at_ns is not None and now_ns >= self._drop_at_ns:
            self._absorb(self.robot.advance(self._drop_at_ns))
            self._drop_all(self._drop_at_ns)
            self._drop_at_ns = None
        actions = self.robot.advance(now_ns)
        if actions:
            self._absorb(actions)
        self.now_ns = now_ns
        moving = True if self.robot.executor.active else False   # executor.moving, without a call
        if moving and not self._was_moving and self.faults.drop_after_motion_ms is not None:
            self._drop_at_ns = now_ns + self.faults.drop_after_motion_ms * NS_PER_MS
        self._was_moving = moving
        if self._drop_at_ns is not None and now_ns >= self._drop_at_ns:
            self._drop_all(now_ns)
            self._drop_at_ns = None
        self._ticked_ns = now_ns

    advance = _tick   # the public name: let time pass up to ``now_ns`` (one call, not two)

    def _drop_all(self, at_ns: int) -> None:
        """Fault ``drop``: close every connection in the middle of a motion."""
        for conn in list(self.framers):
            self._push(Delivery(conn, None, at_ns))
            self.framers.pop(conn, None)
            self.rx_buffers.pop(conn, None)
            self._absorb(self.robot.disconnect(conn, at_ns))

    # ------------------------------------------------------------------ robot output

    def _push(self, delivery: Delivery) -> None:
        self._seq += 1
        heapq.heappush(self._pending, (delivery.at_ns, self._seq, delivery))

    def _absorb(self, actions: list[Action]) -> None:
        if not actions:
            return
        faults = self.faults
        delay = faults.reply_delay_ms * NS_PER_MS
        every = faults.corrupt_checksum_every
        split = faults.split_frames_at
        framers = self.framers
        for action in actions:
            if action.__class__ is Close:
                targets = list(framers) if action.conn is None else [action.conn]
                for conn in targets:
                    self._push(Delivery(conn, None, action.at_ns))
                    framers.pop(conn, None)
                    self.rx_buffers.pop(conn, None)
                continue
            assert action.__class__ is Send
            conn = action.conn
            if conn not in framers:
                continue
            data = action.data
            self._tx_count += 1
            if every and self._tx_count % every == 0:
                data = corrupt_checksum(data)
            at = action.at_ns + delay
            if split is not None and len(data) > 1:
                cut = split if 0 < split < len(data) else len(data) // 2
                self._push(Delivery(conn, data[:cut], at))
                self._push(Delivery(conn, data[cut:], at))
            else:
                self._seq += 1
                # tuple.__new__ builds the Delivery without a Python-level __new__ call.
                heapq.heappush(self._pending, (at, self._seq, _new_tuple(Delivery, (conn, data, at))))
