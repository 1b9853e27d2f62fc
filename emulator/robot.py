"""The emulated TM robot in Listen Node mode: frames in, replies out, no I/O (spec §1, §4-§8).

:class:`Robot` is pure and deterministic.  Every public method takes ``now_ns`` (integer
nanoseconds on whatever clock the caller uses; it must never go backwards) and returns the
:class:`Send`/:class:`Close` actions produced, each stamped with the exact instant it was produced,
which may lie between two calls (e.g. a QueueTag reached in the middle of a step).

Connections are identified by integers chosen by the caller.  Replies go to the connection that
sent the request (spec §1.4).

Reply table (spec §2.1, §4, §5, §6; robot-level part; 01/02/03 come from ``framing.py``):

==============================================  ====================================  ========
condition                                       reply                                 spec
==============================================  ====================================  ========
DATA not UTF-8                                  ``CPERR 04``                          Choice
TMSCT without ``ID,``, ID not alphanumeric      ``CPERR 04``                          §2.1
TMSTA SubCmd not 00/01 (incl. 90-99)            ``CPERR 04``                          §5.5
TMSCT outside the node or while exiting         ``CPERR F1``                          §4.4
script syntax/type/name errors                  ``ID,ERROR;<lines>``, nothing runs    §4.2
invalid argument values (reject_invalid_args)   ``ID,ERROR;<lines>``, nothing runs    §7 [U]
otherwise                                       ``ID,OK`` when the script has run     §4.3
==============================================  ====================================  ========
"""

from __future__ import annotations

from collections import OrderedDict, deque
from enum import Enum
from functools import lru_cache
from typing import Any, Callable, NamedTuple

import numpy as np

from . import script as sc
from .builtins import (BLOCKING_STATEMENTS, FUNCTIONS, ArgError, ScriptContext, ScriptJob, apply_io_marker,
                       format_value, io_read, io_write, new_io)
from .faults import NO_FAULTS, FaultPlan
from .framing import Cperr, Frame, FrameError, encode, encode_cperr
from . import detmath as dm
from .motion import NS_PER_MS, Kinematics, Marker, MotionExecutor, PlannedState, Planner, matrix_to_pose
from .settings import DEFAULT_SETTINGS, AfterExit, EmulatorSettings

_ID_CHARS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789")


@lru_cache(maxsize=2048)
def _parse_cached(script: str, session: tuple[tuple[str, tuple[str, bool]], ...]) -> sc.ParsedScript:
    """Parsing is pure and the result immutable; clients repeat the same scripts a lot."""
    return sc.parse_script(script, dict(session))


# Statements whose dry run (argument check, spec §7) depends only on their literal arguments and
# the settings, never on the session variables, the planned pose or the robot state: a script made
# of these alone gives the same dry-run result every time, so the robot remembers it by script.
# (WaitQueueTag inside an expression reads the tags, motions depend on the planned pose, names
# on the session variables: any of those makes a script "dynamic", dry-run every time.)
_STATIC_STATEMENTS = frozenset({"QueueTag", "WaitQueueTag", "Sleep", "ScriptExit", "Pause", "Resume",
                                "StopAndClearBuffer", "ChangeLoad", "ListenSend", "GetString", "Length"})
_STATIC_EXPR_FUNCTIONS = frozenset({"GetString", "Length"})
_DRY_CACHE_SIZE = 1024


def _literal_only(expr: sc.Expr) -> bool:
    kind = type(expr)
    if kind is sc.Num or kind is sc.Str or kind is sc.Bool:
        return True
    if kind is sc.ArrayLit:
        return all(_literal_only(item) for item in expr.items)
    if kind is sc.Unary:
        return _literal_only(expr.operand)
    if kind is sc.Binary:
        return _literal_only(expr.left) and _literal_only(expr.right)
    if kind is sc.Call:
        return expr.name in _STATIC_EXPR_FUNCTIONS and all(_literal_only(a) for a in expr.args)
    return False


def _dry_run_is_static(parsed: sc.ParsedScript) -> bool:
    """Whether the dry run of ``parsed`` is a pure function of its text (see above)."""
    for line in parsed.lines:
        stmt = line.statement
        if type(stmt) is sc.Empty:
            continue
        if type(stmt) is not sc.ExprStmt:
            return False
        call = stmt.expr
        if type(call) is not sc.Call or call.name not in _STATIC_STATEMENTS:
            return False
        if not all(_literal_only(arg) for arg in call.args):
            return False
    return True


class NodeState(str, Enum):
    """Spec §1 state machine."""

    STOPPED = "STOPPED"    # project not running: port closed
    RUNNING = "RUNNING"    # project running, flow outside the Listen node
    IN_NODE = "IN_NODE"
    EXITING = "EXITING"    # ScriptExit() waiting for the motion queue to drain


# The states the clock code compares with at every advance, as module constants: an Enum member
# read through its class costs ~50 ns on Python 3.11 (the enum's class-attribute lookup), a
# global ~5 ns, and in lockstep the robot's clock moves every scan.
_STOPPED = NodeState.STOPPED
_IN_NODE = NodeState.IN_NODE
_RUNNING = NodeState.RUNNING

