"""The ST type model shared by the checker, the code generator, the runtime and the stdlib.

Types are frozen value records so they can be compared, hashed and pickled into the load cache.
Elementary types are singletons in `ELEMENTARY`; derived types are built by the checker.

They behave as `dataclass(frozen=True)` classes did (the same `__init__` parameters, `==` of
the same class and fields, `hash`, `repr`, assignment raising `FrozenInstanceError`, the
instance `__dict__` that pickle stores), but are written out: `dataclass` builds each class's
methods with `exec` when the module is imported, ~10 ms of every `stvm run` for these 17
classes (issue 33 item 5). Each class writes its `__init__` and lists its fields in `_FIELDS`
(and `_COMPARED` where `==` leaves some out); `stvm.records.FrozenRecord` derives `==`, `hash`
and `repr` from them. A test compares every class with the dataclass it replaces
(tests/semantics/test_types_records.py).

Runtime representation of each type (what generated code and native POUs see):

| ST type                         | Python value                                          |
|---------------------------------|-------------------------------------------------------|
| BOOL                            | bool                                                  |
| SINT…LINT, USINT…ULINT, BYTE…   | int, always inside the type's range (wrapped)         |
| REAL                            | float holding a value exactly representable in binary32 |
| LREAL                           | float                                                 |
| TIME, DATE, TOD, DT             | int nanoseconds (DATE/TOD/DT: since 1970-01-01)       |
| STRING[n]                       | bytes, at most n-1 bytes, never containing 16#00      |
| WSTRING[n]                      | str of UTF-16 code units (one Python character per code unit, 0..16#FFFF; a character outside the BMP is its two surrogates), at most n units |
| enum                            | int (the enumerator's value)                          |
| STRUCT                          | instance of the generated struct class (attributes `v_<name>`) |
| ARRAY                           | list (nested lists for several dimensions)            |
| FUNCTION_BLOCK                  | instance of the generated/native FB class             |
"""

from __future__ import annotations

from stvm.records import FrozenRecord

_set = object.__setattr__


class Type(FrozenRecord):
    """An ST data type as the checker and the lowering see it; `name` is the user's spelling."""

    _FIELDS = ("name",)

    def __init__(self, name: str) -> None:
        _set(self, "name", name)

    @property
    def kind(self) -> str:
        return "type"

    def __str__(self) -> str:
        return self.name


class BoolType(Type):
    """BOOL."""

    @property
    def kind(self) -> str:
        return "bool"


