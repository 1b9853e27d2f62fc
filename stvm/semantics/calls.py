"""Pass 4 of the checker, the body checks (docs/architecture.md, "Checker passes"), one part. Calls of
FUNCTIONs, FB instances and METHODs: argument binding, generics, EN/ENO. Made by
`body.BodyChecker`, one per checked body; the other parts, the walk's state and the hooks the
debugger overrides are reached through `self.bc` (bodypart.py).
"""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics.facts import CallInfo
from stvm.semantics.model import IN_OUT, INPUT, OUTPUT, POUInfo, Variable
from stvm.syntax import nodes as n
from stvm.dialects import allows
from stvm.semantics.typing_rules import (
    TYPE_QUERIES, common_int, implicit_ok, open_rank_ok, conversion_hint,
    trunc_result_from_context, native_result_rule)
from stvm.semantics.bodypart import BodyPart


class CallChecker(BodyPart):
    """Calls of FUNCTIONs, FB instances and METHODs: argument binding, generics, EN/ENO."""

    def expr_Call(self, e: n.Call, expected, statement: bool) -> t.Type | None:
        callee = e.callee
        pou: POUInfo | None = None
        instance: n.Expr | None = None
        if isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in ("__QUERYINTERFACE", "__ISVALIDREF") \
                and self.bc.members.lookup_callable(callee) is None:
            return self.bc.intrinsics.intrinsic(e, callee.parts[0].upper())
        if isinstance(callee, (n.Member, n.Deref)) or (self.fb is not None and isinstance(callee, n.Name)):
            done, ty = self.bc.members.oo_call(e, expected, statement)
            if done:
                return ty
        if isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in ("REF", "ADR") \
                and self.bc.resolve_name(callee) is None and self.bc.members.lookup_callable(callee) is None:
            return self.bc.intrinsics.reference_of(e)
        if isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in TYPE_QUERIES \
                and self.bc.resolve_name(callee) is None and self.bc.members.lookup_callable(callee) is None:
            return self.bc.intrinsics.type_query(e, callee.parts[0].upper())
        if isinstance(callee, n.Name):
            ref = self.bc.resolve_name(callee) if len(callee.parts) == 1 else None
            if ref is not None and getattr(ref, "variable", None) is not None and isinstance(ref.variable.type, t.FBType):  # type: ignore[attr-defined]
                self.bc.expr(callee)
                instance = callee
            elif ref is not None and ref.kind != "result":  # type: ignore[attr-defined]
                self.bc.expr(callee)
                self.error(f"'{callee.text}' is {ref.variable.type.name}, not a function or function block instance", callee.span, "E045")  # type: ignore[attr-defined]
                self.check_args_loosely(e)
                return None
            else:
                pou = self.bc.members.lookup_callable(callee)
                if pou is None:
                    self.error(f"unknown function '{callee.text}'", callee.span, "E045")
                    self.check_args_loosely(e)
                    return None
                if pou.kind != "FUNCTION":
                    self.error(f"'{callee.text}' is a {pou.kind.lower().replace('_', ' ')} type; call an instance of it", callee.span, "E045")
                    self.check_args_loosely(e)
                    return None
        else:
            ty = self.bc.expr(callee)
            if ty is None:
                self.check_args_loosely(e)
                return None
            if not isinstance(ty, t.FBType):
                self.error(f"'{self.bc.exprs.describe(callee)}' is {ty.name}, not a function block instance", callee.span, "E045")
                self.check_args_loosely(e)
                return None
            instance = callee
        if instance is not None:
            fbt = self.facts.types[instance.nid]
            pou = self.c.pous.get(fbt.qualname.lower())  # type: ignore[attr-defined]
            if pou is None:
                return None
            if pou.kind == "PROGRAM":
                self.error("a PROGRAM cannot be called from ST; assign it to a task", e.span, "E045")
                return None
            if not statement:
                self.error(f"a function block call is a statement; read its outputs as {self.bc.exprs.describe(instance)}.Q", e.span, "E045")
            info = CallInfo(pou, True, instance)
            self.bind_args(e, pou, info, fb=True)
            self.facts.calls[e.nid] = info
            return t.VOID
        assert pou is not None
        info = CallInfo(pou, False, None)
        outer, self.bc.call_expected = getattr(self.bc, "call_expected", None), expected
        try:
            self.bind_args(e, pou, info, fb=False)
        finally:
            self.bc.call_expected = outer
        self.facts.calls[e.nid] = info
        ret = pou.return_type
        if ret is None:
            return t.VOID   # a FUNCTION without a result (TwinCAT/CODESYS `void_function`)
        if isinstance(ret, t.GenericType):
            ret = info.generic_type
            if ret is None:
                if e.nid not in self.bc.rejected_calls:
                    self.error(f"cannot infer the result type of {pou.name}", e.span, "E046")
                return None
        return ret

    def check_args_loosely(self, e: n.Call) -> None:
        for arg in e.args:
            if arg.kind in ("input", "positional"):
                self.bc.expr(arg.value)

    def bind_args(self, e: n.Call, pou: POUInfo, info, fb: bool) -> None:
        params = pou.params()
        positional = [a for a in e.args if a.kind == "positional"]
        formal = [a for a in e.args if a.kind != "positional"]
        generic_types: list[t.Type] = []
        bound: set[str] = set()
        if positional and formal:
            if fb or not allows(self.settings.dialect, "mixed_arguments"):
                self.error("mix of formal (name := value) and positional arguments", e.span, "E047")
            else:
                # TwinCAT/CODESYS: the positional arguments take, in order, the inputs no formal
                # argument names (`FIND(STR1 := s, '.')`, TcUnit)
                named = {pou.pin(a.name).key for a in formal if a.kind == "input" and a.name
                         and pou.pin(a.name) is not None}
                free = [p for p in params if p.key not in named]
                if len(positional) > len(free):
                    self.error(f"{self.display(pou)} takes {len(params)} argument(s), got "
                               f"{len(positional) + len(named)}", e.span, "E048")
                for param, arg in zip(free, positional):
                    self.bind_one(pou, param, arg, info, generic_types)
                    bound.add(param.key)
                positional = []
        if not positional and not formal and pou.variadic and not fb:
            self.error(f"{self.display(pou)} takes at least {max(len(params) - 1, 1)} arguments, got 0", e.span, "E048")
        if positional:
            if fb:
                self.error(f"function block {self.display(pou)} needs formal arguments (Name := value)", e.span, "E047")
                return
            if pou.variadic:
                if len(positional) < max(len(params) - 1, 1):
                    self.error(f"{self.display(pou)} takes at least {max(len(params) - 1, 1)} arguments, got {len(positional)}", e.span, "E048")
            elif len(positional) != len(params):
                self.error(f"{self.display(pou)} takes {len(params)} argument(s), got {len(positional)}", e.span, "E048")
            for i, arg in enumerate(positional):
                if i < len(params):
                    self.bind_one(pou, params[i], arg, info, generic_types)
                    bound.add(params[i].key)
                elif pou.variadic and params:
                    last = params[-1]
                    self.bind_one(pou, last, arg, info, generic_types, extra=True)
        for arg in formal:
            assert arg.name is not None
            if self.bind_en_eno(pou, arg, info, e):
                continue
            if arg.kind == "input":
                var = pou.pin(arg.name)
                if var is None and pou.variadic and params:
                    var = self.variadic_pin(pou, arg.name)
                    if var is not None:
                        self.bind_one(pou, var, arg, info, generic_types, extra=True)
                        continue
                if var is None or var.section not in (INPUT, IN_OUT):
                    what = "output" if var is not None and var.section == OUTPUT else "input"
                    hint = "; outputs are bound with =>" if var is not None and var.section == OUTPUT else ""
                    self.error(f"{self.display(pou)} has no {what} '{arg.name}'{hint}" if not hint else
                               f"'{arg.name}' is an output of {self.display(pou)}{hint}", arg.span, "E049")
                    self.bc.expr(arg.value)
                    continue
                if var.key in bound:
                    self.error(f"argument '{arg.name}' given twice", arg.span, "E047")
                bound.add(var.key)
                self.bind_one(pou, var, arg, info, generic_types)
            else:
                var = pou.pin(arg.name)
                if var is None or var.section != OUTPUT:
                    self.error(f"{self.display(pou)} has no output '{arg.name}'", arg.span, "E049")
                    continue
                target_type = self.bc.lvalue(arg.value)
                if self.bc.members.is_property(arg.value, f"the output {arg.name}"):
                    continue
                if target_type is not None:
                    if arg.kind == "output_not" and not isinstance(var.type, t.BoolType):
                        self.error("NOT => needs a BOOL output", arg.span, "E049")
                    elif not implicit_ok(var.type, target_type):
                        self.error(f"output {arg.name} is {var.type.name}; cannot bind it to {target_type.name}"
                                   f"{conversion_hint(var.type, target_type)}", arg.span, "E052")
                info.outputs.append((var, arg.value, arg.kind == "output_not"))
        for p in params:
            if p.section == IN_OUT and p.key not in bound and not (fb and positional):
                if fb:
                    # Choice (IEC 6.6.1.2): an FB in-out must be bound on every call
                    self.error(f"in-out '{p.name}' of {self.display(pou)} is not bound", e.span, "E048")
                else:
                    self.error(f"in-out '{p.name}' of {self.display(pou)} is not bound", e.span, "E048")
        # static argument types in parameter order (omitted inputs: their declared type), extras last
        given = {var.key: value for var, value in info.inputs}
        arg_types = [self.facts.types.get(given[p.key].nid, p.type) if p.key in given else p.type
                     for p in params if not (pou.variadic and p is params[-1] and info.extra and p.key not in given)]
        arg_types += [self.facts.types.get(x.nid, params[-1].type) for x in info.extra]
        info.arg_types = tuple(arg_types)
        rule = native_result_rule(pou, self.c.natives)
        if rule is not None:
            exprs = [given.get(p.key) for p in params
                     if not (pou.variadic and p is params[-1] and info.extra and p.key not in given)]
            exprs += list(info.extra)
            if any(p.type == t.GENERICS["ANY_STRING"] for p in params):
                info.arg_types = self.widen_string_literals(info.arg_types, exprs)
            try:
                info.generic_type = rule(self.literal_context_types(pou, info.arg_types, exprs))
                expected = getattr(self.bc, "call_expected", None)
                if pou.qualname.upper() == "TRUNC" and isinstance(expected, t.IntType) \
                        and not expected.bitstring and trunc_result_from_context(self.settings):
                    info.generic_type = expected   # IEC: TRUNC is ANY_REAL -> ANY_INT
            except Exception as exc:  # a rule rejecting its arguments is a type error in the user's call
                self.error(f"{self.display(pou)}: {exc}", e.span, "E046")
                self.bc.rejected_calls = self.bc.rejected_calls | {e.nid}
        elif generic_types:
            typed = [ty for ty, untyped in generic_types if not untyped]
            info.generic_type = self.common_generic(typed or [ty for ty, _ in generic_types], e)

    def widen_string_literals(self, arg_types: tuple, exprs: list) -> tuple:
        """A '…' literal among WSTRING inputs of a string function is a WSTRING literal, as where
        a WSTRING is expected (`FIND(ws, '€')`, `CONCAT(ws, '!')`; also under sysmac, whose "…"
        is a STRING)."""
        if not any(t.is_wide(ty) for ty, ex in zip(arg_types, exprs)
                   if ex is not None and not isinstance(ex, n.StringLiteral)):
            return arg_types
        out = []
        for ty, ex in zip(arg_types, exprs):
            if isinstance(ex, n.StringLiteral) and isinstance(ex.value, bytes):
                ty = self.bc.exprs.wstring_literal(ex)
                self.facts.types[ex.nid] = ty
            out.append(ty)
        return tuple(out)

    def display(self, pou: POUInfo) -> str:
        """A callee's name in diagnostics: `FB.Method` for a METHOD, the POU's name otherwise."""
        if pou.kind == "METHOD":
            owner = self.c.pous.get(pou.owner)
            return f"method {owner.name}.{pou.name}" if owner is not None else pou.name
        return pou.name

    def literal_context_types(self, pou: POUInfo, arg_types: tuple, exprs: list) -> tuple:
        """The argument types a result rule sees: an untyped literal takes the type of the typed
        arguments it is mixed with (SEL(c, 0, i) is INT, MUX(k, 0.5, r) is REAL), or, when all are
        literals, the type the context expects (j : SINT := SEL(c, 1, 2)) if the literal fits."""
        typed = [ty for ty, ex in zip(arg_types, exprs)
                 if ex is not None and ex.nid not in self.facts.untyped and isinstance(ty, (t.IntType, t.RealType))]
        expected = getattr(self.bc, "call_expected", None)
        out = []
        for ty, ex in zip(arg_types, exprs):
            if ex is None or ex.nid not in self.facts.untyped or not isinstance(ty, (t.IntType, t.RealType)):
                out.append(ty)
                continue
            candidates = [c for c in typed if self.bc.exprs.literal_fits(ex, c) and (isinstance(c, t.RealType) or isinstance(ty, t.IntType))]
            if candidates:
                out.append(candidates[0])
            elif not typed and isinstance(expected, (t.IntType, t.RealType)) and self.bc.exprs.literal_fits(ex, expected) \
                    and (isinstance(expected, t.RealType) or isinstance(ty, t.IntType)):
                out.append(expected)
            else:
                out.append(ty)
        return tuple(out)

    def untyped_bits_literal(self, e: n.Expr, ptype: t.GenericType) -> bool:
        """An untyped non-negative integer literal (16#FF00) may stand for a bit string: it takes
        the type of the call's typed arguments (AND(w, 16#FF00) is WORD)."""
        value = self.facts.consts.get(e.nid)
        return (ptype.name == "ANY_BIT" and e.nid in self.facts.untyped and isinstance(value, int)
                and not isinstance(value, bool) and value >= 0)

    def bind_en_eno(self, pou: POUInfo, arg: n.Argument, info, call: n.Call) -> bool:
        """IEC 6.6.1.6 / 6.6.2.5: `EN := c` and `ENO => v` on any function or FB call (unless the
        POU declares pins of those names). True when `arg` was one of them."""
        word = (arg.name or "").upper()
        if word == "EN" and arg.kind == "input" and pou.pin("EN") is None:
            ty = self.bc.expr(arg.value, expected=t.BOOL)
            if ty is not None:
                self.bc.stmts.require_assignable(arg.value, ty, t.BOOL, arg.value.span)
            info.en = arg.value
        elif word == "ENO" and arg.kind in ("output", "output_not") and pou.pin("ENO") is None:
            ty = self.bc.lvalue(arg.value)
            if ty is not None and not isinstance(ty, t.BoolType):
                self.error(f"ENO is BOOL; cannot bind it to {ty.name}", arg.span, "E052")
            info.eno = (arg.value, arg.kind == "output_not")
        else:
            return False
        if getattr(self.bc, "en_call", None) is not call:
            self.nested_en_eno(info, arg)
        return True

    def nested_en_eno(self, info, arg: n.Argument) -> None:
        """EN/ENO on a call inside a larger expression (`b := 1 + F(EN := c, …)`, a condition):
        lowered in place (`_en_call`); EN FALSE gives the result type's initial value. A method
        call or a function only: an FB call is a statement."""
        if info.is_fb:
            self.error("EN/ENO on a function block call need the call to be a statement", arg.span, "E047")
            return
        info.nested_en = True
        if info.eno is not None:
            # ENO is written through a reference while the expression runs: keep its variable
            # out of Python locals (like a variable whose REF() is taken)
            root = info.eno[0]
            while isinstance(root, (n.Member, n.Index)):
                root = root.base
            ref = self.facts.names.get(root.nid) if isinstance(root, n.Name) else None
            if ref is not None and getattr(ref, "kind", None) == "var":
                self.facts.addressed.add((self.pou.key, ref.variable.key))  # type: ignore[union-attr]

    def variadic_pin(self, pou: POUInfo, name: str) -> Variable | None:
        params = pou.params()
        last = params[-1]
        stem = last.name.rstrip("0123456789")
        if name.lower().startswith(stem.lower()) and name[len(stem):].isdigit():
            return last
        return None

    def common_generic(self, types_: list[t.Type], e: n.Call) -> t.Type | None:
        result = types_[0]
        for ty in types_[1:]:
            if result == ty:
                continue
            if isinstance(result, t.IntType) and isinstance(ty, t.IntType):
                result = common_int(result, ty)
            elif isinstance(result, t.StringType) and isinstance(ty, t.StringType) \
                    and t.is_wide(result) == t.is_wide(ty):
                result = t.WSTRING if t.is_wide(ty) else t.STRING
            elif isinstance(result, (t.IntType, t.RealType)) and isinstance(ty, (t.IntType, t.RealType)):
                result = t.LREAL if t.LREAL in (result, ty) or any(isinstance(x, t.IntType) and x.bits > 16 for x in (result, ty)) else t.REAL
            else:
                self.error(f"arguments of {e.callee.text if isinstance(e.callee, n.Name) else 'call'} have different types "
                           f"({result.name}, {ty.name})", e.span, "E046")
                return None
        return result

    def bind_one(self, pou: POUInfo, var: Variable, arg: n.Argument, info, generic_types: list, extra: bool = False) -> None:
        ptype = var.type
        if var.section == IN_OUT:
            # an in-out is passed by reference: it must be a variable
            if isinstance(ptype, t.ArrayType) and ptype.rank == 1 and isinstance(arg.value, n.Index):
                # Sysmac: an element where an array is expected = the array from that element on
                aty = self.bc.expr(arg.value)
                base_ty = self.facts.types.get(arg.value.base.nid)
                if aty is not None and isinstance(base_ty, t.ArrayType) and self.element_ok(aty, ptype.element):
                    self.facts.array_from_element.add(arg.value.nid)
                    self.lvalue_check_only(arg.value)
                    info.inputs.append((var, arg.value))
                    return
                ty = aty
            elif isinstance(ptype, t.FBType) and self.is_lvalue_shape(arg.value):
                ty = self.bc.expr(arg.value)   # an FB instance passed by reference
            else:
                ty = self.bc.lvalue(arg.value) if self.is_lvalue_shape(arg.value) else None
                if self.bc.members.is_property(arg.value, f"the in-out {var.name}"):
                    return
                if ty is None and not self.is_lvalue_shape(arg.value):
                    self.bc.expr(arg.value)
                    self.error(f"in-out '{var.name}' of {self.display(pou)} needs a variable, not an expression", arg.value.span, "E053")
                    return
            if ty is None:
                return
            if isinstance(ptype, t.GenericType):
                if not ptype.accepts(ty):
                    self.error(f"'{var.name}' of {self.display(pou)} needs {ptype.name}, got {ty.name}", arg.value.span, "E052")
                generic_types.append((ty, False))
            elif isinstance(ptype, t.ArrayType) and isinstance(ty, t.ArrayType) and ptype.dims is None:
                if not self.element_ok(ty.element, ptype.element) or not open_rank_ok(ty, ptype):
                    self.error(f"'{var.name}' of {self.display(pou)} needs {ptype.name}, got {ty.name}", arg.value.span, "E052")
            elif isinstance(ty, t.FBType) and isinstance(ptype, t.FBType) \
                    and self.c.oo.is_derived(ty.qualname.lower(), ptype.qualname.lower()):
                pass   # an instance of a derived FB is an instance of its base
            elif not (ty == ptype or (isinstance(ty, t.StringType) and isinstance(ptype, t.StringType)
                                      and t.is_wide(ty) == t.is_wide(ptype))
                      or (isinstance(ty, (t.StructType, t.EnumType)) and implicit_ok(ty, ptype))
                      or (isinstance(ty, t.ArrayType) and implicit_ok(ty, ptype))
                      or (isinstance(ty, t.IntType) and isinstance(ptype, t.IntType) and ty.bits == ptype.bits)):
                self.error(f"in-out '{var.name}' of {self.display(pou)} is {ptype.name}; got {ty.name}", arg.value.span, "E052")
            info.inputs.append((var, arg.value))
            return
        if isinstance(ptype, t.ArrayType) and ptype.dims is None and ptype.rank == 1 and isinstance(arg.value, n.Index):
            aty = self.bc.expr(arg.value)
            base_ty = self.facts.types.get(arg.value.base.nid)
            if aty is not None and isinstance(base_ty, t.ArrayType) and self.element_ok(aty, ptype.element):
                self.facts.array_from_element.add(arg.value.nid)
                info.inputs.append((var, arg.value))
            return
        ty = self.bc.expr(arg.value, expected=ptype if not isinstance(ptype, t.GenericType) else None)
        if ty is None:
            return
        if isinstance(ptype, t.GenericType):
            if not ptype.accepts(ty) and not self.untyped_bits_literal(arg.value, ptype):
                self.error(f"'{var.name}' of {self.display(pou)} needs {ptype.name}, got {ty.name}", arg.value.span, "E052")
            else:
                # untyped literals only decide the type when no typed argument does
                generic_types.append((ty, arg.value.nid in self.facts.untyped))
        elif isinstance(ptype, t.ArrayType) and ptype.dims is None:
            if not (isinstance(ty, t.ArrayType) and self.element_ok(ty.element, ptype.element)
                    and open_rank_ok(ty, ptype)):
                self.error(f"'{var.name}' of {self.display(pou)} needs {ptype.name}, got {ty.name}", arg.value.span, "E052")
        else:
            self.bc.stmts.require_assignable(arg.value, ty, ptype, arg.value.span)
        if extra:
            info.extra.append(arg.value)
        else:
            info.inputs.append((var, arg.value))

    def element_ok(self, have: t.Type, want: t.Type) -> bool:
        if isinstance(want, t.GenericType):
            return want.accepts(have)
        return have == want or (isinstance(have, t.IntType) and isinstance(want, t.IntType) and have.bits == want.bits)

    def is_lvalue_shape(self, e: n.Expr) -> bool:
        return isinstance(e, (n.Name, n.Member, n.Index, n.BitAccess))

    def lvalue_check_only(self, e: n.Expr) -> None:
        if self.bc.stmts.is_constant_path(e):
            self.error("cannot pass a constant as an in-out", e.span, "E053")
