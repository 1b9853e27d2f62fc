"""The pipeline driver: files → parse → check → lower → compile, with a content-hash cache.

`check(paths)` stops after the checker; `load(paths)` returns a runnable `Project` or raises
`LoadError` carrying every diagnostic. A cache entry (keyed by stvm's version, the settings and
the text of every file including the stdlib) holds the lowered module and the model, so a
repeated load skips parsing, checking and code generation.
"""

from __future__ import annotations

import hashlib
import marshal
import os
import pickle
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from stvm.records import FACTORY, Record
from stvm.version import __version__
from stvm.diagnostics import Diagnostic, has_errors, render, sort_key
from stvm.manifest import MANIFEST, ManifestError, project_files, read_manifest  # noqa: F401 (API)
from stvm.heap import collector_paused
from stvm.settings import DEFAULT_SETTINGS, SysmacSettings
from stvm.source import SourceError, Span, read_source

if TYPE_CHECKING:
    from stvm.cache import SignedCache
    from stvm.lower import LoweredProject
    from stvm.lower.options import LowerOptions
    from stvm.runtime.vm import VM
    from stvm.semantics.model import ProjectModel

# The front end (Lark, the checker, the code generator) is imported only on a cache miss: a
# cached load needs none of it, which halves the start-up time of `stvm run`.


class LoadError(Exception):
    """The ST sources have errors; `diagnostics` holds all of them."""

    def __init__(self, diagnostics: list[Diagnostic], sources: dict[str, str]) -> None:
        super().__init__(f"{sum(d.is_error for d in diagnostics)} error(s)")
        self.diagnostics = diagnostics
        self.sources = sources

    def render(self) -> str:
        return "".join(render(d, self.sources) for d in self.diagnostics)


# Project, Parsed, Checked and Compiled behave as the dataclasses they were (`__init__`, `==` over
# every field, `repr`, unhashable, the `__dict__` pickle stores) but are `stvm.records` classes
# (`__init__` written out, the rest derived from `_FIELDS`): `dataclass`
# builds a class's methods with `exec` at import, a cost of every `stvm run` (issue 33 item 5;
# tests/project/test_project_records.py compares them). Options and ProjectSpec stay dataclasses
# (callers `dataclasses.replace` them).


class Project(Record):
    """A loaded project: its model, its lowered code and what a run or a check needs beside.

    `code`: the generated module's code objects, run in order (lower.product.compile_module);
    `native_modules`: the stdlib modules implementing the natives it calls; `natives_known`:
    native_modules is complete (a cached load), import only those; `files_root`: `--files-root`,
    the SysFile folder (stdlib/sys_file.py). Written out, not a dataclass (see stvm/records.py)."""

    _FIELDS = ('model', 'lowered', 'code', 'sources', 'settings', 'warnings', 'from_cache', 'manifest', 'root', 'native_modules', 'natives_known', 'files_root')

    def __init__(self, model: ProjectModel, lowered: LoweredProject, code: tuple, sources: dict[str, str],
                 settings: SysmacSettings, warnings: list[Diagnostic] = FACTORY, from_cache: bool = False,
                 manifest: dict = FACTORY, root: Path | None = None, native_modules: tuple[str, ...] = (),
                 natives_known: bool = False, files_root: str | None = None) -> None:
        self.model = model
        self.lowered = lowered
        self.code = code
        self.sources = sources
        self.settings = settings
        self.warnings = [] if warnings is FACTORY else warnings
        self.from_cache = from_cache
        self.manifest = {} if manifest is FACTORY else manifest
        self.root = root
        self.native_modules = native_modules
        self.natives_known = natives_known
        self.files_root = files_root

    def start(self, scan: str | int = "10ms", realtime: bool = False, start_dt_ns: int = 0,
              transport=None) -> "VM":
        """A fresh VM for this project (all variables at their initial values)."""
        from stvm.runtime.vm import VM   # lazy: start-up (`stvm check` never runs a VM)
        from stvm.stdlib import natives_for   # lazy: start-up (`import stvm.project`)
        scan_ns = parse_duration(scan) if isinstance(scan, str) else int(scan)
        functions, fbs = natives_for(self)   # only the stdlib modules the program calls, when cached
        vm = VM(self, scan_ns=scan_ns, realtime=realtime, start_dt_ns=start_dt_ns, transport=transport,
                natives=functions, native_fbs=fbs)
        if self.settings.dialect.value == "twincat":   # TwinCAT_SystemInfoVarList (stdlib/tc2_system.py)
            from stvm.stdlib.tc2_system import install_system_info   # lazy: twincat projects only
            from stvm.stdlib.sys_file import install_files   # lazy: twincat projects only
            install_system_info(vm, self)
            install_files(vm, self, self.files_root)
        return vm


def parse_duration(text: str) -> int:
    """'10ms', '1s', '500us', 'T#1ms' → nanoseconds (used by the CLI and the API)."""
    simple = _SIMPLE_DURATION.fullmatch(text.strip())
    if simple:    # '10ms', '1s': the usual --scan, without the literal decoder (start-up)
        return int(simple.group(1)) * _DURATION_UNITS[simple.group(2).lower()]
    from stvm.syntax.literals import LiteralError, decode_time   # lazy: start-up
    body = text.strip()
    if "#" not in body:
        body = "T#" + body
    try:
        ns = decode_time(body)
    except (LiteralError, ValueError, KeyError) as exc:
        raise ValueError(f"invalid duration {text!r} (examples: 1ms, 500us, 2s)") from exc
    return ns


