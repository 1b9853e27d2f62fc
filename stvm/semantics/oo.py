"""Pass 3 of the checker, after the declarations: object orientation (docs/architecture.md,
"Checker passes").

`ClassHierarchy.link_oo` resolves EXTENDS and IMPLEMENTS over the declared POUs, inherits a base's
variables and checks the rules of methods, properties and interfaces (overrides, ABSTRACT, FINAL,
signatures). Its queries (`find_method`, `base_chain`, `is_derived`, …) serve the body checks.
"""

from __future__ import annotations


from stvm.semantics import types as t
from stvm.semantics.context import CheckContext, Pass
from stvm.semantics.model import (EXTERNAL, IN_OUT, INPUT, OUTPUT, POUInfo,
                                  PropertyInfo)
from stvm.syntax import nodes as n


class ClassHierarchy(Pass):
    """EXTENDS, IMPLEMENTS and the rules of methods and properties (module docstring)."""

    def __init__(self, ctx: CheckContext) -> None:
        super().__init__(ctx)

    def members_of(self, info: POUInfo) -> list[POUInfo]:
        """The METHODs and property accessors an FB, PROGRAM or INTERFACE declares itself."""
        out = list(info.methods.values())
        for prop in info.properties.values():
            out += [m for m in (prop.getter, prop.setter) if m is not None]
        return out

    def link_oo(self) -> None:
        """Resolve EXTENDS and IMPLEMENTS, report cycles, inherit the base's variables."""
        for key, pou in self.ctx.index.pou_nodes.items():
            info = self.ctx.pous[key]
            if pou.extends:
                if pou.kind == "INTERFACE":
                    info.interfaces = tuple(k for k in (self.interface_key(name, pou) for name in pou.extends) if k)
                elif pou.kind != "FUNCTION_BLOCK":
                    self.error(f"a {pou.kind} cannot EXTEND; only a FUNCTION_BLOCK or INTERFACE can",
                               pou.extends[0].span, "E064")
                elif len(pou.extends) > 1:
                    self.error("a function block EXTENDS one base function block", pou.extends[1].span, "E064")
                else:
                    base = pou.extends[0]
                    bkey = self.ctx.index.lookup_pou_key(base.parts, pou.namespace)
                    binfo = self.ctx.pous.get(bkey) if bkey else None
                    if binfo is None or binfo.kind != "FUNCTION_BLOCK" or binfo.native:
                        what = "unknown function block" if binfo is None else f"'{base.text}' is not a function block; cannot extend"
                        self.error(f"{what} '{base.text}'" if binfo is None else what, base.span, "E064")
                    elif binfo.final:
                        self.error(f"function block '{binfo.name}' is FINAL and cannot be extended", base.span, "E064")
                    else:
                        info.base = bkey
            if pou.implements:
                if pou.kind not in ("FUNCTION_BLOCK",):
                    self.error(f"a {pou.kind} cannot IMPLEMENT an interface", pou.implements[0].span, "E064")
                else:
                    info.interfaces = tuple(k for k in (self.interface_key(name, pou) for name in pou.implements) if k)
        # cycles: a chain of bases that comes back
        for key, info in self.ctx.pous.items():
            if info.kind == "FUNCTION_BLOCK" and info.base:
                chain, cur = [key], info.base
                while cur is not None and cur not in chain:
                    chain.append(cur)
                    cur = self.ctx.pous[cur].base
                if cur == key:
                    names = " -> ".join(self.ctx.pous[k].name for k in chain + [key])
                    self.error(f"cycle in EXTENDS: {names}", self.ctx.index.pou_nodes[key].extends[0].span, "E065")
                    info.base = None
            if info.kind == "INTERFACE" and info.interfaces:
                seen: set[str] = set()
                stack = list(info.interfaces)
                while stack:
                    cur = stack.pop()
                    if cur == key:
                        self.error(f"cycle in INTERFACE EXTENDS through {info.name}",
                                   self.ctx.index.pou_nodes[key].extends[0].span, "E065")
                        info.interfaces = ()
                        break
                    if cur not in seen:
                        seen.add(cur)
                        stack.extend(self.ctx.pous[cur].interfaces)
        merged: set[str] = set()

        def inherit(key: str) -> None:
            if key in merged:
                return
            merged.add(key)
            info = self.ctx.pous[key]
            if info.base is None:
                return
            inherit(info.base)
            base = self.ctx.pous[info.base]
            variables = dict(base.variables)
            for vkey, var in info.variables.items():
                if vkey in variables:
                    self.error(f"'{var.name}' is already declared in the base function block {base.name}",
                               var.span, "E010")
                    continue
                variables[vkey] = var
            info.inherited = len(base.variables)
            info.variables = variables

        for key, info in list(self.ctx.pous.items()):
            if info.kind == "FUNCTION_BLOCK":
                inherit(key)
        del inherit   # a closure calling itself is a cycle: it would keep the checker alive
        for key, info in self.ctx.pous.items():
            for method in info.methods.values():
                if method.name.lower() in info.variables and info.inherited:
                    self.error(f"'{method.name}' is a variable of the base function block; a method cannot "
                               f"have its name", method.span, "E010")
        self.check_oo_rules()

    def interface_key(self, name: n.Name, pou: n.POU) -> str | None:
        key = self.ctx.index.lookup_pou_key(name.parts, pou.namespace)
        if key is None or self.ctx.pous[key].kind != "INTERFACE":
            self.error(f"unknown interface '{name.text}'" if key is None else f"'{name.text}' is not an interface",
                       name.span, "E064")
            return None
        return key

    def base_chain(self, key: str) -> list[POUInfo]:
        """The FB and its bases, the FB first."""
        out = []
        cur: str | None = key
        while cur is not None and cur in self.ctx.pous and len(out) < 1000:
            out.append(self.ctx.pous[cur])
            cur = self.ctx.pous[cur].base
        return out

    def find_method(self, key: str, name: str) -> POUInfo | None:
        """The method `name` of FB/PROGRAM `key` (own or inherited) or of interface `key` (own or
        from the interfaces it extends)."""
        low = name.lower()
        info = self.ctx.pous.get(key)
        if info is None:
            return None
        if info.kind == "INTERFACE":
            for itf in self.interface_closure(key):
                m = self.ctx.pous[itf].methods.get(low)
                if m is not None:
                    return m
            return None
        for fb in self.base_chain(key):
            if low in fb.methods:
                return fb.methods[low]
        return None

    def find_property(self, key: str, name: str) -> PropertyInfo | None:
        low = name.lower()
        info = self.ctx.pous.get(key)
        if info is None:
            return None
        chain = [self.ctx.pous[k] for k in self.interface_closure(key)] if info.kind == "INTERFACE" else self.base_chain(key)
        for fb in chain:
            if low in fb.properties:
                return fb.properties[low]
        return None

    def interface_closure(self, key: str) -> list[str]:
        """An interface and every interface it extends, itself first."""
        out, stack = [], [key]
        while stack:
            cur = stack.pop(0)
            if cur not in out and cur in self.ctx.pous:
                out.append(cur)
                stack.extend(self.ctx.pous[cur].interfaces)
        return out

    def implemented_interfaces(self, key: str) -> set[str]:
        """Every interface an FB implements (itself or through its bases), with what they extend."""
        out: set[str] = set()
        for fb in self.base_chain(key):
            for itf in fb.interfaces:
                out.update(self.interface_closure(itf))
        return out

    def is_derived(self, key: str, base: str) -> bool:
        return any(fb.key == base for fb in self.base_chain(key))

    def check_oo_rules(self) -> None:
        """Overrides match, FINAL is not overridden, a concrete FB implements every ABSTRACT and
        interface method and property (IEC ed. 3 6.6.5.5-6.6.6)."""
        for key, info in self.ctx.pous.items():
            if info.kind != "FUNCTION_BLOCK":
                continue
            node = self.ctx.index.pou_nodes[key]
            bases = self.base_chain(key)[1:]
            for method in info.methods.values():
                for base in bases:
                    over = base.methods.get(method.name.lower())
                    if over is None:
                        continue
                    if over.final:
                        self.error(f"method '{method.name}' is FINAL in {base.name} and cannot be overridden",
                                   self.ctx.method_nodes[method.key].name_span, "E066")
                    elif over.access == "PRIVATE":
                        pass
                    else:
                        self.same_signature(method, over, f"{base.name}.{over.name}", "overrides")
                    break
            for prop in info.properties.values():
                for base in bases:
                    over = base.properties.get(prop.key)
                    if over is not None:
                        if over.type != prop.type:
                            self.error(f"property '{prop.name}' is {prop.type.name} but overrides "
                                       f"{base.name}.{over.name} of type {over.type.name}", prop.span, "E067")
                        break
            if info.abstract:
                continue
            # every method must have an implementation
            span = node.name_span if node.name_span.line else node.span
            reported: set[str] = set()
            for fb in reversed(self.base_chain(key)):
                for method in fb.methods.values():
                    impl = self.find_method(key, method.name)
                    if impl is not None and impl.abstract and method.name.lower() not in reported:
                        reported.add(method.name.lower())
                        if impl.owner == key:
                            self.error(f"ABSTRACT method '{impl.name}' needs an ABSTRACT function block; "
                                       f"declare FUNCTION_BLOCK ABSTRACT {info.name}",
                                       self.ctx.method_nodes[impl.key].name_span, "E068")
                            continue
                        self.error(f"function block '{info.name}' must implement the ABSTRACT method "
                                   f"'{method.name}' of {self.ctx.pous[impl.owner].name} (or be ABSTRACT)", span, "E068")
            for itf in sorted(self.implemented_interfaces(key)):
                iinfo = self.ctx.pous[itf]
                for method in iinfo.methods.values():
                    impl = self.find_method(key, method.name)
                    if impl is None:
                        self.error(f"function block '{info.name}' does not implement method '{method.name}' "
                                   f"of interface {iinfo.name}", span, "E068")
                    else:
                        if impl.access != "PUBLIC":
                            self.error(f"method '{impl.name}' implements interface {iinfo.name} and must be PUBLIC",
                                       self.ctx.method_nodes[impl.key].name_span, "E067")
                        self.same_signature(impl, method, f"{iinfo.name}.{method.name}", "implements")
                for prop in iinfo.properties.values():
                    impl_p = self.find_property(key, prop.name)
                    if impl_p is None:
                        self.error(f"function block '{info.name}' does not implement property '{prop.name}' "
                                   f"of interface {iinfo.name}", span, "E068")
                    elif impl_p.type != prop.type:
                        self.error(f"property '{impl_p.name}' is {impl_p.type.name}; interface {iinfo.name} "
                                   f"declares it {prop.type.name}", impl_p.span, "E067")
                    else:
                        for kind, want, have in (("GET", prop.getter, impl_p.getter), ("SET", prop.setter, impl_p.setter)):
                            if want is not None and have is None:
                                self.error(f"property '{impl_p.name}' needs a {kind} (interface {iinfo.name} "
                                           f"declares one)", impl_p.span, "E068")
        # an ABSTRACT function block has no instances (only references and interfaces to derived ones)
        seen_vars: set[int] = set()   # Variable objects (shared by a holder and its members), not nodes
        for key, info in self.ctx.pous.items():
            for holder in [info] + self.members_of(info):
                for var in holder.variables.values():
                    if id(var) in seen_vars:   # not a node
                        continue
                    seen_vars.add(id(var))   # not a node
                    ty = var.type
                    while isinstance(ty, t.ArrayType):
                        ty = ty.element
                    if isinstance(ty, t.FBType) and var.section not in (IN_OUT, EXTERNAL):
                        target = self.ctx.pous.get(ty.qualname.lower())
                        if target is not None and target.abstract:
                            self.error(f"cannot instantiate ABSTRACT function block '{target.name}' "
                                       f"('{var.name}'); declare an instance of a derived one", var.span, "E069")
        # an interface method redeclared in an extending interface must keep its signature
        for key, info in self.ctx.pous.items():
            if info.kind == "INTERFACE":
                for method in info.methods.values():
                    for other in self.interface_closure(key)[1:]:
                        over = self.ctx.pous[other].methods.get(method.name.lower())
                        if over is not None:
                            self.same_signature(method, over, f"{self.ctx.pous[other].name}.{over.name}", "redeclares")

    def same_signature(self, method: POUInfo, other: POUInfo, what: str, verb: str) -> None:
        """Report where `method` differs from `other` (return type, parameters in order)."""
        span = self.ctx.method_nodes[method.key].name_span if method.key in self.ctx.method_nodes else method.span

        def params(m: POUInfo) -> list[tuple[str, str, t.Type]]:
            return [(v.key, v.section, v.type) for v in m.variables.values() if v.section in (INPUT, OUTPUT, IN_OUT)]
        mine, theirs = params(method), params(other)
        if (method.return_type or t.VOID) != (other.return_type or t.VOID):
            have = method.return_type.name if method.return_type else "no result"
            want = other.return_type.name if other.return_type else "no result"
            self.error(f"method '{method.name}' returns {have} but {verb} {what}, which returns {want}", span, "E067")
            return
        if mine != theirs:
            def show(ps):
                return ", ".join(f"{sec.replace('VAR_', '')} {[v.name for v in (method.variables | other.variables).values() if v.key == k][0]} : {ty.name}"
                                 for k, sec, ty in ps) or "no parameters"
            self.error(f"signature of method '{method.name}' ({show(mine)}) does not match {what} "
                       f"({show(theirs)}), which it {verb}", span, "E067")
