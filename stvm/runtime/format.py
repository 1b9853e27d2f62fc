"""Values as IEC literals (for `--print`, traces and the debugger), and literals back to values."""

from __future__ import annotations

import math

from stvm.lower.layout import ProjectLayout, struct_layout
from stvm.numeric import f32
from stvm.semantics import types as t

_NS = 1_000_000_000
_TIME_UNITS = [("d", 86_400 * _NS), ("h", 3600 * _NS), ("m", 60 * _NS), ("s", _NS), ("ms", 1_000_000),
               ("us", 1_000), ("ns", 1)]


def format_time(ns: int) -> str:
    if ns == 0:
        return "T#0s"
    sign = "-" if ns < 0 else ""
    rest = abs(ns)
    parts = []
    for unit, size in _TIME_UNITS:
        count, rest = divmod(rest, size)
        if count:
            parts.append(f"{count}{unit}")
    return f"T#{sign}{''.join(parts)}"


def _fraction(ns: int) -> str:
    return f".{ns:09d}".rstrip("0") if ns else ""


def format_date(ns: int) -> str:
    days = ns // (86_400 * _NS)
    y, mo, d = _civil(days)
    return f"D#{y:04d}-{mo:02d}-{d:02d}"


def format_tod(ns: int) -> str:
    secs, frac = divmod(ns, _NS)
    h, rem = divmod(secs, 3600)
    m, s = divmod(rem, 60)
    return f"TOD#{h:02d}:{m:02d}:{s:02d}{_fraction(frac)}"


def format_dt(ns: int) -> str:
    days, rem = divmod(ns, 86_400 * _NS)
    y, mo, d = _civil(days)
    secs, frac = divmod(rem, _NS)
    h, r2 = divmod(secs, 3600)
    m, s = divmod(r2, 60)
    return f"DT#{y:04d}-{mo:02d}-{d:02d}-{h:02d}:{m:02d}:{s:02d}{_fraction(frac)}"


def _civil(days: int) -> tuple[int, int, int]:
    import datetime
    date = datetime.date(1970, 1, 1) + datetime.timedelta(days=days)
    return date.year, date.month, date.day


def format_string(value: bytes) -> str:
    out = ["'"]
    for byte in value:
        ch = chr(byte)
        if ch == "'":
            out.append("$'")
        elif ch == "$":
            out.append("$$")
        elif ch == "\n":
            out.append("$L")
        elif ch == "\r":
            out.append("$R")
        elif ch == "\t":
            out.append("$T")
        elif ch == "\f":
            out.append("$P")
        elif 32 <= byte < 127:
            out.append(ch)
        else:
            out.append(f"${byte:02X}")
    out.append("'")
    return "".join(out)


_WIDE_ESCAPES = {'"': '$"', "$": "$$", "\n": "$L", "\r": "$R", "\t": "$T", "\f": "$P"}


def format_wstring(units: str) -> str:
    """A WSTRING value as its IEC literal, readable: printable characters as themselves (a
    surrogate pair as the one character it encodes), the rest as `$hhhh` code units."""
    out = ['"']
    i = 0
    while i < len(units):
        ch = units[i]
        code = ord(ch)
        if 0xD800 <= code < 0xDC00 and i + 1 < len(units) and 0xDC00 <= ord(units[i + 1]) < 0xE000:
            pair = chr(0x10000 + ((code - 0xD800) << 10) + ord(units[i + 1]) - 0xDC00)
            out.append(pair if pair.isprintable() else f"${code:04X}${ord(units[i + 1]):04X}")
            i += 2
            continue
        if ch in _WIDE_ESCAPES:
            out.append(_WIDE_ESCAPES[ch])
        elif ch.isprintable() and not 0xD800 <= code < 0xE000:
            out.append(ch)
        else:
            out.append(f"${code:04X}")
        i += 1
    out.append('"')
    return "".join(out)


def format_real(value: float, bits: int) -> str:
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    if bits == 32:
        return _shortest_real32(value)
    text = repr(float(value))
    if "e" in text:
        mantissa, exponent = text.split("e")
        if "." not in mantissa:
            mantissa += ".0"
        exp = int(exponent)
        return f"{mantissa}E{'+' if exp >= 0 else '-'}{abs(exp):02d}"
    if "." not in text:
        text += ".0"
    return text


