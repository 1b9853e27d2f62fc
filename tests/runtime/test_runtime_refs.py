"""REF_TO / REF() / ^ / NULL (IEC 61131-3 ed. 3, 6.4.4.10), CODESYS POINTER TO / ADR and
REFERENCE TO / REF= on the VM: reads and writes through references to scalars, array elements,
struct fields and FB instances, comparisons, NULL dereference faults, and what a reference to a
function's local does after the function returned."""

from __future__ import annotations

import pytest

import stvm
from core_helpers import run_st, start_st

PROGRAM = """
TYPE Point : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE

FUNCTION_BLOCK Counter
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT count : INT; END_VAR
count := count + step;
END_FUNCTION_BLOCK

FUNCTION Bump : INT
VAR_INPUT r : REF_TO INT; END_VAR
r^ := r^ + 1;
Bump := r^;
END_FUNCTION

PROGRAM Main
VAR
    a : INT := 5;
    b : INT;
    arr : ARRAY[1..3] OF INT := [10, 20, 30];
    p : Point;
    ri : REF_TO INT;
    rp : REF_TO Point;
    ra : REF_TO ARRAY[1..3] OF INT;
    pi : POINTER TO INT;
    refi : REFERENCE TO INT;
    c : Counter;
    rc : REF_TO Counter;
    same, other, isnull, notnull : BOOL;
    n, k : INT;
END_VAR
ri := REF(a);
ri^ := ri^ + 1;
b := ri^ * 2;
ri := REF(arr[2]);
ri^ := 21;
rp := REF(p);
rp^.x := 3;
rp^.y := rp^.x + 1;
ra := REF(arr);
ra^[3] := ra^[1] + 1;
pi := ADR(b);
pi^ := pi^ + 1;
refi REF= a;
refi := refi + 10;
rc := REF(c);
rc^(step := 2);
same := ri = REF(arr[2]);
other := ri = REF(arr[1]);
isnull := ri = NULL;
notnull := rp <> NULL;
n := Bump(REF(a));
k := k + 1;
END_PROGRAM
"""


def test_reads_and_writes_through_references():
    values = run_st(PROGRAM, cycles=1, prints=["Main.a", "Main.b", "Main.arr", "Main.p.x", "Main.p.y",
                                               "Main.n", "Main.c.count"])
    # a: 5 +1 (ri^) +10 (refi) +1 (Bump) = 17; b: 6*2 = 12, +1 through pi = 13
    assert values == {"Main.a": 17, "Main.b": 13, "Main.arr": [10, 21, 11], "Main.p.x": 3, "Main.p.y": 4,
                      "Main.n": 17, "Main.c.count": 2}


def test_reference_comparisons():
    values = run_st(PROGRAM, cycles=1, prints=["Main.same", "Main.other", "Main.isnull", "Main.notnull"])
    assert values == {"Main.same": True, "Main.other": False, "Main.isnull": False, "Main.notnull": True}


def test_print_paths_reach_through_references():
    text = run_st(PROGRAM, cycles=1, fmt=True,
                  prints=["Main.rp^.x", "Main.rp^", "Main.ri", "Main.ri^", "Main.rp", "Main.rc^.count", "Main.ra^[3]"])
    assert text == {"Main.rp^.x": "3", "Main.rp^": "(x := 3, y := 4)", "Main.ri": "-> 21", "Main.ri^": "21",
                    "Main.rp": "-> Point", "Main.rc^.count": "2", "Main.ra^[3]": "11"}


def test_writes_by_path_through_a_reference_reach_the_target():
    vm = start_st(PROGRAM)
    vm.run(cycles=1)
    vm["Main.rp^.x"] = 42
    assert vm["Main.p.x"] == 42
    vm["Main.ri^"] = 7
    assert vm["Main.arr"][1] == 7


def test_path_through_null_is_an_error():
    vm = start_st("PROGRAM Main VAR r : REF_TO INT; x : INT; END_VAR x := 1; END_PROGRAM")
    vm.run(cycles=1)
    assert vm.format("Main.r") == "NULL"
    from stvm.runtime.vm import PathError
    with pytest.raises(PathError, match="NULL"):
        vm["Main.r^"]
    with pytest.raises(PathError, match="needs a reference"):
        vm["Main.x^"]


