"""The `stvm` command: check · run (trace and debug come in their own modules).

Exit codes (a contract): 0 ok, 1 compile errors, 2 usage error, 3 runtime fault.
"""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
from pathlib import Path

EXIT_OK, EXIT_COMPILE, EXIT_USAGE, EXIT_FAULT = 0, 1, 2, 3


class _UsageError(Exception):
    pass


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 on usage errors, as we want
        self.print_usage(sys.stderr)
        print(f"stvm: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def _settings(args):
    from stvm.project import project_settings
    try:
        dialect = [f"dialect={vars(args)['dialect']}"] if vars(args).get("dialect") else []
        return project_settings(args.files, (getattr(args, "sysmac", None) or []) + dialect)
    except ValueError as exc:
        raise _UsageError(str(exc)) from exc


def _print_diagnostics(diags, sources) -> None:
    from stvm.diagnostics import render
    for d in diags:
        sys.stderr.write(render(d, sources))


def cmd_check(args) -> int:
    from stvm.project import check
    _require_files(args.files)
    analysis, diags, sources = check(args.files, _settings(args), generate=True)
    _print_diagnostics(diags, sources)
    errors = sum(d.is_error for d in diags)
    if errors:
        print(f"{errors} error(s)", file=sys.stderr)
        return EXIT_COMPILE
    return EXIT_OK


def _require_files(files) -> None:
    for f in files:
        if not Path(f).exists():
            raise _UsageError(f"no such file: {f}")


def _parse_assignment(text: str) -> tuple[str, str]:
    name, sep, value = text.partition("=")
    if not sep or not name.strip():
        raise _UsageError(f"--set needs NAME=VALUE, got {text!r}")
    return name.strip(), value.strip()


def cmd_run(args) -> int:
    from stvm.project import LoadError, load, nothing_to_run, parse_duration
    from stvm.runtime.vm import PathError, RuntimeFault, UnboundInOut
    from stvm.semantics.literals import literal_value
    _require_files(args.files)
    settings = _settings(args)
    try:
        scan_ns = parse_duration(args.scan)
        duration_ns = parse_duration(args.duration) if args.duration else None
    except ValueError as exc:
        raise _UsageError(str(exc)) from exc
    if scan_ns <= 0:
        raise _UsageError("--scan must be positive")
    if duration_ns is not None and duration_ns < 0:
        raise _UsageError(f"--duration must not be negative, got {args.duration!r}")
    if args.cycles is not None and args.cycles < 0:
        raise _UsageError("--cycles must be >= 0")
    if args.pnp_cycles is not None and args.pnp_cycles < 1:
        raise _UsageError(f"--pnp-cycles must be >= 1, got {args.pnp_cycles}")
    try:
        project = load(args.files, settings, use_cache=not args.no_cache)
    except LoadError as exc:
        _print_diagnostics(exc.diagnostics, exc.sources)
        print(f"{sum(d.is_error for d in exc.diagnostics)} error(s)", file=sys.stderr)
        return EXIT_COMPILE
    _print_diagnostics(project.warnings, project.sources)
    if nothing_to_run(project):
        print(f"stvm: error: {nothing_to_run(project, args.files)}", file=sys.stderr)
        return EXIT_COMPILE
    _check_demo_flags(args, "demo" in project.manifest)
    demo_mode = "demo" in project.manifest and not args.no_demo
    # the demo talks to a robot that moves in wall-clock time: run on the real-time clock
    realtime = args.realtime or (demo_mode and not args.virtual_clock)
    vm = project.start(scan=scan_ns, realtime=realtime)
    # validate --print names before running, so a typo is a usage error, not a lost run
    for name in args.print or []:
        try:
            vm.resolve(name)
        except UnboundInOut:
            pass   # well-formed; bound once the FB has been called
        except PathError as exc:
            raise _UsageError(str(exc)) from exc
    for item in args.set or []:
        name, text = _parse_assignment(item)
        try:
            ty = vm.type_of(name)
            vm.set(name, literal_value(text, ty))
        except PathError as exc:
            raise _UsageError(str(exc)) from exc
        except ValueError as exc:
            raise _UsageError(f"--set {name}: {exc}") from exc
    demo = opcua = None
    try:
        if demo_mode:
            from stvm.demo import Demo
            demo = Demo(project, vm, args)
            demo.start()
        elif args.scenario:
            from stvm.scenario import ScenarioDriver, load_scenario
            driver = ScenarioDriver(load_scenario(args.scenario), vm)
            driver.apply_initial()
            vm.on_scan_end.append(driver.after_scan)
        from stvm.opcua.cli import start_server
        opcua = start_server(args, project, vm, args.files)
    except (ValueError, KeyError, RuntimeError) as exc:
        if demo is not None:
            demo.stop()
        raise _UsageError(str(exc)) from exc
    hmi = None
    if args.hmi:
        try:
            hmi = _start_hmi(args.hmi, project, vm, demo)
        except BaseException:
            if opcua is not None:
                opcua.stop()
            if demo is not None:
                demo.stop()
            raise
        if hmi is None:
            if opcua is not None:
                opcua.stop()
            if demo is not None:
                demo.stop()
            vm.close()
            return EXIT_COMPILE
    status = EXIT_OK
    interrupted = False
    previous = signal.getsignal(signal.SIGINT)

    def run_scans() -> None:
        vm.run(cycles=args.cycles, duration_ns=duration_ns, until=demo.done if demo else None)

    from stvm.runtime.watchdog import Watchdog
    try:
        try:
            with Watchdog(vm, args.watchdog) if args.watchdog is not None else contextlib.nullcontext():
                if demo is not None:
                    from stvm.demo import run_with_status
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
        if hmi is not None:
            hmi.stop()
        if opcua is not None:
            opcua.stop()
        vm.close()
        if demo is not None:
            demo.stop()
            print(f"PnP cycles completed: {demo.state.cycles}; VM time {vm.now_ns / 1e9:.3f} s; "
                  f"scans {vm.scan_count}; {_realtime_counts(vm)}", file=sys.stderr)
    for name in args.print or []:
        try:
            print(f"{name} = {vm.format(name)}")
        except UnboundInOut as exc:
            print(f"stvm: {exc}", file=sys.stderr)
            status = status or EXIT_USAGE
    if args.stats:
        _print_stats(vm)
    elif vm.realtime and vm.scan_count:
        _print_realtime(vm)
    if interrupted:
        print(f"stopped after {vm.scan_count} scans", file=sys.stderr)
    return status


_DEMO_FLAGS = (("robot", "--robot"), ("emulator_log", "--emulator-log"), ("pnp_cycles", "--pnp-cycles"),
               ("no_demo", "--no-demo"), ("virtual_clock", "--virtual-clock"))


def _check_demo_flags(args, is_demo: bool) -> None:
    """Demo options on a project without a demo would be silently ignored: refuse them."""
    given = [flag for attr, flag in _DEMO_FLAGS if getattr(args, attr, None) not in (None, False)]
    if given and not is_demo:
        raise _UsageError(f"{', '.join(given)}: only for a demo project (a stvm.toml with a [demo] table "
                          f"beside the file, e.g. st_src/); {' '.join(args.files)} has none")
    if getattr(args, "emulator_log", None):
        from emulator.cli import check_log_path
        problem = check_log_path(args.emulator_log)
        if problem:
            raise _UsageError(problem.replace("--log", "--emulator-log", 1))
    if is_demo and args.no_demo:
        extra = [flag for flag in given if flag not in ("--no-demo",)]
        if extra:
            raise _UsageError(f"{', '.join(extra)} cannot be combined with --no-demo")


def _watchdog_seconds(text: str) -> float | None:
    """`--watchdog SECONDS` (a positive finite number) or `off`."""
    import math
    if text.strip().lower() == "off":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs seconds (a positive number) or 'off', got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"needs seconds > 0 (or 'off' for no watchdog), got {text!r}")
    return value


