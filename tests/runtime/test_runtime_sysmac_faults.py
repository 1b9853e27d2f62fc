"""The Sysmac settings that decide between a fault and going on (sysmac.md 1, 2):
`int_div_zero`, `string_overflow` and `array_oob`, each under every value, at every place the
code can meet it (operators, stdlib functions, TIME arithmetic, constants, run-time values,
FB/function pins, ARRAY[*] parameters, compound statements)."""

from __future__ import annotations

import pytest

import stvm
from core_helpers import cli, load_st, write_st
from stvm.settings import ArrayOob, IntDivZero, StringOverflow, SysmacSettings


def run(source: str, cycles: int = 1, **settings):
    vm = load_st(source, settings=SysmacSettings(**{"dialect": "sysmac", **settings})).start()
    vm.run(cycles=cycles)
    return vm


def fault_of(source: str, **settings) -> stvm.RuntimeFault:
    vm = load_st(source, settings=SysmacSettings(**{"dialect": "sysmac", **settings})).start()
    with pytest.raises(stvm.RuntimeFault) as info:
        vm.run(cycles=2)
    return info.value


# ---- int_div_zero: one meaning for `/`, MOD, DIV(), TIME / INT, TIME / REAL and DIV_TIME -------

DIVISIONS = {
    "int_slash": ("q := a / b;", "Main.q", 0),
    "int_mod": ("q := a MOD b;", "Main.q", 0),
    "div_function": ("q := DIV(a, b);", "Main.q", 0),
    "dint_slash": ("l := la / lb;", "Main.l", 0),
    "time_by_int": ("tq := t / b;", "Main.tq", 0),
    "time_by_real": ("tq := t / r;", "Main.tq", 0),
    "div_time": ("tq := DIV_TIME(t, r);", "Main.tq", 0),
}
DIVISION_PROGRAM = """
PROGRAM Main
VAR
    a : INT := 7; b : INT := 0; q : INT := 5;
    la : DINT := 70000; lb : DINT; l : DINT := 5;
    t : TIME := T#1s; tq : TIME := T#5s; r : REAL := 0.0;
END_VAR
{statement}
END_PROGRAM
"""


@pytest.mark.parametrize("case", list(DIVISIONS))
def test_int_div_zero_fault_everywhere(case):
    statement = DIVISIONS[case][0]
    fault = fault_of(DIVISION_PROGRAM.format(statement=statement), int_div_zero=IntDivZero.FAULT)
    assert "by zero" in fault.message
    assert fault.span is not None and fault.span.line == 8


@pytest.mark.parametrize("case", list(DIVISIONS))
def test_int_div_zero_zero_everywhere(case):
    statement, path, expected = DIVISIONS[case]
    vm = run(DIVISION_PROGRAM.format(statement=statement), int_div_zero="zero")
    assert vm[path] == expected


def test_time_divisions_by_nonzero_are_unchanged():
    vm = run(DIVISION_PROGRAM.format(statement="b := 4; r := 4.0; tq := t / b; l := DINT#0; tq := tq + t / r;"))
    assert vm["Main.tq"] == 500_000_000


def test_a_misspelt_int_div_zero_is_a_usage_error_not_a_silent_zero():
    # the example: `zeroo` used to make `a / b` return 0 while DIV(a, b) faulted
    path = write_st(DIVISION_PROGRAM.format(statement="q := a / b; q := DIV(a, b);"))
    rc, out, err = cli(["run", path, "--dialect", "sysmac", "--cycles", "1", "--no-cache", "--sysmac", "int_div_zero=zeroo"])
    assert rc == 2
    assert "int_div_zero: 'zeroo' is not allowed; allowed: fault (default), zero" in err
    with pytest.raises(ValueError, match="allowed: fault"):
        SysmacSettings(int_div_zero="zeroo")


# ---- string_overflow -----------------------------------------------------------------------------

CONSTANT_OVERFLOW = """
PROGRAM Main
VAR s : STRING[4]; n : INT; END_VAR
s := 'toolongliteral';
n := n + 1;
END_PROGRAM
"""

