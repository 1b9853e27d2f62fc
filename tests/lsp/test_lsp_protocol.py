"""The protocol's edges (issue 34 item 11, LSP half): requests with params that do not fit get a
JSON-RPC error and the server keeps serving; a `file://host/…` URI keeps its host; a URI with
`..` is answered under the URI the client used. Raw JSON-RPC over stdio, no client library
(stvm/lsp/stdio_client.py), so the malformed messages reach the server as sent."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import pytest

from stvm.lsp.server import path_of
from stvm.lsp.stdio_client import StdioClient

FIXTURE = Path(__file__).resolve().parent / "fixtures" / "oo"


@pytest.fixture
def client():
    c = StdioClient(capture_stderr=True)
    reply = c.request("initialize", {"processId": os.getpid(), "rootUri": None, "capabilities": {}})
    assert "hover" in json.dumps(reply["result"]["capabilities"]).lower()
    c.notify("initialized", {})
    yield c
    c.close()


@pytest.mark.parametrize("params", [
    {"textDocument": None, "position": {"line": 0, "character": 0}},
    {"textDocument": {"uri": "file:///x.st"}, "position": {"line": -1, "character": 2 ** 40}},
    {"textDocument": {"uri": "file:///x.st"}, "position": {"line": "zero", "character": 0}},
    {"textDocument": {"uri": "file:///x.st"}},
    [1, 2, 3],
    "hover",
])
def test_invalid_params_get_a_json_rpc_error_and_the_server_goes_on(client, params):
    reply = client.request("textDocument/hover", params)
    assert reply.get("error", {}).get("code") == -32602, reply
    assert "Traceback" not in json.dumps(reply)
    # still serving: a valid request on a real file answers
    main = (FIXTURE / "main.st").resolve()
    client.notify("textDocument/didOpen", {"textDocument": {"uri": main.as_uri(), "languageId": "structured-text",
                                                            "version": 1, "text": main.read_text()}})
    reply = client.request("textDocument/hover", {"textDocument": {"uri": main.as_uri()},
                                                  "position": {"line": 2, "character": 5}})
    assert "FB_Axis" in reply["result"]["contents"]["value"]


def test_a_uri_that_names_no_file_is_answered_with_null(client):
    # lsprotocol's converter takes 5 as the string "5": not a file: URI, so nothing to say
    reply = client.request("textDocument/hover", {"textDocument": {"uri": 5}, "position": {"line": 0, "character": 0}})
    assert reply["result"] is None


def test_invalid_notification_params_are_ignored_without_a_traceback(client):
    client.notify("textDocument/didOpen", {"textDocument": {"uri": 7}})
    client.notify("textDocument/didChange", {"textDocument": None, "contentChanges": "x"})
    reply = client.request("workspace/symbol", {"query": "FB"})
    assert "result" in reply
    stderr = client.close()
    assert "Traceback" not in stderr


def test_a_handler_refusal_is_an_lsp_request_failed_error(client):
    main = (FIXTURE / "main.st").resolve()
    client.notify("textDocument/didOpen", {"textDocument": {"uri": main.as_uri(), "languageId": "structured-text",
                                                            "version": 1, "text": main.read_text()}})
    reply = client.request("textDocument/rename", {"textDocument": {"uri": main.as_uri()},
                                                   "position": {"line": 4, "character": 13}, "newName": "X"})
    assert reply.get("error", {}).get("code") == -32803, reply
    assert "standard library" in reply["error"]["message"]


def test_uri_with_a_host_keeps_it():
    assert str(path_of("file://fileserver/share/a.st")) == "//fileserver/share/a.st"
    assert str(path_of("file:///home/a.st")) == "/home/a.st"
    assert str(path_of("file://localhost/home/a.st")) == "/home/a.st"
    assert path_of("untitled:Untitled-1") is None


def test_diagnostics_are_published_under_the_uri_the_client_used(client, tmp_path):
    folder = tmp_path / "proj" / "sub"
    folder.mkdir(parents=True)
    text = "PROGRAM P\nVAR x : INT; END_VAR\nx := y;\nEND_PROGRAM\n"
    (tmp_path / "proj" / "p.st").write_text(text)
    dotted = folder.as_uri() + "/../p.st"
    client.notify("textDocument/didOpen", {"textDocument": {"uri": dotted, "languageId": "structured-text",
                                                            "version": 1, "text": text}})
    uris = client.diagnostics_uris(until=dotted)
    assert (tmp_path / "proj" / "p.st").resolve().as_uri() not in uris
    # and requests on that URI are answered
    reply = client.request("textDocument/hover", {"textDocument": {"uri": dotted}, "position": {"line": 1, "character": 4}})
    assert "(VAR) P.x : INT" in reply["result"]["contents"]["value"]


def test_a_burst_of_edits_ends_with_the_verdict_of_the_last_text(client):
    # edits sent back to back: checks of text already replaced are not published after a
    # newer verdict (the edit cycle, stvm/lsp/server.py), and the last text's verdict stands
    main = (FIXTURE / "main.st").resolve()
    uri, text = main.as_uri(), main.read_text(encoding="utf-8")
    broken = text.replace("reading := drive.Position", "reading := drive.Positio")
    client.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "structured-text",
                                                            "version": 1, "text": text}})
    client.wait_diagnostics(uri)
    version = 1
    for body in [broken, text] * 3 + [broken]:
        version += 1
        client.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": version},
                                                 "contentChanges": [{"text": body}]})
    client.wait_diagnostics(uri, lambda d: any(x["severity"] == 1 for x in d))
    client.notify("textDocument/didChange", {"textDocument": {"uri": uri, "version": version + 1},
                                             "contentChanges": [{"text": text}]})
    client.wait_diagnostics(uri, lambda d: not any(x["severity"] == 1 for x in d))
    # the full check, index and lint that follow publish nothing older
    reply = client.request("workspace/executeCommand", {"command": "stvm.timings", "arguments": []})
    assert 2 <= len(reply["result"]) <= 8      # at most one publish per edit
    time.sleep(1.5)
    late = [m for _, m in list(client.messages.queue)
            if m.get("method") == "textDocument/publishDiagnostics" and m["params"]["uri"] == uri]
    assert not any(d["severity"] == 1 for m in late for d in m["params"]["diagnostics"])
