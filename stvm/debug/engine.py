"""The debug engine: the VM in a worker thread, stopping on ST statements.

The worker runs scans of a debug build (`build.py`). Breakpoints are calls compiled into the
generated code at their lines (`hooks.py`), so `continue` and `scan N` run untraced; while
stepping, or when a pause or the end is asked, `sys.settrace` is installed in the worker thread
only. The trace function follows generated frames (file `<stvm-generated>`) and looks at line
events on statement starts (`StatementMap.stops`); everything else returns at once. At a stop the
worker blocks inside the breakpoint call or the trace function until a front end (console or
DAP, in another thread) resumes it, so the stopped frames, and every variable, stay exactly as
the ST code left them.

Nothing of this runs in `stvm run`: a normal build has no trace function and keeps its locals
cache (see bench/bench_debug_overhead.py).

Execution control, in ST statements:

* `step`: stop at the next statement entered, wherever it is (into FB and FUNCTION bodies, and on
  to the next scan's first statement after the last one of a scan);
* `next`: the next statement at the same call depth or shallower (over calls);
* `finish`: the next statement in a caller; from a PROGRAM body, the end of the scan;
* `scan N`: run until N scan ends have passed (the current scan's end counts as the first);
* `continue`: run until a breakpoint, a pause or a fault.

A loop's test (WHILE, the FOR increment, REPEAT's UNTIL) is a statement entry on every
iteration, as in controller debuggers, so stepping through a loop shows each turn.

Forcing holds a value at the start and the end of every scan (before the first task and after the
last), as controllers force variables; the ST code may change it in between. A runtime fault
stops the engine post-mortem: the call stack comes from the fault's traceback, whose frames keep
every variable.
"""

from __future__ import annotations

import queue
import sys
import threading
import time
from dataclasses import dataclass, field
from types import CodeType, FrameType
from typing import Any, Callable

from stvm.debug.build import DebugBuild
from stvm.debug.hooks import BreakpointHooks, ThreadKicker
from stvm.debug.scope import Compiled, CompiledStore, DebugError, Scope, ScopeCompiler, run_guarded
from stvm.runtime.catalog import Catalog
from stvm.runtime.format import format_time, format_value
from stvm.runtime.helpers import copy_value
from stvm.runtime.vm import GENERATED_FILENAME, RuntimeFault
from stvm.semantics import types as t
from stvm.semantics.model import POUInfo
from stvm.syntax import nodes as n

# execution modes (what the worker is doing until the next stop)
CONTINUE, STEP, NEXT, FINISH, SCAN = "continue", "step", "next", "finish", "scan"

# stop reasons
ENTRY, BREAKPOINT, STEPPED, PAUSED, SCANNED, FAULT = "entry", "breakpoint", "step", "pause", "scan", "fault"

# engine states
INITIAL, RUNNING, STOPPED, FAULTED, TERMINATED = "initial", "running", "stopped", "faulted", "terminated"


class _Terminate(BaseException):
    """Unwinds the worker out of a scan when the session ends (not an Exception: the VM's fault
    handlers must not turn it into a RuntimeFault)."""


@dataclass
class StackFrame:
    """One POU activation on the stopped call stack (index 0 is the innermost)."""

    index: int
    pou: POUInfo
    node: n.POU
    span: n.Span
    name: str                  # instance path for FB/PROGRAM, the function's name for a FUNCTION
    scope: Scope
    py_frame: FrameType | None = field(default=None, repr=False)

    @property
    def location(self) -> str:
        return f"{self.span.file}:{self.span.line}"


@dataclass
class StopEvent:
    reason: str
    task: str
    scan: int                  # the scan running (or, between scans, the next one to run)
    now_ns: int
    frames: list[StackFrame] = field(default_factory=list)
    breakpoints: list[int] = field(default_factory=list)
    message: str = ""
    fault: RuntimeFault | None = None

    @property
    def between_scans(self) -> bool:
        return not self.frames

    @property
    def span(self) -> n.Span | None:
        return self.frames[0].span if self.frames else None

    def describe(self) -> str:
        where = f"{self.frames[0].location} in {self.frames[0].name}" if self.frames else f"before scan {self.scan}"
        what = {ENTRY: "Stopped at entry", BREAKPOINT: "Breakpoint " + ", ".join(map(str, self.breakpoints)),
                STEPPED: "Stopped", PAUSED: "Paused", SCANNED: "Scan end", FAULT: "Fault"}.get(self.reason, self.reason)
        text = f"{what}: {where} (task {self.task or '-'}, scan {self.scan}, t={format_time(self.now_ns)})"
        if self.message:
            text += f"\n{self.message}"
        return text


