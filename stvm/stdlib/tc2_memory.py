"""Beckhoff Tc2_System memory functions (declarations in tc2_memory.st, `--dialect twincat`).

MEMCPY, MEMMOVE, MEMSET and MEMCMP read and write the bytes of the variables their pointers point
into, laid out as TwinCAT lays them out (stvm/runtime/memory.py, docs/memory_model.md). An access
outside the variable a pointer points into stops the task (`MemoryFault`).

References (Beckhoff Information System, TwinCAT 3 PLC library Tc2_System): "MEMCPY", "MEMMOVE",
"MEMSET", "MEMCMP".
"""

from __future__ import annotations

from stvm.runtime.memory import as_ptr, memcmp, memcpy, memset
from stvm.semantics import types as t
from stvm.stdlib.registry import native_function


@native_function("MEMCPY")
def memcpy_(ctx, dest, src, n: int) -> int:
    return memcpy(as_ptr(dest, t.BYTE), as_ptr(src, t.BYTE), n)


@native_function("MEMMOVE")
def memmove_(ctx, dest, src, n: int) -> int:
    return memcpy(as_ptr(dest, t.BYTE), as_ptr(src, t.BYTE), n)   # memcpy reads all before writing


@native_function("MEMSET")
def memset_(ctx, dest, fill: int, n: int) -> int:
    return memset(as_ptr(dest, t.BYTE), fill, n)


@native_function("MEMCMP")
def memcmp_(ctx, a, b, n: int) -> int:
    return memcmp(as_ptr(a, t.BYTE), as_ptr(b, t.BYTE), n)
