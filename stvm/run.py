"""`stvm run`: load a project, start a VM, drive it (demo, scenario, HMI, OPC UA) and report.

The command line itself (options, exit codes, error printing) is `stvm.cli`; this module is the
run. Nothing here knows one project: a demo's cycle (what counts as one, how many to run, and the
short flag that sets the count) comes from the manifest's `[demo]` table, and `--until EXPR` stops
any run when an ST boolean expression over its variables holds after a scan.

Exit codes (a contract): 0 ok, 1 compile errors, 2 usage error, 3 runtime fault.

Only what `stvm --help` needs is imported with this module; the project driver, the VM and the
front ends are imported when a run starts (`# lazy: start-up`).
"""

from __future__ import annotations

import contextlib
import signal
import sys
from pathlib import Path

from stvm.cli_support import (EXIT_COMPILE, EXIT_FAULT, EXIT_OK, EXIT_USAGE, UsageError,  # noqa: F401 (API)
                              compile_errors, print_diagnostics, require_files, resolve_project)


def run_settings(args):
    """The Sysmac settings of the command line's project: defaults, the manifest, then
    `--sysmac`, `--dialect` and `--define` (usage errors); `resolve_project(args).settings`."""
    return resolve_project(args).settings


def parse_assignment(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise UsageError(f"--set needs NAME=VALUE, got {text!r}")
    return name.strip(), value.strip()


# ---------------------------------------------------------------- the demo's flag, from the manifest

def demo_cycles_flag(files) -> str | None:
    """The short flag the project's manifest declares for its demo's cycle count (`[demo]
    cycles_flag = "--pnp-cycles"`), or None; a manifest that cannot be used is a UsageError."""
    from stvm.manifest import ManifestError   # lazy: start-up
    from stvm.project import LoadError, expand_paths
    existing = [f for f in files if Path(f).exists()]
    if not existing:
        return None
    try:
        _, manifest, _ = expand_paths(existing)
    except ManifestError as exc:
        raise UsageError(str(exc)) from exc
    except LoadError:   # nothing to load: the run reports it
        return None
    return manifest.get("demo", {}).get("cycles_flag")


def demo_cycle_limit(args, manifest: dict) -> int | None:
    """How many complete demo cycles to run: the declared flag, else `[demo] cycles`; None or
    0: no limit (Ctrl-C, `--cycles`, `--duration` or `--until` end the run)."""
    given = getattr(args, "demo_cycles", None)
    limit = given if given is not None else manifest.get("demo", {}).get("cycles")
    return limit or None


# ---------------------------------------------------------------- --until EXPR

_COMPARE = {"EQ": lambda a, b: a == b, "NE": lambda a, b: a != b, "LT": lambda a, b: a < b,
            "GT": lambda a, b: a > b, "LE": lambda a, b: a <= b, "GE": lambda a, b: a >= b}
_LOGIC = {"AND": lambda a, b: a and b, "AMP": lambda a, b: a and b, "OR": lambda a, b: a or b,
          "XOR": lambda a, b: a != b}
_SUPPORTED = ("variables, literals, comparisons (= <> < > <= >=), AND, OR, XOR, NOT and parentheses")


class _Untyped:
    """A literal (or a bare name) whose type comes from the variable it is compared with."""

    def __init__(self, kind: str, value, text: str) -> None:
        self.kind, self.value, self.text = kind, value, text


class Until:
    """`--until EXPR`: an ST boolean expression over the run's variables, evaluated after every
    scan; the run stops after the first scan in which it is TRUE. Names are variable paths as for
    `--print` (`PnP_Example_Instance.Prg_Step`, a global, `Main.arr[2]`); a literal takes the type
    of the variable it is compared with (`Prg_Step = 26`, `Color = Color#Red`, `t >= T#1s`).
    A bad expression raises UsageError."""

    def __init__(self, text: str, vm) -> None:
        from stvm.syntax import parse_expression   # lazy: start-up
        self.text = text
        self.vm = vm
        expr, diags = parse_expression(text, "<--until>")
        errors = [d for d in diags if d.is_error]
        if expr is None or errors:
            raise self._error(errors[0].message if errors else "not an ST expression")
        test, ty = self._compile(expr)
        if isinstance(ty, _Untyped):
            test, ty = self._typed(ty, None)
        from stvm.semantics import types as t   # lazy: start-up
        if not isinstance(ty, t.BoolType):
            raise self._error(f"the expression is {ty.name}, not BOOL (compare it: `... = 26`)")
        self._test = test

    def __call__(self) -> bool:
        return bool(self._test())

    def _error(self, message: str) -> UsageError:
        shown = self.text if len(self.text) <= 80 else self.text[:77] + "..."
        return UsageError(f"--until {shown!r}: {message}")

    def _compile(self, e):
        from stvm.runtime.vm import PathError, UnboundInOut   # lazy: start-up
        from stvm.semantics import types as t   # lazy: start-up
        from stvm.syntax import nodes as n   # lazy: start-up
        if isinstance(e, n.BoolLiteral):
            return (lambda value=e.value: value), t.BOOL
        if isinstance(e, n.IntLiteral):
            return None, _Untyped("number", e.value, str(e.value))
        if isinstance(e, n.RealLiteral):
            return None, _Untyped("number", e.value, e.text)
        if isinstance(e, n.StringLiteral):
            return None, _Untyped("string", e.value, repr(e.value))
        if isinstance(e, n.TimeLiteral):
            return None, _Untyped("time", e.value_ns, e.type_name)
        if isinstance(e, n.HashLiteral):
            return None, _Untyped("hash", None, e.text)
        if isinstance(e, (n.Name, n.Member, n.Index, n.Deref)):
            path = self._path(e)
            try:
                accessor = self.vm.accessor(path)
            except UnboundInOut as exc:
                raise self._error(f"{exc} (a VAR_IN_OUT is bound by the FB's first call)") from None
            except PathError as exc:
                if isinstance(e, n.Name):
                    return None, _Untyped("name", e.parts[-1], e.parts[-1])   # an enumerator, maybe
                raise self._error(str(exc)) from None
            return accessor.get, accessor.type
        if isinstance(e, n.Unary) and e.op == "NOT":
            test, ty = self._compile(e.operand)
            if isinstance(ty, _Untyped) or not isinstance(ty, t.BoolType):
                raise self._error("NOT needs a BOOL operand here")
            return (lambda: not test()), t.BOOL
        if isinstance(e, n.Unary) and e.op in ("MINUS", "PLUS"):
            test, ty = self._compile(e.operand)
            if isinstance(ty, _Untyped) and ty.kind in ("number", "time"):
                sign = -1 if e.op == "MINUS" else 1
                return None, _Untyped(ty.kind, sign * ty.value, ("-" if sign < 0 else "") + ty.text)
            raise self._error(f"a sign only goes before a literal here; {_SUPPORTED} are supported")
        if isinstance(e, n.Binary) and e.op in _LOGIC:
            (left, lt), (right, rt) = self._compile(e.left), self._compile(e.right)
            if isinstance(lt, _Untyped):
                left, lt = self._typed(lt, None)
            if isinstance(rt, _Untyped):
                right, rt = self._typed(rt, None)
            if not (isinstance(lt, t.BoolType) and isinstance(rt, t.BoolType)):
                raise self._error(f"{e.op.replace('AMP', '&')} needs BOOL operands here, got {lt.name} and {rt.name}")
            op = _LOGIC[e.op]
            return (lambda: op(left(), right())), t.BOOL
        if isinstance(e, n.Binary) and e.op in _COMPARE:
            (left, lt), (right, rt) = self._compile(e.left), self._compile(e.right)
            if isinstance(lt, _Untyped) and isinstance(rt, _Untyped):
                (left, lt), (right, rt) = self._typed(lt, None), self._typed(rt, None)
            elif isinstance(lt, _Untyped):
                left, lt = self._typed(lt, rt)
            elif isinstance(rt, _Untyped):
                right, rt = self._typed(rt, lt)
            self._comparable(lt, rt)
            op = _COMPARE[e.op]
            return (lambda: op(left(), right())), t.BOOL
        raise self._error(f"only {_SUPPORTED} are supported")

    def _path(self, e) -> str:
        from stvm.syntax import nodes as n   # lazy: start-up
        if isinstance(e, n.Name):
            if len(e.parts) != 1 or e.rooted:
                raise self._error(f"{e.text}: a namespace path is not a variable here")
            return e.parts[0]
        if isinstance(e, n.Member):
            return f"{self._path(e.base)}.{e.name}"
        if isinstance(e, n.Deref):
            return f"{self._path(e.base)}^"
        indices = []
        for index in e.indices:
            sign = 1
            if isinstance(index, n.Unary) and index.op == "MINUS":
                sign, index = -1, index.operand
            if not isinstance(index, n.IntLiteral):
                raise self._error("an array index must be an integer literal here")
            indices.append(str(sign * index.value))
        return f"{self._path(e.base)}[{', '.join(indices)}]"

    def _typed(self, literal: _Untyped, ty):
        """A literal as a value of `ty` (the other operand's type); without one, its own type."""
        from stvm.runtime.vm import coerce_python_value   # lazy: start-up
        from stvm.semantics import types as t   # lazy: start-up
        from stvm.semantics.literals import literal_value   # lazy: start-up
        if ty is None:
            if literal.kind == "number":
                own = t.LREAL if isinstance(literal.value, float) else t.ELEMENTARY["LINT"]
                return (lambda value=literal.value: value), own
            if literal.kind == "string":
                return (lambda value=literal.value: value), t.STRING
            if literal.kind == "time":
                return (lambda value=literal.value: value), t.TimeType(literal.text)
            if literal.kind == "hash" and literal.text.upper() in ("BOOL#TRUE", "BOOL#1", "BOOL#FALSE", "BOOL#0"):
                value = literal.text.upper() in ("BOOL#TRUE", "BOOL#1")
                return (lambda: value), t.BOOL
            raise self._error(f"{literal.text}: not a variable of the run (--print names one the same way)")
        try:
            if literal.kind == "name":
                if not isinstance(ty, t.EnumType):
                    raise ValueError(f"{literal.text} is not a variable of the run")
                value = ty.value_of(literal.text)
                if value is None:
                    raise ValueError(f"{literal.text} is not a value of {ty.name}")
            elif literal.kind == "hash":
                value = coerce_python_value(literal_value(literal.text, ty), ty)
            elif literal.kind == "string":
                if not isinstance(ty, t.StringType):
                    raise ValueError(f"a string cannot be compared with {ty.name}")
                value = literal.value       # compared as written: ST does not cut a literal
            elif literal.kind == "time":
                if not (isinstance(ty, t.TimeType) and ty.name == literal.text):
                    raise ValueError(f"a {literal.text} literal cannot be compared with {ty.name}")
                value = literal.value
            elif isinstance(ty, t.IntType) and isinstance(literal.value, int):
                value = coerce_python_value(literal.value, ty)    # out of range: an error
            elif isinstance(ty, t.RealType):
                value = coerce_python_value(literal.value, ty)    # a REAL literal is binary32
            elif isinstance(ty, t.IntType):
                # `Count = 1.5` could never be TRUE: the run would go on forever (issue 34 item 12)
                raise ValueError(f"{literal.text} is a REAL literal and {ty.name} holds whole numbers "
                                 f"(compare with an integer, or convert: {ty.name}_TO_REAL(...))")
            elif isinstance(ty, t.BoolType) and isinstance(literal.value, int) and literal.value in (0, 1) \
                    and not literal.text.startswith("-"):
                value = bool(literal.value)   # IEC 61131-3 table 5: 0 and 1 are BOOL literals
            else:
                raise ValueError(f"{literal.text} cannot be compared with {ty.name}"
                                 + (" (write a duration as T#5ms)" if isinstance(ty, t.TimeType) else ""))
        except ValueError as exc:
            raise self._error(str(exc)) from None
        return (lambda: value), ty

    def _comparable(self, a, b) -> None:
        from stvm.semantics import types as t   # lazy: start-up
        numbers = (t.IntType, t.RealType)
        if isinstance(a, numbers) and isinstance(b, numbers):
            return
        if type(a) is type(b) and (not isinstance(a, (t.EnumType, t.TimeType)) or a.name == b.name):
            if isinstance(a, (t.BoolType, t.StringType, t.TimeType, t.EnumType)):
                return
        raise self._error(f"{a.name} and {b.name} cannot be compared")


# ---------------------------------------------------------------- the run

_DEMO_FLAGS = (("robot", "--robot"), ("emulator_log", "--emulator-log"), ("no_demo", "--no-demo"),
               ("virtual_clock", "--virtual-clock"))


def cmd_run(args) -> int:
    from stvm.project import LoadError, load, nothing_to_run   # lazy: start-up
    from stvm.runtime.vm import RuntimeFault   # lazy: start-up
    spec = resolve_project(args)
    scan_ns, duration_ns = _run_limits(args)
    try:
        project = load(spec)
    except LoadError as exc:
        return compile_errors(exc.diagnostics, exc.sources)
    print_diagnostics(project.warnings, project.sources)
    if nothing_to_run(project):
        print(f"stvm: error: {nothing_to_run(project, args.files)}", file=sys.stderr)
        return EXIT_COMPILE
    _check_demo_flags(args, "demo" in project.manifest)
    project.files_root = getattr(args, "files_root", None)
    session = _start_session(args, project, scan_ns)
    if session is None:
        return EXIT_COMPILE
    vm, demo, until = session.vm, session.demo, session.until
    status, interrupted = EXIT_OK, False
    previous = signal.getsignal(signal.SIGINT)
    stops = [test for test in (demo.done if demo else None, until) if test is not None]

    def run_scans() -> None:
        vm.run(cycles=args.cycles, duration_ns=duration_ns,
               until=(lambda: any(test() for test in stops)) if stops else None)

    from stvm.runtime.watchdog import Watchdog   # lazy: start-up
    try:
        try:
            with Watchdog(vm, args.watchdog) if args.watchdog is not None else contextlib.nullcontext():
                if demo is not None:
                    from stvm.demo import run_with_status   # lazy: start-up
                    run_with_status(demo, run_scans)
                else:
                    run_scans()
        except KeyboardInterrupt:
            interrupted = True
        except RuntimeFault as fault:
            sys.stderr.write(fault.render(project.sources))
            status = EXIT_FAULT
    finally:
        signal.signal(signal.SIGINT, previous)
        session.close()
        if demo is not None:
            print(f"PnP cycles completed: {demo.state.cycles}; VM time {vm.now_ns / 1e9:.3f} s; "
                  f"scans {vm.scan_count}; {_realtime_counts(vm)}", file=sys.stderr)
    return _report(args, vm, status, until, interrupted)


def _run_limits(args) -> tuple[int, int | None]:
    """(--scan, --duration) in nanoseconds; a bad --scan, --duration or --cycles is a usage error."""
    from stvm.project import parse_duration   # lazy: start-up
    try:
        scan_ns = parse_duration(args.scan)
        duration_ns = parse_duration(args.duration) if args.duration is not None else None   # "" is an error, not "forever"
    except ValueError as exc:
        raise UsageError(str(exc)) from exc
    if scan_ns <= 0:
        raise UsageError("--scan must be positive")
    if duration_ns is not None and duration_ns < 0:
        raise UsageError(f"--duration must not be negative, got {args.duration!r}")
    if args.cycles is not None and args.cycles < 0:
        raise UsageError("--cycles must be >= 0")
    return scan_ns, duration_ns


def _start_session(args, project, scan_ns: int):
    """The run's session (stvm/session.py): the VM, `--print`/`--until` checked and `--set`
    applied before the first scan, then the demo or the scenario, OPC UA and the HMI. None
    after HMI page errors (reported); a bad option is a UsageError. On any error what was
    started is stopped."""
    from stvm.session import Session, SessionConfig   # lazy: start-up
    demo_mode = "demo" in project.manifest and not args.no_demo
    # the demo talks to a robot that moves in wall-clock time: run on the real-time clock
    realtime = args.realtime or (demo_mode and not args.virtual_clock)
    try:
        # the demo brings its own robot and scenario (stvm/demo.py)
        session = Session(project, SessionConfig(scan=scan_ns, scenario=None if demo_mode else args.scenario,
                                                 robot="none", realtime=realtime))
    except ValueError as exc:   # ScenarioError
        raise UsageError(str(exc)) from exc
    session.demo = session.until = None
    try:
        vm = session.vm
        # real sockets get the controller's socket service between scans (stvm/stdlib/sockets.py:
        # one poll of all sockets before each scan, the queued sends after it), made at the first call
        vm.ctx.socket_service_vm = vm
        _check_prints(args, vm)   # a typo is a usage error, not a lost run
        session.until = Until(args.until, vm) if getattr(args, "until", None) is not None else None
        _apply_sets(args, vm, project)
        try:
            if demo_mode:
                from stvm.demo import Demo   # lazy: start-up
                session.demo = Demo(project, vm, args, cycles=demo_cycle_limit(args, project.manifest))
                session.add_robot(session.demo)
                session.demo.start()
            else:
                session.wire()
            from stvm.opcua.cli import start_server   # lazy: start-up
            session.add_front_end(start_server(args, project, vm, args.files))
        except (ValueError, KeyError, RuntimeError) as exc:
            raise UsageError(str(exc)) from exc
        if args.hmi:
            hmi = _start_hmi(args.hmi, project, vm, session.demo)
            if hmi is None:
                session.close()
                return None
            session.add_front_end(hmi)
    except BaseException:
        session.close()
        raise
    return session


def _check_prints(args, vm) -> None:
    from stvm.runtime.vm import PathError, UnboundInOut   # lazy: start-up
    for name in args.print or []:
        try:
            vm.resolve(name)
        except UnboundInOut:
            pass   # well-formed; bound once the FB has been called
        except PathError as exc:
            raise UsageError(str(exc)) from exc


def _apply_sets(args, vm, project=None) -> None:
    """`--set NAME=VALUE`, before the scenario's initial values. The value must be within the
    project's operator limits (stvm/frontend/limits.py: the range the HMI and OPC UA enforce;
    NaN and infinities refused). Choice: `--set` may still preset an output or status (the
    developer's preset before the first scan, like the debugger's `set`, not an operator's write)."""
    if not args.set:
        return
    from stvm.frontend.limits import LimitTable, LimitsError   # lazy: start-up
    from stvm.runtime.vm import PathError   # lazy: start-up
    # lazy: start-up (the literal parser brings the syntax nodes, ~50 ms, which a run from the
    # cache never needs otherwise)
    from stvm.semantics.literals import literal_value
    try:
        table = LimitTable.for_project(project, vm) if project is not None else LimitTable(
            None, lambda path: vm.type_of(path))
    except LimitsError as exc:
        raise UsageError(str(exc)) from exc
    for item in args.set:
        name, text = parse_assignment(item)
        try:
            ty = vm.type_of(name)
            value = literal_value(text, ty)
            limits = table.limits_for(name)
            problem = limits.check(value)
            if problem is not None:
                raise UsageError(f"--set {limits.label or name}: {problem} (limits from {limits.by or 'the type'})")
            vm.set(name, value)
        except PathError as exc:
            raise UsageError(str(exc)) from exc
        except ValueError as exc:
            raise UsageError(f"--set {name}: {exc}") from exc


def _report(args, vm, status: int, until, interrupted: bool) -> int:
    """What a run prints after it ends (--until, --print, --stats, real-time counts)."""
    from stvm.runtime.vm import PathError   # lazy: start-up
    if until is not None and status == EXIT_OK and not interrupted and until():
        print(f"--until {args.until}: TRUE after scan {vm.scan_count}", file=sys.stderr)
    for name in args.print or []:
        try:
            print(f"{name} = {vm.format(name)}")
        except PathError as exc:   # also UnboundInOut: a path through an in-out is checked only now
            print(f"stvm: {exc}", file=sys.stderr)
            status = status or EXIT_USAGE
    if args.stats:
        _print_stats(vm)
        service = None
        if vm.ctx.transport is not None:
            from stvm.stdlib.sockets import socket_service_us   # lazy: start-up
            service = socket_service_us(vm)
        if service is not None:
            print(f"socket service us (between scans, not in the scan time): mean {service[0]:.1f}  "
                  f"p50 {service[1]:.1f}  p99 {service[2]:.1f}  max {service[3]:.1f}")
    elif vm.realtime and vm.scan_count:
        _print_realtime(vm)
    if interrupted:
        print(f"stopped after {vm.scan_count} scans", file=sys.stderr)
    return status


def _check_demo_flags(args, is_demo: bool) -> None:
    """Demo options on a project without a demo would be silently ignored: refuse them."""
    given = [flag for attr, flag in _DEMO_FLAGS if getattr(args, attr, None) not in (None, False)]
    if getattr(args, "demo_cycles", None) is not None:
        given.append(getattr(args, "demo_cycles_flag", "the demo's cycle flag"))
    if given and not is_demo:
        raise UsageError(f"{', '.join(given)}: only for a demo project (a stvm.toml with a [demo] table "
                         f"beside the file, e.g. st_src/); {' '.join(args.files)} has none")
    if getattr(args, "emulator_log", None) and getattr(args, "robot", None):
        # no emulator runs with a real robot: the log would stay empty without a word
        raise UsageError("--emulator-log writes the bundled emulator's frames, and with --robot "
                         "HOST:PORT no emulator runs (drop one of the two)")
    if getattr(args, "emulator_log", None):
        from emulator.cli import check_log_path   # lazy: start-up
        problem = check_log_path(args.emulator_log)
        if problem:
            raise UsageError(problem.replace("--log", "--emulator-log", 1))
    if is_demo and args.no_demo:
        extra = [flag for flag in given if flag not in ("--no-demo",)]
        if extra:
            raise UsageError(f"{', '.join(extra)} cannot be combined with --no-demo")


def _realtime_counts(vm) -> str:
    return (f"overruns {vm.overruns} (started > 1 period late), catch-up scans {vm.catch_up_scans}, "
            f"scans over the period {vm.long_scans}, max lateness {vm.max_lateness_ns / 1000:.0f} us")


def _start_hmi(address: str, project, vm, demo=None):
    """`--hmi`: the web HMI beside the run (stvm/hmi); None after page-file errors (reported)."""
    from stvm.hmi.cli import HmiUsageError, report_load_error, start_hmi   # lazy: start-up
    from stvm.hmi.pages import HmiLoadError
    from stvm.hmi.robot import from_tcp_server
    pose = parameters = None
    if demo is not None and demo.robot_address is not None:
        parameters = {"robot_host": demo.robot_address[0], "robot_port": demo.robot_address[1]}
        if demo.server is not None:
            pose = from_tcp_server(demo.server)
    try:
        return start_hmi(project, vm, address, pose=pose, run_parameters=parameters)
    except HmiUsageError as exc:
        raise UsageError(str(exc)) from exc
    except HmiLoadError as exc:
        report_load_error(exc)
        return None


def _print_realtime(vm) -> None:
    """`--realtime` always reports how well the deadlines were kept (stderr)."""
    from stvm.runtime.vm import timing_us   # lazy: start-up
    jitter = timing_us(vm.jitter_ns)
    if jitter is not None:
        print(f"realtime: {vm.scan_count} scans, {_realtime_counts(vm)}; start jitter us: "
              f"p50 {jitter[1]:.0f}  p99 {jitter[2]:.0f}  max {jitter[3]:.0f}", file=sys.stderr)


def _print_stats(vm) -> None:
    from stvm.runtime.vm import timing_us   # lazy: start-up
    scan = timing_us(vm.scan_durations_ns)
    if scan is None:
        print("scans: 0")
        return
    mean, p50, p99, worst = scan
    print(f"scans: {len(vm.scan_durations_ns)}  scan time us: mean {mean:.1f}  p50 {p50:.1f}  "
          f"p99 {p99:.1f}  max {worst:.1f}")
    if vm.realtime:
        jitter = timing_us(vm.jitter_ns) or (0.0, 0.0, 0.0, 0.0)
        print(f"overruns: {vm.overruns}  catch-up scans: {vm.catch_up_scans}  "
              f"scans over the period: {vm.long_scans}  jitter us: p50 {jitter[1]:.1f}  p99 {jitter[2]:.1f}  max {jitter[3]:.1f}")
