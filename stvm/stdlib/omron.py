"""Omron Sysmac instructions the thesis uses (sysmac.md 6): ToAryByte, AryToString,
RealToFormatString, GetTime, SecToDt, DtToSec, NanoSecToTime, TimeToNanoSec.

Functions finish within the call and keep no state; a failure is an instruction error
(`FunctionError`: ENO FALSE, Out unchanged, sysmac.md 1). BYTE_TO_STRING, UINT_TO_STRING,
STRING_TO_UINT and the other conversions are in `conversions.py`.
"""

from __future__ import annotations

import datetime as _dt
import math
import struct
from decimal import ROUND_HALF_EVEN, ROUND_HALF_UP, Context, Decimal, localcontext

from stvm.runtime.values import ArrayRef, FunctionError
from stvm.semantics.types import (
    ArrayType, BoolType, EnumType, IntType, RealType, StringType, TimeType, Type,
)
from stvm.stdlib.registry import native_function
from stvm.stdlib.typeops import STRING_MAX_BYTES
from stvm.settings import (
    ArytostringOversize, RtfsNegativeZero, RtfsRounding, SectodtRange, ToarybyteStringModel, ToarybyteWideOrder,
)

NS_PER_S = 1_000_000_000
SECTODT_MAX_S = 4_294_943_999  # 2106-02-06-23:59:59 (sysmac.md 6)


def as_array_ref(value) -> ArrayRef:
    """An ARRAY[*] argument as an ArrayRef (the VM passes ArrayRef; tests may pass a list)."""
    return value if isinstance(value, ArrayRef) else ArrayRef(value, 0)


# --- ToAryByte --------------------------------------------------------------------------------

