"""Helpers the generated code calls. Their names (all `_x`) are what `lower.codegen` emits.

Kept small and branch-light: they run inside scans.
"""

from __future__ import annotations

import copy as _shallow
import math

from stvm.numeric import f32, strfit
from stvm.runtime.values import ArrayIndexError, ArrayRef, AttrRef, FunctionError, ItemRef, MapRef, OpenArray, STFault
from stvm.runtime.memory import MEMORY_HELPERS
from stvm.runtime.unions import UNION_HELPERS


def _idiv(a: int, b: int) -> int:
    """IEC integer division: truncates toward zero; division by zero is a major fault."""
    if b == 0:
        raise STFault("integer division by zero")
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def _idiv0(a: int, b: int) -> int:
    """`int_div_zero=zero`: division by zero gives 0."""
    if b == 0:
        return 0
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def _imod(a: int, b: int) -> int:
    """IEC MOD: the result has the dividend's sign; MOD 0 is a division-by-zero fault."""
    if b == 0:
        raise STFault("integer division by zero (MOD 0)")
    return a - b * _idiv(a, b)


def _imod0(a: int, b: int) -> int:
    """`int_div_zero=zero`: MOD 0 gives 0."""
    if b == 0:
        return 0
    return a - b * _idiv(a, b)


def _tdiv(duration_ns: int, divisor: float) -> int:
    """TIME / REAL, truncated to whole ns."""
    # Choice (sysmac.md 1, `int_div_zero`): dividing a TIME by 0.0 is an integer division by
    # zero (the result is a TIME, an integer), as DIV_TIME already treats it
    if divisor == 0:
        raise STFault("integer division by zero (TIME / 0.0)")
    return _time_of(duration_ns / divisor)


def _tdiv0(duration_ns: int, divisor: float) -> int:
    """`int_div_zero=zero`: TIME / 0.0 gives T#0s."""
    if divisor == 0:
        return 0
    return _time_of(duration_ns / divisor)


def _time_of(ns: float) -> int:
    """A float number of ns as a TIME: truncated, wrapped modulo 2^64 like all TIME arithmetic."""
    if ns != ns or ns in (math.inf, -math.inf):
        raise STFault("TIME division result is not a number")
    return ((int(ns) + 2**63) & (2**64 - 1)) - 2**63


def _fdiv(a: float, b: float) -> float:
    """IEEE division: x/0 is ±inf, 0/0 is nan (REAL/LREAL never fault)."""
    try:
        return a / b
    except ZeroDivisionError:
        if a != a or a == 0:
            return math.nan
        return math.copysign(math.inf, a) * math.copysign(1.0, b)


def _expt(a: float, b: float) -> float:
    try:
        result = float(a) ** b
    except ZeroDivisionError:
        return math.inf
    except OverflowError:
        return math.inf
    if isinstance(result, complex):
        return math.nan
    return result


def _oob(index: int, lo: int, hi: int) -> int:
    raise ArrayIndexError(f"array index {index} out of bounds {lo}..{hi}")


class SubrangeError(STFault):
    """A value outside its subrange type, computed at run time (`subrange_check=fault`)."""


def _subrange(value: int, low: int, high: int) -> int:
    if low <= value <= high:
        return value
    raise SubrangeError(f"value {value} is outside the subrange {low}..{high}")


class NullReference(STFault):
    """A dereference of NULL (REF_TO / POINTER TO / REFERENCE TO never bound)."""


def _null_ref():
    raise NullReference("dereference of a NULL reference")


def _null_itf():
    raise NullReference("call through an interface that holds no instance (NULL)")


def _query_itf(obj, key: str, out) -> bool:
    """__QUERYINTERFACE(obj, out): `out` := obj when its FB implements interface `key`."""
    found = obj is not None and key in getattr(obj, "_itfs", ())
    out.set(obj if found else None)
    return found


def _same_ref(a, b) -> bool:
    if a is b:
        return True
    if a is None or b is None:
        return False
    return a.same(b)


def _endless_for(end: int, step: int, type_name: str) -> None:
    raise STFault(f"FOR loop cannot end: the {type_name} loop variable wraps before passing {end} "
                  f"(step {step}); a controller's watchdog would stop the task")


def copy_value(value):
    """Deep copy of an aggregate value (arrays are lists, structs have `_copy`)."""
    if type(value) is list:
        if value and type(value[0]) in (int, float, bool, bytes):
            return value[:]
        return [copy_value(v) for v in value]
    copy = getattr(value, "_copy", None)
    return copy() if copy is not None else value


