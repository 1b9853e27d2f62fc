"""Generators for whole units: STRUCT, FUNCTION_BLOCK/PROGRAM and GVL classes, FUNCTIONs,
METHODs and property accessors, initial values, and the local-variable cache of a call body.

A mixin of `Lowerer` (`stvm/lower/codegen.py`): it writes through `self.w` and reads the checked
facts of `self.facts` and the analysis pass's plan of each body (`self.plan`, stvm/lower/analysis.py:
which variables are cached, whether a METHOD runs frameless); statements and expressions come from
the sibling generators."""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics.model import (EXTERNAL, IN_OUT, INPUT, OUTPUT, TEMP, AddressInit, POUInfo, SiblingInstance,
                                  Variable)
from stvm.dialects import allows
from stvm.lower.names import method_attr, var_attr
from stvm.lower.pycode import CodeWriter, py_literal
from stvm.syntax import nodes as n
from stvm.settings import EnumDefault


class PouGenerator:
    """Units: classes for STRUCTs, FBs/PROGRAMs and globals, functions for FUNCTIONs and
    METHODs, their initial values and call bodies."""

    def enum_default(self, ty: t.EnumType) -> int:
        if ty.default is not None:
            return ty.default
        if self.settings.enum_default is EnumDefault.ZERO or not ty.members:
            return 0
        return ty.members[0][1]

    def default_expr(self, ty: t.Type, init: object = None, fb_args: dict | None = None) -> str:
        if isinstance(init, SiblingInstance):   # `itf := fbOther` in an FB's declaration
            return f"self.{var_attr(init.name)}"
        if isinstance(init, AddressInit):       # `r : REF_TO INT := REF(x)`
            return self.address_init_code(init)
        if isinstance(ty, t.BoolType):
            return py_literal(bool(init) if init is not None else False)
        if isinstance(ty, t.IntType):
            return py_literal(init if init is not None else 0)
        if isinstance(ty, t.RealType):
            return py_literal(float(init) if init is not None else 0.0)
        if isinstance(ty, t.TimeType):
            return py_literal(init if init is not None else 0)
        if isinstance(ty, t.StringType):
            return py_literal(init if init is not None else "" if t.is_wide(ty) else b"")
        if isinstance(ty, t.EnumType):
            return py_literal(init if init is not None else self.enum_default(ty))
        if isinstance(ty, t.StructType):
            cls = self.classes[ty.qualname.lower()]
            if isinstance(init, dict) and init:
                parts = ", ".join(f"{var_attr(ty.field_name(k) or k)}={self.default_expr(ty.field_type(k), v)}"  # type: ignore[arg-type]
                                  for k, v in init.items() if ty.field_type(k) is not None)
                return f"_with({cls}(), {parts})"
            return f"{cls}()"
        if isinstance(ty, t.FBType):
            if isinstance(init, dict) and init:   # `fb : F := (x := 1)` (checker.fb_instance_init)
                made = self.fb_instance_expr(ty, init)
            else:
                made = f"{self.classes[ty.qualname.lower()]}()"
            return self.with_fb_init(ty, made, fb_args)
        if isinstance(ty, t.ArrayType):
            if ty.dims is None:
                return "None"
            values = init if isinstance(init, list) else []
            return self.array_expr(ty, list(ty.dims), values)
        return "None"

    @staticmethod
    def address_init_code(init: AddressInit) -> str:
        """The reference an AddressInit binds: the instance's (`self`) or a global's (`_G`)
        variable, its members and elements; a scalar's through an _AttrRef/_ItemRef, an
        aggregate as the object itself (RefType). Names go through var_attr, offsets through
        int(): no ST text becomes code."""
        code = "_G" if init.scope == "global" else "self"
        steps = list(init.steps)
        last = None if init.aggregate else steps.pop()
        for kind, value in steps:
            code += f".{var_attr(str(value))}" if kind == "field" else f"[{int(value)}]"  # type: ignore[call-overload]
        if last is None:
            return code
        kind, value = last
        if kind == "field":
            return f"_AttrRef({code}, {var_attr(str(value))!r})"
        return f"_ItemRef({code}, {int(value)})"  # type: ignore[call-overload]

    def with_fb_init(self, ty: t.FBType, made: str, fb_args: dict | None = None) -> str:
        """CODESYS FB_init: the instance `made` queued for its FB_init methods (the base's first,
        TwinCAT/CODESYS order), which the VM runs once every instance exists, the inner ones
        first (runtime/vm.py `run_fb_inits`); the bare expression when no FB_init is declared.
        `fb_args` ({input key: constant}, `fb : F(1, 2)`) go to every FB_init with that input."""
        fb_args = fb_args or {}
        chain, after_init = [], {}
        pou = self.model.pous.get(ty.qualname.lower())
        while pou is not None:
            method = pou.methods.get("fb_init")
            if method is not None:
                chain.append((self.classes[pou.key], method))
            # {attribute 'call_after_init'} (on the method anywhere in the chain): called once,
            # through the instance's own class, so an override runs; a base's first
            after_init.update({k: m for k, m in pou.methods.items() if m.call_after_init})
            pou = self.model.pous.get(pou.base) if pou.base else None
        if not chain and not after_init:
            return made
        calls = []
        for cls, method in reversed(chain):
            args = ["True" if v.key == "binitretains" else "False" if v.key == "bincopycode"
                    else self.default_expr(v.type, fb_args[v.key] if v.key in fb_args else v.init)
                    for v in method.params()]
            calls.append(f"({cls}.{method_attr(method.name)}, ({''.join(a + ', ' for a in args)}))")
        own_class = self.classes[ty.qualname.lower()]
        for method in reversed(list(after_init.values())):   # after every FB_init
            calls.append(f"({own_class}.{method_attr(method.name)}, ())")
        return f"_fb_init_later(_fb_pending, {made}, ({''.join(c + ', ' for c in calls)}))"

    def fb_instance_expr(self, ty: t.FBType, init: dict) -> str:
        variables = self.model.pous[ty.qualname.lower()].variables
        parts = ", ".join(f"{var_attr(variables[k].name)}={self.default_expr(variables[k].type, v)}"
                          for k, v in init.items() if k in variables)
        return f"_with({self.classes[ty.qualname.lower()]}(), {parts})"

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
        return self.default_expr(var.type, var.init, var.fb_args)

    def every_initial_value(self):
        """The initial values of the globals, of every POU's variables and of STRUCT fields."""
        yield from (v.init for v in self.model.globals.values())
        for pou in self.model.pous.values():
            yield from (v.init for v in pou.variables.values())
        for inits in self.a.type_inits.values():
            yield from inits.values()

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

    def union_class(self, key: str, st: t.UnionType) -> None:
        """A UNION: a subclass of the runtime's `_Union` (the union's bytes and one value per
        member, `stvm.runtime.unions`) with a descriptor per member, so member access in the
        generated code is the same attribute access as a struct's."""
        w = self.w
        w.blank_span()
        cls = self.classes[key]
        w.line(f"class {cls}(_Union):")
        w.indent += 1
        w.line("__slots__ = ()")
        w.line(f"_size, _codecs, _aggregate = _union_codecs({self.type_const(st)}{self.short_arg()})")
        for index, (name, _) in enumerate(st.fields):
            w.line(f"{var_attr(name)} = _UnionMember({index})")
        w.line("def __init__(self):")
        w.indent += 1
        defaults = ", ".join(self.default_expr(fty) for _, fty in st.fields)
        w.line(f"_Union.__init__(self, [{defaults}])")
        w.indent -= 2

    def struct_assign_body(self, dst: str, src: str, st: t.StructType, depth: int) -> None:
        """Field by field, nested STRUCT fields inline (one Python call per struct assignment,
        not one per nested struct: the thesis copies `_sSOCKET` into every socket FB call)."""
        for name, fty in st.fields:
            attr = var_attr(name)
            if isinstance(fty, t.StructType) and fty.fields and self.options.inline_struct_assign \
                    and not isinstance(fty, t.UnionType):   # a union copies its bytes: `_assign`
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
        if any(isinstance(v, AddressInit) and v.scope == "global" for v in self.every_initial_value()):
            # a REF(global) initial value is bound while the globals are being made: `_G` is
            # this object from the start (the VM sets the same object once it is made)
            w.line("global _G")
            w.line("_G = self")
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
        if allows(self.settings.dialect, "fb_assign"):
            # `fb := other` and FB results (TwinCAT/CODESYS): the instance's variables copied; the
            # nested instances, STRUCTs and ARRAYs it owns copied deeply (stvm/runtime/helpers.py)
            owned = tuple(var_attr(v.name) for v in own if v.section != IN_OUT and t.is_aggregate(v.type))
            w.line(f"_owned = {owned!r}")
            w.line("def _copy(self): return _copy_fb(self)")
            w.line("def _assign(self, src): _assign_fb(self, src)")
        w.line("def __call__(self):")
        w.indent += 1
        self.pou = pou
        self.owner = "self"
        if pou.native:
            w.line("self._impl.call(self, _ctx)")
        else:
            assert node is not None
            cached = dict(self.plan.pous[pou.key].cached)
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
        assert node is not None   # a FUNCTION or METHOD without a result returns None
        plan = self.plan.pous[pou.key]
        if method and plan.frameless:
            # a METHOD none of whose variables is passed by reference keeps them all in Python
            # locals (the inputs are the arguments, the outputs are written back at the end): no
            # frame object
            every = dict(plan.cached)
            prologue = [f"{var_attr(v.name)} = {self.var_default(v)}" for v in pou.variables.values()
                        if v.section not in (INPUT, IN_OUT, "VAR_INST")]
            prologue.append(f"_r = {self.default_expr(pou.return_type)}" if pou.return_type is not None else "_r = None")
            prologue += ["_rb = _Box(_r)"] if self.result_boxed() else []
            epilogue = [f"if o_{var_attr(o.name)} is not None: o_{var_attr(o.name)}.set({var_attr(o.name)})"
                        for o in outputs]
            self.cached_body(pou, node, every, prologue, epilogue, frameless=True)
            w.blank_span()
            w.line("return _rb.value" if self.result_boxed() else "return _r")
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
        prologue += ["_rb = _Box(_r)"] if self.result_boxed() else []
        # VAR_OUTPUT of a function: written through the caller's references when it returns
        epilogue = [f"if o_{var_attr(o.name)} is not None: o_{var_attr(o.name)}.set(_f.{var_attr(o.name)})"
                    for o in outputs]
        self.cached_body(pou, node, dict(plan.cached), prologue, epilogue)
        w.blank_span()
        w.line("return _rb.value" if self.result_boxed() else "return _r")
        w.indent -= 1

    def cached_body(self, pou: POUInfo, node: n.POU, cached: dict[str, Variable], prologue_extra: list[str],
                    epilogue_extra: list[str], frameless: bool = False) -> None:
        """Emit the body of a call with `cached` (the plan's `cached`) in Python locals: prologue,
        try/body/finally write-back. `frameless`: every variable is a local already set by the
        prologue (nothing to load or write back)."""
        outer = self.w
        self.cached = cached
        self.used, self.assigned = set(), set()
        guarded = bool(epilogue_extra) if frameless else (bool(self.cached) or bool(epilogue_extra))
        body_writer = CodeWriter()
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