def _realtime_counts(vm) -> str:
    return (f"overruns {vm.overruns} (started > 1 period late), catch-up scans {vm.catch_up_scans}, "
            f"max lateness {vm.max_lateness_ns / 1000:.0f} us")


def _start_hmi(address: str, project, vm, demo=None):
    """`--hmi`: the web HMI beside the run (stvm/hmi); None after page-file errors (reported)."""
    from stvm.hmi.cli import HmiUsageError, report_load_error, start_hmi
    from stvm.hmi.pages import HmiLoadError
    pose = parameters = None
    if demo is not None and demo.robot_address is not None:
        parameters = {"robot_host": demo.robot_address[0], "robot_port": demo.robot_address[1]}
        if demo.server is not None:
            from stvm.hmi.robot import from_tcp_server
            pose = from_tcp_server(demo.server)
    try:
        return start_hmi(project, vm, address, pose=pose, run_parameters=parameters)
    except HmiUsageError as exc:
        raise _UsageError(str(exc)) from exc
    except HmiLoadError as exc:
        report_load_error(exc)
        return None


def _print_realtime(vm) -> None:
    """`--realtime` always reports how well the deadlines were kept (stderr)."""
    from stvm.runtime.vm import timing_us
    jitter = timing_us(vm.jitter_ns)
    if jitter is not None:
        print(f"realtime: {vm.scan_count} scans, {_realtime_counts(vm)}; start jitter us: "
              f"p50 {jitter[1]:.0f}  p99 {jitter[2]:.0f}  max {jitter[3]:.0f}", file=sys.stderr)


