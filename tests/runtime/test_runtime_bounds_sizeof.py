"""LOWER_BOUND / UPPER_BOUND (IEC 61131-3 ed. 3 6.5.3.2), SIZEOF / XSIZEOF (CODESYS/TwinCAT) and the
numbering of ARRAY[*] parameters (`open_array_bounds`), run and checked as a user would."""

from __future__ import annotations

import functools

import pytest

from core_helpers import SYSMAC, check_text, cli, run_st, write_st

# these tests are about Sysmac behaviour (ARRAY[*] from 0, STRING[n] with the NUL): its dialect
run_st = functools.partial(run_st, settings=SYSMAC)
from stvm.settings import SysmacSettings

SUM_ALL = """
FUNCTION SumAll : DINT
VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
VAR i : DINT; END_VAR
FOR i := LOWER_BOUND(a, 1) TO UPPER_BOUND(a, 1) DO SumAll := SumAll + a[i]; END_FOR;
END_FUNCTION
FUNCTION Bounds : DINT
VAR_INPUT a : ARRAY[*] OF INT; END_VAR
Bounds := LOWER_BOUND(a, 1) * 1000 + UPPER_BOUND(a, 1);
END_FUNCTION
FUNCTION First : INT
VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
First := a[1];
END_FUNCTION
PROGRAM Main
VAR one : ARRAY[1..5] OF INT := [1, 2, 3, 4, 5]; zero : ARRAY[0..2] OF INT := [7, 8, 9];
    m : ARRAY[-2..3, 10..12] OF BOOL;
    s1, s0, b1, b0, f1, f0 : DINT; lo, hi, mlo, mhi : INT; END_VAR
s1 := SumAll(one); s0 := SumAll(zero);
b1 := Bounds(one); b0 := Bounds(zero);
f1 := First(one); f0 := First(zero);
lo := LOWER_BOUND(one, 1); hi := UPPER_BOUND(one, 1);
mlo := LOWER_BOUND(m, 1) * 100 + LOWER_BOUND(m, 2); mhi := UPPER_BOUND(m, 1) * 100 + UPPER_BOUND(m, 2);
END_PROGRAM
"""
NAMES = ["s1", "s0", "b1", "b0", "f1", "f0", "lo", "hi", "mlo", "mhi"]


def test_declared_arrays_have_constant_bounds_and_open_arrays_count_from_zero_on_sysmac():
    values = run_st(SUM_ALL, prints=[f"Main.{v}" for v in NAMES])
    assert values == {"Main.s1": 15, "Main.s0": 24, "Main.b1": 4, "Main.b0": 2,
                      "Main.f1": 2, "Main.f0": 8,            # a[1] is the second element passed
                      "Main.lo": 1, "Main.hi": 5, "Main.mlo": -190, "Main.mhi": 312}


def test_open_array_bounds_actual_keeps_the_arguments_bounds():
    values = run_st(SUM_ALL, prints=[f"Main.{v}" for v in NAMES],
                    settings=SysmacSettings(open_array_bounds="actual"))
    assert values == {"Main.s1": 15, "Main.s0": 24, "Main.b1": 1005, "Main.b0": 2,
                      "Main.f1": 1, "Main.f0": 8,            # a[1] is the argument's own element 1
                      "Main.lo": 1, "Main.hi": 5, "Main.mlo": -190, "Main.mhi": 312}


def test_an_index_outside_the_actual_bounds_faults_at_its_line(tmp_path):
    path = write_st("""
FUNCTION At : INT
VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
VAR_INPUT i : INT; END_VAR
At := a[i];
END_FUNCTION
PROGRAM Main
VAR one : ARRAY[1..3] OF INT; r : INT; END_VAR
r := At(a := one, i := 0);
END_PROGRAM
""", folder=tmp_path)
    rc, _, err = cli(["run", path, "--cycles", "1", "--sysmac", "open_array_bounds=actual"])
    assert rc == 3
    assert f"{path}:5:1: fault: array index 0 out of bounds 1..3" in err


