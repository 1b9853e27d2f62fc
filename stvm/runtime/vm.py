"""Stage 4: the cyclic-task VM.

Tasks run at integer multiples of the base period (the GCD of the task intervals), highest
priority (lowest number) first, as a Sysmac controller's primary and periodic tasks do. One call
of `scan()` is one base period. Time is virtual by default: each scan starts at `scan * base`
nanoseconds and every clock the ST code can see reads `ctx.now_ns`.

A runtime fault (division by zero, index out of bounds, …) stops the VM as a controller's major
fault; `RuntimeFault` carries the ST span found by walking the traceback through the line map.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from types import TracebackType
from typing import Any, Callable, Mapping

from stvm.numeric import f32, strfit, utf16_units
from stvm.runtime.access import PathError, UnboundInOut, VariableAccess  # noqa: F401 (API: PathError, UnboundInOut)
from stvm.runtime.context import RunContext
from stvm.runtime.helpers import HELPERS
from stvm.runtime.memory import guard_bytes, memory_helpers
from stvm.runtime.stats import TimingStats
from stvm.runtime.values import ArrayIndexError, FunctionError, STFault
from stvm.semantics import types as t
from stvm.source import Span
from stvm.settings import FunErrorPolicy, StringOverflow
from stvm.diagnostics import excerpt

GENERATED_FILENAME = "<stvm-generated>"


def timing_us(stats) -> tuple[float, float, float, float] | None:
    """(mean, p50, p99, max) in µs of a `TimingStats` (scan durations or start jitters); None if empty."""
    return stats.summary_us()


# FB instances nest and POUs call each other up to the checker's NESTING_LIMIT (200) levels;
# each level is a few Python frames (constructor, call, copy), more under the debugger's trace
# hook, so the interpreter's limit must be well above 3 x 200 for run and debug alike.
_RECURSION_LIMIT = 4000


def _ensure_recursion_limit() -> None:
    import sys
    if sys.getrecursionlimit() < _RECURSION_LIMIT:
        sys.setrecursionlimit(_RECURSION_LIMIT)


class RuntimeFault(Exception):
    """A major fault: the task stopped at an ST location."""

    def __init__(self, message: str, span: Span | None, task: str, scan: int, now_ns: int) -> None:
        super().__init__(message)
        self.message = message
        self.span = span
        self.task = task
        self.scan = scan
        self.now_ns = now_ns

    def render(self, sources: dict[str, str] | None = None) -> str:
        from stvm.runtime.format import format_time   # lazy: start-up (a run without a fault or --print)
        where = f"{self.span.file}:{self.span.line}:{self.span.column}" if self.span else "<unknown>"
        text = f"{where}: fault: {self.message} (task {self.task}, scan {self.scan}, t={format_time(self.now_ns)})\n"
        if self.span and sources:
            text += excerpt(self.span, sources)
        return text


@dataclass
class Task:
    """One task of the configuration: its programs, run every `every` base periods. (A
    docstring also spares `dataclass` an `inspect.signature` to write one, a start-up cost.)"""

    name: str
    interval_ns: int
    priority: int
    every: int                                   # runs every `every` base ticks
    programs: list[tuple[str, Any]] = field(default_factory=list)   # (instance name, instance)


class VM:
    def __init__(self, project, scan_ns: int = 10_000_000, realtime: bool = False,
                 start_dt_ns: int = 0, transport: Any = None, natives: Mapping[str, Any] | None = None,
                 native_fbs: Mapping[str, type] | None = None) -> None:
        """`natives`, `native_fbs`: the stdlib's implementations (stvm.stdlib.NATIVE_FUNCTIONS,
        NATIVE_FBS) by upper-case name; `Project.start` passes them."""
        _ensure_recursion_limit()
        self.project = project
        self.model = project.model
        # the settings the project was compiled with: the generated code decided some of them
        # (int_div_zero, array_oob, ...), so the stdlib and the VM must read the same ones
        self.settings = project.settings
        self.ctx = RunContext(settings=self.settings, start_dt_ns=start_dt_ns, realtime=realtime,
                              transport=transport)
        self.realtime = realtime
        ns: dict[str, Any] = dict(HELPERS)
        ns.update(memory_helpers(guard_bytes(self.settings)))   # `pointer_overrun`
        NATIVE_FUNCTIONS = natives if natives is not None else {}
        NATIVE_FBS = native_fbs if native_fbs is not None else {}
        ns["_NATIVE_FB"] = NATIVE_FBS
        # a registry that holds only what this program calls (a cached project: see
        # stvm.stdlib.natives_for) says so with `partial`; then a missing native is not an error
        complete = not getattr(NATIVE_FBS, "partial", False)
        lowered = project.lowered
        for py_name, key in lowered.natives.items():
            native = NATIVE_FUNCTIONS.get(key)
            if native is None:
                if not complete:
                    continue    # not called by this program (Project.native_modules)
                raise RuntimeError(f"stdlib declares {key} native but no implementation is registered")
            ns[py_name] = native.impl
        for py_name, key in lowered.native_fbs.items():
            if complete and key not in NATIVE_FBS:
                raise RuntimeError(f"stdlib declares FB {key} native but no implementation is registered")
        ns["_T"] = lowered.types
        ns["_ctx"] = self.ctx
        ns["_fun_error"] = self._fun_error
        ns["_str_overflow"] = self._string_overflow
        ns["_oob_skipped"] = self._index_skipped
        ns["__stvm_unit__"] = lowered
        ns["_fb_pending"] = self._fb_pending = []   # instances with FB_init (run_fb_inits)
        for piece in project.code:   # the generated module, compiled in pieces (lower.product)
            exec(piece, ns)
        self.namespace = ns
        self.globals = ns["G_globals"]()
        ns["_G"] = self.globals
        self.instances: dict[str, tuple[str, Any, str]] = {}   # key → (name, instance, program qualname)
        # where each variable is stored (the lowering's layout): the only way to a variable
        self.layouts = lowered.layouts
        self.access = VariableAccess(self.layouts, self.globals, self.instances)
        self.tasks: list[Task] = []
        self._build_tasks(scan_ns)
        self.scan_count = 0
        self.now_ns = 0
        # bounded memory whatever the run length (a shift-long demo must not grow)
        self.scan_durations_ns = TimingStats()
        self.overruns = 0          # real time: scans started more than a period late (episodes)
        self.catch_up_scans = 0    # real time: scans started at once, behind schedule
        self.long_scans = 0        # scans whose own execution took longer than the base period
        self.max_lateness_ns = 0
        self._late = False
        self.fault: RuntimeFault | None = None
        self.collect_stats = True   # per-scan durations (for --stats); benchmarks switch it off
        self.on_scan_start: list[Callable[["VM"], None]] = []   # front ends' queued writes
        self.on_scan_end: list[Callable[["VM"], None]] = []
        self._rt_start: int | None = None
        self.pacer = None           # real time: the deadline keeper (stvm/runtime/realtime.py)
        self.jitter_ns = TimingStats()
        self.held = False           # a front end's run control holds the VM between two scans
        # called by a loop that holds the VM between two scans (a paused run control, a debugger
        # stopped after a scan): front ends answer reads and apply writes from there
        self.on_idle: list[Callable[["VM"], None]] = []
        if self._fb_pending:
            self.run_fb_inits()

    # ---- setup
    def _instance(self, name: str, qualname: str) -> Any:
        cls = self.namespace[self.project.lowered.classes[qualname.lower()]]
        inst = cls()
        self.instances[name.lower()] = (name, inst, qualname)
        return inst

    def run_fb_inits(self) -> None:
        """CODESYS FB_init(bInitRetains := TRUE, bInCopyCode := FALSE) of every instance that
        declares one, as at a first download: after all instances and their initial values
        exist, inner instances before the ones holding them, a base's FB_init before its
        derived FB's. A fault in one stops the run before the first scan, at its ST line."""
        pending, self._fb_pending[:] = list(self._fb_pending), []
        ctx = self.ctx
        ctx.task = "FB_init"
        try:
            for obj, calls in pending:
                for method, args in calls:
                    method(obj, *args)
        except Exception as exc:
            try:
                self._raise_fault(fault_message(exc), exc.__traceback__, "FB_init")
            except RuntimeFault:
                pass   # kept in self.fault: the first scan raises it

    def _build_tasks(self, scan_ns: int) -> None:
        if self.model.tasks:
            base = 0
            for task in self.model.tasks:
                base = math.gcd(base, task.interval_ns)
            self.base_ns = base
            for task in self.model.tasks:
                runtime_task = Task(task.name, task.interval_ns, task.priority, task.interval_ns // base)
                for inst_name, qualname in task.programs:
                    runtime_task.programs.append((inst_name, self._instance(inst_name, qualname)))
                self.tasks.append(runtime_task)
        else:
            self.base_ns = scan_ns
            default = Task("DefaultTask", scan_ns, 0, 1)
            for qualname in self.model.default_programs:
                name = qualname.split("\\")[-1]
                default.programs.append((name, self._instance(name, qualname)))
            self.tasks.append(default)
        self.tasks.sort(key=lambda tk: tk.priority)
        self._build_schedule()

    # ---- running
    def _fun_error(self, error: FunctionError, site: int) -> None:
        span = self.project.lowered.sites[site]
        if self.settings.fun_error_policy is FunErrorPolicy.FAULT:
            raise STFault(f"instruction error: {error}")
        self.ctx.warn(f"{span.file}:{span.line}:{span.column}: instruction error (ENO FALSE, assignment skipped): {error}",
                      once_key=(site, str(error)))

    def _string_overflow(self, value: bytes, max_bytes: int, file: str, line: int, column: int) -> bytes:
        """A store into STRING[max_bytes + 1] of a value that may not fit (sysmac.md 2,
        `string_overflow`): a fault, or cut to `max_bytes` with one warning per site."""
        if len(value) <= max_bytes:
            return value
        wide = isinstance(value, str)
        destination = f"WSTRING[{max_bytes}]" if wide else f"STRING[{max_bytes + 1}]"
        unit = "code units" if wide else "bytes"
        if self.settings.string_overflow is StringOverflow.ERROR:
            raise STFault(f"a string of {len(value)} {unit} does not fit {destination} "
                          f"({max_bytes} {unit}; string_overflow=error)")
        self.ctx.warn_at(Span(file, line, column, line, column),
                         f"a string of {len(value)} {unit} is truncated to the {max_bytes} {unit} of "
                         f"{destination} (string_overflow=truncate_warn; reported once)",
                         once_key=("string_overflow", file, line, column))
        return HELPERS["_strfit"](value, max_bytes)   # the cut the generated code makes

    def _index_skipped(self, error: ArrayIndexError, site: int) -> None:
        """`array_oob=skip_statement`: the statement with the bad index was not executed."""
        self.ctx.warn_at(self.project.lowered.sites[site],
                         f"{error}: statement skipped (array_oob=skip_statement; reported once)",
                         once_key=("array_oob", site))

    def _build_schedule(self) -> None:
        """Which tasks run at each tick of the hyperperiod, in priority order, as plain lists
        (the scan loop does no arithmetic per task)."""
        period = 1
        for task in self.tasks:
            period = period * task.every // math.gcd(period, task.every)
        self._schedule = [[(task.name, [program for _, program in task.programs])
                           for task in self.tasks if tick % task.every == 0]
                          for tick in range(period)]

    def scan(self) -> None:
        """Run one base period: every task due at this tick, in priority order."""
        if self.fault is not None:
            raise self.fault
        tick = self.scan_count
        if self.realtime and self._rt_start is None:
            # the schedule starts when the first scan does, so the first scan is held to its
            # deadline like every other (it was measured from its own end: never late)
            self._rt_start = time.perf_counter_ns() - tick * self.base_ns
        ctx = self.ctx
        ctx.now_ns = self.now_ns
        ctx.scan = tick
        schedule = self._schedule
        if self.on_scan_start:
            for hook in self.on_scan_start:
                hook(self)
        started = time.perf_counter_ns() if self.collect_stats else 0
        try:
            for task_name, programs in schedule[tick % len(schedule)]:
                ctx.task = task_name
                for program in programs:
                    program()
        except Exception as exc:
            self._raise_fault(fault_message(exc), exc.__traceback__, ctx.task)
        if started:
            took = time.perf_counter_ns() - started
            self.scan_durations_ns.add(took)
            if took > self.base_ns:
                self.long_scans += 1
        if self.on_scan_end:
            for hook in self.on_scan_end:
                hook(self)
        self.scan_count = tick + 1
        self.now_ns += self.base_ns
        if self.realtime:
            self._sleep_to_deadline()

    def _sleep_to_deadline(self) -> None:
        """Wait for the release time of the next scan (`start + scan_count * period`).

        Behind schedule, the next scan starts at once (a catch-up scan), so VM time stays tied
        to the wall clock. An overrun is the first scan of such an episode that starts more than
        one period late; the catch-up scans that follow it are counted apart (one stall of
        57 ms is one overrun and ~57 catch-up scans, not 57 overruns). `long_scans` counts the
        scans whose own execution exceeded the period (TwinCAT's exceed counter counts such
        cycles), so a program always 10x too slow shows as 1 overrun and N scans over the period."""
        now = time.perf_counter_ns()
        if self._rt_start is None:
            self._rt_start = now - self.base_ns
        if self.pacer is None:
            from stvm.runtime.realtime import Pacer   # lazy: start-up (real-time runs only)
            self.pacer = Pacer()
        deadline = self._rt_start + self.scan_count * self.base_ns
        waited = now < deadline
        if waited:
            now = self.pacer.wait_until(deadline)   # sleep, then spin (stvm/runtime/realtime.py)
        lateness = max(0, now - deadline)
        self.jitter_ns.add(lateness)
        if lateness > self.max_lateness_ns:
            self.max_lateness_ns = lateness
        if lateness > self.base_ns:
            if self._late:
                self.catch_up_scans += 1
            else:
                self.overruns += 1
                self._late = True
        elif not waited:
            self.catch_up_scans += 1
        else:
            self._late = False

    def _raise_fault(self, message: str, tb: TracebackType | None, task: str) -> None:
        span = self.st_span(tb)
        self.fault = RuntimeFault(message, span, task, self.scan_count, self.now_ns)
        raise self.fault

    def st_span(self, tb: TracebackType | None) -> Span | None:
        """The innermost ST statement on the traceback (generated frames only)."""
        span = None
        line_map = self.project.lowered.line_map
        while tb is not None:
            if tb.tb_frame.f_code.co_filename == GENERATED_FILENAME:
                found = line_map.span_at(tb.tb_lineno)
                if found is not None:
                    span = found
            tb = tb.tb_next
        return span

    def run(self, cycles: int | None = None, duration_ns: int | None = None,
            until: Callable[[], bool] | None = None) -> None:
        """Run `cycles` scans, or until `duration_ns` of VM time, or forever (Ctrl-C stops)."""
        if cycles is None and duration_ns is not None:
            cycles = -(-duration_ns // self.base_ns)
        if self.realtime and self.pacer is None:
            from stvm.runtime.realtime import Pacer   # lazy: start-up (real-time runs only)
            self.pacer = Pacer()
        if self.pacer is not None:
            self.pacer.take_gc()       # the collector runs between scans, never inside one
        try:
            count = 0
            while cycles is None or count < cycles:
                self.scan()
                count += 1
                if until is not None and until():
                    break
        finally:
            if self.pacer is not None:
                self.pacer.release_gc()

    def close(self) -> None:
        transport = self.ctx.transport
        if transport is not None and hasattr(transport, "close_all"):
            transport.close_all()

    # ---- variable access by path
    def resolve(self, path: str) -> tuple[Any, Any, t.Type]:
        """(container, key, type) for a path; container[key] or getattr(container, key) holds the
        value (`stvm.runtime.access`, through the lowering's layout)."""
        return self.access.resolve(path)

    def accessor(self, path: str) -> "Accessor":
        """A reusable handle on one variable (checked now: raises `PathError` if `path` is unknown)."""
        return Accessor(self, path, self.access.resolve(path)[2])

    def get(self, path: str) -> Any:
        container, key, _ = self.access.resolve(path)
        return container[key] if isinstance(key, int) else getattr(container, key)

    def type_of(self, path: str) -> t.Type:
        return self.access.resolve(path)[2]

    def set(self, path: str, value: Any) -> None:
        container, key, ty = self.access.resolve(path)
        if isinstance(ty, t.StringType):
            self._check_string_fits(path, value, ty)
        value = coerce_python_value(value, ty)
        if isinstance(key, int):
            container[key] = value
        else:
            setattr(container, key, value)

    def _check_string_fits(self, path: str, value: Any, ty: t.StringType) -> None:
        """A string given from outside (API, `--set`, scenario) is stored like an ST assignment:
        too long is an error (`string_overflow=error`) or a warning and a cut."""
        if t.is_wide(ty):
            self._check_wstring_fits(path, value, ty)
            return
        data = value.encode("utf-8") if isinstance(value, str) else value
        if not isinstance(data, (bytes, bytearray)):
            return   # coerce_python_value rejects it
        length = len(bytes(data).split(b"\x00", 1)[0])
        if length <= ty.max_bytes:
            return
        if self.settings.string_overflow is StringOverflow.ERROR:
            raise ValueError(f"a string of {length} bytes does not fit {ty.name} ({ty.max_bytes} bytes; "
                             "string_overflow=error)")
        self.ctx.warn(f"{path}: a string of {length} bytes is truncated to the {ty.max_bytes} bytes of {ty.name}")

    def _check_wstring_fits(self, path: str, value: Any, ty: t.StringType) -> None:
        """`_check_string_fits` for a WSTRING: its length counts UTF-16 code units."""
        if isinstance(value, (bytes, bytearray)):
            value = bytes(value).decode("utf-8", "replace")
        if not isinstance(value, str):
            return
        length = len(utf16_units(value.split("\x00", 1)[0]))
        if length <= ty.max_bytes:
            return
        if self.settings.string_overflow is StringOverflow.ERROR:
            raise ValueError(f"a string of {length} code units does not fit {ty.name} ({ty.max_bytes} code "
                             "units; string_overflow=error)")
        self.ctx.warn(f"{path}: a string of {length} code units is truncated to the {ty.max_bytes} code units "
                      f"of {ty.name}")

    def __getitem__(self, path: str) -> Any:
        return self.get(path)

    def __setitem__(self, path: str, value: Any) -> None:
        self.set(path, value)

    def format(self, path: str) -> str:
        from stvm.runtime.format import format_value   # lazy: start-up (a run without --print)
        container, key, ty = self.access.resolve(path)
        value = container[key] if isinstance(key, int) else getattr(container, key)
        return format_value(value, ty, self.layouts)


class Accessor:
    """One variable of a running VM by path: `get()`, `set(value)`, its ST `type`.

    The container is looked up again on every access, because assigning a STRUCT or ARRAY
    replaces the object and a VAR_IN_OUT follows whatever the FB was last called with."""

    __slots__ = ("vm", "path", "type")

    def __init__(self, vm: VM, path: str, ty: t.Type) -> None:
        self.vm = vm
        self.path = path
        self.type = ty

    def get(self) -> Any:
        return self.vm.get(self.path)

    def set(self, value: Any) -> None:
        """Store `value` (checked and converted to the variable's type)."""
        self.vm.set(self.path, value)

    def bind(self) -> Callable[[Any], None]:
        """Resolve the container now; the returned setter stores an already converted value."""
        container, key, _ = self.vm.access.resolve(self.path)
        if isinstance(key, int):
            return lambda value: container.__setitem__(key, value)
        return lambda value: setattr(container, key, value)


def fault_message(exc: Exception) -> str:
    """What a fault raised by generated code says: the ST fault's own text, or what the
    Python exception means for the program (an stvm bug is still reported at its ST location,
    not as a traceback)."""
    if isinstance(exc, RecursionError):
        return f"stack overflow ({exc})"
    if isinstance(exc, STFault):
        return str(exc) if str(exc) else type(exc).__doc__ or type(exc).__name__
    if isinstance(exc, FunctionError):
        return f"instruction error: {exc}"
    return f"internal error in stvm ({type(exc).__name__}: {exc})"


def coerce_python_value(value: Any, ty: t.Type) -> Any:
    """Check and convert a Python value given through the API or `--set` to `ty`'s representation."""
    if isinstance(ty, t.BoolType):
        if isinstance(value, bool):
            return value
        if value in (0, 1):
            return bool(value)
    elif isinstance(ty, t.IntType):
        if isinstance(value, int) and not isinstance(value, bool):
            if not ty.lo <= value <= ty.hi:
                raise ValueError(f"{value} is out of range for {ty.name} ({ty.lo}..{ty.hi})")
            return value
    elif isinstance(ty, t.RealType):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            try:
                as_float = float(value)
            except OverflowError:
                raise ValueError(f"{value} is out of range for {ty.name}") from None
            return f32(as_float) if ty.bits == 32 else as_float
    elif t.is_wide(ty):
        if isinstance(value, (bytes, bytearray)):
            value = bytes(value).decode("utf-8", "replace")
        if isinstance(value, str):
            return strfit(utf16_units(value.split("\x00", 1)[0]), ty.max_bytes)
    elif isinstance(ty, t.StringType):
        if isinstance(value, str):
            value = value.encode("utf-8")
        if isinstance(value, (bytes, bytearray)):
            value = bytes(value).split(b"\x00", 1)[0]
            return strfit(value, ty.max_bytes)
    elif isinstance(ty, t.TimeType):
        if isinstance(value, int) and not isinstance(value, bool):
            return value
    elif isinstance(ty, t.EnumType):
        if isinstance(value, str):
            v = ty.value_of(value.split("#")[-1])
            if v is not None:
                return v
        if isinstance(value, int) and ty.name_of(value) is not None:
            return value
    raise ValueError(f"cannot store {_describe_value(value)} in {_article(ty.name)} {ty.name} variable")


def _describe_value(value: Any) -> str:
    """A Python value as the user wrote it (TRUE, 5, 'text'), for error messages."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, (bytes, bytearray)):
        value = bytes(value).decode("utf-8", "replace")
    if isinstance(value, str):
        return "'" + value[:40] + ("…'" if len(value) > 40 else "'")
    return repr(value)[:60]


_SPELLED = frozenset({"LREAL", "LINT", "LWORD", "LTIME", "LDATE", "SINT"})   # read letter by letter


def _article(word: str) -> str:
    """'an INT', 'an ARRAY', 'an LREAL', but 'a BOOL', 'a UINT', 'a STRING'."""
    return "an" if word[:1].upper() in "AEIO" or word.upper() in _SPELLED else "a"
