"""Diagnostics: every mistake in the user's ST becomes a `Diagnostic` value, never an exception.

One `render()` (used by the CLI and the tests) prints the contract format::

    FILE:LINE:COL: error: message [E031]
        <the source line>
        ^^^^

Nothing from the input reaches the terminal raw: control characters (ESC, BEL, NUL, …) and
the bidirectional overrides of "Trojan Source" are shown escaped (`\x1b`, `\u202e`), a message
is capped at MESSAGE_LIMIT characters and an excerpt at EXCERPT_WIDTH columns around the caret,
so a binary file or a crafted `.st` cannot drive the user's terminal or flood it.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from enum import Enum
from typing import Iterable, Mapping

from stvm.source import Span


class Severity(str, Enum):
    ERROR = "error"
    WARNING = "warning"


@dataclass(frozen=True)
class Diagnostic:
    """One error, warning or note at a source span, with its registered code."""

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


MESSAGE_LIMIT = 300     # characters of one message (user text inside is cut, never the location)
EXCERPT_WIDTH = 120     # columns of source shown around the caret

# C0 controls but TAB, DEL and C1 controls, and the bidi embeddings/overrides/isolates
_UNSAFE = re.compile("[\x00-\x08\x0a-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def _escape_char(match: re.Match) -> str:
    code = ord(match.group())
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: str, limit: int | None = MESSAGE_LIMIT) -> str:
    """`text` safe for a terminal: control characters escaped, at most `limit` characters."""
    text = _UNSAFE.sub(_escape_char, text)
    if limit is not None and len(text) > limit:
        text = text[:limit - 1] + "…"
    return text


def excerpt(span: Span, sources: Mapping[str, str]) -> str:
    """The source line of `span` and a caret line under the spanned columns ('' if unknown)."""
    text = sources.get(span.file)
    if text is None or span.line <= 0:
        return ""
    # lines end at LF only, as the parser counts them (str.splitlines also splits at VT, FF,
    # FS, NEL, U+2028, …, which would show the wrong line of a file that contains them)
    lines = text.split("\n")
    if span.line > len(lines):
        return ""
    line = lines[span.line - 1].rstrip("\r").replace("\t", " ")
    start = max(span.column, 1)
    width = span.end_column - span.column if span.end_line == span.line and span.end_column > span.column else 1
    width = max(1, min(width, len(line) - start + 1 if len(line) >= start else 1))
    # a window of the line around the caret (a minified or binary "line" can be megabytes)
    first = max(0, start - 1 - EXCERPT_WIDTH // 3)
    lead = "…" if first > 0 else ""
    before = printable(line[first:start - 1], None)
    marked = printable(line[start - 1:start - 1 + width], None)
    budget = max(1, EXCERPT_WIDTH - len(before))
    if len(marked) > budget:
        marked, after = marked[:budget], "…"
    else:
        after = printable(line[start - 1 + width:], None)
        if len(after) > budget - len(marked):
            after = after[:budget - len(marked)] + "…"
    caret = " " * (len(lead) + len(before)) + "^" * max(1, len(marked))
    return f"    {lead}{before}{marked}{after}\n    {caret}\n"


def render(diagnostic: Diagnostic, sources: Mapping[str, str], kind: str | None = None) -> str:
    """`FILE:LINE:COL: error: message [E031]` plus the source excerpt.

    The code (stvm/diagnostics/codes.py) ends the message line, as GCC and Clang append
    `[-Wname]`, so the `FILE:LINE:COL: error: ` prefix every log parser reads stays as it is.
    `kind` overrides the severity word (lint: `warning[SA102]`, which then names the code)."""
    word = kind or diagnostic.severity.value
    span = diagnostic.span
    where = f"{printable(span.file, None)}:{span.line}:{span.column}" if span.line > 0 else printable(span.file, None)
    code = f" [{diagnostic.code}]" if diagnostic.code and kind is None else ""
    return f"{where}: {word}: {printable(diagnostic.message)}{code}\n" + excerpt(span, sources)


def sort_key(diagnostic: Diagnostic) -> tuple:
    span = diagnostic.span
    return (span.file, span.line, span.column, diagnostic.message)
