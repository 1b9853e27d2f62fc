"""CODESYS UNION: members overlay the same little-endian bytes; writing one member and reading
another reinterprets them; SIZEOF is the largest member's."""

from __future__ import annotations

import pytest

from core_helpers import check_text, run_st
from stvm.semantics import types as t

TYPES = """
TYPE U : UNION a : DINT; b : ARRAY[0..3] OF BYTE; r : REAL; END_UNION END_TYPE
TYPE Pair : STRUCT lo : WORD; hi : WORD; END_STRUCT END_TYPE
TYPE Wide : UNION l : LWORD; p : ARRAY[0..1] OF Pair; w : ARRAY[0..1, 0..1] OF WORD; x : BYTE; END_UNION
END_TYPE
TYPE Text : UNION a : DINT; w : ARRAY[0..1] OF WORD; s : STRING[4]; flag : BOOL; END_UNION END_TYPE
"""


def run(body: str, variables: str, prints: list[str], **kwargs):
    return run_st(TYPES + f"PROGRAM Main\nVAR {variables} END_VAR\n{body}\nEND_PROGRAM\n",
                  prints=[f"Main.{p}" for p in prints], **kwargs)


def test_writing_one_member_and_reading_another_reinterprets_the_bytes():
    values = run("""u.a := 16#01020304; b0 := u.b[0]; b3 := u.b[3];
u.b[3] := 16#40; a2 := u.a; u.r := 1.0; bits := u.a; u.b[0] := 255; a3 := u.a;""",
                 "u : U; b0, b3 : BYTE; a2, bits, a3 : DINT;", ["b0", "b3", "a2", "bits", "a3"])
    assert values == {"Main.b0": 4, "Main.b3": 1, "Main.a2": 0x40020304, "Main.bits": 0x3F800000,
                      "Main.a3": 0x3F8000FF}


def test_nested_arrays_and_structs_overlay_row_major():
    values = run("""v.l := 16#1111222233334444; hi1 := v.p[1].hi; w10 := v.w[1, 0];
v.p[0].lo := 16#ABCD; l2 := v.l; v.x := 16#EE; l3 := v.l;""",
                 "v : Wide; hi1, w10 : WORD; l2, l3 : LWORD;", ["hi1", "w10", "l2", "l3"])
    assert values == {"Main.hi1": 0x1111, "Main.w10": 0x2222, "Main.l2": 0x111122223333ABCD,
                      "Main.l3": 0x111122223333ABEE}   # a smaller member keeps the other bytes


def test_strings_bools_references_and_in_outs():
    values = run_st(TYPES + """
FUNCTION Bump : BOOL
VAR_IN_OUT x : DINT; END_VAR
x := x + 1; Bump := TRUE;
END_FUNCTION
PROGRAM Main
VAR u : Text := (a := 16#00434241); s : STRING; ok, flag : BOOL; p : REF_TO DINT; w1 : WORD; a : DINT; END_VAR
s := u.s;
ok := Bump(u.a);
p := REF(u.a);
p^ := p^ + 16#10000;
w1 := u.w[1];
flag := u.flag;
a := u.a;
END_PROGRAM
""", prints=["Main.s", "Main.w1", "Main.flag", "Main.a", "Main.u.s"])
    # reading the BOOL member does not rewrite the byte it overlays
    assert values == {"Main.s": b"ABC", "Main.w1": 0x44, "Main.flag": True, "Main.a": 0x00444242,
                      "Main.u.s": b"BBD"}


def test_assignment_copies_the_bytes_and_sizeof_is_the_largest_member():
    values = run("u.a := -1; copy := u; u.a := 0; b := copy.b[2]; size := SIZEOF(u); wide := SIZEOF(v);",
                 "u, copy : U; v : Wide; b : BYTE; size, wide : DINT;", ["b", "size", "wide"])
    assert values == {"Main.b": 255, "Main.size": 4, "Main.wide": 8}


def test_union_prints_every_member():
    values = run("u.a := 16#3F800000;", "u : U;", ["u"], fmt=True)
    assert values == {"Main.u": "(a := 1065353216, b := [0, 0, 128, 63], r := 1.0)"}


def test_byte_size_of_union_types():
    union = t.UnionType("U", "U", (("a", t.BYTE), ("b", t.DINT)))
    assert t.byte_size(union) == 4 and t.byte_size(t.UnionType("V", "V", (("a", t.string_type(5)),))) == 5


@pytest.mark.parametrize("source, message", [
    ("TYPE V : UNION a : DINT := 5; END_UNION END_TYPE", "1:28: error: a member of UNION V has no initial value"),
    ("TYPE V : UNION t : TON; END_UNION END_TYPE", "1:20: error: UNION member of type TON has no byte image"),
    ("TYPE V : UNION a : DINT; a : INT; END_UNION END_TYPE", "1:26: error: duplicate member 'a' in V"),
    ("TYPE V : UNION END_UNION END_TYPE", "1:10: error: UNION V has no members"),
    ("TYPE V : UNION a : DINT; END_UNION END_TYPE\nPROGRAM Main VAR v : V; END_VAR v.zz := 1; END_PROGRAM",
     "2:33: error: V has no member 'zz'"),
    ("TYPE V : UNION a : DINT; END_UNION END_TYPE\nPROGRAM Main VAR v : V; i : INT; END_VAR i := v; END_PROGRAM",
     "error: type mismatch: cannot assign V to INT"),
])
def test_union_errors(source, message):
    rc, err = check_text(source + "\n")
    assert rc == 1 and message in err, err


def test_copies_keep_the_bytes_after_a_bool_member_was_read():
    # a member-by-member copy would write the BOOL back as 1: copies take the union's bytes
    values = run_st("""
TYPE U : UNION a : DINT; flag : BOOL; END_UNION END_TYPE
TYPE S : STRUCT u : U; END_STRUCT END_TYPE
FUNCTION_BLOCK Take
VAR_INPUT inp : U; s : S; END_VAR
VAR_OUTPUT got, got2 : DINT; END_VAR
got := inp.a; got2 := s.u.a;
END_FUNCTION_BLOCK
PROGRAM Main
VAR u : U; s, s2 : S; f : Take; b : BOOL; END_VAR
u.a := 2; b := u.flag;
s.u.a := 2; b := s.u.flag;
f(inp := u, s := s);
s2 := s;
END_PROGRAM
""", prints=["Main.f.got", "Main.f.got2", "Main.s2.u.a", "Main.b"])
    assert values == {"Main.f.got": 2, "Main.f.got2": 2, "Main.s2.u.a": 2, "Main.b": True}