_SIMPLE_DURATION = re.compile(r"([0-9]{1,15})(ns|us|ms|s)", re.IGNORECASE)
_DURATION_UNITS = {"ns": 1, "us": 1_000, "ms": 1_000_000, "s": 1_000_000_000}


def expand_paths(paths: Sequence[str | Path]) -> tuple[list[Path], dict, Path | None]:
    """Files to load. A folder means the files its `stvm.toml` lists, else its *.st files; files
    of a folder with `stvm.toml` (one or several, all in that folder) mean the project that
    manifest describes (so `stvm run st_src/PnP_Example.st` loads the whole thesis project, and
    `stvm check st_src/A.st st_src/B.st` checks them with it). Raises ManifestError for a
    manifest that cannot be used and LoadError when there is nothing to load (a folder without
    .st files)."""
    out: list[Path] = []
    manifest: dict = {}
    root: Path | None = None
    given_files: list[Path] = []
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            listed = None
            if (path / MANIFEST).exists():
                manifest, root = read_manifest(path / MANIFEST), path
                listed = project_files(manifest, path, path / MANIFEST)
            # a folder with a manifest that lists its files is that project (the files may be in
            # other folders, e.g. a library the project builds on); else every *.st in it
            found = listed or sorted(p for p in path.glob("*.st") if p.is_file()) or _vendor_sources(path)
            if not found:
                raise LoadError([Diagnostic.error(f"no .st files (nor TwinCAT or PLCopen XML sources) in {path}",
                                                  _file_span(path), "E080")], {})
            out += found
        elif path.suffix.lower() == ".plcproj":   # a TwinCAT PLC project: the sources it lists
            from stvm.syntax.vendor_xml import plcproj_items   # lazy: start-up (vendor XML projects only)
            items = plcproj_items(path)
            if not items:
                raise LoadError([Diagnostic.error(f"{path} lists no TwinCAT sources (<Compile Include=\"….TcPOU\">)",
                                                  _file_span(path), "E080")], {})
            out += items
        else:
            out.append(path)
            given_files.append(path)
    folder = _manifest_folder(given_files) if given_files and len(given_files) == len(paths) else None
    if folder is not None:
        manifest, root = read_manifest(folder / MANIFEST), folder
        files = project_files(manifest, folder, folder / MANIFEST) or sorted(folder.glob("*.st"))
        # the manifest's files in its order, then any file given that it does not list
        listed = {f.resolve() for f in files}
        out = files + [p for p in out if p.resolve() not in listed]
    seen: set[Path] = set()
    unique = []
    for p in out:
        key = p.resolve()
        if key not in seen:
            seen.add(key)
            unique.append(p)
    return unique, manifest, root


def _manifest_folder(files: Sequence[Path]) -> Path | None:
    """The folder whose `stvm.toml` the given files belong to: all in one folder that has one."""
    folders = {f.resolve().parent for f in files}
    if len(folders) != 1:
        return None
    folder = Path(files[0]).parent
    return folder if (folder / MANIFEST).exists() else None


def _vendor_sources(folder: Path) -> list[Path]:
    """A folder without .st files: its TwinCAT (.TcPOU …, a .plcproj's) and PLCopen XML sources."""
    from stvm.syntax.vendor_xml import folder_sources   # lazy: start-up (vendor XML projects only)
    return folder_sources(folder)


def read_source_text(path: Path, encoding: str = "utf-8") -> str:
    """The ST text of one source file: an ST file's text, a vendor XML file's ST (a VendorText,
    whose `original` is the XML). Raises SourceError and OSError like `read_source`."""
    if path.suffix.lower() in _VENDOR_SUFFIXES:
        from stvm.syntax.vendor_xml import read_vendor   # lazy: start-up; ST text laid out on the XML's lines
        return read_vendor(path, encoding)
    return read_source(path, encoding)


_VENDOR_SUFFIXES = (".tcpou", ".tcdut", ".tcgvl", ".tcio", ".xml")


def source_texts(texts: Sequence[tuple[str, str]]) -> dict[str, str]:
    """What excerpts show for each file: its text, the XML itself for a vendor XML file."""
    return {name: getattr(text, "original", text) for name, text in texts}


def source_encoding(manifest: dict) -> str:
    """The encoding of the project's sources (`[project] encoding`, default UTF-8)."""
    return manifest.get("project", {}).get("encoding", "utf-8")


def _file_span(path: Path):
    return Span(str(path), 0, 0, 0, 0)


def vendor_dialect(files: Sequence[Path]) -> str | None:
    """The dialect vendor sources are read in unless told otherwise: `twincat` for TwinCAT files
    (with or without PLCopen XML), `iec` for PLCopen XML alone, None when there is an ST file (the
    default dialect, iec, unless the manifest names one)."""
    suffixes = {Path(p).suffix.lower() for p in files}
    if not suffixes:
        return None
    if suffixes <= {".xml"}:
        return "iec"
    if suffixes <= set(_VENDOR_SUFFIXES):
        return "twincat"
    return None