# Immutable records, as named tuples: several are made per frame and a tuple is far cheaper to
# build than a frozen dataclass.
class Send(NamedTuple):
    conn: int
    data: bytes
    at_ns: int


class Close(NamedTuple):
    conn: int | None  # None = every connection (project stopped)
    at_ns: int


Action = Send | Close
_new_tuple = tuple.__new__  # builds a named tuple without its Python-level __new__


class Robot:
    """A TM robot running a project whose flow sits in a Listen node."""

    def __init__(self, settings: EmulatorSettings = DEFAULT_SETTINGS, faults: FaultPlan = NO_FAULTS,
                 now_ns: int = 0) -> None:
        self.settings = settings
        self.faults = faults
        self.kin = Kinematics(settings)
        self.planner = Planner(self.kin, settings)
        self.executor = MotionExecutor(self.kin, settings.home_joints_deg)
        self.executor.stalled = faults.stay_busy
        self.plan = PlannedState(self.executor.rest_joints.copy(), self.executor.rest_tcp.copy())
        self.base = np.eye(4)
        self.base_name = "RobotBase"
        self.tool = np.eye(4)
        self.tcp_name = "NOTOOL"
        self.payload_kg = 0.0
        self.io = new_io()  # digital I/O (builtins.io_read / io_write)
        self.now_ns = now_ns
        self.start_ns = now_ns
        self.motion_ns = 0
        self.paused = False
        self.state = NodeState.RUNNING
        self.connections: list[int] = []
        self.buffer: deque[ScriptJob] = deque()  # §4.3 TMSCT receive buffer, FIFO
        self.current: ScriptJob | None = None
        self.variables: dict[str, list[Any]] = {}  # session-local (§4.1)
        self.tags: OrderedDict[int, str] = OrderedDict()  # tag -> "true"/"false" (§5.2)
        self.tag_owner: dict[int, int] = {}
        self.enter_at_ns: int | None = now_ns + settings.enter_node_delay_ms * NS_PER_MS \
            if settings.start_in_node else None
        self.node_entered_ns = 0
        self.last_packet_ns = now_ns
        self.tmsct_count = 0
        self.next_unsolicited_ns = now_ns + faults.unsolicited_every_ms * NS_PER_MS \
            if faults.unsolicited_every_ms else None
        self.stop_at_ns = now_ns + faults.stop_project_at_ms * NS_PER_MS \
            if faults.stop_project_at_ms is not None else None
        self.exit_path = ""
        # Human-readable events (live view, debugging), formatted when read (see ``log``).
        self._log: deque[tuple[int, str]] = deque(maxlen=200)
        # Dry-run results of static scripts: id(parsed) -> (parsed, settings, error lines).
        self._dry_cache: dict[int, tuple[sc.ParsedScript, EmulatorSettings, tuple[int, ...] | None]] = {}
        self._out: list[Action] = []
        # The instant up to which everything due has been handled by advance()/handle(), with no
        # other public call since: advancing to it again is a no-op and is skipped.
        self._settled_ns: int | None = None
        # After a settling `advance`, the next instant at which something happens by itself
        # (`_next_internal_ns()`, None: nothing pending), valid while `_deadline_known`: until a
        # call other than `advance` changes the state (`forget_deadline`). While nothing is due,
        # time passing does not change it (a motion's end moves with the wall clock and the
        # motion clock together; the other deadlines are wall-clock instants), so `advance` to
        # an earlier instant only moves the clocks: in lockstep that is every scan but the few
        # that deliver a frame or reach a motion's end (about 800 bytecodes a scan otherwise).
        self._deadline_known = False
        self._deadline_ns: int | None = None
        # set by an `InProcessLink` that lets the clocks lag on quiet steps: brings them up to
        # date before `snapshot` reads them
        self.catch_up: Callable[[], None] | None = None
        self._process_due()

    # ================================================================ public API

    @property
    def accepting(self) -> bool:
        """Whether the listener exists (spec §1.2: only while the project runs)."""
        return self.state != NodeState.STOPPED

    def connect(self, conn: int, now_ns: int) -> list[Action]:
        self.forget_deadline()
        self._run_until(now_ns)
        self.connections.append(conn)
        if self.settings.entry_message_on_connect and self.state == NodeState.IN_NODE:
            self.send(conn, encode("TMSCT", "0," + self.settings.send_message))
        return self._take()

    def disconnect(self, conn: int, now_ns: int) -> list[Action]:
        """Forget a connection.  Choice: its scripts already received still run (their replies
        are dropped) and its motions continue, as nothing in the spec aborts them."""
        self.forget_deadline()
        self._run_until(now_ns)
        if conn in self.connections:
            self.connections.remove(conn)
        return self._take()

    def handle(self, conn: int, result: Frame | FrameError, now_ns: int) -> list[Action]:
        """Answer one decoded frame (or framing error) from ``conn``."""
        self._deadline_known = False
        if now_ns != self._settled_ns:
            self._run_until(now_ns)
        self.last_packet_ns = self.now_ns
        if isinstance(result, FrameError):
            self.send(conn, encode_cperr(result.code))
        elif result.header == "TMSTA":
            self._handle_tmsta(conn, result.data)
        else:
            self._handle_tmsct(conn, result.data)
        self._process_due()  # runs until nothing changes: settled at now_ns
        self._settled_ns = now_ns
        return self._take()

    def advance(self, now_ns: int) -> list[Action]:
        """Let time pass up to ``now_ns``."""
        if now_ns != self._settled_ns:
            deadline = self._deadline_ns
            if self._deadline_known and now_ns > self.now_ns and (deadline is None or now_ns < deadline):
                # nothing due up to now_ns (later than self.now_ns, earlier than the known
                # deadline): what `_run_until(now_ns)` would do, written here without its call
                # (the lockstep loop passes here on nearly every scan): the clocks move on, the
                # executor's too (its `advance` with nothing due only moves its clock, and not
                # while the motion is stalled)
                running = not self.paused and self.state != _STOPPED
                if running:
                    self.motion_ns += now_ns - self.now_ns
                self.now_ns = now_ns
                executor = self.executor
                if running and (executor.queue or executor.active) and not executor.stalled \
                        and executor.time_ns < self.motion_ns:
                    executor.time_ns = self.motion_ns
            else:
                self._run_until(now_ns)
                deadline = self._next_internal_ns()
                # known only when nothing is left due at now_ns (see `_run_until`'s step past)
                self._deadline_known = deadline is None or deadline > self.now_ns
                self._deadline_ns = deadline
            self._settled_ns = now_ns
        if self._out:
            return self._take()
        return []

    def next_deadline_ns(self) -> int | None:
        """The next instant at which something happens by itself (None: nothing pending)."""
        if self._deadline_known:
            return self._deadline_ns
        return self._next_internal_ns()

    def forget_deadline(self) -> None:
        """The state is about to change (a public call, a fault plan applied from outside): the
        next `advance` runs in full and the next deadline is computed again."""
        self._deadline_known = False
        self._settled_ns = None

    def start_project(self, now_ns: int) -> list[Action]:
        """Start the project again after a stop (flow enters the node after the entry delay)."""
        self.forget_deadline()
        self._run_until(now_ns)
        if self.state == NodeState.STOPPED:
            self.state = NodeState.RUNNING
            self.enter_at_ns = self.now_ns + self.settings.enter_node_delay_ms * NS_PER_MS
            self._process_due()
        return self._take()

    def stop_project(self, now_ns: int) -> list[Action]:
        """Project stop (operator, fault): motion stops, every socket closed (spec §1.2, §8)."""
        self.forget_deadline()
        self._run_until(now_ns)
        self._stop_project()
        return self._take()

    def enter_node(self, now_ns: int) -> list[Action]:
        """Make the flow reach the Listen node now (if the project runs and it is not in it)."""
        self.forget_deadline()
        self._run_until(now_ns)
        if self.state == NodeState.RUNNING:
            self._enter_node()
        return self._take()

    def snapshot(self) -> dict[str, Any]:
        """Plain-data view of the robot for the live terminal view and tests."""
        if self.catch_up is not None:
            self.catch_up()
        tcp = self.executor.current_tcp()
        return {
            "t_s": (self.now_ns - self.start_ns) / 1e9,
            "state": self.state.value,
            "paused": self.paused,
            "connections": list(self.connections),
            "moving": self.executor.moving,
            "queue_length": len(self.executor.queue),
            "scripts_buffered": len(self.buffer) + (1 if self.current else 0),
            "pose": [round(float(v), 3) for v in self._pose_in_base(tcp)],
            "joints": [round(float(v), 3) for v in self.executor.current_joints(self.tool)],
            "base": self.base_name,
            "tcp": self.tcp_name,
            "tags": dict(self.tags),
            "do": {module: list(values["DO"]) for module, values in self.io.items()},
        }

    def pose_at(self, now_ns: int) -> list[float]:
        """The TCP pose (in the current base, like ``snapshot()["pose"]``) at ``now_ns``,
        interpolated along the active motions without advancing the robot. ``snapshot()`` shows
        the pose of the last event (a frame, a motion's end), which may be a second old in the
        middle of a move; a live view reads this instead. Read-only: no state changes."""
        executor = self.executor
        active = executor.active
        if not active or self.paused or self.state == _STOPPED or executor.stalled or now_ns <= self.now_ns:
            tcp = executor.current_tcp()
        else:
            at = max(executor.time_ns, self.motion_ns + (now_ns - self.now_ns))
            tcp = active[-1].tcp_at(at).copy()
            for older in active[:-1]:   # the superposition current_tcp() draws, at `at`
                tcp[:3, 3] += older.tcp_at(at)[:3, 3] - older.end_tcp[:3, 3]
        return [round(float(v), 3) for v in self._pose_in_base(tcp)]

    # ================================================================ time

    def _take(self) -> list[Action]:
        out, self._out = self._out, []
        return out

    def send(self, conn: int, data: bytes) -> None:
        """Queue ``data`` for ``conn``, stamped now (the caller gets it from the public call)."""
        self._out.append(_new_tuple(Send, (conn, data, self.now_ns)))  # = Send(conn, data, now)

    def _motion_to_wall(self, motion_ns: int) -> int:
        return self.now_ns + max(0, motion_ns - self.motion_ns)

    def _next_internal_ns(self) -> int | None:
        # The earliest of the candidates below (None: none); written without building a list, as
        # it runs several times per received frame.
        best: int | None = None
        executor = self.executor
        if not self.paused and self.state != _STOPPED and (executor.queue or executor.active):
            ev = executor.next_event_ns()
            if ev is not None:
                best = self._motion_to_wall(ev)
        job = self.current
        if job is not None and job.wait is not None and job.wait.until_ns is not None:
            t = job.wait.until_ns
            if best is None or t < best:
                best = t
        t = self.enter_at_ns
        if t is not None and (best is None or t < best):
            best = t
        t = self.next_unsolicited_ns
        if t is not None and (best is None or t < best):
            best = t
        t = self.stop_at_ns
        if t is not None and (best is None or t < best):
            best = t
        settings = self.settings
        if (settings.data_timeout_ms > 0 or settings.connection_timeout_ms > 0) and self.state == _IN_NODE:
            if settings.data_timeout_ms > 0:
                t = max(self.last_packet_ns, self.node_entered_ns) + settings.data_timeout_ms * NS_PER_MS
                if best is None or t < best:
                    best = t
            if settings.connection_timeout_ms > 0 and not self.connections:
                t = self.node_entered_ns + settings.connection_timeout_ms * NS_PER_MS
                if best is None or t < best:
                    best = t
        return best

    def _set_clock(self, t_ns: int) -> None:
        if t_ns <= self.now_ns:
            return
        if not self.paused and self.state != _STOPPED:
            self.motion_ns += t_ns - self.now_ns
        self.now_ns = t_ns

    def _run_until(self, now_ns: int) -> None:
        for _ in range(1_000_000):
            nxt = self._next_internal_ns()
            if nxt is None or nxt > now_ns:
                break
            self._set_clock(nxt)
            if not self._process_due():
                # Nothing changed at this instant; step past it to avoid spinning.
                if nxt >= now_ns:
                    break
                self._set_clock(nxt + 1)
        # Everything due up to now_ns was handled in the loop; only the clocks move on (the
        # executor's too, as the reported pose is sampled at its time).
        if now_ns > self.now_ns:
            self._set_clock(now_ns)
        executor = self.executor
        if not self.paused and self.state != _STOPPED and (executor.queue or executor.active):
            for event in self.executor.advance(self.motion_ns):  # none due: see the loop above
                self._marker_reached(event.marker)

    def _process_due(self) -> bool:
        """Handle everything due at ``self.now_ns``; return whether anything happened."""
        progressed = False
        settings = self.settings
        timeouts = settings.data_timeout_ms > 0 or settings.connection_timeout_ms > 0
        executor = self.executor
        for _ in range(10_000):
            changed = False
            if self.stop_at_ns is not None and self.now_ns >= self.stop_at_ns:
                self.stop_at_ns = None
                self._stop_project()
                changed = True
            if self.enter_at_ns is not None and self.now_ns >= self.enter_at_ns:
                self.enter_at_ns = None
                if self.state == _RUNNING:
                    self._enter_node()
                changed = True
            if self.next_unsolicited_ns is not None and self.now_ns >= self.next_unsolicited_ns:
                self.next_unsolicited_ns = self.now_ns + self.faults.unsolicited_every_ms * NS_PER_MS
                for conn in self.connections:
                    self.send(conn, encode("TMSTA", "90,unsolicited"))
                changed = True
            state = self.state
            if timeouts and state == _IN_NODE and self._timed_out():
                changed = True
                state = self.state
            if not self.paused and state != _STOPPED:
                for event in executor.advance(self.motion_ns):
                    self._marker_reached(event.marker)
                    changed = True
            # (_run_scripts does nothing without a current or buffered script.)
            if (self.current is not None or self.buffer) and self._run_scripts():
                changed = True
            if not changed:
                break
            progressed = True
        return progressed

    def _timed_out(self) -> bool:
        s = self.settings
        if s.data_timeout_ms > 0 and \
                self.now_ns >= max(self.last_packet_ns, self.node_entered_ns) + s.data_timeout_ms * NS_PER_MS:
            self.note("data timeout: Fail path")  # §1.6
            self._leave_node("Fail")
            return True
        if s.connection_timeout_ms > 0 and not self.connections and \
                self.now_ns >= self.node_entered_ns + s.connection_timeout_ms * NS_PER_MS:
            self.note("connection timeout: Fail path")
            self._leave_node("Fail")
            return True
        return False

    def note(self, text: str) -> None:
        """Add one human-readable event to :attr:`log`."""
        self._log.append((self.now_ns, text))

    @property
    def log(self) -> deque[str]:
        """The last 200 events, oldest first, as ``"  seconds text"``."""
        start = self.start_ns
        return deque((f"{(t - start) / 1e9:9.3f} {text}" for t, text in tuple(self._log)), maxlen=200)

    # ================================================================ node lifecycle

    def _enter_node(self) -> None:
        """§1.5: the flow reaches the node: entry message to every open connection."""
        self.state = NodeState.IN_NODE
        self.node_entered_ns = self.now_ns
        self.last_packet_ns = self.now_ns
        self.exit_path = ""
        self.note("entered Listen node")
        for conn in self.connections:
            self.send(conn, encode("TMSCT", "0," + self.settings.send_message))

    def _leave_node(self, path: str) -> None:
        """§1.7: leave via Pass/Fail.  Session variables are dropped; the TCP connections stay."""
        self.state = NodeState.RUNNING
        self.exit_path = path
        self.variables.clear()
        self.note(f"left Listen node ({path})")
        after = self.settings.after_exit
        if after is AfterExit.REENTER:
            self.enter_at_ns = self.now_ns + self.settings.reenter_delay_ms * NS_PER_MS
        elif after is AfterExit.STOP:
            self._stop_project()

    def _stop_project(self) -> None:
        self.note("project stopped")
        self.executor.stop_and_clear(self.tool)
        self.plan = PlannedState(self.executor.rest_joints.copy(), self.executor.rest_tcp.copy(),
                                 self.plan.base, self.plan.tool)
        self.buffer.clear()
        self.current = None
        self.variables.clear()
        self.state = NodeState.STOPPED
        self.enter_at_ns = None
        self.paused = False
        self._out.append(Close(None, self.now_ns))
        self.connections.clear()

    # ================================================================ TMSTA (§5)

    def _handle_tmsta(self, conn: int, data: bytes) -> None:
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            self.send(conn, encode_cperr(Cperr.DATA))
            return
        parts = text.split(",")
        sub = parts[0]
        if sub == "00":
            # §5.1: extra params (tmr_ros2 sends "00,") are ignored.
            if self.state == NodeState.IN_NODE:
                self.send(conn, encode("TMSTA", f"00,true,{self.settings.send_message}"))
            else:
                self.send(conn, encode("TMSTA", "00,false,"))
            return
        if sub == "01" and len(parts) >= 2 and parts[1] != "":
            tag_text = parts[1]
            state = "none"
            if tag_text.isascii() and tag_text.isdigit():
                state = self.tags.get(int(tag_text), "none")
            shown = tag_text if self.settings.tag_reply_echo_text else \
                (f"{int(tag_text):02d}" if tag_text.isascii() and tag_text.isdigit() else tag_text)
            self.send(conn, encode("TMSTA", f"01,{shown},{state}"))
            return
        # §5.5 unknown SubCmd; §5.4/§11 #12 a client sending 90-99; Choice: "01" without a tag.
        self.send(conn, encode_cperr(Cperr.DATA))

    # ================================================================ TMSCT (§4)

    def _handle_tmsct(self, conn: int, data: bytes) -> None:
        try:
            text = data.decode("utf-8")
        except UnicodeDecodeError:
            self.send(conn, encode_cperr(Cperr.DATA))
            return
        script_id, sep, script = text.partition(",")
        # _ID_CHARS: ASCII letters and digits, i.e. isascii() and isalnum().
        if not sep or not script_id or not (script_id.isascii() and script_id.isalnum()):
            self.send(conn, encode_cperr(Cperr.DATA))  # §4.1 ID rule
            return
        if self.state != NodeState.IN_NODE:
            self.send(conn, encode_cperr(Cperr.NOT_IN_NODE))  # §4.4, §4.6 (exiting)
            return
        self.tmsct_count += 1
        session = tuple(sorted((name, (v[0], v[1])) for name, v in self.variables.items())) \
            if self.variables else ()
        parsed = _parse_cached(script, session)
        job = ScriptJob(conn, script_id, parsed)
        every = self.faults.answer_error_every
        if every and self.tmsct_count % every == 0:
            job.forced_error = True
        elif parsed.priority is not None and not parsed.error_lines:
            self._run_priority(job, parsed.priority)
            return
        self.buffer.append(job)

    def reply(self, job: ScriptJob, status: str) -> None:
        """``$TMSCT <id>,<status>`` to the script's connection, then its deferred frames (§4.2)."""
        if job.conn in self.connections:
            self.send(job.conn, encode("TMSCT", f"{job.script_id},{status}"))
        for conn, frame in job.deferred:
            if conn in self.connections:
                self.send(conn, frame)
        job.deferred.clear()

    def _run_priority(self, job: ScriptJob, command: sc.PriorityCommand) -> None:
        """§4.5: handled at once, even while another script blocks.  The interrupted script gets
        its OK first, then this packet's OK."""
        self.note(f"priority {command.name}({command.mode})")
        self.stop_and_clear()
        interrupted = self.current
        if command.name == "ScriptExit" or command.mode >= 1:
            if interrupted is not None:
                self.current = None
                self.reply(interrupted, "OK")
            if command.name == "ScriptExit" or command.mode == 2:
                # Choice: ScriptExit(n) clears the script buffer like StopAndClearBuffer(2); the
                # discarded scripts never get a reply (§4.5 table).
                self.buffer.clear()
        self.reply(job, "OK")
        if command.name == "ScriptExit":
            self._leave_node("Pass" if command.mode == 1 else "Fail")

    def stop_and_clear(self) -> None:
        """Stop the motion and drop the motion queue; the plan restarts from the rest pose (§8)."""
        self.executor.stop_and_clear(self.tool)
        # §8 / §11 #7: dropped tags stay "false", no notification.
        if self.settings.stop_applies_queued_frames:
            base, tool = self.plan.base, self.plan.tool
        else:
            base, tool = self.base, self.tool      # dropped ChangeBase/ChangeTCP markers never happened
        self.plan = PlannedState(self.executor.rest_joints.copy(), self.executor.rest_tcp.copy(), base.copy(), tool.copy())
        self.base, self.tool = base.copy(), tool.copy()

    # ---------------------------------------------------------------- script runner

    def _run_scripts(self) -> bool:
        """Run buffered scripts one at a time (§4.3); return whether anything happened."""
        progressed = False
        while True:
            job = self.current
            if job is None:
                if not self.buffer or self.state not in (NodeState.IN_NODE, NodeState.EXITING):
                    return progressed
                job = self.current = self.buffer.popleft()
                progressed = True
                if not self._start_job(job):
                    self.current = None
                    continue
            if job.wait is not None:
                if not self._wait_over(job):
                    return progressed
                job.wait = None
                progressed = True
                if job.exiting:
                    self._finish_exit(job)
                    continue
            self._resume(job)
            progressed = True
            if job.wait is None and self.current is job:
                self.current = None
                self.reply(job, "OK")

    def _start_job(self, job: ScriptJob) -> bool:
        """Static and dry-run checks; False if the script was answered ERROR (nothing runs)."""
        if job.forced_error:
            self.reply(job, "ERROR;1")  # fault "error"
            return False
        errors: Any = job.parsed.error_lines
        if not errors and self.settings.reject_invalid_args:
            errors = self._dry_run(job)
        if errors:
            self.reply(job, "ERROR;" + ";".join(str(n) for n in sorted(set(errors))))
            return False
        return True

    def _dry_run(self, job: ScriptJob) -> Any:
        """Error lines of the dry run (argument values, spec §7); remembered for static scripts."""
        parsed = job.parsed
        entry = self._dry_cache.get(id(parsed))
        if entry is not None and entry[0] is parsed and entry[1] is self.settings:
            if entry[2] is not None:
                return entry[2]
            static = False
        else:
            static = _dry_run_is_static(parsed)
        ctx = ScriptContext(True, job.conn, {k: list(v) for k, v in self.variables.items()}, self.plan.copy())
        self._execute_lines(job, ctx, dry=True)
        if entry is None or entry[0] is not parsed or entry[1] is not self.settings:
            if len(self._dry_cache) >= _DRY_CACHE_SIZE:
                self._dry_cache.clear()
            # The entry holds ``parsed``, so its id cannot be reused while the entry exists.
            self._dry_cache[id(parsed)] = (parsed, self.settings, tuple(ctx.errors) if static else None)
        return ctx.errors

    def _resume(self, job: ScriptJob) -> None:
        ctx = ScriptContext(False, job.conn, self.variables, self.plan)
        self._execute_lines(job, ctx, dry=False)

    def _execute_lines(self, job: ScriptJob, ctx: ScriptContext, dry: bool) -> None:
        lines = job.parsed.lines
        pc = 0 if dry else job.pc
        while pc < len(lines):
            line = lines[pc]
            pc += 1
            ctx.line = line.number
            try:
                stop = self._exec_statement(job, line.statement, ctx)
            except ArgError as exc:
                if dry:
                    ctx.errors.append(line.number)
                else:
                    self.note(f"{job.script_id} line {line.number}: {exc} (function returns false)")
                continue
            if stop and not dry:
                job.pc = pc
                return
            if stop == "exit":
                break  # §4.6 statements after ScriptExit() are not executed
        if not dry:
            job.pc = len(lines)

    def _wait_over(self, job: ScriptJob) -> bool:
        wait = job.wait
        assert wait is not None
        if wait.kind == "tag":
            return self.tags.get(wait.tag) == "true" or wait.tag not in self.tags
        if wait.kind == "delay":
            return wait.until_ns is not None and self.now_ns >= wait.until_ns
        if wait.kind == "waittag":
            done = self.tags.get(wait.tag) == "true" or wait.tag not in self.tags
            return done or (wait.until_ns is not None and self.now_ns >= wait.until_ns)
        if wait.kind == "drain":
            return self.executor.idle
        return True  # pragma: no cover

    def begin_exit(self) -> None:
        """§4.6 normal ScriptExit(): the node drains the motion queue and accepts no script."""
        self.state = NodeState.EXITING
        self.note("ScriptExit(): draining motion queue")

    def _finish_exit(self, job: ScriptJob) -> None:
        """§4.6: the motion queue drained after ScriptExit(): leave via Pass, then the OK."""
        self.current = None
        self._leave_node("Pass")
        if self.settings.script_exit_ok_after_drain:
            self.reply(job, "OK")

    # ---------------------------------------------------------------- statements

    def _exec_statement(self, job: ScriptJob, stmt: sc.Statement, ctx: ScriptContext) -> str | None:
        """Execute one statement; return "block"/"exit" if the script must stop here."""
        if stmt.__class__ is sc.ExprStmt:  # the common case first (a function call)
            expr = stmt.expr
            if expr.__class__ is sc.Call and expr.name in BLOCKING_STATEMENTS:
                return BLOCKING_STATEMENTS[expr.name](self, job, expr, ctx)
            self.evaluate(expr, ctx)
            return None
        if isinstance(stmt, sc.Empty):
            return None
        if isinstance(stmt, sc.Declare):
            value = self.evaluate(stmt.init, ctx) if stmt.init is not None else (
                [] if stmt.is_array else _default_value(stmt.type_name))
            ctx.variables[stmt.name.lower()] = [stmt.type_name, stmt.is_array,
                                                _coerce(stmt.type_name, stmt.is_array, value)]
            return None
        if isinstance(stmt, sc.Assign):
            self._assign(stmt, ctx)
            return None
        assert isinstance(stmt, sc.ExprStmt)
        expr = stmt.expr
        if isinstance(expr, sc.Call) and expr.name in BLOCKING_STATEMENTS:
            return BLOCKING_STATEMENTS[expr.name](self, job, expr, ctx)
        self.evaluate(expr, ctx)
        return None

    def _assign(self, stmt: sc.Assign, ctx: ScriptContext) -> None:
        value = self.evaluate(stmt.value, ctx)
        target = stmt.target
        if isinstance(target, sc.Name):
            entry = ctx.variables[target.name.lower()]
            if stmt.op != "=":
                value = _arith(stmt.op[0], entry[2], value)
            entry[2] = _coerce(entry[0], entry[1], value)
        elif isinstance(target, sc.Index) and sc.io_member(target.target) is not None:
            member = target.target
            module = self.evaluate(member.target.index, ctx)
            io_write(self, ctx, module, member.name, self.evaluate(target.index, ctx), value)
        elif isinstance(target, sc.Index) and isinstance(target.target, sc.Name):
            entry = ctx.variables[target.target.name.lower()]
            idx = int(self.evaluate(target.index, ctx))
            if not 0 <= idx < len(entry[2]):
                raise ArgError("index out of range")
            if stmt.op != "=":
                value = _arith(stmt.op[0], entry[2][idx], value)
            entry[2] = list(entry[2])
            entry[2][idx] = _coerce(entry[0], False, value)
        else:
            raise ArgError("cannot assign")

    # ---------------------------------------------------------------- expressions

    def evaluate(self, expr: sc.Expr, ctx: ScriptContext) -> Any:
        """The value of a script expression; a built-in call goes to :data:`builtins.FUNCTIONS`."""
        if isinstance(expr, sc.Num):
            return expr.value
        if isinstance(expr, (sc.Str, sc.Bool)):
            return expr.value
        if isinstance(expr, sc.ArrayLit):
            return [self.evaluate(item, ctx) for item in expr.items]
        if isinstance(expr, sc.Name):
            return ctx.variables[expr.name.lower()][2]
        if isinstance(expr, sc.Attr):
            if sc.io_member(expr) is not None:
                return io_read(self, self.evaluate(expr.target.index, ctx), expr.name)
            return self._robot_member(expr.name)
        if isinstance(expr, sc.Index):
            if isinstance(expr.target, sc.Name) and expr.target.name.lower() in ("robot", "io"):
                return None  # Robot[0] / IO["..."] itself; members are read through Attr
            seq = self.evaluate(expr.target, ctx)
            idx = self.evaluate(expr.index, ctx)
            if not isinstance(seq, (list, tuple)) or not isinstance(idx, (int, float)) \
                    or not 0 <= int(idx) < len(seq):
                raise ArgError("index out of range")
            return seq[int(idx)]
        if isinstance(expr, sc.Unary):
            value = self.evaluate(expr.operand, ctx)
            if expr.op == "!":
                return not value
            return -value if expr.op == "-" else +value
        if isinstance(expr, sc.Binary):
            left, right = self.evaluate(expr.left, ctx), self.evaluate(expr.right, ctx)
            return _binary(expr.op, left, right)
        if isinstance(expr, sc.Postfix):
            target = expr.target
            if isinstance(target, sc.Name):
                entry = ctx.variables[target.name.lower()]
                old = entry[2]
                entry[2] = _coerce(entry[0], entry[1], old + (1 if expr.op == "++" else -1))
                return old
            raise ArgError("++/-- on element")
        if isinstance(expr, sc.Call):
            args = [self.evaluate(a, ctx) for a in expr.args]
            return FUNCTIONS[expr.name](self, args, ctx)
        raise ArgError("unsupported expression")  # pragma: no cover

    def _robot_member(self, name: str) -> Any:
        """Robot[0].<member> (read-only robot variables that clients read)."""
        key = name.lower()
        tcp = self.executor.current_tcp()
        if key == "coordrobot":
            return [float(v) for v in matrix_to_pose(tcp)]
        if key == "coordbase":
            return [float(v) for v in self._pose_in_base(tcp)]
        if key == "joint":
            return [float(v) for v in self.executor.current_joints(self.tool)]
        if key == "tcpspeed3d":
            return self._tcp_speed_mm_s()
        if key == "tcpforce3d":
            return 0.0  # no force model
        if key == "basename":
            return self.base_name
        if key == "tcpname":
            return self.tcp_name
        if key == "payload":
            return self.payload_kg
        raise ArgError(f"unknown member {name}")  # pragma: no cover - checked statically

    def _pose_in_base(self, tcp: np.ndarray) -> np.ndarray:
        return matrix_to_pose(dm.matmul(dm.rigid_inverse(self.base), tcp))

    def _tcp_speed_mm_s(self) -> float:
        if not self.executor.active:
            return 0.0
        seg = self.executor.active[-1]
        dt = NS_PER_MS
        t = self.executor.time_ns
        a = seg.tcp_at(max(seg.start_ns, t - dt))[:3, 3]
        b = seg.tcp_at(t)[:3, 3]
        return dm.norm(b - a) / (dt / 1e9)

    # ================================================================ motion queue (§8)

    def queue_motion(self, ctx: ScriptContext, item: Any) -> None:
        """Append a motion segment or marker to the motion queue (not in a dry run)."""
        if not ctx.dry:
            self.executor.enqueue(item)

    def _marker_reached(self, marker: Marker) -> None:
        if marker.kind == "tag":
            tag = int(marker.value)
            state = "false" if self.faults.tag_false else "true"
            if tag in self.tags:
                self.tags[tag] = state
            self.note(f"QueueTag {tag} reached")
            # §5.3: "01,<nn>,true" with nn zero-padded to two digits.
            frame = encode("TMSTA", f"01,{tag:02d},{state}")
            owner = marker.owner
            targets = self.connections if self.settings.tag_notify_broadcast else \
                [owner] if owner in self.connections else []
            job = self.current
            defer = (not self.settings.notify_before_ok and job is not None and job.wait is not None
                     and job.wait.kind == "tag" and job.wait.tag == tag)
            for conn in targets:
                if defer:
                    job.deferred.append((conn, frame))  # §11 #4 alternative: OK first
                else:
                    self.send(conn, frame)
        elif marker.kind == "base":
            self.base_name, self.base = marker.value
        elif marker.kind == "tcp":
            self.tcp_name, self.tool = marker.value
        elif marker.kind == "load":
            self.payload_kg = float(marker.value)
        elif marker.kind == "do":
            apply_io_marker(self, marker)


