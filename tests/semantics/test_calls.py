"""stvm/semantics/calls.py, a part of the body checks (pass 4): calls and argument binding,
called on the part itself."""

from __future__ import annotations

from body_source import SOURCE
from checker_passes import body_checker, expression, messages

from stvm.semantics import types as t


def test_a_call_binds_its_arguments_and_records_what_it_calls():
    ck, bc = body_checker(SOURCE)
    call = expression("Add3(a := 1, b := 2)")
    assert bc.calls.expr_Call(call, None, False) == t.INT
    info = ck.ctx.facts.calls[call.nid]
    assert info.pou.name == "Add3" and not info.is_fb
    assert messages(ck) == []


def test_wrong_arguments_are_reported_against_the_signature():
    ck, bc = body_checker(SOURCE)
    bc.calls.expr_Call(expression("Add3(a := 1, c := 2)"), None, False)
    bc.calls.expr_Call(expression("Add3(1, 2, 3)"), None, False)
    assert messages(ck) == [("E049", "Add3 has no input 'c'"), ("E048", "Add3 takes 2 argument(s), got 3")]
