"""Runtime faults: a controller's major fault, reported at the ST location with task, scan and time."""

from __future__ import annotations

import re

import pytest

import stvm
from core_helpers import cli, load_st, start_st, write_st

FAULT_LINE = re.compile(
    r"^(?P<file>.+?):(?P<line>\d+):(?P<col>\d+): fault: (?P<msg>.+) "
    r"\(task (?P<task>\S+), scan (?P<scan>\d+), t=(?P<t>T#\S+)\)$")


def run_to_fault(source: str, cycles: int = 10, scan: str = "10ms", **kwargs):
    vm = start_st(source, scan=scan, **kwargs)
    with pytest.raises(stvm.RuntimeFault) as info:
        vm.run(cycles=cycles)
    return vm, info.value


def parse_fault(text: str) -> dict:
    first = text.splitlines()[0]
    m = FAULT_LINE.match(first)
    assert m, f"not a fault line: {first!r}"
    return m.groupdict()


FAULT_PROGRAMS = {
    "div_zero": ("""
PROGRAM Main
VAR n, z, q : INT; END_VAR
n := n + 1;
IF n = 3 THEN
  q := 10 / z;
END_IF;
END_PROGRAM""", 6, "division by zero"),
    "mod_zero": ("""
PROGRAM Main
VAR n : INT; z : DINT; q : DINT; END_VAR
n := n + 1;
IF n = 3 THEN
  q := 10 MOD z;
END_IF;
END_PROGRAM""", 6, "division by zero"),
    "time_div_zero": ("""
PROGRAM Main
VAR n : INT; z : DINT; t : TIME := T#1s; END_VAR
n := n + 1;
IF n = 3 THEN
  t := t / z;
END_IF;
END_PROGRAM""", 6, "division by zero"),
    "index_write": ("""
PROGRAM Main
VAR n : INT; arr : ARRAY[1..2] OF INT; i : INT; END_VAR
n := n + 1;
i := i + 1;
IF n = 3 THEN
  arr[i] := n;
END_IF;
END_PROGRAM""", 7, "out of bounds"),
    "index_read_negative_bounds": ("""
PROGRAM Main
VAR n : INT; arr : ARRAY[-5..-3] OF INT; i : INT := -8; x : INT; END_VAR
n := n + 1;
i := i + 2;
IF n = 3 THEN
  x := arr[i];
END_IF;
END_PROGRAM""", 7, "out of bounds"),
    "index_second_dimension": ("""
PROGRAM Main
VAR n : INT; m : ARRAY[1..2, 1..2] OF INT; j : INT; x : INT; END_VAR
n := n + 1;
j := n;
IF n = 3 THEN
  x := m[1, j];
END_IF;
END_PROGRAM""", 7, "out of bounds"),
}


@pytest.mark.parametrize("name", sorted(FAULT_PROGRAMS))
def test_fault_reports_st_location_task_scan_time(name):
    source, line, words = FAULT_PROGRAMS[name]
    vm, fault = run_to_fault(source)
    text = fault.render(vm.project.sources)
    info = parse_fault(text)
    assert info["file"].endswith(".st")
    assert int(info["line"]) == line and int(info["col"]) >= 1
    assert words in info["msg"]
    assert info["task"] == "DefaultTask"
    # the third scan faulted; the time is that scan's start on the virtual clock
    scan = int(info["scan"])
    assert scan in (2, 3)
    assert info["t"] == "T#20ms"
    # the source line and a caret follow
    lines = text.splitlines()
    assert len(lines) >= 3 and "^" in lines[2]
    # values so far are still readable; the VM stays stopped
    assert vm["Main.n"] == 3
    with pytest.raises(stvm.RuntimeFault):
        vm.scan()
    assert vm["Main.n"] == 3


def test_fault_inside_function_called_from_fb_points_into_the_function():
    source = """
FUNCTION MyDiv : INT
VAR_INPUT a, b : INT; END_VAR
VAR t : INT; END_VAR
t := a;
MyDiv := t
  / b;
END_FUNCTION
FUNCTION_BLOCK FB
VAR_INPUT d : INT; END_VAR
VAR_OUTPUT o : INT; END_VAR
o := MyDiv(10, d);
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : FB; n : INT; END_VAR
n := n + 1;
f(d := 2 - n);
END_PROGRAM"""
    vm, fault = run_to_fault(source)
    assert fault.span is not None
    assert (fault.span.line, fault.span.column) == (6, 1)    # the statement's first line
    assert fault.scan in (1, 2) and fault.now_ns == 10_000_000
    assert vm["Main.f.o"] == 10                              # from the first scan


def test_fault_names_the_configured_task():
    source = """
CONFIGURATION C
  RESOURCE R ON PLC
    TASK Fast (INTERVAL := T#2ms, PRIORITY := 1);
    PROGRAM P WITH Fast : Prog;
  END_RESOURCE
END_CONFIGURATION
PROGRAM Prog
VAR n : INT; arr : ARRAY[0..3] OF INT; END_VAR
n := n + 1;
arr[n] := 1;
END_PROGRAM"""
    vm, fault = run_to_fault(source)
    info = parse_fault(fault.render(vm.project.sources))
    assert info["task"] == "Fast"
    assert int(info["line"]) == 11
    assert info["t"] == "T#6ms"                            # fourth scan at 2 ms


def test_int_div_zero_setting_gives_zero_instead_of_a_fault():
    from stvm.settings import SysmacSettings
    source = """
PROGRAM Main
VAR z : INT; q : INT := 5; m : INT := 5; END_VAR
q := 10 / z; m := 7 MOD z;
END_PROGRAM"""
    vm = load_st(source, settings=SysmacSettings(int_div_zero="zero")).start()
    vm.run(cycles=2)
    assert (vm["Main.q"], vm["Main.m"]) == (0, 0)


def test_real_division_by_zero_is_not_a_fault():
    source = """
PROGRAM Main
VAR z : REAL; q : REAL; lz : LREAL; lq : LREAL; END_VAR
q := 1.0 / z; lq := -1.0 / lz;
END_PROGRAM"""
    vm = start_st(source)
    vm.run(cycles=2)
    assert vm["Main.q"] == float("inf") and vm["Main.lq"] == float("-inf")


def test_cli_fault_exit_3_and_values_still_printed():
    path = write_st(FAULT_PROGRAMS["div_zero"][0], "fault_div.st")
    rc, out, err = cli(["run", path, "--cycles", "6", "--no-cache", "--print", "Main.n", "--print", "Main.q"])
    assert rc == 3
    assert out.splitlines() == ["Main.n = 3", "Main.q = 0"]
    info = parse_fault(err)
    assert info["file"] == str(path) and info["line"] == "6"
    assert "Traceback" not in err


def test_recursion_is_rejected_before_it_can_overflow():
    """IEC 61131-3 forbids recursion; stvm reports it instead of overflowing the stack at run time."""
    source = """
FUNCTION Rec : DINT
VAR_INPUT n : DINT; END_VAR
IF n <= 0 THEN Rec := 0; ELSE Rec := n + Rec(n - 1); END_IF;
END_FUNCTION
PROGRAM Main
VAR x : DINT; END_VAR
x := Rec(100000);
END_PROGRAM"""
    path = write_st(source, "recursion.st")
    rc, out, err = cli(["run", path, "--cycles", "1", "--no-cache"])
    assert rc == 1 and ": error:" in err and "Traceback" not in err
