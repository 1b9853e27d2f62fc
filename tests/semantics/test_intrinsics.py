"""stvm/semantics/intrinsics.py, a part of the body checks (pass 4): the calls answered from
their operand's type, called on the part itself."""

from __future__ import annotations

from body_source import SOURCE
from checker_passes import body_checker, expression, messages

from stvm.semantics import types as t


def test_sizeof_and_bounds_of_declared_operands_are_constants():
    ck, bc = body_checker(SOURCE)
    size = expression("SIZEOF(p)")
    assert bc.intrinsics.type_query(size, "SIZEOF") == t.DINT
    assert ck.ctx.facts.type_queries[size.nid] == ("CONST", 2) and ck.ctx.facts.consts[size.nid] == 2
    bound = expression("UPPER_BOUND(arr, 1)")
    assert bc.intrinsics.type_query(bound, "UPPER_BOUND") == t.DINT
    assert ck.ctx.facts.consts[bound.nid] == 3
    assert messages(ck) == []


def test_adr_gives_a_pointer_to_its_operand_type():
    ck, bc = body_checker(SOURCE)
    ty = bc.intrinsics.reference_of(expression("ADR(i)"))
    assert isinstance(ty, t.RefType) and ty.target == t.INT and ty.name == "POINTER TO INT"
