"""CODESYS UNION values: members that overlay the same bytes.

Representation choice: a union instance keeps the union's bytes (`_data`, little-endian as on an
x86 CODESYS target) and one Python value per member in the usual representation (`_vals`). The
member read or written last (`_last`) is the one whose value is current; reading another member
first writes the last one's value into the bytes (only its own bytes: the rest keep what was
there, as in memory) and then decodes the member read from them. So `u.a := 16#01020304` then
`u.b[0]` gives 16#04, and generated code, references and in-outs see plain values and lists.
An aggregate member (array, struct) may be changed in place through the list or object it
returned, so it is always written back; a scalar only after it was assigned.

The byte image of each type is the one of `stvm.runtime.memory.codec` (the serialiser MEMCPY and
cast pointers use too).
"""

from __future__ import annotations

from typing import Any, Callable

from stvm.runtime.memory import codec
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


def union_codecs(ty: t.UnionType, short: bool = False) -> tuple[int, tuple[tuple[Encode, Decode], ...], tuple[bool, ...]]:
    """(size in bytes, (encode, decode) per member, is-aggregate per member) of a union type
    (`short`: the TwinCAT/CODESYS time layout, `stvm.runtime.memory.codec`)."""
    size = t.byte_size(ty, short) or 0
    codecs = tuple(codec(fty, short) for _, fty in ty.fields)
    aggregate = tuple(isinstance(fty, (t.ArrayType, t.StructType)) for _, fty in ty.fields)
    return size, codecs, aggregate


UNION_HELPERS = {"_Union": _Union, "_UnionMember": _UnionMember, "_union_codecs": union_codecs}
