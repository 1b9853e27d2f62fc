"""BCD conversions (IEC 61131-3 ed. 3 table 23): typed (WORD_BCD_TO_INT, INT_TO_BCD_WORD) and
overloaded (BCD_TO_INT, INT_TO_BCD) forms; bad BCD, negative and too-large values are
instruction errors (the assignment is skipped, ENO FALSE)."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st
from stvm.stdlib.bcd import from_bcd, to_bcd
from stvm.runtime.values import FunctionError

SOURCE = """
PROGRAM Main
VAR w : WORD := 16#1234; i, j : INT; k : UDINT; back : WORD; b : BYTE; e : WORD; x : INT := 77;
    l : LINT; lw : LWORD; END_VAR
i := WORD_BCD_TO_INT(w);
j := BCD_TO_INT(w);
k := BCD_TO_UDINT(DWORD#16#99999999);
back := INT_TO_BCD_WORD(i);
b := USINT_TO_BCD_BYTE(USINT#42);
e := INT_TO_BCD(x);
l := LWORD_BCD_TO_LINT(LWORD#16#1234567890123456);
lw := LINT_TO_BCD_LWORD(l);
END_PROGRAM
"""


def test_bcd_round_trips():
    values = run_st(SOURCE, prints=["Main.i", "Main.j", "Main.k", "Main.back", "Main.b", "Main.e", "Main.l", "Main.lw"])
    assert values == {"Main.i": 1234, "Main.j": 1234, "Main.k": 99999999, "Main.back": 0x1234, "Main.b": 0x42,
                      "Main.e": 0x77, "Main.l": 1234567890123456, "Main.lw": 0x1234567890123456}


@pytest.mark.parametrize("line", ["i := WORD_BCD_TO_INT(WORD#16#00FA);", "w := INT_TO_BCD_WORD(INT#-1);",
                                  "b := INT_TO_BCD_BYTE(INT#100);", "i := WORD_BCD_TO_INT(WORD#16#9999) ;"])
def test_bad_values_are_instruction_errors(line):
    # WORD 9999 is fine as BCD and fits INT; 16#FA is no BCD; -1 and 100 do not fit a BYTE's 2 digits
    values = run_st(f"""PROGRAM Main
VAR i : INT := 5; w : WORD := 16#5; b : BYTE := 16#5; END_VAR
{line}
END_PROGRAM
""", prints=["Main.i", "Main.w", "Main.b"])
    if "9999" in line:
        assert values["Main.i"] == 9999
    else:
        assert values == {"Main.i": 5, "Main.w": 5, "Main.b": 5}


def test_decoding_rules():
    assert from_bcd(0x0905, "t") == 905
    with pytest.raises(FunctionError, match="not BCD"):
        from_bcd(0x1A, "t")
    assert to_bcd(0, 8, "t") == 0
    with pytest.raises(FunctionError, match="more than 2 digits"):
        to_bcd(123, 8, "t")


def test_overloaded_bcd_needs_a_bit_string():
    rc, err = check_text("PROGRAM Main\nVAR r : REAL; i : INT; END_VAR\ni := BCD_TO_INT(r);\nEND_PROGRAM\n")
    assert rc == 1 and "case.st:3:" in err and "needs ANY_BIT, got REAL" in err
