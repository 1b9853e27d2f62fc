"""The position → symbol index of one checked project: built once per check from the syntax
tree's spans and what the checker resolved (`Analysis.facts`), then only read.

A *symbol* is something declared (a variable of a POU or method, a global, a POU, a method, a
property, a type, a struct field, an enumerator); its key is a plain tuple:

    ("var", scope, name)     variable of the POU/METHOD/accessor whose key is `scope`
    ("global", name)         VAR_GLOBAL
    ("pou", key)             FUNCTION, FUNCTION_BLOCK, PROGRAM, INTERFACE, METHOD (key owner.method)
    ("prop", owner, name)    PROPERTY of an FB or interface
    ("type", key)            STRUCT, UNION, enumeration, alias
    ("field", type, name)    member of a STRUCT/UNION
    ("enum", type, name)     enumerator

An *occurrence* is a stretch of one line of one file (0-based line, start and end columns, as
LSP counts them for ASCII text) where the symbol is declared or used. Positions in TwinCAT and
PLCopen XML files are the XML's own: the parser lays the ST out on the XML's lines
(stvm/syntax/vendor_xml.py), so the spans already name them.
"""

from __future__ import annotations

import bisect
import re
from dataclasses import dataclass, field

from stvm.semantics import types as t
from stvm.semantics.model import POUInfo, Variable
from stvm.source import is_stdlib_file
from stvm.syntax import nodes as n
from stvm.syntax.walk import walk

VAR, GLOBAL, POU, PROP, TYPE, FIELD, ENUM = "var", "global", "pou", "prop", "type", "field", "enum"


@dataclass
class Symbol:
    key: tuple
    name: str
    kind: str                 # VAR_INPUT …, VAR_GLOBAL, FUNCTION …, METHOD, PROPERTY, STRUCT, ENUM, FIELD, ENUMERATOR
    file: str
    line: int                 # 0-based, the declared name
    col: int
    end_col: int
    type: t.Type | None = None
    container: str = ""       # the POU, method or type it belongs to (its name)
    pou: POUInfo | None = None
    variable: Variable | None = None
    constant: bool = False
    value: object = None      # enumerator value

    @property
    def stdlib(self) -> bool:
        return is_stdlib_file(self.file)


@dataclass(frozen=True, slots=True)
class Occurrence:
    line: int
    col: int
    end: int
    key: tuple
    decl: bool = False


@dataclass
class Scope:
    """Lines [start, end] (0-based) of a POU, METHOD or property accessor: the variables it sees."""
    start: int
    end: int
    key: str                  # the POUInfo key (`fb.m` for a method)
    pou: POUInfo
    owner: POUInfo | None     # a METHOD's / accessor's FB or interface


