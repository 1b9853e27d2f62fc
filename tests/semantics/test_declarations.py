"""stvm/semantics/declarations.py, pass 3 of the checker: globals, TYPEs and POU signatures,
run after the index and before any body."""

from __future__ import annotations

from checker_passes import checker, messages

from stvm.semantics import types as t
from stvm.semantics.model import GLOBAL, INPUT, LOCAL, OUTPUT
from stvm.settings import Dialect

SOURCE = """
VAR_GLOBAL CONSTANT N : INT := 4; END_VAR
VAR_GLOBAL buf : ARRAY[1..N] OF Pt; END_VAR
TYPE Pt : STRUCT x : INT; END_STRUCT; END_TYPE
FUNCTION_BLOCK Counter
VAR_INPUT step : INT := N; END_VAR
VAR_OUTPUT count : DINT; END_VAR
VAR mem : ARRAY[0..N - 1] OF BOOL; END_VAR
END_FUNCTION_BLOCK
"""


def test_globals_types_and_signatures_are_declared_whatever_the_order():
    ck = checker(SOURCE)
    ck.indexer.build_index()
    ck.declarations.declare_all()
    ctx = ck.ctx
    assert ctx.diags == []
    assert ctx.globals["n"].constant and ctx.globals["n"].init == 4 and ctx.globals["n"].section == GLOBAL
    buf = ctx.globals["buf"].type
    assert isinstance(buf, t.ArrayType) and buf.dims == ((1, 4),) and buf.element.name == "Pt"
    fb = ctx.pous["counter"]
    assert [(v.name, v.section) for v in fb.variables.values()] == [
        ("step", INPUT), ("count", OUTPUT), ("mem", LOCAL)]
    assert fb.variables["step"].init == 4
    assert fb.variables["mem"].type.dims == ((0, 3),)
    assert ctx.pous["counter"].base is None            # EXTENDS is linked by oo.py, later


def test_declaration_rules_are_reported_in_declaration_order():
    ck = checker("""
VAR_GLOBAL CONSTANT limit : INT; END_VAR
FUNCTION F : INT
VAR_INPUT a : INT; a : BOOL; END_VAR
VAR_IN_OUT io : INT := 1; END_VAR
END_FUNCTION
PROGRAM P : INT
END_PROGRAM
""")
    ck.indexer.build_index()
    ck.declarations.declare_all()
    assert messages(ck) == [
        ("E013", "constant 'limit' needs an initial value"),
        ("E010", "duplicate declaration of 'a' in F"),
        ("E013", "VAR_IN_OUT 'io' cannot have an initial value"),
        ("E014", "a PROGRAM has no return type"),
    ]


def test_var_stat_is_hoisted_to_a_hidden_global_under_codesys():
    ck = checker("FUNCTION_BLOCK FB_Axis\nVAR_STAT calls : INT := 2; END_VAR\nEND_FUNCTION_BLOCK\n",
                 dialect=Dialect.CODESYS)
    ck.indexer.build_index()
    ck.declarations.declare_all()
    assert "calls" not in ck.ctx.pous["fb_axis"].variables
    assert ck.ctx.pous["fb_axis"].stat_vars == {"calls": "fb_axis__calls"}
    assert ck.ctx.globals["fb_axis__calls"].init == 2 and ck.ctx.any_static
