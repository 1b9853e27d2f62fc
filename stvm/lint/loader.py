"""Parse and check the files to lint, with a parse cache.

Lint needs the checked syntax tree and the checker's per-expression facts, which the compile
cache does not keep; parsing is most of the time (Lark in Python), so each file's tree is
pickled under the stvm cache directory, keyed by its text, the settings and stvm's own code. The
entries go through the signed cache (stvm/cache.py): a pickle is only loaded when it carries the
user's HMAC tag, so a shared or CI `STVM_CACHE_DIR` cannot hand lint a forged pickle.
The checker then runs on the cached trees (fast) and gives the facts.
"""

from __future__ import annotations

import hashlib
import pickle
from dataclasses import dataclass, field
from pathlib import Path
from typing import Sequence

from stvm.cache import SignedCache, default_folder
from stvm.diagnostics import Diagnostic, has_errors, sort_key
from stvm.settings import SysmacSettings
from stvm import syntax
from stvm.syntax.nodes import Span
from stvm.version import __version__
from stvm.source import SourceError, read_source
from stvm.semantics import analyze


@dataclass
class Loaded:
    analysis: object | None            # semantics Analysis, None when the sources have errors
    diagnostics: list[Diagnostic]      # the checker's (errors and warnings)
    sources: dict[str, str]            # display path → text, stdlib included
    files: list[str]                   # the user files, as given/expanded
    manifest: dict = field(default_factory=dict)
    root: Path | None = None


_CACHES: dict[Path, SignedCache] = {}


def _cache() -> SignedCache:
    folder = default_folder() / "lint-ast"
    cached = _CACHES.get(folder)
    if cached is None:
        cached = _CACHES[folder] = SignedCache(folder)
    return cached


_CODE_DIGEST: list[str] = []


def _code_digest() -> str:
    """Hash of the parser's code: a cached tree is only valid for the parser that made it."""
    if not _CODE_DIGEST:
        digest = hashlib.sha256(__version__.encode())
        folder = Path(syntax.__file__).resolve().parent
        for path in sorted(folder.iterdir()):
            if path.suffix in (".py", ".lark"):
                digest.update(path.name.encode() + b"\0" + path.read_bytes())
        _CODE_DIGEST.append(digest.hexdigest())
    return _CODE_DIGEST[0]


_MEMO: dict[str, tuple] = {}


def parse_cached(text: str, name: str, settings: SysmacSettings, use_cache: bool = True):
    """(unit, diagnostics) of one ST text; memoised in-process and pickled on disk."""
    from stvm.syntax.parser import parse_text   # lazy: start-up
    key = hashlib.sha256(b"\0".join([_code_digest().encode(), repr(settings).encode(), name.encode(),
                                     text.encode("utf-8", "replace")])).hexdigest()
    if key in _MEMO:
        unit, diags = _MEMO[key]
        return unit, list(diags)
    name_in_cache = f"{key}.pickle"
    if use_cache:
        payload = _cache().get(name_in_cache)     # None unless signed with the user's key
        if payload is not None:
            try:
                unit, diags = pickle.loads(payload)
                _MEMO[key] = (unit, diags)
                return unit, list(diags)
            except Exception:  # damaged (or from an incompatible stvm): parse again
                pass
    unit, diags = parse_text(text, name, settings)
    _MEMO[key] = (unit, diags)
    if use_cache:
        try:
            _cache().put(name_in_cache, pickle.dumps((unit, diags), protocol=pickle.HIGHEST_PROTOCOL))
        except (pickle.PicklingError, RecursionError):
            pass
    return unit, list(diags)


def load_for_lint(paths: Sequence[str | Path], settings: SysmacSettings, use_cache: bool = True,
                  texts: dict[str, str] | None = None) -> Loaded:
    """Expand `paths` as `stvm check` does (a folder's *.st, a file's stvm.toml project), parse
    (cached) and check. `texts` overrides file contents (an editor's unsaved buffer)."""
    from stvm.project import expand_paths, read_source_text   # lazy: start-up
    from stvm.stdlib import NATIVE_FUNCTIONS, stdlib_sources   # lazy: start-up
    files, manifest, root = expand_paths(paths)
    diags: list[Diagnostic] = []
    sources: dict[str, str] = {}
    units = []
    for name, text in stdlib_sources(settings):
        unit, d = parse_cached(text, name, settings, use_cache)
        units.append(unit)
        diags += d
        sources[name] = text
    names = []
    for path in files:
        name = str(path)
        names.append(name)
        try:
            text = texts[name] if texts is not None and name in texts else read_source_text(Path(path))
        except OSError as exc:
            diags.append(Diagnostic.error(f"cannot read file: {exc.strerror or exc}", Span(name, 0, 0, 0, 0)))
            continue
        except SourceError as exc:   # a binary, mis-encoded or malformed XML file
            diags.append(Diagnostic.error(exc.message, Span(name, exc.line, exc.column, exc.line, exc.column + 1),
                                          "E001"))
            sources[name] = exc.text
            continue
        sources[name] = getattr(text, "original", text)   # a vendor XML file: excerpts show the XML
        unit, d = parse_cached(text, name, settings, use_cache)
        units.append(unit)
        diags += d
    analysis = None
    if not has_errors(diags):
        try:
            analysis = analyze(units, settings, NATIVE_FUNCTIONS)
            diags += analysis.diagnostics
        except RecursionError:
            diags.append(Diagnostic.error("the program is nested too deeply to analyse",
                                          Span(names[-1] if names else "<input>", 1, 1, 1, 2)))
    diags.sort(key=sort_key)
    if has_errors(diags):
        analysis = None
    return Loaded(analysis, diags, sources, names, manifest, root)
