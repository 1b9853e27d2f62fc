"""Stage above semantics: `stvm lint`, static analysis of checked ST for the bugs a PLC
engineer otherwise finds on the plant floor.

Entry point: `lint(paths, settings, select, ignore) -> LintReport`. Each POU gets a control-flow
graph (`cfg`), an interval/constant analysis across scans (`intervals`, on the solver in
`dataflow`) and, for step sequences, a typestate analysis of resources held between scans
(`machines`). Rules (`rules/`) read those facts and the checker's types; the registry gives
each a stable code (SAnnn), a summary, a rationale and an example (`stvm lint --explain`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterable, Sequence

from typing import TYPE_CHECKING

from stvm.diagnostics import Diagnostic
from stvm.settings import SysmacSettings

if TYPE_CHECKING:
    from stvm.project import Options, ProjectSpec
    from stvm.lint.config import LintConfig
    from stvm.lint.findings import Finding, Rule

__all__ = ["lint", "lint_analysis", "LintReport", "Finding", "Rule", "all_rules", "select_rules"]


def __getattr__(name):
    # lazy: start-up (`stvm.lint.cli` registers its sub-commands on every `stvm` call; the rule
    # registry and the config reader load only when lint runs)
    if name in ("all_rules", "select_rules"):
        from stvm.lint import registry   # lazy: start-up
        return getattr(registry, name)
    if name in ("Finding", "Rule"):
        from stvm.lint import findings   # lazy: start-up
        return getattr(findings, name)
    if name in ("LintConfig", "load_config", "suppressed"):
        from stvm.lint import config   # lazy: start-up
        return getattr(config, name)
    raise AttributeError(name)


@dataclass
class LintReport:
    findings: list[Finding]
    diagnostics: list[Diagnostic]       # the checker's: errors stop the analysis
    sources: dict[str, str]
    rules: list[Rule]
    suppressed: int = 0
    files: list[str] = field(default_factory=list)

    @property
    def has_errors(self) -> bool:
        return any(d.is_error for d in self.diagnostics)


def lint_analysis(analysis, settings: SysmacSettings, rules: Iterable[Rule], include_stdlib: bool = False,
                  files: set[str] | None = None) -> list[Finding]:
    """Every finding of `rules` on the checked project (user POUs; the stdlib with
    `include_stdlib`; only POUs of `files` when given), sorted by place."""
    from stvm.lint.context import ProjectContext   # lazy: start-up (see __getattr__)
    project = ProjectContext(analysis, settings)
    rules = list(rules)
    findings: list[Finding] = []
    seen: set[tuple] = set()
    for ctx in project.pou_contexts(include_stdlib):
        if files is not None and ctx.node.span.file not in files:
            continue
        for r in rules:
            for f in r.check(ctx):
                key = (f.code, f.span.file, f.span.line, f.span.column, f.message)
                if key not in seen:
                    seen.add(key)
                    findings.append(f)
    findings.sort(key=lambda f: (f.span.file, f.span.line, f.span.column, f.code))
    return findings


def _reported_files(paths: Sequence[str | Path], loaded: list[str]) -> set[str]:
    """Findings are reported for the files named and the files of the folders named; the other
    files of a file's project (its stvm.toml) are loaded for their declarations only."""
    wanted: set[Path] = set()
    folders: list[Path] = []
    for raw in paths:
        path = Path(raw).resolve()
        if path.is_dir():
            folders.append(path)
        else:
            wanted.add(path)
    return {name for name in loaded
            if Path(name).resolve() in wanted or Path(name).resolve().parent in folders}


def lint(paths: Sequence[str | Path], settings: "SysmacSettings | Options | ProjectSpec | None" = None,
         select: Iterable[str] | None = None, ignore: Iterable[str] = (), use_cache: bool = True,
         texts: dict[str, str] | None = None, config: "LintConfig | None" = None,
         include_stdlib: bool = False) -> LintReport:
    """Parse, check and lint `paths` (files or folders, as `stvm check`). `settings`: None or an
    `Options` (the command line's --sysmac, --dialect, --define) to lint with the project's own
    settings as `stvm check` does (its stvm.toml), explicit `SysmacSettings` to use those, or a
    resolved `ProjectSpec`. `select`/`ignore` take codes, prefixes (SA2) or names; the
    project's stvm.toml `[lint]` adds to them, and `(* stvm: noqa SAnnn *)` on a line
    suppresses that line's findings. `texts` replaces files' contents (an editor's buffers)."""
    from stvm.lint.config import load_config, suppressed   # lazy: start-up
    from stvm.lint.registry import select_rules   # lazy: start-up
    from stvm.project import check_stage, parse_stage   # lazy: start-up
    spec = _lint_spec(paths, settings, use_cache)
    checked = check_stage(parse_stage(spec, texts))
    files = checked.parsed.files
    if config is None:
        config = load_config(spec.manifest, spec.root)
    rules = select_rules(list(select or []) or config.select, list(ignore) + config.ignore)
    report = LintReport([], checked.diagnostics, checked.sources, rules, files=files)
    if checked.analysis is None:
        return report
    findings = lint_analysis(checked.analysis, spec.settings, rules, include_stdlib,
                             None if include_stdlib else _reported_files(paths, files))
    kept = []
    for f in findings:
        if suppressed(f, checked.sources, config):
            report.suppressed += 1
        else:
            kept.append(f)
    report.findings = kept
    return report


def _lint_spec(paths, settings, use_cache: bool):
    """The project `paths` name, resolved by the driver as every command resolves it."""
    from dataclasses import replace   # lazy: start-up
    from stvm.project import Options, ProjectSpec, resolve   # lazy: start-up
    if isinstance(settings, ProjectSpec):
        return replace(settings, use_cache=settings.use_cache and use_cache)
    if settings is None or isinstance(settings, Options):
        options = settings or Options()
        return resolve(paths, replace(options, use_cache=options.use_cache and use_cache))
    return resolve(paths, Options(use_cache=use_cache), settings)
