"""Object orientation on the VM (IEC 61131-3 ed. 3 6.6.5-6.6.6, CODESYS/TwinCAT syntax): METHODs
with inputs, outputs, in-outs, fresh locals and a result; calls as statements and in expressions,
formal and positional; own methods without prefix and through THIS^; EXTENDS, overriding,
SUPER^; interfaces; properties. Black-box programs through the API and the CLI."""

from __future__ import annotations

import pytest

import stvm
from core_helpers import cli, run_st, start_st, write_st

COUNTER = """
FUNCTION_BLOCK FB_Counter
VAR_INPUT step : INT := 1; END_VAR
VAR_OUTPUT count : INT; END_VAR
VAR limit : INT := 10; END_VAR
count := count + step;

METHOD Reset
count := 0;
END_METHOD

METHOD IsReady : BOOL
IsReady := count >= limit;
END_METHOD

METHOD Calc : INT
VAR_INPUT a : INT; b : INT; END_VAR
VAR_OUTPUT doubled : INT; END_VAR
VAR tmp : INT; END_VAR
tmp := tmp + a * b;          (* VAR of a method starts fresh on every call *)
doubled := 2 * tmp;
Calc := tmp + count;
END_METHOD

METHOD AddTwice
VAR_INPUT n : INT; END_VAR
count := count + Calc(n, 1);
THIS^.count := THIS^.count + THIS^.Calc(a := n, b := 1);
END_METHOD
END_FUNCTION_BLOCK

PROGRAM Main
VAR
  c : FB_Counter;
  x : INT;
  d : INT;
  ready : BOOL;
  n : INT;
END_VAR
c(step := 2);
x := c.Calc(a := 1, b := 2, doubled => d);
IF c.IsReady() THEN
  ready := TRUE;
  c.Reset();
END_IF;
n := n + 1;
IF n = 7 THEN c.AddTwice(3); END_IF;
END_PROGRAM
"""


def test_methods_read_and_write_the_instance():
    values = run_st(COUNTER, cycles=4, prints=["Main.x", "Main.d", "Main.ready", "Main.c.count"])
    # count 8 after 4 calls; Calc(1, 2): tmp = 2 (fresh), doubled 4, result 2 + 8
    assert values == {"Main.x": 10, "Main.d": 4, "Main.ready": False, "Main.c.count": 8}


def test_method_in_a_condition_and_as_a_statement():
    values = run_st(COUNTER, cycles=5, prints=["Main.ready", "Main.c.count"])
    assert values == {"Main.ready": True, "Main.c.count": 0}      # IsReady at 10, then Reset


def test_own_methods_without_prefix_and_through_this():
    values = run_st(COUNTER, cycles=7, prints=["Main.c.count", "Main.x"])
    # scan 7: count 4, x = 2 + 4; AddTwice(3): 4 + Calc(3,1) = 4 + 7 = 11, then 11 + (3 + 11) = 25
    assert values == {"Main.c.count": 25, "Main.x": 6}


IN_OUT = """
FUNCTION_BLOCK FB_Acc
VAR total : DINT; END_VAR
METHOD Add : DINT
VAR_INPUT v : DINT; END_VAR
VAR_IN_OUT acc : DINT; END_VAR
VAR_OUTPUT was : DINT; END_VAR
was := acc;
acc := acc + v;
total := total + v;
Add := total;
END_METHOD
END_FUNCTION_BLOCK

PROGRAM Main
VAR a : FB_Acc; s : DINT := 100; w : DINT; r : DINT; arr : ARRAY[1..2] OF DINT; q : BOOL; END_VAR
r := a.Add(v := 5, acc := s, was => w);
a.Add(7, arr[2]);
q := a.Add(v := 1, acc := arr[1]) > 12 AND s = 105;
END_PROGRAM
"""


def test_method_in_out_outputs_and_positional_arguments():
    values = run_st(IN_OUT, cycles=1, prints=["Main.s", "Main.w", "Main.r", "Main.arr", "Main.q", "Main.a.total"])
    assert values == {"Main.s": 105, "Main.w": 100, "Main.r": 5, "Main.arr": [1, 7], "Main.q": True,
                      "Main.a.total": 13}


