"""What lint reads from the checker: one adapter, so the rest of `stvm.lint` never touches how
the semantic facts are stored (today a dict keyed by node identity).

Also the small tree helpers lint needs (sub-expressions of a statement, the calls in it, the
"place" an lvalue denotes).
"""

from __future__ import annotations

from dataclasses import fields, is_dataclass
from typing import Iterator

from stvm.semantics import types as t
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, INPUT, LOCAL, OUTPUT, TEMP, POUInfo, Variable
from stvm.syntax import nodes as n
from stvm.semantics.body import OP_TEXT

NOT_CONST = object()

__all__ = ["FactsView", "NOT_CONST", "iter_exprs", "calls_in", "INPUT", "OUTPUT", "IN_OUT", "LOCAL",
           "TEMP", "GLOBAL", "EXTERNAL"]


class FactsView:
    """Read-only view of the checker's per-expression facts for one checked project."""

    def __init__(self, analysis) -> None:
        self._facts = analysis.facts
        self.model = analysis.model
        self.place_keys: dict[int, str | None] = {}   # memo of place_key, per expression

    def type_of(self, expr: n.Expr) -> t.Type | None:
        return self._facts.types.get(expr.nid)

    def name_ref(self, expr: n.Expr):
        """The checker's NameRef (kind 'var', 'global', 'enum', 'const', 'pou', 'result') or None."""
        return self._facts.names.get(expr.nid)

    def call(self, call: n.Expr):
        """The checker's CallInfo of a call expression (pou, is_fb, instance, inputs, outputs, extra)."""
        return self._facts.calls.get(call.nid)

    def const(self, expr: n.Expr) -> object:
        """The compile-time value of a constant expression, else NOT_CONST."""
        return self._facts.consts.get(expr.nid, NOT_CONST)

    def operand_type(self, binary: n.Binary) -> t.Type | None:
        """The type a comparison compares in."""
        return self._facts.operand_types.get(binary.nid)

    def is_array_from_element(self, expr: n.Expr) -> bool:
        """`Data[0]` passed where an array is expected (Sysmac: the array from that element on)."""
        return expr.nid in self._facts.array_from_element

    def pou(self, qualname: str) -> POUInfo | None:
        return self.model.pous.get(qualname.lower())

    def variable_of(self, expr: n.Expr) -> Variable | None:
        ref = self.name_ref(expr)
        if ref is not None and ref.kind in ("var", "global"):
            return ref.variable
        return None


_FIELDS: dict[type, tuple[str, ...]] = {}


def _field_names(cls: type) -> tuple[str, ...]:
    names = _FIELDS.get(cls)
    if names is None:
        names = tuple(f.name for f in fields(cls) if f.name not in ("span", "end_span"))
        _FIELDS[cls] = names
    return names


def _children(node) -> list:
    out: list = []
    for name in _field_names(type(node)):
        value = getattr(node, name)
        if isinstance(value, n.Node):
            out.append(value)
        elif isinstance(value, tuple) and value:
            _flatten_into(value, out)
    return out


def _flatten_into(value: tuple, out: list) -> None:
    for item in value:
        if isinstance(item, n.Node):
            out.append(item)
        elif isinstance(item, tuple):
            _flatten_into(item, out)


def iter_exprs(node, into_bodies: bool = False) -> Iterator[n.Expr]:
    """Every expression under `node`, pre-order. Statement bodies (IF/CASE/loop bodies) are
    entered only with `into_bodies`, so a CFG node sees just its own expressions."""
    stack = [node]
    while stack:
        item = stack.pop()
        if isinstance(item, n.Expr):
            yield item
        elif isinstance(item, n.Statement) and item is not node and not into_bodies:
            continue
        if is_dataclass(item):
            kids = _children(item)
            kids.reverse()
            stack.extend(kids)


def node_exprs(stmt: n.Statement | None, kind: str, expr: n.Expr | None) -> list[n.Expr]:
    """The top-level expressions a CFG node evaluates."""
    if kind in ("branch", "case"):
        return [expr] if expr is not None else []
    if isinstance(stmt, n.Assign):
        return [stmt.target, stmt.value]
    if isinstance(stmt, n.CallStatement):
        return [stmt.call]
    if isinstance(stmt, n.For):
        if kind == "for_init":
            return [stmt.variable, stmt.start]
        if kind == "for_test":
            return [stmt.end]
        if kind == "for_step":
            return [stmt.step] if stmt.step is not None else []
    return []


