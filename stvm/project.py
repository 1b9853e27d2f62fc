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
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from stvm import __version__
from stvm.diagnostics import Diagnostic, has_errors, render, sort_key
from stvm.runtime.vm import GENERATED_FILENAME, VM
from stvm.settings import DEFAULT_SETTINGS, SysmacSettings

if TYPE_CHECKING:
    from stvm.lower import LoweredProject
    from stvm.semantics.model import ProjectModel

# The front end (Lark, the checker, the code generator) is imported only on a cache miss: a
# cached load needs none of it, which halves the start-up time of `stvm run`.

MANIFEST = "stvm.toml"


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
    file in a folder with `stvm.toml` means the project that manifest describes (so `stvm run st_src/PnP_Example.st` loads the
    whole thesis project)."""
    out: list[Path] = []
    manifest: dict = {}
    root: Path | None = None
    for raw in paths:
        path = Path(raw)
        if path.is_dir():
            listed = None
            if (path / MANIFEST).exists():
                manifest, root = _read_manifest(path / MANIFEST), path
                listed = manifest.get("project", {}).get("files")
            # a folder with a manifest that lists its files is that project (the files may be in
            # other folders, e.g. a library the project builds on); else every *.st in it
            out += [path / f for f in listed] if listed else sorted(path.glob("*.st"))
        else:
            out.append(path)
    if len(paths) == 1 and not Path(paths[0]).is_dir():
        folder = Path(paths[0]).parent
        if (folder / MANIFEST).exists():
            manifest, root = _read_manifest(folder / MANIFEST), folder
            listed = manifest.get("project", {}).get("files")
            files = [folder / f for f in listed] if listed else sorted(folder.glob("*.st"))
            out = files if Path(paths[0]).resolve() in {f.resolve() for f in files} else files + out
    seen: set[Path] = set()
    unique = []
    for p in out:
        key = p.resolve()
        if key not in seen:
            seen.add(key)
            unique.append(p)
    return unique, manifest, root


def _read_manifest(path: Path) -> dict:
    try:
        with path.open("rb") as fh:
            return tomllib.load(fh)
    except OSError as exc:
        raise ManifestError(f"{path}: cannot read the project manifest: {exc.strerror or exc}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ManifestError(f"{path}: not valid TOML: {exc}") from exc


class ManifestError(ValueError):
    """A project manifest (`stvm.toml`) that cannot be used; the message names the file."""


def project_settings(paths: Sequence[str | Path], overrides: Sequence[str] = ()) -> SysmacSettings:
    """The Sysmac settings of a run on `paths`: the spec's defaults, then the `[sysmac]` table of
    the project's `stvm.toml` (when the files belong to one), then `--sysmac NAME=VALUE`
    overrides; the last one wins. Raises ValueError (SettingError, ManifestError) that names
    the setting, the file and the allowed values."""
    _, manifest, root = expand_paths(paths)
    settings = DEFAULT_SETTINGS
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
    base = os.environ.get("STVM_CACHE_DIR")
    if base:
        return Path(base)
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "stvm"


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
    return digest.hexdigest()


def read_source(path: Path) -> str:
    data = path.read_bytes()
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    return data.decode("utf-8", errors="replace")


def _read_all(paths: Sequence[Path]) -> tuple[list[tuple[str, str]], list[Diagnostic]]:
    from stvm.syntax.nodes import Span
    texts = []
    diags = []
    for path in paths:
        try:
            texts.append((str(path), read_source(path)))
        except OSError as exc:
            diags.append(Diagnostic.error(f"cannot read file: {exc.strerror or exc}", Span(str(path), 0, 0, 0, 0)))
    return texts, diags


def check(paths: Sequence[str | Path], settings: SysmacSettings | None = None, generate: bool = False):
    """Parse and check: (analysis or None, diagnostics sorted, sources). With `generate`, also
    lower and compile, so limits that only code generation meets are reported too. Without
    `settings`, the project's own (`project_settings`)."""
    if settings is None:
        settings = project_settings(paths)
    files, _, _ = expand_paths(paths)
    texts, diags = _read_all(files)
    analysis, diags, sources = _check_texts(texts, diags, settings)
    if generate and analysis is not None:
        try:
            _lower_and_compile(analysis, settings, texts, sources)
        except LoadError as exc:
            diags = diags + exc.diagnostics
            analysis = None
    return analysis, diags, sources