@dataclass(frozen=True)
class Options:
    """What a command line (or an editor, a launch request, a caller) asks of a project on top
    of its manifest: `--sysmac NAME=VALUE`, `--dialect`, `--define`, the cache policy, and the
    libraries to load beside it (`--library NAME=DIR`, see `ProjectSpec.libraries`)."""

    sysmac: tuple[str, ...] = ()
    dialect: str | None = None
    defines: tuple[str, ...] = ()
    libraries: tuple[tuple[str, str], ...] = ()
    use_cache: bool = True
    # `--library-param LIB.PARAM=VALUE`: (library, parameter, ST text), see stvm/libraries.py
    library_parameters: tuple[tuple[str, str, str], ...] = ()


@dataclass(frozen=True, eq=False)
class ProjectSpec:
    """Everything a command knows about a project before reading a source: which files, which
    manifest, which settings. The one answer `resolve` gives every command (check, run, trace,
    debug, dap, lint, lsp and the Python API), so they cannot disagree about a project."""

    paths: tuple[Path, ...]                 # as given on the command line
    files: tuple[Path, ...]                 # the project's sources, in load order
    manifest: dict                          # the checked `stvm.toml` ({} without one)
    root: Path | None                       # the manifest's folder
    settings: SysmacSettings                # defaults < manifest < command line
    encoding: str = "utf-8"                 # `[project] encoding`
    # (name, folder) of each library loaded beside the project; their sources are added in
    # `library_files` (the one place a library reaches the pipeline)
    libraries: tuple[tuple[str, Path], ...] = ()
    use_cache: bool = True
    # (library, parameter, ST text) set over the manifest's `[libraries.NAME] parameters`
    library_parameters: tuple[tuple[str, str, str], ...] = ()

    @property
    def dialect(self) -> str:
        return getattr(self.settings.dialect, "value", str(self.settings.dialect))

    @property
    def sources_to_read(self) -> tuple[Path, ...]:
        """The libraries' files, then the project's."""
        return tuple(library_files(self)) + self.files


def resolve(paths: Sequence[str | Path], options: Options | None = None,
            settings: SysmacSettings | None = None) -> ProjectSpec:
    """The project `paths` name (files, a folder, files of a folder with `stvm.toml`): its
    files, manifest and settings. `settings` given: used as they are (an API caller's choice);
    else the defaults, then the manifest (`[project] dialect`, `[sysmac]`, `[project] defines`),
    then `options` (`--sysmac`, `--dialect`, `--define`). Raises ValueError (ManifestError,
    SettingError) naming the file, the setting and what is allowed; LoadError when there is
    nothing to load."""
    options = options or Options()
    files, manifest, root = expand_paths(paths)
    if settings is None:
        settings = _manifest_settings(files, manifest, root)
        overrides = list(options.sysmac) + ([f"dialect={options.dialect}"] if options.dialect else [])
        settings = settings.with_overrides(overrides)
        if options.defines:
            settings = settings.with_defines(list(options.defines))
    libraries = tuple((name, Path(folder)) for name, folder in options.libraries)
    return ProjectSpec(tuple(Path(p) for p in paths), tuple(files), manifest, root, settings,
                       source_encoding(manifest), libraries, options.use_cache, tuple(options.library_parameters))


def library_files(spec: ProjectSpec) -> list[Path]:
    """Sources read as the project's own ahead of its files: none. A library (`--library
    NAME=DIR`, `[libraries]`) is read by `_with_libraries`, which also gives each of its files
    the library's namespace."""
    return []


def _libraries():
    import stvm.libraries   # lazy: start-up (projects without libraries never import it)
    return stvm.libraries


def _with_libraries(texts, diags, spec: ProjectSpec):
    """The texts of the project's libraries (`[libraries]` of stvm.toml, then `--library`) before
    its own, and the namespace of each library file by name. Raises LoadError for a library that
    cannot be used."""
    if not spec.libraries and "libraries" not in spec.manifest and not spec.library_parameters:
        return texts, {}
    lib = _libraries()
    try:
        given = [name for name, _ in spec.libraries]
        wanted = lib.from_manifest(spec.manifest, spec.root, given) + [lib.Library(name, Path(folder))
                                                                       for name, folder in spec.libraries]
        parameters = lib.manifest_parameters(spec.manifest, spec.root)
        for name, param, text in spec.library_parameters:   # the command line over the manifest
            parameters.setdefault(name, {})[param] = text
        lib_texts, spaces, lib_diags = lib.read_libraries(wanted, read_files, spec.encoding)
        spaces = lib.LibrarySpaces(spaces, parameters=parameters)
    except lib.LibraryError as exc:
        raise LoadError([Diagnostic.error(str(exc), Span(str(spec.root or "."), 0, 0, 0, 0), "E081")], {}) from None
    diags += lib_diags
    return lib_texts + list(texts), spaces


def _spaces_key(spaces) -> str:
    if hasattr(spaces, "key"):   # libraries.LibrarySpaces: the parameters too
        return spaces.key()
    return "".join(f"|{name}={ns}" for name, ns in sorted(spaces.items()))