def test_method_locals_are_fresh_each_call():
    src = """
FUNCTION_BLOCK F
METHOD Next : INT
VAR k : INT; END_VAR
k := k + 1;
Next := k;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; a, b : INT; END_VAR
a := f.Next();
b := f.Next() + f.Next();
END_PROGRAM
"""
    assert run_st(src, cycles=3, prints=["Main.a", "Main.b"]) == {"Main.a": 1, "Main.b": 2}


def test_method_with_return_exits_early():
    src = """
FUNCTION_BLOCK F
VAR hits : INT; END_VAR
METHOD Check : INT
VAR_INPUT v : INT; END_VAR
Check := -1;
IF v < 0 THEN RETURN; END_IF;
hits := hits + 1;
Check := hits;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; a, b : INT; END_VAR
a := f.Check(-5);
b := f.Check(3);
END_PROGRAM
"""
    assert run_st(src, cycles=2, prints=["Main.a", "Main.b"]) == {"Main.a": -1, "Main.b": 2}


def test_methods_may_come_before_the_body_and_in_a_program():
    src = """
FUNCTION_BLOCK F
VAR_OUTPUT n : INT; END_VAR
METHOD Bump
n := n + 10;
END_METHOD
n := n + 1;
Bump();
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; seen : INT; END_VAR
f();
Record();
METHOD Record
seen := f.n;
END_METHOD
END_PROGRAM
"""
    assert run_st(src, cycles=2, prints=["Main.seen"]) == {"Main.seen": 22}


def test_the_body_sees_what_its_methods_wrote_in_the_same_call():
    # the FB body holds no copy of its variables while it calls its own methods
    src = """
FUNCTION_BLOCK F
VAR_OUTPUT n : INT; log : INT; END_VAR
n := n + 1; n := n + 1; n := n + 1;
Twice();
log := n;
n := n + 1;
METHOD Twice
n := n * 2;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; END_VAR
f();
END_PROGRAM
"""
    assert run_st(src, cycles=1, prints=["Main.f.log", "Main.f.n"]) == {"Main.f.log": 6, "Main.f.n": 7}


def test_cli_run_prints_values_changed_by_methods(tmp_path):
    path = write_st(COUNTER, "counter.st", tmp_path)
    rc, out, err = cli(["run", path, "--cycles", "7", "--print", "Main.c.count", "--print", "Main.ready"])
    assert rc == 0, err
    assert "Main.c.count = 25" in out and "Main.ready = TRUE" in out


# ---------------------------------------------------------------- EXTENDS, overriding, SUPER^
SHAPES = """
FUNCTION_BLOCK ABSTRACT FB_Shape
VAR_OUTPUT calls : INT; END_VAR
VAR unit : INT := 1; END_VAR
calls := calls + 1;
METHOD ABSTRACT Area : REAL
END_METHOD
METHOD Describe : REAL
Describe := Area() * 10.0;        (* dynamic dispatch: the instance's own Area *)
END_METHOD
METHOD PROTECTED Scale : REAL
VAR_INPUT f : REAL; END_VAR
Scale := f * 2.0;
END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Square EXTENDS FB_Shape
VAR_INPUT side : REAL; END_VAR
VAR_OUTPUT bodyran : INT; END_VAR
SUPER^();                          (* the base body *)
bodyran := bodyran + 1;
METHOD Area : REAL
Area := side * side;
END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Big EXTENDS FB_Square
METHOD Area : REAL
Area := SUPER^.Area() + Scale(1.5) + unit;
END_METHOD
END_FUNCTION_BLOCK

FUNCTION Twice : REAL
VAR_IN_OUT s : FB_Shape; END_VAR
Twice := 2.0 * s.Describe();
END_FUNCTION

PROGRAM Main
VAR sq : FB_Square; big : FB_Big; a, b, c, d : REAL; END_VAR
sq(side := 2.0);
big(side := 3.0);
a := sq.Describe();
b := big.Describe();
c := big.Area();
d := Twice(big);
END_PROGRAM
"""


