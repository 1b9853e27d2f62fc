"""The one place the language server meets the pipeline (stvm/project.py): which files make the
project of an open file, its settings, and a check of it with the editor's unsaved buffers in
place of the files' text.

Everything here goes through `stvm.project`'s public functions (`resolve`,
`read_source_text`, `stdlib_units`, `parse_unit`) and the checker's `analyze`, so the manifest,
dialect, defines and libraries are those of `stvm check`. When the driver's API changes, this
module is the only one to adapt.

Incremental where the pipeline allows. The session keeps what an edit does not change: each
file's parsed unit with the text it came from (an edit re-parses only the file edited; the
stdlib is parsed once per settings), each unopened file's text with its stat, the project's
files and settings with the stat of its manifest, folders and `.plcproj`, and the
declarations-only form of each unit. A full check runs the checker over every body of the
project and the stdlib's declarations (the stdlib's bodies give no diagnostic the editor shows,
and the index does not walk them). While typing, a *focused* check
(`Driver.check(..., focus=file, previous=last full result)`) gives the edited file's
diagnostics sooner: every declaration of the project is still indexed and checked (so names,
types and signatures resolve as in the full check), but only the bodies of the edited file and
of its dependents are checked, and of the stdlib only the POUs the project's text names
(`_stdlib_wanted`); the other files' bodies are left out and their diagnostics are the previous
check's. A dependent is a file whose text names something the edited file declares, and it is
only re-checked when the edited file's declarations changed (an edit inside a body changes what
no other file sees). The server then runs the full check (recursion through another file's
body, which a focused check cannot see, and the index), as before.
"""

from __future__ import annotations

import hashlib
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

from stvm.diagnostics import Diagnostic, has_errors, sort_key
from stvm.source import SourceError, Span

VENDOR_SUFFIXES = (".tcpou", ".tcdut", ".tcgvl", ".tcio", ".xml")
SOURCE_SUFFIXES = (".st",) + VENDOR_SUFFIXES
MANIFEST = "stvm.toml"


def is_source(path: Path) -> bool:
    return path.suffix.lower() in SOURCE_SUFFIXES


def project_root_of(path: Path) -> list[Path]:
    """What `stvm check` is given for an open file. A file of a folder with `stvm.toml` is that
    project (expand_paths does it). Otherwise (a choice, documented in docs/editor.md) the
    file's folder: every .st file in it, or for a TwinCAT/PLCopen file the folder holding its
    `.plcproj` (up to three levels up: POUs/, DUTs/, GVLs/) — so names from the other files of
    the folder resolve, as they do in CODESYS's and TwinCAT's project tree."""
    folder = path.parent
    if (folder / MANIFEST).exists():
        return [path]
    if path.suffix.lower() in VENDOR_SUFFIXES:
        for up in [folder, *list(folder.parents)[:3]]:
            if any(up.glob("*.plcproj")):
                return [up]
        return [folder]
    if path.suffix.lower() == ".st" and any(p.is_file() for p in folder.glob("*.st")):
        return [folder]
    return [path]   # e.g. a new buffer, never saved, alone in its folder: that file only


def project_identity(path: Path) -> tuple[str, ...]:
    """One key per project: its manifest when it has one (every file of st_src/ is the same
    project), else what `project_root_of` checks."""
    manifest = path.parent / MANIFEST
    if manifest.exists():
        return (str(manifest.resolve()),)
    return tuple(str(p.resolve()) for p in project_root_of(path))


@dataclass
class CheckResult:
    """One check of a project: the analysis (None when a file has a syntax error), every
    diagnostic, the ST text of every file (vendor XML: its ST laid out on the XML's lines), the
    files' own text and the project's files."""

    analysis: object | None
    diagnostics: list[Diagnostic]
    texts: dict[str, str]
    files: list[str]
    settings: object
    manifest: dict
    root: Path | None
    seconds: float = 0.0
    units: dict[str, object] = field(default_factory=dict)
    originals: dict[str, str] = field(default_factory=dict)   # each file's own text (vendor XML: the XML)
    focused: frozenset = frozenset()   # a focused check: the files whose bodies were checked (else all)
    stages: dict[str, float] = field(default_factory=dict)   # seconds per stage (bench/bench_lsp.py)


