"""stvm/semantics/oo.py, pass 3 of the checker (after the declarations): EXTENDS, IMPLEMENTS and
the method tables, run on declared POUs before any body."""

from __future__ import annotations

from checker_passes import checker, messages

from stvm.settings import Dialect

SOURCE = """
INTERFACE I_Base
METHOD Reset : BOOL
END_METHOD
END_INTERFACE
INTERFACE I_Motor EXTENDS I_Base
METHOD Move : BOOL
VAR_INPUT target : LREAL; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Base IMPLEMENTS I_Motor
VAR_INPUT enable : BOOL; END_VAR
METHOD Reset : BOOL
END_METHOD
METHOD Move : BOOL
VAR_INPUT target : LREAL; END_VAR
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Axis EXTENDS Base
VAR pos : LREAL; END_VAR
METHOD Move : BOOL
VAR_INPUT target : LREAL; END_VAR
END_METHOD
END_FUNCTION_BLOCK
"""


def linked(source: str):
    ck = checker(source, dialect=Dialect.TWINCAT)
    ck.indexer.build_index()
    ck.declarations.declare_all()
    ck.oo.link_oo()
    return ck


def test_the_hierarchy_is_linked_and_the_base_variables_inherited():
    ck = linked(SOURCE)
    oo, pous = ck.oo, ck.ctx.pous
    assert messages(ck) == []
    assert pous["axis"].base == "base"
    assert list(pous["axis"].variables)[:2] == ["enable", "pos"]      # the base's first
    assert [p.key for p in oo.base_chain("axis")] == ["axis", "base"]
    assert oo.is_derived("axis", "base") and not oo.is_derived("base", "axis")
    assert oo.find_method("axis", "move").owner == "axis"          # its own override
    assert oo.find_method("axis", "reset").owner == "base"         # inherited
    assert set(oo.interface_closure("i_motor")) == {"i_motor", "i_base"}
    assert {"i_motor", "i_base"} <= oo.implemented_interfaces("axis")


def test_a_cycle_of_extends_and_an_unimplemented_method_are_reported():
    ck = linked("FUNCTION_BLOCK A EXTENDS B\nEND_FUNCTION_BLOCK\nFUNCTION_BLOCK B EXTENDS A\nEND_FUNCTION_BLOCK\n")
    assert messages(ck) == [("E065", "cycle in EXTENDS: A -> B -> A")]
    ck = linked(SOURCE.replace("METHOD Reset : BOOL\nEND_METHOD\nMETHOD Move", "METHOD Move", 1))
    assert messages(ck) == [
        ("E068", "function block 'Base' does not implement method 'Reset' of interface I_Base"),
        ("E068", "function block 'Axis' does not implement method 'Reset' of interface I_Base"),
    ]
