"""Settings for every point the Sysmac spec marks UNCERTAIN (docs/sysmac.md, section 9).

Each UNCERTAIN behaviour is exactly one field of `SysmacSettings`, declared once: its type (an
Enum of the allowed values, a bounded integer, or a table), its default (the spec's) and its spec
section. The checker, the code generator, the VM and the stdlib read them from the one instance a
run carries (`ctx.settings`) and compare with the Enum members, never with free strings.

Values come from three places, all checked here, all failing with `SettingError` (a ValueError
whose message lists the allowed values; the CLI turns it into a usage error, exit 2):

* Python: `SysmacSettings(int_literal_type="lint")` (the spelling or the Enum member);
* the command line: `stvm run --sysmac int_literal_type=lint ...` (`with_overrides`);
* the project manifest: a `[sysmac]` table in `stvm.toml` (`with_table`).
"""

from __future__ import annotations

import re
from dataclasses import MISSING, dataclass, field, fields, replace
from enum import Enum
from reprlib import recursive_repr
from typing import Any, Callable, Mapping

from stvm.records import FrozenRecord


# Table and Declaration behave as the frozen dataclasses they were (constructor, ==, hash, repr,
# frozenness) but are `stvm.records` classes (`__init__` written out), and SysmacSettings, still a dataclass (`replace`, `fields`),
# has its ==, hash and repr written out: `dataclass` builds each method with `exec` at import,
# a cost of every `stvm run` (issue 33 item 5; tests/test_settings_records.py compares them).
_set = object.__setattr__


class SettingError(ValueError):
    """A setting name or value that is not allowed; the message lists what is."""


# ---- the allowed values, one Enum per setting (value = the spelling on the command line) ------

class SktProgressWithoutCall(Enum):
    """A busy socket request progresses between calls of its FB."""
    ON = "on"                   # the request completes in the background; seen at the next call
    CANCEL = "cancel"           # a scan without a call cancels the request


class EnumDefault(Enum):
    """Initial value of an enum variable without initialiser."""
    FIRST = "first"             # the first enumerator
    ZERO = "zero"               # the value 0


class FunErrorPolicy(Enum):
    """A function's instruction error (ENO FALSE)."""
    SKIP_ASSIGNMENT = "skip_assignment"   # the receiving assignment is skipped, a warning once per site
    FAULT = "fault"                       # the task stops


class ArrayOob(Enum):
    """An array index out of range in user code."""
    FAULT = "fault"             # the task stops with the ST location (the spec's default)
    # Choice (sysmac.md 1, 9 give no alternative): W501 6-6-3 lists an access beyond the array
    # range among the *instruction errors*, so the alternative treats it like a function's
    # instruction error under `fun_error_policy=skip_assignment`: the statement is not executed,
    # a warning `FILE:LINE:COL: warning: ...` is printed once per statement, the scan goes on.
    SKIP_STATEMENT = "skip_statement"


class OpenArrayBounds(Enum):
    """How an ARRAY[*] parameter numbers the elements passed."""
    ZERO = "zero"               # from 0, whatever the argument's bounds (Sysmac: "the array from this element on")
    # IEC 61131-3 ed. 3 6.5.3.2 and CODESYS/TwinCAT: the argument's own bounds, read with
    # LOWER_BOUND/UPPER_BOUND (an element passed as "array from here" starts at 0 all the same)
    ACTUAL = "actual"


class IntDivZero(Enum):
    """Integer `/` and MOD, DIV(), TIME / INT, TIME / REAL and DIV_TIME by zero (one meaning everywhere)."""
    FAULT = "fault"             # the task stops with the ST location
    ZERO = "zero"               # the result is 0


class SubrangeCheck(Enum):
    """A value outside its subrange type (`INT(0..100)`) computed at run time (a constant is always a check-time error)."""
    FAULT = "fault"             # IEC 61131-3 ed. 3 6.4.4.3 ("an error"): the task stops with the ST location
    # CODESYS/TwinCAT without the implicit CheckRangeSigned/CheckRangeUnsigned functions: the
    # value is stored (wrapped to the base type only)
    STORE = "store"


