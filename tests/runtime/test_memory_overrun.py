"""`pointer_overrun`: an access through a byte pointer a few bytes outside the variable it points
into (docs/memory_model.md, "Outside a variable"). `guard` (the TwinCAT and CODESYS profiles):
an 8-byte guard on each side of every variable absorbs it, writes there are dropped and reads give
0; `fault` (Sysmac, IEC, or chosen): the task stops at the access."""

from __future__ import annotations

import pytest

import stvm
from core_helpers import cli, run_st, write_st
from stvm.runtime import memory
from stvm.semantics import types as t
from stvm.settings import PointerOverrun, SysmacSettings

GUARD = SysmacSettings(dialect="twincat")
FAULT = SysmacSettings(dialect="twincat").with_overrides(["pointer_overrun=fault"])

# TcUnit's FB_StreamBuffer.Append, reduced: it copies bytes while the length is below the buffer's
# size, then writes the terminating NUL one byte past the copied ones, which for a full buffer is
# one byte past its end (TcUnit-Verifier's Test_BufferOverflow)
STREAM = """
PROGRAM Main
VAR
    small : ARRAY[0..9] OF BYTE;
    after : ARRAY[0..3] OF BYTE := [1, 2, 3, 4];
    text : STRING := 'abcdefuwxyz';
    pIn, pOut : POINTER TO BYTE;
    length : UDINT;
    past : BYTE := 16#AA;
END_VAR
pIn := ADR(text);
pOut := ADR(small);
WHILE pIn^ <> 0 AND length < SIZEOF(small) DO
    pOut^ := pIn^;
    pIn := pIn + 1;
    pOut := pOut + 1;
    length := length + 1;
END_WHILE
pOut^ := 0;      // one byte past small
past := pOut^;   // and read back
END_PROGRAM
"""


def run(source: str, prints: list[str], settings: SysmacSettings) -> dict:
    values = run_st(source, prints=[f"Main.{p}" for p in prints], settings=settings)
    return {p: values[f"Main.{p}"] for p in prints}


def test_the_twincat_and_codesys_profiles_guard_and_the_others_fault():
    assert SysmacSettings(dialect="twincat").pointer_overrun is PointerOverrun.GUARD
    assert SysmacSettings(dialect="codesys").pointer_overrun is PointerOverrun.GUARD
    assert SysmacSettings(dialect="sysmac").pointer_overrun is PointerOverrun.FAULT
    assert SysmacSettings(dialect="iec").pointer_overrun is PointerOverrun.FAULT


def test_guard_absorbs_the_nul_written_past_a_full_buffer():
    values = run(STREAM, ["small", "after", "length", "past"], GUARD)
    assert values == {"small": list(b"abcdefuwxy"), "after": [1, 2, 3, 4], "length": 10, "past": 0}


def test_fault_stops_the_task_at_the_nul_written_past_a_full_buffer():
    with pytest.raises(stvm.RuntimeFault, match="access to 1 byte.s. at offset 10 of a 10-byte .*outside the variable"):
        run(STREAM, ["small"], FAULT)


def test_guard_keeps_what_is_inside_and_drops_what_is_outside_a_memcpy():
    source = ("PROGRAM Main VAR a : INT; b : DINT := 16#11223344; c : ARRAY[0..1] OF BYTE := [7, 8]; "
              "d : DINT := -1; END_VAR\n"
              "MEMCPY(ADR(a), ADR(b), 4);      // 2 bytes into a, 2 into its guard\n"
              "MEMCPY(ADR(d), ADR(c), 4);      // 2 bytes from c, 2 from its guard (0)\n"
              "END_PROGRAM")
    assert run(source, ["a", "b", "d"], GUARD) == {"a": 0x3344, "b": 0x11223344, "d": 0x0807}
    with pytest.raises(stvm.RuntimeFault, match="outside the variable"):
        run(source, ["a"], FAULT)


def test_guard_before_the_start_reads_zero_and_drops_writes():
    source = ("PROGRAM Main VAR a : ARRAY[0..3] OF BYTE := [1, 2, 3, 4]; p : POINTER TO BYTE; "
              "w : POINTER TO WORD; before : BYTE := 16#AA; straddle : WORD; END_VAR\n"
              "p := ADR(a) - 1; before := p^; p^ := 16#FF;\n"
              "w := ADR(a) - 1; straddle := w^; w^ := 16#BBCC;\n"
              "END_PROGRAM")
    # the WORD at -1 is its low byte in the guard (0, then dropped) and its high byte a[0]
    assert run(source, ["a", "before", "straddle"], GUARD) == {"a": [0xBB, 2, 3, 4], "before": 0, "straddle": 0x0100}


def test_guard_is_eight_bytes_beyond_it_the_access_faults():
    inside = "PROGRAM Main VAR a : DINT; p : POINTER TO BYTE; END_VAR p := ADR(a) + 11; p^ := 1; END_PROGRAM"
    run(inside, ["a"], GUARD)                 # byte 11 of a 4-byte DINT: the guard's last byte
    beyond = inside.replace("+ 11", "+ 12")
    with pytest.raises(stvm.RuntimeFault, match="outside the variable the pointer points into and its 8-byte guard"):
        run(beyond, ["a"], GUARD)
    before = inside.replace("+ 11", "- 9")
    with pytest.raises(stvm.RuntimeFault, match="8-byte guard"):
        run(before, ["a"], GUARD)


def test_a_pointer_keeps_its_guard_through_casts_and_arithmetic():
    base = [1, 2]
    array = t.ArrayType("ARRAY[0..1] OF BYTE", t.BYTE, ((0, 1),))
    p = memory.Ptr(base, array, 0, t.BYTE, guard=memory.GUARD_BYTES)
    q = memory.cast(memory.add(p, 1, t.BYTE), t.BYTE, t.WORD)
    assert q.guard == memory.GUARD_BYTES
    q.set(0xBEEF)                             # byte 1 of the array, byte 2 in the guard
    assert base == [1, 0xEF] and q.get() == 0x00EF
    assert memory.index(p, 3, t.BYTE).get() == 0


def test_the_setting_comes_from_the_command_line_and_the_manifest(tmp_path):
    source = write_st(STREAM, "stream.st", tmp_path)
    rc, _, err = cli(["run", source, "--dialect", "twincat", "--cycles", "1"])
    assert rc == 0, err
    rc, _, err = cli(["run", source, "--dialect", "codesys", "--cycles", "1", "--sysmac", "pointer_overrun=guard"])
    assert rc == 0, err
    rc, _, err = cli(["run", source, "--dialect", "twincat", "--cycles", "1", "--sysmac", "pointer_overrun=fault"])
    assert rc == 3 and "outside the variable" in err and "Traceback" not in err
    (tmp_path / "stvm.toml").write_text('[project]\ndialect = "twincat"\nfiles = ["stream.st"]\n'
                                        '[sysmac]\npointer_overrun = "fault"\n', encoding="utf-8")
    rc, _, err = cli(["run", tmp_path, "--cycles", "1"])
    assert rc == 3 and "outside the variable" in err