def test_inherited_methods_dispatch_to_the_override():
    values = run_st(SHAPES, cycles=2, prints=["Main.a", "Main.b", "Main.c", "Main.d"])
    # square 2: area 4 -> 40; big 3: 9 + Scale(1.5) 3 + unit 1 = 13 -> 130; via a base in-out: 260
    assert values == {"Main.a": 40.0, "Main.b": 130.0, "Main.c": 13.0, "Main.d": 260.0}


def test_inherited_variables_and_the_base_body_through_super():
    values = run_st(SHAPES, cycles=2, prints=["Main.sq.calls", "Main.sq.bodyran", "Main.big.calls", "Main.big.bodyran"])
    # FB_Big has no statements of its own: its body is empty (the base body runs only through SUPER^())
    assert values == {"Main.sq.calls": 2, "Main.sq.bodyran": 2, "Main.big.calls": 0, "Main.big.bodyran": 0}


def test_print_shows_inherited_variables():
    text = run_st(SHAPES, cycles=1, fmt=True, prints=["Main.sq"])
    assert text == {"Main.sq": "(calls := 1, unit := 1, side := 2.0, bodyran := 1)"}


# ---------------------------------------------------------------- interfaces
MOTORS = """
INTERFACE I_Base
METHOD Id : INT
END_METHOD
END_INTERFACE

INTERFACE I_Motor EXTENDS I_Base
METHOD Start : BOOL
VAR_INPUT speed : INT; END_VAR
VAR_OUTPUT accepted : INT; END_VAR
END_METHOD
PROPERTY Speed : INT
GET END_GET
END_PROPERTY
END_INTERFACE

INTERFACE I_Other
METHOD Ping
END_METHOD
END_INTERFACE

FUNCTION_BLOCK FB_Motor IMPLEMENTS I_Motor
VAR_INPUT ident : INT; END_VAR
VAR sp : INT; END_VAR
METHOD Id : INT
Id := ident;
END_METHOD
METHOD Start : BOOL
VAR_INPUT speed : INT; END_VAR
VAR_OUTPUT accepted : INT; END_VAR
sp := speed;
accepted := speed * 2;
Start := speed > 0;
END_METHOD
PROPERTY Speed : INT
GET
Speed := sp;
END_GET
SET
sp := Speed;
END_SET
END_PROPERTY
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Fast EXTENDS FB_Motor IMPLEMENTS I_Other
METHOD Start : BOOL
VAR_INPUT speed : INT; END_VAR
VAR_OUTPUT accepted : INT; END_VAR
Start := SUPER^.Start(speed := speed * 10, accepted => accepted);
END_METHOD
METHOD Ping
sp := -1;
END_METHOD
END_FUNCTION_BLOCK

PROGRAM Main
VAR
  m1 : FB_Motor;
  m2 : FB_Fast;
  itf : I_Motor;
  base : I_Base;
  other : I_Other;
  ok : BOOL;
  acc : INT;
  ids : INT;
  wasnull, nowset, q1, q2, same, valid : BOOL;
  s1, s2 : INT;
  n : INT;
END_VAR
n := n + 1;
m1(ident := 1); m2(ident := 2);
IF n = 1 THEN wasnull := itf = 0; END_IF;
itf := m1;
nowset := itf <> NULL;
ok := itf.Start(speed := 3, accepted => acc);
s1 := itf.Speed;
itf := m2;
ok := itf.Start(4);
s2 := m2.Speed;
base := itf;
ids := base.Id() * 10 + m1.Id();
q1 := __QUERYINTERFACE(base, other);
q2 := __QUERYINTERFACE(m1, other);
valid := __ISVALIDREF(other);
same := itf = m2 AND base = itf;
m1.Speed := 42;
IF n = 3 THEN
  other := 0;
  other.Ping();
END_IF
END_PROGRAM
"""


def test_calls_through_interfaces_dispatch_to_the_instance():
    values = run_st(MOTORS, cycles=1, prints=["Main.ok", "Main.acc", "Main.s1", "Main.s2", "Main.ids", "Main.m1.sp"])
    # m1.Start(3): accepted 6; FB_Fast.Start(4) -> SUPER^.Start(40): sp 40; m1.Speed := 42 at the end
    assert values == {"Main.ok": True, "Main.acc": 6, "Main.s1": 3, "Main.s2": 40, "Main.ids": 21, "Main.m1.sp": 42}


