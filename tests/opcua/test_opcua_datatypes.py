"""IEC types as OPC UA built-in types: values out, and client writes checked in."""

from datetime import datetime, timezone

import pytest
from asyncua import ua

from stvm.opcua.datatypes import BadWrite, datetime_of, ns_of, ua_type
from stvm.semantics import types as t

V = ua.VariantType


def ty(name):
    return t.StringType("STRING", 10) if name == "STRING[10]" else t.ELEMENTARY[name]


@pytest.mark.parametrize("name, variant, datatype", [
    ("BOOL", V.Boolean, ua.ObjectIds.Boolean), ("SINT", V.SByte, ua.ObjectIds.SByte),
    ("INT", V.Int16, ua.ObjectIds.Int16), ("DINT", V.Int32, ua.ObjectIds.Int32), ("LINT", V.Int64, ua.ObjectIds.Int64),
    ("USINT", V.Byte, ua.ObjectIds.Byte), ("UINT", V.UInt16, ua.ObjectIds.UInt16),
    ("UDINT", V.UInt32, ua.ObjectIds.UInt32), ("ULINT", V.UInt64, ua.ObjectIds.UInt64),
    ("BYTE", V.Byte, ua.ObjectIds.Byte), ("WORD", V.UInt16, ua.ObjectIds.UInt16),
    ("DWORD", V.UInt32, ua.ObjectIds.UInt32), ("LWORD", V.UInt64, ua.ObjectIds.UInt64),
    ("REAL", V.Float, ua.ObjectIds.Float), ("LREAL", V.Double, ua.ObjectIds.Double),
    ("STRING[10]", V.String, ua.ObjectIds.String), ("TIME", V.Int64, ua.ObjectIds.Int64),
    ("TIME_OF_DAY", V.Int64, ua.ObjectIds.Int64), ("DATE", V.DateTime, ua.ObjectIds.DateTime),
    ("DATE_AND_TIME", V.DateTime, ua.ObjectIds.DateTime),
])
def test_mapping_table(name, variant, datatype):
    mapping = ua_type(ty(name))
    assert mapping.variant == variant and mapping.datatype == ua.NodeId(datatype)


def test_values_out():
    assert ua_type(ty("STRING[10]")).to_ua(b"caf\xc3\xa9") == "café"
    assert ua_type(ty("STRING[10]")).to_ua(b"\xff") == "\ufffd"
    assert ua_type(t.TIME).to_ua(1_500_000_000) == 1_500_000_000                   # T#1s500ms in ns
    assert ua_type(t.DT).to_ua(86_400_000_000_000 + 1_234_567) == datetime(1970, 1, 2, 0, 0, 0, 1234,
                                                                           tzinfo=timezone.utc)


def test_datetime_round_trip():
    moment = datetime(2021, 6, 1, 12, 30, 5, 250000, tzinfo=timezone.utc)
    assert datetime_of(ns_of(moment)) == moment
    assert ns_of(moment.replace(tzinfo=None)) == ns_of(moment)     # naive = UTC, as asyncua decodes


@pytest.mark.parametrize("name, variant, value", [
    ("INT", ua.Variant(-5, V.Int64), -5), ("UINT", ua.Variant(65535, V.Int32), 65535),
    ("REAL", ua.Variant(2, V.Int16), 2.0), ("REAL", ua.Variant(1.5, V.Double), 1.5),
    ("BOOL", ua.Variant(True, V.Boolean), True), ("STRING[10]", ua.Variant("abc", V.String), b"abc"),
    ("TIME", ua.Variant(-10, V.Int64), -10), ("TIME_OF_DAY", ua.Variant(3600 * 10**9, V.Int64), 3600 * 10**9),
    ("DATE", ua.Variant(datetime(2020, 1, 2), V.DateTime), ns_of(datetime(2020, 1, 2))),
])
def test_good_writes(name, variant, value):
    assert ua_type(ty(name)).from_ua(variant) == value


@pytest.mark.parametrize("name, variant, status", [
    ("INT", ua.Variant(40000, V.Int32), ua.StatusCodes.BadOutOfRange),
    ("USINT", ua.Variant(-1, V.SByte), ua.StatusCodes.BadOutOfRange),
    ("INT", ua.Variant(1.0, V.Double), ua.StatusCodes.BadTypeMismatch),
    ("INT", ua.Variant(True, V.Boolean), ua.StatusCodes.BadTypeMismatch),
    ("BOOL", ua.Variant(1, V.Int32), ua.StatusCodes.BadTypeMismatch),
    ("REAL", ua.Variant(1e300, V.Double), ua.StatusCodes.BadOutOfRange),
    ("REAL", ua.Variant("1", V.String), ua.StatusCodes.BadTypeMismatch),
    ("STRING[10]", ua.Variant("0123456789", V.String), ua.StatusCodes.BadOutOfRange),   # 10 > 9 bytes
    ("STRING[10]", ua.Variant("a\x00b", V.String), ua.StatusCodes.BadOutOfRange),
    ("STRING[10]", ua.Variant(5, V.Int32), ua.StatusCodes.BadTypeMismatch),
    ("TIME_OF_DAY", ua.Variant(86_400 * 10**9, V.Int64), ua.StatusCodes.BadOutOfRange),
    ("DATE", ua.Variant(datetime(2020, 1, 2, 1), V.DateTime), ua.StatusCodes.BadOutOfRange),
    ("DATE_AND_TIME", ua.Variant(datetime(1969, 12, 31), V.DateTime), ua.StatusCodes.BadOutOfRange),
    ("DATE_AND_TIME", ua.Variant(5, V.Int64), ua.StatusCodes.BadTypeMismatch),
    ("INT", ua.Variant([1, 2], V.Int16), ua.StatusCodes.BadTypeMismatch),
])
def test_bad_writes(name, variant, status):
    with pytest.raises(BadWrite) as bad:
        ua_type(ty(name)).from_ua(variant)
    assert bad.value.status == status


def test_enum_values():
    enum = t.EnumType("Color", "Color", (("Red", 0), ("Blue", 5)))
    mapping = ua_type(enum)
    assert mapping.variant == V.Int32 and mapping.datatype is None
    assert mapping.from_ua(ua.Variant(5, V.Int32)) == 5
    with pytest.raises(BadWrite) as bad:
        mapping.from_ua(ua.Variant(1, V.Int32))
    assert bad.value.status == ua.StatusCodes.BadOutOfRange
    assert ua_type(t.StructType("S")) is None
