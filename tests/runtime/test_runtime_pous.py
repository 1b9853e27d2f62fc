"""POUs on the VM: FUNCTION / FUNCTION_BLOCK / PROGRAM, every VAR section, calls, value semantics."""

from __future__ import annotations

import pytest

from core_helpers import StCase, assert_case, case_params, run_cases, run_st

POU_CASES = [
    StCase("function_formal_positional_defaults", """
FUNCTION PouAdd3 : DINT
VAR_INPUT a, b : DINT; c : DINT := 10; END_VAR
PouAdd3 := a + b + c;
END_FUNCTION
PROGRAM PouCalls
VAR r1, r2, r3, r4 : DINT; END_VAR
r1 := PouAdd3(1, 2, 4);                 (* positional: all inputs *)
r2 := PouAdd3(a := 1, b := 2, c := 3);  (* formal *)
r3 := PouAdd3(b := 5, a := 1);          (* formal, any order, default for c *)
r4 := PouAdd3(PouAdd3(1, 1, 1), 2, 3);   (* nested *)
END_PROGRAM""", {"r1": 7, "r2": 6, "r3": 16, "r4": 8}),
    StCase("function_locals_start_fresh", """
FUNCTION PouFresh : INT
VAR loc : INT; END_VAR
VAR_TEMP tmp : INT; END_VAR
loc := loc + 1; tmp := tmp + 10;
PouFresh := loc + tmp;
END_FUNCTION
PROGRAM PouFreshCall
VAR a, b : INT; END_VAR
a := PouFresh();
b := PouFresh();
END_PROGRAM""", {"a": 11, "b": 11}, cycles=3),
    StCase("function_inputs_are_copies", """
TYPE PouPt : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION PouModIn : INT
VAR_INPUT v : INT; p : PouPt; arr : ARRAY[1..2] OF INT; END_VAR
v := v + 1; p.x := 99; arr[1] := 99; PouModIn := v;
END_FUNCTION
PROGRAM PouCopies
VAR v0 : INT := 1; p : PouPt; arr : ARRAY[1..2] OF INT; r : INT; END_VAR
r := PouModIn(v := v0, p := p, arr := arr);
END_PROGRAM""", {"v0": 1, "r": 2, "p": "(x := 0, y := 0)", "arr": "[0, 0]"}),
    StCase("function_returning_struct_and_call_statement", """
TYPE PouPt2 : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION PouMkPt : PouPt2
VAR_INPUT x : INT; END_VAR
PouMkPt.x := x; PouMkPt.y := x * 2;
END_FUNCTION
FUNCTION PouBump : BOOL
VAR_IN_OUT n : INT; END_VAR
n := n + 1; PouBump := TRUE;
END_FUNCTION
PROGRAM PouStructFn
VAR p : PouPt2; k : INT; END_VAR
p := PouMkPt(3);
PouBump(k);                   (* a function call as a statement: result dropped *)
PouBump(n := k);
END_PROGRAM""", {"p": "(x := 3, y := 6)", "k": 2}),
    StCase("in_out_by_reference", """
TYPE PouPt3 : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION PouSwap : BOOL
VAR_IN_OUT a, b : INT; END_VAR
VAR t : INT; END_VAR
t := a; a := b; b := t; PouSwap := TRUE;
END_FUNCTION
FUNCTION PouIncPt : BOOL
VAR_IN_OUT q : PouPt3; END_VAR
q.y := q.y + 1; PouIncPt := TRUE;
END_FUNCTION
FUNCTION_BLOCK PouDbl
VAR_IN_OUT v : INT; END_VAR
v := v * 2;
END_FUNCTION_BLOCK
PROGRAM PouInOut
VAR x : INT := 1; y : INT := 2; arr : ARRAY[0..2] OF INT := [5, 6, 7]; ok : BOOL; s : PouPt3;
    sa : ARRAY[1..2] OF PouPt3; pa : ARRAY[0..2] OF PouPt3; d : PouDbl; i : INT := 2; END_VAR
ok := PouSwap(x, y);                     (* scalars *)
PouSwap(a := arr[0], b := arr[i]);       (* array elements, computed index *)
ok := PouIncPt(s);                       (* a whole struct *)
ok := PouIncPt(q := sa[2]);              (* an array element that is a struct *)
pa[1].x := 7;
d(v := pa[1].x);                        (* a struct member inside an array element *)
END_PROGRAM""", {"x": 2, "y": 1, "arr": "[7, 6, 5]", "s": "(x := 0, y := 1)",
                 "sa": "[(x := 0, y := 0), (x := 0, y := 1)]", "pa": "[(x := 0, y := 0), (x := 14, y := 0), (x := 0, y := 0)]"}),
    StCase("in_out_through_nested_fbs", """
FUNCTION_BLOCK PouInc
VAR_IN_OUT v : INT; END_VAR
v := v + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK PouOuter
VAR_IN_OUT w : INT; END_VAR
VAR inner : PouInc; END_VAR
inner(v := w); inner(v := w);
END_FUNCTION_BLOCK
PROGRAM PouNested
VAR o : PouOuter; counter : INT; ia : ARRAY[1..2] OF INT; END_VAR
o(w := counter);
o(w := ia[2]);
END_PROGRAM""", {"counter": 6, "ia": "[0, 6]"}, cycles=3),
    StCase("in_out_sees_writes_immediately", """
FUNCTION_BLOCK PouProbe
VAR_IN_OUT v : INT; END_VAR
VAR_INPUT mirror : INT; END_VAR
VAR_OUTPUT seen, copy : INT; END_VAR
v := 42;
seen := v;
copy := mirror;               (* an input is a copy taken at the call *)
END_FUNCTION_BLOCK
PROGRAM PouAlias
VAR p : PouProbe; x : INT := 1; END_VAR
p(v := x, mirror := x);
END_PROGRAM""", {"x": 42, "p.seen": 42, "p.copy": 1}),
    StCase("fb_state_persists_and_omitted_inputs_keep", """
FUNCTION_BLOCK PouCounter
VAR_INPUT inc : INT := 1; END_VAR
VAR_OUTPUT count : INT; END_VAR
VAR_TEMP tmp : INT; END_VAR
tmp := tmp + 1;                      (* VAR_TEMP: fresh at every call *)
count := count + inc * tmp;
END_FUNCTION_BLOCK
PROGRAM PouState
VAR a, b, c : PouCounter; n : INT; END_VAR
n := n + 1;
a();
IF n = 1 THEN b(inc := 5); ELSE b(); END_IF;    (* omitted input keeps 5 *)
IF n = 3 THEN c(); END_IF;                      (* not called: unchanged *)
END_PROGRAM""", {"a.count": 4, "b.count": 20, "c.count": 1, "b.inc": 5}, cycles=4),
    StCase("fb_outputs_and_binding", """
TYPE PouPt4 : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK PouSrc
VAR_INPUT a : INT := 5; en : BOOL; END_VAR
VAR_OUTPUT q : INT; b : BOOL; calls : INT; END_VAR
calls := calls + 1; q := a * 10; b := en;
END_FUNCTION_BLOCK
PROGRAM PouBind
VAR s : PouSrc; p : PouPt4; arr : ARRAY[1..3] OF INT; nb : BOOL; before : INT; keep : INT; n : INT; END_VAR
n := n + 1;
before := s.q;                         (* what the last call left *)
IF n = 1 THEN
  s(q => p.x, a := 3, en := TRUE, q => arr[2], NOT b => nb);   (* `=>` anywhere, twice, NOT *)
ELSE
  s(q => keep);
END_IF;
END_PROGRAM""", {"before": 30, "p": "(x := 30, y := 0)", "arr": "[0, 30, 0]", "nb": False, "keep": 30,
                 "s.calls": 2}, cycles=2),
    StCase("output_binding_into_in_out_member_global_and_wider", """
TYPE Pou_Conn : STRUCT x : INT; w : WORD; sock : INT; END_STRUCT; END_TYPE
VAR_GLOBAL gBound : INT; END_VAR
FUNCTION_BLOCK Pou_Src
VAR_OUTPUT q : INT; END_VAR
q := 42;
END_FUNCTION_BLOCK
FUNCTION_BLOCK Pou_User
VAR_IN_OUT c : Pou_Conn; END_VAR
VAR s : Pou_Src; END_VAR
s(q => c.sock);                 (* sysmac.md 3 #6: Socket=>CBT.Socket *)
c.w.3 := TRUE;                  (* bit access through an in-out member *)
END_FUNCTION_BLOCK
FUNCTION Pou_WithOut : INT
VAR_INPUT a : INT; END_VAR
VAR_OUTPUT o : INT; END_VAR
o := a * 3; Pou_WithOut := a;
END_FUNCTION
PROGRAM Pou_Outs
VAR_EXTERNAL gBound : INT; END_VAR
VAR c : Pou_Conn; u : Pou_User; s : Pou_Src; wide : DINT; r, o : INT; seen : INT; END_VAR
u(c := c);
s(q => gBound);
s(q => wide);                   (* INT output into a DINT: widened *)
r := Pou_WithOut(a := 2, o => o);
seen := gBound;
END_PROGRAM""", {"c": "(x := 0, w := 8, sock := 42)", "seen": 42, "wide": 42, "r": 2, "o": 6}),
    StCase("array_star_views_from_an_element", """
FUNCTION Pou_Sum2 : DINT
VAR_IN_OUT data : ARRAY[*] OF INT; END_VAR
VAR i : DINT; END_VAR
FOR i := 0 TO 1 DO Pou_Sum2 := Pou_Sum2 + data[i]; END_FOR;
data[0] := 0;
END_FUNCTION
PROGRAM Pou_Views
VAR nums : ARRAY[1..4] OF INT := [1, 2, 3, 4]; t1, t2 : DINT; END_VAR
t1 := Pou_Sum2(nums[2]);        (* sysmac.md 3 #4: the array from element 2 on *)
t2 := Pou_Sum2(nums);
END_PROGRAM""", {"t1": 5, "t2": 1, "nums": "[0, 0, 3, 4]"}),
    StCase("string_inputs_and_results_truncate_to_their_size", """
FUNCTION Pou_Short : STRING[4]
VAR_INPUT s : STRING[3]; END_VAR
Pou_Short := CONCAT(s, 'xyz');
END_FUNCTION
PROGRAM Pou_Strs
VAR r : STRING; END_VAR
r := Pou_Short('abcdef');       (* input keeps 'ab', the result 'abx' *)
END_PROGRAM""", {"r": "'abx'"}),
    StCase("program_var_temp_is_fresh_each_scan", """
PROGRAM PouTemp
VAR_TEMP t : INT; END_VAR
VAR kept, seen : INT; END_VAR
t := t + 1; kept := kept + 1; seen := t;
END_PROGRAM""", {"seen": 1, "kept": 5}, cycles=5),
    StCase("constants", """
FUNCTION_BLOCK PouKFb
VAR CONSTANT Step : INT := 3; END_VAR
VAR_OUTPUT v : INT; END_VAR
v := v + Step;
END_FUNCTION_BLOCK
PROGRAM PouConst
VAR CONSTANT K : INT := 2; Name : STRING[8] := 'konst'; END_VAR
VAR x : INT; f : PouKFb; s : STRING[8]; END_VAR
x := x + K; f(); s := Name;
END_PROGRAM""", {"x": 6, "f.v": 9, "s": "'konst'"}, cycles=3),
    StCase("retain_and_var_sections_together", """
PROGRAM PouRetain
VAR RETAIN kept : INT := 10; END_VAR
VAR NON_RETAIN other : INT; END_VAR
VAR CONSTANT Step : INT := 5; END_VAR
kept := kept + Step; other := other + 1;
END_PROGRAM""", {"kept": 25, "other": 3}, cycles=3),
    StCase("case_insensitive_names_and_pins", """
FUNCTION_BLOCK PouPins
VAR_INPUT ConnectionTimeOut : INT; END_VAR
VAR_OUTPUT Done : BOOL; END_VAR
Done := connectiontimeout > 0;
END_FUNCTION_BLOCK
PROGRAM PouCase
VAR Inst : PouPins; FLAG : BOOL; END_VAR
inst(CONNECTIONTIMEOUT := 5);
flag := INST.done;
END_PROGRAM""", {"FLAG": True, "inst.DONE": True}),
    StCase("stdlib_fb_in_user_code_reads_vm_clock", """
PROGRAM PouTimer
VAR t : TON; q5, q6 : BOOL; n : INT; et : TIME; r : R_TRIG; edges : INT; END_VAR
n := n + 1;
t(IN := TRUE, PT := T#50ms);
IF n = 5 THEN q5 := t.Q; END_IF;
IF n = 6 THEN q6 := t.Q; et := t.ET; END_IF;
r(CLK := n MOD 3 = 1);
IF r.Q THEN edges := edges + 1; END_IF;
END_PROGRAM""", {"q5": False, "q6": True, "et": "T#50ms", "edges": 3}, cycles=7),
]


