"""Dialect profiles (stvm/dialects.py, docs/dialects.md): every row of the table, in every profile.

Each row has a probe: a small program whose result shows the row's value in one dialect (the
values a run prints, or the errors a load reports). The test runs the probe under each dialect and
compares with what the row says for it, so the table and the behaviour cannot drift apart.
"""

from __future__ import annotations

from typing import Any, Callable

import pytest

import stvm
from core_helpers import load_st
from stvm.dialects import BY_KEY, PROFILE_FIELDS, ROWS, allows, known_library_prefix, profile_value
from stvm.settings import (ByteToStringFormat, DEFAULT_SETTINGS, Dialect, OpenArrayBounds, PointerOverrun,
                           RealToStringFormat, StringSize, SubrangeCheck, SysmacSettings)

DIALECTS = list(Dialect)


def outcome(source: str, dialect: Dialect, prints: list[str], cycles: int = 1) -> Any:
    """The values of `prints` after `cycles` scans, ("errors", [messages]) or ("fault", message)."""
    try:
        vm = load_st(source, settings=SysmacSettings(dialect=dialect)).start()
    except stvm.LoadError as exc:
        return ("errors", [d.message for d in exc.diagnostics if d.is_error])
    try:
        vm.run(cycles=cycles)
    except stvm.RuntimeFault as fault:
        return ("fault", fault.message)
    return tuple(vm[p] for p in prints)


def accepted(result: Any) -> bool:
    return not (isinstance(result, tuple) and result and result[0] == "errors")


# ---- one probe per row: (dialect, the row's value there) -> nothing, asserts --------------------

def probe_byte_to_string_format(dialect, value):
    text = outcome("PROGRAM Main VAR s : STRING; END_VAR s := BYTE_TO_STRING(BYTE#42); END_PROGRAM",
                   dialect, ["Main.s"])
    assert text == ({ByteToStringFormat.HEX_NOPAD: b"2A", ByteToStringFormat.DECIMAL: b"42"}[value],)


def probe_real_to_string_format(dialect, value):
    text = outcome("PROGRAM Main VAR s, l, t : STRING; END_VAR s := REAL_TO_STRING(3.5); "
                   "l := LREAL_TO_STRING(LREAL#1.4); t := TO_STRING(REAL#-0.25); END_PROGRAM",
                   dialect, ["Main.s", "Main.l", "Main.t"])
    expected = {RealToStringFormat.C_EXP: (b"3.500000e+00", b"1.40000000000000e+00", b"-2.500000e-01"),
                RealToStringFormat.SHORTEST: (b"3.5", b"1.4", b"-0.25"),
                RealToStringFormat.DIGITS15: (b"3.5", b"1.4", b"-0.25")}[value]
    assert text == expected
    # ten additions of 0.01 make 0.09999999999999999 in binary floating point
    small = outcome("PROGRAM Main VAR s, t : STRING; x : LREAL; i : INT; END_VAR FOR i := 1 TO 10 DO "
                    "x := x + 0.01; END_FOR s := LREAL_TO_STRING(x); t := LREAL_TO_STRING(LREAL#0.0099385); "
                    "END_PROGRAM", dialect, ["Main.s", "Main.t"])
    assert small == {RealToStringFormat.C_EXP: (b"1.00000000000000e-01", b"9.93850000000000e-03"),
                     RealToStringFormat.SHORTEST: (b"0.09999999999999999", b"0.0099385"),
                     RealToStringFormat.DIGITS15: (b"0.1", b"9.9385e-3")}[value]


def probe_string_size(dialect, value):
    source = ("PROGRAM Main VAR s : STRING[5]; n : INT; END_VAR s := 'abcdefgh'; n := LEN(s); END_PROGRAM"
              if dialect is Dialect.SYSMAC else
              "PROGRAM Main VAR s : STRING(5); n : INT; END_VAR s := 'abcdefgh'; n := LEN(s); END_PROGRAM")
    held = {StringSize.WITH_NUL: 4, StringSize.CHARACTERS: 5}[value]
    assert outcome(source, dialect, ["Main.n"]) == (held,)


