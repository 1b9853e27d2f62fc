"""Checker rules TwinCAT libraries (TcUnit) rely on (stvm/semantics/qualified.py, checker.py,
body.py): each case is what TwinCAT accepts and what it does at run time."""

from __future__ import annotations

from stvm.settings import SysmacSettings
from tests.core_helpers import run_st

TWINCAT = SysmacSettings(dialect="twincat")


def test_a_method_variable_shadows_a_qualified_only_enumerator():
    # TcUnit's FB_AdsLogStringMessageFifoQueue: a method output `Error` beside E_XmlError.Error
    src = """
{attribute 'qualified_only'}
TYPE E_XmlError : (Ok, Error); END_TYPE
FUNCTION_BLOCK FB_Queue
VAR_OUTPUT last : BOOL; END_VAR
METHOD Pop
VAR_OUTPUT Error : BOOL; END_VAR
Error := TRUE;
last := Error;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR q : FB_Queue; e : E_XmlError := E_XmlError.Error; END_VAR
q.Pop();
END_PROGRAM
"""
    assert run_st(src, prints=["Main.q.last", "Main.e"], fmt=True, settings=TWINCAT) == \
        {"Main.q.last": "TRUE", "Main.e": "E_XmlError#Error"}


GVL_TWO_BLOCKS = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <GVL Name="GVL_Lib" Id="{78472b76-c9a4-4b27-a580-8e7898edc3d7}">
    <Declaration><![CDATA[{attribute 'qualified_only'}
VAR_GLOBAL
    Count : INT := 3;
END_VAR
VAR_GLOBAL CONSTANT
    Scale : LREAL := 1.0 / 4.0;
END_VAR]]></Declaration>
  </GVL>
</TcPlcObject>
"""


def test_every_block_of_a_global_variable_list_belongs_to_it():
    # TcUnit's GVL_TcUnit: a VAR_GLOBAL then a VAR_GLOBAL CONSTANT, used as GVL_TcUnit.<name>
    main = "PROGRAM Main VAR d : LREAL; END_VAR d := GVL_Lib.Count * GVL_Lib.Scale; END_PROGRAM\n"
    assert run_st({"GVL_Lib.TcGVL": GVL_TWO_BLOCKS, "main.st": main}, prints=["Main.d"],
                  settings=TWINCAT) == {"Main.d": 0.75}


def test_a_method_result_reference_to_is_bound_with_ref_and_read_through():
    # TcUnit's FB_TestResults.GetTestSuiteResults : REFERENCE TO ST_TestSuiteResults
    src = """
TYPE ST_R : STRUCT n : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK FB_Res
VAR res : ST_R; END_VAR
METHOD Get : REFERENCE TO ST_R
Get REF= res;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : FB_Res; r : REFERENCE TO ST_R; v : INT; END_VAR
r REF= f.Get();
r.n := r.n + 1;
v := f.Get().n;
END_PROGRAM
"""
    assert run_st(src, cycles=2, prints=["Main.v", "Main.f.res.n"], settings=TWINCAT) == \
        {"Main.v": 2, "Main.f.res.n": 2}


def test_isvalidref_of_a_reference_to_an_instance_and_an_in_out_constant():
    src = """
FUNCTION_BLOCK FB_T
VAR_OUTPUT n : INT; END_VAR
n := n + 1;
END_FUNCTION_BLOCK
FUNCTION Count : INT
VAR_IN_OUT CONSTANT c : FB_T; END_VAR
c();
Count := c.n;
END_FUNCTION
PROGRAM Main
VAR r : REFERENCE TO FB_T; f : FB_T; before, after : BOOL; k : INT; END_VAR
before := __ISVALIDREF(r);
r REF= f;
after := __ISVALIDREF(r);
k := Count(f);
END_PROGRAM
"""
    assert run_st(src, prints=["Main.before", "Main.after", "Main.k"], settings=TWINCAT) == \
        {"Main.before": False, "Main.after": True, "Main.k": 1}


def test_a_method_returning_an_instance_returns_a_copy():
    # TcUnit's FB_TestSuite.GetTestByPosition : FB_Test; the caller's copy changes alone
    src = """
FUNCTION_BLOCK FB_Test
VAR name : STRING; arr : ARRAY[1..2] OF INT; END_VAR
METHOD SetName
VAR_INPUT s : STRING; END_VAR
name := s; arr[1] := LEN(s);
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Suite
VAR tests : ARRAY[1..3] OF FB_Test; END_VAR
METHOD Get : FB_Test
VAR_INPUT i : INT; END_VAR
Get := tests[i];
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR s : FB_Suite; cur : FB_Test; n : STRING; a : INT; END_VAR
s.tests[2].SetName('second');
cur := s.Get(2);
n := cur.name;
a := cur.arr[1];
cur.SetName('changed');
END_PROGRAM
"""
    assert run_st(src, prints=["Main.n", "Main.a", "Main.s.tests[2].name", "Main.cur.name"], settings=TWINCAT) == \
        {"Main.n": b"second", "Main.a": 6, "Main.s.tests[2].name": b"second", "Main.cur.name": b"changed"}


def test_an_interface_initialised_with_an_instance_declared_before_it():
    # TcUnit's FB_TcUnitRunner: `AdsTestResultLogger : FB_AdsTestResultLogger(TestResults);` and
    # `TestResultLogger : I_TestResultLogger := AdsTestResultLogger;`
    src = """
INTERFACE I_Res
METHOD Count : INT END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Res IMPLEMENTS I_Res
VAR_INPUT n : INT := 7; END_VAR
METHOD Count : INT
Count := n;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Log
VAR res : I_Res; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; iRes : I_Res; END_VAR
res := iRes;
END_METHOD
METHOD Show : INT
Show := res.Count();
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Runner
VAR
  results : FB_Res;
  logger : FB_Log(results);
  itf : I_Res := results;
END_VAR
END_FUNCTION_BLOCK
PROGRAM Main
VAR r : FB_Runner; a, b : INT; END_VAR
r.results.n := 9;
a := r.logger.Show();
b := r.itf.Count();
END_PROGRAM
"""
    assert run_st(src, prints=["Main.a", "Main.b"], settings=TWINCAT) == {"Main.a": 9, "Main.b": 9}
