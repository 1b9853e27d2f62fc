"""`--hmi [HOST:]PORT` for `stvm run` and `stvm debug`: serve the project's HMI beside the run.

Errors follow the CLI contract: a malformed option, a project without pages or a port that cannot
be bound are usage errors (exit 2, `HmiUsageError`); mistakes inside the page files are reported
as `FILE:LINE:COL: error:` like ST diagnostics (exit 1, `HmiLoadError`).
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from stvm.hmi.pages import HmiLoadError
from stvm.frontend import VariableBridge
from stvm.hmi.pages import load_pages
from stvm.hmi.guard import ServerLimits
from stvm.hmi.server import HmiServer

HELP = ("serve the project's HMI pages (stvm.toml [hmi]) on [HOST:]PORT while the VM runs "
        "(default host 127.0.0.1; any other host needs the token printed at start-up)")


class HmiUsageError(ValueError):
    pass


def add_argument(parser) -> None:
    parser.add_argument("--hmi", metavar="[HOST:]PORT", help=HELP)


def parse_address(text: str) -> tuple[str, int]:
    """`8080` → ("127.0.0.1", 8080); `0.0.0.0:8080`, `[::1]:8080`; port 0 picks a free one."""
    text = text.strip()
    host, sep, port = text.rpartition(":")
    if not sep:
        host, port = "127.0.0.1", text
    host = host.strip("[]") or "127.0.0.1"
    if not port.isdigit() or len(port) > 5 or not 0 <= int(port) < 65536:   # (5,000 digits: exit 70)
        raise HmiUsageError(f"--hmi needs [HOST:]PORT (e.g. 8080 or 127.0.0.1:8080), got {text!r}")
    return host, int(port)


def page_files(project) -> tuple[list[Path], str | None]:
    """The page files the project's manifest lists (relative to the manifest's folder)."""
    table = (project.manifest or {}).get("hmi")
    if not isinstance(table, dict) or not table.get("pages"):
        raise HmiUsageError("this project has no HMI pages: list them in stvm.toml as "
                            "[hmi] pages = [\"hmi/Main.toml\", …] (docs/hmi.md)")
    pages = table["pages"]
    if not isinstance(pages, list) or not all(isinstance(p, str) for p in pages):
        raise HmiUsageError("stvm.toml: [hmi] pages must be a list of file names")
    root = project.root or Path(".")
    files = [root / p for p in pages]
    for f in files:
        if not f.exists():
            raise HmiUsageError(f"stvm.toml [hmi] pages: no such file: {f}")
    start = table.get("start")
    return files, start if isinstance(start, str) else None


def start_hmi(project, vm, address: str, pose=None, run_parameters: dict[str, Any] | None = None,
              stream=None):
    """Load the pages, attach a bridge to `vm` and start the server; prints the URL on `stream`.
    Raises HmiUsageError or HmiLoadError (nothing is started then)."""
    host, port = parse_address(address)
    files, start = page_files(project)
    table = (project.manifest or {}).get("hmi") or {}
    try:
        limits = ServerLimits.from_table(table.get("server"))
    except ValueError as exc:
        raise HmiUsageError(f"stvm.toml {exc}") from None
    from stvm.frontend.limits import LimitTable, LimitsError   # lazy: start-up (only a run with --hmi)
    try:
        limit_table = LimitTable.for_project(project, vm)
    except LimitsError as exc:
        raise HmiUsageError(str(exc)) from None
    bridge = VariableBridge(vm)
    hmi = load_pages(files, bridge.type_of, start)
    server = HmiServer(hmi, bridge, host=host, port=port, pose=pose, run_parameters=run_parameters,
                       limits=limits, limit_table=limit_table)
    try:
        server.start()
    except OSError as exc:
        raise HmiUsageError(f"--hmi {address}: cannot listen on {host}:{port}: {exc.strerror or exc}") from None
    stream = stream or sys.stderr
    urls = server.urls()
    print(f"HMI: {urls[0]}" + (f"  (token {server.token}: needed because {host} is not loopback)"
                               if server.token else ""), file=stream, flush=True)
    for other in urls[1:]:
        print(f"HMI: also {other}", file=stream, flush=True)
    return server


def report_load_error(exc: HmiLoadError) -> None:
    sys.stderr.write(exc.render())
    print(f"{len(exc.diagnostics)} error(s) in HMI pages", file=sys.stderr)
