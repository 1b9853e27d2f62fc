"""Generators for whole units: STRUCT, FUNCTION_BLOCK/PROGRAM and GVL classes, FUNCTIONs,
METHODs and property accessors, initial values, and the local-variable cache of a call body.

A mixin of `Lowerer` (`stvm/lower/codegen.py`): it writes through `self.w` and reads the checked
facts of `self.facts`; statements and expressions come from the sibling generators."""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics.model import EXTERNAL, GLOBAL, IN_OUT, INPUT, OUTPUT, TEMP, POUInfo, Variable
from stvm.lower.hot_uses import for_variables, hot_uses
from stvm.lower.names import method_attr, var_attr
from stvm.lower.pycode import CodeWriter, py_literal
from stvm.syntax import nodes as n
from stvm.syntax.walk import calls_in, name_uses
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

    def default_expr(self, ty: t.Type, init: object = None) -> str:
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
        w.line(f"_size, _codecs, _aggregate = _union_codecs({self.type_const(st)})")
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
        if method and self.options.frameless_methods:
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

    def cached_vars(self, pou: POUInfo, node: n.POU, min_uses: int = -1,
                    outputs_local: bool = False) -> dict[str, Variable]:
        """Variables a call may keep in Python locals (LOAD_FAST instead of attribute access).

        Safe for every variable of the POU's own instance/frame that is never passed by reference
        (as a scalar in-out argument): nothing else can observe it during the call. Aggregates
        (arrays, structs, FB instances) are never rebound, so a local alias is always safe; scalars
        are written back in a `finally`, so values survive RETURN and faults.
        """
        if not self.options.cache_locals:
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
        hot = self.hot_path_uses(node) if self.options.hot_path_cache and min_uses < 0 else None
        out = {}
        for var in pou.variables.values():
            if var.section in (EXTERNAL, GLOBAL, "VAR_INST") or var.key in referenced:
                continue
            if var.section == IN_OUT and not isinstance(var.type, (t.StructType, t.ArrayType, t.FBType)):
                continue  # a scalar in-out is a reference object; keep it on the instance
            if hot is not None and var.section != TEMP:
                if not self.hot_enough(var, hot):
                    continue
            # a local costs a load on entry (and a store on exit): worth it from a few uses on
            elif uses.get(var.key, 0) < (_CACHE_MIN_USES if min_uses < 0 else min_uses):
                continue
            out[var.key] = var
        return out

    def hot_path_uses(self, node: n.POU) -> tuple[dict[str, float], set[str]]:
        """`hot_uses` of a body (loops already weigh their uses) and its FOR variables."""
        return hot_uses(node.body), for_variables(node.body)

    def hot_enough(self, var: Variable, hot: tuple[dict[str, float], set[str]]) -> bool:
        """`hot_path_cache`: is a local worth its load on entry (and store on exit) on a typical
        call? Yes for a FOR variable (a range-FOR needs it in a local), or when the uses one call
        is expected to make (branches weighted, loops multiplied by `hot_uses`) reach the
        threshold; an aggregate is only aliased (no write-back), so it pays off sooner. A
        temporary keeps the plain rule: uncached, it is reset on the instance every call anyway."""
        counts, for_vars = hot
        if var.key in for_vars:
            return True
        aggregate = isinstance(var.type, (t.StructType, t.ArrayType, t.FBType))
        return counts.get(var.key, 0.0) >= (_HOT_MIN_USES_AGGREGATE if aggregate else _HOT_MIN_USES)

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


_CACHE_MIN_USES = 3          # uses of a variable in a body (a use inside a loop counts as many)
# `hot_path_cache`: expected uses per call (see stvm/lower/hot_uses.py) from which a local pays:
# a cached scalar costs ~6 bytecodes (load on entry, store back on exit) and saves ~1.5 per use
_HOT_MIN_USES = 3.0
_HOT_MIN_USES_AGGREGATE = 2.0
