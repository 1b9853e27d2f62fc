"""`stvm trace`: record a lockstep run, write it, and compare it with a golden trace.

    stvm trace FILE... [--scan 1ms] [--cycles N] --watch PATTERN... [--scenario S] -o OUT
               [--compare GOLDEN] [--context K] [--latency-scans N] [--fault F] [--svg]

Exit codes: 0 ok (and equal to the golden), 1 compile errors, 2 usage, 3 runtime fault (without
--compare), 4 golden mismatch (the first divergence goes to stderr).
"""

from __future__ import annotations

import sys
from pathlib import Path

from stvm.cli_support import (EXIT_COMPILE, EXIT_FAULT, EXIT_MISMATCH, EXIT_OK, EXIT_USAGE,  # noqa: F401 (API)
                              UsageError, add_project_options, compile_errors, require_files, resolve_project,
                              usage)


def register(subparsers) -> None:
    trace = subparsers.add_parser(
        "trace", help="record a lockstep run (with the emulated robot) and compare it with a golden trace",
        description="Run ST programs in lockstep with the in-process TM emulator, record the watched "
                    "variables once per scan plus the robot's frames, write them by suffix "
                    "(.jsonl .csv .vcd .json), and optionally compare with a golden trace.")
    trace.add_argument("files", nargs="+", help="ST files (a file of a folder with stvm.toml loads that project)")
    trace.add_argument("--scan", default=None, help="default task period (default: the scenario's, else 1ms)")
    trace.add_argument("--cycles", type=int, default=None, help="scans to run (default: the scenario's, else 1000)")
    trace.add_argument("--watch", action="append", nargs="+", metavar="PATTERN", default=None,
                       help="variables to record: paths with globs (* one level, ** any depth); repeatable")
    trace.add_argument("--scenario", help="scenario TOML (inputs, events, faults, [record] watch)")
    trace.add_argument("-o", "--output", action="append", metavar="OUT",
                       help="trace file(s) to write: .jsonl .csv .vcd .json (WaveDrom), or .svg/.png: "
                            "a picture of the robot's TCP path (top and side view; needs matplotlib); repeatable")
    trace.add_argument("--compare", metavar="GOLDEN", help="golden trace (.jsonl or .csv) to compare with (exit 4 if different)")
    trace.add_argument("--context", type=int, default=3, metavar="K", help="scans shown before a divergence (default 3)")
    trace.add_argument("--latency-scans", type=int, default=None, metavar="N",
                       help="one-way robot latency in scans (default: the scenario's, else 1)")
    trace.add_argument("--fault", action="append", metavar="NAME[:ARG]", help="emulator fault from the start (as tm-emulator --fault)")
    trace.add_argument("--svg", action="store_true", help="also render the WaveDrom diagram as SVG (needs wavedrom)")
    trace.add_argument("--max-columns", type=int, default=120, metavar="N", help="WaveDrom: at most N change points (default 120)")
    trace.add_argument("--no-writer", action="store_true", help="on a mismatch, do not replay to find the ST line that wrote the value")
    trace.add_argument("--no-cache", action="store_true", help="do not use the compile cache")
    add_project_options(trace)
    trace.set_defaults(func=cmd_trace)


