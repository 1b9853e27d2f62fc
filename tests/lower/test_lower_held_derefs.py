"""`hold_derefs_in_loops` (stvm/lower/options.py, issue 11): a loop that only touches Python locals and
one reference's scalar target keeps `r^` in a local. Each program runs with the option on and off:
the same values scan by scan, the same faults at the same ST lines; the plan refuses the loops in
which something else could read or write the target."""

from __future__ import annotations

import re

import pytest

import stvm
from core_helpers import write_st
from stvm.lower.analysis import plan_project
from stvm.lower.options import DEFAULT_OPTIONS
from stvm.project import check, project_settings
from test_lower_scan_options import load_with, run_both

OPTION = "hold_derefs_in_loops"

SWITCHING = """
PROGRAM Main
VAR a : DINT; arr : ARRAY[1..3] OF DINT; n : INT; i : INT; r : REF_TO DINT; pi : POINTER TO DINT;
    bits : WORD; rw : REF_TO WORD; END_VAR
n := n + 1;
IF n MOD 2 = 0 THEN r := REF(a); ELSE r := REF(arr[2]); END_IF;
FOR i := 1 TO 10 DO
    r^ := r^ + i;
    IF r^ > 100 THEN r^ := r^ - 100; END_IF;
END_FOR;
pi := ADR(arr[3]);
WHILE pi^ < n * 5 DO pi^ := pi^ + 2; END_WHILE;
rw := REF(bits);
REPEAT rw^.3 := NOT rw^.3; i := i - 1; UNTIL i < 5 END_REPEAT;
END_PROGRAM
"""


def test_loops_hold_the_target_and_compute_the_same():
    paths = ["Main.a", "Main.arr[2]", "Main.arr[3]", "Main.bits", "Main.i"]
    on, off, seen = run_both(SWITCHING, OPTION, 6, lambda k: {}, paths)
    assert on.count("_held") > 0 and "_held" not in off
    assert seen[-1]["Main.a"] != 0 and seen[-1]["Main.arr[2]"] != 0 and seen[-1]["Main.arr[3]"] >= 30


EXITS = """
FUNCTION Sum : DINT
VAR_INPUT r : REF_TO DINT; n : INT; END_VAR
VAR i : INT; END_VAR
FOR i := 1 TO 20 DO
    r^ := r^ + i;
    IF i = n THEN RETURN; END_IF;
END_FOR;
Sum := r^;
END_FUNCTION
PROGRAM Main
VAR a : DINT; b : DINT; k : INT; res : DINT; r : REF_TO DINT; END_VAR
r := REF(b);
k := 0;
WHILE TRUE DO
    r^ := r^ + 1;
    k := k + 1;
    IF k >= 3 THEN EXIT; END_IF;
END_WHILE;
res := Sum(REF(a), 4);
END_PROGRAM
"""


def test_exit_and_return_leave_the_target_written():
    on, _, seen = run_both(EXITS, OPTION, 2, lambda k: {}, ["Main.a", "Main.b", "Main.res"])
    assert "_held" in on
    assert seen == [{"Main.a": 10, "Main.b": 3, "Main.res": 0}, {"Main.a": 20, "Main.b": 6, "Main.res": 0}]


NULL_IN_LOOP = """
PROGRAM Main
VAR r : REF_TO DINT; i : INT; n : INT; x : DINT; END_VAR
FOR i := 1 TO n DO
    x := x + i;
    r^ := x;
END_FOR;
n := 2;
END_PROGRAM
"""


@pytest.mark.parametrize("options", [DEFAULT_OPTIONS, DEFAULT_OPTIONS.without(OPTION)], ids=["on", "off"])
def test_null_reference_faults_at_its_line_only_when_the_loop_runs(options):
    vm = load_with(NULL_IN_LOOP, options).start(scan="10ms")
    vm.scan()   # no iteration: a NULL reference is never dereferenced
    with pytest.raises(stvm.RuntimeFault) as info:
        vm.scan()
    assert info.value.message == "dereference of a NULL reference"
    assert info.value.span.line == 6 and vm["Main.x"] == 1


FAULT_MID_LOOP = """
PROGRAM Main
VAR a : DINT; r : REF_TO DINT; i : INT; d : DINT := 3; q : DINT; END_VAR
r := REF(a);
FOR i := 1 TO 10 DO
    r^ := r^ + 1;
    d := d - 1;
    q := 10 / d;
END_FOR;
END_PROGRAM
"""


@pytest.mark.parametrize("options", [DEFAULT_OPTIONS, DEFAULT_OPTIONS.without(OPTION)], ids=["on", "off"])
def test_a_fault_inside_the_loop_sees_the_target_as_written(options):
    vm = load_with(FAULT_MID_LOOP, options).start(scan="10ms")
    with pytest.raises(stvm.RuntimeFault) as info:
        vm.scan()
    assert info.value.span.line == 8
    assert vm["Main.a"] == 3


