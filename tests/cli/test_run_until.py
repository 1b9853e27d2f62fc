"""`stvm run --until EXPR` (stop after the first scan in which an ST boolean expression holds) and
the demo's cycle count from the manifest (`[demo] cycles`, and the flag `cycles_flag` declares)."""

from __future__ import annotations

import pytest

from core_helpers import assert_no_traceback, cli, write_files, write_st

PROGRAM = """
TYPE Color : (Red, Green, Blue); END_TYPE
PROGRAM Main
VAR
    n : INT;
    r : REAL;
    c : Color;
    s : STRING[10];
    t : TIME;
    b : BOOL;
    arr : ARRAY[1..3] OF INT;
END_VAR
n := n + 1;
r := r + 0.1;
t := t + T#1ms;
arr[2] := n * 2;
IF n = 5 THEN c := Color#Blue; s := 'five'; END_IF;
b := n > 7;
END_PROGRAM
"""


@pytest.fixture(scope="module")
def main_st():
    return write_st(PROGRAM, "main.st")


@pytest.mark.parametrize("expr, scans", [
    ("Main.n = 26", 26),
    ("Main.n >= 3 AND Main.n <> 4", 3),
    ("Main.c = Color#Blue", 5),
    ("Main.c = Blue", 5),                      # a bare enumerator of the compared variable's type
    ("Main.s = 'five'", 5),
    ("Main.t >= T#12ms", 12),
    ("Main.b", 8),                             # a BOOL variable alone
    ("NOT Main.b AND (Main.n > 3 OR Main.n = 1)", 1),
    ("Main.r > 1.0", 10),                      # REAL accumulates in binary32: 10 x 0.1 > 1.0
    ("Main.n > 2 XOR Main.n > 4", 3),
    ("Main.arr[2] = 8", 4),
    ("26 = Main.n", 26),                       # the literal may stand on either side
    ("Main.n = -1 OR Main.n = 2", 2),
])
def test_the_run_stops_after_the_first_scan_in_which_the_expression_holds(main_st, expr, scans):
    rc, out, err = cli(["run", main_st, "--cycles", "100", "--until", expr, "--print", "Main.n"])
    assert rc == 0, err
    assert out == f"Main.n = {scans}\n"
    assert f"--until {expr}: TRUE after scan {scans}" in err


def test_cycles_still_bound_a_run_whose_condition_never_holds(main_st):
    rc, out, err = cli(["run", main_st, "--cycles", "20", "--until", "Main.n = 1000", "--print", "Main.n"])
    assert rc == 0, err
    assert out == "Main.n = 20\n"
    assert "--until" not in err


@pytest.mark.parametrize("expr, message", [
    ("Main.n", "the expression is INT, not BOOL"),
    ("Main.x = 1", "Main has no variable 'x'"),
    ("Main.n = 100000", "100000 is out of range for INT"),
    ("Main.n = T#1s", "a TIME literal cannot be compared with INT"),
    ("Main.t = 5", "5 cannot be compared with TIME (write a duration as T#5ms)"),
    ("Main.b = 2", "2 cannot be compared with BOOL"),   # (0 and 1 are BOOL literals)
    ("Main.n = 1.5", "1.5 is a REAL literal and INT holds whole numbers"),
    ("Main.s = 5", "5 cannot be compared with STRING[10]"),
    ("Main.c = Purple", "Purple is not a value of Color"),
    ("Main.n + 1 = 3", "only variables, literals, comparisons"),
    ("Main.n AND Main.b", "AND needs BOOL operands here, got INT and BOOL"),
    ("Main.n = Main.s", "INT and STRING[10] cannot be compared"),
    ("Main.n +", "--until 'Main.n +': unexpected end of file"),
    ("", "--until '':"),
])
def test_a_bad_expression_is_a_usage_error_before_the_first_scan(main_st, expr, message):
    rc, out, err = cli(["run", main_st, "--cycles", "5", "--until", expr, "--print", "Main.n"])
    assert rc == 2, err
    assert out == ""                     # nothing ran, nothing printed
    assert message in err
    assert err.startswith(f"stvm: error: --until {expr!r}: ")
    assert_no_traceback(err)


DEMO_PROGRAM = """
PROGRAM Main
VAR
    step : INT;
END_VAR
step := step + 1;
IF step > 3 THEN step := 1; END_IF;
END_PROGRAM
"""


def _demo_project(demo_table: str):
    files = write_files({"main.st": DEMO_PROGRAM, "stvm.toml": (
        '[project]\nfiles = ["main.st"]\n\n[demo]\nstep_variable = "Main.step"\ncycle_from = 3\n'
        f'cycle_to = 1\n{demo_table}')})
    return files[0].parent


def test_the_manifest_sets_the_demo_cycle_count():
    folder = _demo_project("cycles = 2\n")
    rc, out, err = cli(["run", folder, "--scan", "1ms", "--virtual-clock", "--cycles", "100", "--print", "Main.step"])
    assert rc == 0, err
    # cycles end on 3 -> 1: after scans 4 and 7
    assert "PnP cycles completed: 2;" in err and "scans 7;" in err
    assert out.endswith("Main.step = 1\n")     # after the status line of the demo


def test_the_declared_flag_sets_the_count_and_only_that_project_has_it():
    folder = _demo_project('cycles = 2\ncycles_flag = "--rounds"\n')
    for argv in (["--rounds", "1"], ["--rounds=1"]):
        rc, out, err = cli(["run", folder, "--scan", "1ms", "--virtual-clock", "--cycles", "100", *argv])
        assert rc == 0, err
        assert "PnP cycles completed: 1;" in err and "scans 4;" in err
    rc, out, err = cli(["run", "--rounds", "0", folder, "--scan", "1ms", "--virtual-clock", "--cycles", "30"])
    assert rc == 0, err
    assert "PnP cycles completed: 9;" in err          # 0: no limit, --cycles ends the run
    rc, _, err = cli(["run", folder, "--virtual-clock", "--cycles", "5", "--rounds", "x"])
    assert rc == 2 and "--rounds needs a number of cycles, got 'x'" in err
    rc, _, err = cli(["run", folder, "--no-demo", "--cycles", "5", "--rounds", "1"])
    assert rc == 2 and "--rounds cannot be combined with --no-demo" in err
    # a project that declares no flag: argparse does not know it
    other = write_st(DEMO_PROGRAM, "plain.st")
    rc, _, err = cli(["run", other, "--cycles", "5", "--rounds", "1"])
    assert rc == 2 and "unrecognized arguments: --rounds 1" in err
    # and stvm run itself has no demo-specific count
    rc, _, err = cli(["run", other, "--cycles", "5", "--pnp-cycles", "1"])
    assert rc == 2 and "unrecognized arguments: --pnp-cycles 1" in err


def test_a_bad_cycles_entry_is_a_manifest_error():
    folder = _demo_project('cycles_flag = "pnp"\n')
    rc, _, err = cli(["run", folder, "--cycles", "1"])
    assert rc == 2
    assert "[demo] cycles_flag must be a command-line flag" in err
    folder = _demo_project("cycles = -1\n")
    rc, _, err = cli(["run", folder, "--cycles", "1"])
    assert rc == 2 and "[demo] cycles must be a number of complete cycles" in err