RUNTIME_OVERFLOW = """
FUNCTION Short : STRING[4]
VAR_INPUT text : STRING[3]; END_VAR
Short := CONCAT(text, 'xyz');
END_FUNCTION
FUNCTION_BLOCK Keeper
VAR_INPUT pin : STRING[3]; END_VAR
VAR_OUTPUT out : STRING[20]; END_VAR
out := CONCAT(pin, '-done');
END_FUNCTION_BLOCK
PROGRAM Main
VAR
    long : STRING[20] := 'abcdefghij';
    s : STRING[4]; p : STRING[4]; f : STRING[20]; o : STRING[4];
    k : Keeper; n : INT;
END_VAR
s := long;
f := Short(long);
k(pin := long, out => o);
n := n + 1;
END_PROGRAM
"""


def test_constant_overflow_warns_at_check_time_and_truncates():
    path = write_st(CONSTANT_OVERFLOW)
    rc, out, err = cli(["check", path, "--dialect", "sysmac"])
    assert rc == 0
    assert f"{path}:4:6: warning: a string of 14 bytes is truncated to the 3 bytes of STRING[4]" in err
    vm = run(CONSTANT_OVERFLOW, cycles=2)
    assert vm["Main.s"] == b"too"


def test_constant_overflow_is_a_check_time_error_under_error():
    path = write_st(CONSTANT_OVERFLOW)
    rc, out, err = cli(["check", path, "--dialect", "sysmac", "--sysmac", "string_overflow=error"])
    assert rc == 1
    assert f"{path}:4:6: error: a string of 14 bytes does not fit STRING[4] (3 bytes; string_overflow=error)" in err
    assert "s := 'toolongliteral';" in err     # with the source excerpt


def test_initial_value_overflow_follows_the_setting():
    source = "PROGRAM Main\nVAR s : STRING[4] := 'initial'; END_VAR\nEND_PROGRAM\n"
    path = write_st(source)
    rc, _, err = cli(["check", path, "--dialect", "sysmac"])
    assert rc == 0 and f"{path}:2:22: warning: initial value truncated to 3 bytes of STRING[4]" in err
    rc, _, err = cli(["check", path, "--dialect", "sysmac", "--sysmac", "string_overflow=error"])
    assert rc == 1 and f"{path}:2:22: error: a string of 7 bytes does not fit STRING[4]" in err


def test_runtime_overflow_truncates_with_one_warning_per_site():
    path = write_st(RUNTIME_OVERFLOW)
    rc, out, err = cli(["run", path, "--dialect", "sysmac", "--cycles", "3", "--no-cache", "--print", "Main.s", "--print", "Main.f",
                        "--print", "Main.o"])
    assert rc == 0, err
    # STRING[3] pins keep 'ab'; the function's STRING[4] result 'abxyz' becomes 'abx'
    assert out.splitlines() == ["Main.s = 'abc'", "Main.f = 'abx'", "Main.o = 'ab-'"]
    warnings = [line for line in err.splitlines() if "warning:" in line]
    # sites: s := long (17:6); the function's input (18:12) and result (4:10); the FB pin
    # (19:10) and its output bound with => (19:23): each once, though the program ran 3 scans
    assert sorted(w.split(": warning:")[0].rsplit(":", 2)[1:] for w in warnings) == sorted(
        [["17", "6"], ["18", "12"], ["4", "10"], ["19", "10"], ["19", "23"]]), err
    assert all(w.startswith(f"{path}:") and "string_overflow=truncate_warn" in w for w in warnings)


def test_runtime_overflow_faults_under_error():
    fault = fault_of(RUNTIME_OVERFLOW, string_overflow=StringOverflow.ERROR)
    assert fault.message == "a string of 10 bytes does not fit STRING[4] (3 bytes; string_overflow=error)"
    assert (fault.span.line, fault.span.column) == (17, 1)


def test_fitting_runtime_strings_never_warn_or_fault():
    source = RUNTIME_OVERFLOW.replace("'abcdefghij'", "'a'").replace("'xyz'", "'y'").replace("'-done'", "'-'")
    path = write_st(source)
    for value in ("truncate_warn", "error"):
        rc, out, err = cli(["run", path, "--dialect", "sysmac", "--cycles", "2", "--no-cache", "--sysmac", f"string_overflow={value}",
                            "--print", "Main.f"])
        assert (rc, out, err) == (0, "Main.f = 'ay'\n", "")


