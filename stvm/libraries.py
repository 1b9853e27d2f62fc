"""Libraries with namespaces, as TwinCAT 3 and CODESYS use them: a folder of sources (ST files,
TwinCAT XML) or a `.plcproj` loaded as library NAME, whose POUs and types are reachable as
`NAME.X` (and by their short name when unambiguous), e.g. TcUnit: `EXTENDS TcUnit.FB_TestSuite`,
`TcUnit.RUN();`.

Where a library comes from:
- `--library NAME=DIR` on the command line (DIR a folder or a .plcproj file); it replaces the
  manifest's folder for a library of the same name;
- a `[libraries]` table in the project's `stvm.toml`: `NAME = "dir"` (relative to the manifest),
  or a table `[libraries.NAME]` with `path = "dir"` (optional when `--library` names it) and
  `parameters = { NAME = VALUE }`.

Library parameters: TwinCAT and CODESYS libraries declare parameter lists, global constants the
project using the library may set to other values in its library manager (TcUnit's
`GVL_Param_TcUnit.xUnitEnablePublish`, `.MaxNumberOfTestSuites`). stvm sets them from
`[libraries.NAME] parameters` and `--library-param NAME.PARAM=VALUE` (the last one wins): the
initial value of the constant PARAM (or GVL.PARAM) of a `VAR_GLOBAL CONSTANT` block of library
NAME is replaced by VALUE, an ST expression as it would follow `:=` in the declaration (`TRUE`,
`500`, `'out.xml'`, `T#20ms`; in the manifest a TOML boolean or number may stand for itself).
The replacement is made on the syntax tree before the checker runs, so a parameter sizing an
array (`ARRAY[1..MaxNumberOfTestSuites]`) sizes it, as in TwinCAT, where a parameter is a
constant the library is compiled with.

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


def from_manifest(manifest: Mapping, root: Path | None, given: Iterable[str] = ()) -> list[Library]:
    """The `[libraries]` table of a project's stvm.toml: `NAME = "dir"` or `[libraries.NAME]`
    with `path = "dir"`, relative to the manifest. `given`: the names `--library` gives a
    folder (their manifest folder is not used; a table without `path` needs one)."""
    given_keys = {g.lower() for g in given}
    out = []
    for name, (path, _) in _manifest_entries(manifest, root).items():
        if name.lower() in given_keys:
            continue
        if path is None:
            where = f"{Path(root or '.') / 'stvm.toml'}: [libraries.{name}]"
            raise LibraryError(f"{where} has no path: add path = \"folder\" or give --library {name}=DIR")
        out.append(Library(name, path))
    return out


def manifest_parameters(manifest: Mapping, root: Path | None) -> dict[str, dict[str, str]]:
    """{library: {parameter: ST text}} of the manifest's `[libraries.NAME] parameters` tables."""
    return {name: params for name, (_, params) in _manifest_entries(manifest, root).items() if params}


_ENTRY_KEYS = ("path", "parameters")


def _manifest_entries(manifest: Mapping, root: Path | None) -> dict[str, tuple[Path | None, dict[str, str]]]:
    """NAME → (folder or None, {parameter: ST text}) of the `[libraries]` table."""
    table = manifest.get("libraries")
    if table is None:
        return {}
    where = f"{Path(root or '.') / 'stvm.toml'}: [libraries]"
    if not isinstance(table, dict):
        raise LibraryError(f"{where} must be a table of NAME = \"folder\"")
    out: dict[str, tuple[Path | None, dict[str, str]]] = {}
    for name, value in table.items():
        if not _NAME.match(str(name)):
            raise LibraryError(f"{where}: {name!r} is not an identifier (a library's name)")
        params: dict[str, str] = {}
        if isinstance(value, dict):
            extra = sorted(set(value) - set(_ENTRY_KEYS))
            if extra:
                raise LibraryError(f"{where}.{name}: unknown key(s) {', '.join(extra)}; known: path, parameters")
            text = value.get("path")
            if text is not None and (not isinstance(text, str) or not text):
                raise LibraryError(f"{where}.{name}: path must be a folder or a .plcproj (a string)")
            raw = value.get("parameters", {})
            if not isinstance(raw, dict):
                raise LibraryError(f"{where}.{name}: parameters must be a table of PARAM = VALUE")
            for param, given in raw.items():
                params[str(param)] = _parameter_text(given, f"{where}.{name}.parameters: {param}")
        elif isinstance(value, str) and value:
            text = value
        else:
            raise LibraryError(f"{where}: {name} must be set to a folder or a .plcproj (a string), "
                               f"or be a table with path and parameters")
        path = None
        if text is not None:
            path = Path(text)
            path = path if path.is_absolute() else Path(root or ".") / path
        out[str(name)] = (path, params)
    return out