def test_interface_comparisons_and_query_interface():
    values = run_st(MOTORS, cycles=1, prints=["Main.wasnull", "Main.nowset", "Main.q1", "Main.q2", "Main.valid",
                                              "Main.same"])
    # m1 implements no I_Other: q2 FALSE and `other` back to NULL
    assert values == {"Main.wasnull": True, "Main.nowset": True, "Main.q1": True, "Main.q2": False,
                      "Main.valid": False, "Main.same": True}


def test_print_of_an_interface_variable():
    assert run_st(MOTORS, cycles=1, fmt=True, prints=["Main.itf", "Main.other"]) == \
        {"Main.itf": "-> FB_Fast", "Main.other": "NULL"}


def test_call_through_an_unassigned_interface_faults_at_its_line(tmp_path):
    path = write_st(MOTORS, "motors.st", tmp_path)
    rc, out, err = cli(["run", path, "--cycles", "5"])
    line = MOTORS.splitlines().index("  other.Ping();") + 1
    assert rc == 3
    assert f"motors.st:{line}:3: fault: call through an interface that holds no instance (NULL)" in err
    assert "scan 2" in err and "Traceback" not in err


def test_api_fault_names_the_line():
    vm = start_st(MOTORS)
    vm.run(cycles=2)
    with pytest.raises(stvm.RuntimeFault, match="interface") as info:
        vm.run(cycles=1)
    assert info.value.span.line == MOTORS.splitlines().index("  other.Ping();") + 1


# ---------------------------------------------------------------- properties
TANK = """
FUNCTION_BLOCK FB_Tank
VAR_OUTPUT log : INT; END_VAR
VAR lvl : INT; maxv : INT := 100; writes : INT; END_VAR
Level := Level + 1;             (* inside the FB a bare property name calls GET and SET *)
log := Level;

PROPERTY Level : INT            (* TwinCAT stores GET and SET apart: two blocks of one name *)
GET
Level := lvl;
END_GET
END_PROPERTY

PROPERTY PUBLIC Level : INT
SET
writes := writes + 1;
IF Level > maxv THEN lvl := maxv; ELSE lvl := Level; END_IF;
END_SET
END_PROPERTY

PROPERTY WriteCount : INT
GET
VAR doubled : INT; END_VAR
doubled := writes * 2;
WriteCount := doubled / 2;
END_GET
END_PROPERTY

METHOD Fill
THIS^.Level := 500;
END_METHOD
END_FUNCTION_BLOCK

PROGRAM Main
VAR t : FB_Tank; a, w : INT; r : REAL; END_VAR
t();
t.Level := t.Level + 10;
a := t.Level;
IF a > 30 THEN t.Fill(); END_IF;
w := t.WriteCount;
r := t.Level * 1.5;
END_PROGRAM
"""


def test_properties_are_used_like_variables():
    values = run_st(TANK, cycles=3, prints=["Main.a", "Main.w", "Main.r", "Main.t.log", "Main.t.lvl"])
    # per scan: body +1 and t.Level +10 (two SETs); scan 3: 33 > 30, Fill sets 500, clamped to 100
    assert values == {"Main.a": 33, "Main.w": 7, "Main.r": 150.0, "Main.t.log": 23, "Main.t.lvl": 100}


def test_property_setter_runs_once_per_assignment():
    assert run_st(TANK, cycles=1, prints=["Main.t.writes"]) == {"Main.t.writes": 2}


def test_method_outputs_are_written_on_return_and_en_eno_works():
    src = """
FUNCTION_BLOCK F
VAR calls : INT; END_VAR
METHOD Split : BOOL
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT hi, lo : INT; END_VAR
calls := calls + 1;
hi := v / 10;
IF v < 0 THEN RETURN; END_IF;
lo := v MOD 10;
Split := TRUE;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; h1, l1, h2, l2 : INT; ok1, ok2, eno : BOOL; END_VAR
ok1 := f.Split(v := 42, hi => h1, lo => l1);
ok2 := f.Split(v := -35, hi => h2, lo => l2);
f.Split(EN := FALSE, v := 7, ENO => eno);
END_PROGRAM
"""
    values = run_st(src, cycles=1, prints=["Main.ok1", "Main.h1", "Main.l1", "Main.ok2", "Main.h2", "Main.l2",
                                           "Main.eno", "Main.f.calls"])
    assert values == {"Main.ok1": True, "Main.h1": 4, "Main.l1": 2, "Main.ok2": False, "Main.h2": -3, "Main.l2": 0,
                      "Main.eno": False, "Main.f.calls": 2}


