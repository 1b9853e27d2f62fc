"""Elementary and derived types on the VM (sysmac.md 2): wraparound, result types, REAL rounding,
TIME/DATE arithmetic, STRING[n], literals, structs, enums, arrays, aliases, subranges, namespaces."""

from __future__ import annotations

import calendar

import numpy as np
import pytest

from core_helpers import StCase, assert_case, case_params, run_cases, run_st

S = 1_000_000_000
MS = 1_000_000


def f32(x: float) -> float:
    return float(np.float32(x))


def f32_sum(step: float, n: int) -> float:
    acc = np.float32(0.0)
    for _ in range(n):
        acc = np.float32(acc + np.float32(step))
    return float(acc)


def wrap(v: int, bits: int, signed: bool) -> int:
    v &= (1 << bits) - 1
    if signed and v >= 1 << (bits - 1):
        v -= 1 << bits
    return v


def epoch_ns(*parts) -> int:
    return calendar.timegm(parts + (0,) * (6 - len(parts))) * S


# ================================================================ integers: wraparound
WRAP_TYPES = [("SINT", 8, True), ("INT", 16, True), ("DINT", 32, True), ("LINT", 64, True),
              ("USINT", 8, False), ("UINT", 16, False), ("UDINT", 32, False), ("ULINT", 64, False),
              ("BYTE", 8, False), ("WORD", 16, False), ("DWORD", 32, False), ("LWORD", 64, False)]


def _wrap_case(name: str, bits: int, signed: bool) -> StCase:
    hi = (1 << (bits - 1)) - 1 if signed else (1 << bits) - 1
    lo = -(1 << (bits - 1)) if signed else 0
    return StCase(f"wrap_{name.lower()}", f"""
PROGRAM W_{name}
VAR up : {name} := {hi}; down : {name} := {lo}; twice : {name} := {hi}; mul : {name} := {hi}; END_VAR
up := up + 1;
down := down - 1;
twice := twice + twice;
mul := mul * {name}#3;
END_PROGRAM""", {"up": lo, "down": hi, "twice": wrap(2 * hi, bits, signed), "mul": wrap(3 * hi, bits, signed)})


