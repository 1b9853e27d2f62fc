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
        lines = self.lines
        lines.append("    " * self.indent + text)
        span = self.span
        spans = self.line_map.spans
        if span is not None or (spans and spans[-1] is not None):
            # what `LineMap.add` does for a line after every line mapped so far (each entry
            # names a line already written): one call less per generated line
            self.line_map.lines.append(len(lines))
            spans.append(span)

    def blank_span(self) -> None:
        self.span = None

    def append(self, other: "CodeWriter") -> None:
        """Append a body generated separately, shifting its line map."""
        offset = len(self.lines)
        self.lines.extend(other.lines)
        theirs = other.line_map
        if not theirs.lines:
            return
        # only the first entry can meet the last one here (at the same line); the others follow
        # one another at increasing lines, as `add` would keep them
        self.line_map.add(theirs.lines[0] + offset, theirs.spans[0])
        self.line_map.lines.extend([line + offset for line in theirs.lines[1:]])
        self.line_map.spans.extend(theirs.spans[1:])
