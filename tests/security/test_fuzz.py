"""Fuzz tests of the doors issue 34 names (hypothesis, fixed seed, bounded here; `python
bench/bench_fuzz.py` runs them with many more examples through STVM_FUZZ_EXAMPLES):

* TMSCT frames and raw bytes against a running emulator over loopback: every frame is answered
  (OK, ERROR;<line>, CPERR) and a new client is served afterwards;
* DAP messages against the adapter: every request with an integer seq gets a response under
  that seq, no traceback, the adapter ends normally;
* values and variable paths: a result or a ValueError in ST terms, nothing else;
* vendor XML sources: `stvm check` ends with exit 0 or 1, never 70.
"""

from __future__ import annotations

import io
import json
import os
import socket

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from emulator import start_server
from emulator.framing import encode
from stvm.cli import main
from stvm.debug.dap import DapServer
from stvm.runtime.paths import PathSyntaxError, parse_path
from stvm.semantics import types as t
from stvm.semantics.literals import literal_value

EXAMPLES = int(os.environ.get("STVM_FUZZ_EXAMPLES", "40"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
QUERY = b"$TMSTA,2,00,*41\r\n"
IN_NODE = b"$TMSTA,15,00,true,Listen1,*79\r\n"


# ------------------------------------------------------------------ TMSCT against the emulator

_SCRIPT_ALPHABET = "()[]{}+-*/%,\"'0123456789.eExabcfinotruvs_ =!<>&|^~;\\"
_SCRIPT_PIECES = st.sampled_from(["(", ")", "[", "]", "{", "}", "abs(", "Ctrl(", "PTP(", "float ", "int ",
                                  "var_a", "=", "+", "-", "!", "1", "1.5e308", "0x" + "F" * 40, "\"s\"", ",",
                                  "QueueTag(1)", "\r\n", "9" * 450, "((((((((((", "]]]]]]]]"])
_SCRIPT = st.one_of(st.text(_SCRIPT_ALPHABET, max_size=300),
                    st.lists(_SCRIPT_PIECES, max_size=120).map("".join))


@pytest.fixture(scope="module")
def emulator():
    srv = start_server(port=0)
    yield srv
    srv.stop()


def _read_frame(sock: socket.socket) -> bytes:
    buf = b""
    while not buf.endswith(b"\r\n"):
        chunk = sock.recv(65536)
        if not chunk:
            raise ConnectionError("closed by the emulator")
        buf += chunk
    return buf


def _serves(srv) -> bool:
    with socket.create_connection(("127.0.0.1", srv.port), timeout=10) as sock:
        sock.sendall(QUERY)
        return _read_frame(sock) == IN_NODE


@FUZZ
@given(script=_SCRIPT)
def test_tmsct_frames_are_answered_and_the_emulator_keeps_serving(emulator, script: str) -> None:
    with socket.create_connection(("127.0.0.1", emulator.port), timeout=10) as sock:
        sock.sendall(encode("TMSCT", "1," + script))
        reply = _read_frame(sock)
    assert reply.startswith((b"$TMSCT,", b"$CPERR,")), reply[:80]
    assert emulator.error is None and emulator.handler_errors == 0
    assert _serves(emulator)


@FUZZ
@given(data=st.binary(max_size=2000))
def test_raw_bytes_never_stop_the_emulator(emulator, data: bytes) -> None:
    with socket.create_connection(("127.0.0.1", emulator.port), timeout=10) as sock:
        sock.sendall(data)
    assert emulator.error is None and emulator.handler_errors == 0
    assert _serves(emulator)


# ------------------------------------------------------------------ DAP messages

_COMMANDS = ["initialize", "launch", "setBreakpoints", "setExceptionBreakpoints", "configurationDone", "threads",
             "stackTrace", "scopes", "variables", "source", "continue", "next", "stepIn", "stepOut", "pause",
             "setVariable", "evaluate", "exceptionInfo", "terminate", "frobnicate", "__init__", ""]
_JSON = st.recursive(st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False) | st.text(max_size=30),
                     lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=10), inner, max_size=4),
                     max_leaves=12)
_ARGUMENTS = st.one_of(st.dictionaries(st.sampled_from(["program", "scan", "cycles", "expression", "frameId",
                                                        "variablesReference", "source", "breakpoints", "threadId",
                                                        "context", "name", "value", "sourceReference"]),
                                       _JSON, max_size=5), _JSON)