NULL_DEREF = """
PROGRAM Main
VAR ri : REF_TO INT; x : INT; n : INT; END_VAR
n := n + 1;
IF n = 3 THEN
    x := ri^;
END_IF
END_PROGRAM
"""


def test_null_dereference_faults_at_its_line():
    vm = start_st(NULL_DEREF)
    vm.run(cycles=2)
    with pytest.raises(stvm.RuntimeFault) as info:
        vm.run(cycles=1)
    fault = info.value
    assert fault.message == "dereference of a NULL reference"
    assert fault.span.line == 6 and fault.scan == 2


@pytest.mark.parametrize("statement", ["ri^ := 1;", "refi := 1;", "x := refi;", "rp^.x := 1;", "x := rp^.x;"])
def test_every_null_access_faults(statement):
    src = f"""
TYPE Point : STRUCT x : INT; END_STRUCT; END_TYPE
PROGRAM Main
VAR ri : REF_TO INT; refi : REFERENCE TO INT; rp : REF_TO Point; x : INT; END_VAR
{statement}
END_PROGRAM
"""
    vm = start_st(src)
    with pytest.raises(stvm.RuntimeFault, match="NULL reference") as info:
        vm.run(cycles=1)
    assert info.value.span.line == 5


LOCAL_AFTER_RETURN = """
FUNCTION Leak : REF_TO INT
VAR tmp : INT; END_VAR
tmp := 41;
Leak := REF(tmp);
END_FUNCTION

PROGRAM Main
VAR r : REF_TO INT; first, second : INT; END_VAR
r := Leak();
first := r^;
r^ := r^ + 1;
second := r^;
END_PROGRAM
"""


def test_reference_to_a_functions_local_after_return():
    # Choice (README): the frame of the call stays alive while a reference to it exists; the
    # reference reads the value the local had at the return, and writes change only that
    # frame (each call gets a new one). A PLC would read whatever reuses the stack there.
    values = run_st(LOCAL_AFTER_RETURN, cycles=2, prints=["Main.first", "Main.second"])
    assert values == {"Main.first": 41, "Main.second": 42}


def test_referenced_locals_are_not_held_in_python_locals():
    # x is used often (a candidate for a Python local), but its reference is taken: writes
    # through r inside the same scan must be seen by x and the other way round
    src = """
PROGRAM Main
VAR x : INT; r : REF_TO INT; a, b, c : INT; END_VAR
r := REF(x);
x := 1; a := x; r^ := x + 1; b := x; x := x + r^; c := x;
END_PROGRAM
"""
    values = run_st(src, cycles=1, prints=["Main.a", "Main.b", "Main.c", "Main.x"])
    assert values == {"Main.a": 1, "Main.b": 2, "Main.c": 4, "Main.x": 4}


def test_reference_to_fb_output_from_outside():
    src = """
FUNCTION_BLOCK Up
VAR_OUTPUT q : INT; END_VAR
q := q + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR u : Up; r : REF_TO INT; seen : INT; END_VAR
r := REF(u.q);
u();
seen := r^;
END_PROGRAM
"""
    assert run_st(src, cycles=3, prints=["Main.seen"]) == {"Main.seen": 3}


def test_reference_to_in_out_parameter_is_the_callers_variable():
    src = """
FUNCTION_BLOCK Setter
VAR_IN_OUT v : INT; END_VAR
VAR r : REF_TO INT; END_VAR
r := REF(v);
r^ := 99;
END_FUNCTION_BLOCK
PROGRAM Main
VAR s : Setter; x : INT; END_VAR
s(v := x);
END_PROGRAM
"""
    assert run_st(src, cycles=1, prints=["Main.x"]) == {"Main.x": 99}


def test_reference_in_struct_field_and_global():
    src = """
TYPE Node : STRUCT value : INT; next : REF_TO Node; END_STRUCT; END_TYPE
VAR_GLOBAL g : INT; gr : REF_TO INT; END_VAR
PROGRAM Main
VAR a, b : Node; sum : INT; END_VAR
a.value := 1; b.value := 2;
a.next := REF(b);
sum := a.value + a.next^.value;
gr := REF(g);
gr^ := sum;
END_PROGRAM
"""
    vm = start_st(src)
    vm.run(cycles=1)
    assert vm["Main.sum"] == 3 and vm["g"] == 3
    assert vm.format("Main.a.next^.value") == "2"
    assert vm.format("Main.a.next") == "-> Node"
