"""IEC 61131-3 types as OPC UA built-in types, both ways (values out, client writes in).

| ST type                    | OPC UA DataType (wire Variant)  | notes                                  |
|----------------------------|---------------------------------|----------------------------------------|
| BOOL                       | Boolean                         |                                        |
| SINT INT DINT LINT         | SByte Int16 Int32 Int64         | PLCopen's mapping (OPC UA for IEC 61131-3) |
| USINT UINT UDINT ULINT     | Byte UInt16 UInt32 UInt64       |                                        |
| BYTE WORD DWORD LWORD      | Byte UInt16 UInt32 UInt64       |                                        |
| REAL, LREAL                | Float, Double                   |                                        |
| STRING[n]                  | String                          | UTF-8; at most n-1 bytes, no NUL       |
| WSTRING[n]                 | String                          | the text of its UTF-16 code units; at most n units, no NUL |
| TIME                       | Int64: nanoseconds              | Choice: exact (stvm's own unit)        |
| TIME_OF_DAY                | Int64: nanoseconds since midnight |                                      |
| DATE, DATE_AND_TIME        | DateTime                        | UTC; microsecond resolution            |
| enum                       | an Enumeration DataType (Int32) | EnumStrings / EnumValues, EnumDefinition |

A client write is checked against the ST type, never coerced silently: a Variant of another kind
is `BadTypeMismatch`; a value of the right kind that the ST type cannot hold is `BadOutOfRange`.
Integer nodes take any integer Variant whose value fits (clients such as asyncua send a Python int
as Int64), real nodes take Float, Double or integers.
"""

from __future__ import annotations

import functools
import math
import struct
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone
from typing import Any, Callable

from asyncua import ua

from stvm.numeric import utf16_text, utf16_units
from stvm.semantics import types as t

NS_PER_DAY = 86_400 * 1_000_000_000
EPOCH = datetime(1970, 1, 1, tzinfo=timezone.utc)
_F32_MAX = struct.unpack("<f", b"\xff\xff\x7f\x7f")[0]

_INT_VARIANTS = {ua.VariantType.SByte, ua.VariantType.Byte, ua.VariantType.Int16, ua.VariantType.UInt16,
                 ua.VariantType.Int32, ua.VariantType.UInt32, ua.VariantType.Int64, ua.VariantType.UInt64}
_INT_BY_BITS = {(8, True): ua.VariantType.SByte, (16, True): ua.VariantType.Int16,
                (32, True): ua.VariantType.Int32, (64, True): ua.VariantType.Int64,
                (8, False): ua.VariantType.Byte, (16, False): ua.VariantType.UInt16,
                (32, False): ua.VariantType.UInt32, (64, False): ua.VariantType.UInt64}
INT64_MIN, INT64_MAX = -(1 << 63), (1 << 63) - 1


class BadWrite(Exception):
    """A client value the ST type cannot take; `status` is the OPC UA status code to answer."""

    def __init__(self, status: int, reason: str) -> None:
        super().__init__(reason)
        self.status = status


@dataclass(frozen=True)
class UaType:
    """How one ST type travels: `variant` on the wire, `datatype` in the address space."""

    variant: ua.VariantType
    datatype: ua.NodeId | None      # None: the enum's own DataType node (made by the address space)
    to_ua: Callable[[Any], Any]     # stvm value → Variant value
    from_ua: Callable[[ua.Variant], Any]   # client Variant → stvm value (raises BadWrite)
    text: str                       # the ST type as the Description shows it


@functools.lru_cache(maxsize=None)
def ua_type(ty: t.Type) -> UaType | None:
    """The mapping of an elementary ST type; None for a type published as an object."""
    if isinstance(ty, t.BoolType):
        return UaType(ua.VariantType.Boolean, _dt(ua.ObjectIds.Boolean), bool, _bool_in, ty.name)
    if isinstance(ty, t.IntType):
        variant = _INT_BY_BITS[(ty.bits, ty.signed)]
        return UaType(variant, _dt(variant.value), int, _int_in(ty.lo, ty.hi, ty.name), ty.name)
    if isinstance(ty, t.RealType):
        if ty.bits == 32:
            return UaType(ua.VariantType.Float, _dt(ua.ObjectIds.Float), float, _real_in(True), ty.name)
        return UaType(ua.VariantType.Double, _dt(ua.ObjectIds.Double), float, _real_in(False), ty.name)
    if t.is_wide(ty):
        return UaType(ua.VariantType.String, _dt(ua.ObjectIds.String), utf16_text, _wstring_in(ty.max_bytes, ty.name),
                      ty.name)
    if isinstance(ty, t.StringType):
        text = f"STRING[{ty.size}]" if ty.size != t.STRING.size else "STRING"
        return UaType(ua.VariantType.String, _dt(ua.ObjectIds.String), _string_out, _string_in(ty.max_bytes, text),
                      text)
    if isinstance(ty, t.TimeType):
        if ty.family in ("DATE", "DATE_AND_TIME"):     # LDATE / LDT alike (same 64-bit ns)
            return UaType(ua.VariantType.DateTime, _dt(ua.ObjectIds.DateTime), datetime_of,
                          _datetime_in(ty.family == "DATE", ty.name), ty.name)
        if ty.family == "TIME_OF_DAY":
            return UaType(ua.VariantType.Int64, _dt(ua.ObjectIds.Int64), int, _int_in(0, NS_PER_DAY - 1, ty.name),
                          ty.name)
        return UaType(ua.VariantType.Int64, _dt(ua.ObjectIds.Int64), int, _int_in(INT64_MIN, INT64_MAX, ty.name),
                      ty.name)
    if isinstance(ty, t.EnumType):
        values = {value for _, value in ty.members}
        return UaType(ua.VariantType.Int32, None, int, _enum_in(values, ty.name), ty.qualname or ty.name)
    return None