class PointerOverrun(Enum):
    """A read or write through a byte pointer (MEMCPY, `p^` of a cast or moved pointer) a few bytes outside the variable it points into (docs/memory_model.md)."""
    FAULT = "fault"             # the task stops with the ST location (stvm's memory model has no neighbours)
    # TwinCAT/CODESYS: the access lands in neighbouring memory without an error; stvm gives every
    # variable an 8-byte guard on each side that absorbs it (writes dropped, reads 0)
    GUARD = "guard"


class IntLiteralType(Enum):
    """Type of an untyped integer literal."""
    DINT = "dint"               # DINT if it fits, else LINT
    LINT = "lint"               # always LINT (no 32-bit overflow)


class StringLengthUnit(Enum):
    """What string lengths and positions count."""
    UTF8 = "utf8"               # UTF-8 characters (an invalid byte counts 1)
    BYTES = "bytes"


class StringOverflow(Enum):
    """A text longer than STRING[n] holds, assigned to it."""
    TRUNCATE_WARN = "truncate_warn"   # cut to n-1 bytes, `FILE:LINE:COL: warning: ...` once per site
    ERROR = "error"                   # a constant: a check-time error; at run time: a fault


class Dialect(Enum):
    """The vendor dialect: its profile of language rules, conversions and vendor types (`--dialect`, stvm/dialects.py)."""
    SYSMAC = "sysmac"           # Omron Sysmac Studio: W501's name rules (no leading `_`, `P_`, trailing `_`, `__`)
    IEC = "iec"                 # IEC 61131-3 ed. 3 6.1.2: one leading `_` allowed, no `__`, no trailing `_`
    CODESYS = "codesys"         # CODESYS V3: any identifier that is not a keyword
    TWINCAT = "twincat"         # TwinCAT 3: as codesys, plus T_MaxString, PVOID, XWORD, XINT, UXINT (x64)


class RealToStringFormat(Enum):
    """REAL/LREAL_TO_STRING (and TO_STRING of a real)."""
    C_EXP = "c_exp"             # Omron (Choice): C `%e` with the type's digits, 3.5 -> '3.500000e+00'
    SHORTEST = "shortest"       # CODESYS: the shortest text that reads back the same, 3.5 -> '3.5'
    # TwinCAT: an LREAL rounded to 15 significant digits first (0.06999999999999999 -> '0.07'), and
    # below 0.01 a mantissa and exponent as a TwinCAT runtime logs them (0.0099385 -> '9.9385e-3')
    DIGITS15 = "digits15"


class StringSize(Enum):
    """What the n of STRING[n] / STRING(n) counts."""
    WITH_NUL = "with_nul"       # Omron W501: n bytes of storage including the NUL; holds n-1
    CHARACTERS = "characters"   # IEC 61131-3 ed. 3 6.3.3, Beckhoff, CODESYS: holds n (n+1 bytes with the NUL)


class BareEnumerators(Enum):
    """An enumerator written without `Type#`."""
    RESOLVE_UNIQUE = "resolve_unique"  # looked up in every visible enum; ambiguity is an error
    REQUIRE_TYPE = "require_type"      # always an error


class DollarN(Enum):
    """The `$N` escape."""
    LF = "lf"
    CRLF = "crlf"


class InvalidDollarEscape(Enum):
    """An unknown `$x` escape."""
    ERROR = "error"             # a build error
    LITERAL = "literal"         # kept as the two characters


class DoubleQuoteStrings(Enum):
    """A double-quoted STRING literal."""
    ACCEPT_WARN = "accept_warn"
    ERROR = "error"


class ForEndEval(Enum):
    """When a FOR loop evaluates its end expression."""
    ONCE = "once"               # before the first iteration
    EACH = "each"               # before every iteration


class SktSendCopy(Enum):
    """When SktTCPSend copies its data bytes."""
    AT_START = "at_start"       # at the call that starts the request
    AT_SERVICE = "at_service"   # when the request is serviced


class SktErrorIdReset(Enum):
    """When ErrorID goes back to 0."""
    START_AND_CLEAR = "start_and_clear"   # at a start and when Error clears
    START_ONLY = "start_only"


class SockaddrPortnoType(Enum):
    """The type of `_sSOCKET_ADDRESS.PortNo`."""
    UINT = "UINT"
    UDINT = "UDINT"             # as printed in the thesis


class SktConnectSrcport0(Enum):
    """SktTCPConnect with SrcTcpPort 0."""
    EPHEMERAL = "ephemeral"     # the system picks a port
    ERROR = "error"             # error 16#0400


