"""What lowering produces (`LoweredProject`, its `LineMap`): kept apart from the code generator so
that a cached load and the VM unpickle them without importing the generator and the checker
(start-up time of `stvm run`)."""

from __future__ import annotations

import bisect
from dataclasses import dataclass, field

from stvm.semantics import types as t
from stvm.source import Span


@dataclass
class LineMap:
    """Generated line → ST span; `span_at` finds the statement a generated line belongs to."""

    lines: list[int] = field(default_factory=list)
    spans: list[Span | None] = field(default_factory=list)   # None: generated glue, no ST line

    def add(self, line: int, span: Span | None) -> None:
        if self.lines and self.lines[-1] == line:
            self.spans[-1] = span
            return
        self.lines.append(line)
        self.spans.append(span)

    def span_at(self, line: int) -> Span | None:
        """The ST statement generated line `line` belongs to; None for glue code (native FB
        wrappers, class headers), so a fault there is attributed to the calling statement."""
        i = bisect.bisect_right(self.lines, line) - 1
        return self.spans[i] if i >= 0 else None

    def lines_for(self, file: str, st_line: int) -> list[int]:
        """Generated lines where a statement starting at `file:st_line` begins (for breakpoints)."""
        out = []
        for gen_line, span in zip(self.lines, self.spans):
            if span is not None and span.file == file and span.line == st_line:
                out.append(gen_line)
        return out


@dataclass
class LoweredProject:
    source: str
    line_map: LineMap
    classes: dict[str, str]            # POU/struct qualname key → Python class/function name
    natives: dict[str, str]            # Python name → native registry key (functions)
    native_fbs: dict[str, str]         # Python class name → native FB registry key
    types: list[t.Type]                # `_T[i]` constants
    sites: list[Span]                # spans of `_fun_error(e, i)` and `_oob_skipped(e, i)` calls
    globals_class: str = "G_globals"