def _shortest_real32(value: float) -> str:
    """The shortest decimal that reads back as the same binary32 value; positional for
    1e-4 <= |x| < 1e6, else scientific (`1.6777216e+07`), as numpy prints float32."""
    for digits in range(0, 10):
        text = f"{value:.{digits}e}"
        if f32(float(text)) == value:
            break
    mantissa, exponent = text.split("e")
    mantissa = mantissa.rstrip("0").rstrip(".") if "." in mantissa else mantissa
    exp = int(exponent)
    if -4 <= exp < 6:
        digits_text = mantissa.replace("-", "").replace(".", "")
        sign = "-" if mantissa.startswith("-") else ""
        point = exp + 1
        if point <= 0:
            text = f"{sign}0.{'0' * -point}{digits_text}"
        elif point >= len(digits_text):
            text = f"{sign}{digits_text}{'0' * (point - len(digits_text))}.0"
        else:
            text = f"{sign}{digits_text[:point]}.{digits_text[point:]}"
        return text
    if "." not in mantissa:
        mantissa += ".0"   # an IEC real literal has digits on both sides of the point
    return f"{mantissa}E{'+' if exp >= 0 else '-'}{abs(exp):02d}"


def format_value(value: object, ty: t.Type, layouts: ProjectLayout | None = None) -> str:
    """`value` (runtime representation) of type `ty` as an IEC literal. Members are read through
    the lowering's layout (`layouts`; a struct formats without one, an FB instance shows `(…)`)."""
    if isinstance(ty, t.BoolType):
        return "TRUE" if value else "FALSE"
    if isinstance(ty, t.IntType):
        return str(int(value))  # type: ignore[arg-type]
    if isinstance(ty, t.RealType):
        return format_real(float(value), ty.bits)  # type: ignore[arg-type]
    if isinstance(ty, t.TimeType):
        ns = int(value)  # type: ignore[arg-type]
        text = {"TIME": format_time, "DATE": format_date, "TIME_OF_DAY": format_tod,
                "DATE_AND_TIME": format_dt}[ty.family](ns)
        return "L" + text if ty.long else text   # LTIME#…, LDATE#…, LTOD#…, LDT#…
    if isinstance(ty, t.StringType):
        if isinstance(value, str):
            return format_wstring(value)
        return format_string(value)  # type: ignore[arg-type]
    if isinstance(ty, t.EnumType):
        name = ty.name_of(int(value))  # type: ignore[arg-type]
        return f"{ty.name}#{name}" if name is not None else str(value)
    if isinstance(ty, t.StructType):
        layout = layouts.of(ty) if layouts is not None else struct_layout(ty)
        parts = [f"{slot.name} := {format_value(getattr(value, slot.storage), slot.type, layouts)}"
                 for slot in layout]  # type: ignore[union-attr]
        return "(" + ", ".join(parts) + ")"
    if isinstance(ty, t.ArrayType):
        if ty.dims is None and ty.rank > 1:   # an ARRAY[*, *] parameter: the lists passed
            return _format_array(value.data, ty, ty.rank, layouts)  # type: ignore[attr-defined]
        if ty.dims is None:
            return "[" + ", ".join(format_value(v, ty.element, layouts) for v in value.data[value.start:]) + "]"  # type: ignore[attr-defined]
        return _format_array(value, ty, len(ty.dims), layouts)  # type: ignore[arg-type]
    if isinstance(ty, t.FBType) and layouts is not None:
        layout = layouts.of(ty)
        if layout is None:
            return "(…)"
        parts = [f"{slot.name} := {format_value(getattr(value, slot.storage), slot.type, layouts)}"
                 for slot in layout.owned()]
        return "(" + ", ".join(parts) + ")"
    if isinstance(ty, t.InterfaceType):
        # an interface variable: NULL, or `-> FB_Type` of the instance it holds
        return "NULL" if value is None else f"-> {getattr(value, '_st', 'instance')}"
    if isinstance(ty, t.RefType):
        # Choice: a reference prints as `-> value` of a scalar target, `-> TYPE` of an aggregate
        # (a self-referencing struct must not recurse); `r^` in a path shows the target in full
        if value is None:
            return "NULL"
        if ty.target is None or t.is_aggregate(ty.target):
            return f"-> {ty.target.name if ty.target is not None else '?'}"
        return f"-> {format_value(value.get(), ty.target, layouts)}"  # type: ignore[attr-defined]
    return repr(value)


def _format_array(value: list, ty: t.ArrayType, depth: int, layouts) -> str:
    if depth == 1:
        return "[" + ", ".join(format_value(v, ty.element, layouts) for v in value) + "]"
    return "[" + ", ".join(_format_array(v, ty, depth - 1, layouts) for v in value) + "]"


def parse_datetime_ns(y: int, mo: int, d: int, h: int = 0, mi: int = 0, s: int = 0) -> int:
    import calendar   # lazy: start-up (calendar pulls in datetime and locale)
    return calendar.timegm((y, mo, d, h, mi, s)) * _NS
