"""An HTTP bridge between a browser editor and `stvm lsp` (stdio JSON-RPC), for the screenshots
of docs/editor.md (tools/editor_screens/shoot.py drives Monaco in Chromium through it).

The browser POSTs one JSON-RPC message to /lsp: a request (it has an `id`) is answered with the
server's response to it; a notification gets 204 at once. What the server sends on its own
(publishDiagnostics, workspace/inlayHint/refresh …) is kept and handed out by GET /events, and a
request the server makes of the client (workspace/configuration, …) is answered with a null
result, as a client without that capability would. Any other GET serves a file of `static`.
Only 127.0.0.1: this is a local tool, not a server for a network.
"""

from __future__ import annotations

import json
import mimetypes
import queue
import sys
import threading
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

from stvm.lsp.stdio_client import SharedClient

REQUEST_TIMEOUT = 60.0   # the first request waits for the whole project's check


def make_handler(server: SharedClient, static: Path | None, mounts: dict[str, Path]):
    class Handler(BaseHTTPRequestHandler):
        def log_message(self, *args) -> None:   # quiet: the screenshot run prints its own steps
            pass

        def _send(self, status: int, body: bytes = b"", kind: str = "application/json") -> None:
            self.send_response(status)
            self.send_header("Content-Type", kind)
            self.send_header("Content-Length", str(len(body)))
            self.end_headers()
            self.wfile.write(body)

        def do_POST(self) -> None:
            if self.path != "/lsp":
                return self._send(404)
            try:
                message = json.loads(self.rfile.read(int(self.headers.get("Content-Length", 0))))
                if not isinstance(message, dict) or not isinstance(message.get("method"), str):
                    raise ValueError("not a JSON-RPC request or notification")
            except ValueError as exc:
                return self._send(400, json.dumps({"jsonrpc": "2.0", "id": None, "error": {
                    "code": -32700, "message": f"parse error: {exc}"}}).encode())
            if "id" not in message:
                server.send(message)
                return self._send(204)
            try:
                answer = server.forward(message, timeout=REQUEST_TIMEOUT)
            except queue.Empty:
                answer = {"jsonrpc": "2.0", "id": message.get("id"), "error": {
                    "code": -32603, "message": f"no answer from stvm lsp in {REQUEST_TIMEOUT} s"}}
            self._send(200, json.dumps(answer).encode())

        def do_GET(self) -> None:
            if self.path == "/events":
                events = []
                while not server.unsolicited.empty():
                    events.append(server.unsolicited.get())
                return self._send(200, json.dumps(events).encode())
            for prefix, root in [*mounts.items(), ("/", static)]:
                if root is None or not self.path.startswith(prefix):
                    continue
                path = (root / self.path[len(prefix):].split("?")[0].lstrip("/")).resolve()
                if path.is_relative_to(root.resolve()) and path.is_file():
                    kind = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
                    return self._send(200, path.read_bytes(), kind)
            self._send(404)

    return Handler


def start(command: list[str] | None = None, static: Path | None = None,
          mounts: dict[str, Path] | None = None, cwd: Path | None = None):
    """Start `stvm lsp` and the HTTP bridge on a free port of 127.0.0.1 (a thread);
    returns (http server, stdio server). Stop with `stop(...)`."""
    lsp = SharedClient(command or [sys.executable, "-m", "stvm", "lsp"], cwd=cwd, timeout=REQUEST_TIMEOUT)
    http = ThreadingHTTPServer(("127.0.0.1", 0), make_handler(lsp, static, mounts or {}))
    threading.Thread(target=http.serve_forever, daemon=True).start()
    return http, lsp


def stop(http: ThreadingHTTPServer, lsp: SharedClient) -> None:
    http.shutdown()
    http.server_close()
    lsp.close()
