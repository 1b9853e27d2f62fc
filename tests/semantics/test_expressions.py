"""stvm/semantics/expressions.py, a part of the body checks (pass 4): operators and literals,
called on the part itself."""

from __future__ import annotations

from body_source import SOURCE
from checker_passes import body_checker, expression, messages

from stvm.semantics import types as t


def test_binary_operators_take_the_higher_ranked_operand_type():
    ck, bc = body_checker(SOURCE)
    exprs = bc.exprs
    assert exprs.expr_Binary(expression("i + 1"), None) == t.INT     # the literal takes INT
    assert exprs.expr_Binary(expression("d * i"), None) == t.DINT
    assert exprs.expr_Binary(expression("i < d"), None) == t.BOOL
    assert exprs.operand_type(t.INT, t.DINT, False, False, expression("i + d")) == t.DINT
    assert messages(ck) == []


def test_a_comparison_of_unrelated_types_is_an_error():
    ck, bc = body_checker(SOURCE)
    assert bc.exprs.expr_Binary(expression("i = TRUE"), None) is None
    assert messages(ck) == [("E039", "cannot compare INT = BOOL")]


def test_indexing_an_array_gives_its_element_type():
    ck, bc = body_checker(SOURCE)
    assert bc.exprs.expr_Index(expression("arr[2]"), None) == t.INT
    assert messages(ck) == []
