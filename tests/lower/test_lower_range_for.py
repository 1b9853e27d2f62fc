"""Range-FOR loops with constant bounds (stvm/lower/gen_stmt.py range_for): the hoisted bounds
check and the wrap-around guard are decided while lowering, so only the loop copy that can run is
emitted. Each program runs with `hoist_bounds` on and off: same values, same fault."""

from __future__ import annotations

import re

import pytest

import stvm
from core_helpers import load_st
from stvm.lower.options import DEFAULT_OPTIONS
from test_lower_scan_options import load_with

LOOP = """
PROGRAM Main
VAR a : ARRAY[0..9] OF INT; total : DINT; i : INT; n : INT := {n}; END_VAR
FOR i := {start} TO {end} BY {step} DO
  a[i] := a[i] + i; total := total + a[i];
END_FOR;
total := total + i;
END_PROGRAM
"""


def loops_in(code: str) -> int:
    return len(re.findall(r"^\s+for v_i in _range", code, re.M))


def run(source: str, options, scans: int = 3):
    vm = load_with(source, options).start(scan="10ms")
    fault = None
    try:
        vm.run(cycles=scans)
    except stvm.RuntimeFault as exc:
        fault = str(exc)
    return {p: vm[p] for p in ("Main.total", "Main.i", "Main.a")}, fault


@pytest.mark.parametrize("start, end, step, copies, checked", [
    ("0", "9", "1", 1, False),        # inside the array: one unchecked copy
    ("9", "0", "-1", 1, False),
    ("2", "5", "2", 1, False),
    ("0", "10", "1", 1, True),        # passes the end: one checked copy, faults at i = 10
    ("-1", "3", "1", 1, True),
    ("5", "2", "1", 1, False),        # empty: the hoisted test holds, nothing runs
    ("0", "n", "1", 2, None),         # a variable bound: both copies, chosen at run time
])
def test_constant_bounds_emit_one_copy_and_behave_the_same(start, end, step, copies, checked):
    source = LOOP.format(start=start, end=end, step=step, n=9)
    code = load_with(source, DEFAULT_OPTIONS).lowered.source
    body = code[code.index("class P"):]
    assert loops_in(body) == copies
    if checked is not None:
        assert ("_oob(" in body) is checked
        assert "_endless_for(" not in body    # a constant end can never wrap an INT
    on, off = run(source, DEFAULT_OPTIONS), run(source, DEFAULT_OPTIONS.without("hoist_bounds"))
    assert on == off
    assert (on[1] is not None) == bool(checked)


def test_a_constant_end_at_the_types_limit_still_reports_the_endless_loop():
    source = """
PROGRAM Main
VAR i : SINT; n : INT; END_VAR
FOR i := 0 TO 127 DO n := n + 1; END_FOR;
END_PROGRAM
"""
    code = load_st(source).lowered.source
    assert "_endless_for(" in code
    with pytest.raises(stvm.RuntimeFault):
        load_st(source).start(scan="10ms").run(cycles=1)
