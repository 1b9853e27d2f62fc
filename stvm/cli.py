"""The `stvm` command: check · run (trace and debug come in their own modules).

Exit codes (a contract): 0 ok, 1 compile errors, 2 usage error, 3 runtime fault.
"""

from __future__ import annotations

import argparse
import gc
import importlib
import math
import os
import sys
import warnings

from stvm.cli_support import (EXIT_COMPILE, EXIT_FAULT, EXIT_INTERNAL, EXIT_INTERRUPTED, EXIT_OK,  # noqa: F401 (API)
                              EXIT_USAGE, UsageError, add_project_options, print_diagnostics, resolve_project)
from stvm.run import cmd_run, demo_cycles_flag, run_settings  # noqa: F401 (API)
from stvm.version import __version__


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # argparse exits 2 on usage errors, as we want
        self.print_usage(sys.stderr)
        print(f"stvm: error: {message}", file=sys.stderr)
        raise SystemExit(EXIT_USAGE)


def cmd_check(args) -> int:
    if args.explain:
        return _explain(args.explain)
    if not args.files:
        print("stvm: error: check needs FILE or DIR arguments (or --explain CODE)", file=sys.stderr)
        return EXIT_USAGE
    if args.emit_python or args.pou:
        return _emit_python(args)
    from stvm.project import check   # lazy: start-up
    analysis, diags, sources = check(resolve_project(args), generate=True)
    print_diagnostics(diags, sources)
    errors = sum(d.is_error for d in diags)
    if errors:
        print(f"{errors} error(s)", file=sys.stderr)
        return EXIT_COMPILE
    return EXIT_OK


def _emit_python(args) -> int:
    """`stvm check --emit-python`: check, lower through the driver's stages, then print the
    generated Python of the project's POUs (or the `--pou` named) beside their ST lines."""
    from stvm.lower.listing import render, select   # lazy: start-up
    from stvm.project import LoadError, check_stage, compile_stage, parse_stage   # lazy: start-up
    checked = check_stage(parse_stage(resolve_project(args)))
    print_diagnostics(checked.diagnostics, checked.sources)
    errors = sum(d.is_error for d in checked.diagnostics)
    if errors:
        print(f"{errors} error(s)", file=sys.stderr)
        return EXIT_COMPILE
    try:
        compiled = compile_stage(checked)
    except LoadError as exc:    # a limit only code generation meets (nesting, size)
        print_diagnostics(exc.diagnostics, checked.sources)
        print(f"{sum(d.is_error for d in exc.diagnostics)} error(s)", file=sys.stderr)
        return EXIT_COMPILE
    chosen, titles = select(compiled.lowered, checked.analysis, checked.parsed.files, args.pou or ())
    if args.pou and not chosen:
        raise UsageError(f"--pou {', '.join(args.pou)}: no such POU, STRUCT or VAR_GLOBAL in the project")
    sys.stdout.write(render(compiled.lowered, chosen, titles))
    return EXIT_OK


def _explain(code: str) -> int:
    """`stvm check --explain E031` (ALL: every entry), as `stvm lint --explain SA102`."""
    from stvm.diagnostics.codes import CODES, explain, lookup   # lazy: start-up
    if code.strip().upper() == "ALL":
        sys.stdout.write("\n".join(explain(entry) for entry in CODES.values()))
        return EXIT_OK
    entry = lookup(code)
    if entry is None:
        print(f"stvm: error: unknown error code {code[:40]!r} (codes are E001…, W001…; "
              f"`stvm check --explain ALL` lists them; lint's SA codes: `stvm lint --explain`)", file=sys.stderr)
        return EXIT_USAGE
    sys.stdout.write(explain(entry))
    return EXIT_OK


def _watchdog_seconds(text: str) -> float | None:
    """`--watchdog SECONDS` (a positive finite number) or `off`."""
    if text.strip().lower() == "off":
        return None
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs seconds (a positive number) or 'off', got {text!r}") from None
    if not math.isfinite(value) or value <= 0:
        raise argparse.ArgumentTypeError(f"needs seconds > 0 (or 'off' for no watchdog), got {text!r}")
    return value


