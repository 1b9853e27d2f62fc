"""Pragmas and attributes (`{…}`): CODESYS and TwinCAT write them anywhere, before declarations,
POUs, variables, inside var blocks and statements (`{attribute 'qualified_only'}`, `{attribute
'hide'}`, `{warning 'text'}`, `{IF defined(X)}`). The lexer drops every one (st.lark `%ignore
PRAGMA`) and hands the tokens to `parse_text`; `attach` gives each POU, type declaration and
global block the pragmas that stand right before it, outside any other element. The ones stvm
gives a meaning are read from there (`{native}` & co. of the stdlib on POUs, `qualified_only` on a
global block or an enumeration, the GVL name a vendor file gives its global block); the rest are
accepted and ignored.
"""

from __future__ import annotations

import bisect
import dataclasses
import re

from stvm.syntax import nodes as n

_ATTRIBUTE = re.compile(r"^\s*attribute\s+'([^']*)'(?:\s*:=\s*'([^']*)')?\s*$", re.I | re.S)


def attribute(pragma: str) -> tuple[str, str] | None:
    """`attribute 'name' := 'value'` → (name lower-cased, value); None for other pragmas."""
    m = _ATTRIBUTE.match(pragma)
    if m is None:
        return None
    return m.group(1).strip().lower(), m.group(2) or ""


def has_attribute(pragmas: tuple[str, ...], name: str) -> bool:
    return any((a := attribute(p)) is not None and a[0] == name for p in pragmas)


def attribute_value(pragmas: tuple[str, ...], name: str) -> str | None:
    for p in pragmas:
        a = attribute(p)
        if a is not None and a[0] == name:
            return a[1]
    return None


def attach(unit: n.CompilationUnit, tokens: list) -> n.CompilationUnit:
    """The unit with each element's leading pragmas (text inside the braces, stripped)."""
    elements: list[tuple[tuple[int, int], tuple[int, int], str, int]] = []
    for kind, items in (("pous", unit.pous), ("types", unit.types), ("globals", unit.globals)):
        for i, item in enumerate(items):
            s = item.span
            elements.append(((s.line, s.column), (s.end_line, s.end_column), kind, i))
    for conf in unit.configurations:
        s = conf.span
        elements.append(((s.line, s.column), (s.end_line, s.end_column), "", -1))
    elements.sort()
    starts = [e[0] for e in elements]
    found: dict[tuple[str, int], list[str]] = {}
    for tok in tokens:
        where = (tok.line, tok.column)
        i = bisect.bisect_left(starts, where)
        if i >= len(elements) or elements[i][3] < 0:
            continue
        if i > 0 and elements[i - 1][1] > where:
            continue      # inside the element before it (a variable's or a statement's pragma)
        found.setdefault((elements[i][2], elements[i][3]), []).append(str(tok)[1:-1].strip())
    if not found and not any(p.methods or p.var_blocks for p in unit.pous):
        return unit

    def with_pragmas(kind: str, items: tuple) -> tuple:
        out = []
        for i, item in enumerate(items):
            extra = found.get((kind, i))
            if kind == "pous" and item.methods:
                item = with_method_pragmas(item, tokens)
            if kind == "pous" and item.var_blocks:
                item = with_variable_pragmas(item, tokens)
            if extra:
                item = dataclasses.replace(item, pragmas=tuple(item.pragmas) + tuple(extra))
                if kind == "globals":
                    gvl = attribute_value(item.pragmas, "gvl")
                    if gvl:
                        item = dataclasses.replace(item, gvl=gvl)
            out.append(item)
        return tuple(out)

    return dataclasses.replace(unit, pous=with_pragmas("pous", unit.pous), types=with_pragmas("types", unit.types),
                               globals=_one_list(with_pragmas("globals", unit.globals)))


def _one_list(blocks: tuple) -> tuple:
    """A global variable list with several VAR_GLOBAL blocks (TcUnit's GVL_TcUnit has a VAR_GLOBAL
    and a VAR_GLOBAL CONSTANT): the pragmas before the first block name the list and its
    `qualified_only`, which hold for every block of it, as in TwinCAT."""
    out, gvl, strict = [], "", ()
    for item in blocks:
        if item.gvl:
            gvl = item.gvl
            strict = tuple(p for p in item.pragmas if attribute(p) == ("qualified_only", ""))
        elif gvl:
            item = dataclasses.replace(item, gvl=gvl, pragmas=tuple(item.pragmas) + strict)
        out.append(item)
    return tuple(out)


def with_method_pragmas(pou, tokens: list):
    """`pou` with each METHOD's leading pragmas (`{attribute 'call_after_init'}` right before
    METHOD): the ones inside the POU with no variable block, statement, method or property
    between them and the method."""
    s = pou.span
    inside = [tok for tok in tokens if (s.line, s.column) < (tok.line, tok.column) < (s.end_line, s.end_column)]
    if not inside:
        return pou
    parts = sorted(((x.span.line, x.span.column), (x.span.end_line, x.span.end_column))
                   for x in (*pou.var_blocks, *pou.body, *pou.methods, *pou.properties))
    methods = []
    for m in pou.methods:
        start = (m.span.line, m.span.column)
        # the end of the last element before the method: a pragma after it belongs to the method
        before = max((end for begin, end in parts if begin < start), default=(s.line, s.column))
        mine = tuple(str(tok)[1:-1].strip() for tok in inside if before <= (tok.line, tok.column) < start)
        methods.append(dataclasses.replace(m, pragmas=tuple(m.pragmas) + mine) if mine else m)
    return dataclasses.replace(pou, methods=tuple(methods))


def with_variable_pragmas(pou, tokens: list):
    """`pou` with each variable declaration's leading pragmas (`{attribute 'instance-path'}` on
    the line before `InstancePath : T_MaxString;`): the ones inside its var block after the
    declaration before it (or the block's keyword)."""
    blocks = []
    changed = False
    for block in pou.var_blocks:
        b = block.span
        inside = [tok for tok in tokens
                  if (b.line, b.column) < (tok.line, tok.column) < (b.end_line, b.end_column)]
        if not inside:
            blocks.append(block)
            continue
        decls, before = [], (b.line, b.column)
        for decl in block.decls:
            start = (decl.span.line, decl.span.column)
            mine = tuple(str(tok)[1:-1].strip() for tok in inside if before <= (tok.line, tok.column) < start)
            decls.append(dataclasses.replace(decl, pragmas=tuple(decl.pragmas) + mine) if mine else decl)
            before = (decl.span.end_line, decl.span.end_column)
        blocks.append(dataclasses.replace(block, decls=tuple(decls)))
        changed = True
    return dataclasses.replace(pou, var_blocks=tuple(blocks)) if changed else pou