def _print_stats(vm) -> None:
    from stvm.runtime.vm import timing_us
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
              f"jitter us: p50 {jitter[1]:.1f}  p99 {jitter[2]:.1f}  max {jitter[3]:.1f}")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="stvm", description="Structured Text virtual machine")
    parser.add_argument("--version", action="version", version="stvm " + __import__("stvm").__version__)
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    sysmac_help = "override a Sysmac UNCERTAIN setting, NAME=VALUE (see README)"
    dialects = ["iec", "sysmac", "codesys", "twincat"]
    dialect_help = "vendor dialect: name rules and vendor types (default: stvm.toml's, else sysmac)"

    check = sub.add_parser("check", help="check ST files and print diagnostics")
    check.add_argument("files", nargs="+")
    check.add_argument("--sysmac", action="append", metavar="NAME=VALUE", help=sysmac_help)
    check.add_argument("--dialect", choices=dialects, help=dialect_help)
    check.set_defaults(func=cmd_check)

    run = sub.add_parser("run", help="run ST programs on the VM")
    run.add_argument("files", nargs="+")
    run.add_argument("--scan", default="10ms", help="default task period (default 10ms)")
    limit = run.add_mutually_exclusive_group()
    limit.add_argument("--cycles", type=int, help="number of scans to run")
    limit.add_argument("--duration", help="VM time to run, e.g. 5s")
    run.add_argument("--print", action="append", metavar="NAME", help="print NAME = VALUE after the run")
    run.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a variable before the first scan")
    run.add_argument("--realtime", action="store_true", help="sleep to each deadline (default: virtual clock)")
    run.add_argument("--stats", action="store_true", help="print scan-time statistics")
    run.add_argument("--no-cache", action="store_true", help="do not use the compile cache")
    run.add_argument("--scenario", help="scenario TOML applied to the run (see README)")
    run.add_argument("--watchdog", type=_watchdog_seconds, default=5.0, metavar="SECONDS",
                     help="fault when one scan runs longer than this wall-clock time (default 5; off: none)")
    from stvm.opcua.cli import add_option
    add_option(run)
    demo = run.add_argument_group("demo (projects whose stvm.toml has [demo], e.g. st_src/)")
    demo.add_argument("--robot", metavar="HOST:PORT", help="talk to this robot instead of the bundled emulator")
    demo.add_argument("--emulator-log", metavar="FILE", help="write the emulator's frame log (JSON lines)")
    demo.add_argument("--pnp-cycles", type=int, metavar="N", help="stop after N complete PnP cycles")
    demo.add_argument("--no-demo", action="store_true", help="run the project without the demo driver")
    demo.add_argument("--virtual-clock", action="store_true", help="demo on the virtual clock (default: real time)")
    run.add_argument("--hmi", metavar="[HOST:]PORT",
                     help="serve the project's HMI pages (stvm.toml [hmi], docs/hmi.md) while the VM runs; "
                          "host 127.0.0.1 unless given, any other host needs the token printed at start-up")
    run.add_argument("--sysmac", action="append", metavar="NAME=VALUE", help=sysmac_help)
    run.add_argument("--dialect", choices=dialects, help=dialect_help)
    run.set_defaults(func=cmd_run)
    _register_extensions(sub)
    return parser


def _register_extensions(sub) -> None:
    """Commands living in their own modules (demo, trace, debug) register themselves here."""
    import importlib
    for module_name in ("stvm.demo.cli", "stvm.trace.cli", "stvm.debug.cli", "stvm.lint.cli"):
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name and module_name.startswith(exc.name):
                continue
            raise
        module.register(sub)


EXIT_INTERNAL = 70   # EX_SOFTWARE: a bug in stvm, never the user's input


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:
        # Ctrl-C before the run started (imports, loading): nothing ran, nothing to print
        print("stvm: interrupted", file=sys.stderr)
        return 130


def _show_cache_warnings() -> None:
    """A cache that cannot be used safely is one `stvm: warning:` line, not a Python warning."""
    import warnings
    from stvm.cache import CacheWarning
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, CacheWarning):
            print(f"stvm: warning: {message}", file=sys.stderr)
        else:
            shown(message, category, filename, lineno, file, line)
    warnings.showwarning = show


def _main(argv: list[str] | None) -> int:
    from stvm.diagnostics import printable
    _show_cache_warnings()
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        return _dispatch(args)
    except _UsageError as exc:
        print(f"stvm: error: {printable(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return EXIT_OK
    except KeyboardInterrupt:
        # Ctrl-C before the run started (while loading): nothing ran, nothing to print
        print("stvm: interrupted", file=sys.stderr)
        return 130
    except MemoryError:
        print("stvm: error: out of memory", file=sys.stderr)
        return EXIT_COMPILE
    except Exception as exc:   # a bug in stvm: one line, not a traceback (STVM_TRACEBACK=1 shows it)
        import os
        if os.environ.get("STVM_TRACEBACK"):
            raise
        print(f"stvm: internal error: {type(exc).__name__}: {printable(str(exc))} "
              f"(a bug in stvm; STVM_TRACEBACK=1 shows where)", file=sys.stderr)
        return EXIT_INTERNAL


def _dispatch(args) -> int:
    """Run the command; errors that name a bad input become usage (2) or source (1) errors."""
    from stvm.manifest import ManifestError
    from stvm.project import LoadError
    try:
        return args.func(args)
    except ManifestError as exc:
        raise _UsageError(str(exc)) from exc
    except LoadError as exc:   # nothing to load (an empty folder) or unreadable sources
        _print_diagnostics(exc.diagnostics, exc.sources)
        return EXIT_COMPILE


if __name__ == "__main__":
    raise SystemExit(main())