@dataclass
class Index:
    symbols: dict[tuple, Symbol] = field(default_factory=dict)
    by_file: dict[str, list[Occurrence]] = field(default_factory=dict)
    refs: dict[tuple, list[tuple[str, Occurrence]]] = field(default_factory=dict)
    scopes: dict[str, list[Scope]] = field(default_factory=dict)
    folds: dict[str, list[tuple[int, int]]] = field(default_factory=dict)
    texts: dict[str, str] = field(default_factory=dict)        # ST text (vendor XML: as ST, on the XML's lines)
    originals: dict[str, str] = field(default_factory=dict)    # the files' own text (the XML), what positions index
    files: list[str] = field(default_factory=list)
    model: object = None
    pou_by_key: dict[str, POUInfo] = field(default_factory=dict)   # every POU, method, accessor
    type_names: dict[str, tuple] = field(default_factory=dict)     # lower-case name → symbol key
    cache: dict = field(default_factory=dict)                      # answers derived once (completion lists)

    # ---- queries ---------------------------------------------------------------------------------

    def at(self, file: str, line: int, col: int) -> Occurrence | None:
        """The occurrence under (line, col): the one starting at or before it and ending after it
        (or right at its end, so a cursor just after a name still finds it)."""
        occs = self.by_file.get(file)
        if not occs:
            return None
        i = bisect.bisect_right(occs, (line, col), key=lambda o: (o.line, o.col))
        best = None
        for o in reversed(occs[max(0, i - 8):i]):
            if o.line == line and o.col <= col <= o.end:
                if best is None or (o.end - o.col) < (best.end - best.col):
                    best = o
        return best

    def scope_at(self, file: str, line: int) -> Scope | None:
        best = None
        for s in self.scopes.get(file, ()):
            if s.start <= line <= s.end and (best is None or s.start >= best.start):
                best = s
        return best

    def references(self, key: tuple) -> list[tuple[str, Occurrence]]:
        return self.refs.get(key, [])

    def pou_info(self, qualname: str) -> POUInfo | None:
        return self.pou_by_key.get(qualname.lower())

    def members(self, ty: t.Type | None, inside: bool = False) -> list[Symbol]:
        """What `x.` offers for a value of type `ty`: an FB's inputs, outputs, in-outs (all its
        variables from inside it), methods and properties, through its bases; an interface's
        methods and properties, through the interfaces it extends; a struct's fields."""
        ty = deref(ty)
        out: list[Symbol] = []
        if isinstance(ty, t.StructType):
            key = ty.qualname.lower()
            for name, _ in ty.fields:
                sym = self.symbols.get((FIELD, key, name.lower()))
                if sym is not None:
                    out.append(sym)
            return out
        if isinstance(ty, (t.FBType, t.InterfaceType)):
            seen: set[str] = set()
            for pou in self.lineage(ty.qualname.lower()):
                for var in pou.variables.values():
                    if var.key in seen or (not inside and var.section not in ("VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT")):
                        continue
                    seen.add(var.key)
                    sym = self.symbols.get((VAR, pou.key, var.key))
                    if sym is not None:
                        out.append(sym)
                for method in pou.methods.values():
                    if method.key.rsplit(".", 1)[-1] not in seen and (inside or method.access == "PUBLIC"):
                        seen.add(method.key.rsplit(".", 1)[-1])
                        sym = self.symbols.get((POU, method.key))
                        if sym is not None:
                            out.append(sym)
                for prop in pou.properties.values():
                    if prop.key not in seen and (inside or prop.access == "PUBLIC"):
                        seen.add(prop.key)
                        sym = self.symbols.get((PROP, pou.key, prop.key))
                        if sym is not None:
                            out.append(sym)
        return out

    def lineage(self, key: str) -> list[POUInfo]:
        """The POU `key`, then its bases (FB EXTENDS) and interfaces, each once."""
        out: list[POUInfo] = []
        todo = [key]
        seen: set[str] = set()
        while todo:
            k = todo.pop(0)
            if k in seen:
                continue
            seen.add(k)
            pou = self.pou_by_key.get(k) or self._short_pou(k)
            if pou is None:
                continue
            out.append(pou)
            if pou.base:
                todo.append(pou.base.lower())
            todo += [i.lower() for i in pou.interfaces]
        return out

    def _short_pou(self, key: str) -> POUInfo | None:
        sym_key = self.type_names.get(key.rsplit("\\", 1)[-1].rsplit(".", 1)[-1])
        if sym_key and sym_key[0] == POU:
            return self.pou_by_key.get(sym_key[1])
        return None

    def type_symbol(self, ty: t.Type | None) -> Symbol | None:
        ty = deref(ty)
        while isinstance(ty, t.ArrayType):
            ty = ty.element
        qual = getattr(ty, "qualname", "")
        if not qual:
            return None
        key = qual.lower()
        return self.symbols.get((POU, key)) or self.symbols.get((TYPE, key))


def deref(ty: t.Type | None) -> t.Type | None:
    while isinstance(ty, t.RefType):
        ty = ty.target
    return ty


_POU_KIND = {"FUNCTION": "FUNCTION", "FUNCTION_BLOCK": "FUNCTION_BLOCK", "PROGRAM": "PROGRAM",
             "INTERFACE": "INTERFACE", "METHOD": "METHOD"}


