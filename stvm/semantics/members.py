"""Pass 4 of the checker, the body checks (docs/architecture.md, "Checker passes"), one part. Names
and members: variables, enumerators, FB members, properties, METHOD calls, access rules. Made by
`body.BodyChecker`, one per checked body; the other parts, the walk's state and the hooks the
debugger overrides are reached through `self.bc` (bodypart.py).
"""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics.facts import CallInfo, NameRef
from stvm.semantics.model import EXTERNAL, INPUT, OUTPUT, POUInfo, Variable
from stvm.syntax import nodes as n
from stvm.dialects import allows
from stvm.semantics.typing_rules import with_access
from stvm.semantics.bodypart import BodyPart


class MemberChecker(BodyPart):
    """Names and members: variables, enumerators, FB members, properties, METHOD calls, access rules."""

    def resolve_name(self, name: n.Name) -> object:
        """Resolve a Name: a NameRef for variables/enumerators/result, or None (diagnosed)."""
        if len(name.parts) == 1 and not name.rooted:
            key = name.parts[0].lower()
            if self.c.any_static:
                static = self.static_variable(key)
                if static is not None:
                    return NameRef("global", static)
            var = self.pou.variables.get(key)
            if var is not None:
                if var.section == "VAR_INST" and self.fb is not None and key in self.pou.inst_vars:
                    return NameRef("field", self.fb.variables[self.pou.inst_vars[key]])
                if var.section == EXTERNAL:
                    g = self.c.globals.get(key)
                    return NameRef("global", g) if g is not None else None
                return NameRef("var", var)
            if key == self.pou.name.lower() and self.pou.kind in ("FUNCTION", "METHOD") \
                    and self.pou.return_type is not None:
                return NameRef("result", pou=self.pou)
            if self.fb is not None and self.fb is not self.pou:
                var = self.fb.variables.get(key)   # a method sees its instance's variables
                if var is not None:
                    if var.section == EXTERNAL:
                        g = self.c.globals.get(key)
                        return NameRef("global", g) if g is not None else None
                    return NameRef("field", var)
            if self.fb is not None:
                prop = self.c.oo.find_property(self.fb.key, key)
                if prop is not None:
                    return NameRef("prop", pou=prop.getter, value=prop)
            g = self.c.globals.get(key)
            if g is not None:
                return NameRef("global", g)
            enum = self.c.constants.bare_enumerator(name.parts[0], name.span)
            if enum is not None:
                return NameRef("enum", value=enum[1], pou=None, variable=Variable(name.parts[0], "ENUM", enum[0]))
        return None

    def static_variable(self, key: str) -> Variable | None:
        """The hidden global of VAR_STAT `key`: this POU's, else (unless a variable of this POU
        has the name) its FB's or a base's (checker.hoist_static_variables)."""
        hidden = self.pou.stat_vars.get(key)
        if hidden is None and key not in self.pou.variables:
            fb = self.fb
            while hidden is None and fb is not None and key not in fb.variables:
                hidden = fb.stat_vars.get(key)
                fb = self.c.pous.get(fb.base) if fb.base else None
        return self.c.globals.get(hidden) if hidden else None

    def lookup_callable(self, name: n.Name) -> POUInfo | None:
        key = self.c.index.lookup_pou_key(name.parts, self.pou_namespace)
        if key is None:
            return None
        return self.c.pous.get(key)

    def undeclared(self, name: n.Name) -> None:
        if self.lookup_callable(name) is not None:
            self.error(f"'{name.text}' is a POU, not a variable", name.span, "E031")
        else:
            self.error(f"'{name.text}' is not declared", name.span, "E031")

    def expr_Member(self, e: n.Member, expected) -> t.Type | None:
        known, self.bc.member_base = self.bc.member_base, None
        base = known[1] if known is not None and known[0] is e.base else self.bc.expr(e.base)
        if base is None:
            return None
        if isinstance(base, t.StructType):
            fty = base.field_type(e.name)
            if fty is None:
                self.error(f"{base.name} has no member '{e.name}'", e.span, "E034")
            return fty
        if isinstance(base, (t.FBType, t.InterfaceType)):
            prop = self.c.oo.find_property(base.qualname.lower(), e.name)
            if prop is not None:
                return self.property_load(e, prop, self.member_how(e.base, base))
        if isinstance(base, t.InterfaceType):
            what = "method" if self.c.oo.find_method(base.qualname.lower(), e.name) else "member"
            self.error(f"interface {base.name} has no property '{e.name}'" if what == "member" else
                       f"'{e.name}' is a method of interface {base.name}; call it: {e.name}(…)", e.span, "E034")
            return None
        if isinstance(base, t.FBType):
            fb = self.c.pous.get(base.qualname.lower())
            var = fb.pin(e.name) if fb else None
            if var is None:
                if fb is not None and self.c.oo.find_method(fb.key, e.name) is not None:
                    self.error(f"'{e.name}' is a method of {base.name}; call it: {e.name}(…)", e.span, "E034")
                    return None
                self.error(f"function block {base.name} has no member '{e.name}'", e.span, "E034")
                return None
            if self.inside_own(e.base, base):
                return var.type
            return var.type if self.bc.member_visible(base, var, e) else None
        self.error(f"'{self.bc.exprs.describe(e.base)}' is {base.name}, which has no members", e.span, "E034")
        return None

    def member_visible(self, base: t.FBType, var: Variable, e: n.Member) -> bool:
        """IEC: outside an FB only its inputs and outputs are visible (the debugger sees all)."""
        if var.section not in (INPUT, OUTPUT) and not base.is_program and not \
                allows(self.settings.dialect, "fb_internal_read"):
            self.error(f"'{e.name}' is internal to {base.name}; only inputs and outputs are visible outside", e.span, "E034")
            return False
        return True

    def through_property(self, base: n.Expr) -> bool:
        """`fb.P.x := …` / `fb.P[i] := …`: the GET returns a copy, so the write would be lost."""
        while isinstance(base, (n.Member, n.Index)):
            if self.facts.props and base.nid in self.facts.props:
                name = self.facts.props[base.nid][0].name
                self.error(f"cannot assign into property '{name}': its GET returns a copy; assign the whole "
                           f"property", base.span, "E073")
                return True
            base = base.base
        if isinstance(base, n.Name) and self.facts.props and base.nid in self.facts.props:
            self.error(f"cannot assign into property '{base.parts[0]}': its GET returns a copy; assign the whole "
                       f"property", base.span, "E073")
            return True
        return False

    def is_property(self, e: n.Expr, what: str) -> bool:
        """A property where a variable is needed (FOR, `=>`, an in-out, REF()): an error, since
        it has no storage of its own (its GET and SET are calls)."""
        if self.facts.props and e.nid in self.facts.props:
            self.error(f"{what} needs a variable; property '{self.facts.props[e.nid][0].name}' is a pair of "
                       f"GET/SET calls (use a variable and assign the property)", e.span, "E073")
            return True
        return False

    def this_or_super(self, e: n.Name) -> t.Type | None:
        """THIS (a POINTER TO the instance) and SUPER (to its base part), inside an FB or method."""
        word = e.parts[0].upper()
        if self.fb is None or self.fb.kind not in ("FUNCTION_BLOCK", "PROGRAM"):
            self.error(f"{word} is only meaningful inside a function block or its methods", e.span, "E070")
            return None
        key = self.fb.key
        if word == "SUPER":
            if self.fb.base is None:
                self.error(f"SUPER: {self.fb.name} does not EXTEND a function block", e.span, "E070")
                return None
            key = self.fb.base
        info = self.c.pous[key]
        self.facts.names[e.nid] = NameRef(word.lower(), pou=info)  # type: ignore[assignment]
        return t.ref_type(t.FBType(info.name, info.qualname, info.kind == "PROGRAM"), "POINTER")

    def inside_own(self, base: n.Expr, base_type: t.FBType) -> bool:
        """Is `base` THIS^ / SUPER^, or an instance of the FB being checked (whose internals its
        own body and methods may see)?"""
        if isinstance(base, n.Deref) and isinstance(base.base, n.Name) and base.base.parts[0].upper() in ("THIS", "SUPER") \
                and getattr(self.facts.names.get(base.base.nid), "kind", None) in ("this", "super"):
            return True
        return False

    def member_how(self, base: n.Expr, base_type: t.Type) -> str:
        if isinstance(base_type, t.InterfaceType):
            return "itf"
        if isinstance(base, n.Deref) and isinstance(base.base, n.Name) \
                and getattr(self.facts.names.get(base.base.nid), "kind", None) == "super":
            return "super"
        return "inst"

    def check_access(self, member: POUInfo, what: str, span: n.Span) -> bool:
        """PRIVATE: only the declaring FB; PROTECTED: it and derived FBs; INTERNAL: its namespace."""
        access = member.access
        if access == "PUBLIC":
            return True
        owner = self.c.pous.get(member.owner)
        here = self.fb.key if self.fb is not None else None
        ok = True
        if access == "PRIVATE":
            ok = here == member.owner
        elif access == "PROTECTED":
            ok = here is not None and self.c.oo.is_derived(here, member.owner)
        elif access == "INTERNAL":
            ok = owner is None or self.c.index.pou_nodes[member.owner].namespace == self.pou_namespace
        if not ok:
            where = {"PRIVATE": f"only {owner.name if owner else '?'} itself",
                     "PROTECTED": f"only {owner.name if owner else '?'} and the function blocks extending it",
                     "INTERNAL": "only its own namespace"}[access]
            self.error(f"{what} '{member.name}' of {owner.name if owner else '?'} is {access}: {where} may use it",
                       span, "E071")
        return ok

    def property_load(self, e: n.Expr, prop, how: str) -> t.Type | None:
        if prop.getter is None:
            self.error(f"property '{prop.name}' has no GET; it can only be written", e.span, "E072")
            return None
        self.check_access(prop.getter if prop.access == "PUBLIC" else with_access(prop.getter, prop.access),
                          "property", e.span)
        self.facts.props[e.nid] = (prop, how)
        return prop.type

    def property_store(self, target: n.Expr, prop, how: str) -> t.Type | None:
        if prop.setter is None:
            self.error(f"property '{prop.name}' has no SET; it can only be read", target.span, "E072")
            return None
        self.check_access(prop.setter if prop.access == "PUBLIC" else with_access(prop.setter, prop.access),
                          "property", target.span)
        self.facts.props[target.nid] = (prop, how)
        self.facts.types[target.nid] = prop.type
        return prop.type

    def method_call(self, e: n.Call, method: POUInfo, oo: str, instance: n.Expr | None, static_owner: str,
                    expected) -> t.Type | None:
        self.check_access(method, "method", e.callee.span)
        if oo == "super" and method.abstract:
            self.error(f"SUPER^.{method.name}: the method is ABSTRACT in {self.c.pous[method.owner].name}",
                       e.callee.span, "E070")
        info = CallInfo(method, False, instance, oo=oo, static_owner=static_owner)
        outer, self.bc.call_expected = getattr(self.bc, "call_expected", None), expected
        try:
            self.bc.calls.bind_args(e, method, info, fb=False)
        finally:
            self.bc.call_expected = outer
        self.facts.calls[e.nid] = info
        return method.return_type or t.VOID

    def oo_call(self, e: n.Call, expected, statement: bool) -> tuple[bool, t.Type | None]:
        """A METHOD call or SUPER^(): (True, result type) when `e` is one; (False, None) if not."""
        callee = e.callee
        if isinstance(callee, n.Name):
            if len(callee.parts) == 1 and not callee.rooted and self.fb is not None:
                method = self.c.oo.find_method(self.fb.key, callee.parts[0])
                if method is not None and self.bc.resolve_name(callee) is None:
                    return True, self.method_call(e, method, "self", None, "", expected)
            return False, None
        if isinstance(callee, n.Deref) and isinstance(callee.base, n.Name) and callee.base.parts[0].upper() == "SUPER" \
                and self.bc.resolve_name(callee.base) is None:
            ty = self.bc.expr(callee)
            if ty is None:
                self.bc.calls.check_args_loosely(e)
                return True, None
            if e.args:
                self.error("SUPER^() calls the base body; it takes no arguments", e.span, "E047")
            if not statement:
                self.error("SUPER^() is a statement", e.span, "E045")
            base = self.c.pous[self.fb.base]  # type: ignore[union-attr,index]
            self.facts.calls[e.nid] = CallInfo(base, True, None, oo="super_body", static_owner=base.key)
            return True, t.VOID
        if not isinstance(callee, n.Member):
            return False, None
        base_type = self.bc.expr(callee.base)
        if base_type is None:
            self.bc.calls.check_args_loosely(e)
            return True, None
        if isinstance(base_type, t.InterfaceType):
            method = self.c.oo.find_method(base_type.qualname.lower(), callee.name)
            if method is None:
                self.error(f"interface {base_type.name} has no method '{callee.name}'", callee.span, "E045")
                self.bc.calls.check_args_loosely(e)
                return True, None
            return True, self.method_call(e, method, "itf", callee.base, "", expected)
        if isinstance(base_type, t.FBType):
            method = self.c.oo.find_method(base_type.qualname.lower(), callee.name)
            if method is None:
                fb = self.c.pous.get(base_type.qualname.lower())
                if fb is not None and fb.pin(callee.name) is None and (fb.methods or fb.base or fb.properties):
                    self.error(f"function block {base_type.name} has no method '{callee.name}'", callee.span, "E045")
                    self.bc.calls.check_args_loosely(e)
                    return True, None
                self.bc.member_base = (callee.base, base_type)   # expr_Call types the callee next
                return False, None
            how = self.member_how(callee.base, base_type)
            if how == "super":
                return True, self.method_call(e, method, "super", None, self.fb.base or "", expected)  # type: ignore[union-attr]
            if isinstance(callee.base, n.Deref) and self.inside_own(callee.base, base_type):
                return True, self.method_call(e, method, "self", None, "", expected)
            return True, self.method_call(e, method, "inst", callee.base, "", expected)
        self.bc.member_base = (callee.base, base_type)
        return False, None
