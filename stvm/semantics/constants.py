"""Pass 2 of the checker, its other half: compile-time constants (docs/architecture.md,
"Checker passes").

`ConstantEvaluator` folds constant expressions (array bounds, string sizes, CASE labels, initial
values), converts a constant to the type it initialises and records `fb : F := (x := 1)` instance
initialisers for `InstanceInits`. It reads the globals and POU constants declared so far.
"""

from __future__ import annotations

import math
import weakref

from stvm.dialects import allows
from stvm.numeric import f32, utf16_units
from stvm.semantics import types as t
from stvm.semantics import dialect_rules
from stvm.semantics.context import CheckContext, Pass
from stvm.semantics.facts import NOT_CONST
from stvm.semantics.model import (SiblingInstance, EXTERNAL, IN_OUT, POUInfo)
from stvm.settings import BareEnumerators
from stvm.syntax import nodes as n


def _round_real(value: float, ty: t.Type) -> float:
    if isinstance(ty, t.RealType) and ty.bits == 32:
        return f32(value)
    return float(value)


def _time_compatible(literal_type: str, target: str) -> bool:
    """May a T#/D#/TOD#/DT# literal (or its long form) initialise a variable of `target`?"""
    literal, wanted = t.ELEMENTARY[literal_type], t.ELEMENTARY[target]
    return literal.family == wanted.family and (wanted.long or not literal.long)  # type: ignore[attr-defined]