def cmd_trace(args) -> int:
    # lazy: start-up (`stvm.cli` imports this module on every call to register `stvm trace`)
    from stvm.trace.golden import compare, locate_writer, render_report
    from stvm.trace.run import TraceSpec, run_trace
    from stvm.trace.signals import WatchError
    from stvm.trace.writers import SUFFIXES, TraceFormatError, read_trace, write_trace
    from stvm.project import LoadError, load   # lazy: start-up
    from stvm.scenario import ScenarioError   # lazy: start-up

    try:
        require_files(args.files)
    except UsageError as exc:
        return usage(str(exc))
    outputs = args.output or []
    if not outputs and not args.compare:
        return usage("give -o OUT (.jsonl .csv .vcd .json .svg .png) and/or --compare GOLDEN")
    from stvm.trace.tcp_path import PICTURE_SUFFIXES   # lazy: start-up
    pictures = [o for o in outputs if Path(o).suffix.lower() in PICTURE_SUFFIXES]
    outputs = [o for o in outputs if o not in pictures]
    for out in outputs:
        if Path(out).suffix.lower() not in SUFFIXES:
            return usage(f"-o {out}: unknown trace format (use {', '.join(SUFFIXES + PICTURE_SUFFIXES)})")
    if pictures:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            return usage("-o .svg/.png draws the TCP path with matplotlib: pip install 'stvm[plot]'")
    if args.svg and not any(Path(o).suffix.lower() == ".json" for o in outputs):
        return usage("--svg renders the WaveDrom output: add -o NAME.json")
    if args.cycles is not None and args.cycles < 0:
        return usage("--cycles must be >= 0")
    if args.context < 0:
        return usage("--context must be >= 0")
    if args.latency_scans is not None and args.latency_scans < 0:
        return usage(f"--latency-scans must be >= 0, got {args.latency_scans}")
    if args.max_columns < 1:
        return usage(f"--max-columns must be >= 1, got {args.max_columns}")
    if args.scenario and not Path(args.scenario).exists():
        return usage(f"no such scenario: {args.scenario}")
    if args.compare and not Path(args.compare).exists():
        return usage(f"no such golden trace: {args.compare} (record one with -o {args.compare})")
    try:
        resolved = resolve_project(args)
        if args.scan is not None:
            from stvm.project import parse_duration   # lazy: start-up
            if parse_duration(args.scan) <= 0:
                return usage("--scan must be positive")
        from emulator import parse_faults   # lazy: start-up
        parse_faults(args.fault or [])
    except (ValueError, UsageError) as exc:
        return usage(str(exc))
    watch = [p for group in (args.watch or []) for p in group]
    spec = TraceSpec(files=args.files, scan=args.scan, cycles=args.cycles, watch=watch, scenario=args.scenario,
                     latency_scans=args.latency_scans, faults=args.fault or [],
                     settings_overrides=args.sysmac or [], use_cache=not args.no_cache,
                     record_tcp=bool(pictures), resolved=resolved)
    try:
        project = load(resolved)
    except LoadError as exc:
        return compile_errors(exc.diagnostics, exc.sources)
    try:
        run = run_trace(spec, project)
    except (WatchError, ScenarioError) as exc:
        return usage(str(exc))
    if run.fault is not None:
        sys.stderr.write(run.fault.render(project.sources))
    try:
        for out in outputs:
            for written in write_trace(run.trace, out, svg=args.svg and Path(out).suffix.lower() == ".json",
                                       max_columns=args.max_columns):
                print(f"wrote {written}", file=sys.stderr)
        for out in pictures:
            from stvm.trace.tcp_path import render_tcp_path   # lazy: start-up
            name = Path(str(args.scenario or args.files[0])).stem
            print(f"wrote {render_tcp_path(run.tcp_path, out, title=f'TCP path of {name}')}", file=sys.stderr)
    except TraceFormatError as exc:
        return usage(str(exc))
    except OSError as exc:
        return usage(f"cannot write trace: {exc}")
    if args.compare:
        try:
            golden = read_trace(args.compare)
        except TraceFormatError as exc:
            return usage(str(exc))
        divergence = compare(golden, run.trace)
        if divergence is None:
            print(f"trace matches {args.compare} ({run.trace.scans} scans)", file=sys.stderr)
            return EXIT_OK
        if not args.no_writer:
            divergence.writer = locate_writer(spec, run.trace, divergence, project)
        sys.stderr.write(render_report(divergence, golden, run.trace, args.context, args.compare))
        return EXIT_MISMATCH
    return EXIT_FAULT if run.fault is not None else EXIT_OK