_CORE_COMMANDS = ("check", "run")


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The whole command line; given `command` (the first argument) and it is one of this
    module's own commands, the extension commands are left out (and for `check`, `run` too):
    importing their modules is a tenth of a warm `stvm run`'s start-up, and the parse of a core
    command never looks at the other commands."""
    parser = _Parser(prog="stvm", description="Structured Text virtual machine")
    parser.add_argument("--version", action="version", version="stvm " + __version__)
    sub = parser.add_subparsers(dest="command", parser_class=_Parser)
    check = sub.add_parser("check", help="check ST files and print diagnostics")
    check.add_argument("files", nargs="*")
    check.add_argument("--explain", metavar="CODE", help="print what an error code means (ALL: every code)")
    check.add_argument("--emit-python", action="store_true",
                       help="also print the generated Python of each POU with the ST file:line of every line")
    check.add_argument("--pou", action="append", metavar="NAME",
                       help="with --emit-python: only this POU (repeatable; stdlib POUs too, e.g. TON; "
                            "VAR_GLOBAL for the globals)")
    add_project_options(check)
    check.set_defaults(func=cmd_check)
    if command == "check":   # `run`'s options import the OPC UA configuration: a check needs neither
        return parser

    run = sub.add_parser("run", help="run ST programs on the VM")
    run.add_argument("files", nargs="+")
    run.add_argument("--scan", default="10ms", help="default task period (default 10ms)")
    limit = run.add_mutually_exclusive_group()
    limit.add_argument("--cycles", type=int, help="number of scans to run")
    limit.add_argument("--duration", help="VM time to run, e.g. 5s")
    run.add_argument("--until", metavar="EXPR",
                     help="stop after the first scan in which this ST boolean expression holds, "
                          "e.g. \"Main.step = 26\" (variables as for --print)")
    run.add_argument("--print", action="append", metavar="NAME", help="print NAME = VALUE after the run")
    run.add_argument("--set", action="append", metavar="NAME=VALUE", help="set a variable before the first scan")
    run.add_argument("--realtime", action="store_true", help="sleep to each deadline (default: virtual clock)")
    run.add_argument("--stats", action="store_true", help="print scan-time statistics")
    run.add_argument("--no-cache", action="store_true", help="do not use the compile cache")
    run.add_argument("--files-root", metavar="DIR",
                     help="twincat: the folder SysFile/SysDir and the file FBs work in (default: "
                          "[files] root of stvm.toml, else stvm_files beside it, else a temporary folder)")
    run.add_argument("--scenario", help="scenario TOML applied to the run (see README)")
    run.add_argument("--watchdog", type=_watchdog_seconds, default=5.0, metavar="SECONDS",
                     help="fault when one scan runs longer than this wall-clock time (default 5; off: none)")
    from stvm.opcua.cli import add_option   # lazy: start-up (`stvm --version`)
    add_option(run)
    demo = run.add_argument_group(
        "demo (projects whose stvm.toml has [demo], e.g. st_src/; its `cycles_flag`, e.g. --pnp-cycles N, "
        "sets how many complete cycles to run)")
    demo.add_argument("--robot", metavar="HOST:PORT", help="talk to this robot instead of the bundled emulator")
    demo.add_argument("--emulator-log", metavar="FILE", help="write the emulator's frame log (JSON lines)")
    demo.add_argument("--no-demo", action="store_true", help="run the project without the demo driver")
    demo.add_argument("--virtual-clock", action="store_true", help="demo on the virtual clock (default: real time)")
    run.add_argument("--hmi", metavar="[HOST:]PORT",
                     help="serve the project's HMI pages (stvm.toml [hmi], docs/hmi.md) while the VM runs; "
                          "host 127.0.0.1 unless given, any other host needs the token printed at start-up")
    add_project_options(run)
    run.set_defaults(func=cmd_run)
    _register_extensions(sub, command in _CORE_COMMANDS)
    return parser


def _register_extensions(sub, core_only: bool = False) -> None:
    """Commands living in their own modules (trace, debug, lint, lsp) register themselves here.
    (The demo is `stvm run` on a project with a `[demo]` table: it has no command of its own.)"""
    if core_only:
        return
    for module_name in ("stvm.trace.cli", "stvm.debug.cli", "stvm.lint.cli", "stvm.lsp.cli",
                        "stvm.testrunner.cli"):
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name and module_name.startswith(exc.name):
                continue
            raise
        module.register(sub)


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:
        # Ctrl-C before the run started (imports, loading): nothing ran, nothing to print
        print("stvm: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


def program() -> int:
    """The `stvm` program (its console script, `python -m stvm`): `main`, then the process ends.

    The process is about to exit, so the loaded project's millions of objects are moved out of
    the collector's reach (`gc.freeze`): the collections of interpreter shutdown over that heap,
    and the freeing of its cycles one object at a time, cost 0.6 s of a 100,000-line program's
    `stvm run` (bench/bench_large.py); the system reclaims the memory at once. Exit handlers,
    `finally` blocks and the flushing of sys.stdout/stderr run as before; the files a command
    writes are closed when it returns (the emulator's frame log and the DAP log, open for a
    whole run, flush every line). Not in `main`, which tests and tools call in-process."""
    code = main()
    gc.freeze()
    try:
        sys.stdout.flush()
    except OSError as exc:   # stdout on a full device (/dev/full): an error, not "Exception ignored"
        _quiet_stdout()
        print(f"stvm: error: cannot write the output: {exc.strerror or exc}", file=sys.stderr)
        return code or EXIT_COMPILE
    except ValueError:   # the command closed stdout itself (the language server at the end of its session)
        pass
    return code


def _quiet_stdout() -> None:
    """Point stdout at /dev/null, so the flush at exit does not fail again on what is left."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass


def _show_cache_warnings() -> None:
    """A cache that cannot be used safely is one `stvm: warning:` line, not a Python warning."""
    from stvm.cache import CacheWarning   # lazy: start-up
    shown = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, CacheWarning):
            print(f"stvm: warning: {message}", file=sys.stderr)
        else:
            shown(message, category, filename, lineno, file, line)
    warnings.showwarning = show


def _main(argv: list[str] | None) -> int:
    from stvm.diagnostics import printable   # lazy: start-up
    _show_cache_warnings()
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv[0] if argv else None)
    try:
        args = _parse(parser, argv)
    except UsageError as exc:
        print(f"stvm: error: {printable(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
    if not getattr(args, "func", None):
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        return _dispatch(args)
    except UsageError as exc:
        print(f"stvm: error: {printable(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        return EXIT_OK
    except KeyboardInterrupt:
        # Ctrl-C before the run started (while loading): nothing ran, nothing to print
        print("stvm: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        print("stvm: error: out of memory", file=sys.stderr)
        return EXIT_COMPILE
    except OSError as exc:   # the system refused (a full disk or stdout, a name too long): not a bug
        _quiet_stdout()
        name = f": {printable(str(exc.filename))[:80]}" if exc.filename else ""
        print(f"stvm: error: {exc.strerror or exc}{name}", file=sys.stderr)
        return EXIT_COMPILE
    except Exception as exc:   # a bug in stvm: one line, not a traceback (STVM_TRACEBACK=1 shows it)
        if os.environ.get("STVM_TRACEBACK"):
            raise
        print(f"stvm: internal error: {type(exc).__name__}: {printable(str(exc))} "
              f"(a bug in stvm; STVM_TRACEBACK=1 shows where)", file=sys.stderr)
        return EXIT_INTERNAL


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> argparse.Namespace:
    """The command line; for `stvm run`, also the short flag the project's manifest declares for
    its demo's cycle count (`[demo] cycles_flag = "--pnp-cycles"`), which only that project has."""
    args, extra = parser.parse_known_args(argv)
    if not extra or getattr(args, "command", None) != "run":
        return parser.parse_args(argv)             # argparse reports what it does not know
    flag, value, rest = _take_declared_flag(parser, argv, extra)
    if flag is None:
        return parser.parse_args(argv)
    args = parser.parse_args(rest)
    try:
        count = int(value)
    except ValueError:
        raise UsageError(f"{flag} needs a number of cycles, got {value!r}") from None
    if count < 0:
        raise UsageError(f"{flag} must be >= 0 (0: no limit), got {count}")
    args.demo_cycles, args.demo_cycles_flag = count, flag
    return args


def _take_declared_flag(parser, argv: list[str], extra: list[str]):
    """(flag, value, argv without it) when `extra` holds the flag the manifest of the run's files
    declares, else (None, None, argv)."""
    unknown = [word.split("=", 1)[0] for word in extra if word.startswith("--")]
    # the files, once each unknown option and the value after it are left out
    cleaned, skip = [], False
    for word in argv:
        if skip:
            skip = False
            continue
        if word.split("=", 1)[0] in unknown:
            skip = "=" not in word
            continue
        cleaned.append(word)
    try:
        files = parser.parse_known_args(cleaned)[0].files
        declared = demo_cycles_flag(files)
    except SystemExit:
        return None, None, argv
    if not isinstance(declared, str) or declared not in unknown:
        return None, None, argv
    rest, value, i = [], None, 0
    while i < len(argv):
        word = argv[i]
        if word == declared and value is None and i + 1 < len(argv):
            value, i = argv[i + 1], i + 2
            continue
        if word.startswith(declared + "=") and value is None:
            value, i = word.split("=", 1)[1], i + 1
            continue
        rest.append(word)
        i += 1
    if value is None:
        raise UsageError(f"{declared} needs a number of cycles")
    return declared, value, rest


def _dispatch(args) -> int:
    """Run the command; errors that name a bad input become usage (2) or source (1) errors."""
    from stvm.manifest import ManifestError   # lazy: start-up
    from stvm.project import LoadError   # lazy: start-up
    try:
        return args.func(args)
    except ManifestError as exc:
        raise UsageError(str(exc)) from exc
    except LoadError as exc:   # nothing to load (an empty folder) or unreadable sources
        print_diagnostics(exc.diagnostics, exc.sources)
        return EXIT_COMPILE


if __name__ == "__main__":
    raise SystemExit(main())
