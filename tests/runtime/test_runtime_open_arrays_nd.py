"""Open arrays of several dimensions, `ARRAY[*, *]` in VAR_IN_OUT (IEC 61131-3 ed. 3, 6.5.3.2),
with LOWER_BOUND(a, dim) / UPPER_BOUND(a, dim) numbered per `open_array_bounds`."""

from __future__ import annotations

import functools

import pytest

from core_helpers import SYSMAC, check_text, cli, run_st, write_st

# these tests are about Sysmac behaviour (ARRAY[*] from 0, STRING[n] with the NUL): its dialect
run_st = functools.partial(run_st, settings=SYSMAC)
from stvm.settings import SysmacSettings

SOURCE = """
FUNCTION SumAll : DINT
VAR_IN_OUT m : ARRAY[*, *] OF INT; END_VAR
VAR i, j : DINT; END_VAR
FOR i := LOWER_BOUND(m, 1) TO UPPER_BOUND(m, 1) DO
    FOR j := LOWER_BOUND(m, 2) TO UPPER_BOUND(m, 2) DO
        SumAll := SumAll + m[i, j];
    END_FOR;
END_FOR;
END_FUNCTION

FUNCTION_BLOCK Grid
VAR_IN_OUT cells : ARRAY[*, *] OF INT; END_VAR
VAR_OUTPUT lo1, hi1, lo2, hi2, total : DINT; END_VAR
lo1 := LOWER_BOUND(cells, 1); hi1 := UPPER_BOUND(cells, 1);
lo2 := LOWER_BOUND(cells, 2); hi2 := UPPER_BOUND(cells, 2);
cells[lo1, hi2] := 7;                 (* writes the caller's array *)
total := SumAll(cells);               (* an ARRAY[*, *] passed on *)
END_FUNCTION_BLOCK

PROGRAM Main
VAR g : ARRAY[1..2, 3..5] OF INT := [1, 2, 3, 4, 5, 6]; cube : ARRAY[0..1, 0..1, 0..1] OF INT := [8(1)];
    f : Grid; direct, three : DINT; END_VAR
f(cells := g);
direct := SumAll(g);
three := Corner(cube);
END_PROGRAM

FUNCTION Corner : DINT
VAR_IN_OUT c : ARRAY[*, *, *] OF INT; END_VAR
Corner := c[UPPER_BOUND(c, 1), 0, UPPER_BOUND(c, 3)] + UPPER_BOUND(c, 3);
END_FUNCTION
"""
NAMES = ["f.lo1", "f.hi1", "f.lo2", "f.hi2", "f.total", "direct", "g[1, 5]", "three"]


def test_open_arrays_count_from_zero_on_sysmac():
    values = run_st(SOURCE, prints=[f"Main.{v}" for v in NAMES])
    assert values == {"Main.f.lo1": 0, "Main.f.hi1": 1, "Main.f.lo2": 0, "Main.f.hi2": 2, "Main.f.total": 25,
                      "Main.direct": 25, "Main.g[1, 5]": 7, "Main.three": 2}


def test_open_array_bounds_actual_keeps_each_dimensions_bounds():
    values = run_st(SOURCE, prints=[f"Main.{v}" for v in NAMES],
                    settings=SysmacSettings(open_array_bounds="actual"))
    assert values == {"Main.f.lo1": 1, "Main.f.hi1": 2, "Main.f.lo2": 3, "Main.f.hi2": 5, "Main.f.total": 25,
                      "Main.direct": 25, "Main.g[1, 5]": 7, "Main.three": 2}


def test_the_parameter_prints_as_the_array_passed():
    path = write_st(SOURCE)
    rc, out, err = cli(["run", path, "--cycles", "1", "--print", "Main.f.cells", "--print", "Main.f.cells[0, 2]",
                        "--dialect", "sysmac"])
    assert rc == 0, err
    assert out.splitlines() == ["Main.f.cells = [[1, 2, 7], [4, 5, 6]]", "Main.f.cells[0, 2] = 7"]
    rc, out, err = cli(["run", path, "--cycles", "1", "--print", "Main.f.cells[2, 0]", "--dialect", "sysmac"])
    assert rc == 2 and "stvm: 'Main.f.cells[2, 0]': index 2 outside 0..1" in err and "Traceback" not in err


def test_an_index_outside_the_passed_bounds_faults_at_its_line():
    path = write_st("""FUNCTION Get : INT
VAR_IN_OUT m : ARRAY[*, *] OF INT; END_VAR
Get := m[0, 3];
END_FUNCTION
PROGRAM Main
VAR g : ARRAY[0..1, 0..2] OF INT; x : INT; END_VAR
x := Get(g);
END_PROGRAM
""")
    rc, _, err = cli(["run", path, "--cycles", "1"])
    assert rc == 3 and ":3:" in err and "fault" in err and "Traceback" not in err, err


@pytest.mark.parametrize("line, message", [
    ("x := F(m := one);", "'m' of F needs ARRAY[*, *] OF INT, got ARRAY[0..3] OF INT"),
    ("x := F(m := r);", "'m' of F needs ARRAY[*, *] OF INT, got ARRAY[0..1,0..1] OF REAL"),
    ("x := F(m := cube);", "'m' of F needs ARRAY[*, *] OF INT, got ARRAY[0..1,0..1,0..1] OF INT"),
    ("x := F(m := two[0]);", "needs 2 index(es), got 1"),
])
def test_passing_the_wrong_shape_is_an_error(line, message):
    rc, err = check_text(f"""FUNCTION F : DINT
VAR_IN_OUT m : ARRAY[*, *] OF INT; END_VAR
F := m[0, 0];
END_FUNCTION
PROGRAM Main
VAR one : ARRAY[0..3] OF INT; two : ARRAY[0..1, 0..1] OF INT; r : ARRAY[0..1, 0..1] OF REAL;
    cube : ARRAY[0..1, 0..1, 0..1] OF INT; x : DINT; END_VAR
{line}
END_PROGRAM
""")
    assert rc == 1 and ":8:" in err and message in err, err


@pytest.mark.parametrize("body, message", [
    ("F := m[1];", "3:6: error: an ARRAY[*, *] parameter takes 2 index(es), got 1"),
    ("F := LOWER_BOUND(m, 3);", "3:21: error: the dimension of LOWER_BOUND() must be a constant 1..2"),
])
def test_bad_uses_inside_are_errors(body, message):
    rc, err = check_text(f"""FUNCTION F : DINT
VAR_IN_OUT m : ARRAY[*, *] OF INT; END_VAR
{body}
END_FUNCTION
""")
    assert rc == 1 and message in err, err


def test_mixed_open_and_fixed_dimensions_are_an_error():
    rc, err = check_text("""FUNCTION F : DINT
VAR_IN_OUT m : ARRAY[*, 1..2] OF INT; END_VAR
END_FUNCTION
""")
    assert rc == 1 and "2:16: error: an open array has '*' for every dimension: ARRAY[*, *]" in err, err