class SktSocketAfterClose(Enum):
    """The Socket output of SktTCPConnect after the socket is closed."""
    UNCHANGED = "unchanged"
    ZEROED = "zeroed"


class SktStatusClosedHandle(Enum):
    """SktGetTCPStatus on a handle closed by SktClose."""
    DONE_CLOSED = "done_closed"  # Done with `_CLOSED`
    ERROR = "error"              # error 16#2007


class SktSendSize0(Enum):
    """SktTCPSend with Size 0."""
    DONE = "done"               # Done, nothing sent
    ERROR = "error"             # error 16#0400


class SktRcvTimeout0(Enum):
    """SktTCPRcv with TimeOut 0."""
    FOREVER = "forever"                  # wait forever
    ERROR_IF_EMPTY = "error_if_empty"    # error 16#2006 when nothing is buffered


class SktRcvPeerClosed(Enum):
    """SktTCPRcv after the peer's FIN with nothing buffered."""
    DONE_ZERO = "done_zero"     # Done, RcvSize 0
    ERROR = "error"             # error 16#2003


class ToarybyteStringModel(Enum):
    """The bytes ToAryByte writes for a STRING."""
    TEXT_NUL = "text_nul"       # the text bytes and one 16#00
    TEXT = "text"               # the text bytes only
    IMAGE = "image"             # the whole declared storage


class ToarybyteWideOrder(Enum):
    """Word order of 4/8-byte values in ToAryByte."""
    BIG_ENDIAN = "big_endian"
    WORD_SWAPPED = "word_swapped"


class ArytostringOversize(Enum):
    """AryToString with Size > 1985 or more than the elements left."""
    ERROR = "error"
    TRUNCATE = "truncate"


class RtfsRounding(Enum):
    """RealToFormatString rounding of a tie."""
    HALF_AWAY = "half_away"     # half away from zero
    HALF_EVEN = "half_even"


class RtfsNegativeZero(Enum):
    """RealToFormatString of a negative value that rounds to 0, with Sign TRUE."""
    MINUS = "minus"             # '-0'
    PLUS = "plus"               # '+0'


class ByteToStringFormat(Enum):
    """BYTE/WORD/DWORD/LWORD_TO_STRING."""
    HEX_NOPAD = "hex_nopad"     # 16#0A -> 'A'
    HEX_PAD2 = "hex_pad2"       # 16#0A -> '0A'
    DECIMAL = "decimal"         # 16#0A -> '10'


class StouTrailing(Enum):
    """STRING_TO_UINT with characters after the number."""
    ERROR = "error"
    IGNORE_BLANKS = "ignore_blanks"


class StouPlus(Enum):
    """STRING_TO_UINT with a leading `+`."""
    ACCEPT = "accept"
    ERROR = "error"


class SectodtRange(Enum):
    """SecToDt outside 0 .. 4,294,943,999."""
    ERROR = "error"
    CLAMP = "clamp"


class TimerClock(Enum):
    """The clock the timers read."""
    SCAN_START = "scan_start"   # the VM clock at the start of the scan
    CALL_TIME = "call_time"     # the clock at the call (a free-running clock)


class RtrigFirstCall(Enum):
    """R_TRIG's first call with CLK TRUE."""
    FIRE = "fire"
    NO_FIRE = "no_fire"


class TonPtBelowEt(Enum):
    """TON whose PT drops below ET while timing."""
    Q_TRUE = "q_true"           # Q TRUE, ET := PT
    KEEP_TIMING = "keep_timing"


class TonNonpositivePtEt(Enum):
    """ET of a TON with PT <= 0 once IN is TRUE."""
    ZERO = "zero"
    PT = "pt"


class IecPinAliases(Enum):
    """Omron pin spellings (Reset, Load, Set1, Reset1) as aliases of IEC pins."""
    ON = "on"
    OFF = "off"


class StringResultOverflow(Enum):
    """A string function whose result exceeds 1985 bytes."""
    ERROR = "error"             # a function error
    TRUNCATE = "truncate"


class StringFnRange(Enum):
    """A string function position out of range."""
    ERROR = "error"             # a function error
    CLAMP = "clamp"


class ConcatArity(Enum):
    """CONCAT with one input."""
    ONE_WARNS = "one_warns"     # 1..32 inputs; one input is the identity, with a warning
    TWO_OR_MORE = "two_or_more"


