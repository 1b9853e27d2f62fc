"""IEC 61131-3 ed. 3 table 5: `0` and `1` are BOOL literals (Annex F's HYSTERESIS and RAMP use
them) — in initial values, assignments, BOOL inputs, logic and comparisons; other integers are not."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st

SOURCE = """
PROGRAM Main
VAR b : BOOL := 1; c : BOOL := 0; d, e, f, g : BOOL; t : TON; q : BOOL; END_VAR
d := 1;
e := d AND 1;
f := d = 0;
g := 0 OR c;
t(IN := 1, PT := T#0s);
q := t.Q;
END_PROGRAM
"""


def test_zero_and_one_are_bool_literals():
    values = run_st(SOURCE, cycles=2, prints=["Main.b", "Main.c", "Main.d", "Main.e", "Main.f", "Main.g", "Main.q"])
    assert values == {"Main.b": True, "Main.c": False, "Main.d": True, "Main.e": True, "Main.f": False,
                      "Main.g": False, "Main.q": True}
    assert all(type(v) is bool for v in values.values())


@pytest.mark.parametrize("line, message", [
    ("b := 2;", "cannot assign DINT to BOOL"),
    ("b := b AND 2;", "AND needs BOOL"),
    ("b := -1;", "cannot assign DINT to BOOL"),
    ("b := 1.0;", "cannot assign LREAL to BOOL"),
])
def test_other_numbers_are_not_bool(line, message):
    rc, err = check_text(f"PROGRAM Main\nVAR b : BOOL; END_VAR\n{line}\nEND_PROGRAM\n")
    assert rc == 1 and "case.st:3:" in err and message in err, err


def test_initial_value_two_is_an_error():
    rc, err = check_text("PROGRAM Main\nVAR b : BOOL := 2; END_VAR\nb := TRUE;\nEND_PROGRAM\n")
    assert rc == 1 and "case.st:2:17: error: initial value does not fit type BOOL" in err
