"""Decoding of ST literal text: $-escaped strings, T#/D#/TOD#/DT# values, based integers.

Separate from the parser so that the command line can read durations (`--scan 1ms`) without
importing Lark.
"""

from __future__ import annotations

import calendar
import re
from fractions import Fraction
from functools import lru_cache

from stvm.settings import DollarN, InvalidDollarEscape, SysmacSettings

_ESCAPES = {"$": b"$", "'": b"'", '"': b'"', "L": b"\n", "P": b"\f", "R": b"\r", "T": b"\t"}
_TIME_UNITS = [("d", 86_400_000_000_000), ("h", 3_600_000_000_000), ("ms", 1_000_000),
               ("us", 1_000), ("ns", 1), ("m", 60_000_000_000), ("s", 1_000_000_000)]
_TIME_PART = re.compile(r"([0-9][0-9_]*(?:\.[0-9_]+)?)(d|h|ms|us|ns|m|s)", re.I)


class LiteralError(ValueError):
    """A malformed literal; the message is shown to the user."""


def decode_string(token_text: str, settings: SysmacSettings) -> tuple[bytes, list[str]]:
    """Decode a quoted ST string literal to bytes; returns (value, warnings). Raises LiteralError."""
    quote = token_text[0]
    body = token_text[1:-1]
    out = bytearray()
    warnings: list[str] = []
    i = 0
    hex_digits = 2 if quote == "'" else 4
    while i < len(body):
        ch = body[i]
        if ch != "$":
            out += ch.encode("utf-8")
            i += 1
            continue
        nxt = body[i + 1] if i + 1 < len(body) else ""
        if nxt.upper() in _ESCAPES and nxt not in ("'", '"') or nxt == quote:
            out += _ESCAPES[nxt.upper()]
            i += 2
        elif nxt.upper() == "N":
            # Choice (sysmac.md 3 #7, `dollar_n`): $N is a newline
            out += b"\n" if settings.dollar_n is DollarN.LF else b"\r\n"
            i += 2
        elif re.fullmatch(r"[0-9A-Fa-f]{%d}" % hex_digits, body[i + 1:i + 1 + hex_digits] or "x"):
            code = int(body[i + 1:i + 1 + hex_digits], 16)
            if hex_digits == 4 and 0xD800 <= code < 0xE000:
                # a STRING is UTF-8 text: half of a UTF-16 pair has no UTF-8 form
                raise LiteralError(f"'${body[i + 1:i + 5]}' is half of a UTF-16 surrogate pair, which a "
                                   "STRING cannot hold (write the character itself)")
            out += bytes([code]) if hex_digits == 2 else chr(code).encode("utf-8")
            i += 1 + hex_digits
        else:
            if settings.invalid_dollar_escape is InvalidDollarEscape.ERROR:
                raise LiteralError(f"invalid escape '${nxt}' in string literal (valid: $$ $' $L $N $P $R $T $hh)")
            out += b"$"
            i += 1
    value = bytes(out)
    if b"\x00" in value:
        # an Omron STRING ends at its first NUL
        value = value[: value.index(b"\x00")]
    return value, warnings


def decode_wstring(token_text: str, settings: SysmacSettings) -> str:
    """Decode a double-quoted WSTRING literal (IEC 61131-3 ed. 3, 6.3.3 table 7) to its UTF-16
    code units, one Python character each (a character outside the BMP becomes two surrogates);
    `$hhhh` is one code unit (4 hex digits), `$"` a quote. Raises LiteralError."""
    body = token_text[1:-1]
    out: list[str] = []
    i = 0
    while i < len(body):
        ch = body[i]
        if ch != "$":
            if ord(ch) >= 0x10000:
                code = ord(ch) - 0x10000
                out += [chr(0xD800 | code >> 10), chr(0xDC00 | code & 0x3FF)]
            else:
                out.append(ch)
            i += 1
            continue
        nxt = body[i + 1] if i + 1 < len(body) else ""
        if nxt.upper() in _ESCAPES:
            out.append(_ESCAPES[nxt.upper()].decode("ascii"))
            i += 2
        elif nxt.upper() == "N":
            out.append("\n" if settings.dollar_n is DollarN.LF else "\r\n")
            i += 2
        elif re.fullmatch(r"[0-9A-Fa-f]{4}", body[i + 1:i + 5] or "x"):
            out.append(chr(int(body[i + 1:i + 5], 16)))
            i += 5
        else:
            if settings.invalid_dollar_escape is InvalidDollarEscape.ERROR:
                raise LiteralError(f"invalid escape '${nxt}' in WSTRING literal "
                                   "(valid: $$ $\" $' $L $N $P $R $T $hhhh)")
            out.append("$")
            i += 1
    value = "".join(out)
    return value.split("\x00", 1)[0]   # as a STRING, a WSTRING ends at its first NUL


