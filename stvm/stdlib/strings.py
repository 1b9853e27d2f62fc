"""IEC string functions: CONCAT, LEN, LEFT, RIGHT, MID, FIND, INSERT, DELETE, REPLACE (sysmac.md 7).

Positions are 1-based and count characters: UTF-8 characters by default, an invalid byte counting
as one (sysmac.md 2, `string_length_unit`); with `bytes`, one byte is one character. Decoding with
`surrogateescape` gives exactly that model (each undecodable byte becomes one code point) and
encodes back to the same bytes. Results longer than a STRING holds are an instruction error
(`string_result_overflow`); a position out of range is an instruction error (`string_fn_range`).
"""

from __future__ import annotations

from stvm.runtime.values import FunctionError
from stvm.stdlib.registry import native_function
from stvm.stdlib.typeops import string_result
from stvm.settings import ConcatArity, StringFnRange, StringLengthUnit

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


@native_function("CONCAT", variadic=True)
def concat(ctx, *texts: bytes) -> bytes:
    # Choice (sysmac.md 7, `concat_arity`): one input is the identity with a warning; the thesis
    # listing has such calls (sysmac.md 3.1) and a build error would stop the whole program.
    if len(texts) < 2:
        if ctx.settings.concat_arity is ConcatArity.TWO_OR_MORE:
            raise FunctionError("CONCAT needs at least two inputs")
        ctx.warn("CONCAT called with one input: result is that input", once_key="concat_arity")
    if len(texts) > CONCAT_MAX_INPUTS:
        raise FunctionError(f"CONCAT takes at most {CONCAT_MAX_INPUTS} inputs, got {len(texts)}")
    return string_result(ctx, b"".join(texts), "CONCAT")


@native_function("LEN")
def len_(ctx, text: bytes) -> int:
    return char_count(ctx, text)


@native_function("LEFT")
def left(ctx, text: bytes, length: int) -> bytes:
    if text.isascii():
        return text[:length]
    return encode_chars(ctx, decode_chars(ctx, text)[:length])


@native_function("RIGHT")
def right(ctx, text: bytes, length: int) -> bytes:
    if length == 0:
        return b""
    if text.isascii():
        return text[-length:]
    return encode_chars(ctx, decode_chars(ctx, text)[-length:])


@native_function("MID")
def mid(ctx, text: bytes, length: int, position: int) -> bytes:
    chars = decode_chars(ctx, text)
    # Choice (sysmac.md 7): only P is range-checked (1 ≤ P ≤ LEN); L past the end takes the rest,
    # as LEFT/RIGHT do with L ≥ LEN.
    position = _check_position(ctx, "MID", position, 1, len(chars))
    return encode_chars(ctx, chars[position - 1:position - 1 + length])


@native_function("FIND")
def find(ctx, text: bytes, pattern: bytes) -> int:
    if not pattern:
        return ctx.settings.find_empty.value  # sysmac.md 7, `find_empty`
    if text.isascii() and pattern.isascii():
        return text.find(pattern) + 1
    return decode_chars(ctx, text).find(decode_chars(ctx, pattern)) + 1


@native_function("INSERT")
def insert(ctx, text: bytes, addition: bytes, position: int) -> bytes:
    chars = decode_chars(ctx, text)
    position = _check_position(ctx, "INSERT", position, 0, len(chars))
    result = chars[:position] + decode_chars(ctx, addition) + chars[position:]
    return string_result(ctx, encode_chars(ctx, result), "INSERT")


@native_function("DELETE")
def delete(ctx, text: bytes, length: int, position: int) -> bytes:
    chars = decode_chars(ctx, text)
    position = _check_position(ctx, "DELETE", position, 1, len(chars))
    return encode_chars(ctx, chars[:position - 1] + chars[position - 1 + length:])


@native_function("REPLACE")
def replace(ctx, text: bytes, replacement: bytes, length: int, position: int) -> bytes:
    chars = decode_chars(ctx, text)
    position = _check_position(ctx, "REPLACE", position, 1, len(chars))
    result = chars[:position - 1] + decode_chars(ctx, replacement) + chars[position - 1 + length:]
    return string_result(ctx, encode_chars(ctx, result), "REPLACE")