# ---------------------------------------------------------------- values


def _default_value(type_name: str) -> Any:
    return {"string": "", "bool": False, "float": 0.0, "double": 0.0}.get(type_name, 0)


def _coerce(type_name: str, is_array: bool, value: Any) -> Any:
    if is_array:
        if not isinstance(value, (list, tuple)):
            raise ArgError("array expected")
        return [_coerce(type_name, False, v) for v in value]
    try:
        if type_name in ("int", "byte"):
            if isinstance(value, str):
                value = float(value)
            number = int(value)
            return number & 0xFF if type_name == "byte" else number
        if type_name in ("float", "double"):
            return float(value)
        if type_name == "string":
            return format_value(value)
        if type_name == "bool":
            if isinstance(value, str):
                return value.lower() == "true"
            return bool(value)
    except (TypeError, ValueError, OverflowError):
        raise ArgError(f"cannot convert {value!r} to {type_name}") from None
    return value


def _arith(op: str, left: Any, right: Any) -> Any:
    return _binary(op, left, right)


def _binary(op: str, left: Any, right: Any) -> Any:
    if op == "+" and (isinstance(left, str) or isinstance(right, str)):
        return format_value(left) + format_value(right)
    if op in ("&&", "||"):
        return (bool(left) and bool(right)) if op == "&&" else (bool(left) or bool(right))
    if op in ("==", "!="):
        return (left == right) if op == "==" else (left != right)
    if isinstance(left, (list, tuple)) or isinstance(right, (list, tuple)) \
            or isinstance(left, str) or isinstance(right, str):
        raise ArgError(f"operator {op} on these values")
    if op == "<":
        return left < right
    if op == ">":
        return left > right
    if op == "<=":
        return left <= right
    if op == ">=":
        return left >= right
    if op == "+":
        return left + right
    if op == "-":
        return left - right
    if op == "*":
        return left * right
    if op in ("/", "%"):
        if right == 0:
            raise ArgError("division by zero")
        if op == "%":
            return left % right
        if isinstance(left, int) and isinstance(right, int) and not isinstance(left, bool):
            return int(left / right)  # integer division truncates toward zero
        return left / right
    raise ArgError(f"unknown operator {op}")  # pragma: no cover