NOT_HELD = """
TYPE Pt : STRUCT x : DINT; END_STRUCT; END_TYPE
FUNCTION Id : DINT
VAR_INPUT v : DINT; END_VAR
Id := v;
END_FUNCTION
PROGRAM Main
VAR a, b : DINT; p : Pt; arr : ARRAY[1..2] OF DINT; i : INT; r, r2 : REF_TO DINT; rp : REF_TO Pt; END_VAR
r := REF(p.x); r2 := REF(a); rp := REF(p);
FOR i := 1 TO 2 DO r^ := r^ + 1; p.x := p.x + 1; END_FOR;      (* held; p.x is r^: run time *)
FOR i := 1 TO 2 DO r^ := r^ + 1; rp^.x := rp^.x + 1; END_FOR;  (* held; rp^.x is r^: run time *)
FOR i := 1 TO 2 DO r^ := r^ + 1; r2^ := r2^ + 1; END_FOR;      (* two references *)
FOR i := 1 TO 2 DO r^ := Id(r^); END_FOR;                      (* a call *)
FOR i := 1 TO 2 DO r^ := r^ + arr[i]; END_FOR;                 (* held; checked at run time *)
FOR i := 1 TO 2 DO r^ := r^ + 1; r := REF(a); END_FOR;         (* r changes *)
FOR i := 1 TO 2 DO r^ := r^ + 1; b := a; END_FOR;              (* a is referenced: not a local *)
FOR i := 1 TO 2 DO r2^ := r2^ + i; END_FOR;                    (* held *)
END_PROGRAM
"""


def test_the_plan_refuses_loops_where_the_target_may_be_reached_otherwise():
    path = write_st(NOT_HELD)
    settings = project_settings([path])
    analysis, diags, _ = check([path], settings, use_cache=False)
    assert analysis is not None, diags
    fors = [s for s in analysis.pou_nodes["main"].body if s.__class__.__name__ == "For"]
    held = plan_project(analysis, settings, DEFAULT_OPTIONS).held_derefs
    assert [s.nid in held for s in fors] == [True, True, False, False, True, False, False, True]
    assert [b.__class__.__name__ for b in held[fors[0].nid].bases] == ["Name"]
    assert held[fors[-1].nid].ref.key == "r2" and held[fors[-1].nid].written
    assert [b.__class__.__name__ for b in held[fors[1].nid].bases] == ["Deref"]
    assert not plan_project(analysis, settings, DEFAULT_OPTIONS.without(OPTION)).held_derefs
    assert not plan_project(analysis, settings, DEFAULT_OPTIONS.without("cache_locals")).held_derefs
    paths = ["Main.a", "Main.b", "Main.p.x"]
    run_both(NOT_HELD, OPTION, 2, lambda k: {}, paths)


FIELDS = """
TYPE In : STRUCT x : DINT; y : DINT; END_STRUCT; END_TYPE
TYPE Pt : STRUCT x : DINT; q : In; END_STRUCT; END_TYPE
FUNCTION_BLOCK Acc
VAR_INPUT step : DINT; END_VAR
VAR_OUTPUT total : DINT; END_VAR
total := total + step;
END_FUNCTION_BLOCK
PROGRAM Main
VAR a, seen : DINT; p, p2 : Pt; acc : Acc; n, i : INT; r : REF_TO DINT; rp : REF_TO Pt; END_VAR
n := n + 1;
CASE n MOD 5 OF
  0: r := REF(a);
  1: r := REF(p.x);
  2: r := REF(p.q.x);
  3: r := REF(acc.total); acc(step := 2);
  4: r := REF(p2.q.y);
END_CASE;
IF n MOD 3 = 0 THEN rp := REF(p); ELSE rp := REF(p2); END_IF;
FOR i := 1 TO 4 DO
    r^ := r^ + i;
    p.x := p.x + r^;
    p.q.x := p.q.x + 1;
    rp^.x := rp^.x - 1;
    seen := seen + acc.total + r^;
END_FOR;
END_PROGRAM
"""


def test_fields_in_the_loop_are_checked_against_the_target_at_run_time():
    paths = ["Main.a", "Main.p.x", "Main.p.q.x", "Main.p2.x", "Main.p2.q.y", "Main.acc.total", "Main.seen"]
    on, off, seen = run_both(FIELDS, OPTION, 12, lambda k: {}, paths)
    assert re.search(r"_ref\d+\.obj is not self\.v_acc and _ref\d+\.obj is not v_rp", on) and "_held" not in off
    assert seen[-1]["Main.acc.total"] != 0 and seen[-1]["Main.p.x"] != 0


