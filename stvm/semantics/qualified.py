"""Qualified names of CODESYS/TwinCAT: `GVL_Main.nSpeed` (a variable of a named global variable
list) and `E_State.eIdle` (an enumerator written with its type and a dot), and the attribute
`{attribute 'qualified_only'}` that makes them the only way in.

Run before the checker, over the user's units: `GVL.x` becomes the global `x`, `Enum.member` the
enumerator literal `Enum#member`; with `qualified_only` on the GVL (the attribute before its
VAR_GLOBAL) or on the enumeration (before its TYPE or its name), an unqualified use is a
diagnostic. Names a POU declares itself shadow both. The pass walks the trees only when there is
something to find (a named GVL, an enumeration or the attribute), and rebuilds only the nodes
it changes.
"""

from __future__ import annotations

import dataclasses

from stvm.diagnostics import Diagnostic
from stvm.syntax import nodes as n
from stvm.source import is_stdlib_file
from stvm.syntax.pragmas import has_attribute


class _Scope:
    def __init__(self) -> None:
        self.gvls: dict[str, tuple[str, set[str]]] = {}       # gvl lower -> (name, variable names lower)
        self.enums: dict[str, tuple[str, set[str]]] = {}      # enum type lower -> (name, members lower)
        self.strict_globals: dict[str, str] = {}               # variable lower -> its GVL's name
        self.loose_globals: set[str] = set()
        self.strict_members: dict[str, str] = {}               # enumerator lower -> its type's name
        self.loose_members: set[str] = set()


def _collect(units: list[n.CompilationUnit]) -> _Scope:
    scope = _Scope()
    for unit in units:
        for g in unit.globals:
            names = {name.lower() for d in g.block.decls for name, _ in d.names}
            strict = has_attribute(g.pragmas, "qualified_only") and bool(g.gvl)
            if g.gvl:
                known = scope.gvls.setdefault(g.gvl.lower(), (g.gvl, set()))
                known[1].update(names)
            for name in names:
                if strict:
                    scope.strict_globals.setdefault(name, g.gvl)
                else:
                    scope.loose_globals.add(name)
        for decl in unit.types:
            if isinstance(decl.body, n.EnumDecl):
                members = {m[0].lower() for m in decl.body.members}
                scope.enums.setdefault(decl.name.lower(), (decl.name, members))
                strict = has_attribute(decl.pragmas, "qualified_only") and not is_stdlib_file(decl.span.file)
                for member in members:
                    if strict:
                        scope.strict_members.setdefault(member, decl.name)
                    else:
                        scope.loose_members.add(member)
    return scope


def resolve(units: list[n.CompilationUnit]) -> tuple[list[n.CompilationUnit], list[Diagnostic]]:
    """The units with qualified names resolved, and the diagnostics of `qualified_only`."""
    user = [u for u in units if not is_stdlib_file(u.path)]
    # a platform library's enumeration (TcEventSeverity.Error) is reached the same way: a user unit
    # naming one with a dot is walked even when the user declares no enumeration of its own
    bases = set().union(*(u.member_bases for u in user)) if user else set()
    if not any(g.gvl for u in user for g in u.globals) and \
            not any(isinstance(d.body, n.EnumDecl) for u in user for d in u.types) and \
            not any(isinstance(d.body, n.EnumDecl) and d.name.lower() in bases for u in units for d in u.types):
        return units, []
    scope = _collect(units)
    qualifiers = set(scope.gvls) | set(scope.enums)
    strict = bool(scope.strict_globals or scope.strict_members)
    diagnostics: list[Diagnostic] = []
    out = []
    for unit in units:
        # a unit is walked only if it may name a GVL or an enum with a dot, or if an unqualified
        # name may break a qualified_only rule
        if is_stdlib_file(unit.path) or not (strict or qualifiers & unit.member_bases):
            out.append(unit)
            continue
        pous = tuple(_Rewriter(scope, _locals(p), diagnostics).pou(p) for p in unit.pous)
        rw = _Rewriter(scope, set(), diagnostics)
        types = tuple(rw.walk(d) for d in unit.types)
        globals_ = tuple(rw.walk(g) for g in unit.globals)
        out.append(dataclasses.replace(unit, pous=pous, types=types, globals=globals_))
    return out, diagnostics


def _locals(pou: n.POU | n.Method | n.Property | n.Accessor) -> set[str]:
    names = {name.lower() for b in pou.var_blocks if b.kind != "VAR_EXTERNAL" for d in b.decls for name, _ in d.names}
    if not isinstance(pou, n.Accessor):
        names.add(pou.name.lower())
    return names