def probe_open_array_bounds(dialect, value):
    source = """FUNCTION Bounds : DINT VAR_IN_OUT a : ARRAY[*] OF INT; END_VAR
Bounds := LOWER_BOUND(a, 1) * 1000 + UPPER_BOUND(a, 1); END_FUNCTION
PROGRAM Main VAR x : ARRAY[2..5] OF INT; y : ARRAY[-3..10] OF INT; bx, bY2 : DINT; END_VAR
bx := Bounds(x); bY2 := Bounds(y); END_PROGRAM"""
    expected = {OpenArrayBounds.ZERO: (3, 13), OpenArrayBounds.ACTUAL: (2005, -2990)}[value]
    assert outcome(source, dialect, ["Main.bx", "Main.bY2"]) == expected


def probe_subrange_check(dialect, value):
    result = outcome("PROGRAM Main VAR p : INT(0..100) := 90; i : INT := 20; END_VAR p := p + i; END_PROGRAM",
                     dialect, ["Main.p"])
    if value is SubrangeCheck.FAULT:
        assert result[0] == "fault"
    else:
        assert result == (110,)


def probe_pointer_overrun(dialect, value):
    result = outcome("PROGRAM Main VAR a : ARRAY[0..3] OF BYTE; p : POINTER TO BYTE; n : BYTE := 7; END_VAR\n"
                     "p := ADR(a) + 4; p^ := 16#FF; n := p^; END_PROGRAM", dialect, ["Main.a", "Main.n"])
    if dialect in (Dialect.SYSMAC, Dialect.IEC):   # no pointer arithmetic there
        assert value is PointerOverrun.FAULT and not accepted(result)
    elif value is PointerOverrun.GUARD:
        assert result == ([0, 0, 0, 0], 0)
    else:
        assert result[0] == "fault"


def probe_p_prefix_rule(dialect, value):
    result = outcome("FUNCTION P_Double : INT VAR_INPUT x : INT; END_VAR P_Double := x * 2; END_FUNCTION\n"
                     "PROGRAM Main VAR p_count : INT; END_VAR p_count := P_Double(21); END_PROGRAM",
                     dialect, ["Main.p_count"])
    assert (result == (42,)) is not value
    if value:
        assert any("may not start with 'P_'" in m for m in result[1])


def probe_wstring_literal(dialect, value):
    as_string = outcome('PROGRAM Main VAR s : STRING; END_VAR s := "abc"; END_PROGRAM', dialect, ["Main.s"])
    if value:   # a WSTRING: a STRING does not take it without WSTRING_TO_STRING
        assert outcome('PROGRAM Main VAR w : WSTRING; END_VAR w := "abc"; END_PROGRAM', dialect, ["Main.w"]) == ("abc",)
        assert not accepted(as_string)
    else:       # Sysmac: a STRING literal (with a warning)
        assert as_string == (b"abc",)


def probe_persistent(dialect, value):
    # an ordinary name everywhere
    assert outcome("PROGRAM Main VAR persistent : INT; END_VAR persistent := 3; END_PROGRAM",
                   dialect, ["Main.persistent"]) == (3,)
    result = outcome("PROGRAM Main VAR PERSISTENT kept : INT; END_VAR kept := kept + 1; END_PROGRAM",
                     dialect, ["Main.kept"], cycles=2)
    assert (result == (2,)) is value


def probe_ref_initial_value(dialect, value):
    result = outcome("PROGRAM Main VAR counter : INT := 5; r : REF_TO INT := REF(counter); v : INT; END_VAR\n"
                     "v := r^; END_PROGRAM", dialect, ["Main.v"])
    assert (result == (5,)) is value
    if not value:   # Sysmac: the message it always gave
        assert result[1] == ["initial value must be a constant expression"]
        return
    # each FB instance's reference points at its own member; globals, struct members, array
    # elements, POINTER TO with ADR(); bound at initialisation in declaration order
    result = outcome(REF_INITIAL_VALUES, dialect, ["Main.v", "Main.w", "Main.x", "Main.y", "Main.e", "Main.arr", "g"])
    assert result == (6, 6, 2, 1, 42, [0, 9, 0], 18)


REF_INITIAL_VALUES = """TYPE ST : STRUCT a : INT; b : ARRAY[1..3] OF DINT; END_STRUCT END_TYPE
VAR_GLOBAL g : INT := 7; rg : REF_TO INT := REF(g); s : ST; rs : REF_TO DINT := REF(s.b[2]); END_VAR
FUNCTION_BLOCK FB VAR n : INT; END_VAR VAR_OUTPUT r : REF_TO INT := REF(n); END_VAR n := n + 1; END_FUNCTION_BLOCK
PROGRAM Main
VAR counter : INT := 5; r : REF_TO INT := REF(counter); p : POINTER TO INT := ADR(counter); v, w : INT;
    f1, f2 : FB; x, y : INT; arr : ARRAY[0..2] OF INT; ra : REF_TO ARRAY[0..2] OF INT := REF(arr); e : DINT;
    rgl : REF_TO INT := REF(g); END_VAR
counter := counter + 1; v := r^; w := p^; f1(); f1(); f2(); x := f1.r^; y := f2.r^; rs^ := 42; e := s.b[2];
ra^[1] := 9; rg^ := rg^ + 1; rgl^ := rgl^ + 10;
END_PROGRAM
"""