def test_external_writes_follow_string_overflow(capsys):
    source = "PROGRAM Main\nVAR s : STRING[4]; END_VAR\nEND_PROGRAM\n"
    vm = run(source)
    vm["Main.s"] = "abcdefg"
    assert vm["Main.s"] == b"abc"
    assert "Main.s: a string of 7 bytes is truncated to the 3 bytes of STRING[4]" in capsys.readouterr().err
    strict = run(source, string_overflow="error")
    with pytest.raises(ValueError, match="does not fit STRING"):
        strict["Main.s"] = "abcdefg"
    assert strict["Main.s"] == b""


# ---- array_oob -------------------------------------------------------------------------------------

OOB_PROGRAM = """
FUNCTION Pick : INT
VAR_IN_OUT data : ARRAY[*] OF INT; END_VAR
VAR_INPUT at : INT; END_VAR
Pick := data[at];
END_FUNCTION
PROGRAM Main
VAR
    a : ARRAY[0..3] OF INT := [1, 2, 3, 4];
    i : INT := 7; n : INT; x : INT := -1; y : INT := -1; z : INT := -1; w : INT := -1;
END_VAR
n := n + 1;
a[i] := 5;
x := a[i];
IF a[i] > 0 THEN y := 100; END_IF;
z := Pick(data := a, at := i);
w := Pick(data := a, at := 2);
END_PROGRAM
"""


def test_array_oob_fault_by_default():
    fault = fault_of(OOB_PROGRAM)
    assert fault.message == "array index 7 out of bounds 0..3"
    assert (fault.span.line, fault.scan) == (13, 0)


def test_array_oob_fault_in_an_array_star_parameter():
    fault = fault_of(OOB_PROGRAM.replace("a[i] := 5;\nx := a[i];\nIF a[i] > 0 THEN y := 100; END_IF;\n", ""),
                     array_oob=ArrayOob.FAULT)
    assert fault.message == "array index 7 out of bounds 0..3"
    assert fault.span.line == 5                  # inside the function, on the ARRAY[*] access


def test_array_oob_skip_statement_skips_each_bad_statement_and_warns_once():
    path = write_st(OOB_PROGRAM)
    rc, out, err = cli(["run", path, "--dialect", "sysmac", "--cycles", "3", "--no-cache", "--sysmac", "array_oob=skip_statement",
                        "--print", "Main.n", "--print", "Main.a", "--print", "Main.x", "--print", "Main.y",
                        "--print", "Main.z", "--print", "Main.w"])
    assert rc == 0, err
    assert out.splitlines() == ["Main.n = 3", "Main.a = [1, 2, 3, 4]", "Main.x = -1", "Main.y = -1",
                                "Main.z = 0", "Main.w = 3"]   # Pick's only statement skipped: result 0
    warnings = [line for line in err.splitlines() if "warning:" in line]
    assert [w.split(": warning:")[0] for w in warnings] == [f"{path}:13:1", f"{path}:14:1", f"{path}:15:1",
                                                            f"{path}:5:1"], err
    assert all("array index 7 out of bounds 0..3: statement skipped (array_oob=skip_statement" in w
               for w in warnings)


def test_array_oob_skip_inside_a_loop_skips_only_the_bad_iterations():
    source = """
PROGRAM Main
VAR a : ARRAY[1..3] OF INT; i : INT; sum : INT; END_VAR
FOR i := 0 TO 4 DO
    a[i] := i * 10;
    sum := sum + 1;
END_FOR;
END_PROGRAM
"""
    vm = run(source, array_oob="skip_statement")
    assert (vm["Main.a"], vm["Main.sum"]) == ([10, 20, 30], 5)
    with pytest.raises(stvm.RuntimeFault, match="array index 0 out of bounds 1..3"):
        run(source)


def test_array_oob_skip_statement_leaves_default_code_alone():
    # the skip wrapping is only generated under the alternative: the default build is unchanged
    default = load_st(OOB_PROGRAM).lowered.source
    skipping = load_st(OOB_PROGRAM, settings=SysmacSettings(array_oob="skip_statement")).lowered.source
    assert "_ArrayIndexError" not in default and "_oob_skipped" in skipping
