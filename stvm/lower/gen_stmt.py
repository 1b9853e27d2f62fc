"""Generators for ST statements: assignments and stores, IF/CASE/FOR/WHILE/REPEAT, EXIT,
CONTINUE and RETURN, FB calls, EN/ENO, and the range-FOR optimisation.

A mixin of `Lowerer` (`stvm/lower/codegen.py`); one Python statement group per ST statement, each
line tagged with the statement's span (see `CodeWriter`). What is decided about a statement before
it is written (caught errors, range-FORs, inlined and direct FB calls, kept array references) is
read from the analysis pass's plan, `self.plan` (stvm/lower/analysis.py)."""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics.facts import CallInfo
from stvm.semantics.model import IN_OUT, POUInfo, Variable
from stvm.lower.analysis import loop_offset
from stvm.lower.names import var_attr
from stvm.lower.pycode import py_literal, wrap_int
from stvm.syntax import nodes as n
from stvm.settings import ForEndEval, OpenArrayBounds


class StatementGenerator:
    """Statements: `statement(s)` writes the lines of one ST statement."""

    def body(self, stmts: tuple[n.Statement, ...]) -> None:
        # `share_struct_sources` keeps a source only within one statement list: a list starts
        # with nothing kept (the previous POU's last call, a block's enclosing statement) and
        # leaves nothing kept behind
        self.hoisted = None
        if not stmts:
            self.w.line("pass")
            return
        for s in stmts:
            self.statement(s)
        self.hoisted = None

    def statement(self, s: n.Statement) -> None:
        self.w.span = s.span
        # `share_struct_sources`: a struct source read by the previous statement stays in locals
        # only across a run of plain native FB call statements (`hoist_safe_call`)
        safe = self.options.share_struct_sources and self.options.cache_locals and self.hoist_safe_call(s)
        if not safe or (self.hoisted is not None and not self.unowned_by(self.hoisted[2], s)):  # type: ignore[arg-type]
            self.hoisted = None
        self.sharing = s if safe else None
        try:
            self.statement_body(s)
        finally:
            self.sharing = None
        if not safe:
            self.hoisted = None   # nor out of a compound statement's inner blocks

    def statement_body(self, s: n.Statement) -> None:
        # a statement calling a FUNCTION catches its instruction errors; under
        # array_oob=skip_statement, a statement with an array access is skipped when an index
        # is out of range (a compound one only for its own expressions: inner statements skip
        # themselves)
        guarded = s.nid in self.plan.catches_function_errors
        skippable = s.nid in self.plan.skips_on_bad_index
        if guarded or skippable:
            self.w.line("try:")
            self.w.indent += 1
        if s.nid in self.plan.held_derefs:
            self.held_deref_loop(s)
        else:
            getattr(self, "st_" + type(s).__name__)(s)
        if guarded or skippable:
            self.w.indent -= 1
            self.w.span = s.span
        if guarded:
            self.sites.append(s.span)
            self.w.line(f"except _FunctionError as _e: _fun_error(_e, {len(self.sites) - 1})")
        if skippable:
            self.sites.append(s.span)
            self.w.line(f"except _ArrayIndexError as _e: _oob_skipped(_e, {len(self.sites) - 1})")

    def with_en_eno(self, call: n.Expr, emit) -> bool:
        """Emit `emit()` under the call's EN (run only when TRUE) and set its ENO: FALSE before
        the call (an instruction error leaves it FALSE), TRUE after it, FALSE when EN is FALSE.
        False when the call has neither."""
        info = self.facts.calls.get(call.nid) if isinstance(call, n.Call) else None
        if info is None or (info.en is None and info.eno is None):
            return False

        def set_eno(value: bool) -> None:
            if info.eno is not None:
                target, negate = info.eno
                self.store(target, repr(value != negate), t.BOOL)
        if info.en is not None:
            self.w.line(f"if {self.expr_as(info.en, t.BOOL)}:")
            self.w.indent += 1
        set_eno(False)
        emit()
        set_eno(True)
        if info.en is not None:
            self.w.indent -= 1
            self.w.line("else:")
            self.w.indent += 1
            set_eno(False)
            if info.eno is None:
                self.w.line("pass")
            self.w.indent -= 1
        return True

    def st_Assign(self, s: n.Assign) -> None:
        if self.with_en_eno(s.value, lambda: self.plain_assign(s)):
            return
        self.plain_assign(s)

    def plain_assign(self, s: n.Assign) -> None:
        target_type = self.facts.types.get(s.target.nid)
        if target_type is None and isinstance(s.target, n.Name):
            target_type = self.pou.return_type  # type: ignore[union-attr]
        value = self.expr_as(s.value, target_type)
        self.store(s.target, value, target_type)

    def st_CallStatement(self, s: n.CallStatement) -> None:
        if self.with_en_eno(s.call, lambda: self.plain_call(s)):
            return
        self.plain_call(s)

    def plain_call(self, s: n.CallStatement) -> None:
        info = self.facts.calls[s.call.nid]
        if info.oo == "super_body":
            self.w.line(f"{self.classes[info.static_owner]}.__call__(self)")
        elif info.is_fb:
            self.fb_call(s.call, info)  # type: ignore[arg-type]
        else:
            self.w.line(self.function_call(s.call, info))  # type: ignore[arg-type]

    def st_If(self, s: n.If) -> None:
        for i, (cond, body) in enumerate(s.branches):
            self.w.span = cond.span if i else s.span
            self.w.line(f"{'if' if i == 0 else 'elif'} {self.expr(cond)}:")
            self.w.indent += 1
            self.body(body)
            self.w.indent -= 1
        if s.else_body is not None:
            self.w.span = s.span
            self.w.line("else:")
            self.w.indent += 1
            self.body(s.else_body)
            self.w.indent -= 1

    def st_Case(self, s: n.Case) -> None:
        sel = self.new_tmp("case")
        self.w.line(f"{sel} = {self.expr(s.selector)}")
        first = True
        for labels, body in s.elements:
            tests = []
            for label in labels:
                lo = self.facts.consts.get(label.low.nid)
                if label.high is None:
                    tests.append(f"{sel} == {py_literal(lo)}")
                else:
                    hi = self.facts.consts.get(label.high.nid)
                    tests.append(f"{py_literal(lo)} <= {sel} <= {py_literal(hi)}")
            self.w.line(f"{'if' if first else 'elif'} {' or '.join(tests) or 'False'}:")
            first = False
            self.w.indent += 1
            self.body(body)
            self.w.indent -= 1
        if s.else_body is not None:
            if first:
                self.w.line("if True:")
            else:
                self.w.line("else:")
            self.w.indent += 1
            self.body(s.else_body)
            self.w.indent -= 1

    def st_For(self, s: n.For) -> None:
        var_type = self.facts.types[s.variable.nid]
        assert isinstance(var_type, t.IntType)
        step_const = self.facts.consts.get(s.step.nid) if s.step is not None else 1
        if s.nid in self.plan.range_fors:
            self.range_for(s, var_type, step_const)  # type: ignore[arg-type]
            return
        self.store(s.variable, self.expr_as(s.start, var_type), var_type)
        end = self.new_tmp("end")
        self.w.line(f"{end} = {self.expr_as(s.end, var_type)}")
        read = self.expr(s.variable)
        if isinstance(step_const, int):
            step = py_literal(step_const)
            cond = f"{read} <= {end}" if step_const > 0 else f"{read} >= {end}"
        else:
            step = self.new_tmp("step")
            self.w.line(f"{step} = {self.expr_as(s.step, var_type)}")  # type: ignore[arg-type]
            cond = f"({read} <= {end} if {step} > 0 else {read} >= {end})"
        increment = self.store_code(s.variable, wrap_int(f"{read} + {step}", var_type), var_type)
        if self.settings.for_end_eval is ForEndEval.EACH:
            cond = cond.replace(end, f"({self.expr_as(s.end, var_type)})")
        self.w.line(f"while {cond}:")
        self.w.indent += 1
        self.loops.append(("for", increment))
        self.body(s.body)
        self.loops.pop()
        self.w.span = s.span
        for line in increment:
            self.w.line(line)
        self.w.indent -= 1

    def range_for(self, s: n.For, var_type: t.IntType, step: int) -> None:
        var = self.expr(s.variable)
        key = s.variable.parts[0].lower()
        start = self.new_tmp("start")
        end = self.new_tmp("end")
        self.w.line(f"{start} = {self.expr_as(s.start, var_type)}")
        self.w.line(f"{end} = {self.expr_as(s.end, var_type)}")
        plan = self.plan.range_fors[s.nid]
        # constant bounds (in the variable's range, so expr_as left them as they are) decide the
        # guards below while lowering: only the code that can run is emitted
        end_value = plan.bounds[1] if plan.bounds is not None else None
        limit = var_type.hi - step if step > 0 else var_type.lo - step
        # the loop variable would wrap before passing `end`: an endless loop on the controller
        guard = f"{end} > {limit}" if step > 0 else f"{end} < {limit}"
        if end_value is None or (end_value > limit if step > 0 else end_value < limit):
            self.w.line(f"if {guard}: _endless_for({end}, {step}, {var_type.name!r})")
        stop = f"{end} + 1" if step > 0 else f"{end} - 1"
        rng = self.new_tmp("range")
        self.w.line(f"{rng} = range({start}, {stop}, {step})")
        self.assigned.add(key)
        start_const = plan.start
        accesses = plan.hoisted
        if accesses:
            # Bounds checks hoisted out of the loop: if every `a[i + c]` stays inside its array
            # for the whole range, run a copy of the loop without per-access checks; otherwise
            # the checked copy faults at exactly the iteration the controller would.
            first, last = (start, end) if step > 0 else (end, start)
            if plan.fits is not None:
                # the analysis ran the test on the constant bounds: one copy, the one that would run
                if plan.fits:
                    self.unchecked.add(key)
                self.range_loop(s, var, key, rng, start, step, start_const, var_type)
                self.unchecked.discard(key)
                return
            conds = [f"{first} + {c} >= {lo} and {last} + {c} <= {hi}" for c, lo, hi in accesses]
            self.w.line(f"if {' and '.join(conds)}:")
            self.w.indent += 1
            self.unchecked.add(key)
            self.range_loop(s, var, key, rng, start, step, start_const, var_type)
            self.unchecked.discard(key)
            self.w.indent -= 1
            self.w.line("else:")
            self.w.indent += 1
            self.range_loop(s, var, key, rng, start, step, start_const, var_type)
            self.w.indent -= 1
        else:
            self.range_loop(s, var, key, rng, start, step, start_const, var_type)

    def range_loop(self, s: n.For, var: str, key: str, rng: str, start: str, step: int,
                   start_const: object, var_type: t.IntType) -> None:
        self.w.span = s.span
        self.w.line(f"for {var} in {rng}:")
        self.w.indent += 1
        self.range_vars[key] = (step, start_const if isinstance(start_const, int) else None, var_type)
        self.loops.append(("range", []))
        self.body(s.body)
        self.loops.pop()
        del self.range_vars[key]
        self.w.indent -= 1
        self.w.span = s.span
        self.w.line("else:")
        self.w.indent += 1
        # IEC: after the loop the variable holds the first value past `end`
        self.w.line(f"{var} = {start} + {step} * len({rng})")
        self.w.indent -= 1

    def loop_offset(self, ix: n.Expr, key: str) -> int | None:
        """c when `ix` is `key`, `key + c` or `key - c` (constant c), else None."""
        return loop_offset(self.facts, ix, key)

    def held_deref_loop(self, s: n.Statement) -> None:
        """A loop that keeps `r^` in a Python local (the plan's `HeldDeref`): read once before the
        loop and, when the loop stores through `r`, written back in a `finally` (RETURN, EXIT and
        faults leave the target as the loop left it). A NULL `r` runs the loop as written, so its
        first dereference faults at its own line."""
        hold = self.plan.held_derefs[s.nid]
        emit = getattr(self, "st_" + type(s).__name__)
        ref, value = self.new_tmp("ref"), self.new_tmp("held")
        self.w.line(f"{ref} = {self.var_place(hold.ref, False)}")
        if hold.bases or hold.arrays:
            # the loop also touches fields of these objects and elements of these arrays: r^
            # must be none of them (an `AttrRef` is a field or variable, never an element; an
            # `ItemRef` an element, never a field; other references are not held)
            objects = [self.var_place(self.facts.names[b.base.nid].variable, False) if isinstance(b, n.Deref)
                       else self.expr(b) for b in hold.bases]
            attr_ok = " and ".join([f"type({ref}) is _AttrRef"] + [f"{ref}.obj is not {code}" for code in objects])
            # an element of an ARRAY[*] argument is an `ItemRef` of an `ArrayRef`: not held
            lists = [self.expr(a) for a in hold.arrays]
            item_ok = " and ".join([f"type({ref}) is _ItemRef"] + ([f"type({ref}.lst) is list"] if lists else [])
                                   + [f"{ref}.lst is not {code}" for code in lists])
            self.w.line(f"if not ({attr_ok} or {item_ok}):")
        elif self.byte_pointers():
            # a byte-addressed pointer (docs/memory_model.md) may overlap anything: never held
            self.w.line(f"if {ref} is None or type({ref}) is _Ptr:")
        else:
            self.w.line(f"if {ref} is None:")
        self.w.indent += 1
        emit(s)
        self.w.indent -= 1
        self.w.span = s.span
        self.w.line("else:")
        self.w.indent += 1
        self.w.line(f"{value} = {ref}.get()")
        if hold.written:
            self.w.line("try:")
            self.w.indent += 1
        self.held[hold.ref.key] = value
        emit(s)
        del self.held[hold.ref.key]
        if hold.written:
            self.w.indent -= 1
            self.w.span = s.span
            self.w.line("finally:")
            self.w.indent += 1
            self.w.line(f"{ref}.set({value})")
            self.w.indent -= 1
        self.w.indent -= 1

    def held_local(self, e: n.Expr) -> str | None:
        """The local holding `e`'s target when `e` names a reference a loop holds (see above)."""
        if self.held and isinstance(e, n.Name):
            ref = self.facts.names.get(e.nid)
            if ref is not None and ref.variable is not None:
                return self.held.get(ref.variable.key)
        return None

    def st_While(self, s: n.While) -> None:
        self.w.line(f"while {self.expr(s.condition)}:")
        self.w.indent += 1
        self.loops.append(("while", []))
        self.body(s.body)
        self.loops.pop()
        self.w.indent -= 1

    def st_Repeat(self, s: n.Repeat) -> None:
        self.w.line("while True:")
        self.w.indent += 1
        cond = self.expr(s.condition)
        self.loops.append(("repeat", [f"if {cond}: break"]))
        self.body(s.body)
        self.loops.pop()
        self.w.span = s.condition.span
        self.w.line(f"if {cond}: break")
        self.w.indent -= 1

    def st_Exit(self, s: n.Exit) -> None:
        self.w.line("break")

    def st_Continue(self, s: n.Continue) -> None:
        kind, code = self.loops[-1]
        for line in code:
            self.w.line(line)
        self.w.line("continue")

    def st_Return(self, s: n.Return) -> None:
        self.w.line(("return _rb.value" if self.result_boxed() else "return _r")
                    if self.pou and self.pou.kind in ("FUNCTION", "METHOD") else "return")

    def st_Empty(self, s: n.Empty) -> None:
        self.w.line("pass")

    def st_RefAssign(self, s: n.RefAssign) -> None:
        place = self.raw_place(s.target)
        if isinstance(s.target, n.Name) and s.target.parts[0].lower() in self.cached:
            self.assigned.add(s.target.parts[0].lower())
        self.w.line(f"{place} = {self.reference_code(s.value)}")

    def store(self, target: n.Expr, value: str, ty: t.Type | None) -> None:
        for line in self.store_code(target, value, ty):
            self.w.line(line)

    def store_code(self, target: n.Expr, value: str, ty: t.Type | None) -> list[str]:
        """Python statements that store `value` (already converted to `ty`) into `target`."""
        aggregate = isinstance(ty, (t.StructType, t.ArrayType, t.FBType))   # an FB: `fb_assign`
        if self.facts.props and target.nid in self.facts.props:
            return [f"{self.property_target(target, 'SET')}({value})"]
        if isinstance(target, n.Name):
            ref = self.facts.names[target.nid]
            if ref.kind == "result":
                result = "_rb.value" if self.result_boxed() else "_r"
                if target.nid in self.facts.auto_deref:   # a result REFERENCE TO: store through it
                    return self.store_through(result, value, ty)
                return [f"{result} = {value}" if not aggregate else f"{result} = _copy_value({value})"]
            var = ref.variable
            assert var is not None
            place = self.name_place(ref)
            if target.nid in self.facts.auto_deref:
                return self.store_through(place, value, ty)
            if var.key in self.cached and ref.kind not in ("global", "field"):
                self.assigned.add(var.key)
            if var.section == IN_OUT and not aggregate:
                return [f"{place}.set({value})"]
            return [self.assign_into(place, value, ty)]
        if isinstance(target, n.Index) and isinstance(self.facts.types.get(target.base.nid), t.RefType):
            return [f"{self.pointer_index(target)}.set({value})"]   # TwinCAT/CODESYS `p[i] := v`
        if isinstance(target, n.Deref):
            held = self.held_local(target.base)
            if held is not None:
                return [f"{held} = {value}"]
            return self.store_through(self.expr(target.base), value, ty)
        if isinstance(target, n.Member):
            base = self.expr(target.base)
            base_type = self.facts.types[target.base.nid]
            attr = var_attr(self.member_name(base_type, target.name))
            if target.nid in self.facts.auto_deref:
                return self.store_through(f"{base}.{attr}", value, ty)
            return [self.assign_into(f"{base}.{attr}", value, ty)]
        if isinstance(target, n.Index):
            place = self.index_code(target)
            return [self.assign_into(place, value, ty)]
        if isinstance(target, n.PartialAccess):
            current = self.expr(target.base)
            base_type = self.facts.types[target.base.nid]
            shift, mask = target.bit * target.width, (1 << target.width) - 1
            merged = f"(({current}) & {~(mask << shift) & ((1 << base_type.bits) - 1)}) | (({value}) << {shift})"  # type: ignore[attr-defined]
            if base_type.signed:  # type: ignore[attr-defined]
                merged = wrap_int(merged, base_type)  # type: ignore[arg-type]
            return self.store_code(target.base, merged, base_type)
        if isinstance(target, n.BitAccess):
            current = self.expr(target.base)
            base_type = self.facts.types[target.base.nid]
            return self.store_code(target.base, f"_setbit({current}, {target.bit}, {value})", base_type)
        raise AssertionError("checked: not an lvalue")

    def store_through(self, ref: str, value: str, ty: t.Type | None) -> list[str]:
        """Store through a reference (`r^ := v`, a REFERENCE TO variable); NULL faults."""
        if ty is not None and t.is_aggregate(ty):
            return [self.assign_into(f"({ref} or _null_ref())", value, ty)]
        return [f"({ref} or _null_ref()).set({value})"]

    def assign_into(self, place: str, value: str, ty: t.Type | None) -> str:
        if isinstance(ty, (t.StructType, t.FBType)):   # an FB: `fb_assign` (TwinCAT/CODESYS)
            return f"{place}._assign({value})"
        if isinstance(ty, t.ArrayType):
            return f"_assign_array({place}, {value})"
        return f"{place} = {value}"

    def fb_call(self, e: n.Call, info: CallInfo) -> None:
        assert info.instance is not None
        inst = self.expr(info.instance)
        inlined = self.plan.inlined_fbs.get(e.nid)
        if not inst.replace(".", "").replace("_", "").isalnum() or (inlined is not None and "." in inst):
            tmp = self.new_tmp("fb")
            self.w.line(f"{tmp} = {inst}")
            inst = tmp
        for var, value in info.inputs:
            attr = var_attr(var.name)
            code = self.arg_code(var, value)
            if var.section != IN_OUT and isinstance(var.type, t.StructType):
                if not self.inline_input_copy(f"{inst}.{attr}", self.expr(value), var.type, value):
                    self.w.line(f"{inst}.{attr}._assign({self.expr(value)})")
            elif var.section != IN_OUT and isinstance(var.type, t.ArrayType) and var.type.dims is not None:
                self.w.line(f"_assign_array({inst}.{attr}, {self.expr(value)})")
            elif not self.reused_array_ref(f"{inst}.{attr}", var, value):
                self.w.line(f"{inst}.{attr} = {code}")
        if inlined is not None:
            self.inline_fb_body(inst, info.pou, inlined)
        else:
            self.w.line(self.direct_native_call(inst, e, info.pou) or f"{inst}()")
        for var, target, negate in info.outputs:
            target_type = self.facts.types.get(target.nid)
            value = f"{inst}.{var_attr(var.name)}"
            if negate:
                value = f"(not {value})"
            elif target_type is not None:
                value = self.coerce(value, var.type, target_type, target.span)
            if not negate and isinstance(var.type, t.StructType) and target_type == var.type \
                    and self.inline_output_copy(target, value, var.type):
                continue
            self.store(target, value, target_type)

    def hoist_safe_call(self, s: n.Statement) -> bool:
        """`share_struct_sources`: a call statement across which a struct source's leaf values
        cannot change: a native FB called directly (its implementation touches only its own
        instance), no EN/ENO, no caught errors, no in-out but ARRAY[*] ones (an `ArrayRef` reaches
        a list, never a struct field), no reference or pointer pin, every input a plain variable
        path or literal (no call, no property, no computed index), every output a plain scalar
        variable of the caller or a global (never a struct field, a reference or a property)."""
        if not isinstance(s, n.CallStatement) or not isinstance(s.call, n.Call):
            return False
        if s.nid in self.plan.catches_function_errors or s.nid in self.plan.skips_on_bad_index \
                or s.nid in self.plan.held_derefs:
            return False
        info = self.facts.calls.get(s.call.nid)
        if info is None or not info.is_fb or info.oo or info.en is not None or info.eno is not None \
                or not info.pou.native or s.call.nid not in self.plan.direct_native \
                or s.call.nid in self.plan.inlined_fbs or info.extra:
            return False
        for var in info.pou.variables.values():
            if isinstance(var.type, t.RefType) or (var.section == IN_OUT and not isinstance(var.type, t.ArrayType)):
                return False
        if info.instance is None or not self.plain_path(info.instance):
            return False
        for _, value in info.inputs:
            if not self.plain_path(value):
                return False
        for var, target, _ in info.outputs:
            if not isinstance(target, n.Name) or target.nid in self.facts.auto_deref \
                    or (self.facts.props and target.nid in self.facts.props):
                return False
            ref = self.facts.names.get(target.nid)
            if ref is None or ref.kind not in ("var", "global") or ref.variable is None \
                    or ref.variable.section == IN_OUT or t.is_aggregate(ref.variable.type) \
                    or t.is_aggregate(var.type):
                return False
        return True

    def plain_path(self, e: n.Expr) -> bool:
        """A variable path (`a`, `a.b`, `a.b[3]`), or a literal: evaluated without a call, a
        property or an index that could fault."""
        if self.facts.props and e.nid in self.facts.props:
            return False
        if isinstance(e, _LITERALS):
            return True
        if isinstance(e, n.Name):
            return e.nid not in self.facts.auto_deref
        if isinstance(e, n.Member):
            return e.nid not in self.facts.auto_deref and self.plain_path(e.base)
        if isinstance(e, n.Index):
            base = self.facts.types.get(e.base.nid)
            if not isinstance(base, t.ArrayType) or not base.dims or len(base.dims) != len(e.indices) \
                    or e.nid in self.facts.auto_deref:
                return False
            for ix, (lo, hi) in zip(e.indices, base.dims):
                value = self.facts.consts.get(ix.nid)
                if not isinstance(ix, n.IntLiteral) or not isinstance(value, int) or not lo <= value <= hi:
                    return False
            return self.plain_path(e.base)
        return False

    def inline_input_copy(self, dst: str, src: str, st: t.StructType, node: n.Expr | None = None) -> bool:
        """`inline_input_copy`: a STRUCT input of an FB call copied field by field in place, no
        `_assign` call (the thesis copies its `_sSOCKET` into three socket FBs per CBT FB and
        its parameter structs into every CBT FB, every scan). Only for structs of at most
        `_INLINE_COPY_LEAVES` leaf fields (code size). False when not applied."""
        if not self.options.inline_input_copy or struct_leaves(st) > _INLINE_COPY_LEAVES \
                or isinstance(st, t.UnionType):   # a union copies its bytes (`_assign`), not member by member
            return False
        # `_assign`'s `src is self` shortcut is not needed: copying a struct onto itself field
        # by field changes nothing
        if node is not None and self.share_source(dst, src, st, node):
            return True
        self.w.line(f"_sd = {dst}; _ss = {src}")
        self.struct_assign_body("_sd", "_ss", st, 0)
        return True

    def share_source(self, dst: str, src: str, st: t.StructType, node: n.Expr) -> bool:
        """`share_struct_sources`: inside a run of `hoist_safe_call` statements, the first copy
        from `src` keeps its leaf values in locals (`_h0`, `_h1`, ...) and the later copies from
        the same `src` store those (the thesis copies `CBT.Socket` into three to six socket FBs
        in a row). Only for structs of scalar leaves, and never when a destination lies inside
        the source's root or the source inside the destination's (then nothing is kept). False:
        not applied, the plain copy is written."""
        call = self.sharing
        if not self.options.share_struct_sources or not self.options.cache_locals or call is None:
            return False
        leaves = scalar_leaves(st)
        shape = source_shape(self.facts, node)
        if leaves is None or shape is None or not self.unowned_by(shape, call):
            return False
        hoisted = self.hoisted
        if hoisted is not None and hoisted[0] == src and hoisted[1] == st:
            self.w.line(f"_sd = {dst}")
            self.shared_copy_body("_sd", leaves, 0, [0])
            return True
        self.w.line(f"_sd = {dst}; _ss = {src}")
        self.shared_first_copy("_sd", "_ss", st, 0, [0])
        self.hoisted = (src, st, shape)
        return True

    def unowned_by(self, shape: tuple, call: n.CallStatement) -> bool:
        """Can the struct a source path (`source_shape`) reaches not be part of the instance this
        call's native writes? It is part of it only if one of its containers is that instance,
        or, past a reference or in-out, if the container it points to could lie inside it (its
        type is one the callee's variables hold)."""
        info = self.facts.calls[call.call.nid]
        callee = type_key(t.FBType(name=info.pou.name, qualname=info.pou.qualname))
        indirect, pointed, containers = shape
        if callee in {type_key(c) for c in containers}:
            return False
        return not indirect or (pointed is not None and type_key(pointed) not in self.owned_types(info.pou))

    def owned_types(self, pou) -> set:
        """Keys of the struct and FB types an instance of `pou` holds by value (its in-outs and
        references excluded: they hold nothing)."""
        seen: set = set()

        def walk(ty) -> None:
            if isinstance(ty, t.ArrayType):
                walk(ty.element)
            elif isinstance(ty, t.StructType):
                key = type_key(ty)
                if key not in seen:
                    seen.add(key)
                    for _, fty in ty.fields:
                        walk(fty)
            elif isinstance(ty, t.FBType):
                key = type_key(ty)
                if key not in seen:
                    seen.add(key)
                    inner = self.model.pous.get(ty.qualname.lower())
                    for var in (inner.variables.values() if inner is not None else ()):
                        if var.section != IN_OUT:
                            walk(var.type)
        for var in pou.variables.values():
            if var.section != IN_OUT:
                walk(var.type)
        return seen

    def shared_first_copy(self, dst: str, src: str, st: t.StructType, depth: int, counter: list[int]) -> None:
        for name, fty in st.fields:
            attr = var_attr(name)
            if isinstance(fty, t.StructType):
                d, s = f"d{depth}", f"s{depth}"
                self.w.line(f"{d} = {dst}.{attr}; {s} = {src}.{attr}")
                self.shared_first_copy(d, s, fty, depth + 1, counter)
            else:
                self.w.line(f"{dst}.{attr} = _h{counter[0]} = {src}.{attr}")
                counter[0] += 1

    def shared_copy_body(self, dst: str, leaves: list, depth: int, counter: list[int]) -> None:
        for attr, sub in leaves:
            if sub is not None:
                d = f"d{depth}"
                self.w.line(f"{d} = {dst}.{attr}")
                self.shared_copy_body(d, sub, depth + 1, counter)
            else:
                self.w.line(f"{dst}.{attr} = _h{counter[0]}")
                counter[0] += 1

    def inline_output_copy(self, target: n.Expr, value: str, st: t.StructType) -> bool:
        """`inline_input_copy` for a STRUCT output (`Socket => CBT.Socket`, every scan in the
        thesis's CBT_Connect): the store `place._assign(value)` written as the field-by-field copy
        into `place`. False when not applied (the store is something else, or not inlined)."""
        lines = self.store_code(target, value, st)
        call = f"._assign({value})"
        if len(lines) != 1 or not lines[0].endswith(call):
            return False
        return self.inline_input_copy(lines[0][:-len(call)], value, st)

    def direct_native_call(self, inst: str, call: n.Call, pou: POUInfo) -> str | None:
        """`direct_native_calls` (decided by the analysis): a native FB called straight through
        its implementation, `inst._impl.call(inst, _ctx)`; with `skip_quiet_native_calls` and a
        quiet pin declared, only while that pin is not `inst._impl.quiet`."""
        if call.nid not in self.plan.direct_native:
            return None
        native = f"{inst}._impl.call({inst}, _ctx)"
        pin = self.quiet_pin(pou) if self.options.skip_quiet_native_calls else None
        return native if pin is None else f"if {inst}.{pin} is not {inst}._impl.quiet: {native}"

    @staticmethod
    def quiet_pin(pou: POUInfo) -> str | None:
        """The storage name of the pin a native FB declares quiet (`{native quiet:Execute}`,
        stdlib/registry.py), None without one."""
        return None if pou.quiet_pin is None else var_attr(pou.variables[pou.quiet_pin].name)

    def reused_array_ref(self, place: str, var: Variable, value: n.Expr) -> bool:
        """`reuse_array_refs` (decided by the analysis, `ArrayRefReuse`): keep the `ArrayRef` the
        instance already holds when it names the same list from the same element on. False when
        not applied (the plain `arg_code` path)."""
        reuse = self.plan.array_refs.get(value.nid)
        if reuse is None:
            return False
        base, start, lo = self.expr(reuse.base), reuse.start, reuse.lo
        if not base.replace(".", "").replace("_", "").isalnum():
            return False   # only a plain variable path is evaluated twice
        actual = self.settings.open_array_bounds is OpenArrayBounds.ACTUAL
        # under `open_array_bounds=actual` the kept one may come from a call site passing `lo`
        # (`_ar.start` for `_ar.start != 0`: an int's truth, two bytecodes less on every call)
        moved = f"_ar.start != {start}" if start else "_ar.start"
        same = f"_ar.data is not {base} or {moved}" + (f" or _ar.lo != {lo}" if actual else "")
        made = f"_ArrayRef({base}, {start}, {lo})" if lo else f"_ArrayRef({base}, {start})"
        self.w.line(f"if (_ar := {place}) is None or {same}: {place} = {made}")
        return True

    def inline_fb_body(self, inst: str, pou, node: n.POU) -> None:
        """Lower `node`'s body here with `inst` (a plain name) as the owner of its variables."""
        saved = (self.pou, self.owner, self.cached, self.used, self.assigned, self.range_vars, self.unchecked)
        span = self.w.span
        self.pou, self.owner = pou, inst
        self.cached, self.used, self.assigned, self.range_vars, self.unchecked = {}, set(), set(), {}, set()
        try:
            self.body(node.body)
        finally:
            self.pou, self.owner, self.cached, self.used, self.assigned, self.range_vars, self.unchecked = saved
            self.w.span = span