@pytest.mark.parametrize(("declaration", "message"), [
    ("r : REF_TO INT := REF(later); later : INT;", "takes a variable declared before"),
    ("x : DINT; r : REF_TO INT := REF(x);", "type mismatch: cannot initialise REF_TO INT with REF() of a DINT"),
    ("a : ARRAY[1..2] OF INT; r : REF_TO INT := REF(a[3]);", "takes a variable declared before"),
    ("x : INT; i : INT := REF(x);", "can initialise a REF_TO or POINTER TO variable, not INT"),
])
def test_ref_initial_value_refusals(declaration, message):
    result = outcome(f"PROGRAM Main VAR {declaration} END_VAR END_PROGRAM", Dialect.TWINCAT, [])
    assert any(message in m for m in result[1]), result


def test_ref_initial_value_is_refused_in_a_function():
    result = outcome("FUNCTION F : INT VAR x : INT; r : REF_TO INT := REF(x); END_VAR F := 1; END_FUNCTION\n"
                     "PROGRAM Main VAR i : INT; END_VAR i := F(); END_PROGRAM", Dialect.CODESYS, [])
    assert any("only in a PROGRAM, a FUNCTION_BLOCK or VAR_GLOBAL, not in a FUNCTION" in m for m in result[1])


def probe_input_constant(dialect, value):
    result = outcome("FUNCTION_BLOCK FB VAR_INPUT CONSTANT Bits : INT; END_VAR VAR_OUTPUT q : INT; END_VAR\n"
                     "q := Bits + 1; END_FUNCTION_BLOCK\n"
                     "PROGRAM Main VAR f : FB; g : FB; END_VAR f(); g(Bits := 7); END_PROGRAM",
                     dialect, ["Main.f.q", "Main.g.q"])
    assert (result == (1, 8)) is value


def probe_pointer_arithmetic(dialect, value):
    result = outcome("PROGRAM Main VAR a : ARRAY[0..3] OF BYTE := [1, 2, 3, 4]; p : POINTER TO BYTE; v : BYTE; END_VAR\n"
                     "p := ADR(a); p := p + 1; v := p^; END_PROGRAM", dialect, ["Main.v"])
    assert (result == (2,)) is value


def probe_adr_of_constant(dialect, value):
    result = outcome("PROGRAM Main VAR CONSTANT k : INT := 5; END_VAR\n"
                     "VAR pk : POINTER TO INT; v : INT; pr : POINTER TO REAL; n : DINT; END_VAR\n"
                     "pk := ADR(k); v := pk^; n := SIZEOF(pr^); END_PROGRAM", dialect, ["Main.v", "Main.n"])
    assert (result == (5, 4)) is value
    if not value:
        assert any("ADR() of constant 'k'" in m for m in result[1])


def probe_any_input(dialect, value):
    result = outcome("FUNCTION F : DINT VAR_INPUT v : ANY; END_VAR VAR_OUTPUT c : INT; b : BYTE; END_VAR\n"
                     "c := UDINT_TO_INT(v.TypeClass); b := v.pValue[1]; F := v.diSize; END_FUNCTION\n"
                     "PROGRAM Main VAR i : INT := 16#0102; n : DINT; c : INT; b : BYTE; END_VAR\n"
                     "n := F(v := i, c => c, b => b); END_PROGRAM", dialect, ["Main.n", "Main.c", "Main.b"])
    assert (result == (2, 7, 1)) is value   # INT: 2 bytes, TYPE_INT = 7, high byte 16#01
    if not value:
        assert any("generic type ANY" in m for m in result[1])


