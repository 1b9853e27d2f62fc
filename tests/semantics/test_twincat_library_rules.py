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
