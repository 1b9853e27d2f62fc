"""EN/ENO (IEC 61131-3 ed. 3 6.6.1.6, 6.6.2.5) on calls of user functions, FBs and standard
functions: EN FALSE skips the call (no assignment, outputs unchanged) and gives ENO FALSE; an
instruction error gives ENO FALSE; otherwise ENO TRUE."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st

SOURCE = """
FUNCTION_BLOCK Inc
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT q : INT; END_VAR
q := q + step;
END_FUNCTION_BLOCK
FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := 2 * x;
END_FUNCTION
PROGRAM Main
VAR c : BOOL; f : Inc; eno1, eno2, eno3, eno4, neno : BOOL; a : INT := 5; b : INT := 1; m : INT := 9;
    k : INT := 5; mx : INT := 3; out : INT; END_VAR
f(EN := c, step := 1, ENO => eno1);
f(EN := TRUE, step := 10, ENO => eno2, q => out);
b := Twice(EN := c, x := a, ENO => eno3);
a := Twice(EN := TRUE, x := a, ENO => eno4);
m := MUX(EN := TRUE, K := k, IN0 := 1, IN1 := 2, NOT ENO => neno);
mx := MAX(EN := NOT c, IN1 := mx, IN2 := 7);
END_PROGRAM
"""


def test_en_eno_semantics():
    names = ["f.q", "eno1", "eno2", "out", "b", "eno3", "a", "eno4", "m", "neno", "mx"]
    values = run_st(SOURCE, prints=[f"Main.{v}" for v in names])
    assert values == {"Main.f.q": 10, "Main.eno1": False, "Main.eno2": True, "Main.out": 10, "Main.b": 1,
                      "Main.eno3": False, "Main.a": 10, "Main.eno4": True, "Main.m": 9, "Main.neno": True,
                      "Main.mx": 7}


@pytest.mark.parametrize("line, message", [
    ("b := Twice(EN := 5, x := 1);", "cannot assign DINT to BOOL"),
    ("b := Twice(x := 1, ENO => b);", "ENO is BOOL; cannot bind it to INT"),
    ("b := 1 + Twice(EN := 1.5, x := 1);", "cannot assign LREAL to BOOL"),
    ("b := 1 + Twice(x := 1, ENO => b);", "ENO is BOOL; cannot bind it to INT"),
    ("b := Twice(EN := c, 1);", "mix of formal"),
    ("f(EN := c, ENO => 5);", "syntax error"),
])
def test_en_eno_errors(line, message):
    rc, err = check_text(f"""FUNCTION_BLOCK Inc
VAR_INPUT step : INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := 2 * x;
END_FUNCTION
PROGRAM Main
VAR c : BOOL; b : INT; f : Inc; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1 and "case.st:10:" in err and message in err, err


def test_a_pou_with_its_own_en_pin_keeps_it():
    values = run_st("""FUNCTION_BLOCK Own
VAR_INPUT EN : BOOL; END_VAR
VAR_OUTPUT ENO : BOOL; seen : BOOL; END_VAR
seen := EN;
ENO := NOT EN;
END_FUNCTION_BLOCK
PROGRAM Main
VAR o : Own; e : BOOL; END_VAR
o(EN := FALSE, ENO => e);
END_PROGRAM
""", prints=["Main.o.seen", "Main.e"])
    assert values == {"Main.o.seen": False, "Main.e": True}


NESTED = """
FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := 2 * x;
END_FUNCTION
FUNCTION_BLOCK Counter
VAR_OUTPUT n : INT; END_VAR
METHOD Next : INT
n := n + 1; Next := n;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR c : BOOL; b, b2, d, k, i : INT; ok1, ok2, ok3, err, ok4, ok5, ok6, short : BOOL := TRUE; f : Counter;
    s : STRING := 'keep'; arr : ARRAY[0..1] OF BOOL; END_VAR
b := 1 + Twice(EN := c, x := 5, ENO => ok1);           (* EN FALSE: the initial value, 0 *)
b2 := 1 + Twice(EN := NOT c, x := 5, ENO => ok2);
IF Twice(EN := TRUE, x := 2, ENO => ok3) = 4 THEN d := 1; END_IF;
k := INT#10 + MUX(EN := c, K := 1, IN0 := k, IN1 := b, NOT ENO => err);
i := f.Next(EN := c, ENO => ok4) + f.Next(EN := TRUE, ENO => arr[1]);
short := c AND Twice(EN := TRUE, x := 1, ENO => ok6) = 2;   (* not evaluated: ENO untouched *)
s := CONCAT(s, MID(EN := TRUE, IN := 'abc', L := 1, P := 9, ENO => ok5));   (* instruction error *)
END_PROGRAM
"""


def test_en_eno_inside_larger_expressions():
    names = ["b", "ok1", "b2", "ok2", "d", "ok3", "k", "err", "i", "ok4", "arr[1]", "f.n", "ok6", "s", "ok5"]
    values = run_st(NESTED, prints=[f"Main.{v}" for v in names])
    assert values == {"Main.b": 1, "Main.ok1": False, "Main.b2": 11, "Main.ok2": True, "Main.d": 1,
                      "Main.ok3": True, "Main.k": 10, "Main.err": True, "Main.i": 1, "Main.ok4": False,
                      "Main.arr[1]": True, "Main.f.n": 1, "Main.ok6": True, "Main.s": b"keep", "Main.ok5": False}
