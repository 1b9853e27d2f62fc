"""The pipeline driver: files → parse → check → lower → compile, with a content-hash cache.

`check(paths)` stops after the checker; `load(paths)` returns a runnable `Project` or raises
`LoadError` carrying every diagnostic. A cache entry (keyed by stvm's version, the settings and
the text of every file including the stdlib) holds the lowered module and the model, so a
repeated load skips parsing, checking and code generation.
"""

from __future__ import annotations

import contextlib
import gc
import hashlib
import marshal
import pickle
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from stvm.version import __version__
from stvm.diagnostics import Diagnostic, has_errors, render, sort_key
from stvm.manifest import MANIFEST, ManifestError, project_files, read_manifest  # noqa: F401 (API)
from stvm.runtime.vm import GENERATED_FILENAME, VM
from stvm.settings import DEFAULT_SETTINGS, SysmacSettings
from stvm.source import SourceError, Span, read_source

if TYPE_CHECKING:
    from stvm.cache import SignedCache
    from stvm.lower import LoweredProject
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


@dataclass
class Project:
    model: "ProjectModel"
    lowered: "LoweredProject"
    code: object
    sources: dict[str, str]
    settings: SysmacSettings
    warnings: list[Diagnostic] = field(default_factory=list)
    from_cache: bool = False
    manifest: dict = field(default_factory=dict)
    root: Path | None = None

    def start(self, scan: str | int = "10ms", realtime: bool = False, start_dt_ns: int = 0,
              transport=None) -> VM:
        """A fresh VM for this project (all variables at their initial values)."""
        scan_ns = parse_duration(scan) if isinstance(scan, str) else int(scan)
        return VM(self, scan_ns=scan_ns, realtime=realtime, start_dt_ns=start_dt_ns, transport=transport)


def parse_duration(text: str) -> int:
    """'10ms', '1s', '500us', 'T#1ms' → nanoseconds (used by the CLI and the API)."""
    from stvm.syntax.literals import LiteralError, decode_time
    body = text.strip()
    if "#" not in body:
        body = "T#" + body
    try:
        ns = decode_time(body)
    except (LiteralError, ValueError, KeyError) as exc:
        raise ValueError(f"invalid duration {text!r} (examples: 1ms, 500us, 2s)") from exc
    return ns


def expand_paths(paths: Sequence[str | Path]) -> tuple[list[Path], dict, Path | None]:
    """Files to load. A folder means the files its `stvm.toml` lists, else its *.st files; a lone
    file in a folder with `stvm.toml` means the project that manifest describes (so `stvm run
    st_src/PnP_Example.st` loads the whole thesis project). Raises ManifestError for a manifest
    that cannot be used and LoadError when there is nothing to load (a folder without .st files)."""
    out: list[Path] = []
    manifest: dict = {}
    root: Path | None = None
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
                                                  _file_span(path))], {})
            out += found
        elif path.suffix.lower() == ".plcproj":   # a TwinCAT PLC project: the sources it lists
            from stvm.syntax.vendor_xml import plcproj_items
            items = plcproj_items(path)
            if not items:
                raise LoadError([Diagnostic.error(f"{path} lists no TwinCAT sources (<Compile Include=\"….TcPOU\">)",
                                                  _file_span(path))], {})
            out += items
        else:
            out.append(path)
    if len(paths) == 1 and not Path(paths[0]).is_dir():
        folder = Path(paths[0]).parent
        if (folder / MANIFEST).exists():
            manifest, root = read_manifest(folder / MANIFEST), folder
            files = project_files(manifest, folder, folder / MANIFEST) or sorted(folder.glob("*.st"))
            out = files if Path(paths[0]).resolve() in {f.resolve() for f in files} else files + out
    seen: set[Path] = set()
    unique = []
    for p in out:
        key = p.resolve()
        if key not in seen:
            seen.add(key)
            unique.append(p)
    return unique, manifest, root


def _vendor_sources(folder: Path) -> list[Path]:
    """A folder without .st files: its TwinCAT (.TcPOU …, a .plcproj's) and PLCopen XML sources."""
    from stvm.syntax.vendor_xml import folder_sources
    return folder_sources(folder)


def read_source_text(path: Path, encoding: str = "utf-8") -> str:
    """The ST text of one source file: an ST file's text, a vendor XML file's ST (a VendorText,
    whose `original` is the XML). Raises SourceError and OSError like `read_source`."""
    if path.suffix.lower() in _VENDOR_SUFFIXES:
        from stvm.syntax.vendor_xml import read_vendor   # ST text laid out on the XML's lines
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
    """The dialect vendor sources are read in unless told otherwise: `twincat` for TwinCAT files,
    `codesys` for PLCopen XML (with or without TwinCAT files), None when there is an ST file."""
    suffixes = {Path(p).suffix.lower() for p in files}
    if not suffixes:
        return None
    if suffixes <= set(_VENDOR_SUFFIXES[:4]):
        return "twincat"
    if suffixes <= set(_VENDOR_SUFFIXES):
        return "codesys"
    return None


