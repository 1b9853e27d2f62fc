"""The function forms of the operators (IEC 61131-3 ed. 3 tables 24, 26, 28): ADD SUB MUL DIV
MOD AND OR XOR, and the comparisons GT GE EQ LE LT (extensible: each neighbouring pair) and NE."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st

SOURCE = """
PROGRAM Main
VAR a : INT := 7; b : INT := 3; w : WORD := 16#F0F0; r : REAL := 1.5;
    gt1, gt3, ge1, eq1, ne1, lt1, le1, gtr : BOOL; m, m2 : INT; wa, wo, wx : WORD; ba : BOOL;
    s1, s2, mu, d : INT; md : DINT; END_VAR
gt1 := GT(a, b);
gt3 := GT(a, b, 1);
ge1 := GE(b, b, 4);
eq1 := EQ(a, 7, a);
ne1 := NE(a, b);
lt1 := LT(1, b, a);
le1 := LE(a, b);
gtr := GT(r, 1.0);
m := MOD(a, b);
m2 := MOD(-a, b);
md := mod(IN1 := 17, IN2 := 5);
wa := AND(w, 16#FF00);
wo := OR(w, 16#000F, 16#0100);
wx := XOR(w, 16#FFFF);
ba := AND(TRUE, gt1, NOT le1);
s1 := ADD(a, b, 1);
s2 := SUB(a, b);
mu := MUL(a, b);
d := DIV(a, b);
END_PROGRAM
"""

EXPECTED = {"gt1": True, "gt3": True, "ge1": False, "eq1": True, "ne1": True, "lt1": True, "le1": False,
            "gtr": True, "m": 1, "m2": -1, "md": 2, "wa": 0xF000, "wo": 0xF1FF, "wx": 0x0F0F, "ba": True,
            "s1": 11, "s2": 4, "mu": 21, "d": 2}


def test_operator_functions_compute_like_the_operators():
    values = run_st(SOURCE, prints=[f"Main.{k}" for k in EXPECTED])
    assert values == {f"Main.{k}": v for k, v in EXPECTED.items()}


def test_mod_function_by_zero_faults_like_the_operator():
    import stvm
    from core_helpers import start_st
    vm = start_st("PROGRAM Main VAR a, b, m : INT; END_VAR a := 5; m := MOD(a, b); END_PROGRAM")
    with pytest.raises(stvm.RuntimeFault, match="division by zero"):
        vm.run(cycles=1)


@pytest.mark.parametrize("line, message", [
    ("x := GT();", "at least"),
    ("x := NE(a, b, a);", "takes 2 argument"),
    ("w := AND(r, r);", "needs ANY_BIT, got REAL"),
    ("a := MOD(r, 2);", "needs ANY_INT, got REAL"),
    ("x := EQ(a, s);", "different types"),
])
def test_operator_function_errors(line, message):
    rc, err = check_text(f"""PROGRAM Main
VAR a, b : INT; r : REAL; w : WORD; x : BOOL; s : STRING[4]; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1 and "case.st:3:" in err and message in err, err