SIZES = """
TYPE Pt : STRUCT x : REAL; b : BOOL; d : LREAL; END_STRUCT; END_TYPE
TYPE Small : STRUCT a, b : BYTE; w : WORD; END_STRUCT; END_TYPE
TYPE Color : (Red, Green); END_TYPE
TYPE Level : USINT (Low, High); END_TYPE
PROGRAM Main
VAR arr : ARRAY[0..4] OF INT; p : Pt; big : ARRAY[1..100] OF LREAL; str : STRING[81];
    pts : ARRAY[1..3] OF Pt; sm : Small; c : Color; lv : Level; t : TIME;
    n_arr, n_p, n_big, n_str, n_pts, n_sm, n_c, n_lv, n_t, n_types : UDINT; x_str : UDINT; tiny : USINT; END_VAR
n_arr := SIZEOF(arr); n_p := SIZEOF(p); n_big := SIZEOF(big); n_str := SIZEOF(str);
n_pts := SIZEOF(pts); n_sm := SIZEOF(sm); n_c := SIZEOF(c); n_lv := SIZEOF(lv); n_t := SIZEOF(t);
n_types := SIZEOF(BOOL) + SIZEOF(DINT) * 10 + SIZEOF(Pt) * 100;
x_str := XSIZEOF(str);
tiny := SIZEOF(sm);
END_PROGRAM
"""


def test_sizeof_counts_bytes_with_natural_alignment():
    names = ["n_arr", "n_p", "n_big", "n_str", "n_pts", "n_sm", "n_c", "n_lv", "n_t", "n_types", "x_str", "tiny"]
    values = run_st(SIZES, prints=[f"Main.{v}" for v in names])
    assert values == {"Main.n_arr": 10,        # the CODESYS manual's own example
                      "Main.n_p": 16,          # REAL at 0, BOOL at 4, LREAL at 8
                      "Main.n_big": 800, "Main.n_str": 81, "Main.n_pts": 48, "Main.n_sm": 4,
                      "Main.n_c": 2, "Main.n_lv": 1, "Main.n_t": 8, "Main.n_types": 1641,
                      "Main.x_str": 81, "Main.tiny": 4}


@pytest.mark.parametrize("line, message", [
    ("i := LOWER_BOUND(arr);", "LOWER_BOUND() takes an array and a constant dimension: LOWER_BOUND(arr, 1)"),
    ("i := UPPER_BOUND(arr, 2);", "the dimension of UPPER_BOUND() must be a constant 1..1"),
    ("i := UPPER_BOUND(i, 1);", "UPPER_BOUND() needs an array; 'i' is INT"),
    ("i := LOWER_BOUND(arr, d);", "the dimension of LOWER_BOUND() must be a constant 1..1"),
    ("i := SIZEOF(fb1);", "SIZEOF() of FB: its size in bytes is not defined here"),
    ("i := SIZEOF(nosuch);", "'nosuch' is not declared"),
    ("i := SIZEOF(arr, 1);", "SIZEOF() takes one variable or type name"),
    ("i := SIZEOF(r);", "SIZEOF() of REF_TO INT: its size in bytes is not defined here"),
    ("s := SIZEOF(big);", "800 is out of range for SINT"),
])
def test_bad_uses_are_diagnostics(line, message):
    rc, err = check_text(f"""FUNCTION_BLOCK FB VAR x : INT; END_VAR END_FUNCTION_BLOCK
PROGRAM Main
VAR arr : ARRAY[1..5] OF INT; i : INT; d : DINT; fb1 : FB; r : REF_TO INT; s : SINT; big : ARRAY[1..100] OF LREAL; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1
    assert "case.st:4:" in err and f"error: {message}" in err, err
    assert "Traceback" not in err


def test_a_user_function_of_the_same_name_wins():
    values = run_st("""
FUNCTION SIZEOF : INT VAR_INPUT x : INT; END_VAR SIZEOF := 42; END_FUNCTION
PROGRAM Main VAR r : INT; END_VAR r := SIZEOF(7); END_PROGRAM
""", prints=["Main.r"])
    assert values == {"Main.r": 42}