class IntType(Type):
    """Signed/unsigned integers and bit strings (BYTE…LWORD are unsigned, `bitstring`)."""

    _FIELDS = ('name', 'bits', 'signed', 'bitstring')

    def __init__(self, name: str, bits: int = 16, signed: bool = True, bitstring: bool = False) -> None:
        _set(self, "name", name)
        _set(self, "bits", bits)
        _set(self, "signed", signed)
        _set(self, "bitstring", bitstring)

    @property
    def kind(self) -> str:
        return "int"

    @property
    def lo(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def hi(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else (1 << self.bits) - 1

    @property
    def rank(self) -> int:
        # sysmac.md 2: 1 USINT/SINT/BYTE, 2 UINT/INT/WORD, 4 DINT/UDINT/DWORD, 6 LINT/ULINT/LWORD
        return {8: 1, 16: 2, 32: 4, 64: 6}[self.bits]

    def wrap(self, value: int) -> int:
        mask = (1 << self.bits) - 1
        value &= mask
        if self.signed and value > self.hi:
            value -= 1 << self.bits
        return value


class SubrangeType(IntType):
    """`INT(0..100)` (IEC 61131-3 ed. 3, 6.4.4.3): an integer of the base type (same `name`,
    width and wrap) whose values must lie in low..high. A constant outside is a check-time error;
    a value computed at run time outside follows `subrange_check`."""

    _FIELDS = ('name', 'bits', 'signed', 'bitstring', 'low', 'high')

    def __init__(self, name: str, bits: int = 16, signed: bool = True, bitstring: bool = False,
                 low: int = 0, high: int = 0) -> None:
        _set(self, "name", name)
        _set(self, "bits", bits)
        _set(self, "signed", signed)
        _set(self, "bitstring", bitstring)
        _set(self, "low", low)
        _set(self, "high", high)

    @property
    def text(self) -> str:
        return f"{self.name}({self.low}..{self.high})"


def subrange_of(base: IntType, low: int, high: int) -> SubrangeType:
    return SubrangeType(base.name, base.bits, base.signed, base.bitstring, low, high)


class RealType(Type):
    """REAL (32 bits) or LREAL (64 bits)."""

    _FIELDS = ('name', 'bits')

    def __init__(self, name: str, bits: int = 32) -> None:
        _set(self, "name", name)
        _set(self, "bits", bits)

    @property
    def kind(self) -> str:
        return "real"

    @property
    def rank(self) -> int:
        return 3 if self.bits == 32 else 5


_LONG_TIMES = {"LTIME": "TIME", "LDATE": "DATE", "LTIME_OF_DAY": "TIME_OF_DAY", "LDATE_AND_TIME": "DATE_AND_TIME"}


class TimeType(Type):
    """TIME (a duration) and DATE/TOD/DT (points in time), all integer nanoseconds; their long
    forms LTIME, LDATE, LTIME_OF_DAY, LDATE_AND_TIME (IEC ed. 3) are distinct types of the same
    `family`. Sysmac's TIME is already 64-bit nanoseconds, so both forms hold the same values."""

    @property
    def kind(self) -> str:
        return "time"

    @property
    def family(self) -> str:
        """TIME, DATE, TIME_OF_DAY or DATE_AND_TIME, for the long forms too."""
        return _LONG_TIMES.get(self.name, self.name)

    @property
    def long(self) -> bool:
        return self.name in _LONG_TIMES


class StringType(Type):
    """STRING[size]: `size` bytes of storage including the terminating NUL (Omron)."""

    _FIELDS = ('name', 'size')

    def __init__(self, name: str, size: int = 1986) -> None:
        _set(self, "name", name)
        _set(self, "size", size)

    @property
    def kind(self) -> str:
        return "string"

    @property
    def max_bytes(self) -> int:
        return self.size - 1


class WStringType(StringType):
    """WSTRING[n] (IEC 61131-3 ed. 3, 6.3.3): at most n UTF-16 code units. `size` is n + 1, so
    that `max_bytes` (the code units it holds, here) reads as for STRING, whose size counts the NUL.

    A subclass so that every string rule (comparison, ANY_STRING, stores that cut at `max_bytes`)
    holds for it; the places where STRING and WSTRING differ (values are `str`, not `bytes`; one
    is not assignable to the other) test `is_wide`.
    """


def is_wide(ty: Type | None) -> bool:
    """Is `ty` a WSTRING (its values `str` of UTF-16 code units)?"""
    return isinstance(ty, WStringType)


class EnumType(Type):
    """An enumeration: its enumerators and values, base type, declared default and attributes.

    `members`: (enumerator, value) in declaration order; `default`: the declared initial value
    (`TYPE E : (A, B) := B;`); `strict`, `to_string`: {attribute 'strict'} / {attribute
    'to_string'} on its declaration (TwinCAT/CODESYS; read by semantics/dialect_rules.py, which
    says what they change in which dialect)."""

    _FIELDS = ('name', 'qualname', 'members', 'base', 'default', 'strict', 'to_string')

    def __init__(self, name: str, qualname: str = "", members: tuple[tuple[str, int], ...] = (), base: Type | None = None,
                 default: int | None = None, strict: bool = False, to_string: bool = False) -> None:
        _set(self, "name", name)
        _set(self, "qualname", qualname)
        _set(self, "members", members)
        _set(self, "base", base)
        _set(self, "default", default)
        _set(self, "strict", strict)
        _set(self, "to_string", to_string)

    @property
    def kind(self) -> str:
        return "enum"

    def value_of(self, member: str) -> int | None:
        for name, value in self.members:
            if name.lower() == member.lower():
                return value
        return None

    def name_of(self, value: int) -> str | None:
        for name, member_value in self.members:
            if member_value == value:
                return name
        return None


class StructType(Type):
    """A STRUCT: its fields, (field name, field type) in declaration order, which `==` and `hash`
    leave out (two structs are the same type by name and qualified name)."""

    _FIELDS = ('name', 'qualname', 'fields')
    _COMPARED = ('name', 'qualname')

    def __init__(self, name: str, qualname: str = "", fields: tuple[tuple[str, Type], ...] = ()) -> None:
        _set(self, "name", name)
        _set(self, "qualname", qualname)
        _set(self, "fields", fields)

    @property
    def kind(self) -> str:
        return "struct"

    def field_type(self, name: str) -> Type | None:
        for field_name, field_type in self.fields:
            if field_name.lower() == name.lower():
                return field_type
        return None

    def field_name(self, name: str) -> str | None:
        for field_name, _ in self.fields:
            if field_name.lower() == name.lower():
                return field_name
        return None


class UnionType(StructType):
    """CODESYS UNION: the members overlay the same bytes, each at offset 0 (little-endian, as on
    an x86 CODESYS target); its size is the largest member's, padded to the largest alignment.
    A StructType, so member access, initialisers and copies follow the struct rules; the value
    keeps the union's bytes (`stvm.runtime.unions`)."""


class ArrayType(Type):
    """An ARRAY: element type and bounds per dimension (none for an `ARRAY[*]` parameter).

    `dims`: (lo, hi) per dimension; None for an `ARRAY[*]` parameter (any bounds). `rank`: the
    dimensions of an open array (`dims` None): 1 for ARRAY[*], 2 for ARRAY[*, *], …"""

    _FIELDS = ('name', 'element', 'dims', 'rank')

    def __init__(self, name: str, element: Type = None,   # type: ignore[assignment]
                 dims: tuple[tuple[int, int], ...] | None = (), rank: int = 1) -> None:
        _set(self, "name", name)
        _set(self, "element", element)
        _set(self, "dims", dims)
        _set(self, "rank", rank)

    @property
    def kind(self) -> str:
        return "array"

    @property
    def length(self) -> int:
        total = 1
        for lo, hi in self.dims or ():
            total *= hi - lo + 1
        return total


class FBType(Type):
    """A FUNCTION_BLOCK or PROGRAM type; members are looked up in the project index."""

    _FIELDS = ('name', 'qualname', 'is_program')

    def __init__(self, name: str, qualname: str = "", is_program: bool = False) -> None:
        _set(self, "name", name)
        _set(self, "qualname", qualname)
        _set(self, "is_program", is_program)

    @property
    def kind(self) -> str:
        return "program" if self.is_program else "fb"


class InterfaceType(Type):
    """An INTERFACE type (IEC ed. 3 6.6.6): a variable of it holds a reference to an FB instance
    implementing it (at run time the instance object itself), or NULL (None)."""

    _FIELDS = ('name', 'qualname')

    def __init__(self, name: str, qualname: str = "") -> None:
        _set(self, "name", name)
        _set(self, "qualname", qualname)

    @property
    def kind(self) -> str:
        return "interface"


class GenericType(Type):
    """IEC generic types (ANY, ANY_NUM, …) usable only in stdlib signatures."""

    @property
    def kind(self) -> str:
        return "generic"

    def accepts(self, other: Type) -> bool:
        k = other.kind
        n = self.name
        if n in ("ANY", "ANY_ELEMENTARY"):
            return k in ("bool", "int", "real", "time", "string", "enum") or n == "ANY"
        if n == "ANY_NUM":
            return k in ("int", "real") and not getattr(other, "bitstring", False)
        if n == "ANY_MAGNITUDE":
            return (k in ("int", "real") and not getattr(other, "bitstring", False)) or getattr(other, "family", "") == "TIME"
        if n == "ANY_INT":
            return k == "int" and not other.bitstring  # type: ignore[attr-defined]
        if n == "ANY_REAL":
            return k == "real"
        if n == "ANY_BIT":
            return k == "bool" or (k == "int" and other.bitstring)  # type: ignore[attr-defined]
        if n == "ANY_BIT_OR_INT":   # stdlib only: TwinCAT/CODESYS SHL/SHR/ROL/ROR (stvm/dialects.py)
            return k in ("bool", "int")
        if n == "ANY_STRING":
            return k == "string"
        if n == "ANY_DATE":
            return k == "time" and other.family != "TIME"  # type: ignore[attr-defined]
        return False


class RefType(Type):
    """REF_TO T (IEC), POINTER TO T and REFERENCE TO T (CODESYS): a reference to a variable.

    At run time a reference to a scalar is an `AttrRef`/`ItemRef` (get/set), a reference to an
    aggregate (STRUCT, ARRAY, FB instance) is the aggregate object itself (aggregates are never
    rebound), and NULL is None. `flavour` REFERENCE is dereferenced implicitly where it is used.
    """

    _FIELDS = ('name', 'target', 'flavour')

    def __init__(self, name: str, target: Type = None,   # type: ignore[assignment]  # None only for the NULL literal's type
                 flavour: str = "REF_TO") -> None:
        _set(self, "name", name)
        _set(self, "target", target)
        _set(self, "flavour", flavour)

    @property
    def kind(self) -> str:
        return "ref"

    @property
    def is_null(self) -> bool:
        return self.target is None


def ref_type(target: Type, flavour: str = "REF_TO") -> RefType:
    word = {"REF_TO": "REF_TO", "POINTER": "POINTER TO", "REFERENCE": "REFERENCE TO"}[flavour]
    return RefType(f"{word} {target.name}", target, flavour)


NULL_REF = RefType("NULL", None, "REF_TO")


def same_type(a: Type, b: Type) -> bool:
    """Equal types for a reference's target (structs, enums and FBs by qualified name)."""
    if a == b:
        return True
    qa, qb = getattr(a, "qualname", None), getattr(b, "qualname", None)
    if qa and qb and type(a) is type(b):
        return qa.lower() == qb.lower()
    if isinstance(a, RefType) and isinstance(b, RefType):
        return a.flavour == b.flavour and same_type(a.target, b.target)
    return False


def is_aggregate(ty: Type) -> bool:
    """Values that are objects the program never rebinds (a reference to them is the object)."""
    return isinstance(ty, (StructType, ArrayType, FBType))


class VoidType(Type):
    """What a FUNCTION or METHOD without a result type returns."""

    @property
    def kind(self) -> str:
        return "void"


def _ints() -> dict[str, Type]:
    table: dict[str, Type] = {}
    for name, bits, signed, bitstring in [
        ("SINT", 8, True, False), ("INT", 16, True, False), ("DINT", 32, True, False), ("LINT", 64, True, False),
        ("USINT", 8, False, False), ("UINT", 16, False, False), ("UDINT", 32, False, False), ("ULINT", 64, False, False),
        ("BYTE", 8, False, True), ("WORD", 16, False, True), ("DWORD", 32, False, True), ("LWORD", 64, False, True),
    ]:
        table[name] = IntType(name, bits, signed, bitstring)
    return table


BOOL = BoolType("BOOL")
REAL = RealType("REAL", 32)
LREAL = RealType("LREAL", 64)
TIME = TimeType("TIME")
DATE = TimeType("DATE")
TOD = TimeType("TIME_OF_DAY")
DT = TimeType("DATE_AND_TIME")
LTIME = TimeType("LTIME")
LDATE = TimeType("LDATE")
LTOD = TimeType("LTIME_OF_DAY")
LDT = TimeType("LDATE_AND_TIME")
STRING = StringType("STRING", 1986)
WSTRING = WStringType("WSTRING", 1986)   # Choice: as many code units as a STRING holds bytes
VOID = VoidType("VOID")

ELEMENTARY: dict[str, Type] = {
    "BOOL": BOOL, "REAL": REAL, "LREAL": LREAL,
    "TIME": TIME, "DATE": DATE, "TIME_OF_DAY": TOD, "TOD": TOD, "DATE_AND_TIME": DT, "DT": DT,
    "LTIME": LTIME, "LDATE": LDATE, "LTIME_OF_DAY": LTOD, "LTOD": LTOD, "LDATE_AND_TIME": LDT, "LDT": LDT,
    "STRING": STRING, "WSTRING": WSTRING,
    **_ints(),
}
GENERICS: dict[str, Type] = {
    name: GenericType(name)
    for name in ("ANY", "ANY_ELEMENTARY", "ANY_NUM", "ANY_MAGNITUDE", "ANY_INT", "ANY_REAL",
                 "ANY_BIT", "ANY_STRING", "ANY_DATE", "ANY_BIT_OR_INT")
}

SINT, INT, DINT, LINT = (ELEMENTARY[n] for n in ("SINT", "INT", "DINT", "LINT"))
USINT, UINT, UDINT, ULINT = (ELEMENTARY[n] for n in ("USINT", "UINT", "UDINT", "ULINT"))
BYTE, WORD, DWORD, LWORD = (ELEMENTARY[n] for n in ("BYTE", "WORD", "DWORD", "LWORD"))


def time_type(family: str, long: bool) -> TimeType:
    """The TIME-family type of `family` (TIME, DATE, TIME_OF_DAY, DATE_AND_TIME), long or not."""
    if not long:
        return ELEMENTARY[family]  # type: ignore[return-value]
    return next(ty for ty in (LTIME, LDATE, LTOD, LDT) if ty.family == family)


def string_type(size: int, name: str | None = None) -> StringType:
    """STRING of `size` bytes with the NUL; `name` as the source spells it (`STRING(5)`: size 6)."""
    return STRING if size == 1986 else StringType(name or f"STRING[{size}]", size)


def wstring_type(units: int) -> WStringType:
    """WSTRING[units]: holds `units` UTF-16 code units."""
    return WSTRING if units == WSTRING.max_bytes else WStringType(f"WSTRING[{units}]", units + 1)


def is_integer(t: Type) -> bool:
    return isinstance(t, IntType)


def is_numeric(t: Type) -> bool:
    return isinstance(t, (IntType, RealType))


# ---- sizes in bytes (SIZEOF / XSIZEOF) ---------------------------------------------------------
# Choice (no controller memory is modelled): the sizes a CODESYS/TwinCAT x86 target reports, with
# Sysmac's own widths where they differ — TIME, DATE, TOD and DT are 64-bit (Sysmac, and LTIME
# everywhere); STRING[n] is its n bytes of storage (Sysmac counts the NUL in n); an enumeration
# is its base type (INT unless it names one). STRUCTs use natural alignment (every member at a multiple of its
# own alignment, the struct padded to its largest one: CODESYS's default pack mode 8). Function
# block instances and references have no defined size here: None.

def byte_size(ty: Type, short_times: bool = False) -> int | None:
    """SIZEOF of `ty`. `short_times`: the TwinCAT/CODESYS layout of the time types (the
    `short_times` profile row): TIME and TIME_OF_DAY 32-bit milliseconds, DATE and DATE_AND_TIME
    32-bit seconds; the long forms (LTIME, …) stay 64-bit nanoseconds (docs/memory_model.md)."""
    if isinstance(ty, BoolType):
        return 1
    if isinstance(ty, (IntType, RealType)):
        return ty.bits // 8
    if isinstance(ty, TimeType):
        return 4 if short_times and not ty.long else 8
    if isinstance(ty, WStringType):
        return 2 * ty.size   # two bytes a code unit, the NUL included (CODESYS)
    if isinstance(ty, StringType):
        return ty.size
    if isinstance(ty, EnumType):
        return byte_size(ty.base) if ty.base is not None else 2
    if isinstance(ty, ArrayType):
        element = byte_size(ty.element, short_times)
        return None if element is None or ty.dims is None else element * ty.length
    if isinstance(ty, UnionType):
        sizes = [byte_size(f, short_times) for _, f in ty.fields]
        align = _alignment(ty, short_times)
        if None in sizes or align is None:
            return None
        return -(-max(sizes, default=0) // align) * align  # type: ignore[type-var]
    if isinstance(ty, StructType):
        offset, largest = 0, 1
        for _, field_type in ty.fields:
            size, align = byte_size(field_type, short_times), _alignment(field_type, short_times)
            if size is None or align is None:
                return None
            offset = -(-offset // align) * align + size
            largest = max(largest, align)
        return -(-offset // largest) * largest
    return None


def _alignment(ty: Type, short_times: bool = False) -> int | None:
    if isinstance(ty, ArrayType):
        return _alignment(ty.element, short_times)
    if isinstance(ty, StructType):
        aligns = [_alignment(f, short_times) for _, f in ty.fields]
        return None if None in aligns else max(aligns, default=1)  # type: ignore[type-var]
    if isinstance(ty, WStringType):
        return 2
    if isinstance(ty, StringType):
        return 1
    return byte_size(ty, short_times)


def alignment(ty: Type, short_times: bool = False) -> int | None:
    """The alignment in bytes a member of `ty` gets in a STRUCT (see `byte_size`)."""
    return _alignment(ty, short_times)