def _element_bytes(value, element_type: Type) -> bytes:
    """Little-endian storage image of one elementary value."""
    if isinstance(element_type, BoolType):
        return b"\x01" if value else b"\x00"
    if isinstance(element_type, IntType):
        return (value & ((1 << element_type.bits) - 1)).to_bytes(element_type.bits // 8, "little")
    if isinstance(element_type, RealType):
        return struct.pack("<f" if element_type.bits == 32 else "<d", value)
    if isinstance(element_type, TimeType):
        return (value & ((1 << 64) - 1)).to_bytes(8, "little")
    if isinstance(element_type, EnumType):
        # Choice: an enum is stored as its base type, DINT when it has none
        if isinstance(element_type.base, IntType):
            return _element_bytes(value, element_type.base)
        return (value & 0xFFFF_FFFF).to_bytes(4, "little")
    raise FunctionError(f"ToAryByte cannot convert a {element_type}")


def _string_bytes(ctx, text: bytes, string_type: Type) -> bytes:
    """A STRING's bytes per `toarybyte_string_model` (sysmac.md 6)."""
    model = ctx.settings.toarybyte_string_model
    if model is ToarybyteStringModel.TEXT:
        return text
    if model is ToarybyteStringModel.IMAGE:
        size = string_type.size if isinstance(string_type, StringType) else len(text) + 1
        return text + bytes(size - len(text))
    return text + b"\x00"  # text_nul: the text and its terminating NUL


def _flatten(value) -> list:
    if isinstance(value, ArrayRef):
        value = value.data[value.start:]
    flat: list = []
    for item in value:
        flat.extend(_flatten(item) if isinstance(item, (list, ArrayRef)) else [item])
    return flat


def _high_low(ctx, chunk: bytes) -> bytes:
    """One value in `_HIGH_LOW` order: big-endian; 4/8-byte values per `toarybyte_wide_order`."""
    if ctx.settings.toarybyte_wide_order is ToarybyteWideOrder.WORD_SWAPPED and len(chunk) > 2:
        # Choice: 16-bit words in little-endian order, each word big-endian (33 44 11 22)
        return b"".join(chunk[i:i + 2][::-1] for i in range(0, len(chunk), 2))
    return chunk[::-1]


def _swap_pairs(data: bytes) -> bytes:
    """One-byte data in `_HIGH_LOW` order: swap each pair, an odd count padded with 16#00."""
    if len(data) % 2:
        data += b"\x00"
    swapped = bytearray(data)
    swapped[0::2], swapped[1::2] = data[1::2], data[0::2]
    return bytes(swapped)


@native_function("ToAryByte", typed=True)
def to_ary_byte(ctx, arg_types, value, order, ary_out) -> int:
    source_type = arg_types[0]
    if isinstance(source_type, ArrayType):
        element_type, elements = source_type.element, _flatten(value)
    else:
        element_type, elements = source_type, [value]
    if isinstance(element_type, StringType):
        chunks = [_string_bytes(ctx, text, element_type) for text in elements]
        one_byte_data = True
    else:
        chunks = [_element_bytes(item, element_type) for item in elements]
        one_byte_data = all(len(chunk) == 1 for chunk in chunks)
    high_low = order == ctx.settings.byte_order_values.get("_HIGH_LOW", 1)
    if not high_low:
        data = b"".join(chunks)
    elif one_byte_data:
        data = _swap_pairs(b"".join(chunks))
    else:
        data = b"".join(_high_low(ctx, chunk) for chunk in chunks)
    target = as_array_ref(ary_out)
    if len(data) > len(target):
        # sysmac.md 6: too few elements left -> nothing written, instruction error
        raise FunctionError(f"ToAryByte: {len(data)} bytes do not fit in the {len(target)} "
                            "elements passed")
    target.write(data)
    return len(data)


# --- AryToString -------------------------------------------------------------------------------

@native_function("AryToString")
def ary_to_string(ctx, ary_in, size: int) -> bytes:
    source = as_array_ref(ary_in)
    limit = min(STRING_MAX_BYTES, len(source))
    if size > limit:
        if ctx.settings.arytostring_oversize is not ArytostringOversize.TRUNCATE:
            raise FunctionError(f"AryToString: Size {size} exceeds "
                                f"{'1985 bytes' if size > STRING_MAX_BYTES else f'the {len(source)} elements passed'}")
        size = limit
    data = bytes(source.read(size))
    # sysmac.md 6: cut at the first 16#00; no UTF-8 check
    return data.split(b"\x00", 1)[0]


# --- RealToFormatString ------------------------------------------------------------------------

_ROUNDING = {RtfsRounding.HALF_AWAY: ROUND_HALF_UP, RtfsRounding.HALF_EVEN: ROUND_HALF_EVEN}  # ROUND_HALF_UP is away from 0


def format_real(ctx, value: float, exponent: bool, sign: bool, min_len: int, dec_place: int) -> bytes:
    """The printf model of sysmac.md 6: the exact binary value rounded to DecPlace decimals."""
    settings = ctx.settings
    if min_len > settings.rtfs_max_minlen or dec_place > settings.rtfs_max_decplace:
        raise FunctionError(f"RealToFormatString: MinLen {min_len} / DecPlace {dec_place} out of "
                            f"range (≤ {settings.rtfs_max_minlen} / ≤ {settings.rtfs_max_decplace})")
    rounding = _ROUNDING[settings.rtfs_rounding]
    if math.isnan(value):
        body, negative = "nan", False
    elif math.isinf(value):
        body, negative = "inf", value < 0
    else:
        with localcontext(_EXACT):
            body, negative = _format_finite(settings, value, exponent, dec_place, rounding)
    prefix = "-" if negative else "+" if sign else ""
    return f"{prefix}{body}".rjust(min_len).encode()


# Enough digits that no step rounds before the final quantize: a double's exact decimal expansion
# has at most 767 significant digits.
_EXACT = Context(prec=2000)


def _format_finite(settings, value: float, exponent: bool, dec_place: int,
                   rounding: str) -> tuple[str, bool]:
    """(digits without sign, whether a '-' is shown) for a finite value."""
    exact = Decimal(value)  # exact: 123.45 as REAL is 123.4499969482421875
    quantum = Decimal(1).scaleb(-dec_place)
    if exponent:
        power = exact.adjusted() if exact else 0
        mantissa = exact.scaleb(-power).quantize(quantum, rounding=rounding)
        if abs(mantissa) >= 10:  # 9.99…5 rounded up to 10: one more power of ten
            power += 1
            mantissa = exact.scaleb(-power).quantize(quantum, rounding=rounding)
        body = f"{abs(mantissa):f}e{'-' if power < 0 else '+'}{abs(power):02d}"
        rounded_zero = mantissa == 0
    else:
        rounded = exact.quantize(quantum, rounding=rounding)
        body = f"{abs(rounded):f}"
        rounded_zero = rounded == 0
    negative = value < 0
    if negative and rounded_zero and settings.rtfs_negative_zero is RtfsNegativeZero.PLUS:
        negative = False  # '-0' only under the default `rtfs_negative_zero = minus`
    return body, negative


@native_function("RealToFormatString")
def real_to_format_string(ctx, value: float, exponent: bool, sign: bool, min_len: int,
                          dec_place: int) -> bytes:
    return format_real(ctx, value, exponent, sign, min_len, dec_place)


# --- time -------------------------------------------------------------------------------------

_EPOCH = _dt.datetime(1970, 1, 1)


@native_function("GetTime")
def get_time(ctx) -> int:
    """The VM clock as DT (sysmac.md 6): start DT + virtual time; host local time in real time."""
    if ctx.realtime:
        now = _dt.datetime.now()  # local wall time, as the controller's clock shows it
        delta = now - _EPOCH
        ns = (delta.days * 86_400 + delta.seconds) * NS_PER_S + delta.microseconds * 1_000
    else:
        ns = ctx.start_dt_ns + ctx.now_ns
    resolution = ctx.settings.gettime_resolution_ns
    return ns - ns % resolution


@native_function("SecToDt")
def sec_to_dt(ctx, seconds: int) -> int:
    if not 0 <= seconds <= SECTODT_MAX_S:
        if ctx.settings.sectodt_range is not SectodtRange.CLAMP:
            raise FunctionError(f"SecToDt: {seconds} s is outside 0..{SECTODT_MAX_S}")
        seconds = max(0, min(seconds, SECTODT_MAX_S))
    return seconds * NS_PER_S


@native_function("DtToSec")
def dt_to_sec(ctx, dt_ns: int) -> int:
    return dt_ns // NS_PER_S


@native_function("NanoSecToTime")
def nano_sec_to_time(ctx, ns: int) -> int:
    return ns  # sysmac.md 6: the same number of ns; every LINT is a valid TIME


@native_function("TimeToNanoSec")
def time_to_nano_sec(ctx, time_ns: int) -> int:
    return time_ns
