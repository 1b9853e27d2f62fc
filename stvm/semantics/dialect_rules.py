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

