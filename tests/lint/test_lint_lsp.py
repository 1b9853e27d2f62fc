"""`stvm lsp` over stdio, as VS Code talks to it: LSP JSON-RPC with Content-Length framing
(stvm/lsp/stdio_client.py)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from lint_helpers import write_st
from stvm.lsp.stdio_client import StdioClient

BAD = """FUNCTION_BLOCK Probe
VAR_INPUT a, b : INT; END_VAR
VAR_OUTPUT y : INT; END_VAR
y := a / b;
END_FUNCTION_BLOCK
"""
GOOD = BAD.replace("y := a / b;", "IF b <> 0 THEN y := a / b; END_IF;")
BROKEN = BAD.replace("y := a / b;", "y := a / ;")


@pytest.fixture
def client():
    c = StdioClient()
    reply = c.request("initialize", {"processId": os.getpid(), "rootUri": None, "capabilities": {}})
    sync = reply["result"]["capabilities"]["textDocumentSync"]
    assert sync["openClose"] and sync["save"]["includeText"]
    c.notify("initialized", {})
    yield c
    c.close()


def test_open_save_publish_check_and_lint_diagnostics(client):
    path = write_st(BAD, "probe.st")
    uri = path.resolve().as_uri()
    client.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "structured-text",
                                                            "version": 1, "text": BAD}})
    diags = client.diagnostics(uri)
    assert [(d["code"], d["source"], d["severity"], d["range"]["start"]) for d in diags] == \
        [("SA204", "stvm-lint", 2, {"line": 3, "character": 9})]
    href = diags[0]["codeDescription"]["href"]
    assert href.endswith("docs/lint.md#sa204") or href == "stvm-rule:SA204"
    if href.startswith("file:"):
        assert Path(href[len("file://"):].split("#")[0]).exists()

    # saving the fixed text clears the finding (the unsaved buffer is what is linted)
    client.notify("textDocument/didSave", {"textDocument": {"uri": uri}, "text": GOOD})
    assert client.diagnostics(uri) == []

    # a syntax error comes from the checker, as an error
    client.notify("textDocument/didSave", {"textDocument": {"uri": uri}, "text": BROKEN})
    diags = client.diagnostics(uri)
    assert diags and all(d["source"] == "stvm" and d["severity"] == 1 for d in diags)
    assert diags[0]["range"]["start"]["line"] == 3


def test_non_st_documents_are_ignored_and_close_clears(client):
    path = write_st(BAD, "probe.st")
    uri = path.resolve().as_uri()
    other = path.with_suffix(".txt")
    other.write_text("hello")
    client.notify("textDocument/didOpen", {"textDocument": {"uri": other.as_uri(), "languageId": "plaintext",
                                                            "version": 1, "text": "hello"}})
    client.notify("textDocument/didOpen", {"textDocument": {"uri": uri, "languageId": "structured-text",
                                                            "version": 1, "text": BAD}})
    assert client.diagnostics(uri)           # the .st file answers first: the .txt was skipped
    client.notify("textDocument/didClose", {"textDocument": {"uri": uri}})
    assert client.diagnostics(uri) == []
