"""The byte-addressable memory of the TwinCAT/CODESYS profiles (stvm/runtime/memory.py,
docs/memory_model.md): MEMCPY/MEMSET/MEMCMP, pointer arithmetic and casts, ANY inputs,
FB_MemRingBuffer — and the same constructs refused where the profile has no byte pointers."""

from __future__ import annotations

import struct

import pytest

from core_helpers import check_text, run_st
from stvm.runtime import memory
from stvm.semantics import types as t
from stvm.settings import SysmacSettings

TWINCAT = SysmacSettings(dialect="twincat")


def run(source: str, prints: list[str], settings=TWINCAT, **kwargs):
    values = run_st(source, prints=[f"Main.{p}" for p in prints], settings=settings, **kwargs)
    return {p: values[f"Main.{p}"] for p in prints}


def program(variables: str, body: str, extra: str = "") -> str:
    return f"{extra}\nPROGRAM Main\nVAR\n{variables}\nEND_VAR\n{body}\nEND_PROGRAM\n"


# ---- MEMCPY / MEMSET / MEMCMP -------------------------------------------------------------------
def test_memcpy_copies_elementary_values_strings_structs_and_arrays():
    extra = "TYPE ST_Rec : STRUCT a : INT; b : REAL; s : STRING(10); END_STRUCT END_TYPE"
    values = run(program(
        "i1 : INT := -1234; i2 : INT; r1 : REAL := 1.5; r2 : REAL; s1 : STRING(20) := 'hello'; s2 : STRING(20);"
        "st1, st2 : ST_Rec; a1 : ARRAY[0..3] OF BYTE := [1, 2, 3, 4]; a2 : ARRAY[0..3] OF BYTE; rc : UDINT;",
        "MEMCPY(ADR(i2), ADR(i1), SIZEOF(i1));\n"
        "rc := MEMCPY(destAddr := ADR(r2), srcAddr := ADR(r1), n := SIZEOF(REAL));\n"
        "MEMCPY(ADR(s2), ADR(s1), SIZEOF(s1));\n"
        "st1.a := 7; st1.b := 2.25; st1.s := 'abc'; MEMCPY(ADR(st2), ADR(st1), SIZEOF(st1));\n"
        "MEMCPY(ADR(a2), ADR(a1), SIZEOF(a1));", extra),
        ["i2", "r2", "s2", "st2.a", "st2.b", "st2.s", "a2", "rc"])
    assert values == {"i2": -1234, "r2": 1.5, "s2": b"hello", "st2.a": 7, "st2.b": 2.25, "st2.s": b"abc",
                      "a2": [1, 2, 3, 4], "rc": 1}


def test_memcpy_between_types_reinterprets_the_bytes_little_endian():
    values = run(program("r : REAL := 1.0; dw : DWORD; b : ARRAY[0..3] OF BYTE; w : WORD := 16#ABCD;"
                         "i : INT; s : STRING(5) := 'AB';",
                         "MEMCPY(ADR(dw), ADR(r), 4); MEMCPY(ADR(b), ADR(dw), 4); MEMCPY(ADR(i), ADR(s), 2);"),
                 ["dw", "b", "i"])
    assert values == {"dw": 0x3F800000, "b": [0, 0, 0x80, 0x3F], "i": 0x4241}   # 'A' low, 'B' high


def test_memcpy_of_a_part_keeps_the_other_bytes():
    values = run(program("d : DINT := 16#11223344; b : BYTE := 16#FF;", "MEMCPY(ADR(d), ADR(b), 1);"), ["d"])
    assert values == {"d": 0x112233FF}


def test_memset_and_memcmp():
    values = run(program("a : ARRAY[0..5] OF BYTE; b : ARRAY[0..5] OF BYTE; eq, lt, gt, zero : DINT;",
                         "MEMSET(ADR(a), 16#AB, 4); MEMSET(ADR(b), 16#AB, 4); eq := MEMCMP(ADR(a), ADR(b), 6);\n"
                         "b[2] := 16#AC; lt := MEMCMP(ADR(a), ADR(b), 6); gt := MEMCMP(ADR(b), ADR(a), 6);\n"
                         "zero := MEMCMP(ADR(a), ADR(b), 0);"),
                 ["a", "eq", "lt", "gt", "zero"])
    assert values == {"a": [0xAB] * 4 + [0, 0], "eq": 0, "lt": -1, "gt": 1, "zero": 0}


