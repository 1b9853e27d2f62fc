"""Literals typed by a user (`--set`, scenario files, the debugger's `set`, the HMI and the
front-end bridge): ST literal text checked against a variable's type and turned into its value.

It sits in the checker's stage because it judges text against a type, with the same literal
decoding the parser uses; every reader of user values takes it from here.
"""

from __future__ import annotations

import math

from stvm.semantics import types as t
from stvm.syntax import nodes as n
from stvm.syntax.literals import LiteralError, decode_int


MAX_VALUE_CHARS = 16384
"""The longest value text read (a WSTRING literal of the longest WSTRING fits)."""


def literal_value(text: str, ty):
    """An IEC literal typed by a user, converted to the value a variable of type `ty` holds
    (raises ValueError saying what is wrong, the text cut to a readable length)."""
    if len(text) > MAX_VALUE_CHARS:
        raise ValueError(f"a value of {len(text)} characters is longer than any literal stvm reads "
                         f"({MAX_VALUE_CHARS})")
    try:
        return _literal_value(text, ty)
    except ValueError as exc:
        if len(text) <= 60:
            raise
        short = text[:40] + "…"
        message = str(exc).replace(repr(text), repr(short)).replace(text, short)
        raise ValueError(message) from None


def _literal_value(text: str, ty):
    from stvm.syntax.parser import parse_expression   # lazy: Lark is loaded only when a literal is read
    expr, diags = parse_expression(text, "<--set>")
    if expr is None or any(d.is_error for d in diags):
        stripped = text.strip()
        if stripped[:1] in ("'", '"'):
            # a quote opens an ST string: one that does not parse is a mistake, not text
            quote = stripped[0]
            raise ValueError(f"{text!r} is not a complete string literal (close it with {quote}, "
                             f"write $' for a quote inside)")
        if isinstance(ty, t.StringType):
            return text.encode("utf-8")
        first = next((d.message for d in diags if d.is_error), "")
        raise ValueError(f"{text!r} is not an ST literal" + (f" ({first[:120]})" if first else ""))
    negate = False
    if isinstance(expr, n.Unary) and expr.op == "MINUS":
        negate, expr = True, expr.operand
    if isinstance(expr, (n.IntLiteral, n.RealLiteral, n.BoolLiteral, n.StringLiteral)):
        value = expr.value
    elif isinstance(expr, n.TimeLiteral):
        value = expr.value_ns
    elif isinstance(expr, n.HashLiteral):
        if isinstance(ty, t.EnumType):
            return expr.text
        text_value = expr.text
        try:
            if isinstance(ty, t.BoolType):
                value = text_value.upper() in ("TRUE", "1")
            elif "." in text_value or "e" in text_value.lower() and "#" not in text_value:
                value = float(text_value)
            else:
                value = decode_int(text_value.lstrip("+-")) * (-1 if text_value.startswith("-") else 1)
        except ValueError as exc:   # never Python's own words ("could not convert string to float")
            detail = str(exc) if isinstance(exc, LiteralError) else "not a number"
            raise ValueError(f"{text!r} is not an ST literal ({detail})") from None
    elif isinstance(expr, n.Name) and len(expr.parts) == 1 and isinstance(ty, t.EnumType):
        return expr.parts[0]
    else:
        raise ValueError(f"{text!r} is not a literal")
    if negate:
        value = -value
    _check_kind(text, expr, value, ty)
    if isinstance(ty, t.BoolType) and isinstance(expr, n.IntLiteral):
        value = bool(value)
    if isinstance(ty, t.RealType) and isinstance(value, int) and not isinstance(value, bool):
        try:
            value = float(value)
        except OverflowError:
            raise ValueError(f"{text!r} is out of range for {ty.name}") from None
    if isinstance(ty, t.RealType) and isinstance(value, (int, float)) and not isinstance(value, bool):
        limit = 3.4028234663852886e38 if ty.bits == 32 else 1.7976931348623157e308
        if not math.isfinite(value) or abs(value) > limit:
            raise ValueError(f"{text} is out of range for {ty.name} (at most ±{limit:.8g})")
    return value


def _check_kind(text: str, expr, value, ty) -> None:
    """User text must be a literal of the variable's kind: TIME takes T#5ms (5 alone would be
    5 ns), BOOL takes TRUE/FALSE (or BOOL#1), not 1."""
    if isinstance(ty, t.TimeType) and not isinstance(expr, (n.TimeLiteral, n.HashLiteral)):
        raise ValueError(f"{text!r} is not a duration: write it as TIME, e.g. T#5ms or T#1s500ms")
    if isinstance(ty, t.BoolType) and isinstance(expr, n.IntLiteral) and value in (0, 1) \
            and not text.strip().startswith(("-", "+")):
        return   # IEC 61131-3 table 5: 0 and 1 are BOOL literals (as BOOL#0 and BOOL#1)
    if isinstance(ty, t.BoolType) and not isinstance(expr, (n.BoolLiteral, n.HashLiteral)):
        raise ValueError(f"{text!r} is not a BOOL: write TRUE or FALSE (or 1 or 0)")
    if isinstance(ty, (t.IntType, t.RealType)) and isinstance(expr, n.TimeLiteral):
        raise ValueError(f"{text!r} is a duration (TIME), and {ty.name} holds a number")
    if isinstance(ty, t.IntType) and isinstance(expr, n.RealLiteral):
        raise ValueError(f"{text!r} is a REAL literal, and {ty.name} holds whole numbers")
    if isinstance(ty, (t.IntType, t.RealType)) and isinstance(expr, n.StringLiteral):
        raise ValueError(f"{text!r} is a string, and {ty.name} holds a number")
