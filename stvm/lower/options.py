"""The lowering's optimisations, each a named switch.

Every optimisation keeps the ST semantics exactly (the differential test lowers the core and thesis
suites with all of them off and compares); they only change how fast the generated code runs. The
debug build switches `cache_locals` off, because a debugger stopped inside a call must read and
write the storage the code itself uses (see `stvm/debug/build.py`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace


@dataclass(frozen=True)
class LowerOptions:
    # A call keeps its POU's often-used variables in Python locals and writes the scalars back in
    # a `finally` (LOAD_FAST instead of attribute access).
    cache_locals: bool = True
    # A METHOD none of whose variables is passed by reference runs without a frame object: its
    # variables are Python locals. Needs `cache_locals`.
    frameless_methods: bool = True
    # FOR with a constant step, the end evaluated once and an unassigned local loop variable
    # becomes a Python `for … in range()`. Needs `cache_locals`.
    range_for: bool = True
    # Inside a range-FOR, `a[i + c]` gets one bounds check before the loop instead of one per
    # access (a checked copy of the loop runs when the check fails). Needs `range_for`.
    hoist_bounds: bool = True
    # `i + k` on a range-FOR variable that provably stays in its type needs no wrap code.
    # Needs `range_for`.
    no_wrap_in_range: bool = True
    # A chain of + - * in one integer type wraps once at its end (arithmetic modulo 2^n).
    ring_chain: bool = True
    # A STRUCT assignment copies nested STRUCT fields inline (one Python call per assignment).
    inline_struct_assign: bool = True

    @classmethod
    def none(cls) -> "LowerOptions":
        """Every optimisation off: the reference lowering of the differential test."""
        return cls(**{f.name: False for f in fields(cls)})

    def without(self, *names: str) -> "LowerOptions":
        """These options with the named optimisations switched off."""
        unknown = [name for name in names if name not in self.names()]
        if unknown:
            raise ValueError(f"unknown lowering optimisation {unknown[0]!r}; known: {', '.join(self.names())}")
        return replace(self, **{name: False for name in names})

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


DEFAULT_OPTIONS = LowerOptions()