class FindEmpty(Enum):
    """FIND(s, '')."""
    ZERO = 0
    ONE = 1


# ---- tables ------------------------------------------------------------------------------------

CONNECTION_STATES = ("_CLOSED", "_LISTEN", "_SYN_SENT", "_SYN_RECEIVED", "_ESTABLISHED", "_CLOSE_WAIT",
                     "_FIN_WAIT1", "_CLOSING", "_LAST_ACK", "_FIN_WAIT2", "_TIME_WAIT")
BYTE_ORDERS = ("_LOW_HIGH", "_HIGH_LOW")
SOCKET_ERROR_KINDS = ("out_of_range", "too_few_elements", "port_in_use", "unresolvable",
                      "wrong_state", "timeout", "bad_handle", "too_many_sockets")


def _bsd_connection_states() -> dict[str, int]:
    # Choice (spec 5, `connection_state_values`): BSD order of the TCP states.
    return {name: value for value, name in enumerate(CONNECTION_STATES)}


def _default_byte_orders() -> dict[str, int]:
    return {"_LOW_HIGH": 0, "_HIGH_LOW": 1}


def _default_skt_error_codes() -> dict[str, int]:
    # Choice (spec 5, `skt_error_codes`): the mapping the spec proposes.
    return {
        "out_of_range": 0x0400,      # Size 0 / too large, DstTcpPort 0, bad TimeOut
        "too_few_elements": 0x0407,  # fewer array elements left than Size
        "port_in_use": 0x2001,
        "unresolvable": 0x2002,
        "wrong_state": 0x2003,       # refused, not connected, peer reset
        "timeout": 0x2006,           # 75 s connect, receive timeout
        "bad_handle": 0x2007,        # handle 0, unknown, or closed by SktClose
        "too_many_sockets": 0x2008,  # more than 16 sockets
    }


class Table(FrozenRecord):
    """A setting whose value is a name → integer table (settable from Python or `stvm.toml`);
    `distinct`: the values must differ (they are an enum's)."""

    _FIELDS = ('keys', 'lo', 'hi', 'distinct')

    def __init__(self, keys: tuple[str, ...], lo: int, hi: int, distinct: bool) -> None:
        _set(self, "keys", keys)
        _set(self, "lo", lo)
        _set(self, "hi", hi)
        _set(self, "distinct", distinct)

    def check(self, name: str, value: object) -> dict[str, int]:
        if not isinstance(value, Mapping):
            raise SettingError(f"{name} is a table of {', '.join(self.keys)}; got {value!r}")
        out: dict[str, int] = {}
        for key, number in value.items():
            if key not in self.keys:
                raise SettingError(f"{name}: unknown entry {key!r}; allowed: {', '.join(self.keys)}")
            if isinstance(number, bool) or not isinstance(number, int) or not self.lo <= number <= self.hi:
                raise SettingError(f"{name}.{key}: {number!r} is not allowed; allowed: an integer "
                                   f"{self.lo}..{self.hi}")
            out[key] = number
        if self.distinct and len(set(out.values())) != len(out):
            raise SettingError(f"{name}: the values must differ (they are an enum's), got {out}")
        return out


_DINT = (-2**31, 2**31 - 1)


def setting(default: Any = None, spec: str = "", *, lo: int | None = None, hi: int | None = None,
            table: Table | None = None, factory: Callable[[], Any] | None = None, doc: str = "") -> Any:
    """Declare one setting: its default, its spec section (of sysmac.md), for a number its range,
    and what it means (an Enum setting says that in the Enum's docstring)."""
    meta = {"spec": spec, "lo": lo, "hi": hi, "table": table, "doc": doc}
    if factory is not None:
        return field(default_factory=factory, metadata=meta)
    return field(default=default, metadata=meta)


