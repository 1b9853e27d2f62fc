"""IEC numeric, arithmetic, selection and bit-shift functions (sysmac.md 7, IEC 61131-3 2.5.1.5).

All are generic: the checker passes the resolved result type and the implementation computes in
that type (integers wrap, REAL rounds to binary32, sysmac.md 2). Real mathematics follows IEEE 754
(SQRT(-1.0) is NaN, LN(0.0) is -inf): a controller's FPU gives these values, not an error.
"""

from __future__ import annotations

import copy
import math


from stvm.runtime.values import FunctionError, STFault
from stvm.semantics.types import BoolType, IntType, RealType, Type, DINT, LINT, LREAL
from stvm.stdlib.registry import native_function
from stvm.stdlib.typeops import coerce, common_type, real_to_integer
from stvm.settings import IntDivZero


def _first_argument_type(arg_types) -> Type:
    return arg_types[0]


def _power_type(arg_types) -> Type:
    """EXPT's result: the base's real type; an integer base (CODESYS/TwinCAT allow one, stdlib
    __init__ `_apply_settings`) gives LREAL, as TwinCAT documents ("return type is always LREAL")."""
    return arg_types[0] if isinstance(arg_types[0], RealType) else LREAL


def _common_after_first(arg_types) -> Type:
    return common_type(arg_types[1:])


def _integer_for_real(arg_types) -> Type:
    # W502 2-284: TRUNC/Round/RoundUp give DINT for a REAL and LINT for an LREAL.
    source = arg_types[0]
    return LINT if isinstance(source, RealType) and source.bits == 64 else DINT


# --- arithmetic ------------------------------------------------------------------------------

@native_function("ABS", generic=True)
def abs_(ctx, result_type, value):
    return coerce(abs(value), result_type)


def _numpy():
    import numpy   # lazy: start-up (a program that calls no REAL function never loads numpy)
    return numpy


def _real_function(numpy_name):
    function = []     # the numpy ufunc, looked up on the first call

    def apply(ctx, result_type, value):
        np = _numpy()
        if not function:
            function.append(getattr(np, numpy_name))
        with np.errstate(all="ignore"):
            return coerce(float(function[0](np.float64(value))), result_type)
    return apply


# Choice: computed in double precision and rounded to the result type; for REAL this is the
# correctly rounded single-precision result in all but rare double-rounding cases.
REAL_FUNCTIONS = {
    "SQRT": "sqrt", "LN": "log", "LOG": "log10", "EXP": "exp",
    "SIN": "sin", "COS": "cos", "TAN": "tan",
    "ASIN": "arcsin", "ACOS": "arccos", "ATAN": "arctan",
}
for _name, _function in REAL_FUNCTIONS.items():
    native_function(_name, generic=True)(_real_function(_function))


@native_function("EXPT", generic=True, result_rule=_power_type)
def expt(ctx, result_type, base, exponent):
    np = _numpy()
    with np.errstate(all="ignore"):
        return coerce(float(np.power(np.float64(base), np.float64(exponent))), result_type)


def _integer_division_by_zero(ctx, what: str) -> int:
    if ctx.settings.int_div_zero is IntDivZero.ZERO:
        return 0
    raise STFault(f"integer division by zero in {what}")


@native_function("ADD", generic=True, variadic=True)
def add(ctx, result_type, *values):
    total = coerce(values[0], result_type)
    for value in values[1:]:
        total = coerce(total + value, result_type)  # each step in the result type
    return total


@native_function("MUL", generic=True, variadic=True)
def mul(ctx, result_type, *values):
    product = coerce(values[0], result_type)
    for value in values[1:]:
        product = coerce(product * value, result_type)
    return product


@native_function("SUB", generic=True)
def sub(ctx, result_type, minuend, subtrahend):
    return coerce(minuend - subtrahend, result_type)


@native_function("DIV", generic=True)
def div(ctx, result_type, dividend, divisor):
    if isinstance(result_type, RealType):
        dividend, divisor = float(dividend), float(divisor)
        if divisor == 0.0:
            # IEEE: x/0 is ±inf, 0/0 NaN
            if dividend == 0.0 or math.isnan(dividend):
                return math.nan
            return math.copysign(math.inf, dividend) * math.copysign(1.0, divisor)
        return coerce(dividend / divisor, result_type)
    if divisor == 0:
        return _integer_division_by_zero(ctx, "DIV")
    quotient = abs(int(dividend)) // abs(int(divisor))  # IEC: truncation toward zero
    return coerce(quotient if (dividend < 0) == (divisor < 0) else -quotient, result_type)


def _truncate(value: float) -> int:
    return math.trunc(value) if math.isfinite(value) else 0


def _round_away(value: float) -> int:
    if not math.isfinite(value):
        return 0
    return math.ceil(value) if value > 0 else math.floor(value)


# W502 2-284: TRUNC toward zero, Round half to even, RoundUp away from zero.
ROUNDING_FUNCTIONS = {"TRUNC": _truncate, "Round": real_to_integer, "RoundUp": _round_away}


def _rounding_function(rounding):
    def apply(ctx, result_type, value):
        return coerce(rounding(value), result_type)
    return apply


for _name, _rounding in ROUNDING_FUNCTIONS.items():
    native_function(_name, generic=True, result_rule=_integer_for_real)(_rounding_function(_rounding))