def type_key(ty: t.Type) -> tuple[str, str]:
    """A struct or FB type by kind and qualified name (what `unowned_by` compares)."""
    if isinstance(ty, t.FBType):
        return ("fb", ty.qualname.lower())
    if isinstance(ty, t.StructType):
        return ("struct", ty.qualname.lower())
    return ("other", repr(ty))


def source_shape(facts, e: n.Expr) -> tuple[bool, t.Type | None, list[t.Type]] | None:
    """(through a reference or in-out, the type it points to, the types of the objects the path
    passes through from the root or from that reference on) of a plain variable path; None for
    anything else."""
    if isinstance(e, n.Name):
        ref = facts.names.get(e.nid)
        ty = facts.types.get(e.nid)
        if ref is None or ref.variable is None or ty is None:
            return None
        var = ref.variable
        if var.section == IN_OUT or isinstance(var.type, t.RefType) or e.nid in facts.auto_deref:
            return (True, ty, [ty])
        return (False, None, [ty])
    if isinstance(e, (n.Member, n.Index)):
        inner = source_shape(facts, e.base)
        ty = facts.types.get(e.nid)
        if inner is None or ty is None:
            return None
        if e.nid in facts.auto_deref or isinstance(facts.types.get(e.base.nid), t.RefType):
            return (True, ty, [ty])
        indirect, pointed, containers = inner
        return (indirect, pointed, containers + [ty])
    return None


def scalar_leaves(st: t.StructType) -> list | None:
    """`[(attr, sub)]` of a struct whose every leaf is a scalar (`sub` None, or the nested
    struct's list), in `struct_assign_body`'s order; None when a leaf is an array, a union, a
    reference or an FB (copied otherwise, or aliased)."""
    out: list = []
    for name, fty in st.fields:
        if isinstance(fty, t.UnionType):
            return None
        if isinstance(fty, t.StructType):
            sub = scalar_leaves(fty)
            if sub is None or not fty.fields:
                return None
            out.append((var_attr(name), sub))
        elif t.is_aggregate(fty) or isinstance(fty, (t.RefType, t.InterfaceType)):
            return None
        else:
            out.append((var_attr(name), None))
    return out


_LITERALS = (n.IntLiteral, n.RealLiteral, n.BoolLiteral, n.StringLiteral, n.TimeLiteral)


def struct_leaves(st: t.StructType) -> int:
    """Stores a field-by-field copy of `st` makes (an array field is one `_assign_array`)."""
    count = 0
    for _, fty in st.fields:
        count += struct_leaves(fty) if isinstance(fty, t.StructType) else 1
    return count


_INLINE_COPY_LEAVES = 32
