"""Libraries with namespaces, as TwinCAT 3 and CODESYS use them: a folder of sources (ST files,
TwinCAT XML) or a `.plcproj` loaded as library NAME, whose POUs and types are reachable as
`NAME.X` (and by their short name when unambiguous), e.g. TcUnit: `EXTENDS TcUnit.FB_TestSuite`,
`TcUnit.RUN();`.

Where a library comes from:
- `--library NAME=DIR` on the command line (DIR a folder or a .plcproj file);
- a `[libraries]` table in the project's `stvm.toml`: `NAME = "dir"` (relative to the manifest).

How it works: every declaration of a library file is put into the namespace NAME (the same
namespaces Sysmac's `NAMESPACE … END_NAMESPACE` makes, semantics/checker.py resolves names in
them), and every dotted access whose first name is a library's (`TcUnit.RUN`,
`TcUnit.GVL_Param_TcUnit.MaxNumberOfTestSuites`) is rewritten into the qualified name the checker
resolves (`TcUnit\\RUN`), before the checker runs. Global variables stay global (a library's GVL
is reached as `GVL.x`, with `{attribute 'qualified_only'}` honoured by semantics/qualified.py).
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Mapping, Sequence

from stvm.syntax import nodes as n
from stvm.syntax.pragmas import has_attribute

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


class LibraryError(ValueError):
    """A library that cannot be used: a bad `NAME=DIR`, a missing folder, nothing to load."""


@dataclass(frozen=True)
class Library:
    name: str
    path: Path


def parse_option(text: str) -> Library:
    """`NAME=DIR` of `--library`."""
    name, sep, path = text.partition("=")
    name, path = name.strip(), path.strip()
    if not sep or not _NAME.match(name) or not path:
        raise LibraryError(f"--library {text!r}: expected NAME=DIR (NAME an identifier, DIR a folder or a .plcproj)")
    return Library(name, Path(path))


def from_manifest(manifest: Mapping, root: Path | None) -> list[Library]:
    """The `[libraries]` table of a project's stvm.toml: `NAME = "dir"`, relative to the manifest."""
    table = manifest.get("libraries")
    if table is None:
        return []
    where = f"{Path(root or '.') / 'stvm.toml'}: [libraries]"
    if not isinstance(table, dict):
        raise LibraryError(f"{where} must be a table of NAME = \"folder\"")
    out = []
    for name, value in table.items():
        if not _NAME.match(str(name)) or not isinstance(value, str) or not value:
            raise LibraryError(f"{where}: {name} must be an identifier set to a folder or a .plcproj (a string)")
        path = Path(value)
        out.append(Library(str(name), path if path.is_absolute() else Path(root or ".") / path))
    return out


def library_files(lib: Library) -> list[Path]:
    """The source files of a library: a .plcproj's compile items; a folder's .plcproj (the first
    one found), else its .st files and its TwinCAT/PLCopen XML sources."""
    from stvm.syntax.vendor_xml import folder_sources, plcproj_items   # lazy: vendor XML only
    path = lib.path
    if path.is_file() and path.suffix.lower() == ".plcproj":
        files = plcproj_items(path)
    elif path.is_dir():
        projects = sorted(path.glob("*.plcproj")) or sorted(path.glob("*/*.plcproj"))
        if projects:
            files = plcproj_items(projects[0])
        else:
            # a folder mixing .st files and TwinCAT XML (a GVL kept as .TcGVL for its name): both
            files = sorted(p for p in path.rglob("*.st") if p.is_file()) + list(folder_sources(path))
    else:
        raise LibraryError(f"library {lib.name}: {path} is neither a folder nor a .plcproj file")
    if not files:
        raise LibraryError(f"library {lib.name}: no sources in {path} (.st, TwinCAT XML or a .plcproj)")
    return list(files)


def namespaced(unit: n.CompilationUnit, name: str) -> n.CompilationUnit:
    """`unit` with every POU and type declared in namespace `name` (globals stay global)."""
    prefix = (name,)
    pous = tuple(dataclasses.replace(p, namespace=prefix + p.namespace) for p in unit.pous)
    types = tuple(dataclasses.replace(d, namespace=prefix + d.namespace) for d in unit.types)
    globals_ = tuple(dataclasses.replace(g, namespace=prefix + g.namespace) for g in unit.globals)
    return dataclasses.replace(unit, pous=pous, types=types, globals=globals_)


