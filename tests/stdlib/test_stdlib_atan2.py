"""ATAN2(Y, X) (CODESYS): the angle of (X, Y), -pi..pi, in the arguments' REAL type."""

from __future__ import annotations

import math

import numpy as np

from core_helpers import check_text, run_st


def test_atan2_quadrants_and_types():
    values = run_st("""PROGRAM Main
VAR a, b, c : LREAL; r : REAL; z : LREAL; y : REAL := 1.0; x : REAL := -1.0; END_VAR
a := ATAN2(LREAL#1.0, LREAL#1.0);
b := ATAN2(Y := LREAL#-1.0, X := LREAL#-1.0);
c := ATAN2(LREAL#0.0, LREAL#-1.0);
r := ATAN2(y, x);
z := ATAN2(LREAL#0.0, LREAL#0.0);
END_PROGRAM
""", prints=["Main.a", "Main.b", "Main.c", "Main.r", "Main.z"])
    assert values["Main.a"] == math.pi / 4
    assert values["Main.b"] == -3 * math.pi / 4
    assert values["Main.c"] == math.pi
    assert values["Main.r"] == float(np.float32(3 * math.pi / 4))
    assert values["Main.z"] == 0.0


def test_atan2_needs_reals():
    rc, err = check_text("PROGRAM Main\nVAR i : INT; r : REAL; END_VAR\nr := ATAN2(i, r);\nEND_PROGRAM\n")
    assert rc == 1 and "case.st:3:" in err and "needs ANY_REAL, got INT" in err