def _manifest_settings(files: Sequence[Path], manifest: dict, root: Path | None) -> SysmacSettings:
    settings = DEFAULT_SETTINGS
    dialect = manifest.get("project", {}).get("dialect")
    if dialect is None:
        dialect = vendor_dialect(files)
    if dialect is not None:
        settings = settings.with_table({"dialect": dialect}, f"{Path(root or '.') / MANIFEST}: [project]")
    table = manifest.get("sysmac")
    if table is not None:
        where = f"{Path(root or '.') / MANIFEST}: [sysmac]"
        if not isinstance(table, dict):
            raise ManifestError(f"{where} must be a table of NAME = VALUE")
        settings = settings.with_table(table, where)
    defines = manifest.get("project", {}).get("defines")
    if defines:
        settings = settings.with_defines(defines, f"{Path(root or '.') / MANIFEST}: [project] defines")
    return settings


def project_settings(paths: Sequence[str | Path], overrides: Sequence[str] = ()) -> SysmacSettings:
    """The Sysmac settings of a run on `paths`: the spec's defaults, then the `[sysmac]` table of
    the project's `stvm.toml` (when the files belong to one), then `--sysmac NAME=VALUE`
    overrides; the last one wins (`resolve(paths).settings`, kept for the API)."""
    return resolve(paths, Options(sysmac=tuple(overrides))).settings


def _spec(paths, settings, use_cache: bool = True, libraries: Sequence = ()) -> ProjectSpec:
    """`paths` may already be a resolved spec (what the commands pass); `libraries`
    (stvm.libraries.Library values, the API's) are loaded beside the spec's own."""
    if isinstance(paths, ProjectSpec):
        spec = paths if settings is None else replace(paths, settings=settings)
    else:
        spec = resolve(paths, Options(use_cache=use_cache), settings)
    if libraries:
        spec = replace(spec, libraries=spec.libraries + tuple((lib.name, Path(lib.path)) for lib in libraries))
    return spec


def _stdlib(settings: SysmacSettings = DEFAULT_SETTINGS) -> list[tuple[str, str]]:
    # part of the stdlib text depends on the settings (R_TRIG's first call, pin aliases, …)
    from stvm.stdlib import stdlib_sources   # lazy: start-up
    return stdlib_sources(settings)


def _cache_dir() -> Path:
    from stvm.cache import default_folder   # lazy: start-up
    return default_folder()


def _cache() -> "SignedCache":
    """The compile cache: entries signed with the user's key (stvm/cache.py), so a shared
    STVM_CACHE_DIR cannot hand stvm a pickle someone else wrote."""
    from stvm.cache import SignedCache   # lazy: start-up
    folder = _cache_dir()
    cached = _CACHES.get(folder)
    if cached is None:
        cached = _CACHES[folder] = SignedCache(folder)
    return cached


_CACHES: dict[Path, "SignedCache"] = {}


_CODE_DIGEST: list[str] = []


def _stvm_code_digest() -> str:
    """Fingerprint of stvm's own sources: a cache entry is only valid for the code that generated
    it. Each source file's path, size and modification time (ns), as Python's own .pyc files are
    checked: reading and hashing the 2 MB of sources was ~5 % of a warm `stvm run`'s CPU, and an
    edit, a checkout or a new install changes the time (a file rewritten to the same size within
    the same nanosecond would not)."""
    if not _CODE_DIGEST:
        digest = hashlib.sha256()
        package = str(Path(__file__).resolve().parent)
        entries = []
        for folder, dirs, names in os.walk(package):
            dirs[:] = [d for d in dirs if d != "__pycache__"]
            for name in names:
                if name.endswith((".py", ".lark", ".st")):
                    path = os.path.join(folder, name)
                    info = os.stat(path)
                    entries.append(f"{path[len(package):]}\0{info.st_size}\0{info.st_mtime_ns}\n")
        for entry in sorted(entries):
            digest.update(entry.encode("utf-8", "surrogateescape"))
        _CODE_DIGEST.append(digest.hexdigest())
    return _CODE_DIGEST[0]


def _cache_key(texts: list[tuple[str, str]], settings: SysmacSettings, kind: str = "") -> str:
    """Content hash of a cache entry: stvm's version and own code (the stdlib's ST text is part
    of that code, generated from it and the settings), the settings, and the name and text of
    every unit given. `kind` keeps entries of different stages apart."""
    digest = hashlib.sha256()
    digest.update(kind.encode() + b"\0")
    digest.update(__version__.encode())
    digest.update(_stvm_code_digest().encode())
    digest.update(repr(settings).encode())
    for name, text in texts:
        digest.update(name.encode() + b"\0" + text.encode("utf-8", "replace") + b"\0")
        if hasattr(text, "original"):   # a vendor XML file: its excerpts come from the XML itself
            digest.update(text.original.encode("utf-8", "replace") + b"\0")
    return digest.hexdigest()