VALUES = """
INTERFACE I_Val
METHOD Get : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_Const IMPLEMENTS I_Val
VAR_INPUT v : INT; END_VAR
METHOD Get : INT
Get := v;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Sum
VAR_INPUT src : I_Val; END_VAR
VAR_OUTPUT total : INT; END_VAR
IF src <> 0 THEN total := total + src.Get(); END_IF;
END_FUNCTION_BLOCK
FUNCTION Read : INT
VAR_INPUT i : I_Val; END_VAR
Read := i.Get() * 100;
END_FUNCTION
PROGRAM Main
VAR
  a : FB_Const; b : FB_Const;
  list : ARRAY[1..2] OF I_Val;
  s : FB_Sum; k : INT; r : INT; n : INT;
END_VAR
a(v := 1); b(v := 2);
list[1] := a; list[2] := b;
FOR k := 1 TO 2 DO
  s(src := list[k]);
END_FOR;
s(src := 0);
r := Read(list[2]) + Read(i := a);
n := list[1].Get() + list[2].Get();
END_PROGRAM
"""


def test_interfaces_as_inputs_array_elements_and_function_parameters():
    values = run_st(VALUES, cycles=2, prints=["Main.s.total", "Main.r", "Main.n"])
    # two scans of s(src := a), s(src := b): 2 * (1 + 2); s(src := 0) adds nothing
    assert values == {"Main.s.total": 6, "Main.r": 300, "Main.n": 3}
    assert run_st(VALUES, cycles=1, fmt=True, prints=["Main.list"]) == {"Main.list": "[-> FB_Const, -> FB_Const]"}


def test_var_inst_of_a_method_lives_in_the_instance():
    src = """
FUNCTION_BLOCK F
METHOD Tick : INT
VAR_INST count : INT := 100; END_VAR
VAR fresh : INT; END_VAR
count := count + 1;
fresh := fresh + 1;
Tick := count * 10 + fresh;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main VAR a, b : F; x, y : INT; END_VAR
x := a.Tick();
y := b.Tick() + b.Tick();
END_PROGRAM
"""
    # per instance, kept between calls and scans (CODESYS VAR_INST); VAR starts fresh
    assert run_st(src, cycles=2, prints=["Main.x", "Main.y"]) == {"Main.x": 1021, "Main.y": 2072}
    assert run_st(src, cycles=1, fmt=True, prints=["Main.a"]) == {"Main.a": "(Tick__count := 101)"}


def test_properties_are_inherited_overridden_and_reached_through_super():
    src = """
FUNCTION_BLOCK FB_Base
VAR raw : INT := 4; END_VAR
PROPERTY Scaled : INT
GET
Scaled := raw * 10;
END_GET
END_PROPERTY
METHOD Report : INT
Report := Scaled + 1;          (* dynamic: the instance's own Scaled *)
END_METHOD
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Derived EXTENDS FB_Base
PROPERTY Scaled : INT
GET
Scaled := SUPER^.Scaled * 2;
END_GET
END_PROPERTY
END_FUNCTION_BLOCK

PROGRAM Main VAR b : FB_Base; d : FB_Derived; rb, rd, sd : INT; END_VAR
rb := b.Report();
rd := d.Report();
sd := d.Scaled;
END_PROGRAM
"""
    assert run_st(src, cycles=1, prints=["Main.rb", "Main.rd", "Main.sd"]) == {"Main.rb": 41, "Main.rd": 81, "Main.sd": 80}


