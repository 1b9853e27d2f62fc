"""Dialect profiles: one declarative table of everything that differs between the vendors stvm
speaks (Omron Sysmac, plain IEC 61131-3 ed. 3, CODESYS V3, Beckhoff TwinCAT 3).

A row is one point of difference: what it is, the value in each dialect, and where that value
comes from. Two kinds of rows:

* setting rows (`setting` names a field of `SysmacSettings`): the dialect gives the setting its
  value unless the user set it (`--sysmac NAME=VALUE`, `[sysmac]` in stvm.toml); the code reads the
  setting as before, so a user can still mix and match;
* rule rows (`setting` is None): a language rule the parser or checker applies by asking
  `allows(dialect, rule)` (a row whose values are booleans) or reading the row's text.

The Sysmac profile is stvm's behaviour before profiles existed (the thesis project, its goldens and
its TM frames depend on it); the others follow their vendor's documentation, named per row.
docs/dialects.md shows this table; tests/semantics/test_dialect_profiles.py tests every row in
every profile.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

# no import of stvm.settings: it reads this table while it builds its defaults. Setting rows give
# the setting's spelling (as on the command line); dialects are named by their `--dialect` spelling.
SYSMAC, IEC, CODESYS, TWINCAT = "sysmac", "iec", "codesys", "twincat"

W501 = "Omron W501 (Sysmac Studio ST reference)"
W502 = "Omron W502 (instructions reference)"
IEC3 = "IEC 61131-3 ed. 3"
CDS = "CODESYS V3 online help"
TC3 = "Beckhoff Infosys, TwinCAT 3 PLC"


@dataclass(frozen=True)
class Row:
    """One difference between the dialects: its value in each one, and the sources."""

    key: str                  # the setting's name, or the rule's name for `allows`
    subject: str              # what differs, in words
    sysmac: Any
    iec: Any
    codesys: Any
    twincat: Any
    sources: str              # vendor references, one clause per dialect that differs
    setting: bool = False     # True: `key` is a field of SysmacSettings

    def value(self, dialect) -> Any:
        """The value in `dialect` (a Dialect member or its spelling)."""
        return getattr(self, getattr(dialect, "value", dialect))


ROWS: tuple[Row, ...] = (
    # ---- rows that set a setting ----------------------------------------------------------------
    Row("byte_to_string_format", "BYTE/WORD/DWORD/LWORD_TO_STRING (and TO_STRING of a bit string)",
        "hex_nopad", "decimal", "decimal",
        "decimal",
        f"{W502} BYTE_TO_STRING: hexadecimal without leading zeros, BYTE#42 -> '2A'; {TC3} / {CDS} "
        "'TO_STRING conversions': the number in decimal, BYTE#42 -> '42'; IEC: as CODESYS (Choice: "
        "the standard gives no text form)", setting=True),
    Row("real_to_string_format", "REAL/LREAL_TO_STRING (and TO_STRING of a real)",
        "c_exp", "shortest", "shortest",
        "digits15",
        "Sysmac: C %e with the type's digits, 3.5 -> '3.500000e+00' (stvm's choice, which the thesis "
        f"checksum relies on); {TC3} 'TO_STRING conversions' (LREAL_TO_STRING -> '1.4'), "
        "'REAL/LREAL_TO_<type>' (the digits are limited, the last one rounded) and Tc2_Utilities "
        "'LREAL_TO_FMTSTR' (an LREAL has at most 15 significant digits): the shortest text of the "
        "value rounded to 15 digits, 0.06999999999999999 -> '0.07'; below 0.01 mantissa and exponent, "
        "0.0099385 -> '9.9385e-3', as TcUnit's messages from a TwinCAT runtime show them "
        "(github.com/tcunit/TcUnit pull request 231); IEC and CODESYS: the shortest text, 3.5 -> '3.5'",
        setting=True),
    Row("string_size", "what n counts in STRING[n] / STRING(n)",
        "with_nul", "characters", "characters", "characters",
        f"{W501}: STRING[n] is n bytes including the NUL (holds n-1); {IEC3} 6.3.3, {TC3} 'STRING' "
        "(STRING(46) reserves 46+1 bytes for 46 characters) and CODESYS: holds n characters, so "
        "TwinCAT's T_MaxString = STRING(255) holds 255", setting=True),
    Row("open_array_bounds", "LOWER_BOUND/UPPER_BOUND of an ARRAY[*] parameter",
        "zero", "actual", "actual", "actual",
        f"{W501}: an array parameter numbers from 0; {IEC3} 6.5.3.2 and {CDS} 'LOWER_BOUND': the "
        "caller's bounds (ARRAY[2..5] gives 2 and 5); TwinCAT is CODESYS-based", setting=True),
    Row("subrange_check", "a subrange variable given a value outside its range at run time",
        "fault", "fault", "store", "store",
        f"{IEC3} 6.4.4.3: an error; {CDS} / {TC3} 'Subrange types': checked only by the implicit "
        "CheckRangeSigned/CheckRangeUnsigned functions, without them the value is stored", setting=True),
    Row("pointer_overrun", "an access through a byte pointer a few bytes outside the variable it points into",
        "fault", "fault", "guard", "guard",
        f"{TC3} 'POINTER TO' and 'CheckPointer' / {CDS} 'POINTER TO' and 'POU CheckPointer': pointers "
        "are not checked at run time unless the project adds the implicit CheckPointer function, so "
        "a write past a variable's end lands in the neighbouring memory (stvm: an 8-byte guard "
        "absorbs it, docs/memory_model.md); Sysmac and IEC have no pointer arithmetic: a fault",
        setting=True),
    # ---- rule rows ------------------------------------------------------------------------------
    Row("p_prefix_rule", "names may not start with '_' or 'P_', end with '_', contain '__'",
        True, False, False, False,
        f"{W501} 'Variable names': these forms are reserved for system names; {IEC3} 6.1.2 allows "
        "one leading '_' (checked: no '__', no trailing '_'); CODESYS/TwinCAT: any identifier"),
    Row("wstring_literal", 'double-quoted text "abc" is a WSTRING literal',
        False, True, True, True,
        f"{IEC3} 6.3.3 table 7; {TC3} 'WSTRING' (initialised with double quotes); Sysmac has no "
        "WSTRING and takes it as a STRING with a warning (`double_quote_strings`)"),
    Row("persistent", "PERSISTENT is a variable qualifier (`VAR PERSISTENT`)",
        True, False, True, True,
        f"{CDS} / {TC3} 'Persistent variables'; not an IEC keyword: in IEC code `persistent` is an "
        "ordinary name (stvm reads the word as a qualifier only right after VAR/VAR_GLOBAL, so a "
        "variable may have that name in every dialect)"),
    Row("ref_initial_value", "REF(variable) as an initial value (`r : REF_TO INT := REF(x);`)",
        False, True, True, True,
        f"{CDS} 'REF_TO' / {TC3} 'Reference' and RuSTy: the address of a variable is a constant of "
        "the load; Sysmac has no REF_TO"),
    Row("input_constant", "VAR_INPUT CONSTANT without an initial value (fixed at the instance's declaration, default 0)",
        False, False, True, True,
        f"{TC3} / {CDS} 'VAR_INPUT CONSTANT': an input that may be set only where the instance is "
        "declared; IEC and Sysmac require a constant's initial value"),
    Row("pointer_arithmetic", "POINTER TO arithmetic (`p := p + 1`) and assignment between pointer types",
        False, False, True, True,
        f"{TC3} / {CDS} 'POINTER TO' and 'ADR': a pointer is an address-sized unsigned integer"),
    Row("adr_of_constant", "ADR() of a constant (to read it through the pointer); SIZEOF(p^) of a pointer's target",
        False, False, True, True,
        f"{TC3} / {CDS} 'ADR': the address of any variable, constants included; SIZEOF of the "
        "dereferenced pointer is its target type's size (accepted in every dialect that has POINTER TO)"),
    Row("any_input", "ANY as the type of a VAR_INPUT of user code (read as .TypeClass, .pValue, .diSize)",
        False, False, True, True,
        f"{TC3} 'ANY and ANY_<type>' / {CDS} 'ANY': the compiler passes a structure of the argument's "
        "type class, address and size; IEC 61131-3 and Sysmac keep generic types to library functions"),
    Row("short_times", "TIME and TIME_OF_DAY take 4 bytes (milliseconds), DATE and DATE_AND_TIME 4 bytes (seconds)",
        False, False, True, True,
        f"{TC3} 'TIME', 'TIME_OF_DAY', 'DATE', 'DATE_AND_TIME' and {CDS}: 32-bit values in ms / s (LTIME "
        f"64-bit ns); {W501}: TIME, DATE, TOD and DT are 64-bit nanoseconds; IEC 61131-3 leaves the "
        "size open (stvm keeps 64 bits there). Seen by SIZEOF, MEMCPY, cast pointers and UNION members"),
    Row("unsigned_time", "TIME and LTIME are unsigned: TIME 0..T#49d17h2m47s295ms (32-bit ms), LTIME "
        "0..LTIME#213503d23h34m33s709ms551us615ns (64-bit ns); arithmetic wraps there, LTIME_TO_STRING "
        "writes LTIME#",
        False, False, True, True,
        f"{TC3} 'TIME/LTIME': TIME is handled like a UDINT, LTIME like a ULINT, lower limit 0; {CDS} "
        "'Data type: TIME, LTIME': DWORD / LWORD, T#0MS..T#49D17H2M47S295MS and "
        f"LTIME#0NS..LTIME#213503D23H34M33S709MS551US615NS; IEC 61131-3 and {W501}: signed 64-bit "
        "nanoseconds (±106751d23h47m16s854ms775us807ns), arithmetic wraps as a LINT, LTIME_TO_STRING "
        "writes LT#"),
    Row("enum_integer", "an enumeration without {attribute 'strict'} mixes with integers: assigned to and from "
        "integer variables, in arithmetic and comparisons (`i := e + 1; e := 3;`)",
        False, False, True, True,
        f"{TC3} 'Enumerations' and 'Attribute strict' / {CDS} 'Data type: Enumeration': without the "
        "attribute an enumeration value is used as its integer value (the static-analysis rules SA0034 "
        "and SA0058 flag such uses); IEC 61131-3 and Sysmac: enumerations are distinct types"),
    Row("enum_strict_attribute", "{attribute 'strict'} on an enumeration refuses arithmetic on it and assigning "
        "it an integer that is not a constant equal to one of its values (reading it into an integer stays "
        "allowed)",
        False, False, True, True,
        f"{TC3} 'Attribute strict' (compile errors for arithmetic, a constant that is no enumeration value, "
        "a non-constant value of another type; its 'to_string' example assigns a strict enumeration to an "
        f"INT) / {CDS} 'Data type: Enumeration' (C0354's example assigns 0, a value of the strict "
        "enumeration); comparing with an integer is no arithmetic and stays allowed (stvm's choice). IEC "
        "61131-3 and Sysmac: no attribute, every enumeration is strict"),
    Row("enum_to_string_attribute", "TO_STRING of an enumeration with {attribute 'to_string'} gives the "
        "enumerator's name ('eStart'); without it the number ('1')",
        False, False, True, True,
        f"{TC3} 'Attribute to_string' and 'TO_STRING/TO_WSTRING for enumeration variables' (TC3.1 build "
        f"4024) / {CDS} 'Attribute: to_string'; IEC 61131-3 and Sysmac have no such attribute (TO_STRING "
        "of an enumeration gives its number)"),
    Row("enum_qualified_only", "an enumerator of an enumeration with {attribute 'qualified_only'} must be "
        "written `E.member` (a bare `member` is an error)",
        True, True, True, True,
        f"{TC3} 'Attribute qualified_only' / {CDS} 'Attribute: qualified_only'; Sysmac and IEC have no "
        "attributes, and stvm honours the pragma in every dialect (a pragma another vendor's compiler "
        "ignores; code written without it is unchanged)"),
    Row("shift_any_integer", "SHL/SHR/ROL/ROR on signed and unsigned integers, not only bit strings",
        False, False, True, True,
        f"{IEC3} table 29 and {W502}: ANY_BIT operands; {TC3} / {CDS} 'SHL': any integer type"),
    Row("call_syntax", "calls with an empty output binding `Q=> ,` and a trailing comma before `)`",
        False, False, True, True,
        f"{TC3}: the editor's declaration-to-call template writes `Error=> ,`; the compiler accepts "
        "both forms (public TwinCAT code uses them); IEC 61131-3 and Sysmac do not"),
    Row("set_reset_assign", "`x S= cond;` / `x R= cond;` (set/reset assignment)",
        False, False, True, True, f"{CDS} / {TC3} 'Assignment operators S= and R='"),
    Row("assignment_expression", "an assignment used as an expression: `IF (i := i + 1) = n THEN`",
        False, False, True, True, f"{CDS} / {TC3} 'Assignment as expression' (value: the value assigned)"),
    Row("method_recursion", "a method calling itself (directly or through others)",
        False, False, True, True, f"{CDS} / {TC3} allow recursion with a warning; Sysmac and IEC refuse it"),
    Row("void_function", "a FUNCTION without a return type, called as a statement (`FUNCTION RUN`)",
        False, False, True, True,
        f"{CDS} 'Function' / {TC3} 'Function': the return type may be left out; such a function "
        "returns nothing and is called as a statement (TcUnit's RUN, TEST, ...); its name is then no "
        "result variable, so a local may share it. IEC 61131-3 and Sysmac require one"),
    Row("mixed_arguments", "formal arguments followed by positional ones (`FIND(STR1 := s, '.')`)",
        False, False, True, True,
        f"{TC3} / {CDS}: the compiler accepts a call that names some inputs and gives the rest by "
        "position (public TwinCAT code such as TcUnit uses it); the positional ones take, in order, "
        "the inputs not named. IEC 61131-3 6.6.1.4 and Sysmac: all formal or all positional"),
    Row("fb_assign", "assigning a function block instance to another of its type (a copy of its variables)",
        False, False, True, True,
        f"{TC3} / {CDS}: an FB instance is assigned like a structure (its memory is copied) unless "
        "the FB has {attribute 'no_assign'}; a METHOD may return an FB (TcUnit's GetTestByPosition). "
        "IEC 61131-3 and Sysmac: an instance cannot be assigned"),
    Row("fb_input_assign", "writing an input of an FB instance outside its call (`fbTimer.IN := TRUE;`)",
        False, False, True, True,
        f"{TC3} / {CDS}: an instance's inputs are read and written from outside like variables (the "
        "next call uses the value); IEC 61131-3 6.6.1.2 and Sysmac: inputs are set in the call only"),
    Row("fb_internal_read", "reading a VAR (internal) variable of an FB instance from outside (`fb.counter`)",
        False, False, False, True,
        f"{TC3}: TwinCAT 3 compiles read access to an instance's internal variables (TcUnit reads "
        "FB_TestSuite's Tests and FB_Test's TestName); writing them stays an error. IEC 61131-3, "
        "Sysmac and CODESYS (stvm's choice: not confirmed for CODESYS): only inputs and outputs are "
        "visible outside"),
    Row("int_div_zero", "integer division or MOD by zero",
        "fault", "fault", "fault", "fault",
        f"{W501}: an instruction error stops the task; {TC3} 'Division by zero': an exception (the "
        "PLC stops); CODESYS alike; IEC: an error. Same in every profile (`int_div_zero` switches it)"),
    Row("int_overflow", "integer overflow in arithmetic",
        "wraps", "wraps", "wraps", "wraps",
        f"{W501} and {TC3}: two's complement wrap-around, no error. Same in every profile"),
    Row("time_to_string", "TIME/DATE/TOD/DT_TO_STRING text",
        "IEC literal", "IEC literal", "IEC literal", "IEC literal",
        f"{TC3} 'TO_STRING conversions': TIME_TO_STRING(T#12ms) = 'T#12ms', D#2002-08-18, "
        "TOD#14:01:05.123, DT#1998-02-13-14:20...; stvm writes the same literal forms in every "
        "profile (zero units left out, seconds always shown for TOD/DT)"),
    Row("bool_to_string", "BOOL_TO_STRING", "'TRUE'/'FALSE'", "'TRUE'/'FALSE'", "'TRUE'/'FALSE'",
        "'TRUE'/'FALSE'", f"{TC3} 'TO_STRING conversions': BOOL_TO_STRING(TRUE) = 'TRUE'"),
    Row("unsized_string", "STRING without a size",
        "1985 bytes", "1985 bytes", "80 characters", "80 characters",
        f"{W501}: 1986 bytes with the NUL. TwinCAT and CODESYS reserve 80 characters ({TC3} "
        "'STRING': 'if no size is specified, 80 characters'); IEC leaves it to the implementer and "
        "stvm keeps Sysmac's 1985 there; the stdlib's own STRING parameters keep 1985 everywhere"),
)

BY_KEY = {row.key: row for row in ROWS}
PROFILE_FIELDS = frozenset(row.key for row in ROWS if row.setting)


def profile_value(dialect, name: str) -> str:
    """The value (its spelling) the profile of `dialect` gives setting `name`."""
    return BY_KEY[name].value(dialect)


def allows(dialect, rule: str) -> bool:
    """Whether `dialect` accepts the language rule `rule` (a boolean row)."""
    value = BY_KEY[rule].value(dialect)
    assert isinstance(value, bool), rule
    return value


def known_library_prefix(parts: tuple[str, ...], known) -> tuple[str, ...]:
    """The POU or type a dotted library-qualified name designates (`TcUnit.FB_TestSuite`,
    `FsCommon.I_Runnable`): the name itself when `known(parts)`, else the name without its leading
    library part(s) when that is known, else the name as given (the caller reports it unknown).
    The one place where a vendor library's namespace is taken off a name; a library loaded as a
    real namespace makes the full name known and wins (`Lib.ENUMERATOR`, an enumerator of the one
    enumeration of Lib that has it, is resolved with the namespaces in stvm/libraries.py `qualify`;
    docs/dialects.md "Library enumerators")."""
    if known(parts):
        return parts
    for start in range(1, len(parts)):
        if known(parts[start:]):
            return parts[start:]
    return parts


def _cell(row: Row, value: Any) -> str:
    """A value as docs/dialects.md shows it: yes/no for a rule, `code` for a setting's spelling or
    a one-word value, plain text otherwise."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    text = str(value)
    if row.setting or text.replace("_", "").isalnum():
        return f"`{text}`"
    return text


def table_markdown() -> str:
    """The table of docs/dialects.md, generated from ROWS (tools/gen_dialect_docs.py writes it;
    tests/semantics/test_dialect_profiles.py checks the page against it)."""
    lines = ["| row | what differs | sysmac | iec | codesys | twincat | sources |",
             "|---|---|---|---|---|---|---|"]
    for row in ROWS:
        key = f"`{row.key}` (setting)" if row.setting else f"`{row.key}`"
        cells = [_cell(row, row.value(d)) for d in (SYSMAC, IEC, CODESYS, TWINCAT)]
        text = [key, row.subject, *cells, row.sources]
        lines.append("| " + " | ".join(t.replace("|", "\\|") for t in text) + " |")
    return "\n".join(lines) + "\n"
