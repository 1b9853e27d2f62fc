"""`stvm check --emit-python`: the Python stvm generates for each POU, beside the ST line each
generated line comes from.

For a user who wants to see what a statement became (integer wrapping, REAL rounding, hoisted
bounds checks, inlined FB calls) and for bug reports: the listing names the generated line
numbers a runtime fault or a Python traceback of stvm would name, and the ST `file:line` of each.

The generated module is one Python source; each POU is one top-level `class` (PROGRAM,
FUNCTION_BLOCK with its METHODs, STRUCT) or `def` (FUNCTION), and the globals are one class
(`G_globals`). A unit runs from its `class`/`def` line to the next one. Lines of glue (class
headers, `__init__`, native FB wrappers) have no ST line and show an empty column.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass
from typing import Iterable

from stvm.lower.product import LoweredProject

_UNIT_START = re.compile(r"(?:class|def) ([A-Za-z_][A-Za-z0-9_]*)")


@dataclass(frozen=True)
class Unit:
    """One top-level class or function of the generated module."""

    python_name: str     # `P502_main`
    key: str             # the POU/STRUCT key (lower-case qualname), "" for the globals class
    first: int           # first generated line (1-based)
    last: int            # last generated line


def units(lowered: LoweredProject) -> list[Unit]:
    """The top-level units of the generated module, in module order."""
    keys = {python: key for key, python in lowered.classes.items()}
    lines = lowered.source.splitlines()
    starts: list[tuple[int, str]] = []
    for number, line in enumerate(lines, 1):
        match = _UNIT_START.match(line)
        if match is not None:
            starts.append((number, match.group(1)))
    out = []
    for index, (first, name) in enumerate(starts):
        last = starts[index + 1][0] - 1 if index + 1 < len(starts) else len(lines)
        key = keys.get(name, "" if name == lowered.globals_class else None)
        if key is not None:
            out.append(Unit(name, key, first, last))
    return out


def _where(file: str, line: int) -> str:
    """`file:line` with the file relative to the working folder when it is below it."""
    if not file.startswith("<") and os.path.isabs(file):
        try:
            relative = os.path.relpath(file)
        except ValueError:   # another drive (Windows)
            relative = file
        if not relative.startswith(".."):
            file = relative
    return f"{file}:{line}"


def render(lowered: LoweredProject, chosen: Iterable[Unit], titles: dict[str, str]) -> str:
    """The listing of `chosen` units: a title line per unit (`titles[key]`), then each generated
    line as `NUMBER  ST-FILE:LINE  | code`."""
    lines = lowered.source.splitlines()
    chosen = list(chosen)
    rows: list[tuple[int, str, str]] = []
    for unit in chosen:
        for number in range(unit.first, unit.last + 1):
            span = lowered.line_map.span_at(number)
            rows.append((number, _where(span.file, span.line) if span is not None else "", lines[number - 1]))
    width = max((len(where) for _, where, _ in rows), default=0)
    digits = len(str(max((number for number, _, _ in rows), default=1)))
    out: list[str] = []
    row = 0
    for unit in chosen:
        out.append(f"# {titles.get(unit.key, unit.python_name)}: generated lines {unit.first}-{unit.last}")
        for _ in range(unit.first, unit.last + 1):
            number, where, code = rows[row]
            row += 1
            out.append(f"{number:>{digits}}  {where:<{width}}  | {code}".rstrip())
        out.append("")
    return "\n".join(out)


def select(lowered: LoweredProject, analysis, files: Iterable[str], names: Iterable[str] = ()) -> tuple[list[Unit], dict[str, str]]:
    """The units to list and their titles: those named (`--pou`, case-insensitive, the stdlib's
    too), else every POU, STRUCT and the globals the project's own `files` declare."""
    model = analysis.model
    own = {os.path.normcase(os.path.abspath(f)) for f in files if not f.startswith("<")}

    def declared_here(file: str) -> bool:
        return not file.startswith("<") and os.path.normcase(os.path.abspath(file)) in own

    own_types: set[str] = set()
    own_globals = False
    for unit in analysis.units:
        if declared_here(unit.path):
            for decl in unit.types:
                own_types.add(decl.name.lower())
                own_types.add(".".join(decl.namespace + (decl.name,)).lower())
            own_globals = own_globals or bool(unit.globals)
    wanted = {name.lower() for name in names}
    chosen: list[Unit] = []
    titles: dict[str, str] = {}
    for unit in units(lowered):
        pou = model.pous.get(unit.key)
        if pou is not None:
            title = f"{pou.kind} {pou.qualname}"
            if pou.span.file:
                title += f" ({_where(pou.span.file, pou.span.line)})"
            name, mine = pou.qualname, declared_here(pou.span.file or pou.file)
        elif unit.key:
            struct = model.structs.get(unit.key)
            name = getattr(struct, "qualname", "") or unit.key
            title, mine = f"TYPE {name} (STRUCT)", unit.key in own_types
        else:
            name, title, mine = "VAR_GLOBAL", "VAR_GLOBAL (every global variable)", own_globals
        titles[unit.key] = f"{title} -> {unit.python_name}"
        if (name.lower() in wanted or unit.key in wanted) if wanted else mine:
            chosen.append(unit)
    return chosen, titles