def test_a_copy_beyond_the_variable_faults():
    # with `pointer_overrun=fault`; the profile's guard absorbs a few bytes (test_memory_overrun.py)
    with pytest.raises(Exception, match="outside the variable"):
        run(program("a : INT; b : DINT;", "MEMCPY(ADR(a), ADR(b), 4);"), ["a"],
            settings=TWINCAT.with_overrides(["pointer_overrun=fault"]))


# ---- pointer arithmetic, casts, indexing --------------------------------------------------------
def test_a_byte_pointer_walks_an_array_and_a_scalar():
    values = run(program("a : ARRAY[0..3] OF BYTE := [10, 20, 30, 40]; p : POINTER TO BYTE; k : INT; sum : UDINT;"
                         "d : DWORD := 16#04030201; q : POINTER TO BYTE; last : BYTE; back : BYTE;",
                         "p := ADR(a[0]); FOR k := 0 TO 3 DO sum := sum + p^; p := p + 1; END_FOR\n"
                         "q := ADR(d) + 3; last := q^; q := q - 2; back := q^; q^ := 16#FF;"),
                 ["sum", "last", "back", "d"])
    assert values == {"sum": 100, "last": 4, "back": 2, "d": 0x0403FF01}


def test_a_cast_pointer_reads_and_writes_through_another_type():
    values = run(program("r : REAL := 1.5; pDW : POINTER TO DWORD; dw : DWORD; pW : POINTER TO WORD;"
                         "x : DINT := 16#12345678; lo : WORD;",
                         "pDW := ADR(r); dw := pDW^; pW := ADR(x); lo := pW^; pW := pW + 2; pW^ := 16#ABCD;"),
                 ["dw", "lo", "x"])
    assert values == {"dw": struct.unpack("<I", struct.pack("<f", 1.5))[0], "lo": 0x5678, "x": 0xABCD5678 - 2**32}


def test_pointer_index_scales_by_the_target_size_and_null_compares_with_zero():
    values = run(program("a : ARRAY[0..3] OF INT := [5, 6, 7, 8]; p : POINTER TO INT; v : INT;"
                         "isnull, notnull : BOOL; q : POINTER TO BYTE; same : BOOL;",
                         "isnull := p = 0; p := ADR(a[0]); notnull := p <> 0; v := p[2]; p[3] := 80;\n"
                         "q := ADR(a[1]); same := q = ADR(a) + 2;"),
                 ["v", "a", "isnull", "notnull", "same"])
    assert values == {"v": 7, "a": [5, 6, 7, 80], "isnull": True, "notnull": True, "same": True}


def test_adr_of_a_functions_result():
    values = run(program("r : REAL := 1.5; dw : DWORD;", "dw := F_Bits(r);",
                         "FUNCTION F_Bits : DWORD VAR_INPUT x : REAL; END_VAR MEMCPY(ADR(F_Bits), ADR(x), 4); "
                         "END_FUNCTION"),
                 ["dw"])
    assert values == {"dw": 0x3FC00000}


# ---- ANY inputs ---------------------------------------------------------------------------------
ANY_INFO = """FUNCTION F_Info : DINT
VAR_INPUT v : ANY; END_VAR
VAR_OUTPUT cls : INT; first : BYTE; END_VAR
cls := UDINT_TO_INT(v.TypeClass);
first := v.pValue[0];
F_Info := v.diSize;
END_FUNCTION
"""


