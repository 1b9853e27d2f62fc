"""A rule and its findings: stable codes, names, one-line summaries, rationale and examples.

Each module of `stvm.lint.rules` registers its rules here with `@rule`; `stvm.lint.registry`
imports them all and selects among them.

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

import textwrap
from dataclasses import dataclass
from typing import Callable, Iterable

from stvm.source import Span

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
    return textwrap.dedent(text).strip("\n")