def read_files(paths: Sequence[Path], encoding: str = "utf-8",
               overrides: dict[str, str] | None = None) -> tuple[list[tuple[str, str]], list[Diagnostic]]:
    """(name, text) of each file, and a diagnostic for each file that cannot be used (its text
    is then empty or decoded with replacement characters, so a binary file is never parsed).
    `overrides` replaces the text of the files it names (an editor's unsaved buffer)."""
    texts = []
    diags = []
    for path in paths:
        if overrides is not None and str(path) in overrides:
            texts.append((str(path), overrides[str(path)]))
            continue
        try:
            texts.append((str(path), read_source_text(path, encoding)))
        except SourceError as exc:
            if path.suffix.lower() in _VENDOR_SUFFIXES and exc.text:   # malformed XML: shown, never parsed
                from stvm.syntax.vendor_xml import unreadable   # lazy: start-up (vendor XML only)
                texts.append((str(path), unreadable(exc.text)))
            else:
                texts.append((str(path), exc.text))
            diags.append(Diagnostic.error(exc.message, Span(str(path), exc.line, exc.column, exc.line,
                                                             exc.column + 1), exc.code))
        except OSError as exc:
            texts.append((str(path), ""))
            diags.append(Diagnostic.error(f"cannot read file: {exc.strerror or exc}", Span(str(path), 0, 0, 0, 0),
                                          "E006"))
    return texts, diags


def check(paths: "Sequence[str | Path] | ProjectSpec", settings: SysmacSettings | None = None, generate: bool = False,
          use_cache: bool = True, libraries: Sequence = ()):
    """Parse and check: (analysis or None, diagnostics sorted, sources). With `generate`, also
    lower and compile, so limits that only code generation meets are reported too. Without
    `settings`, the project's own (`project_settings`).

    The verdict (the diagnostics) of a project is cached by content hash (stvm's version and
    code, the settings, every file's name and text): an unchanged project skips parsing,
    checking and lowering. The analysis is then computed only if the caller reads it."""
    spec = _spec(paths, settings, use_cache, libraries)
    settings, use_cache = spec.settings, use_cache and spec.use_cache
    texts, diags = read_files(spec.sources_to_read, spec.encoding)
    texts, spaces = _with_libraries(texts, diags, spec)
    kind = ('check+generate' if generate else 'check') + _spaces_key(spaces)
    cache_name = f"check-{_cache_key(texts, settings, kind)}.diag"
    cacheable = use_cache and not diags      # an unreadable file is reported afresh every time
    if cacheable:
        payload = _cache().get(cache_name)
        if payload is not None:
            try:
                # verified: only this user's stvm (holding the key) can have written it
                ok, cached_diags, extra_sources = pickle.loads(payload)
            except Exception:  # a stale entry (an older stvm's classes) is rebuilt, never fatal
                pass
            else:
                sources = source_texts(texts)
                sources.update(extra_sources)
                analysis = _DeferredAnalysis(texts, settings, spaces) if ok else None
                return analysis, list(cached_diags), sources
    analysis, diags, sources = _check_texts(texts, diags, settings, use_cache, spaces=spaces)
    if generate and analysis is not None:
        try:
            _lower_and_compile(analysis, settings, texts, sources)
        except LoadError as exc:
            diags = diags + exc.diagnostics
            analysis = None
    if cacheable:
        user = {name for name, _ in texts}
        # the stdlib's text is kept with the verdict: a diagnostic may point into it
        extra = {name: text for name, text in sources.items() if name not in user}
        try:
            payload = pickle.dumps((analysis is not None, diags, extra), protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, RecursionError, TypeError):
            payload = None
        if payload is not None:
            _cache().put(cache_name, payload)
            _cache().prune("check-*.diag", CACHE_MAX_ENTRIES)
    return analysis, diags, sources


class _DeferredAnalysis:
    """The `Analysis` of a project whose verdict came from the cache: computed (parse from the
    unit cache, check) on first use, so `stvm check` of an unchanged project never builds it."""

    def __init__(self, texts, settings, spaces=None) -> None:
        self._texts = texts
        self._settings = settings
        self._spaces = spaces
        self._analysis = None

    def __getattr__(self, name):
        if name.startswith("_"):
            raise AttributeError(name)
        if self._analysis is None:
            self._analysis, _, _ = _check_texts(list(self._texts), [], self._settings, spaces=self._spaces)
        return getattr(self._analysis, name)


_STDLIB_UNITS: dict[str, tuple[list, list[Diagnostic]]] = {}


def stdlib_units(settings: SysmacSettings) -> tuple[list, list[Diagnostic], dict[str, str]]:
    """The parsed stdlib: memoised in-process, shipped prebuilt for the default settings
    (stvm/stdlib/prebuilt.py), else pickled in the cache dir (it never changes between runs of
    one stvm version, and parsing it is most of a cold start)."""
    if settings.defines:    # the stdlib has no conditional code: parsed (and prebuilt) without them
        settings = replace(settings, defines=())
    texts = _stdlib(settings)
    key = _cache_key([], settings, "stdlib-units")
    sources = dict(texts)
    if key in _STDLIB_UNITS:
        units, diags = _STDLIB_UNITS[key]
        return units, list(diags), sources
    from stvm.stdlib import prebuilt   # lazy: start-up
    shipped = prebuilt.load(texts, settings)    # parsed once when stvm was built (default settings)
    if shipped is not None:
        _STDLIB_UNITS[key] = shipped
        return shipped[0], list(shipped[1]), sources
    from stvm.syntax.parser import parse_text   # lazy: start-up
    cache = _cache()
    entry = f"stdlib-{key}.ast"
    try:
        payload = cache.get(entry)
        if payload is None:
            raise LookupError(entry)
        units, diags = pickle.loads(payload)   # verified: written by this user's stvm
    except Exception:  # missing, unreadable or not ours: parse again
        units, diags = [], []
        for name, text in texts:
            unit, d = parse_text(text, name, settings)
            units.append(unit)
            diags += d
        cache.put(entry, pickle.dumps((units, diags), protocol=pickle.HIGHEST_PROTOCOL))
    _STDLIB_UNITS[key] = (units, diags)
    return units, list(diags), sources