def test_any_inputs_carry_the_type_class_address_and_size():
    values = run(program("r : REAL := 1.5; i : INT := 258; s : STRING(10) := 'AB'; a : ARRAY[1..3] OF LINT;"
                         "n1, n2, n3, n4, n5 : DINT; c1, c2, c3, c4, c5 : INT; b1, b2, b3, b4, b5 : BYTE;",
                         "n1 := F_Info(v := r, cls => c1, first => b1); n2 := F_Info(v := i, cls => c2, first => b2);\n"
                         "n3 := F_Info(v := s, cls => c3, first => b3); n4 := F_Info(v := 16#12345678, cls => c4, first => b4);\n"
                         "n5 := F_Info(v := a, cls => c5, first => b5);", ANY_INFO),
                 ["n1", "c1", "b1", "n2", "c2", "b2", "n3", "c3", "b3", "n4", "c4", "b4", "n5", "c5"])
    assert values == {"n1": 4, "c1": 14, "b1": 0, "n2": 2, "c2": 7, "b2": 2, "n3": 11, "c3": 16, "b3": 65,
                      "n4": 4, "c4": 8, "b4": 0x78, "n5": 24, "c5": 26}


def test_an_any_input_copies_its_value_with_memcpy():
    values = run(program("x : LREAL := 2.5; y : LREAL; t : STRING(30) := 'text'; u : STRING(30);",
                         "CopyAny(src := x, dst := ADR(y)); CopyAny(src := t, dst := ADR(u));",
                         "FUNCTION CopyAny : BOOL VAR_INPUT src : ANY; dst : POINTER TO BYTE; END_VAR "
                         "MEMCPY(dst, src.pValue, DINT_TO_UDINT(src.diSize)); END_FUNCTION"),
                 ["y", "u"])
    assert values == {"y": 2.5, "u": b"text"}


# ---- FB_MemRingBuffer ---------------------------------------------------------------------------
RING = """TYPE ST_Msg : STRUCT mask : DWORD; text : STRING(20); END_STRUCT END_TYPE
FUNCTION_BLOCK Queue
VAR_OUTPUT bOk : BOOL; nCount : UDINT; cbSize : UDINT; END_VAR
VAR rb : FB_MemRingBuffer; buf : ARRAY[0..(3 * (SIZEOF(ST_Msg) + MEM_RING_BUFFER_INTERNAL_USE_PER_DATA_RECORD)) - 1] OF BYTE; END_VAR
METHOD Put VAR_INPUT m : ST_Msg; END_VAR
rb.A_AddTail(pWrite := ADR(m), cbWrite := SIZEOF(m), pBuffer := ADR(buf), cbBuffer := SIZEOF(buf));
bOk := rb.bOk; nCount := rb.nCount; cbSize := rb.cbSize;
END_METHOD
METHOD Take VAR_OUTPUT m : ST_Msg; END_VAR
rb.A_RemoveHead(pRead := ADR(m), cbRead := SIZEOF(m), pBuffer := ADR(buf), cbBuffer := SIZEOF(buf));
bOk := rb.bOk; nCount := rb.nCount; cbSize := rb.cbSize;
END_METHOD
METHOD Peek VAR_OUTPUT m : ST_Msg; END_VAR
rb.A_GetHead(pRead := ADR(m), cbRead := SIZEOF(m), pBuffer := ADR(buf), cbBuffer := SIZEOF(buf));
bOk := rb.bOk; nCount := rb.nCount;
END_METHOD
END_FUNCTION_BLOCK
"""


def test_ring_buffer_is_a_fifo_that_wraps_round_and_refuses_overflow():
    values = run(program(
        "q : Queue; m, r : ST_Msg; k : INT; added : INT; taken : ARRAY[1..6] OF STRING(20); ok : ARRAY[1..6] OF BOOL;"
        "full : BOOL; empty : BOOL; peeked : STRING(20); count : UDINT;",
        "FOR k := 1 TO 4 DO m.mask := INT_TO_DWORD(k); m.text := CONCAT('m', INT_TO_STRING(k)); q.Put(m); "
        "IF q.bOk THEN added := added + 1; END_IF END_FOR\n"
        "full := q.bOk;\n"
        "q.Take(m => r); taken[1] := r.text; ok[1] := q.bOk;\n"
        "m.text := 'm5'; q.Put(m); ok[2] := q.bOk;\n"    # wraps round the end of the buffer
        "q.Peek(m => r); peeked := r.text; count := q.nCount;\n"
        "FOR k := 3 TO 6 DO q.Take(m => r); taken[k - 1] := r.text; ok[k] := q.bOk; END_FOR\n"
        "empty := q.nCount = 0;", RING),
        ["added", "full", "taken", "ok", "peeked", "count", "empty", "q.cbSize"])
    assert values["added"] == 3 and values["full"] is False          # the 4th record does not fit
    assert values["taken"][:5] == [b"m1", b"m2", b"m3", b"m5", b""]
    assert values["ok"] == [True, True, True, True, True, False]       # the last Take finds it empty
    assert values["peeked"] == b"m2" and values["count"] == 3
    assert values["empty"] is True and values["q.cbSize"] == 0


