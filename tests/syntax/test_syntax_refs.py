"""REF_TO / POINTER TO / REFERENCE TO type specs, `^` and `REF=` in the syntax tree."""

from __future__ import annotations

import pytest

from stvm.syntax import nodes as n
from stvm.syntax.parser import parse_text


def _pou(text: str) -> n.POU:
    unit, diags = parse_text(text, "t.st")
    assert not [d for d in diags if d.severity.name == "ERROR"], diags
    return unit.pous[0]


@pytest.mark.parametrize("spec, flavour", [("REF_TO INT", "REF_TO"), ("POINTER TO INT", "POINTER"),
                                           ("REFERENCE TO INT", "REFERENCE"), ("ref_to int", "REF_TO")])
def test_reference_type_specs(spec, flavour):
    pou = _pou(f"PROGRAM P VAR r : {spec}; END_VAR END_PROGRAM")
    ts = pou.var_blocks[0].decls[0].type_spec
    assert isinstance(ts, n.RefTypeSpec) and ts.flavour == flavour
    assert ts.target.parts[0].upper() == "INT"


def test_deref_chain_and_ref_assign():
    pou = _pou("PROGRAM P VAR r : INT; END_VAR r^.x^ := 1; r REF= q; END_PROGRAM")
    first, second = pou.body
    assert isinstance(first, n.Assign)
    assert first.target == n.Deref(n.Member(n.Deref(n.Name(("r",))), "x"))
    assert second == n.RefAssign(n.Name(("r",)), n.Name(("q",)))


def test_a_variable_named_ref_still_compares():
    pou = _pou("PROGRAM P VAR ref, x : INT; END_VAR IF ref=x THEN x := ref; END_IF END_PROGRAM")
    cond = pou.body[0].branches[0][0]
    assert cond == n.Binary("EQ", n.Name(("ref",)), n.Name(("x",)))


def test_ref_assign_needs_a_value():
    unit, diags = parse_text("PROGRAM P r REF= ; END_PROGRAM", "t.st")
    assert any(d.severity.name == "ERROR" for d in diags)