def probe_short_times(dialect, value):
    result = outcome("TYPE U : UNION t : TIME; d : LWORD; END_UNION END_TYPE\n"
                     "PROGRAM Main VAR t : TIME := T#1500MS; a, b, c, e : DINT; u : U; w : LWORD; END_VAR\n"
                     "a := SIZEOF(t); b := SIZEOF(TOD); c := SIZEOF(LTIME); e := SIZEOF(DT);\n"
                     "u.t := t; w := u.d; END_PROGRAM"
                     if dialect in (Dialect.CODESYS, Dialect.TWINCAT, Dialect.IEC) else
                     "PROGRAM Main VAR t : TIME := T#1500MS; a, b, c, e : DINT; w : LWORD; END_VAR\n"
                     "a := SIZEOF(t); b := SIZEOF(TOD); c := SIZEOF(LTIME); e := SIZEOF(DT); w := 1500; END_PROGRAM",
                     dialect, ["Main.a", "Main.b", "Main.c", "Main.e", "Main.w"])
    # TwinCAT/CODESYS: T#1500MS is 1500 (ms) in 4 bytes; 64-bit ns elsewhere
    assert (result == (4, 4, 8, 4, 1500)) is value
    if not value and dialect is not Dialect.SYSMAC:
        assert result == (8, 8, 8, 8, 1_500_000_000)


def probe_unsigned_time(dialect, value):
    result = outcome("PROGRAM Main VAR d : LTIME; t : TIME; s : STRING; END_VAR\n"
                     "d := LTIME#0ns - LTIME#1ns; t := T#0ms - T#1ms; s := LTIME_TO_STRING(LTIME#1ms); END_PROGRAM",
                     dialect, ["Main.d", "Main.t", "Main.s"])
    # TwinCAT/CODESYS: ULINT ns and UDINT ms wrap-around; elsewhere signed 64-bit ns
    assert (result == (2**64 - 1, (2**32 - 1) * 1_000_000, b"LTIME#1ms")) is value
    if not value:
        assert result == (-1, -1_000_000, b"LT#1ms")
    largest = outcome("PROGRAM Main VAR d : LTIME := LTIME#213503D23H34M33S709MS551US615NS; END_VAR END_PROGRAM",
                      dialect, ["Main.d"])
    assert (largest == (2**64 - 1,)) is value


def probe_enum_integer(dialect, value):
    result = outcome("TYPE E : (A := 3, B := 5); END_TYPE\n"
                     "PROGRAM Main VAR x : E := E.B; i, j : INT; f, g : E; b : BOOL; END_VAR\n"
                     "i := x; f := 3; j := x + 1; g := E.A + 1; b := x > 4; END_PROGRAM",
                     dialect, ["Main.i", "Main.f", "Main.j", "Main.g", "Main.b"])
    assert (result == (5, 3, 6, 4, True)) is value
    if not value:
        assert any("cannot be applied to E" in m for m in result[1])


STRICT_ENUM = "{attribute 'strict'}\nTYPE E : (A := 3, B := 5); END_TYPE\n"


def probe_enum_strict_attribute(dialect, value):
    # read into an integer, compared, and given a constant that is one of its values: accepted
    # where enumerations mix with integers, strict or not (Beckhoff's own example does the first)
    kept = outcome(STRICT_ENUM + "PROGRAM Main VAR x : E := E.B; i : INT; b : BOOL; END_VAR\n"
                   "i := x; b := x = 5; x := 3; END_PROGRAM", dialect, ["Main.i", "Main.b", "Main.x"])
    assert (kept == (5, True, 3)) is (value or allows(dialect, "enum_integer"))
    for body in ("x := x + 1;", "x := 4;", "x := i;"):
        refused = outcome(STRICT_ENUM + "PROGRAM Main VAR x : E; i : INT := 3; END_VAR\n" + body + " END_PROGRAM",
                          dialect, ["Main.x"])
        assert not accepted(refused), body
        plain = outcome(STRICT_ENUM.replace("{attribute 'strict'}", "") + "PROGRAM Main VAR x : E; i : INT := 3; "
                        "END_VAR\n" + body + " END_PROGRAM", dialect, ["Main.x"])
        # without the attribute, the dialects that mix take it (and only those)
        assert accepted(plain) is allows(dialect, "enum_integer"), body
    if value:
        assert allows(dialect, "enum_integer")