def test_ring_buffer_reset_and_a_record_too_big_for_the_reader():
    values = run(program(
        "rb : FB_MemRingBuffer; buf : ARRAY[0..63] OF BYTE; big : ARRAY[0..9] OF BYTE := [1,2,3,4,5,6,7,8,9,10];"
        "small : ARRAY[0..3] OF BYTE; okSmall : BOOL; need : UDINT; n1, n2 : UDINT; okReset : BOOL;",
        "rb.A_AddTail(pWrite := ADR(big), cbWrite := 10, pBuffer := ADR(buf), cbBuffer := 64);\n"
        "rb.A_RemoveHead(pRead := ADR(small), cbRead := 4, pBuffer := ADR(buf), cbBuffer := 64);\n"
        "okSmall := rb.bOk; need := rb.cbReturn; n1 := rb.nCount;\n"
        "rb.A_Reset(); okReset := rb.bOk; n2 := rb.nCount;"),
        ["okSmall", "need", "n1", "okReset", "n2", "small"])
    assert values == {"okSmall": False, "need": 10, "n1": 1, "okReset": True, "n2": 0, "small": [0, 0, 0, 0]}


# ---- the profile rule: no byte pointers in Sysmac and IEC code ---------------------------------
@pytest.mark.parametrize("dialect", ["sysmac", "iec"])
def test_byte_pointers_are_refused_outside_twincat_and_codesys(dialect):
    source = program("a : ARRAY[0..3] OF BYTE; p : POINTER TO BYTE; q : POINTER TO INT; i : INT;",
                     "p := ADR(a); p := p + 1; q := ADR(i); p := q;")
    rc, err = check_text(source, dialect=dialect)
    assert rc == 1
    assert "operator + cannot be applied to POINTER TO BYTE" in err
    assert "cannot assign POINTER TO INT to POINTER TO BYTE" in err


def test_codesys_has_the_same_pointer_arithmetic():
    values = run(program("d : DWORD := 16#04030201; p : POINTER TO BYTE; v : BYTE;", "p := ADR(d); p := p + 2; v := p^;"),
                 ["v"], settings=SysmacSettings(dialect="codesys"))
    assert values == {"v": 3}


# ---- the serialiser and SIZEOF agree ------------------------------------------------------------
def test_sizeof_is_the_length_of_the_byte_image():
    values = run(program("s : ST_Pad; n : DINT;", "n := SIZEOF(s);",
                         "TYPE ST_Pad : STRUCT b : BYTE; l : LREAL; w : WORD; s : STRING(4); END_STRUCT END_TYPE"),
                 ["n"])
    # Beckhoff Infosys "Alignment" (TwinCAT 3, 8-byte alignment): b at 0, l at 8, w at 16, s at 18..22,
    # the whole padded to a multiple of 8
    assert values == {"n": 24}


def test_codec_round_trips_and_lays_out_little_endian():
    assert bytes(memory.image(-2, t.INT)) == b"\xfe\xff"
    assert bytes(memory.image(True, t.BOOL)) == b"\x01"
    assert bytes(memory.image(b"ab", t.StringType("STRING(3)", 4))) == b"ab\x00\x00"
    assert bytes(memory.image("é", t.wstring_type(2))) == "é".encode("utf-16-le") + bytes(4)
    buf = memory.image(2.5, t.LREAL)
    assert memory.codec(t.LREAL)[1](buf, 0, None) == 2.5


