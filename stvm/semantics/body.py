"""Type checking of POU bodies: statements, expressions, calls (IEC 61131-3 + Sysmac rules).

Typing rules follow docs/sysmac.md section 2 (typing_rules.py):
* integer results take the highest-ranked operand type (signed+unsigned of one rank → unsigned) and
  wrap at that width *before* any widening for the assignment;
* an untyped integer literal takes the other operand's type when it fits, else DINT (LINT when
  it does not fit DINT, or always LINT with `int_literal_type=lint`);
* implicit conversions are the widening chart plus same-size signed↔unsigned; anything else is an
  error that names the conversion function to use.

`BodyChecker` is pass 4 of the checker (docs/architecture.md, "Checker passes"): one per body, it
holds the walk's state and dispatches each statement and expression to the part that checks it
(statements.py, expressions.py, members.py, calls.py, intrinsics.py; bodypart.py).
"""

from __future__ import annotations

from typing import Any

from stvm.semantics import types as t
from stvm.semantics.calls import CallChecker
from stvm.semantics.expressions import ExpressionTyper
from stvm.semantics.intrinsics import IntrinsicCalls
from stvm.semantics.members import MemberChecker
from stvm.semantics.model import EXTERNAL, POUInfo, Variable
from stvm.semantics.statements import StatementChecker
from stvm.semantics.typing_rules import (  # noqa: F401 (API: body.OP_TEXT, body.RESULT_KEY, …)
    OP_TEXT, RESULT_KEY, TYPE_QUERIES, common_int, conversion_hint, implicit_ok, int_literal_type,
    is_any_descriptor, native_result_rule, open_rank_ok, real_for, trunc_result_from_context)
from stvm.syntax import nodes as n


_PART_INDEX: dict[tuple, int] = {}   # (prefix, node class, the parts' classes) -> index of the part checking it


class BodyChecker:
    # `checker`: the Checker that runs this body check (stvm.semantics.checker imports this module)
    # calls whose result rule rejected the arguments (reported once: no "cannot infer" after it)
    rejected_calls: frozenset[int] = frozenset()

    def __init__(self, checker: Any, pou: POUInfo, node, fb: POUInfo | None = None,
                 fb_node: n.POU | None = None) -> None:
        self.c = checker
        self.pou = pou
        self.node = node
        # the FB (or PROGRAM) whose instance the body runs on: its own body, or a method's owner
        self.fb = fb if fb is not None else (pou if pou.kind in ("FUNCTION_BLOCK", "PROGRAM") else None)
        self.fb_node = fb_node if fb_node is not None else node
        self.member_base: tuple[n.Expr, t.Type] | None = None   # a callee's base oo_call typed already
        self.facts = checker.facts
        self.settings = checker.settings
        self.loop_depth = 0
        self.for_vars: list[str] = []
        self.stmts = StatementChecker(self)
        self.exprs = ExpressionTyper(self)
        self.members = MemberChecker(self)
        self.calls = CallChecker(self)
        self.intrinsics = IntrinsicCalls(self)
        # node class -> the bound stmt_… / expr_… method of the part that checks it, looked up
        # once per body instead of building the name per node
        self._stmt_methods: dict[type, Any] = {}
        self._expr_methods: dict[type, Any] = {}

    def _method(self, table: dict[type, Any], prefix: str, node_cls: type):
        name = prefix + node_cls.__name__
        parts = (self.stmts, self.exprs, self.members, self.calls)
        # which part checks a node class depends only on the parts' classes: found once per
        # process, not once per body (the search was ~5 % of a large program's check)
        key = (prefix, node_cls, *(p.__class__ for p in parts))
        index = _PART_INDEX.get(key)
        if index is None:
            index = _PART_INDEX[key] = next((i for i, p in enumerate(parts) if hasattr(p, name)), 0)
        method = table[node_cls] = getattr(parts[index], name)
        return method

    def error(self, message: str, span: n.Span, code: str = "") -> None:
        self.c.error(message, span, code)

    # ---- statements
    def check(self) -> None:
        try:
            for var in self.pou.variables.values():
                if var.section == EXTERNAL and var.key not in self.c.globals:
                    self.error(f"VAR_EXTERNAL '{var.name}' has no matching VAR_GLOBAL", var.span, "E033")
                elif var.section == EXTERNAL and self.c.globals[var.key].type != var.type:
                    self.error(f"VAR_EXTERNAL '{var.name}' is {var.type.name} but the global is "
                               f"{self.c.globals[var.key].type.name}", var.span, "E033")
            self.statements(self.node.body)
        finally:
            self.release()

    def release(self) -> None:
        """Drop the parts: each refers back to this checker (bodypart.py), a cycle that would keep
        the Checker and the syntax tree alive until the collector runs. The body checker is done."""
        self.stmts = self.exprs = self.members = self.calls = self.intrinsics = None
        self._stmt_methods.clear()
        self._expr_methods.clear()

    def statements(self, body: tuple[n.Statement, ...]) -> None:
        for stmt in body:
            self.statement(stmt)

    def statement(self, s: n.Statement) -> None:
        method = self._stmt_methods.get(s.__class__)
        if method is None:
            method = self._method(self._stmt_methods, "stmt_", s.__class__)
        method(s)

    @property
    def pou_namespace(self) -> tuple[str, ...]:
        return self.fb_node.namespace

    # ---- expressions
    def expr(self, e: n.Expr, expected: t.Type | None = None, statement: bool = False) -> t.Type | None:
        method = self._expr_methods.get(e.__class__)
        if method is None:
            method = self._method(self._expr_methods, "expr_", e.__class__)
        if isinstance(e, n.Call):
            ty = self.calls.expr_Call(e, expected, statement)
            if isinstance(ty, t.RefType) and ty.flavour == "REFERENCE" and e.nid in self.facts.calls:
                ty = self.exprs.implicit_deref(e, ty)   # a METHOD/FUNCTION result REFERENCE TO: its target
        else:
            ty = method(e, expected)
        if ty is not None:
            self.facts.types[e.nid] = ty
        return ty

    # ---- the hooks the debugger's checker overrides (stvm/debug/scope.py): the parts call them here
    def resolve_name(self, name: n.Name) -> object:
        return self.members.resolve_name(name)

    def member_visible(self, base: t.FBType, var: Variable, e: n.Member) -> bool:
        return self.members.member_visible(base, var, e)

    def lvalue(self, target: n.Expr) -> t.Type | None:
        return self.stmts.lvalue(target)

    def is_constant_path(self, base: n.Expr) -> bool:
        return self.stmts.is_constant_path(base)
