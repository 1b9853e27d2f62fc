"""`stvm test PATH... [--library NAME=DIR]... [--junit FILE] [--timeout 120s] [-k PATTERN]`.

Runs a TcUnit test project (stvm/testrunner/runner.py) and prints, on stdout, every message
TcUnit sends through ADSLOGSTR as one line (`error: …`, `warning: …`, `hint: …` after the message
type of its control mask), then a one-line summary. Exit codes (docs/unit_tests.md):

    0  every selected test passed (skipped ones count as passed)
    1  a test failed, a suite did not finish within the timeout, or the project has compile errors
    2  usage: a bad option, a missing file or library folder, no test framework, no test suite
    3  a runtime fault in the ST code (its FILE:LINE:COL on stderr)
"""

from __future__ import annotations

import fnmatch
import sys
from pathlib import Path

from stvm.cli_support import (EXIT_COMPILE, EXIT_FAULT, EXIT_OK, EXIT_USAGE, UsageError, add_project_options,
                              compile_errors, print_diagnostics, resolve_project)

EXIT_FAILED = 1


def register(sub) -> None:
    p = sub.add_parser("test", help="run TcUnit test suites (unit tests in ST) on the virtual clock")
    p.add_argument("files", nargs="+", metavar="PATH", help="the test project: a folder, its files or a .plcproj")
    p.add_argument("--junit", metavar="FILE", help="write the xUnit XML that TcUnit's FB_xUnitXmlPublisher produces")
    p.add_argument("--timeout", metavar="TIME",
                   help="virtual time the suites may take, e.g. 120s (default: stvm.toml [test] timeout, else 120s)")
    p.add_argument("-k", dest="select", metavar="PATTERN",
                   help="report and judge only the tests whose SUITE::TEST contains PATTERN (or matches it as a "
                        "glob with * ? [ ]); TcUnit still runs every suite")
    p.add_argument("--scan", metavar="TIME", help="the task period (default: stvm.toml [test] scan, else 10ms)")
    p.add_argument("--framework", metavar="NAME",
                   help="the test framework library (default: stvm.toml [test] library, else TcUnit or CfUnit)")
    p.add_argument("--watchdog", type=float, default=5.0, metavar="SECONDS",
                   help="fault when one scan runs longer than this wall-clock time (default 5)")
    p.add_argument("--no-cache", action="store_true", help="do not use the compile cache")
    add_project_options(p)
    p.set_defaults(func=cmd_test)


def selected(test_id: str, pattern: str | None) -> bool:
    """Whether `SUITE::TEST` is selected by `-k PATTERN`: a glob when PATTERN has * ? or [,
    else a substring; both without regard to case (TcUnit's names are ST names)."""
    if not pattern:
        return True
    text, pattern = test_id.lower(), pattern.lower()
    if any(c in pattern for c in "*?["):
        return fnmatch.fnmatchcase(text, pattern)
    return pattern in text


def cmd_test(args) -> int:
    from stvm.project import LoadError, parse_duration   # lazy: start-up
    from stvm.testrunner.runner import TestRunError, default_dialect, run_tests   # lazy: start-up
    spec = resolve_project(args)
    if args.dialect is None:
        spec = default_dialect(spec)
    try:
        timeout_ns = parse_duration(args.timeout) if args.timeout else None
        if args.scan:
            parse_duration(args.scan)
    except ValueError as exc:
        raise UsageError(str(exc)) from None
    if timeout_ns is not None and timeout_ns <= 0:
        raise UsageError("--timeout must be positive")
    if args.junit and Path(args.junit).is_dir():
        raise UsageError(f"--junit {args.junit}: is a folder (give a file name)")
    pattern = args.select
    out = sys.stdout

    def show(word: str, text: str) -> None:
        from stvm.diagnostics import printable   # lazy: start-up
        if pattern and not _message_selected(text, pattern):
            return
        out.write(f"{word}: {printable(text)}\n")

    try:
        run = run_tests(spec, library=args.framework, scan=args.scan, timeout_ns=timeout_ns,
                        junit=bool(args.junit), on_message=show, watchdog_s=args.watchdog)
    except TestRunError as exc:
        raise UsageError(str(exc)) from None
    except LoadError as exc:
        return compile_errors(exc.diagnostics, exc.sources)
    except ValueError as exc:   # a bad [test] scan/timeout in the manifest
        raise UsageError(str(exc)) from None
    print_diagnostics(run.project_warnings, run.sources)
    out.flush()
    return report(run, pattern, args.junit)


