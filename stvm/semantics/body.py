"""Type checking of POU bodies: statements, expressions, calls (IEC 61131-3 + Sysmac rules).

Typing rules follow docs/sysmac.md section 2:
* integer results take the highest-ranked operand type (signed+unsigned of one rank → unsigned) and
  wrap at that width *before* any widening for the assignment;
* an untyped integer literal takes the other operand's type when it fits, else DINT (LINT when
  it does not fit DINT, or always LINT with `int_literal_type=lint`);
* implicit conversions are the widening chart plus same-size signed↔unsigned; anything else is an
  error that names the conversion function to use.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

from stvm.semantics import types as t
from stvm.numeric import utf16_units
from stvm.semantics.facts import NOT_CONST, CallInfo, NameRef
from stvm.semantics.model import EXTERNAL, IN_OUT, INPUT, OUTPUT, POUInfo, Variable
from stvm.syntax import nodes as n
from stvm.dialects import allows
from stvm.settings import IntLiteralType


_ARITH = {"PLUS": "+", "MINUS": "-", "STAR": "*", "SLASH": "/", "MOD": "MOD", "POW": "**"}
_COMPARE = {"EQ": "=", "NE": "<>", "LT": "<", "GT": ">", "LE": "<=", "GE": ">="}
_LOGIC = {"AND": "AND", "AMP": "AND", "OR": "OR", "XOR": "XOR", "AND_THEN": "AND_THEN", "OR_ELSE": "OR_ELSE"}
OP_TEXT = {**_ARITH, **_COMPARE, **_LOGIC, "NOT": "NOT"}
# operators answered from their operand's type (a user POU of the same name wins)
TYPE_QUERIES = ("LOWER_BOUND", "UPPER_BOUND", "SIZEOF", "XSIZEOF")


def int_literal_type(value: int, settings) -> t.Type:
    if settings.int_literal_type is IntLiteralType.LINT:
        return t.LINT
    if t.DINT.lo <= value <= t.DINT.hi:
        return t.DINT
    if t.LINT.lo <= value <= t.LINT.hi:
        return t.LINT
    return t.ULINT


def common_int(a: t.IntType, b: t.IntType) -> t.IntType:
    if a.rank != b.rank:
        return a if a.rank > b.rank else b
    if a == b:
        return a
    # same rank: bit string, then unsigned wins (sysmac.md 2)
    for cand in (a, b):
        if cand.bitstring:
            return cand
    return a if not a.signed else b


def real_for(int_type: t.IntType) -> t.RealType:
    # Choice (sysmac.md 2 ranks REAL below DINT): an 8/16-bit integer with REAL stays REAL;
    # a 32/64-bit integer mixed with a real computes in LREAL so no integer precision is lost.
    return t.REAL if int_type.bits <= 16 else t.LREAL


def is_any_descriptor(ty: t.Type | None) -> bool:
    """The structure an ANY input of user code holds (`__SYSTEM.AnyType`, TwinCAT/CODESYS)."""
    return isinstance(ty, t.StructType) and ty.qualname.lower().replace("\\", ".") == "__system.anytype"


# the key under which `facts.addressed` records that ADR() takes the address of the POU's result
# (no variable has this name)
RESULT_KEY = "<result>"


def implicit_ok(src: t.Type, dst: t.Type) -> bool:
    """May a value of `src` be assigned/passed to `dst` without a conversion function?"""
    if src == dst:
        return True
    if isinstance(src, t.StringType) and isinstance(dst, t.StringType):
        return t.is_wide(src) == t.is_wide(dst)   # STRING <-> WSTRING needs a conversion function
    if isinstance(src, t.IntType) and isinstance(dst, t.IntType):
        if src.bits == dst.bits:
            return True
        return src.bits < dst.bits and (not src.signed or dst.signed)
    if isinstance(src, t.IntType) and isinstance(dst, t.RealType):
        return not src.bitstring
    if isinstance(src, t.RealType) and isinstance(dst, t.RealType):
        return src.bits <= dst.bits
    if isinstance(src, t.StructType) and isinstance(dst, t.StructType):
        return src.qualname.lower() == dst.qualname.lower()
    if isinstance(src, t.EnumType) and isinstance(dst, t.EnumType):
        return src.qualname.lower() == dst.qualname.lower()
    if isinstance(src, t.ArrayType) and isinstance(dst, t.ArrayType):
        if dst.dims is None:
            return implicit_ok(src.element, dst.element) and src.element.kind == dst.element.kind \
                and open_rank_ok(src, dst)
        return (src.dims is not None and len(src.dims) == len(dst.dims)
                and all(h1 - l1 == h2 - l2 for (l1, h1), (l2, h2) in zip(src.dims, dst.dims))
                and (src.element == dst.element or (isinstance(src.element, t.StringType) and isinstance(dst.element, t.StringType)
                                                   and t.is_wide(src.element) == t.is_wide(dst.element))
                     or (getattr(src.element, "qualname", None) or "x").lower() == (getattr(dst.element, "qualname", None) or "y").lower()))
    if isinstance(src, t.TimeType) and isinstance(dst, t.TimeType):
        # IEC ed. 3 (implicit conversions): TIME -> LTIME, DATE -> LDATE, TOD -> LTOD, DT -> LDT
        return src.family == dst.family and (dst.long or not src.long)
    return False


def open_rank_ok(src: t.ArrayType, dst: t.ArrayType) -> bool:
    """An array passed to an open array of several dimensions (ARRAY[*, *]) has that many
    (ARRAY[*] takes any array, as before: Sysmac passes a whole array's elements in order)."""
    if dst.rank == 1:
        return src.dims is not None or src.rank == 1
    return len(src.dims) == dst.rank if src.dims is not None else src.rank == dst.rank


def conversion_hint(src: t.Type, dst: t.Type) -> str:
    def base(ty: t.Type) -> str:
        return ty.name.split("[")[0]
    if src.kind in ("int", "real", "bool", "string", "time") and dst.kind in ("int", "real", "bool", "string", "time"):
        return f"; use {base(src)}_TO_{base(dst)}"
    return ""


def trunc_result_from_context(settings) -> bool:
    """Does TRUNC take its integer result type from the context (IEC ed. 3 table 22: ANY_REAL ->
    ANY_INT, so `i : INT := TRUNC(r)`)? Sysmac's TRUNC gives DINT for REAL, LINT for LREAL (W502
    2-284) — that rule remains when the context expects no integer or under a dialect where this
    returns False. The single dialect switch for it (lang-dialects: False under sysmac)."""
    return True


def _with_access(method: POUInfo, access: str) -> POUInfo:
    """A property accessor checked with its property's access specifier."""
    return replace(method, access=access)


def native_result_rule(pou: POUInfo, natives):
    """The stdlib's result-type rule for a generic native (SHL, MUX, TRUNC, …), if it has one;
    `natives`: the native functions the checker was given (stvm.stdlib.NATIVE_FUNCTIONS)."""
    if not pou.native or pou.kind != "FUNCTION":
        return None
    native = natives.get(pou.qualname.split("\\")[-1].upper())
    return native.result_rule if native is not None else None


class BodyChecker:
    # `checker`: the Checker that runs this body check (stvm.semantics.checker imports this module)
    # calls whose result rule rejected the arguments (reported once: no "cannot infer" after it)
    rejected_calls: frozenset[int] = frozenset()
    # per checker class (a subclass gets its own): node class -> its stmt_… / expr_… function,
    # looked up once instead of building the name and a bound method per node
    _stmt_methods: dict[type, Any] = {}
    _expr_methods: dict[type, Any] = {}

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        cls._stmt_methods, cls._expr_methods = {}, {}

    @classmethod
    def _method(cls, table: dict[type, Any], prefix: str, node_cls: type):
        method = table[node_cls] = getattr(cls, prefix + node_cls.__name__)
        return method

    def __init__(self, checker: Any, pou: POUInfo, node, fb: POUInfo | None = None,
                 fb_node: n.POU | None = None) -> None:
        self.c = checker
        self.pou = pou
        self.node = node
        # the FB (or PROGRAM) whose instance the body runs on: its own body, or a method's owner
        self.fb = fb if fb is not None else (pou if pou.kind in ("FUNCTION_BLOCK", "PROGRAM") else None)
        self.fb_node = fb_node if fb_node is not None else node
        self.member_base: tuple[n.Expr, t.Type] | None = None   # a callee's base oo_call typed already
        self.facts = checker.facts
        self.settings = checker.settings
        self.loop_depth = 0
        self.for_vars: list[str] = []

    def error(self, message: str, span: n.Span, code: str = "") -> None:
        self.c.error(message, span, code)

    # ---- statements
    def check(self) -> None:
        for var in self.pou.variables.values():
            if var.section == EXTERNAL and var.key not in self.c.globals:
                self.error(f"VAR_EXTERNAL '{var.name}' has no matching VAR_GLOBAL", var.span, "E033")
            elif var.section == EXTERNAL and self.c.globals[var.key].type != var.type:
                self.error(f"VAR_EXTERNAL '{var.name}' is {var.type.name} but the global is "
                           f"{self.c.globals[var.key].type.name}", var.span, "E033")
        self.statements(self.node.body)

    def statements(self, body: tuple[n.Statement, ...]) -> None:
        for stmt in body:
            self.statement(stmt)

    def statement(self, s: n.Statement) -> None:
        method = self._stmt_methods.get(s.__class__)
        if method is None:
            method = self._method(self._stmt_methods, "stmt_", s.__class__)
        method(self, s)

    def stmt_Assign(self, s: n.Assign) -> None:
        self.en_call = s.value   # EN/ENO are allowed on this call (bind_en_eno)
        target_type = self.lvalue(s.target)
        value_type = self.expr(s.value, expected=target_type)
        if target_type is not None and value_type is not None:
            self.require_assignable(s.value, value_type, target_type, s.value.span)

    def stmt_CallStatement(self, s: n.CallStatement) -> None:
        if not isinstance(s.call, n.Call):
            if isinstance(s.call, n.Name) and self.lookup_callable(s.call) is not None:
                self.error(f"'{s.call.text}' is called without parentheses; write {s.call.text}();", s.span, "E040")
            else:
                self.expr(s.call)
                self.error("this statement does nothing: expected an assignment (:=) or a call", s.span, "E040")
            return
        self.en_call = s.call
        self.expr(s.call, statement=True)

    def condition(self, expr: n.Expr, what: str) -> None:
        ty = self.expr(expr)
        if ty is not None and not isinstance(ty, t.BoolType):
            self.error(f"{what} must be BOOL, not {ty.name}", expr.span, "E041")

    def stmt_If(self, s: n.If) -> None:
        for cond, body in s.branches:
            self.condition(cond, "IF condition")
            self.statements(body)
        if s.else_body is not None:
            self.statements(s.else_body)

    def stmt_Case(self, s: n.Case) -> None:
        sel = self.expr(s.selector)
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
            self.statements(body)
        if s.else_body is not None:
            self.statements(s.else_body)

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
        var_type = self.lvalue(s.variable)
        if self.is_property(s.variable, "FOR"):
            var_type = None
        if var_type is not None and not isinstance(var_type, t.IntType):
            self.error(f"FOR variable must be an integer, not {var_type.name}", s.variable.span, "E043")
        for part in (s.start, s.end) + ((s.step,) if s.step is not None else ()):
            ty = self.expr(part, expected=var_type)
            if ty is not None and var_type is not None:
                self.require_assignable(part, ty, var_type, part.span)
        if s.step is not None:
            step = self.c.constants.const_value(s.step, self.pou_namespace, self.pou)
            if step == 0:
                self.error("FOR step is 0: the loop never ends", s.step.span, "E043")
        self.loop_depth += 1
        self.statements(s.body)
        self.loop_depth -= 1

    def stmt_While(self, s: n.While) -> None:
        self.condition(s.condition, "WHILE condition")
        self.loop_depth += 1
        self.statements(s.body)
        self.loop_depth -= 1

    def stmt_Repeat(self, s: n.Repeat) -> None:
        self.loop_depth += 1
        self.statements(s.body)
        self.loop_depth -= 1
        self.condition(s.condition, "UNTIL condition")

    def stmt_Exit(self, s: n.Exit) -> None:
        if self.loop_depth == 0:
            self.error("EXIT outside a loop", s.span, "E044")

    def stmt_Continue(self, s: n.Continue) -> None:
        if self.loop_depth == 0:
            self.error("CONTINUE outside a loop", s.span, "E044")

    def stmt_Return(self, s: n.Return) -> None:
        pass

    def stmt_Empty(self, s: n.Empty) -> None:
        pass

    @property
    def pou_namespace(self) -> tuple[str, ...]:
        return self.fb_node.namespace

    # ---- names
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

    # ---- lvalues
    def lvalue(self, target: n.Expr) -> t.Type | None:
        """Check an assignment target; returns its type (None when already diagnosed)."""
        if isinstance(target, n.Name):
            ref = self.resolve_name(target)
            if ref is None:
                self.undeclared(target)
                return None
            self.facts.names[target.nid] = ref  # type: ignore[assignment]
            kind = ref.kind  # type: ignore[attr-defined]
            if kind == "enum":
                self.error(f"cannot assign to enumerator '{target.text}'", target.span, "E050")
                return None
            if kind == "prop":
                return self.property_store(target, ref.value, "self")  # type: ignore[attr-defined]
            if kind == "result":
                ty = self.implicit_deref(target, self.pou.return_type) if self.pou.return_type else None
                self.facts.types[target.nid] = ty  # type: ignore[assignment]
                return ty
            var: Variable = ref.variable  # type: ignore[attr-defined]
            if var.constant:
                self.error(f"cannot assign to constant '{target.text}'", target.span, "E050")
            if isinstance(var.type, t.FBType) and not allows(self.settings.dialect, "fb_assign"):
                self.error(f"cannot assign to function block instance '{target.text}'", target.span, "E050")
                return None
            self.facts.types[target.nid] = self.implicit_deref(target, var.type)
            return self.facts.types[target.nid]
        if isinstance(target, n.Deref):
            return self.expr(target)
        if isinstance(target, n.Member):
            base_type = self.expr(target.base)
            if base_type is None:
                return None
            if isinstance(base_type, (t.FBType, t.InterfaceType)):
                prop = self.c.oo.find_property(base_type.qualname.lower(), target.name)
                if prop is not None:
                    self.facts.names.pop(target.nid, None)
                    return self.property_store(target, prop, self.member_how(target.base, base_type))
            if isinstance(base_type, t.FBType) and not self.inside_own(target.base, base_type):
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
            ty = self.expr(target)
            if ty is not None and self.is_constant_path(target.base):
                self.error("cannot assign to a member of a constant", target.span, "E050")
            if ty is not None and self.through_property(target.base):
                return None
            return ty
        if isinstance(target, (n.Index, n.BitAccess)):
            ty = self.expr(target)
            if ty is not None and self.is_constant_path(target.base):
                self.error("cannot assign into a constant", target.span, "E050")
            if ty is not None and isinstance(target, n.Index) and self.through_property(target.base):
                return None
            return ty
        if isinstance(target, n.Call):
            self.expr(target)
            self.error("cannot assign to a call result", target.span, "E050")
            return None
        self.error("this expression cannot be assigned to", target.span, "E050")
        return None

    def is_constant_path(self, base: n.Expr) -> bool:
        while isinstance(base, (n.Member, n.Index, n.BitAccess)):
            base = base.base
        ref = self.facts.names.get(base.nid)
        return bool(ref is not None and getattr(ref, "variable", None) is not None and ref.variable.constant)  # type: ignore[attr-defined]

    def undeclared(self, name: n.Name) -> None:
        if self.lookup_callable(name) is not None:
            self.error(f"'{name.text}' is a POU, not a variable", name.span, "E031")
        else:
            self.error(f"'{name.text}' is not declared", name.span, "E031")

    # ---- assignability
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
        if allows(self.settings.dialect, "enum_integer") and (
                isinstance(src, t.EnumType) and isinstance(dst, t.IntType)
                or isinstance(src, t.IntType) and isinstance(dst, t.EnumType)):
            return   # TwinCAT: an enumeration converts to and from its integer value
        if isinstance(src, t.IntType) and isinstance(dst, t.IntType):
            self.error(f"cannot assign {src.name} to {dst.name} implicitly (value may not fit){conversion_hint(src, dst)}", span, "E052")
            return
        self.error(f"type mismatch: cannot assign {src.name} to {dst.name}{conversion_hint(src, dst)}", span, "E052")

    def mark_addressed(self, expr: n.Expr) -> None:
        """The variable under `expr` (a name, field, element) has its address taken: lowering keeps
        it where a reference can reach it (never in a Python local)."""
        root = expr
        while isinstance(root, (n.Member, n.Index)):
            if isinstance(root, n.Member):
                base_type = self.facts.types.get(root.base.nid)
                if isinstance(base_type, t.FBType):
                    self.facts.addressed.add((base_type.qualname.lower(), root.name.lower()))
            root = root.base
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

    def intrinsic(self, e: n.Call, word: str) -> t.Type | None:
        """__QUERYINTERFACE(itf, itf2) (CODESYS): itf2 := the instance itf holds when its FB
        implements itf2's interface, else 0; TRUE when it does. __ISVALIDREF(x): x is not NULL."""
        args = [a for a in e.args if a.kind == "positional"]
        want = 2 if word == "__QUERYINTERFACE" else 1
        if len(args) != want or len(e.args) != want:
            self.check_args_loosely(e)
            self.error(f"{word} takes {want} positional argument(s)", e.span, "E048")
            return None
        ty = self.expr(args[0].value)
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
        tty = self.lvalue(target) if self.is_lvalue_shape(target) else None
        if not isinstance(tty, t.InterfaceType):
            if tty is not None or not self.is_lvalue_shape(target):
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

    def string_constant_fits(self, expr: n.Expr, dst: t.StringType, span: n.Span) -> None:
        """A constant text that provably overflows STRING[n] (sysmac.md 2, `string_overflow`):
        the code generator cuts it at build time, so the check-time diagnostic is its only
        report (a warning, or an error under `string_overflow=error`)."""
        value = self.facts.consts.get(expr.nid)
        if isinstance(value, (bytes, str)) and len(value) > dst.max_bytes:
            self.c.string_overflow(len(value), dst, span)

    # ---- expressions
    def expr(self, e: n.Expr, expected: t.Type | None = None, statement: bool = False) -> t.Type | None:
        method = self._expr_methods.get(e.__class__)
        if method is None:
            method = self._method(self._expr_methods, "expr_", e.__class__)
        if isinstance(e, n.Call):
            ty = self.expr_Call(e, expected, statement)
            if isinstance(ty, t.RefType) and ty.flavour == "REFERENCE" and e.nid in self.facts.calls:
                ty = self.implicit_deref(e, ty)   # a METHOD/FUNCTION result REFERENCE TO: its target
        else:
            ty = method(self, e, expected)
        if ty is not None:
            self.facts.types[e.nid] = ty
        return ty

    def expr_IntLiteral(self, e: n.IntLiteral, expected) -> t.Type:
        self.facts.untyped.add(e.nid)
        self.facts.consts[e.nid] = e.value
        return int_literal_type(e.value, self.settings)

    def expr_RealLiteral(self, e: n.RealLiteral, expected) -> t.Type:
        self.facts.untyped.add(e.nid)
        self.facts.consts[e.nid] = e.value
        return t.LREAL

    def expr_BoolLiteral(self, e, expected) -> t.Type:
        self.facts.consts[e.nid] = e.value
        return t.BOOL

    def expr_StringLiteral(self, e: n.StringLiteral, expected) -> t.Type:
        if isinstance(e.value, str) or t.is_wide(expected):
            return self.wstring_literal(e)
        self.facts.consts[e.nid] = e.value
        return t.string_type(max(len(e.value) + 1, 1))

    def wstring_literal(self, e: n.StringLiteral) -> t.Type:
        """A WSTRING literal ("…"), or a STRING literal where a WSTRING is expected (CODESYS takes
        `ws := 'abc'`): its value is the `str` of its UTF-16 code units."""
        value = e.value if isinstance(e.value, str) else utf16_units(e.value.decode("utf-8", "replace"))
        self.facts.consts[e.nid] = value
        return t.wstring_type(max(len(value), 1))

    def expr_TimeLiteral(self, e: n.TimeLiteral, expected) -> t.Type:
        self.facts.consts[e.nid] = e.value_ns
        return t.ELEMENTARY[e.type_name]

    def expr_HashLiteral(self, e: n.HashLiteral, expected) -> t.Type | None:
        lit = self.c.constants.hash_literal(e, self.pou_namespace)
        if lit is None:
            return None
        self.facts.consts[e.nid] = lit[1]
        return lit[0]

    def expr_Name(self, e: n.Name, expected) -> t.Type | None:
        ref = self.resolve_name(e)
        if ref is None:
            if len(e.parts) == 1 and isinstance(expected, t.EnumType) and expected.value_of(e.parts[0]) is not None:
                ref = NameRef("enum", value=expected.value_of(e.parts[0]), variable=Variable(e.parts[0], "ENUM", expected))
            elif len(e.parts) == 1 and not e.rooted and e.parts[0].upper() == "NULL":
                self.facts.names[e.nid] = NameRef("null")  # type: ignore[assignment]
                return t.NULL_REF
            elif len(e.parts) == 1 and not e.rooted and e.parts[0].upper() in ("THIS", "SUPER"):
                return self.this_or_super(e)
            else:
                self.undeclared(e)
                return None
        self.facts.names[e.nid] = ref  # type: ignore[assignment]
        if ref.kind == "enum":  # type: ignore[attr-defined]
            self.facts.consts[e.nid] = ref.value  # type: ignore[attr-defined]
            return ref.variable.type  # type: ignore[attr-defined]
        if ref.kind == "result":  # type: ignore[attr-defined]
            return self.implicit_deref(e, self.pou.return_type) if self.pou.return_type is not None else None
        if ref.kind == "prop":  # type: ignore[attr-defined]
            return self.property_load(e, ref.value, "self")  # type: ignore[attr-defined]
        var: Variable = ref.variable  # type: ignore[attr-defined]
        if var.constant and var.init is not None and not isinstance(var.init, (list, dict)):
            self.facts.consts[e.nid] = var.init
        return self.implicit_deref(e, var.type)

    def expr_Member(self, e: n.Member, expected) -> t.Type | None:
        known, self.member_base = self.member_base, None
        base = known[1] if known is not None and known[0] is e.base else self.expr(e.base)
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
            return var.type if self.member_visible(base, var, e) else None
        self.error(f"'{self.describe(e.base)}' is {base.name}, which has no members", e.span, "E034")
        return None

    def member_visible(self, base: t.FBType, var: Variable, e: n.Member) -> bool:
        """IEC: outside an FB only its inputs and outputs are visible (the debugger sees all)."""
        if var.section not in (INPUT, OUTPUT) and not base.is_program and not \
                allows(self.settings.dialect, "fb_internal_read"):
            self.error(f"'{e.name}' is internal to {base.name}; only inputs and outputs are visible outside", e.span, "E034")
            return False
        return True

    # ---- object orientation
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
        self.check_access(prop.getter if prop.access == "PUBLIC" else _with_access(prop.getter, prop.access),
                          "property", e.span)
        self.facts.props[e.nid] = (prop, how)
        return prop.type

    def property_store(self, target: n.Expr, prop, how: str) -> t.Type | None:
        if prop.setter is None:
            self.error(f"property '{prop.name}' has no SET; it can only be read", target.span, "E072")
            return None
        self.check_access(prop.setter if prop.access == "PUBLIC" else _with_access(prop.setter, prop.access),
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
        outer, self.call_expected = getattr(self, "call_expected", None), expected
        try:
            self.bind_args(e, method, info, fb=False)
        finally:
            self.call_expected = outer
        self.facts.calls[e.nid] = info
        return method.return_type or t.VOID

    def oo_call(self, e: n.Call, expected, statement: bool) -> tuple[bool, t.Type | None]:
        """A METHOD call or SUPER^(): (True, result type) when `e` is one; (False, None) if not."""
        callee = e.callee
        if isinstance(callee, n.Name):
            if len(callee.parts) == 1 and not callee.rooted and self.fb is not None:
                method = self.c.oo.find_method(self.fb.key, callee.parts[0])
                if method is not None and self.resolve_name(callee) is None:
                    return True, self.method_call(e, method, "self", None, "", expected)
            return False, None
        if isinstance(callee, n.Deref) and isinstance(callee.base, n.Name) and callee.base.parts[0].upper() == "SUPER" \
                and self.resolve_name(callee.base) is None:
            ty = self.expr(callee)
            if ty is None:
                self.check_args_loosely(e)
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
        base_type = self.expr(callee.base)
        if base_type is None:
            self.check_args_loosely(e)
            return True, None
        if isinstance(base_type, t.InterfaceType):
            method = self.c.oo.find_method(base_type.qualname.lower(), callee.name)
            if method is None:
                self.error(f"interface {base_type.name} has no method '{callee.name}'", callee.span, "E045")
                self.check_args_loosely(e)
                return True, None
            return True, self.method_call(e, method, "itf", callee.base, "", expected)
        if isinstance(base_type, t.FBType):
            method = self.c.oo.find_method(base_type.qualname.lower(), callee.name)
            if method is None:
                fb = self.c.pous.get(base_type.qualname.lower())
                if fb is not None and fb.pin(callee.name) is None and (fb.methods or fb.base or fb.properties):
                    self.error(f"function block {base_type.name} has no method '{callee.name}'", callee.span, "E045")
                    self.check_args_loosely(e)
                    return True, None
                self.member_base = (callee.base, base_type)   # expr_Call types the callee next
                return False, None
            how = self.member_how(callee.base, base_type)
            if how == "super":
                return True, self.method_call(e, method, "super", None, self.fb.base or "", expected)  # type: ignore[union-attr]
            if isinstance(callee.base, n.Deref) and self.inside_own(callee.base, base_type):
                return True, self.method_call(e, method, "self", None, "", expected)
            return True, self.method_call(e, method, "inst", callee.base, "", expected)
        self.member_base = (callee.base, base_type)
        return False, None

    def expr_BitAccess(self, e: n.BitAccess, expected) -> t.Type | None:
        base = self.expr(e.base)
        if base is None:
            return None
        if not isinstance(base, t.IntType):
            self.error(f"bit access needs an integer or bit string, not {base.name}", e.span, "E035")
            return None
        if not 0 <= e.bit < base.bits:
            self.error(f"bit {e.bit} is outside {base.name} (0..{base.bits - 1})", e.span, "E035")
            return None
        return t.BOOL

    def expr_PartialAccess(self, e: n.PartialAccess, expected) -> t.Type | None:
        base = self.expr(e.base)
        if base is None:
            return None
        part = {8: t.BYTE, 16: t.WORD, 32: t.DWORD}[e.width]
        letter = {8: "B", 16: "W", 32: "D"}[e.width]
        if not isinstance(base, t.IntType):
            self.error(f"%{letter} access needs a bit string or integer, not {base.name}", e.span, "E035")
            return None
        count = base.bits // e.width
        if e.bit >= count:
            what = f"{base.name} has no {part.name}s" if count == 0 else f"{base.name} has {part.name}s 0..{count - 1}"
            self.error(f"%{letter}{e.bit} is outside {base.name}: {what}", e.span, "E035")
            return None
        return part

    def expr_Index(self, e: n.Index, expected) -> t.Type | None:
        base = self.expr(e.base)
        for ix in e.indices:
            ity = self.expr(ix)
            if ity is not None and not isinstance(ity, (t.IntType, t.EnumType)):
                self.error(f"array index must be an integer, not {ity.name}", ix.span, "E036")
        if base is None:
            return None
        if self.byte_pointer(base) and len(e.indices) == 1 and t.byte_size(base.target) is not None:  # type: ignore[union-attr]
            return self.canonical(base.target)   # TwinCAT/CODESYS `p[i]`: the i-th element from p
        if not isinstance(base, t.ArrayType):
            self.error(f"'{self.describe(e.base)}' is {base.name}, not an array", e.span, "E036")
            return None
        if base.dims is None:
            if len(e.indices) != base.rank:
                self.error(f"an {base.name.split(' OF ')[0]} parameter takes {base.rank} index(es), got "
                           f"{len(e.indices)}", e.span, "E036")
            return base.element
        if len(e.indices) != len(base.dims):
            self.error(f"{base.name} needs {len(base.dims)} index(es), got {len(e.indices)}", e.span, "E036")
            return None
        for ix, (lo, hi) in zip(e.indices, base.dims):
            value = self.facts.consts.get(ix.nid)
            if isinstance(value, int) and not isinstance(value, bool) and not lo <= value <= hi:
                self.error(f"index {value} is outside the bounds {lo}..{hi}", ix.span, "E036")
        return base.element

    def expr_Deref(self, e: n.Deref, expected) -> t.Type | None:
        base = self.expr(e.base)
        if base is None:
            return None
        if not isinstance(base, t.RefType) or base.flavour == "REFERENCE":
            self.error(f"'^' needs a reference (REF_TO or POINTER TO), but '{self.describe(e.base)}' is {base.name}",
                       e.span, "E037")
            return None
        if base.is_null:
            self.error("NULL cannot be dereferenced", e.span, "E037")
            return None
        return self.canonical(base.target)

    def canonical(self, ty: t.Type) -> t.Type:
        """A struct named inside its own declaration (`next : REF_TO Node`) was resolved to a
        placeholder without fields; the finished type replaces it."""
        if isinstance(ty, t.StructType):
            return self.c.structs.get(ty.qualname.lower(), ty)
        return ty

    # ---- references (REF_TO / POINTER TO / REFERENCE TO)
    def implicit_deref(self, e: n.Expr, ty: t.Type) -> t.Type:
        """A REFERENCE TO variable stands for its target wherever it is used (CODESYS)."""
        if isinstance(ty, t.RefType) and ty.flavour == "REFERENCE":
            self.facts.auto_deref.add(e.nid)
            return self.canonical(ty.target)
        return ty

    def reference_of(self, e: n.Call) -> t.Type | None:
        """REF(x) (IEC) / ADR(x) (CODESYS): a reference to the variable x, never to a value."""
        word = e.callee.parts[0].upper()  # type: ignore[attr-defined]
        if len(e.args) != 1 or e.args[0].kind != "positional":
            self.check_args_loosely(e)
            self.error(f"{word}() takes one variable", e.span, "E055")
            return None
        arg = e.args[0].value
        ty = self.expr(arg)
        if ty is None or self.is_property(arg, f"{word}()"):
            return None
        if not isinstance(arg, (n.Name, n.Member, n.Index, n.Deref)):
            what = "a single bit, which has no reference" if isinstance(arg, n.BitAccess) else "a temporary value"
            shown = self.describe(arg)
            shown = "this expression" if shown == "expression" else f"'{shown}'"
            self.error(f"{word}() needs a variable; {shown} is {what}", arg.span, "E055")
            return None
        root: n.Expr = arg
        while isinstance(root, (n.Member, n.Index)):
            if isinstance(root, n.Member):
                base_type = self.facts.types.get(root.base.nid)
                if isinstance(base_type, t.FBType):
                    self.facts.addressed.add((base_type.qualname.lower(), root.name.lower()))
            root = root.base
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

    # ---- operators answered from the types (LOWER_BOUND, UPPER_BOUND, SIZEOF, XSIZEOF)
    def type_query(self, e: n.Call, word: str) -> t.Type | None:
        """Operators computed from the static type of their operand. A fixed array's bounds and
        every SIZEOF are constants; the bounds of an ARRAY[*] parameter are read at run time from
        what the caller passed (`open_array_bounds`)."""
        if word in ("LOWER_BOUND", "UPPER_BOUND"):
            return self.array_bound(e, word)
        if len(e.args) != 1 or e.args[0].kind != "positional":
            self.check_args_loosely(e)
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
        if isinstance(arg, n.Name) and self.resolve_name(arg) is None:
            spec = n.NamedTypeSpec(arg.parts, False, arg.span)
            if len(arg.parts) == 1 and (arg.parts[0].upper() in t.ELEMENTARY or arg.parts[0].upper() == "WSTRING") \
                    or self.c.index.lookup_type_key(arg.parts, False, self.pou_namespace) is not None:
                return self.c.types.resolve_type_spec(spec, self.pou_namespace)
        return self.expr(arg)

    def array_bound(self, e: n.Call, word: str) -> t.Type | None:
        """LOWER_BOUND(arr, dim) / UPPER_BOUND(arr, dim) (IEC 61131-3 ed. 3, 6.5.3.2): DINT."""
        if len(e.args) != 2 or any(a.kind != "positional" for a in e.args):
            self.check_args_loosely(e)
            self.error(f"{word}() takes an array and a constant dimension: {word}(arr, 1)", e.span, "E070")
            return None
        arr, dim_expr = e.args[0].value, e.args[1].value
        ty = self.expr(arr)
        self.expr(dim_expr)
        if ty is None:
            return None
        if not isinstance(ty, t.ArrayType):
            self.error(f"{word}() needs an array; '{self.describe(arr)}' is {ty.name}", arr.span, "E070")
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

    def stmt_RefAssign(self, s: n.RefAssign) -> None:
        target = s.target
        raw = None
        if isinstance(target, (n.Name, n.Member)):
            self.lvalue(target)
            if target.nid in self.facts.auto_deref:
                if isinstance(target, n.Name) and self.facts.names[target.nid].kind == "result":  # type: ignore[attr-defined]
                    raw = self.pou.return_type   # `Get REF= x;` in a METHOD ... : REFERENCE TO
                elif isinstance(target, n.Name):
                    raw = self.facts.names[target.nid].variable.type  # type: ignore[attr-defined]
                else:
                    raw = self.member_raw_type(target)
        if raw is None:
            self.expr(s.value)
            self.error("REF= needs a REFERENCE TO variable on its left", target.span, "E056")
            return
        self.facts.types[target.nid] = raw
        value_type = self.expr(s.value)
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

    def expr_Unary(self, e: n.Unary, expected) -> t.Type | None:
        ty = self.expr(e.operand, expected)
        if ty is None:
            return None
        if e.op == "NOT":
            if isinstance(ty, t.BoolType) or (isinstance(ty, t.IntType)):
                if e.operand.nid in self.facts.consts and isinstance(ty, t.BoolType):
                    self.facts.consts[e.nid] = not self.facts.consts[e.operand.nid]
                return ty
            self.error(f"NOT needs BOOL or a bit string, not {ty.name}", e.span, "E038")
            return None
        if isinstance(ty, (t.IntType, t.RealType)) or getattr(ty, "family", "") == "TIME":
            if e.operand.nid in self.facts.untyped:
                value = self.facts.consts[e.operand.nid]
                folded = -value if e.op == "MINUS" else value
                self.facts.untyped.add(e.nid)
                self.facts.consts[e.nid] = folded
                if isinstance(folded, int):
                    return int_literal_type(folded, self.settings)
                return ty
            if isinstance(ty, t.IntType) and not ty.signed and e.op == "MINUS":
                # IEC: negation of an unsigned value wraps; Sysmac accepts it
                return ty
            if e.operand.nid in self.facts.consts and e.op == "MINUS" and isinstance(self.facts.consts[e.operand.nid], (int, float)) \
                    and not isinstance(self.facts.consts[e.operand.nid], bool):
                self.facts.consts[e.nid] = -self.facts.consts[e.operand.nid]  # type: ignore[operator]
            return ty
        self.error(f"unary {OP_TEXT.get(e.op, e.op)} needs a number, not {ty.name}", e.span, "E038")
        return None

    def literal_fits(self, e: n.Expr, ty: t.Type) -> bool:
        value = self.facts.consts.get(e.nid)
        if isinstance(ty, t.IntType) and isinstance(value, int) and not isinstance(value, bool):
            return ty.lo <= value <= ty.hi
        if isinstance(ty, t.RealType):
            return isinstance(value, (int, float)) and not isinstance(value, bool)
        return False

    def expr_Binary(self, e: n.Binary, expected) -> t.Type | None:
        lt = self.expr(e.left)
        rt = self.expr(e.right)
        if lt is None or rt is None:
            return None
        lu = e.left.nid in self.facts.untyped
        ru = e.right.nid in self.facts.untyped
        op = e.op
        sym = OP_TEXT.get(op, op)
        if op in _LOGIC or op in ("EQ", "NE"):
            # IEC: 0 and 1 are BOOL literals (`b AND 1`, `b = 0`)
            if isinstance(lt, t.BoolType) and self.bool_literal(e.right):
                rt = t.BOOL
            elif isinstance(rt, t.BoolType) and self.bool_literal(e.left):
                lt = t.BOOL
        if op in _COMPARE:
            if self.comparable(lt, rt, e.left, e.right, op):
                self.facts.types[e.nid] = t.BOOL
                operand = self.operand_type(lt, rt, lu, ru, e)
                if operand is not None:
                    self.facts.operand_types[e.nid] = operand
                return t.BOOL
            self.error(f"cannot compare {lt.name} {sym} {rt.name}", e.span, "E039")
            return None
        if op in _LOGIC:
            if isinstance(lt, t.BoolType) and isinstance(rt, t.BoolType):
                return t.BOOL
            if op in ("AND_THEN", "OR_ELSE"):
                self.error(f"{sym} needs BOOL operands, not {lt.name} and {rt.name}", e.span, "E039")
                return None
            if isinstance(lt, t.IntType) and isinstance(rt, t.IntType):
                return self.operand_type(lt, rt, lu, ru, e)
            self.error(f"{sym} needs BOOL or bit-string operands, not {lt.name} and {rt.name}", e.span, "E039")
            return None
        # arithmetic
        if op == "POW":
            if isinstance(lt, (t.IntType, t.RealType)) and isinstance(rt, (t.IntType, t.RealType)):
                if isinstance(lt, t.RealType):
                    return t.LREAL if lu else lt
                return real_for(lt)  # type: ignore[arg-type]
            self.error(f"** needs numbers, not {lt.name} and {rt.name}", e.span, "E039")
            return None
        if lu and ru:
            folded = self.c.constants.const_value(e, self.pou_namespace, self.pou)
            if folded is not NOT_CONST and isinstance(folded, (int, float)):
                self.facts.untyped.add(e.nid)
                self.facts.consts[e.nid] = folded
                if isinstance(folded, int):
                    return int_literal_type(folded, self.settings)
                return t.LREAL
        if isinstance(lt, t.TimeType) or isinstance(rt, t.TimeType):
            return self.time_arith(e, lt, rt)
        if (op in ("PLUS", "MINUS") and self.byte_pointer(lt) and isinstance(rt, t.IntType)
                or op == "PLUS" and isinstance(lt, t.IntType) and self.byte_pointer(rt)) \
                and t.byte_size((lt if isinstance(lt, t.RefType) else rt).target) is not None:  # type: ignore[union-attr]
            # TwinCAT/CODESYS: `p + n` is the address n bytes further, of p's type
            self.facts.untyped.discard(e.nid)
            return lt if isinstance(lt, t.RefType) else rt
        if isinstance(lt, (t.IntType, t.RealType)) and isinstance(rt, (t.IntType, t.RealType)):
            if op == "MOD" and not (isinstance(lt, t.IntType) and isinstance(rt, t.IntType)):
                self.error(f"MOD needs integers, not {lt.name} and {rt.name}", e.span, "E039")
                return None
            return self.operand_type(lt, rt, lu, ru, e)
        self.error(f"operator {sym} cannot be applied to {lt.name} and {rt.name}", e.span, "E039")
        return None

    def bool_literal(self, e: n.Expr) -> bool:
        if e.nid in self.facts.untyped and self.facts.consts.get(e.nid) in (0, 1) \
                and not isinstance(self.facts.consts.get(e.nid), float):
            self.facts.types[e.nid] = t.BOOL
            self.facts.consts[e.nid] = bool(self.facts.consts[e.nid])
            return True
        return False

    def operand_type(self, lt: t.Type, rt: t.Type, lu: bool, ru: bool, e: n.Binary) -> t.Type | None:
        """The type a binary operation on these operands computes in."""
        if isinstance(lt, t.IntType) and isinstance(rt, t.IntType):
            if lu and not ru and self.literal_fits(e.left, rt):
                return rt
            if ru and not lu and self.literal_fits(e.right, lt):
                return lt
            return common_int(lt, rt)
        if isinstance(lt, t.RealType) and isinstance(rt, t.RealType):
            if lu and not ru:
                return rt
            if ru and not lu:
                return lt
            return t.LREAL if t.LREAL in (lt, rt) else t.REAL
        if isinstance(lt, t.RealType) and isinstance(rt, t.IntType):
            if lu:
                return t.REAL if ru or rt.bits <= 16 else real_for(rt)
            return lt if lt.bits == 64 or ru else (t.REAL if rt.bits <= 16 else t.LREAL)
        if isinstance(lt, t.IntType) and isinstance(rt, t.RealType):
            if ru:
                return t.REAL if lu or lt.bits <= 16 else real_for(lt)
            return rt if rt.bits == 64 or lu else (t.REAL if lt.bits <= 16 else t.LREAL)
        if lt == rt:
            return lt
        return None

    def comparable(self, lt: t.Type, rt: t.Type, le: n.Expr, re_: n.Expr, op: str) -> bool:
        if isinstance(lt, (t.IntType, t.RealType)) and isinstance(rt, (t.IntType, t.RealType)):
            return True
        if isinstance(lt, t.StringType) and isinstance(rt, t.StringType):
            return t.is_wide(lt) == t.is_wide(rt)
        if isinstance(lt, t.EnumType) and isinstance(rt, t.EnumType):
            return lt.qualname.lower() == rt.qualname.lower()
        if isinstance(lt, t.BoolType) and isinstance(rt, t.BoolType):
            return True
        if self.c.settings.dialect.value == "twincat" and \
                {type(lt), type(rt)} <= {t.EnumType, t.IntType, t.SubrangeType} and t.EnumType in {type(lt), type(rt)}:
            # TwinCAT: an enumeration without {attribute 'strict'} compares with integers as its
            # value (Beckhoff, "Enumerations"); stvm does not read 'strict' yet: every one does
            return True
        if isinstance(lt, t.TimeType) and isinstance(rt, t.TimeType):
            return lt.family == rt.family
        if (isinstance(lt, t.InterfaceType) or isinstance(rt, t.InterfaceType)) and op in ("EQ", "NE"):
            others = [(ty, ex) for ty, ex in ((lt, le), (rt, re_)) if not isinstance(ty, t.InterfaceType)]
            return all(isinstance(ty, t.FBType) or (isinstance(ty, t.RefType) and ty.is_null) or self.is_zero_literal(ex)
                       for ty, ex in others)
        if isinstance(lt, t.RefType) and isinstance(rt, t.RefType) and op in ("EQ", "NE"):
            return lt.is_null or rt.is_null or t.same_type(lt.target, rt.target) \
                or (self.byte_pointer(lt) and self.byte_pointer(rt))
        if op in ("EQ", "NE") and (self.byte_pointer(lt) and self.is_zero_literal(re_)
                                   or self.byte_pointer(rt) and self.is_zero_literal(le)):
            return True   # TwinCAT/CODESYS: `p = 0` tests for the NULL address
        return False

    def time_arith(self, e: n.Binary, lt: t.Type, rt: t.Type) -> t.Type | None:
        """IEC table 30 on the TIME family; a long operand (LTIME, LDT, …) makes the result long."""
        op = e.op
        ln, rn = getattr(lt, "family", lt.name), getattr(rt, "family", rt.name)
        long = getattr(lt, "long", False) or getattr(rt, "long", False)
        if op == "PLUS":
            if ln == rn == "TIME":
                return t.time_type("TIME", long)
            if ln in ("DATE_AND_TIME", "TIME_OF_DAY") and rn == "TIME":
                return t.time_type(ln, long)
            if rn in ("DATE_AND_TIME", "TIME_OF_DAY") and ln == "TIME":
                return t.time_type(rn, long)
        if op == "MINUS":
            if ln == rn:
                return t.time_type("TIME", long)
            if ln in ("DATE_AND_TIME", "TIME_OF_DAY") and rn == "TIME":
                return t.time_type(ln, long)
        if op in ("STAR", "SLASH") and ln == "TIME" and isinstance(rt, (t.IntType, t.RealType)):
            return lt
        if op == "STAR" and rn == "TIME" and isinstance(lt, (t.IntType, t.RealType)):
            return rt
        self.error(f"operator {OP_TEXT.get(op, op)} cannot be applied to {lt.name} and {rt.name}", e.span, "E039")
        return None

    def describe(self, e: n.Expr) -> str:
        if isinstance(e, n.Name):
            return e.text
        if isinstance(e, n.Member):
            return f"{self.describe(e.base)}.{e.name}"
        if isinstance(e, n.Index):
            return f"{self.describe(e.base)}[…]"
        if isinstance(e, n.Deref):
            return f"{self.describe(e.base)}^"
        if isinstance(e, n.Call):
            return f"{self.describe(e.callee)}(…)"
        return "expression"

    # ---- calls
    def expr_Call(self, e: n.Call, expected, statement: bool) -> t.Type | None:
        callee = e.callee
        pou: POUInfo | None = None
        instance: n.Expr | None = None
        if isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in ("__QUERYINTERFACE", "__ISVALIDREF") \
                and self.lookup_callable(callee) is None:
            return self.intrinsic(e, callee.parts[0].upper())
        if isinstance(callee, (n.Member, n.Deref)) or (self.fb is not None and isinstance(callee, n.Name)):
            done, ty = self.oo_call(e, expected, statement)
            if done:
                return ty
        if isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in ("REF", "ADR") \
                and self.resolve_name(callee) is None and self.lookup_callable(callee) is None:
            return self.reference_of(e)
        if isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in TYPE_QUERIES \
                and self.resolve_name(callee) is None and self.lookup_callable(callee) is None:
            return self.type_query(e, callee.parts[0].upper())
        if isinstance(callee, n.Name):
            ref = self.resolve_name(callee) if len(callee.parts) == 1 else None
            if ref is not None and getattr(ref, "variable", None) is not None and isinstance(ref.variable.type, t.FBType):  # type: ignore[attr-defined]
                self.expr(callee)
                instance = callee
            elif ref is not None and ref.kind != "result":  # type: ignore[attr-defined]
                self.expr(callee)
                self.error(f"'{callee.text}' is {ref.variable.type.name}, not a function or function block instance", callee.span, "E045")  # type: ignore[attr-defined]
                self.check_args_loosely(e)
                return None
            else:
                pou = self.lookup_callable(callee)
                if pou is None:
                    self.error(f"unknown function '{callee.text}'", callee.span, "E045")
                    self.check_args_loosely(e)
                    return None
                if pou.kind != "FUNCTION":
                    self.error(f"'{callee.text}' is a {pou.kind.lower().replace('_', ' ')} type; call an instance of it", callee.span, "E045")
                    self.check_args_loosely(e)
                    return None
        else:
            ty = self.expr(callee)
            if ty is None:
                self.check_args_loosely(e)
                return None
            if not isinstance(ty, t.FBType):
                self.error(f"'{self.describe(callee)}' is {ty.name}, not a function block instance", callee.span, "E045")
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
                self.error(f"a function block call is a statement; read its outputs as {self.describe(instance)}.Q", e.span, "E045")
            info = CallInfo(pou, True, instance)
            self.bind_args(e, pou, info, fb=True)
            self.facts.calls[e.nid] = info
            return t.VOID
        assert pou is not None
        info = CallInfo(pou, False, None)
        outer, self.call_expected = getattr(self, "call_expected", None), expected
        try:
            self.bind_args(e, pou, info, fb=False)
        finally:
            self.call_expected = outer
        self.facts.calls[e.nid] = info
        ret = pou.return_type
        if ret is None:
            return t.VOID   # a FUNCTION without a result (TwinCAT/CODESYS `void_function`)
        if isinstance(ret, t.GenericType):
            ret = info.generic_type
            if ret is None:
                if e.nid not in self.rejected_calls:
                    self.error(f"cannot infer the result type of {pou.name}", e.span, "E046")
                return None
        return ret

    def check_args_loosely(self, e: n.Call) -> None:
        for arg in e.args:
            if arg.kind in ("input", "positional"):
                self.expr(arg.value)

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
                    self.expr(arg.value)
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
                target_type = self.lvalue(arg.value)
                if self.is_property(arg.value, f"the output {arg.name}"):
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
                expected = getattr(self, "call_expected", None)
                if pou.qualname.upper() == "TRUNC" and isinstance(expected, t.IntType) \
                        and not expected.bitstring and trunc_result_from_context(self.settings):
                    info.generic_type = expected   # IEC: TRUNC is ANY_REAL -> ANY_INT
            except Exception as exc:  # a rule rejecting its arguments is a type error in the user's call
                self.error(f"{self.display(pou)}: {exc}", e.span, "E046")
                self.rejected_calls = self.rejected_calls | {e.nid}
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
                ty = self.wstring_literal(ex)
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
        expected = getattr(self, "call_expected", None)
        out = []
        for ty, ex in zip(arg_types, exprs):
            if ex is None or ex.nid not in self.facts.untyped or not isinstance(ty, (t.IntType, t.RealType)):
                out.append(ty)
                continue
            candidates = [c for c in typed if self.literal_fits(ex, c) and (isinstance(c, t.RealType) or isinstance(ty, t.IntType))]
            if candidates:
                out.append(candidates[0])
            elif not typed and isinstance(expected, (t.IntType, t.RealType)) and self.literal_fits(ex, expected) \
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
            ty = self.expr(arg.value, expected=t.BOOL)
            if ty is not None:
                self.require_assignable(arg.value, ty, t.BOOL, arg.value.span)
            info.en = arg.value
        elif word == "ENO" and arg.kind in ("output", "output_not") and pou.pin("ENO") is None:
            ty = self.lvalue(arg.value)
            if ty is not None and not isinstance(ty, t.BoolType):
                self.error(f"ENO is BOOL; cannot bind it to {ty.name}", arg.span, "E052")
            info.eno = (arg.value, arg.kind == "output_not")
        else:
            return False
        if getattr(self, "en_call", None) is not call:
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
                aty = self.expr(arg.value)
                base_ty = self.facts.types.get(arg.value.base.nid)
                if aty is not None and isinstance(base_ty, t.ArrayType) and self.element_ok(aty, ptype.element):
                    self.facts.array_from_element.add(arg.value.nid)
                    self.lvalue_check_only(arg.value)
                    info.inputs.append((var, arg.value))
                    return
                ty = aty
            elif isinstance(ptype, t.FBType) and self.is_lvalue_shape(arg.value):
                ty = self.expr(arg.value)   # an FB instance passed by reference
            else:
                ty = self.lvalue(arg.value) if self.is_lvalue_shape(arg.value) else None
                if self.is_property(arg.value, f"the in-out {var.name}"):
                    return
                if ty is None and not self.is_lvalue_shape(arg.value):
                    self.expr(arg.value)
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
            aty = self.expr(arg.value)
            base_ty = self.facts.types.get(arg.value.base.nid)
            if aty is not None and isinstance(base_ty, t.ArrayType) and self.element_ok(aty, ptype.element):
                self.facts.array_from_element.add(arg.value.nid)
                info.inputs.append((var, arg.value))
            return
        ty = self.expr(arg.value, expected=ptype if not isinstance(ptype, t.GenericType) else None)
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
            self.require_assignable(arg.value, ty, ptype, arg.value.span)
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
        if self.is_constant_path(e):
            self.error("cannot pass a constant as an in-out", e.span, "E053")

