"""The typing rules the body checks share (IEC 61131-3 + Sysmac rules).

Typing rules follow docs/sysmac.md section 2:
* integer results take the highest-ranked operand type (signed+unsigned of one rank → unsigned) and
  wrap at that width *before* any widening for the assignment;
* an untyped integer literal takes the other operand's type when it fits, else DINT (LINT when
  it does not fit DINT, or always LINT with `int_literal_type=lint`);
* implicit conversions are the widening chart plus same-size signed↔unsigned; anything else is an
  error that names the conversion function to use.
"""

from __future__ import annotations


from stvm.semantics import types as t
from stvm.semantics.model import POUInfo
from stvm.settings import IntLiteralType


_ARITH = {"PLUS": "+", "MINUS": "-", "STAR": "*", "SLASH": "/", "MOD": "MOD", "POW": "**"}
COMPARE_OPS = {"EQ": "=", "NE": "<>", "LT": "<", "GT": ">", "LE": "<=", "GE": ">="}
LOGIC_OPS = {"AND": "AND", "AMP": "AND", "OR": "OR", "XOR": "XOR", "AND_THEN": "AND_THEN", "OR_ELSE": "OR_ELSE"}
OP_TEXT = {**_ARITH, **COMPARE_OPS, **LOGIC_OPS, "NOT": "NOT"}
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


def with_access(method: POUInfo, access: str) -> POUInfo:
    """A property accessor checked with its property's access specifier."""
    return method.replace(access=access)


def native_result_rule(pou: POUInfo, natives):
    """The stdlib's result-type rule for a generic native (SHL, MUX, TRUNC, …), if it has one;
    `natives`: the native functions the checker was given (stvm.stdlib.NATIVE_FUNCTIONS)."""
    if not pou.native or pou.kind != "FUNCTION":
        return None
    native = natives.get(pou.qualname.split("\\")[-1].upper())
    return native.result_rule if native is not None else None
