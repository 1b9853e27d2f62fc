"""Pass 4 of the checker, the body checks (docs/architecture.md, "Checker passes"), one part.
Statements: assignments, IF, CASE, loops, RETURN, REF=, and what may be assigned to what. Made by
`body.BodyChecker`, one per checked body; the other parts, the walk's state and the hooks the
debugger overrides are reached through `self.bc` (bodypart.py).
"""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics import dialect_rules
from stvm.semantics.model import IN_OUT, INPUT, OUTPUT, Variable
from stvm.syntax import nodes as n
from stvm.dialects import allows
from stvm.semantics.typing_rules import is_any_descriptor, implicit_ok, conversion_hint
from stvm.semantics.bodypart import BodyPart


class StatementChecker(BodyPart):
    """Statements: assignments, IF, CASE, loops, RETURN, REF=, and what may be assigned to what."""

    def stmt_Assign(self, s: n.Assign) -> None:
        self.bc.en_call = s.value   # EN/ENO are allowed on this call (bind_en_eno)
        target_type = self.bc.lvalue(s.target)
        value_type = self.bc.expr(s.value, expected=target_type)
        if target_type is not None and value_type is not None:
            self.require_assignable(s.value, value_type, target_type, s.value.span)

    def stmt_CallStatement(self, s: n.CallStatement) -> None:
        if not isinstance(s.call, n.Call):
            if isinstance(s.call, n.Name) and self.bc.members.lookup_callable(s.call) is not None:
                self.error(f"'{s.call.text}' is called without parentheses; write {s.call.text}();", s.span, "E040")
            else:
                self.bc.expr(s.call)
                self.error("this statement does nothing: expected an assignment (:=) or a call", s.span, "E040")
            return
        self.bc.en_call = s.call
        self.bc.expr(s.call, statement=True)

    def condition(self, expr: n.Expr, what: str) -> None:
        ty = self.bc.expr(expr)
        if ty is not None and not isinstance(ty, t.BoolType):
            self.error(f"{what} must be BOOL, not {ty.name}", expr.span, "E041")

    def stmt_If(self, s: n.If) -> None:
        for cond, body in s.branches:
            self.condition(cond, "IF condition")
            self.bc.statements(body)
        if s.else_body is not None:
            self.bc.statements(s.else_body)

    def stmt_Case(self, s: n.Case) -> None:
        sel = self.bc.expr(s.selector)
        if sel is not None and not isinstance(sel, (t.IntType, t.EnumType)):
            self.error(f"CASE selector must be an integer or enumeration, not {sel.name}", s.selector.span, "E042")
        seen: dict[int, n.Span] = {}
        for labels, body in s.elements:
            for label in labels:
                lo = self.case_value(label.low, sel)
                hi = self.case_value(label.high, sel) if label.high is not None else lo
                if lo is not None and hi is not None:
                    if hi < lo:
                        self.error(f"empty case range {lo}..{hi}", label.span, "E042")
                    elif hi - lo < 100000:
                        for v in range(lo, hi + 1):
                            if v in seen:
                                self.error(f"case value {v} appears twice", label.span, "E042")
                                break
                            seen[v] = label.span
            self.bc.statements(body)
        if s.else_body is not None:
            self.bc.statements(s.else_body)

    def case_value(self, expr: n.Expr, sel: t.Type | None) -> int | None:
        if isinstance(expr, n.Name):
            if isinstance(sel, t.EnumType):
                value = sel.value_of(expr.parts[0])
                if value is not None:
                    self.facts.consts[expr.nid] = value
                    return value
            value = self.c.constants.const_value(expr, self.pou_namespace, self.pou)
            if isinstance(value, int) and not isinstance(value, bool):
                self.facts.consts[expr.nid] = value
                return value
            self.error(f"case label '{expr.parts[0]}' is not a constant of the selector's type", expr.span, "E042")
            return None
        if isinstance(expr, n.HashLiteral):
            lit = self.c.constants.hash_literal(expr, self.pou_namespace)
            if lit is None:
                return None
            if isinstance(sel, t.EnumType) and lit[0] != sel:
                self.error(f"case label is {lit[0].name}, the selector is {sel.name}", expr.span, "E042")
            self.facts.consts[expr.nid] = lit[1]
            return lit[1]  # type: ignore[return-value]
        if isinstance(expr, n.IntLiteral):
            if isinstance(sel, t.EnumType):
                self.error(f"case label {expr.value} is an integer; the selector is {sel.name}", expr.span, "E042")
            elif isinstance(sel, t.IntType) and not sel.lo <= expr.value <= sel.hi:
                self.error(f"case label {expr.value} is out of range for {sel.name}", expr.span, "E042")
            self.facts.consts[expr.nid] = expr.value
            return expr.value
        return None

    def stmt_For(self, s: n.For) -> None:
        var_type = self.bc.lvalue(s.variable)
        if self.bc.members.is_property(s.variable, "FOR"):
            var_type = None
        if var_type is not None and not isinstance(var_type, t.IntType):
            self.error(f"FOR variable must be an integer, not {var_type.name}", s.variable.span, "E043")
        for part in (s.start, s.end) + ((s.step,) if s.step is not None else ()):
            ty = self.bc.expr(part, expected=var_type)
            if ty is not None and var_type is not None:
                self.require_assignable(part, ty, var_type, part.span)
        if s.step is not None:
            step = self.c.constants.const_value(s.step, self.pou_namespace, self.pou)
            if step == 0:
                self.error("FOR step is 0: the loop never ends", s.step.span, "E043")
        self.bc.loop_depth += 1
        self.bc.statements(s.body)
        self.bc.loop_depth -= 1

    def stmt_While(self, s: n.While) -> None:
        self.condition(s.condition, "WHILE condition")
        self.bc.loop_depth += 1
        self.bc.statements(s.body)
        self.bc.loop_depth -= 1

    def stmt_Repeat(self, s: n.Repeat) -> None:
        self.bc.loop_depth += 1
        self.bc.statements(s.body)
        self.bc.loop_depth -= 1
        self.condition(s.condition, "UNTIL condition")

    def stmt_Exit(self, s: n.Exit) -> None:
        if self.bc.loop_depth == 0:
            self.error("EXIT outside a loop", s.span, "E044")

    def stmt_Continue(self, s: n.Continue) -> None:
        if self.bc.loop_depth == 0:
            self.error("CONTINUE outside a loop", s.span, "E044")

    def stmt_Return(self, s: n.Return) -> None:
        pass

    def stmt_Empty(self, s: n.Empty) -> None:
        pass

    def lvalue(self, target: n.Expr) -> t.Type | None:
        """Check an assignment target; returns its type (None when already diagnosed)."""
        if isinstance(target, n.Name):
            ref = self.bc.resolve_name(target)
            if ref is None:
                self.bc.members.undeclared(target)
                return None
            self.facts.names[target.nid] = ref  # type: ignore[assignment]
            kind = ref.kind  # type: ignore[attr-defined]
            if kind == "enum":
                self.error(f"cannot assign to enumerator '{target.text}'", target.span, "E050")
                return None
            if kind == "prop":
                return self.bc.members.property_store(target, ref.value, "self")  # type: ignore[attr-defined]
            if kind == "result":
                ty = self.bc.exprs.implicit_deref(target, self.pou.return_type) if self.pou.return_type else None
                self.facts.types[target.nid] = ty  # type: ignore[assignment]
                return ty
            var: Variable = ref.variable  # type: ignore[attr-defined]
            if var.constant:
                self.error(f"cannot assign to constant '{target.text}'", target.span, "E050")
            if isinstance(var.type, t.FBType) and not allows(self.settings.dialect, "fb_assign"):
                self.error(f"cannot assign to function block instance '{target.text}'", target.span, "E050")
                return None
            self.facts.types[target.nid] = self.bc.exprs.implicit_deref(target, var.type)
            return self.facts.types[target.nid]
        if isinstance(target, n.Deref):
            return self.bc.expr(target)
        if isinstance(target, n.Member):
            base_type = self.bc.expr(target.base)
            if base_type is None:
                return None
            if isinstance(base_type, (t.FBType, t.InterfaceType)):
                prop = self.c.oo.find_property(base_type.qualname.lower(), target.name)
                if prop is not None:
                    self.facts.names.pop(target.nid, None)
                    return self.bc.members.property_store(target, prop, self.bc.members.member_how(target.base, base_type))
            if isinstance(base_type, t.FBType) and not self.bc.members.inside_own(target.base, base_type):
                fb = self.c.pous.get(base_type.qualname.lower())
                pin = fb.pin(target.name) if fb else None
                if pin is not None and pin.section in (INPUT, OUTPUT, IN_OUT) and not (
                        pin.section == INPUT and allows(self.settings.dialect, "fb_input_assign")):
                    what = {INPUT: "an input", OUTPUT: "an output", IN_OUT: "an in-out"}[pin.section]
                    self.error(f"cannot assign to '{target.name}', {what} of function block {base_type.name}; "
                               f"pass it in the call instead", target.span, "E051")
                    return None
                inner = fb.variables.get(target.name.lower()) if fb else None
                if inner is not None and inner.section not in (INPUT, OUTPUT, IN_OUT) \
                        and not base_type.is_program and allows(self.settings.dialect, "fb_internal_read"):
                    # `fb_internal_read` lets TwinCAT code read an instance's internals, not write them
                    self.error(f"cannot assign to '{target.name}', internal to {base_type.name}",
                               target.span, "E034")
                    return None
            ty = self.bc.expr(target)
            if ty is not None and self.is_constant_path(target.base):
                self.error("cannot assign to a member of a constant", target.span, "E050")
            if ty is not None and self.bc.members.through_property(target.base):
                return None
            return ty
        if isinstance(target, (n.Index, n.BitAccess)):
            ty = self.bc.expr(target)
            if ty is not None and self.is_constant_path(target.base):
                self.error("cannot assign into a constant", target.span, "E050")
            if ty is not None and isinstance(target, n.Index) and self.bc.members.through_property(target.base):
                return None
            return ty
        if isinstance(target, n.Call):
            self.bc.expr(target)
            self.error("cannot assign to a call result", target.span, "E050")
            return None
        self.error("this expression cannot be assigned to", target.span, "E050")
        return None

    def is_constant_path(self, base: n.Expr) -> bool:
        while isinstance(base, (n.Member, n.Index, n.BitAccess)):
            base = base.base
        ref = self.facts.names.get(base.nid)
        return bool(ref is not None and getattr(ref, "variable", None) is not None and ref.variable.constant)  # type: ignore[attr-defined]

    def require_assignable(self, expr: n.Expr, src: t.Type, dst: t.Type, span: n.Span) -> None:
        if is_any_descriptor(dst) and not is_any_descriptor(src):
            # an ANY input (TwinCAT/CODESYS) takes any value that has bytes: the call passes its
            # type class, address and size
            if isinstance(src, (t.FBType, t.InterfaceType, t.VoidType)) or t.byte_size(src) is None:
                self.error(f"an ANY input takes a value with a size in bytes, not {src.name}", span, "E052")
            else:
                self.mark_addressed(expr)   # the call passes its address (pValue)
            return
        if isinstance(dst, t.InterfaceType) or isinstance(src, t.InterfaceType):
            self.interface_assignable(expr, src, dst, span)
            return
        if isinstance(dst, t.FBType) or isinstance(src, t.FBType):
            if not (allows(self.settings.dialect, "fb_assign") and isinstance(dst, t.FBType)
                    and isinstance(src, t.FBType) and src.qualname.lower() == dst.qualname.lower()):
                self.error("function block instances cannot be assigned", span, "E052")
            return
        if not allows(self.settings.dialect, "fb_assign") and (_array_of_fb(dst) or _array_of_fb(src)):
            # the rule above holds for the elements too: without it `B := A` of two ARRAY OF FB
            # was accepted and left B's elements the very instances of A (no copy is defined here)
            self.error("arrays of function block instances cannot be assigned", span, "E052")
            return
        if isinstance(src, t.VoidType):
            self.error("this call has no result value", span, "E052")
            return
        if expr.nid in self.facts.untyped:
            value = self.facts.consts.get(expr.nid)
            if isinstance(value, int) and not isinstance(value, bool):
                if isinstance(dst, t.IntType):
                    if not dst.lo <= value <= dst.hi:
                        self.error(f"{value} is out of range for {dst.name} ({dst.lo}..{dst.hi})", span, "E022")
                    elif isinstance(dst, t.SubrangeType) and not dst.low <= value <= dst.high:
                        self.error(f"{value} is outside the subrange {dst.text}", span, "E022")
                    return
                if isinstance(dst, t.RealType):
                    return
                if isinstance(dst, t.BoolType) and value in (0, 1):
                    return   # IEC 61131-3 ed. 3 6.3.3 table 5: 0 and 1 are BOOL literals
            if isinstance(value, float) and isinstance(dst, t.RealType):
                return
        if isinstance(dst, t.StringType) and isinstance(src, t.StringType):
            self.string_constant_fits(expr, dst, span)
        if isinstance(src, t.RefType) or isinstance(dst, t.RefType):
            if isinstance(src, t.RefType) and self.refs_assignable(src, dst):
                return
            if isinstance(dst, t.RefType) and not isinstance(src, t.RefType):
                self.error(f"type mismatch: cannot assign {src.name} to {dst.name}; take a reference with "
                           f"{'ADR' if dst.flavour == 'POINTER' else 'REF'}(…)", span, "E052")
                return
            self.error(f"type mismatch: cannot assign {src.name} to {dst.name}", span, "E052")
            return
        if implicit_ok(src, dst):
            return
        if dialect_rules.enum_assignable(self.settings, src, dst, self.facts.consts.get(expr.nid)):
            return   # TwinCAT/CODESYS: an enumeration converts to (and, unless strict, from) an integer
        if isinstance(src, t.IntType) and isinstance(dst, t.IntType):
            self.error(f"cannot assign {src.name} to {dst.name} implicitly (value may not fit){conversion_hint(src, dst)}", span, "E052")
            return
        self.error(f"type mismatch: cannot assign {src.name} to {dst.name}{conversion_hint(src, dst)}", span, "E052")

    def mark_members_addressed(self, expr: n.Expr) -> n.Expr:
        """Mark every FB member on the path `expr` (fields, elements) as addressed; the path's
        root (a name, or whatever expression the path starts from)."""
        root = expr
        while isinstance(root, (n.Member, n.Index)):
            if isinstance(root, n.Member):
                base_type = self.facts.types.get(root.base.nid)
                if isinstance(base_type, t.FBType):
                    self.facts.addressed.add((base_type.qualname.lower(), root.name.lower()))
            root = root.base
        return root

    def mark_addressed(self, expr: n.Expr) -> None:
        """The variable under `expr` (a name, field, element) has its address taken: lowering keeps
        it where a reference can reach it (never in a Python local)."""
        root = self.mark_members_addressed(expr)
        if isinstance(root, n.Name):
            ref = self.facts.names.get(root.nid)
            if getattr(ref, "kind", None) == "var":
                self.facts.addressed.add((self.pou.key, ref.variable.key))  # type: ignore[union-attr]

    def interface_assignable(self, expr: n.Expr, src: t.Type, dst: t.Type, span: n.Span) -> None:
        """`itf := fbInstance` (its FB implements the interface), `itf := itf2` (the same or an
        extending interface), `itf := 0` / `NULL`."""
        if not isinstance(dst, t.InterfaceType):
            self.error(f"type mismatch: cannot assign interface {src.name} to {dst.name}", span, "E052")
            return
        key = dst.qualname.lower()
        if isinstance(src, t.FBType):
            if key not in self.c.oo.implemented_interfaces(src.qualname.lower()):
                self.error(f"function block {src.name} does not implement interface {dst.name}", span, "E052")
            return
        if isinstance(src, t.InterfaceType):
            if key not in self.c.oo.interface_closure(src.qualname.lower()):
                self.error(f"type mismatch: interface {src.name} does not extend {dst.name}", span, "E052")
            return
        if (isinstance(src, t.RefType) and src.is_null) or self.is_zero_literal(expr):
            return
        self.error(f"type mismatch: cannot assign {src.name} to interface {dst.name}", span, "E052")

    def is_zero_literal(self, expr: n.Expr) -> bool:
        return expr.nid in self.facts.untyped and self.facts.consts.get(expr.nid) == 0

    def string_constant_fits(self, expr: n.Expr, dst: t.StringType, span: n.Span) -> None:
        """A constant text that provably overflows STRING[n] (sysmac.md 2, `string_overflow`):
        the code generator cuts it at build time, so the check-time diagnostic is its only
        report (a warning, or an error under `string_overflow=error`)."""
        value = self.facts.consts.get(expr.nid)
        if isinstance(value, (bytes, str)) and len(value) > dst.max_bytes:
            self.c.string_overflow(len(value), dst, span)

    def stmt_RefAssign(self, s: n.RefAssign) -> None:
        target = s.target
        raw = None
        if isinstance(target, (n.Name, n.Member)):
            self.bc.lvalue(target)
            if target.nid in self.facts.auto_deref:
                if isinstance(target, n.Name) and self.facts.names[target.nid].kind == "result":  # type: ignore[attr-defined]
                    raw = self.pou.return_type   # `Get REF= x;` in a METHOD ... : REFERENCE TO
                elif isinstance(target, n.Name):
                    raw = self.facts.names[target.nid].variable.type  # type: ignore[attr-defined]
                else:
                    raw = self.member_raw_type(target)
        if raw is None:
            self.bc.expr(s.value)
            self.error("REF= needs a REFERENCE TO variable on its left", target.span, "E056")
            return
        self.facts.types[target.nid] = raw
        value_type = self.bc.expr(s.value)
        if value_type is None:
            return
        if isinstance(value_type, t.RefType) and value_type.is_null:
            return
        if not isinstance(s.value, (n.Name, n.Member, n.Index, n.Deref)) and not (
                isinstance(s.value, n.Call) and s.value.nid in self.facts.auto_deref):
            self.error("REF= needs a variable; this expression is a temporary value", s.value.span, "E055")
            return
        if not t.same_type(value_type, raw.target):
            self.error(f"REF= binds {raw.name} to a {value_type.name}", s.value.span, "E052")
            return
        root: n.Expr = s.value
        while isinstance(root, (n.Member, n.Index)):
            root = root.base
        ref = self.facts.names.get(root.nid) if isinstance(root, n.Name) else None
        if ref is not None and getattr(ref, "kind", None) == "var":
            self.facts.addressed.add((self.pou.key, ref.variable.key))  # type: ignore[union-attr]

    def member_raw_type(self, target: n.Member) -> t.Type | None:
        base = self.facts.types.get(target.base.nid)
        if isinstance(base, t.StructType):
            return base.field_type(target.name)
        if isinstance(base, t.FBType):
            fb = self.c.pous.get(base.qualname.lower())
            var = fb.pin(target.name) if fb else None
            return var.type if var else None
        return None

    def refs_assignable(self, src: t.RefType, dst: t.Type) -> bool:
        if not isinstance(dst, t.RefType):
            return False
        if self.byte_pointer(src) and self.byte_pointer(dst) and not isinstance(src.target, t.FBType) \
                and not isinstance(dst.target, t.FBType):  # type: ignore[union-attr]
            # TwinCAT/CODESYS: an address is an address (`pointer_arithmetic`); stvm has no byte
            # image of an FB instance, so FB pointers keep their type (docs/memory_model.md)
            return True
        return src.is_null or t.same_type(src.target, dst.target)

    def byte_pointer(self, ty: t.Type | None) -> bool:
        """A POINTER TO of a profile with byte-addressed pointers (`pointer_arithmetic`:
        TwinCAT, CODESYS; docs/memory_model.md)."""
        return isinstance(ty, t.RefType) and ty.flavour == "POINTER" and not ty.is_null \
            and allows(self.settings.dialect, "pointer_arithmetic")


def _array_of_fb(ty: t.Type) -> bool:
    """True for an ARRAY (of arrays…) whose elements are function block instances."""
    while isinstance(ty, t.ArrayType):
        ty = ty.element
        if isinstance(ty, t.FBType):
            return True
    return False
