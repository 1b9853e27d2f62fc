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
