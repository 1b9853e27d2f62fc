"""Native FB implementations written against ST names: `@st_names("IN", "PT", "Q", "ET")`.

A native FB (stvm/stdlib/timers.py, sockets.py) reads and writes the variables of the instance the
generated code hands it. It spells them as ST does, `inst.Q = True`, and declares which ST names it
uses; the decorator renames those attributes in the compiled code, once, at class-definition time,
to the storage names `stvm.lower.names` gives the generated class (`v_q`). So the naming scheme of
generated code is built in one place, and the native FBs never spell it.

Why rewriting the code's attribute names rather than `getattr(inst, Q)` with a looked-up name: a
native FB runs on every scan (the thesis calls ~30 socket FBs and timers per scan), and a `getattr`
with a computed name costs ~25 ns more than an attribute access (about 1.5 % of the thesis's scan);
the renamed code is exactly the code a hand-written `inst.v_q` would compile to, with no per-scan
cost at all. The rename is checked: a declared name used as anything but an attribute (a global, a
local, an import) is refused when the class is defined.
"""

from __future__ import annotations

import dis
from types import CodeType, FunctionType
from typing import Callable, TypeVar

from stvm.lower.names import var_attr

_ATTRIBUTE_OPS = frozenset({"LOAD_ATTR", "STORE_ATTR", "DELETE_ATTR", "LOAD_METHOD"})
_T = TypeVar("_T")


def st_names(*names: str) -> Callable[[_T], _T]:
    """Decorator for a class or function: attributes spelled as one of `names` (the ST spelling,
    exactly as written in the code) are read and written under their storage names. A class also
    binds the names its bases declared (a subclass of a protocol base uses the base's pins)."""
    own = {name: var_attr(name) for name in names}

    def bind(obj: _T) -> _T:
        if isinstance(obj, type):
            mapping: dict[str, str] = {}
            for base in reversed(obj.__mro__[1:]):
                mapping.update(getattr(base, "__st_names__", {}))
            mapping.update(own)
            for member in vars(obj).values():
                function = member.__func__ if isinstance(member, (staticmethod, classmethod)) else member
                if isinstance(function, FunctionType):
                    function.__code__ = _renamed(function.__code__, mapping)
            obj.__st_names__ = mapping   # type: ignore[attr-defined]
        elif isinstance(obj, FunctionType):
            obj.__code__ = _renamed(obj.__code__, own)
        else:
            raise TypeError(f"@st_names decorates a class or a function, not {obj!r}")
        return obj

    return bind


def _renamed(code: CodeType, mapping: dict[str, str]) -> CodeType:
    """`code` with its attribute names in `mapping` renamed (nested functions and lambdas too)."""
    for instruction in dis.get_instructions(code):
        if instruction.argval in mapping and isinstance(instruction.argval, str) \
                and instruction.opname not in _ATTRIBUTE_OPS and instruction.opcode in dis.hasname:
            raise TypeError(f"{code.co_qualname}: ST name {instruction.argval!r} is used as a "
                            f"{instruction.opname} here, not as an attribute; rename the Python name")
    consts = tuple(_renamed(c, mapping) if isinstance(c, CodeType) else c for c in code.co_consts)
    return code.replace(co_names=tuple(mapping.get(name, name) for name in code.co_names), co_consts=consts)
