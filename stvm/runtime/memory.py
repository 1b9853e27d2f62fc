"""The byte-addressable view of memory of the TwinCAT and CODESYS profiles (docs/memory_model.md).

stvm keeps ST values as Python values (ints, floats, bytes, lists, struct objects); a pointer is a
reference to a variable (`AttrRef`/`ItemRef`), an aggregate object itself, or None. TwinCAT code
also treats memory as bytes: `MEMCPY(ADR(a), ADR(b), SIZEOF(b))`, `p := p + 1` on a
`POINTER TO BYTE`, `pDW := ADR(realVar); dw := pDW^`. For that, a pointer whose target type is
not the type of the variable it points into is a `Ptr`: the variable it points into (`base`, its
type `base_type`), a byte offset into it, and the type it is read as (`view`). Reading through a
`Ptr` lays the variable out as bytes (`codec`, below, the one serialiser) and decodes the view's
bytes at the offset; writing encodes the view's value into those bytes and decodes the variable
back from them, so the variable keeps its usual Python representation.

The byte image of each type (`codec`) is TwinCAT's on x86/x64, little-endian: BOOL one byte
(0/1; any non-zero byte reads TRUE), integers, enumerations in their width, REAL/LREAL IEEE 754,
TIME/TOD 32-bit milliseconds and DATE/DT 32-bit seconds (the `short_times` row; 64-bit
nanoseconds in the other profiles and for LTIME & co.), STRING(n) n+1 bytes up to a NUL,
WSTRING(n) 2(n+1) bytes, arrays row-major, structs with each member at a multiple of its own
alignment (at most 8) and the whole padded to its largest member's alignment — the layout of
`byte_size`, which SIZEOF reports, so SIZEOF and the bytes agree.
"""

from __future__ import annotations

import struct
from functools import partial
from typing import Any, Callable

from stvm.lower.layout import struct_layout
from stvm.runtime.values import ItemRef, STFault
from stvm.semantics import types as t
from stvm.settings import PointerOverrun

Encode = Callable[[Any, bytearray, int], None]
Decode = Callable[[bytearray, int, Any], Any]


class MemoryFault(STFault):
    """A read or write through a pointer outside the variable it points into (TwinCAT: a page
    fault or a silent overwrite of a neighbour; stvm stops the task, unless the access stays
    within the guard of `pointer_overrun=guard`)."""


GUARD_BYTES = 8
"""The guard of `pointer_overrun=guard`: how many bytes before and after a variable absorb an
access through a byte pointer (writes there are dropped, reads give 0). 8 is TwinCAT 3's
alignment (Beckhoff "Alignment"): what lies within 8 bytes of a variable's end is its padding or
its neighbour, which a real PLC overwrites without an error."""


# ---- the serialiser ------------------------------------------------------------------------------
_CODECS: dict[tuple[t.Type, bool], tuple[Encode, Decode]] = {}
_MS, _S = 1_000_000, 1_000_000_000   # nanoseconds in a millisecond, in a second


def codec(ty: t.Type, short: bool = False) -> tuple[Encode, Decode]:
    """Write a value of `ty` at an offset of a bytearray, and read one back (an aggregate is read
    into the existing list or object given, so that it keeps its identity). `short`: the
    TwinCAT/CODESYS time layout (`short_times`: TIME/TOD 32-bit ms, DATE/DT 32-bit s)."""
    if isinstance(ty, (t.StructType, t.ArrayType, t.EnumType)):
        # not cached: a struct or enum type compares by name only (two projects of one process may
        # declare different ST_X), and building an aggregate's codec is cheap beside using it
        return _build_codec(ty, short)
    found = _CODECS.get((ty, short))
    if found is None:
        found = _CODECS[ty, short] = _build_codec(ty, short)
    return found


