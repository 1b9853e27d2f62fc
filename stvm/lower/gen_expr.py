"""Generators for ST expressions: names and places, conversions, operators, references,
array indexing, and FUNCTION / METHOD calls with their arguments.

A mixin of `Lowerer` (`stvm/lower/codegen.py`); each method returns Python source for one
expression. Only names from `lower.names` and `py_literal` constants are written."""

from __future__ import annotations

from stvm.numeric import f32, strfit
from stvm.dialects import allows
from stvm.semantics import types as t
from stvm.semantics.body import RESULT_KEY, is_any_descriptor
from stvm.semantics.facts import CallInfo
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, Variable
from stvm.lower.names import method_attr, var_attr
from stvm.lower.pycode import int_contains, py_literal, wrap_int
from stvm.syntax import nodes as n
from stvm.settings import IntDivZero, OpenArrayBounds, SubrangeCheck


_RING_OPS = {"PLUS": "+", "MINUS": "-", "STAR": "*"}


class ExpressionGenerator:
    """Expressions: `expr(e)` returns the Python source of one ST expression."""

    def member_name(self, base_type: t.Type, name: str) -> str:
        if isinstance(base_type, t.StructType):
            return base_type.field_name(name) or name
        if isinstance(base_type, t.FBType):
            pou = self.model.pous[base_type.qualname.lower()]
            var = pou.pin(name)
            return var.name if var else name
        return name

    def var_place(self, var: Variable, is_global: bool) -> str:
        if is_global or var.section in (GLOBAL, EXTERNAL):
            return f"_G.{var_attr(var.name)}"
        key = var.key
        if key in self.cached:
            self.used.add(key)
            return var_attr(var.name)
        return f"{self.owner}.{var_attr(var.name)}"

    def expr_as(self, e: n.Expr, ty: t.Type | None) -> str:
        """Code for `e` converted to type `ty` (implicit conversion of an assignment/argument)."""
        src = self.facts.types.get(e.nid)
        if ty is None or src is None:
            return self.expr(e)
        if isinstance(ty, t.InterfaceType) and e.nid in self.facts.untyped:
            return "None"   # `itf := 0`
        if e.nid in self.facts.consts and not isinstance(self.facts.consts[e.nid], (list, dict)):
            value = self.facts.consts[e.nid]
            converted = self.convert_const(value, ty)
            if converted is not None:
                return py_literal(converted)
        return self.coerce(self.expr(e), src, ty, e.span)

    def convert_const(self, value: object, ty: t.Type) -> object:
        if isinstance(ty, t.RealType) and isinstance(value, (int, float)) and not isinstance(value, bool):
            return f32(float(value)) if ty.bits == 32 else float(value)
        if isinstance(ty, t.IntType) and isinstance(value, int) and not isinstance(value, bool):
            return ty.wrap(value)
        if isinstance(ty, t.StringType) and isinstance(value, bytes if not t.is_wide(ty) else str):
            return strfit(value, ty.max_bytes)
        if isinstance(ty, t.BoolType) and isinstance(value, int):
            return bool(value)   # IEC: 0 and 1 are BOOL literals
        if isinstance(ty, (t.TimeType, t.EnumType)) and isinstance(value, (bool, int)):
            return value
        return None

    def coerce(self, code: str, src: t.Type, dst: t.Type, span: n.Span | None = None) -> str:
        if src == dst:
            return code
        if self.pointer_cast(src, dst):
            # TwinCAT/CODESYS: POINTER TO A into a POINTER TO B reads A's bytes as B's
            return f"_ptr_cast({code}, {self.type_const(src.target)}, {self.type_const(dst.target)}{self.short_arg()})"  # type: ignore[attr-defined]
        if isinstance(dst, t.SubrangeType) and isinstance(src, t.IntType):
            code = code if int_contains(dst, src) else wrap_int(code, dst)
            if isinstance(src, t.SubrangeType) and dst.low <= src.low and src.high <= dst.high:
                return code
            if self.settings.subrange_check is SubrangeCheck.FAULT:
                return f"_subrange({code}, {dst.low}, {dst.high})"
            return code
        if isinstance(dst, t.IntType) and isinstance(src, t.IntType):
            return code if int_contains(dst, src) else wrap_int(code, dst)
        if isinstance(dst, t.RealType):
            if isinstance(src, t.IntType) or (isinstance(src, t.RealType) and src.bits > dst.bits):
                return f"_f32({code})" if dst.bits == 32 else f"float({code})"
            return code
        if isinstance(dst, t.StringType) and isinstance(src, t.StringType):
            if src.size <= dst.size:
                return code
            if span is None:
                return f"_strfit({code}, {dst.max_bytes})"
            # string_overflow: a fault, or a cut and one warning per site (the site's location
            # is passed, not an index, so debugger expressions lowered on their own work too)
            return f"_str_overflow({code}, {dst.max_bytes}, {span.file!r}, {span.line}, {span.column})"
        return code

    def expr(self, e: n.Expr) -> str:
        if e.nid in self.facts.consts and not isinstance(e, n.Call):
            value = self.facts.consts[e.nid]
            ty = self.facts.types.get(e.nid)
            if ty is not None and not isinstance(value, (list, dict)):
                converted = self.convert_const(value, ty)
                if converted is not None:
                    return py_literal(converted)
            if isinstance(value, (bool, int, float, bytes)):
                return py_literal(value)
        return getattr(self, "ex_" + type(e).__name__)(e)

    def ex_Name(self, e: n.Name) -> str:
        if self.facts.props and e.nid in self.facts.props:
            return self.property_get(e)
        ref = self.facts.names[e.nid]
        if ref.kind == "enum":
            return py_literal(ref.value)
        if ref.kind == "result":
            result = "_rb.value" if self.result_boxed() else "_r"
            if e.nid in self.facts.auto_deref:   # a result REFERENCE TO: read through it
                return self.deref_code(result, self.pou.return_type.target)
            return result
        if ref.kind == "null":
            return "None"
        if ref.kind in ("this", "super"):
            return "self"
        var = ref.variable
        assert var is not None
        place = self.name_place(ref)
        if e.nid in self.facts.auto_deref:
            return self.deref_code(place, var.type.target)  # type: ignore[attr-defined]
        if var.section == IN_OUT and not isinstance(var.type, (t.StructType, t.ArrayType, t.FBType)):
            return f"{place}.get()"
        return place

    def name_place(self, ref) -> str:
        """Where a variable Name lives: a method's view of its instance (`self.v_x`) or var_place."""
        if ref.kind == "field":
            return f"self.{var_attr(ref.variable.name)}"
        return self.var_place(ref.variable, ref.kind == "global")

    def property_target(self, e: n.Expr, accessor: str) -> str:
        """`obj.g_p` / `obj.s_p` for a property use (checked: facts.props)."""
        prop, how = self.facts.props[e.nid]
        attr = method_attr(prop.name, accessor)
        if how == "self":
            return f"self.{attr}"
        assert isinstance(e, n.Member)
        if how == "super":
            owner = self.model.pous[prop.owner]
            return f"{self.classes[owner.key]}.{attr}.__get__(self)"
        base = self.expr(e.base)
        if how == "itf":
            base = f"({base} or _null_itf())"
        return f"{base}.{attr}"

    def property_get(self, e: n.Expr) -> str:
        return f"{self.property_target(e, 'GET')}()"

    def deref_code(self, code: str, target: t.Type) -> str:
        """Read through a reference: the aggregate itself, or the scalar's current value; NULL
        (None) faults at the statement (`_null_ref`)."""
        if t.is_aggregate(target):
            if self.byte_pointers():
                return f"_ptr_deref_agg({code} or _null_ref())"
            return f"({code} or _null_ref())"
        return f"({code} or _null_ref()).get()"

    def ex_Deref(self, e: n.Deref) -> str:
        if isinstance(e.base, n.Name) and getattr(self.facts.names.get(e.base.nid), "kind", None) in ("this", "super"):
            return "self"   # THIS^ / SUPER^: the instance itself, never NULL
        held = self.held_local(e.base)  # type: ignore[attr-defined]
        if held is not None:
            return held
        return self.deref_code(self.expr(e.base), self.facts.types[e.nid])

    def raw_place(self, target: n.Expr) -> str:
        """The storage of a Name/Member itself (for a REFERENCE TO variable: the reference)."""
        if isinstance(target, n.Name):
            ref = self.facts.names[target.nid]
            return "_r" if ref.kind == "result" else self.name_place(ref)
        assert isinstance(target, n.Member)
        base_type = self.facts.types[target.base.nid]
        return f"{self.expr(target.base)}.{var_attr(self.member_name(base_type, target.name))}"

    def reference_code(self, value: n.Expr) -> str:
        """REF(x) / ADR(x) / `REF= x`: the reference object for the variable x (see RefType)."""
        ty = self.facts.types[value.nid]
        if isinstance(value, n.Deref):
            return self.expr(value.base)
        if isinstance(value, (n.Name, n.Member)) and value.nid in self.facts.auto_deref:
            return self.raw_place(value)
        if isinstance(value, n.Call) and value.nid in self.facts.auto_deref:
            return self.call_code(value)   # a call's REFERENCE TO result: the reference itself
        if isinstance(ty, t.RefType) and ty.is_null:
            return "None"
        if t.is_aggregate(ty):
            return self.expr(value)
        return self.ref_code(value)

    def ex_AssignExpr(self, e: n.AssignExpr) -> str:
        """`(x := v)` (CODESYS/TwinCAT): the target's reference first, then the value converted to
        the target's type, stored once and returned (`_assigned`, runtime/helpers.py)."""
        ty = self.facts.types.get(e.target.nid)
        return f"_assigned({self.ref_code(e.target)}, {self.expr_as(e.value, ty)})"

    def ex_Member(self, e: n.Member) -> str:
        if self.facts.props and e.nid in self.facts.props:
            return self.property_get(e)
        base_type = self.facts.types[e.base.nid]
        return f"{self.expr(e.base)}.{var_attr(self.member_name(base_type, e.name))}"

    def ex_PartialAccess(self, e: n.PartialAccess) -> str:
        return f"((({self.expr(e.base)}) >> {e.bit * e.width}) & {(1 << e.width) - 1})"

    def ex_BitAccess(self, e: n.BitAccess) -> str:
        return f"((({self.expr(e.base)}) >> {e.bit}) & 1 == 1)"

    def index_code(self, e: n.Index) -> str:
        prefix, last = self.index_parts(e)
        return f"{prefix}[{last}]"

    def index_parts(self, e: n.Index) -> tuple[str, str]:
        """(code of the container, code of the last subscript) for an element access."""
        base_type = self.facts.types[e.base.nid]
        code = self.expr(e.base)
        assert isinstance(base_type, t.ArrayType)
        if base_type.dims is None and base_type.rank > 1:
            return self.open_array_n_parts(code, e)
        if base_type.dims is None:
            # an ARRAY[*] parameter: index 0 .. elements passed - 1, checked like any array
            # access in user code (`array_oob`); ArrayRef's own check is the instructions'
            ix = self.expr(e.indices[0])
            if self.settings.open_array_bounds is OpenArrayBounds.ACTUAL:
                # the argument's own bounds: lo .. lo + elements passed - 1
                tmp = self.new_tmp("i")
                return code, (f"{tmp} - {code}.lo if {code}.lo <= ({tmp} := {ix}) < {code}.lo + len({code}) "
                              f"else _oob({tmp}, {code}.lo, {code}.lo + len({code}) - 1)")
            if not ix.replace(".", "").replace("_", "").isalnum():
                tmp = self.new_tmp("i")
                return code, f"{tmp} if 0 <= ({tmp} := {ix}) < len({code}) else _oob({tmp}, 0, len({code}) - 1)"
            return code, f"{ix} if 0 <= {ix} < len({code}) else _oob({ix}, 0, len({code}) - 1)"
        subscripts = []
        if len(e.indices) == 1 and len(base_type.dims) == 1:
            for key in self.unchecked:
                c = self.loop_offset(e.indices[0], key)
                if c is not None:
                    offset = c - base_type.dims[0][0]
                    ix = e.indices[0]
                    name = self.expr(ix if isinstance(ix, n.Name) else ix.left)  # type: ignore[attr-defined]
                    return code, name if offset == 0 else f"{name} + {offset}" if offset > 0 else f"{name} - {-offset}"
        for ix, (lo, hi) in zip(e.indices, base_type.dims):
            const = self.facts.consts.get(ix.nid)
            if isinstance(const, int):
                subscripts.append(f"{const - lo}")
                continue
            inner = self.expr(ix)
            if inner.replace(".", "").replace("_", "").isalnum():
                subscripts.append(f"({inner}) - {lo} if {lo} <= {inner} <= {hi} else _oob({inner}, {lo}, {hi})")
            else:
                tmp = self.new_tmp("i")
                subscripts.append(f"{tmp} - {lo} if {lo} <= ({tmp} := {inner}) <= {hi} else _oob({tmp}, {lo}, {hi})")
        for sub in subscripts[:-1]:
            code += f"[{sub}]"
        return code, subscripts[-1]

    def ex_Index(self, e: n.Index) -> str:
        if isinstance(self.facts.types.get(e.base.nid), t.RefType):
            return f"{self.pointer_index(e)}.get()"
        return self.index_code(e)

    def pointer_index(self, e: n.Index) -> str:
        """`p[i]` (TwinCAT/CODESYS): a pointer to the i-th element from p."""
        ty = self.facts.types[e.base.nid]
        return (f"_ptr_index({self.expr(e.base)}, {self.expr(e.indices[0])}, "
                f"{self.type_const(ty.target)}{self.short_arg()})")  # type: ignore[attr-defined]

    def ex_Unary(self, e: n.Unary) -> str:
        ty = self.facts.types[e.nid]
        operand = self.expr_as(e.operand, ty)
        if e.op == "NOT":
            if isinstance(ty, t.BoolType):
                return f"(not {operand})"
            assert isinstance(ty, t.IntType)
            return f"(~{operand} & {(1 << ty.bits) - 1})" if not ty.signed else f"(~{operand})"
        if e.op == "PLUS":
            return operand
        if isinstance(ty, t.IntType):
            return wrap_int(f"-{operand}", ty)
        if getattr(ty, "family", "") == "TIME":
            return self.time_wrap(f"-{operand}", ty)
        return f"(-{operand})"

    def ex_Binary(self, e: n.Binary) -> str:
        op = e.op
        lt = self.facts.types.get(e.left.nid)
        if op in ("EQ", "NE") and (isinstance(lt, t.InterfaceType)
                                   or isinstance(self.facts.types.get(e.right.nid), t.InterfaceType)):
            # interfaces compare by the instance they hold; 0 and NULL are "none"
            left, right = ("None" if x.nid in self.facts.untyped else self.expr(x) for x in (e.left, e.right))
            return f"({left} {'is' if op == 'EQ' else 'is not'} {right})"
        if op in ("EQ", "NE") and self.byte_pointers() and (
                isinstance(lt, t.RefType) and e.right.nid in self.facts.untyped
                or isinstance(self.facts.types.get(e.right.nid), t.RefType) and e.left.nid in self.facts.untyped):
            # `p = 0`: the NULL address
            side = e.right if e.left.nid in self.facts.untyped else e.left
            return f"({self.expr(side)} {'is' if op == 'EQ' else 'is not'} None)"
        if op in ("EQ", "NE") and isinstance(lt, t.RefType) and lt.flavour == "POINTER" and not lt.is_null \
                and self.byte_pointers() and isinstance(self.facts.types.get(e.right.nid), t.RefType) \
                and not self.facts.types[e.right.nid].is_null:
            # byte-addressed pointers: the same byte of the same variable, whatever the pointers' types
            target = self.type_const(lt.target)  # type: ignore[attr-defined]
            left, right = self.expr(e.left), self.expr_as(e.right, lt)
            same = f"_same_ref(_as_ptr({left}, {target}{self.short_arg()}), _as_ptr({right}, {target}{self.short_arg()}))"
            return same if op == "EQ" else f"(not {same})"
        if op in ("EQ", "NE") and isinstance(lt, t.RefType):
            rt = self.facts.types[e.right.nid]
            target = lt.target if not lt.is_null else rt.target  # type: ignore[attr-defined]
            left, right = self.expr(e.left), self.expr(e.right)
            # aggregates: the same object; scalars: the same variable (AttrRef/ItemRef equality)
            same = f"({left} is {right})" if target is None or t.is_aggregate(target) else f"_same_ref({left}, {right})"
            return same if op == "EQ" else f"(not {same})"
        if op in ("EQ", "NE", "LT", "GT", "LE", "GE"):
            operand = self.facts.operand_types.get(e.nid)
            left = self.expr_as(e.left, operand) if operand is not None else self.expr(e.left)
            right = self.expr_as(e.right, operand) if operand is not None else self.expr(e.right)
            pyop = {"EQ": "==", "NE": "!=", "LT": "<", "GT": ">", "LE": "<=", "GE": ">="}[op]
            return f"({left} {pyop} {right})"
        ty = self.facts.types[e.nid]
        if op in ("AND_THEN", "OR_ELSE"):
            # short-circuit: the right operand runs only when the left does not decide
            return f"({self.expr_as(e.left, ty)} {'and' if op == 'AND_THEN' else 'or'} {self.expr_as(e.right, ty)})"
        if op in ("AND", "AMP", "OR", "XOR"):
            pyop = {"AND": "&", "AMP": "&", "OR": "|", "XOR": "^"}[op]
            return f"({self.expr_as(e.left, ty)} {pyop} {self.expr_as(e.right, ty)})"
        if isinstance(ty, t.RefType):
            # TwinCAT/CODESYS pointer arithmetic: bytes further (or back)
            ptr, delta = (e.left, e.right) if isinstance(lt, t.RefType) else (e.right, e.left)
            amount = self.expr(delta) if op == "PLUS" else f"-({self.expr(delta)})"
            return f"_ptr_add({self.expr(ptr)}, {amount}, {self.type_const(ty.target)}{self.short_arg()})"  # type: ignore[attr-defined]
        if isinstance(ty, t.TimeType):
            return self.time_binary(e, ty)
        if op == "POW":
            code = f"_expt({self.expr(e.left)}, {self.expr(e.right)})"
            return f"_f32({code})" if isinstance(ty, t.RealType) and ty.bits == 32 else code
        if self.options.ring_chain and isinstance(ty, t.IntType) and op in _RING_OPS \
                and not self.in_range_without_wrap(e, ty) \
                and e.nid not in self.facts.consts:
            # A chain of + - * in one integer type wraps once at the end: arithmetic modulo 2^n
            # gives the same result as wrapping every step, and long sums stay shallow for Python.
            return wrap_int(self.ring_chain(e, ty), ty)
        left = self.expr_as(e.left, ty)
        right = self.expr_as(e.right, ty)
        if isinstance(ty, t.IntType):
            if op == "SLASH":
                div = "_idiv" if self.settings.int_div_zero is IntDivZero.FAULT else "_idiv0"
                return wrap_int(f"{div}({left}, {right})", ty)
            if op == "MOD":
                mod = "_imod" if self.settings.int_div_zero is IntDivZero.FAULT else "_imod0"
                return f"{mod}({left}, {right})"
            pyop = {"PLUS": "+", "MINUS": "-", "STAR": "*"}[op]
            if self.in_range_without_wrap(e, ty):
                return f"({left} {pyop} {right})"
            return wrap_int(f"{left} {pyop} {right}", ty)
        assert isinstance(ty, t.RealType)
        if op == "SLASH":
            code = f"_fdiv({left}, {right})"
        else:
            code = f"({left} {({'PLUS': '+', 'MINUS': '-', 'STAR': '*'})[op]} {right})"
        return f"_f32({code})" if ty.bits == 32 else code

    def ring_chain(self, e: n.Binary, ty: t.IntType) -> str:
        """Unwrapped Python code of `e` (+, -, * in type `ty`), flattening operands that are
        themselves + - * chains computed in the same type."""
        def operand(x: n.Expr) -> tuple[str, str | None]:
            if isinstance(x, n.Binary) and x.op in _RING_OPS and self.facts.types.get(x.nid) == ty \
                    and x.nid not in self.facts.consts and not self.in_range_without_wrap(x, ty):
                return self.ring_chain(x, ty), x.op
            return self.expr_as(x, ty), None
        left, left_op = operand(e.left)
        right, right_op = operand(e.right)
        if left_op in ("PLUS", "MINUS") and e.op == "STAR":
            left = f"({left})"
        if right_op is not None:
            right = f"({right})"
        return f"{left} {_RING_OPS[e.op]} {right}"

    def in_range_without_wrap(self, e: n.Binary, ty: t.IntType) -> bool:
        """`i + k` / `i - k` on a range-FOR variable that provably stays inside `ty` (no wrap code).

        The loop guard ensures i <= hi - step (step > 0), so i + k <= hi for 0 <= k <= step;
        with a constant start s, i >= s, so i - k >= lo when s - k >= lo."""
        if not self.options.no_wrap_in_range:
            return False
        if not isinstance(e.left, n.Name) or e.op not in ("PLUS", "MINUS"):
            return False
        info = self.range_vars.get(e.left.parts[0].lower())
        k = self.facts.consts.get(e.right.nid)
        if info is None or not isinstance(k, int) or isinstance(k, bool) or k < 0:
            return False
        step, start, var_type = info
        if not int_contains(ty, var_type):
            return False
        if e.op == "PLUS":
            return step > 0 and k <= step and var_type.hi <= ty.hi
        return step > 0 and start is not None and start - k >= ty.lo

    def time_binary(self, e: n.Binary, ty: t.Type) -> str:
        lt = self.facts.types[e.left.nid]
        rt = self.facts.types[e.right.nid]
        left, right = self.expr(e.left), self.expr(e.right)
        if e.op in ("PLUS", "MINUS"):
            return self.time_wrap(f"{left} {'+' if e.op == 'PLUS' else '-'} {right}", ty)
        if e.op == "STAR":
            if isinstance(lt, t.RealType) or isinstance(rt, t.RealType):
                return f"int({left} * {right})"
            return self.time_wrap(f"{left} * {right}", ty)
        zero = self.settings.int_div_zero is IntDivZero.ZERO   # TIME / 0 is an integer division by 0
        if isinstance(rt, t.RealType):
            return f"{'_tdiv0' if zero else '_tdiv'}({left}, {right})"
        return self.time_wrap(f"{'_idiv0' if zero else '_idiv'}({left}, {right})", ty)

    def time_wrap(self, code: str, ty: t.Type) -> str:
        """A time result wrapped as the dialect's runtime does: TIME/LTIME are unsigned under
        `unsigned_time` (TwinCAT/CODESYS: modulo 2^32 ms, 2^64 ns), else a LINT of nanoseconds."""
        if isinstance(ty, t.TimeType) and ty.family == "TIME" and allows(self.settings.dialect, "unsigned_time"):
            return f"(({code}) % {1 << 64 if ty.long else (1 << 32) * 1_000_000})"
        return wrap_int(code, t.LINT)  # type: ignore[arg-type]

    def open_array_code(self, code: str, vtype: t.Type | None) -> str:
        """A whole fixed array passed to an ARRAY[*] parameter (see `open_array_bounds`)."""
        if self.settings.open_array_bounds is OpenArrayBounds.ACTUAL and isinstance(vtype, t.ArrayType) \
                and vtype.dims and vtype.dims[0][0] != 0:
            return f"_ArrayRef({code}, 0, {vtype.dims[0][0]})"
        return f"_ArrayRef({code}, 0)"

    def open_array_n_parts(self, code: str, e: n.Index) -> tuple[str, str]:
        """An element of an ARRAY[*, *] parameter (an `_OpenArray`): each subscript checked
        against the bounds the argument brought (`array_oob`, as any array access)."""
        subscripts = []
        for d, ix in enumerate(e.indices):
            tmp = self.new_tmp("i")
            lo, hi = f"{code}.bounds[{d}][0]", f"{code}.bounds[{d}][1]"
            subscripts.append(f"{tmp} - {lo} if {lo} <= ({tmp} := {self.expr(ix)}) <= {hi} else _oob({tmp}, {lo}, {hi})")
        return f"{code}.data" + "".join(f"[{sub}]" for sub in subscripts[:-1]), subscripts[-1]

    def open_array_n_code(self, code: str, vtype: t.Type | None) -> str:
        """A fixed array passed to an ARRAY[*, *] parameter: its lists with the bounds the callee
        sees (`open_array_bounds`); an ARRAY[*, *] passed on is the same object."""
        if not isinstance(vtype, t.ArrayType) or vtype.dims is None:
            return code
        if self.settings.open_array_bounds is OpenArrayBounds.ACTUAL:
            bounds = tuple(vtype.dims)
        else:
            bounds = tuple((0, hi - lo) for lo, hi in vtype.dims)
        return f"_OpenArray({code}, {bounds!r})"

    def type_query_code(self, e: n.Call) -> str:
        """LOWER_BOUND / UPPER_BOUND of an ARRAY[*] parameter, or a constant (see body.py)."""
        word, operand = self.facts.type_queries[e.nid]
        if word == "CONST":
            ty = self.facts.types.get(e.nid)
            converted = self.convert_const(operand, ty) if ty is not None else None
            return py_literal(operand if converted is None else converted)
        if isinstance(operand, tuple):   # ARRAY[*, *]: (array, dimension)
            array, dim = operand
            return f"{self.expr(array)}.bounds[{dim - 1}][{0 if word == 'LOWER_BOUND' else 1}]"
        code = self.expr(operand)  # type: ignore[arg-type]
        if word == "LOWER_BOUND":
            return f"{code}.lo"
        return f"({code}.lo + len({code}) - 1)"

    def ex_Call(self, e: n.Call) -> str:
        if e.nid in self.facts.ref_calls:
            return self.reference_code(e.args[0].value)
        if e.nid in self.facts.type_queries:
            return self.type_query_code(e)
        if self.facts.intrinsics and e.nid in self.facts.intrinsics:
            what, key = self.facts.intrinsics[e.nid]
            if what == "valid":
                arg = e.args[0].value   # a REFERENCE TO variable: the reference, not its target
                code = self.raw_place(arg) if arg.nid in self.facts.auto_deref else self.expr(arg)
                return f"({code} is not None)"
            return f"_query_itf({self.expr(e.args[0].value)}, {key!r}, {self.ref_code(e.args[1].value)})"
        if e.nid in self.facts.auto_deref:   # a result REFERENCE TO: read through it
            return self.deref_code(self.call_code(e), self.facts.types[e.nid])
        return self.call_code(e)

    def call_code(self, e: n.Call) -> str:
        info = self.facts.calls[e.nid]
        if info.nested_en:
            return self.nested_en_call(e, info)
        return self.function_call(e, info)

    def nested_en_call(self, e: n.Call, info: CallInfo) -> str:
        """A call with EN/ENO inside a larger expression: `_en_call` runs it only when EN is TRUE
        (else the result type's initial value) and sets ENO around it, where the call stands."""
        enabled = self.expr_as(info.en, t.BOOL) if info.en is not None else "True"
        result = info.generic_type if isinstance(info.pou.return_type, t.GenericType) else info.pou.return_type
        default = self.default_expr(result) if result is not None else "None"
        eno, negate = (self.ref_code(info.eno[0]), info.eno[1]) if info.eno is not None else ("None", False)
        return f"_en_call({enabled}, lambda: {self.function_call(e, info)}, lambda: {default}, {eno}, {negate})"

    def arg_code(self, var: Variable, value: n.Expr) -> str:
        """Code for one argument bound to parameter `var` (by value, or a reference for in-outs)."""
        if value.nid in self.facts.array_from_element:
            assert isinstance(value, n.Index)
            base_code = self.expr(value.base)
            base_type = self.facts.types[value.base.nid]
            assert isinstance(base_type, t.ArrayType)
            if base_type.dims is None:
                return f"_ArrayRef({base_code}.data, {base_code}.start + {self.expr(value.indices[0])})"
            lo, hi = base_type.dims[0]
            ix = self.expr(value.indices[0])
            return f"_ArrayRef({base_code}, ({ix}) - {lo} if {lo} <= {ix} <= {hi} else _oob({ix}, {lo}, {hi}))"
        ptype = var.type
        vtype = self.facts.types.get(value.nid)
        if isinstance(ptype, t.ArrayType) and ptype.dims is None and ptype.rank > 1:
            return self.open_array_n_code(self.expr(value), vtype)
        if var.section == IN_OUT:
            if isinstance(ptype, t.ArrayType) and ptype.dims is None:
                code = self.expr(value)
                if isinstance(vtype, t.ArrayType) and vtype.dims is None:
                    return code
                return self.open_array_code(code, vtype)
            if isinstance(vtype, (t.StructType, t.ArrayType, t.FBType)):
                return self.expr(value)
            return self.ref_code(value)
        if isinstance(ptype, t.ArrayType) and ptype.dims is None:
            code = self.expr(value)
            return code if isinstance(vtype, t.ArrayType) and vtype.dims is None else self.open_array_code(code, vtype)
        if isinstance(ptype, t.GenericType):
            return self.expr(value)
        if is_any_descriptor(ptype) and not is_any_descriptor(vtype):
            return self.any_descriptor(value, ptype)  # type: ignore[arg-type]
        code = self.expr_as(value, ptype)
        if isinstance(ptype, (t.StructType, t.ArrayType)):
            return f"_copy_value({code})"
        return code

    def any_descriptor(self, value: n.Expr, descriptor: t.StructType) -> str:
        """An argument of an ANY input (TwinCAT/CODESYS): the `__SYSTEM.AnyType` structure of its
        type class, a POINTER TO BYTE to it and its size in bytes. A value that is not a variable
        gets a temporary (`_Box`), as the compiler's temporary in TwinCAT."""
        vtype = self.facts.types[value.nid]
        props = self.facts.props or {}
        variable = value.nid not in props and (
            isinstance(value, (n.Member, n.Index, n.Deref))
            or isinstance(value, n.Name) and getattr(self.facts.names.get(value.nid), "kind", None)
            not in ("enum", "null", "result", "this", "super"))
        if variable and value.nid not in self.facts.consts:
            ref = self.reference_code(value)
        elif t.is_aggregate(vtype):
            ref = f"_copy_value({self.expr(value)})"
        else:
            ref = f"_Box({self.expr(value)})"
        pointer = f"_ptr_cast({ref}, {self.type_const(vtype)}, {self.type_const(t.BYTE)}{self.short_arg()})"  # type: ignore[attr-defined]
        size = t.byte_size(vtype, allows(self.settings.dialect, "short_times")) or 0
        fields = {"TypeClass": type_class(vtype), "pValue": pointer, "diSize": size}
        names = {name.lower(): name for name, _ in descriptor.fields}
        binds = ", ".join(f"{var_attr(names[key.lower()])}={code}" for key, code in fields.items())
        return f"_with({self.default_expr(descriptor)}, {binds})"  # type: ignore[attr-defined]

    def byte_pointers(self) -> bool:
        """The profile's pointers are byte addresses (`pointer_arithmetic`, docs/memory_model.md)."""
        return allows(self.settings.dialect, "pointer_arithmetic")

    def short_arg(self) -> str:
        """The time-layout argument of the memory helpers: `, True` under `short_times`."""
        return ", True" if allows(self.settings.dialect, "short_times") else ""

    def pointer_cast(self, src: t.Type | None, dst: t.Type | None) -> bool:
        return (isinstance(src, t.RefType) and isinstance(dst, t.RefType) and src.flavour == dst.flavour == "POINTER"
                and not src.is_null and not dst.is_null and not t.same_type(src.target, dst.target)
                and self.byte_pointers())

    def result_boxed(self) -> bool:
        """Does ADR() take the address of this POU's result? Then the result lives in a `_Box`
        (`_rb`) that the pointer references, not in the local `_r`."""
        return self.pou is not None and (self.pou.key, RESULT_KEY) in self.facts.addressed

    def ref_code(self, value: n.Expr) -> str:
        if isinstance(value, n.Name):
            ref = self.facts.names[value.nid]
            if ref.kind == "result":
                return "_rb"
            var = ref.variable
            assert var is not None
            if var.section == IN_OUT and ref.kind != "global":
                return f"{'self' if ref.kind == 'field' else self.owner}.{var_attr(var.name)}"
            place = self.name_place(ref)
            if value.nid in self.facts.auto_deref:
                return place   # a REFERENCE TO variable passed on: its reference object
            obj, attr = place.rsplit(".", 1)
            return f"_AttrRef({obj}, {attr!r})"
        if isinstance(value, n.Deref):
            return self.expr(value.base)
        if isinstance(value, n.Member):
            base_type = self.facts.types[value.base.nid]
            return f"_AttrRef({self.expr(value.base)}, {var_attr(self.member_name(base_type, value.name))!r})"
        if isinstance(value, n.Index) and isinstance(self.facts.types.get(value.base.nid), t.RefType):
            return self.pointer_index(value)
        if isinstance(value, n.Index):
            base, ix = self.index_parts(value)
            return f"_ItemRef({base}, {ix})"
        raise AssertionError("checked: in-out needs a variable")

    def function_call(self, e: n.Call, info: CallInfo) -> str:
        pou = info.pou
        name = self.classes[pou.key] if not info.oo else ""
        given = {var.key: value for var, value in info.inputs}
        args = []
        for p in pou.params():
            if p.key in given:
                args.append(self.arg_code(p, given[p.key]))
            elif pou.variadic and p is pou.params()[-1] and info.extra:
                continue
            else:
                args.append(self.var_default(p))
        for extra in info.extra:
            last = pou.params()[-1]
            args.append(self.arg_code(last, extra))
        for var, target, negate in info.outputs:
            ref = self.ref_code(target)
            target_type = self.facts.types.get(target.nid)
            convert = "(not v)" if negate else self.coerce("v", var.type, target_type, target.span) \
                if target_type is not None else "v"
            if convert != "v":
                ref = f"_MapRef({ref}, lambda v: {convert})"
            args.append(f"o_{var_attr(var.name)}={ref}")
        if info.oo:
            attr = method_attr(pou.name)
            if info.oo == "self":
                return f"self.{attr}({', '.join(args)})"
            if info.oo == "super":
                return f"{self.classes[info.static_owner]}.{attr}({', '.join(['self'] + args)})"
            inst = self.expr(info.instance)  # type: ignore[arg-type]
            if info.oo == "itf":
                inst = f"({inst} or _null_itf())"
            return f"{inst}.{attr}({', '.join(args)})"
        if pou.native:
            lead = ["_ctx"]
            if pou.generic:
                lead.append(self.type_const(info.generic_type) if info.generic_type is not None else "None")
            if pou.typed:
                lead.append(self.types_const(info.arg_types))
            return f"{name}({', '.join(lead + args)})"
        return f"{name}({', '.join(args)})"


