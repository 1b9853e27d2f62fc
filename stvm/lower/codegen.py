"""Stage 3: lower the checked project to one Python module, with a map back to ST lines.

Each FUNCTION_BLOCK/PROGRAM becomes a class (variables are slots `v_<name>`, the body is
`__call__`), each FUNCTION a Python function with a frame object, each STRUCT a class with
`_copy`/`_assign`. One Python statement group per ST statement; `LineMap` maps every generated
line to the ST statement's span, so faults and breakpoints speak ST.

Safety: only names from `lower.names` and `repr()`-ed literals of checked Python types are
written; no ST text is ever copied into the generated source.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from stvm.numeric import f32, strfit
from stvm.semantics import types as t
from stvm.semantics.checker import Analysis
from stvm.semantics.facts import CallInfo
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, INPUT, OUTPUT, TEMP, POUInfo, Variable
from stvm.lower.layout import build_layout
from stvm.lower.names import method_attr, unit_name, var_attr
from stvm.syntax import nodes as n
from stvm.syntax.walk import calls_in, name_uses, root_name, walk
from stvm.settings import ArrayOob, EnumDefault, ForEndEval, IntDivZero, OpenArrayBounds, SubrangeCheck
from stvm.lower.product import LineMap, LoweredProject  # noqa: F401 (API)


def _lit(value: object) -> str:
    """Python source for a checked runtime constant (bool, int, float, bytes)."""
    if isinstance(value, bool) or value is None:
        return repr(value)
    if isinstance(value, int):
        return repr(value)
    if isinstance(value, float):
        if math.isnan(value):
            return "float('nan')"
        if math.isinf(value):
            return "float('inf')" if value > 0 else "float('-inf')"
        return repr(value)
    if isinstance(value, bytes):
        return repr(value)
    raise AssertionError(f"not a literal: {type(value).__name__}")


_RING_OPS = {"PLUS": "+", "MINUS": "-", "STAR": "*"}


def _wrap(code: str, ty: t.IntType) -> str:
    mask = (1 << ty.bits) - 1
    if ty.signed:
        half = 1 << (ty.bits - 1)
        return f"((({code}) + {half} & {mask}) - {half})"
    return f"(({code}) & {mask})"


def _contains(dst: t.IntType, src: t.IntType) -> bool:
    return dst.lo <= src.lo and src.hi <= dst.hi


class _Writer:
    def __init__(self) -> None:
        self.lines: list[str] = []
        self.indent = 0
        self.line_map = LineMap()
        self.span: n.Span | None = None

    def line(self, text: str) -> None:
        self.lines.append("    " * self.indent + text)
        spans = self.line_map.spans
        if self.span is not None or (spans and spans[-1] is not None):
            self.line_map.add(len(self.lines), self.span)

    def blank_span(self) -> None:
        self.span = None

    def append(self, other: "_Writer") -> None:
        """Append a body generated separately, shifting its line map."""
        offset = len(self.lines)
        self.lines.extend(other.lines)
        for line, span in zip(other.line_map.lines, other.line_map.spans):
            self.line_map.add(line + offset, span)


class Lowerer:
    def __init__(self, analysis: Analysis, settings) -> None:
        self.a = analysis
        self.model = analysis.model
        self.facts = analysis.facts
        self.settings = settings
        self.w = _Writer()
        self.classes: dict[str, str] = {}
        self.natives: dict[str, str] = {}
        self.native_fbs: dict[str, str] = {}
        self.types: list[t.Type] = []
        self.sites: list[n.Span] = []
        self.tmp = 0
        # per-POU state
        self.pou: POUInfo | None = None
        self.owner = "self"
        self.loops: list[tuple[str, list[str]]] = []   # (kind, continue-code lines)
        # Variables held in Python locals during a call (see `cached_vars`): key → Variable,
        # and which of them the body used / assigned (for the prologue and the write-back).
        self.cached: dict[str, Variable] = {}
        self.used: set[str] = set()
        self.assigned: set[str] = set()
        self.cache_locals = getattr(settings, "cache_locals", True)
        # loop variables of range-FORs in scope: key → (step, constant start or None, type)
        self.range_vars: dict[str, tuple[int, int | None, t.IntType]] = {}
        self.unchecked: set[str] = set()   # range-FOR variables whose array accesses were hoisted

    # ---- names
    def assign_names(self) -> None:
        for i, (key, st) in enumerate(sorted(self.model.structs.items())):
            self.classes[key] = unit_name("S", i, st.qualname)  # type: ignore[attr-defined]
        for i, (key, pou) in enumerate(sorted(self.model.pous.items())):
            if pou.kind == "FUNCTION":
                name = unit_name("N" if pou.native else "F", i, pou.qualname)
                if pou.native:
                    self.natives[name] = pou.qualname.split("\\")[-1].upper()
            else:
                name = unit_name("P", i, pou.qualname)
                if pou.native:
                    self.native_fbs[name] = pou.qualname.split("\\")[-1].upper()
            self.classes[key] = name

    def type_const(self, ty: t.Type) -> str:
        for i, existing in enumerate(self.types):
            if existing == ty and type(existing) is type(ty):
                return f"_T[{i}]"
        self.types.append(ty)
        return f"_T[{len(self.types) - 1}]"

    def types_const(self, types_: tuple[t.Type, ...]) -> str:
        """A tuple of types in `_T` (for `typed` natives)."""
        return "(" + "".join(self.type_const(ty) + ", " for ty in types_) + ")"

    def new_tmp(self, stem: str) -> str:
        self.tmp += 1
        return f"_{stem}{self.tmp}"

    # ---- default values
    def enum_default(self, ty: t.EnumType) -> int:
        if ty.default is not None:
            return ty.default
        if self.settings.enum_default is EnumDefault.ZERO or not ty.members:
            return 0
        return ty.members[0][1]

    def default_expr(self, ty: t.Type, init: object = None) -> str:
        if isinstance(ty, t.BoolType):
            return _lit(bool(init) if init is not None else False)
        if isinstance(ty, t.IntType):
            return _lit(init if init is not None else 0)
        if isinstance(ty, t.RealType):
            return _lit(float(init) if init is not None else 0.0)
        if isinstance(ty, t.TimeType):
            return _lit(init if init is not None else 0)
        if isinstance(ty, t.StringType):
            return _lit(init if init is not None else b"")
        if isinstance(ty, t.EnumType):
            return _lit(init if init is not None else self.enum_default(ty))
        if isinstance(ty, t.StructType):
            cls = self.classes[ty.qualname.lower()]
            if isinstance(init, dict) and init:
                parts = ", ".join(f"{var_attr(ty.field_name(k) or k)}={self.default_expr(ty.field_type(k), v)}"  # type: ignore[arg-type]
                                  for k, v in init.items() if ty.field_type(k) is not None)
                return f"_with({cls}(), {parts})"
            return f"{cls}()"
        if isinstance(ty, t.FBType):
            return f"{self.classes[ty.qualname.lower()]}()"
        if isinstance(ty, t.ArrayType):
            if ty.dims is None:
                return "None"
            values = init if isinstance(init, list) else []
            return self.array_expr(ty, list(ty.dims), values)
        return "None"

    def array_expr(self, ty: t.ArrayType, dims: list[tuple[int, int]], flat: list) -> str:
        lo, hi = dims[0]
        count = hi - lo + 1
        if len(dims) == 1:
            elem = ty.element
            scalar = isinstance(elem, (t.BoolType, t.IntType, t.RealType, t.TimeType, t.StringType, t.EnumType))
            if not flat:
                if scalar:
                    return f"[{self.default_expr(elem)}] * {count}"
                return f"[{self.default_expr(elem)} for _ in range({count})]"
            items = [self.default_expr(elem, flat[i] if i < len(flat) else None) for i in range(count)]
            return "[" + ", ".join(items) + "]"
        inner = 1
        for l2, h2 in dims[1:]:
            inner *= h2 - l2 + 1
        rows = []
        for i in range(count):
            rows.append(self.array_expr(ty, dims[1:], flat[i * inner:(i + 1) * inner]))
        return "[" + ", ".join(rows) + "]"

    def var_default(self, var: Variable) -> str:
        return self.default_expr(var.type, var.init)

    # ---- module
    def lower(self) -> LoweredProject:
        self.assign_names()
        w = self.w
        w.line("# generated by stvm from checked ST; do not edit")
        for key, st in sorted(self.model.structs.items()):
            self.struct_class(key, st)  # type: ignore[arg-type]
        self.globals_class()
        for key, pou in self.class_order():
            node = self.a.pou_nodes.get(key)
            if pou.kind == "FUNCTION":
                if not pou.native:
                    self.function(pou, node)
            elif pou.kind != "INTERFACE":
                self.fb_class(pou, node)
        # the layout (lower/layout.py) is computed from the model with the same `names` the
        # generator used, not collected while emitting: readers need neither the generator nor facts
        return LoweredProject("\n".join(w.lines) + "\n", w.line_map, self.classes, self.natives,
                              self.native_fbs, self.types, self.sites, layouts=build_layout(self.model))

    def class_order(self) -> list[tuple[str, POUInfo]]:
        """POUs in key order, except that a base FB comes before the FBs extending it."""
        pous = self.model.pous
        order: list[tuple[str, POUInfo]] = []
        done: set[str] = set()

        def visit(key: str) -> None:
            if key in done:
                return
            done.add(key)
            base = pous[key].base
            if base is not None and base in pous:
                visit(base)
            order.append((key, pous[key]))

        for key in sorted(pous):
            visit(key)
        return order

    def struct_class(self, key: str, st: t.StructType) -> None:
        w = self.w
        w.blank_span()
        cls = self.classes[key]
        attrs = [var_attr(name) for name, _ in st.fields]
        inits = self.a.type_inits.get(key, {})
        w.line(f"class {cls}:")
        w.indent += 1
        w.line(f"__slots__ = {tuple(attrs)!r}")
        w.line("def __init__(self):")
        w.indent += 1
        for (name, fty), attr in zip(st.fields, attrs):
            w.line(f"self.{attr} = {self.default_expr(fty, inits.get(name.lower()))}")
        if not attrs:
            w.line("pass")
        w.indent -= 1
        w.line("def _copy(self):")
        w.indent += 1
        w.line(f"other = {cls}.__new__({cls})")
        for (name, fty), attr in zip(st.fields, attrs):
            if isinstance(fty, (t.StructType, t.ArrayType)):
                w.line(f"other.{attr} = _copy_value(self.{attr})")
            else:
                w.line(f"other.{attr} = self.{attr}")
        w.line("return other")
        w.indent -= 1
        w.line("def _assign(self, src):")
        w.indent += 1
        w.line("if src is self: return")
        self.struct_assign_body("self", "src", st, 0)
        w.indent -= 2

    def struct_assign_body(self, dst: str, src: str, st: t.StructType, depth: int) -> None:
        """Field by field, nested STRUCT fields inline (one Python call per struct assignment,
        not one per nested struct: the thesis copies `_sSOCKET` into every socket FB call)."""
        for name, fty in st.fields:
            attr = var_attr(name)
            if isinstance(fty, t.StructType) and fty.fields:
                d, s = f"d{depth}", f"s{depth}"
                self.w.line(f"{d} = {dst}.{attr}; {s} = {src}.{attr}")
                self.struct_assign_body(d, s, fty, depth + 1)
            elif isinstance(fty, t.StructType):
                self.w.line(f"{dst}.{attr}._assign({src}.{attr})")
            elif isinstance(fty, t.ArrayType):
                self.w.line(f"_assign_array({dst}.{attr}, {src}.{attr})")
            else:
                self.w.line(f"{dst}.{attr} = {src}.{attr}")

    def globals_class(self) -> None:
        w = self.w
        w.blank_span()
        attrs = [var_attr(v.name) for v in self.model.globals.values()]
        w.line("class G_globals:")
        w.indent += 1
        w.line(f"__slots__ = {tuple(attrs)!r}")
        w.line("def __init__(self):")
        w.indent += 1
        for var in self.model.globals.values():
            w.line(f"self.{var_attr(var.name)} = {self.var_default(var)}")
        if not attrs:
            w.line("pass")
        w.indent -= 2

    def fb_class(self, pou: POUInfo, node: n.POU | None) -> None:
        w = self.w
        w.blank_span()
        cls = self.classes[pou.key]
        base = self.model.pous[pou.base] if pou.base is not None else None
        inherited = set(base.variables) if base is not None else set()
        own = [v for v in pou.variables.values() if v.section != EXTERNAL and v.key not in inherited]
        attrs = [var_attr(v.name) for v in own]
        if pou.native:
            attrs.append("_impl")
        w.line(f"class {cls}({self.classes[base.key]}):" if base is not None else f"class {cls}:")
        w.indent += 1
        w.line(f"__slots__ = {tuple(attrs)!r}")
        if pou.interfaces or base is not None:
            # what __QUERYINTERFACE asks: every interface the instance implements (keys)
            w.line(f"_itfs = {tuple(sorted(self.implemented(pou)))!r}")
            w.line(f"_st = {pou.name!r}")
        w.line("def __init__(self):")
        w.indent += 1
        if base is not None:
            w.line(f"{self.classes[base.key]}.__init__(self)")
        for var in own:
            if var.section == IN_OUT:
                w.line(f"self.{var_attr(var.name)} = None")
            else:
                w.line(f"self.{var_attr(var.name)} = {self.var_default(var)}")
        if pou.native:
            w.line(f"self._impl = _NATIVE_FB[{pou.qualname.split(chr(92))[-1].upper()!r}]()")
        if not attrs:
            w.line("pass")
        w.indent -= 1
        w.line("def __call__(self):")
        w.indent += 1
        self.pou = pou
        self.owner = "self"
        if pou.native:
            w.line("self._impl.call(self, _ctx)")
        else:
            assert node is not None
            cached = self.cached_vars(pou, node)
            temps_reset = [f"self.{var_attr(v.name)} = {self.var_default(v)}" for v in pou.variables.values()
                           if v.section == TEMP and v.key not in cached]
            self.cached_body(pou, node, cached, temps_reset, [])
        w.indent -= 1
        for method in pou.methods.values():
            if not method.abstract:
                self.function(method, self.a.method_nodes[method.key], method_attr(method.name))
        for prop in pou.properties.values():
            for kind, accessor in (("GET", prop.getter), ("SET", prop.setter)):
                if accessor is not None and not accessor.abstract:
                    self.function(accessor, self.a.method_nodes[accessor.key], method_attr(prop.name, kind))
        self.pou = pou
        w.indent -= 1
        w.blank_span()

    def implemented(self, pou: POUInfo) -> set[str]:
        out: set[str] = set()
        cur: POUInfo | None = pou
        while cur is not None:
            stack = list(cur.interfaces)
            while stack:
                key = stack.pop()
                if key not in out and key in self.model.pous:
                    out.add(key)
                    stack.extend(self.model.pous[key].interfaces)
            cur = self.model.pous.get(cur.base) if cur.base else None
        return out

    def function(self, pou: POUInfo, node, method: str = "") -> None:
        """A FUNCTION, or (`method`: its Python name) a METHOD / property accessor of the FB class
        being written: the same frame, with `self` the instance."""
        w = self.w
        w.blank_span()
        name = method or self.classes[pou.key]
        params = pou.params()
        outputs = [v for v in pou.variables.values() if v.section == OUTPUT]
        args = ", ".join((["self"] if method else []) + [var_attr(p.name) for p in params]
                         + [f"o_{var_attr(o.name)}=None" for o in outputs])
        w.line(f"def {name}({args}):")
        w.indent += 1
        self.pou = pou
        self.owner = "_f"
        assert node is not None and (pou.return_type is not None or method)
        if method:
            # a METHOD none of whose variables is passed by reference keeps them all in Python
            # locals (the inputs are the arguments, the outputs are written back at the end): no
            # frame object
            every = self.cached_vars(pou, node, min_uses=0, outputs_local=True)
            if all(v.key in every for v in pou.variables.values() if v.section != "VAR_INST"):
                prologue = [f"{var_attr(v.name)} = {self.var_default(v)}" for v in pou.variables.values()
                            if v.section not in (INPUT, IN_OUT, "VAR_INST")]
                prologue.append(f"_r = {self.default_expr(pou.return_type)}" if pou.return_type is not None else "_r = None")
                epilogue = [f"if o_{var_attr(o.name)} is not None: o_{var_attr(o.name)}.set({var_attr(o.name)})"
                            for o in outputs]
                self.cached_body(pou, node, every, prologue, epilogue, frameless=True)
                w.blank_span()
                w.line("return _r")
                w.indent -= 1
                return
        # every variable lives on the frame `_f` (so in-outs can reference it); the often used
        # ones are copied into Python locals by cached_body
        prologue = ["_f = _Frame()"] if pou.variables or not method else []
        for p in params:
            prologue.append(f"_f.{var_attr(p.name)} = {var_attr(p.name)}")
        for var in pou.variables.values():
            if var.section not in (INPUT, IN_OUT, EXTERNAL, "VAR_INST"):
                prologue.append(f"_f.{var_attr(var.name)} = {self.var_default(var)}")
        prologue.append(f"_r = {self.default_expr(pou.return_type)}" if pou.return_type is not None else "_r = None")
        # VAR_OUTPUT of a function: written through the caller's references when it returns
        epilogue = [f"if o_{var_attr(o.name)} is not None: o_{var_attr(o.name)}.set(_f.{var_attr(o.name)})"
                    for o in outputs]
        self.cached_body(pou, node, self.cached_vars(pou, node), prologue, epilogue)
        w.blank_span()
        w.line("return _r")
        w.indent -= 1

    # ---- statements
    def body(self, stmts: tuple[n.Statement, ...]) -> None:
        if not stmts:
            self.w.line("pass")
            return
        for s in stmts:
            self.statement(s)

    def statement(self, s: n.Statement) -> None:
        self.w.span = s.span
        guarded = isinstance(s, (n.Assign, n.CallStatement)) and self.has_native_call(s)
        # array_oob=skip_statement: a statement with an array access is skipped when an index
        # is out of range (a compound one only for its own expressions: inner statements skip
        # themselves)
        skippable = self.settings.array_oob is ArrayOob.SKIP_STATEMENT and self.has_index(s)
        if guarded or skippable:
            self.w.line("try:")
            self.w.indent += 1
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

    def has_index(self, node: object) -> bool:
        return any(isinstance(x, n.Index) for x in walk((node,)))

    def has_native_call(self, node: object) -> bool:
        """Does this statement call a FUNCTION (which may raise an instruction error)?"""
        for x in walk((node,)):
            if isinstance(x, n.Call):
                info = self.facts.calls.get(id(x))
                if info is not None and not info.is_fb and not info.oo:
                    return True
        return False

    def with_en_eno(self, call: n.Expr, emit) -> bool:
        """Emit `emit()` under the call's EN (run only when TRUE) and set its ENO: FALSE before
        the call (an instruction error leaves it FALSE), TRUE after it, FALSE when EN is FALSE.
        False when the call has neither."""
        info = self.facts.calls.get(id(call)) if isinstance(call, n.Call) else None
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
        target_type = self.facts.types.get(id(s.target))
        if target_type is None and isinstance(s.target, n.Name):
            target_type = self.pou.return_type  # type: ignore[union-attr]
        value = self.expr_as(s.value, target_type)
        self.store(s.target, value, target_type)

    def st_CallStatement(self, s: n.CallStatement) -> None:
        if self.with_en_eno(s.call, lambda: self.plain_call(s)):
            return
        self.plain_call(s)

    def plain_call(self, s: n.CallStatement) -> None:
        info = self.facts.calls[id(s.call)]
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
                lo = self.facts.consts.get(id(label.low))
                if label.high is None:
                    tests.append(f"{sel} == {_lit(lo)}")
                else:
                    hi = self.facts.consts.get(id(label.high))
                    tests.append(f"{_lit(lo)} <= {sel} <= {_lit(hi)}")
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
        var_type = self.facts.types[id(s.variable)]
        assert isinstance(var_type, t.IntType)
        step_const = self.facts.consts.get(id(s.step)) if s.step is not None else 1
        if self.range_for_ok(s, step_const):
            self.range_for(s, var_type, step_const)  # type: ignore[arg-type]
            return
        self.store(s.variable, self.expr_as(s.start, var_type), var_type)
        end = self.new_tmp("end")
        self.w.line(f"{end} = {self.expr_as(s.end, var_type)}")
        read = self.expr(s.variable)
        if isinstance(step_const, int):
            step = _lit(step_const)
            cond = f"{read} <= {end}" if step_const > 0 else f"{read} >= {end}"
        else:
            step = self.new_tmp("step")
            self.w.line(f"{step} = {self.expr_as(s.step, var_type)}")  # type: ignore[arg-type]
            cond = f"({read} <= {end} if {step} > 0 else {read} >= {end})"
        increment = self.store_code(s.variable, _wrap(f"{read} + {step}", var_type), var_type)
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

    def range_for_ok(self, s: n.For, step: object) -> bool:
        """Can this FOR become a Python `for … in range()` (same semantics, much faster)?

        Needs: a constant non-zero step, the end evaluated once, a loop variable held in a local
        that the body never assigns, and no EXIT/RETURN (so a wrap-around at the type's limit
        is a genuinely endless loop, reported as a fault instead of hanging)."""
        if not isinstance(step, int) or isinstance(step, bool) or step == 0:
            return False
        if self.settings.for_end_eval is not ForEndEval.ONCE:
            return False
        ref = self.facts.names.get(id(s.variable))
        if ref is None or ref.kind != "var" or ref.variable is None or ref.variable.key not in self.cached:
            return False
        key = ref.variable.key
        for node in walk(s.body):
            if isinstance(node, (n.Exit, n.Return)):
                return False
            if isinstance(node, n.Assign) and root_name(node.target) == key:
                return False
            if isinstance(node, n.For) and node.variable.parts[0].lower() == key:
                return False
            if isinstance(node, n.Argument) and node.kind != "input" and node.kind != "positional" \
                    and root_name(node.value) == key:
                return False
        return True

    def range_for(self, s: n.For, var_type: t.IntType, step: int) -> None:
        var = self.expr(s.variable)
        key = s.variable.parts[0].lower()
        start = self.new_tmp("start")
        end = self.new_tmp("end")
        self.w.line(f"{start} = {self.expr_as(s.start, var_type)}")
        self.w.line(f"{end} = {self.expr_as(s.end, var_type)}")
        limit = var_type.hi - step if step > 0 else var_type.lo - step
        # the loop variable would wrap before passing `end`: an endless loop on the controller
        guard = f"{end} > {limit}" if step > 0 else f"{end} < {limit}"
        self.w.line(f"if {guard}: _endless_for({end}, {step}, {var_type.name!r})")
        stop = f"{end} + 1" if step > 0 else f"{end} - 1"
        rng = self.new_tmp("range")
        self.w.line(f"{rng} = range({start}, {stop}, {step})")
        self.assigned.add(key)
        start_const = self.facts.consts.get(id(s.start))
        accesses = self.hoistable_accesses(s.body, key)
        if accesses:
            # Bounds checks hoisted out of the loop: if every `a[i + c]` stays inside its array
            # for the whole range, run a copy of the loop without per-access checks; otherwise
            # the checked copy faults at exactly the iteration the controller would.
            first, last = (start, end) if step > 0 else (end, start)
            conds = [f"{first} + {c} >= {lo} and {last} + {c} <= {hi}" for c, lo, hi in sorted(accesses)]
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
        if isinstance(ix, n.Name) and len(ix.parts) == 1 and ix.parts[0].lower() == key:
            return 0
        if isinstance(ix, n.Binary) and ix.op in ("PLUS", "MINUS") and isinstance(ix.left, n.Name) \
                and len(ix.left.parts) == 1 and ix.left.parts[0].lower() == key:
            c = self.facts.consts.get(id(ix.right))
            if isinstance(c, int) and not isinstance(c, bool) and id(ix.right) in self.facts.untyped:
                return c if ix.op == "PLUS" else -c
        return None

    def hoistable_accesses(self, body, key: str) -> set[tuple[int, int, int]]:
        """(offset, lo, hi) of every 1-D array access indexed by the loop variable (+/- const)."""
        found: set[tuple[int, int, int]] = set()
        for node in walk(body):
            if isinstance(node, n.Index) and len(node.indices) == 1:
                base_type = self.facts.types.get(id(node.base))
                if isinstance(base_type, t.ArrayType) and base_type.dims and len(base_type.dims) == 1:
                    c = self.loop_offset(node.indices[0], key)
                    if c is not None:
                        lo, hi = base_type.dims[0]
                        found.add((c, lo, hi))
        return found

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
        self.w.line("return _r" if self.pou and self.pou.kind in ("FUNCTION", "METHOD") else "return")

    def st_Empty(self, s: n.Empty) -> None:
        self.w.line("pass")

    # ---- stores
    def store(self, target: n.Expr, value: str, ty: t.Type | None) -> None:
        for line in self.store_code(target, value, ty):
            self.w.line(line)

    def store_code(self, target: n.Expr, value: str, ty: t.Type | None) -> list[str]:
        """Python statements that store `value` (already converted to `ty`) into `target`."""
        aggregate = isinstance(ty, (t.StructType, t.ArrayType))
        if self.facts.props and id(target) in self.facts.props:
            return [f"{self.property_target(target, 'SET')}({value})"]
        if isinstance(target, n.Name):
            ref = self.facts.names[id(target)]
            if ref.kind == "result":
                return [f"_r = {value}" if not aggregate else f"_r = _copy_value({value})"]
            var = ref.variable
            assert var is not None
            place = self.name_place(ref)
            if id(target) in self.facts.auto_deref:
                return self.store_through(place, value, ty)
            if var.key in self.cached and ref.kind not in ("global", "field"):
                self.assigned.add(var.key)
            if var.section == IN_OUT and not aggregate:
                return [f"{place}.set({value})"]
            return [self.assign_into(place, value, ty)]
        if isinstance(target, n.Deref):
            return self.store_through(self.expr(target.base), value, ty)
        if isinstance(target, n.Member):
            base = self.expr(target.base)
            base_type = self.facts.types[id(target.base)]
            attr = var_attr(self.member_name(base_type, target.name))
            if id(target) in self.facts.auto_deref:
                return self.store_through(f"{base}.{attr}", value, ty)
            return [self.assign_into(f"{base}.{attr}", value, ty)]
        if isinstance(target, n.Index):
            place = self.index_code(target)
            return [self.assign_into(place, value, ty)]
        if isinstance(target, n.PartialAccess):
            current = self.expr(target.base)
            base_type = self.facts.types[id(target.base)]
            shift, mask = target.bit * target.width, (1 << target.width) - 1
            merged = f"(({current}) & {~(mask << shift) & ((1 << base_type.bits) - 1)}) | (({value}) << {shift})"  # type: ignore[attr-defined]
            if base_type.signed:  # type: ignore[attr-defined]
                merged = _wrap(merged, base_type)  # type: ignore[arg-type]
            return self.store_code(target.base, merged, base_type)
        if isinstance(target, n.BitAccess):
            current = self.expr(target.base)
            base_type = self.facts.types[id(target.base)]
            return self.store_code(target.base, f"_setbit({current}, {target.bit}, {value})", base_type)
        raise AssertionError("checked: not an lvalue")

    def store_through(self, ref: str, value: str, ty: t.Type | None) -> list[str]:
        """Store through a reference (`r^ := v`, a REFERENCE TO variable); NULL faults."""
        if ty is not None and t.is_aggregate(ty):
            return [self.assign_into(f"({ref} or _null_ref())", value, ty)]
        return [f"({ref} or _null_ref()).set({value})"]

    def assign_into(self, place: str, value: str, ty: t.Type | None) -> str:
        if isinstance(ty, t.StructType):
            return f"{place}._assign({value})"
        if isinstance(ty, t.ArrayType):
            return f"_assign_array({place}, {value})"
        return f"{place} = {value}"

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
        if var.key in self.cached:
            self.used.add(var.key)
            return var_attr(var.name)
        return f"{self.owner}.{var_attr(var.name)}"

    def cached_vars(self, pou: POUInfo, node: n.POU, min_uses: int = -1,
                    outputs_local: bool = False) -> dict[str, Variable]:
        """Variables a call may keep in Python locals (LOAD_FAST instead of attribute access).

        Safe for every variable of the POU's own instance/frame that is never passed by reference
        (as a scalar in-out argument): nothing else can observe it during the call. Aggregates
        (arrays, structs, FB instances) are never rebound, so a local alias is always safe; scalars
        are written back in a `finally`, so values survive RETURN and faults.
        """
        if not self.cache_locals:
            return {}
        referenced: set[str] = set()
        for call in calls_in(node.body):
            info = self.facts.calls.get(id(call))
            if info is None:
                continue
            for var, value in info.inputs:
                if var.section == IN_OUT and isinstance(value, n.Name):
                    referenced.add(value.parts[0].lower())
            if not info.is_fb:
                # a function writes its outputs through references at its end
                for var, target, _ in info.outputs:
                    if isinstance(target, n.Name):
                        referenced.add(target.parts[0].lower())
        if pou.kind in ("FUNCTION", "METHOD") and not outputs_local:
            referenced |= {v.key for v in pou.variables.values() if v.section == OUTPUT}
        if pou.kind != "METHOD" and self.has_members(pou):
            # its methods and properties read and write the instance's variables while the body
            # runs (own calls, calls back through interfaces): only temporaries and aggregates
            # may stay in Python locals
            referenced |= {v.key for v in pou.variables.values() if v.section != TEMP
                           and not isinstance(v.type, (t.StructType, t.ArrayType, t.FBType))}
        # a variable whose reference is taken (REF/ADR/REF=) may be read or written through it
        referenced |= {var for owner, var in self.facts.addressed if owner == pou.key}
        uses = name_uses(node.body)
        out = {}
        for var in pou.variables.values():
            if var.section in (EXTERNAL, GLOBAL, "VAR_INST") or var.key in referenced:
                continue
            if var.section == IN_OUT and not isinstance(var.type, (t.StructType, t.ArrayType, t.FBType)):
                continue  # a scalar in-out is a reference object; keep it on the instance
            # a local costs a load on entry (and a store on exit): worth it from a few uses on
            if uses.get(var.key, 0) < (_CACHE_MIN_USES if min_uses < 0 else min_uses):
                continue
            out[var.key] = var
        return out

    def has_members(self, pou: POUInfo) -> bool:
        cur: POUInfo | None = pou
        while cur is not None:
            if cur.methods or cur.properties:
                return True
            cur = self.model.pous.get(cur.base) if cur.base else None
        return False

    def cached_body(self, pou: POUInfo, node: n.POU, cached: dict[str, Variable], prologue_extra: list[str],
                    epilogue_extra: list[str], frameless: bool = False) -> None:
        """Emit the body of a call with `cached` (from `cached_vars`) in Python locals: prologue,
        try/body/finally write-back. `frameless`: every variable is a local already set by the
        prologue (nothing to load or write back)."""
        outer = self.w
        self.cached = cached
        self.used, self.assigned = set(), set()
        guarded = bool(epilogue_extra) if frameless else (bool(self.cached) or bool(epilogue_extra))
        body_writer = _Writer()
        body_writer.indent = outer.indent + (1 if guarded else 0)
        self.w = body_writer
        self.body(node.body)
        self.w = outer
        # prologue and write-back lines belong to the POU itself (a fault there names its header)
        outer.span = node.span
        for line in prologue_extra:
            outer.line(line)
        temps = {v.key for v in pou.variables.values() if v.section == TEMP}
        for key in sorted(self.used) if not frameless else ():
            var = self.cached[key]
            attr = var_attr(var.name)
            if key in temps:
                outer.line(f"{attr} = {self.var_default(var)}")
            else:
                outer.line(f"{attr} = {self.owner}.{attr}")
        write_back = [k for k in sorted(self.assigned & self.used)
                      if not isinstance(self.cached[k].type, (t.StructType, t.ArrayType, t.FBType))] if not frameless else []
        if guarded:
            outer.line("try:")
        outer.append(body_writer)
        outer.span = node.span
        if guarded:
            outer.line("finally:")
            outer.indent += 1
            for key in write_back:
                attr = var_attr(self.cached[key].name)
                outer.line(f"{self.owner}.{attr} = {attr}")
            for line in epilogue_extra:
                outer.line(line)
            if not write_back and not epilogue_extra:
                outer.line("pass")
            outer.indent -= 1
        else:
            for line in epilogue_extra:
                outer.line(line)
        self.cached, self.used, self.assigned = {}, set(), set()

    # ---- expressions
    def expr_as(self, e: n.Expr, ty: t.Type | None) -> str:
        """Code for `e` converted to type `ty` (implicit conversion of an assignment/argument)."""
        src = self.facts.types.get(id(e))
        if ty is None or src is None:
            return self.expr(e)
        if isinstance(ty, t.InterfaceType) and id(e) in self.facts.untyped:
            return "None"   # `itf := 0`
        if id(e) in self.facts.consts and not isinstance(self.facts.consts[id(e)], (list, dict)):
            value = self.facts.consts[id(e)]
            converted = self.convert_const(value, ty)
            if converted is not None:
                return _lit(converted)
        return self.coerce(self.expr(e), src, ty, e.span)

    def convert_const(self, value: object, ty: t.Type) -> object:
        if isinstance(ty, t.RealType) and isinstance(value, (int, float)) and not isinstance(value, bool):
            return f32(float(value)) if ty.bits == 32 else float(value)
        if isinstance(ty, t.IntType) and isinstance(value, int) and not isinstance(value, bool):
            return ty.wrap(value)
        if isinstance(ty, t.StringType) and isinstance(value, bytes):
            return strfit(value, ty.max_bytes)
        if isinstance(ty, t.BoolType) and isinstance(value, int):
            return bool(value)   # IEC: 0 and 1 are BOOL literals
        if isinstance(ty, (t.TimeType, t.EnumType)) and isinstance(value, (bool, int)):
            return value
        return None

    def coerce(self, code: str, src: t.Type, dst: t.Type, span: n.Span | None = None) -> str:
        if src == dst:
            return code
        if isinstance(dst, t.SubrangeType) and isinstance(src, t.IntType):
            code = code if _contains(dst, src) else _wrap(code, dst)
            if isinstance(src, t.SubrangeType) and dst.low <= src.low and src.high <= dst.high:
                return code
            if self.settings.subrange_check is SubrangeCheck.FAULT:
                return f"_subrange({code}, {dst.low}, {dst.high})"
            return code
        if isinstance(dst, t.IntType) and isinstance(src, t.IntType):
            return code if _contains(dst, src) else _wrap(code, dst)
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
        if id(e) in self.facts.consts and not isinstance(e, n.Call):
            value = self.facts.consts[id(e)]
            ty = self.facts.types.get(id(e))
            if ty is not None and not isinstance(value, (list, dict)):
                converted = self.convert_const(value, ty)
                if converted is not None:
                    return _lit(converted)
            if isinstance(value, (bool, int, float, bytes)):
                return _lit(value)
        return getattr(self, "ex_" + type(e).__name__)(e)

    def ex_Name(self, e: n.Name) -> str:
        if self.facts.props and id(e) in self.facts.props:
            return self.property_get(e)
        ref = self.facts.names[id(e)]
        if ref.kind == "enum":
            return _lit(ref.value)
        if ref.kind == "result":
            return "_r"
        if ref.kind == "null":
            return "None"
        if ref.kind in ("this", "super"):
            return "self"
        var = ref.variable
        assert var is not None
        place = self.name_place(ref)
        if id(e) in self.facts.auto_deref:
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
        prop, how = self.facts.props[id(e)]
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
            return f"({code} or _null_ref())"
        return f"({code} or _null_ref()).get()"

    def ex_Deref(self, e: n.Deref) -> str:
        if isinstance(e.base, n.Name) and getattr(self.facts.names.get(id(e.base)), "kind", None) in ("this", "super"):
            return "self"   # THIS^ / SUPER^: the instance itself, never NULL
        return self.deref_code(self.expr(e.base), self.facts.types[id(e)])

    def raw_place(self, target: n.Expr) -> str:
        """The storage of a Name/Member itself (for a REFERENCE TO variable: the reference)."""
        if isinstance(target, n.Name):
            return self.name_place(self.facts.names[id(target)])
        assert isinstance(target, n.Member)
        base_type = self.facts.types[id(target.base)]
        return f"{self.expr(target.base)}.{var_attr(self.member_name(base_type, target.name))}"

    def reference_code(self, value: n.Expr) -> str:
        """REF(x) / ADR(x) / `REF= x`: the reference object for the variable x (see RefType)."""
        ty = self.facts.types[id(value)]
        if isinstance(value, n.Deref):
            return self.expr(value.base)
        if isinstance(value, (n.Name, n.Member)) and id(value) in self.facts.auto_deref:
            return self.raw_place(value)
        if isinstance(ty, t.RefType) and ty.is_null:
            return "None"
        if t.is_aggregate(ty):
            return self.expr(value)
        return self.ref_code(value)

    def st_RefAssign(self, s: n.RefAssign) -> None:
        place = self.raw_place(s.target)
        if isinstance(s.target, n.Name) and s.target.parts[0].lower() in self.cached:
            self.assigned.add(s.target.parts[0].lower())
        self.w.line(f"{place} = {self.reference_code(s.value)}")

    def ex_Member(self, e: n.Member) -> str:
        if self.facts.props and id(e) in self.facts.props:
            return self.property_get(e)
        base_type = self.facts.types[id(e.base)]
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
        base_type = self.facts.types[id(e.base)]
        code = self.expr(e.base)
        assert isinstance(base_type, t.ArrayType)
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
            const = self.facts.consts.get(id(ix))
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
        return self.index_code(e)

    def ex_Unary(self, e: n.Unary) -> str:
        ty = self.facts.types[id(e)]
        operand = self.expr_as(e.operand, ty)
        if e.op == "NOT":
            if isinstance(ty, t.BoolType):
                return f"(not {operand})"
            assert isinstance(ty, t.IntType)
            return f"(~{operand} & {(1 << ty.bits) - 1})" if not ty.signed else f"(~{operand})"
        if e.op == "PLUS":
            return operand
        if isinstance(ty, t.IntType):
            return _wrap(f"-{operand}", ty)
        if getattr(ty, "family", "") == "TIME":
            return _wrap(f"-{operand}", t.LINT)  # type: ignore[arg-type]
        return f"(-{operand})"

    def ex_Binary(self, e: n.Binary) -> str:
        op = e.op
        lt = self.facts.types.get(id(e.left))
        if op in ("EQ", "NE") and (isinstance(lt, t.InterfaceType)
                                   or isinstance(self.facts.types.get(id(e.right)), t.InterfaceType)):
            # interfaces compare by the instance they hold; 0 and NULL are "none"
            left, right = ("None" if id(x) in self.facts.untyped else self.expr(x) for x in (e.left, e.right))
            return f"({left} {'is' if op == 'EQ' else 'is not'} {right})"
        if op in ("EQ", "NE") and isinstance(lt, t.RefType):
            rt = self.facts.types[id(e.right)]
            target = lt.target if not lt.is_null else rt.target  # type: ignore[attr-defined]
            left, right = self.expr(e.left), self.expr(e.right)
            # aggregates: the same object; scalars: the same variable (AttrRef/ItemRef equality)
            same = f"({left} is {right})" if target is None or t.is_aggregate(target) else f"_same_ref({left}, {right})"
            return same if op == "EQ" else f"(not {same})"
        if op in ("EQ", "NE", "LT", "GT", "LE", "GE"):
            operand = self.facts.operand_types.get(id(e))
            left = self.expr_as(e.left, operand) if operand is not None else self.expr(e.left)
            right = self.expr_as(e.right, operand) if operand is not None else self.expr(e.right)
            pyop = {"EQ": "==", "NE": "!=", "LT": "<", "GT": ">", "LE": "<=", "GE": ">="}[op]
            return f"({left} {pyop} {right})"
        ty = self.facts.types[id(e)]
        if op in ("AND", "AMP", "OR", "XOR"):
            pyop = {"AND": "&", "AMP": "&", "OR": "|", "XOR": "^"}[op]
            return f"({self.expr_as(e.left, ty)} {pyop} {self.expr_as(e.right, ty)})"
        if isinstance(ty, t.TimeType):
            return self.time_binary(e, ty)
        if op == "POW":
            code = f"_expt({self.expr(e.left)}, {self.expr(e.right)})"
            return f"_f32({code})" if isinstance(ty, t.RealType) and ty.bits == 32 else code
        if isinstance(ty, t.IntType) and op in _RING_OPS and not self.in_range_without_wrap(e, ty) \
                and id(e) not in self.facts.consts:
            # A chain of + - * in one integer type wraps once at the end: arithmetic modulo 2^n
            # gives the same result as wrapping every step, and long sums stay shallow for Python.
            return _wrap(self.ring_chain(e, ty), ty)
        left = self.expr_as(e.left, ty)
        right = self.expr_as(e.right, ty)
        if isinstance(ty, t.IntType):
            if op == "SLASH":
                div = "_idiv" if self.settings.int_div_zero is IntDivZero.FAULT else "_idiv0"
                return _wrap(f"{div}({left}, {right})", ty)
            if op == "MOD":
                mod = "_imod" if self.settings.int_div_zero is IntDivZero.FAULT else "_imod0"
                return f"{mod}({left}, {right})"
            pyop = {"PLUS": "+", "MINUS": "-", "STAR": "*"}[op]
            if self.in_range_without_wrap(e, ty):
                return f"({left} {pyop} {right})"
            return _wrap(f"{left} {pyop} {right}", ty)
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
            if isinstance(x, n.Binary) and x.op in _RING_OPS and self.facts.types.get(id(x)) == ty \
                    and id(x) not in self.facts.consts and not self.in_range_without_wrap(x, ty):
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
        if not isinstance(e.left, n.Name) or e.op not in ("PLUS", "MINUS"):
            return False
        info = self.range_vars.get(e.left.parts[0].lower())
        k = self.facts.consts.get(id(e.right))
        if info is None or not isinstance(k, int) or isinstance(k, bool) or k < 0:
            return False
        step, start, var_type = info
        if not _contains(ty, var_type):
            return False
        if e.op == "PLUS":
            return step > 0 and k <= step and var_type.hi <= ty.hi
        return step > 0 and start is not None and start - k >= ty.lo

    def time_binary(self, e: n.Binary, ty: t.Type) -> str:
        lt = self.facts.types[id(e.left)]
        rt = self.facts.types[id(e.right)]
        left, right = self.expr(e.left), self.expr(e.right)
        if e.op in ("PLUS", "MINUS"):
            return _wrap(f"{left} {'+' if e.op == 'PLUS' else '-'} {right}", t.LINT)  # type: ignore[arg-type]
        if e.op == "STAR":
            if isinstance(lt, t.RealType) or isinstance(rt, t.RealType):
                return f"int({left} * {right})"
            return _wrap(f"{left} * {right}", t.LINT)  # type: ignore[arg-type]
        zero = self.settings.int_div_zero is IntDivZero.ZERO   # TIME / 0 is an integer division by 0
        if isinstance(rt, t.RealType):
            return f"{'_tdiv0' if zero else '_tdiv'}({left}, {right})"
        return _wrap(f"{'_idiv0' if zero else '_idiv'}({left}, {right})", t.LINT)  # type: ignore[arg-type]

    def open_array_code(self, code: str, vtype: t.Type | None) -> str:
        """A whole fixed array passed to an ARRAY[*] parameter (see `open_array_bounds`)."""
        if self.settings.open_array_bounds is OpenArrayBounds.ACTUAL and isinstance(vtype, t.ArrayType) \
                and vtype.dims and vtype.dims[0][0] != 0:
            return f"_ArrayRef({code}, 0, {vtype.dims[0][0]})"
        return f"_ArrayRef({code}, 0)"

    def type_query_code(self, e: n.Call) -> str:
        """LOWER_BOUND / UPPER_BOUND of an ARRAY[*] parameter, or a constant (see body.py)."""
        word, operand = self.facts.type_queries[id(e)]
        if word == "CONST":
            ty = self.facts.types.get(id(e))
            converted = self.convert_const(operand, ty) if ty is not None else None
            return _lit(operand if converted is None else converted)
        code = self.expr(operand)  # type: ignore[arg-type]
        if word == "LOWER_BOUND":
            return f"{code}.lo"
        return f"({code}.lo + len({code}) - 1)"

    # ---- calls
    def ex_Call(self, e: n.Call) -> str:
        if id(e) in self.facts.ref_calls:
            return self.reference_code(e.args[0].value)
        if id(e) in self.facts.type_queries:
            return self.type_query_code(e)
        if self.facts.intrinsics and id(e) in self.facts.intrinsics:
            what, key = self.facts.intrinsics[id(e)]
            if what == "valid":
                return f"({self.expr(e.args[0].value)} is not None)"
            return f"_query_itf({self.expr(e.args[0].value)}, {key!r}, {self.ref_code(e.args[1].value)})"
        return self.function_call(e, self.facts.calls[id(e)])

    def arg_code(self, var: Variable, value: n.Expr) -> str:
        """Code for one argument bound to parameter `var` (by value, or a reference for in-outs)."""
        if id(value) in self.facts.array_from_element:
            assert isinstance(value, n.Index)
            base_code = self.expr(value.base)
            base_type = self.facts.types[id(value.base)]
            assert isinstance(base_type, t.ArrayType)
            if base_type.dims is None:
                return f"_ArrayRef({base_code}.data, {base_code}.start + {self.expr(value.indices[0])})"
            lo, hi = base_type.dims[0]
            ix = self.expr(value.indices[0])
            return f"_ArrayRef({base_code}, ({ix}) - {lo} if {lo} <= {ix} <= {hi} else _oob({ix}, {lo}, {hi}))"
        ptype = var.type
        vtype = self.facts.types.get(id(value))
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
        code = self.expr_as(value, ptype)
        if isinstance(ptype, (t.StructType, t.ArrayType)):
            return f"_copy_value({code})"
        return code

    def ref_code(self, value: n.Expr) -> str:
        if isinstance(value, n.Name):
            ref = self.facts.names[id(value)]
            var = ref.variable
            assert var is not None
            if var.section == IN_OUT and ref.kind != "global":
                return f"{'self' if ref.kind == 'field' else self.owner}.{var_attr(var.name)}"
            place = self.name_place(ref)
            if id(value) in self.facts.auto_deref:
                return place   # a REFERENCE TO variable passed on: its reference object
            obj, attr = place.rsplit(".", 1)
            return f"_AttrRef({obj}, {attr!r})"
        if isinstance(value, n.Deref):
            return self.expr(value.base)
        if isinstance(value, n.Member):
            base_type = self.facts.types[id(value.base)]
            return f"_AttrRef({self.expr(value.base)}, {var_attr(self.member_name(base_type, value.name))!r})"
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
            target_type = self.facts.types.get(id(target))
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

    def fb_call(self, e: n.Call, info: CallInfo) -> None:
        assert info.instance is not None
        inst = self.expr(info.instance)
        if not inst.replace(".", "").replace("_", "").isalnum():
            tmp = self.new_tmp("fb")
            self.w.line(f"{tmp} = {inst}")
            inst = tmp
        for var, value in info.inputs:
            attr = var_attr(var.name)
            code = self.arg_code(var, value)
            if var.section != IN_OUT and isinstance(var.type, t.StructType):
                self.w.line(f"{inst}.{attr}._assign({self.expr(value)})")
            elif var.section != IN_OUT and isinstance(var.type, t.ArrayType) and var.type.dims is not None:
                self.w.line(f"_assign_array({inst}.{attr}, {self.expr(value)})")
            else:
                self.w.line(f"{inst}.{attr} = {code}")
        self.w.line(f"{inst}()")
        for var, target, negate in info.outputs:
            target_type = self.facts.types.get(id(target))
            value = f"{inst}.{var_attr(var.name)}"
            if negate:
                value = f"(not {value})"
            elif target_type is not None:
                value = self.coerce(value, var.type, target_type, target.span)
            self.store(target, value, target_type)


_CACHE_MIN_USES = 3          # uses of a variable in a body (a use inside a loop counts as many)
def lower_project(analysis: Analysis, settings) -> LoweredProject:
    """Generate the Python module for a checked project."""
    return Lowerer(analysis, settings).lower()
