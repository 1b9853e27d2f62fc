"""Partial access of bit strings (IEC 61131-3 ed. 3 6.5.2.3, table 16): `w.%X3`, `d.%B1`,
`l.%W0`, `l.%D1`, read and write, on variables, array elements and struct fields."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st

SOURCE = """
TYPE S : STRUCT w : WORD; END_STRUCT; END_TYPE
PROGRAM Main
VAR w : WORD := 16#00F8; d : DWORD := 16#12345678; l : LWORD := 16#1122334455667788;
    i : INT := -1; arr : ARRAY[0..1] OF DWORD; s : S;
    x3, x0 : BOOL; b1 : BYTE; w0 : WORD; d1 : DWORD; ib : BYTE; ab : BYTE; END_VAR
x3 := w.%X3;
x0 := w.%x0;
b1 := d.%B1;
w0 := l.%W0;
d1 := l.%D1;
ib := i.%B1;
w.%X0 := TRUE;
d.%B3 := 16#AB;
l.%W3 := 16#BEEF;
i.%B1 := 16#7F;
arr[1].%W1 := 16#CAFE;
ab := arr[1].%B3;
s.w.%B0 := 16#11;
s.w.%X15 := 1;
END_PROGRAM
"""


def test_partial_reads_and_writes():
    names = ["x3", "x0", "b1", "w0", "d1", "ib", "w", "d", "l", "i", "arr", "s.w", "ab"]
    values = run_st(SOURCE, prints=[f"Main.{v}" for v in names])
    assert values == {
        "Main.x3": True, "Main.x0": False, "Main.b1": 0x56, "Main.w0": 0x7788, "Main.d1": 0x11223344,
        "Main.ib": 0xFF, "Main.w": 0xF9, "Main.d": 0xAB345678, "Main.l": 0xBEEF334455667788,
        "Main.i": 0x7FFF, "Main.arr": [0, 0xCAFE0000], "Main.s.w": 0x8011, "Main.ab": 0xCA}


@pytest.mark.parametrize("line, message", [
    ("b := w.%B2;", "%B2 is outside WORD: WORD has BYTEs 0..1"),
    ("b := r.%B0;", "%B access needs a bit string or integer, not REAL"),
    ("dw := w.%D0;", "%D0 is outside WORD: WORD has no DWORDs"),
    ("x := w.%X16;", "bit 16 is outside WORD"),
    ("w := w.%B0;", None),
    ("b := w.%W0;", "cannot assign WORD to BYTE"),
])
def test_partial_access_errors(line, message):
    rc, err = check_text(f"""PROGRAM Main
VAR w : WORD; b : BYTE; r : REAL; dw : DWORD; x : BOOL; END_VAR
{line}
END_PROGRAM
""")
    if message is None:
        assert rc == 0, err
    else:
        assert rc == 1 and "case.st:3:" in err and message in err, err
