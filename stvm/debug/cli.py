"""`stvm debug` (interactive console) and `stvm dap` (Debug Adapter Protocol over stdio).

    stvm debug FILE... [--scan 1ms] [--scenario S] [--robot lockstep|emulator|HOST:PORT]
                       [--set NAME=VALUE] [-x COMMANDS] [--sysmac NAME=VALUE] [--dialect D] [--define N]
    stvm dap [--log FILE]

This module is imported by every `stvm` command (to register the subcommands), so it imports
nothing heavy at module level: the engine is loaded only when a debug command runs.

Exit codes: 0 ok, 1 compile errors, 2 usage error.
"""

from __future__ import annotations

import sys

from stvm.cli_support import (EXIT_COMPILE, EXIT_OK, EXIT_USAGE, UsageError,  # noqa: F401 (API)
                              add_project_options, compile_errors, error, print_diagnostics, require_files)
from stvm.source import SourceError, read_limited


def register(subparsers) -> None:
    debug = subparsers.add_parser(
        "debug", help="debug ST interactively: breakpoints, stepping, watch, set and force",
        description="Run ST programs under the debugger console (type help at the prompt).")
    debug.add_argument("files", nargs="+", help="ST files (a file of a folder with stvm.toml loads that project)")
    debug.add_argument("--scan", default=None, help="default task period (default: the scenario's, else 10ms)")
    debug.add_argument("--scenario", help="scenario TOML: initial values, timed events, robot address")
    debug.add_argument("--robot", metavar="lockstep|emulator|HOST:PORT",
                       help="the robot: in-process emulator on the VM clock (default with a scenario "
                            "[robot]), bundled TCP emulator, or a robot's address")
    debug.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                       help="set a variable before the first scan")
    debug.add_argument("-x", "--commands", metavar="FILE", help="run the debugger commands in FILE first")
    debug.add_argument("--realtime", action="store_true", help="sleep to each deadline (default: virtual clock)")
    add_project_options(debug)
    debug.add_argument("--hmi", metavar="[HOST:]PORT",
                       help="serve the project's HMI pages while debugging (values between scans, "
                            "writes at the next scan start; docs/hmi.md)")
    from stvm.opcua.cli import add_option   # lazy: start-up
    add_option(debug)
    debug.set_defaults(func=cmd_debug)

    dap = subparsers.add_parser(
        "dap", help="Debug Adapter Protocol server on stdin/stdout (for VS Code and other editors)",
        description="Serve one debug session over the Debug Adapter Protocol on stdin/stdout. "
                    "The launch request names the program; see docs/debugging.md.")
    dap.add_argument("--log", metavar="FILE", help="append every protocol message to FILE")
    dap.set_defaults(func=cmd_dap)


def cmd_debug(args) -> int:
    from stvm.debug.console import Console   # lazy: start-up
    from stvm.debug.session import SessionOptions, open_session   # lazy: start-up
    from stvm.project import LoadError   # lazy: start-up
    from stvm.scenario import ScenarioError   # lazy: start-up
    try:
        require_files(args.files)
    except UsageError as exc:
        return error(str(exc))
    commands: list[str] = []
    if args.commands:
        try:
            commands = read_limited(args.commands, "command file").decode("utf-8").splitlines()
        except OSError as exc:
            return error(f"cannot read {args.commands}: {exc.strerror or exc}")
        except SourceError as exc:
            return error(f"{args.commands}: {exc.message}")
        except UnicodeDecodeError:
            return error(f"{args.commands}: the command file is not UTF-8 text")
    options = SessionOptions(args.files, scan=args.scan, scenario=args.scenario, sets=args.set,
                             sysmac=args.sysmac or [], dialect=args.dialect, defines=args.define or [],
                             robot=args.robot, realtime=args.realtime)
    try:
        session = open_session(options)
    except LoadError as exc:
        return compile_errors(exc.diagnostics, exc.sources)
    except (ValueError, KeyError, ScenarioError) as exc:
        return error(str(exc))
    print_diagnostics(session.build.project.warnings, session.build.project.sources)
    if session.robot != "none":
        print(f"robot: {session.robot}" + (f" on port {session.server.port}" if session.server else ""))
    hmi = None
    opcua = None
    try:
        from stvm.opcua.cli import start_server   # lazy: start-up
        # the debugger is the run control: no Runtime.Scan/Pause/Resume beside it
        opcua = start_server(args, session.build.project, session.engine.vm, args.files, run_control=False)
    except (ValueError, RuntimeError) as exc:
        session.close()
        return error(str(exc))
    try:
        if getattr(args, "hmi", None):
            hmi = _start_hmi(args.hmi, session)
            if hmi is None:
                return EXIT_COMPILE
        return Console(session.engine).run(commands)
    except ValueError as exc:   # HmiUsageError
        return error(str(exc))
    finally:
        if hmi is not None:
            hmi.stop()
        if opcua is not None:
            opcua.stop()
        session.close()


def _start_hmi(address: str, session):
    """`--hmi`: the web HMI on the debugged VM; the robot view reads the session's emulator."""
    from stvm.hmi.cli import report_load_error, start_hmi   # lazy: start-up
    from stvm.hmi.pages import HmiLoadError   # lazy: start-up
    from stvm.hmi.robot import from_lockstep, from_tcp_server   # lazy: start-up
    pose = parameters = None
    if session.transport is not None:
        from stvm.lockstep import LOCKSTEP_HOST, LOCKSTEP_PORT   # lazy: start-up
        pose = from_lockstep(session.transport)
        parameters = {"robot_host": LOCKSTEP_HOST, "robot_port": LOCKSTEP_PORT}
    elif session.server is not None:
        pose = from_tcp_server(session.server)
        parameters = {"robot_host": "127.0.0.1", "robot_port": session.server.port}
    try:
        return start_hmi(session.build.project, session.engine.vm, address, pose=pose,
                         run_parameters=parameters, stream=sys.stdout)
    except HmiLoadError as exc:
        report_load_error(exc)
        return None


def cmd_dap(args) -> int:
    from stvm.debug.dap import serve   # lazy: start-up
    protocol_out = sys.stdout.buffer
    # stdout carries the protocol only: anything else printed during the session goes to stderr
    sys.stdout = sys.stderr
    try:
        return serve(sys.stdin.buffer, protocol_out, log_path=args.log)
    finally:
        sys.stdout = sys.__stdout__