def node_subexprs(node) -> list[n.Expr]:
    """Every expression a CFG node evaluates (pre-order), computed once per node."""
    cached = getattr(node, "_subexprs", None)
    if cached is None:
        cached = [sub for expr in node_exprs(node.stmt, node.kind, node.expr) for sub in iter_exprs(expr)]
        node._subexprs = cached
    return cached


def node_calls(node) -> list[n.Call]:
    """The calls a CFG node makes, innermost first, computed once per node."""
    cached = getattr(node, "_calls", None)
    if cached is None:
        cached = []
        for expr in node_exprs(node.stmt, node.kind, node.expr):
            cached += calls_in(expr)
        node._calls = cached
    return cached


def calls_in(expr: n.Expr) -> list[n.Call]:
    """Calls inside an expression, innermost first (the order they run)."""
    out = [e for e in iter_exprs(expr) if isinstance(e, n.Call)]
    out.reverse()
    return out


def place_key(expr: n.Expr, facts: FactsView) -> str | None:
    """A canonical name for the storage an expression denotes ('x', 'cbt.connected',
    'buf[0]'), or None when it is not a fixed place (`a[i]`, a call result, a bit)."""
    memo = facts.place_keys
    key = expr.nid
    if key in memo:
        return memo[key]
    value = memo[key] = _place_key(expr, facts)
    return value


def _place_key(expr: n.Expr, facts: FactsView) -> str | None:
    if isinstance(expr, n.Name):
        var = facts.variable_of(expr)
        return var.key if var is not None else None
    if isinstance(expr, n.Member):
        base = place_key(expr.base, facts)
        return f"{base}.{expr.name.lower()}" if base is not None else None
    if isinstance(expr, n.Index):
        base = place_key(expr.base, facts)
        if base is None:
            return None
        values = [facts.const(ix) for ix in expr.indices]
        if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            return f"{base}[{','.join(str(v) for v in values)}]"
        return None
    return None


def root_expr(expr: n.Expr) -> n.Expr:
    """The variable an lvalue path starts from (`a` of `a.b[i].c`)."""
    while isinstance(expr, (n.Member, n.Index, n.BitAccess)):
        expr = expr.base
    return expr


def text_of(expr: n.Expr) -> str:
    """A short source-like rendering of an expression, for messages."""
    if isinstance(expr, n.Name):
        return expr.text
    if isinstance(expr, n.Member):
        return f"{text_of(expr.base)}.{expr.name}"
    if isinstance(expr, n.Index):
        return f"{text_of(expr.base)}[{', '.join(text_of(i) for i in expr.indices)}]"
    if isinstance(expr, n.BitAccess):
        return f"{text_of(expr.base)}.{expr.bit}"
    if isinstance(expr, n.IntLiteral):
        return str(expr.value)
    if isinstance(expr, n.BoolLiteral):
        return "TRUE" if expr.value else "FALSE"
    if isinstance(expr, n.StringLiteral):
        return "'" + expr.value.decode("utf-8", "replace") + "'"
    if isinstance(expr, n.HashLiteral):
        return "\\".join(expr.prefix) + "#" + expr.text
    if isinstance(expr, n.RealLiteral):
        return expr.text
    if isinstance(expr, n.Call):
        args = []
        for a in expr.args:
            value = text_of(a.value)
            if a.kind == "input":
                args.append(f"{a.name}:={value}")
            elif a.kind in ("output", "output_not"):
                args.append(f"{a.name}=>{value}")
            else:
                args.append(value)
        inner = ", ".join(args)
        if len(inner) > 60:
            inner = "…"
        return f"{text_of(expr.callee)}({inner})"
    if isinstance(expr, n.Unary):
        return f"{'NOT ' if expr.op == 'NOT' else '-'}{text_of(expr.operand)}"
    if isinstance(expr, n.Binary):
        return f"{text_of(expr.left)} {OP_TEXT.get(expr.op, expr.op)} {text_of(expr.right)}"
    return "expression"
