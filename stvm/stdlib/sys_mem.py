"""CODESYS SysMem natives (declarations in sys_mem.st, `--dialect codesys`).

SysMemCpy, SysMemMove, SysMemSet and SysMemCmp read and write the bytes of the variables their
pointers point into, laid out as CODESYS on x64 lays them out (stvm/runtime/memory.py, the same
byte view as the Tc2_System MEMCPY family in tc2_memory.py). An access outside the variable a
pointer points into stops the task (`MemoryFault`).

Reference: CODESYS online help, SysMem library ("SysMemCpy": the destination pointer is returned).
Choice: a NULL pDest or pSrc copies nothing and returns NULL (the runtime returns NULL for an
invalid pointer); SysMemCmp of a NULL pointer stops the task, as MEMCMP does.
"""

from __future__ import annotations

from stvm.runtime.memory import as_ptr, memcmp, memcpy, memset
from stvm.semantics import types as t
from stvm.stdlib.registry import native_function


def _copy(dest, src, count: int):
    dest_ptr, src_ptr = as_ptr(dest, t.BYTE), as_ptr(src, t.BYTE)
    if dest_ptr is None or src_ptr is None:
        return None
    memcpy(dest_ptr, src_ptr, count)   # reads every byte before writing: overlap is safe
    return dest


@native_function("SysMemCpy")
def sys_mem_cpy(ctx, dest, src, count: int):
    return _copy(dest, src, count)


@native_function("SysMemMove")
def sys_mem_move(ctx, dest, src, count: int):
    return _copy(dest, src, count)


@native_function("SysMemSet")
def sys_mem_set(ctx, dest, value: int, count: int):
    dest_ptr = as_ptr(dest, t.BYTE)
    if dest_ptr is None:
        return None
    memset(dest_ptr, value & 0xFF, count)
    return dest


@native_function("SysMemCmp")
def sys_mem_cmp(ctx, a, b, count: int) -> int:
    return memcmp(as_ptr(a, t.BYTE), as_ptr(b, t.BYTE), count)