def _dt(identifier: int) -> ua.NodeId:
    return ua.NodeId(identifier, 0)


def datetime_of(ns: int) -> datetime:
    """DT/DATE nanoseconds since 1970 as a UTC datetime (microseconds kept; OPC UA has 100 ns)."""
    return EPOCH + timedelta(microseconds=ns // 1000)


def ns_of(moment: datetime) -> int:
    if moment.tzinfo is None:
        moment = moment.replace(tzinfo=timezone.utc)   # asyncua decodes DateTime as naive UTC
    delta = moment - EPOCH
    return (delta.days * 86_400 + delta.seconds) * 1_000_000_000 + delta.microseconds * 1000


def _string_out(value: bytes) -> str:
    # Choice: bytes that are not UTF-8 (a receive buffer turned into a STRING) show as U+FFFD
    return value.decode("utf-8", "replace")


def _mismatch(variant: ua.Variant, expected: str) -> BadWrite:
    return BadWrite(ua.StatusCodes.BadTypeMismatch,
                    f"expected {expected}, got {variant.VariantType.name}")


def _scalar(variant: ua.Variant) -> None:
    if variant.is_array or isinstance(variant.Value, list):
        raise BadWrite(ua.StatusCodes.BadTypeMismatch, "expected a scalar, got an array")


def _bool_in(variant: ua.Variant) -> bool:
    _scalar(variant)
    if variant.VariantType != ua.VariantType.Boolean:
        raise _mismatch(variant, "Boolean")
    return bool(variant.Value)


def _int_in(lo: int, hi: int, name: str) -> Callable[[ua.Variant], int]:
    def convert(variant: ua.Variant) -> int:
        _scalar(variant)
        if variant.VariantType not in _INT_VARIANTS:
            raise _mismatch(variant, f"an integer for {name}")
        value = int(variant.Value)
        if not lo <= value <= hi:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, f"{value} is outside {name}'s range {lo}..{hi}")
        return value
    return convert


def _real_in(single: bool) -> Callable[[ua.Variant], float]:
    def convert(variant: ua.Variant) -> float:
        _scalar(variant)
        if variant.VariantType in _INT_VARIANTS:
            value = float(variant.Value)
        elif variant.VariantType in (ua.VariantType.Float, ua.VariantType.Double):
            value = float(variant.Value)
        else:
            raise _mismatch(variant, "Float or Double" if single else "Double")
        if single and math.isfinite(value) and abs(value) > _F32_MAX:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, f"{value!r} is outside REAL's range")
        return value
    return convert


def _string_in(max_bytes: int, name: str) -> Callable[[ua.Variant], bytes]:
    def convert(variant: ua.Variant) -> bytes:
        _scalar(variant)
        if variant.VariantType != ua.VariantType.String:
            raise _mismatch(variant, "String")
        data = (variant.Value or "").encode("utf-8")
        if b"\x00" in data:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, "a STRING cannot hold NUL characters")
        if len(data) > max_bytes:
            # Choice: refuse rather than truncate (the controller would keep a cut value silently)
            raise BadWrite(ua.StatusCodes.BadOutOfRange, f"{len(data)} bytes do not fit {name} (at most {max_bytes})")
        return data
    return convert


def _wstring_in(max_units: int, name: str) -> Callable[[ua.Variant], str]:
    """A client's String into a WSTRING: its UTF-16 code units (`stvm.numeric.utf16_units`)."""
    def convert(variant: ua.Variant) -> str:
        _scalar(variant)
        if variant.VariantType != ua.VariantType.String:
            raise _mismatch(variant, "String")
        units = utf16_units(variant.Value or "")
        if "\x00" in units:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, "a WSTRING cannot hold NUL characters")
        if len(units) > max_units:
            raise BadWrite(ua.StatusCodes.BadOutOfRange,
                           f"{len(units)} UTF-16 code units do not fit {name} (at most {max_units})")
        return units
    return convert


def _datetime_in(date_only: bool, name: str) -> Callable[[ua.Variant], int]:
    def convert(variant: ua.Variant) -> int:
        _scalar(variant)
        if variant.VariantType != ua.VariantType.DateTime or not isinstance(variant.Value, datetime):
            raise _mismatch(variant, "DateTime")
        ns = ns_of(variant.Value)
        if ns < 0:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, f"{name} starts at 1970-01-01")
        if date_only and ns % NS_PER_DAY:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, "a DATE is a midnight (UTC): no time of day")
        return ns
    return convert


def _enum_in(values: set[int], name: str) -> Callable[[ua.Variant], int]:
    def convert(variant: ua.Variant) -> int:
        _scalar(variant)
        if variant.VariantType not in _INT_VARIANTS:
            raise _mismatch(variant, f"an Int32 value of {name}")
        value = int(variant.Value)
        if value not in values:
            raise BadWrite(ua.StatusCodes.BadOutOfRange, f"{value} is not a value of {name}")
        return value
    return convert