def probe_enum_to_string_attribute(dialect, value):
    result = outcome("{attribute 'to_string'}\nTYPE E_Sample : (eInit := 0, eStart, eStop); END_TYPE\n"
                     "TYPE E_Plain : (pInit := 0, pStart, pStop); END_TYPE\n"
                     "PROGRAM Main VAR e : E_Sample; p : E_Plain := E_Plain.pStart; s, c, n : STRING; "
                     "w : WSTRING; END_VAR\n"
                     "s := TO_STRING(e); c := TO_STRING(E_Sample.eStart); n := TO_STRING(p); "
                     "w := TO_WSTRING(E_Sample.eStop); END_PROGRAM",
                     dialect, ["Main.s", "Main.c", "Main.n", "Main.w"])
    if value:   # Beckhoff's example, and a plain enumeration's number
        assert result == (b"eInit", b"eStart", b"1", "eStop")
    else:
        assert result == (b"0", b"1", b"1", "2")


def probe_enum_qualified_only(dialect, value):
    source = ("{attribute 'qualified_only'}\nTYPE E : (Red, Green); END_TYPE\n"
              "PROGRAM Main VAR x : E; END_VAR x := %s; END_PROGRAM")
    assert outcome(source % "E.Green", dialect, ["Main.x"]) == (1,)
    bare = outcome(source % "Green", dialect, ["Main.x"])
    assert (not accepted(bare)) is value
    if value:
        assert any("qualified_only" in m for m in bare[1])


def probe_shift_any_integer(dialect, value):
    result = outcome("PROGRAM Main VAR i : INT := -8; u : UINT := 16#8001; a, b : INT; c : UINT; END_VAR\n"
                     "a := SHL(i, 1); b := SHR(i, 1); c := ROR(u, 4); END_PROGRAM",
                     dialect, ["Main.a", "Main.b", "Main.c"])
    if value:   # the type's bits shifted as unsigned (stvm's choice for the sign)
        assert result == (-16, 0x7FFC, 0x1800)
    else:
        assert not accepted(result) and any("needs ANY_BIT" in m for m in result[1])


def probe_call_syntax(dialect, value):
    result = outcome("FUNCTION_BLOCK FB VAR_INPUT a : INT; END_VAR VAR_OUTPUT q : INT; Error : BOOL; END_VAR\n"
                     "q := a * 2; END_FUNCTION_BLOCK\n"
                     "PROGRAM Main VAR f : FB; r : INT; END_VAR f(a := 3, q => r, Error=> ,); END_PROGRAM",
                     dialect, ["Main.r"])
    assert (result == (6,)) is value


def probe_set_reset_assign(dialect, value):
    result = outcome("PROGRAM Main VAR s : BOOL; r : BOOL := TRUE; c : BOOL := TRUE; off : BOOL; END_VAR\n"
                     "s S= c; r R= c; s R= off; END_PROGRAM", dialect, ["Main.s", "Main.r"])
    assert (result == (True, False)) is value


def probe_assignment_expression(dialect, value):
    result = outcome("PROGRAM Main VAR i, hits : INT; END_VAR\n"
                     "IF ((i := i + 1) = 2) THEN hits := hits + 1; END_IF; END_PROGRAM",
                     dialect, ["Main.i", "Main.hits"], cycles=3)
    assert (result == (3, 1)) is value
    if not value:
        assert any("assignment used as an expression" in m and "CODESYS/TwinCAT syntax, not" in m
                   for m in result[1])
        return
    # the vendors' examples (chains, `IF b := (i = 1)`), WHILE, FB members, array elements and
    # struct members as targets, left to right, the value converted to the target's type
    result = outcome(ASSIGNMENT_EXPRESSIONS, dialect,
                     ["Main.i", "Main.hits", "Main.a", "Main.b", "Main.r", "Main.loops", "Main.arr", "Main.s.m",
                      "Main.fb.q", "Main.bb"])
    assert result == (2, 100, 7, 7, 1.0, 4, [4, 0, 10], 6, 10, True)
    wrong = outcome("PROGRAM Main VAR i : INT; r : REAL; END_VAR i := r := i; END_PROGRAM", dialect, [])
    assert any("cannot assign REAL to INT" in m for m in wrong[1])   # the vendors' "incorrect" example