@dataclass(frozen=True, eq=False, repr=False)   # ==, hash, repr below
class SysmacSettings:
    """One field per UNCERTAIN item of the Sysmac spec; defaults are the spec's (section 9)."""

    # section 1: execution model
    skt_progress_without_call: SktProgressWithoutCall = setting(SktProgressWithoutCall.ON, "1")
    enum_default: EnumDefault = setting(EnumDefault.FIRST, "1")
    fun_error_policy: FunErrorPolicy = setting(FunErrorPolicy.SKIP_ASSIGNMENT, "1")
    array_oob: ArrayOob = setting(ArrayOob.FAULT, "1")
    int_div_zero: IntDivZero = setting(IntDivZero.FAULT, "1")
    # section 2: types
    int_literal_type: IntLiteralType = setting(IntLiteralType.DINT, "2")
    string_length_unit: StringLengthUnit = setting(StringLengthUnit.UTF8, "2")
    string_overflow: StringOverflow = setting(StringOverflow.TRUNCATE_WARN, "2")
    subrange_check: SubrangeCheck = setting(None, "2")
    # section 3: dialect
    dialect: Dialect = setting(Dialect.IEC, "3")
    string_size: StringSize = setting(None, "2")
    real_to_string_format: RealToStringFormat = setting(None, "6")
    bare_enumerators: BareEnumerators = setting(BareEnumerators.RESOLVE_UNIQUE, "3 #3")
    dollar_n: DollarN = setting(DollarN.LF, "3 #7")
    invalid_dollar_escape: InvalidDollarEscape = setting(InvalidDollarEscape.ERROR, "3 #7")
    double_quote_strings: DoubleQuoteStrings = setting(DoubleQuoteStrings.ACCEPT_WARN, "3 #8")
    for_end_eval: ForEndEval = setting(ForEndEval.ONCE, "9")
    open_array_bounds: OpenArrayBounds = setting(None, "3 #4")
    pointer_overrun: PointerOverrun = setting(None, "3")
    # section 4/5: sockets
    skt_send_copy: SktSendCopy = setting(SktSendCopy.AT_START, "4 #2")
    skt_errorid_reset: SktErrorIdReset = setting(SktErrorIdReset.START_AND_CLEAR, "4 #2")
    skt_min_latency_calls: int = setting(1, "4 #3", lo=0, hi=1000,
                                         doc="Calls after the starting call before a socket request can complete")
    sockaddr_portno_type: SockaddrPortnoType = setting(SockaddrPortnoType.UINT, "5")
    connection_state_values: dict = setting(spec="5", factory=_bsd_connection_states,
                                            table=Table(CONNECTION_STATES, *_DINT, distinct=False),
                                            doc="Values of `_eCONNECTION_STATE` (default: BSD order)")
    byte_order_values: dict = setting(spec="5", factory=_default_byte_orders,
                                      table=Table(BYTE_ORDERS, *_DINT, distinct=True),
                                      doc="Values of `_eBYTE_ORDER`")
    skt_connect_srcport0: SktConnectSrcport0 = setting(SktConnectSrcport0.EPHEMERAL, "5")
    skt_socket_after_close: SktSocketAfterClose = setting(SktSocketAfterClose.UNCHANGED, "5")
    skt_status_closed_handle: SktStatusClosedHandle = setting(SktStatusClosedHandle.DONE_CLOSED, "5")
    skt_send_size0: SktSendSize0 = setting(SktSendSize0.DONE, "5")
    skt_send_max: int = setting(2000, "5", lo=0, hi=65535,               # Size is a UINT
                                doc="Largest SktTCPSend Size; above it error 16#0400")
    skt_rcv_timeout0: SktRcvTimeout0 = setting(SktRcvTimeout0.FOREVER, "5")
    skt_rcv_timeout_unit_ns: int = setting(100_000_000, "5", lo=1, hi=2**63 - 1,
                                           doc="What one unit of SktTCPRcv TimeOut is, in ns")
    skt_rcv_peer_closed: SktRcvPeerClosed = setting(SktRcvPeerClosed.DONE_ZERO, "5")
    skt_error_codes: dict = setting(spec="5", factory=_default_skt_error_codes,
                                    table=Table(SOCKET_ERROR_KINDS, 0, 0xFFFF, distinct=False),
                                    doc="ErrorID of each socket failure (default: the spec's table)")
    # section 6: Omron functions
    toarybyte_string_model: ToarybyteStringModel = setting(ToarybyteStringModel.TEXT_NUL, "6")
    toarybyte_wide_order: ToarybyteWideOrder = setting(ToarybyteWideOrder.BIG_ENDIAN, "6")
    arytostring_oversize: ArytostringOversize = setting(ArytostringOversize.ERROR, "6")
    rtfs_rounding: RtfsRounding = setting(RtfsRounding.HALF_AWAY, "6")
    rtfs_negative_zero: RtfsNegativeZero = setting(RtfsNegativeZero.MINUS, "6")
    rtfs_max_minlen: int = setting(24, "6", lo=0, hi=255,         # MinLen is a USINT
                                   doc="Largest RealToFormatString MinLen (`rtfs_limits`)")
    rtfs_max_decplace: int = setting(7, "6", lo=0, hi=255,        # DecPlace is a USINT
                                     doc="Largest RealToFormatString DecPlace (`rtfs_limits`)")
    byte_to_string_format: ByteToStringFormat = setting(None, "6")
    stou_trailing: StouTrailing = setting(StouTrailing.ERROR, "6")
    stou_plus: StouPlus = setting(StouPlus.ACCEPT, "6")
    gettime_resolution_ns: int = setting(1_000_000, "6", lo=1, hi=86_400_000_000_000,
                                         doc="GetTime's resolution in ns")
    sectodt_range: SectodtRange = setting(SectodtRange.ERROR, "6")
    # section 7: IEC library
    timer_clock: TimerClock = setting(TimerClock.SCAN_START, "7")
    rtrig_first_call: RtrigFirstCall = setting(RtrigFirstCall.FIRE, "7")
    ton_pt_below_et: TonPtBelowEt = setting(TonPtBelowEt.Q_TRUE, "7")
    ton_nonpositive_pt_et: TonNonpositivePtEt = setting(TonNonpositivePtEt.ZERO, "7")
    iec_pin_aliases: IecPinAliases = setting(IecPinAliases.ON, "7")
    string_result_overflow: StringResultOverflow = setting(StringResultOverflow.ERROR, "7")
    string_fn_range: StringFnRange = setting(StringFnRange.ERROR, "7")
    concat_arity: ConcatArity = setting(ConcatArity.ONE_WARNS, "7")
    find_empty: FindEmpty = setting(FindEmpty.ZERO, "7")
    # not from the spec: a resource limit (docs/security.md). Sysmac's own memory ends far below
    # (a CPU unit holds a few MB of variables); stvm's VM keeps one Python object per element, so
    # ARRAY[0..2000000000] OF INT passed the check and then exhausted the host's memory.
    max_array_elements: int = setting(16_777_216, "limits", lo=1, hi=2**31 - 1,
                                      doc="Most elements one array variable may have, nested arrays "
                                          "counted (a larger array is a check error)")
    # not an UNCERTAIN setting: the conditional-compilation defines, (NAME, VALUE) pairs from
    # `stvm.toml` `[project] defines` and `--define` (stvm/syntax/conditional.py); carried here so
    # that every parse and every cache key sees them
    defines: tuple = field(default=(), metadata={"not_a_setting": True})
    # the settings a dialect profile decides (stvm/dialects.py) that the user set, and the dialect
    # the others were taken from: a change of dialect moves only those the user did not set
    _explicit: frozenset = field(default=frozenset(), repr=False, compare=False, metadata={"not_a_setting": True})
    _profile_dialect: Any = field(default=None, repr=False, compare=False, metadata={"not_a_setting": True})

    def __post_init__(self) -> None:
        # every value is checked (and a spelling turned into its Enum member) at construction,
        # so no code ever sees a value the declaration does not allow
        from stvm.dialects import PROFILE_FIELDS, profile_value   # lazy: start-up
        declared_all = _declarations()
        object.__setattr__(self, "dialect", declared_all["dialect"].coerce(self.dialect))
        explicit = set(self._explicit)
        previous = self._profile_dialect
        for name, declared in declared_all.items():
            value = getattr(self, name)
            if name in PROFILE_FIELDS and name not in explicit:
                # not set by the user: None (a new instance), or the previous profile's value
                # carried over by `replace`, becomes this dialect's value
                if value is None or (previous is not None
                                     and declared.coerce(value) is declared.coerce(profile_value(previous, name))):
                    object.__setattr__(self, name, declared.coerce(profile_value(self.dialect, name)))
                    continue
                explicit.add(name)
            object.__setattr__(self, name, declared.coerce(value))
        object.__setattr__(self, "_explicit", frozenset(explicit))
        object.__setattr__(self, "_profile_dialect", self.dialect)
        object.__setattr__(self, "defines", _checked_defines(self.defines))

    @recursive_repr()
    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={getattr(self, name)!r}" for name in _SHOWN)
        return f"{self.__class__.__qualname__}({shown})"

    def __eq__(self, other: object):
        if other.__class__ is self.__class__:
            return tuple(getattr(self, name) for name in _COMPARED) == tuple(getattr(other, name) for name in _COMPARED)
        return NotImplemented

    def __hash__(self) -> int:
        return hash(tuple(getattr(self, name) for name in _COMPARED))

    def with_defines(self, items: list[str] | tuple[str, ...], where: str = "--define") -> "SysmacSettings":
        """Return a copy with `NAME` / `NAME=VALUE` defines added (a later one replaces an
        earlier one of the same name)."""
        merged = dict(self.defines)
        for item in items:
            try:
                name, value = parse_define(item)
            except SettingError as exc:
                raise SettingError(f"{where}: {exc}") from None
            merged[name] = value
        return replace(self, defines=tuple(sorted(merged.items())))

    def with_overrides(self, assignments: list[str] | tuple[str, ...]) -> "SysmacSettings":
        """Return a copy with `name=value` strings applied (from `--sysmac name=value`)."""
        changes: dict[str, object] = {}
        for item in assignments:
            name, sep, text = item.partition("=")
            name = name.strip()
            if not sep:
                raise SettingError(f"--sysmac needs NAME=VALUE, got {item!r}")
            changes[name] = declaration(name).parse_text(text.strip())
        return self._changed(changes)

    def _changed(self, changes: dict[str, object]) -> "SysmacSettings":
        """A copy with `changes`, which the user made (a profile no longer decides them)."""
        from stvm.dialects import PROFILE_FIELDS   # lazy: start-up
        explicit = self._explicit | (PROFILE_FIELDS & set(changes))
        return replace(self, **changes, _explicit=explicit)

    def with_table(self, table: Mapping[str, object], where: str = "[sysmac]") -> "SysmacSettings":
        """Return a copy with a TOML table applied (`[sysmac]` of `stvm.toml`); a table-valued
        setting given as a sub-table changes only the entries it names."""
        changes: dict[str, object] = {}
        for name, value in table.items():
            try:
                declared = declaration(name)
                if declared.table is not None and isinstance(value, Mapping):
                    value = {**getattr(self, name), **value}
                changes[name] = declared.coerce(value)
            except SettingError as exc:
                raise SettingError(f"{where}: {exc}") from None
        return self._changed(changes)


