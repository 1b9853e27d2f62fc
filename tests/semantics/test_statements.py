"""stvm/semantics/statements.py, a part of the body checks (pass 4): statements and what may be
assigned to what, called on the part itself."""

from __future__ import annotations

from body_source import SOURCE
from checker_passes import body_checker, expression, messages

from stvm.semantics import types as t
from stvm.syntax import nodes as n


def test_narrowing_assignments_name_the_conversion_function():
    ck, bc = body_checker(SOURCE)
    d = expression("d")
    bc.stmts.require_assignable(d, t.DINT, t.INT, d.span)
    bc.stmts.require_assignable(d, t.INT, t.DINT, d.span)     # widening: fine
    assert messages(ck) == [("E052", "cannot assign DINT to INT implicitly (value may not fit); use DINT_TO_INT")]


def test_a_constant_is_no_assignment_target():
    ck, bc = body_checker(SOURCE)
    assert bc.stmts.lvalue(expression("K")) == t.INT
    assert messages(ck) == [("E050", "cannot assign to constant 'K'")]


def test_exit_outside_a_loop_is_reported_and_the_loop_depth_is_the_body_checkers():
    ck, bc = body_checker(SOURCE)
    span = bc.node.span
    bc.stmts.stmt_Exit(n.Exit(span))
    assert [code for code, _ in messages(ck)] == ["E044"]
    bc.loop_depth = 1
    bc.stmts.stmt_Exit(n.Exit(span))
    assert len(ck.ctx.diags) == 1