def test_struct_property_and_a_bit_of_a_property():
    src = """
TYPE Pt : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK F
VAR v : Pt; w : INT; END_VAR
PROPERTY S : Pt
GET S := v; END_GET
SET v := S; END_SET
END_PROPERTY
PROPERTY B : INT
GET B := w; END_GET
SET w := B; END_SET
END_PROPERTY
END_FUNCTION_BLOCK
PROGRAM Main VAR f : F; p : Pt; k : INT; END_VAR
p.x := 7;
f.S := p;
p.x := 9;                  (* the property holds its own copy *)
k := f.S.x;
f.B.3 := TRUE;             (* GET, set bit 3, SET *)
END_PROGRAM
"""
    assert run_st(src, cycles=1, prints=["Main.k", "Main.f.w"]) == {"Main.k": 7, "Main.f.w": 8}


VAR_STAT_SOURCE = """
FUNCTION Counter : INT
VAR_STAT calls : INT := 100; END_VAR
VAR fresh : INT; END_VAR
calls := calls + 1;
fresh := fresh + 1;
Counter := calls * 10 + fresh;
END_FUNCTION

FUNCTION_BLOCK FB_Base
VAR_STAT made : INT; END_VAR
made := made + 1;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_A EXTENDS FB_Base
VAR_STAT shared : INT; END_VAR
VAR own : INT; END_VAR
SUPER^();
shared := shared + 1;
own := own + 1;

METHOD Bump : INT
VAR_STAT n : INT; END_VAR
VAR fresh : INT; END_VAR
n := n + 1;
fresh := fresh + 1;
shared := shared + 10;
Bump := n * 100 + fresh + made * 1000;
END_METHOD
END_FUNCTION_BLOCK

PROGRAM Main
VAR a, b : FB_A; r1, r2, c : INT; END_VAR
c := Counter();
c := Counter();
a(); b();
r1 := a.Bump();
r2 := b.Bump();
END_PROGRAM
"""


def test_var_stat_is_kept_across_calls_and_shared_by_every_instance():
    values = run_st(VAR_STAT_SOURCE, cycles=2, prints=["Main.c", "Main.r1", "Main.r2", "Main.a.own",
                                                      "FB_A__shared", "FB_A__Bump__n", "Counter__calls"])
    # Counter: 4 calls (its VAR starts fresh); shared: per scan +1 from each body, +10 from each Bump;
    # the method's VAR_STAT n counts the calls of every instance; the base's VAR_STAT is seen by the method
    assert values == {"Main.c": 1041, "Main.r1": 4301, "Main.r2": 4401, "Main.a.own": 2,
                      "FB_A__shared": 44, "FB_A__Bump__n": 4, "Counter__calls": 104}
    assert run_st(VAR_STAT_SOURCE, cycles=1, fmt=True, prints=["Main.a"]) == {"Main.a": "(own := 1)"}


def test_an_fb_instance_takes_initial_values_at_its_creation():
    src = """
FUNCTION_BLOCK B
VAR_INPUT base_in : INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK F EXTENDS B
VAR_INPUT x : INT; END_VAR
VAR y : INT := 5; t : TON := (PT := T#2s); END_VAR
VAR_OUTPUT q : INT; END_VAR
q := x + y + base_in;
END_FUNCTION_BLOCK
VAR_GLOBAL gf : F := (x := 100, base_in := 1000); END_VAR
PROGRAM Main
VAR f : F := (x := 1, y := 2); g : F; r : INT; arr : ARRAY[1..2] OF F := [(x := 7), (y := 8)]; END_VAR
f();
g();
gf();
arr[1](); arr[2]();
r := f.q;
END_PROGRAM
"""
    # inputs, internal variables, an inherited input, a nested FB (TON's PT), globals and array elements
    values = run_st(src, prints=["Main.r", "Main.g.q", "gf.q", "Main.arr[1].q", "Main.arr[2].q"])
    assert values == {"Main.r": 3, "Main.g.q": 5, "gf.q": 1105, "Main.arr[1].q": 12, "Main.arr[2].q": 8}
    assert run_st(src, fmt=True, prints=["Main.f.t.PT"]) == {"Main.f.t.PT": "T#2s"}


FB_INIT_SOURCE = """FUNCTION_BLOCK Inner
VAR order : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
gSeq := gSeq + 1;
order := gSeq;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK B
VAR_INPUT x : INT; END_VAR
VAR inner : Inner; baseOrder : INT; retains : BOOL; copy : BOOL := TRUE; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
gSeq := gSeq + 1;
baseOrder := gSeq;
retains := bInitRetains;
copy := bInCopyCode;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK D EXTENDS B
VAR derivedOrder : INT; seenX : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
gSeq := gSeq + 1;
derivedOrder := gSeq;
seenX := x;
END_METHOD
END_FUNCTION_BLOCK
VAR_GLOBAL gSeq : INT; END_VAR
PROGRAM Main
VAR d : D := (x := 5); END_VAR
END_PROGRAM
"""


