"""Mangled Python names for ST names. Only names built here reach generated code.

ST identifiers are validated (`[A-Za-z_][A-Za-z0-9_]*`) and given a kind prefix, so they can never
collide with Python keywords, builtins or the generator's own helpers (which start with `_`).
"""

from __future__ import annotations

import re

_SAFE_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def _checked(st_name: str) -> str:
    if not _SAFE_NAME.fullmatch(st_name):  # semantics checked it; this catches our own bugs
        raise AssertionError(f"unsafe ST name {st_name!r}")
    return st_name.lower()


def var_attr(st_name: str) -> str:
    """Attribute holding variable/field/pin `st_name` on an instance, struct or frame."""
    attr = _VAR_ATTRS.get(st_name)
    if attr is None:
        attr = "v_" + _checked(st_name)
        if len(_VAR_ATTRS) < _VAR_ATTRS_MAX:
            _VAR_ATTRS[st_name] = attr
    return attr


# var_attr's results: the generator asks for the same few names hundreds of thousands of times
# (each use of a variable), each a regex match and a lower(); bounded, as a long-lived process
# (the DAP server, the HMI) lowers program after program
_VAR_ATTRS: dict[str, str] = {}
_VAR_ATTRS_MAX = 100_000


_VAR_ATTR = re.compile(r"v_[a-z_][a-z0-9_]*")


def is_var_attr(attr: str) -> bool:
    """Whether `attr` is a name `var_attr` makes (for code that writes storage names it was handed
    into generated text, e.g. the trace sampler: anything else is a bug, never ST text)."""
    return _VAR_ATTR.fullmatch(attr) is not None


def st_name_of_attr(attr: str) -> str:
    """Reverse of `var_attr` (lower-case ST name), for the debugger and tracer."""
    return attr[2:] if attr.startswith("v_") else attr


def unit_name(kind: str, index: int, qualname: str) -> str:
    """Class/function name of a POU or struct: kind P (FB/PROGRAM), F (function), N (native fn), S (struct)."""
    leaf = qualname.split("\\")[-1]
    return f"{kind}{index}_{_checked(leaf)}"


def method_attr(st_name: str, accessor: str = "") -> str:
    """Python method of an FB class for METHOD `st_name` (m_), or a PROPERTY's GET (g_) / SET (s_)."""
    return {"": "m_", "GET": "g_", "SET": "s_"}[accessor] + _checked(st_name)
