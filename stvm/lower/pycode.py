"""Building blocks of the generated Python source: the line writer with its ST line map, checked
constants as Python literals, and integer wrapping.

Nothing here sees ST text: a literal is a checked runtime value written with `repr()`."""

from __future__ import annotations

import math

from stvm.lower.product import LineMap
from stvm.semantics import types as t
from stvm.syntax import nodes as n


def py_literal(value: object) -> str:
    """Python source for a checked runtime constant (bool, int, float, bytes, str)."""
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int):
        return repr(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "float('nan')"
        if math.isinf(value):
            return "float('inf')" if value > 0 else "float('-inf')"
        return repr(value)
    if isinstance(value, bytes):
        return repr(value)
    if isinstance(value, str):
        return ascii(value)   # a WSTRING's code units; ascii() keeps the source ASCII (surrogates escaped)
    raise AssertionError(f"not a literal: {type(value).__name__}")


def wrap_int(code: str, ty: t.IntType) -> str:
    mask = (1 << ty.bits) - 1
    if ty.signed:
        half = 1 << (ty.bits - 1)
        return f"((({code}) + {half} & {mask}) - {half})"
    return f"(({code}) & {mask})"


def int_contains(dst: t.IntType, src: t.IntType) -> bool:
    return dst.lo <= src.lo and src.hi <= dst.hi


class CodeWriter:
    """Lines of generated code, each tagged with the ST span being lowered (`span`)."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.indent = 0
        self.line_map = LineMap()
        self.span: n.Span | None = None

    def line(self, text: str) -> None:
        self.lines.append("    " * self.indent + text)
        spans = self.line_map.spans
        if self.span is not None or (spans and spans[-1] is not None):
            self.line_map.add(len(self.lines), self.span)

    def blank_span(self) -> None:
        self.span = None

    def append(self, other: "CodeWriter") -> None:
        """Append a body generated separately, shifting its line map."""
        offset = len(self.lines)
        self.lines.extend(other.lines)
        for line, span in zip(other.line_map.lines, other.line_map.spans):
            self.line_map.add(line + offset, span)
