"""Language rules that differ between dialects (stvm/dialects.py rows), kept out of the checker's
passes so that each rule is one function the passes call with a line.

Enumerations (rows `enum_integer`, `enum_strict_attribute`, `enum_to_string_attribute`): in
TwinCAT and CODESYS an enumeration mixes with integers unless its declaration carries
`{attribute 'strict'}`. Beckhoff Infosys, TwinCAT 3 PLC "Attribute 'strict'" lists what the
attribute refuses: arithmetic on values of the enumeration, assigning it a constant that is none
of its values, and assigning it a non-constant value of another type. Reading an enumeration into
an integer stays allowed with 'strict' (the same pages' example `nCurrentValue := eSample;` on a
strict enumeration). IEC 61131-3 and Sysmac keep every enumeration a distinct type.
"""

from __future__ import annotations

from stvm.dialects import allows
from stvm.semantics import types as t
from stvm.semantics.model import EXTERNAL, IN_OUT, TEMP, AddressInit
from stvm.syntax import nodes as n
from stvm.syntax.pragmas import has_attribute


def enum_attributes(enum: t.EnumType, pragmas: tuple[str, ...], settings) -> t.EnumType:
    """`enum` with the 'strict' and 'to_string' attributes of its declaration's pragmas, in the
    dialects that have them (IEC and Sysmac have no attributes: every enumeration is strict there
    and TO_STRING gives its number)."""
    strict = has_attribute(pragmas, "strict") and allows(settings.dialect, "enum_strict_attribute")
    to_string = has_attribute(pragmas, "to_string") and allows(settings.dialect, "enum_to_string_attribute")
    if not (strict or to_string):
        return enum
    return t.EnumType(enum.name, enum.qualname, enum.members, enum.base, enum.default, strict, to_string)


def mixes_with_integers(settings, ty: t.Type | None) -> bool:
    """An enumeration that arithmetic and assignments take as its integer value."""
    return isinstance(ty, t.EnumType) and not ty.strict and allows(settings.dialect, "enum_integer")


def as_integer(settings, ty: t.Type | None) -> t.Type | None:
    """The integer base type of a non-strict enumeration of TwinCAT/CODESYS, else `ty`."""
    if mixes_with_integers(settings, ty):
        return ty.base if isinstance(ty.base, t.IntType) else t.INT   # type: ignore[union-attr]
    return ty


def binary_operands(settings, lt: t.Type, rt: t.Type) -> tuple[t.Type, t.Type]:
    """The operand types an operator sees: a non-strict enumeration beside anything but its own
    type is its integer value (`E.B + 1`, `e = 3`); two values of one enumeration stay that."""
    if isinstance(lt, t.EnumType) and isinstance(rt, t.EnumType) and lt.qualname.lower() == rt.qualname.lower():
        return lt, rt
    return as_integer(settings, lt), as_integer(settings, rt)   # type: ignore[return-value]


def enum_compares_with_integer(settings, lt: t.Type, rt: t.Type) -> bool:
    """A strict enumeration compared with an integer: allowed in TwinCAT/CODESYS (a comparison is
    no arithmetic and the attribute's list does not name it; stvm's choice, docs/dialects.md)."""
    kinds = {type(lt), type(rt)}
    return (allows(settings.dialect, "enum_integer") and t.EnumType in kinds
            and kinds <= {t.EnumType, t.IntType, t.SubrangeType})


def enum_assignable(settings, src: t.Type, dst: t.Type, constant) -> bool:
    """An enumeration assigned to an integer, or an integer (`constant`: its value when it is one,
    else None) to an enumeration, in a dialect where they mix."""
    if not allows(settings.dialect, "enum_integer"):
        return False
    if isinstance(src, t.EnumType) and isinstance(dst, t.IntType):
        return True
    if isinstance(src, t.IntType) and isinstance(dst, t.EnumType):
        if not dst.strict:
            return True
        return isinstance(constant, int) and not isinstance(constant, bool) and dst.name_of(constant) is not None
    return False


# ---- REF(variable) / ADR(variable) as an initial value (row `ref_initial_value`) -----------------
# CODESYS V3 online help "REF_TO" / "Data Type: Reference", Beckhoff Infosys "Pointers" /
# "References" and RuSTy: the address of a variable is known when the application is loaded, so
# it may initialise a REF_TO / POINTER TO. stvm binds it when the instance (or the globals) are
# made, in declaration order: the variable must be declared before the reference (an aggregate
# object must exist to be referred to), in the same PROGRAM/FUNCTION_BLOCK or among the globals.

_ADDRESS_FUNCTIONS = ("REF", "ADR")


def is_address_call(expr: n.Expr) -> bool:
    return (isinstance(expr, n.Call) and isinstance(expr.callee, n.Name) and len(expr.callee.parts) == 1
            and expr.callee.parts[0].upper() in _ADDRESS_FUNCTIONS)


