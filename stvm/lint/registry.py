"""The rule registry: every rule of `stvm.lint.rules` (registered by importing it), and the
selection of rules by code, prefix or name (`--select`, `--ignore`, noqa lists)."""

from __future__ import annotations

from typing import Iterable, Iterator

import stvm.lint.rules  # noqa: F401  (importing it registers every rule)
from stvm.lint.findings import RULES, Rule

def all_rules() -> list[Rule]:
    return [RULES[code] for code in sorted(RULES)]


class SelectionError(ValueError):
    pass


def _matches(rule_: Rule, pattern: str) -> bool:
    p = pattern.strip()
    if not p:
        return False
    if p.upper() == "ALL":
        return True
    return rule_.code.upper().startswith(p.upper()) or rule_.name == p.lower()


def resolve_patterns(patterns: Iterable[str]) -> list[str]:
    """Validate codes/prefixes/names; raises SelectionError naming an unknown one."""
    rules = all_rules()
    out = []
    for raw in patterns:
        for pattern in raw.split(","):
            pattern = pattern.strip()
            if not pattern:
                continue
            if not any(_matches(r, pattern) for r in rules):
                raise SelectionError(f"unknown rule {pattern!r} (codes SA101…SA502, prefixes like SA2, "
                                     f"or names like read-before-write; see stvm lint --explain ALL)")
            out.append(pattern)
    return out


def select_rules(select: Iterable[str] | None = None, ignore: Iterable[str] = ()) -> list[Rule]:
    """Rules matching `select` (all when None or empty) minus those matching `ignore`."""
    select = resolve_patterns(select or [])
    ignore = resolve_patterns(ignore)
    out = []
    for r in all_rules():
        if select and not any(_matches(r, p) for p in select):
            continue
        if any(_matches(r, p) for p in ignore):
            continue
        out.append(r)
    return out


def matching(codes: Iterable[str]) -> Iterator[str]:
    """Rule codes that any of these patterns match (for noqa lists and per-file ignores)."""
    patterns = list(codes)
    for r in all_rules():
        if any(_matches(r, p) for p in patterns):
            yield r.code
