"""The overloaded conversions TO_<type> (IEC 61131-3 ed. 3 table 22): `TO_STRING(i)`,
`TO_WSTRING(r)`, `TO_DINT(t)`, … are the `<SRC>_TO_<type>` of the argument's static type
(a subrange or an enumeration by its base type, STRING[n] as STRING, the type itself as is);
a type without such a conversion is a check-time error."""

from __future__ import annotations

import pytest

from core_helpers import SYSMAC, check_text, run_st
from stvm.semantics.types import ELEMENTARY
from stvm.stdlib.conversions import conversion_pairs, generic_conversion_functions

SOURCE = """
TYPE Pct : INT(0..100); END_TYPE
TYPE Col : (Red, Green := 5); END_TYPE
PROGRAM Main
VAR i : INT := 5; p : Pct := 42; c : Col := Col#Green; r : REAL := 2.5; t : TIME := T#1500ms;
  s1, s2, s4 : STRING; ws, ws2 : WSTRING; d, d2 : DINT; b : BYTE; x : INT; tt : TIME; s3 : STRING[20];
  lr : LREAL; tod1 : TOD; bo : BOOL; lt : LTIME;
END_VAR
s1 := TO_STRING(i);
s2 := TO_STRING(r);
ws := TO_WSTRING(i);
ws2 := TO_WSTRING(s3);
d := TO_DINT(r);
d2 := TO_DINT(t);
b := TO_BYTE(p);
x := TO_INT(c);
tt := TO_TIME(d);
s3 := 'abc';
s4 := TO_STRING(s3);
lr := TO_LREAL(TO_WSTRING('1.5'));
tod1 := TO_TIME_OF_DAY(DT#2020-01-01-10:00:00);
bo := TO_BOOL(7);
lt := TO_LTIME(t);
END_PROGRAM
"""


def test_to_type_picks_the_conversion_of_the_argument_type():
    names = ["s1", "s2", "ws", "d", "d2", "b", "x", "tt", "s4", "lr", "tod1", "bo", "lt"]
    values = run_st(SOURCE, fmt=True, prints=[f"Main.{n}" for n in names], settings=SYSMAC)   # Omron's REAL text
    assert values == {"Main.s1": "'5'", "Main.s2": "'2.500000e+00'", "Main.ws": '"5"', "Main.d": "2",
                      "Main.d2": "1500", "Main.b": "42", "Main.x": "5", "Main.tt": "T#2ms", "Main.s4": "'abc'",
                      "Main.lr": "1.5", "Main.tod1": "TOD#10:00:00", "Main.bo": "TRUE", "Main.lt": "LT#1s500ms"}


def test_every_target_type_has_a_to_function():
    targets = {target for _, target in generic_conversion_functions()}
    assert targets == {b for _, b in conversion_pairs()} and all(t in ELEMENTARY for t in targets)
    assert {"TO_TOD", "TO_TIME_OF_DAY", "TO_WSTRING", "TO_LDATE_AND_TIME"} <= {n for n, _ in generic_conversion_functions()}


@pytest.mark.parametrize("line, message", [
    ("tod1 := TO_TOD(T#1h);", "TO_TOD: no conversion from TIME to TOD"),
    ("tt := TO_TIME(TRUE);", "TO_TIME: no conversion from BOOL to TIME"),
    ("s1 := TO_WSTRING(i);", "WSTRING"),
])
def test_to_type_without_a_conversion_is_an_error(line, message):
    rc, err = check_text(f"PROGRAM Main\nVAR i : INT; s1 : STRING; tt : TIME; tod1 : TOD; END_VAR\n{line}\nEND_PROGRAM\n")
    assert rc == 1 and "Traceback" not in err
    assert "case.st:3:" in err and message in err, err