def address_initial_value(ev, expr: n.Expr, ty: t.Type, namespace: tuple[str, ...], pou):
    """The AddressInit of `expr` (`REF(x)` / `ADR(x)`) for a variable of type `ty` declared in
    `pou` (None: a global), or None when `expr` is no such call or the dialect has none. Reports
    what it refuses through the constant evaluator `ev` (constants.py) and then returns False."""
    if not is_address_call(expr):
        return None
    func = expr.callee.parts[0].upper()   # type: ignore[attr-defined]
    span = expr.span
    if not allows(ev.ctx.settings.dialect, "ref_initial_value"):
        return None   # Sysmac: the checker's "initial value must be a constant expression", as before
    if not isinstance(ty, t.RefType) or ty.flavour == "REFERENCE":
        ev.error(f"{func}() can initialise a REF_TO or POINTER TO variable, not {ty.name}", span, "E052")
        return False
    if len(expr.args) != 1 or expr.args[0].kind != "positional":
        ev.error(f"{func}() takes one variable", span, "E023")
        return False
    if pou is not None and pou.kind not in ("FUNCTION_BLOCK", "PROGRAM"):
        ev.error(f"{func}() as an initial value is bound when an instance is made: only in a PROGRAM, a "
                "FUNCTION_BLOCK or VAR_GLOBAL, not in a {kind}".replace("{kind}", pou.kind), span, "E023")
        return False
    found = _address_steps(ev, expr.args[0].value, namespace, pou)
    if found is None:
        ev.error(f"{func}() as an initial value takes a variable declared before, in the same "
                "PROGRAM/FUNCTION_BLOCK or in VAR_GLOBAL, its members and elements at constant indices",
                expr.args[0].value.span, "E023")
        return False
    scope, steps, target = found
    if not t.same_type(target, ty.target):
        ev.error(f"type mismatch: cannot initialise {ty.name} with {func}() of a {target.name}", span, "E052")
        return False
    _note_addressed(ev.ctx, pou, steps)
    return AddressInit(scope, tuple(steps), t.is_aggregate(target))


def _note_addressed(ctx, pou, steps) -> None:
    """The lowering keeps a referenced variable in its instance (never in a Python local)."""
    if pou is not None:
        ctx.facts.addressed.add((pou.key, str(steps[0][1]).lower()))


def _address_steps(ev, expr: n.Expr, namespace: tuple[str, ...], pou):
    """(scope, steps, type) of a variable path made of a name, members and constant indices."""
    if isinstance(expr, n.Name) and len(expr.parts) == 1 and not expr.rooted:
        key = expr.parts[0].lower()
        var = pou.variables.get(key) if pou is not None else None
        if var is not None and var.section in (IN_OUT, TEMP):
            return None
        if var is None or var.section == EXTERNAL:
            var = ev.ctx.globals.get(key)
            if var is None:
                return None
            return "global", [("field", var.name)], var.type
        return "self", [("field", var.name)], var.type
    if isinstance(expr, n.Member):
        inner = _address_steps(ev, expr.base, namespace, pou)
        if inner is None or not isinstance(inner[2], t.StructType) or isinstance(inner[2], t.UnionType):
            return None
        scope, steps, ty = inner
        name = ty.field_name(expr.name)
        if name is None:
            return None
        return scope, steps + [("field", name)], ty.field_type(name)
    if isinstance(expr, n.Index):
        inner = _address_steps(ev, expr.base, namespace, pou)
        if inner is None or not isinstance(inner[2], t.ArrayType) or not inner[2].dims \
                or len(expr.indices) != len(inner[2].dims):
            return None
        scope, steps, ty = inner
        for index, (lo, hi) in zip(expr.indices, ty.dims):
            value = ev.const_value(index, namespace, pou)
            if not (isinstance(value, int) and not isinstance(value, bool) and lo <= value <= hi):
                return None
            steps = steps + [("item", value - lo)]
        return scope, steps, ty.element
    return None


# ---- an assignment used as an expression (row `assignment_expression`) ---------------------------
# CODESYS V3 online help / Beckhoff Infosys "ExST assignment as expression": `a := b := c + 9`
# gives both the value; `IF b := (i = 1) THEN` tests the value stored; `int := real := int` is an
# error, so the value has the target's type. stvm stores through a reference to the target
# (evaluated first: left to right, the target written once), so the target is kept in its
# instance or frame, never in a Python local.

def check_assign_expr(b, e: n.AssignExpr) -> t.Type | None:
    """Check `target := value` inside an expression on the body checker `b` (body.py); its type
    is the target's."""
    target_type = b.lvalue(e.target)
    value_type = b.expr(e.value, expected=target_type)
    if target_type is None or value_type is None:
        return None
    b.stmts.require_assignable(e.value, value_type, target_type, e.value.span)
    target = e.target
    ref = b.facts.names.get(target.nid) if isinstance(target, n.Name) else None
    if t.is_aggregate(target_type) or isinstance(target, (n.BitAccess, n.PartialAccess)) \
            or (b.facts.props and target.nid in b.facts.props) or getattr(ref, "kind", None) == "result":
        b.error(f"an assignment used as an expression needs a variable of an elementary type as its target "
                f"(not {target_type.name}, a bit, a property or a function's result)", target.span, "E050")
        return None
    b.stmts.mark_addressed(target)
    return target_type
