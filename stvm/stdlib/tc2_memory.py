"""Beckhoff Tc2_System memory functions (declarations in tc2_memory.st, `--dialect twincat`).

MEMCPY, MEMMOVE, MEMSET and MEMCMP read and write the bytes of the variables their pointers point
into, laid out as TwinCAT lays them out (stvm/runtime/memory.py, docs/memory_model.md). An access
outside the variable a pointer points into stops the task (`MemoryFault`), unless it stays within
the guard `pointer_overrun=guard` gives each variable (the natives make their pointers with the
run's guard, as the generated code does).

References (Beckhoff Information System, TwinCAT 3 PLC library Tc2_System): "MEMCPY", "MEMMOVE",
"MEMSET", "MEMCMP".
"""

from __future__ import annotations

from stvm.runtime.memory import as_ptr, guard_bytes, memcmp, memcpy, memset
from stvm.semantics import types as t
from stvm.stdlib.registry import native_function


def _bytes(ctx, p):
    """A pointer argument as a byte pointer with the run's guard."""
    return as_ptr(p, t.BYTE, guard=guard_bytes(ctx.settings))


@native_function("MEMCPY")
def memcpy_(ctx, dest, src, n: int) -> int:
    return memcpy(_bytes(ctx, dest), _bytes(ctx, src), n)


@native_function("MEMMOVE")
def memmove_(ctx, dest, src, n: int) -> int:
    return memcpy(_bytes(ctx, dest), _bytes(ctx, src), n)   # memcpy reads all before writing


@native_function("MEMSET")
def memset_(ctx, dest, fill: int, n: int) -> int:
    return memset(_bytes(ctx, dest), fill, n)


@native_function("MEMCMP")
def memcmp_(ctx, a, b, n: int) -> int:
    return memcmp(_bytes(ctx, a), _bytes(ctx, b), n)
