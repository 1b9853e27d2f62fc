"""Run the checker's passes one by one on small sources (no stdlib), for the tests of each pass."""

from __future__ import annotations

from dataclasses import replace

from stvm.semantics.checker import Checker
from stvm.settings import DEFAULT_SETTINGS, Dialect
from stvm.syntax.parser import parse_text


def checker(*sources: str, dialect: Dialect = Dialect.SYSMAC, **settings_changes) -> Checker:
    """A Checker made over `sources` (files case0.st, case1.st, …): no pass has run yet."""
    settings = replace(DEFAULT_SETTINGS, dialect=dialect, **settings_changes)
    units = []
    for i, text in enumerate(sources):
        unit, diags = parse_text(text, f"case{i}.st", settings)
        assert not [d for d in diags if d.is_error], diags
        units.append(unit)
    return Checker(units, settings)


def declared(*sources: str, **kwargs) -> Checker:
    """Passes 1 to 3 run: indexed, declared, linked, instance initialisers resolved."""
    ck = checker(*sources, **kwargs)
    ck.build_index()
    return ck


def messages(ck: Checker) -> list[tuple[str, str]]:
    return [(d.code, d.message) for d in ck.ctx.diags]


def body_checker(source: str, pou: str = "main", **kwargs):
    """(Checker, BodyChecker) for POU `pou` of `source`, after passes 1 to 3: its parts can be
    called one by one."""
    from stvm.semantics.body import BodyChecker   # lazy: only the body tests need it
    ck = declared(source, **kwargs)
    return ck, BodyChecker(ck, ck.ctx.pous[pou], ck.ctx.index.pou_nodes[pou])


def expression(text: str):
    from stvm.syntax.parser import parse_expression   # lazy: only the body tests need it
    expr, diags = parse_expression(text)
    assert expr is not None and not diags, diags
    return expr
