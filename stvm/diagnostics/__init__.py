"""Diagnostics: every mistake in the user's ST becomes a `Diagnostic` value, never an exception.

One `render()` (used by the CLI and the tests) prints the contract format::

    FILE:LINE:COL: error: message
        <the source line>
        ^^^^
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import Iterable, Mapping

from stvm.syntax.nodes import Span


class Severity(str, Enum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True)
class Diagnostic:
    severity: Severity
    message: str
    span: Span
    code: str = ""

    @classmethod
    def error(cls, message: str, span: Span, code: str = "") -> "Diagnostic":
        return cls(Severity.ERROR, message, span, code)

    @classmethod
    def warning(cls, message: str, span: Span, code: str = "") -> "Diagnostic":
        return cls(Severity.WARNING, message, span, code)

    @property
    def is_error(self) -> bool:
        return self.severity is Severity.ERROR


def has_errors(diagnostics: Iterable[Diagnostic]) -> bool:
    return any(d.is_error for d in diagnostics)


def excerpt(span: Span, sources: Mapping[str, str]) -> str:
    """The source line of `span` and a caret line under the spanned columns ('' if unknown)."""
    text = sources.get(span.file)
    if text is None or span.line <= 0:
        return ""
    lines = text.splitlines()
    if span.line > len(lines):
        return ""
    line = lines[span.line - 1].replace("\t", " ")
    start = max(span.column, 1)
    width = span.end_column - span.column if span.end_line == span.line and span.end_column > span.column else 1
    width = max(1, min(width, len(line) - start + 1 if len(line) >= start else 1))
    return f"    {line}\n    {' ' * (start - 1)}{'^' * width}\n"


def render(diagnostic: Diagnostic, sources: Mapping[str, str], kind: str | None = None) -> str:
    """`FILE:LINE:COL: error: message` plus the source excerpt; `kind` overrides the severity word."""
    word = kind or diagnostic.severity.value
    span = diagnostic.span
    return f"{span.file}:{span.line}:{span.column}: {word}: {diagnostic.message}\n" + excerpt(span, sources)


def sort_key(diagnostic: Diagnostic) -> tuple:
    span = diagnostic.span
    return (span.file, span.line, span.column, diagnostic.message)
