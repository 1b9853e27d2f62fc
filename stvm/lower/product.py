"""What lowering produces (`LoweredProject`, its `LineMap`): kept apart from the code generator so
that a cached load and the VM unpickle them without importing the generator and the checker
(start-up time of `stvm run`)."""

from __future__ import annotations

import bisect
from types import CodeType

from stvm.records import FACTORY, Record
from stvm.lower.layout import ProjectLayout
from stvm.semantics import types as t
from stvm.source import Span

# LineMap and LoweredProject behave as the dataclasses they were (`__init__`, `==` over every
# field, `repr`, unhashable, the `__dict__` pickle stores) but are `stvm.records` classes
# (`__init__` written out, the rest derived from `_FIELDS`): `dataclass` builds
# a class's methods with `exec` at import, a cost of every `stvm run` (issue 33 item 5;
# tests/lower/test_product_records.py compares them).

class LineMap(Record):
    """Generated line → ST span; `span_at` finds the statement a generated line belongs to
    (`spans`: None for generated glue, no ST line)."""

    _FIELDS = ('lines', 'spans')

    def __init__(self, lines: list[int] = FACTORY, spans: list[Span | None] = FACTORY) -> None:
        self.lines = [] if lines is FACTORY else lines
        self.spans = [] if spans is FACTORY else spans

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


class LoweredProject(Record):
    """What the lowering gives the VM: the Python source, where each line comes from, and the
    names and constants the generated module is bound with.

    `classes`: POU/struct qualname key → Python class/function name; `natives`: Python name →
    native registry key (functions); `native_fbs`: Python class name → native FB registry key;
    `types`: the `_T[i]` constants; `sites`: spans of `_fun_error(e, i)` and `_oob_skipped(e, i)`
    calls; `layouts`: where each ST variable is stored (stvm/lower/layout.py), what the VM, trace,
    debugger and the front ends read variables through, set by `lower_project`."""

    _FIELDS = ('source', 'line_map', 'classes', 'natives', 'native_fbs', 'types', 'sites', 'globals_class', 'layouts')

    def __init__(self, source: str, line_map: LineMap, classes: dict[str, str], natives: dict[str, str],
                 native_fbs: dict[str, str], types: list[t.Type], sites: list[Span],
                 globals_class: str = "G_globals", layouts: ProjectLayout | None = None) -> None:
        self.source = source
        self.line_map = line_map
        self.classes = classes
        self.natives = natives
        self.native_fbs = native_fbs
        self.types = types
        self.sites = sites
        self.globals_class = globals_class
        self.layouts = layouts


CHUNK_LINES = 1500
"""About how many generated lines `compile_module` compiles at once. Smaller pieces compile
faster per line (the compiler's syntax tree and tables of a piece stay in the CPU caches):
the 208,000-line module of a 100,000-line program compiles in ~10 % less time in pieces of
1,500 lines than of 4,000 (bench/bench_large.py), with a lower peak."""


def compile_module(source: str, filename: str) -> tuple[CodeType, ...]:
    """The generated module compiled in pieces of about CHUNK_LINES lines, cut before a top-level
    `class`/`def` (the generator writes nothing else at column 0 that a cut could split), each
    keeping its own line numbers (the LineMap's). Python's compiler holds the whole syntax tree of
    what it compiles: one 10 MB module costs ~850 MB at its peak, pieces a small fraction. The VM
    runs the pieces in order in one namespace, which is the module run at once."""
    lines = source.splitlines(keepends=True)
    if len(lines) <= CHUNK_LINES:
        return (compile(source, filename, "exec"),)
    codes = []
    start = 0
    while start < len(lines):
        end = min(start + CHUNK_LINES, len(lines))
        while end < len(lines) and not lines[end].startswith(("class ", "def ")):
            end += 1
        try:
            code = compile("".join(lines[start:end]), filename, "exec")
        except SyntaxError as exc:   # at its line in the whole module (the LineMap's)
            if exc.lineno is not None:
                exc.lineno += start
            if getattr(exc, "end_lineno", None) is not None:
                exc.end_lineno += start
            raise
        codes.append(_moved_down(code, start))
        start = end
    return tuple(codes)


def _moved_down(code: CodeType, lines: int) -> CodeType:
    """`code` (and every code object inside it) as if compiled `lines` lines further down: the
    piece gets its place in the module, so line numbers of faults, breakpoints and the LineMap
    stay those of the whole module. A code object's line table counts from its
    `co_firstlineno`; moving that is what compiling the piece behind `lines` blank lines did,
    without the compiler reading millions of blank lines (a tenth of compiling a 100,000-line
    program's module)."""
    if not lines:
        return code
    consts = code.co_consts
    if any(isinstance(c, CodeType) for c in consts):
        consts = tuple(_moved_down(c, lines) if isinstance(c, CodeType) else c for c in consts)
        return code.replace(co_firstlineno=code.co_firstlineno + lines, co_consts=consts)
    return code.replace(co_firstlineno=code.co_firstlineno + lines)