def test_fb_init_runs_at_instance_creation_inner_and_base_first():
    values = run_st(FB_INIT_SOURCE, cycles=1, fmt=True, prints=[
        "Main.d.inner.order", "Main.d.baseOrder", "Main.d.derivedOrder", "Main.d.seenX", "Main.d.retains",
        "Main.d.copy", "gSeq"])
    # the inner instance's FB_init, then the base's, then the derived FB's, after the instance's
    # initial values (x := 5); as at a first download: bInitRetains TRUE, bInCopyCode FALSE
    assert values == {"Main.d.inner.order": "1", "Main.d.baseOrder": "2", "Main.d.derivedOrder": "3",
                      "Main.d.seenX": "5", "Main.d.retains": "TRUE", "Main.d.copy": "FALSE", "gSeq": "3"}
    vm = start_st(FB_INIT_SOURCE)
    assert vm["gSeq"] == 3        # before the first scan, and once only
    vm.run(cycles=3)
    assert vm["gSeq"] == 3


def test_a_fault_in_fb_init_stops_the_run_at_its_line():
    rc, out, err = cli(["run", write_st("""FUNCTION_BLOCK F
VAR n : INT; z : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
n := 10 / z;
END_METHOD
END_FUNCTION_BLOCK
VAR_GLOBAL gf : F; END_VAR
PROGRAM Main
VAR c : INT; END_VAR
c := c + 1;
END_PROGRAM
"""), "--cycles", "1"])
    assert rc == 3 and ":5:1: fault: integer division by zero (task FB_init, scan 0" in err, err


def test_fb_init_arguments_in_a_declaration_reach_every_fb_init_of_the_chain():
    src = """FUNCTION_BLOCK F
VAR_INPUT x : INT; END_VAR
VAR n : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; a : INT; nMax : INT := 100; END_VAR
n := a + nMax + x;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK G EXTENDS F
VAR seen : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; a : INT; nMax : INT := 100; END_VAR
seen := nMax;
END_METHOD
END_FUNCTION_BLOCK
VAR_GLOBAL gf : F(7, 8); END_VAR
PROGRAM Main
VAR f1 : F(1, 2); f2 : F(a := 3) := (x := 4); f3 : F(); g : G(nMax := 20, a := 1); END_VAR
END_PROGRAM
"""
    # positional and named, the instance initialiser (x := 4) before FB_init, the other inputs'
    # initial values (nMax := 100), a base's FB_init gets the derived instance's arguments
    assert run_st(src, prints=["gf.n", "Main.f1.n", "Main.f2.n", "Main.f3.n", "Main.g.n", "Main.g.seen"]) == {
        "gf.n": 15, "Main.f1.n": 3, "Main.f2.n": 107, "Main.f3.n": 100, "Main.g.n": 21, "Main.g.seen": 20}


def test_call_after_init_methods_run_once_after_fb_init():
    src = """FUNCTION_BLOCK B
VAR seq : INT; initAt : INT; afterAt : INT; baseAfter : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; END_VAR
seq := seq + 1; initAt := seq;
END_METHOD
{attribute 'call_after_init'}
METHOD BaseReady
seq := seq + 1; baseAfter := seq;
END_METHOD
END_FUNCTION_BLOCK
{attribute 'call_after_init'}
FUNCTION_BLOCK F EXTENDS B
VAR_INPUT x : INT; END_VAR
VAR seen : INT; END_VAR
{attribute 'call_after_init'}
METHOD Ready
seq := seq + 1; afterAt := seq; seen := x;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK P
VAR n : INT; END_VAR
{attribute 'call_after_init'}
METHOD Only
n := n + 10;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F := (x := 3); p : P; END_VAR
END_PROGRAM
"""
    # after FB_init and the instance initialiser, a base's first; once (not every scan); also
    # on an FB without FB_init
    assert run_st(src, cycles=3, prints=["Main.f.initAt", "Main.f.baseAfter", "Main.f.afterAt", "Main.f.seen",
                                         "Main.p.n"]) == {
        "Main.f.initAt": 1, "Main.f.baseAfter": 2, "Main.f.afterAt": 3, "Main.f.seen": 3, "Main.p.n": 10}


