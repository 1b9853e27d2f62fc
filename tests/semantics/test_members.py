"""stvm/semantics/members.py, a part of the body checks (pass 4): names and members, called on
the part itself."""

from __future__ import annotations

from body_source import SOURCE
from checker_passes import body_checker, expression, messages

from stvm.semantics import types as t


def test_a_name_resolves_to_the_variable_it_declares():
    ck, bc = body_checker(SOURCE)
    ref = bc.members.resolve_name(expression("i"))
    assert ref.kind == "var" and ref.variable.name == "i" and ref.variable.type == t.INT
    assert bc.members.resolve_name(expression("ghost")) is None and messages(ck) == []   # the caller reports
    assert bc.exprs.expr_Name(expression("ghost"), None) is None
    assert messages(ck) == [("E031", "'ghost' is not declared")]


def test_struct_fields_are_visible_fb_internals_are_not():
    ck, bc = body_checker(SOURCE)
    assert bc.members.expr_Member(expression("p.x"), None) == t.INT
    assert bc.members.expr_Member(expression("m.speed"), None) == t.INT
    assert bc.members.expr_Member(expression("m.hidden"), None) is None
    assert messages(ck) == [("E034", "'hidden' is internal to Motor; only inputs and outputs are visible outside")]