def _collector_paused():
    """The collector paused while the front end builds the project's objects, and what it built
    aged into the oldest generation after (they live as long as the project)."""
    return collector_paused(age_survivors=True)


def parse_unit(name: str, text: str, settings: SysmacSettings, use_cache: bool = True, write: bool = True):
    """(unit, parse diagnostics) of one file, from the cache when its text, the settings and
    stvm are unchanged: an edit re-parses only the file edited. Without `write`, a unit parsed
    is not stored (an entry found is still used)."""
    from stvm.syntax.parser import parse_text   # lazy: start-up (a cached project never parses)
    if not use_cache:
        return parse_text(text, name, settings)
    entry = f"unit-{_cache_key([(name, text)], settings, 'unit')}.ast"
    payload = _cache().get(entry)
    if payload is not None:
        try:
            unit, diags = pickle.loads(payload)   # verified: written by this user's stvm
            return unit, list(diags)
        except Exception:  # a stale entry is parsed again, never fatal
            pass
    unit, diags = parse_text(text, name, settings)
    if not write:
        return unit, diags
    try:
        payload = pickle.dumps((unit, diags), protocol=pickle.HIGHEST_PROTOCOL)
    except (pickle.PicklingError, RecursionError, TypeError):
        payload = None
    if payload is not None:
        _cache().put(entry, payload)
        if "unit" not in _PRUNED:     # once a process: a cold project writes one entry a file
            _PRUNED.add("unit")
            _cache().prune("unit-*.ast", UNIT_CACHE_MAX_ENTRIES)
    return unit, diags


_PRUNED: set[str] = set()


def _check_texts(texts, diags, settings, use_cache: bool = True, unit_entries: bool = True, spaces=None):
    with _collector_paused():
        return _check_texts_unpaused(texts, diags, settings, use_cache, unit_entries, spaces)


def _check_texts_unpaused(texts, diags, settings, use_cache: bool = True, unit_entries: bool = True, spaces=None):
    units, diags, sources = _parse_units(texts, diags, settings, use_cache, unit_entries, spaces)
    analysis, _, diags = _analyze(units, diags, settings)
    return analysis, diags, sources


def _parse_units(texts, diags, settings, use_cache: bool = True, unit_entries: bool = True, spaces=None):
    """(units: the stdlib's then the files', diagnostics, sources: stdlib included). `spaces`:
    the library namespace of each library file by name (`_with_libraries`)."""
    sources = source_texts(texts)
    units, stdlib_diags, stdlib_sources = stdlib_units(settings)
    units = list(units)
    diags = list(diags) + stdlib_diags
    sources.update(stdlib_sources)
    for name, text in texts:
        unit, d = parse_unit(name, text, settings, use_cache, unit_entries)
        if spaces and name in spaces:
            unit = _libraries().namespaced(unit, spaces[name])
        units.append(unit)
        diags += d
    if getattr(spaces, "parameters", None) and not has_errors(diags):
        lib = _libraries()
        try:
            units = lib.apply_parameters(units, spaces.parameters, settings)
        except lib.LibraryError as exc:
            diags.append(Diagnostic.error(str(exc), Span(units[-1].path if units else "<input>", 0, 0, 0, 0), "E081"))
    if spaces or getattr(settings.dialect, "value", settings.dialect) == "twincat":
        units = _libraries().qualify(units, _libraries().namespaces(spaces or {}, settings))
    return units, diags, sources


def _analyze(units, diags, settings):
    """(analysis or None, the checker, diagnostics sorted): the checker runs when parsing found
    no error; the analysis is None when anything has an error."""
    from stvm.semantics.checker import Checker   # lazy: start-up
    from stvm.stdlib import NATIVE_FUNCTIONS   # lazy: start-up
    diags = list(diags)
    analysis = checker = None
    if not has_errors(diags):
        try:
            checker = Checker(units, settings, NATIVE_FUNCTIONS)
            analysis = checker.run()
            diags += analysis.diagnostics
        except RecursionError:
            diags.append(_too_deep(units[-1].path if units else "<input>"))
    diags.sort(key=sort_key)
    return (None if has_errors(diags) else analysis), checker, diags


# ---------------------------------------------------------------- the stages, one by one
#
# What `load` and `check` do in one call (with their caches), as typed steps for the commands
# that need a step's product: lint reads the checked tree, the debugger the checker and a build
# lowered with other options. Every step starts from a `ProjectSpec` (`resolve`).