@dataclass
class Breakpoint:
    id: int
    file: str                  # as spans name it
    line: int                  # the ST line it stops on (a statement starts there)
    requested_line: int
    pou: POUInfo
    node: n.POU
    gen_lines: list[int]
    condition: str | None = None
    compiled: Compiled | None = None
    hits: int = 0

    def describe(self) -> str:
        text = f"{self.id}: {self.file}:{self.line} in {self.pou.name}"
        if self.condition:
            text += f" if {self.condition}"
        if self.requested_line != self.line:
            text += f" (asked for line {self.requested_line})"
        return text + f", hit {self.hits} time(s)"


@dataclass
class Force:
    target: str                # as the user wrote it
    key: str                   # canonical absolute target, for `unforce`
    value_text: str
    value: Any
    store: CompiledStore
    scope: Scope

    def describe(self) -> str:
        return f"{self.key_display} := {self.value_text}"

    @property
    def key_display(self) -> str:
        prefix = self.scope.path + "." if self.store.root_is_local and self.scope.path else ""
        return prefix + self.target


class Engine:
    """One debug session on one VM. Front ends call the public methods from their own thread;
    `listeners` are called from the worker thread at every stop and at the end."""

    def __init__(self, build: DebugBuild, scan_ns: int = 10_000_000, realtime: bool = False,
                 transport: Any = None, start_dt_ns: int = 0, max_scans: int | None = None) -> None:
        self.build = build
        self.vm = build.project.start(scan=scan_ns, realtime=realtime, start_dt_ns=start_dt_ns, transport=transport)
        self.vm.collect_stats = False
        self.vm.ctx.warn_sink = self._warn
        self.model = build.analysis.model
        self.statements = build.statements
        self.compiler = ScopeCompiler(build)
        self.compiler.set_programs(self.vm.instances)
        self.max_scans = max_scans
        self.breakpoints: dict[int, Breakpoint] = {}
        self.forces: dict[str, Force] = {}
        self.listeners: list[Callable[[StopEvent | None], None]] = []   # None: the session ended
        self.output: list[Callable[[str], None]] = []                    # warnings and notices
        self.state = INITIAL
        self.stop_event: StopEvent | None = None
        self.fault: RuntimeFault | None = None
        self._bp_lines: dict[int, list[Breakpoint]] = {}
        self._next_bp = 1
        self._paths = self._instance_paths()
        self._commands: queue.Queue = queue.Queue()
        self._changed = threading.Condition()
        self._serial = 0                 # counts stops and the end; front ends wait for it to move
        self._mode = CONTINUE
        self._depth = 0                  # call depth a next/finish started from
        self._scans_left = 0
        self._attention = False          # stepping, pausing or ending: look at every statement
        self._code_lines: dict[CodeType, frozenset[int] | None] = {}   # None: never traced
        self._pause = False
        self._terminate = False
        self._statement_seen = False
        self._thread: threading.Thread | None = None
        self._stops = self.statements.stops
        self.vm.on_scan_end.insert(0, self._force_all)
        self._make_tracers()
        # breakpoints as calls in the generated code (hooks.py); the frame a trace function
        # already handled at a hooked line, so that the hook call that follows does not
        self._hooks = BreakpointHooks(build.project.lowered.source, self.vm.namespace, self._hook)
        self._handled: FrameType | None = None
        self._frame_kinds: dict[CodeType, str] = {}            # code object → its POU's kind
        self._condition_names: dict[str, Any] | None = None   # _T and _G of condition evaluation
        self._kicker: ThreadKicker | None = None
        self._trace_wanted_always = False   # a breakpoint line no hook could take: trace it

    # ================================================================ front-end API
    def start(self, stop_on_entry: bool = True) -> None:
        """Start the worker; it stops before the first scan when `stop_on_entry`."""
        if self._thread is not None:
            raise DebugError("the session has already started")
        self.state = RUNNING
        # The scan-end hooks (scenario, lockstep emulator) run no ST code: run them untraced, so
        # the emulator's Python does not pay for the trace function's call events.
        self.vm.on_scan_end[:] = [hook if hook == self._force_all else _untraced(hook, self._trace_call)
                                  for hook in self.vm.on_scan_end]
        self._thread = threading.Thread(target=self._worker, args=(stop_on_entry,), name="stvm-debug-vm", daemon=True)
        self._thread.start()

    def resume(self, mode: str = CONTINUE, count: int = 1) -> int:
        """Resume a stopped engine; returns the serial to pass to `wait`."""
        with self._changed:
            if self.state == FAULTED:
                raise DebugError("the program stopped on a fault; nothing more can run (restart the session)")
            if self.state == TERMINATED:
                raise DebugError("the session has ended")
            if self.state != STOPPED:
                raise DebugError("the program is running")
            serial = self._serial
            self.state = RUNNING
        self._commands.put((mode, count))
        return serial

    def wait(self, serial: int, timeout: float | None = None) -> StopEvent | None:
        """Wait until the engine stops (or ends) after `serial`; the stop, or None if it ended or
        the timeout passed."""
        with self._changed:
            self._changed.wait_for(lambda: self._serial > serial, timeout)
            if self._serial <= serial or self.state == TERMINATED:
                return None
            return self.stop_event

    def run(self, mode: str = CONTINUE, count: int = 1, timeout: float | None = None) -> StopEvent | None:
        """`resume` and `wait` in one call (the console's way)."""
        return self.wait(self.resume(mode, count), timeout)

    def wait_started(self, timeout: float | None = None) -> StopEvent | None:
        """After `start(stop_on_entry=True)`: wait for the entry stop."""
        return self.wait(0, timeout)

    def pause(self) -> None:
        """Ask a running engine to stop at the next statement (or scan end)."""
        if self.state != RUNNING:
            return
        self._pause = True
        self._attention = True
        self._kick()

    def terminate(self, timeout: float = 5.0) -> None:
        """End the session: the worker unwinds, the VM closes its sockets."""
        self._terminate = True
        self._attention = True
        self._kick()
        if self._thread is None:
            self._finish_session()
            return
        self._commands.put(("terminate", 0))
        if threading.current_thread() is not self._thread:
            self._thread.join(timeout)

    @property
    def serial(self) -> int:
        return self._serial

    @property
    def stopped(self) -> bool:
        return self.state in (STOPPED, FAULTED)

    # ---- breakpoints
    def add_breakpoint(self, file: str, line: int, condition: str | None = None, _index: bool = True) -> Breakpoint:
        """A breakpoint on the first statement at or after `file:line`. (`_index` False: the
        caller recompiles the breakpoint calls once for several.)"""
        span_file = self.build.span_file(file)
        if span_file is None:
            known = ", ".join(sorted(self.statements.st_lines)) or "none"
            raise DebugError(f"no ST file {file!r} in the project (files: {known})")
        actual = self.statements.next_st_line(span_file, line)
        if actual is None:
            raise DebugError(f"no statement at or after {span_file}:{line}")
        found = self.build.pou_at(span_file, actual)
        if found is None:
            raise DebugError(f"{span_file}:{actual} is not in a POU")
        pou, node = found
        compiled = None
        if condition is not None and condition.strip():
            compiled = self.compiler.compile_condition(Scope(pou, node), condition)
        else:
            condition = None
        bp = Breakpoint(self._next_bp, span_file, actual, line, pou, node,
                        list(self.statements.by_st_line[(span_file, actual)]), condition, compiled)
        self._next_bp += 1
        self.breakpoints[bp.id] = bp
        if _index:
            self._index_breakpoints()
        return bp

    def delete_breakpoint(self, bp_id: int | None = None) -> None:
        """Delete one breakpoint, or all of them (None)."""
        if bp_id is None:
            self.breakpoints.clear()
        elif self.breakpoints.pop(bp_id, None) is None:
            raise DebugError(f"no breakpoint {bp_id}")
        self._index_breakpoints()

    def set_file_breakpoints(self, file: str, specs: list[tuple[int, str | None]]) -> list[Breakpoint | DebugError]:
        """Replace every breakpoint of `file` (the DAP way); one result per spec, in order."""
        span_file = self.build.span_file(file) or file
        for bp_id in [b.id for b in self.breakpoints.values() if b.file == span_file]:
            del self.breakpoints[bp_id]
        results: list[Breakpoint | DebugError] = []
        for line, condition in specs:
            try:
                results.append(self.add_breakpoint(file, line, condition, _index=False))
            except DebugError as exc:
                results.append(exc)
        self._index_breakpoints()
        return results

    def _index_breakpoints(self) -> None:
        index: dict[int, list[Breakpoint]] = {}
        for bp in self.breakpoints.values():
            for gen_line in bp.gen_lines:
                index.setdefault(gen_line, []).append(bp)
        self._hooks.update(set(index))
        self._trace_wanted_always = bool(self._hooks.unhooked)
        self._bp_lines = index   # one assignment: the worker sees the old or the new table
        if self.state == RUNNING:
            # frames running code compiled before this change: armed by the trace function
            self._kick()

    # ---- inspection (while stopped)
    def frames(self) -> list[StackFrame]:
        return list(self.stop_event.frames) if self.stop_event else []

    def scope(self, frame_index: int = 0) -> Scope:
        """The scope of a stopped frame (the global scope between scans, or for index -1)."""
        frames = self.frames()
        if not frames or frame_index < 0:
            return Scope()
        if not 0 <= frame_index < len(frames):
            raise DebugError(f"no frame {frame_index} (0..{len(frames) - 1})")
        return frames[frame_index].scope

    def _require_stopped(self) -> None:
        if self.state not in (STOPPED, FAULTED, INITIAL):
            raise DebugError("the program is running; pause it first")

    def evaluate(self, text: str, frame_index: int = 0) -> tuple[Any, t.Type]:
        """Value and type of an ST expression in a frame's scope."""
        self._require_stopped()
        scope = self.scope(frame_index)
        compiled = self.compiler.compile_expression(scope, text)
        return self.compiler.evaluate(self.vm, scope, compiled), compiled.type

    def format(self, value: Any, ty: t.Type) -> str:
        return format_value(value, ty, self.vm.layouts)

    def evaluate_text(self, text: str, frame_index: int = 0) -> str:
        value, ty = self.evaluate(text, frame_index)
        return self.format(value, ty)

    def assign(self, target: str, value_text: str, frame_index: int = 0) -> str:
        """`target := value` once, with ST assignment rules; returns the new value as text."""
        self._require_stopped()
        scope = self.scope(frame_index)
        store = self.compiler.compile_store(scope, target, value_text)
        value = self.compiler.value(self.vm, scope, store)
        self.compiler.store(self.vm, scope, store, value)
        return self.format(value, store.type)

    def force(self, target: str, value_text: str, frame_index: int = 0) -> Force:
        """Hold `target` at the value of `value_text` (evaluated now) at the start and end of every
        scan until `unforce`; applied at once too."""
        self._require_stopped()
        scope = self.scope(frame_index)
        store = self.compiler.compile_store(scope, target, value_text)
        if store.root_is_local and scope.pou is not None and scope.pou.kind in ("FUNCTION", "METHOD"):
            raise DebugError(f"a {scope.pou.kind}'s variables exist only during a call; they cannot be forced")
        value = self.compiler.value(self.vm, scope, store)
        key = (scope.path.lower() + "." if store.root_is_local and scope.path else "") + store.canonical
        forced = Force(target.strip(), key, value_text.strip(), value, store, scope)
        self.compiler.store(self.vm, scope, store, copy_value(value))
        self.forces[key] = forced
        return forced

    def unforce(self, target: str | None = None, frame_index: int = 0) -> list[Force]:
        """Release one forced variable (as written in `force`, in the same scope or by its full
        path), or all (None); returns what was released."""
        if target is None:
            released = list(self.forces.values())
            self.forces.clear()
            return released
        key = target.strip().lower().replace(" ", "")
        if key in self.forces:
            return [self.forces.pop(key)]
        scope = self.scope(frame_index) if self.stopped else Scope()
        store = self.compiler.compile_store(scope, target, target)   # only to resolve the target
        full = (scope.path.lower() + "." if store.root_is_local and scope.path else "") + store.canonical
        if full in self.forces:
            return [self.forces.pop(full)]
        raise DebugError(f"{target.strip()} is not forced (forced: {', '.join(f.key_display for f in self.forces.values()) or 'nothing'})")

    def where(self) -> str:
        """Task, scan, virtual time and the call stack with ST lines."""
        event = self.stop_event
        if event is None:
            return "not started"
        lines = [f"task {event.task or '-'}, scan {event.scan}, t={format_time(event.now_ns)}"
                 + (" (between scans)" if event.between_scans else "")]
        for frame in event.frames:
            lines.append(f"  #{frame.index} {frame.name} ({frame.pou.name}) at {frame.location}")
        return "\n".join(lines)

    def instance_path(self, obj: Any) -> str | None:
        return self._paths.get(id(obj))

    # ================================================================ worker thread
    def _worker(self, stop_on_entry: bool) -> None:
        vm = self.vm
        self._kicker = ThreadKicker(self._kicked)
        self._apply_tracing(None)
        try:
            if stop_on_entry:
                self._stop(ENTRY, None)
            while not self._terminate:
                if self.max_scans is not None and vm.scan_count >= self.max_scans:
                    break
                self._statement_seen = False
                self._force_all()
                try:
                    vm.scan()
                except RuntimeFault as fault:
                    self._post_mortem(fault)
                    break
                self._scan_ended()
        except _Terminate:
            pass
        finally:
            sys.settrace(None)
            self._kicker.close()
            self._finish_session()

    def _finish_session(self) -> None:
        try:
            self.vm.close()
        finally:
            with self._changed:
                self.state = TERMINATED
                self._serial += 1
                self._changed.notify_all()
            for listener in list(self.listeners):
                listener(None)

    def _scan_ended(self) -> None:
        if not self._attention and sys.gettrace() is not None:
            self._apply_tracing(None)   # a kick for a breakpoint change has done its work
        mode = self._mode
        if self._pause:
            self._stop(PAUSED, None)
        elif mode == FINISH:
            self._stop(STEPPED, None)
        elif mode == SCAN:
            self._scans_left -= 1
            if self._scans_left <= 0:
                self._stop(SCANNED, None)
        elif mode in (STEP, NEXT) and not self._statement_seen:
            self._stop(STEPPED, None)   # a scan without statements (nothing to step to)

    # ---- tracing
    # The worker runs untraced unless something needs line events: stepping, a pause, the end
    # of the session (`_attention`), or a breakpoint line no hook could take. Breakpoints are
    # calls compiled into the generated code (`_hook`, stvm/debug/hooks.py). When tracing is on,
    # only frames that may stop get line events: while stepping (or asked to pause or end),
    # every POU frame; otherwise the frames whose code has a breakpoint line without a hook. A
    # frame already running when that changes is armed by setting its `f_trace`; a running
    # worker is reached through `ThreadKicker`, which makes it install the trace function itself.
    def _make_tracers(self) -> None:
        """`_trace_call` (the thread's trace function) and `_trace_line` (a frame's), as closures
        over their tables: they run on every call and every traced line."""
        stops, code_lines, generated, engine = self._stops, self._code_lines, GENERATED_FILENAME, self

        def trace_line(frame: FrameType, event: str, arg: Any):
            if event == "line":
                line = frame.f_lineno
                if line in stops:
                    if line in engine._hooks.hooked.get(frame.f_code, ()):
                        engine._handled = frame   # the hook call that runs next: already handled
                    if engine._attention or line in engine._bp_lines:
                        engine._statement(frame, line)
            return trace_line

        def trace_call(frame: FrameType, event: str, arg: Any):
            code = frame.f_code
            if code.co_filename != generated:
                return None
            lines = code_lines.get(code, ())
            if lines == ():
                lines = code_lines[code] = engine._pou_code_lines(code)
            if lines is None:
                return None
            if engine._attention:
                return trace_line
            hooked = engine._hooks.hooked.get(code)
            if not (lines - hooked if hooked else lines).isdisjoint(engine._bp_lines):
                return trace_line
            return None

        self._trace_call = trace_call
        self._trace_line = trace_line

    def _hook(self, line: int) -> None:
        """A breakpoint line's compiled-in call (runs in the worker, in the ST frame's call)."""
        frame = sys._getframe(1)
        if self._handled is frame:     # the trace function saw this line first
            self._handled = None
            return
        if self._attention or line in self._bp_lines:
            self._statement(frame, line)

    def _apply_tracing(self, frame: FrameType | None) -> None:
        """(Worker thread) install or remove the trace function for what runs next."""
        if self._attention or self._trace_wanted_always or self._kicker is None or not self._kicker.available:
            sys.settrace(self._trace_call)
            if self._attention:
                self._arm(frame)
            return
        stale = self._stale_frames(frame)
        if stale:
            # running code compiled before a breakpoint set while stopped: those frames are
            # traced until the scan ends (new calls run the new code, untraced)
            sys.settrace(self._trace_call)
            for stale_frame in stale:
                stale_frame.f_trace = self._trace_line
        else:
            sys.settrace(None)

    def _stale_frames(self, frame: FrameType | None) -> list[FrameType]:
        """Frames on the stack whose code has a breakpoint line without its compiled call."""
        out = []
        bp_lines = self._bp_lines
        while frame is not None and bp_lines:
            code = frame.f_code
            lines = self._code_lines.get(code, ())
            if lines == ():
                lines = self._code_lines[code] = self._pou_code_lines(code)
            if lines and not (lines - self._hooks.hooked.get(code, frozenset())).isdisjoint(bp_lines):
                out.append(frame)
            frame = frame.f_back
        return out

    def _kick(self) -> None:
        """(Front-end thread) make a running worker look at `_attention` and the breakpoints now."""
        thread = self._thread
        if thread is None or thread.ident is None or threading.current_thread() is thread:
            return
        kicker = self._kicker
        if kicker is not None and kicker.available:
            kicker.kick()
        else:
            self._arm_running_frames()

    def _kicked(self) -> None:
        """(Worker thread, at the line it was running) the trace function on, its frames armed."""
        sys.settrace(self._trace_call)
        self._arm(sys._getframe(1))

    def _pou_code_lines(self, code: CodeType) -> frozenset[int] | None:
        """Statement lines of a POU body's code object (None for helper code: struct copies,
        constructors, lambdas of output references, which never stop)."""
        unit = code.co_qualname.split(".")[0]
        if unit not in self.build.unit_pous or (code.co_name not in ("__call__", unit)
                                                and (unit, code.co_name) not in self.build.unit_methods):
            return None
        return frozenset(line for _, _, line in code.co_lines() if line in self._stops)

    def _arm(self, frame: FrameType | None) -> None:
        """Give `frame` and its ST callers line events (they may have been called untraced)."""
        while frame is not None:
            if self._code_lines.get(frame.f_code) or self._pou_code_lines(frame.f_code):
                frame.f_trace = self._trace_line
            frame = frame.f_back

    def _arm_running_frames(self) -> None:
        thread = self._thread
        if thread is None or thread.ident is None or threading.current_thread() is thread:
            return
        self._arm(sys._current_frames().get(thread.ident))

    def _statement(self, frame: FrameType, line: int) -> None:
        if self._terminate:
            raise _Terminate()
        self._statement_seen = True
        hit = []
        message = ""
        for bp in self._bp_lines.get(line, ()):
            if bp.compiled is not None:
                try:
                    if not self._condition_holds(bp.compiled, frame):
                        continue
                except DebugError as exc:
                    message = f"breakpoint {bp.id}: condition {bp.condition!r} failed: {exc}"
            bp.hits += 1
            hit.append(bp.id)
        if hit:
            self._stop(BREAKPOINT, frame, hit, message)
            return
        if self._pause:
            self._stop(PAUSED, frame)
            return
        mode = self._mode
        if mode == STEP:
            self._stop(STEPPED, frame)
        elif mode == NEXT:
            if _depth(frame) <= self._depth:
                self._stop(STEPPED, frame)
        elif mode == FINISH:
            if _depth(frame) < self._depth:
                self._stop(STEPPED, frame)

    def _condition_holds(self, compiled: Compiled, frame: FrameType) -> Any:
        """A breakpoint condition in `frame`: what `compiler.evaluate` in the frame's scope gives,
        with the frame's kind looked up once per code object and the names bound directly (a
        condition on a hot line runs at every pass)."""
        kind = self._frame_kinds.get(frame.f_code)
        if kind is None:
            scope = self._frame_scope(frame)
            kind = self._frame_kinds[frame.f_code] = scope.pou.kind if scope.pou is not None else ""
        local_vars = frame.f_locals
        names = self._condition_names
        if names is None:
            names = self._condition_names = self.compiler.namespace(self.vm, Scope())
        if kind == "FUNCTION":
            bound = dict(names, self=None, _f=local_vars.get("_f"), _r=local_vars.get("_r"))
        elif kind == "METHOD":
            bound = dict(names, self=local_vars.get("self"), _f=local_vars.get("_f"), _r=local_vars.get("_r"))
        else:
            bound = dict(names, self=local_vars.get("self"), _f=None, _r=None)
        return run_guarded(lambda: eval(compiled.code, self.vm.namespace, bound))

    def _stop(self, reason: str, frame: FrameType | None, breakpoints: list[int] | None = None,
              message: str = "") -> None:
        """Block the worker at a stop until a front end resumes it."""
        vm = self.vm
        in_scan = frame is not None
        event = StopEvent(reason, vm.ctx.task if in_scan else "", vm.scan_count, vm.now_ns,
                          self._stack(frame) if frame is not None else [], breakpoints or [], message)
        self._pause = False
        self._publish(event, STOPPED)
        if in_scan:
            mode, count = self._commands.get()
        else:
            mode, count = self._wait_between_scans()
        if mode == "terminate" or self._terminate:
            raise _Terminate()
        if self.vm.realtime:
            # real-time clock: the time spent stopped is not an overrun; deadlines restart from now
            # (VM._sleep_to_deadline measures from `_rt_start`)
            self.vm._rt_start = time.perf_counter_ns() - self.vm.scan_count * self.vm.base_ns
        self._mode = mode
        self._depth = _depth(frame) if frame is not None else 1 << 30
        if mode == FINISH and frame is None:
            mode, count = SCAN, 1
            self._mode = SCAN
        self._scans_left = count if mode == SCAN else 0
        self._attention = mode in (STEP, NEXT, FINISH) or self._pause or self._terminate
        self._apply_tracing(frame)

    def _wait_between_scans(self) -> tuple[str, int]:
        """The next command; meanwhile the VM's idle hooks run (front ends beside the debugger,
        `stvm debug --opcua`, read and write a VM stopped between two scans)."""
        while True:
            try:
                return self._commands.get(timeout=0.01 if self.vm.on_idle else None)
            except queue.Empty:
                for hook in self.vm.on_idle:
                    hook(self.vm)

    def _publish(self, event: StopEvent, state: str) -> None:
        with self._changed:
            self.stop_event = event
            self.state = state
            self._serial += 1
            self._changed.notify_all()
        for listener in list(self.listeners):
            listener(event)

    def _post_mortem(self, fault: RuntimeFault) -> None:
        """Stop at the faulting statement with the frames of the fault's traceback."""
        self.fault = fault
        cause = fault.__context__
        tb = cause.__traceback__ if cause is not None else fault.__traceback__
        pairs = []
        while tb is not None:
            if tb.tb_frame.f_code.co_filename == GENERATED_FILENAME:
                pairs.append((tb.tb_frame, tb.tb_lineno))
            tb = tb.tb_next
        frames = []
        for py_frame, line in reversed(pairs):
            frame = self._make_frame(len(frames), py_frame, line)
            if frame is not None:
                frames.append(frame)
        event = StopEvent(FAULT, fault.task, fault.scan, fault.now_ns, frames, [], fault.message, fault)
        self._publish(event, FAULTED)
        while True:   # nothing can run after a major fault; wait for the end of the session
            mode, _ = self._commands.get()
            if mode == "terminate" or self._terminate:
                return

    # ---- frames
    def _stack(self, frame: FrameType) -> list[StackFrame]:
        out: list[StackFrame] = []
        f: FrameType | None = frame
        while f is not None:
            if f.f_code.co_filename == GENERATED_FILENAME:
                try:
                    made = self._make_frame(len(out), f, f.f_lineno)
                except Exception as exc:  # noqa: BLE001 - runs in the trace function: never escape
                    self._warn(f"cannot show a frame ({type(exc).__name__}: {exc}); this is an stvm bug")
                    made = None
                if made is not None:
                    out.append(made)
            f = f.f_back
        return out

    def _make_frame(self, index: int, py_frame: FrameType, line: int) -> StackFrame | None:
        unit = py_frame.f_code.co_qualname.split(".")[0]
        method = self.build.unit_methods.get((unit, py_frame.f_code.co_name))
        if method is not None:   # a METHOD / property accessor: shown as `instance.Method`
            pou, node, fb = method
            span = self.statements.spans.get(line) or self.build.project.lowered.line_map.span_at(line) or node.span
            scope = self._frame_scope(py_frame, pou, node)  # type: ignore[arg-type]
            return StackFrame(index, pou, node, span, f"{scope.path or fb.name}.{pou.name}", scope, py_frame)  # type: ignore[arg-type]
        pou = self.build.unit_pous.get(unit)
        if pou is None or py_frame.f_code.co_name not in ("__call__", unit):
            return None   # helper code (struct copies, output-reference lambdas) is not a POU frame
        node = self.build.analysis.pou_nodes[pou.key]
        span = self.statements.spans.get(line) or self.build.project.lowered.line_map.span_at(line) or node.span
        scope = self._frame_scope(py_frame, pou, node)
        name = scope.path or pou.name
        return StackFrame(index, pou, node, span, name, scope, py_frame)

    def _frame_scope(self, py_frame: FrameType, pou: POUInfo | None = None, node: n.POU | None = None) -> Scope:
        if pou is None:
            unit = py_frame.f_code.co_qualname.split(".")[0]
            method = self.build.unit_methods.get((unit, py_frame.f_code.co_name))
            if method is not None:
                pou, node = method[0], method[1]  # type: ignore[assignment]
            else:
                pou = self.build.unit_pous[unit]
                node = self.build.analysis.pou_nodes[pou.key]
        local_vars = py_frame.f_locals
        if pou.kind == "FUNCTION":
            return Scope(pou, node, None, local_vars.get("_f"), local_vars.get("_r"), "")
        instance = local_vars.get("self")
        if pou.kind == "METHOD":   # its own variables on the call's frame, THIS is the instance
            return Scope(pou, node, instance, local_vars.get("_f"), local_vars.get("_r"),
                         self._paths.get(id(instance), ""))
        return Scope(pou, node, instance, None, None, self._paths.get(id(instance), ""))

    def _instance_paths(self) -> dict[int, str]:
        """id of every ST FB instance → its path, from the one variable catalog (only the nodes
        that can hold an FB instance are expanded)."""
        paths: dict[int, str] = {}
        stack = [root for root in Catalog(self.vm).roots if root.kind == "program"]
        while stack:
            node = stack.pop()
            if isinstance(node.type, t.FBType):
                paths[id(node.read())] = node.path   # not a node: one path per instance object
            if _may_hold_instances(node.type):
                stack.extend(child for child in node.children if _may_hold_instances(child.type))
        return paths

    # ---- forcing
    def _force_all(self, vm: Any = None) -> None:
        if not self.forces:
            return
        for key, forced in list(self.forces.items()):
            try:
                self.compiler.store(self.vm, forced.scope, forced.store, copy_value(forced.value))
            except DebugError as exc:
                del self.forces[key]
                self._warn(f"force {forced.describe()} released: {exc}")

    def _warn(self, message: str) -> None:
        if not self.output:
            print(f"warning: {message}", file=sys.stderr)
        for sink in list(self.output):
            sink(message)


def _untraced(hook: Callable, tracer: Callable) -> Callable:
    def run_untraced(vm: Any) -> None:
        tracing = sys.gettrace()
        if tracing is None:
            hook(vm)
            return
        sys.settrace(None)
        try:
            hook(vm)
        finally:
            sys.settrace(tracing)
    return run_untraced


def _depth(frame: FrameType | None) -> int:
    """How many generated (ST) frames are on the stack from `frame` outwards."""
    depth = 0
    while frame is not None:
        if frame.f_code.co_filename == GENERATED_FILENAME:
            depth += 1
        frame = frame.f_back
    return depth


def _may_hold_instances(ty: t.Type) -> bool:
    """An FB instance, or a struct or array that may contain one."""
    while isinstance(ty, t.ArrayType):
        ty = ty.element
    return isinstance(ty, (t.FBType, t.StructType))
