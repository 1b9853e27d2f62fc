"""Omron instructions (sysmac.md 6): ToAryByte, AryToString, RealToFormatString, time functions."""

from __future__ import annotations

import math

import pytest

from stdlib_helpers import MS, S, call, make_ctx
from stvm.runtime.values import ArrayRef, FunctionError
from stvm.semantics.types import (
    ArrayType, BOOL, BYTE, DINT, INT, LREAL, REAL, SINT, TIME, UINT, string_type, EnumType,
)
from stvm.stdlib.typeops import to_real32

LOW_HIGH, HIGH_LOW = 0, 1
STRING50 = string_type(50)


def to_ary_byte(ctx, value, value_type, order, size=12, start=0, fill=0xEE):
    data = [fill] * size
    count = call("ToAryByte", ctx, value, order, ArrayRef(data, start), arg_types=(value_type, None, None))
    return count, data


def test_string_text_nul_low_high():
    # the thesis case: the text and its NUL (sysmac.md 8 #1: the checksum loop reads the NUL)
    count, data = to_ary_byte(make_ctx(), b"ABC", STRING50, LOW_HIGH, size=6)
    assert count == 4
    assert data == [0x41, 0x42, 0x43, 0x00, 0xEE, 0xEE]


def test_string_models():
    count, data = to_ary_byte(make_ctx(toarybyte_string_model="text"), b"ABC", STRING50, LOW_HIGH, size=5)
    assert (count, data) == (3, [0x41, 0x42, 0x43, 0xEE, 0xEE])
    count, data = to_ary_byte(make_ctx(toarybyte_string_model="image"), b"AB", string_type(4), LOW_HIGH, size=5)
    assert (count, data) == (4, [0x41, 0x42, 0x00, 0x00, 0xEE])


def test_string_high_low_swaps_pairs_and_pads():
    count, data = to_ary_byte(make_ctx(), b"AB", STRING50, HIGH_LOW, size=6)
    assert (count, data[:5]) == (4, [0x42, 0x41, 0x00, 0x00, 0xEE])


def test_empty_string_is_just_the_nul():
    assert to_ary_byte(make_ctx(), b"", STRING50, LOW_HIGH, size=2) == (1, [0x00, 0xEE])


def test_one_byte_array_orders():
    sint3 = ArrayType("ARRAY[0..2] OF SINT", SINT, ((0, 2),))
    count, data = to_ary_byte(make_ctx(), [1, 2, -1], sint3, LOW_HIGH, size=5)
    assert (count, data) == (3, [1, 2, 0xFF, 0xEE, 0xEE])
    count, data = to_ary_byte(make_ctx(), [1, 2, -1], sint3, HIGH_LOW, size=5)
    assert (count, data) == (4, [2, 1, 0x00, 0xFF, 0xEE])  # SINT[3] -> 4 bytes


@pytest.mark.parametrize(("value", "value_type", "order", "settings", "expected"), [
    (0x1234, UINT, LOW_HIGH, {}, [0x34, 0x12]),
    (0x1234, UINT, HIGH_LOW, {}, [0x12, 0x34]),
    (-2, INT, LOW_HIGH, {}, [0xFE, 0xFF]),
    (0x11223344, DINT, HIGH_LOW, {}, [0x11, 0x22, 0x33, 0x44]),
    (0x11223344, DINT, HIGH_LOW, {"toarybyte_wide_order": "word_swapped"}, [0x33, 0x44, 0x11, 0x22]),
    (1.0, REAL, LOW_HIGH, {}, [0x00, 0x00, 0x80, 0x3F]),
    (1.0, LREAL, HIGH_LOW, {}, [0x3F, 0xF0, 0, 0, 0, 0, 0, 0]),
    (True, BOOL, LOW_HIGH, {}, [0x01]),
    (0xAB, BYTE, HIGH_LOW, {}, [0x00, 0xAB]),  # one byte padded and swapped
    (1_000_000, TIME, LOW_HIGH, {}, [0x40, 0x42, 0x0F, 0, 0, 0, 0, 0]),
    (2, EnumType("E", "E", (("A", 0), ("B", 2))), LOW_HIGH, {}, [2, 0, 0, 0]),
])
def test_elementary_values(value, value_type, order, settings, expected):
    count, data = to_ary_byte(make_ctx(**settings), value, value_type, order)
    assert count == len(expected)
    assert data[:count] == expected and data[count:] == [0xEE] * (12 - count)


def test_writes_from_the_element_given():
    count, data = to_ary_byte(make_ctx(), b"AB", STRING50, LOW_HIGH, size=6, start=2)
    assert (count, data) == (3, [0xEE, 0xEE, 0x41, 0x42, 0x00, 0xEE])


def test_too_few_elements_writes_nothing():
    with pytest.raises(FunctionError):
        to_ary_byte(make_ctx(), b"ABCDE", STRING50, LOW_HIGH, size=6, start=2)


def test_aryto_string():
    ctx = make_ctx()
    data = list(b"HELLO\x00OLD") + [0] * 3
    assert call("AryToString", ctx, ArrayRef(data, 0), 5) == b"HELLO"
    assert call("AryToString", ctx, ArrayRef(data, 0), 9) == b"HELLO"     # cut at the NUL
    assert call("AryToString", ctx, ArrayRef(data, 1), 3) == b"ELL"
    assert call("AryToString", ctx, ArrayRef(data, 0), 0) == b""
    assert call("AryToString", ctx, [0xC3, 0x28, 0xFF], 3) == b"\xc3\x28\xff"  # no UTF-8 check