ASSIGNMENT_EXPRESSIONS = """TYPE ST : STRUCT m : INT; END_STRUCT END_TYPE
FUNCTION_BLOCK FB VAR_OUTPUT q : INT; END_VAR VAR k : INT; END_VAR
IF (k := k + 1) = 2 THEN q := 10; END_IF
END_FUNCTION_BLOCK
FUNCTION Dec : INT VAR_IN_OUT c : INT; END_VAR c := c - 1; Dec := c; END_FUNCTION
PROGRAM Main VAR i, hits, a, b, n, x, loops : INT := 0; r : REAL; arr : ARRAY[1..3] OF INT; s : ST; fb : FB;
    bb : BOOL; END_VAR
IF ((i := i + 1) = 2) THEN hits := hits + 1; END_IF;
a := b := 7;
r := (n := 3) / 2;
n := 5; x := 0;
WHILE (x := Dec(n)) > 0 DO loops := loops + 1; END_WHILE;
arr[(i := 2) + 1] := (arr[1] := 4) + (s.m := 6);
fb(); fb();
IF bb := (a = 7) THEN hits := hits + 100; END_IF
END_PROGRAM
"""


def probe_method_recursion(dialect, value):
    result = outcome("FUNCTION_BLOCK FB\nMETHOD Fact : DINT VAR_INPUT n : DINT; END_VAR\n"
                     "IF n <= 1 THEN Fact := 1; ELSE Fact := n * THIS^.Fact(n - 1); END_IF\nEND_METHOD\n"
                     "END_FUNCTION_BLOCK\n"
                     "PROGRAM Main VAR f : FB; r : DINT; END_VAR r := f.Fact(5); END_PROGRAM", dialect, ["Main.r"])
    assert (result == (120,)) is value


def probe_void_function(dialect, value):
    # the function's name is no result variable, so a local may share it (TcUnit's TEST has `Test`)
    result = outcome("FUNCTION Bump VAR_INPUT n : INT; END_VAR VAR bump2 : INT; END_VAR G := G + n; END_FUNCTION\n"
                     "VAR_GLOBAL G : INT; END_VAR\n"
                     "PROGRAM Main Bump(n := 2); Bump(3); END_PROGRAM", dialect, ["G"])
    assert (result == (5,)) is value


def probe_mixed_arguments(dialect, value):
    result = outcome("FUNCTION Sub3 : INT VAR_INPUT a, b, c : INT; END_VAR Sub3 := a - b - c; END_FUNCTION\n"
                     "PROGRAM Main VAR r : INT; END_VAR r := Sub3(b := 1, 10, 2); END_PROGRAM",
                     dialect, ["Main.r"])
    assert (result == (7,)) is value


def probe_fb_assign(dialect, value):
    # a copy, not an alias: changing the copy leaves the original
    result = outcome("FUNCTION_BLOCK FB VAR_INPUT x : INT; END_VAR VAR a : ARRAY[1..2] OF INT; END_VAR END_FUNCTION_BLOCK\n"
                     "PROGRAM Main VAR f, g : FB; r, q : INT; END_VAR\n"
                     "f(x := 4); g := f; g(x := 9); r := g.x; q := f.x; END_PROGRAM", dialect, ["Main.r", "Main.q"])
    assert (result == (9, 4)) is value
    # the same for arrays of instances: each element copied, or the assignment refused (never
    # two arrays sharing their instances)
    arrays = outcome("FUNCTION_BLOCK FB VAR_INPUT x : INT; END_VAR END_FUNCTION_BLOCK\n"
                     "PROGRAM Main VAR a, b : ARRAY[1..2] OF FB; r, q : INT; END_VAR\n"
                     "a[1](x := 4); b := a; b[1](x := 9); r := b[1].x; q := a[1].x; END_PROGRAM",
                     dialect, ["Main.r", "Main.q"])
    assert (arrays == (9, 4)) is value
    assert accepted(arrays) is value


def probe_fb_input_assign(dialect, value):
    result = outcome("PROGRAM Main VAR t : TON; q : BOOL; END_VAR\n"
                     "t.IN := TRUE; t.PT := T#20MS; t(); q := t.Q; END_PROGRAM", dialect, ["Main.q"], cycles=3)
    assert (result == (True,)) is value


def probe_fb_internal_read(dialect, value):
    result = outcome("FUNCTION_BLOCK FB VAR n : INT; END_VAR n := n + 1; END_FUNCTION_BLOCK\n"
                     "PROGRAM Main VAR f : FB; r : INT; END_VAR f(); f(); r := f.n; END_PROGRAM", dialect, ["Main.r"])
    assert (result == (2,)) is value
    written = outcome("FUNCTION_BLOCK FB VAR n : INT; END_VAR END_FUNCTION_BLOCK\n"
                      "PROGRAM Main VAR f : FB; END_VAR f.n := 3; END_PROGRAM", dialect, [])
    assert not accepted(written)