_STDLIB_UNITS: dict[str, tuple[list, list[Diagnostic]]] = {}


def _stdlib_units(settings: SysmacSettings) -> tuple[list, list[Diagnostic], dict[str, str]]:
    """The parsed stdlib, memoised in-process and pickled in the cache dir (it never changes
    between runs of one stvm version, and parsing it is most of a cold start)."""
    texts = _stdlib(settings)
    key = _cache_key(texts, settings)
    sources = dict(texts)
    if key in _STDLIB_UNITS:
        units, diags = _STDLIB_UNITS[key]
        return units, list(diags), sources
    from stvm.syntax.parser import parse_text
    path = _cache_dir() / f"stdlib-{key}.ast"
    try:
        with path.open("rb") as fh:
            units, diags = pickle.load(fh)
    except Exception:  # missing or unreadable: parse again
        units, diags = [], []
        for name, text in texts:
            unit, d = parse_text(text, name, settings)
            units.append(unit)
            diags += d
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(".tmp%d" % os.getpid())
            with tmp.open("wb") as fh:
                pickle.dump((units, diags), fh, protocol=pickle.HIGHEST_PROTOCOL)
            tmp.replace(path)
        except OSError:
            pass
    _STDLIB_UNITS[key] = (units, diags)
    return units, list(diags), sources


def _check_texts(texts, diags, settings):
    from stvm.semantics import analyze
    from stvm.syntax.parser import parse_text
    sources = dict(texts)
    units, stdlib_diags, stdlib_sources = _stdlib_units(settings)
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
    """Generate and compile the Python module; Python's own limits become diagnostics."""
    from stvm.lower import lower_project
    from stvm.syntax.nodes import Span
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
    from stvm.syntax.nodes import Span
    return Diagnostic.error("expression or statement nesting too deep for stvm (split it into smaller parts)",
                            Span(file, 1, 1, 1, 2), "E003")


def load(paths: Sequence[str | Path], settings: SysmacSettings | None = None, use_cache: bool = True) -> Project:
    """Load a runnable project from ST files (raises LoadError with every diagnostic). Without
    `settings`, the project's own: `stvm.toml` `[sysmac]` over the defaults (`project_settings`)."""
    if settings is None:
        settings = project_settings(paths)
    files, manifest, root = expand_paths(paths)
    texts, read_diags = _read_all(files)
    if read_diags:
        raise LoadError(read_diags, {})
    key = _cache_key(texts + _stdlib(settings), settings)
    cache_file = _cache_dir() / f"{key}.bin"
    if use_cache and cache_file.exists():
        try:
            with cache_file.open("rb") as fh:
                model, lowered, warnings, code_bytes, sources = pickle.load(fh)
            os.utime(cache_file)   # recently used: pruning drops the oldest first
            return Project(model, lowered, marshal.loads(code_bytes), sources, settings, warnings, True, manifest, root)
        except Exception:  # a stale or damaged cache entry is rebuilt, never fatal
            pass
    analysis, diags, sources = _check_texts(texts, [], settings)
    if analysis is None:
        raise LoadError(diags, sources)
    lowered, code = _lower_and_compile(analysis, settings, texts, sources)
    warnings = [d for d in diags if not d.is_error]
    project = Project(analysis.model, lowered, code, sources, settings, warnings, False, manifest, root)
    if use_cache:
        try:
            cache_file.parent.mkdir(parents=True, exist_ok=True)
            tmp = cache_file.with_suffix(".tmp%d" % os.getpid())
            with tmp.open("wb") as fh:
                pickle.dump((analysis.model, lowered, warnings, marshal.dumps(code), sources), fh,
                            protocol=pickle.HIGHEST_PROTOCOL)
            tmp.replace(cache_file)
            _prune_cache(cache_file.parent)
        except OSError:
            pass
    return project


CACHE_MAX_ENTRIES = 200


def _prune_cache(folder: Path) -> None:
    """Keep the cache from growing without bound: drop the least recently used entries."""
    entries = sorted(folder.glob("*.bin"), key=lambda p: p.stat().st_mtime)
    for old in entries[:-CACHE_MAX_ENTRIES]:
        try:
            old.unlink()
        except OSError:
            pass