def test_ring_buffer_record_split_across_the_end_of_the_buffer():
    values = run(program(
        "rb : FB_MemRingBuffer; buf : ARRAY[0..19] OF BYTE; a : ARRAY[0..5] OF BYTE := [1,2,3,4,5,6];"
        "b : ARRAY[0..1] OF BYTE := [7, 8]; c : ARRAY[0..5] OF BYTE := [11,12,13,14,15,16];"
        "outB : ARRAY[0..1] OF BYTE; outC : ARRAY[0..5] OF BYTE; dummy : ARRAY[0..5] OF BYTE; okC : BOOL; sizeC : UDINT;",
        "rb.A_AddTail(pWrite := ADR(a), cbWrite := 6, pBuffer := ADR(buf), cbBuffer := 20);\n"
        "rb.A_AddTail(pWrite := ADR(b), cbWrite := 2, pBuffer := ADR(buf), cbBuffer := 20);\n"
        "rb.A_RemoveHead(pRead := ADR(dummy), cbRead := 6, pBuffer := ADR(buf), cbBuffer := 20);\n"
        # C's length goes into bytes 16..19, its data wraps round to bytes 0..5
        "rb.A_AddTail(pWrite := ADR(c), cbWrite := 6, pBuffer := ADR(buf), cbBuffer := 20); okC := rb.bOk;\n"
        "rb.A_RemoveHead(pRead := ADR(outB), cbRead := 2, pBuffer := ADR(buf), cbBuffer := 20);\n"
        "rb.A_RemoveHead(pRead := ADR(outC), cbRead := 6, pBuffer := ADR(buf), cbBuffer := 20); sizeC := rb.cbReturn;"),
        ["okC", "outB", "outC", "sizeC", "buf", "rb.nCount"])
    assert values["okC"] is True and values["outB"] == [7, 8] and values["outC"] == [11, 12, 13, 14, 15, 16]
    assert values["sizeC"] == 6 and values["rb.nCount"] == 0
    assert values["buf"][:6] == [11, 12, 13, 14, 15, 16] and values["buf"][16:] == [6, 0, 0, 0]


# TcUnit's pattern (FB_TestSuite.AssertEquals, F_AnyToUnionValue): ANY inputs copied with MEMCPY
# into a member of the function's UNION result through ADR(F.member), compared with MEMCMP
ASSERT_EQUALS = """TYPE U_Val : UNION
    b : BOOL; i : INT; r : REAL; s : T_MaxString; w : WSTRING(255); t : TIME;
END_UNION
END_TYPE
FUNCTION F_ToUnion : U_Val
VAR_INPUT
    AnySize : UDINT;
    AnyTypeClass : IBaseLibrary.TypeClass;
    AnyValue : POINTER TO BYTE;
END_VAR
CASE AnyTypeClass OF
    IBaseLibrary.TypeClass.TYPE_INT :
        MEMCPY(destaddr := ADR(F_ToUnion.i), srcAddr := AnyValue, n := AnySize);
    IBaseLibrary.TypeClass.TYPE_REAL :
        MEMCPY(destaddr := ADR(F_ToUnion.r), srcAddr := AnyValue, n := AnySize);
    IBaseLibrary.TypeClass.TYPE_STRING :
        MEMCPY(destaddr := ADR(F_ToUnion.s), srcAddr := AnyValue, n := AnySize);
    IBaseLibrary.TypeClass.TYPE_WSTRING :
        MEMCPY(destaddr := ADR(F_ToUnion.w), srcAddr := AnyValue, n := AnySize);
    IBaseLibrary.TypeClass.TYPE_TIME :
        MEMCPY(destaddr := ADR(F_ToUnion.t), srcAddr := AnyValue, n := AnySize);
END_CASE
END_FUNCTION

FUNCTION_BLOCK FB_Suite
METHOD AssertEquals : BOOL
VAR_INPUT
    Expected : ANY;
    Actual : ANY;
END_VAR
VAR
    e, a : U_Val;
    stringExpected, stringActual : T_MaxString;
END_VAR
IF Expected.TypeClass <> Actual.TypeClass THEN RETURN; END_IF
IF UDINT_TO_INT(Expected.TypeClass) = IBaseLibrary.TypeClass.TYPE_STRING THEN
    MEMCPY(destAddr := ADR(stringExpected), srcAddr := Expected.pValue, n := DINT_TO_UDINT(Expected.diSize));
    MEMCPY(destAddr := ADR(stringActual), srcAddr := Actual.pValue, n := DINT_TO_UDINT(Actual.diSize));
    AssertEquals := stringExpected = stringActual;
    RETURN;
END_IF
e := F_ToUnion(AnySize := DINT_TO_UDINT(Expected.diSize), AnyTypeClass := UDINT_TO_INT(Expected.TypeClass), AnyValue := Expected.pValue);
a := F_ToUnion(AnySize := DINT_TO_UDINT(Actual.diSize), AnyTypeClass := UDINT_TO_INT(Actual.TypeClass), AnyValue := Actual.pValue);
AssertEquals := MEMCMP(ADR(e), ADR(a), SIZEOF(e)) = 0;
END_METHOD
END_FUNCTION_BLOCK

"""


