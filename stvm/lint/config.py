"""Suppression: `(* stvm: noqa SA201 *)` (or `// stvm: noqa SA201, SA3`) on the finding's line,
and the `[lint]` table of the project's stvm.toml::

    [lint]
    select = ["SA"]                 # default: every rule
    ignore = ["SA304"]              # codes, prefixes (SA3) or names (concat-overflow)

    [lint.per-file-ignores]
    "Program_Example.st" = ["SA105"]   # glob relative to the stvm.toml folder

A bare `(* stvm: noqa *)` suppresses every rule on that line.
"""

from __future__ import annotations

import fnmatch
import re
from dataclasses import dataclass, field
from pathlib import Path

from stvm.lint.findings import Finding
from stvm.lint.registry import matching, resolve_patterns

_NOQA = re.compile(r"(?:\(\*|//)\s*stvm:\s*noqa\b(?P<codes>[^*\n]*)", re.IGNORECASE)


class ConfigError(ValueError):
    pass


@dataclass
class LintConfig:
    select: list[str] = field(default_factory=list)
    ignore: list[str] = field(default_factory=list)
    per_file_ignores: dict[str, list[str]] = field(default_factory=dict)
    root: Path | None = None


def load_config(manifest: dict, root: Path | None) -> LintConfig:
    """The `[lint]` table of a manifest (already read by stvm.project.expand_paths)."""
    table = manifest.get("lint", {}) if isinstance(manifest, dict) else {}
    if not isinstance(table, dict):
        raise ConfigError("stvm.toml: [lint] must be a table")

    def codes(value, where: str) -> list[str]:
        if isinstance(value, str):
            value = [value]
        if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
            raise ConfigError(f"stvm.toml: {where} must be a list of rule codes")
        try:
            return resolve_patterns(value)
        except ValueError as exc:
            raise ConfigError(f"stvm.toml: {where}: {exc}") from exc

    unknown = set(table) - {"select", "ignore", "per-file-ignores"}
    if unknown:
        raise ConfigError(f"stvm.toml: unknown key(s) in [lint]: {', '.join(sorted(unknown))}")
    per_file = table.get("per-file-ignores", {})
    if not isinstance(per_file, dict):
        raise ConfigError("stvm.toml: [lint.per-file-ignores] must be a table of glob = [codes]")
    return LintConfig(codes(table.get("select", []), "[lint] select"), codes(table.get("ignore", []), "[lint] ignore"),
                      {glob: codes(v, f"[lint.per-file-ignores] {glob!r}") for glob, v in per_file.items()}, root)


def noqa_codes(line: str) -> set[str] | None:
    """The rule codes a line's noqa comment names; empty set = all; None = no noqa comment."""
    match = _NOQA.search(line)
    if match is None:
        return None
    text = match.group("codes").replace("*)", " ")
    words = [w for w in re.split(r"[\s,]+", text) if w]
    patterns = [w for w in words if re.fullmatch(r"SA\d{0,3}", w, re.IGNORECASE)]
    return set(matching(patterns)) if patterns else set()


def suppressed(finding: Finding, sources: dict[str, str], config: LintConfig) -> bool:
    text = sources.get(finding.span.file)
    if text is not None and finding.span.line > 0:
        lines = text.splitlines()
        if finding.span.line <= len(lines):
            codes = noqa_codes(lines[finding.span.line - 1])
            if codes is not None and (not codes or finding.code in codes):
                return True
    if config.per_file_ignores:
        path = Path(finding.span.file)
        rel = path.name
        if config.root is not None:
            try:
                rel = path.resolve().relative_to(config.root.resolve()).as_posix()
            except ValueError:
                rel = path.as_posix()
        for glob, codes in config.per_file_ignores.items():
            if fnmatch.fnmatch(rel, glob) and finding.code in set(matching(codes)):
                return True
    return False
