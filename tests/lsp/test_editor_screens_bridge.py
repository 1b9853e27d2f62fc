"""tools/editor_screens/bridge.py, the HTTP bridge the docs' editor screenshots go through
(Monaco in Chromium ⇄ bridge ⇄ `stvm lsp`), without a browser: a JSON-RPC request POSTed to it
gets the real server's answer, a notification is forwarded, what the server publishes on its own
comes out of /events, and malformed input gets JSON-RPC's parse error."""

from __future__ import annotations

import importlib.util
import json
import time
import urllib.error
import urllib.request

from lsp_helpers import FIXTURES, ROOT

spec = importlib.util.spec_from_file_location("editor_screens_bridge", ROOT / "tools" / "editor_screens" / "bridge.py")
bridge = importlib.util.module_from_spec(spec)
spec.loader.exec_module(bridge)

MAIN = FIXTURES / "oo" / "main.st"


def post(port: int, message: dict | bytes):
    body = message if isinstance(message, bytes) else json.dumps(message).encode()
    request = urllib.request.Request(f"http://127.0.0.1:{port}/lsp", data=body, method="POST")
    try:
        with urllib.request.urlopen(request, timeout=90) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


def test_a_request_through_the_bridge_gets_the_servers_answer():
    http, lsp = bridge.start(cwd=ROOT)
    port = http.server_port
    try:
        status, body = post(port, {"jsonrpc": "2.0", "id": 1, "method": "initialize",
                                   "params": {"processId": None, "rootUri": None, "capabilities": {}}})
        assert status == 200
        answer = json.loads(body)
        assert answer["id"] == 1 and "hoverProvider" in answer["result"]["capabilities"]

        assert post(port, {"jsonrpc": "2.0", "method": "initialized", "params": {}})[0] == 204
        uri = MAIN.as_uri()
        text = MAIN.read_text(encoding="utf-8").replace("point.x", "point.z")   # one error, for /events
        assert post(port, {"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument": {
            "uri": uri, "languageId": "structured-text", "version": 1, "text": text}}})[0] == 204

        status, body = post(port, {"jsonrpc": "2.0", "id": "h", "method": "textDocument/hover", "params": {
            "textDocument": {"uri": uri}, "position": {"line": 13, "character": 2}}})
        hover = json.loads(body)
        assert status == 200 and hover["id"] == "h"
        assert "(VAR) Main.delay : TON" in hover["result"]["contents"]["value"]
        assert "waits before the lamp turns blue" in hover["result"]["contents"]["value"]

        diagnostics = []
        deadline = time.monotonic() + 60
        while not diagnostics and time.monotonic() < deadline:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/events", timeout=10) as response:
                events = json.loads(response.read())
            diagnostics = [d for e in events if e.get("method") == "textDocument/publishDiagnostics"
                           and e["params"]["uri"] == uri for d in e["params"]["diagnostics"]]
            time.sleep(0.2)
        assert any(d.get("code") == "E034" and "'z'" in d["message"] for d in diagnostics)

        status, body = post(port, b"{not json")
        assert status == 400 and json.loads(body)["error"]["code"] == -32700
        status, body = post(port, {"jsonrpc": "2.0", "id": 2, "method": "no/such/method"})
        assert status == 200 and json.loads(body)["error"]["code"] == -32601
    finally:
        bridge.stop(http, lsp)
    assert lsp.proc.returncode == 0
