"""The debug build of a project, and where each ST statement starts in the generated code.

A debug build is the normal pipeline (parse, check, lower, compile) with one lowering switch
changed: `cache_locals` off (`DEBUG_OPTIONS`). The normal build keeps a POU's variables in Python locals during a
call and writes them back in a `finally`; a debugger stopped in the middle of that call would read
stale values from the instance and its writes would be lost. Without the cache every variable
lives on its instance (FB/PROGRAM) or call frame (`_f`, FUNCTION), so what the debugger reads and
writes is the storage the code itself uses. (A range-FOR needs its loop variable in a local, so
without the cache no FOR becomes one.)

The build is never written to the compile cache (its code differs from the normal build's), and
it keeps the `Checker`, whose project index types the debugger's expressions.
"""

from __future__ import annotations

import bisect
import os
from dataclasses import dataclass, field, replace
from typing import Sequence

from stvm.lower.names import method_attr
from stvm.lower.options import DEFAULT_OPTIONS
from stvm.project import Project, ProjectSpec, check_stage, compile_stage, parse_stage, resolve
from stvm.semantics.checker import Analysis, Checker
from stvm.semantics.model import POUInfo
from stvm.settings import SysmacSettings
from stvm.syntax import nodes as n


# What the debugger needs: every variable in its instance or frame, never in a Python local;
# every FB body in its own call (a stack frame per ST call, breakpoints in the FB's body).
DEBUG_OPTIONS = DEFAULT_OPTIONS.without("cache_locals", "inline_small_fbs")


def is_library_file(file: str) -> bool:
    """Files of the stdlib (`<stdlib>/…`) and other built-in text: stepping never stops there."""
    return file.startswith("<")


@dataclass
class StatementMap:
    """Where ST statements start in the generated module.

    `stops` holds each generated line that begins the code of an ST statement (or of an ELSIF
    condition, or of a loop's test or increment, which run again on every iteration): the line's
    span differs from the span of the line before it. A line event on one of them is a statement
    entry, where stepping and breakpoints stop. Lines of library files are not stops (stepping
    steps over the stdlib's ST blocks, as a controller's debugger steps over system FBs).
    """

    spans: dict[int, n.Span] = field(default_factory=dict)          # generated line → ST span
    stops: set[int] = field(default_factory=set)
    by_st_line: dict[tuple[str, int], list[int]] = field(default_factory=dict)  # (file, ST line) → stops
    st_lines: dict[str, list[int]] = field(default_factory=dict)     # file → sorted ST lines with a stop

    @classmethod
    def build(cls, line_map, pou_spans: frozenset[n.Span] | set[n.Span] = frozenset()) -> "StatementMap":
        """`pou_spans`: spans of whole POUs, which the code generator gives a call's prologue and
        write-back lines (a fault there names the POU's header); they are not statements."""
        out = cls()
        previous: n.Span | None = None
        previous_line = 0
        for gen_line, span in zip(line_map.lines, line_map.spans):
            if span is None:   # generated glue (native FB wrappers): no ST statement
                previous = None
                continue
            out.spans[gen_line] = span
            starts = previous is None or gen_line != previous_line + 1 or span != previous
            if starts and not is_library_file(span.file) and span not in pou_spans:
                out.stops.add(gen_line)
                out.by_st_line.setdefault((span.file, span.line), []).append(gen_line)
            previous, previous_line = span, gen_line
        for file, line in out.by_st_line:
            out.st_lines.setdefault(file, []).append(line)
        for lines in out.st_lines.values():
            lines.sort()
        return out

    def next_st_line(self, file: str, line: int, last: int | None = None) -> int | None:
        """The first ST line >= `line` (and <= `last`) where a statement starts, or None."""
        lines = self.st_lines.get(file, [])
        i = bisect.bisect_left(lines, line)
        if i == len(lines) or (last is not None and lines[i] > last):
            return None
        return lines[i]