def project_settings(paths: Sequence[str | Path], overrides: Sequence[str] = ()) -> SysmacSettings:
    """The Sysmac settings of a run on `paths`: the spec's defaults, then the `[sysmac]` table of
    the project's `stvm.toml` (when the files belong to one), then `--sysmac NAME=VALUE`
    overrides; the last one wins. Raises ValueError (SettingError, ManifestError) that names
    the setting, the file and the allowed values."""
    files, manifest, root = expand_paths(paths)
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
    return settings.with_overrides(list(overrides))


def _stdlib(settings: SysmacSettings = DEFAULT_SETTINGS) -> list[tuple[str, str]]:
    # part of the stdlib text depends on the settings (R_TRIG's first call, pin aliases, …)
    from stvm.stdlib import stdlib_sources
    return stdlib_sources(settings)


def _cache_dir() -> Path:
    from stvm.cache import default_folder
    return default_folder()


def _cache() -> "SignedCache":
    """The compile cache: entries signed with the user's key (stvm/cache.py), so a shared
    STVM_CACHE_DIR cannot hand stvm a pickle someone else wrote."""
    from stvm.cache import SignedCache
    folder = _cache_dir()
    cached = _CACHES.get(folder)
    if cached is None:
        cached = _CACHES[folder] = SignedCache(folder)
    return cached


_CACHES: dict[Path, "SignedCache"] = {}


_CODE_DIGEST: list[str] = []


def _stvm_code_digest() -> str:
    """Hash of stvm's own sources: a cache entry is only valid for the code that generated it."""
    if not _CODE_DIGEST:
        digest = hashlib.sha256()
        package = Path(__file__).resolve().parent
        for path in sorted(package.rglob("*")):
            if path.suffix in (".py", ".lark", ".st") and "__pycache__" not in path.parts:
                digest.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes())
        _CODE_DIGEST.append(digest.hexdigest())
    return _CODE_DIGEST[0]


def _cache_key(texts: list[tuple[str, str]], settings: SysmacSettings) -> str:
    digest = hashlib.sha256()
    digest.update(__version__.encode())
    digest.update(_stvm_code_digest().encode())
    digest.update(repr(settings).encode())
    for name, text in texts:
        digest.update(name.encode() + b"\0" + text.encode("utf-8", "replace") + b"\0")
        if hasattr(text, "original"):   # a vendor XML file: its excerpts come from the XML itself
            digest.update(text.original.encode("utf-8", "replace") + b"\0")
    return digest.hexdigest()


def read_files(paths: Sequence[Path], encoding: str = "utf-8") -> tuple[list[tuple[str, str]], list[Diagnostic]]:
    """(name, text) of each file, and a diagnostic for each file that cannot be used (its text
    is then empty or decoded with replacement characters, so a binary file is never parsed)."""
    texts = []
    diags = []
    for path in paths:
        try:
            texts.append((str(path), read_source_text(path, encoding)))
        except SourceError as exc:
            if path.suffix.lower() in _VENDOR_SUFFIXES and exc.text:   # malformed XML: shown, never parsed
                from stvm.syntax.vendor_xml import unreadable
                texts.append((str(path), unreadable(exc.text)))
            else:
                texts.append((str(path), exc.text))
            diags.append(Diagnostic.error(exc.message, Span(str(path), exc.line, exc.column, exc.line,
                                                             exc.column + 1), "E001"))
        except OSError as exc:
            texts.append((str(path), ""))
            diags.append(Diagnostic.error(f"cannot read file: {exc.strerror or exc}", Span(str(path), 0, 0, 0, 0)))
    return texts, diags


def check(paths: Sequence[str | Path], settings: SysmacSettings | None = None, generate: bool = False):
    """Parse and check: (analysis or None, diagnostics sorted, sources). With `generate`, also
    lower and compile, so limits that only code generation meets are reported too. Without
    `settings`, the project's own (`project_settings`)."""
    if settings is None:
        settings = project_settings(paths)
    files, manifest, _ = expand_paths(paths)
    texts, diags = read_files(files, source_encoding(manifest))
    analysis, diags, sources = _check_texts(texts, diags, settings)
    if generate and analysis is not None:
        try:
            _lower_and_compile(analysis, settings, texts, sources)
        except LoadError as exc:
            diags = diags + exc.diagnostics
            analysis = None
    return analysis, diags, sources


_STDLIB_UNITS: dict[str, tuple[list, list[Diagnostic]]] = {}