def _parameter_text(value, where: str) -> str:
    """A manifest parameter value as ST text: booleans and numbers as themselves, a string as
    the ST expression it holds."""
    if isinstance(value, bool):
        return "TRUE" if value else "FALSE"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str) and value.strip():
        return value
    raise LibraryError(f"{where} must be a boolean, a number or an ST literal in a string "
                       f"(e.g. \"'results.xml'\", \"T#20ms\")")


def parse_parameter_option(text: str) -> tuple[str, str, str]:
    """`NAME.PARAM=VALUE` (or `NAME.GVL.PARAM=VALUE`) of `--library-param`: (library, param, ST text)."""
    target, sep, value = text.partition("=")
    lib, dot, param = target.strip().partition(".")
    parts = param.split(".") if dot else []
    if not sep or not _NAME.match(lib) or not parts or len(parts) > 2 \
            or not all(_NAME.match(p) for p in parts) or not value.strip():
        raise LibraryError(f"--library-param {text!r}: expected LIB.PARAM=VALUE (e.g. "
                           f"TcUnit.xUnitEnablePublish=TRUE; VALUE an ST literal)")
    return lib, param, value.strip()


class LibrarySpaces(dict):
    """The namespace of each library file by its name, and the library parameters to set
    (`{library: {parameter: ST text}}`): what the driver hands the parser stage."""

    def __init__(self, *args, parameters: Mapping[str, Mapping[str, str]] | None = None) -> None:
        super().__init__(*args)
        self.parameters = {lib: dict(p) for lib, p in (parameters or {}).items() if p}

    def key(self) -> str:
        """What the compile cache keys on (the namespaces and the parameters)."""
        text = "".join(f"|{name}={ns}" for name, ns in sorted(self.items()))
        for lib in sorted(self.parameters, key=str.lower):
            text += "".join(f"|{lib}.{p}:={v}" for p, v in sorted(self.parameters[lib].items()))
        return text