class Stopwatch:
    """Seconds spent per named stage, in the order the stages ran (what `stvm.timings` reports
    and bench/bench_lsp.py tabulates)."""

    def __init__(self) -> None:
        self.stages: dict[str, float] = {}
        self._last = time.perf_counter()

    def lap(self, stage: str) -> None:
        now = time.perf_counter()
        self.stages[stage] = self.stages.get(stage, 0.0) + now - self._last
        self._last = now


@dataclass
class _Project:
    """What `resolve` said of a project, with the file-system stamps it was read under: the
    same stamps, the same answer (no manifest, folder or .plcproj changed)."""

    settings: object
    files: list[Path]
    names: list[str]            # the files' resolved paths
    manifest: dict
    root: Path | None
    watched: tuple[Path, ...]
    stamp: tuple


def _stamp(paths: tuple[Path, ...]) -> tuple:
    """(mtime, size, inode) of each path, None for one that is missing: a folder's mtime moves
    when a file is added, removed or renamed in it, a file's when it is written."""
    out = []
    for p in paths:
        try:
            st = os.stat(p)
            out.append((st.st_mtime_ns, st.st_size, st.st_ino))
        except OSError:
            out.append(None)
    return tuple(out)


class Driver:
    """Checks projects with the editor's buffers. The session keeps what an edit does not change
    (module docstring): each file's parsed unit keyed by its text, each unopened file's text
    keyed by its stat, the project's files and settings keyed by the stat of its manifest,
    folders and .plcproj, and the declarations-only form of every unit."""

    def __init__(self, options=None) -> None:
        from stvm.project import Options   # lazy: start-up
        self.options = options if options is not None else Options()   # `stvm lsp` options + the client's
        self._units: dict[tuple[str, str, str], tuple[object, list[Diagnostic]]] = {}
        self._projects: dict[tuple, _Project] = {}
        self._reads: dict[str, tuple] = {}          # file → (stat stamp, encoding, text, digest)
        self._declarations: dict[int, tuple[object, object]] = {}   # id(unit) → (unit, its declarations)
        self._names: dict[str, tuple[str, frozenset]] = {}          # file → (digest, identifiers in it)
        self._stdlib_names: tuple | None = None     # (stdlib units, {POU name → identifiers of its text})

    def forget(self) -> None:
        """Drop what was read from the disk (a save, an open: the files may have changed in ways
        a stat does not show); parsed units stay, keyed by their text."""
        self._projects.clear()
        self._reads.clear()

    def project(self, path: Path) -> _Project:
        """The files, settings and manifest of the project of `path` (resolved path), as
        `stvm check` resolves them; resolved again only when a file it was read from changed."""
        from stvm.project import resolve   # lazy: start-up
        paths = project_root_of(path)
        key = (tuple(paths), path, self.options)
        known = self._projects.get(key)
        if known is not None and _stamp(known.watched) == known.stamp:
            return known
        spec = resolve(paths, self.options)
        files = list(spec.files)
        names = [str(f.resolve()) for f in files]
        if str(path) not in names:
            files.append(path)      # an open file the manifest does not list: checked with it
            names.append(str(path))
        folders = {p if p.is_dir() else p.parent for p in paths} | {Path(n).parent for n in names}
        watched = sorted(folders) + [f / MANIFEST for f in sorted(folders)] + \
            sorted(q for f in folders if f.is_dir() for q in f.glob("*.plcproj"))
        project = _Project(spec.settings, files, names, spec.manifest, spec.root, tuple(watched), ())
        project.stamp = _stamp(project.watched)
        if len(self._projects) > 16:
            self._projects.clear()
        self._projects[key] = project
        return project

    def read(self, file: Path, name: str, encoding: str) -> tuple[str, str]:
        """(text, digest of its own text) of an unopened file, read again only when its stat
        changed; raises SourceError and OSError as `read_source_text` does."""
        from stvm.project import read_source_text   # lazy: start-up
        try:
            st = os.stat(file)
            stamp = (st.st_mtime_ns, st.st_size, st.st_ino)
        except OSError:
            stamp = None
        known = self._reads.get(name)
        if stamp is not None and known is not None and known[0] == stamp and known[1] == encoding:
            return known[2], known[3]
        text = read_source_text(file, encoding)
        digest = _digest(getattr(text, "original", None) or str(text))
        if stamp is not None:
            self._reads[name] = (stamp, encoding, text, digest)
        return text, digest

    def declarations(self, unit):
        """`declarations_of(unit)`, made once per unit object (an unchanged file keeps its unit)."""
        known = self._declarations.get(id(unit))
        if known is not None and known[0] is unit:
            return known[1]
        out = declarations_of(unit)
        self._declarations[id(unit)] = (unit, out)
        return out

    def check(self, path: Path, buffers: dict[str, str], focus: bool = False,
              previous: CheckResult | None = None) -> CheckResult:
        """Check the project of the open file `path`; `buffers` (file name → editor text) replace
        the files' content. With `focus` and the `previous` full result of the same project, a
        focused check of `path` (module docstring) when one can be made, else a full one. The
        collector is paused meanwhile, as `stvm check` does: the checker builds many small
        objects that live as long as the result, and collecting them while they are built
        doubled the time of a check of st_src/."""
        from stvm.heap import collector_paused   # lazy: start-up
        with collector_paused(age_survivors=True):
            return self._check(path, buffers, previous if focus else None)

    def _check(self, path: Path, buffers: dict[str, str], previous: CheckResult | None = None) -> CheckResult:
        from stvm.project import parse_unit, stdlib_units   # lazy: start-up
        from stvm.semantics import analyze   # lazy: start-up
        from stvm.stdlib import NATIVE_FUNCTIONS   # lazy: start-up
        started = time.perf_counter()
        watch = Stopwatch()
        path = path.resolve()
        project = self.project(path)
        settings, manifest, root = project.settings, project.manifest, project.root
        encoding = manifest.get("project", {}).get("encoding", "utf-8")
        watch.lap("project: manifest, settings, files")
        std_units, diags, std_texts = stdlib_units(settings)
        watch.lap("stdlib units")
        units = list(std_units)
        texts: dict[str, str] = dict(std_texts)
        names: list[str] = []
        unit_of: dict[str, object] = {}
        originals: dict[str, str] = {}
        settings_key = repr(settings)
        for file, name in zip(project.files, project.names):
            names.append(name)
            try:
                if name in buffers:
                    text = buffers[name]
                    if file.suffix.lower() in VENDOR_SUFFIXES:
                        from stvm.syntax.vendor_xml import translate   # lazy: vendor XML only
                        text = translate(text, name)
                    digest = _digest(getattr(text, "original", None) or str(text))
                else:
                    text, digest = self.read(file, name, encoding)
            except SourceError as exc:
                diags.append(Diagnostic.error(exc.message, Span(name, exc.line, exc.column, exc.line,
                                                                 exc.column + 1), exc.code))
                texts[name] = exc.text
                continue
            except OSError as exc:
                diags.append(Diagnostic.error(f"cannot read file: {exc.strerror or exc}", Span(name, 0, 0, 0, 0), "E006"))
                continue
            texts[name] = str(text)
            originals[name] = getattr(text, "original", None) or str(text)
            key = (name, settings_key, digest)
            parsed = self._units.get(key)
            if parsed is None:
                watch.lap("read files")
                parsed = parse_unit(name, text, settings, use_cache=False)
                for old in [k for k in self._units if k[0] == name]:
                    del self._units[old]      # one version of each file kept
                self._units[key] = parsed
                watch.lap("parse changed files")
            unit, d = parsed
            units.append(unit)
            unit_of[name] = unit
            diags += d
        watch.lap("read files")
        analysis = None
        focused = frozenset()
        if not has_errors(diags):
            bodies = None if previous is None else \
                _bodies_to_check(str(path), previous, names, unit_of, texts, settings, self.declarations)
            if bodies is not None:
                focused = frozenset(bodies)
                wanted = self._stdlib_wanted(std_units, std_texts, names, texts)
                units = [_only_pous(self.declarations(u), wanted) for u in std_units] + \
                        [unit_of[n] if n in bodies else self.declarations(unit_of[n]) for n in names if n in unit_of]
            else:
                # the stdlib's bodies give no diagnostic the editor shows and the index does
                # not walk them (stvm/lsp/index.py): their declarations are enough
                units = [self.declarations(u) for u in std_units] + [unit_of[n] for n in names if n in unit_of]
            live = {id(u) for u in std_units} | {id(u) for u in unit_of.values()}
            if len(self._declarations) > 2 * len(live):
                self._declarations = {k: v for k, v in self._declarations.items() if k in live}
        watch.lap("focus: files to check, declarations")
        if not has_errors(diags):
            try:
                analysis = analyze(units, settings, NATIVE_FUNCTIONS)
                diags += analysis.diagnostics
            except RecursionError:
                diags.append(Diagnostic.error("the program is nested too deeply to analyse",
                                              Span(names[-1] if names else "<input>", 1, 1, 1, 2), "E003"))
        if focused:
            # the files whose bodies were left out keep the verdict of the last full check
            diags = [d for d in diags if d.span.file in focused] + \
                    [d for d in previous.diagnostics if d.span.file not in focused]
        watch.lap("checker (analyze)")
        diags.sort(key=sort_key)
        watch.lap("merge, sort diagnostics")
        return CheckResult(analysis, diags, texts, names, settings, manifest, root,
                           time.perf_counter() - started, unit_of, originals, focused, watch.stages)

    def _identifiers(self, name: str, text: str) -> frozenset:
        digest = _digest(text)
        known = self._names.get(name)
        if known is not None and known[0] == digest:
            return known[1]
        found = frozenset(_names_in(text))
        self._names[name] = (digest, found)
        return found

    def _stdlib_wanted(self, std_units: list, std_texts: dict[str, str], names: list[str],
                       texts: dict[str, str]) -> set[str]:
        """The stdlib POUs a focused check declares: those whose name the project's text
        contains, and, through their own declarations, the ones they name. The checker finds
        a stdlib POU only by its name written somewhere (no rule of it names one implicitly),
        so the project's verdict is the same with the other ~850 left out, and declaring those
        was most of a focused check's time (docs/editor.md, "Speed")."""
        if self._stdlib_names is None or self._stdlib_names[0] is not std_units:
            by_pou: dict[str, set[str]] = {}
            for unit in std_units:
                lines = std_texts.get(unit.path, "").splitlines()
                for pou in unit.pous:
                    text = "\n".join(lines[max(pou.span.line - 1, 0):max(pou.span.end_line, pou.span.line)])
                    by_pou.setdefault(pou.name.lower(), set()).update(_names_in(text))
            self._stdlib_names = (std_units, by_pou)
        by_pou = self._stdlib_names[1]
        used: set[str] = set()
        for name in names:
            used |= self._identifiers(name, texts.get(name, ""))
        wanted: set[str] = set()
        todo = [w for w in used if w in by_pou]
        while todo:
            pou = todo.pop()
            if pou not in wanted:
                wanted.add(pou)
                todo += [w for w in by_pou[pou] if w in by_pou and w not in wanted]
        return wanted

    def lint_findings(self, result: CheckResult, only: set[str] | None = None) -> list:
        """The lint findings of a checked project (the files `only`, else the project's), with the
        project's `[lint]` configuration and `noqa` comments applied."""
        if result.analysis is None:
            return []
        from stvm.lint import lint_analysis   # lazy: start-up
        from stvm.lint.config import load_config, suppressed   # lazy: start-up
        from stvm.lint.registry import select_rules   # lazy: start-up
        config = load_config(result.manifest, result.root)
        rules = select_rules(list(config.select), list(config.ignore))
        findings = lint_analysis(result.analysis, result.settings, rules, False,
                                 only if only is not None else set(result.files))
        return [f for f in findings if not suppressed(f, result.texts, config)]