@dataclass
class DebugBuild:
    project: Project
    analysis: Analysis
    checker: Checker
    statements: StatementMap
    unit_pous: dict[str, POUInfo]        # generated class/function name → POU
    files: dict[str, str]                # absolute path → the file name spans use
    # (FB class name, Python method name) → (METHOD or property accessor, its node, the FB)
    unit_methods: dict[tuple[str, str], tuple[POUInfo, n.Method, POUInfo]] = field(default_factory=dict)

    def pou_at(self, file: str, line: int) -> tuple[POUInfo, n.POU] | None:
        """The user POU (or METHOD / property accessor) whose text contains `file:line`."""
        for method, node, _ in self.unit_methods.values():
            span = node.span
            if span.file == file and span.line <= line <= span.end_line:
                return method, node  # type: ignore[return-value]
        for key, node in self.analysis.pou_nodes.items():
            span = node.span
            if span.file == file and span.line <= line <= max(span.end_line, node.end_span.line):
                return self.analysis.model.pous[key], node
        return None

    def span_file(self, name: str) -> str | None:
        """The span file name for a path as a user or an editor writes it: the name given to
        `load`, an absolute or relative path, a base name (`CBT_MoveAbsolute.st`) or a stem
        (`CBT_MoveAbsolute`) when it is unique."""
        if name in self.statements.st_lines or name in self.project.sources:
            return name
        for candidate in (os.path.abspath(name), os.path.realpath(name)):
            key = os.path.normcase(candidate)
            if key in self.files:
                return self.files[key]
        lowered = name.lower()
        matches = sorted({f for f in self.files.values()
                          if os.path.basename(f).lower() == lowered
                          or os.path.splitext(os.path.basename(f))[0].lower() == lowered})
        return matches[0] if len(matches) == 1 else None

    def absolute_path(self, file: str) -> str | None:
        """The absolute path of a user file (None for library text, which has no file)."""
        if is_library_file(file):
            return None
        return os.path.abspath(file)


def load_debug(paths: "Sequence[str | os.PathLike] | ProjectSpec",
               settings: SysmacSettings | None = None) -> DebugBuild:
    """Parse, check and lower `paths` for debugging (raises LoadError with every diagnostic):
    the project driver's stages (`stvm.project`), lowered with `DEBUG_OPTIONS`. `paths` may be a
    resolved `ProjectSpec`; `settings` given replace the project's own."""
    spec = paths if isinstance(paths, ProjectSpec) else resolve(paths, settings=settings)
    if settings is not None and isinstance(paths, ProjectSpec):
        spec = replace(spec, settings=settings)
    checked = check_stage(parse_stage(spec))
    compiled = compile_stage(checked, DEBUG_OPTIONS)
    analysis, checker, lowered = checked.analysis, checked.checker, compiled.lowered
    texts = checked.parsed.texts
    project = compiled.project()
    unit_pous = {lowered.classes[key]: pou for key, pou in analysis.model.pous.items() if key in lowered.classes}
    user_files = {os.path.normcase(os.path.abspath(name)): name for name, _ in texts}
    user_files.update({os.path.normcase(os.path.realpath(name)): name for name, _ in texts})
    pou_spans = {node.span for node in analysis.pou_nodes.values()}
    unit_methods = {}
    for cls, pou in unit_pous.items():
        for method in pou.methods.values():
            if method.key in analysis.method_nodes:
                unit_methods[(cls, method_attr(method.name))] = (method, analysis.method_nodes[method.key], pou)
        for prop in pou.properties.values():
            for kind, accessor in (("GET", prop.getter), ("SET", prop.setter)):
                if accessor is not None and accessor.key in analysis.method_nodes:
                    unit_methods[(cls, method_attr(prop.name, kind))] = (accessor, analysis.method_nodes[accessor.key], pou)
    # a METHOD's header lines (its frame's set-up) are no statements either
    pou_spans |= {node.span for _, node, _ in unit_methods.values()}
    return DebugBuild(project, analysis, checker, StatementMap.build(lowered.line_map, pou_spans), unit_pous,
                      user_files, unit_methods)