_REQUEST = st.fixed_dictionaries({"seq": st.one_of(st.integers(1, 10**6), _JSON), "type": st.just("request"),
                                  "command": st.one_of(st.sampled_from(_COMMANDS), _JSON),
                                  "arguments": _ARGUMENTS})


def _frame(message: dict) -> bytes:
    data = json.dumps(message).encode("utf-8")
    return b"Content-Length: %d\r\n\r\n" % len(data) + data


@FUZZ
@given(requests=st.lists(_REQUEST, min_size=1, max_size=6))
def test_dap_answers_every_request_under_its_seq(requests: list[dict]) -> None:
    for request in requests:   # never a real program: a launch may only name missing files
        if request.get("command") == "launch" and isinstance(request.get("arguments"), dict):
            request["arguments"]["program"] = "no_such_program_for_the_fuzz.st"
    stream = b"".join(_frame(r) for r in requests)
    out = io.BytesIO()
    server = DapServer(io.BytesIO(stream), out)
    assert server.serve() == 0
    answered: dict[int, dict] = {}
    data = out.getvalue()
    while data:
        head, _, rest = data.partition(b"\r\n\r\n")
        length = int(head.split(b":")[1])
        message = json.loads(rest[:length])
        data = rest[length:]
        if message["type"] == "response":
            answered[message["request_seq"]] = message
    text = out.getvalue().decode("utf-8")
    assert "Traceback" not in text and "internal error" not in text
    for request in requests:
        seq = request["seq"]
        if isinstance(seq, int) and not isinstance(seq, bool):
            assert seq in answered, request


# ------------------------------------------------------------------ values and paths

_PATH_TEXT = st.one_of(st.text("Mainxab_.[]0123456789,^ #-+16", max_size=40), st.text(max_size=40))
_TYPES = [t.ELEMENTARY[name] for name in ("BOOL", "INT", "DINT", "LREAL", "REAL", "TIME", "BYTE")] + [t.STRING]
_LITERAL_TEXT = st.one_of(
    st.text("0123456789_.eE+-#TtSsMmHhDd;' abcfFx", max_size=40),
    st.sampled_from(["TRUE", "FALSE", "BOOL#1", "INT#5", "16#FF", "2#1010", "T#1s", "LTIME#5d", "1__0", "1_0",
                     "1; DROP", "1.0E999", "REAL#abc", "'abc'", "\"w\"", "-0", "9" * 5000, "16#" + "F" * 3000]),
    st.text(max_size=30))


@FUZZ
@given(text=_PATH_TEXT)
def test_paths_are_tokens_or_a_path_error(text: str) -> None:
    try:
        tokens = parse_path(text)
    except PathSyntaxError as exc:
        assert "variable path" in str(exc)
        return
    assert tokens and tokens[0][0] == "name"


@FUZZ
@given(text=_LITERAL_TEXT, ty=st.sampled_from(_TYPES))
def test_literals_are_values_or_a_message_in_st_terms(text: str, ty) -> None:
    try:
        literal_value(text, ty)
    except ValueError as exc:
        message = str(exc)
        assert "could not convert" not in message and "invalid literal for int" not in message
        assert "Exceeds the limit" not in message


# ------------------------------------------------------------------ XML sources

_XML = ('<?xml version="1.0" encoding="utf-8"?>\n<TcPlcObject Version="1.1.0.1"><POU Name="Main">'
        '<Declaration><![CDATA[PROGRAM Main\nVAR x : INT; END_VAR]]></Declaration>'
        '<Implementation><ST><![CDATA[x := x + 1;]]></ST></Implementation></POU></TcPlcObject>\n')


@settings(max_examples=max(5, EXAMPLES // 4), derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(cut=st.integers(0, len(_XML)), insert=st.text(max_size=20), encoding=st.sampled_from(
    ["utf-8", "latin-1", "x-unknown", "utf-16", "", "ascii"]))
def test_xml_sources_check_with_exit_0_or_1(tmp_path_factory, capsys, cut: int, insert: str, encoding: str) -> None:
    folder = tmp_path_factory.mktemp("xml")
    text = _XML.replace('encoding="utf-8"', f'encoding="{encoding}"')
    text = text[:cut] + insert + text[cut:]
    path = folder / "Main.TcPOU"
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    code = main(["check", str(path)])
    err = capsys.readouterr().err
    assert code in (0, 1), err
    assert "internal error" not in err and "Traceback" not in err
