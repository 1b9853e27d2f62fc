"""*_TO_* conversions (W502 data type conversion instructions; sysmac.md 2 and 6)."""

from __future__ import annotations

import ctypes
import math

import pytest
from hypothesis import given, settings as hypothesis_settings, strategies as st

from stdlib_helpers import S, call, make_ctx
from stvm.runtime.values import FunctionError
from stvm.semantics.types import ELEMENTARY, IntType
from stvm.stdlib.conversions import conversion_functions, conversion_pairs
from stvm.stdlib.registry import NATIVE_FUNCTIONS
from stvm.stdlib.typeops import to_real32

DAY = 86_400 * S


@pytest.mark.parametrize(("name", "value", "result"), [
    # sysmac.md 6: BYTE_TO_STRING hexadecimal, upper case, no leading zero
    ("BYTE_TO_STRING", 0x0A, b"A"),
    ("BYTE_TO_STRING", 0x00, b"0"),
    ("BYTE_TO_STRING", 0x4F, b"4F"),
    ("BYTE_TO_STRING", 0x05, b"5"),
    ("BYTE_TO_STRING", 0xFF, b"FF"),
    ("WORD_TO_STRING", 0x00FF, b"FF"),
    ("LWORD_TO_STRING", 2**64 - 1, b"F" * 16),
    ("UINT_TO_STRING", 0, b"0"),
    ("UINT_TO_STRING", 65535, b"65535"),
    ("INT_TO_STRING", -5, b"-5"),
    ("INT_TO_STRING", 7, b"7"),
    ("LINT_TO_STRING", -2**63, b"-9223372036854775808"),
    ("BOOL_TO_STRING", True, b"TRUE"),
    ("REAL_TO_STRING", to_real32(-123.45), b"-1.234500e+02"),
    ("REAL_TO_STRING", 0.0, b"0.000000e+00"),
    ("LREAL_TO_STRING", 1.5, b"1.50000000000000e+00"),
    ("REAL_TO_STRING", math.inf, b"inf"),
    ("REAL_TO_STRING", math.nan, b"nan"),
    ("TIME_TO_STRING", 0, b"T#0s"),
    ("TIME_TO_STRING", 5_400 * S, b"T#1h30m"),
    ("TIME_TO_STRING", -250_000_000, b"T#-250ms"),
    ("TIME_TO_STRING", DAY + 1, b"T#1d1ns"),
    ("DATE_TO_STRING", 0, b"D#1970-01-01"),
    ("TOD_TO_STRING", 3_723 * S + 500_000_000, b"TOD#01:02:03.5"),
    ("TIME_OF_DAY_TO_STRING", 0, b"TOD#00:00:00"),
    ("DT_TO_STRING", 1_700_000_000 * S, b"DT#2023-11-14-22:13:20"),
    ("DATE_AND_TIME_TO_STRING", 0, b"DT#1970-01-01-00:00:00"),
])
def test_to_string(name, value, result):
    assert call(name, make_ctx(dialect="sysmac"), value) == result


@pytest.mark.parametrize(("style", "value", "result"), [
    ("hex_pad2", 0x0A, b"0A"), ("hex_pad2", 0x00, b"00"), ("decimal", 0x0A, b"10"), ("hex_nopad", 0x0A, b"A"),
])
def test_byte_to_string_formats(style, value, result):
    assert call("BYTE_TO_STRING", make_ctx(byte_to_string_format=style), value) == result


def test_word_hex_pad2_pads_every_byte():
    assert call("WORD_TO_STRING", make_ctx(byte_to_string_format="hex_pad2"), 0xFF) == b"00FF"


@pytest.mark.parametrize(("text", "result"), [
    (b"123", 123), (b"  00123", 123), (b"1_000", 1000), (b"-0", 0), (b"+5", 5),
    (b"000000000065535", 65535), (b"0", 0),
])
def test_string_to_uint(text, result):
    assert call("STRING_TO_UINT", make_ctx(), text) == result


@given(st.text(alphabet="0123456789", min_size=1, max_size=8))
def test_string_to_uint_plain_digits(digits):
    """Digits only (the fast path of text_to_integer): the number, or out of range."""
    text = digits.encode()
    if int(digits) <= 65535:
        assert call("STRING_TO_UINT", make_ctx(), text) == int(digits)
        assert call("STRING_TO_UINT", make_ctx(), b" " + text) == int(digits)   # the pattern path
    else:
        with pytest.raises(FunctionError, match="outside"):
            call("STRING_TO_UINT", make_ctx(), text)


