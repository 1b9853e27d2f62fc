"""IEC string functions: CONCAT, LEN, LEFT, RIGHT, MID, FIND, INSERT, DELETE, REPLACE (sysmac.md 7),
on STRING and on WSTRING (whose positions count UTF-16 code units).

Positions are 1-based and count characters: UTF-8 characters by default, an invalid byte counting
as one (sysmac.md 2, `string_length_unit`); with `bytes`, one byte is one character. Decoding with
`surrogateescape` gives exactly that model (each undecodable byte becomes one code point) and
encodes back to the same bytes. Results longer than a STRING holds are an instruction error
(`string_result_overflow`); a position out of range is an instruction error (`string_fn_range`).
"""

from __future__ import annotations

from stvm.numeric import utf16_text, utf16_units
from stvm.runtime.values import FunctionError
from stvm.semantics.types import STRING, WSTRING, StringType, is_wide
from stvm.stdlib.registry import native_function
from stvm.stdlib.typeops import string_result
from stvm.settings import ConcatArity, StringFnRange, StringLengthUnit, StringResultOverflow

CONCAT_MAX_INPUTS = 32  # sysmac.md 7: CONCAT takes 2…32 inputs


def decode_chars(ctx, text: bytes) -> str:
    """The characters of a STRING value, one code point per ST character."""
    if ctx.settings.string_length_unit is StringLengthUnit.BYTES:
        return text.decode("latin-1")
    return text.decode("utf-8", "surrogateescape")


def encode_chars(ctx, chars: str) -> bytes:
    if ctx.settings.string_length_unit is StringLengthUnit.BYTES:
        return chars.encode("latin-1")
    return chars.encode("utf-8", "surrogateescape")


def char_count(ctx, text: bytes) -> int:
    if text.isascii() or ctx.settings.string_length_unit is StringLengthUnit.BYTES:
        return len(text)
    return len(text.decode("utf-8", "surrogateescape"))


def _check_position(ctx, what: str, position: int, low: int, high: int) -> int:
    """Position `position` must lie in low..high; else an error, or the nearest valid one when
    `string_fn_range` is `clamp`."""
    if low <= position <= high:
        return position
    if ctx.settings.string_fn_range is StringFnRange.CLAMP:
        return max(low, min(position, high))
    raise FunctionError(f"{what}: position {position} outside {low}..{high}")


def text_family(arg_types) -> StringType:
    """The result type of a string function: WSTRING when its text inputs are WSTRINGs, else
    STRING; mixing the two is a type error (convert with STRING_TO_WSTRING/WSTRING_TO_STRING)."""
    wide = {is_wide(ty) for ty in arg_types if isinstance(ty, StringType)}
    if len(wide) > 1:
        raise TypeError("mixes STRING and WSTRING inputs; convert one with STRING_TO_WSTRING or "
                        "WSTRING_TO_STRING")
    return WSTRING if True in wide else STRING


def _wstring_result(ctx, units: str, what: str) -> str:
    """A WSTRING result longer than a WSTRING holds: as `string_result` for STRING."""
    if len(units) <= WSTRING.max_bytes:
        return units
    if ctx.settings.string_result_overflow is StringResultOverflow.TRUNCATE:
        return units[:WSTRING.max_bytes]
    raise FunctionError(f"{what}: result of {len(units)} code units exceeds the WSTRING maximum of "
                        f"{WSTRING.max_bytes}")


# A WSTRING value is a `str` of UTF-16 code units: LEN, positions and lengths count code units
# with plain str operations. A STRING value is `bytes` (characters as `string_length_unit` says).

@native_function("CONCAT", generic=True, variadic=True, result_rule=text_family)
def concat(ctx, result_type, *texts: bytes) -> bytes:
    # Choice (sysmac.md 7, `concat_arity`): one input is the identity with a warning; the thesis
    # listing has such calls (sysmac.md 3.1) and a build error would stop the whole program.
    if len(texts) < 2:
        if ctx.settings.concat_arity is ConcatArity.TWO_OR_MORE:
            raise FunctionError("CONCAT needs at least two inputs")
        ctx.warn("CONCAT called with one input: result is that input", once_key="concat_arity")
    if len(texts) > CONCAT_MAX_INPUTS:
        raise FunctionError(f"CONCAT takes at most {CONCAT_MAX_INPUTS} inputs, got {len(texts)}")
    if is_wide(result_type):
        return _wstring_result(ctx, "".join(texts), "CONCAT")
    return string_result(ctx, b"".join(texts), "CONCAT")