class Parsed(Record):
    """The parse stage's product: the texts ((name, text) of each user file, libraries first),
    the syntax trees (the stdlib's, then the files'), the diagnostics of reading and parsing,
    and the sources excerpts show (every file and the stdlib)."""

    _FIELDS = ('spec', 'texts', 'units', 'diagnostics', 'sources')

    def __init__(self, spec: ProjectSpec, texts: list[tuple[str, str]], units: list,
                 diagnostics: list[Diagnostic], sources: dict[str, str]) -> None:
        self.spec = spec
        self.texts = texts
        self.units = units
        self.diagnostics = diagnostics
        self.sources = sources

    @property
    def files(self) -> list[str]:
        return [name for name, _ in self.texts]


class Checked(Record):
    """The check stage's product: the analysis (semantics.Analysis; None after an error), the
    Checker whose index types expressions (the debugger's) and every diagnostic (reading,
    parsing and checking, sorted)."""

    _FIELDS = ('parsed', 'analysis', 'checker', 'diagnostics')

    def __init__(self, parsed: Parsed, analysis: object | None, checker: object | None,
                 diagnostics: list[Diagnostic]) -> None:
        self.parsed = parsed
        self.analysis = analysis
        self.checker = checker
        self.diagnostics = diagnostics

    @property
    def spec(self) -> ProjectSpec:
        return self.parsed.spec

    @property
    def sources(self) -> dict[str, str]:
        return self.parsed.sources


class Compiled(Record):
    """The lowering stage's product: the generated Python and its compiled code."""

    _FIELDS = ('checked', 'lowered', 'code')

    def __init__(self, checked: Checked, lowered: LoweredProject, code: tuple) -> None:
        self.checked = checked
        self.lowered = lowered
        self.code = code

    def project(self) -> Project:
        spec = self.checked.spec
        model = self.checked.analysis.model
        warnings = [d for d in self.checked.diagnostics if not d.is_error]
        return Project(model, self.lowered, self.code, self.checked.sources, spec.settings, warnings, False,
                       spec.manifest, spec.root, _native_modules(self.lowered))


def parse_stage(spec: ProjectSpec, overrides: dict[str, str] | None = None) -> Parsed:
    """Read and parse `spec`'s files (each file's tree from the cache when unchanged);
    `overrides`: texts that replace files' contents (an editor's unsaved buffers)."""
    texts, diags = read_files(spec.sources_to_read, spec.encoding, overrides)
    texts, spaces = _with_libraries(texts, diags, spec)
    with _collector_paused():
        units, diags, sources = _parse_units(texts, diags, spec.settings, spec.use_cache, spaces=spaces)
    return Parsed(spec, texts, units, diags, sources)


def check_stage(parsed: Parsed) -> Checked:
    """Check the parsed project (nothing is checked when reading or parsing found an error)."""
    with _collector_paused():
        analysis, checker, diags = _analyze(parsed.units, parsed.diagnostics, parsed.spec.settings)
    return Checked(parsed, analysis, checker, diags)


def check_project(paths: "Sequence[str | Path] | ProjectSpec", settings: SysmacSettings | None = None,
                  overrides: dict[str, str] | None = None) -> Checked:
    """`resolve`, `parse_stage` and `check_stage` in one call (lint, the benchmarks, tools)."""
    return check_stage(parse_stage(_spec(paths, settings), overrides))


def compile_stage(checked: Checked, options: "LowerOptions | None" = None) -> Compiled:
    """Lower and compile a checked project (raises LoadError when it has errors, or when the
    generated code meets one of Python's limits). `options`: the lowering switches (the
    debugger's build differs from the normal one); such a build is never cached."""
    if checked.analysis is None:
        raise LoadError(checked.diagnostics, checked.sources)
    lowered, code = _lower_and_compile(checked.analysis, checked.spec.settings, checked.parsed.texts,
                                       checked.sources, options)
    return Compiled(checked, lowered, code)


def _lower_and_compile(analysis, settings, texts, sources, options=None):
    with _collector_paused():
        return _lower_and_compile_unpaused(analysis, settings, texts, sources, options)


def _lower_and_compile_unpaused(analysis, settings, texts, sources, options=None):
    """Generate and compile the Python module; Python's own limits become diagnostics.

    `analysis` may come handed over in a one-item list, which is emptied once lowered: with no
    other reference left, the syntax tree and the checker's facts (1.5 million objects for
    100,000 lines) are freed before Python's compile() reaches its memory peak."""
    from stvm.lower import lower_project   # lazy: start-up
    from stvm.runtime.vm import GENERATED_FILENAME   # lazy: start-up
    from stvm.lower.product import compile_module   # lazy: start-up
    fallback = Span(texts[-1][0] if texts else "<input>", 1, 1, 1, 2)
    lowered = None
    try:
        # the lowering's own default options unless a build asks for others (the debugger's)
        extra = {} if options is None else {"options": options}
        if isinstance(analysis, list):
            lowered = lower_project(analysis[0], settings, **extra)
            analysis.clear()
        else:
            lowered = lower_project(analysis, settings, **extra)
        del analysis
        code = compile_module(lowered.source, GENERATED_FILENAME)
    except RecursionError:
        raise LoadError([_too_deep(fallback.file)], sources) from None
    except SyntaxError as exc:
        # nesting depth of blocks/parentheses in the generated module
        span = lowered.line_map.span_at(exc.lineno) if lowered is not None and exc.lineno else None
        raise LoadError([Diagnostic.error(f"this code is nested too deeply for stvm to compile ({exc.msg}); "
                                          f"split it into smaller POUs or statements", span or fallback, "E004")],
                        sources) from None
    return lowered, code