@pytest.mark.parametrize(("name", "digits"), [("STRING_TO_SINT", "127"), ("STRING_TO_SINT", "128"),
                                             ("STRING_TO_USINT", "255"), ("STRING_TO_USINT", "0256"),
                                             ("STRING_TO_DINT", "2147483648"), ("STRING_TO_ULINT", "0")])
def test_string_to_integer_plain_digits_each_type(name, digits):
    """The converters' digits-only path gives what the full reading gives, in and out of range."""
    padded = b"  " + digits.encode()       # blanks: never the digits-only path
    try:
        expected = call(name, make_ctx(), padded)
    except FunctionError as error:
        with pytest.raises(FunctionError, match="outside"):
            call(name, make_ctx(), digits.encode())
        assert "outside" in str(error)
    else:
        assert call(name, make_ctx(), digits.encode()) == expected == int(digits)


@pytest.mark.parametrize("text", [b"", b" ", b"abc", b"12a", b"12 ", b"-1", b"65536", b"1.5",
                                  b"_", b"- 1", b"16#10"])
def test_string_to_uint_errors(text):
    with pytest.raises(FunctionError):
        call("STRING_TO_UINT", make_ctx(), text)


def test_string_to_uint_settings():
    assert call("STRING_TO_UINT", make_ctx(stou_trailing="ignore_blanks"), b"12  ") == 12
    with pytest.raises(FunctionError):
        call("STRING_TO_UINT", make_ctx(stou_trailing="ignore_blanks"), b"12 x")
    with pytest.raises(FunctionError):
        call("STRING_TO_UINT", make_ctx(stou_plus="error"), b"+5")


@pytest.mark.parametrize(("name", "text", "result"), [
    ("STRING_TO_INT", b"-32768", -32768),
    ("STRING_TO_SINT", b"-128", -128),
    ("STRING_TO_ULINT", b"18446744073709551615", 2**64 - 1),
    ("STRING_TO_BYTE", b"FF", 255),
    ("STRING_TO_BYTE", b"16#1f", 31),
    ("STRING_TO_WORD", b"00FF", 255),
    ("STRING_TO_BOOL", b"true", True),
    ("STRING_TO_BOOL", b" 0", False),
    ("STRING_TO_REAL", b" - 12.5e1", -125.0),
    ("STRING_TO_REAL", b"3", 3.0),
    ("STRING_TO_REAL", b"0.1", to_real32(0.1)),
    ("STRING_TO_LREAL", b"0.1", 0.1),
    ("STRING_TO_TIME", b"T#1h30m", 5_400 * S),
    ("STRING_TO_TIME", b"1.5s", 1_500_000_000),
    ("STRING_TO_TIME", b"TIME#-250ms", -250_000_000),
    ("STRING_TO_TIME", b"t#1m_30s", 90 * S),
    ("STRING_TO_DATE", b"D#2106-02-06", 49_709 * DAY),
    ("STRING_TO_TOD", b"TOD#01:02:03.5", 3_723 * S + 500_000_000),
    ("STRING_TO_DT", b"DT#2023-11-14-22:13:20", 1_700_000_000 * S),
    ("STRING_TO_DATE_AND_TIME", b"1970-01-01-00:00:01", S),
])
def test_from_string(name, text, result):
    assert call(name, make_ctx(dialect="sysmac"), text) == result


@pytest.mark.parametrize(("name", "text"), [
    ("STRING_TO_INT", b"-32769"), ("STRING_TO_SINT", b"128"), ("STRING_TO_BYTE", b"100"),
    ("STRING_TO_BYTE", b"G"), ("STRING_TO_BOOL", b"yes"), ("STRING_TO_REAL", b".5"),
    ("STRING_TO_REAL", b"1e40"), ("STRING_TO_REAL", b"1.5x"), ("STRING_TO_TIME", b"5"),
    ("STRING_TO_TIME", b"T#5x"), ("STRING_TO_DATE", b"2106-02-07"), ("STRING_TO_DATE", b"1969-12-31"),
    ("STRING_TO_DATE", b"2023-02-30"), ("STRING_TO_TOD", b"24:00:00"), ("STRING_TO_DT", b"2023-01-01"),
])
def test_from_string_errors(name, text):
    with pytest.raises(FunctionError):
        call(name, make_ctx(dialect="sysmac"), text)