_LEAVES = {str, int, float, bool, bytes, type(None), n.Span, n.IntLiteral, n.RealLiteral, n.BoolLiteral,
           n.StringLiteral, n.TimeLiteral, n.HashLiteral}
_FIELDS: dict[type, tuple[str, ...]] = {}


def _fields_of(cls: type) -> tuple[str, ...]:
    names = _FIELDS.get(cls)
    if names is None:
        names = _FIELDS[cls] = tuple(f.name for f in dataclasses.fields(cls) if f.init and f.name != "span")
    return names


class _Rewriter:
    def __init__(self, scope: _Scope, local_names: set[str], diagnostics: list[Diagnostic]) -> None:
        self.scope = scope
        self.check_names = bool(scope.strict_globals or scope.strict_members)
        self.locals = local_names
        self.diagnostics = diagnostics

    def pou(self, pou: n.POU) -> n.POU:
        # VAR_EXTERNAL x names the global x: unqualified on purpose, like a declaration
        self.externals = {name.lower() for b in pou.var_blocks if b.kind == "VAR_EXTERNAL"
                          for d in b.decls for name, _ in d.names}
        return self.walk(pou)

    externals: set[str] = set()

    def walk(self, obj):
        cls = type(obj)
        if cls is n.Member:
            return self.member(obj)
        if cls is n.Name:
            if self.check_names:
                self.name(obj)
            return obj
        if cls is tuple:
            out = None
            for i, x in enumerate(obj):
                if type(x) in _LEAVES:
                    continue
                y = self.walk(x)
                if y is not x:
                    if out is None:
                        out = list(obj)
                    out[i] = y
            return obj if out is None else tuple(out)
        if cls in _LEAVES or not isinstance(obj, n.Node):
            return obj
        if cls is n.Method or cls is n.Property or cls is n.Accessor:
            # a METHOD's or property's own variables shadow an enumerator or a GVL variable of the
            # same name inside it, as the POU's do (TcUnit: a method output `Error` beside the
            # qualified_only enumerator E_XmlError.Error)
            outer = self.locals
            self.locals = outer | _locals(obj)
            try:
                return self.fields(obj, cls)
            finally:
                self.locals = outer
        return self.fields(obj, cls)

    def fields(self, obj, cls):
        changes = None
        for name in _fields_of(cls):
            value = getattr(obj, name)
            if type(value) in _LEAVES:
                continue
            new = self.walk(value)
            if new is not value:
                if changes is None:
                    changes = {}
                changes[name] = new
        return dataclasses.replace(obj, **changes) if changes else obj

    def member(self, e: n.Member):
        base = e.base
        if isinstance(base, n.Name) and len(base.parts) == 1 and not base.rooted:
            first = base.parts[0].lower()
            if first not in self.locals:
                gvl = self.scope.gvls.get(first)
                if gvl is not None and e.name.lower() in gvl[1]:
                    if e.name.lower() in self.locals:
                        self.diagnostics.append(Diagnostic.error(
                            f"'{e.name}' of {gvl[0]} is hidden here by a local '{e.name}' (stvm reaches a "
                            f"global list's variables by their own name; rename the local)", e.span, "E057"))
                    return n.Name((e.name,), False, e.span)
                enum = self.scope.enums.get(first)
                if enum is not None and e.name.lower() in enum[1]:
                    return n.HashLiteral((base.parts[0],), False, e.name, e.span)
        new_base = self.walk(base)
        return e if new_base is base else dataclasses.replace(e, base=new_base)

    def name(self, e: n.Name) -> None:
        if len(e.parts) != 1 or e.rooted:
            return
        key = e.parts[0].lower()
        if key in self.locals or key in self.externals:
            return
        gvl = self.scope.strict_globals.get(key)
        if gvl is not None and key not in self.scope.loose_globals:
            self.diagnostics.append(Diagnostic.error(
                f"'{e.parts[0]}' is in the global variable list {gvl}, which is "
                f"{{attribute 'qualified_only'}}: write {gvl}.{e.parts[0]}", e.span, "E057"))
            return
        enum = self.scope.strict_members.get(key)
        if enum is not None and key not in self.scope.loose_members and key not in self.scope.loose_globals:
            self.diagnostics.append(Diagnostic.error(
                f"'{e.parts[0]}' is an enumerator of {enum}, which is {{attribute 'qualified_only'}}: "
                f"write {enum}.{e.parts[0]} (or {enum}#{e.parts[0]})", e.span, "E057"))