def _too_deep(file: str) -> Diagnostic:
    return Diagnostic.error("expression or statement nesting too deep for stvm (split it into smaller parts)",
                            Span(file, 1, 1, 1, 2), "E003")


def load(paths: "Sequence[str | Path] | ProjectSpec", settings: SysmacSettings | None = None, use_cache: bool = True,
         libraries: Sequence = ()) -> Project:
    """Load a runnable project from ST files (raises LoadError with every diagnostic). Without
    `settings`, the project's own: `stvm.toml` `[sysmac]` over the defaults (`project_settings`)."""
    spec = _spec(paths, settings, use_cache, libraries)
    settings, use_cache, manifest, root = spec.settings, use_cache and spec.use_cache, spec.manifest, spec.root
    texts, read_diags = read_files(spec.sources_to_read, spec.encoding)
    texts, spaces = _with_libraries(texts, read_diags, spec)
    if read_diags:
        raise LoadError(read_diags, source_texts(texts))
    key = _cache_key(texts, settings, "load" + _spaces_key(spaces))
    cache_name = f"{key}.bin"
    payload = _cache().get(cache_name) if use_cache else None
    if payload is not None:
        try:
            # verified: only this user's stvm (holding the key) can have written it
            model, lowered, warnings, code_bytes, sources, native_modules = pickle.loads(payload)
            return Project(model, lowered, marshal.loads(code_bytes), sources, settings, warnings, True, manifest, root,
                           native_modules, True)
        except Exception:  # a stale entry (an older stvm's classes) is rebuilt, never fatal
            pass
    # A one-file project writes no unit entry: the load entry written below serves every run of
    # the unchanged file, and an edit makes both stale, so the unit's entry would only spare a
    # later `stvm check` of the unchanged file its parse. Pickling it is a tenth of a first load
    # (1.0-1.4 s of a 100,000-line file, bench/bench_large.py). A file of a larger project keeps
    # its entry: an edit of another file re-parses only that one.
    analysis, diags, sources = _check_texts(texts, [], settings, use_cache, unit_entries=len(texts) > 1,
                                            spaces=spaces)
    if analysis is None:
        raise LoadError(diags, sources)
    model = analysis.model
    handed_over = [analysis]
    del analysis   # freed once lowered (see _lower_and_compile_unpaused)
    lowered, code = _lower_and_compile(handed_over, settings, texts, sources)
    warnings = [d for d in diags if not d.is_error]
    project = Project(model, lowered, code, sources, settings, warnings, False, manifest, root,
                      _native_modules(lowered))
    if use_cache:
        try:
            with _collector_paused():   # pickling allocates (its memo) but frees nothing cyclic
                payload = pickle.dumps((model, lowered, warnings, marshal.dumps(code), sources,
                                        project.native_modules), protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, RecursionError, TypeError):
            payload = None
        if payload is not None:
            _cache().put(cache_name, payload)
            _cache().prune("*.bin", CACHE_MAX_ENTRIES)
    return project


def _native_modules(lowered) -> tuple[str, ...]:
    """The stdlib modules that implement the natives the generated code of `lowered` names
    (what a cached load imports; a superset: a name found in the source counts as called). A
    native FB's class is always in the source: its module is imported when an instance is made."""
    from stvm.stdlib.registry import NATIVE_FUNCTIONS   # lazy: start-up
    named = set(_NATIVE_NAME.findall(lowered.source))
    modules = {NATIVE_FUNCTIONS[k].impl.__module__ for py, k in lowered.natives.items()
               if py in named and k in NATIVE_FUNCTIONS}
    return tuple(sorted(modules))


# a generated native's name (`\bN[0-9]+_\w+`), the word boundary tested behind the `N`: a
# pattern that starts with a literal is searched for by its first letter, ~50x faster over the
# megabytes of a large program's module
_NATIVE_NAME = re.compile(r"N(?<=\bN)[0-9]+_\w+")

CACHE_MAX_ENTRIES = 200
UNIT_CACHE_MAX_ENTRIES = 2000   # parsed files (a few KiB to a few MiB each)


def nothing_to_run(project: Project, files: Sequence[str | Path] = ()) -> str | None:
    """Why `project` cannot run (no PROGRAM and no CONFIGURATION task), or None if it can."""
    if project.model.tasks or project.model.default_programs:
        return None
    names = ", ".join(str(f) for f in files) or "the project"
    return (f"no PROGRAM in {names}: a run needs a PROGRAM (or a CONFIGURATION with tasks); "
            f"FUNCTIONs and FUNCTION_BLOCKs alone are a library (stvm check FILE checks it)")
