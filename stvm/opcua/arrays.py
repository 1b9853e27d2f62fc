"""Array-valued variables beside the element variables, and OPC UA NumericRange (IndexRange).

An ST ARRAY of an elementary type whose elements are all published is also served as one
variable `ns;s=<array path>.@Value` (BrowseName `Value`, a component of the array's object):
Value an array of the element's DataType, ValueRank the ST array's rank, ArrayDimensions its
lengths. OPC UA arrays start at 0 whatever the ST lower bound (`Counts : ARRAY[1..5] OF INT`:
OPC UA index 0 is `Counts[1]`); a multi-dimensional array is flattened with the last index
fastest (OPC UA Part 6 §5.2.2.16, which is ST's own order).

IndexRange (OPC UA Part 4 §7.27 NumericRange): `i` or `i:j` (i < j) per dimension, dimensions
joined by commas. On Read a range that starts past the end is Bad_IndexRangeNoData and one
that ends past the end returns the part that exists; on Write the range must lie inside the
array (else Bad_IndexRangeNoData) and the value must have exactly the range's size (else
Bad_IndexRangeDataMismatch). One more dimension than the array on an array of STRING selects
characters of each string (Part 4 §7.27: arrays of strings).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from itertools import product
from typing import Any

from asyncua import ua

from stvm.opcua.datatypes import UaType
from stvm.opcua.nodes import PublishedVariable
from stvm.semantics import types as t

_RANGE = re.compile(r"(\d+)(?::(\d+))?")


class RangeError(Exception):
    def __init__(self, status: int) -> None:
        super().__init__(ua.StatusCode(status).name)
        self.status = status


@dataclass(eq=False)
class PublishedArray:
    """One ARRAY of an elementary type served as an array-valued variable."""

    path: str
    elements: list[PublishedVariable]     # row-major, the last index fastest
    dims: list[int]                       # length of each dimension
    uatype: UaType
    writable: bool
    nodeid: ua.NodeId | None = None
    value_attr: Any = None
    last: tuple | None = field(default=None, repr=False)

    @property
    def paths(self) -> list[str]:
        return [e.path for e in self.elements]

    def variant(self, values) -> ua.Variant:
        to_ua = self.uatype.to_ua
        converted = [to_ua(v) for v in values]
        return ua.Variant(converted, self.uatype.variant, Dimensions=self.dims if len(self.dims) > 1 else None,
                          is_array=True)


def find_arrays(roots, variables: dict[str, PublishedVariable]) -> list[tuple[Any, PublishedArray]]:
    """(catalog node, array) for every ARRAY whose elements are all published elementary values."""
    found = []
    for root in roots:
        for node in root.walk():
            if not isinstance(node.type, t.ArrayType) or not node.children:
                continue
            elements = [variables.get(child.path) for child in node.children]
            if any(e is None for e in elements):
                continue
            dims = [hi - lo + 1 for lo, hi in node.type.dims]
            if len(elements) != _size(dims):
                continue
            first = elements[0].uatype
            if any(e.uatype.variant != first.variant for e in elements):
                continue
            found.append((node, PublishedArray(node.path, elements, dims, first, all(e.writable for e in elements))))
    return found


def _size(dims: list[int]) -> int:
    size = 1
    for d in dims:
        size *= d
    return size


def parse_range(text: str) -> list[tuple[int, int]]:
    """NumericRange text → [(first, last)] per dimension (inclusive); raises RangeError
    (Bad_IndexRangeInvalid) for text that is no NumericRange."""
    ranges = []
    for part in text.split(","):
        match = _RANGE.fullmatch(part)
        if match is None:
            raise RangeError(ua.StatusCodes.BadIndexRangeInvalid)
        first = int(match.group(1))
        last = int(match.group(2)) if match.group(2) is not None else first
        if match.group(2) is not None and last <= first:
            raise RangeError(ua.StatusCodes.BadIndexRangeInvalid)
        ranges.append((first, last))
    return ranges


def _positions(dims: list[int], ranges: list[tuple[int, int]], clip: bool) -> tuple[list[int], list[int]]:
    """Flat positions selected by `ranges` over `dims`, and the selection's shape."""
    axes = []
    for (first, last), length in zip(ranges, dims):
        if first >= length:
            raise RangeError(ua.StatusCodes.BadIndexRangeNoData)
        if last >= length:
            if not clip:
                raise RangeError(ua.StatusCodes.BadIndexRangeNoData)
            last = length - 1
        axes.append(range(first, last + 1))
    strides = [_size(dims[i + 1:]) for i in range(len(dims))]
    positions = [sum(i * s for i, s in zip(index, strides)) for index in product(*axes)]
    return positions, [len(a) for a in axes]


def read_range(array: PublishedArray, values: list, text: str) -> ua.Variant:
    """The Variant a Read with IndexRange `text` returns (raises RangeError)."""
    ranges = parse_range(text)
    rank = len(array.dims)
    chars = None
    if len(ranges) == rank + 1 and array.uatype.variant == ua.VariantType.String:
        chars = ranges.pop()
    elif len(ranges) != rank:
        raise RangeError(ua.StatusCodes.BadIndexRangeNoData)
    positions, shape = _positions(array.dims, ranges, clip=True)
    picked = [array.uatype.to_ua(values[p]) for p in positions]
    if chars is not None:
        first, last = chars
        picked = [s[first:last + 1] for s in picked]
        if all(s == "" for s in picked):
            raise RangeError(ua.StatusCodes.BadIndexRangeNoData)
    return ua.Variant(picked, array.uatype.variant, Dimensions=shape if rank > 1 else None, is_array=True)


def write_positions(array: PublishedArray, text: str | None, count: int) -> list[int]:
    """Flat positions a Write of `count` values with IndexRange `text` sets (raises RangeError)."""
    if not text:
        if count != len(array.elements):
            raise RangeError(ua.StatusCodes.BadTypeMismatch)    # the whole array: its exact size
        return list(range(count))
    ranges = parse_range(text)
    if len(ranges) != len(array.dims):
        raise RangeError(ua.StatusCodes.BadIndexRangeNoData)
    positions, _ = _positions(array.dims, ranges, clip=False)
    if len(positions) != count:
        raise RangeError(ua.StatusCodes.BadIndexRangeDataMismatch)
    return positions


def flat(value: Any) -> list:
    """A Variant's array value as a flat list (asyncua hands a matrix as nested lists)."""
    if not isinstance(value, list):
        return [value]
    out: list = []
    for item in value:
        out.extend(flat(item) if isinstance(item, list) else [item])
    return out