def _only_pous(unit, wanted: set[str]):
    """`unit` with the POUs named in `wanted` only."""
    from dataclasses import replace   # lazy: start-up
    return replace(unit, pous=tuple(pou for pou in unit.pous if pou.name.lower() in wanted))


def declarations_of(unit):
    """`unit` without the statements of its POUs, methods and property accessors: what the
    other files of a project see of it (nodes compare without their spans, so two versions of a
    file whose declarations are the same compare equal however its lines moved)."""
    from dataclasses import replace   # lazy: start-up
    pous = tuple(replace(pou, body=(), methods=tuple(replace(m, body=()) for m in pou.methods),
                         properties=tuple(replace(prop, getter=prop.getter and replace(prop.getter, body=()),
                                                  setter=prop.setter and replace(prop.setter, body=()))
                                          for prop in pou.properties))
                 for pou in unit.pous)
    return replace(unit, pous=pous)


_IDENT = None


def _names_in(text: str) -> set[str]:
    global _IDENT
    if _IDENT is None:
        import re   # lazy: start-up
        _IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
    return {m.lower() for m in _IDENT.findall(text)}


def _declared_names(unit) -> set[str]:
    """The global names `unit` declares: its POUs, its global variables and their list's name."""
    out = {pou.name.lower() for pou in unit.pous}
    for block in unit.globals:
        out |= {name.lower() for decl in block.block.decls for name, _ in decl.names}
        if block.gvl:
            out.add(block.gvl.lower())
    return out


