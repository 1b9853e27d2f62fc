"""stvm/semantics/constants.py, pass 2 of the checker: compile-time constants, tested on a
context that holds the declared globals (no body checked)."""

from __future__ import annotations

from dataclasses import replace

from stvm.semantics import types as t
from stvm.semantics.constants import ConstantEvaluator
from stvm.semantics.context import CheckContext
from stvm.semantics.facts import NOT_CONST
from stvm.semantics.index import DeclarationIndex, Indexer
from stvm.semantics.model import GLOBAL, Variable
from stvm.semantics.resolve import TypeResolver
from stvm.settings import DEFAULT_SETTINGS, BareEnumerators
from stvm.syntax.nodes import Span
from stvm.syntax.parser import parse_expression, parse_text

SPAN = Span("case.st", 1, 1, 1, 2)


def evaluator(source: str = "", **settings_changes) -> tuple[CheckContext, ConstantEvaluator]:
    settings = replace(DEFAULT_SETTINGS, **settings_changes)
    unit, _ = parse_text(source, "case.st", settings)
    ctx = CheckContext([unit], settings, None, [], DeclarationIndex(settings.dialect))
    indexer = Indexer(ctx)
    indexer.build_index()
    types = TypeResolver(ctx, indexer)
    constants = ConstantEvaluator(ctx, types)
    for key in ctx.index.type_decls:
        types.resolve_declared_type(key)
    ctx.globals["n"] = Variable("N", GLOBAL, t.DINT, True, SPAN)
    ctx.globals["n"].init = 4
    ctx.globals["v"] = Variable("v", GLOBAL, t.DINT, False, SPAN)
    return ctx, constants


def value(constants: ConstantEvaluator, text: str) -> object:
    expr, diags = parse_expression(text)
    assert expr is not None and not diags, diags
    return constants.const_value(expr, (), None)


def test_constant_expressions_fold_with_the_declared_constants():
    _, constants = evaluator("TYPE Mode : (Idle, Busy := 3); END_TYPE\n")
    assert value(constants, "N * 2 + 1") == 9
    assert value(constants, "-7 / 2") == -3          # integer division truncates toward zero
    assert value(constants, "7 MOD 3") == 1
    assert value(constants, "Busy") == 3             # a bare enumerator
    assert value(constants, "v + 1") is NOT_CONST    # not a constant
    assert value(constants, "1 / 0") is NOT_CONST


def test_const_int_reports_what_is_not_a_constant_integer():
    ctx, constants = evaluator()
    expr, _ = parse_expression("v * 2")
    assert constants.const_int(expr, ()) is None
    assert [(d.code, d.message) for d in ctx.diags] == [("E020", "expected a constant integer expression")]


def test_conversions_check_the_range_and_the_kind_of_the_target():
    ctx, constants = evaluator()
    assert constants.convert_constant(100, t.SINT, SPAN) == 100
    assert constants.convert_constant(300, t.SINT, SPAN) is None
    assert constants.convert_constant(1, t.BOOL, SPAN, parse_expression("1")[0]) is True
    assert constants.convert_constant(b"abcdef", t.string_type(4), SPAN) == b"abc"   # STRING[3]: 4 bytes with the NUL
    assert [d.code for d in ctx.diags] == ["E022", "W001"]


def test_enumerators_may_be_required_to_name_their_type():
    ctx, constants = evaluator("TYPE Mode : (Idle, Busy); END_TYPE\n", bare_enumerators=BareEnumerators.REQUIRE_TYPE)
    assert constants.bare_enumerator("Busy", SPAN) is None
    assert [d.message for d in ctx.diags] == ["enumerator 'Busy' needs its type: write Type#Busy"]