@native_function("LEN")
def len_(ctx, text: bytes) -> int:
    if isinstance(text, str):
        return len(text)
    return char_count(ctx, text)


@native_function("LEFT", generic=True, result_rule=text_family)
def left(ctx, result_type, text: bytes, length: int) -> bytes:
    if isinstance(text, str) or text.isascii():
        return text[:length]
    return encode_chars(ctx, decode_chars(ctx, text)[:length])


@native_function("RIGHT", generic=True, result_rule=text_family)
def right(ctx, result_type, text: bytes, length: int) -> bytes:
    if length == 0:
        return text[:0]
    if isinstance(text, str) or text.isascii():
        return text[-length:]
    return encode_chars(ctx, decode_chars(ctx, text)[-length:])


def _chars(ctx, text):
    """The characters a function indexes: a WSTRING's code units as they are, a STRING decoded."""
    return text if isinstance(text, str) else decode_chars(ctx, text)


def _back(ctx, chars: str, wide: bool):
    return chars if wide else encode_chars(ctx, chars)


@native_function("MID", generic=True, result_rule=text_family)
def mid(ctx, result_type, text: bytes, length: int, position: int) -> bytes:
    chars = _chars(ctx, text)
    # Choice (sysmac.md 7): only P is range-checked (1 ≤ P ≤ LEN); L past the end takes the rest,
    # as LEFT/RIGHT do with L ≥ LEN.
    position = _check_position(ctx, "MID", position, 1, len(chars))
    return _back(ctx, chars[position - 1:position - 1 + length], isinstance(text, str))


@native_function("FIND", result_rule=text_family)
def find(ctx, text: bytes, pattern: bytes) -> int:
    if not pattern:
        return ctx.settings.find_empty.value  # sysmac.md 7, `find_empty`
    if isinstance(text, str) or (text.isascii() and pattern.isascii()):
        return text.find(pattern) + 1
    return decode_chars(ctx, text).find(decode_chars(ctx, pattern)) + 1


@native_function("INSERT", generic=True, result_rule=text_family)
def insert(ctx, result_type, text: bytes, addition: bytes, position: int) -> bytes:
    chars = _chars(ctx, text)
    position = _check_position(ctx, "INSERT", position, 0, len(chars))
    result = chars[:position] + _chars(ctx, addition) + chars[position:]
    if is_wide(result_type):
        return _wstring_result(ctx, result, "INSERT")
    return string_result(ctx, encode_chars(ctx, result), "INSERT")


@native_function("DELETE", generic=True, result_rule=text_family)
def delete(ctx, result_type, text: bytes, length: int, position: int) -> bytes:
    chars = _chars(ctx, text)
    position = _check_position(ctx, "DELETE", position, 1, len(chars))
    return _back(ctx, chars[:position - 1] + chars[position - 1 + length:], isinstance(text, str))


@native_function("REPLACE", generic=True, result_rule=text_family)
def replace(ctx, result_type, text: bytes, replacement: bytes, length: int, position: int) -> bytes:
    chars = _chars(ctx, text)
    position = _check_position(ctx, "REPLACE", position, 1, len(chars))
    result = chars[:position - 1] + _chars(ctx, replacement) + chars[position - 1 + length:]
    if is_wide(result_type):
        return _wstring_result(ctx, result, "REPLACE")
    return string_result(ctx, encode_chars(ctx, result), "REPLACE")


# ---- STRING <-> WSTRING (the conversion table in stvm.stdlib.conversions uses these) ----------

def wide_from_text(ctx, text: bytes, what: str) -> str:
    """STRING_TO_WSTRING: a STRING's characters as UTF-16 code units (an invalid UTF-8 byte is
    U+FFFD)."""
    if ctx.settings.string_length_unit is StringLengthUnit.BYTES:
        chars = text.decode("latin-1")
    else:
        chars = text.decode("utf-8", "replace")
    return _wstring_result(ctx, utf16_units(chars), what)


def text_from_wide(ctx, units: str, what: str) -> bytes:
    """WSTRING_TO_STRING: the WSTRING's characters in UTF-8 (a lone surrogate is U+FFFD); with
    `string_length_unit=bytes`, a character above U+00FF is '?'."""
    chars = utf16_text(units)
    if ctx.settings.string_length_unit is StringLengthUnit.BYTES:
        return string_result(ctx, chars.encode("latin-1", "replace"), what)
    return string_result(ctx, chars.encode("utf-8"), what)