def _bodies_to_check(focus: str, previous: CheckResult, names: list[str], unit_of: dict,
                     texts: dict[str, str], settings, declarations=None) -> set[str] | None:
    """The files whose bodies a focused check of `focus` checks, or None when a full check is
    needed (no full previous check of the same files and settings, another file changed too)."""
    if previous.analysis is None or previous.focused or previous.files != names \
            or repr(previous.settings) != repr(settings) or focus not in unit_of:
        return None
    if any(previous.texts.get(name) != texts.get(name) for name in names if name != focus):
        return None
    old = previous.units.get(focus)
    if old is None:
        return None
    new = unit_of[focus]
    declarations = declarations or declarations_of
    if declarations(old) == declarations(new):
        return {focus}
    if old.types or new.types:
        return None     # a TYPE's enumerators are used bare: no cheap test finds its dependents
    # the declarations changed: the files that name something it declares (before or after)
    declared = _declared_names(old) | _declared_names(new)
    return {focus} | {name for name in names if name != focus and declared & _names_in(texts.get(name, ""))}


def _digest(text: str) -> str:
    return hashlib.blake2b(text.encode("utf-8", "surrogatepass"), digest_size=16).hexdigest()


def stdlib_folder() -> Path:
    """Where the stdlib's sources are written so an editor can open them (go to definition into
    `<stdlib>/iec_standard.st`): the cache folder's `lsp-stdlib/`, private to the user."""
    from stvm.folders import default_folder   # lazy: start-up
    folder = default_folder() / "lsp-stdlib"
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    return folder


def stdlib_path(display_name: str, text: str) -> Path:
    """The file holding stdlib source `display_name` (`<stdlib>/x.st`) with `text`, written once
    per content (read-only: it is a view of stvm's library, not a file to edit)."""
    base = display_name.split("/", 1)[-1] if display_name.startswith("<stdlib") else Path(display_name).name
    folder = stdlib_folder() / _digest(text)[:12]
    target = folder / base
    if not target.exists():
        folder.mkdir(parents=True, exist_ok=True, mode=0o700)
        tmp = folder / f".{base}.{os.getpid()}"
        tmp.write_text(text, encoding="utf-8")
        os.chmod(tmp, 0o400)
        os.replace(tmp, target)
    return target
