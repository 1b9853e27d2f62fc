"""Which variables a CFG node reads and writes, in evaluation order.

Kinds: 'read'; 'write' (the whole variable); 'write_part' (a member, element or bit of it);
'inout' (passed by reference to a VAR_IN_OUT: the callee may read and write it).
Function results assigned by name are reported as the pseudo-variable RESULT.
"""

from __future__ import annotations

from dataclasses import dataclass

from stvm.lint.facts_view import FactsView, node_exprs
from stvm.semantics.model import IN_OUT, Variable
from stvm.syntax import nodes as n

RESULT = Variable("<result>", "RESULT", None)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Access:
    kind: str
    var: Variable
    expr: n.Expr


class _Collector:
    def __init__(self, facts: FactsView) -> None:
        self.facts = facts
        self.out: list[Access] = []

    def var_of(self, expr: n.Expr) -> Variable | None:
        ref = self.facts.name_ref(expr)
        if ref is None:
            return None
        if ref.kind == "result":
            return RESULT
        if ref.kind in ("var", "global"):
            return ref.variable
        return None

    def value(self, e: n.Expr) -> None:
        if isinstance(e, n.Name):
            var = self.var_of(e)
            if var is not None:
                self.out.append(Access("read", var, e))
        elif isinstance(e, (n.Member, n.BitAccess, n.Deref)):
            self.value(e.base)
        elif isinstance(e, n.Index):
            self.value(e.base)
            for ix in e.indices:
                self.value(ix)
        elif isinstance(e, n.Call):
            self.call(e)
        elif isinstance(e, n.Unary):
            self.value(e.operand)
        elif isinstance(e, n.Binary):
            self.value(e.left)
            self.value(e.right)

    def indices(self, e: n.Expr) -> None:
        """The reads an lvalue's path makes (`a[i].b` reads i), not the place itself."""
        while isinstance(e, (n.Member, n.Index, n.BitAccess)):
            if isinstance(e, n.Index):
                for ix in e.indices:
                    self.value(ix)
            e = e.base

    def root(self, e: n.Expr) -> tuple[Variable | None, bool]:
        whole = isinstance(e, n.Name)
        while isinstance(e, (n.Member, n.Index, n.BitAccess)):
            e = e.base
        return (self.var_of(e) if isinstance(e, n.Name) else None), whole

    def write(self, target: n.Expr) -> None:
        self.indices(target)
        var, whole = self.root(target)
        if var is not None:
            self.out.append(Access("write" if whole else "write_part", var, target))

    def call(self, e: n.Call) -> None:
        info = self.facts.call(e)
        if info is None:
            for arg in e.args:
                self.value(arg.value)
            return
        if info.is_fb and info.instance is not None:
            self.value(info.instance)
        elif isinstance(e.callee, n.Member):
            # `itf.M()`, `fb.M()`: the method is called through the variable, which reads it
            # (an interface variable used only so was "written but never read", SA102)
            self.value(e.callee.base)
        for var, value in info.inputs:
            if var.section == IN_OUT:
                self.indices(value)
                root, _ = self.root(value)
                if root is not None:
                    self.out.append(Access("inout", root, value))
            else:
                self.value(value)
        for value in info.extra:
            self.value(value)
        for _var, target, _negate in info.outputs:
            self.write(target)


def node_accesses(node, facts: FactsView) -> list[Access]:
    """The accesses of a CFG node, computed once per node."""
    cached = getattr(node, "_accesses", None)
    if cached is None:
        cached = node._accesses = _node_accesses(node, facts)
    return cached


def _node_accesses(node, facts: FactsView) -> list[Access]:
    c = _Collector(facts)
    stmt, kind = node.stmt, node.kind
    if kind == "assign":
        c.value(stmt.value)
        c.write(stmt.target)
    elif kind == "for_init":
        c.value(stmt.start)
        c.write(stmt.variable)
    elif kind == "for_step":
        c.value(stmt.variable)
        if stmt.step is not None:
            c.value(stmt.step)
        c.write(stmt.variable)
    elif kind == "for_test":
        c.value(stmt.variable)
        c.value(stmt.end)
    else:
        for expr in node_exprs(stmt, kind, node.expr):
            c.value(expr)
    return c.out