def probe_int_div_zero(dialect, value):
    result = outcome("PROGRAM Main VAR a : INT := 7; z : INT; q : INT; END_VAR q := a / z; END_PROGRAM",
                     dialect, ["Main.q"])
    assert value == "fault" and result[0] == "fault"


def probe_int_overflow(dialect, value):
    result = outcome("PROGRAM Main VAR i : INT := 32767; u : USINT := 255; END_VAR i := i + 1; u := u + 1; "
                     "END_PROGRAM", dialect, ["Main.i", "Main.u"])
    assert value == "wraps" and result == (-32768, 0)


def probe_time_to_string(dialect, value):
    result = outcome("PROGRAM Main VAR a, b, c, d : STRING; END_VAR a := TIME_TO_STRING(T#12ms); "
                     "b := DATE_TO_STRING(D#2002-08-18); c := TOD_TO_STRING(TOD#14:01:05.123); "
                     "d := DT_TO_STRING(DT#1998-02-13-14:20:00); END_PROGRAM",
                     dialect, ["Main.a", "Main.b", "Main.c", "Main.d"])
    assert value == "IEC literal"
    assert result == (b"T#12ms", b"D#2002-08-18", b"TOD#14:01:05.123", b"DT#1998-02-13-14:20:00")


def probe_bool_to_string(dialect, value):
    result = outcome("PROGRAM Main VAR a, b : STRING; END_VAR a := BOOL_TO_STRING(TRUE); "
                     "b := TO_STRING(FALSE); END_PROGRAM", dialect, ["Main.a", "Main.b"])
    assert value == "'TRUE'/'FALSE'" and result == (b"TRUE", b"FALSE")


def probe_unsized_string(dialect, value):
    result = outcome("PROGRAM Main VAR s : STRING; i, n : INT; END_VAR\n"
                     "FOR i := 1 TO 2000 DO s := CONCAT(s, 'x'); END_FOR; n := LEN(s); END_PROGRAM",
                     dialect, ["Main.n"])
    assert result == ({"1985 bytes": 1985, "80 characters": 80}[value],)


PROBES: dict[str, Callable[[Dialect, Any], None]] = {
    name[len("probe_"):]: fn for name, fn in globals().items() if name.startswith("probe_")}


def test_every_row_has_a_probe_and_every_probe_a_row():
    assert set(PROBES) == set(BY_KEY)


def test_every_row_names_its_sources_and_every_dialect():
    for row in ROWS:
        assert row.sources and row.subject
        for dialect in DIALECTS:
            assert row.value(dialect) is not None


# rows whose vendor behaviour stvm does not implement yet (docs/dialects.md "Not yet done"): none
KNOWN_GAPS: set[tuple[str, Dialect]] = set()


@pytest.mark.parametrize("dialect", DIALECTS, ids=[d.value for d in DIALECTS])
@pytest.mark.parametrize("key", list(BY_KEY))
def test_row_in_profile(key, dialect):
    row = BY_KEY[key]
    if (key, dialect) in KNOWN_GAPS:
        pytest.xfail(f"{key} in {dialect.value}: not implemented yet (docs/dialects.md)")
    value = row.value(dialect)
    if row.setting:   # the setting's Enum member
        value = type(getattr(DEFAULT_SETTINGS, key))(value)
    PROBES[key](dialect, value)


@pytest.mark.parametrize("dialect", DIALECTS, ids=[d.value for d in DIALECTS])
def test_profile_sets_its_settings(dialect):
    settings = SysmacSettings(dialect=dialect)
    for name in PROFILE_FIELDS:
        assert getattr(settings, name).value == profile_value(dialect, name)


def test_sysmac_profile_is_the_behaviour_before_profiles():
    # the values every Sysmac setting had before dialects were profiles (the thesis depends on them)
    s = SysmacSettings(dialect="sysmac")
    assert (s.byte_to_string_format, s.real_to_string_format, s.string_size, s.open_array_bounds,
            s.subrange_check) == (ByteToStringFormat.HEX_NOPAD, RealToStringFormat.C_EXP, StringSize.WITH_NUL,
                                  OpenArrayBounds.ZERO, SubrangeCheck.FAULT)


def test_iec_is_the_default_dialect():
    assert DEFAULT_SETTINGS.dialect is Dialect.IEC


