"""Value helpers the native stdlib shares: REAL rounding, coercion into a type, common types.

Values follow the representation table of `stvm.semantics.types` (ints always wrapped into their
type, REAL a float exactly representable in binary32, TIME/DT int ns, STRING bytes).
"""

from __future__ import annotations

import math
import struct

from stvm.semantics.types import (
    BoolType, EnumType, IntType, RealType, StringType, TimeType, Type, LINT,
)
from stvm.settings import StringLengthUnit, StringResultOverflow
from stvm.runtime.values import FunctionError

STRING_MAX_BYTES = 1985
"""Bytes of text a plain STRING holds (1986 bytes with the NUL, sysmac.md 2)."""

_FLOAT32 = struct.Struct("<f")


def to_real32(value: float) -> float:
    """Round a Python float to the nearest binary32 value (overflow gives ±inf, as IEEE does)."""
    try:
        return _FLOAT32.unpack(_FLOAT32.pack(value))[0]
    except OverflowError:
        return math.copysign(math.inf, value)


def coerce(value, target: Type):
    """Convert a value of any elementary type to `target`'s representation.

    Used for generic results (MAX of an INT and a REAL typed REAL). Reals go to integers with the
    Omron REAL_TO_** rounding (half to even, W502 2-248); integers wrap.
    """
    if isinstance(target, BoolType):
        return bool(value)
    if isinstance(target, (IntType, EnumType)):
        if isinstance(value, float):
            value = real_to_integer(value)
        value = int(value)
        return target.wrap(value) if isinstance(target, IntType) else value
    if isinstance(target, RealType):
        value = float(value)
        return to_real32(value) if target.bits == 32 else value
    if isinstance(target, TimeType):
        if isinstance(value, float):
            value = real_to_integer(value)
        return LINT.wrap(int(value))
    return value


def real_to_integer(value: float) -> int:
    """Round a real to an integer as Omron's REAL_TO_** do: nearest, ties to even (W502 2-248).

    Choice: NaN and ±inf have no integer ("Out will contain an illegal value", W502); stvm gives 0.
    """
    if not math.isfinite(value):
        return 0
    return round(value)  # Python's round() is half-to-even on the exact binary value


_RANKS = {8: 1, 16: 2, 32: 4, 64: 6}


def type_rank(t: Type) -> int:
    """Rank for the result type of mixed operands (sysmac.md 2)."""
    if isinstance(t, IntType):
        return _RANKS[t.bits]
    if isinstance(t, RealType):
        return 3 if t.bits == 32 else 5
    return 0


def common_type(types) -> Type | None:
    """The result type of mixed arguments: the highest-ranked wins; signed and unsigned of one
    rank give the unsigned one (sysmac.md 2). Non-numeric types: the first, or the longest
    STRING."""
    present = [t for t in types if t is not None]
    if not present:
        return None
    numeric = [t for t in present if isinstance(t, (IntType, RealType))]
    if len(numeric) == len(present):
        best = max(numeric, key=type_rank)
        if isinstance(best, IntType) and best.signed:
            for t in numeric:
                if isinstance(t, IntType) and t.bits == best.bits and not t.signed:
                    return t
        return best
    if all(isinstance(t, StringType) for t in present):
        return max(present, key=lambda t: t.size)
    return present[0]


def string_result(ctx, text: bytes, what: str) -> bytes:
    """Apply the STRING result limit of the string functions (sysmac.md 7,
    `string_result_overflow`): more than 1985 bytes is an instruction error, or is cut."""
    if len(text) <= STRING_MAX_BYTES:
        return text
    if ctx.settings.string_result_overflow is StringResultOverflow.TRUNCATE:
        cut = STRING_MAX_BYTES
        if ctx.settings.string_length_unit is StringLengthUnit.UTF8:
            # do not split a UTF-8 character: back off over continuation bytes
            while cut > STRING_MAX_BYTES - 3 and 0x80 <= text[cut] <= 0xBF:
                cut -= 1
        return text[:cut]
    raise FunctionError(f"{what}: result of {len(text)} bytes exceeds the STRING maximum of "
                        f"{STRING_MAX_BYTES}")