def apply_parameters(units: Sequence[n.CompilationUnit], parameters: Mapping[str, Mapping[str, str]],
                     settings) -> list[n.CompilationUnit]:
    """`units` with each library parameter's initial value replaced (the module docstring).
    Raises LibraryError for a parameter the library does not declare or a value that is not
    an ST expression."""
    from stvm.syntax.parser import parse_expression   # lazy: start-up (parameters are rare)
    wanted: dict[str, dict[str, n.Expr]] = {}
    for lib, params in parameters.items():
        for param, text in params.items():
            expr, diags = parse_expression(text, f"<parameter {lib}.{param}>", settings)
            if expr is None or any(d.is_error for d in diags):
                raise LibraryError(f"library parameter {lib}.{param}: {text!r} is not an ST expression "
                                   f"(a STRING value is quoted: '...')")
            wanted.setdefault(lib.lower(), {})[param.lower()] = expr
    if not wanted:
        return list(units)
    found: set[tuple[str, str]] = set()
    declared: dict[str, list[str]] = {}
    out = []
    for unit in units:
        changed = False
        new_globals = []
        for g in unit.globals:
            lib = g.namespace[0].lower() if g.namespace else ""
            if lib not in wanted or not g.block.constant:
                new_globals.append(g)
                continue
            decls = []
            for decl in g.block.decls:
                init = decl.init
                for name, _ in decl.names:
                    declared.setdefault(lib, []).append(f"{g.gvl}.{name}" if g.gvl else name)
                    for key in (name.lower(), f"{g.gvl}.{name}".lower()):
                        if key in wanted[lib]:
                            if len(decl.names) > 1:
                                raise LibraryError(f"library parameter {key}: declared together with other "
                                                   f"names ({', '.join(x for x, _ in decl.names)}); stvm sets "
                                                   f"only a parameter declared alone")
                            init = n.ExprInit(wanted[lib][key], decl.span)
                            found.add((lib, key))
                if init is not decl.init:
                    decl = dataclasses.replace(decl, init=init)
                    changed = True
                decls.append(decl)
            new_globals.append(dataclasses.replace(g, block=dataclasses.replace(g.block, decls=tuple(decls))))
        out.append(dataclasses.replace(unit, globals=tuple(new_globals)) if changed else unit)
    for lib, params in parameters.items():
        for param in params:
            if (lib.lower(), param.lower()) not in found:
                known = declared.get(lib.lower())
                hint = f"its parameters: {', '.join(known)}" if known else \
                    f"it declares no parameter list (VAR_GLOBAL CONSTANT), or no library {lib} is loaded"
                raise LibraryError(f"library parameter {lib}.{param}: library {lib} has no such parameter ({hint})")
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
    # `Lib.x` besides a POU or type: a global variable of the library, an enumerator of one of
    # its enumerations (`SysFile.AM_READ`, `SysTypes.RTS_INVALID_HANDLE`: CODESYS libraries)
    # An enumerator is reached this way only when exactly one enumeration of Lib has it and that
    # one is not qualified_only (None marks the others), and a POU or type of Lib of the same
    # name wins (TcUnit-Verifier writes `IBaseLibrary.TYPE_BIT`).
    members: dict[tuple[str, str], object] = {}
    declared: set[tuple[str, str]] = set()
    for unit in units:
        for p in unit.pous:
            if p.namespace and p.namespace[-1].lower() in libs:
                declared.add((p.namespace[-1].lower(), p.name.lower()))
        for d in unit.types:
            if d.namespace and d.namespace[-1].lower() in libs:
                declared.add((d.namespace[-1].lower(), d.name.lower()))
            if d.namespace and d.namespace[-1].lower() in libs and isinstance(d.body, n.EnumDecl):
                enums.add((d.namespace[-1].lower(), d.name.lower()))
                strict = has_attribute(d.pragmas, "qualified_only")
                for m in d.body.members:
                    key = (d.namespace[-1].lower(), m[0].lower())
                    members[key] = None if strict or key in members else (d.namespace + (d.name,))
        for g in unit.globals:
            if g.namespace and g.namespace[-1].lower() in libs and g.gvl:
                gvls.add((g.namespace[-1].lower(), g.gvl.lower()))
            if g.namespace and g.namespace[-1].lower() in libs:
                for decl in g.block.decls:
                    for name, _ in decl.names:
                        members[(g.namespace[-1].lower(), name.lower())] = "global"   # a variable wins
    members = {key: found for key, found in members.items()
               if found is not None and (found == "global" or key not in declared)}
    out = []
    for unit in units:
        if not libs & unit.member_bases:
            out.append(unit)
            continue
        pous = tuple(_Qualifier(libs, _locals(p), enums, gvls, members).walk(p) for p in unit.pous)
        rw = _Qualifier(libs, set(), enums, gvls, members)
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
    def __init__(self, libs: set[str], local_names: set[str], enums, gvls, members=None) -> None:
        self.libs = libs - local_names
        self.enums = enums
        self.gvls = gvls
        self.members = members or {}

    def walk(self, obj):
        if isinstance(obj, n.Member):
            obj = self.nested_library(obj)
            if not isinstance(obj, n.Member):
                return obj
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
                found = self.members.get((base.parts[0].lower(), obj.name.lower()))
                if found == "global":      # `Lib.x`: the library's global variable x
                    return n.Name((obj.name,), False, obj.span)
                if isinstance(found, tuple):   # `Lib.member`: the enumerator of Lib's enumeration
                    return n.HashLiteral(found, False, obj.name, obj.span)
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


    def nested_library(self, obj: n.Member):
        """`SysFile.SysTypes.RTS_IEC_HANDLE`, `SysDir.CmpErrors.Errors.ERR_OK`: a library reached
        through another one that references it (CODESYS/TwinCAT); the outer names are dropped."""
        chain = []
        cur = obj
        while isinstance(cur, n.Member):
            chain.append(cur)
            cur = cur.base
        if not (isinstance(cur, n.Name) and len(cur.parts) == 1 and not cur.rooted
                and cur.parts[0].lower() in self.libs and chain and chain[-1].name.lower() in self.libs):
            return obj
        drop = len(chain) - 1    # chain[-1] is `Outer.Inner`
        while drop > 0 and chain[drop - 1].name.lower() in self.libs:
            drop -= 1            # `A.B.C.x` with A, B, C libraries: C.x
        inner = chain[drop]
        out: n.Expr = n.Name((inner.name,), False, inner.span)
        for member in reversed(chain[:drop]):
            out = dataclasses.replace(member, base=out)
        return out


def namespaces(spaces: Mapping[str, str], settings) -> set[str]:
    """The library names `Lib.X` may start with: the project's libraries, and under the twincat
    dialect the platform's namespaces (`IBaseLibrary.TypeClass`, `__SYSTEM.TYPE_CLASS`), under
    codesys those of its type classes and ANY descriptor."""
    names = set(spaces.values())
    if settings.dialect.value == "twincat":
        from stvm.stdlib import TWINCAT_NAMESPACES   # lazy: start-up
        names |= set(TWINCAT_NAMESPACES)
    elif settings.dialect.value == "codesys":
        from stvm.stdlib import CODESYS_NAMESPACES   # lazy: start-up
        names |= set(CODESYS_NAMESPACES)
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