# what the dataclass's own ==, hash and repr would read: the fields compared, the fields shown
_COMPARED = tuple(f.name for f in fields(SysmacSettings) if f.compare)
_SHOWN = tuple(f.name for f in fields(SysmacSettings) if f.repr)


# ---- the declarations, read from the dataclass ---------------------------------------------------

class Declaration(FrozenRecord):
    """What one field declares: name, type (an Enum class, int or dict), default, spec section,
    range."""

    _FIELDS = ('name', 'kind', 'default', 'spec', 'lo', 'hi', 'table', 'doc')

    def __init__(self, name: str, kind: Any, default: Any, spec: str, lo: int | None, hi: int | None,
                 table: Table | None, doc: str) -> None:
        _set(self, "name", name)
        _set(self, "kind", kind)
        _set(self, "default", default)
        _set(self, "spec", spec)
        _set(self, "lo", lo)
        _set(self, "hi", hi)
        _set(self, "table", table)
        _set(self, "doc", doc)

    @property
    def meaning(self) -> str:
        """What the setting decides (the Enum's docstring, or the declaration's `doc`)."""
        return self.doc or (self.kind.__doc__ or "").strip()

    @property
    def choices(self) -> tuple[Enum, ...]:
        return tuple(self.kind) if isinstance(self.kind, type) and issubclass(self.kind, Enum) else ()

    def allowed(self) -> str:
        """The allowed values in words (for error messages and the README)."""
        if self.choices:
            return ", ".join(f"{member.value} (default)" if member is self.default else str(member.value)
                             for member in self.choices)
        if self.table is not None:
            return f"a table of {', '.join(self.table.keys)} (stvm.toml [sysmac.{self.name}] or Python)"
        return f"an integer {self.lo}..{self.hi} (default {self.default})"

    def coerce(self, value: object) -> object:
        """`value` as the declared type (an Enum member from its spelling too); else SettingError."""
        if self.choices:
            if isinstance(value, self.kind):
                return value
            for member in self.choices:
                if value == member.value or (isinstance(value, str) and isinstance(member.value, str)
                                             and value.lower() == member.value.lower()):
                    if not isinstance(value, bool):
                        return member
            raise SettingError(f"{self.name}: {value!r} is not allowed; allowed: {self.allowed()}")
        if self.table is not None:
            return self.table.check(self.name, value)
        if isinstance(value, bool) or not isinstance(value, int):
            raise SettingError(f"{self.name}: {value!r} is not allowed; allowed: {self.allowed()}")
        assert self.lo is not None and self.hi is not None
        if not self.lo <= value <= self.hi:
            raise SettingError(f"{self.name}: {value} is out of range; allowed: {self.allowed()}")
        return value

    def parse_text(self, text: str) -> object:
        """A value typed on the command line."""
        if self.table is not None:
            raise SettingError(f"{self.name} is a table: set it in stvm.toml [sysmac.{self.name}] "
                               "or from the Python API")
        if self.choices:
            by_text = {str(member.value).lower(): member for member in self.choices}
            member = by_text.get(text.lower())
            if member is None:
                raise SettingError(f"{self.name}: {text!r} is not allowed; allowed: {self.allowed()}")
            return member
        try:
            number = int(text.replace("_", ""), 0)
        except ValueError:
            raise SettingError(f"{self.name}: {text!r} is not an integer; allowed: {self.allowed()}") from None
        return self.coerce(number)


