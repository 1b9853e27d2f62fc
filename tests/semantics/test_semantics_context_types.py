"""Typing from context (issue 11, found by running outside code): untyped literals in SEL/MUX/
LIMIT take the other arguments' type or the expected one, TRUNC's integer result follows the
target (IEC ANY_REAL -> ANY_INT), a local constant may size an array declared above it, a
subrange variable without an initial value starts at its lower bound."""

from __future__ import annotations

import pytest

from core_helpers import SYSMAC, check_text, run_st

SOURCE = """
TYPE Range : INT(5..10); R2 : Range; S : STRUCT a : INT(-3..3); b : Range; c : SINT(1..2) := 2; END_STRUCT; END_TYPE
VAR_GLOBAL g : UINT(100..200); END_VAR
PROGRAM Main
VAR
    arr : ARRAY[1..N] OF INT;
    name : STRING[LEN_MAX];
    c : BOOL; i : INT := 4; k : INT; r : REAL := 2.5; m : REAL; u : UDINT; lim : REAL; mx : REAL;
    t : DINT; tt : INT; j : SINT; lt : LINT;
    sr : INT(5..10); rr : Range; r2 : R2; s : S; x : INT(1..9) := 4;
END_VAR
VAR CONSTANT N : INT := 3; LEN_MAX : INT := 4; END_VAR
k := SEL(c, 0, i);
m := SEL(c, 1.5, r);
lim := LIMIT(0.0, r, 1.0);
mx := MUX(1, 0.5, r);
u := 3000000000;
t := TRUNC(r);
tt := TRUNC(-r);
lt := TRUNC(LREAL#1.0E12);
j := SEL(c, 1, 2);
arr[N] := 7;
name := 'abcdef';
END_PROGRAM
"""


def test_context_typing_runs():
    values = run_st(SOURCE, settings=SYSMAC, prints=["Main.k", "Main.m", "Main.lim", "Main.mx", "Main.u", "Main.t", "Main.tt",
                                    "Main.lt", "Main.j", "Main.arr", "Main.name"])
    assert values == {"Main.k": 0, "Main.m": 1.5, "Main.lim": 1.0, "Main.mx": 2.5, "Main.u": 3000000000,
                      "Main.t": 2, "Main.tt": -2, "Main.lt": 10 ** 12, "Main.j": 1, "Main.arr": [0, 0, 7],
                      "Main.name": b"abc"}


def test_subranges_start_at_their_lower_bound():
    text = run_st(SOURCE, settings=SYSMAC, fmt=True, prints=["Main.sr", "Main.rr", "Main.r2", "Main.s", "Main.x", "g"])
    assert text == {"Main.sr": "5", "Main.rr": "5", "Main.r2": "5", "Main.s": "(a := -3, b := 5, c := 2)",
                    "Main.x": "4", "g": "100"}


@pytest.mark.parametrize("line, message", [
    ("k := SEL(c, 70000, i);", "cannot assign DINT to INT"),          # the literal does not fit INT
    ("j := SEL(c, 1, 300);", "cannot assign DINT to SINT"),
    ("k := TRUNC(i);", "needs ANY_REAL, got INT"),
    ("u := 5000000000;", "5000000000 is out of range for UDINT"),
    ("w := TRUNC(r);", "cannot assign DINT to WORD"),                 # a bit string is no ANY_INT
])
def test_context_typing_errors(line, message):
    rc, err = check_text(f"""PROGRAM Main
VAR c : BOOL; i, k : INT; j : SINT; u : UDINT; r : REAL; w : WORD; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1 and "case.st:3:" in err and message in err, err


def test_a_constant_used_before_its_block_must_still_be_constant():
    rc, err = check_text("""PROGRAM Main
VAR arr : ARRAY[1..N] OF INT; END_VAR
VAR N : INT := 3; END_VAR
arr[1] := 1;
END_PROGRAM
""")
    assert rc == 1 and "case.st:2:" in err and "expected a constant integer" in err, err
