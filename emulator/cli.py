"""``tm-emulator``: run the emulated TM robot on a TCP port.

Prints ``tm-emulator listening on HOST:PORT`` once bound (``--port 0`` picks a free port), then
shows a live view (rich) when stdout is a terminal, until Ctrl-C.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from typing import Any, Sequence

from .faults import parse_faults
from .settings import DEFAULT_SETTINGS, parse_setting_assignment
from .terminal_text import plain, printable
from .transport import MAX_CONNECTIONS, TcpServer


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs a TCP port number 0-65535, got {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"needs a TCP port number 0-65535 (0: any free port), got {port}")
    return port


def _host(text: str) -> str:
    # socket.bind(("", port)) listens on every interface: an empty --host (an unset shell
    # variable) must not open the robot to the network without a word (issue 34 item 8)
    if not text.strip():
        raise argparse.ArgumentTypeError("needs an address to listen on (127.0.0.1 for this machine only; "
                                         "0.0.0.0 for every interface)")
    return text


WILDCARD_HOSTS = ("0.0.0.0",)


def _count(text: str) -> int:
    if not text.isdigit() or len(text) > 6 or int(text) < 1:
        raise argparse.ArgumentTypeError(f"needs a number 1-999999, got {text!r}")
    return int(text)


def _seconds(text: str) -> float:
    import math
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"needs seconds, got {text!r}") from None
    if not math.isfinite(value) or value < 0:
        raise argparse.ArgumentTypeError(f"needs seconds >= 0, got {text!r}")
    return value


def check_log_path(path: str) -> str | None:
    """Why frames cannot be logged to `path` (None if they can): checked before the socket is
    bound, so an unwritable log is not reported as a socket error."""
    import os
    try:
        with open(path, "a", encoding="utf-8"):
            pass
    except OSError as exc:
        return f"--log {path}: cannot write the frame log: {exc.strerror or exc}"
    if os.path.isdir(path):
        return f"--log {path}: is a folder"
    return None


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="tm-emulator",
        description="Emulated TM robot in Listen Node mode (TMSCT/TMSTA/CPERR on TCP).")
    parser.add_argument("--host", type=_host, default="127.0.0.1",
                        help="address to bind (default 127.0.0.1; 0.0.0.0 = every interface)")
    parser.add_argument("--port", type=_port, default=5890, help="TCP port 0-65535 (default 5890; 0 = any free)")
    parser.add_argument("--log", metavar="FILE", help="append every frame as a JSON line to FILE")
    parser.add_argument("--fault", action="append", default=[], metavar="NAME[:ARG]",
                        help="inject a fault (repeatable): refuse[:N], delay:MS, drop[:MS], corrupt[:N], "
                             "split[:N], error[:N], busy, tag_false, unsolicited:MS, stop:MS")
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", dest="settings",
                        help="change an EmulatorSettings field (repeatable), e.g. "
                             "--set accept_one_digit_checksum=true")
    parser.add_argument("--max-connections", type=_count, default=MAX_CONNECTIONS, metavar="N",
                        help=f"clients served at once; more are reset (default {MAX_CONNECTIONS})")
    parser.add_argument("--quiet", action="store_true", help="no live view, only the listening line")
    parser.add_argument("--duration", type=_seconds, default=None, help=argparse.SUPPRESS)  # tests
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        faults = parse_faults(args.fault)
        settings = DEFAULT_SETTINGS
        for assignment in args.settings:
            settings = parse_setting_assignment(assignment, settings)
    except ValueError as exc:
        print(f"tm-emulator: error: {exc}", file=sys.stderr)
        return 2
    if args.log:
        problem = check_log_path(args.log)
        if problem:
            print(f"tm-emulator: error: {problem}", file=sys.stderr)
            return 2
    try:
        server = TcpServer(args.host, args.port, settings, faults, args.log, args.max_connections).start()
    except OSError as exc:
        print(f"tm-emulator: cannot listen on {args.host}:{args.port}: {exc}", file=sys.stderr)
        return 1
    print(f"tm-emulator listening on {args.host}:{server.port}", flush=True)
    if args.host in WILDCARD_HOSTS:
        print(f"tm-emulator: warning: listening on every network interface (--host {args.host}): "
              f"anyone who can reach this machine can move the emulated robot", file=sys.stderr, flush=True)
    for line in faults.describe():
        print(f"  fault: {line}", flush=True)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    deadline = None if args.duration is None else time.monotonic() + args.duration
    try:
        if sys.stdout.isatty() and not args.quiet:
            _live_view(server, stop, deadline)
        else:
            while not stop.wait(0.2):
                if deadline is not None and time.monotonic() >= deadline:
                    break
                if server.error is not None:
                    break
    except KeyboardInterrupt:
        pass
    finally:
        server.stop()
    return 1 if server.error is not None else 0


def _render(snap: dict[str, Any]) -> Any:
    from rich.console import Group
    from rich.panel import Panel
    from rich.table import Table

    # Every cell is plain text with its control characters escaped: frame text, tags and the
    # event log come from clients (issue 34 item 6: no markup, no terminal escapes).
    state = Table.grid(padding=(0, 2))
    state.add_row("address", plain(snap["address"]), "time", f"{snap['t_s']:.1f} s")
    state.add_row("node", plain(snap["state"] + (" (paused)" if snap["paused"] else "")),
                  "connections", str(len(snap["connections"])))
    state.add_row("moving", str(snap["moving"]), "queue", f"{snap['queue_length']} items, "
                  f"{snap['scripts_buffered']} scripts")
    state.add_row("pose", " ".join(f"{v:8.2f}" for v in snap["pose"]), "base/tcp",
                  plain(f"{snap['base']} / {snap['tcp']}"))
    state.add_row("joints", " ".join(f"{v:8.2f}" for v in snap["joints"]), "tags",
                  plain(" ".join(f"{k}:{v}" for k, v in snap["tags"].items()) or "-"))
    frames = Table(show_header=True, header_style="bold", expand=True)
    frames.add_column("t (s)", width=10)
    frames.add_column("dir", width=3)
    frames.add_column("conn", width=4)
    frames.add_column("frame")
    for t_s, direction, text, conn in snap["recent_frames"]:
        frames.add_row(f"{t_s:.3f}", direction, str(conn), plain(text.replace("\r\n", "⏎").rstrip("⏎")))
    from rich.text import Text
    events = Text("\n".join(printable(line) for line in snap["log"]) or "-")
    return Group(Panel(state, title="tm-emulator"), Panel(frames, title=f"last frames (rx {snap['frames']['rx']}, "
                                                                         f"tx {snap['frames']['tx']})"),
                 Panel(events, title="events"))


def _live_view(server: TcpServer, stop: threading.Event, deadline: float | None) -> None:
    try:
        from rich.live import Live
    except ImportError:  # rich is optional: fall back to the quiet mode
        while not stop.wait(0.2):
            if deadline is not None and time.monotonic() >= deadline:
                return
        return
    with Live(_render(server.snapshot()), refresh_per_second=5, screen=False) as live:
        while not stop.wait(0.2):
            live.update(_render(server.snapshot()))
            if deadline is not None and time.monotonic() >= deadline:
                return


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
