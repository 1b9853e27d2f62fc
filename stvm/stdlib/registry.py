"""Binding of `{native}` stdlib POUs to their Python implementations.

A native POU is declared in ST (a `.st` file in this folder) with the pragma `{native}` before
FUNCTION/FUNCTION_BLOCK, so the checker treats it like any POU; its implementation is registered
here under the POU's name (case-insensitive).

Functions: `@native_function("LEN")` on `def len_(ctx, In)`. Arguments arrive positionally in the
order of the ST declaration (VAR_INPUT then VAR_IN_OUT); omitted inputs arrive as their initial
value. The return value is the function result. Signal an instruction error with
`raise FunctionError(msg)`. `generic=True` functions (return type ANY_*) get the resolved result
type as a second argument: `def max_(ctx, result_type, *values)`. `variadic=True` functions
(CONCAT, MAX, MIN, MUX, …) receive every argument given, in order.

Additions (stdlib, issue 4):
* `typed=True` (pragma `{native typed}`): the implementation needs the static types of its
  arguments (ToAryByte's `In : ANY` must know INT from UINT, a STRING's declared size). It gets the
  tuple of argument types (declaration order; omitted inputs as their declared type) right after
  `ctx` (after `result_type` when also generic): `def toarybyte(ctx, arg_types, In, Order, AryOut)`.
* `result_rule`: for a generic function whose result is not the common type of all its generic
  inputs (SHL's `N : ANY_INT`, MUX's `K`, EXPT's exponent, TRUNC returning an integer), a callable
  `rule(arg_types) -> Type` the checker uses instead of the common type (same argument-type tuple
  as for `typed`). Without a rule the result is the common type of the generic inputs.

Function blocks: `@native_fb("TON")` on a class. The VM creates one implementation object per
FB instance, `impl = cls()`, and on every call of the instance runs `impl.call(inst, ctx)`, where
`inst` holds the ST-visible variables (inputs already copied in, in-outs bound to
references/objects) under the storage names of the lowering's layout. The implementation spells
them as ST does, `inst.Q`, and declares them with `@st_names("IN", "PT", "Q", "ET")`
(`stvm.lower.bind`), which binds those attributes to the storage names once, when the class is
defined; it writes outputs into `inst` and keeps private state on itself.

`{native quiet:PIN}` (the socket FBs, `quiet:Execute`): the implementation keeps `impl.quiet`, a
value of the input PIN for which its next call would change nothing (None when any call may), and
the generated call site calls only while `inst.PIN is not impl.quiet` (lowering option
`skip_quiet_native_calls`). The implementation must keep it exact after every call: a call that
is skipped must be one that would have stored nothing, in `inst` or on itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


@dataclass(frozen=True)
class NativeFunction:
    """A stdlib FUNCTION written in Python: its implementation and how its calls are typed."""

    name: str
    impl: Callable
    generic: bool = False
    variadic: bool = False
    typed: bool = False
    result_rule: Callable | None = None


NATIVE_FUNCTIONS: dict[str, NativeFunction] = {}
NATIVE_FBS: dict[str, type] = {}


def native_function(name: str, *, generic: bool = False, variadic: bool = False,
                    typed: bool = False, result_rule: Callable | None = None):
    def register(impl: Callable) -> Callable:
        NATIVE_FUNCTIONS[name.upper()] = NativeFunction(name, impl, generic, variadic, typed,
                                                        result_rule)
        return impl
    return register


def native_fb(name: str):
    def register(cls: type) -> type:
        NATIVE_FBS[name.upper()] = cls
        return cls
    return register
