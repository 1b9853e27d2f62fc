"""Pass 4 of the checker, the body checks (docs/architecture.md, "Checker passes"), one part.
ADR/REF/SIZEOF/LOWER_BOUND/__QUERYINTERFACE…: calls the checker answers from operand types. Made by
`body.BodyChecker`, one per checked body; the other parts, the walk's state and the hooks the
debugger overrides are reached through `self.bc` (bodypart.py).
"""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.syntax import nodes as n
from stvm.dialects import allows
from stvm.semantics.typing_rules import int_literal_type, RESULT_KEY
from stvm.semantics.bodypart import BodyPart


class IntrinsicCalls(BodyPart):
    """ADR/REF/SIZEOF/LOWER_BOUND/__QUERYINTERFACE…: calls the checker answers from operand types."""

    def intrinsic(self, e: n.Call, word: str) -> t.Type | None:
        """__QUERYINTERFACE(itf, itf2) (CODESYS): itf2 := the instance itf holds when its FB
        implements itf2's interface, else 0; TRUE when it does. __ISVALIDREF(x): x is not NULL."""
        args = [a for a in e.args if a.kind == "positional"]
        want = 2 if word == "__QUERYINTERFACE" else 1
        if len(args) != want or len(e.args) != want:
            self.bc.calls.check_args_loosely(e)
            self.error(f"{word} takes {want} positional argument(s)", e.span, "E048")
            return None
        ty = self.bc.expr(args[0].value)
        if ty is None:
            return None
        if word == "__ISVALIDREF":
            if not isinstance(ty, (t.InterfaceType, t.RefType)) and args[0].value.nid not in self.facts.auto_deref:
                self.error(f"__ISVALIDREF needs an interface or a reference, not {ty.name}", args[0].value.span, "E052")
                return None
            self.facts.intrinsics[e.nid] = ("valid", None)
            return t.BOOL
        if not isinstance(ty, (t.InterfaceType, t.FBType)):
            self.error(f"__QUERYINTERFACE needs an interface or an FB instance, not {ty.name}", args[0].value.span, "E052")
            return None
        target = args[1].value
        tty = self.bc.lvalue(target) if self.bc.calls.is_lvalue_shape(target) else None
        if not isinstance(tty, t.InterfaceType):
            if tty is not None or not self.bc.calls.is_lvalue_shape(target):
                self.error("the second argument of __QUERYINTERFACE must be an interface variable", target.span, "E052")
            return None
        root = target
        while isinstance(root, (n.Member, n.Index)):
            root = root.base
        ref = self.facts.names.get(root.nid) if isinstance(root, n.Name) else None
        if ref is not None and ref.kind in ("var", "field"):  # type: ignore[attr-defined]
            owner = self.pou.key if ref.kind == "var" else self.fb.key  # type: ignore[attr-defined,union-attr]
            self.facts.addressed.add((owner, ref.variable.key))  # type: ignore[attr-defined]
        self.facts.intrinsics[e.nid] = ("query", tty.qualname.lower())
        return t.BOOL

    def reference_of(self, e: n.Call) -> t.Type | None:
        """REF(x) (IEC) / ADR(x) (CODESYS): a reference to the variable x, never to a value."""
        word = e.callee.parts[0].upper()  # type: ignore[attr-defined]
        if len(e.args) != 1 or e.args[0].kind != "positional":
            self.bc.calls.check_args_loosely(e)
            self.error(f"{word}() takes one variable", e.span, "E055")
            return None
        arg = e.args[0].value
        ty = self.bc.expr(arg)
        if ty is None or self.bc.members.is_property(arg, f"{word}()"):
            return None
        if not isinstance(arg, (n.Name, n.Member, n.Index, n.Deref)):
            what = "a single bit, which has no reference" if isinstance(arg, n.BitAccess) else "a temporary value"
            shown = self.bc.exprs.describe(arg)
            shown = "this expression" if shown == "expression" else f"'{shown}'"
            self.error(f"{word}() needs a variable; {shown} is {what}", arg.span, "E055")
            return None
        root = self.bc.stmts.mark_members_addressed(arg)
        if isinstance(root, n.Name):
            ref = self.facts.names.get(root.nid)
            kind = getattr(ref, "kind", None)
            if kind == "result" and word == "ADR" and allows(self.settings.dialect, "pointer_arithmetic"):
                # TwinCAT/CODESYS: the function's (method's) result is a variable with an address
                self.facts.addressed.add((self.pou.key, RESULT_KEY))
                self.facts.ref_calls.add(e.nid)
                return t.ref_type(ty, "POINTER")
            if kind in ("enum", "null", "result"):
                self.error(f"{word}() needs a variable; '{root.text}' is a value", arg.span, "E055")
                return None
            var = ref.variable  # type: ignore[union-attr]
            # TwinCAT/CODESYS take the address of a constant (to read it through the pointer)
            if var.constant and not (word == "ADR" and allows(self.settings.dialect, "adr_of_constant")):
                self.error(f"{word}() of constant '{root.text}': a constant cannot be written through a reference",
                           arg.span, "E055")
                return None
            if kind == "var":
                self.facts.addressed.add((self.pou.key, var.key))
        self.facts.ref_calls.add(e.nid)
        return t.ref_type(ty, "POINTER" if word == "ADR" else "REF_TO")

    def type_query(self, e: n.Call, word: str) -> t.Type | None:
        """Operators computed from the static type of their operand. A fixed array's bounds and
        every SIZEOF are constants; the bounds of an ARRAY[*] parameter are read at run time from
        what the caller passed (`open_array_bounds`)."""
        if word in ("LOWER_BOUND", "UPPER_BOUND"):
            return self.array_bound(e, word)
        if len(e.args) != 1 or e.args[0].kind != "positional":
            self.bc.calls.check_args_loosely(e)
            self.error(f"{word}() takes one variable or type name", e.span, "E070")
            return None
        arg = e.args[0].value
        ty = self.sizeof_operand(arg)
        if ty is None:
            return None
        size = t.byte_size(ty, allows(self.settings.dialect, "short_times"))
        if size is None:
            self.error(f"{word}() of {ty.name}: its size in bytes is not defined here "
                       "(stvm does not model the memory of function blocks or references)", arg.span, "E070")
            return None
        if word == "XSIZEOF":
            self.facts.type_queries[e.nid] = ("CONST", size)
            return t.UDINT   # Choice: a 32-bit platform (CODESYS: UDINT there, ULINT on 64-bit ones)
        # CODESYS/TwinCAT: "the type adapts to the size" (USINT < 256 <= UINT ...): a constant that
        # takes the type its context needs, like an untyped literal
        return self.constant_type_query(e, size)

    def constant_type_query(self, e: n.Call, value: int) -> t.Type:
        self.facts.type_queries[e.nid] = ("CONST", value)
        self.facts.consts[e.nid] = value
        self.facts.untyped.add(e.nid)
        return int_literal_type(value, self.settings)

    def sizeof_operand(self, arg: n.Expr) -> t.Type | None:
        """The type SIZEOF measures: a variable's, or a type named directly (`SIZEOF(INT)`)."""
        if isinstance(arg, n.Name) and self.bc.resolve_name(arg) is None:
            spec = n.NamedTypeSpec(arg.parts, False, arg.span)
            if len(arg.parts) == 1 and (arg.parts[0].upper() in t.ELEMENTARY or arg.parts[0].upper() == "WSTRING") \
                    or self.c.index.lookup_type_key(arg.parts, False, self.pou_namespace) is not None:
                return self.c.types.resolve_type_spec(spec, self.pou_namespace)
        return self.bc.expr(arg)

    def array_bound(self, e: n.Call, word: str) -> t.Type | None:
        """LOWER_BOUND(arr, dim) / UPPER_BOUND(arr, dim) (IEC 61131-3 ed. 3, 6.5.3.2): DINT."""
        if len(e.args) != 2 or any(a.kind != "positional" for a in e.args):
            self.bc.calls.check_args_loosely(e)
            self.error(f"{word}() takes an array and a constant dimension: {word}(arr, 1)", e.span, "E070")
            return None
        arr, dim_expr = e.args[0].value, e.args[1].value
        ty = self.bc.expr(arr)
        self.bc.expr(dim_expr)
        if ty is None:
            return None
        if not isinstance(ty, t.ArrayType):
            self.error(f"{word}() needs an array; '{self.bc.exprs.describe(arr)}' is {ty.name}", arr.span, "E070")
            return None
        dim = self.c.constants.const_value(dim_expr, self.pou_namespace, self.pou)
        ndims = ty.rank if ty.dims is None else len(ty.dims)
        if isinstance(dim, bool) or not isinstance(dim, int) or not 1 <= dim <= ndims:
            self.error(f"the dimension of {word}() must be a constant 1..{ndims}", dim_expr.span, "E070")
            return None
        if ty.dims is not None:
            lo, hi = ty.dims[dim - 1]
            return self.constant_type_query(e, lo if word == "LOWER_BOUND" else hi)
        # ARRAY[*, *]: the dimension goes with the operand (ARRAY[*] keeps the plain operand)
        self.facts.type_queries[e.nid] = (word, arr if ty.rank == 1 else (arr, dim))
        return t.DINT