@pytest.mark.parametrize(("name", "value", "result"), [
    # W502 2-248/2-250: nearest, ties to even; bit strings take the two's complement bits
    ("REAL_TO_INT", 2.5, 2), ("REAL_TO_INT", 1.5, 2), ("REAL_TO_INT", -2.5, -2),
    ("REAL_TO_INT", -1.6, -2), ("REAL_TO_INT", 1.49, 1), ("REAL_TO_DINT", 3.5, 4),
    ("REAL_TO_WORD", -1.6, 0xFFFE), ("REAL_TO_WORD", 3.5, 4), ("LREAL_TO_UINT", 1.6, 2),
    ("REAL_TO_INT", 40000.0, 40000 - 65536),   # out of range: wraps (W502: "illegal value")
    ("REAL_TO_INT", math.nan, 0), ("REAL_TO_DINT", -math.inf, 0),
    ("INT_TO_UINT", -1, 65535), ("DINT_TO_INT", 70000, 4464), ("UDINT_TO_DINT", 2**32 - 1, -1),
    ("SINT_TO_LWORD", -1, 2**64 - 1), ("BYTE_TO_SINT", 0xFF, -1),
    ("UINT_TO_REAL", 65535, 65535.0), ("DINT_TO_REAL", 16_777_217, 16_777_216.0),
    ("LREAL_TO_REAL", 0.1, to_real32(0.1)), ("LREAL_TO_REAL", 1e300, math.inf),
    ("REAL_TO_LREAL", to_real32(0.1), to_real32(0.1)),
    ("BOOL_TO_INT", True, 1), ("BOOL_TO_REAL", False, 0.0), ("INT_TO_BOOL", 0, False),
    ("INT_TO_BOOL", -5, True), ("REAL_TO_BOOL", 0.0, False), ("BYTE_TO_BOOL", 2, True),
    ("DT_TO_DATE", 3 * DAY + 5 * S, 3 * DAY), ("DT_TO_TOD", 3 * DAY + 5 * S, 5 * S),
    ("DATE_AND_TIME_TO_TIME_OF_DAY", DAY + 1, 1), ("DATE_AND_TIME_TO_DATE", DAY + 1, DAY),
])
def test_numeric_conversion(name, value, result):
    assert call(name, make_ctx(), value) == result


INT_TYPES = [name for name, t in ELEMENTARY.items() if isinstance(t, IntType)]
C_TYPES = {8: (ctypes.c_int8, ctypes.c_uint8), 16: (ctypes.c_int16, ctypes.c_uint16),
           32: (ctypes.c_int32, ctypes.c_uint32), 64: (ctypes.c_int64, ctypes.c_uint64)}


@hypothesis_settings(max_examples=300, deadline=None)
@given(source=st.sampled_from(INT_TYPES), target=st.sampled_from(INT_TYPES), data=st.data())
def test_integer_conversions_match_c(source, target, data):
    if source == target:
        return
    source_type, target_type = ELEMENTARY[source], ELEMENTARY[target]
    value = data.draw(st.integers(source_type.lo, source_type.hi))
    signed, unsigned = C_TYPES[target_type.bits]
    expected = (signed if target_type.signed else unsigned)(value).value
    assert call(f"{source}_TO_{target}", make_ctx(), value) == expected


def test_every_declared_conversion_is_registered():
    for name, _, _ in conversion_functions():
        assert name in NATIVE_FUNCTIONS, name
    # numeric pairs, X <-> STRING, DT -> DATE/TOD and LDT -> LDATE/LTOD, each time type <-> its
    # long form, the 8 time types <-> 14 numbers (not BOOL), STRING <-> WSTRING and X <-> WSTRING
    assert len(conversion_pairs()) == 15 * 14 + 23 * 2 + 4 + 4 * 2 + 8 * 14 * 2 + 2 + 23 * 2


def test_time_text_round_trip():
    ctx = make_ctx()
    for value in [0, 1, 999, 86_399 * S + 123_456_789, -(DAY + 7)]:
        assert call("STRING_TO_TIME", ctx, call("TIME_TO_STRING", ctx, value)) == value
    for value in [0, 1_700_000_000 * S + 5, 49_710 * DAY - 1]:
        assert call("STRING_TO_DT", ctx, call("DT_TO_STRING", ctx, value)) == value