# --- selection -------------------------------------------------------------------------------

@native_function("MAX", generic=True, variadic=True)
def max_(ctx, result_type, *values):
    return coerce(max(values), result_type)


@native_function("MIN", generic=True, variadic=True)
def min_(ctx, result_type, *values):
    return coerce(min(values), result_type)


@native_function("LIMIT", generic=True)
def limit(ctx, result_type, low, value, high):
    return coerce(min(max(value, low), high), result_type)


@native_function("SEL", generic=True, result_rule=_common_after_first)
def sel(ctx, result_type, select_second, first, second):
    return coerce(second if select_second else first, result_type)


@native_function("MUX", generic=True, variadic=True, result_rule=_common_after_first)
def mux(ctx, result_type, index, *choices):
    if not 0 <= index < len(choices):
        raise FunctionError(f"MUX: K = {index} selects none of the {len(choices)} inputs")
    return coerce(choices[index], result_type)


@native_function("MOVE", generic=True)
def move(ctx, result_type, value):
    # arrays and structs are values (sysmac.md 2): the result must not alias the argument
    if isinstance(value, (bool, int, float, bytes)):
        return coerce(value, result_type)
    return copy.deepcopy(value)


# --- bit shifts ------------------------------------------------------------------------------

def _bit_width(result_type: Type) -> int:
    if isinstance(result_type, BoolType):
        return 1
    if isinstance(result_type, IntType):
        return result_type.bits
    raise FunctionError(f"{result_type} is not a bit string")


def _shift_count(what: str, count: int) -> int:
    if count < 0:
        raise FunctionError(f"{what}: negative shift count {count}")
    return count


def _as_bits(value) -> int:
    return int(value)


def _bits_result(result_type: Type, bits: int):
    if isinstance(result_type, BoolType):
        return bool(bits)
    if isinstance(result_type, IntType) and result_type.signed:
        # TwinCAT/CODESYS shift a signed integer's two's complement bits (Choice: as unsigned,
        # SHR fills with 0; Beckhoff documents no sign rule); the result reads back as signed
        width = result_type.bits
        bits &= (1 << width) - 1
        return bits - (1 << width) if bits >> (width - 1) else bits
    return bits


@native_function("SHL", generic=True, result_rule=_first_argument_type)
def shl(ctx, result_type, value, count):
    width = _bit_width(result_type)
    count = _shift_count("SHL", count)
    return _bits_result(result_type, (_as_bits(value) << count) & ((1 << width) - 1) if count < width else 0)


@native_function("SHR", generic=True, result_rule=_first_argument_type)
def shr(ctx, result_type, value, count):
    count = _shift_count("SHR", count)
    bits = _as_bits(value) & ((1 << _bit_width(result_type)) - 1)   # a signed value's bits, as unsigned
    return _bits_result(result_type, bits >> count)  # logical


@native_function("ROL", generic=True, result_rule=_first_argument_type)
def rol(ctx, result_type, value, count):
    width = _bit_width(result_type)
    count = _shift_count("ROL", count) % width
    bits = _as_bits(value)
    rotated = ((bits << count) | (bits >> (width - count))) & ((1 << width) - 1)
    return _bits_result(result_type, rotated)


@native_function("ROR", generic=True, result_rule=_first_argument_type)
def ror(ctx, result_type, value, count):
    width = _bit_width(result_type)
    count = _shift_count("ROR", count) % width
    bits = _as_bits(value)
    rotated = ((bits >> count) | (bits << (width - count))) & ((1 << width) - 1)
    return _bits_result(result_type, rotated)


# ---- comparison functions (IEC table 28): extensible ones compare each neighbouring pair
def _chain(test):
    def compare(ctx, result_type, *values):
        return all(test(a, b) for a, b in zip(values, values[1:]))
    return compare


for _name, _test in (("GT", lambda a, b: a > b), ("GE", lambda a, b: a >= b), ("EQ", lambda a, b: a == b),
                     ("LE", lambda a, b: a <= b), ("LT", lambda a, b: a < b)):
    native_function(_name, generic=True, variadic=True)(_chain(_test))


@native_function("NE", generic=True)
def ne(ctx, result_type, first, second):
    return first != second


@native_function("__MOD", generic=True)
def mod_function(ctx, result_type, dividend, divisor):
    """MOD(a, b) as the MOD operator: the sign of the dividend; /0 per `int_div_zero`."""
    if divisor == 0:
        return _integer_division_by_zero(ctx, "MOD")
    return coerce(int(math.fmod(int(dividend), int(divisor))), result_type)


def _bitwise(operation):
    def combine(ctx, result_type, *values):
        acc = values[0]
        for value in values[1:]:
            acc = operation(acc, value)
        return bool(acc) if isinstance(result_type, BoolType) else coerce(acc, result_type)
    return combine


native_function("__AND", generic=True, variadic=True)(_bitwise(lambda a, b: a & b))
native_function("__OR", generic=True, variadic=True)(_bitwise(lambda a, b: a | b))
native_function("__XOR", generic=True, variadic=True)(_bitwise(lambda a, b: a ^ b))


@native_function("ATAN2", generic=True)
def atan2(ctx, result_type, y, x):
    """CODESYS ATAN2(Y, X): the angle of (X, Y) in radians, -pi..pi (atan2(0, 0) = 0)."""
    return coerce(math.atan2(float(y), float(x)), result_type)