class ConstantEvaluator(Pass):
    """Compile-time values of constant expressions (module docstring)."""

    def __init__(self, ctx: CheckContext, types) -> None:
        super().__init__(ctx)
        # resolve.TypeResolver, which holds this evaluator: a weak reference, since a cycle would
        # keep the check (and its syntax tree) alive after a load until the collector runs
        # (tests/test_load_garbage.py)
        self.types = weakref.proxy(types)
        types.constants = self

    def const_int(self, expr: n.Expr, namespace: tuple[str, ...]) -> int | None:
        value = self.const_value(expr, namespace, self.ctx.declaring)
        if isinstance(value, bool) or not isinstance(value, int):
            if value is not NOT_CONST:
                self.error("expected a constant integer", expr.span, "E020")
            else:
                self.error("expected a constant integer expression", expr.span, "E020")
            return None
        return value

    def const_value(self, expr: n.Expr, namespace: tuple[str, ...], pou: POUInfo | None) -> object:
        """Evaluate a constant expression at compile time; `NOT_CONST` if it is not one."""
        if isinstance(expr, n.Call):
            # LOWER_BOUND/UPPER_BOUND of a declared array, SIZEOF: constants once checked
            word, value = self.ctx.facts.type_queries.get(expr.nid, ("", None))
            if word == "CONST":
                return value
            return self.declared_sizeof(expr, namespace, pou)
        if isinstance(expr, (n.IntLiteral, n.BoolLiteral, n.StringLiteral)):
            return expr.value
        if isinstance(expr, n.RealLiteral):
            return expr.value
        if isinstance(expr, n.TimeLiteral):
            return expr.value_ns
        if isinstance(expr, n.HashLiteral):
            lit = self.hash_literal(expr, namespace, report=False)
            return NOT_CONST if lit is None else lit[1]
        if isinstance(expr, n.Unary):
            v = self.const_value(expr.operand, namespace, pou)
            if v is NOT_CONST:
                return v
            if expr.op == "MINUS" and isinstance(v, (int, float)) and not isinstance(v, bool):
                return -v
            if expr.op == "PLUS":
                return v
            if expr.op == "NOT" and isinstance(v, bool):
                return not v
            return NOT_CONST
        if isinstance(expr, n.Binary):
            a = self.const_value(expr.left, namespace, pou)
            b = self.const_value(expr.right, namespace, pou)
            if a is NOT_CONST or b is NOT_CONST or isinstance(a, (bytes, bool)) or isinstance(b, (bytes, bool)):
                return NOT_CONST
            try:
                if expr.op == "PLUS":
                    return a + b
                if expr.op == "MINUS":
                    return a - b
                if expr.op == "STAR":
                    return a * b
                if expr.op == "SLASH":
                    if isinstance(a, int) and isinstance(b, int):
                        q = abs(a) // abs(b)
                        return q if (a < 0) == (b < 0) else -q
                    return a / b
                if expr.op == "MOD" and isinstance(a, int) and isinstance(b, int):
                    return int(math.fmod(a, b))
            except ZeroDivisionError:
                return NOT_CONST
            return NOT_CONST
        if isinstance(expr, n.Name) and len(expr.parts) == 1:
            key = expr.parts[0].lower()
            var = pou.variables.get(key) if pou else None
            if var is None:
                var = self.ctx.globals.get(key)
            if var is not None:
                if var.constant and var.init is not None:
                    return var.init
                return NOT_CONST
            enum = self.bare_enumerator(expr.parts[0], expr.span, report=False)
            if enum is not None:
                return enum[1]
        return NOT_CONST

    def declared_sizeof(self, expr: n.Call, namespace: tuple[str, ...], pou: POUInfo | None) -> object:
        """SIZEOF(T) / SIZEOF(v) in a declaration (an array bound: `ARRAY[0..n * SIZEOF(ST_X) - 1]`),
        before any body is checked: the size of the named type, or of a declared variable's type."""
        callee = expr.callee
        if not (isinstance(callee, n.Name) and len(callee.parts) == 1 and callee.parts[0].upper() in ("SIZEOF", "XSIZEOF")
                and len(expr.args) == 1 and expr.args[0].kind == "positional" and isinstance(expr.args[0].value, n.Name)):
            return NOT_CONST
        arg = expr.args[0].value
        var = None
        if len(arg.parts) == 1:
            key = arg.parts[0].lower()
            var = (pou.variables.get(key) if pou else None) or self.ctx.globals.get(key)
        if var is not None:
            ty = var.type
        elif (len(arg.parts) == 1 and arg.parts[0].upper() in t.ELEMENTARY) \
                or self.ctx.index.lookup_type_key(arg.parts, False, namespace) is not None:
            ty = self.types.resolve_type_spec(n.NamedTypeSpec(arg.parts, False, arg.span), namespace)
        else:
            return NOT_CONST
        size = t.byte_size(ty, allows(self.ctx.settings.dialect, "short_times")) if ty is not None else None
        return NOT_CONST if size is None else size

    def bare_enumerator(self, name: str, span: n.Span, report: bool = True) -> tuple[t.EnumType, int] | None:
        cands = self.ctx.enumerators.get(name.lower(), [])
        if not cands:
            return None
        if self.ctx.settings.bare_enumerators is BareEnumerators.REQUIRE_TYPE:
            if report:
                self.error(f"enumerator '{name}' needs its type: write Type#{name}", span, "E021")
            return None
        distinct = {c[0].qualname.lower(): c for c in cands}
        if len(distinct) > 1:
            if report:
                names = ", ".join(sorted(c[0].name for c in distinct.values()))
                self.error(f"enumerator '{name}' is ambiguous (in {names}); write Type#{name}", span, "E021")
            return None
        return cands[0]

    def hash_literal(self, expr: n.HashLiteral, namespace: tuple[str, ...], report: bool = True) -> tuple[t.Type, object] | None:
        """Resolve `Prefix#value`: (type, runtime value) or None (with a diagnostic when `report`)."""
        prefix = expr.prefix
        if len(prefix) == 1 and prefix[0].upper() in t.ELEMENTARY and not expr.rooted:
            ty = t.ELEMENTARY[prefix[0].upper()]
            text = expr.text
            try:
                if isinstance(ty, t.IntType):
                    value = int(text.replace("_", "").split("#")[-1], int(text.split("#")[0]) if text.count("#") else 10) \
                        if "#" in text else int(text.replace("_", ""))
                    if text.startswith("-") and "#" in text:
                        value = -int(text[1:].replace("_", "").split("#")[1], int(text[1:].split("#")[0]))
                    if not ty.lo <= value <= ty.hi:
                        if report:
                            self.error(f"{value} is out of range for {ty.name} ({ty.lo}..{ty.hi})", expr.span, "E022")
                        return None
                    return ty, value
                if isinstance(ty, t.RealType):
                    value = float(text.replace("_", ""))
                    return ty, _round_real(value, ty)
                if isinstance(ty, t.BoolType):
                    if text.upper() in ("TRUE", "1"):
                        return ty, True
                    if text.upper() in ("FALSE", "0"):
                        return ty, False
            except ValueError:
                pass
            if report:
                self.error(f"malformed typed literal '{prefix[0]}#{text}'", expr.span, "E022")
            return None
        key = self.ctx.index.lookup_type_key(prefix, expr.rooted, namespace)
        if key is None:
            # Sysmac listings sometimes print the enum type without its leading 'e' (sysmac.md 3 #1):
            # that stays an error; the restored source fixes it.
            if report:
                self.error(f"unknown enumeration type '{chr(92).join(prefix)}' in '{chr(92).join(prefix)}#{expr.text}'", expr.span, "E018")
            return None
        ty = self.types.resolve_declared_type(key)
        if not isinstance(ty, t.EnumType):
            if report:
                self.error(f"'{chr(92).join(prefix)}' is not an enumeration type", expr.span, "E018")
            return None
        value = ty.value_of(expr.text)
        if value is None:
            if report:
                self.error(f"'{expr.text}' is not an enumerator of {ty.name}", expr.span, "E016")
            return None
        return ty, value

    def initial_value(self, init: n.Initializer, ty: t.Type, namespace: tuple[str, ...], pou: POUInfo | None) -> object:
        """Compile-time initial value in runtime representation (structs: dict, arrays: list)."""
        if isinstance(init, n.ExprInit):
            if isinstance(ty, t.ArrayType) and ty.dims:
                # `ARRAY … := 5` is not an initialiser for the whole array
                self.error("an array initialiser is written in brackets: [1, 2, 3(0)]", init.span, "E023")
                return None
            value = self.const_value(init.expr, namespace, pou)
            if value is NOT_CONST:
                if isinstance(init.expr, n.Name) and len(init.expr.parts) == 1 and isinstance(ty, t.EnumType):
                    v = ty.value_of(init.expr.parts[0])
                    if v is not None:
                        return v
                sibling = self.sibling_instance(init.expr, ty, pou)
                if sibling is not None:
                    return sibling
                address = dialect_rules.address_initial_value(self, init.expr, ty, namespace, pou)
                if address is not None:   # REF(x) / ADR(x): an AddressInit, or False when refused
                    return address or None
                self.error("initial value must be a constant expression", init.span, "E023")
                return None
            if isinstance(ty, t.EnumType) and isinstance(init.expr, n.Name):
                v = ty.value_of(init.expr.parts[0])
                if v is not None:
                    return v
            return self.convert_constant(value, ty, init.span, init.expr)
        if isinstance(init, n.ArrayInit):
            if not isinstance(ty, t.ArrayType) or not ty.dims:
                self.error(f"an array initialiser cannot initialise {ty.name}", init.span, "E023")
                return None
            values: list = []
            for count, item in init.items:
                v = self.initial_value(item, ty.element, namespace, pou) if item is not None else None
                values.extend([v] * count)
            if len(values) > ty.length:
                self.error(f"{len(values)} initial values for an array of {ty.length} elements", init.span, "E023")
                values = values[: ty.length]
            return values
        if isinstance(init, n.StructInit) and isinstance(ty, t.FBType):
            return self.fb_instance_init(init, ty, namespace, pou)
        if isinstance(init, n.StructInit):
            if not isinstance(ty, t.StructType):
                self.error(f"a structure initialiser cannot initialise {ty.name}", init.span, "E023")
                return None
            out = {}
            for fname, finit in init.items:
                ftype = ty.field_type(fname)
                if ftype is None:
                    self.error(f"{ty.name} has no member '{fname}'", finit.span, "E024")
                    continue
                out[fname.lower()] = self.initial_value(finit, ftype, namespace, pou)
            return out
        return None

    def fb_instance_init(self, init: n.StructInit, ty: t.FBType, namespace: tuple[str, ...],
                         pou: POUInfo | None) -> dict:
        """`fb : F := (x := 1, y := 2)` (IEC 61131-3 ed. 3 6.5.2.2, CODESYS): the instance's inputs,
        outputs and internal variables set at its creation, as {variable key: value}. The FB's
        variables (and its base's) may not be declared yet when a global or an earlier POU is:
        the dict is filled in place once every POU is (`resolve_fb_instance_inits`)."""
        out: dict = {}
        self.ctx.fb_instance_inits.append((out, init, ty, namespace, pou))
        return out

    def sibling_instance(self, expr: n.Expr, ty: t.Type, pou: POUInfo | None, before: str | None = None):
        """`itf : I_X := fbOther;` or `fb : F(fbOther)` (TwinCAT/CODESYS, the `ref_initial_value`
        row): an interface given an FB instance declared earlier in the same FUNCTION_BLOCK or
        PROGRAM (TcUnit's FB_TcUnitRunner). None when `expr` is not such an instance. Choice: the
        instance must be declared before, as it is made first."""
        if not (isinstance(expr, n.Name) and len(expr.parts) == 1 and pou is not None
                and pou.kind in ("FUNCTION_BLOCK", "PROGRAM") and isinstance(ty, t.InterfaceType)
                and allows(self.ctx.settings.dialect, "ref_initial_value")):
            return None
        keys = list(pou.variables)
        key = expr.parts[0].lower()
        var = pou.variables.get(key)
        if var is None or not isinstance(var.type, t.FBType) or var.section in (IN_OUT, EXTERNAL):
            return None
        if before is not None and before in keys and keys.index(key) > keys.index(before):
            return None
        return SiblingInstance(var.name)

    def convert_constant(self, value: object, ty: t.Type, span: n.Span, expr: n.Expr | None = None) -> object:
        if isinstance(ty, t.BoolType):
            if isinstance(value, bool):
                return value
            if isinstance(expr, n.IntLiteral) and value in (0, 1):
                return bool(value)   # IEC 61131-3 ed. 3 table 5: 0 and 1 are BOOL literals
        elif isinstance(ty, t.IntType):
            if isinstance(value, int) and not isinstance(value, bool):
                if not ty.lo <= value <= ty.hi:
                    typed = isinstance(expr, n.HashLiteral)
                    if not typed:
                        self.error(f"{value} is out of range for {ty.name} ({ty.lo}..{ty.hi})", span, "E022")
                        return None
                    value = ty.wrap(value)
                if isinstance(ty, t.SubrangeType) and not ty.low <= value <= ty.high:
                    self.error(f"{value} is outside the subrange {ty.text}", span, "E022")
                    return None
                return value
        elif isinstance(ty, t.RealType):
            if isinstance(value, (int, float)) and not isinstance(value, bool):
                return _round_real(float(value), ty)
        elif t.is_wide(ty):
            return self.wstring_initial_value(value, ty, span)
        elif isinstance(ty, t.StringType):
            if isinstance(value, str):
                self.error(f"a WSTRING literal cannot initialise {ty.name}: write STRING literals in single "
                           "quotes, or convert with WSTRING_TO_STRING", span, "E023")
                return None
            if isinstance(value, bytes):
                if len(value) > ty.max_bytes:
                    self.string_overflow(len(value), ty, span, initial=True)
                    return value[: ty.max_bytes]
                return value
        elif isinstance(ty, t.TimeType):
            if isinstance(value, int) and not isinstance(value, bool) and expr is not None:
                if isinstance(expr, n.TimeLiteral) and _time_compatible(expr.type_name, ty.name):
                    return value
                if not isinstance(expr, n.TimeLiteral) and not isinstance(expr, n.IntLiteral):
                    return value
        elif isinstance(ty, t.EnumType):
            if isinstance(value, int) and isinstance(expr, (n.HashLiteral, n.Name)):
                return value
        self.error(f"initial value does not fit type {ty.name}", span, "E023")
        return None

    def wstring_initial_value(self, value: object, ty: t.StringType, span: n.Span) -> object:
        """The initial value of a WSTRING: a WSTRING literal, or a STRING literal taken as its
        characters (CODESYS accepts `ws : WSTRING := 'abc'`)."""
        if isinstance(value, bytes):
            value = utf16_units(value.decode("utf-8", "replace"))
        if not isinstance(value, str):
            self.error(f"initial value does not fit type {ty.name}", span, "E023")
            return None
        if len(value) > ty.max_bytes:
            self.string_overflow(len(value), ty, span, initial=True)
            return value[: ty.max_bytes]
        return value
