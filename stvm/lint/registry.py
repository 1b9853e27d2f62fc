"""The rule registry: stable codes, names, one-line summaries, rationale and examples.

Codes never change meaning once released; a retired rule keeps its code reserved. The hundreds
digit is the family:

| codes  | family                                  |
|--------|-----------------------------------------|
| SA1xx  | data flow (reads, writes, calls)        |
| SA2xx  | ranges (indices, overflow, division)    |
| SA3xx  | formatting and protocol                 |
| SA4xx  | control flow                            |
| SA5xx  | resources held across scans             |
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterable, Iterator

from stvm.syntax.nodes import Span

FAMILIES = {
    "SA1": "Data flow",
    "SA2": "Ranges",
    "SA3": "Formatting and protocol",
    "SA4": "Control flow",
    "SA5": "Resources",
}


@dataclass(frozen=True)
class Finding:
    code: str
    message: str
    span: Span


@dataclass(frozen=True)
class Rule:
    code: str
    name: str              # kebab-case, also accepted by --select/--ignore
    summary: str           # one line
    rationale: str         # why it matters on a controller (markdown)
    example: str           # ST that triggers the rule
    fixed: str             # the same code without the finding
    check: Callable[..., Iterable[Finding]]
    thesis: str = ""       # where the thesis code shows it (st_src/README.md, ERRATA.md, findings)

    @property
    def family(self) -> str:
        return FAMILIES[self.code[:3]]


RULES: dict[str, Rule] = {}


def rule(code: str, name: str, summary: str, rationale: str, example: str, fixed: str, thesis: str = ""):
    """Register the decorated `check(ctx) -> Iterable[Finding]` as a rule."""
    def register(check):
        if code in RULES:
            raise AssertionError(f"duplicate rule code {code}")
        RULES[code] = Rule(code, name, summary, _dedent(rationale), _dedent(example), _dedent(fixed), check,
                           _dedent(thesis))
        return check
    return register


def _dedent(text: str) -> str:
    import textwrap
    return textwrap.dedent(text).strip("\n")


def all_rules() -> list[Rule]:
    from stvm.lint import rules  # noqa: F401  (registers every rule)
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
