"""CODESYS SysMem (stvm/stdlib/sys_mem.*, `--dialect codesys`): SysMemCpy, SysMemMove,
SysMemSet, SysMemCmp on the byte view of the memory model (docs/memory_model.md)."""

from __future__ import annotations

import pytest

from stvm.project import LoadError, load
from stvm.runtime.vm import RuntimeFault
from stvm.settings import DEFAULT_SETTINGS
from tests.core_helpers import write_files

CODESYS = DEFAULT_SETTINGS.with_table({"dialect": "codesys"}, "test")

SOURCE = """
PROGRAM Main
VAR
    a : ARRAY[0..3] OF BYTE := [1, 2, 3, 4];
    b : ARRAY[0..3] OF BYTE;
    d : DWORD;
    x : LREAL := 1.5;
    y : LREAL;
    p : POINTER TO BYTE;
    first : BYTE;
    same, less, greater : DINT;
    shifted : ARRAY[0..3] OF BYTE := [1, 2, 3, 4];
END_VAR
p := SysMemCpy(ADR(b), ADR(a), SIZEOF(a));
first := p^;
SysMemSet(ADR(d), 16#1AB, 2);
SysMemCpy(pDest := ADR(y), pSrc := ADR(x), udiCount := SIZEOF(x));
same := SysMemCmp(ADR(a), ADR(b), 4);
b[2] := 9;
less := SysMemCmp(ADR(a), ADR(b), 4);
greater := SysMemCmp(ADR(b), ADR(a), 4);
SysMemMove(ADR(shifted[1]), ADR(shifted[0]), 3);
END_PROGRAM
"""


def test_copy_set_compare_move() -> None:
    vm = load(write_files({"main.st": SOURCE}), CODESYS, use_cache=False).start()
    vm.run(cycles=1)
    assert vm["Main.b"] == [1, 2, 9, 4]           # copied, then b[2] changed
    assert vm["Main.first"] == 1                  # SysMemCpy returns the destination
    assert vm["Main.d"] == 0xABAB                 # the low byte of the value, two bytes of the DWORD
    assert vm["Main.y"] == 1.5                    # an LREAL's eight bytes
    assert (vm["Main.same"], vm["Main.less"], vm["Main.greater"]) == (0, -1, 1)
    assert vm["Main.shifted"] == [1, 1, 2, 3]     # overlapping areas: as memmove


def test_a_copy_beyond_the_variable_stops_the_task() -> None:
    # under codesys the `pointer_overrun` guard absorbs 8 bytes past a variable (docs/memory_model.md):
    # 18 bytes past it go beyond the guard
    src = """
PROGRAM Main
VAR
    a : ARRAY[0..31] OF BYTE;
    b : ARRAY[0..1] OF BYTE;
END_VAR
SysMemCpy(ADR(b), ADR(a), 20);
END_PROGRAM
"""
    vm = load(write_files({"main.st": src}), CODESYS, use_cache=False).start()
    with pytest.raises(RuntimeFault, match="outside the variable"):
        vm.run(cycles=1)


def test_sysmem_is_codesys_only() -> None:
    with pytest.raises(LoadError) as info:
        load(write_files({"main.st": SOURCE}), DEFAULT_SETTINGS.with_table({"dialect": "twincat"}, "test"),
             use_cache=False)
    assert "SysMemCpy" in info.value.render()