def test_a_tcunit_style_assert_equals_on_any_inputs():
    values = run(program(
        "suite : FB_Suite; i : INT := 42; r : REAL := 2.5; s : STRING(80) := 'abc'; w : WSTRING(80) := \"wide\";"
        "tm : TIME := T#1500MS; ok1, ok2, ok3, ok4, ok5, bad1, bad2, bad3 : BOOL;",
        "ok1 := suite.AssertEquals(Expected := INT#42, Actual := i);\n"
        "ok2 := suite.AssertEquals(Expected := REAL#2.5, Actual := r);\n"
        "ok3 := suite.AssertEquals(Expected := 'abc', Actual := s);\n"
        "ok4 := suite.AssertEquals(Expected := \"wide\", Actual := w);\n"
        "ok5 := suite.AssertEquals(Expected := T#1.5S, Actual := tm);\n"
        "bad1 := suite.AssertEquals(Expected := INT#41, Actual := i);\n"
        "bad2 := suite.AssertEquals(Expected := 'abd', Actual := s);\n"
        "bad3 := suite.AssertEquals(Expected := i, Actual := r);", ASSERT_EQUALS),
        ["ok1", "ok2", "ok3", "ok4", "ok5", "bad1", "bad2", "bad3"])
    assert values == {"ok1": True, "ok2": True, "ok3": True, "ok4": True, "ok5": True,
                      "bad1": False, "bad2": False, "bad3": False}


def test_time_types_have_twincats_32_bit_layout():
    values = run(program("t : TIME := T#1500MS; tod : TOD := TOD#00:00:02.5; d : DATE := D#1970-01-02;"
                         "lt : LTIME := LTIME#1US; a, b, c : UDINT; l : LWORD; n1, n2 : DINT; back : TIME;",
                         "MEMCPY(ADR(a), ADR(t), SIZEOF(t)); MEMCPY(ADR(b), ADR(tod), 4); MEMCPY(ADR(c), ADR(d), 4);\n"
                         "MEMCPY(ADR(l), ADR(lt), 8); n1 := SIZEOF(t); n2 := SIZEOF(lt); a := a + 1;\n"
                         "MEMCPY(ADR(back), ADR(a), 4);"),
                 ["a", "b", "c", "l", "n1", "n2", "back"])
    # Beckhoff: TIME and TOD in milliseconds, DATE in seconds (32 bits), LTIME in nanoseconds (64)
    assert values == {"a": 1501, "b": 2500, "c": 86400, "l": 1000, "n1": 4, "n2": 8, "back": 1_501_000_000}


def test_a_byte_pointer_on_an_array_element_reads_and_writes_that_element_as_its_bytes_would():
    # the direct path for a whole element (Ptr._slot) keeps the codec's wrap-around and sign
    sint = t.ELEMENTARY["SINT"]
    array = t.ArrayType("ARRAY[0..2] OF SINT", sint, ((0, 2),))
    base = [1, 2, 3]
    p = memory.Ptr(base, array, 0, sint)
    memory.index(p, 1, sint).set(200)
    memory.index(p, 2, sint).set(-129)
    assert base == [1, -56, 127] and memory.index(p, 1, sint).get() == -56
    word = memory.cast(memory.add(p, 1, sint), sint, t.WORD)     # two elements as one WORD: the byte path
    assert word.get() == 0x7FC8
    bools = [False, True]
    q = memory.Ptr(bools, t.ArrayType("ARRAY[0..1] OF BOOL", t.BOOL, ((0, 1),)), 1, t.BOOL)
    q.set(0)
    assert bools == [False, False] and q.get() is False