TYPE_CASES = [_wrap_case(*t) for t in WRAP_TYPES] + [
    StCase("wrap_over_scans", """
PROGRAM W_Scans
VAR s : SINT := 120; u : USINT := 250; END_VAR
s := s + 1; u := u + 1;
END_PROGRAM""", {"s": -126, "u": 4}, cycles=10),
    StCase("negation_wraps", """
PROGRAM W_Neg
VAR a : INT := -32768; b : INT; u : USINT := 1; nu : USINT; d : DINT := -2147483648; nd : DINT; END_VAR
b := -a; nu := -u; nd := -d;
END_PROGRAM""", {"b": -32768, "nu": 255, "nd": -2147483648}),

    # ---- result type: highest rank, same rank signed+unsigned -> unsigned, before widening
    StCase("computed_before_widening", """
PROGRAM R_Widen
VAR i : INT := 300; d1 : DINT; li : LINT; l2 : LINT; us : USINT := 200; w16 : UINT; END_VAR
d1 := i * i;                            (* INT * INT wraps at 16 bits, then widens *)
li := UDINT#16#FFFF_FFFF + DINT#1;      (* sysmac.md 2: 0 even in a LINT *)
l2 := LINT#2147483647 + DINT#1;         (* LINT wins: no wrap *)
w16 := us + us;                         (* USINT + USINT wraps at 8 bits *)
END_PROGRAM""", {"d1": 24464, "li": 0, "l2": 2147483648, "w16": 144}),
    StCase("same_rank_signed_unsigned_is_unsigned", """
PROGRAM R_Sign
VAR sn : SINT := -1; us : USINT := 2; q : USINT; m : USINT; lt : BOOL; i : INT := -7; ui : UINT := 3; q2 : UINT; s2 : UINT; END_VAR
q := sn / us;          (* computed in USINT: 255 / 2 *)
m := sn MOD us;
lt := sn < us;         (* compared in USINT: 255 < 2 *)
q2 := i / ui;          (* 65529 / 3 *)
s2 := sn + us;
END_PROGRAM""", {"q": 127, "m": 1, "lt": False, "q2": 21843, "s2": 1}),
    StCase("higher_rank_wins", """
PROGRAM R_Rank
VAR s : SINT := -100; i : INT := 1000; r : INT; d : DINT := 100000; ud : UDINT; x : DINT; END_VAR
r := s * i;                  (* INT *)
x := d * i;                  (* DINT *)
ud := UINT#65535 + UDINT#1;  (* UDINT: no wrap at 16 bits *)
END_PROGRAM""", {"r": -100000 + 131072, "x": 100000000, "ud": 65536}),
    StCase("implicit_widening_and_same_size", """
PROGRAM R_Implicit
VAR i : INT := -1; u : UINT; s : SINT := -5; d : DINT; us : USINT := 200; i2 : INT; ui : UINT := 40000;
    r : REAL; lr : LREAL; lw : LINT; big : DINT := 16777217; lr2 : LREAL; END_VAR
u := i;              (* same size: bits kept *)
d := s;              (* SINT -> DINT *)
i2 := us;            (* USINT -> INT *)
r := ui;             (* UINT -> REAL (thesis ChangeTCP) *)
lw := d;
lr := big;           (* DINT -> LREAL exactly *)
lr2 := r;            (* REAL -> LREAL keeps the float32 value *)
END_PROGRAM""", {"u": 65535, "d": -5, "i2": 200, "r": 40000.0, "lw": -5, "lr": 16777217.0, "lr2": 40000.0}),
    StCase("untyped_literal_thesis_timeout", """
PROGRAM R_Thesis
VAR t60 : UINT := 60; t10 : UINT := 10; t22 : UINT := 22; a, b, c : LINT; END_VAR
a := t60 * 100000000;      (* sysmac.md 8 #7: UINT * DINT literal wraps at 32 bits *)
b := t10 * 100000000;
c := t22 * 100000000;
END_PROGRAM""", {"a": 1705032704, "b": 1000000000, "c": wrap(22 * 100000000, 32, True)}),

    # ---- integer division and MOD (IEC: truncate toward zero, MOD has the dividend's sign)
    StCase("int_division_and_mod", """
PROGRAM R_Div
VAR a, b, c, d, e, f, g, h : DINT; m : INT := -32768; m2 : INT; END_VAR
a := 7 / 2; b := -7 / 2; c := 7 / -2; d := -7 / -2;
e := 7 MOD 3; f := -7 MOD 3; g := 7 MOD -3; h := -7 MOD -3;
m2 := m / INT#-1;           (* wraps, no fault *)
END_PROGRAM""", {"a": 3, "b": -3, "c": -3, "d": 3, "e": 1, "f": -1, "g": 1, "h": -1, "m2": -32768}),

    # ---- bit strings
    StCase("bitstring_ops", """
PROGRAM R_Bits
VAR a : WORD := 16#0FF0; b : WORD := 16#00FF; x, o, n, aa : WORD; bx : BYTE; b1 : BYTE := 16#5A; b2 : BYTE := 16#FF;
    dw : DWORD; lw : LWORD; END_VAR
x := a XOR b; o := a OR b; aa := a AND b; n := NOT b;
bx := b1 XOR b2;
dw := NOT DWORD#0;
lw := NOT LWORD#0;
END_PROGRAM""", {"x": 0x0F0F, "o": 0x0FFF, "aa": 0x00F0, "n": 0xFF00, "bx": 0xA5, "dw": 2**32 - 1, "lw": 2**64 - 1}),
    StCase("bit_access", """
PROGRAM R_BitAccess
VAR w : WORD := 16#00F0; b4, b0, b15 : BOOL; w2 : WORD; bt : BYTE; END_VAR
b4 := w.4; b0 := w.0;
w.0 := TRUE; w.4 := FALSE; w.15 := TRUE;
w2 := w; b15 := w.15;
bt.7 := TRUE;
END_PROGRAM""", {"b4": True, "b0": False, "w2": 0x80E1, "b15": True, "bt": 128}),
    StCase("bool_logic", """
PROGRAM R_Bool
VAR t : BOOL := TRUE; f : BOOL; a, o, x, n, amp, cmp : BOOL; END_VAR
a := t AND f; o := t OR f; x := t XOR t; n := NOT f; amp := t & t; cmp := t = NOT f;
END_PROGRAM""", {"a": False, "o": True, "x": False, "n": True, "amp": True, "cmp": True}),

    # ---- REAL (float32 on every store) vs LREAL
    StCase("real_rounds_to_float32", """
PROGRAM F_Real
VAR r : REAL; lr : LREAL; big : REAL := 16777216.0; bigl : LREAL := 16777216.0; acc : REAL; lacc : LREAL;
    i : INT; q : REAL; lq : LREAL; a : REAL := 7.0; b : REAL := 3.0; wide : LREAL; END_VAR
r := 0.1; lr := 0.1;
big := big + 1.0; bigl := bigl + 1.0;
FOR i := 1 TO 10 DO acc := acc + 0.1; lacc := lacc + 0.1; END_FOR;
q := a / b; lq := a / b;     (* REAL / REAL is computed in REAL, then widened *)
wide := r;
END_PROGRAM""", {"r": f32(0.1), "lr": 0.1, "big": 16777216.0, "bigl": 16777217.0,
                 "acc": f32_sum(0.1, 10), "lacc": sum([0.1] * 10, 0.0),
                 "q": f32(7 / 3), "lq": f32(7 / 3), "wide": f32(0.1)}),
    StCase("real_special_values", """
PROGRAM F_Special
VAR r : REAL := 1.0E38; big : REAL; z : REAL; inf : REAL; ninf : LREAL; lz : LREAL; isnan : BOOL; nn : REAL; END_VAR
big := r * 10.0;            (* float32 overflow -> +inf *)
inf := r / z;
ninf := -1.0 / lz;
nn := z / z;
isnan := nn <> nn;
END_PROGRAM""", {"big": float("inf"), "inf": float("inf"), "ninf": float("-inf"), "isnan": True}),
    StCase("real_mixed_with_int", """
PROGRAM F_Mixed
VAR r : REAL := 1.5; us : USINT := 200; i : INT := 3; d : DINT := 16777217; a : REAL; b : LREAL; c : REAL; END_VAR
a := r * us;        (* 8/16-bit int with REAL: REAL *)
b := r * d;         (* 32-bit int with REAL: LREAL (stvm's Choice), no precision lost *)
c := i / 2.0;
END_PROGRAM""", {"a": 300.0, "b": 1.5 * 16777217, "c": 1.5}),
    StCase("expt", """
PROGRAM F_Expt
VAR p : LREAL; q : LREAL; r : LREAL; END_VAR
p := 2.0 ** 10;
q := -2.0 ** 2.0;       (* unary minus binds tighter: (-2)**2 *)
r := 2.0 ** 0.5;
END_PROGRAM""", {"p": 1024.0, "q": 4.0, "r": 2 ** 0.5}),

    # ---- literals: typed, based, grouped, exponents
    StCase("literals", """
PROGRAM L_Lits
VAR a : INT := 16#7FFF; b : DINT := 2#1010_1010; c : DINT := 8#777; d : DINT := 1_000_000; e : REAL := 1.5e3;
    f : LREAL := 2E-2; g : INT := INT#-5; h : BYTE := BYTE#16#0A; k : BOOL := BOOL#1; l : REAL := REAL#-2.5;
    m : UINT := UINT#5; n : LREAL := 1.0E+300; o : DINT; p : REAL := 3; q : WORD := 16#FFFF; END_VAR
o := 16#10 + 2#11 + 8#10 + 1_0;
END_PROGRAM""", {"a": 32767, "b": 170, "c": 511, "d": 1000000, "e": 1500.0, "f": 0.02, "g": -5, "h": 10,
                 "k": True, "l": -2.5, "m": 5, "n": 1e300, "o": 16 + 3 + 8 + 10, "p": 3.0, "q": 65535}),

    # ---- TIME, DATE, TOD, DT
    StCase("time_literals_and_arithmetic", """
PROGRAM T_Time
VAR t1 : TIME := T#1s; a, b, c, d, e, f, g : TIME; lt, ge : BOOL; x : TIME := T#1h2m3s4ms5us6ns; END_VAR
a := t1 + T#500ms;
b := t1 - T#2s;
c := t1 * 3;
d := t1 / 4;
e := -t1;
f := TIME#1m30s + T#1.5s;
g := T#1d - T#1ns;
lt := a < c; ge := t1 >= T#1000ms;
END_PROGRAM""", {"a": 1500 * MS, "b": -1 * S, "c": 3 * S, "d": 250 * MS, "e": -S, "f": 91500 * MS,
                 "g": 86400 * S - 1, "lt": True, "ge": True, "x": 3723004005006}),
    StCase("date_tod_dt", """
PROGRAM T_Date
VAR d : DATE := D#2024-02-29; tod1 : TOD := TOD#23:00:00; tod2 : TOD; dt1 : DT := DT#2024-01-01-00:00:00; dt2 : DT;
    span : TIME; span2 : TIME; dflt : DT; dd : DATE := DATE#1970-01-02; later : BOOL; END_VAR
tod2 := tod1 + T#30m;
dt2 := dt1 + T#1d2h;
span := dt2 - dt1;
span2 := TOD#12:00:00 - TOD#11:59:59.5;
later := dt2 > dt1;
END_PROGRAM""", {"d": epoch_ns(2024, 2, 29), "tod2": (23 * 3600 + 1800) * S,
                 "dt2": epoch_ns(2024, 1, 2, 2), "span": (26 * 3600) * S, "span2": 500 * MS,
                 "dflt": 0, "dd": 86400 * S, "later": True}),

    # ---- STRING[n]
    StCase("strings", """
PROGRAM Str_Basic
VAR s5 : STRING[5]; s : STRING := 'a$'b$$c$L$R$T$P$41'; e : STRING; p : STRING(10);
    eq, ne, lt : BOOL; s1 : STRING[10] := 'abc'; s2 : STRING := 'abc'; u : STRING := 'ü€'; u3 : STRING[3];
    cut : STRING[4]; nul : STRING := 'ab$00cd'; frame : STRING := '$$TMSTA,2,00,*41$R$L'; END_VAR
s5 := 'hello world';            (* STRING[5]: 4 text bytes *)
p := 'abcdefghijklmnop';
eq := s1 = s2; ne := s1 <> 'abd'; lt := s1 < 'abd';
u3 := u;                        (* 2 bytes: never cut inside a UTF-8 character *)
cut := CONCAT('abc', 'def');
END_PROGRAM""", {"s5": b"hell", "s": b"a'b$c\n\r\t\x0cA", "e": b"", "p": b"abcdefghi", "eq": True, "ne": True,
                 "lt": True, "u3": "ü".encode(), "cut": b"abc", "nul": b"ab", "frame": b"$TMSTA,2,00,*41\r\n"}),
    StCase("string_default_size", """
PROGRAM Str_Default
VAR s : STRING; n, n2 : UINT; i : INT; acc : STRING; END_VAR
s := '""" + "0123456789" * 200 + """';   (* 2000 bytes into STRING = 1986: 1985 text bytes *)
n := LEN(s);
FOR i := 1 TO 200 DO acc := CONCAT(acc, '0123456789'); END_FOR;
n2 := LEN(acc);                 (* CONCAT over 1985 bytes is an instruction error: stays at 1980 *)
END_PROGRAM""", {"n": 1985, "n2": 1980}),

    # ---- STRUCT
    StCase("struct_init_nested_copy", """
TYPE
  D_Pt : STRUCT x : INT := 1; y : INT := 2; END_STRUCT;
  D_Line : STRUCT a : D_Pt; b : D_Pt := (x := 5, y := 6); name : STRING[10] := 'ln'; END_STRUCT;
END_TYPE
PROGRAM D_Struct
VAR p : D_Pt; l : D_Line; l2 : D_Line; q : D_Pt := (y := 9); ax, bx, px : INT; copy : D_Pt; END_VAR
l2 := l;
l2.a.x := 100;                  (* a copy: l unchanged *)
ax := l.a.x; bx := l2.a.x;
p := l.b;
copy := p; p.x := 55; px := copy.x;
END_PROGRAM""", {"ax": 1, "bx": 100, "p": "(x := 55, y := 6)", "q": "(x := 1, y := 9)", "px": 5,
                 "l": "(a := (x := 1, y := 2), b := (x := 5, y := 6), name := 'ln')",
                 "l2": "(a := (x := 100, y := 2), b := (x := 5, y := 6), name := 'ln')"}),

    StCase("nested_struct_and_array_initialisers", """
TYPE I_Pt : STRUCT x : INT; y : INT; END_STRUCT; I_Line : STRUCT a : I_Pt; b : I_Pt; name : STRING[5]; END_STRUCT; END_TYPE
PROGRAM I_Inits
VAR l : I_Line := (a := (x := 1), name := 'q', b := (y := 2, x := 3));
    ps : ARRAY[1..4] OF I_Pt := [2((x := 1)), (y := 5)];     (* repetition of a struct; the rest default *)
    part : ARRAY[0..4] OF INT := [7, 8];
    t : TIME := T#1s; scaled : TIME; END_VAR
scaled := t * 2.5;
END_PROGRAM""", {"l": "(a := (x := 1, y := 0), b := (x := 3, y := 2), name := 'q')",
                 "ps": "[(x := 1, y := 0), (x := 1, y := 0), (x := 0, y := 5), (x := 0, y := 0)]",
                 "part": "[7, 8, 0, 0, 0]", "scaled": "T#2s500ms"}),

    # ---- ENUM
    StCase("enums", """
TYPE
  E_Color : (Red, Green, Blue);
  E_Level : INT (Low := 10, High := 20);
  E_Gap : (G0 := 0, G5 := 5, G6);
END_TYPE
PROGRAM E_Enum
VAR c : E_Color; c2 : E_Color := E_Color#Blue; c3 : E_Color; lv : E_Level; lv2 : E_Level := High;
    eq, ne : BOOL; g : E_Gap := G6; END_VAR
c3 := Green;
lv := E_Level#High;
eq := c2 = E_Color#Blue; ne := c <> c3;
END_PROGRAM""", {"c": "E_Color#Red", "c2": "E_Color#Blue", "c3": "E_Color#Green", "lv": "E_Level#High",
                 "lv2": 20, "eq": True, "ne": True, "g": 6}),
    StCase("enum_type_default_initial_value", """
TYPE E_Mode : (Off := 5, On := 7) := On; END_TYPE
PROGRAM E_Default
VAR m : E_Mode; END_VAR
END_PROGRAM""", {"m": "E_Mode#On"}),

    # ---- ARRAY
    StCase("arrays_bounds_multidim_init", """
PROGRAM A_Arr
VAR a2 : ARRAY[-2..2] OF INT := [1, 2(7), 2(0)]; m3 : ARRAY[1..2, 0..2] OF INT := [1, 2, 3, 4, 5, 6];
    rep : ARRAY[0..5] OF INT := [3(1), 3(2)]; k, j : INT; arr : ARRAY[1..3] OF INT := [5, 6, 7]; cp : ARRAY[1..3] OF INT;
    other : ARRAY[0..2] OF INT; big : ARRAY[1000..1002] OF DINT := [1000, 1001, 1002]; sum : DINT; i : INT; END_VAR
k := a2[-1] + m3[2, 1];
j := m3[1, 2];
cp := arr; arr[1] := 99;         (* assignment copies *)
other := cp;                     (* same length, other bounds *)
FOR i := 1000 TO 1002 DO sum := sum + big[i]; END_FOR;
END_PROGRAM""", {"k": 12, "j": 3, "a2": "[1, 7, 7, 0, 0]", "m3": "[[1, 2, 3], [4, 5, 6]]", "rep": "[1, 1, 1, 2, 2, 2]",
                 "cp": "[5, 6, 7]", "other": "[5, 6, 7]", "arr": "[99, 6, 7]", "sum": 3003}),
    StCase("arrays_of_structs_and_fbs", """
TYPE A_Pt : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK A_Acc
VAR_INPUT v : INT; END_VAR
VAR_OUTPUT total : INT; END_VAR
total := total + v;
END_FUNCTION_BLOCK
PROGRAM A_Agg
VAR ps : ARRAY[0..1] OF A_Pt := [(x := 9), (y := 8)]; arr1 : ARRAY[0..2] OF A_Pt; arr2 : ARRAY[1..3] OF A_Pt;
    fbs : ARRAY[1..3] OF A_Acc; i : INT; t1, t3 : INT; END_VAR
arr1[1].x := 5; arr2 := arr1; arr1[1].x := 6;
FOR i := 1 TO 3 DO fbs[i](v := i); END_FOR;
t1 := fbs[1].total; t3 := fbs[3].total;
END_PROGRAM""", {"ps": "[(x := 9, y := 0), (x := 0, y := 8)]", "arr2": "[(x := 0, y := 0), (x := 5, y := 0), (x := 0, y := 0)]",
                 "t1": 2, "t3": 6}, cycles=2),

    # ---- aliases and subranges
    StCase("aliases_and_subranges", """
TYPE D_Count : DINT; D_Small : INT (0..10); D_Name : STRING[4]; D_Vec : ARRAY[1..3] OF INT; END_TYPE
PROGRAM D_Alias
VAR c : D_Count := 5; d : DINT; sm : D_Small := 3; n : D_Name; v : D_Vec; w : D_Vec; END_VAR
d := c * 2;
sm := sm + 5;
n := 'abcdef';
v[2] := 4; w := v;
END_PROGRAM""", {"d": 10, "sm": 8, "n": b"abc", "w": [0, 4, 0]}),
    StCase("alias_type_initial_value", """
TYPE D_Seven : INT := 7; END_TYPE
PROGRAM D_AliasInit
VAR s : D_Seven; END_VAR
END_PROGRAM""", {"s": 7}),
    StCase("array_type_initial_value", """
TYPE D_Fours : ARRAY[1..3] OF INT := [3(4)]; END_TYPE
PROGRAM D_ArrInit
VAR v : D_Fours; END_VAR
END_PROGRAM""", {"v": [4, 4, 4]}),

    # ---- default initial values (sysmac.md 1)
    StCase("defaults", """
TYPE Z_E : (First, Second); Z_S : STRUCT b : BOOL; t : TIME; s : STRING[5]; e : Z_E; END_STRUCT; END_TYPE
PROGRAM Z_Defaults
VAR b : BOOL; i : LINT; r : REAL; s : STRING; t : TIME; dt : DT; e : Z_E; st : Z_S; a : ARRAY[1..2] OF Z_S; END_VAR
END_PROGRAM""", {"b": "FALSE", "i": "0", "r": "0.0", "s": "''", "t": "T#0s", "dt": "DT#1970-01-01-00:00:00",
                 "e": "Z_E#First", "st": "(b := FALSE, t := T#0s, s := '', e := Z_E#First)"}),
]