def _fb_slots(cls) -> tuple[tuple[str, bool], ...]:
    """Every variable slot of an FB class, its bases' included, with whether the instance owns
    the value (a nested instance, STRUCT or ARRAY: copied) or holds it (a number, a string, a
    reference, an interface, a pointer: the value itself is copied)."""
    out = []
    for klass in cls.__mro__:
        owned = getattr(klass, "_owned", ())
        out += [(slot, slot in owned) for slot in getattr(klass, "__slots__", ()) if slot != "__dict__"]
    return tuple(out)


def _copy_fb(src):
    """A copy of an FB instance (TwinCAT/CODESYS `fb_assign`: the instance's memory copied)."""
    cls = type(src)
    other = cls.__new__(cls)
    for slot, owned in _fb_slots(cls):
        if hasattr(src, slot):
            value = getattr(src, slot)
            setattr(other, slot, copy_value(value) if owned else _shallow.copy(value) if slot == "_impl" else value)
    return other


def _assign_fb(dst, src) -> None:
    """`dst := src` for FB instances: every variable copied into `dst`, the nested instances,
    structures and arrays in place (references to them see the new values)."""
    if src is dst:
        return
    for slot, owned in _fb_slots(type(dst)):
        if not hasattr(src, slot):
            continue
        value, mine = getattr(src, slot), getattr(dst, slot, None)
        if not owned:
            setattr(dst, slot, _shallow.copy(value) if slot == "_impl" else value)
        elif type(value) is list and type(mine) is list:
            _assign_array(mine, value)
        elif type(mine) is type(value) and hasattr(mine, "_assign"):
            mine._assign(value)
        else:
            setattr(dst, slot, copy_value(value))


def _assign_array(dst: list, src) -> None:
    if isinstance(src, ArrayRef):
        src = src.data[src.start:]
    dst[:] = copy_value(src)


def _setbit(word: int, bit: int, value: bool) -> int:
    return word | (1 << bit) if value else word & ~(1 << bit)


def _assigned(ref, value):
    """An assignment used as an expression (CODESYS/TwinCAT `(x := v)`): store, then give the
    value stored (already converted to the target's type by the lowering)."""
    ref.set(value)
    return value


def _with(obj, **fields):
    for name, value in fields.items():
        setattr(obj, name, value)
    return obj


def _fb_init_later(pending: list, obj, calls: tuple):
    """Queue `obj`'s FB_init calls (CODESYS), run by the VM once every instance exists."""
    pending.append((obj, calls))
    return obj


def _en_call(enabled, call, default, eno, negate: bool):
    """A call with EN/ENO inside an expression: run `call()` only when `enabled`, else the
    result type's initial value (`default()`); ENO (a reference, or None) is FALSE before the
    call (an instruction error leaves it so) and when EN is FALSE, TRUE after it."""
    if eno is not None:
        eno.set(negate)
    if not enabled:
        return default()
    value = call()
    if eno is not None:
        eno.set(not negate)
    return value


class _Frame:
    """Variables of one function call (attributes `v_<name>`), so in-outs can reference them."""

    __slots__ = ("__dict__",)


HELPERS = {
    "_f32": f32, "_idiv": _idiv, "_idiv0": _idiv0, "_imod": _imod, "_imod0": _imod0, "_fdiv": _fdiv,
    "_tdiv": _tdiv, "_tdiv0": _tdiv0, "_expt": _expt, "_oob": _oob, "_subrange": _subrange, "_endless_for": _endless_for, "_strfit": strfit, "_copy_value": copy_value,
    "_assign_array": _assign_array, "_setbit": _setbit, "_with": _with, "_Frame": _Frame,
    "_fb_init_later": _fb_init_later, "_copy_fb": _copy_fb, "_assign_fb": _assign_fb,
    "_assigned": _assigned, "_AttrRef": AttrRef, "_MapRef": MapRef, "_ItemRef": ItemRef, "_ArrayRef": ArrayRef, "_FunctionError": FunctionError,
    "_STFault": STFault, "_null_ref": _null_ref, "_null_itf": _null_itf, "_query_itf": _query_itf, "_same_ref": _same_ref, "_ArrayIndexError": ArrayIndexError,
}
HELPERS.update(UNION_HELPERS)   # the base class and member descriptor of generated UNION classes
HELPERS.update(MEMORY_HELPERS)  # byte-addressed pointers of the TwinCAT/CODESYS profiles
HELPERS["_OpenArray"] = OpenArray   # ARRAY[*, *] arguments
HELPERS["_en_call"] = _en_call      # EN/ENO inside an expression
