"""TIME/TOD/DATE/DT <-> integer and REAL conversions (TIME_TO_DINT, DINT_TO_TIME, DT_TO_UDINT, …).
Choice (stvm/stdlib/conversions.py `time_unit_ns`, CODESYS convention): TIME and TOD count
milliseconds, DATE and DT seconds since 1970; toward zero into integers."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st

MS = 1_000_000
S = 1_000_000_000


def test_time_numeric_conversions():
    values = run_st("""PROGRAM Main
VAR t : TIME := T#1m2s500ms; d : DINT; r : REAL; t2 : TIME; dt1 : DT := DT#1970-01-02-00:00:10; u : UDINT;
    day : DATE; tod1 : TOD := TOD#01:00:00; lr : LREAL; t3 : TIME; neg : DINT; w : WORD; tw : TIME;
    b : SINT; END_VAR
d := TIME_TO_DINT(t);
r := TIME_TO_REAL(t);
t2 := DINT_TO_TIME(1500);
u := DT_TO_UDINT(dt1);
day := UDINT_TO_DATE(86400);
lr := TIME_OF_DAY_TO_LREAL(tod1);
t3 := REAL_TO_TIME(REAL#2.5);
neg := TIME_TO_DINT(T#-1500us);
w := TIME_TO_WORD(T#70s);
tw := WORD_TO_TIME(WORD#16#FFFF);
b := TIME_TO_SINT(T#200ms);
END_PROGRAM
""", prints=[f"Main.{v}" for v in ("d", "r", "t2", "u", "day", "lr", "t3", "neg", "w", "tw", "b")])
    assert values == {"Main.d": 62500, "Main.r": 62500.0, "Main.t2": 1500 * MS, "Main.u": 86410,
                      "Main.day": 86400 * S, "Main.lr": 3600000.0, "Main.t3": 2 * MS + 500_000,
                      "Main.neg": -1, "Main.w": 70000 - 65536, "Main.tw": 65535 * MS, "Main.b": -56}


@pytest.mark.parametrize("line, message", [
    ("d := TIME_TO_DINT(5);", "cannot assign"),
    ("d := t;", "use TIME_TO_DINT"),
    ("x := TIME_TO_BOOL(t);", "unknown function 'TIME_TO_BOOL'"),
])
def test_time_conversion_errors(line, message):
    rc, err = check_text(f"PROGRAM Main\nVAR t : TIME; d : DINT; x : BOOL; END_VAR\n{line}\nEND_PROGRAM\n")
    assert rc == 1 and "case.st:3:" in err and message in err, err
