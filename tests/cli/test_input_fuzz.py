"""Every input a user controls ends in a clear error (issue 17): one hypothesis fuzz test per kind.

Random TOML manifests and scenarios, random DAP frames, random `stvm` argument lists and random
bytes as sources. Each example asserts: no traceback, an exit code in {0, 1, 2, 3} (70, stvm's
"internal error", fails the test), and the command ends (a SIGALRM watchdog).

Fixed seed (derandomize) and a bounded number of examples here; `python bench/bench_fuzz.py`
runs the same properties with many more (STVM_FUZZ_EXAMPLES).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import signal
import string
import tempfile
from contextlib import contextmanager
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from core_helpers import cli
from stvm.runtime.vm import _ensure_recursion_limit

_ensure_recursion_limit()   # what every VM does; set before hypothesis records the limit

EXAMPLES = int(os.environ.get("STVM_FUZZ_EXAMPLES", "40"))
FUZZ = settings(max_examples=EXAMPLES, derandomize=True, deadline=None, database=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                       HealthCheck.data_too_large])
ALLOWED = {0, 1, 2, 3}
TIME_LIMIT_S = 60

PROGRAM = """PROGRAM Main
VAR x : INT; b : BOOL; s : STRING[10]; t : TIME; r : REAL; arr : ARRAY[0..3] OF INT; END_VAR
x := x + 1;
b := x > 2;
END_PROGRAM
"""

_WORK = Path(tempfile.mkdtemp(prefix="stvm-fuzz-"))


@contextmanager
def watchdog(what: str):
    def expired(*_):
        raise AssertionError(f"{what} did not end within {TIME_LIMIT_S} s")
    previous = signal.signal(signal.SIGALRM, expired)
    signal.alarm(TIME_LIMIT_S)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def run_cli(argv) -> tuple[int, str, str]:
    with watchdog(" ".join(map(str, argv))[:200]):
        rc, out, err = cli(argv)
    assert "Traceback" not in err, err[-3000:]
    assert rc in ALLOWED, (rc, argv, err[-2000:])
    return rc, out, err


def fresh_folder() -> Path:
    return Path(tempfile.mkdtemp(dir=_WORK))


# ---------------------------------------------------------------- TOML documents

_keys = st.sampled_from(["project", "files", "encoding", "demo", "scenario", "step_variable", "cycle_from",
                         "cycle_to", "status", "errors", "sysmac", "int_div_zero", "hmi", "set", "robot",
                         "address", "port", "at", "scan", "time", "when", "fault", "record", "watch", "run",
                         "cycles", "emulator", "latency_scans", "latency", "faults", "settings", "time_scale",
                         "description", "Main.x", "Main.b", "Main.s", "Main.t", "Main.r", "Main.arr[1]",
                         "Main.nope", "x", "\"quoted key\""])
_strings = st.sampled_from(["main.st", "missing.st", "", "Main.x", "Main.b", "Main.x +", ")(", "1ms", "0",
                            "-5ms", "T#5ms", "'text'", "'unterminated", "16#FF", "drop", "error:0", "delay:5",
                            "utf-8", "klingon", "zero", "Main.arr[abc]", "é\x1b[31m", "1e40", "TRUE"]) \
    | st.text(string.printable, max_size=12)
_scalars = st.one_of(st.booleans(), st.integers(-10**20, 10**20), st.floats(allow_nan=True), _strings)


def _toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return {"nan": "nan", "inf": "inf", "-inf": "-inf"}.get(repr(value), repr(value))
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list):
        return "[" + ", ".join(_toml_value(v) for v in value) + "]"
    return "{ " + ", ".join(f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items()) + " }"


_values = st.recursive(_scalars, lambda inner: st.lists(inner, max_size=3)
                       | st.dictionaries(_keys, inner, max_size=3), max_leaves=8)
_tables = st.dictionaries(_keys, st.dictionaries(_keys, _values, max_size=4) | _values, max_size=5)


@st.composite
def toml_documents(draw) -> str:
    """A TOML document: mostly well-formed (tables of random keys and values), sometimes broken."""
    doc = draw(_tables)
    lines = []
    for key, value in doc.items():
        if isinstance(value, dict) and draw(st.booleans()):
            lines.append(f"[{json.dumps(key) if not key.isidentifier() else key}]")
            lines += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in value.items()]
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            for item in value:
                lines.append(f"[[{json.dumps(key)}]]")
                lines += [f"{json.dumps(k)} = {_toml_value(v)}" for k, v in item.items()]
        else:
            lines.insert(0, f"{json.dumps(key)} = {_toml_value(value)}")
    text = "\n".join(lines) + "\n"
    if draw(st.integers(0, 9)) == 0:   # a syntax error somewhere
        cut = draw(st.integers(0, len(text)))
        text = text[:cut] + draw(st.sampled_from(["[", "]]", "=", "\"", "\x00", "[project", "\n= 5"])) + text[cut:]
    return text


@FUZZ
@given(toml_documents())
def test_random_manifests(document):
    folder = fresh_folder()
    (folder / "main.st").write_text(PROGRAM)
    (folder / "stvm.toml").write_text(document, encoding="utf-8")
    run_cli(["check", folder / "main.st"])
    run_cli(["run", folder / "main.st", "--cycles", "2", "--no-demo"] if "demo" in document
            else ["run", folder / "main.st", "--cycles", "2"])
    run_cli(["check", folder])


@FUZZ
@given(toml_documents())
def test_random_scenarios(document):
    folder = fresh_folder()
    (folder / "main.st").write_text(PROGRAM)
    scenario = folder / "s.toml"
    scenario.write_text(document, encoding="utf-8")
    run_cli(["run", folder / "main.st", "--cycles", "3", "--scenario", scenario])
    run_cli(["trace", folder / "main.st", "--cycles", "3", "--scenario", scenario, "--watch", "Main.*",
             "-o", folder / "out.jsonl"])


# ---------------------------------------------------------------- DAP frames

_requests = st.fixed_dictionaries({
    "seq": st.one_of(st.integers(-5, 100), st.text(max_size=3), st.none()),
    "type": st.sampled_from(["request", "event", "response", 5]),
    "command": st.sampled_from(["initialize", "launch", "setBreakpoints", "configurationDone", "threads",
                                "stackTrace", "scopes", "variables", "evaluate", "setVariable", "continue",
                                "next", "stepIn", "pause", "source", "disconnect", "terminate", "nope",
                                "__init__", ""]) | st.integers(),
}, optional={"arguments": st.one_of(st.dictionaries(st.sampled_from([
    "program", "cwd", "scan", "set", "sysmac", "cycles", "breakpoints", "lines", "source", "frameId",
    "variablesReference", "expression", "context", "threadId", "start", "count", "name", "value",
    "sourceReference", "levels", "startFrame", "stopOnEntry", "robot", "scenario"]), _values, max_size=5),
    _values)})


@st.composite
def dap_streams(draw) -> bytes:
    frames = []
    for _ in range(draw(st.integers(1, 6))):
        kind = draw(st.integers(0, 9))
        if kind <= 5:
            body = json.dumps(draw(_requests)).encode()
            frames.append(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        elif kind == 6:
            body = draw(st.binary(max_size=40))
            frames.append(b"Content-Length: %d\r\n\r\n" % len(body) + body)
        elif kind == 7:
            frames.append(b"Content-Length: " + draw(st.sampled_from([b"abc", b"-5", b"999999999999", b"",
                                                                     b"1e3", b"0x10"])) + b"\r\n\r\n{}")
        else:
            frames.append(draw(st.binary(max_size=60)))
    return b"".join(frames)


def _frames(raw: bytes) -> list[dict]:
    out = []
    while raw:
        head, sep, rest = raw.partition(b"\r\n\r\n")
        assert sep, raw[:100]
        length = int(head.split(b":")[1])
        out.append(json.loads(rest[:length]))
        raw = rest[length:]
    return out


@FUZZ
@given(dap_streams())
def test_random_dap_frames(stream):
    from stvm.debug.dap import DapServer
    out = io.BytesIO()
    with watchdog("stvm dap"):
        server = DapServer(io.BytesIO(stream), out)
        rc = server.serve()
    assert rc in (0, 2)
    for message in _frames(out.getvalue()):       # whatever it answered is well-framed JSON
        assert message["type"] in ("response", "event")
        if message["type"] == "response" and not message["success"]:
            assert "internal error" not in message.get("message", ""), message


# ---------------------------------------------------------------- command lines

_OPTIONS = ["--scan", "--cycles", "--duration", "--print", "--set", "--stats", "--no-cache", "--scenario",
            "--watchdog", "--robot", "--emulator-log", "--pnp-cycles", "--no-demo", "--virtual-clock",
            "--sysmac", "--watch", "-o", "--compare", "--context", "--latency-scans", "--fault", "--svg",
            "--max-columns", "--no-writer", "--realtime"]
_VALUES = ["1ms", "0", "-1", "abc", "nan", "inf", "off", "5", "99999999999", "Main.x", "Main.nope", "Main.arr[abc]",
           "Main.arr[9]", "Main.x=5", "Main.t=5", "Main.b=1", "Main.s='open", "Main.r=1e40", "x=", "=",
           "int_div_zero=zero", "bogus=1", "127.0.0.1:1", "host", "/no/dir/x", "out.jsonl", "out.xyz", "Main.*",
           "drop", "error:0", "T#1ms", "1e-9s", "", "é", "\x1b[2J"]


@st.composite
def command_lines(draw) -> list[str]:
    command = draw(st.sampled_from(["run", "check", "trace", "bogus", "--version"]))
    argv = [command]
    if command in ("run", "check", "trace") and draw(st.integers(0, 5)):
        argv.append("{main}")
    for _ in range(draw(st.integers(0, 6))):
        if draw(st.booleans()):
            argv.append(draw(st.sampled_from(_OPTIONS)))
        argv.append(draw(st.sampled_from(_VALUES) | st.text(string.printable, max_size=8)))
    if command == "run":
        # a run without a bound runs until Ctrl-C by design: bound it (a usage error may win)
        argv += draw(st.sampled_from([["--cycles", "3"], ["--duration", "3ms"]]))
        if "--realtime" in argv:
            argv += ["--scan", "1ms"]
    return argv


@FUZZ
@given(command_lines())
def test_random_command_lines(argv):
    folder = fresh_folder()
    (folder / "main.st").write_text(PROGRAM)
    argv = [a.replace("{main}", str(folder / "main.st")) for a in argv]
    argv = [str(folder / a) if a in ("out.jsonl", "out.xyz") else a for a in argv]
    if argv[0] == "--version":
        with pytest.raises(SystemExit):
            from stvm.cli import main
            main(argv)
        return
    run_cli(argv)


@FUZZ
@given(st.lists(st.sampled_from(["--port", "--host", "--log", "--fault", "--set", "--quiet", "--duration"])
                | st.sampled_from(["99999", "-1", "0", "abc", "127.0.0.1", "/no/dir/x", "error:0", "busy:3",
                                   "time_scale=-1", "time_scale=abc", "nope=1", "0.05", "nan"]), max_size=6))
def test_random_emulator_command_lines(argv):
    from emulator.cli import main
    argv = list(argv) + ["--quiet", "--duration", "0.05", "--port", "0", "--host", "127.0.0.1"]
    err = io.StringIO()
    # `--log NAME` writes NAME relative to the working directory: keep it in a fresh folder
    with watchdog("tm-emulator"), contextlib_redirect(err), contextlib.chdir(fresh_folder()):
        try:
            rc = main(argv)
        except SystemExit as exc:
            rc = exc.code
    assert "Traceback" not in err.getvalue()
    assert rc in (0, 1, 2), (rc, argv, err.getvalue())


@contextmanager
def contextlib_redirect(err):
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        yield


# ---------------------------------------------------------------- sources

@FUZZ
@given(st.one_of(st.binary(max_size=400),
                 st.builds(lambda cut, junk: PROGRAM.encode()[:cut] + junk + PROGRAM.encode()[cut:],
                           st.integers(0, len(PROGRAM)), st.binary(min_size=1, max_size=8))))
def test_random_bytes_as_sources(data):
    folder = fresh_folder()
    path = folder / "main.st"
    path.write_bytes(data)
    rc, out, err = run_cli(["check", path])
    # nothing raw reaches the terminal: control characters are escaped in every diagnostic
    assert not any(ch in err for ch in "\x00\x07\x1b\x7f"), err[:500]
    run_cli(["run", path, "--cycles", "1", "--no-cache"])