def _build_codec(ty: t.Type, short: bool) -> tuple[Encode, Decode]:
    if isinstance(ty, t.BoolType):
        def encode(value, buf, at):
            buf[at] = 1 if value else 0

        def decode(buf, at, old):
            return buf[at] != 0
        return encode, decode
    if isinstance(ty, t.EnumType):
        return codec(ty.base if ty.base is not None else t.INT, short)
    if isinstance(ty, t.IntType):
        return _int_codec(ty.bits // 8, ty.signed)
    if isinstance(ty, t.TimeType):
        if short and not ty.long:
            return _scaled_codec(_MS if ty.family in ("TIME", "TIME_OF_DAY") else _S)
        # the TwinCAT/CODESYS layout is that of the unsigned time types (`unsigned_time`): LTIME a ULINT
        return _int_codec(8, not (short and ty.family == "TIME"))
    if isinstance(ty, t.RealType):
        packer = struct.Struct("<f" if ty.bits == 32 else "<d")

        def encode(value, buf, at):
            packer.pack_into(buf, at, value)

        def decode(buf, at, old):
            return packer.unpack_from(buf, at)[0]
        return encode, decode
    if isinstance(ty, t.WStringType):
        return _wstring_codec(ty)
    if isinstance(ty, t.StringType):
        return _string_codec(ty)
    if isinstance(ty, t.ArrayType):
        return _array_codec(ty, short)
    if isinstance(ty, t.UnionType):
        return _nested_union_codec(ty, short)
    if isinstance(ty, t.StructType):
        return _struct_codec(ty, short)
    raise TypeError(f"{ty.name} has no byte image")   # the checker refuses such members


def _int_codec(size: int, signed: bool) -> tuple[Encode, Decode]:
    def encode(value, buf, at):
        buf[at:at + size] = (int(value) & ((1 << 8 * size) - 1)).to_bytes(size, "little")

    def decode(buf, at, old):
        return int.from_bytes(buf[at:at + size], "little", signed=signed)
    return encode, decode


def _scaled_codec(unit: int) -> tuple[Encode, Decode]:
    """A time held in nanoseconds, stored as a 32-bit unsigned count of `unit` (TwinCAT TIME/TOD:
    milliseconds, DATE/DT: seconds); what does not fit a whole unit is dropped, as TwinCAT's
    32-bit value cannot hold it."""
    def encode(value, buf, at):
        buf[at:at + 4] = ((int(value) // unit) & 0xFFFFFFFF).to_bytes(4, "little")

    def decode(buf, at, old):
        return int.from_bytes(buf[at:at + 4], "little") * unit
    return encode, decode


def _string_codec(ty: t.StringType) -> tuple[Encode, Decode]:
    size, most = ty.size, ty.max_bytes

    def encode(value, buf, at):
        data = bytes(value[:most])
        buf[at:at + size] = data + bytes(size - len(data))

    def decode(buf, at, old):
        return bytes(buf[at:at + most]).split(b"\x00", 1)[0]
    return encode, decode


def _wstring_codec(ty: t.StringType) -> tuple[Encode, Decode]:
    size, most = 2 * ty.size, ty.max_bytes

    def encode(value, buf, at):
        data = b"".join(ord(unit).to_bytes(2, "little") for unit in value[:most])
        buf[at:at + size] = data + bytes(size - len(data))

    def decode(buf, at, old):
        units = []
        for i in range(most):
            unit = buf[at + 2 * i] | buf[at + 2 * i + 1] << 8
            if unit == 0:
                break
            units.append(chr(unit))
        return "".join(units)
    return encode, decode


def _array_codec(ty: t.ArrayType, short: bool) -> tuple[Encode, Decode]:
    element = ty.element
    step = t.byte_size(element, short) or 0
    encode_one, decode_one = codec(element, short)
    counts = [hi - lo + 1 for lo, hi in ty.dims or ()]
    strides = [step] * len(counts)
    for d in range(len(counts) - 2, -1, -1):
        strides[d] = strides[d + 1] * counts[d + 1]
    aggregate = isinstance(element, (t.ArrayType, t.StructType))

    def encode(value, buf, at, depth=0):
        stride = strides[depth]
        for i, item in enumerate(value):
            if depth + 1 < len(counts):
                encode(item, buf, at + i * stride, depth + 1)
            else:
                encode_one(item, buf, at + i * stride)

    def decode(buf, at, old, depth=0):
        stride = strides[depth]
        for i in range(len(old)):
            if depth + 1 < len(counts):
                decode(buf, at + i * stride, old[i], depth + 1)
            elif aggregate:
                decode_one(buf, at + i * stride, old[i])
            else:
                old[i] = decode_one(buf, at + i * stride, old[i])
        return old
    return encode, decode


def _struct_codec(ty: t.StructType, short: bool) -> tuple[Encode, Decode]:
    members = []
    offset = 0
    for slot in struct_layout(ty):   # the storage names of the struct's members, in order
        fty = slot.type
        align = t.alignment(fty, short) or 1
        offset = -(-offset // align) * align
        members.append((slot.storage, offset, *codec(fty, short), isinstance(fty, (t.ArrayType, t.StructType))))
        offset += t.byte_size(fty, short) or 0

    def encode(value, buf, at):
        for attr, where, encode_one, _, _ in members:
            encode_one(getattr(value, attr), buf, at + where)

    def decode(buf, at, old):
        for attr, where, _, decode_one, aggregate in members:
            if aggregate:
                decode_one(buf, at + where, getattr(old, attr))
            else:
                setattr(old, attr, decode_one(buf, at + where, None))
        return old
    return encode, decode


def _nested_union_codec(ty: t.UnionType, short: bool) -> tuple[Encode, Decode]:
    size = t.byte_size(ty, short) or 0

    def encode(value, buf, at):
        value._sync()
        buf[at:at + size] = value._data

    def decode(buf, at, old):
        old._data[:] = buf[at:at + size]
        index = old._last
        old._vals[index] = old._codecs[index][1](old._data, 0, old._vals[index])
        old._dirty = old._aggregate[index]
        return old
    return encode, decode


def image(value, ty: t.Type, short: bool = False) -> bytearray:
    """The bytes of a value of `ty`."""
    buf = bytearray(t.byte_size(ty, short) or 0)
    codec(ty, short)[0](value, buf, 0)
    return buf


# ---- byte-addressed pointers ---------------------------------------------------------------------
_SIZES: dict[t.Type, int] = {}   # the size of an integer or BOOL element type (no time layout involved)

class Ptr:
    """A pointer `offset` bytes into a variable, read as `view`. `base` is a reference (get/set) to
    a scalar variable, or an aggregate object (a list for an array, a struct or union object) that
    is changed in place; `base_type` is the variable's type; `short`: the time layout (`codec`)."""

    __slots__ = ("base", "base_type", "offset", "view", "short", "guard")

    def __init__(self, base, base_type: t.Type, offset: int, view: t.Type, short: bool = False,
                 guard: int = 0) -> None:
        self.base = base
        self.base_type = base_type
        self.offset = offset
        self.view = view
        self.short = short
        self.guard = guard      # bytes on each side that absorb an overrun (`pointer_overrun`)

    # the variable's bytes
    def _aggregate(self) -> bool:
        return t.is_aggregate(self.base_type)

    def load(self) -> bytearray:
        value = self.base if self._aggregate() else self.base.get()
        return image(value, self.base_type, self.short)

    def store(self, buf: bytearray) -> None:
        decode = codec(self.base_type, self.short)[1]
        if self._aggregate():
            decode(buf, 0, self.base)
        else:
            self.base.set(decode(buf, 0, None))

    def span(self, count: int) -> tuple[int, int]:
        """The bytes lo..hi-1 of the variable an access of `count` bytes touches: the part inside
        the variable (empty when all of it falls in the guard). An access outside the variable
        faults, unless it stays within the guard (`pointer_overrun=guard`)."""
        size = t.byte_size(self.base_type, self.short) or 0
        lo, hi = self.offset, self.offset + count
        if lo < 0 or hi > size:
            if lo < -self.guard or hi > size + self.guard:
                beyond = f" and its {self.guard}-byte guard" if self.guard else ""
                raise MemoryFault(f"access to {count} byte(s) at offset {lo} of a {size}-byte "
                                  f"{self.base_type.name}: outside the variable the pointer points into{beyond}")
            lo, hi = max(lo, 0), max(min(hi, size), max(lo, 0))
        return lo, hi

    def _window(self, lo: int, hi: int):
        """For a one-dimensional array: (its list, the element's codec, the element's size, the
        first and last element index that bytes lo..hi-1 touch), so that a read or write handles
        only those elements and not the whole variable (a MEMCPY of 500 bytes into a 1 MB byte
        buffer, as TcUnit's message queue does every scan, must not encode a million bytes).
        None for any other variable (it is encoded whole: structs and scalars are small)."""
        ty = self.base_type
        if not isinstance(ty, t.ArrayType) or len(ty.dims or ()) != 1 or type(self.base) is not list:
            return None
        step = t.byte_size(ty.element, self.short) or 0
        if step <= 0 or hi <= lo:
            return None
        return self.base, codec(ty.element, self.short), step, lo // step, (hi - 1) // step

    def read(self, count: int) -> bytes:
        lo, hi = self.span(count)
        inside = self._read_inside(lo, hi)
        if hi - lo == count:
            return inside
        if not inside:
            return bytes(count)
        before = lo - self.offset    # bytes in the guard before the variable: they read 0
        return bytes(before) + inside + bytes(count - before - len(inside))

    def _read_inside(self, lo: int, hi: int) -> bytes:
        if hi <= lo:
            return b""
        window = self._window(lo, hi)
        if window is None:
            return bytes(self.load()[lo:hi])
        items, (encode, _), step, first, last = window
        if _is_octet(self.base_type.element):     # an ARRAY OF BYTE/USINT: its elements are its bytes
            return bytes(items[lo:hi])
        buf = bytearray(step * (last - first + 1))
        for k in range(last - first + 1):
            encode(items[first + k], buf, k * step)
        start = lo - first * step
        return bytes(buf[start:start + hi - lo])

    def write(self, data: bytes) -> None:
        lo, hi = self.span(len(data))
        if hi - lo != len(data):     # partly or wholly in the guard: that part is dropped
            data = data[lo - self.offset:hi - self.offset]
            if not data:
                return
        window = self._window(lo, hi)
        if window is None:
            buf = self.load()
            buf[lo:hi] = data
            self.store(buf)
            return
        items, (encode, decode), step, first, last = window
        if _is_octet(self.base_type.element):     # MEMSET/MEMCPY into an ARRAY OF BYTE: the bytes are the elements
            items[lo:hi] = data
            return
        buf = bytearray(step * (last - first + 1))
        for k in range(last - first + 1):    # the touched elements' bytes, then the new ones over them
            encode(items[first + k], buf, k * step)
        start = lo - first * step
        buf[start:start + len(data)] = data
        aggregate = t.is_aggregate(self.base_type.element)
        for k in range(last - first + 1):
            if aggregate:
                decode(buf, k * step, items[first + k])
            else:
                items[first + k] = decode(buf, k * step, items[first + k])

    def _slot(self) -> int:
        """The index of the list element this pointer reads whole, as the element's own type, in
        a one-dimensional array of integers or BOOLs (`p^` of a POINTER TO BYTE walking an ARRAY
        OF BYTE, TcUnit's stream and XML buffers: one element, not the bytes of a window), else -1."""
        base, ty = self.base, self.base_type
        if type(base) is not list or type(ty) is not t.ArrayType or len(ty.dims or ()) != 1:
            return -1
        element = ty.element
        if type(element) not in (t.IntType, t.BoolType) or not (self.view is element or t.same_type(self.view, element)):
            return -1
        step = _SIZES.get(element)
        if step is None:
            step = _SIZES[element] = t.byte_size(element) or 1
        at, rest = divmod(self.offset, step)
        return at if rest == 0 and 0 <= at < len(base) else -1

    # the pointer's target, as generated code reads and writes it (`p^`)
    def get(self):
        at = self._slot()
        if at >= 0:
            return self.base[at]
        if self.offset == 0 and t.same_type(self.view, self.base_type):
            return self.base if self._aggregate() else self.base.get()
        if t.is_aggregate(self.view):
            raise MemoryFault(f"a {self.base_type.name} read as {self.view.name} through a pointer: "
                              "stvm reads only elementary values and strings through a cast pointer")
        size = t.byte_size(self.view, self.short) or 0
        return codec(self.view, self.short)[1](bytearray(self.read(size)), 0, None)

    def set(self, value) -> None:
        at = self._slot()
        if at >= 0:   # the value as the element's bytes would hold it (the codec's wrap)
            view = self.view
            if type(view) is t.BoolType:
                self.base[at] = bool(value)
            else:
                word = int(value) & ((1 << view.bits) - 1)
                self.base[at] = word - (1 << view.bits) if view.signed and word >> (view.bits - 1) else word
            return
        if self.offset == 0 and t.same_type(self.view, self.base_type) and not self._aggregate():
            self.base.set(value)
            return
        size = t.byte_size(self.view, self.short) or 0
        buf = bytearray(self.read(size))    # the bytes as they are (a STRING leaves its tail)
        codec(self.view, self.short)[0](value, buf, 0)
        self.write(bytes(buf))

    def same(self, other) -> bool:
        other = as_ptr(other, self.view, self.short)
        return type(other) is Ptr and other.offset == self.offset and _same_base(self.base, other.base)

    def moved(self, delta: int, view: t.Type) -> "Ptr":
        return Ptr(self.base, self.base_type, self.offset + delta, view, self.short, self.guard)


def _is_octet(ty: t.Type) -> bool:
    """An unsigned 8-bit integer type (BYTE, USINT): held as ints 0..255, the same as its bytes."""
    return type(ty) is t.IntType and ty.bits == 8 and not ty.signed


def _same_base(a, b) -> bool:
    if a is b:
        return True
    same = getattr(a, "same", None)
    return same is not None and same(b)


def as_ptr(p, target: t.Type, short: bool = False, *, guard: int = 0):
    """The pointer value `p` of static type POINTER TO `target` as a `Ptr` (None stays None).
    A value that is not a `Ptr` points to a variable of exactly `target` (the invariant the
    generated code keeps: every cast makes a `Ptr`); an array element's pointer is widened to
    the element's array, so that arithmetic walks the array."""
    if p is None or type(p) is Ptr:
        return p
    if type(p) is ItemRef and type(p.lst) is list:
        size = t.byte_size(target, short) or 0
        array = t.ArrayType(f"ARRAY[0..{len(p.lst) - 1}] OF {target.name}", target, ((0, len(p.lst) - 1),))
        return Ptr(p.lst, array, p.index * size, target, short, guard)
    return Ptr(p, target, 0, target, short, guard)


def cast(p, source: t.Type, target: t.Type, short: bool = False, *, guard: int = 0):
    """`POINTER TO target := POINTER TO source` (TwinCAT/CODESYS accept it: an address is an
    address); the result reads the same bytes as `target`."""
    if p is None:
        return None
    ptr = as_ptr(p, source, short, guard=guard)
    return Ptr(ptr.base, ptr.base_type, ptr.offset, target, ptr.short, ptr.guard)


def add(p, delta: int, target: t.Type, short: bool = False, *, guard: int = 0):
    """`p + delta` / `p - delta` on a POINTER TO `target`: `delta` bytes further (TwinCAT and
    CODESYS add bytes, not elements: 'ADR(x) + 1' is the next byte)."""
    if p is None:
        raise MemoryFault("pointer arithmetic on a NULL pointer (address 0)")
    ptr = as_ptr(p, target, short, guard=guard)
    return ptr.moved(delta, target)


def index(p, i: int, target: t.Type, short: bool = False, *, guard: int = 0):
    """`p[i]` on a POINTER TO `target`: the i-th element from the pointer (CODESYS/TwinCAT scale
    the index by the target's size, unlike `+`)."""
    return add(p, i * (t.byte_size(target, short) or 0), target, short, guard=guard)


def deref_aggregate(p):
    """`p^` for a pointer to an aggregate: the object itself (it is changed in place)."""
    if type(p) is Ptr:
        return p.get()
    return p


# ---- Tc2_System memory functions (natives with the pointer arguments already made `Ptr`s) --------
def memcpy(dest, src, count: int) -> int:
    """MEMCPY(destAddr, srcAddr, n): n bytes from src to dest; the bytes are read before any is
    written, so overlapping areas copy as MEMMOVE does. Returns the destination's "address"
    (non-zero), 0 when a pointer is NULL (Beckhoff: 0 on error)."""
    if count == 0:
        return 1 if dest is not None else 0
    if dest is None or src is None:
        return 0
    dest.write(src.read(count))
    return 1


def memset(dest, fill: int, count: int) -> int:
    """MEMSET(destAddr, fillByte, n): n bytes of dest set to fillByte."""
    if dest is None:
        return 0
    if count:
        dest.write(bytes([fill & 0xFF]) * count)
    return 1


def memcmp(a, b, count: int) -> int:
    """MEMCMP(pBuf1, pBuf2, n): 0 when the n bytes are equal, else 1 or -1 as the first
    different byte of pBuf1 is greater or smaller (Beckhoff; the sign of C's memcmp)."""
    if count == 0:
        return 0
    if a is None or b is None:
        raise MemoryFault("MEMCMP of a NULL pointer")
    left, right = a.read(count), b.read(count)
    return 0 if left == right else (1 if left > right else -1)


class Box:
    """A value that has no variable (an ANY argument given as an expression): the temporary
    TwinCAT makes for it, so that its address can be taken."""

    __slots__ = ("value",)

    def __init__(self, value) -> None:
        self.value = value

    def get(self):
        return self.value

    def set(self, value) -> None:
        self.value = value

    def same(self, other) -> bool:
        return other is self


MEMORY_HELPERS = {"_ptr_cast": cast, "_ptr_add": add, "_ptr_index": index, "_ptr_deref_agg": deref_aggregate,
                  "_as_ptr": as_ptr, "_Box": Box, "_Ptr": Ptr}


def guard_bytes(settings) -> int:
    """The guard a run with `settings` gives every byte pointer (`pointer_overrun`)."""
    return GUARD_BYTES if settings.pointer_overrun is PointerOverrun.GUARD else 0


def memory_helpers(guard: int) -> dict:
    """The helpers of the generated code for a program run with a guard of `guard` bytes
    (`pointer_overrun=guard`: GUARD_BYTES; `fault`: 0, the module's own functions): every byte
    pointer the program makes carries the guard, and a pointer derived from it keeps it."""
    if not guard:
        return dict(MEMORY_HELPERS)
    return {**MEMORY_HELPERS, "_ptr_cast": partial(cast, guard=guard), "_ptr_add": partial(add, guard=guard),
            "_ptr_index": partial(index, guard=guard), "_as_ptr": partial(as_ptr, guard=guard)}

__all__ = ["Box", "GUARD_BYTES", "MEMORY_HELPERS", "MemoryFault", "Ptr", "add", "as_ptr", "cast", "codec",
           "image", "index", "guard_bytes", "memcmp", "memcpy", "memory_helpers", "memset"]