def test_a_setting_the_user_chose_survives_a_change_of_dialect():
    chosen = SysmacSettings().with_overrides(["byte_to_string_format=hex_pad2"])
    moved = chosen.with_overrides(["dialect=sysmac"])
    assert moved.byte_to_string_format is ByteToStringFormat.HEX_PAD2
    assert moved.real_to_string_format is RealToStringFormat.C_EXP        # not chosen: the profile's
    back = moved.with_overrides(["dialect=twincat"])
    assert back.real_to_string_format is RealToStringFormat.DIGITS15
    assert back.byte_to_string_format is ByteToStringFormat.HEX_PAD2


def test_thesis_manifests_name_sysmac():
    from stvm.project import project_settings
    for folder in ("st_src", "st_src/cbt_v2", "st_src/rockwell", "st_src/kuka", "st_src/schneider",
                   "st_src/schneider/oo"):
        assert project_settings([folder]).dialect is Dialect.SYSMAC, folder


def test_twincat_max_string_holds_255():
    result = outcome("PROGRAM Main VAR s : T_MaxString; i, n : INT; END_VAR\n"
                     "FOR i := 1 TO 300 DO s := CONCAT(s, 'x'); END_FOR; n := LEN(s); END_PROGRAM",
                     Dialect.TWINCAT, ["Main.n"])
    assert result == (255,)


def test_errors_name_the_dialect_that_accepts_the_construct():
    result = outcome("PROGRAM Main VAR s : BOOL; END_VAR s S= TRUE; END_PROGRAM", Dialect.IEC, [])
    assert any("'S=' is CODESYS/TwinCAT syntax" in m for m in result[1])
    result = outcome("PROGRAM Main VAR PERSISTENT k : INT; END_VAR END_PROGRAM", Dialect.IEC, [])
    assert any("PERSISTENT is a CODESYS/TwinCAT qualifier" in m for m in result[1])


@pytest.mark.parametrize(("parts", "known", "expected"), [
    (("TcUnit", "FB_TestSuite"), {("FB_TestSuite",)}, ("FB_TestSuite",)),
    (("FsCommon", "I_Runnable"), {("FsCommon", "I_Runnable")}, ("FsCommon", "I_Runnable")),
    (("Nowhere", "FB_X"), set(), ("Nowhere", "FB_X")),
])
def test_known_library_prefix(parts, known, expected):
    assert known_library_prefix(parts, lambda p: p in known) == expected


LIBRARY_NAMES = """INTERFACE I_Runnable
METHOD Run : BOOL
END_METHOD
END_INTERFACE
FUNCTION_BLOCK FB_TestSuite
VAR_OUTPUT n : INT; END_VAR
n := n + 1;
END_FUNCTION_BLOCK
FUNCTION_BLOCK FB_Mine EXTENDS TcUnit.FB_TestSuite IMPLEMENTS FsCommon.I_Runnable
METHOD Run : BOOL
Run := TRUE;
END_METHOD
SUPER^();
END_FUNCTION_BLOCK
PROGRAM Main
VAR t : TcUnit.FB_TestSuite; m : FB_Mine; END_VAR
t(); m();
END_PROGRAM
"""


@pytest.mark.parametrize("dialect", [Dialect.CODESYS, Dialect.TWINCAT, Dialect.IEC], ids=["codesys", "twincat", "iec"])
def test_library_qualified_names_resolve_to_the_loaded_pou(dialect):
    # `TcUnit.FB_TestSuite` in EXTENDS, IMPLEMENTS and a declaration: the POU of that name
    assert outcome(LIBRARY_NAMES, dialect, ["Main.t.n", "Main.m.n"], cycles=2) == (2, 2)


def test_library_qualified_names_stay_unknown_in_sysmac():
    result = outcome(LIBRARY_NAMES, Dialect.SYSMAC, [])
    assert any("unknown function block 'TcUnit\\FB_TestSuite'" in m for m in result[1])


def test_a_library_prefix_of_an_unknown_pou_is_reported():
    result = outcome("PROGRAM Main VAR t : TcUnit.FB_Nowhere; END_VAR END_PROGRAM", Dialect.TWINCAT, [])
    assert any("unknown type 'TcUnit\\FB_Nowhere'" in m for m in result[1])


def test_the_docs_page_shows_the_table_of_the_code():
    import subprocess
    import sys
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    page = (root / "docs" / "dialects.md").read_text(encoding="utf-8")
    for row in ROWS:
        assert f"| `{row.key}`" in page, row.key
    proc = subprocess.run([sys.executable, str(root / "tools" / "gen_dialect_docs.py"), "--check"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