def stdlib_units(settings: SysmacSettings) -> tuple[list, list[Diagnostic], dict[str, str]]:
    """The parsed stdlib, memoised in-process and pickled in the cache dir (it never changes
    between runs of one stvm version, and parsing it is most of a cold start)."""
    texts = _stdlib(settings)
    key = _cache_key(texts, settings)
    sources = dict(texts)
    if key in _STDLIB_UNITS:
        units, diags = _STDLIB_UNITS[key]
        return units, list(diags), sources
    from stvm.syntax.parser import parse_text
    cache = _cache()
    name = f"stdlib-{key}.ast"
    try:
        payload = cache.get(name)
        if payload is None:
            raise LookupError(name)
        units, diags = pickle.loads(payload)   # verified: written by this user's stvm
    except Exception:  # missing, unreadable or not ours: parse again
        units, diags = [], []
        for name, text in texts:
            unit, d = parse_text(text, name, settings)
            units.append(unit)
            diags += d
        cache.put(name, pickle.dumps((units, diags), protocol=pickle.HIGHEST_PROTOCOL))
    _STDLIB_UNITS[key] = (units, diags)
    return units, list(diags), sources


@contextlib.contextmanager
def _collector_paused():
    """The cyclic garbage collector off while the front end builds millions of small objects
    (parse tree, nodes, facts): none of them is garbage yet, and the collector's passes over the
    growing heap took more than half of a 100,000-line load (bench/bench_large.py)."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


def _check_texts(texts, diags, settings):
    with _collector_paused():
        return _check_texts_unpaused(texts, diags, settings)


def _check_texts_unpaused(texts, diags, settings):
    from stvm.semantics import analyze
    from stvm.syntax.parser import parse_text
    sources = source_texts(texts)
    units, stdlib_diags, stdlib_sources = stdlib_units(settings)
    units = list(units)
    diags += stdlib_diags
    sources.update(stdlib_sources)
    for name, text in texts:
        unit, d = parse_text(text, name, settings)
        units.append(unit)
        diags += d
    analysis = None
    if not has_errors(diags):
        try:
            analysis = analyze(units, settings)
            diags += analysis.diagnostics
        except RecursionError:
            diags.append(_too_deep(units[-1].path if units else "<input>"))
    diags.sort(key=sort_key)
    return (None if has_errors(diags) else analysis), diags, sources


def _lower_and_compile(analysis, settings, texts, sources):
    with _collector_paused():
        return _lower_and_compile_unpaused(analysis, settings, texts, sources)


def _lower_and_compile_unpaused(analysis, settings, texts, sources):
    """Generate and compile the Python module; Python's own limits become diagnostics."""
    from stvm.lower import lower_project
    fallback = Span(texts[-1][0] if texts else "<input>", 1, 1, 1, 2)
    lowered = None
    try:
        lowered = lower_project(analysis, settings)
        code = compile(lowered.source, GENERATED_FILENAME, "exec")
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


def load(paths: Sequence[str | Path], settings: SysmacSettings | None = None, use_cache: bool = True) -> Project:
    """Load a runnable project from ST files (raises LoadError with every diagnostic). Without
    `settings`, the project's own: `stvm.toml` `[sysmac]` over the defaults (`project_settings`)."""
    if settings is None:
        settings = project_settings(paths)
    files, manifest, root = expand_paths(paths)
    texts, read_diags = read_files(files, source_encoding(manifest))
    if read_diags:
        raise LoadError(read_diags, source_texts(texts))
    key = _cache_key(texts + _stdlib(settings), settings)
    cache_name = f"{key}.bin"
    payload = _cache().get(cache_name) if use_cache else None
    if payload is not None:
        try:
            # verified: only this user's stvm (holding the key) can have written it
            model, lowered, warnings, code_bytes, sources = pickle.loads(payload)
            return Project(model, lowered, marshal.loads(code_bytes), sources, settings, warnings, True, manifest, root)
        except Exception:  # a stale entry (an older stvm's classes) is rebuilt, never fatal
            pass
    analysis, diags, sources = _check_texts(texts, [], settings)
    if analysis is None:
        raise LoadError(diags, sources)
    lowered, code = _lower_and_compile(analysis, settings, texts, sources)
    warnings = [d for d in diags if not d.is_error]
    project = Project(analysis.model, lowered, code, sources, settings, warnings, False, manifest, root)
    if use_cache:
        try:
            payload = pickle.dumps((analysis.model, lowered, warnings, marshal.dumps(code), sources),
                                   protocol=pickle.HIGHEST_PROTOCOL)
        except (pickle.PicklingError, RecursionError, TypeError):
            payload = None
        if payload is not None:
            _cache().put(cache_name, payload)
            _cache().prune("*.bin", CACHE_MAX_ENTRIES)
    return project


CACHE_MAX_ENTRIES = 200


def nothing_to_run(project: Project, files: Sequence[str | Path] = ()) -> str | None:
    """Why `project` cannot run (no PROGRAM and no CONFIGURATION task), or None if it can."""
    if project.model.tasks or project.model.default_programs:
        return None
    names = ", ".join(str(f) for f in files) or "the project"
    return (f"no PROGRAM in {names}: a run needs a PROGRAM (or a CONFIGURATION with tasks); "
            f"FUNCTIONs and FUNCTION_BLOCKs alone are a library (stvm check FILE checks it)")