@pytest.fixture(scope="module")
def results():
    return run_cases(TYPE_CASES)


@pytest.mark.parametrize("case", case_params(TYPE_CASES))
def test_types(case, results):
    assert_case(case, results[case.name])


# ================================================================ outside the shared load
NAMESPACE_FILES = {
    "main.st": r"""
PROGRAM Main
VAR
  conn : CBT_Commands_Lib\stCBT_Connection;
  mv : CBT_Commands_Lib\eCBT_MovCmd_Movement := CBT_Commands_Lib\eCBT_MovCmd_Movement#PTP;
  mv2 : CBT_Commands_Lib\eCBT_MovCmd_Movement;
  bo : _eBYTE_ORDER := _eBYTE_ORDER#_HIGH_LOW;
  cs : _eCONNECTION_STATE;
  r : INT; fb : CBT_Commands_Lib\Helper; isline : BOOL;
END_VAR
mv2 := \\CBT_Commands_Lib\eCBT_MovCmd_Movement#Line;
isline := mv2 = CBT_Commands_Lib\eCBT_MovCmd_Movement#Line;
cs := _CLOSE_WAIT;
conn.Count := conn.Count + 1;
fb(c := conn);
r := CBT_Commands_Lib\Twice(21);
END_PROGRAM
""",
    "lib.st": r"""
NAMESPACE CBT_Commands_Lib
TYPE
  eCBT_MovCmd_Movement : (Line := 0, PTP := 1);
  stCBT_Connection : STRUCT Count : INT; Mode : eCBT_MovCmd_Movement := PTP; END_STRUCT;
END_TYPE
FUNCTION Twice : INT
VAR_INPUT x : INT; END_VAR
Twice := x * 2;
END_FUNCTION
FUNCTION_BLOCK Helper
VAR_IN_OUT c : stCBT_Connection; END_VAR
c.Count := Twice(c.Count);           (* short names inside the own namespace *)
c.Mode := eCBT_MovCmd_Movement#Line;
END_FUNCTION_BLOCK
END_NAMESPACE
""",
}


def test_namespaces_and_sysmac_enum_literals():
    out = run_st(NAMESPACE_FILES, cycles=1,
                 prints=["Main.conn.Count", "Main.mv", "Main.mv2", "Main.bo", "Main.cs", "Main.r", "Main.isline"])
    assert out["Main.conn.Count"] == 2
    assert out["Main.mv"] == 1 and out["Main.mv2"] == 0
    assert out["Main.bo"] == 1              # _HIGH_LOW (byte_order_values default)
    assert out["Main.cs"] == 5              # _CLOSE_WAIT (BSD order default)
    assert out["Main.r"] == 42 and out["Main.isline"] is True


def test_int_literal_type_lint_setting_removes_32_bit_wrap():
    from stvm.settings import SysmacSettings
    src = """
PROGRAM Main
VAR t60 : UINT := 60; a : LINT; END_VAR
a := t60 * 100000000;
END_PROGRAM"""
    assert run_st(src, prints=["Main.a"])["Main.a"] == 1705032704
    lint = run_st(src, prints=["Main.a"], settings=SysmacSettings(int_literal_type="lint"))
    assert lint["Main.a"] == 6_000_000_000
