"""stvm/semantics/resolve.py, pass 2 of the checker: TYPE declarations and type specifications
into types, tested on an indexed context (no POU declared, no body checked)."""

from __future__ import annotations

from dataclasses import replace

from stvm.semantics import types as t
from stvm.semantics.constants import ConstantEvaluator
from stvm.semantics.context import CheckContext
from stvm.semantics.index import DeclarationIndex, Indexer
from stvm.semantics.resolve import TypeResolver
from stvm.settings import DEFAULT_SETTINGS, Dialect
from stvm.syntax.parser import parse_text


def resolver(source: str, dialect: Dialect = Dialect.SYSMAC) -> tuple[CheckContext, TypeResolver]:
    settings = replace(DEFAULT_SETTINGS, dialect=dialect)
    unit, diags = parse_text(source, "case.st", settings)
    assert not [d for d in diags if d.is_error], diags
    ctx = CheckContext([unit], settings, None, [], DeclarationIndex(settings.dialect))
    indexer = Indexer(ctx)
    indexer.build_index()
    types = TypeResolver(ctx, indexer)
    ConstantEvaluator(ctx, types)   # array bounds and sizes are constants: made together
    return ctx, types


TYPES = """
TYPE
  Color : (Red, Green := 5, Blue) := Green;
  Pt : STRUCT x : INT := 3; y : Small; END_STRUCT;
  Small : INT := 7;
  Row : ARRAY[1..4] OF Pt;
  Name : STRING[10];
END_TYPE
"""


def test_each_declared_type_resolves_once_whatever_the_declaration_order():
    ctx, types = resolver(TYPES)
    color = types.resolve_declared_type("color")
    assert isinstance(color, t.EnumType) and color.members == (("Red", 0), ("Green", 5), ("Blue", 6))
    assert color.value_of("Green") == 5
    pt = types.resolve_declared_type("pt")
    assert isinstance(pt, t.StructType) and [f[0] for f in pt.fields] == ["x", "y"]
    assert pt.fields[1][1] == t.INT
    assert ctx.type_inits["pt"] == {"x": 3, "y": 7}       # y takes its alias type's initial value
    row = types.resolve_declared_type("row")
    assert isinstance(row, t.ArrayType) and row.dims == ((1, 4),) and row.element is pt
    assert types.resolve_declared_type("pt") is pt        # cached in ctx.resolved_types
    assert ctx.enumerators["blue"] == [(color, 6)] and ctx.structs["pt"] is pt
    assert ctx.diags == []


def test_a_type_defined_in_terms_of_itself_is_reported_once():
    ctx, types = resolver("TYPE A : B; END_TYPE\nTYPE B : A; END_TYPE\n")
    assert types.resolve_declared_type("a") is None
    assert [(d.code, d.message) for d in ctx.diags] == [("E015", "type 'A' is defined in terms of itself")]


def test_unsized_strings_follow_the_dialect_profile():
    _, sysmac = resolver(TYPES)
    _, twincat = resolver(TYPES, Dialect.TWINCAT)
    span = sysmac.ctx.index.type_decls["name"].span
    assert sysmac.unsized_string(span) == t.STRING
    assert twincat.unsized_string(span).max_bytes == 80 and twincat.unsized_string(span).name == "STRING[80]"


def test_an_unknown_type_name_and_a_bad_bound_are_errors():
    ctx, types = resolver("TYPE R : ARRAY[1..0] OF Nothing; END_TYPE\n")
    assert types.resolve_declared_type("r") is None
    assert [d.code for d in ctx.diags] and all(d.is_error for d in ctx.diags)
