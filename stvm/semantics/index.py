"""Pass 1 of the checker: the index of every declaration (docs/architecture.md, "Checker passes").

`Indexer.build_index` records each TYPE and POU of all units by its qualified key
(`ns1\\ns2\\name`, lower case) in a `DeclarationIndex`, reporting duplicates and names the dialect
forbids. Nothing is resolved yet: file order and declaration order never matter to the passes after
it, which look names up here (`lookup_type_key`, `lookup_pou_key`).
"""

from __future__ import annotations

from stvm.dialects import known_library_prefix
from stvm.semantics import types as t
from stvm.semantics.context import Pass
from stvm.settings import Dialect
from stvm.source import is_stdlib_file
from stvm.syntax import nodes as n

# Reserved words that the contextual lexer may still let through as names.
_RESERVED = {
    "if", "then", "else", "elsif", "end_if", "case", "of", "end_case", "for", "to", "by", "do", "end_for",
    "while", "end_while", "repeat", "until", "end_repeat", "exit", "continue", "return", "and", "or", "xor",
    "not", "mod", "true", "false", "var", "end_var", "function", "function_block", "program", "type",
    "struct", "array", "constant", "retain",
}

_VENDOR_EXTRAS = {"<stdlib>/twincat_types.st"}   # a dialect's own types, which user code may redeclare


def _is_stdlib(file: str) -> bool:
    return is_stdlib_file(file)


class DeclarationIndex:
    """Every TYPE and POU declaration by key, and the keys of each short name (plain data, plus
    the name lookups every later pass shares)."""

    def __init__(self, dialect: Dialect) -> None:
        self.dialect = dialect   # outside Sysmac a library's namespace may prefix a name
        self.type_decls: dict[str, n.TypeDecl] = {}
        self.pou_nodes: dict[str, n.POU] = {}
        self.short_types: dict[str, list[str]] = {}
        self.short_pous: dict[str, list[str]] = {}

    def lookup_type_key(self, parts: tuple[str, ...], rooted: bool, namespace: tuple[str, ...]) -> str | None:
        if len(parts) > 1 and self.dialect is not Dialect.SYSMAC:
            # `Tc2_System.T_MaxString`: as lookup_pou_key, one place for a library's namespace
            parts = known_library_prefix(parts, lambda p: self._lookup_type_key(p, rooted, namespace) is not None)
        return self._lookup_type_key(parts, rooted, namespace)

    def _lookup_type_key(self, parts: tuple[str, ...], rooted: bool, namespace: tuple[str, ...]) -> str | None:
        key = "\\".join(parts).lower()
        if key in self.type_decls:
            return key
        if not rooted:
            for depth in range(len(namespace), 0, -1):
                cand = "\\".join(namespace[:depth] + parts).lower()
                if cand in self.type_decls:
                    return cand
            if len(parts) == 1:
                # Choice: a short name unique across namespaces resolves (Sysmac resolves
                # library types by short name when unambiguous; ambiguity is an error).
                cands = self.short_types.get(parts[0].lower(), [])
                if len(cands) == 1:
                    return cands[0]
        return None

    def lookup_pou_key(self, parts: tuple[str, ...], namespace: tuple[str, ...]) -> str | None:
        if len(parts) > 1 and self.dialect is not Dialect.SYSMAC:
            # `TcUnit.FB_TestSuite`: a library's namespace, taken off when only the POU is loaded
            parts = known_library_prefix(parts, lambda p: self._lookup_pou_key(p, namespace) is not None)
        return self._lookup_pou_key(parts, namespace)

    def _lookup_pou_key(self, parts: tuple[str, ...], namespace: tuple[str, ...]) -> str | None:
        key = "\\".join(parts).lower()
        if key in self.pou_nodes:
            return key
        for depth in range(len(namespace), 0, -1):
            cand = "\\".join(namespace[:depth] + parts).lower()
            if cand in self.pou_nodes:
                return cand
        if len(parts) == 1:
            cands = self.short_pous.get(parts[0].lower(), [])
            if len(cands) == 1:
                return cands[0]
        return None


class Indexer(Pass):
    """Fills `ctx.index` from the units; checks each declared name (also for the later passes)."""

    def build_index(self) -> None:
        for unit in self.ctx.units:
            for name, span in getattr(unit, "namespace_names", ()):
                self.check_identifier(name, span)
            for decl in unit.types:
                key = "\\".join(decl.namespace + (decl.name,)).lower()
                known = self.ctx.index.type_decls.get(key)
                if known is not None and known.span.file in _VENDOR_EXTRAS and not _is_stdlib(decl.span.file):
                    self.ctx.index.type_decls[key] = decl   # a user declaration shadows a vendor extra
                    continue
                if key in self.ctx.index.type_decls or decl.name.upper() in t.ELEMENTARY:
                    self.error(f"duplicate declaration of type '{decl.name}'", decl.span, "E010")
                    continue
                self.check_identifier(decl.name, decl.span)
                self.ctx.index.type_decls[key] = decl
                self.ctx.index.short_types.setdefault(decl.name.lower(), []).append(key)
            for pou in unit.pous:
                key = "\\".join(pou.namespace + (pou.name,)).lower()
                if key in self.ctx.index.pou_nodes:
                    self.error(f"duplicate declaration of POU '{pou.name}'", pou.span, "E010")
                    continue
                self.ctx.index.pou_nodes[key] = pou
                self.ctx.index.short_pous.setdefault(pou.name.lower(), []).append(key)

    def check_identifier(self, name: str, span: n.Span) -> None:
        if name.lower() in _RESERVED:
            self.error(f"'{name}' is a reserved word and cannot be used as a name", span, "E011")
            return
        if _is_stdlib(span.file):
            return  # system names (`_sSOCKET`, `_CLOSED`) live in the stdlib
        dialect = self.ctx.settings.dialect
        problem = None
        if dialect is Dialect.IEC:
            # IEC 61131-3 ed. 3 6.1.2: letters, digits and single underscores, not at the end
            if "__" in name:
                problem = "may not contain '__' (IEC 61131-3 6.1.2)"
            elif name.endswith("_"):
                problem = "may not end with '_' (IEC 61131-3 6.1.2)"
        elif dialect is not Dialect.SYSMAC:
            return    # CODESYS, TwinCAT: any identifier that is not a keyword
        # sysmac.md 1 (CONFIRMED, W501): rules for user-defined names
        elif name.startswith("_"):
            problem = "may not start with '_' (reserved for system names)"
        elif name.upper().startswith("P_"):
            problem = "may not start with 'P_' (reserved for system-defined variables)"
        elif name.endswith("_"):
            problem = "may not end with '_'"
        elif "__" in name:
            problem = "may not contain '__'"
        elif len(name.encode("utf-8")) > 127:
            problem = "is longer than 127 bytes"
        if problem:
            self.error(f"name '{name[:40]}{'…' if len(name) > 40 else ''}' {problem}", span, "E011")