_DEFINE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def parse_define(text: object) -> tuple[str, str]:
    """`NAME` or `NAME=VALUE` → (NAME, VALUE); a value may be quoted ('1' or "1")."""
    if not isinstance(text, str):
        raise SettingError(f"a define is a string NAME or NAME=VALUE, got {text!r}")
    name, sep, value = text.partition("=")
    name, value = name.strip(), value.strip()
    if not _DEFINE_NAME.fullmatch(name):
        raise SettingError(f"a define is NAME or NAME=VALUE with NAME an identifier, got {text!r}")
    if len(value) >= 2 and value[0] == value[-1] and value[0] in "'\"":
        value = value[1:-1]
    return name, value


def _checked_defines(defines: object) -> tuple:
    if not isinstance(defines, tuple) or not all(
            isinstance(d, tuple) and len(d) == 2 and all(isinstance(x, str) for x in d) for d in defines):
        raise SettingError(f"defines must be (NAME, VALUE) pairs, got {defines!r}")
    for name, _ in defines:
        if not _DEFINE_NAME.fullmatch(name):
            raise SettingError(f"a define's NAME must be an identifier, got {name!r}")
    return tuple(sorted(dict(defines).items()))


_DECLARATIONS: dict[str, Declaration] = {}


def _declarations() -> dict[str, Declaration]:
    if not _DECLARATIONS:
        for f in fields(SysmacSettings):
            if f.metadata.get("not_a_setting"):
                continue
            default = f.default_factory() if f.default_factory is not MISSING else f.default
            if default is None:   # decided by the dialect: the default dialect's value
                from stvm.dialects import profile_value   # lazy: start-up
                default = globals()[f.type](profile_value(Dialect.IEC, f.name))   # the Enum, by its name
            # the kind is the default's type (an Enum class, int or dict): the same as the
            # annotation, without evaluating 50 annotation strings at every start-up
            kind = type(default)
            meta = f.metadata
            _DECLARATIONS[f.name] = Declaration(f.name, kind, default, meta["spec"], meta["lo"], meta["hi"],
                                                meta["table"], meta["doc"])
    return _DECLARATIONS


def declarations() -> list[Declaration]:
    """Every setting's declaration, in declaration order."""
    return list(_declarations().values())


def declaration(name: str) -> Declaration:
    """The declaration of setting `name`; SettingError (naming close matches) if there is none."""
    found = _declarations().get(name)
    if found is None:
        import difflib   # lazy: start-up (heapq and difflib, ~2-5 ms, only for this message)
        close = difflib.get_close_matches(name, list(_declarations()), n=3)
        hint = f"; did you mean {' or '.join(close)}?" if close else ""
        raise SettingError(f"unknown Sysmac setting {name!r}{hint} (known: {', '.join(_declarations())})")
    return found


DEFAULT_SETTINGS = SysmacSettings()
