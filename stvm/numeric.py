"""IEC value helpers that the checker (constant folding), the lowering (constant initial values)
and the runtime (every REAL store, every STRING[n] store) must compute the same way.

Nothing here imports the rest of stvm: it sits below the syntax, so each stage can use it.
"""

from __future__ import annotations

import math
import struct

_pack_f = struct.Struct("<f")


def f32(x: float) -> float:
    """Round to IEEE binary32 (every REAL store), keeping inf/nan; overflow becomes ±inf."""
    try:
        return _pack_f.unpack(_pack_f.pack(x))[0]
    except OverflowError:
        if x != x:
            return x
        return math.inf if x > 0 else -math.inf


def strfit(value: bytes, max_bytes: int) -> bytes:
    """Store into STRING[n]: truncate to n-1 bytes (Omron), never inside a UTF-8 sequence.
    A WSTRING value (`str` of UTF-16 code units) is cut at `max_bytes` code units."""
    if len(value) <= max_bytes:
        return value
    if isinstance(value, str):
        return value[:max_bytes]
    cut = value[:max_bytes]
    # drop a partial UTF-8 character at the end
    i = len(cut)
    while i > 0 and (cut[i - 1] & 0xC0) == 0x80:
        i -= 1
    if i > 0 and cut[i - 1] >= 0xC0:
        needed = 2 if cut[i - 1] < 0xE0 else 3 if cut[i - 1] < 0xF0 else 4
        if len(cut) - (i - 1) < needed:
            cut = cut[: i - 1]
    return cut


def utf16_units(text: str) -> str:
    """A WSTRING value from text: one Python character per UTF-16 code unit (a character outside
    the BMP becomes its two surrogates), so len(), slicing and find() count code units."""
    if all(ord(ch) < 0x10000 for ch in text):
        return text
    data = text.encode("utf-16-le", "surrogatepass")
    return "".join(chr(data[i] | data[i + 1] << 8) for i in range(0, len(data), 2))


def utf16_text(units: str) -> str:
    """The text a WSTRING value spells: surrogate pairs joined, a lone surrogate shown as U+FFFD."""
    return units.encode("utf-16-le", "surrogatepass").decode("utf-16-le", "replace")