class _Builder:
    def __init__(self, analysis, texts: dict[str, str], files: list[str], originals: dict[str, str] | None = None) -> None:
        self.a = analysis
        self.facts = analysis.facts
        self.model = analysis.model
        self.ix = Index(texts=texts, originals=dict(originals or {}), files=list(files), model=analysis.model)
        self.by_span: dict[tuple[str, int, int], tuple] = {}
        self.by_var: dict[int, tuple] = {}
        self.user = set(files)
        self.seen: set[tuple] = set()
        self.externals: list[tuple] = []
        self.lines: dict[str, list[str]] = {}

    # ---- symbols from the model ------------------------------------------------------------------

    def add(self, sym: Symbol) -> None:
        self.ix.symbols.setdefault(sym.key, sym)
        if sym.line >= 0:
            self.by_span.setdefault((sym.file, sym.line, sym.col), sym.key)

    def var_symbol(self, scope: POUInfo, var: Variable, key: tuple) -> None:
        sp = var.span
        self.by_var.setdefault(id(var), key)
        self.add(Symbol(key, var.name, var.section, sp.file, sp.line - 1, sp.column - 1,
                        sp.column - 1 + len(var.name), var.type, scope.name, scope, var, var.constant))

    def pou_symbols(self, pou: POUInfo, owner: POUInfo | None = None) -> None:
        self.ix.pou_by_key[pou.key] = pou
        node = self.a.pou_nodes.get(pou.key) if owner is None else self.a.method_nodes.get(pou.key)
        name_span = getattr(node, "name_span", None) if node is not None else None
        sp = name_span if name_span is not None and name_span.line > 0 else pou.span
        if not pou.name.startswith("__"):
            self.add(Symbol((POU, pou.key), pou.name, _POU_KIND.get(pou.kind, pou.kind), sp.file, sp.line - 1,
                            sp.column - 1, sp.column - 1 + len(pou.name), pou.return_type,
                            owner.name if owner is not None else "", pou))
        own = list(pou.variables.values())[pou.inherited:]
        for var in own:
            if var.section == "VAR_EXTERNAL" and var.key in self.model.globals:
                # `VAR_EXTERNAL x` names the global x: its uses are the global's, and renaming
                # the global renames the external declaration with it
                key = (GLOBAL, var.key)
                self.by_var[id(var)] = key
                sp = var.span
                self.by_span.setdefault((sp.file, sp.line - 1, sp.column - 1), key)
                self.externals.append((sp.file, sp.line - 1, sp.column - 1, sp.column - 1 + len(var.name), key))
                continue
            self.var_symbol(pou, var, (VAR, pou.key, var.key))
        for method in pou.methods.values():
            self.pou_symbols(method, pou)
        for prop in pou.properties.values():
            sp = prop.span
            self.add(Symbol((PROP, pou.key, prop.key), prop.name, "PROPERTY", sp.file, sp.line - 1, sp.column - 1,
                            sp.column - 1 + len(prop.name), prop.type, pou.name, None))
            for acc in (prop.getter, prop.setter):
                if acc is not None:
                    self.ix.pou_by_key[acc.key] = acc
                    for var in acc.variables.values():
                        self.var_symbol(acc, var, (VAR, acc.key, var.key))

    def type_symbols(self, unit: n.CompilationUnit) -> None:
        for decl in unit.types:
            key = "\\".join((*decl.namespace, decl.name)).lower()
            sp = decl.span
            body = decl.body
            ty = self.model.structs.get(key) or self.model.enums.get(key)
            kind = ("UNION" if isinstance(body, n.UnionDecl) else "STRUCT" if isinstance(body, n.StructDecl)
                    else "ENUM" if isinstance(body, n.EnumDecl) else "ALIAS")
            self.add(Symbol((TYPE, key), decl.name, kind, sp.file, sp.line - 1, sp.column - 1,
                            sp.column - 1 + len(decl.name), ty, ""))
            self.ix.type_names.setdefault(decl.name.lower(), (TYPE, key))
            if isinstance(body, n.StructDecl):
                for vd in body.fields:
                    for name, nsp in vd.names:
                        fty = ty.field_type(name) if isinstance(ty, t.StructType) else None
                        self.add(Symbol((FIELD, key, name.lower()), name, "FIELD", nsp.file, nsp.line - 1,
                                        nsp.column - 1, nsp.column - 1 + len(name), fty, decl.name))
            elif isinstance(body, n.EnumDecl):
                for name, _, nsp in body.members:
                    value = ty.value_of(name) if isinstance(ty, t.EnumType) else None
                    self.add(Symbol((ENUM, key, name.lower()), name, "ENUMERATOR", nsp.file, nsp.line - 1,
                                    nsp.column - 1, nsp.column - 1 + len(name), ty, decl.name, value=value))

    # ---- occurrences -----------------------------------------------------------------------------

    def occ(self, file: str, line: int, col: int, end: int, key: tuple | None, decl: bool = False) -> None:
        if key is None or line < 0 or col < 0 or end <= col or file not in self.user:
            return
        seen = (file, line, col, key)
        if seen in self.seen:
            return
        self.seen.add(seen)
        o = Occurrence(line, col, end, key, decl)
        self.ix.by_file.setdefault(file, []).append(o)
        self.ix.refs.setdefault(key, []).append((file, o))

    def var_key(self, var: Variable | None) -> tuple | None:
        if var is None:
            return None
        key = self.by_var.get(id(var))
        if key is None:
            sp = var.span
            key = self.by_span.get((sp.file, sp.line - 1, sp.column - 1))
        return key

    def name_at_end(self, span, name: str) -> tuple[int, int, int]:
        """(line, start, end) 0-based of `name` ending where `span` ends (a member, a pin)."""
        end = span.end_column - 1
        return span.end_line - 1, end - len(name), end

    def resolve_type_name(self, parts: tuple[str, ...]) -> tuple | None:
        full = "\\".join(parts).lower()
        if full in self.ix.pou_by_key and (POU, full) in self.ix.symbols:
            return (POU, full)
        if (TYPE, full) in self.ix.symbols:
            return (TYPE, full)
        return self.ix.type_names.get(parts[-1].lower())

    def type_spec(self, spec) -> None:
        if isinstance(spec, n.NamedTypeSpec):
            key = self.resolve_type_name(spec.parts)
            sp = spec.span
            if key is not None and sp.line > 0:
                self.occ(sp.file, *self.name_at_end(sp, spec.parts[-1]), key)
        elif isinstance(spec, n.ArrayTypeSpec):
            self.type_spec(spec.element)
        elif isinstance(spec, n.RefTypeSpec):
            self.type_spec(spec.target)

    def member_key(self, ty: t.Type | None, name: str) -> tuple | None:
        ty = deref(ty)
        low = name.lower()
        if isinstance(ty, t.StructType):
            return (FIELD, ty.qualname.lower(), low)
        if isinstance(ty, (t.FBType, t.InterfaceType)):
            for pou in self.ix.lineage(ty.qualname.lower()):
                if low in pou.variables and list(pou.variables).index(low) >= pou.inherited:
                    return (VAR, pou.key, low)
                if low in pou.methods:
                    return (POU, pou.methods[low].key)
                if low in pou.properties:
                    return (PROP, pou.key, low)
        return None

    def body(self, stmts, scope: POUInfo) -> None:
        names, types, calls, props = self.facts.names, self.facts.types, self.facts.calls, self.facts.props
        for node in walk(stmts):
            cls = node.__class__
            sp = node.span
            if sp.line <= 0:
                continue
            if cls is n.Name:
                ref = names.get(node.nid)
                key = None
                if ref is not None:
                    kind = ref.kind
                    if kind == "enum" and ref.variable is not None and isinstance(ref.variable.type, t.EnumType):
                        key = (ENUM, ref.variable.type.qualname.lower(), node.parts[-1].lower())
                    elif kind in ("pou", "result") and ref.pou is not None:
                        key = self.accessor_property(ref.pou) or (POU, ref.pou.key)
                    elif kind == "result":
                        key = self.accessor_property(scope) or (POU, scope.key)
                    else:
                        key = self.var_key(ref.variable) or (
                            (GLOBAL, node.parts[-1].lower()) if (GLOBAL, node.parts[-1].lower()) in self.ix.symbols else None)
                if key is not None:
                    self.occ(sp.file, *self.name_at_end(sp, node.parts[-1]), key)
            elif cls is n.Member:
                prop = props.get(node.nid)
                if prop is not None:
                    key = (PROP, prop[0].owner, prop[0].key)
                else:
                    key = self.member_key(types.get(node.base.nid), node.name)
                self.occ(sp.file, *self.name_at_end(sp, node.name), key)
            elif cls is n.Call:
                info = calls.get(node.nid)
                if info is None:
                    continue
                callee = node.callee
                if isinstance(callee, n.Name) and callee.nid not in names and callee.span.line > 0:
                    self.occ(callee.span.file, *self.name_at_end(callee.span, callee.parts[-1]), (POU, info.pou.key))
                elif isinstance(callee, n.Member) and info.oo and callee.span.line > 0:
                    self.occ(callee.span.file, *self.name_at_end(callee.span, callee.name), (POU, info.pou.key))
                pins = info.pou
                for arg in node.args:
                    if arg.name and arg.span.line > 0:
                        pin = pins.pin(arg.name)
                        if pin is not None:
                            owner = self._pin_owner(pins, pin)
                            line, col = arg.span.line - 1, arg.span.column - 1
                            if arg.kind == "output_not":
                                col = self._after_not(arg.span, col)
                            self.occ(arg.span.file, line, col, col + len(arg.name), (VAR, owner, pin.key))
            elif cls is n.HashLiteral:
                self.hash_literal(node)

    def source_lines(self, file: str) -> list[str]:
        lines = self.lines.get(file)
        if lines is None:
            text = self.ix.originals.get(file) or self.ix.texts.get(file, "")
            lines = self.lines[file] = text.splitlines()
        return lines

    def accessor_property(self, pou: POUInfo) -> tuple | None:
        """A property's GET/SET (`owner.__get_p`) stands for the property `p` itself."""
        owner, _, name = pou.key.rpartition(".")
        if name.startswith(("__get_", "__set_")):
            return (PROP, owner, name[6:])
        return None

    def _after_not(self, span, col: int) -> int:
        line = self.source_lines(span.file)[span.line - 1:span.line]
        m = re.match(r"NOT\s+", line[0][col:], re.I) if line else None
        return col + (m.end() if m else 0)

    def _pin_owner(self, pou: POUInfo, pin: Variable) -> str:
        for p in self.ix.lineage(pou.key):
            own = list(p.variables)[p.inherited:]
            if pin.key in own:
                return p.key
        return pou.key

    def hash_literal(self, node: n.HashLiteral) -> None:
        sp = node.span
        prefix = node.prefix
        key = self.resolve_type_name(prefix) if prefix else None
        if key is None or key[0] != TYPE:
            return
        lines = self.source_lines(sp.file)
        if sp.line - 1 < len(lines) and sp.line == sp.end_line:
            text = lines[sp.line - 1][sp.column - 1:sp.end_column - 1]
            hash_at = text.rfind("#")
            if hash_at > 0:
                end = sp.column - 1 + hash_at
                self.occ(sp.file, sp.line - 1, end - len(prefix[-1]), end, key)
        member = node.text.rsplit("#", 1)[-1]
        self.occ(sp.file, *self.name_at_end(sp, member), (ENUM, key[1], member.lower()))

    def var_blocks(self, blocks, scope: POUInfo | None) -> None:
        for block in blocks:
            for decl in block.decls:
                self.type_spec(decl.type_spec)
                if decl.init is not None:
                    self.init(decl.init, scope)
            self.fold(block.span)

    def init(self, init, scope) -> None:
        if isinstance(init, n.ExprInit):
            for node in walk([init.expr]):
                if isinstance(node, n.HashLiteral):
                    self.hash_literal(node)
                elif isinstance(node, n.Name) and len(node.parts) == 1 and scope is not None:
                    key = None
                    low = node.parts[0].lower()
                    if low in scope.variables:
                        key = self.var_key(scope.variables[low])
                    elif (GLOBAL, low) in self.ix.symbols:
                        key = (GLOBAL, low)
                    if key is not None:
                        self.occ(node.span.file, *self.name_at_end(node.span, node.parts[0]), key)
        elif isinstance(init, n.ArrayInit):
            for _, item in init.items:
                if item is not None:
                    self.init(item, scope)
        elif isinstance(init, n.StructInit):
            for _, item in init.items:
                self.init(item, scope)

    def fold(self, span, end_span=None) -> None:
        if span.line <= 0:
            return
        end = (end_span.line if end_span is not None and end_span.line > 0 else span.end_line) - 1
        if end > span.line - 1:
            self.ix.folds.setdefault(span.file, []).append((span.line - 1, end))

    def statement_folds(self, stmts) -> None:
        for node in walk(stmts):
            if isinstance(node, (n.If, n.Case, n.For, n.While, n.Repeat)):
                self.fold(node.span)

    def scope(self, file: str, span, end_span, pou: POUInfo, owner: POUInfo | None) -> None:
        if span.line <= 0:
            return
        end = (end_span.line if end_span is not None and end_span.line > 0 else span.end_line) - 1
        self.ix.scopes.setdefault(file, []).append(Scope(span.line - 1, max(end, span.line - 1), pou.key, pou, owner))

    def unit(self, unit: n.CompilationUnit) -> None:
        for decl in unit.types:
            body = decl.body
            self.fold(decl.span)
            if isinstance(body, n.StructDecl):
                for vd in body.fields:
                    self.type_spec(vd.type_spec)
            elif isinstance(body, n.AliasDecl):
                self.type_spec(body.type_spec)
        for gv in unit.globals:
            self.var_blocks([gv.block], None)
        for conf in unit.configurations:
            self.var_blocks(conf.globals, None)
            for res in conf.resources:
                self.var_blocks(res.globals, None)
        for node in unit.pous:
            key = "\\".join((*node.namespace, node.name)).lower()
            pou = self.ix.pou_by_key.get(key)
            if pou is None:
                continue
            file = node.span.file
            self.scope(file, node.span, node.end_span, pou, None)
            self.fold(node.span, node.end_span)
            for ref in (*node.extends, *node.implements):
                target = self.resolve_type_name(ref.parts)
                if target is not None:
                    self.occ(ref.span.file, *self.name_at_end(ref.span, ref.parts[-1]), target)
            self.var_blocks(node.var_blocks, pou)
            if node.return_type is not None:
                self.type_spec(node.return_type)
            self.body(node.body, pou)
            self.statement_folds(node.body)
            for m in node.methods:
                minfo = pou.methods.get(m.name.lower())
                if minfo is None:
                    continue
                self.scope(file, m.span, None, minfo, pou)
                self.fold(m.span)
                self.var_blocks(m.var_blocks, minfo)
                if m.return_type is not None:
                    self.type_spec(m.return_type)
                self.body(m.body, minfo)
                self.statement_folds(m.body)
            for p in node.properties:
                pinfo = pou.properties.get(p.name.lower())
                self.type_spec(p.type_spec)
                self.fold(p.span)
                if pinfo is None:
                    continue
                for acc_node, acc in ((p.getter, pinfo.getter), (p.setter, pinfo.setter)):
                    if acc_node is None or acc is None:
                        continue
                    self.scope(file, acc_node.span, None, acc, pou)
                    self.var_blocks(acc_node.var_blocks, acc)
                    self.body(acc_node.body, acc)

    def build(self) -> Index:
        model = self.model
        for pou in model.pous.values():
            self.pou_symbols(pou)
        for var in model.globals.values():
            key = (GLOBAL, var.key)
            sp = var.span
            self.by_var.setdefault(id(var), key)
            self.add(Symbol(key, var.name, "VAR_GLOBAL", sp.file, sp.line - 1, sp.column - 1,
                            sp.column - 1 + len(var.name), var.type, "", None, var, var.constant))
        for pou in model.pous.values():
            if pou.kind in ("FUNCTION_BLOCK", "PROGRAM", "INTERFACE", "FUNCTION"):
                self.ix.type_names.setdefault(pou.name.lower(), (POU, pou.key))
        for unit in self.a.units:
            self.type_symbols(unit)
        # every declaration is an occurrence of its symbol (declarations are found by rename and
        # references like the uses)
        for sym in self.ix.symbols.values():
            if sym.file in self.user:
                self.occ(sym.file, sym.line, sym.col, sym.end_col, sym.key, decl=True)
        for file, line, col, end, key in self.externals:
            self.occ(file, line, col, end, key)
        for unit in self.a.units:
            if unit.path in self.user:
                self.unit(unit)
        for occs in self.ix.by_file.values():
            occs.sort(key=lambda o: (o.line, o.col, -o.end))
        for file, folds in self.ix.folds.items():
            self.ix.folds[file] = sorted(set(folds))
        return self.ix


def build_index(analysis, texts: dict[str, str], files: list[str], originals: dict[str, str] | None = None) -> Index:
    """The index of a checked project; `files` are the user's (their uses are indexed; the
    stdlib's declarations are symbols, its bodies are not walked)."""
    return _Builder(analysis, texts, files, originals).build()
