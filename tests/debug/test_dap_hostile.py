"""`stvm dap` against hostile or careless requests (issue 34 item 11): each gets a short error
response under its own request_seq, and the session goes on."""

from __future__ import annotations

import pytest

from core_helpers import write_st
from dap_client import DapClient

PROGRAM = "PROGRAM Main\nVAR x : INT; END_VAR\nx := x + 1;\nEND_PROGRAM\n"


@pytest.fixture
def dap():
    client = DapClient()
    yield client
    assert client.close() == 0


def _launched(dap: DapClient) -> None:
    prog = write_st(PROGRAM, "dap_hostile.st")
    dap.launch(str(prog), stopOnEntry=True)
    dap.stopped()


def test_integer_scan_is_refused_with_a_clear_message(dap) -> None:
    prog = write_st(PROGRAM, "dap_hostile.st")
    dap.body("initialize", adapterID="stvm")
    failed = dap.request("launch", ok=False, program=str(prog), scan=5)
    assert not failed["success"]
    assert "\"scan\" must be a duration in a string" in failed["message"]
    assert "internal error" not in failed["message"]


def test_second_launch_is_refused_and_the_first_session_goes_on(dap) -> None:
    _launched(dap)
    prog = write_st(PROGRAM, "dap_hostile.st")
    second = dap.request("launch", ok=False, program=str(prog))
    assert not second["success"] and "already launched" in second["message"]
    assert dap.evaluate("Main.x + 1")["result"] == "1"


HOSTILE = {
    "20,000-term chain": "+".join(["Main.x"] * 20_000),
    "2,000-term chain": "Main.x" + "+1" * 2000,
    "4,000 unary minus": "-" * 4000 + "Main.x",
    "1,000 NOT": "NOT " * 1000 + "TRUE",
    "800 nested calls": "ABS(" * 800 + "Main.x" + ")" * 800,
    "1,000 indexes": "Main.x" + "[0]" * 1000,
}


@pytest.mark.parametrize("expression", list(HOSTILE.values()), ids=list(HOSTILE))
def test_huge_or_deep_expression_gets_a_short_error(dap, expression: str) -> None:
    _launched(dap)
    for context in ("watch", "repl", "hover"):
        failed = dap.request("evaluate", ok=False, expression=expression, context=context)
        assert not failed["success"]
        message = failed["message"]
        assert len(message) < 300, message[:300]
        assert "stvm bug" not in message and "internal error" not in message
        assert "nested" in message or "characters long" in message
    assert dap.evaluate("Main.x + 1")["result"] == "1"


@pytest.mark.parametrize("request_body", [
    {"seq": 41, "type": "request", "command": 5},
    {"seq": 42, "type": "request", "command": "evaluate", "arguments": "x"},
    {"seq": 43, "type": "request", "command": ["launch"]},
])
def test_malformed_request_is_answered_under_its_own_seq(dap, request_body: dict) -> None:
    dap.body("initialize", adapterID="stvm")
    dap._send(request_body)
    seq = request_body["seq"]
    while seq not in dap.responses:
        assert dap._pump(30), "no response"
    response = dap.responses.pop(seq)
    assert response["request_seq"] == seq and not response["success"]
    assert "a request needs" in response["message"]


def test_too_many_breakpoints_in_one_file_is_an_error_and_the_session_goes_on(dap) -> None:
    _launched(dap)
    prog = write_st(PROGRAM, "dap_hostile.st")
    specs = [{"line": 3, "condition": f"Main.x = {i}"} for i in range(1001)]
    failed = dap.request("setBreakpoints", ok=False, source={"path": str(prog)}, breakpoints=specs)
    assert not failed["success"] and "the limit is 1000" in failed["message"]
    assert dap.evaluate("Main.x + 1")["result"] == "1"
