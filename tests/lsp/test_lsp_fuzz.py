"""`stvm lsp` under malformed and random JSON-RPC (issue 34): messages drawn by hypothesis
(fixed seed, bounded) are sent over stdio to one server; each gets the JSON-RPC answer the
specification asks for, the server answers a real request after every one, and nothing it
writes to stderr is a traceback. The client is stvm/lsp/stdio_client.py: raw frames, no client
library."""

from __future__ import annotations

import json

import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from lsp_helpers import FIXTURES, ROOT, position
from stvm.lsp.stdio_client import StdioClient

MAIN = (FIXTURES / "oo" / "main.st").resolve()
PARSE_ERROR, INVALID_REQUEST, METHOD_NOT_FOUND, INVALID_PARAMS, INTERNAL_ERROR = -32700, -32600, -32601, -32602, -32603
REQUEST_FAILED = -32803
TIMEOUT = 120       # seconds for one answer (the machine may be loaded)
LIFECYCLE = ("initialize", "initialized", "shutdown", "exit")   # not fuzzed: they end or restart the session

REQUESTS = ["textDocument/hover", "textDocument/definition", "textDocument/declaration", "textDocument/typeDefinition",
            "textDocument/implementation", "textDocument/references", "textDocument/documentHighlight",
            "textDocument/documentSymbol", "textDocument/completion", "textDocument/signatureHelp",
            "textDocument/prepareRename", "textDocument/rename", "textDocument/semanticTokens/full",
            "textDocument/foldingRange", "textDocument/inlayHint", "workspace/symbol", "workspace/executeCommand",
            "stvm/noSuchMethod", "textdocument/hover", ""]
NOTIFICATIONS = ["textDocument/didChange", "textDocument/didClose", "textDocument/didSave", "$/cancelRequest",
                 "$/setTrace", "workspace/didChangeConfiguration", "stvm/noSuchNotification"]

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2**40, 2**40) | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=12),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=10), inner, max_size=4),
    max_leaves=12)
positions = st.fixed_dictionaries({"line": st.integers(-5, 2**33), "character": st.integers(-5, 2**33)})


class Server(StdioClient):
    """`stvm lsp` over stdio: raw frames in, every message out on a queue, stderr kept."""

    def __init__(self) -> None:
        super().__init__(cwd=ROOT, timeout=TIMEOUT, capture_stderr=True, first_id=1000)

    def answers_hover(self) -> list[dict]:
        """A real hover (the server still serves); the messages that came before its answer."""
        msg_id = self.fresh_id()
        at = position(MAIN, "axis :")
        self.send({"jsonrpc": "2.0", "id": msg_id, "method": "textDocument/hover",
                   "params": {"textDocument": {"uri": MAIN.as_uri()}, "position": {"line": at.line, "character": at.character}}})
        got = self.until(lambda m: m.get("id") == msg_id and "method" not in m)
        assert "FB_Axis" in got[-1]["result"]["contents"]["value"], got[-1]
        return got[:-1]


@pytest.fixture(scope="module")
def server():
    srv = Server()
    reply = srv.request("initialize", {"processId": None, "rootUri": MAIN.parent.as_uri(), "capabilities": {}})
    assert "capabilities" in reply["result"]
    srv.send({"jsonrpc": "2.0", "method": "initialized", "params": {}})
    srv.send({"jsonrpc": "2.0", "method": "textDocument/didOpen", "params": {"textDocument": {
        "uri": MAIN.as_uri(), "languageId": "structured-text", "version": 1, "text": MAIN.read_text(encoding="utf-8")}}})
    srv.answers_hover()
    yield srv
    stderr = srv.close()
    assert "Traceback" not in stderr, stderr
    assert srv.proc.returncode == 0


def errors(messages: list[dict]) -> list[tuple]:
    return [(m.get("id", "absent"), m["error"]["code"]) for m in messages if "error" in m]