def qualify(units: Sequence[n.CompilationUnit], names: Iterable[str]) -> list[n.CompilationUnit]:
    """Rewrite `Lib.X` (a member access on a library's name, which no variable of the POU
    shadows) into the qualified name `Lib\\X` in every unit that mentions a library."""
    libs = {x.lower() for x in names}
    if not libs:
        return list(units)
    # what `Lib.X.y` can be besides a POU or type: an enumerator, a GVL's variable
    enums: set[tuple[str, str]] = set()
    gvls: set[tuple[str, str]] = set()
    # `Lib.member` without the enumeration's name (TcUnit-Verifier: `IBaseLibrary.TYPE_BIT`): the
    # enumerator of the one enumeration of Lib that has it, unless that one is qualified_only or
    # Lib declares something else of that name (a POU, type or variable wins, as before)
    members: dict[tuple[str, str], tuple[str, str] | None] = {}
    declared: set[tuple[str, str]] = set()
    for unit in units:
        for d in unit.types:
            if d.namespace and d.namespace[0].lower() in libs:
                lib = d.namespace[0].lower()
                declared.add((lib, d.name.lower()))
                if isinstance(d.body, n.EnumDecl):
                    enums.add((lib, d.name.lower()))
                    strict = has_attribute(d.pragmas, "qualified_only")
                    for member in d.body.members:
                        key = (lib, member[0].lower())
                        # None: ambiguous (two enumerations) or reachable only with its type's name
                        members[key] = None if strict or key in members else (d.namespace[0], d.name)
        for p in unit.pous:
            if p.namespace and p.namespace[0].lower() in libs:
                declared.add((p.namespace[0].lower(), p.name.lower()))
        for g in unit.globals:
            if g.namespace and g.namespace[0].lower() in libs:
                if g.gvl:
                    gvls.add((g.namespace[0].lower(), g.gvl.lower()))
                    declared.add((g.namespace[0].lower(), g.gvl.lower()))
                declared.update((g.namespace[0].lower(), name.lower()) for decl in g.block.decls for name, _ in decl.names)
    enumerators = {key: enum for key, enum in members.items() if enum is not None and key not in declared}
    out = []
    for unit in units:
        if not libs & unit.member_bases:
            out.append(unit)
            continue
        pous = tuple(_Qualifier(libs, _locals(p), enums, gvls, enumerators).walk(p) for p in unit.pous)
        rw = _Qualifier(libs, set(), enums, gvls, enumerators)
        out.append(dataclasses.replace(unit, pous=pous, types=tuple(rw.walk(d) for d in unit.types),
                                       globals=tuple(rw.walk(g) for g in unit.globals)))
    return out


def _locals(pou: n.POU) -> set[str]:
    names = {name.lower() for b in pou.var_blocks for d in b.decls for name, _ in d.names}
    for m in pou.methods:
        names |= {name.lower() for b in m.var_blocks for d in b.decls for name, _ in d.names}
    return names


_LEAVES = (str, int, float, bool, bytes, type(None), n.Span)


class _Qualifier:
    def __init__(self, libs: set[str], local_names: set[str], enums, gvls, enumerators) -> None:
        self.libs = libs - local_names
        self.enums = enums
        self.gvls = gvls
        self.enumerators = enumerators   # (lib, enumerator) lower -> (lib, enumeration) as declared

    def walk(self, obj):
        if isinstance(obj, n.Member):
            base = obj.base
            inner = base.base if isinstance(base, n.Member) else None
            if isinstance(inner, n.Name) and len(inner.parts) == 1 and not inner.rooted \
                    and inner.parts[0].lower() in self.libs:
                pair = (inner.parts[0].lower(), base.name.lower())
                if pair in self.enums:     # `Lib.E_Enum.member`: the enumerator
                    return n.HashLiteral((inner.parts[0], base.name), False, obj.name, obj.span)
                if pair in self.gvls:      # `Lib.GVL.x`: the GVL's variable (semantics/qualified.py)
                    return dataclasses.replace(obj, base=n.Name((base.name,), False, base.span))
            if isinstance(base, n.Name) and len(base.parts) == 1 and not base.rooted \
                    and base.parts[0].lower() in self.libs:
                enum = self.enumerators.get((base.parts[0].lower(), obj.name.lower()))
                if enum is not None:       # `Lib.member`: the enumerator of Lib's one enumeration with it
                    return n.HashLiteral(enum, False, obj.name, obj.span)
                return n.Name((base.parts[0], obj.name), False, obj.span)
            new = self.walk(base)
            return obj if new is base else dataclasses.replace(obj, base=new)
        if isinstance(obj, tuple):
            items = [self.walk(x) for x in obj]
            return obj if all(a is b for a, b in zip(items, obj)) else tuple(items)
        if isinstance(obj, _LEAVES) or not isinstance(obj, n.Node):
            return obj
        changes = {}
        for f in dataclasses.fields(obj):
            if not f.init or f.name == "span":
                continue
            value = getattr(obj, f.name)
            if isinstance(value, _LEAVES):
                continue
            new = self.walk(value)
            if new is not value:
                changes[f.name] = new
        return dataclasses.replace(obj, **changes) if changes else obj


def namespaces(spaces: Mapping[str, str], settings) -> set[str]:
    """The library names `Lib.X` may start with: the project's libraries, and under the twincat
    dialect the platform's namespaces (`IBaseLibrary.TypeClass`, `__SYSTEM.TYPE_CLASS`)."""
    names = set(spaces.values())
    if settings.dialect.value == "twincat":
        from stvm.stdlib import TWINCAT_NAMESPACES   # lazy: start-up
        names |= set(TWINCAT_NAMESPACES)
    return names


def read_libraries(libraries: Sequence[Library], read_files, encoding: str = "utf-8"):
    """(texts, namespace of each library file by its name, diagnostics) of `libraries`, read with
    the driver's `read_files` (stvm.project: it imports this module, so it hands its reader in)."""
    texts: list[tuple[str, str]] = []
    spaces: dict[str, str] = {}
    diags = []
    seen: set[str] = set()
    for lib in libraries:
        if lib.name.lower() in seen:
            raise LibraryError(f"library {lib.name} is given twice")
        seen.add(lib.name.lower())
        files = library_files(lib)
        t, d = read_files(files, encoding)
        texts += t
        diags += d
        spaces.update({name: lib.name for name, _ in t})
    return texts, spaces, diags
