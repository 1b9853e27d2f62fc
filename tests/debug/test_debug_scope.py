"""Debugger expressions (stvm/debug/scope.py): ST text typed and lowered in a POU's scope."""

from __future__ import annotations

import pytest

from core_helpers import write_st
from debug_helpers import line_of, start_engine

from stvm.debug.build import load_debug
from stvm.debug.engine import CONTINUE
from stvm.debug.scope import DebugError

SOURCE = """\
TYPE Mode : (Idle, Running, Failed); END_TYPE

VAR_GLOBAL
    gCount : DINT := 7;
END_VAR

FUNCTION_BLOCK Bump
VAR_IN_OUT
    Target : INT;
END_VAR
VAR_INPUT
    Step : INT := 1;
END_VAR
VAR_EXTERNAL
    gCount : DINT;
END_VAR
VAR
    calls : UDINT;
END_VAR
Target := Target + Step;
calls := calls + 1;
gCount := gCount + 1;
END_FUNCTION_BLOCK

PROGRAM Main
VAR
    b : Bump;
    value : INT := 10;
    flags : WORD := 16#0005;
    state : Mode := Running;
    name : STRING[20] := 'stvm';
    wait : TIME := T#1s500ms;
    ratio : REAL := 0.1;
END_VAR
b(Target := value, Step := 2);
value := value + 0;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def build():
    return load_debug([str(write_st(SOURCE, "scope_prog.st"))])


@pytest.fixture
def engine(build):
    eng = start_engine(build)
    eng.add_breakpoint("scope_prog.st", line_of(SOURCE, "calls := calls + 1;"))
    assert eng.run(CONTINUE, timeout=30) is not None
    yield eng
    eng.terminate()


def test_a_scalar_in_out_reads_and_writes_through_its_reference(engine):
    assert engine.evaluate_text("Target") == "12"               # already incremented by the FB
    assert engine.evaluate_text("Main.value", 1) == "12"        # the caller's variable it refers to
    assert engine.evaluate_text("Main.b.Target") == "12"        # the member, from outside
    engine.assign("Target", "40")
    assert engine.evaluate_text("value", 1) == "40"
    engine.assign("Main.b.Target", "41")
    assert engine.evaluate_text("value", 1) == "41"


def test_types_print_as_iec_literals(engine):
    assert engine.evaluate_text("Main.flags.2") == "TRUE"       # bit access
    assert engine.evaluate_text("Main.flags.1") == "FALSE"
    assert engine.evaluate_text("Main.state") == "Mode#Running"
    assert engine.evaluate_text("Main.state = Mode#Running") == "TRUE"
    assert engine.evaluate_text("Main.name") == "'stvm'"
    assert engine.evaluate_text("CONCAT(Main.name, '!')") == "'stvm!'"
    assert engine.evaluate_text("Main.wait + T#500ms") == "T#2s"
    assert engine.evaluate_text("Main.ratio") == "0.1"          # REAL: single precision, shortest text
    assert engine.evaluate_text("Main.value / 5") == "2"        # integer division, INT
    assert engine.evaluate_text("Main.value MOD 5") == "2"


def test_globals_externals_and_scope_rules(engine):
    assert engine.evaluate_text("gCount") == "7"                # an EXTERNAL in the FB's scope
    assert engine.evaluate_text("calls") == "0"                  # this call has not counted yet
    with pytest.raises(DebugError, match="global gCount"):
        engine.evaluate_text("Main.b.gCount")                    # an FB's external is the global
    with pytest.raises(DebugError, match="not declared"):
        engine.evaluate_text("value")                            # Main's variable: not in Bump's scope
    engine.assign("Main.state", "Mode#Failed")
    assert engine.evaluate_text("Main.state") == "Mode#Failed"
    with pytest.raises(DebugError, match="cannot assign"):
        engine.assign("Main", "1")                               # a program instance
    with pytest.raises(DebugError):
        engine.assign("Main.b", "Main.b")                        # FB instances are not assignable


def test_forcing_a_bit_and_a_string(engine):
    engine.force("Main.flags.1", "TRUE")
    engine.force("Main.name", "'forced'")
    assert engine.evaluate_text("Main.flags") == "7"
    assert engine.evaluate_text("Main.name") == "'forced'"
    assert sorted(engine.forces) == ["main.flags.1", "main.name"]
    engine.unforce(None)
    assert not engine.forces
