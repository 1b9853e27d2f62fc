"""stvm/semantics/body.py, pass 4 of the checker: the BodyChecker that dispatches each node to
its part and holds the hooks the debugger overrides (stvm/debug/scope.py)."""

from __future__ import annotations

import gc
import weakref

from body_source import SOURCE
from checker_passes import body_checker, declared, expression, messages

from stvm.semantics import types as t
from stvm.semantics.body import BodyChecker
from stvm.semantics.facts import NameRef
from stvm.semantics.model import LOCAL, Variable
from stvm.syntax import nodes as n


def test_each_node_goes_to_the_part_that_checks_it():
    ck, bc = body_checker(SOURCE)
    for text, part in (("i + 1", bc.exprs), ("p.x", bc.members), ("Add3(a := 1, b := 2)", bc.calls)):
        e = expression(text)
        assert bc.expr(e) == t.INT and ck.ctx.facts.types[e.nid] == t.INT
        assert bc._expr_methods[e.__class__].__self__ is part
    bc.statement(n.Exit(bc.node.span))
    assert bc._stmt_methods[n.Exit].__self__ is bc.stmts
    assert [code for code, _ in messages(ck)] == ["E044"]


def test_the_parts_call_the_hooks_a_subclass_overrides():
    class Wider(BodyChecker):
        def resolve_name(self, name: n.Name) -> object:
            if name.parts == ("ghost",):
                return NameRef("var", Variable("ghost", LOCAL, t.LREAL))
            return super().resolve_name(name)

    ck = declared(SOURCE)
    bc = Wider(ck, ck.ctx.pous["main"], ck.ctx.index.pou_nodes["main"])
    assert bc.expr(expression("ghost * 2.0")) == t.LREAL     # found by the expression part through the hook
    assert bc.expr(expression("i + 1")) == t.INT
    assert messages(ck) == []


def test_a_whole_body_is_checked_and_freed_without_the_collector():
    source = SOURCE.replace("END_PROGRAM", "i := d;\nFOR i := 1 TO 3 DO b := NOT b; END_FOR;\nEND_PROGRAM")
    ck, bc = body_checker(source)
    bc.check()
    assert messages(ck) == [("E052", "cannot assign DINT to INT implicitly (value may not fit); use DINT_TO_INT")]
    gc.disable()
    try:
        gone = weakref.ref(bc)
        del bc
        assert gone() is None      # the parts hold it weakly: no cycle
    finally:
        gc.enable()