@pytest.fixture(scope="module")
def results():
    return run_cases(POU_CASES)


@pytest.mark.parametrize("case", case_params(POU_CASES))
def test_pou(case, results):
    assert_case(case, results[case.name])


# ================================================================ globals and externals
GLOBALS = """
VAR_GLOBAL gCount : DINT; gName : STRING[10] := 'init'; END_VAR
VAR_GLOBAL CONSTANT gStep : DINT := 2; END_VAR
FUNCTION_BLOCK Bumper
VAR_EXTERNAL gCount : DINT; END_VAR
VAR_EXTERNAL CONSTANT gStep : DINT; END_VAR
gCount := gCount + gStep;
END_FUNCTION_BLOCK
PROGRAM Main
VAR_EXTERNAL gCount : DINT; gName : STRING[10]; END_VAR
VAR b : Bumper; seen : DINT; END_VAR
b();
seen := gCount;
gName := 'main';
END_PROGRAM
"""


def test_globals_shared_through_var_external():
    out = run_st(GLOBALS, cycles=3, prints=["gCount", "Main.seen", "gName"], fmt=True)
    assert out == {"gCount": "6", "Main.seen": "6", "gName": "'main'"}


# ================================================================ declaration order and files
ORDER_FILES = {
    # uses everything before it is declared, in this file or the next ones
    "a_main.st": """
PROGRAM Main
VAR_EXTERNAL gLimit : INT; END_VAR
VAR acc : Accumulator; p : LaterPoint; c : LaterColor := LaterColor#Blue; r : INT; k : INT; END_VAR
acc(step := Helper(2));
p.x := acc.total;
CASE c OF Blue: k := 1; ELSE k := 2; END_CASE;
r := gLimit;
END_PROGRAM
""",
    "b_fb.st": """
FUNCTION_BLOCK Accumulator
VAR_INPUT step : INT; END_VAR
VAR_OUTPUT total : INT; END_VAR
VAR pt : LaterPoint; END_VAR
total := total + step; pt.x := total;
END_FUNCTION_BLOCK
""",
    "c_types.st": """
FUNCTION Helper : INT
VAR_INPUT x : INT; END_VAR
Helper := x * Factor;
END_FUNCTION
TYPE LaterPoint : STRUCT x : INT; y : INT; END_STRUCT; LaterColor : (Red, Blue); END_TYPE
VAR_GLOBAL gLimit : INT := 77; END_VAR
VAR_GLOBAL CONSTANT Factor : INT := 3; END_VAR
""",
}


@pytest.mark.parametrize("order", [("a_main.st", "b_fb.st", "c_types.st"), ("c_types.st", "b_fb.st", "a_main.st"),
                                   ("b_fb.st", "a_main.st", "c_types.st")], ids=["abc", "cba", "bac"])
def test_file_and_declaration_order_do_not_matter(order):
    files = {name: ORDER_FILES[name] for name in order}
    out = run_st(files, cycles=2, prints=["Main.p.x", "Main.k", "Main.r"])
    assert out == {"Main.p.x": 12, "Main.k": 1, "Main.r": 77}