# The longest integer literal read: a ULINT in binary is 64 digits (plus separators). Longer
# text is refused before conversion: a 100,000-digit 16# literal took seconds and ended in exit 70,
# and Python refuses decimal text over 4,300 digits with a ValueError (issue 34 item 9).
MAX_INT_LITERAL_CHARS = 160
# TIME/LTIME are 64-bit counts of nanoseconds (about ±106,751 days)
TIME_NS_MIN, TIME_NS_MAX = -2**63, 2**63 - 1
# ... unless unsigned (the `unsigned_time` profile row, TwinCAT/CODESYS): TIME a 32-bit count of
# milliseconds, LTIME a 64-bit count of nanoseconds, both from 0
UNSIGNED_TIME_NS_MAX = {"TIME": (2**32 - 1) * 1_000_000, "LTIME": 2**64 - 1}
UNSIGNED_TIME_TEXT = {"TIME": "T#0ms..T#49d17h2m47s295ms (32-bit milliseconds)",
                      "LTIME": "LTIME#0ns..LTIME#213503d23h34m33s709ms551us615ns (64-bit nanoseconds)"}


def check_digit_separators(text: str) -> None:
    """IEC 61131-3: an underscore stands between two digits (`1_000`, `16#FF_FF`); `1__0`, `1_`
    and `_1` are not numbers. Raises LiteralError."""
    digits = text.split("#", 1)[-1].lstrip("+-")
    if "__" in digits or digits.startswith("_") or digits.endswith("_"):
        raise LiteralError(f"malformed number {text!r}: an underscore must stand between two digits")


def decode_int(text: str) -> int:
    """An ST integer literal's value (`1_000`, `16#FF`, `2#1010`). Raises LiteralError."""
    if len(text) > MAX_INT_LITERAL_CHARS:
        raise LiteralError(f"integer literal of {len(text)} characters: longer than any ST integer type "
                           f"needs (at most {MAX_INT_LITERAL_CHARS})")
    if "_" in text:
        check_digit_separators(text)
        text = text.replace("_", "")
    if "#" in text:
        base, digits = text.split("#", 1)
        return int(digits, int(base))
    return int(text)


@lru_cache(maxsize=4096)   # the same few durations recur in a program (PT := T#100ms); Fractions are slow
def decode_time(text: str, unsigned: str | None = None) -> int:
    """`T#1h2m3s4ms5us6ns` → nanoseconds. Raises LiteralError. `unsigned`: "TIME" or "LTIME" when
    the dialect's time types are unsigned (`unsigned_time`), which sets the range."""
    body = text.split("#", 1)[1].replace("_", "")
    sign = 1
    if body and body[0] in "+-":
        sign = -1 if body[0] == "-" else 1
        body = body[1:]
    pos = 0
    total = Fraction(0)
    if not body:
        raise LiteralError(f"empty duration in {text!r}")
    # a plain number without unit is not valid; every part needs one
    for match in _TIME_PART.finditer(body):
        if match.start() != pos:
            break
        total += Fraction(match.group(1)) * dict(_TIME_UNITS)[match.group(2).lower()]
        pos = match.end()
    if pos != len(body):
        raise LiteralError(f"malformed duration literal {text!r}")
    value = sign * int(total)
    if unsigned is not None:
        if not 0 <= value <= UNSIGNED_TIME_NS_MAX[unsigned]:
            raise LiteralError(f"duration {text if len(text) <= 40 else text[:40] + '…'} is out of range: "
                               f"{unsigned} holds {UNSIGNED_TIME_TEXT[unsigned]} in this dialect")
        return value
    if not TIME_NS_MIN <= value <= TIME_NS_MAX:
        raise LiteralError(f"duration {text if len(text) <= 40 else text[:40] + '…'} is out of range: "
                           f"TIME and LTIME hold at most ±106751d23h47m16s854ms775us807ns (64-bit nanoseconds)")
    return value


def _date_ns(y: int, mo: int, d: int) -> int:
    if not (1 <= mo <= 12 and 1 <= d <= calendar.monthrange(y, mo)[1]):
        raise LiteralError(f"invalid date {y:04d}-{mo:02d}-{d:02d}")
    return calendar.timegm((y, mo, d, 0, 0, 0)) * 1_000_000_000


def _tod_ns(text: str) -> int:
    parts = text.split(":")
    h, m = int(parts[0]), int(parts[1])
    sec = Fraction(parts[2]) if len(parts) > 2 else Fraction(0)
    if h > 23 or m > 59 or sec >= 60:
        raise LiteralError(f"invalid time of day {text}")
    return int((h * 3600 + m * 60 + sec) * 1_000_000_000)


def decode_date(text: str) -> int:
    y, mo, d = (int(x) for x in text.split("#", 1)[1].split("-"))
    return _date_ns(y, mo, d)


def decode_tod(text: str) -> int:
    return _tod_ns(text.split("#", 1)[1])


def decode_dt(text: str) -> int:
    body = text.split("#", 1)[1]
    y, mo, d, rest = body.split("-", 3)
    return _date_ns(int(y), int(mo), int(d)) + _tod_ns(rest)


