"""The debugger on object-oriented code: a breakpoint in a METHOD (and a property accessor) stops
there, the frame is `instance.Method` above its caller, expressions see the method's variables,
its result so far and the instance's variables (also through THIS^)."""

from __future__ import annotations


import pytest

from core_helpers import write_st
from debug_helpers import start_engine

from stvm.debug.build import load_debug
from stvm.debug.engine import BREAKPOINT, CONTINUE, STEP

T = 30

SOURCE = """\
FUNCTION_BLOCK FB_Counter
VAR_OUTPUT count : INT; END_VAR
VAR maxc : INT := 3; END_VAR
count := count + 1;

METHOD Calc : INT
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT twice : INT; END_VAR
VAR tmp : INT; END_VAR
tmp := a + count;
twice := tmp * 2;
Calc := tmp;
END_METHOD

PROPERTY Limit : INT
GET
Limit := maxc;
END_GET
END_PROPERTY
END_FUNCTION_BLOCK

PROGRAM Main
VAR c : FB_Counter; x, y, z : INT; END_VAR
c();
x := c.Calc(a := 10, twice => y);
z := c.Limit;
END_PROGRAM
"""


def _line(snippet: str) -> int:
    return next(i + 1 for i, line in enumerate(SOURCE.splitlines()) if snippet in line)


@pytest.fixture
def engine(tmp_path):
    path = write_st(SOURCE, "oo.st", tmp_path)
    eng = start_engine(load_debug([str(path)]))
    yield eng
    eng.terminate()


def test_breakpoint_in_a_method_stops_with_its_frame_and_variables(engine):
    bp = engine.add_breakpoint("oo.st", _line("twice := tmp * 2;"))
    event = engine.run(CONTINUE, timeout=T)
    assert event is not None and event.reason == BREAKPOINT and event.breakpoints == [bp.id]
    assert event.span.line == _line("twice := tmp * 2;")
    assert [f.name for f in event.frames] == ["Main.c.Calc", "Main"]
    assert engine.evaluate_text("tmp") == "11"            # the method's local
    assert engine.evaluate_text("a") == "10"
    assert engine.evaluate_text("count") == "1"           # the instance's variable
    assert engine.evaluate_text("THIS^.maxc") == "3"
    assert engine.evaluate_text("x", 1) == "0"            # the caller, before the assignment


def test_breakpoint_in_a_property_getter_and_stepping_out(engine):
    engine.add_breakpoint("oo.st", _line("Limit := maxc;"))
    event = engine.run(CONTINUE, timeout=T)
    assert event is not None and event.span.line == _line("Limit := maxc;")
    assert [f.name for f in event.frames] == ["Main.c.Limit", "Main"]
    event = engine.run(STEP, timeout=T)   # back in the caller, whose last statement was running
    assert event is not None and event.span.line == _line("c();") and event.scan == 1


def test_conditional_breakpoint_in_a_method(engine):
    engine.add_breakpoint("oo.st", _line("Calc := tmp;"), "tmp > 12")
    event = engine.run(CONTINUE, timeout=T)
    assert event is not None and event.scan == 2            # count 3 in the third scan: 10 + 3
    assert engine.evaluate_text("tmp") == "13"


def test_dap_method_frame_shows_locals_result_and_this(tmp_path):
    from dap_client import DapClient
    path = write_st(SOURCE, "oo.st", tmp_path)
    dap = DapClient()
    try:
        line = _line("Calc := tmp;")
        results = dap.launch(str(path), breakpoints={str(path): [{"line": line}]})
        assert results[str(path)]["breakpoints"][0]["verified"]
        dap.stopped("breakpoint")
        frames = dap.body("stackTrace", threadId=1)["stackFrames"]
        assert frames[0]["name"].startswith("Main.c.Calc") and frames[0]["line"] == line
        scopes = dap.scope_variables(frames[0]["id"])
        assert scopes["Locals"]["tmp"]["value"] == "11"
        assert scopes["Inputs/Outputs"]["a"]["value"] == "10" and scopes["Inputs/Outputs"]["twice"]["value"] == "22"
        this = scopes["Locals"]["THIS"]
        assert this["variablesReference"] > 0
        assert dap.variables(this["variablesReference"])["count"]["value"] == "1"
        assert dap.evaluate("THIS^.count + tmp", frames[0]["id"])["result"] == "12"
    finally:
        assert dap.close() == 0
