"""stvm/semantics/typing_rules.py: the typing rules the body checks share (sysmac.md 2)."""

from __future__ import annotations

from dataclasses import replace

from stvm.semantics import types as t
from stvm.semantics.typing_rules import common_int, conversion_hint, implicit_ok, int_literal_type, real_for
from stvm.settings import DEFAULT_SETTINGS, IntLiteralType


def test_implicit_conversions_are_the_widening_chart_plus_same_size_sign_changes():
    assert implicit_ok(t.INT, t.DINT) and implicit_ok(t.UINT, t.DINT) and implicit_ok(t.INT, t.UINT)
    assert not implicit_ok(t.DINT, t.INT) and not implicit_ok(t.INT, t.UDINT)
    assert implicit_ok(t.INT, t.REAL) and not implicit_ok(t.WORD, t.REAL)
    assert not implicit_ok(t.STRING, t.WSTRING)
    assert conversion_hint(t.DINT, t.INT) == "; use DINT_TO_INT"


def test_result_types_follow_the_ranks():
    assert common_int(t.INT, t.DINT) == t.DINT
    assert common_int(t.INT, t.UINT) == t.UINT          # same rank: unsigned wins
    assert common_int(t.UINT, t.WORD) == t.WORD         # then the bit string
    assert real_for(t.INT) == t.REAL and real_for(t.DINT) == t.LREAL


def test_untyped_integer_literals_are_dint_unless_they_do_not_fit():
    assert int_literal_type(5, DEFAULT_SETTINGS) == t.DINT
    assert int_literal_type(2**40, DEFAULT_SETTINGS) == t.LINT
    assert int_literal_type(2**63, DEFAULT_SETTINGS) == t.ULINT
    assert int_literal_type(5, replace(DEFAULT_SETTINGS, int_literal_type=IntLiteralType.LINT)) == t.LINT
