"""The declarations the tests of the body checks' parts share (tests/semantics/test_<part>.py)."""

SOURCE = """
TYPE Pt : STRUCT x : INT; END_STRUCT; END_TYPE
FUNCTION Add3 : INT
VAR_INPUT a : INT; b : INT; END_VAR
Add3 := a + b;
END_FUNCTION
FUNCTION_BLOCK Motor
VAR_INPUT speed : INT; END_VAR
VAR hidden : BOOL; END_VAR
END_FUNCTION_BLOCK
PROGRAM Main
VAR i : INT; d : DINT; b : BOOL; p : Pt; m : Motor; arr : ARRAY[1..3] OF INT; END_VAR
VAR CONSTANT K : INT := 3; END_VAR
END_PROGRAM
"""