def test_a_recursive_method_runs_under_codesys():
    src = """FUNCTION_BLOCK F
METHOD Down : INT
VAR_INPUT k : INT; END_VAR
IF k > 0 THEN Down := THIS^.Down(k - 1) + 1; END_IF
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; r : INT; END_VAR
r := f.Down(5);
END_PROGRAM
"""
    rc, out, err = cli(["run", write_st(src), "--dialect", "codesys", "--cycles", "1", "--print", "Main.r"])
    assert (rc, out) == (0, "Main.r = 5\n") and "warning: recursive method call F.Down -> F.Down" in err


REF_TO_INTERFACE = """INTERFACE I
METHOD Get : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
VAR v : INT := 7; END_VAR
METHOD Get : INT
Get := v;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK G IMPLEMENTS I
METHOD Get : INT
Get := 9;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; g : G; i : I; r : REF_TO I; x, y : INT; empty, isset : BOOL; j : I; END_VAR
r := REF(i);
empty := r^ = 0;
r^ := f;
x := i.Get();
r^ := g;
y := r^.Get();
isset := r^ <> 0 AND r <> NULL;
j := r^;
END_PROGRAM
"""

REF_TO_INTERFACE_IN_STRUCT = """INTERFACE I
METHOD Get : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
METHOD Get : INT
Get := 7;
END_METHOD
END_FUNCTION_BLOCK
TYPE S : STRUCT p : REF_TO I; END_STRUCT END_TYPE
FUNCTION Use : INT
VAR_INPUT p : REF_TO I; END_VAR
Use := p^.Get() * 2;
END_FUNCTION
PROGRAM Main
VAR f : F; i : I; s : S; x : INT; y : INT; n : INT; END_VAR
i := f;
s.p := REF(i);
x := Use(s.p);
n := n + 1;
IF n = 2 THEN s.p := NULL; END_IF
y := s.p^.Get();
END_PROGRAM
"""

REFERENCE_AND_POINTER_TO_INTERFACE = """INTERFACE I
METHOD Get : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK F IMPLEMENTS I
METHOD Get : INT
Get := 7;
END_METHOD
END_FUNCTION_BLOCK
PROGRAM Main
VAR f : F; i : I; rr : REFERENCE TO I; p : POINTER TO I; x, y : INT; END_VAR
i := f;
rr REF= i;
x := rr.Get();
p := ADR(i);
y := p^.Get();
END_PROGRAM
"""


def test_ref_to_an_interface_reads_writes_and_calls_through_it():
    values = run_st(REF_TO_INTERFACE, fmt=True, prints=["Main.x", "Main.y", "Main.empty", "Main.isset", "Main.j", "Main.r^"])
    assert values == {"Main.x": "7", "Main.y": "9", "Main.empty": "TRUE", "Main.isset": "TRUE", "Main.j": "-> G",
                      "Main.r^": "-> G"}
    assert run_st(REFERENCE_AND_POINTER_TO_INTERFACE, prints=["Main.x", "Main.y"]) == {"Main.x": 7, "Main.y": 7}


def test_ref_to_an_interface_in_a_struct_and_as_an_input_and_its_faults():
    assert run_st(REF_TO_INTERFACE_IN_STRUCT, prints=["Main.x", "Main.y"]) == {"Main.x": 14, "Main.y": 7}
    path = write_st(REF_TO_INTERFACE_IN_STRUCT)
    rc, _, err = cli(["run", path, "--cycles", "3"])
    assert rc == 3 and ":22:1: fault: dereference of a NULL reference" in err, err
    rc, _, err = cli(["run", write_st(REF_TO_INTERFACE_IN_STRUCT.replace("s.p := NULL;", "i := 0;")), "--cycles", "3"])
    assert rc == 3 and ":22:1: fault: call through an interface that holds no instance (NULL)" in err, err