def _message_selected(text: str, pattern: str) -> bool:
    """A FAILED TEST line of a test -k leaves out is not shown; every other message is."""
    from stvm.testrunner.runner import FAILED_TEST   # lazy: start-up
    match = FAILED_TEST.match(text)
    return match is None or selected(f"{match['suite']}::{match['test']}", pattern)


def report(run, pattern: str | None, junit: str | None) -> int:
    """The summary line (stdout), the errors (stderr) and the exit code of a run."""
    tests = [t for t in run.tests if selected(t.id, pattern)]
    passed = sum(t.status == "passed" for t in tests)
    failed = [t for t in tests if t.status == "failed"]
    skipped = sum(t.status == "skipped" for t in tests)
    unfinished = [t for t in tests if t.status == "unfinished"]
    suites = {t.suite for t in tests} if pattern else {s.name for s in run.suites}
    deselected = len(run.tests) - len(tests)
    parts = [f"{passed} passed"] + ([f"{len(failed)} failed"] if failed else []) + \
        ([f"{skipped} skipped"] if skipped else []) + ([f"{len(unfinished)} unfinished"] if unfinished else []) + \
        ([f"{deselected} deselected"] if deselected else [])
    print(f"stvm test: {len(suites)} suite(s), {len(tests)} test(s): {', '.join(parts)} "
          f"in {run.virtual_ns / 1e9:.3f} s of virtual time ({run.scans} scans, {run.wall_s:.2f} s wall)")
    for t in failed:
        print(f"FAILED {t.id}" + (f": {t.message}" if t.message else ""))
    sys.stdout.flush()
    if run.fault is not None:
        sys.stderr.write(run.fault.render(run.sources))
        where = f" in test {run.fault_test}" if run.fault_test else ""
        print(f"stvm: error: the tests stopped at a runtime fault{where}", file=sys.stderr)
        return EXIT_FAULT
    if run.timed_out:
        print(f"stvm: error: {timeout_message(run)}", file=sys.stderr)
        return EXIT_FAILED
    if not run.suites:
        print("stvm: error: no test suite ran: declare instances of FBs that EXTEND TcUnit.FB_TestSuite in a "
              "PROGRAM that calls TcUnit.RUN()", file=sys.stderr)
        return EXIT_USAGE
    if pattern and not tests:
        print(f"stvm: error: -k {pattern!r} selects none of the {len(run.tests)} test(s)", file=sys.stderr)
        return EXIT_USAGE
    if junit:
        if run.junit_xml is None:
            print("stvm: error: TcUnit wrote no xUnit file (its FB_xUnitXmlPublisher writes through the file "
                  "function blocks; see docs/unit_tests.md)", file=sys.stderr)
            return EXIT_FAILED
        try:
            Path(junit).write_bytes(run.junit_xml)
        except OSError as exc:
            print(f"stvm: error: cannot write {junit}: {exc.strerror or exc}", file=sys.stderr)
            return EXIT_USAGE
    return EXIT_FAILED if failed else EXIT_OK


def timeout_message(run) -> str:
    running = run.unfinished_suites()
    seconds = run.virtual_ns / 1e9
    if running:
        names = "; ".join(_running(s) for s in running)
        return (f"timeout: after {seconds:g} s of virtual time ({run.scans} scans) these suites had not "
                f"finished: {names}")
    return (f"timeout: after {seconds:g} s of virtual time ({run.scans} scans) every suite had finished but "
            f"TcUnit had not finished reporting (its runner or its message queue); raise --timeout")


def _running(suite) -> str:
    waiting = [t.name for t in suite.tests if t.status == "unfinished"]
    if not suite.tests:
        return f"{suite.name} (no test started)"
    return f"{suite.name} (waiting for TEST_FINISHED in {', '.join(waiting)})" if waiting else suite.name


__all__ = ["register", "cmd_test", "selected", "EXIT_COMPILE"]
