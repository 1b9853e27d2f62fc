"""`--opcua [opc.tcp://HOST:PORT]` for `stvm run` and `stvm debug`: the option and its start-up."""

from __future__ import annotations

import sys

OPTION_HELP = ("serve the variables over OPC UA (default endpoint: the manifest's [opcua] endpoint, "
               "else opc.tcp://127.0.0.1:4840; see README)")


def add_option(parser) -> None:
    parser.add_argument("--opcua", nargs="?", const="", default=None, metavar="opc.tcp://HOST:PORT",
                        help=OPTION_HELP)


def start_server(args, project, vm, files, run_control: bool = True):
    """The started server when `--opcua` was given, else None. Raises ValueError (a usage error)
    for a bad URL or `[opcua]` table and RuntimeError when the endpoint cannot be served."""
    if getattr(args, "opcua", None) is None:
        return None
    from stvm.opcua.config import load_config   # lazy: start-up (every run builds this option)
    config = load_config(project.manifest, project.root, files, args.opcua or None)
    try:
        from stvm.opcua.server import OpcUaServer   # lazy: start-up (asyncua)
    except ModuleNotFoundError as exc:
        raise RuntimeError(f"--opcua needs the asyncua package ({exc.name} is missing): "
                           f"pip install 'stvm[opcua]'") from exc
    server = OpcUaServer(vm, config, run_control=run_control)
    url = server.start()
    steps = "; Runtime.Scan/Pause/Resume" if server.control is not None else ""
    paused = " (paused: call Runtime.Scan or Resume)" if config.start_paused and server.control else ""
    print(f"OPC UA server on {url}: namespace {config.namespace_uri} (ns={server.ns}), "
          f"{len(server.variables)} variables, {server.writable_count} writable{steps}{paused}",
          file=sys.stderr, flush=True)
    if config.start_paused and server.control is None:
        print("opcua: start = \"paused\" is ignored: stepping needs the virtual clock under stvm run",
              file=sys.stderr)
    for skipped in server.selection.skipped[:5]:
        print(f"opcua: not published (no OPC UA mapping): {skipped}", file=sys.stderr)
    return server