def test_aryto_string_oversize():
    data = [0x41] * 2000
    with pytest.raises(FunctionError):
        call("AryToString", make_ctx(), ArrayRef(data, 0), 1986)
    with pytest.raises(FunctionError):
        call("AryToString", make_ctx(), ArrayRef(data, 1990), 11)
    assert call("AryToString", make_ctx(arytostring_oversize="truncate"), ArrayRef(data, 0), 1986) == b"A" * 1985
    assert call("AryToString", make_ctx(arytostring_oversize="truncate"), ArrayRef(data, 1990), 20) == b"A" * 10


def rtfs(value, exponent=False, sign=True, min_len=1, dec_place=0, **settings):
    return call("RealToFormatString", make_ctx(**settings), to_real32(value), exponent, sign, min_len, dec_place)


@pytest.mark.parametrize(("value", "half_away", "half_even"), [
    # the spec's examples with the thesis arguments (FALSE, TRUE, 1, 0)
    (123.4, b"+123", b"+123"), (123.6, b"+124", b"+124"), (-45.6, b"-46", b"-46"),
    (0.0, b"+0", b"+0"), (0.3, b"+0", b"+0"), (-0.3, b"-0", b"-0"),
    (2.5, b"+3", b"+2"), (12.5, b"+13", b"+12"), (-2.5, b"-3", b"-2"), (0.5, b"+1", b"+0"),
])
def test_real_to_format_string_thesis_arguments(value, half_away, half_even):
    assert rtfs(value) == half_away
    assert rtfs(value, rtfs_rounding="half_even") == half_even


def test_real_to_format_string_decimals_use_the_exact_binary_value():
    assert rtfs(123.45, dec_place=1) == b"+123.4"   # 123.45 is 123.4499969... as REAL
    assert rtfs(0.15, dec_place=1) == b"+0.2"       # 0.15 is 0.150000006...
    assert rtfs(1.0, sign=False, dec_place=3) == b"1.000"


def test_real_to_format_string_negative_zero_setting():
    assert rtfs(-0.3, rtfs_negative_zero="plus") == b"+0"
    assert rtfs(-0.3, sign=False, rtfs_negative_zero="plus") == b"0"
    assert rtfs(-0.0) == b"+0"


def test_real_to_format_string_padding_and_exponent():
    assert rtfs(5.0, sign=False, min_len=4) == b"   5"
    assert rtfs(-5.0, min_len=4) == b"  -5"
    assert rtfs(123.456, exponent=True, sign=False, dec_place=2) == b"1.23e+02"
    assert rtfs(0.000123, exponent=True, dec_place=1) == b"+1.2e-04"
    assert rtfs(9.9996, exponent=True, sign=False, dec_place=3) == b"1.000e+01"
    assert rtfs(0.0, exponent=True, sign=False, dec_place=2) == b"0.00e+00"
    assert rtfs(5e9, exponent=True, sign=False, dec_place=0) == b"5e+09"


def test_real_to_format_string_specials_and_limits():
    # printf model: the sign flag applies to nan/inf too
    assert call("RealToFormatString", make_ctx(), math.nan, False, True, 1, 0) == b"+nan"
    assert call("RealToFormatString", make_ctx(), math.nan, False, False, 1, 0) == b"nan"
    assert call("RealToFormatString", make_ctx(), -math.inf, False, True, 5, 0) == b" -inf"
    assert call("RealToFormatString", make_ctx(), math.inf, False, True, 1, 0) == b"+inf"
    assert rtfs(1.0, min_len=24, dec_place=7) == b"+1.0000000".rjust(24)
    with pytest.raises(FunctionError):
        rtfs(1.0, min_len=25)
    with pytest.raises(FunctionError):
        rtfs(1.0, dec_place=8)
    assert rtfs(1.0, dec_place=8, rtfs_max_decplace=9) == b"+1.00000000"
    assert rtfs(1.0, min_len=25, rtfs_max_minlen=30) == b"+1".rjust(25)
    with pytest.raises(FunctionError):
        rtfs(1.0, min_len=11, rtfs_max_minlen=10)


def test_get_time_is_start_dt_plus_virtual_time_at_1_ms():
    ctx = make_ctx()
    ctx.start_dt_ns = 1_700_000_000 * S
    ctx.now_ns = 1_500 * MS + 700_000
    assert call("GetTime", ctx) == 1_700_000_000 * S + 1_500 * MS
    assert call("GetTime", make_ctx(gettime_resolution_ns=1)) == 0
    fine = make_ctx(gettime_resolution_ns=1)
    fine.now_ns = 123
    assert call("GetTime", fine) == 123


def test_get_time_real_time_reads_the_host_clock():
    ctx = make_ctx()
    ctx.realtime = True
    assert call("GetTime", ctx) > 1_600_000_000 * S


def test_sec_to_dt_and_back():
    ctx = make_ctx()
    assert call("SecToDt", ctx, 0) == 0                       # thesis line 1473
    assert call("SecToDt", ctx, 4_294_943_999) == 4_294_943_999 * S
    for bad in (-1, 4_294_944_000):
        with pytest.raises(FunctionError):
            call("SecToDt", ctx, bad)
    clamp = make_ctx(sectodt_range="clamp")
    assert call("SecToDt", clamp, -5) == 0
    assert call("SecToDt", clamp, 2**40) == 4_294_943_999 * S
    assert call("DtToSec", ctx, 5 * S + 999_999_999) == 5


def test_nanosec_time_conversions_keep_the_count():
    ctx = make_ctx()
    # sysmac.md 8 #7: UINT*DINT literal wraps to a negative LINT; NanoSecToTime keeps it
    assert call("NanoSecToTime", ctx, -1_294_967_296) == -1_294_967_296
    assert call("TimeToNanoSec", ctx, 1_000_000_000) == 1_000_000_000
