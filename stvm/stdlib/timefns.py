"""IEC time arithmetic functions (IEC 61131-3 table 30): ADD_TIME … CONCAT_DATE_TOD.

Native rather than ST: they would be one-line ST bodies, but `DT + TIME` and friends are operator
overloads the core need not offer. TIME is a signed 64-bit ns count and wraps (sysmac.md 2);
TOD stays within one day (Choice: modulo 24 h, like a clock); a DATE/DT result before 1970 or
after 2106-02-06 is an instruction error.
"""

from __future__ import annotations

import math
from fractions import Fraction

from stvm.runtime.values import FunctionError, STFault
from stvm.semantics.types import LINT
from stvm.stdlib.conversions import DATE_LAST_NS, NS_PER_DAY
from stvm.stdlib.registry import native_function
from stvm.settings import IntDivZero


def _time(ns: int) -> int:
    return LINT.wrap(ns)


def _date_time(what: str, ns: int) -> int:
    if not 0 <= ns <= DATE_LAST_NS:
        raise FunctionError(f"{what}: result outside DT#1970-01-01-00:00:00…2106-02-06")
    return ns


@native_function("ADD_TIME")
def add_time(ctx, first: int, second: int) -> int:
    return _time(first + second)


@native_function("SUB_TIME")
def sub_time(ctx, first: int, second: int) -> int:
    return _time(first - second)


@native_function("MUL_TIME")
def mul_time(ctx, duration: int, factor: float) -> int:
    if not math.isfinite(factor):
        raise FunctionError(f"MUL_TIME: the factor {factor} is not a finite number")
    whole = int(factor)
    if whole == factor:   # a whole factor (`MUL_TIME(T#1s, TimeOutSeconds)`, every scan): exact as it is
        return _time(duration * whole)
    # exact: the ns nearest to duration x the REAL's value (ties to even), on every machine
    return _time(round(Fraction(duration) * Fraction(factor)))  # Choice: to the nearest ns


@native_function("DIV_TIME")
def div_time(ctx, duration: int, divisor: float) -> int:
    if divisor == 0:
        if ctx.settings.int_div_zero is IntDivZero.ZERO:
            return 0
        raise STFault("DIV_TIME by zero")
    if not math.isfinite(divisor):
        raise FunctionError(f"DIV_TIME: the divisor {divisor} is not a finite number")
    return _time(round(Fraction(duration) / Fraction(divisor)))


@native_function("ADD_TOD_TIME")
def add_tod_time(ctx, time_of_day: int, duration: int) -> int:
    return (time_of_day + duration) % NS_PER_DAY


@native_function("SUB_TOD_TIME")
def sub_tod_time(ctx, time_of_day: int, duration: int) -> int:
    return (time_of_day - duration) % NS_PER_DAY


@native_function("SUB_TOD_TOD")
def sub_tod_tod(ctx, first: int, second: int) -> int:
    return _time(first - second)


@native_function("ADD_DT_TIME")
def add_dt_time(ctx, date_time: int, duration: int) -> int:
    return _date_time("ADD_DT_TIME", date_time + duration)


@native_function("SUB_DT_TIME")
def sub_dt_time(ctx, date_time: int, duration: int) -> int:
    return _date_time("SUB_DT_TIME", date_time - duration)


@native_function("SUB_DT_DT")
def sub_dt_dt(ctx, first: int, second: int) -> int:
    return _time(first - second)


@native_function("SUB_DATE_DATE")
def sub_date_date(ctx, first: int, second: int) -> int:
    return _time(first - second)


@native_function("CONCAT_DATE_TOD")
def concat_date_tod(ctx, date: int, time_of_day: int) -> int:
    return _date_time("CONCAT_DATE_TOD", date + time_of_day)