FUZZ = settings(max_examples=60, deadline=None, database=None, derandomize=True,
                suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@seed(20261207)
@FUZZ
@given(body=st.binary(min_size=1, max_size=60))
def test_a_body_that_is_not_json_gets_a_parse_error(server, body):
    try:
        value = json.loads(body)
    except ValueError:
        value = ...
    server.frame(body)
    before = server.answers_hover()
    if value is ...:
        assert errors(before) == [(None, PARSE_ERROR)]
    elif not isinstance(value, dict):
        assert errors(before) == [(None, INVALID_REQUEST)]


@seed(20261207)
@FUZZ
@given(value=json_values)
def test_json_that_is_no_message_gets_invalid_request(server, value):
    if isinstance(value, dict) and "jsonrpc" in value:
        value = dict(value, jsonrpc=1)
    server.send(value)
    before = server.answers_hover()
    msg_id = value.get("id") if isinstance(value, dict) else None
    msg_id = msg_id if isinstance(msg_id, (int, str)) and not isinstance(msg_id, bool) else None
    assert errors(before) == [(msg_id, INVALID_REQUEST)]


@seed(20261207)
@FUZZ
@given(method=st.sampled_from(REQUESTS) | st.text(max_size=20).filter(lambda m: m not in LIFECYCLE), params=json_values,
       msg_id=st.integers(1, 2**31) | st.text(min_size=1, max_size=8))
def test_a_request_with_random_params_gets_its_answer(server, method, params, msg_id):
    server.send({"jsonrpc": "2.0", "id": msg_id, "method": method, "params": params})
    before = server.answers_hover()
    mine = [m for m in before if m.get("id") == msg_id and "method" not in m]
    if not mine:    # an async handler (inlayHint) may answer after the hover
        mine = server.until(lambda m: m.get("id") == msg_id and "method" not in m)[-1:]
    [answer] = mine
    if "error" in answer:
        assert answer["error"]["code"] in (METHOD_NOT_FOUND, INVALID_PARAMS, REQUEST_FAILED), answer
        if method not in REQUESTS[:-3]:
            assert answer["error"]["code"] == METHOD_NOT_FOUND
    else:
        assert "result" in answer and method in REQUESTS


@seed(20261207)
@FUZZ
@given(method=st.sampled_from(REQUESTS[:16]), at=positions, name=st.text(max_size=12))
def test_well_formed_requests_at_random_positions(server, method, at, name):
    params = {"textDocument": {"uri": MAIN.as_uri()}, "position": at, "newName": name, "query": name,
              "context": {"includeDeclaration": True},
              "range": {"start": at, "end": at}}
    answer = server.request(method, params)
    out_of_range = not all(0 <= v < 2**31 for v in at.values())
    if "error" in answer:
        assert answer["error"]["code"] in ((INVALID_PARAMS,) if out_of_range else (INVALID_PARAMS, REQUEST_FAILED)), answer
    else:
        assert not out_of_range or method == "workspace/symbol" or method.endswith(("documentSymbol", "semanticTokens/full",
                                                                                   "foldingRange"))
    server.answers_hover()


@seed(20261207)
@FUZZ
@given(method=st.sampled_from(NOTIFICATIONS) | st.text(max_size=20).filter(lambda m: m not in LIFECYCLE), params=json_values)
def test_a_notification_with_random_params_gets_no_answer(server, method, params):
    server.send({"jsonrpc": "2.0", "method": method, "params": params})
    before = server.answers_hover()
    assert errors(before) == []


def test_framing_faults_then_a_request(server):
    for junk in (b"X-Junk: 1\r\n", b"Content-Length: abc\r\n\r\n", b"\r\n", b"Content-Type: x\r\n"):
        server.proc.stdin.write(junk)
    server.proc.stdin.flush()
    server.answers_hover()
    # a message whose id is no number or string; one of JSON-RPC 1.0; a response nobody asked for
    for message, expected in (({"jsonrpc": "2.0", "id": [1], "method": "textDocument/hover"}, [(None, INVALID_REQUEST)]),
                              ({"jsonrpc": "1.0", "id": 7, "method": "textDocument/hover"}, [(7, INVALID_REQUEST)]),
                              ({"jsonrpc": "2.0", "id": 8, "result": None}, []),
                              ({"jsonrpc": "2.0", "id": 9, "method": "no/such"}, [(9, METHOD_NOT_FOUND)])):
        server.send(message)
        assert errors(server.answers_hover()) == expected