# __SYSTEM.TYPE_CLASS of a type (stvm/stdlib/type_classes.st: the values of the CODESYS Base
# Interfaces library "TypeClass", which TwinCAT ships)
_TYPE_CLASSES = {"BOOL": 0, "BYTE": 2, "WORD": 3, "DWORD": 4, "LWORD": 5, "SINT": 6, "INT": 7, "DINT": 8,
                 "LINT": 9, "USINT": 10, "UINT": 11, "UDINT": 12, "ULINT": 13, "REAL": 14, "LREAL": 15,
                 "TIME": 18, "DATE": 19, "DATE_AND_TIME": 20, "TIME_OF_DAY": 21, "LTIME": 37, "LDATE": 46,
                 "LDATE_AND_TIME": 47, "LTIME_OF_DAY": 48}


def type_class(ty: t.Type) -> int:
    if isinstance(ty, t.SubrangeType):
        return 24
    if isinstance(ty, t.WStringType):
        return 17
    if isinstance(ty, t.StringType):
        return 16
    if isinstance(ty, t.EnumType):
        return 25
    if isinstance(ty, t.ArrayType):
        return 26
    if isinstance(ty, t.RefType):
        return 23 if ty.flavour == "REFERENCE" else 22
    if isinstance(ty, (t.StructType, t.FBType)):
        return 28   # TYPE_USERDEF
    if ty.name in _TYPE_CLASSES:
        return _TYPE_CLASSES[ty.name]
    if isinstance(ty, t.TimeType):
        return _TYPE_CLASSES.get(ty.family, 18)
    return 29   # TYPE_NONE
