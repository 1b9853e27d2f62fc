"""stvm/semantics/index.py, pass 1 of the checker: the declaration index, tested on its own
(no declaration is resolved yet when it runs)."""

from __future__ import annotations

from dataclasses import replace

from stvm.semantics.context import CheckContext
from stvm.semantics.index import DeclarationIndex, Indexer
from stvm.settings import DEFAULT_SETTINGS, Dialect
from stvm.syntax.nodes import Span
from stvm.syntax.parser import parse_text

SOURCE = """
NAMESPACE Lib
TYPE Mode : (Off, On); END_TYPE
FUNCTION_BLOCK Motor
VAR_INPUT m : Mode; END_VAR
END_FUNCTION_BLOCK
END_NAMESPACE
TYPE Pt : STRUCT x : INT; END_STRUCT; END_TYPE
PROGRAM Main
VAR p : Pt; END_VAR
END_PROGRAM
"""


def indexed(*sources: str, dialect: Dialect = Dialect.SYSMAC) -> CheckContext:
    settings = replace(DEFAULT_SETTINGS, dialect=dialect)
    units = []
    for i, text in enumerate(sources):
        unit, diags = parse_text(text, f"case{i}.st", settings)
        assert not [d for d in diags if d.is_error], diags
        units.append(unit)
    ctx = CheckContext(units, settings, None, [], DeclarationIndex(settings.dialect))
    Indexer(ctx).build_index()
    return ctx


def test_every_type_and_pou_is_indexed_by_its_qualified_key_and_its_short_name():
    ctx = indexed(SOURCE)
    index = ctx.index
    assert set(index.type_decls) == {"lib\\mode", "pt"}
    assert set(index.pou_nodes) == {"lib\\motor", "main"}
    assert index.short_types == {"mode": ["lib\\mode"], "pt": ["pt"]}
    assert index.short_pous["motor"] == ["lib\\motor"]
    assert ctx.diags == []
    assert ctx.pous == {} and ctx.resolved_types == {}   # nothing is resolved by the index


def test_lookups_search_the_namespace_outwards_then_a_unique_short_name():
    index = indexed(SOURCE).index
    assert index.lookup_type_key(("Mode",), False, ("Lib",)) == "lib\\mode"
    assert index.lookup_type_key(("Mode",), False, ()) == "lib\\mode"        # unique short name
    assert index.lookup_type_key(("Mode",), True, ()) is None                 # rooted: no search
    assert index.lookup_type_key(("Lib", "Mode"), True, ()) == "lib\\mode"
    assert index.lookup_pou_key(("Motor",), ("Lib",)) == "lib\\motor"
    assert index.lookup_pou_key(("Nothing",), ()) is None


def test_an_ambiguous_short_name_resolves_to_nothing():
    other = "NAMESPACE Other\nTYPE Mode : (A, B); END_TYPE\nEND_NAMESPACE\n"
    index = indexed(SOURCE, other).index
    assert index.lookup_type_key(("Mode",), False, ()) is None
    assert index.lookup_type_key(("Mode",), False, ("Other",)) == "other\\mode"


def test_a_library_prefix_is_taken_off_outside_sysmac_only():
    lib = "FUNCTION_BLOCK FB_Test\nEND_FUNCTION_BLOCK\n"
    assert indexed(lib, dialect=Dialect.TWINCAT).index.lookup_pou_key(("TcUnit", "FB_Test"), ()) == "fb_test"
    assert indexed(lib, dialect=Dialect.SYSMAC).index.lookup_pou_key(("TcUnit", "FB_Test"), ()) is None


def test_duplicates_are_reported_in_source_order_and_the_first_declaration_stays():
    ctx = indexed(SOURCE, "TYPE Pt : STRUCT y : INT; END_STRUCT; END_TYPE\nPROGRAM main\nEND_PROGRAM\n"
                          "TYPE INT : STRUCT z : INT; END_STRUCT; END_TYPE\n")
    assert [(d.code, d.message) for d in ctx.diags] == [
        ("E010", "duplicate declaration of type 'Pt'"),
        ("E010", "duplicate declaration of type 'INT'"),
        ("E010", "duplicate declaration of POU 'main'"),
    ]
    assert ctx.index.type_decls["pt"].span.file == "case0.st"


def test_declared_names_follow_the_dialects_rules():
    source = "TYPE Bad_ : STRUCT x : INT; END_STRUCT; END_TYPE\n"
    assert [d.code for d in indexed(source).diags] == ["E011"]                    # Sysmac W501
    assert indexed(source, dialect=Dialect.TWINCAT).diags == []                   # any non-keyword
    ctx = indexed(dialect=Dialect.IEC)
    names = Indexer(ctx)
    span = Span("case.st", 1, 1, 1, 5)
    for name in ("a__b", "ok_name", "end_", "_lead", "while"):
        names.check_identifier(name, span)
    assert [d.message for d in ctx.diags] == [
        "name 'a__b' may not contain '__' (IEC 61131-3 6.1.2)",
        "name 'end_' may not end with '_' (IEC 61131-3 6.1.2)",
        "'while' is a reserved word and cannot be used as a name",
    ]