def planned(source: str):
    path = write_st(source)
    settings = project_settings([path])
    analysis, diags, _ = check([path], settings, use_cache=False)
    assert analysis is not None, diags
    fors = [s for s in analysis.pou_nodes["main"].body if s.__class__.__name__ == "For"]
    held = plan_project(analysis, settings, DEFAULT_OPTIONS).held_derefs
    return [s.nid in held for s in fors]


def test_fields_that_cannot_be_named_before_the_loop_or_whole_aggregates_are_refused():
    src = """
TYPE In : STRUCT x : DINT; END_STRUCT; END_TYPE
TYPE Pt : STRUCT x : DINT; q : In; END_STRUCT; END_TYPE
PROGRAM Main
VAR p : Pt; s : In; i : INT; r : REF_TO DINT; rp : REF_TO Pt; END_VAR
FOR i := 1 TO 2 DO r^ := r^ + 1; rp^.q.x := 1; END_FOR;  (* rp^.q: rp may be NULL *)
FOR i := 1 TO 2 DO r^ := r^ + 1; p.q := s; END_FOR;      (* writes every field of p.q *)
FOR i := 1 TO 2 DO r^ := r^ + 1; rp := REF(p); END_FOR;  (* rp changes *)
FOR i := 1 TO 2 DO r^ := r^ + 1; p.q.x := 1; END_FOR;    (* held *)
END_PROGRAM
"""
    assert planned(src) == [False, False, False, True]


def test_no_fields_in_a_project_with_unions():
    src = """
TYPE U : UNION a : DINT; b : REAL; END_UNION; END_TYPE
TYPE Pt : STRUCT x : DINT; END_STRUCT; END_TYPE
PROGRAM Main
VAR p : Pt; u : U; i : INT; r : REF_TO DINT; END_VAR
r := REF(u.a);
FOR i := 1 TO 2 DO r^ := r^ + 1; p.x := 1; END_FOR;
FOR i := 1 TO 2 DO r^ := r^ + 1; END_FOR;
END_PROGRAM
"""
    assert planned(src) == [False, True]


ELEMENTS = """
FUNCTION Walk : DINT
VAR_IN_OUT xs : ARRAY[*] OF DINT; END_VAR
VAR_INPUT k : INT; END_VAR
VAR r : REF_TO DINT; own : ARRAY[0..3] OF DINT; i : INT; END_VAR
r := REF(xs[k]);     (* an ItemRef of the ArrayRef: an element of the caller's arr *)
FOR i := 0 TO 3 DO r^ := r^ + 1; own[i] := r^; END_FOR;
Walk := own[3];
END_FUNCTION
PROGRAM Main
VAR a, res : DINT; arr, other : ARRAY[1..4] OF DINT; n, i : INT; r : REF_TO DINT; END_VAR
n := n + 1;
CASE n MOD 3 OF
  0: r := REF(a);
  1: r := REF(arr[2]);
  2: r := REF(other[3]);
END_CASE;
FOR i := 1 TO 4 DO
    r^ := r^ + i;
    arr[i] := arr[i] + r^;
END_FOR;
FOR i := 1 TO 4 DO
    r := REF(arr[1]);
END_FOR;
r := REF(arr[3]);
FOR i := 1 TO 4 DO
    arr[i] := arr[i] + 1;
    res := res + Walk(xs := arr, k := 2) + r^;
END_FOR;
END_PROGRAM
"""


def test_array_elements_in_the_loop_are_checked_against_the_target_at_run_time():
    paths = ["Main.a", "Main.arr[1]", "Main.arr[2]", "Main.arr[3]", "Main.arr[4]", "Main.other[3]", "Main.res"]
    on, off, seen = run_both(ELEMENTS, OPTION, 9, lambda k: {}, paths)
    assert "type(_ref" in on and ".lst) is list" in on and "_held" not in off
    assert seen[-1]["Main.arr[2]"] != 0 and seen[-1]["Main.other[3]"] != 0


def test_element_accesses_that_cannot_be_checked_are_refused():
    src = """
PROGRAM Main
VAR m : ARRAY[1..2, 1..2] OF DINT; aa : ARRAY[1..2] OF ARRAY[1..2] OF DINT; ra : REF_TO ARRAY[1..2] OF DINT;
    v : ARRAY[1..2] OF DINT; i : INT; r : REF_TO DINT; END_VAR
FOR i := 1 TO 2 DO r^ := r^ + m[i, 1]; END_FOR;    (* a row of m: not named before the loop *)
FOR i := 1 TO 2 DO r^ := r^ + aa[i][1]; END_FOR;   (* the same *)
FOR i := 1 TO 2 DO r^ := r^ + ra^[i]; END_FOR;     (* ra may be NULL *)
FOR i := 1 TO 2 DO r^ := r^ + v[i]; END_FOR;       (* held *)
END_PROGRAM
"""
    assert planned(src) == [False, False, False, True]
