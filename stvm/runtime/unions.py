"""CODESYS UNION values: members that overlay the same bytes.

Representation choice: a union instance keeps the union's bytes (`_data`, little-endian as on an
x86 CODESYS target) and one Python value per member in the usual representation (`_vals`). The
member read or written last (`_last`) is the one whose value is current; reading another member
first writes the last one's value into the bytes (only its own bytes: the rest keep what was
there, as in memory) and then decodes the member read from them. So `u.a := 16#01020304` then
`u.b[0]` gives 16#04, and generated code, references and in-outs see plain values and lists.
An aggregate member (array, struct) may be changed in place through the list or object it
returned, so it is always written back; a scalar only after it was assigned.

The byte image of each type follows `stvm.semantics.types.byte_size`: BOOL one byte (0/1, any
non-zero byte reads TRUE), integers, enumerations and TIME-family values in their width (the
times 8 bytes of int64 ns), REAL/LREAL IEEE, STRING[n] its n bytes up to a NUL, WSTRING two bytes
a code unit, arrays row-major, structs with natural alignment.
"""

from __future__ import annotations

import struct
from typing import Any, Callable

from stvm.lower.layout import struct_layout
from stvm.semantics import types as t

Encode = Callable[[Any, bytearray, int], None]
Decode = Callable[[bytearray, int, Any], Any]


class _Union:
    __slots__ = ("_vals", "_last", "_data", "_dirty")
    _size = 0
    _codecs: tuple[tuple[Encode, Decode], ...] = ()
    _aggregate: tuple[bool, ...] = ()

    def __init__(self, values: list) -> None:
        self._vals = values
        self._last = 0
        self._data = bytearray(self._size)
        self._dirty = True

    def _sync(self) -> None:
        """Write the current member's value into the bytes."""
        if self._dirty:
            self._codecs[self._last][0](self._vals[self._last], self._data, 0)
            self._dirty = self._aggregate[self._last]

    def _switch(self, index: int) -> None:
        self._sync()
        self._vals[index] = self._codecs[index][1](self._data, 0, self._vals[index])
        self._last = index
        self._dirty = self._aggregate[index]

    def _copy(self):
        self._sync()
        other = type(self).__new__(type(self))
        other._data = bytearray(self._data)
        other._vals = [_copied(value) for value in self._vals]
        other._last = self._last
        other._dirty = self._aggregate[self._last]
        return other

    def _assign(self, src: "_Union") -> None:
        if src is self:
            return
        src._sync()
        self._data[:] = src._data
        index = src._last
        self._vals[index] = self._codecs[index][1](self._data, 0, self._vals[index])
        self._last = index
        self._dirty = self._aggregate[index]


class _UnionMember:
    """The descriptor of one member (`v_<name>` on the generated union class)."""

    __slots__ = ("index",)

    def __init__(self, index: int) -> None:
        self.index = index

    def __get__(self, obj, cls=None):
        if obj is None:
            return self
        if obj._last != self.index:
            obj._switch(self.index)
        return obj._vals[self.index]

    def __set__(self, obj, value) -> None:
        index = self.index
        if obj._last != index:
            obj._sync()   # the bytes this member does not cover keep the last member's
        obj._vals[index] = value
        obj._last = index
        obj._dirty = True


def _copied(value):
    if type(value) is list:
        return [_copied(v) for v in value]
    copy = getattr(value, "_copy", None)
    return copy() if copy is not None else value


def union_codecs(ty: t.UnionType) -> tuple[int, tuple[tuple[Encode, Decode], ...], tuple[bool, ...]]:
    """(size in bytes, (encode, decode) per member, is-aggregate per member) of a union type."""
    size = t.byte_size(ty) or 0
    codecs = tuple(codec(fty) for _, fty in ty.fields)
    aggregate = tuple(isinstance(fty, (t.ArrayType, t.StructType)) for _, fty in ty.fields)
    return size, codecs, aggregate


def codec(ty: t.Type) -> tuple[Encode, Decode]:
    """Write a value of `ty` at an offset of a bytearray, and read one back (an aggregate is read
    into the existing list or object given, so that it keeps its identity)."""
    if isinstance(ty, t.BoolType):
        def encode(value, buf, at):
            buf[at] = 1 if value else 0

        def decode(buf, at, old):
            return buf[at] != 0
        return encode, decode
    if isinstance(ty, t.EnumType):
        return codec(ty.base if ty.base is not None else t.INT)
    if isinstance(ty, t.IntType):
        return _int_codec(ty.bits // 8, ty.signed)
    if isinstance(ty, t.TimeType):
        return _int_codec(8, True)
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
        return _array_codec(ty)
    if isinstance(ty, t.UnionType):
        return _nested_union_codec(ty)
    if isinstance(ty, t.StructType):
        return _struct_codec(ty)
    raise TypeError(f"{ty.name} has no byte image")   # the checker refuses such members


def _int_codec(size: int, signed: bool) -> tuple[Encode, Decode]:
    def encode(value, buf, at):
        buf[at:at + size] = int(value).to_bytes(size, "little", signed=signed)

    def decode(buf, at, old):
        return int.from_bytes(buf[at:at + size], "little", signed=signed)
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


def _array_codec(ty: t.ArrayType) -> tuple[Encode, Decode]:
    element = ty.element
    step = t.byte_size(element) or 0
    encode_one, decode_one = codec(element)
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


def _struct_codec(ty: t.StructType) -> tuple[Encode, Decode]:
    members = []
    offset = 0
    for slot in struct_layout(ty):   # the storage names of the struct's members, in order
        fty = slot.type
        align = t.alignment(fty) or 1
        offset = -(-offset // align) * align
        members.append((slot.storage, offset, *codec(fty), isinstance(fty, (t.ArrayType, t.StructType))))
        offset += t.byte_size(fty) or 0

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


def _nested_union_codec(ty: t.UnionType) -> tuple[Encode, Decode]:
    size = t.byte_size(ty) or 0

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


UNION_HELPERS = {"_Union": _Union, "_UnionMember": _UnionMember, "_union_codecs": union_codecs}
